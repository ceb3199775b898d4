//! Non-negative fields with gamma marginals from a Gaussian field (a
//! Gaussian copula), and the calibration that makes their line-average
//! variance follow the rendering model's (`docs/theory.md` §1.8).
//!
//! A unit-variance Gaussian field `Z` is mapped voxel by voxel to
//! `X = G_α⁻¹(Φ(Z))`, `G_α` the gamma distribution of shape `α` and mean 1.
//! Each voxel of a spectrally synthesized field is exactly Gaussian, so `X`
//! has exactly that marginal. Two voxels whose `Z` have correlation `r`
//! have `cov(X, X') = T(r) = Σ_{n≥1} c_n² r^n` with the Hermite coefficients
//! `c_n = E[X h_n(Z)]` (`h_n` the orthonormal Hermite polynomials, Mehler's
//! expansion), so the line-average variance of `X` follows from the
//! Gaussian field's exact axis covariance ([`axis_covariance`]).
//!
//! [`calibrate_gamma`] chooses the Gaussian field's Hurst parameter and the
//! voxel shape `α` so that `σ_m² var[X̄_m]` is closest, in `ln`, to the
//! model's `var[σ̄_t]` at `t = m dx` over the rendered segment lengths.

use crate::line_variance::{axis_covariance, segment_variance};
use crate::synth::{discrete_spectral_variance, SynthParams};
use fgf_core::ParamError;
use std::f64::consts::{FRAC_1_SQRT_2, PI};

/// Half-width of the table of the map in units of `Z` (beyond it the map is
/// held constant: probability 1.5e-23).
const Z_MAX: f64 = 10.0;
/// Table nodes (`dz ≈ 0.017`).
const NODES: usize = 1201;
/// Hermite terms kept in `T(r)`; the remainder of the variance is put on
/// the next power, which keeps `T(1)` exact.
const HERMITE_TERMS: usize = 64;

/// Regularized incomplete gamma functions `(P(a, x), Q(a, x))`: the power
/// series for `x < a + 1`, else the continued fraction of `Q` (modified
/// Lentz).
fn gamma_pq(a: f64, x: f64) -> (f64, f64) {
    if x <= 0.0 {
        return (0.0, 1.0);
    }
    let ln_pre = a * x.ln() - x - libm::lgamma(a);
    if x < a + 1.0 {
        let (mut term, mut ap) = (1.0 / a, a);
        let mut sum = term;
        for _ in 0..10_000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term < sum * 1e-17 {
                break;
            }
        }
        let p = (sum * ln_pre.exp()).min(1.0);
        (p, 1.0 - p)
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-16 {
                break;
            }
        }
        let q = (h * ln_pre.exp()).min(1.0);
        (1.0 - q, q)
    }
}

/// Quantile of the gamma distribution of shape `a` (rate 1) at the standard
/// normal score `z` (lower tail through `P` for `z <= 0`, upper tail through
/// `Q` otherwise, so neither tail loses digits). Safeguarded Newton on
/// `ln x`.
fn gamma_quantile_at_score(a: f64, z: f64) -> f64 {
    let upper = z > 0.0;
    let tail = 0.5 * libm::erfc(z.abs() * FRAC_1_SQRT_2);
    let ln_tail = tail.ln();
    let f = |u: f64| -> (f64, f64) {
        let x = u.exp();
        let (p, q) = gamma_pq(a, x);
        let dens = (a * u - x - libm::lgamma(a)).exp();
        if upper {
            (q.max(1e-320).ln() - ln_tail, -dens / q.max(1e-320))
        } else {
            (p.max(1e-320).ln() - ln_tail, dens / p.max(1e-320))
        }
    };
    // Lower tail for small x: P ≈ x^a / Γ(a+1).
    let small = (ln_tail + libm::lgamma(a + 1.0)) / a;
    let (mut lo, mut hi) = (-700.0f64, (10.0 * a + 200.0).ln());
    if !upper && small < lo {
        return 0.0;
    }
    let mut u = if upper {
        (a.max(1.0) + 1.0).ln()
    } else {
        small.min(a.max(1e-3).ln()).max(lo)
    };
    for _ in 0..200 {
        let (g, dg) = f(u);
        // g increases with u for the lower tail, decreases for the upper.
        let increasing = !upper;
        if (g > 0.0) == increasing {
            hi = u;
        } else {
            lo = u;
        }
        let mut next = u - g / dg;
        if !(next.is_finite() && next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        if (next - u).abs() < 1e-13 * u.abs().max(1.0) {
            u = next;
            break;
        }
        u = next;
    }
    u.exp()
}

/// The map `z ↦ G_α⁻¹(Φ(z))` to a gamma variable of shape `α` and mean 1,
/// tabulated, with its correlation transfer `T(r)`.
#[derive(Debug, Clone)]
pub struct GammaCopula {
    /// Shape `α` of the voxel marginal (mean 1, variance `1/α`).
    pub alpha: f64,
    table: Vec<f64>,
    hermite: Vec<f64>,
    remainder: f64,
    variance: f64,
}

impl GammaCopula {
    /// `1e-3 <= alpha <= 1e5`.
    pub fn new(alpha: f64) -> Result<GammaCopula, ParamError> {
        if !(alpha.is_finite() && (1e-3..=1e5).contains(&alpha)) {
            return Err(ParamError::new(
                "alpha",
                alpha,
                "gamma shape of the voxel marginal out of range",
                "1e-3 <= alpha <= 1e5",
            ));
        }
        let dz = 2.0 * Z_MAX / (NODES - 1) as f64;
        let zs: Vec<f64> = (0..NODES).map(|i| -Z_MAX + i as f64 * dz).collect();
        let mut table: Vec<f64> = zs
            .iter()
            .map(|&z| gamma_quantile_at_score(alpha, z) / alpha)
            .collect();
        let w: Vec<f64> = zs
            .iter()
            .map(|&z| (-0.5 * z * z).exp() / (2.0 * PI).sqrt() * dz)
            .collect();
        // Quadrature mean exactly 1 (the correction is ~1e-10).
        let mean: f64 = table.iter().zip(&w).map(|(g, w)| g * w).sum();
        table.iter_mut().for_each(|g| *g /= mean);
        let second: f64 = table.iter().zip(&w).map(|(g, w)| g * g * w).sum();
        let variance = second - 1.0;
        let mut hermite = Vec::with_capacity(HERMITE_TERMS);
        let mut h_prev = vec![1.0; NODES];
        let mut h = zs.clone();
        for n in 1..=HERMITE_TERMS {
            let c: f64 = table
                .iter()
                .zip(&w)
                .zip(&h)
                .map(|((g, w), h)| g * w * h)
                .sum();
            hermite.push(c * c);
            let (a, b) = (1.0 / ((n + 1) as f64).sqrt(), (n as f64).sqrt());
            let next: Vec<f64> = zs
                .iter()
                .zip(&h)
                .zip(&h_prev)
                .map(|((z, h), hp)| a * (z * h - b * hp))
                .collect();
            h_prev = std::mem::replace(&mut h, next);
        }
        let remainder = (variance - hermite.iter().sum::<f64>()).max(0.0);
        Ok(GammaCopula {
            alpha,
            table,
            hermite,
            remainder,
            variance,
        })
    }

    /// The gamma value (mean 1) for a standard normal score `z`.
    #[inline]
    pub fn map(&self, z: f64) -> f64 {
        let t = ((z + Z_MAX) / (2.0 * Z_MAX) * (NODES - 1) as f64).clamp(0.0, (NODES - 1) as f64);
        let i = (t as usize).min(NODES - 2);
        let f = t - i as f64;
        self.table[i] * (1.0 - f) + self.table[i + 1] * f
    }

    /// Variance of the marginal as tabulated (`≈ 1/α`).
    pub fn variance(&self) -> f64 {
        self.variance
    }

    /// `cov(X, X')` of two mapped voxels whose scores have correlation `r`.
    pub fn covariance(&self, r: f64) -> f64 {
        let r = r.clamp(-1.0, 1.0);
        let mut acc = self.remainder * r;
        for &b in self.hermite.iter().rev() {
            acc = (acc + b) * r;
        }
        acc
    }

    /// Fraction of the variance left beyond the Hermite terms kept.
    pub fn hermite_remainder(&self) -> f64 {
        self.remainder / self.variance
    }
}

/// A calibrated gamma-copula medium for one grid.
#[derive(Debug, Clone)]
pub struct Calibration {
    /// Hurst parameter of the 3D Gaussian field `Z` (unanchored and periodic
    /// on the padded domain, so stationary there even for `H_Z > 0`).
    pub hurst_gauss: f64,
    /// Shape of the voxel marginal.
    pub alpha_voxel: f64,
    /// Segment lengths of the comparison, in voxels along x.
    pub lengths: Vec<usize>,
    /// The model's `var[σ̄_t]` at `t = m dx`.
    pub target: Vec<f64>,
    /// `σ_m² var[X̄_m]` of the calibrated grid (exact spectral sum through
    /// the Hermite transfer).
    pub achieved: Vec<f64>,
    /// Variance of the synthesized Gaussian field with `S_w = 1`, by which
    /// it is divided to get `Z`.
    pub gaussian_variance: f64,
}

/// Line-average variances `σ_m² var[X̄_m]` of the gamma copula of a
/// Gaussian field of axis correlation `rho` (`rho[0] = 1`).
pub fn copula_line_variances(
    copula: &GammaCopula,
    rho: &[f64],
    lengths: &[usize],
    sigma_m: f64,
) -> Vec<f64> {
    let cov: Vec<f64> = rho
        .iter()
        .enumerate()
        .map(|(j, &r)| {
            if j == 0 {
                copula.variance()
            } else {
                copula.covariance(r)
            }
        })
        .collect();
    lengths
        .iter()
        .map(|&m| sigma_m * sigma_m * segment_variance(&cov, m))
        .collect()
}

/// The synthesis refuses `H = 0` (and integers): keep the search off them.
fn gauss_hurst(h: f64) -> f64 {
    if h.abs() < 1e-3 {
        1e-3f64.copysign(h)
    } else {
        h
    }
}

fn golden(lo: f64, hi: f64, iters: usize, mut f: impl FnMut(f64) -> f64) -> (f64, f64) {
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let (mut a, mut b) = (lo, hi);
    let mut c = b - g * (b - a);
    let mut d = a + g * (b - a);
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..iters {
        if fc < fd {
            b = d;
            d = c;
            fd = fc;
            c = b - g * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + g * (b - a);
            fd = f(d);
        }
    }
    if fc < fd {
        (c, fc)
    } else {
        (d, fd)
    }
}

/// Choose `(H_Z, α)` so that the gamma copula of the Gaussian field on the
/// grid of `base` (its `shape`, `spacing` and `padding`; `hurst`, `sw` and
/// `seed` are ignored) has `σ_m² var[X̄_m]` closest to `target[i]` at
/// `m = lengths[i]`, in the least-squares sense on `ln` (nested
/// golden-section searches, `H_Z ∈ [-d/2 + 0.05, 0.95]` (unanchored, periodic), `ln α` within 3 of
/// `ln(σ_m²/target[0])`). Deterministic.
pub fn calibrate_gamma(
    base: &SynthParams,
    sigma_m: f64,
    lengths: &[usize],
    target: &[f64],
) -> Result<(Calibration, GammaCopula), ParamError> {
    ParamError::check_positive("sigma_m", sigma_m)?;
    assert_eq!(lengths.len(), target.len());
    let d = base.shape.len() as f64;
    let rho_for = |h: f64| -> Result<(Vec<f64>, f64), ParamError> {
        let mut p = base.clone();
        p.hurst = gauss_hurst(h);
        p.anchor = crate::Anchor::None;
        p.sw = 1.0;
        let c = axis_covariance(&p)?;
        let v = c[0];
        Ok((c.iter().map(|x| x / v).collect(), v))
    };
    let loss = |got: &[f64]| -> f64 {
        got.iter()
            .zip(target)
            .map(|(g, t)| (g.max(1e-300).ln() - t.ln()).powi(2))
            .sum::<f64>()
            / target.len() as f64
    };
    let ln_ref = (sigma_m * sigma_m / target[0]).ln();
    let (a_lo, a_hi) = (
        (ln_ref - 3.0).max(1e-3f64.ln()),
        (ln_ref + 3.0).min(1e5f64.ln()),
    );
    // A target beyond the copula's range pins α to the nearest bound.
    let a_lo = a_lo.min(a_hi);
    let a_hi = a_hi.max(a_lo);
    let shape = |la: f64| la.exp().clamp(1e-3, 1e5);
    let mut err: Option<ParamError> = None;
    let inner = |rho: &[f64], err: &mut Option<ParamError>| -> (f64, f64) {
        golden(a_lo, a_hi, 15, |la| match GammaCopula::new(shape(la)) {
            Ok(c) => loss(&copula_line_variances(&c, rho, lengths, sigma_m)),
            Err(e) => {
                *err = Some(e);
                f64::INFINITY
            }
        })
    };
    let (h_best, _) = golden(-d / 2.0 + 0.05, 0.95, 18, |h| match rho_for(h) {
        Ok((rho, _)) => inner(&rho, &mut err).1,
        Err(e) => {
            err = Some(e);
            f64::INFINITY
        }
    });
    if let Some(e) = err {
        return Err(e);
    }
    let (rho, gv) = rho_for(h_best)?;
    let mut e2 = None;
    let (la, _) = inner(&rho, &mut e2);
    if let Some(e) = e2 {
        return Err(e);
    }
    let copula = GammaCopula::new(shape(la))?;
    let achieved = copula_line_variances(&copula, &rho, lengths, sigma_m);
    let h_best = gauss_hurst(h_best);
    let mut p = base.clone();
    p.hurst = h_best;
    p.anchor = crate::Anchor::None;
    p.sw = 1.0;
    debug_assert!((discrete_spectral_variance(&p)? - gv).abs() <= 1e-9 * gv);
    Ok((
        Calibration {
            hurst_gauss: h_best,
            alpha_voxel: copula.alpha,
            lengths: lengths.to_vec(),
            target: target.to_vec(),
            achieved,
            gaussian_variance: gv,
        },
        copula,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synthesize;

    #[test]
    fn incomplete_gamma_known_values() {
        // a = 1: P = 1 - e^-x.
        for x in [0.1, 1.0, 3.0, 20.0] {
            let (p, q) = gamma_pq(1.0, x);
            assert!((q - (-x).exp()).abs() < 1e-14 * q.max(1e-300) + 1e-16);
            assert!((p + q - 1.0).abs() < 1e-14);
        }
        // a = 1/2: P = erf(sqrt x).
        for x in [0.01, 0.5, 2.0, 9.0] {
            let (p, _) = gamma_pq(0.5, x);
            assert!((p - libm::erf(x.sqrt())).abs() < 1e-13, "{x}");
        }
    }

    #[test]
    fn quantile_inverts_the_cdf() {
        for a in [0.05, 0.2, 1.0, 4.0, 300.0] {
            for z in [-8.0, -2.0, -0.3, 0.0, 0.7, 3.0, 9.0] {
                let x = gamma_quantile_at_score(a, z);
                let (p, q) = gamma_pq(a, x);
                let want = 0.5 * libm::erfc(z.abs() * FRAC_1_SQRT_2);
                let got = if z > 0.0 { q } else { p };
                assert!(
                    x == 0.0 || (got / want - 1.0).abs() < 1e-9,
                    "a {a} z {z}: x {x} tail {got} want {want}"
                );
            }
        }
    }

    #[test]
    fn copula_moments_and_transfer() {
        for a in [0.2, 1.0, 10.0] {
            let c = GammaCopula::new(a).unwrap();
            assert!(
                (c.variance() * a - 1.0).abs() < 2e-3,
                "a {a}: var {}",
                c.variance()
            );
            assert!((c.covariance(1.0) - c.variance()).abs() < 1e-12);
            assert!(c.covariance(0.0).abs() < 1e-15);
            // T(r) <= r var for r in (0, 1) (all Mehler coefficients >= 0).
            for r in [0.1, 0.5, 0.9] {
                let t = c.covariance(r);
                assert!(t > 0.0 && t <= r * c.variance() * (1.0 + 1e-12), "{a} {r}");
            }
            assert!(
                c.hermite_remainder() < 1e-3,
                "{a}: {}",
                c.hermite_remainder()
            );
        }
    }

    /// The transfer against Monte Carlo: the copula of a small pink grid,
    /// line-average variances by the spectral sum through `T` against the
    /// mean over the fields (SE from the spread of per-field estimates,
    /// tolerance 4.5 SE).
    #[test]
    fn copula_line_variance_matches_monte_carlo() {
        copula_mc(-0.3, 0.3, 150);
    }

    /// The calibration uses `H_Z > 0` (periodic, unanchored): same check.
    #[test]
    fn copula_line_variance_matches_monte_carlo_positive_hurst() {
        copula_mc(0.25, 0.3, 300);
    }

    fn copula_mc(hurst: f64, alpha: f64, fields: u64) {
        let mut p = SynthParams::new(&[16, 16, 16], hurst);
        p.anchor = crate::Anchor::None;
        p.spacing = 1.0 / 16.0;
        p.padding = Some(4.0);
        let cov = axis_covariance(&p).unwrap();
        let rho: Vec<f64> = cov.iter().map(|c| c / cov[0]).collect();
        let copula = GammaCopula::new(alpha).unwrap();
        let lengths = [1usize, 4, 16];
        let want = copula_line_variances(&copula, &rho, &lengths, 1.0);
        let mut per: Vec<Vec<f64>> = vec![Vec::new(); lengths.len()];
        let sd = cov[0].sqrt();
        for r in 0..fields {
            p.seed = 77 + r;
            let f = synthesize(&p, &fgf_core::NoProgress).unwrap();
            let x: Vec<f64> = f
                .data
                .to_f32()
                .iter()
                .map(|&u| copula.map(u as f64 / sd) - 1.0)
                .collect();
            let lv =
                crate::estimators::line_average_second_moment(&x, &p.shape, 2, &lengths).unwrap();
            for (k, v) in lv.into_iter().enumerate() {
                per[k].push(v);
            }
        }
        for (k, &m) in lengths.iter().enumerate() {
            let n = per[k].len() as f64;
            let mean = per[k].iter().sum::<f64>() / n;
            let var = per[k].iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
            let se = (var / n).sqrt();
            assert!(
                (mean - want[k]).abs() < 4.5 * se,
                "H {hurst} m = {m}: MC {mean} ± {se} vs transfer {}",
                want[k]
            );
        }
    }
}
