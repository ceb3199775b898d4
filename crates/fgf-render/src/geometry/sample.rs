//! Uniform area sampling of a shape, for area lights.

use super::types::{
    Hit, PositionSample, ShapeSampling, KIND_DISK, KIND_SHIFT, KIND_SPHERE, KIND_TRI,
};
use super::Geometry;
use crate::math::{sample_concentric_disk, sample_uniform_sphere, sample_uniform_triangle};
use glam::Vec3A;

impl Geometry {
    /// A point uniformly distributed (by area) on shape `shape`; the pdf
    /// with respect to area is `1 / areas[shape]`.
    #[inline]
    pub fn sample_shape(&self, shape: usize, u_sel: f32, u: [f32; 2]) -> PositionSample {
        self.sample_shape_prim(shape, u_sel, u).0
    }

    /// The point [`Self::sample_shape`] gives for the same variates, as a
    /// [`Hit`] (with its primitive and barycentrics, for
    /// [`Self::uv`]); `t` is zero.
    pub(crate) fn sample_shape_hit(&self, shape: usize, u_sel: f32, u: [f32; 2]) -> Hit {
        let (ps, prim, bary) = self.sample_shape_prim(shape, u_sel, u);
        Hit {
            t: 0.0,
            p: ps.p,
            n: ps.n,
            ns: ps.ns,
            shape: shape as u32,
            prim,
            bary,
        }
    }

    /// The sample and its primitive and barycentrics (dropped, unused, by
    /// [`Self::sample_shape`]).
    #[inline(always)]
    fn sample_shape_prim(
        &self,
        shape: usize,
        u_sel: f32,
        u: [f32; 2],
    ) -> (PositionSample, u32, [f32; 2]) {
        match &self.sampling[shape] {
            ShapeSampling::Tris { first, cdf } => {
                // Choose a triangle by area, then a uniform point on it.
                let k = cdf.partition_point(|&c| c <= u_sel).min(cdf.len() - 1);
                let t = self.tri(*first as usize + k);
                let b = if t.quad {
                    u
                } else {
                    sample_uniform_triangle(u)
                };
                let ns = self.shading_normal(&self.corners[*first as usize + k], b, t.n);
                (
                    PositionSample {
                        p: t.v0 + b[0] * t.e1 + b[1] * t.e2,
                        n: t.n,
                        ns,
                    },
                    (KIND_TRI << KIND_SHIFT) | (*first + k as u32),
                    b,
                )
            }
            ShapeSampling::Sphere(i) => {
                let s = &self.spheres[*i as usize];
                let d = sample_uniform_sphere(u);
                (
                    PositionSample {
                        p: s.center + s.radius * d,
                        n: d * s.sign,
                        ns: d * s.sign,
                    },
                    (KIND_SPHERE << KIND_SHIFT) | *i,
                    [0.0; 2],
                )
            }
            ShapeSampling::Disk(i) => {
                let d = &self.disks[*i as usize];
                let q = sample_concentric_disk(u);
                (
                    PositionSample {
                        p: d.to_world.transform_point3a(Vec3A::new(q[0], q[1], 0.0)),
                        n: d.n,
                        ns: d.n,
                    },
                    (KIND_DISK << KIND_SHIFT) | *i,
                    [0.0; 2],
                )
            }
        }
    }
}
