//! The renderer's one colour type, [`Spectrum`]: linear RGB radiance,
//! throughput and per-channel coefficients (σ_t, albedo), with the one
//! conversion from the scene description's [`Rgb`].

use fgf_scene::Rgb;
use glam::Vec3A;

/// Linear RGB radiance/throughput; component-wise arithmetic. glam's
/// 16-byte `Vec3A`, like the renderer's points and directions: one SSE
/// instruction per operation on the three components, where glam's `Vec3`
/// takes three (see `docs/benchmarks.md`, "Vec3A").
pub type Spectrum = Vec3A;

/// The scene description's colour as a [`Spectrum`].
#[inline]
pub fn from_rgb(c: Rgb) -> Spectrum {
    Vec3A::from_array(c)
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
