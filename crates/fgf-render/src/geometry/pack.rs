//! The 4-wide leaf test: the triangles of a BVH leaf are stored in packs
//! of 4 and intersected at once (the leaves start at multiples of
//! [`super::bvh::PACK`]).

use super::types::{Tri, INDEX_MASK, KIND_SHIFT, KIND_TRI, PAD};
use crate::ray::Ray;
use glam::Vec4;

/// Four triangles in structure-of-arrays form, intersected at once with
/// SSE (glam's `Vec4`) by projection onto precomputed planes: with
/// `N = e1 × e2`, a point `P` of the plane is `v0 + u e1 + v e2` for
/// `u = (P - v0)·a`, `v = (P - v0)·b`, where `a = (e2 × N)/|N|²` and
/// `b = (N × e1)/|N|²`. That is about 35 operations per pack against
/// Möller–Trumbore's 55, which derives the equivalent of `N`, `a`, `b` per
/// ray. Lanes without a triangle have `N = 0`, so `t` is NaN and they never
/// hit.
#[derive(Debug, Clone, Copy)]
pub(super) struct TriPack {
    v0: [Vec4; 3],
    n: [Vec4; 3],
    a: [Vec4; 3],
    b: [Vec4; 3],
    /// Per lane: 1 for a triangle (`u + v ≤ 1`), 0 for a parallelogram
    /// (`v ≤ 1`); `u ≤ 1` is tested for both.
    tri_k: Vec4,
    /// Lanes holding triangles / other primitives (spheres, disks).
    pub(super) tri_mask: u32,
    pub(super) other_mask: u32,
}

impl TriPack {
    /// The pack of the (up to) 4 primitive references `chunk`: its
    /// triangles (`tris` indexed by the references) go to the SIMD lanes,
    /// spheres and disks are only flagged, padding is left empty.
    pub(super) fn new(chunk: &[u32], tris: &[Tri]) -> TriPack {
        let mut v0 = [[0f32; 4]; 3];
        let mut n = [[0f32; 4]; 3];
        let mut a = [[0f32; 4]; 3];
        let mut b = [[0f32; 4]; 3];
        let (mut tri_mask, mut other_mask) = (0u32, 0u32);
        let mut tri_k = [1f32; 4];
        for (lane, &p) in chunk.iter().enumerate() {
            if p == PAD {
                continue;
            }
            if p >> KIND_SHIFT == KIND_TRI {
                let t = &tris[(p & INDEX_MASK) as usize];
                // In f64: a and b divide by |N|², which can be tiny.
                let (e1, e2) = (t.e1.as_dvec3(), t.e2.as_dvec3());
                let nn = e1.cross(e2);
                let ta = e2.cross(nn) / nn.length_squared();
                let tb = nn.cross(e1) / nn.length_squared();
                for k in 0..3 {
                    v0[k][lane] = t.v0[k];
                    n[k][lane] = nn[k] as f32;
                    a[k][lane] = ta[k] as f32;
                    b[k][lane] = tb[k] as f32;
                }
                if t.quad {
                    tri_k[lane] = 0.0;
                }
                tri_mask |= 1 << lane;
            } else {
                other_mask |= 1 << lane;
            }
        }
        let v = |a: [[f32; 4]; 3]| a.map(Vec4::from_array);
        TriPack {
            v0: v(v0),
            n: v(n),
            a: v(a),
            b: v(b),
            tri_k: Vec4::from_array(tri_k),
            tri_mask,
            other_mask,
        }
    }

    /// The 4 triangles against one ray: the mask of triangle lanes hit
    /// with `0 < t < t_max`, and every lane's `t`, `u`, `v`.
    #[inline(always)]
    pub(super) fn hits(&self, o: [Vec4; 3], d: [Vec4; 3], t_max: f32) -> (u32, Vec4, Vec4, Vec4) {
        let dot = |a: &[Vec4; 3], b: &[Vec4; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let w = [self.v0[0] - o[0], self.v0[1] - o[1], self.v0[2] - o[2]];
        // A ray parallel to the plane (or an empty lane) gives ±inf or NaN,
        // and NaN fails every comparison below.
        let t = dot(&w, &self.n) / dot(&d, &self.n);
        // P - v0 = t d - w.
        let u = t * dot(&d, &self.a) - dot(&w, &self.a);
        let v = t * dot(&d, &self.b) - dot(&w, &self.b);
        let zero = Vec4::ZERO;
        let ok = u.cmpge(zero)
            & v.cmpge(zero)
            & u.cmple(Vec4::ONE)
            & (u * self.tri_k + v).cmple(Vec4::ONE)
            & t.cmpgt(zero)
            & t.cmplt(Vec4::splat(t_max));
        (ok.bitmask() & self.tri_mask, t, u, v)
    }
}

/// A ray's origin and direction splatted for the 4-wide tests.
#[inline(always)]
pub(super) fn splat_ray(ray: &Ray) -> ([Vec4; 3], [Vec4; 3]) {
    (
        ray.o.to_array().map(Vec4::splat),
        ray.d.to_array().map(Vec4::splat),
    )
}
