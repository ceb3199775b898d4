//! The shading frame of a hit oriented by the surface tangent, as Mitsuba 3
//! orients its `sh_frame` (the frame in which an anisotropic BSDF's
//! `alpha_u` runs along `s`). Computed only for BSDFs that need it
//! ([`crate::world::World::frame_at`]); the others use [`Frame::from_normal`].
//!
//! `s` is `∂p/∂u` made orthogonal to the shading normal and normalised,
//! `t = n × s`; where `∂p/∂u` vanishes (a sphere's poles, a disk's centre)
//! `s, t` are [`Frame::from_normal`]'s. `∂p/∂u` follows each shape's
//! parameterisation (the texture coordinates of the module docs):
//!
//! * triangles and parallelograms with texture coordinates: the `u`
//!   derivative of the affine map from `(u, v)` to the face, or, when the
//!   face's `(u, v)` are degenerate (collinear), the first tangent of
//!   [`Frame::from_normal`] of the unflipped face normal `e1 × e2`;
//! * triangles without: the edge `e1` from the first to the second vertex
//!   (the barycentric parameterisation);
//! * `rectangle` (a parallelogram with `(u, v) = ((x + 1)/2, (y + 1)/2)`):
//!   `to_world · (2, 0, 0)`; `cube`: per face, the derivative of its affine
//!   map;
//! * `sphere`: `to_world · (-y, x, 0)` at the local point (the direction of
//!   increasing azimuth φ);
//! * `disk`: `to_world · (cos φ, sin φ, 0)` (the radial direction).
//!
//! Checked against `si.sh_frame` of the `mitsuba` package
//! (`tests/test_anisotropic.py`).

use super::types::{Hit, INDEX_MASK, KIND_SHIFT, KIND_SPHERE, KIND_TRI};
use super::Geometry;
use crate::math::Frame;
use glam::Vec3A;

impl Geometry {
    /// `∂p/∂u` at `hit` (world space, not normalised; zero where the
    /// parameterisation is singular).
    pub fn dp_du(&self, hit: &Hit) -> Vec3A {
        let i = (hit.prim & INDEX_MASK) as usize;
        match hit.prim >> KIND_SHIFT {
            KIND_TRI => {
                let t = self.tri(i);
                let (e1, e2) = (t.e1, t.e2);
                let Some(uv) = self.corner_uvs(&self.corners[i]) else {
                    return e1;
                };
                let (d1, d2) = (uv[1] - uv[0], uv[2] - uv[0]);
                let det = d1.x * d2.y - d1.y * d2.x;
                if det != 0.0 {
                    (d2.y * e1 - d1.y * e2) / det
                } else {
                    Frame::from_normal(e1.cross(e2).normalize()).s
                }
            }
            KIND_SPHERE => {
                let s = &self.spheres[i];
                let to_local = self.sphere_to_local[i];
                let l = to_local * (hit.p - s.center);
                to_local.inverse() * Vec3A::new(-l.y, l.x, 0.0)
            }
            _ => {
                let d = &self.disks[i];
                let q = d.to_local.transform_point3a(hit.p);
                let r = q.x.hypot(q.y);
                if r > 0.0 {
                    d.to_world
                        .transform_vector3a(Vec3A::new(q.x / r, q.y / r, 0.0))
                } else {
                    Vec3A::ZERO
                }
            }
        }
    }

    /// Mitsuba's shading frame at `hit`: normal `hit.ns`, `s` along
    /// `∂p/∂u` (see the module docs).
    #[inline(never)]
    pub fn shading_frame(&self, hit: &Hit) -> Frame {
        let n = hit.ns;
        let dp = self.dp_du(hit);
        if dp == Vec3A::ZERO {
            return Frame::from_normal(n);
        }
        match (dp - n * n.dot(dp)).try_normalize() {
            Some(s) => Frame {
                s,
                t: n.cross(s),
                n,
            },
            None => Frame::from_normal(n),
        }
    }
}
