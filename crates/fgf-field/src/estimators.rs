//! Estimators on grid fields: variogram and covariance along an axis, the
//! radially averaged power spectrum, and the variance of line averages along
//! axis-aligned rays. Used by the tests and offered to users.
//!
//! All take C-order data (`shape = [x]`, `[y, x]` or `[z, y, x]`) of f32 or
//! f64. Sums are accumulated in f64 per line and added in line order, so the
//! results are identical for any thread count.

use fgf_core::ParamError;
use rayon::prelude::*;
use rustfft::num_complex::Complex;
use rustfft::FftPlanner;
use std::f64::consts::PI;

/// Most bins [`radial_power_spectrum`] accepts: far more than any field
/// has distinct radii worth averaging, and small enough to allocate.
pub const MAX_BINS: usize = 1 << 20;

fn check(shape: &[usize], len: usize, axis: Option<usize>) -> Result<(), ParamError> {
    if shape.is_empty() || shape.len() > 3 || shape.iter().product::<usize>() != len || len == 0 {
        return Err(ParamError::new(
            "shape",
            format!("{shape:?}"),
            format!("must have 1 to 3 axes whose product is the data length {len}"),
            "1 <= len(shape) <= 3, prod(shape) = len(data)",
        ));
    }
    if let Some(a) = axis {
        if a >= shape.len() {
            return Err(ParamError::new(
                "axis",
                a,
                format!("the field has {} axes", shape.len()),
                format!("0 <= axis < {}", shape.len()),
            ));
        }
    }
    Ok(())
}

/// Start offsets, length and stride of every line along `axis`.
fn lines(shape: &[usize], axis: usize) -> (Vec<usize>, usize, usize) {
    let n = shape[axis];
    let stride: usize = shape[axis + 1..].iter().product();
    let outer: usize = shape[..axis].iter().product();
    let mut starts = Vec::with_capacity(outer * stride);
    for o in 0..outer {
        for i in 0..stride {
            starts.push(o * n * stride + i);
        }
    }
    (starts, n, stride)
}

fn check_lag(max_lag: usize, n: usize) -> Result<(), ParamError> {
    if max_lag >= n {
        return Err(ParamError::new(
            "max_lag",
            max_lag,
            "must be shorter than the axis",
            format!("0 <= max_lag < {n}"),
        ));
    }
    Ok(())
}

/// Sums over pairs `(f(x), f(x+h))` along `axis`, lags `0..=max_lag`, with
/// `pair(a, b)` the summand; returns the per-lag means (non-periodic: only
/// pairs inside the grid).
fn pair_means<T, F>(
    data: &[T],
    shape: &[usize],
    axis: usize,
    max_lag: usize,
    pair: F,
) -> Result<Vec<f64>, ParamError>
where
    T: Copy + Into<f64> + Sync,
    F: Fn(f64, f64) -> f64 + Sync,
{
    check(shape, data.len(), Some(axis))?;
    let (starts, n, stride) = lines(shape, axis);
    check_lag(max_lag, n)?;
    let per_line: Vec<Vec<f64>> = starts
        .par_iter()
        .map(|&s| {
            let line: Vec<f64> = (0..n).map(|i| data[s + i * stride].into()).collect();
            (0..=max_lag)
                .map(|h| (0..n - h).map(|i| pair(line[i], line[i + h])).sum::<f64>())
                .collect()
        })
        .collect();
    let mut sums = vec![0.0; max_lag + 1];
    for l in &per_line {
        for (s, v) in sums.iter_mut().zip(l) {
            *s += v;
        }
    }
    Ok(sums
        .iter()
        .enumerate()
        .map(|(h, s)| s / ((n - h) * starts.len()) as f64)
        .collect())
}

/// Empirical variogram along `axis`: `γ(h) = ½ mean (f(x + h e) - f(x))²`
/// for lags `h = 0..=max_lag` samples (distance `h · spacing`).
pub fn variogram_along_axis<T: Copy + Into<f64> + Sync>(
    data: &[T],
    shape: &[usize],
    axis: usize,
    max_lag: usize,
) -> Result<Vec<f64>, ParamError> {
    pair_means(data, shape, axis, max_lag, |a, b| 0.5 * (b - a) * (b - a))
}

/// Empirical covariance along `axis`: `mean (f(x) - μ)(f(x + h e) - μ)` with
/// `μ` the mean of the whole field, lags `0..=max_lag` samples.
pub fn covariance_along_axis<T: Copy + Into<f64> + Sync>(
    data: &[T],
    shape: &[usize],
    axis: usize,
    max_lag: usize,
) -> Result<Vec<f64>, ParamError> {
    check(shape, data.len(), Some(axis))?;
    let mu = mean(data);
    pair_means(data, shape, axis, max_lag, move |a, b| (a - mu) * (b - mu))
}

fn mean<T: Copy + Into<f64> + Sync>(data: &[T]) -> f64 {
    // Fixed chunking, partial sums added in order: deterministic.
    let parts: Vec<f64> = data
        .par_chunks(1 << 16)
        .map(|c| c.iter().map(|&v| v.into()).sum::<f64>())
        .collect();
    parts.iter().sum::<f64>() / data.len() as f64
}

/// Radially averaged power spectrum (see [`radial_power_spectrum`]).
#[derive(Debug, Clone, PartialEq)]
pub struct RadialSpectrum {
    /// Mean `|k|` of the modes in each bin (rad per scene unit).
    pub k: Vec<f64>,
    /// Mean periodogram in each bin, an unbiased estimate of `P(k)`.
    pub power: Vec<f64>,
    /// Number of modes in each bin (empty bins are left out).
    pub count: Vec<usize>,
}

/// Radially averaged periodogram `I(k) = |FFT(f)_m|² dx^d / N`, whose
/// expectation for a synthesized (periodic, unanchored) field is exactly
/// `P(k) = S_w |k|^(-2s)`. Modes `k ≠ 0` with `|k| <= π/dx` (inside the
/// Nyquist sphere) are grouped into `n_bins` logarithmic bins from the
/// fundamental `2π/(n_max dx)` to `π/dx`.
pub fn radial_power_spectrum<T: Copy + Into<f64> + Sync>(
    data: &[T],
    shape: &[usize],
    spacing: f64,
    n_bins: usize,
) -> Result<RadialSpectrum, ParamError> {
    check(shape, data.len(), None)?;
    ParamError::check_positive("spacing", spacing)?;
    if n_bins == 0 || n_bins > MAX_BINS {
        return Err(ParamError::new(
            "n_bins",
            n_bins,
            "need at least one bin, and no more than MAX_BINS (the bins are allocated up front)",
            format!("1 <= n_bins <= {MAX_BINS}"),
        ));
    }
    let d = shape.len();
    let n_total = data.len();
    let mut spec: Vec<Complex<f64>> = data.iter().map(|&v| Complex::new(v.into(), 0.0)).collect();
    let mut planner = FftPlanner::<f64>::new();
    for axis in 0..d {
        let fft = planner.plan_fft_forward(shape[axis]);
        let (starts, n, stride) = lines(shape, axis);
        let mut line = vec![Complex::new(0.0, 0.0); n];
        for s in starts {
            for i in 0..n {
                line[i] = spec[s + i * stride];
            }
            fft.process(&mut line);
            for i in 0..n {
                spec[s + i * stride] = line[i];
            }
        }
    }
    let nmax = *shape.iter().max().unwrap() as f64;
    let k_lo = 2.0 * PI / (nmax * spacing);
    let k_hi = PI / spacing;
    let (mut ksum, mut psum, mut count) =
        (vec![0.0; n_bins], vec![0.0; n_bins], vec![0usize; n_bins]);
    let norm = spacing.powi(d as i32) / n_total as f64;
    for (flat, v) in spec.iter().enumerate() {
        let mut rem = flat;
        let mut k2 = 0.0;
        for axis in (0..d).rev() {
            let n = shape[axis];
            let i = rem % n;
            rem /= n;
            let m = if i <= n / 2 {
                i as f64
            } else {
                i as f64 - n as f64
            };
            k2 += (2.0 * PI * m / (n as f64 * spacing)).powi(2);
        }
        let k = k2.sqrt();
        if k == 0.0 || k > k_hi * (1.0 + 1e-12) {
            continue;
        }
        // Logarithmic bin; modes below the lowest fundamental of a
        // non-cubic grid land in bin 0.
        let b = if k <= k_lo {
            0
        } else {
            (((k / k_lo).ln() / (k_hi / k_lo).ln() * n_bins as f64) as usize).min(n_bins - 1)
        };
        ksum[b] += k;
        psum[b] += v.norm_sqr() * norm;
        count[b] += 1;
    }
    let mut out = RadialSpectrum {
        k: vec![],
        power: vec![],
        count: vec![],
    };
    for b in 0..n_bins {
        if count[b] > 0 {
            out.k.push(ksum[b] / count[b] as f64);
            out.power.push(psum[b] / count[b] as f64);
            out.count.push(count[b]);
        }
    }
    Ok(out)
}

/// Second moment of line averages along `axis`: for each segment length
/// `L` (in samples) in `lengths`, the mean of `σ̄² = (mean of L consecutive
/// samples)²` over all non-overlapping segments `[jL, (j+1)L)` of every
/// line. Samples are cell averages, so `σ̄` is the line average over length
/// `L · spacing`. This is `var[σ̄]` for a zero-mean field (synthesized
/// fields are: `k = 0` is dropped); subtract the mean first otherwise.
pub fn line_average_second_moment<T: Copy + Into<f64> + Sync>(
    data: &[T],
    shape: &[usize],
    axis: usize,
    lengths: &[usize],
) -> Result<Vec<f64>, ParamError> {
    check(shape, data.len(), Some(axis))?;
    let (starts, n, stride) = lines(shape, axis);
    for &l in lengths {
        if l == 0 || l > n {
            return Err(ParamError::new(
                "length",
                l,
                "segment must fit on the axis",
                format!("1 <= length <= {n}"),
            ));
        }
    }
    let per_line: Vec<Vec<f64>> = starts
        .par_iter()
        .map(|&s| {
            lengths
                .iter()
                .map(|&l| {
                    (0..n / l)
                        .map(|j| {
                            let m = (0..l)
                                .map(|i| data[s + (j * l + i) * stride].into())
                                .sum::<f64>()
                                / l as f64;
                            m * m
                        })
                        .sum::<f64>()
                })
                .collect()
        })
        .collect();
    Ok(lengths
        .iter()
        .enumerate()
        .map(|(i, &l)| per_line.iter().map(|v| v[i]).sum::<f64>() / ((n / l) * starts.len()) as f64)
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn variogram_and_covariance_of_a_ramp() {
        // f(y, x) = x: γ(h) = h²/2 along x, 0 along y.
        let shape = [3, 5];
        let data: Vec<f64> = (0..15).map(|i| (i % 5) as f64).collect();
        let g = variogram_along_axis(&data, &shape, 1, 2).unwrap();
        assert_eq!(g, vec![0.0, 0.5, 2.0]);
        assert_eq!(
            variogram_along_axis(&data, &shape, 0, 2).unwrap(),
            vec![0.0; 3]
        );
        let c = covariance_along_axis(&data, &shape, 1, 0).unwrap();
        assert!((c[0] - 2.0).abs() < 1e-12, "{c:?}"); // variance of 0..4
        assert!(variogram_along_axis(&data, &shape, 2, 1).is_err());
        assert!(variogram_along_axis(&data, &shape, 1, 5).is_err());
    }

    #[test]
    fn periodogram_of_a_single_mode() {
        // f = cos(2π·3x/n): all power at |k| = 2π·3/(n dx), total Σ I·(Δk/2π)
        // equals the variance 1/2 (Parseval).
        let n = 64;
        let dx = 0.5;
        let data: Vec<f64> = (0..n)
            .map(|i| (2.0 * PI * 3.0 * i as f64 / n as f64).cos())
            .collect();
        let s = radial_power_spectrum(&data, &[n], dx, 40).unwrap();
        let (ib, _) = s
            .power
            .iter()
            .enumerate()
            .fold((0, 0.0), |a, (i, &p)| if p > a.1 { (i, p) } else { a });
        assert!((s.k[ib] - 2.0 * PI * 3.0 / (n as f64 * dx)).abs() < 1e-9);
        let total: f64 = s
            .power
            .iter()
            .zip(&s.count)
            .map(|(p, c)| p * *c as f64)
            .sum::<f64>()
            / (n as f64 * dx);
        assert!((total - 0.5).abs() < 1e-9, "{total}");
    }

    #[test]
    fn line_average_of_alternating_signs_vanishes() {
        let data: Vec<f32> = (0..8)
            .map(|i| if i % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        let m = line_average_second_moment(&data, &[8], 0, &[1, 2, 3]).unwrap();
        assert_eq!(m[0], 1.0);
        assert_eq!(m[1], 0.0);
        assert!((m[2] - 1.0 / 9.0).abs() < 1e-12);
    }
}
