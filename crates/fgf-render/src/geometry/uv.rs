//! Texture coordinates of a hit (parameterisations in the parent module's
//! docs), computed on demand from the hit's primitive and barycentrics.

use super::types::{Hit, INDEX_MASK, KIND_SHIFT, KIND_SPHERE, KIND_TRI};
use super::Geometry;
use glam::{Vec2, Vec3A};
use std::f32::consts::{FRAC_1_PI, TAU};

/// `atan2(y, x)` mapped to `[0, 1)` (Mitsuba adds 2π to a negative angle).
#[inline]
fn turn(y: f32, x: f32) -> f32 {
    let phi = y.atan2(x);
    (if phi < 0.0 { phi + TAU } else { phi }) / TAU
}

impl Geometry {
    /// The texture coordinates `(u, v)` at `hit`.
    pub fn uv(&self, hit: &Hit) -> Vec2 {
        let i = (hit.prim & INDEX_MASK) as usize;
        let [a, b] = hit.bary;
        match hit.prim >> KIND_SHIFT {
            KIND_TRI => {
                let Some(uv) = self.corner_uvs(&self.corners[i]) else {
                    return Vec2::new(a, b);
                };
                (1.0 - a - b) * uv[0] + a * uv[1] + b * uv[2]
            }
            KIND_SPHERE => {
                let s = &self.spheres[i];
                let d = (self.sphere_to_local[i] * (hit.p - s.center)).normalize_or(Vec3A::Z);
                Vec2::new(turn(d.y, d.x), d.z.clamp(-1.0, 1.0).acos() * FRAC_1_PI)
            }
            _ => {
                let q = self.disks[i].to_local.transform_point3a(hit.p);
                Vec2::new(q.x.hypot(q.y), turn(q.y, q.x))
            }
        }
    }
}

/// Mitsuba 3's `cube` texture coordinates on the face of outward normal
/// `sign · e_axis`, at the local point `p` (in `[-1, 1]³`): each face maps
/// affinely onto the unit square (checked against the `mitsuba` package).
pub(super) fn cube_uv(axis: usize, sign: f32, p: Vec3A) -> Vec2 {
    let h = |x: f32| 0.5 * (x + 1.0);
    let g = |x: f32| 0.5 * (1.0 - x);
    match (axis, sign > 0.0) {
        (0, true) => Vec2::new(h(p.y), g(p.z)),
        (0, false) => Vec2::new(h(p.y), h(p.z)),
        (1, true) => Vec2::new(g(p.x), g(p.z)),
        (1, false) => Vec2::new(h(p.z), h(p.x)),
        (_, true) => Vec2::new(h(p.y), h(p.x)),
        (_, false) => Vec2::new(g(p.y), h(p.x)),
    }
}
