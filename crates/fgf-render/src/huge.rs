//! Large read-mostly arrays of a render (BVH nodes and leaf packs, triangle
//! records, voxel grids, environment maps, bitmap textures) backed by 2 MiB
//! pages where the system allows it.
//!
//! A traversal or a grid lookup touches a few bytes at scattered places of
//! arrays that reach tens of MiB. With 4 KiB pages each such access needs
//! its own TLB entry, and a scene of a few MiB already has more pages than
//! the first-level TLB holds. Linux (6.1 and later) collapses an existing,
//! filled range into huge pages on request (`madvise(MADV_COLLAPSE)`),
//! whatever the system-wide transparent-huge-page mode (Debian's default is
//! `madvise`: nothing is collapsed unless asked). The advice changes no
//! content, so results are unaffected; where it is refused (an older
//! kernel, another system, memory too fragmented) nothing changes.
//! Measured in `docs/benchmarks.md` ("Shadow rays, huge pages, and where
//! the mesh scene's time goes", and "Huge pages for whole arrays").

/// Ask for huge pages under all of `v`'s memory if it is at least
/// [`MIN_BYTES`]: every 2 MiB page it touches, one by one, the first and
/// the last included although they may also hold other memory of the
/// process (the advice changes no content; a page not wholly within one
/// mapping is left as it is). A large allocation starts anywhere in a
/// 2 MiB page (the allocator maps it at some 4 KiB boundary), so the pages
/// wholly within `v` would leave out up to 4 MiB of it, and all of an
/// array below 2 MiB. Best effort: errors are ignored.
pub(crate) fn advise<T>(v: &[T]) {
    #[cfg(target_os = "linux")]
    {
        let start = v.as_ptr() as usize;
        let bytes = std::mem::size_of_val(v);
        if bytes < MIN_BYTES {
            return;
        }
        let mut page = start & !(HUGE - 1);
        while page < start + bytes {
            // SAFETY: MADV_COLLAPSE keeps the contents of the memory it
            // is given; an address that is not mapped makes it fail.
            unsafe {
                libc::madvise(page as *mut libc::c_void, HUGE, libc::MADV_COLLAPSE);
            }
            page += HUGE;
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = v;
}

/// The huge page size the advice assumes: 2 MiB (x86-64, and aarch64
/// with 4 KiB base pages).
#[cfg(target_os = "linux")]
const HUGE: usize = 1 << 21;

/// Arrays below this many bytes (64 pages of 4 KiB) are left as they are.
const MIN_BYTES: usize = 256 * 1024;

/// The system allocator, with every block of at least 4 MiB (`FRESH_MIN`)
/// advised for huge pages (`madvise(MADV_HUGEPAGE)`) as it is made, before
/// anything touches it: its 2 MiB pages are then each faulted in once,
/// where 4 KiB pages take 512 faults, and a large scene's preparation
/// (which fills and drops arrays of hundreds of MiB) spent about a second
/// of system time in them (`docs/benchmarks.md`, "Large meshes"). The
/// advice changes no content; where it is refused nothing changes. The
/// binaries declare it as their `#[global_allocator]`.
pub struct HugePages;

/// Blocks below this many bytes (two huge pages) are not advised.
const FRESH_MIN: usize = 4 << 20;

impl HugePages {
    /// Advise the 2 MiB pages wholly inside `size` bytes at `p` (new memory,
    /// or memory just reallocated) for huge pages.
    #[inline]
    fn fresh(p: *mut u8, size: usize) {
        #[cfg(target_os = "linux")]
        if !p.is_null() && size >= FRESH_MIN {
            let start = (p as usize).next_multiple_of(HUGE);
            let end = (p as usize + size) & !(HUGE - 1);
            if end > start {
                // SAFETY: the range lies within the block just allocated;
                // MADV_HUGEPAGE changes how it is backed, not its contents.
                unsafe {
                    libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE);
                }
            }
        }
        #[cfg(not(target_os = "linux"))]
        let _ = (p, size);
    }
}

// SAFETY: every call is the system allocator's; the advice only changes
// how the memory it returned is backed.
unsafe impl std::alloc::GlobalAlloc for HugePages {
    unsafe fn alloc(&self, layout: std::alloc::Layout) -> *mut u8 {
        let p = unsafe { std::alloc::System.alloc(layout) };
        Self::fresh(p, layout.size());
        p
    }
    unsafe fn alloc_zeroed(&self, layout: std::alloc::Layout) -> *mut u8 {
        let p = unsafe { std::alloc::System.alloc_zeroed(layout) };
        Self::fresh(p, layout.size());
        p
    }
    unsafe fn dealloc(&self, p: *mut u8, layout: std::alloc::Layout) {
        unsafe { std::alloc::System.dealloc(p, layout) }
    }
    unsafe fn realloc(&self, p: *mut u8, layout: std::alloc::Layout, size: usize) -> *mut u8 {
        let q = unsafe { std::alloc::System.realloc(p, layout, size) };
        Self::fresh(q, size);
        q
    }
}

#[cfg(test)]
mod tests {
    use std::alloc::{GlobalAlloc, Layout};

    /// Blocks made, grown and shrunk by the allocator keep what was
    /// written to them, below and above the size it advises, and a zeroed
    /// block reads as zeros.
    #[test]
    fn huge_page_allocator_keeps_contents() {
        let a = super::HugePages;
        for size in [64usize, (4 << 20) - 1, 5 << 20, 37 << 20] {
            let layout = Layout::from_size_align(size, 64).unwrap();
            // SAFETY: the layouts are non-zero; each block is written and
            // read within its size and freed once, with its layout.
            unsafe {
                let z = a.alloc_zeroed(layout);
                assert!(!z.is_null());
                assert!(std::slice::from_raw_parts(z, size).iter().all(|&b| b == 0));
                a.dealloc(z, layout);
                let p = a.alloc(layout);
                assert!(!p.is_null());
                for i in (0..size).step_by(4093) {
                    *p.add(i) = (i % 251) as u8;
                }
                let grown = a.realloc(p, layout, 2 * size);
                assert!(!grown.is_null());
                for i in (0..size).step_by(4093) {
                    assert_eq!(*grown.add(i), (i % 251) as u8, "size {size}, byte {i}");
                }
                let layout2 = Layout::from_size_align(2 * size, 64).unwrap();
                let shrunk = a.realloc(grown, layout2, size / 2 + 1);
                assert!(!shrunk.is_null());
                for i in (0..size / 2).step_by(4093) {
                    assert_eq!(*shrunk.add(i), (i % 251) as u8, "size {size}, byte {i}");
                }
                a.dealloc(shrunk, Layout::from_size_align(size / 2 + 1, 64).unwrap());
            }
        }
    }

    /// The advice keeps every byte, for arrays below, across and well
    /// beyond the 2 MiB page, aligned or not.
    #[test]
    fn advice_keeps_contents() {
        for len in [0usize, 1, 4096, (1 << 21) - 3, (1 << 21) + 7, 5 << 20] {
            let v: Vec<u32> = (0..len as u32)
                .map(|i| i.wrapping_mul(2_654_435_761))
                .collect();
            let w = v.clone();
            super::advise(&v);
            super::advise(&v[len.min(3)..]);
            assert_eq!(v, w, "len {len}");
        }
    }
}
