//! Uniform area sampling of a shape, for area lights.

use super::types::{PositionSample, ShapeSampling};
use super::Geometry;
use crate::math::{sample_concentric_disk, sample_uniform_sphere, sample_uniform_triangle};
use glam::Vec3;

impl Geometry {
    /// A point uniformly distributed (by area) on shape `shape`; the pdf
    /// with respect to area is `1 / areas[shape]`.
    pub fn sample_shape(&self, shape: usize, u_sel: f32, u: [f32; 2]) -> PositionSample {
        match &self.sampling[shape] {
            ShapeSampling::Tris { first, cdf } => {
                // Choose a triangle by area, then a uniform point on it.
                let k = cdf.partition_point(|&c| c <= u_sel).min(cdf.len() - 1);
                let t = &self.tris[*first as usize + k];
                let b = if t.quad {
                    u
                } else {
                    sample_uniform_triangle(u)
                };
                let ns = if t.normals != u32::MAX {
                    let vn = &self.vertex_normals[t.normals as usize];
                    let n = (1.0 - b[0] - b[1]) * vn[0] + b[0] * vn[1] + b[1] * vn[2];
                    n.try_normalize().unwrap_or(t.n)
                } else {
                    t.n
                };
                PositionSample {
                    p: (t.v0 + b[0] * t.e1 + b[1] * t.e2).into(),
                    n: t.n,
                    ns,
                }
            }
            ShapeSampling::Sphere(i) => {
                let s = &self.spheres[*i as usize];
                let d = sample_uniform_sphere(u);
                PositionSample {
                    p: s.center + s.radius * d,
                    n: d * s.sign,
                    ns: d * s.sign,
                }
            }
            ShapeSampling::Disk(i) => {
                let d = &self.disks[*i as usize];
                let q = sample_concentric_disk(u);
                PositionSample {
                    p: d.to_world.transform_point3(Vec3::new(q[0], q[1], 0.0)),
                    n: d.n,
                    ns: d.n,
                }
            }
        }
    }
}
