//! The API every transmittance model implements: the [`Transmittance`]
//! trait.

/// A transmittance model and its reciprocal companions, in distance units
/// for the model's mean extinction `σ_m` (1/length): `t` is a distance, the
/// transmittances are dimensionless, `pdf` and the `*_medium` functions are
/// densities in 1/length. With `Tr = T_ss` (`docs/theory.md` §4):
///
/// | method | meaning |
/// |---|---|
/// | `tr(t)` = `surface_surface(t)` | `T_ss(t)`: a segment from a surface reaches a surface |
/// | `pdf(t)` = `surface_medium(t)` | `T_sm = -dTr/dt`: free-flight pdf from a surface (energy-conserving kernel's `p`) |
/// | `sigma_bar()` | `σ̄ = T_sm(0)` |
/// | `medium_surface(t)` | `T_ms = T_sm / σ̄`: a segment from a medium vertex reaches a surface |
/// | `medium_medium(t)` | `T_mm = -dT_ms/dt`: free-flight pdf from a medium vertex |
/// | `sample_surface(u)` | inverse of the cdf `1 - T_ss` |
/// | `sample_medium(u)` | inverse of the cdf `1 - T_ms` |
///
/// Medium–medium connections in the reciprocal kernel use `T_mm / σ̄`
/// (Bitterli's `eval` divides by `sigmaBar`); that division is the caller's.
/// The domain, limits and special values are those of the
/// [module docs](super).
///
/// Implemented by the four models and by [`Model`](super::Model), which
/// dispatches to them by `match` (static dispatch, no `dyn`):
///
/// ```
/// use fgf_core::transmittance::{Fgf, Model, Transmittance};
/// let pink = Fgf::new(4.0, -0.1, 4.0, None).unwrap();
/// let m = Model::from(pink);
/// assert_eq!(m.tr(0.3), pink.tr(0.3));
/// assert_eq!(m.surface_surface(0.3), m.tr(0.3));
/// let t = m.sample_surface(0.5);
/// assert!((m.tr(t) - 0.5).abs() < 1e-12);
/// ```
pub trait Transmittance {
    /// `Tr(t) = T_ss(t)`, dimensionless.
    fn tr(&self, t: f64) -> f64;
    /// `p(t) = -dTr/dt = T_sm(t)` (1/length): the free-flight pdf from a
    /// surface; `∫p = 1`.
    fn pdf(&self, t: f64) -> f64;
    /// `T_ss(t) = Tr(t)`.
    #[inline]
    fn surface_surface(&self, t: f64) -> f64 {
        self.tr(t)
    }
    /// `T_sm(t) = -dTr/dt = p(t)`.
    #[inline]
    fn surface_medium(&self, t: f64) -> f64 {
        self.pdf(t)
    }
    /// `T_ms(t) = T_sm(t) / σ̄`, dimensionless.
    fn medium_surface(&self, t: f64) -> f64;
    /// `T_mm(t) = -dT_ms/dt` (1/length): the free-flight pdf from a medium
    /// vertex.
    fn medium_medium(&self, t: f64) -> f64;
    /// `σ̄ = T_sm(0)` (1/length).
    fn sigma_bar(&self) -> f64;
    /// Mean extinction `σ_m` (1/length) the model was built with.
    fn sigma_t(&self) -> f64;
    /// Free-flight distance from a surface: solves `1 - T_ss(t) = u` for
    /// `u ∈ [0, 1)`.
    fn sample_surface(&self, u: f64) -> f64;
    /// Free-flight distance from a medium vertex: solves `1 - T_ms(t) = u`
    /// for `u ∈ [0, 1)`.
    fn sample_medium(&self, u: f64) -> f64;
}
