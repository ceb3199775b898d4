//! # Exponential transmittance (classical media)
//!
//! `Tr(t) = exp(-σ_t t)`: the reference every other model is compared
//! with. All four reciprocal functions coincide up to `σ̄ = σ_t`.
//!
//! | parameter | units | valid range | default |
//! |---|---|---|---|
//! | `sigma_t` | 1/length | `0 < sigma_t < inf` | required |
//!
//! Scene (Mitsuba 3 XML, fgf's `nonexponential` medium):
//!
//! ```xml
//! <medium type="nonexponential" id="fog">
//!     <string name="transmittance" value="exponential"/>
//!     <float name="sigma_t" value="4.0"/>
//!     <rgb name="albedo" value="0.8"/>
//! </medium>
//! ```
//!
//! Python:
//!
//! ```python
//! import fgf
//! m = fgf.Exponential(4.0)
//! m.tr([0.0, 0.5]), m.sample_surface(0.5)   # exp(-4t); ln 2 / 4
//! ```

use super::api::Transmittance;
use crate::error::{ParamError, Result};

/// `Tr = exp(-σ_t t)`. See the module docs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Exponential {
    sigma_t: f64,
}

impl Exponential {
    /// Errors unless `sigma_t` is finite and > 0.
    pub fn new(sigma_t: f64) -> Result<Self> {
        ParamError::check_positive("sigma_t", sigma_t)?;
        Ok(Exponential { sigma_t })
    }
}

impl Transmittance for Exponential {
    /// `Tr(t) = exp(-σ_t t)`; NaN for `t < 0`.
    #[inline]
    fn tr(&self, t: f64) -> f64 {
        if !(t >= 0.0) {
            return f64::NAN;
        }
        (-self.sigma_t * t).exp()
    }
    /// `-dTr/dt = σ_t exp(-σ_t t)`.
    #[inline]
    fn pdf(&self, t: f64) -> f64 {
        self.sigma_t * self.tr(t)
    }
    /// `T_ms = T_sm / σ̄ = Tr`.
    #[inline]
    fn medium_surface(&self, t: f64) -> f64 {
        self.tr(t)
    }
    /// `T_mm = -dT_ms/dt = σ_t Tr`.
    #[inline]
    fn medium_medium(&self, t: f64) -> f64 {
        self.pdf(t)
    }
    /// `σ̄ = σ_t`.
    #[inline]
    fn sigma_bar(&self) -> f64 {
        self.sigma_t
    }
    #[inline]
    fn sigma_t(&self) -> f64 {
        self.sigma_t
    }
    /// `t = -ln(1-u) / σ_t` (`ln_1p` keeps small `u` accurate).
    #[inline]
    fn sample_surface(&self, u: f64) -> f64 {
        -(-u).ln_1p() / self.sigma_t
    }
    /// Same as `sample_surface`: `T_ms = T_ss`.
    #[inline]
    fn sample_medium(&self, u: f64) -> f64 {
        self.sample_surface(u)
    }
}
