//! The FFT pipeline of [`synthesize`](super::synthesize) (steps 1-4 of the
//! module docs): noise and the forward transforms, the filter and the
//! Taylor sums per y-plane, the inverse transforms with cropping, all in
//! one buffer holding the half spectrum.

use super::anchor::{Poly, Taylor};
use super::filter::Filter;
use super::plan::{Plan, B};
use super::Real;
use crate::error::FieldError;
use crate::noise::{stream, Purpose};
use fgf_core::Progress;
use rand::Rng;
use rand_distr::StandardNormal;
use rayon::prelude::*;
use realfft::RealFftPlanner;
use rustfft::num_complex::Complex;
use rustfft::num_traits::Zero;
use rustfft::{Fft, FftPlanner};
use std::sync::Arc;

/// A raw pointer shared by parallel jobs that touch disjoint elements.
#[derive(Clone, Copy)]
struct SyncPtr<T>(*mut T);
unsafe impl<T> Send for SyncPtr<T> {}
unsafe impl<T> Sync for SyncPtr<T> {}
impl<T: Copy> SyncPtr<T> {
    /// Copy a block of `bw` columns of `n` strided rows, elements
    /// `first + r·stride + j` (`r < n`, `j < bw`), into `tmp[j·n + r]`: each
    /// column becomes a contiguous line for the FFT.
    ///
    /// # Safety
    /// The elements lie inside the buffer and belong to the calling job
    /// (no other thread touches them meanwhile).
    #[inline]
    unsafe fn gather(self, first: usize, stride: usize, n: usize, bw: usize, tmp: &mut [T]) {
        for r in 0..n {
            let src = std::slice::from_raw_parts(self.0.add(first + r * stride), bw);
            for (j, v) in src.iter().enumerate() {
                tmp[j * n + r] = *v;
            }
        }
    }

    /// The inverse of [`SyncPtr::gather`]: `tmp[j·n + r]` back to element
    /// `first + r·stride + j`.
    ///
    /// # Safety
    /// As for [`SyncPtr::gather`].
    #[inline]
    unsafe fn scatter(self, first: usize, stride: usize, n: usize, bw: usize, tmp: &[T]) {
        for r in 0..n {
            let dst = std::slice::from_raw_parts_mut(self.0.add(first + r * stride), bw);
            for (j, v) in dst.iter_mut().enumerate() {
                *v = tmp[j * n + r];
            }
        }
    }
}

/// View a row of `2m` reals as `m` complex numbers (`Complex` is `repr(C)`).
fn as_complex_mut<T>(row: &mut [T]) -> &mut [Complex<T>] {
    debug_assert!(row.len() % 2 == 0);
    // SAFETY: Complex<T> is repr(C) { re: T, im: T }: same alignment as T,
    // size 2·size_of::<T>(); the length is halved.
    unsafe { std::slice::from_raw_parts_mut(row.as_mut_ptr() as *mut Complex<T>, row.len() / 2) }
}

/// FFT along y of the columns `x0..x0+B` (or to the end of the row) of the
/// z-slab that starts at element `slab_first` (`n1` rows of `nxh` complex),
/// through `tmp`.
///
/// # Safety
/// As for [`SyncPtr::gather`]: the block belongs to the calling job.
#[allow(clippy::too_many_arguments)]
unsafe fn y_fft_block<T: Real>(
    spec: SyncPtr<Complex<T>>,
    slab_first: usize,
    n1: usize,
    nxh: usize,
    x0: usize,
    fft: &Arc<dyn Fft<T>>,
    tmp: &mut [Complex<T>],
    scr: &mut [Complex<T>],
) {
    let bw = B.min(nxh - x0);
    spec.gather(slab_first + x0, nxh, n1, bw, tmp);
    fft.process_with_scratch(&mut tmp[..bw * n1], scr);
    spec.scatter(slab_first + x0, nxh, n1, bw, tmp);
}

/// FFT along y of one contiguous z-slab (`n1` rows of `nxh` complex), in
/// blocks of `B` columns.
fn y_fft_slab<T: Real>(
    slab: &mut [Complex<T>],
    n1: usize,
    nxh: usize,
    fft: &Arc<dyn Fft<T>>,
    tmp: &mut [Complex<T>],
    scr: &mut [Complex<T>],
) {
    assert!(slab.len() >= n1 * nxh);
    let spec = SyncPtr(slab.as_mut_ptr());
    for x0 in (0..nxh).step_by(B) {
        // SAFETY: `slab` is borrowed mutably and holds the n1 rows.
        unsafe { y_fft_block(spec, 0, n1, nxh, x0, fft, tmp, scr) };
    }
}

/// Slab-fused passes (noise + x + y in one z-slab while it is in cache) are
/// used when there are enough slabs to keep every thread busy.
fn fuse_slabs(n0: usize) -> bool {
    n0 >= 4 * rayon::current_num_threads()
}

/// FFT along y of every (z, x-block) of slabs `0..nz`, in place.
fn y_pass<T: Real>(
    spec: SyncPtr<Complex<T>>,
    dims: [usize; 3],
    nz: usize,
    fft: &Arc<dyn Fft<T>>,
    progress: &dyn Progress,
) {
    let [_, n1, n2] = dims;
    let nxh = n2 / 2 + 1;
    let nblk = nxh.div_ceil(B);
    (0..nz * nblk).into_par_iter().for_each_init(
        || {
            (
                vec![Complex::<T>::zero(); B * n1],
                vec![Complex::<T>::zero(); fft.get_inplace_scratch_len()],
            )
        },
        |(tmp, scr), job| {
            if progress.cancelled() {
                return;
            }
            let (z, x0) = (job / nblk, (job % nblk) * B);
            // SAFETY: job (z, block) owns elements [z][*][x0..x0+B].
            unsafe { y_fft_block(spec, z * n1 * nxh, n1, nxh, x0, fft, tmp, scr) };
            progress.inc(1);
        },
    );
}

pub(super) fn run<T: Real>(
    plan: &Plan,
    seed: u64,
    progress: &dyn Progress,
) -> Result<Vec<T>, FieldError> {
    let [n0, n1, n2] = plan.pad;
    let nxh = n2 / 2 + 1;
    let row_len = 2 * nxh;
    let mut buf: Vec<T> = vec![T::zero(); n0 * n1 * row_len];
    let mut rplanner = RealFftPlanner::<T>::new();
    let r2c = rplanner.plan_fft_forward(n2);
    let c2r = rplanner.plan_fft_inverse(n2);
    let mut planner = FftPlanner::<T>::new();
    let (fy, iy) = (planner.plan_fft_forward(n1), planner.plan_fft_inverse(n1));
    let (fz, iz) = (planner.plan_fft_forward(n0), planner.plan_fft_inverse(n0));

    // 1. Noise and real-to-complex FFT along x, row by row; 2. FFT along y.
    // With many z-slabs both run per slab while it is in cache.
    let noise_row = |inp: &mut [T], r: usize| {
        let mut rng = stream(seed, Purpose::GridRow, r as u64);
        for v in inp.iter_mut() {
            *v = T::of(rng.sample::<f64, _>(StandardNormal));
        }
    };
    let nblk = nxh.div_ceil(B);
    if n1 > 1 && fuse_slabs(n0) {
        buf.par_chunks_mut(n1 * row_len).enumerate().for_each_init(
            || {
                (
                    r2c.make_input_vec(),
                    r2c.make_scratch_vec(),
                    vec![Complex::<T>::zero(); B * n1],
                    vec![Complex::<T>::zero(); fy.get_inplace_scratch_len()],
                )
            },
            |(inp, rscr, tmp, yscr), (z, slab)| {
                if progress.cancelled() {
                    return;
                }
                for (y, row) in slab.chunks_mut(row_len).enumerate() {
                    noise_row(inp, z * n1 + y);
                    r2c.process_with_scratch(inp, as_complex_mut(row), rscr)
                        .expect("FFT lengths match");
                }
                y_fft_slab(as_complex_mut(slab), n1, nxh, &fy, tmp, yscr);
                progress.inc((n1 + nblk) as u64);
            },
        );
        progress.check_cancelled()?;
    } else {
        buf.par_chunks_mut(row_len).enumerate().for_each_init(
            || (r2c.make_input_vec(), r2c.make_scratch_vec()),
            |(inp, scr), (r, row)| {
                if progress.cancelled() {
                    return;
                }
                noise_row(inp, r);
                r2c.process_with_scratch(inp, as_complex_mut(row), scr)
                    .expect("FFT lengths match");
                progress.inc(1);
            },
        );
        progress.check_cancelled()?;
        if n1 > 1 {
            y_pass(
                SyncPtr(buf.as_mut_ptr() as *mut Complex<T>),
                plan.pad,
                n0,
                &fy,
                progress,
            );
            progress.check_cancelled()?;
        }
    }
    let spec = SyncPtr(buf.as_mut_ptr() as *mut Complex<T>);

    // 3. Per y-plane: FFT along z, filter (and Taylor sums), inverse FFT along z.
    let filter = Filter::new(plan);
    let taylor = plan.anchor.map(|a| Taylor::new(plan, a));
    let n_terms = plan.terms.len();
    let kz_orders = taylor.as_ref().map_or(0, |t| t.kz_orders());
    let sums: Vec<Vec<f64>> = (0..n1)
        .into_par_iter()
        .map_init(
            || {
                let scr = fz
                    .get_inplace_scratch_len()
                    .max(iz.get_inplace_scratch_len());
                (
                    vec![Complex::<T>::zero(); B * n0],
                    vec![Complex::<T>::zero(); scr],
                )
            },
            |(tmp, scr), y| {
                let mut acc = vec![0.0f64; n_terms];
                if progress.cancelled() {
                    return acc;
                }
                for blk in 0..nblk {
                    let x0 = blk * B;
                    let bw = B.min(nxh - x0);
                    // SAFETY: job y owns elements [*][y][*].
                    unsafe { spec.gather(y * nxh + x0, n1 * nxh, n0, bw, tmp) };
                    if n0 > 1 {
                        fz.process_with_scratch(&mut tmp[..bw * n0], scr);
                    }
                    for j in 0..bw {
                        let ix = x0 + j;
                        let line = &mut tmp[j * n0..(j + 1) * n0];
                        for (z, v) in line.iter_mut().enumerate() {
                            *v = *v * T::of(filter.at(z, y, ix));
                        }
                        if let Some(t) = &taylor {
                            let mut sums = [Complex::new(0.0f64, 0.0); 3];
                            for (z, v) in line.iter().enumerate() {
                                let f = Complex::new(v.re.as_f64(), v.im.as_f64()) * t.phase[0][z];
                                let kz = t.k[0][z];
                                sums[0] += f;
                                if kz_orders > 1 {
                                    sums[1] += f * kz;
                                }
                                if kz_orders > 2 {
                                    sums[2] += f * (kz * kz);
                                }
                            }
                            t.add_line(&mut acc, &sums, y, ix);
                        }
                    }
                    if n0 > 1 {
                        iz.process_with_scratch(&mut tmp[..bw * n0], scr);
                    }
                    unsafe { spec.scatter(y * nxh + x0, n1 * nxh, n0, bw, tmp) };
                }
                progress.inc(1);
                acc
            },
        )
        .collect();
    progress.check_cancelled()?;
    // Fixed-order reduction over planes: thread-count independent.
    let poly = plan.anchor.map(|a| {
        let mut d = vec![0.0f64; n_terms];
        for s in &sums {
            for (di, si) in d.iter_mut().zip(s) {
                *di += si;
            }
        }
        Poly {
            terms: plan.terms.iter().copied().zip(d).collect(),
            a,
            dx: plan.dx,
        }
    });

    // 4. Inverse FFT along y (only the slabs that are kept), then
    //    complex-to-real along x with cropping and the Taylor subtraction;
    //    slab-fused like steps 1-2 when there are enough slabs.
    let [o0, o1, o2] = plan.out;
    let fused = n1 > 1 && fuse_slabs(o0);
    if n1 > 1 && !fused {
        y_pass(spec, plan.pad, o0, &iy, progress);
        progress.check_cancelled()?;
    }
    let finish_row = |c: &mut [Complex<T>],
                      o: &mut [T],
                      scr: &mut [Complex<T>],
                      dst: &mut [T],
                      z: usize,
                      y: usize| {
        // The imaginary parts of the x = 0 and Nyquist bins are zero up to
        // rounding (Hermitian symmetry); realfft wants them exactly zero.
        c[0].im = T::zero();
        if n2 % 2 == 0 {
            c[nxh - 1].im = T::zero();
        }
        c2r.process_with_scratch(c, o, scr)
            .expect("FFT lengths match");
        match &poly {
            Some(p) => {
                for (x, v) in dst.iter_mut().enumerate() {
                    *v = T::of(o[x].as_f64() - p.at(z, y, x));
                }
            }
            None => dst.copy_from_slice(&o[..dst.len()]),
        }
    };
    let y_init = || {
        (
            vec![Complex::<T>::zero(); B * n1],
            vec![Complex::<T>::zero(); iy.get_inplace_scratch_len()],
        )
    };
    // Each kept row's values go to its own first o2 reals; the rows are then
    // compacted to the front of the buffer, so the output never needs a
    // second allocation, with or without padding.
    if fused {
        buf.par_chunks_mut(n1 * row_len)
            .take(o0)
            .enumerate()
            .for_each_init(
                || {
                    (
                        c2r.make_output_vec(),
                        c2r.make_scratch_vec(),
                        vec![Complex::<T>::zero(); nxh],
                        y_init(),
                    )
                },
                |(o, scr, c, (tmp, yscr)), (z, slab)| {
                    if progress.cancelled() {
                        return;
                    }
                    y_fft_slab(as_complex_mut(slab), n1, nxh, &iy, tmp, yscr);
                    for (y, row) in slab.chunks_mut(row_len).take(o1).enumerate() {
                        c.copy_from_slice(as_complex_mut(row));
                        finish_row(c, o, scr, &mut row[..o2], z, y);
                    }
                    progress.inc((nblk + o1) as u64);
                },
            );
    } else {
        buf.par_chunks_mut(row_len).enumerate().for_each_init(
            || {
                (
                    c2r.make_output_vec(),
                    c2r.make_scratch_vec(),
                    vec![Complex::<T>::zero(); nxh],
                )
            },
            |(o, scr, c), (r, row)| {
                let (z, y) = (r / n1, r % n1);
                if z >= o0 || y >= o1 || progress.cancelled() {
                    return;
                }
                c.copy_from_slice(as_complex_mut(row));
                finish_row(c, o, scr, &mut row[..o2], z, y);
                progress.inc(1);
            },
        );
    }
    progress.check_cancelled()?;
    // Front to back, each row moves to a lower or equal offset
    // ((z·o1 + y)·o2 <= (z·n1 + y)·row_len), so nothing unread is overwritten.
    for z in 0..o0 {
        for y in 0..o1 {
            let (src, dst) = ((z * n1 + y) * row_len, (z * o1 + y) * o2);
            if src != dst {
                buf.copy_within(src..src + o2, dst);
            }
        }
    }
    buf.truncate(o0 * o1 * o2);
    buf.shrink_to_fit();
    Ok(buf)
}
