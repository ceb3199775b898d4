//! Exact 1D samplers, the ground truth for verification (`docs/theory.md` §1,
//! "Exact 1D samplers").
//!
//! * [`sample_optical_depth`]: the fluctuating optical depth
//!   `τ_u(t) = ∫_0^t σ_u` of white or pink noise along a ray is exactly a
//!   fractional Brownian motion with Hurst `h = H + 1` and
//!   `var τ_u(t) = S_p t^(2h)` (`S_p = S_w` for white noise). Its increments
//!   on a uniform grid (fractional Gaussian noise) are drawn exactly by
//!   circulant embedding (Davies & Harte 1987; Dietrich & Newsam 1997 show the
//!   embedding of fGn is non-negative definite for every `h`), then summed.
//! * [`sample_kfbm_1d`]: the anchored 1D k-fBm (`k-1 < H < k`) at `x_i = i L/n`
//!   by Cholesky factorisation of its covariance
//!   `C(H,1) S_w [|x-y|^(2H) - Σ_{j<k} binom(2H,j) ((-x)^j y^(2H-j) + (-y)^j x^(2H-j))]`
//!   (for `x, y > 0`; the Taylor subtraction of `docs/theory.md` §1 in 1D, whose
//!   diagonal is the point variance `2 C S_w (-1)^k binom(2H-1,k-1) x^(2H)`).
//!   Cost `n³/3` flops and `8 n²` bytes: limited to
//!   [`MAX_CHOLESKY_STEPS`] = 4096 steps (128 MiB, ~10 s on two cores).
//!
//! Each ray (or pair of rays for Davies–Harte, which yields two independent
//! paths per FFT) draws from its own counter-based stream `(seed, index)`:
//! results are identical for any thread count.

use crate::error::{check_memory, FieldError};
use crate::noise::{stream, Purpose};
use fgf_core::stats::{binom, c_const, s_p, Regime};
use fgf_core::{ParamError, Progress};
use rand::Rng;
use rand_distr::StandardNormal;
use rayon::prelude::*;
use rustfft::num_complex::Complex;
use rustfft::FftPlanner;

/// Largest `n_steps` of [`sample_kfbm_1d`] (dense Cholesky: `8 n²` bytes,
/// `n³/3` flops).
pub const MAX_CHOLESKY_STEPS: usize = 4096;

/// Paths sampled on a uniform grid: `values[r * t.len() + i]` is path `r` at
/// `t[i] = i · t_max / n_steps`; column 0 (the start / anchor) is 0.
#[derive(Debug, Clone, PartialEq)]
pub struct Samples1d {
    pub t: Vec<f64>,
    pub n_paths: usize,
    pub values: Vec<f64>,
}

fn check_counts(n_paths: usize, paths_name: &str, n_steps: usize) -> Result<(), ParamError> {
    if n_paths == 0 {
        return Err(ParamError::new(
            paths_name,
            n_paths,
            "need at least one path",
            format!("{paths_name} >= 1"),
        ));
    }
    if n_steps == 0 {
        return Err(ParamError::new(
            "n_steps",
            n_steps,
            "need at least one step",
            "n_steps >= 1",
        ));
    }
    Ok(())
}

fn grid(n_steps: usize, t_max: f64) -> Vec<f64> {
    (0..=n_steps)
        .map(|i| t_max * i as f64 / n_steps as f64)
        .collect()
}

/// Exact optical depth `τ_u(t_i)` of white (`H = -1/2`) or pink
/// (`-1/2 < H < 0`) noise with strength `sw` along `n_rays` independent rays,
/// at `t_i = i · t_max / n_steps`, `i = 0..=n_steps` (Davies–Harte). The line
/// average is `τ_u(t)/t` with variance `S_p t^(2H)`.
pub fn sample_optical_depth(
    n_rays: usize,
    n_steps: usize,
    t_max: f64,
    hurst: f64,
    sw: f64,
    seed: u64,
    progress: &dyn Progress,
) -> Result<Samples1d, FieldError> {
    check_counts(n_rays, "n_rays", n_steps)?;
    ParamError::check_positive("t_max", t_max)?;
    ParamError::check_positive("sw", sw)?;
    match Regime::from_hurst(hurst)? {
        Regime::White | Regime::Pink => {}
        Regime::KFbm { .. } => return Err(ParamError::new(
            "hurst",
            hurst,
            "the optical-depth sampler covers white and pink noise; use sample_kfbm_1d for k-fBm",
            "-0.5 <= hurst < 0",
        )
        .into()),
    }
    let cols = n_steps + 1;
    let m = n_steps;
    let big_m = 2 * m;
    // Output, the eigenvalues and one complex FFT buffer per thread.
    let bytes = (n_rays as u64)
        .checked_mul(cols as u64)
        .and_then(|v| v.checked_add(3 * big_m as u64))
        .and_then(|v| v.checked_mul(8));
    check_memory(&format!("{n_rays} rays of {n_steps} steps"), bytes)?;

    // fGn autocovariance of the increments over dt = t_max/n:
    // γ(j) = var/2 (|j+1|^2h - 2|j|^2h + |j-1|^2h), var = S_p dt^2h.
    let h = hurst + 1.0;
    let dt = t_max / n_steps as f64;
    let var = s_p(hurst, sw) * dt.powf(2.0 * h);
    // For very long or very short steps `dt^(2h)` alone over- or underflows
    // although the paths (which scale as `dt^h`, self-similarity) do not:
    // then build the unit-step paths and scale them by `dt^h`.
    let (var, path_scale) = if var.is_normal() {
        (var, 1.0)
    } else {
        (s_p(hurst, sw), dt.powf(h))
    };
    let gamma = |j: usize| {
        let j = j as f64;
        0.5 * var
            * ((j + 1.0).powf(2.0 * h) - 2.0 * j.powf(2.0 * h) + (j - 1.0).abs().powf(2.0 * h))
    };
    // Circulant embedding c = [γ0..γm, γ(m-1)..γ1] of size 2m; its DFT gives
    // the eigenvalues, real since c is symmetric.
    let mut c: Vec<Complex<f64>> = (0..big_m)
        .map(|i| Complex::new(gamma(if i <= m { i } else { big_m - i }), 0.0))
        .collect();
    let mut planner = FftPlanner::<f64>::new();
    let fft = planner.plan_fft_forward(big_m);
    fft.process(&mut c);
    let lmax = c.iter().map(|v| v.re).fold(0.0, f64::max);
    // Round-off can make eigenvalues that are mathematically >= 0 slightly
    // negative; anything below -1e-10 of the largest would be a bug.
    if let Some(bad) = c.iter().find(|v| v.re < -1e-10 * lmax) {
        return Err(ParamError::new(
            "hurst",
            hurst,
            format!(
                "circulant embedding not non-negative (eigenvalue {})",
                bad.re
            ),
            "-0.5 <= hurst < 0",
        )
        .into());
    }
    let sqrt_lambda: Vec<f64> = c
        .iter()
        .map(|v| (v.re.max(0.0) / big_m as f64).sqrt() * path_scale)
        .collect();

    let mut values = vec![0.0f64; n_rays * cols];
    values.par_chunks_mut(2 * cols).enumerate().for_each_init(
        || {
            (
                vec![Complex::new(0.0, 0.0); big_m],
                vec![Complex::new(0.0, 0.0); fft.get_inplace_scratch_len()],
            )
        },
        |(buf, scr), (pair, out)| {
            if progress.cancelled() {
                return;
            }
            let mut rng = stream(seed, Purpose::DaviesHarte, pair as u64);
            for (b, &s) in buf.iter_mut().zip(&sqrt_lambda) {
                *b = Complex::new(
                    rng.sample::<f64, _>(StandardNormal),
                    rng.sample::<f64, _>(StandardNormal),
                ) * s;
            }
            fft.process_with_scratch(buf, scr);
            // Real and imaginary parts are two independent fGn paths.
            let (first, second) = out.split_at_mut(cols);
            let mut acc = 0.0;
            for i in 0..m {
                acc += buf[i].re;
                first[i + 1] = acc;
            }
            if !second.is_empty() {
                let mut acc = 0.0;
                for i in 0..m {
                    acc += buf[i].im;
                    second[i + 1] = acc;
                }
            }
            progress.inc(1);
        },
    );
    progress.check_cancelled()?;
    if let Some(v) = values.iter().find(|v| !v.is_finite()) {
        return Err(ParamError::new(
            "t_max",
            t_max,
            format!("the optical depth overflows double precision ({v}) with sw = {sw}; use a shorter t_max or a smaller sw"),
            "tau_u(t_max) within the double range",
        )
        .into());
    }
    Ok(Samples1d {
        t: grid(n_steps, t_max),
        n_paths: n_rays,
        values,
    })
}

/// Covariance of the 1D k-fBm anchored at 0, at `x, y > 0` (see module docs).
pub fn kfbm_covariance_1d(hurst: f64, sw: f64, x: f64, y: f64) -> f64 {
    let k = hurst.ceil() as u32;
    let a = 2.0 * hurst;
    let mut v = (x - y).abs().powf(a);
    for j in 0..k {
        let b = binom(a, j);
        v -= b
            * ((-x).powi(j as i32) * y.powf(a - j as f64)
                + (-y).powi(j as i32) * x.powf(a - j as f64));
    }
    c_const(hurst, 1) * sw * v
}

/// Exact anchored 1D k-fBm (`k-1 < H < k`, `k = 1, 2, 3, ...`) with strength
/// `sw` at `x_i = i · length / n_steps`, `i = 0..=n_steps` (`x_0` is the
/// anchor, value 0), `n_samples` independent paths, by Cholesky.
///
/// On fine grids the covariance of a smooth (k ≥ 2) field is numerically
/// singular; pivots below `1e-13` of their diagonal entry are treated as 0,
/// which makes that sample a deterministic function of the earlier ones to
/// that relative accuracy.
pub fn sample_kfbm_1d(
    n_samples: usize,
    n_steps: usize,
    length: f64,
    hurst: f64,
    sw: f64,
    seed: u64,
    progress: &dyn Progress,
) -> Result<Samples1d, FieldError> {
    check_counts(n_samples, "n_samples", n_steps)?;
    ParamError::check_positive("length", length)?;
    ParamError::check_positive("sw", sw)?;
    if !matches!(Regime::from_hurst(hurst)?, Regime::KFbm { .. }) {
        return Err(ParamError::new(
            "hurst",
            hurst,
            "the Cholesky sampler is for anchored k-fBm; use sample_optical_depth for white/pink noise",
            "0 < hurst, non-integer",
        )
        .into());
    }
    if n_steps > MAX_CHOLESKY_STEPS {
        return Err(ParamError::new(
            "n_steps",
            n_steps,
            "dense Cholesky is O(n³) in time and O(n²) in memory",
            format!("1 <= n_steps <= {MAX_CHOLESKY_STEPS}"),
        )
        .into());
    }
    let n = n_steps;
    let cols = n + 1;
    let bytes = (n_samples as u64)
        .checked_mul(cols as u64)
        .and_then(|v| v.checked_add((n * n) as u64))
        .and_then(|v| v.checked_mul(8));
    check_memory(
        &format!("{n_samples} k-fBm paths of {n_steps} steps"),
        bytes,
    )?;
    let x: Vec<f64> = (1..=n).map(|i| length * i as f64 / n as f64).collect();

    // Lower factor, row-major; column-by-column (Cholesky–Crout) with the
    // rows below the pivot in parallel: each entry is one sequential dot
    // product, so the factor does not depend on the thread count.
    let mut l = vec![0.0f64; n * n];
    for j in 0..n {
        let (row_j, below) = l[j * n..].split_at_mut(n);
        let ajj = kfbm_covariance_1d(hurst, sw, x[j], x[j]);
        let d = ajj - row_j[..j].iter().map(|v| v * v).sum::<f64>();
        // Semidefinite pivot: see the function docs.
        let ljj = if d > 1e-13 * ajj { d.sqrt() } else { 0.0 };
        row_j[j] = ljj;
        let row_j: &[f64] = row_j;
        below
            .par_chunks_mut(n)
            .enumerate()
            .for_each(|(off, row_i)| {
                let i = j + 1 + off;
                row_i[j] = if ljj > 0.0 {
                    let dot: f64 = row_i[..j].iter().zip(&row_j[..j]).map(|(a, b)| a * b).sum();
                    (kfbm_covariance_1d(hurst, sw, x[i], x[j]) - dot) / ljj
                } else {
                    0.0
                };
            });
        progress.check_cancelled()?;
    }
    let mut values = vec![0.0f64; n_samples * cols];
    values.par_chunks_mut(cols).enumerate().for_each_init(
        || vec![0.0f64; n],
        |z, (s, out)| {
            if progress.cancelled() {
                return;
            }
            let mut rng = stream(seed, Purpose::Cholesky, s as u64);
            for v in z.iter_mut() {
                *v = rng.sample(StandardNormal);
            }
            for i in 0..n {
                out[i + 1] = l[i * n..i * n + i + 1]
                    .iter()
                    .zip(&z[..i + 1])
                    .map(|(a, b)| a * b)
                    .sum();
            }
            progress.inc(1);
        },
    );
    progress.check_cancelled()?;
    Ok(Samples1d {
        t: grid(n_steps, length),
        n_paths: n_samples,
        values,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use fgf_core::stats::kfbm_point_variance;
    use fgf_core::NoProgress;

    #[test]
    fn kfbm_covariance_diagonal_is_the_point_variance() {
        for h in [0.3, 0.8, 1.2, 1.7, 2.4, 2.9] {
            for x in [0.1, 1.0, 3.5] {
                let a = kfbm_covariance_1d(h, 2.0, x, x);
                let b = kfbm_point_variance(h, 2.0, x);
                assert!((a - b).abs() < 1e-9 * b, "H={h} x={x}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn one_fbm_covariance_is_levy() {
        // k = 1: C S_w (|x-y|^2H - |x|^2H - |y|^2H).
        let (h, x, y) = (0.35f64, 0.7f64, 1.9f64);
        let c = c_const(h, 1);
        let want = c * ((x - y).abs().powf(2.0 * h) - x.powf(2.0 * h) - y.powf(2.0 * h));
        assert!((kfbm_covariance_1d(h, 1.0, x, y) - want).abs() < 1e-14);
    }

    #[test]
    fn samplers_are_deterministic_anchored_and_thread_independent() {
        let a = sample_optical_depth(5, 37, 2.0, -0.3, 0.7, 4, &NoProgress).unwrap();
        assert_eq!(a.values.len(), 5 * 38);
        assert!(a.values.chunks(38).all(|r| r[0] == 0.0));
        let k = sample_kfbm_1d(3, 50, 1.5, 1.4, 1.0, 4, &NoProgress).unwrap();
        assert!(k.values.chunks(51).all(|r| r[0] == 0.0));
        for t in [1, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .unwrap();
            let b = pool
                .install(|| sample_optical_depth(5, 37, 2.0, -0.3, 0.7, 4, &NoProgress).unwrap());
            let c = pool.install(|| sample_kfbm_1d(3, 50, 1.5, 1.4, 1.0, 4, &NoProgress).unwrap());
            assert_eq!(a, b);
            assert_eq!(k, c);
        }
    }

    #[test]
    fn samplers_reject_the_other_regime() {
        assert!(sample_optical_depth(1, 4, 1.0, 0.5, 1.0, 0, &NoProgress)
            .unwrap_err()
            .to_string()
            .contains("sample_kfbm_1d"));
        assert!(sample_kfbm_1d(1, 4, 1.0, -0.3, 1.0, 0, &NoProgress)
            .unwrap_err()
            .to_string()
            .contains("sample_optical_depth"));
        assert!(sample_kfbm_1d(1, 5000, 1.0, 0.3, 1.0, 0, &NoProgress)
            .unwrap_err()
            .to_string()
            .contains("n_steps"));
        assert!(sample_optical_depth(0, 4, 1.0, -0.2, 1.0, 0, &NoProgress).is_err());
        assert!(sample_optical_depth(1, 4, 1.0, -0.7, 1.0, 0, &NoProgress).is_err());
    }

    /// Ensemble check (slow): var τ(t)/t² = S_p t^(2H) and var M~(x) = point
    /// variance, within z = 4 standard errors (chi-square SE of a variance,
    /// sqrt(2/M)·var for Gaussian samples); 12 comparisons, family error rate
    /// < 1e-3.
    #[test]
    #[ignore]
    fn ensemble_variances_match_theory() {
        let m = 20000;
        let z = 4.0;
        let s = sample_optical_depth(m, 256, 4.0, -0.3, 0.5, 1, &NoProgress).unwrap();
        for i in [1usize, 16, 128, 256] {
            let t = s.t[i];
            let est = (0..m)
                .map(|r| (s.values[r * 257 + i] / t).powi(2))
                .sum::<f64>()
                / m as f64;
            let want = fgf_core::stats::line_average_variance(-0.3, 0.5, t, None).unwrap();
            assert!(
                (est - want).abs() < z * want * (2.0 / m as f64).sqrt(),
                "t={t}: {est} vs {want}"
            );
        }
        for h in [0.6, 1.5] {
            let k = sample_kfbm_1d(m, 128, 2.0, h, 1.3, 2, &NoProgress).unwrap();
            for i in [1usize, 32, 64, 128] {
                let est = (0..m).map(|r| k.values[r * 129 + i].powi(2)).sum::<f64>() / m as f64;
                let want = kfbm_point_variance(h, 1.3, k.t[i]);
                assert!(
                    (est - want).abs() < z * want * (2.0 / m as f64).sqrt(),
                    "H={h} x={}: {est} vs {want}",
                    k.t[i]
                );
            }
        }
    }
}
