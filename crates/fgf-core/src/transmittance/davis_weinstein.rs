//! # Davis–Weinstein transmittance (Bitterli et al. 2018)
//!
//! The gamma closure with a distance-dependent shape, in optical depth
//! `τ = σ_t t`:
//!
//! ```text
//! α(τ) = τ^(2-2h) / c^(2h),   Tr = (1 + τ/α(τ))^(-α(τ))
//! ```
//!
//! It is exactly the pink-noise regime of [`Fgf`](super::Fgf) with
//! `h = H + 1` and `c = S_p^(1/(2H+2)) / σ_m` (`docs/theory.md` §3, checked
//! numerically in the tests; [`Fgf::to_davis_weinstein`](super::Fgf::to_davis_weinstein)).
//! The end points are limits of the same formula: `h = 1` is Davis with
//! `α = 1/c²`, `h = 1/2` is an exponential with `σ_eff = σ_t ln(1+c)/c`
//! (white noise). Here `σ̄ = T_sm(0)`, which is `σ_t` except at `h = 1/2`,
//! where it is `σ_eff` (Tungsten's `sigmaBar` returns 1 there, which is not
//! `T_sm(0)`).
//!
//! For `1/2 < h < 1` sampling has no closed form:
//! [`sample_surface`](super::Transmittance::sample_surface) and
//! [`sample_medium`](super::Transmittance::sample_medium) run the
//! safeguarded iteration on `ln t` described in [`Fgf`](super::Fgf) (tolerances
//! [`SURFACE_TOL`](super::SURFACE_TOL) and [`MEDIUM_TOL`](super::MEDIUM_TOL),
//! cap [`SAMPLE_MAX_ITER`](super::SAMPLE_MAX_ITER), bisection fallback).
//!
//! | parameter | units | valid range | default |
//! |---|---|---|---|
//! | `sigma_t` | 1/length | `0 < sigma_t < inf` | required |
//! | `h` | – | `0.5 <= h <= 1` | required |
//! | `c` | – | `0 < c < inf` | required |
//!
//! Scene:
//!
//! ```xml
//! <medium type="nonexponential" id="smoke">
//!     <string name="transmittance" value="davis_weinstein"/>
//!     <float name="h" value="0.9"/>
//!     <float name="c" value="0.78"/>
//!     <float name="sigma_t" value="4.0"/>
//!     <rgb name="albedo" value="0.8"/>
//! </medium>
//! ```
//!
//! Python:
//!
//! ```python
//! import fgf
//! m = fgf.DavisWeinstein(4.0, h=0.9, c=0.78)
//! m.tr(0.25), m.sample_medium(0.5)
//! ```

use super::gamma::GammaCore;
use crate::error::{ParamError, Result};

/// Davis–Weinstein model. See the module docs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DavisWeinstein {
    h: f64,
    c: f64,
    pub(crate) core: GammaCore,
}

impl DavisWeinstein {
    /// Errors unless `sigma_t` is finite and > 0, `0.5 <= h <= 1`, and `c`
    /// is finite and > 0.
    pub fn new(sigma_t: f64, h: f64, c: f64) -> Result<Self> {
        ParamError::check_positive("sigma_t", sigma_t)?;
        if !(0.5..=1.0).contains(&h) {
            return Err(ParamError::new(
                "h",
                h,
                "must lie in [0.5, 1]",
                "0.5 <= h <= 1",
            ));
        }
        ParamError::check_positive("c", c)?;
        // In distance units x = τ/α(τ) = c^(2h) τ^(2h-1) = k t^e with
        // e = 2h-1 and k = c^(2h) σ^(2h-1), formed in log space.
        let e = 2.0 * h - 1.0;
        let k = (2.0 * h * c.ln() + e * sigma_t.ln()).exp();
        Ok(DavisWeinstein {
            h,
            c,
            core: GammaCore::new(sigma_t, k, e),
        })
    }

    /// `h` (`= H + 1` for pink noise).
    pub fn h(&self) -> f64 {
        self.h
    }
    /// `c` (dimensionless).
    pub fn c(&self) -> f64 {
        self.c
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transmittance::MEDIUM_TOL;

    /// For the benchmark's medium (`h = 0.9`, `c = 0.78`) the medium
    /// sampler's fitted start is well below `MEDIUM_TOL`, so that one
    /// evaluation suffices.
    #[test]
    fn benchmark_medium_fit_needs_one_evaluation() {
        let core = DavisWeinstein::new(4.0, 0.9, 0.78).unwrap().core;
        let err = core.medium_guess_max_err().unwrap();
        assert!(err < 0.1 * MEDIUM_TOL, "{err:e}");
    }
}
