//! # FGF transmittance (Guo et al. 2019, gamma closure)
//!
//! The extinction along a ray is `σ_t(x) = σ_m + σ_u(x)` with `σ_u` a
//! zero-mean fractional Gaussian field of Hurst parameter `H` and
//! white-noise strength `S_w`. The line average `σ̄_t` over a segment of
//! length `t` is replaced by a gamma variable with mean `σ_m` and variance
//! `v(t) = var[σ̄_t]` (`docs/theory.md` §2–3):
//!
//! ```text
//! α(t) = σ_m² / v(t),   Tr(t) = (1 + σ_m t/α)^(-α) = exp(-α log1p(σ_m t/α))
//! p(t) = -dTr/dt        (free-flight pdf of the energy-conserving kernel)
//! ```
//!
//! | regime | `hurst` | `v(t)` | model |
//! |---|---|---|---|
//! | white | `-0.5` | `S_w/t` | exponential, `σ_eff = (σ_m²/S_w) ln(1 + S_w/σ_m)` |
//! | pink | `(-0.5, 0)` | `S_p t^(2H)` | Davis–Weinstein, `h = H+1`, `c = S_p^(1/(2H+2))/σ_m` |
//! | k-fBm | `(k-1, k)` | `S_kf L^(2H)` | Davis, `α = σ_m²/(S_kf L^(2H))` |
//!
//! Sampling: closed-form inverses for white noise and k-fBm. Pink noise has
//! none: a safeguarded Newton-type iteration on `ln t` solves `Tr(t) = 1-u`
//! (Householder's 4th-order steps, tolerance [`SURFACE_TOL`](super::SURFACE_TOL),
//! started from a polynomial fit of the root made in the constructor: one
//! evaluation per sample for typical parameters) and `T_ms(t) = 1-u` (Halley,
//! [`MEDIUM_TOL`](super::MEDIUM_TOL), started from a per-model polynomial fit
//! of `ln t` against `ln(-ln(1-u))`: also one evaluation for typical
//! parameters); at most
//! [`SAMPLE_MAX_ITER`](super::SAMPLE_MAX_ITER) iterations, bisection as the
//! fallback inside the bracket. For white noise `p(0) = σ̄ = σ_eff`, not
//! `σ_m`.
//!
//! | parameter | units | valid range | default |
//! |---|---|---|---|
//! | `sigma_t` | 1/length | `0 < sigma_t < inf` (the mean `σ_m`) | required |
//! | `hurst` | – | `-0.5` (white), `(-0.5, 0)` (pink), `(0, 1000)` non-integer (k-fBm) | required |
//! | `sw` | length^-(2+2H) (so that `v(t)` is in 1/length²; 1/length for white noise) | `0 < sw < inf` | required |
//! | `length` | length | `0 < length < inf`; k-fBm only (an error for white/pink) | required for k-fBm |
//!
//! Scene (the renderer's `fgf` medium; `length` defaults there to the
//! bounding-box diagonal of the shapes bounding the medium):
//!
//! ```xml
//! <medium type="fgf" id="interior">
//!     <float name="sigma_t" value="4.0"/>
//!     <rgb name="albedo" value="0.8"/>
//!     <float name="hurst" value="-0.1"/>
//!     <float name="sw" value="4.0"/>
//!     <string name="kernel" value="energy_conserving"/>
//! </medium>
//! ```
//!
//! Python:
//!
//! ```python
//! import fgf, numpy as np
//! m = fgf.Fgf(sigma_t=4.0, hurst=-0.1, sw=4.0)                # pink noise
//! t = np.linspace(0, 3, 1000)
//! m.variance(t), m.alpha(t), m.tr(t), m.pdf(t)
//! fgf.Fgf(sigma_t=4.0, hurst=1.2, sw=34.0, length=1.0)        # 2-fBm = Davis
//! ```

use super::davis::Davis;
use super::davis_weinstein::DavisWeinstein;
use super::gamma::GammaCore;
use crate::error::{ParamError, Result};
use crate::stats::{check_length, ln_line_average_variance, s_p, Regime, HURST_RANGE};

/// FGF gamma-closure transmittance. See the module docs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fgf {
    hurst: f64,
    sw: f64,
    /// `L` for k-fBm, 0 otherwise (valid lengths are > 0; not NaN, so that
    /// `PartialEq` stays reflexive): an `Option<f64>` would cost an 8-byte
    /// tag, and `ln L` is recomputed (bit-identically) where needed, so that
    /// `Model` keeps within 256 bytes with the samplers' fitted starts.
    length: f64,
    regime: Regime,
    pub(crate) core: GammaCore,
}

impl Fgf {
    /// Validates every parameter: `sigma_t`, `sw` finite and > 0; `hurst` by
    /// [`Regime::from_hurst`]; `length` finite and > 0 for k-fBm, absent
    /// otherwise.
    pub fn new(sigma_t: f64, hurst: f64, sw: f64, length: Option<f64>) -> Result<Self> {
        ParamError::check_positive("sigma_t", sigma_t)?;
        let regime = Regime::from_hurst(hurst)?;
        ParamError::check_positive("sw", sw)?;
        let length = check_length(regime, length)?;
        let ln_length = length.map_or(0.0, f64::ln);
        // x(t) = t v(t) / σ_m = k t^e; ln k = ln(t v(t)) - ln σ at t = 1.
        let e = match regime {
            Regime::White => 0.0,
            Regime::Pink => 1.0 + 2.0 * hurst,
            Regime::KFbm { .. } => 1.0,
        };
        let ln_v1 = ln_line_average_variance(regime, hurst, sw, 0.0, ln_length);
        let k = (ln_v1 - sigma_t.ln()).exp();
        Ok(Fgf {
            hurst,
            sw,
            length: length.unwrap_or(0.0),
            regime,
            core: GammaCore::new(sigma_t, k, e),
        })
    }

    pub fn hurst(&self) -> f64 {
        self.hurst
    }
    pub fn sw(&self) -> f64 {
        self.sw
    }
    pub fn length(&self) -> Option<f64> {
        (self.length > 0.0).then_some(self.length)
    }

    /// `ln L` for k-fBm, 0 otherwise (unused there).
    fn ln_length(&self) -> f64 {
        self.length().map_or(0.0, f64::ln)
    }
    pub fn regime(&self) -> Regime {
        self.regime
    }

    /// `v(t) = var[σ̄_t]` (1/length²): `+inf` at `t = 0` for white and pink
    /// noise, constant for k-fBm; NaN for `t < 0`.
    pub fn variance(&self, t: f64) -> f64 {
        if !(t >= 0.0) {
            return f64::NAN;
        }
        ln_line_average_variance(self.regime, self.hurst, self.sw, t.ln(), self.ln_length()).exp()
    }

    /// `α(t) = σ_m² / v(t)`: 0 at `t = 0` for white and pink noise, constant
    /// for k-fBm; NaN for `t < 0`.
    pub fn alpha(&self, t: f64) -> f64 {
        if !(t >= 0.0) {
            return f64::NAN;
        }
        let ln_v =
            ln_line_average_variance(self.regime, self.hurst, self.sw, t.ln(), self.ln_length());
        (2.0 * self.core.sigma.ln() - ln_v).exp()
    }

    /// The equal [`Davis`] model of a k-fBm medium, `α = σ_m²/(S_kf L^(2H))`
    /// (`docs/theory.md` §3). Errors for white/pink noise, or when `α` over- or
    /// underflows `f64`.
    pub fn to_davis(&self) -> Result<Davis> {
        match self.regime {
            Regime::KFbm { .. } => Davis::new(self.core.sigma, self.alpha(1.0)),
            _ => Err(ParamError::new(
                "hurst",
                self.hurst,
                "to_davis needs a k-fBm medium (hurst > 0); use to_davis_weinstein",
                HURST_RANGE,
            )),
        }
    }

    /// The equal [`DavisWeinstein`] model of a white or pink medium,
    /// `h = H + 1`, `c = S_p^(1/(2H+2)) / σ_m` (`docs/theory.md` §3; at
    /// `H = -1/2`, `S_p = S_w`). Errors for k-fBm.
    pub fn to_davis_weinstein(&self) -> Result<DavisWeinstein> {
        match self.regime {
            Regime::White | Regime::Pink => {
                let h = self.hurst + 1.0;
                let c = (s_p(self.hurst, self.sw).ln() / (2.0 * h) - self.core.sigma.ln()).exp();
                DavisWeinstein::new(self.core.sigma, h, c)
            }
            Regime::KFbm { .. } => Err(ParamError::new(
                "hurst",
                self.hurst,
                "to_davis_weinstein needs white or pink noise (hurst < 0); use to_davis",
                HURST_RANGE,
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transmittance::MEDIUM_TOL;

    /// For the benchmark's pink medium (`H = -0.1`, `S_w = 4`) the medium
    /// sampler's fitted start is well below `MEDIUM_TOL`, so that one
    /// evaluation suffices.
    #[test]
    fn benchmark_medium_fit_needs_one_evaluation() {
        let core = Fgf::new(4.0, -0.1, 4.0, None).unwrap().core;
        let err = core.medium_guess_max_err().unwrap();
        assert!(err < 0.1 * MEDIUM_TOL, "{err:e}");
    }
}
