//! Rays and spawning them off surfaces: the one geometric type that media,
//! the camera and the geometry all need.

use glam::Vec3A;

/// A ray `o + t d` with unit `d`.
#[derive(Debug, Clone, Copy)]
pub struct Ray {
    pub o: Vec3A,
    pub d: Vec3A,
}

impl Ray {
    #[inline]
    pub fn at(&self, t: f32) -> Vec3A {
        self.o + t * self.d
    }
}

/// Relative size of the offset that moves a spawned ray off its surface:
/// `(1 + max|p|)·2⁻¹⁶`. Triangle and sphere hit points carry a rounding
/// error of a few ulps of `|p|` (≈ 1e-7·|p|); the offset is two orders of
/// magnitude above that, and still far below any feature of a scene in
/// metre-ish units. (Mitsuba uses a comparable `mint` of ≈ 9e-5·(1 + max|p|).)
const OFFSET_SCALE: f32 = 1.0 / 65536.0;

/// Offset of the hit point `p` along `n`, to the side `d` points to.
#[inline]
pub fn offset_point(p: Vec3A, n: Vec3A, d: Vec3A) -> Vec3A {
    let eps = (1.0 + p.abs().max_element()) * OFFSET_SCALE;
    if d.dot(n) >= 0.0 {
        p + eps * n
    } else {
        p - eps * n
    }
}

/// Distance to stop a shadow ray short of a sampled light point `q`, so that
/// it does not hit the light's own surface.
#[inline]
pub fn shadow_epsilon(q: Vec3A) -> f32 {
    4.0 * (1.0 + q.abs().max_element()) * OFFSET_SCALE
}
