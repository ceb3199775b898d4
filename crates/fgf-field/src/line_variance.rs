//! The exact line-average variance of a synthesized grid field, by its
//! discrete spectral sum (`docs/theory.md` §1.4, §1.8).
//!
//! A field of [`synthesize`](crate::synthesize) is periodic on its padded
//! domain and stationary there (unanchored). Its covariance between two
//! samples `j` voxels apart along x is the spectral sum
//!
//! ```text
//! c(j) = (S_w/dx^d) (1/N) Σ_{m ≠ 0} |k_m|^(-2s) cos(k_x,m j dx)
//! ```
//!
//! over every mode of the padded domain (Nyquist modes dropped for k-fBm,
//! as the synthesis does). A renderer that looks the grid up with nearest
//! filtering sees a piecewise-constant field, so the average of the
//! extinction over `m` whole voxels along x is the mean of `m` consecutive
//! samples, whose variance is
//!
//! ```text
//! var(m) = (1/m²) [ m c(0) + 2 Σ_{j=1}^{m-1} (m - j) c(j) ].
//! ```
//!
//! The sum over `k_y, k_z` is done once per `k_x` on the sorted, merged set
//! of distinct `k_y² + k_z²` (cubic domains have few), so a 256³ domain
//! costs about a million powers.

use crate::synth::{padded_shape, SynthParams};
use fgf_core::ParamError;
use rayon::prelude::*;
use std::f64::consts::PI;

/// Squared wavenumbers of one axis of `n` samples (RustFFT order, signed
/// index folded) and whether each mode is kept.
fn axis_k2(n: usize, dx: f64, drop_nyquist: bool) -> Vec<(f64, bool)> {
    (0..n)
        .map(|i| {
            let m = if i <= n / 2 { i } else { n - i };
            let keep = !(drop_nyquist && n % 2 == 0 && n > 1 && i == n / 2);
            ((2.0 * PI * m as f64 / (n as f64 * dx)).powi(2), keep)
        })
        .collect()
}

/// Covariance `c(j)`, `j = 0 … shape_x - 1`, between samples `j` voxels
/// apart along x (the last axis) of the field `params` describes, as if it
/// were not anchored (exact for pink and white noise; for a k-fBm it is the
/// covariance of the periodic field before the Taylor subtraction). `c(0)`
/// equals [`discrete_spectral_variance`](crate::discrete_spectral_variance).
pub fn axis_covariance(params: &SynthParams) -> Result<Vec<f64>, ParamError> {
    let pad = padded_shape(params)?;
    let d = pad.len();
    let dx = params.spacing;
    let s = params.hurst + d as f64 / 2.0;
    let drop_nyquist = params.hurst > 0.0;
    let nx = pad[d - 1];
    let n_total: f64 = pad.iter().map(|&n| n as f64).product();
    // Distinct k_⊥² with multiplicities.
    let mut perp: Vec<f64> = vec![0.0];
    for &n in &pad[..d - 1] {
        let ax = axis_k2(n, dx, drop_nyquist);
        let mut next = Vec::with_capacity(perp.len() * n);
        for &q in &perp {
            for &(k2, keep) in &ax {
                if keep {
                    next.push(q + k2);
                }
            }
        }
        perp = next;
    }
    perp.sort_by(f64::total_cmp);
    let mut groups: Vec<(f64, f64)> = Vec::new();
    for q in perp {
        match groups.last_mut() {
            Some((v, c)) if *v == q => *c += 1.0,
            _ => groups.push((q, 1.0)),
        }
    }
    let xs = axis_k2(nx, dx, drop_nyquist);
    // Full x spectrum as the half spectrum with weights 1 (0, Nyquist) or 2.
    let half: Vec<(usize, f64)> = (0..=nx / 2)
        .filter(|&i| xs[i].1)
        .map(|i| {
            (
                i,
                if i == 0 || (nx % 2 == 0 && i == nx / 2) {
                    1.0
                } else {
                    2.0
                },
            )
        })
        .collect();
    let spec: Vec<f64> = half
        .par_iter()
        .map(|&(i, w)| {
            let kx2 = xs[i].0;
            let mut acc = 0.0;
            for &(q, c) in &groups {
                let k2 = kx2 + q;
                if k2 > 0.0 {
                    acc += c * k2.powf(-s);
                }
            }
            w * acc
        })
        .collect();
    let scale = params.sw / dx.powi(d as i32) / n_total;
    let n_out = *params.shape.last().unwrap_or(&1);
    Ok((0..n_out)
        .map(|j| {
            let mut acc = 0.0;
            for (&(i, _), &p) in half.iter().zip(&spec) {
                acc += p * (2.0 * PI * (i * j % nx) as f64 / nx as f64).cos();
            }
            scale * acc
        })
        .collect())
}

/// Variance of the mean of `m` consecutive samples of a stationary sequence
/// with covariance `cov` (`1 <= m <= cov.len()`).
pub fn segment_variance(cov: &[f64], m: usize) -> f64 {
    assert!(
        m >= 1 && m <= cov.len(),
        "segment of {m} samples on {}",
        cov.len()
    );
    let mut acc = m as f64 * cov[0];
    for (j, &c) in cov.iter().enumerate().take(m).skip(1) {
        acc += 2.0 * (m - j) as f64 * c;
    }
    acc / (m * m) as f64
}

/// Segment lengths (in voxels) of the comparisons: about `count` integers
/// spaced evenly in `ln m` from 1 to `n` (duplicates merged).
pub fn log_lengths(n: usize, count: usize) -> Vec<usize> {
    let n = n.max(1);
    let count = count.max(2);
    let mut v: Vec<usize> = (0..count)
        .map(|i| ((n as f64).powf(i as f64 / (count - 1) as f64)).round() as usize)
        .map(|m| m.clamp(1, n))
        .collect();
    v.dedup();
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{discrete_spectral_variance, synthesize};

    #[test]
    fn lag_zero_is_the_discrete_spectral_variance() {
        for (shape, h, pad) in [
            (vec![12, 10, 16], -0.3, 2.0),
            (vec![16, 16, 16], -0.1, 4.0),
            (vec![24, 20], -0.6, 1.0),
        ] {
            let mut p = SynthParams::new(&shape, h);
            p.spacing = 0.1;
            p.sw = 2.5;
            p.padding = Some(pad);
            let c = axis_covariance(&p).unwrap();
            let v = discrete_spectral_variance(&p).unwrap();
            assert!((c[0] - v).abs() < 1e-10 * v, "{shape:?}: {} vs {v}", c[0]);
            assert_eq!(c.len(), *shape.last().unwrap());
        }
    }

    /// The spectral sum against a direct Monte Carlo estimate of the
    /// line-average variance on small padded pink grids: 200 fields of
    /// 16³ (padded 4× to 64³), all x-lines and disjoint segments. The
    /// segments of one field are correlated, so the standard error comes
    /// from the spread of the per-field estimates; tolerance 4.5 SE.
    #[test]
    fn spectral_sum_matches_monte_carlo() {
        let mut p = SynthParams::new(&[16, 16, 16], -0.2);
        p.spacing = 1.0 / 16.0;
        p.padding = Some(4.0);
        let cov = axis_covariance(&p).unwrap();
        let lengths = [1usize, 2, 4, 8, 16];
        let fields = 200;
        let mut per: Vec<Vec<f64>> = vec![Vec::new(); lengths.len()];
        for r in 0..fields {
            p.seed = 1000 + r;
            let f = synthesize(&p, &fgf_core::NoProgress).unwrap();
            let u = f.data.to_f32();
            let lv =
                crate::estimators::line_average_second_moment(&u, &p.shape, 2, &lengths).unwrap();
            for (k, v) in lv.into_iter().enumerate() {
                per[k].push(v);
            }
        }
        for (k, &m) in lengths.iter().enumerate() {
            let n = per[k].len() as f64;
            let mean = per[k].iter().sum::<f64>() / n;
            let var = per[k].iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
            let se = (var / n).sqrt();
            let want = segment_variance(&cov, m);
            assert!(
                (mean - want).abs() < 4.5 * se,
                "m = {m}: MC {mean} ± {se} vs spectral sum {want}"
            );
        }
    }

    #[test]
    fn log_lengths_span_the_axis() {
        let v = log_lengths(64, 12);
        assert_eq!(v[0], 1);
        assert_eq!(*v.last().unwrap(), 64);
        assert!(v.windows(2).all(|w| w[0] < w[1]));
    }
}
