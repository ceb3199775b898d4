//! # Davis power-law transmittance (Bitterli et al. 2018)
//!
//! `Tr(t) = (1 + σ_t t / α)^(-α)`, the gamma closure with a constant
//! shape `α`. It is exactly the k-fBm regime of [`Fgf`](super::Fgf) with
//! `α = σ_m² / (S_kf L^(2H))` (`docs/theory.md` §3, [`Fgf::to_davis`](super::Fgf::to_davis)).
//!
//! ```text
//! T_sm = σ_t (1 + σ_t t/α)^(-α-1),   σ̄ = σ_t
//! T_ms = (1 + σ_t t/α)^(-α-1)
//! T_mm = σ_t (α+1)/α (1 + σ_t t/α)^(-α-2)
//! sample_surface: t = (α/σ_t) ((1-u)^(-1/α) - 1)
//! sample_medium:  t = (α/σ_t) ((1-u)^(-1/(α+1)) - 1)
//! ```
//!
//! `α → ∞` is the exponential; `α → 0` becomes fully transparent (the
//! samplers then return huge distances, `f64::INFINITY` once they exceed
//! the `f64` range). The mean free path is finite only for `α > 1`.
//!
//! | parameter | units | valid range | default |
//! |---|---|---|---|
//! | `sigma_t` | 1/length | `0 < sigma_t < inf` | required |
//! | `alpha` | – | `0 < alpha < inf` | required |
//!
//! Scene:
//!
//! ```xml
//! <medium type="nonexponential" id="clouds">
//!     <string name="transmittance" value="davis"/>
//!     <float name="alpha" value="4.0"/>
//!     <float name="sigma_t" value="4.0"/>
//!     <rgb name="albedo" value="0.8"/>
//!     <string name="kernel" value="reciprocal"/>
//! </medium>
//! ```
//!
//! Python:
//!
//! ```python
//! import fgf
//! m = fgf.Davis(4.0, alpha=4.0)
//! m.tr(1.0)              # (1 + 1)^-4 = 0.0625
//! ```

use super::gamma::GammaCore;
use crate::error::{ParamError, Result};

/// Davis power law. See the module docs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Davis {
    alpha: f64,
    pub(crate) core: GammaCore,
}

impl Davis {
    /// Errors unless `sigma_t` and `alpha` are finite and > 0.
    pub fn new(sigma_t: f64, alpha: f64) -> Result<Self> {
        ParamError::check_positive("sigma_t", sigma_t)?;
        ParamError::check_positive("alpha", alpha)?;
        // x = σ t / α = k t with k = σ/α; k may overflow to inf for a
        // subnormal alpha, which the core treats as the α → 0 limit.
        Ok(Davis {
            alpha,
            core: GammaCore::new(sigma_t, sigma_t / alpha, 1.0),
        })
    }

    /// The shape parameter `α`.
    pub fn alpha(&self) -> f64 {
        self.alpha
    }
}
