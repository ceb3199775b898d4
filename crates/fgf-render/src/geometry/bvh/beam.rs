//! Beam traversal: a bundle of up to 16 nearly parallel rays, such as the
//! camera rays of the samples of one pixel, walks the 8-wide tree once
//! for all of them.
//!
//! Each node's boxes are tested against the bundle with interval
//! arithmetic (`docs/theory.md` §7.18): per axis, the rays' origin
//! components lie in `[o_min, o_max]` and their inverse direction
//! components in `[i_lo, i_hi]`, all of one sign, so a lower bound of
//! every ray's entry distance into a slab and an upper bound of every
//! ray's exit distance are each the extreme of two products. A box that
//! this test rejects is rejected by every ray's own slab test
//! ([`Bvh::walk`]), also with rounding: a rounded difference or product is
//! monotone in each operand, so the bounds hold for the rounded values the
//! single-ray test computes. A bundle whose direction components change
//! sign along an axis, or are 0, has no beam ([`Beam::new`] returns
//! `None`); its rays are traced one by one.
//!
//! At a leaf, the rays test its box eight at a time ([`Bvh::leaf_may_hit8`],
//! each lane by the operations of the ray's own test), and those that may
//! hit it test its primitives one by one, with the same code as a single
//! ray (`Geometry::intersect_beam`), so every ray gets the nearest hit it
//! would get alone: the same distance and primitive (of primitives hit at
//! exactly the same distance, both keep the least id, whatever order the
//! leaves come in).

use super::{fixed_stack, slab_hit_finite8, slab_planes, Bvh, Entry, F8, PACK, STACK};
use crate::ray::Ray;
use glam::Vec3A;

/// Most rays in a beam. The node test does not depend on the number of
/// rays; more share each node's fetch and test (16 took the depth-1 mesh
/// render 14 % less time than 8, see `docs/benchmarks.md`).
pub const BEAM: usize = 16;

/// The interval bounds of a bundle of rays (see the module docs).
#[derive(Debug, Clone, Copy)]
pub struct Beam {
    /// Per axis, the origin component that bounds the entry distances
    /// from below (the largest if the directions are positive along the
    /// axis, else the smallest), and the one that bounds the exit
    /// distances from above.
    o_near: [f32; 3],
    o_far: [f32; 3],
    /// Per axis, the least and greatest inverse direction component.
    inv_lo: [f32; 3],
    inv_hi: [f32; 3],
    /// Per axis, whether the directions are negative along it.
    neg: [bool; 3],
}

impl Beam {
    /// The beam of `rays`, whose inverse directions are `inv_d` (as
    /// `d.recip()` computes them, which the single-ray traversal uses too),
    /// or `None` if there are no rays or along some axis their direction
    /// components differ in sign or one has no finite non-zero inverse.
    pub fn new(rays: &[Ray], inv_d: &[Vec3A]) -> Option<Beam> {
        let (mut o_min, mut o_max) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
        let (mut lo, mut hi) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
        // Bit `a` set while every ray's inverse is positive (negative)
        // along axis `a`, and it and the origin component are finite.
        let (mut pos, mut neg) = (7u32, 7u32);
        for (r, &inv) in rays.iter().zip(inv_d) {
            let finite = (inv.is_finite_mask() & r.o.is_finite_mask()).bitmask();
            pos &= inv.cmpgt(Vec3A::ZERO).bitmask() & finite;
            neg &= inv.cmplt(Vec3A::ZERO).bitmask() & finite;
            (lo, hi) = (lo.min(inv), hi.max(inv));
            (o_min, o_max) = (o_min.min(r.o), o_max.max(r.o));
        }
        if rays.is_empty() || pos | neg != 7 {
            return None;
        }
        let neg = [neg & 1 != 0, neg & 2 != 0, neg & 4 != 0];
        let (mut o_near, mut o_far) = (o_max.to_array(), o_min.to_array());
        for a in 0..3 {
            if neg[a] {
                (o_near[a], o_far[a]) = (o_min[a], o_max[a]);
            }
        }
        Some(Beam {
            o_near,
            o_far,
            inv_lo: lo.to_array(),
            inv_hi: hi.to_array(),
            neg,
        })
    }
}

impl Bvh {
    /// Visit the leaves whose boxes some ray of `beam` may hit before
    /// `t_max` (the greatest of the rays' own limits), nearer boxes first:
    /// `hit(start, count, t_max)` as in [`Bvh::traverse_leaves`], returning
    /// the new greatest limit of the rays.
    #[inline]
    pub fn traverse_leaves_beam(
        &self,
        beam: &Beam,
        t_max: f32,
        mut hit: impl FnMut(u32, u32, f32) -> f32,
    ) -> f32 {
        let (start, count) = self.root_leaf;
        if count > 0 {
            return hit(start, count, t_max);
        }
        if self.nodes.is_empty() {
            return t_max;
        }
        if self.stack_need <= STACK {
            self.walk_beam(&mut fixed_stack(), beam, t_max, &mut hit)
        } else {
            self.walk_beam(
                &mut vec![Entry::uninit(); self.stack_need],
                beam,
                t_max,
                &mut hit,
            )
        }
    }

    /// Which of eight rays of a beam (origins `o`, inverse directions
    /// `inv_d`, all finite as [`Beam::new`] requires, and limits `t_max`,
    /// in lanes) may hit the box of the leaf starting at primitive `start`
    /// before their limits: the mask of those lanes. Each lane gets the
    /// answer of the ray's own slab test (`slab_hit_finite8`).
    #[inline(always)]
    pub(crate) fn leaf_may_hit8(&self, start: u32, o: &[F8; 3], inv_d: &[F8; 3], t_max: F8) -> u32 {
        let b = &self.leaf_boxes[start as usize / PACK];
        slab_hit_finite8(b.min, b.max, o, inv_d, t_max)
    }

    /// [`Bvh::walk`] for a beam: the same order and culling, with the
    /// interval slab test.
    #[inline(never)]
    fn walk_beam(
        &self,
        stack: &mut [Entry],
        beam: &Beam,
        t_max: f32,
        hit: &mut impl FnMut(u32, u32, f32) -> f32,
    ) -> f32 {
        let splat3 = |v: [f32; 3]| [F8::splat(v[0]), F8::splat(v[1]), F8::splat(v[2])];
        let (o_near, o_far) = (splat3(beam.o_near), splat3(beam.o_far));
        let (lo, hi) = (splat3(beam.inv_lo), splat3(beam.inv_hi));
        let (near, far) = slab_planes(beam.neg);
        let zero = F8::splat(0.0);
        self.walk_with::<true>(
            stack,
            t_max,
            #[inline(always)]
            |b, t_max| {
                // The least entry and the greatest exit distance of the
                // rays per slab: the extremes of the two products of the
                // bounding difference with the extreme inverses.
                let entry = |a: usize| {
                    let x = b[near[a]].sub(o_near[a]);
                    x.mul(lo[a]).min(x.mul(hi[a]))
                };
                let exit = |a: usize| {
                    let x = b[far[a]].sub(o_far[a]);
                    x.mul(lo[a]).max(x.mul(hi[a]))
                };
                let tn = entry(0).max(entry(1).max(entry(2).max(zero)));
                let tf = exit(0).min(exit(1).min(exit(2).min(F8::splat(t_max))));
                (tn, tf)
            },
            hit,
        )
    }
}
