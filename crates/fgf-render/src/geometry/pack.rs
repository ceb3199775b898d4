//! The 8-wide leaf test: the triangles of a BVH leaf are stored in a pack
//! of 8 and intersected at once (the leaves start at multiples of
//! [`super::bvh::PACK`]).

use super::bvh::PACK;
use super::types::{Tri, INDEX_MASK, KIND_SHIFT, KIND_TRI, PAD};
use crate::lanes::{F8, M8};
use crate::ray::Ray;

/// Eight triangles in structure-of-arrays form, intersected at once with
/// AVX ([`F8`]; two SSE halves in a portable build) by projection onto precomputed planes: with
/// `N = e1 × e2`, a point `P` of the plane is `v0 + u e1 + v e2` for
/// `u = (P - v0)·a`, `v = (P - v0)·b`, where `a = (e2 × N)/|N|²` and
/// `b = (N × e1)/|N|²`. That is about 35 operations per pack against
/// Möller–Trumbore's 55, which derives the equivalent of `N`, `a`, `b` per
/// ray. Lanes without a triangle have `N = 0`, so `t` is NaN and they never
/// hit.
///
/// A pack is its 12 vectors, 6 whole cache lines (64-byte aligned): every
/// byte less counts on large meshes, whose packs outgrow the last-level
/// cache (`docs/benchmarks.md`). Parallelograms (tested for `v ≤ 1`
/// instead of `u + v ≤ 1`; `u ≤ 1` is tested for both) are marked by the
/// sign bit of `N.x`: `N` is stored as `±N`, which changes no bit of `t`
/// (both dot products change sign, exactly), with the sign bit of `N.x`
/// set for parallelograms and clear for triangles. Which lanes hold
/// spheres or disks is kept apart ([`TriPack::new`]).
#[derive(Debug, Clone, Copy)]
#[repr(C, align(64))]
pub(super) struct TriPack {
    v0: [F8; 3],
    n: [F8; 3],
    a: [F8; 3],
    b: [F8; 3],
}

impl TriPack {
    /// The pack of the (up to) 8 primitive references `chunk`: its
    /// triangles (`tri` of the references' indices) go to the SIMD lanes,
    /// spheres and disks only to the returned mask of their lanes, padding
    /// is left empty.
    pub(super) fn new(chunk: &[u32], tri: impl Fn(usize) -> Tri) -> (TriPack, u8) {
        let mut v0 = [[0f32; PACK]; 3];
        let mut n = [[0f32; PACK]; 3];
        let mut a = [[0f32; PACK]; 3];
        let mut b = [[0f32; PACK]; 3];
        let mut other = 0u8;
        for (lane, &p) in chunk.iter().enumerate() {
            if p == PAD {
                continue;
            }
            if p >> KIND_SHIFT == KIND_TRI {
                let t = tri((p & INDEX_MASK) as usize);
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
                // The sign bit of N.x: set for parallelograms (see above).
                if n[0][lane].is_sign_negative() != t.quad {
                    for nk in &mut n {
                        nk[lane] = -nk[lane];
                    }
                }
            } else {
                other |= 1 << lane;
            }
        }
        let v = |a: [[f32; PACK]; 3]| a.map(F8::from_array);
        let pack = TriPack {
            v0: v(v0),
            n: v(n),
            a: v(a),
            b: v(b),
        };
        (pack, other)
    }

    /// The 8 triangles against one ray: the mask of triangle lanes hit
    /// with `0 < t < t_max` (with `TIES`, `0 < t <= t_max`), and every
    /// lane's `t`, `u`, `v`.
    #[inline(always)]
    pub(super) fn hits<const TIES: bool>(
        &self,
        o: [F8; 3],
        d: [F8; 3],
        t_max: f32,
    ) -> (u32, F8, F8, F8) {
        let (ok, t, u, v) = self.test::<TIES>(o, d, t_max);
        (ok.bitmask(), t, u, v)
    }

    /// The two nearest of [`Self::hits`] (without ties), nearer first, as
    /// `(lane, t, u, v)`; of hits at the same distance, the lesser lane
    /// first. This is what [`Self::hits`] gives a query that keeps the two
    /// nearest hits it is shown in lane order, found here without a
    /// branch per hit (the lone pack of a scene of a few primitives).
    #[inline(always)]
    pub(super) fn two_nearest(
        &self,
        o: [F8; 3],
        d: [F8; 3],
        t_max: f32,
    ) -> [Option<(usize, f32, f32, f32)>; 2] {
        let Some((t, t0, u, v)) = self.least(o, d, t_max) else {
            return [None, None];
        };
        let inf = F8::splat(f32::INFINITY);
        let (u, v) = (u.to_array(), v.to_array());
        let at = |l: u32, t: f32| {
            let l = l as usize;
            (l, t, u[l], v[l])
        };
        let nearest = t.le(F8::splat(t0));
        let lanes0 = nearest.bitmask();
        let first = at(lanes0.trailing_zeros(), t0);
        let rest = lanes0 & (lanes0 - 1);
        if rest != 0 {
            return [Some(first), Some(at(rest.trailing_zeros(), t0))];
        }
        let t = nearest.select(inf, t);
        let t1 = t.hmin();
        if t1 == f32::INFINITY {
            return [Some(first), None];
        }
        let l1 = t.le(F8::splat(t1)).bitmask().trailing_zeros();
        [Some(first), Some(at(l1, t1))]
    }

    /// The nearest of [`Self::hits`] (without ties) as `(lane, t, u, v)`;
    /// of hits at the same distance, that of the least primitive id in
    /// `prims` (the pack's references, by lane), as the walk's nearest-hit
    /// query chooses.
    #[inline(always)]
    pub(super) fn nearest(
        &self,
        o: [F8; 3],
        d: [F8; 3],
        t_max: f32,
        prims: &[u32],
    ) -> Option<(usize, f32, f32, f32)> {
        let (t, t0, u, v) = self.least(o, d, t_max)?;
        let mut lanes = t.le(F8::splat(t0)).bitmask();
        let mut best = lanes.trailing_zeros() as usize;
        lanes &= lanes - 1;
        while lanes != 0 {
            let l = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            if prims[l] < prims[best] {
                best = l;
            }
        }
        Some((best, t0, u.to_array()[best], v.to_array()[best]))
    }

    /// [`Self::hits`] (without ties) as the lanes' distances, +∞ where
    /// not hit, with the least of them (finite: below `t_max`) and the
    /// lanes' `u`, `v`; `None` if no lane is hit.
    #[inline(always)]
    fn least(&self, o: [F8; 3], d: [F8; 3], t_max: f32) -> Option<(F8, f32, F8, F8)> {
        let (ok, t, u, v) = self.test::<false>(o, d, t_max);
        let t = ok.select(t, F8::splat(f32::INFINITY));
        let t0 = t.hmin();
        (t0 != f32::INFINITY).then_some((t, t0, u, v))
    }

    /// The test behind [`Self::hits`], its hit lanes as a lane mask.
    #[inline(always)]
    fn test<const TIES: bool>(&self, o: [F8; 3], d: [F8; 3], t_max: f32) -> (M8, F8, F8, F8) {
        // Sums left to right, as `a.x * b.x + a.y * b.y + a.z * b.z`.
        let dot = |a: &[F8; 3], b: &[F8; 3]| a[0].mul(b[0]).add(a[1].mul(b[1])).add(a[2].mul(b[2]));
        let w = [
            self.v0[0].sub(o[0]),
            self.v0[1].sub(o[1]),
            self.v0[2].sub(o[2]),
        ];
        // A ray parallel to the plane (or an empty lane) gives ±inf or NaN,
        // and NaN fails every comparison below.
        let t = dot(&w, &self.n).div(dot(&d, &self.n));
        // P - v0 = t d - w.
        let u = t.mul(dot(&d, &self.a)).sub(dot(&w, &self.a));
        let v = t.mul(dot(&d, &self.b)).sub(dot(&w, &self.b));
        let (zero, one) = (F8::splat(0.0), F8::splat(1.0));
        let ok = zero
            .le(u)
            .and(zero.le(v))
            .and(u.le(one))
            .and(zero.lt(t))
            .and(if TIES {
                t.le(F8::splat(t_max))
            } else {
                t.lt(F8::splat(t_max))
            });
        // The last edge: `u + v ≤ 1` for triangles, `v ≤ 1` for
        // parallelograms (the sign bit of N.x).
        let edge = self.n[0].sign_mask().select(v, u.add(v));
        (ok.and(edge.le(one)), t, u, v)
    }
}

/// A ray's origin and direction splatted for the 8-wide tests.
#[inline(always)]
pub(super) fn splat_ray(ray: &Ray) -> ([F8; 3], [F8; 3]) {
    (
        ray.o.to_array().map(F8::splat),
        ray.d.to_array().map(F8::splat),
    )
}
