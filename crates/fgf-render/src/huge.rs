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
        const HUGE: usize = 1 << 21;
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

/// Arrays below this many bytes (64 pages of 4 KiB) are left as they are.
const MIN_BYTES: usize = 256 * 1024;

#[cfg(test)]
mod tests {
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
