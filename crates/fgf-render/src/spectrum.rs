//! The renderer's one colour type, [`Spectrum`]: linear RGB radiance,
//! throughput and per-channel coefficients (σ_t, albedo), with the one
//! conversion from the scene description's [`Rgb`].

use fgf_scene::Rgb;
use glam::Vec3;

/// Linear RGB radiance/throughput; component-wise arithmetic.
pub type Spectrum = Vec3;

/// The scene description's colour as a [`Spectrum`].
#[inline]
pub fn from_rgb(c: Rgb) -> Spectrum {
    Vec3::from_array(c)
}

/// Largest component (Russian roulette, majorants).
#[inline]
pub fn max_comp(s: Spectrum) -> f32 {
    s.x.max(s.y).max(s.z)
}

/// Mean of the three channels (the one-sample spectral MIS mixture).
#[inline]
pub fn mean(s: Spectrum) -> f32 {
    (s.x + s.y + s.z) * (1.0 / 3.0)
}
