//! Statistics of fractional Gaussian fields (`docs/theory.md` §1–2).
//!
//! An FGF `M = (-Δ)^(-s/2) W` with white-noise strength `S_w` (`sw`) and
//! Hurst parameter `H = s - d/2` (`hurst`). Along a ray the extinction is
//! `σ_t(x) = σ_m + σ_u(x)` with `σ_u` a zero-mean FGF, and the rendering
//! model needs the variance of the line-averaged extinction
//! `σ̄_t = τ(x, t) / t`:
//!
//! | regime | `hurst` | `var[σ̄_t]` | function |
//! |---|---|---|---|
//! | white | `-1/2` | `S_w / t` | [`line_average_variance`] |
//! | pink | `(-1/2, 0)` | `S_p(H) t^(2H)` | [`s_p`] |
//! | k-fBm | `(k-1, k)`, `k = ⌈H⌉` | `S_kf(H) L^(2H)` | [`s_kf`] |
//!
//! Every closed form uses the 1D constant `C(H, 1)` (the model is a 1D field
//! along each ray). Gamma functions come from `libm` (std has none) and are
//! evaluated in log space (`lgamma`) wherever a product of gammas could
//! overflow for large `H`; `sin(πH)` is evaluated with the argument reduced
//! exactly to `[-1/2, 1/2]` so that `H` near an integer keeps its relative
//! accuracy.
//!
//! ```
//! use fgf_core::stats::{line_average_variance, s_p};
//! // Pink noise: var = S_p t^(2H).
//! let v = line_average_variance(-0.1, 4.0, 2.0, None).unwrap();
//! assert!((v - s_p(-0.1, 4.0) * 2f64.powf(-0.2)).abs() < 1e-12 * v);
//! ```

use crate::error::{ParamError, Result};

/// Which closed form of `docs/theory.md` §2 applies for a Hurst parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Regime {
    /// `H = -1/2`: uncorrelated extinction, `var[σ̄_t] = S_w / t`.
    White,
    /// `-1/2 < H < 0`: `var[σ̄_t] = S_p(H) t^(2H)`.
    Pink,
    /// `k-1 < H < k`, `k ≥ 1`: `var[σ̄_t] = S_kf(H) L^(2H)` (needs the length `L`).
    KFbm {
        /// `k = ⌈H⌉`, the number of subtracted Taylor terms.
        k: u32,
    },
}

/// Largest accepted `hurst`. Beyond it the k-fBm order `k` is meaningless for
/// rendering and `Γ(2H+2)` alone exceeds 10^5000; the limit keeps `k` a small
/// integer. It is a validation bound, never a clamp.
pub const HURST_MAX: f64 = 1000.0;

/// Smallest accepted `|hurst|` (pink and k-fBm alike). The line-average
/// variance diverges like `1/|H|` as `H → 0` and the k-fBm closed forms need
/// `2H` next to 1 (`1 + 2H`, `t^(2H) - 1`): below about `1e-16` double
/// precision rounds `1 + 2H` to 1 and the model returns NaN; at `1e-15` the
/// forms still keep several digits (checked on a log grid down to the
/// smallest double by the tests). A validation bound, never a clamp.
pub const HURST_MIN_ABS: f64 = 1e-15;

/// Valid range of `hurst`, as quoted in error messages.
pub const HURST_RANGE: &str =
    "hurst = -0.5 (white), -0.5 < hurst <= -1e-15 (pink), or 1e-15 <= hurst < 1000 non-integer (k-fBm)";

impl Regime {
    /// Classify `hurst`; errors for NaN/inf, `H < -1/2`, `H = 0`, integer `H`
    /// and `H ≥ 1000` ([`HURST_MAX`]).
    pub fn from_hurst(hurst: f64) -> Result<Regime> {
        let err = |reason: &str| ParamError::new("hurst", hurst, reason, HURST_RANGE);
        if !hurst.is_finite() {
            return Err(err("must be finite"));
        }
        if hurst < -0.5 {
            return Err(err("must be >= -0.5 (the 1D line average diverges below)"));
        }
        if hurst == -0.5 {
            return Ok(Regime::White);
        }
        if hurst <= -HURST_MIN_ABS {
            return Ok(Regime::Pink);
        }
        if hurst == 0.0 {
            return Err(err("must not be 0 (the covariance is logarithmic there)"));
        }
        if hurst.abs() < HURST_MIN_ABS {
            return Err(err(
                "must be at least 1e-15 away from 0 (the variance diverges like 1/|hurst| and double precision loses the model below)",
            ));
        }
        if hurst >= HURST_MAX {
            return Err(err("must be < 1000"));
        }
        if hurst.fract() == 0.0 {
            return Err(err("must not be an integer (C(H,d) has a pole there)"));
        }
        Ok(Regime::KFbm {
            k: hurst.ceil() as u32,
        })
    }
}

/// `sin(π x)` with the argument reduced exactly: `x = n + f`, `|f| ≤ 1/2`,
/// `sin(πx) = (-1)^n sin(πf)`. `x - round(x)` is exact in floating point, so
/// the result keeps full relative accuracy near integers, where `(PI * x).sin()`
/// would lose digits.
pub fn sin_pi(x: f64) -> f64 {
    let n = x.round();
    let f = x - n;
    let s = (std::f64::consts::PI * f).sin();
    if n.rem_euclid(2.0) == 0.0 {
        s
    } else {
        -s
    }
}

/// `ln |Γ(x)|` and the sign of `Γ(x)` (libm's `lgamma_r`).
fn ln_gamma(x: f64) -> (f64, f64) {
    let (lg, sign) = libm::lgamma_r(x);
    (lg, if sign < 0 { -1.0 } else { 1.0 })
}

/// `C(H, d) = Γ(-H) / (2^(2H+d) π^(d/2) Γ(H + d/2))`, the constant of the
/// pink-noise covariance `cov(x, y) = C(H,d) S_w |x-y|^(2H)` (`docs/theory.md` §1).
///
/// Evaluated as `sign · exp(lnΓ(-H) - lnΓ(H+d/2) - ...)` so that large `|H|`
/// does not overflow. `1/Γ(H + d/2)` is taken as 0 at the poles of Γ (e.g.
/// `C(-1/2, 1) = 0`: white noise has no power-law covariance). The result is
/// not finite when `H` is a non-negative integer (pole of `Γ(-H)`).
pub fn c_const(hurst: f64, d: u32) -> f64 {
    let half_d = 0.5 * d as f64;
    let b = hurst + half_d;
    if b <= 0.0 && b.fract() == 0.0 {
        return 0.0;
    }
    if hurst >= 0.0 && hurst.fract() == 0.0 {
        return f64::NAN;
    }
    let (lg_a, s_a) = ln_gamma(-hurst);
    let (lg_b, s_b) = ln_gamma(b);
    let ln_mag = lg_a
        - lg_b
        - (2.0 * hurst + d as f64) * std::f64::consts::LN_2
        - half_d * std::f64::consts::PI.ln();
    s_a * s_b * ln_mag.exp()
}

/// Generalised binomial coefficient `binom(a, k) = a (a-1) ... (a-k+1) / k!`
/// for real `a` (`binom(a, 0) = 1`). Computed as the product of `k` ratios,
/// which is exact enough for the small `k` used here; it overflows to ±inf
/// only when the true value exceeds `f64::MAX`.
pub fn binom(a: f64, k: u32) -> f64 {
    (0..k).fold(1.0, |acc, j| acc * (a - j as f64) / (j as f64 + 1.0))
}

/// `ln S_p(H) = ln S_w - lnΓ(2H+3) - ln|sin πH|`.
fn ln_s_p(hurst: f64, sw: f64) -> f64 {
    sw.ln() - libm::lgamma(2.0 * hurst + 3.0) - sin_pi(hurst).abs().ln()
}

/// `S_p(H) = S_w / (Γ(2H+3) |sin πH|)`: pink-noise line-average variance
/// `var[σ̄_t] = S_p t^(2H)` for `-1/2 < H < 0` (`docs/theory.md` §2). At
/// `H = -1/2` it equals `S_w`, so the white-noise law `S_w / t` is its limit.
/// No validation: see [`line_average_variance`] for the checked entry point.
pub fn s_p(hurst: f64, sw: f64) -> f64 {
    ln_s_p(hurst, sw).exp()
}

/// `ln binom(2H-1, k-1)` for `k-1 < H < k` (all its factors are positive
/// there, since `2H-1 > 2k-3 ≥ k-2`), through `lnΓ` so that large `H` and
/// `k` do not overflow.
fn ln_binom_kfbm(hurst: f64, k: u32) -> f64 {
    let a = 2.0 * hurst - 1.0;
    let km1 = (k - 1) as f64;
    libm::lgamma(a + 1.0) - libm::lgamma(km1 + 1.0) - libm::lgamma(a - km1 + 1.0)
}

/// `ln S_kf(H)`; `k = ⌈H⌉`.
fn ln_s_kf(hurst: f64, sw: f64) -> f64 {
    let k = hurst.ceil() as u32;
    sw.ln() + ln_binom_kfbm(hurst, k) - libm::lgamma(2.0 * hurst + 2.0) - sin_pi(hurst).abs().ln()
}

/// `S_kf(H) = S_w binom(2H-1, k-1) / (Γ(2H+2) |sin πH|)`, `k = ⌈H⌉`:
/// k-fBm line-average variance `var[σ̄_t] = S_kf L^(2H)` for `k-1 < H < k`
/// (`docs/theory.md` §2). Equals the point variance of the anchored k-fBm
/// averaged over `[0, L]`, divided by `L^(2H)`. Evaluated in log space. No
/// validation (NaN for `H ≤ 0`): see [`line_average_variance`].
pub fn s_kf(hurst: f64, sw: f64) -> f64 {
    if hurst <= 0.0 {
        return f64::NAN;
    }
    ln_s_kf(hurst, sw).exp()
}

/// Point variance of the anchored k-fBm (`docs/theory.md` §1):
/// `var M~(x) = 2 C(H,1) S_w (-1)^k binom(2H-1, k-1) |x|^(2H)`, `k = ⌈H⌉`.
///
/// Evaluated as `(2H+1) S_kf |x|^(2H)` in log space (the same quantity:
/// `(1/L) ∫_0^L (2H+1) x^(2H) dx = L^(2H)`). NaN for `H ≤ 0` or integer `H`.
pub fn kfbm_point_variance(hurst: f64, sw: f64, x: f64) -> f64 {
    if !(hurst > 0.0) || hurst.fract() == 0.0 {
        return f64::NAN;
    }
    if x == 0.0 {
        return 0.0;
    }
    (ln_s_kf(hurst, sw) + (2.0 * hurst + 1.0).ln() + 2.0 * hurst * x.abs().ln()).exp()
}

/// `ln var[σ̄_t]` for an already validated regime; `ln_t` is `ln t` (unused
/// for k-fBm), `ln_length` is `ln L` (k-fBm only).
pub(crate) fn ln_line_average_variance(
    regime: Regime,
    hurst: f64,
    sw: f64,
    ln_t: f64,
    ln_length: f64,
) -> f64 {
    match regime {
        Regime::White => sw.ln() - ln_t,
        Regime::Pink => ln_s_p(hurst, sw) + 2.0 * hurst * ln_t,
        Regime::KFbm { .. } => ln_s_kf(hurst, sw) + 2.0 * hurst * ln_length,
    }
}

/// Check the `length` argument against the regime: required (finite, > 0)
/// for k-fBm, refused for white and pink noise (where nothing would use it).
pub(crate) fn check_length(regime: Regime, length: Option<f64>) -> Result<Option<f64>> {
    match (regime, length) {
        (Regime::KFbm { .. }, Some(l)) => ParamError::check_positive("length", l).map(Some),
        (Regime::KFbm { .. }, None) => Err(ParamError::new(
            "length",
            "None",
            "is required for k-fBm (hurst > 0): the variance is S_kf L^(2H)",
            "0 < length < inf",
        )),
        (_, Some(l)) => Err(ParamError::new(
            "length",
            l,
            "is only used by k-fBm (hurst > 0); leave it unset for white or pink noise",
            "unset when hurst < 0",
        )),
        (_, None) => Ok(None),
    }
}

/// `var[σ̄_t]`, the variance of the extinction averaged over a segment of
/// length `t` (`docs/theory.md` §2), for any valid regime.
///
/// * `hurst`: see [`Regime::from_hurst`];
/// * `sw`: `S_w > 0`, finite;
/// * `t > 0` (`+inf` allowed: the white/pink variance is 0 there);
/// * `length`: `L > 0`, required for k-fBm and refused otherwise.
///
/// Errors name the offending parameter and its valid range.
pub fn line_average_variance(hurst: f64, sw: f64, t: f64, length: Option<f64>) -> Result<f64> {
    let regime = Regime::from_hurst(hurst)?;
    ParamError::check_positive("sw", sw)?;
    if !(t > 0.0) {
        return Err(ParamError::new(
            "t",
            t,
            "must be > 0 (the variance diverges at t = 0)",
            "0 < t <= inf",
        ));
    }
    let length = check_length(regime, length)?;
    let ln_length = length.map_or(0.0, f64::ln);
    Ok(ln_line_average_variance(regime, hurst, sw, t.ln(), ln_length).exp())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rel(a: f64, b: f64) -> f64 {
        ((a - b) / b).abs()
    }

    #[test]
    fn regime_classification() {
        assert_eq!(Regime::from_hurst(-0.5).unwrap(), Regime::White);
        assert_eq!(Regime::from_hurst(-0.1).unwrap(), Regime::Pink);
        assert_eq!(Regime::from_hurst(0.2).unwrap(), Regime::KFbm { k: 1 });
        assert_eq!(Regime::from_hurst(1.2).unwrap(), Regime::KFbm { k: 2 });
        assert_eq!(Regime::from_hurst(2.5).unwrap(), Regime::KFbm { k: 3 });
    }

    #[test]
    fn invalid_hurst_is_rejected_with_its_name_and_range() {
        for h in [
            -0.6,
            0.0,
            1.0,
            2.0,
            f64::NAN,
            f64::INFINITY,
            -f64::INFINITY,
            1000.5,
        ] {
            let e = Regime::from_hurst(h).unwrap_err();
            assert_eq!(e.name, "hurst");
            assert!(e.to_string().contains("valid:"), "{e}");
        }
    }

    #[test]
    fn c_const_known_values_and_identities() {
        // docs/theory.md §1: C(1/2, 1) = -1/2.
        assert!(rel(c_const(0.5, 1), -0.5) < 1e-14);
        for h in [-0.45, -0.3, -0.1, 0.2, 0.7, 1.2, 1.8, 2.5] {
            // 1D closed form -1 / (2 Γ(2H+1) sin πH).
            let c1 = -1.0 / (2.0 * libm::tgamma(2.0 * h + 1.0) * sin_pi(h));
            assert!(rel(c_const(h, 1), c1) < 1e-13, "h = {h}");
            // C(H,3) = C(H,1) / (2π(2H+1)).
            let c3 = c1 / (2.0 * std::f64::consts::PI * (2.0 * h + 1.0));
            assert!(rel(c_const(h, 3), c3) < 1e-13, "h = {h}");
        }
        // White noise has no power-law covariance.
        assert_eq!(c_const(-0.5, 1), 0.0);
    }

    #[test]
    fn c_const_matches_fourier_transform_of_the_spectrum() {
        // cov(h) = (S_w/π) ∫_0^∞ ω^(-2H-1) cos(ωh) dω = (S_w/π) Γ(-2H) cos(πH) h^(2H)
        // for -1/2 < H < 0 (∫_0^∞ x^(μ-1) cos x dx = Γ(μ) cos(πμ/2), μ = -2H).
        for h in [-0.45, -0.25, -0.1, -0.01] {
            let c =
                libm::tgamma(-2.0 * h) * (std::f64::consts::PI * h).cos() / std::f64::consts::PI;
            assert!(rel(c_const(h, 1), c) < 1e-13, "h = {h}");
        }
    }

    #[test]
    fn binom_values() {
        assert_eq!(binom(5.0, 2), 10.0);
        assert_eq!(binom(1.4, 0), 1.0);
        assert!(rel(binom(1.4, 1), 1.4) < 1e-15);
        assert!(rel(binom(-0.5, 3), -0.3125) < 1e-15);
        assert!(rel(binom(3.0, 2), 3.0) < 1e-15);
    }

    #[test]
    fn s_p_limit_at_white_noise_is_sw() {
        assert!(rel(s_p(-0.5, 3.0), 3.0) < 1e-14);
        assert!(rel(s_p(-0.5 + 1e-9, 3.0), 3.0) < 1e-7);
    }

    /// Point variance by the independent form of docs/theory.md §1, the variance of
    /// M minus its Taylor polynomial through the generalised covariance:
    /// `-2 C(H,1) S_w x^(2H) Σ_{j<k} (-1)^j binom(2H, j)`.
    #[test]
    fn kfbm_point_variance_matches_taylor_sum() {
        for h in [0.2f64, 0.5, 0.9, 1.2, 1.5, 1.8, 2.3, 3.7] {
            let k = h.ceil() as u32;
            let sum: f64 = (0..k)
                .map(|j| if j % 2 == 0 { 1.0 } else { -1.0 } * binom(2.0 * h, j))
                .sum();
            for x in [0.3f64, 1.0, 2.5] {
                let want = -2.0 * c_const(h, 1) * 1.7 * x.powf(2.0 * h) * sum;
                let got = kfbm_point_variance(h, 1.7, x);
                assert!(want > 0.0);
                assert!(rel(got, want) < 1e-12, "h = {h}, x = {x}: {got} vs {want}");
            }
        }
    }

    #[test]
    fn kfbm_h_half_is_brownian_motion() {
        // H = 1/2, k = 1: Brownian motion with var = -2 C(1/2,1) S_w x = S_w x.
        assert!(rel(kfbm_point_variance(0.5, 2.0, 3.0), 6.0) < 1e-13);
    }

    #[test]
    fn line_average_variance_regimes() {
        assert!(rel(line_average_variance(-0.5, 4.0, 2.0, None).unwrap(), 2.0) < 1e-15);
        let v = line_average_variance(-0.1, 4.0, 2.0, None).unwrap();
        assert!(rel(v, s_p(-0.1, 4.0) * 2f64.powf(-0.2)) < 1e-14);
        let v = line_average_variance(1.2, 34.0, 5.0, Some(2.0)).unwrap();
        assert!(rel(v, s_kf(1.2, 34.0) * 2f64.powf(2.4)) < 1e-14);
        assert_eq!(
            line_average_variance(-0.1, 4.0, f64::INFINITY, None).unwrap(),
            0.0
        );
    }

    #[test]
    fn line_average_variance_rejects_bad_arguments() {
        let name = |r: Result<f64>| r.unwrap_err().name;
        assert_eq!(name(line_average_variance(-0.7, 1.0, 1.0, None)), "hurst");
        assert_eq!(name(line_average_variance(0.0, 1.0, 1.0, None)), "hurst");
        assert_eq!(
            name(line_average_variance(1.0, 1.0, 1.0, Some(1.0))),
            "hurst"
        );
        assert_eq!(name(line_average_variance(-0.1, 0.0, 1.0, None)), "sw");
        assert_eq!(name(line_average_variance(-0.1, f64::NAN, 1.0, None)), "sw");
        assert_eq!(name(line_average_variance(-0.1, 1.0, 0.0, None)), "t");
        assert_eq!(name(line_average_variance(-0.1, 1.0, -1.0, None)), "t");
        assert_eq!(
            name(line_average_variance(-0.1, 1.0, 1.0, Some(1.0))),
            "length"
        );
        assert_eq!(name(line_average_variance(1.2, 1.0, 1.0, None)), "length");
        assert_eq!(
            name(line_average_variance(1.2, 1.0, 1.0, Some(-1.0))),
            "length"
        );
        assert_eq!(
            name(line_average_variance(1.2, 1.0, 1.0, Some(f64::INFINITY))),
            "length"
        );
    }
}
