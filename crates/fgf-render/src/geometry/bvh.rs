//! A bounding volume hierarchy over every primitive of the scene (triangles
//! of all meshes, spheres, disks): a binned surface-area-heuristic build
//! (12 bins per axis, leaves of at most 8 primitives, tested as one SIMD
//! pack of 8, with the SAH cost counted in packs), collapsed into an
//! 8-wide tree whose nodes hold their children's boxes in SIMD form
//! (`F8`: AVX, or two SSE halves in a portable build), and traversed
//! nearest child first with a small stack.
//!
//! We wrote our own rather than depend on a crate: it is a few hundred
//! lines, its leaves mix triangles with analytic spheres and disks, and it
//! tests leaf triangles 8 at a time (`TriPack` in `geometry/pack.rs`),
//! which is what matters for scenes of a handful of primitives like the
//! reference ones. On the homogeneous reference scene, SIMD slab tests and
//! 4-wide leaf packs made the whole renderer 15 % faster than per-triangle
//! tests; counting a node visit as 2 pack tests in the SAH (one leaf for
//! its 8 primitives) another 9 %, and one 8-wide pack instead of two 4-wide
//! ones another 9.6 % of its instructions (see `docs/benchmarks.md`). On a
//! 120,000-triangle mesh, 4-wide nodes (one SIMD slab test for four boxes,
//! the children visited by entry distance, pending ones skipped once a hit
//! is nearer than their boxes) took 17 % off the render's instructions
//! against the binary tree visited in split-axis order; 8-wide nodes
//! another 4.4 %, 8-wide leaf packs 3.4 % more, and a fast path for nodes
//! with two children hit 2.6 % more.

mod beam;

pub use beam::{Beam, BEAM};

use crate::lanes::F8;
use crate::math::bin_index;
use glam::Vec3A;
use std::mem::MaybeUninit;

/// Axis-aligned bounding box.
#[derive(Debug, Clone, Copy)]
pub struct Aabb {
    pub min: Vec3A,
    pub max: Vec3A,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: Vec3A::splat(f32::INFINITY),
        max: Vec3A::splat(f32::NEG_INFINITY),
    };

    #[inline]
    pub fn union(self, o: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }
    #[inline]
    pub fn grow(self, p: Vec3A) -> Aabb {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }
    #[inline]
    pub fn centroid(&self) -> Vec3A {
        0.5 * (self.min + self.max)
    }
    pub fn surface_area(&self) -> f32 {
        let d = (self.max - self.min).max(Vec3A::ZERO);
        2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
    }
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x
    }

    /// Slab test; returns the entry and exit distances clipped to `[0, t_max]`.
    #[inline]
    pub fn intersect(&self, o: Vec3A, inv_d: Vec3A, t_max: f32) -> Option<(f32, f32)> {
        let (tn, tf) = slab_interval(self.min, self.max, o, inv_d, t_max);
        // The factor 1 + 2γ(3) (pbrt) makes the test conservative against
        // the rounding of the differences and products of `slab_interval`.
        if tn <= tf * 1.000_000_4 {
            Some((tn, tf))
        } else {
            None
        }
    }
}

/// A node of the binary tree that the build makes.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Node {
    min: Vec3A,
    max: Vec3A,
    /// Leaf: first primitive in `order`; interior: index of the second child
    /// (the first child follows the node directly).
    offset: u32,
    /// Number of primitives of a leaf, 0 for an interior node.
    count: u16,
}

impl Node {
    fn area(&self) -> f32 {
        Aabb {
            min: self.min,
            max: self.max,
        }
        .surface_area()
    }
}

/// The width of the tree: children per node.
const WIDTH: usize = 8;

/// A node of the 8-wide tree: the boxes of up to 8 children, one SIMD
/// lane each, so that one slab test on [`F8`]s tests them all. Lanes
/// without a child hold an empty box (lower bounds +∞, upper −∞), which
/// no ray hits: its entry distance is +∞ and its exit −∞ whatever the
/// direction (no NaN: the bounds are infinite, never equal to the origin).
#[derive(Debug, Clone, Copy)]
struct Node8 {
    /// Lower x, y, z then upper x, y, z bounds of the children.
    bounds: [F8; 6],
    /// Per lane: a [`Node8`] index, or a leaf (`LEAF` set; see [`leaf_ref`]).
    child: [u32; WIDTH],
}

/// A sorting network of eight keys (19 compare-exchanges in 6 layers).
const SORT8: [(usize, usize); 19] = [
    (0, 2),
    (1, 3),
    (4, 6),
    (5, 7),
    (0, 4),
    (1, 5),
    (2, 6),
    (3, 7),
    (0, 1),
    (2, 3),
    (4, 5),
    (6, 7),
    (2, 4),
    (3, 5),
    (1, 4),
    (3, 6),
    (1, 2),
    (3, 4),
    (5, 6),
];

/// Marks a child reference of a [`Node8`] as a leaf.
const LEAF: u32 = 1 << 31;
/// Stack entries of the traversal on the stack (deeper trees, which only
/// degenerate inputs make, get a heap stack).
const STACK: usize = 64;

/// An entry of a walk's stack: a child still to visit and the distance
/// where the ray (or beam) enters its box. The stacks start uninitialised:
/// zeroing the 512 bytes of the fixed one before every walk took 16 stores,
/// and a walk reads only the entries it has pushed.
type Entry = MaybeUninit<(u32, f32)>;

/// A fixed stack of [`STACK`] entries, not initialised.
#[inline(always)]
fn fixed_stack() -> [Entry; STACK] {
    [const { MaybeUninit::uninit() }; STACK]
}

/// The reference to the leaf of primitives `start..start + count` (`start`
/// a multiple of [`PACK`], `1 <= count <= MAX_LEAF`).
fn leaf_ref(start: u32, count: u32) -> u32 {
    // 27 bits of packs: more primitives than any scene that fits in memory.
    debug_assert!(start / (PACK as u32) < 1 << 27 && (1..=16).contains(&count));
    LEAF | (start / PACK as u32) << 4 | (count - 1)
}

/// The range (start, count) of a leaf reference.
#[inline(always)]
fn leaf_range(r: u32) -> (u32, u32) {
    (((r & !LEAF) >> 4) * PACK as u32, (r & 15) + 1)
}

/// The hierarchy. Its leaves are ranges of the primitive order that
/// [`Bvh::build`] returns.
#[derive(Debug, Clone)]
pub struct Bvh {
    nodes: Vec<Node8>,
    /// The primitive range (start, count) of a root that is a leaf; count
    /// 0 if the root is `nodes[0]` or there are no primitives.
    root_leaf: (u32, u32),
    /// Bounds of the whole scene.
    min: Vec3A,
    max: Vec3A,
    /// Most stack entries a traversal can need.
    stack_need: usize,
    /// The box of the leaf starting at pack `k` (other packs: empty), for
    /// the rays of a beam to test before its primitives (`beam.rs`).
    leaf_boxes: Vec<Aabb>,
}

const BINS: usize = 12;
/// Leaves are tested in SIMD packs of 8 primitives; a leaf holds at most
/// `MAX_LEAF` (one pack) and the SAH counts cost in packs, not primitives.
/// (With 4-wide packs, leaves of 2 packs rather than 4 made the render of
/// a 120,000-triangle mesh 3 % cheaper in instructions, and one 8-wide
/// pack rather than 2 of 4 another 3.4 %.) The reference cubes' 8
/// primitives stay one leaf.
pub const PACK: usize = 8;
const MAX_LEAF: usize = 8;
/// Cost of visiting a node (slab test, stack, branch) relative to one pack
/// test. Measured with 4-wide packs, not derived: 2 made renders faster than
/// 0.5 or 1 both on the reference scenes (+9 %: their 8 primitives become
/// one leaf of two packs instead of three leaves) and on an 80k-triangle
/// mesh (+5 %). With `PACK == MAX_LEAF` it decides nothing (a node of at
/// most one pack is always a leaf, a larger one always split; 1 and 2 give
/// the same tree); it matters again if leaves may hold several packs.
const TRAVERSAL_COST: f32 = 2.0;

#[inline]
fn packs(n: usize) -> f32 {
    n.div_ceil(PACK) as f32
}

impl Bvh {
    /// Build over primitives given by their bounds (which it reorders as
    /// it goes). Returns the hierarchy
    /// and the order it puts the primitives in: every leaf is a range of
    /// that order starting at a multiple of [`PACK`], the gaps between
    /// leaves filled with `None`, so that a leaf's primitives can be stored
    /// contiguously and tested in SIMD packs.
    pub fn build(mut bounds: Vec<Aabb>) -> (Bvh, Vec<Option<u32>>) {
        let mut order: Vec<u32> = (0..bounds.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * bounds.len().max(1));
        if !bounds.is_empty() {
            build_rec(&mut bounds, &mut order, 0, None, PAR_MIN, &mut nodes);
        }
        let padded = pad_leaves(&mut nodes, &order);
        // The tree is chosen on the primitives' own bounds, then every box
        // grown by a few units in the last place: the bounds of a triangle
        // are `v0 + e1` and `v0 + e2` rounded, which may lie inside the
        // corners that its test (of `v0`, `e1`, `e2`) accepts by up to half
        // a unit of the coordinates, more than the slab test's relative
        // widening covers far from the origin (`docs/theory.md` §7.19).
        for n in &mut nodes {
            (n.min, n.max) = (widen_down(n.min), widen_up(n.max));
        }
        let mut bvh = Bvh {
            nodes: Vec::with_capacity(nodes.len() / 2),
            root_leaf: (0, 0),
            min: Vec3A::INFINITY,
            max: Vec3A::NEG_INFINITY,
            stack_need: 0,
            leaf_boxes: vec![Aabb::EMPTY; padded.len() / PACK],
        };
        for leaf in nodes.iter().filter(|n| n.count > 0) {
            bvh.leaf_boxes[leaf.offset as usize / PACK] = Aabb {
                min: leaf.min,
                max: leaf.max,
            };
        }
        if let Some(root) = nodes.first() {
            bvh.min = root.min;
            bvh.max = root.max;
            if root.count > 0 {
                bvh.root_leaf = (root.offset, root.count as u32);
            } else {
                bvh.stack_need = bvh.collapse(&nodes, 0);
            }
        }
        crate::huge::advise(&bvh.nodes);
        crate::huge::advise(&bvh.leaf_boxes);
        (bvh, padded)
    }

    /// Add the 8-wide node of the binary interior node `idx` and those of
    /// its subtree. Its children are the binary node's grandchildren and so
    /// on, the interior one of largest area opened first, until there are 8
    /// or only leaves. Returns the most stack entries a traversal of the
    /// subtree needs (a node pushes all but one of its children).
    fn collapse(&mut self, nodes: &[Node], idx: usize) -> usize {
        let second = |i: usize| nodes[i].offset as usize;
        let mut kids = [0usize; WIDTH];
        (kids[0], kids[1]) = (idx + 1, second(idx));
        let mut n = 2;
        while n < WIDTH {
            let open = (0..n)
                .filter(|&k| nodes[kids[k]].count == 0)
                .max_by(|&a, &b| nodes[kids[a]].area().total_cmp(&nodes[kids[b]].area()));
            let Some(k) = open else { break };
            let i = kids[k];
            kids[k] = i + 1;
            kids[n] = second(i);
            n += 1;
        }
        let slot = self.nodes.len();
        let mut lo = [[f32::INFINITY; WIDTH]; 3];
        let mut hi = [[f32::NEG_INFINITY; WIDTH]; 3];
        let mut child = [0u32; WIDTH];
        for (lane, &k) in kids[..n].iter().enumerate() {
            for a in 0..3 {
                lo[a][lane] = nodes[k].min[a];
                hi[a][lane] = nodes[k].max[a];
            }
        }
        self.nodes.push(Node8 {
            bounds: [lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]].map(F8::from_array),
            child,
        });
        let mut deepest = 0;
        for (lane, &k) in kids[..n].iter().enumerate() {
            child[lane] = if nodes[k].count > 0 {
                leaf_ref(nodes[k].offset, nodes[k].count as u32)
            } else {
                let c = self.nodes.len() as u32;
                deepest = deepest.max(self.collapse(nodes, k));
                c
            };
        }
        self.nodes[slot].child = child;
        deepest + n - 1
    }

    /// The most stack entries a traversal can need (0 for a root leaf).
    #[cfg(test)]
    pub(super) fn depth_bound(&self) -> usize {
        self.stack_need
    }

    /// The range of primitives of a root that is a leaf (`count == 0`:
    /// the root is a node, or there is nothing).
    pub(super) fn root_leaf(&self) -> (u32, u32) {
        self.root_leaf
    }

    /// Bounds of the whole scene (empty if there is nothing).
    pub fn bounds(&self) -> Aabb {
        Aabb {
            min: self.min,
            max: self.max,
        }
    }

    /// Visit the leaves whose boxes the ray `o + t d`, `t ∈ [0, t_max]`,
    /// may hit: `hit(start, count, t_max)` is called once per leaf with its
    /// range in the order [`Self::build`] returned, and returns the new
    /// `t_max` (smaller if it hit something). A negative `t_max` returned
    /// by `hit` ends the traversal.
    ///
    /// `ORDERED`: the children of a node are visited nearest box first,
    /// which lets a nearest-hit query skip the boxes beyond its hit.
    /// Otherwise in the order of the node's lanes, without the sort: for
    /// queries whose answer does not depend on the order and whose `t_max`
    /// does not shrink (any hit, every hit of a segment), which then cost
    /// less per node (shadow rays over a 120,000-triangle mesh took 24–30 %
    /// less time, `docs/benchmarks.md`).
    #[inline]
    pub fn traverse_leaves<const ORDERED: bool>(
        &self,
        o: Vec3A,
        d: Vec3A,
        t_max: f32,
        mut hit: impl FnMut(u32, u32, f32) -> f32,
    ) -> f32 {
        // A root that is a leaf (scenes of a few primitives, such as the
        // reference ones) is one pack of at most 8 primitives, tested at
        // once: no stack, and no box test either, which would cost about a
        // third of the pack test for every ray and save the pack test only
        // for rays that miss the scene's bounds (none, when the camera is
        // inside them).
        let (start, count) = self.root_leaf;
        if count > 0 {
            return hit(start, count, t_max);
        }
        if self.nodes.is_empty() {
            return t_max;
        }
        let inv_d = d.recip();
        if self.stack_need <= STACK {
            self.walk::<ORDERED>(&mut fixed_stack(), o, inv_d, t_max, &mut hit)
        } else {
            self.walk_heap::<ORDERED>(o, inv_d, t_max, &mut hit)
        }
    }

    /// [`Self::walk`] with a stack on the heap, for trees too deep for the
    /// fixed one (only degenerate inputs make them).
    #[cold]
    #[inline(never)]
    fn walk_heap<const ORDERED: bool>(
        &self,
        o: Vec3A,
        inv_d: Vec3A,
        t_max: f32,
        hit: &mut impl FnMut(u32, u32, f32) -> f32,
    ) -> f32 {
        self.walk::<ORDERED>(
            &mut vec![Entry::uninit(); self.stack_need],
            o,
            inv_d,
            t_max,
            hit,
        )
    }

    /// The traversal of the 8-wide tree from its root, with `stack` for
    /// the children still to visit and the distances where the ray enters
    /// their boxes.
    #[inline(never)]
    fn walk<const ORDERED: bool>(
        &self,
        stack: &mut [Entry],
        o: Vec3A,
        inv_d: Vec3A,
        t_max: f32,
        hit: &mut impl FnMut(u32, u32, f32) -> f32,
    ) -> f32 {
        let p = o * inv_d;
        if !p.is_finite() {
            // (The scene's box is tested only here, as before, for rays
            // with a zero direction component or a non-finite origin. On
            // the common path the root node's test of its children culls
            // a ray that misses the scene's bounds as well, and nearly
            // every ray of a render starts inside them.)
            if !slab_hit(self.min, self.max, o, inv_d, t_max) {
                return t_max;
            }
            return self.walk_unfused::<ORDERED>(stack, o, inv_d, t_max, hit);
        }
        let inv = [F8::splat(inv_d.x), F8::splat(inv_d.y), F8::splat(inv_d.z)];
        let (q_near, q_far) = slab_offsets(p);
        // Each distance one multiply–subtract `b·(1/d) − q` (`docs/theory.md`
        // §7.19).
        self.walk_ray::<ORDERED>(stack, inv_d, t_max, hit, |b, a, entry| {
            b.mul_sub_bound(inv[a], if entry { q_near[a] } else { q_far[a] })
        })
    }

    /// [`Self::walk`] for a ray with a zero (or subnormal) direction
    /// component, whose `o·(1/d)` is not finite: each distance computed as
    /// `(b − o)·(1/d)`, which is an exact infinity of the right sign where
    /// the origin lies off the slab's plane (the offsets of the fused form
    /// would give NaN on one side of 0, and so cull nothing along that
    /// axis).
    #[cold]
    #[inline(never)]
    fn walk_unfused<const ORDERED: bool>(
        &self,
        stack: &mut [Entry],
        o: Vec3A,
        inv_d: Vec3A,
        t_max: f32,
        hit: &mut impl FnMut(u32, u32, f32) -> f32,
    ) -> f32 {
        let o = [F8::splat(o.x), F8::splat(o.y), F8::splat(o.z)];
        let inv = [F8::splat(inv_d.x), F8::splat(inv_d.y), F8::splat(inv_d.z)];
        self.walk_ray::<ORDERED>(stack, inv_d, t_max, hit, |b, a, _| b.sub(o[a]).mul(inv[a]))
    }

    /// The walk of one ray, the slab test of `slab_hit` on 8 boxes:
    /// `dist(b, a, entry)` is the distance along the ray to the planes `b`
    /// of axis `a` (those it enters by if `entry`, else those it leaves by).
    /// A NaN distance (a zero direction component, the origin on a slab
    /// plane) is the first operand of `max`/`min`, which then return the
    /// second (see `F8`): that slab is ignored, a conservative hit.
    #[inline(always)]
    fn walk_ray<const ORDERED: bool>(
        &self,
        stack: &mut [Entry],
        inv_d: Vec3A,
        t_max: f32,
        hit: &mut impl FnMut(u32, u32, f32) -> f32,
        dist: impl Fn(F8, usize, bool) -> F8,
    ) -> f32 {
        let (near, far) = slab_planes([inv_d.x < 0.0, inv_d.y < 0.0, inv_d.z < 0.0]);
        let zero = F8::splat(0.0);
        self.walk_with::<ORDERED>(
            stack,
            t_max,
            #[inline(always)]
            |b, t_max| {
                let tn = |a: usize| dist(b[near[a]], a, true);
                let tf = |a: usize| dist(b[far[a]], a, false);
                let tn = tn(0).max(tn(1).max(tn(2).max(zero)));
                let tf = tf(0).min(tf(1).min(tf(2).min(F8::splat(t_max))));
                (tn, tf)
            },
            hit,
        )
    }

    /// The traversal order and culling of the 8-wide tree, shared by the
    /// ray ([`Self::walk`]) and the beam (`beam.rs`): `test(bounds, t_max)`
    /// gives, per child lane, an entry distance that no ray enters the box
    /// before and an exit distance that none leaves it after (`(tn, tf)`;
    /// the child is visited if `tn <= tf`, widened by the rounding factor
    /// of [`Aabb::intersect`]); `hit` is called per leaf as in
    /// [`Self::traverse_leaves`].
    #[inline(always)]
    fn walk_with<const ORDERED: bool>(
        &self,
        stack: &mut [Entry],
        mut t_max: f32,
        test: impl Fn(&[F8; 6], f32) -> (F8, F8),
        hit: &mut impl FnMut(u32, u32, f32) -> f32,
    ) -> f32 {
        let widen = F8::splat(1.000_000_4);
        let mut sp = 0usize;
        let mut cur = 0u32;
        loop {
            if cur & LEAF != 0 {
                let (start, count) = leaf_range(cur);
                t_max = hit(start, count, t_max);
                if t_max < 0.0 {
                    break;
                }
            } else {
                let node = &self.nodes[cur as usize];
                let (tn, tf) = test(&node.bounds, t_max);
                let mut mask = tn.le(tf.mul(widen)).bitmask();
                if mask != 0 {
                    if mask & (mask - 1) == 0 {
                        cur = node.child[mask.trailing_zeros() as usize];
                        continue;
                    }
                    if !ORDERED {
                        // Lane order: visit the first child, push the
                        // others (with entry 0: a `t_max` that does not
                        // shrink culls none of them).
                        cur = node.child[mask.trailing_zeros() as usize];
                        mask &= mask - 1;
                        while mask != 0 {
                            stack[sp].write((node.child[mask.trailing_zeros() as usize], 0.0));
                            sp += 1;
                            mask &= mask - 1;
                        }
                        continue;
                    }
                    let tn = tn.to_array();
                    // Two children (the commonest case): visit the nearer,
                    // push the other. (This branch predicts well; without
                    // it the mesh rendered 4 % slower, docs/benchmarks.md.)
                    let rest = mask & (mask - 1);
                    if rest & (rest - 1) == 0 {
                        let (l0, l1) = (
                            mask.trailing_zeros() as usize,
                            rest.trailing_zeros() as usize,
                        );
                        let (near, far) = if tn[l0] < tn[l1] { (l0, l1) } else { (l1, l0) };
                        stack[sp].write((node.child[far], tn[far]));
                        sp += 1;
                        cur = node.child[near];
                        continue;
                    }
                    // More: sorting networks of their (entry, child) keys,
                    // whose order is the entries' (never negative, so their
                    // bits order as they do), on a tie the lesser child's;
                    // the insertion sort they replace branched on the data
                    // in loops of varying length. All but the nearest are
                    // pushed, farthest first; the nearest is visited next.
                    // (The query's answer does not depend on the order,
                    // `docs/theory.md` §7.18.)
                    let key =
                        |l: usize| u64::from(tn[l].to_bits()) << 32 | u64::from(node.child[l]);
                    let entry = |k: u64| (k as u32, f32::from_bits((k >> 32) as u32));
                    let ce = |x: u64, y: u64| (x.min(y), x.max(y));
                    // The key of the lowest lane of `m`, taken out of it.
                    let next = |m: &mut u32| {
                        let l = m.trailing_zeros() as usize;
                        *m &= m.wrapping_sub(1);
                        key(l)
                    };
                    let (a, b, c) = (next(&mut mask), next(&mut mask), next(&mut mask));
                    if mask & mask.wrapping_sub(1) == 0 {
                        // Three or four (the missing key last).
                        let four = mask != 0;
                        let d = if four { next(&mut mask) } else { u64::MAX };
                        let (a, b) = ce(a, b);
                        let (c, d) = ce(c, d);
                        let (a, c) = ce(a, c);
                        let (b, d) = ce(b, d);
                        let (b, c) = ce(b, c);
                        if four {
                            stack[sp].write(entry(d));
                            sp += 1;
                        }
                        stack[sp].write(entry(c));
                        stack[sp + 1].write(entry(b));
                        sp += 2;
                        cur = a as u32;
                        continue;
                    }
                    // Five to eight: a network of eight (19
                    // compare-exchanges), the missing keys last.
                    let mut keys = [a, b, c, u64::MAX, u64::MAX, u64::MAX, u64::MAX, u64::MAX];
                    let mut n = 3;
                    while mask != 0 {
                        keys[n] = next(&mut mask);
                        n += 1;
                    }
                    for &(i, j) in &SORT8 {
                        (keys[i], keys[j]) = ce(keys[i], keys[j]);
                    }
                    for &k in keys[1..n].iter().rev() {
                        stack[sp].write(entry(k));
                        sp += 1;
                    }
                    cur = keys[0] as u32;
                    continue;
                }
            }
            // The next pending child that the ray may still reach before
            // t_max (which may have shrunk since it was pushed).
            let mut next = None;
            while sp > 0 {
                sp -= 1;
                // SAFETY: the entries below `sp` are the ones pushed.
                let (c, t_entry) = unsafe { stack[sp].assume_init() };
                if !(t_entry > t_max * 1.000_000_4) {
                    next = Some(c);
                    break;
                }
            }
            match next {
                Some(c) => cur = c,
                None => break,
            }
        }
        t_max
    }
}

/// Re-lay `order` so that every leaf of `nodes` starts at a multiple of
/// [`PACK`], with `None` in the gaps, and point the leaves at their new
/// ranges.
fn pad_leaves(nodes: &mut [Node], order: &[u32]) -> Vec<Option<u32>> {
    let mut padded = Vec::with_capacity(order.len() * 2);
    for node in nodes.iter_mut().filter(|n| n.count > 0) {
        while padded.len() % PACK != 0 {
            padded.push(None);
        }
        let start = node.offset as usize;
        let new_start = padded.len();
        padded.extend(
            order[start..start + node.count as usize]
                .iter()
                .map(|&p| Some(p)),
        );
        node.offset = new_start as u32;
    }
    while padded.len() % PACK != 0 {
        padded.push(None);
    }
    padded
}

/// Per axis, the index in [`Node8::bounds`] of the bounds a ray enters by
/// (the lower ones unless the direction is negative along it, `neg`) and
/// of those it leaves by. (Written out: `array::map` is not always
/// inlined.)
#[inline(always)]
fn slab_planes(neg: [bool; 3]) -> ([usize; 3], [usize; 3]) {
    let [nx, ny, nz] = neg;
    (
        [3 * nx as usize, 1 + 3 * ny as usize, 2 + 3 * nz as usize],
        [3 * !nx as usize, 1 + 3 * !ny as usize, 2 + 3 * !nz as usize],
    )
}

/// `x` moved down by `2⁻²²·|x|` and the least normal float (at least one
/// unit in its last place), where finite.
fn widen_down(x: Vec3A) -> Vec3A {
    let m = x.abs() * (1.0 / (1 << 22) as f32) + Vec3A::splat(f32::MIN_POSITIVE);
    Vec3A::select(x.is_finite_mask(), x - m, x)
}

/// `x` moved up as [`widen_down`] moves it down.
fn widen_up(x: Vec3A) -> Vec3A {
    -widen_down(-x)
}

/// Per axis, the offsets `q` that turn a ray's distance to a slab plane
/// `b` into one multiply–subtract `b·(1/d) − q` in [`Bvh::walk`], from
/// `p = o·(1/d)` (finite): `p` moved by `2⁻²¹·|p|` and the least normal
/// float, up for the planes the ray enters by and down for those it leaves
/// by, so that the rounding of `p` and of the product `b·(1/d)` (when not
/// fused) can only widen the slab (`docs/theory.md` §7.19).
#[inline(always)]
fn slab_offsets(p: Vec3A) -> ([F8; 3], [F8; 3]) {
    let m = p.abs() * (1.0 / (1 << 21) as f32) + Vec3A::splat(f32::MIN_POSITIVE);
    let (up, down) = (p + m, p - m);
    (
        [F8::splat(up.x), F8::splat(up.y), F8::splat(up.z)],
        [F8::splat(down.x), F8::splat(down.y), F8::splat(down.z)],
    )
}

/// The distances at which the ray `o + t d` (`inv_d = d.recip()`) enters
/// and leaves the box `[min, max]`, clipped to `[0, t_max]` (the box is
/// missed if the first exceeds the second). Along an axis where the
/// direction is 0 and the origin lies on one of the box's planes, a product
/// `0·∞` is NaN, which `max`/`min` pass over: the ray runs in the box's
/// face, and that slab is ignored (a conservative hit).
#[inline(always)]
fn slab_interval(min: Vec3A, max: Vec3A, o: Vec3A, inv_d: Vec3A, t_max: f32) -> (f32, f32) {
    let neg = inv_d.cmplt(Vec3A::ZERO);
    let t_in = (Vec3A::select(neg, max, min) - o) * inv_d;
    let t_out = (Vec3A::select(neg, min, max) - o) * inv_d;
    // A NaN lane is the first operand of `max`/`min`, which then return the
    // second (`maxps`/`minps`; elsewhere glam's `f32::max`/`min`, which
    // ignore NaN either way).
    (
        t_in.max(Vec3A::ZERO).max_element(),
        t_out.min(Vec3A::splat(t_max)).min_element(),
    )
}

/// The slab test of [`Aabb::intersect`], hit or miss only.
#[inline(always)]
fn slab_hit(min: Vec3A, max: Vec3A, o: Vec3A, inv_d: Vec3A, t_max: f32) -> bool {
    let (tn, tf) = slab_interval(min, max, o, inv_d, t_max);
    !(tn > tf * 1.000_000_4)
}

/// The slab test of eight rays whose inverse directions are finite (a
/// beam's, see [`Beam::new`]: no product is NaN), origins `o`, inverse
/// directions `inv_d` and limits `t_max` in lanes, against the box
/// `[min, max]`: the mask of the lanes that may hit it. Each lane gets
/// the answer of the ray's own [`slab_hit`]: with finite inverses, the
/// lesser of a slab's two distances is the one `slab_hit` takes as the
/// entry, the greater its exit, and the clipping to `[0, t_max]` and the
/// widened comparison are the same.
#[inline(always)]
pub(super) fn slab_hit_finite8(
    min: Vec3A,
    max: Vec3A,
    o: &[F8; 3],
    inv_d: &[F8; 3],
    t_max: F8,
) -> u32 {
    let t = |b: Vec3A, a: usize| F8::splat(b[a]).sub(o[a]).mul(inv_d[a]);
    let (t0, t1) = (
        [t(min, 0), t(min, 1), t(min, 2)],
        [t(max, 0), t(max, 1), t(max, 2)],
    );
    let lo = |a: usize| t0[a].min(t1[a]);
    let hi = |a: usize| t0[a].max(t1[a]);
    let (tn, tf) = (lo(0).max(lo(1)).max(lo(2)), hi(0).min(hi(1)).min(hi(2)));
    let zero = F8::splat(0.0);
    let tn = zero.lt(tn).select(tn, zero);
    let tf = tf.lt(t_max).select(tf, t_max);
    tn.le(tf.mul(F8::splat(1.000_000_4))).bitmask()
}

/// Subtrees of at least this many primitives have their two halves built
/// on two threads ([`build_rec`]).
const PAR_MIN: usize = 4096;

/// Build the binary subtree of the primitives `order` (which start at
/// `start` in the whole order; `refs` holds their bounds, in the same
/// order) into `nodes`, in pre-order, and return its root's index; `order`
/// and `refs` are partitioned in place together, so that every pass over a
/// node's primitives reads their bounds in sequence, not through `order`.
/// `bounds`: the union of `refs` and the bounds of their centroids, if the
/// parent has them (from its bins and its partition), else found here.
/// The two halves of a subtree of `par_min` primitives or more are built
/// in parallel, the second into a vector of its own that is then appended:
/// the same nodes, in the same order, as a build on one thread.
fn build_rec(
    refs: &mut [Aabb],
    order: &mut [u32],
    start: usize,
    bounds: Option<(Aabb, Aabb)>,
    par_min: usize,
    nodes: &mut Vec<Node>,
) -> usize {
    let node_idx = nodes.len();
    let (bb, cb) = bounds.unwrap_or_else(|| {
        let mut bb = Aabb::EMPTY;
        let mut cb = Aabb::EMPTY;
        for r in refs.iter() {
            bb = bb.union(*r);
            cb = cb.grow(r.centroid());
        }
        (bb, cb)
    });
    let n = order.len();
    nodes.push(Node {
        min: bb.min,
        max: bb.max,
        offset: start as u32,
        count: n as u16,
    });
    if n <= PACK {
        return node_idx;
    }
    // Choose the axis and bin boundary of least SAH cost.
    let extent = cb.max - cb.min;
    let scale = Vec3A::splat(BINS as f32) / extent;
    // The bin of a centroid `c` along `axis`: one function for the SAH
    // sweep and the partition, which must agree. (Along an axis of no
    // extent the bin is meaningless and not used.)
    let bin = |c: Vec3A, axis: usize| bin_index((c[axis] - cb.min[axis]) * scale[axis], BINS);
    // All three axes binned in one pass over the boxes.
    let mut bin_bounds = [[Aabb::EMPTY; BINS]; 3];
    let mut bin_count = [[0usize; BINS]; 3];
    for r in refs.iter() {
        let c = r.centroid();
        for axis in 0..3 {
            let b = bin(c, axis);
            bin_count[axis][b] += 1;
            bin_bounds[axis][b] = bin_bounds[axis][b].union(*r);
        }
    }
    let mut best: Option<(f32, usize, usize)> = None;
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let (bin_bounds, bin_count) = (&bin_bounds[axis], &bin_count[axis]);
        // Sweep from the right to get the suffix areas, then from the left.
        let mut right_area = [0f32; BINS];
        let mut right_count = [0usize; BINS];
        let mut acc = Aabb::EMPTY;
        let mut cnt = 0;
        for b in (1..BINS).rev() {
            acc = acc.union(bin_bounds[b]);
            cnt += bin_count[b];
            right_area[b] = acc.surface_area();
            right_count[b] = cnt;
        }
        let mut acc = Aabb::EMPTY;
        let mut cnt = 0;
        for split in 1..BINS {
            acc = acc.union(bin_bounds[split - 1]);
            cnt += bin_count[split - 1];
            if cnt == 0 || right_count[split] == 0 {
                continue;
            }
            let cost =
                acc.surface_area() * packs(cnt) + right_area[split] * packs(right_count[split]);
            let better = match best {
                Some((c, _, _)) => cost < c,
                None => true,
            };
            if better {
                best = Some((cost, axis, split));
            }
        }
    }
    let (mid, halves) = match best {
        Some((cost, axis, split)) => {
            // Surface-area heuristic in pack units: a leaf costs its packs
            // times SA(node); a split costs one traversal step plus the
            // children's packs weighted by their areas. Leaves up to
            // MAX_LEAF primitives stay leaves when splitting does not pay.
            if TRAVERSAL_COST * bb.surface_area() + cost >= packs(n) * bb.surface_area()
                && n <= MAX_LEAF
            {
                return node_idx;
            }
            // Those of the first bins swapped forward, in order, and the
            // bounds of each side's centroids found on the way. The boxes'
            // unions are those of the bins on either side of the split.
            let (mut cl, mut cr) = (Aabb::EMPTY, Aabb::EMPTY);
            let mut i = 0;
            for j in 0..n {
                let c = refs[j].centroid();
                if bin(c, axis) < split {
                    cl = cl.grow(c);
                    refs.swap(i, j);
                    order.swap(i, j);
                    i += 1;
                } else {
                    cr = cr.grow(c);
                }
            }
            let union = |bins: &[Aabb]| bins.iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
            let (bl, br) = bin_bounds[axis].split_at(split);
            (i, Some(((union(bl), cl), (union(br), cr))))
        }
        None => {
            // All centroids coincide: split by count so leaves stay small.
            if n <= MAX_LEAF {
                return node_idx;
            }
            (n / 2, None)
        }
    };
    let (left_bounds, right_bounds) = halves.unzip();
    nodes[node_idx].count = 0;
    let (left, right) = order.split_at_mut(mid);
    let (left_refs, right_refs) = refs.split_at_mut(mid);
    let right_idx = if n >= par_min {
        // The first half into `nodes` itself, the second into a vector of
        // its own, appended after it.
        let mut r = Vec::new();
        rayon::join(
            || build_rec(left_refs, left, start, left_bounds, par_min, nodes),
            || {
                build_rec(
                    right_refs,
                    right,
                    start + mid,
                    right_bounds,
                    par_min,
                    &mut r,
                )
            },
        );
        // Its interior nodes point at their second child by index within
        // `r`: shift them by where it lands.
        let at = nodes.len();
        nodes.extend(r.into_iter().map(|mut node| {
            if node.count == 0 {
                node.offset += at as u32;
            }
            node
        }));
        at
    } else {
        build_rec(left_refs, left, start, left_bounds, par_min, nodes);
        build_rec(right_refs, right, start + mid, right_bounds, par_min, nodes)
    };
    nodes[node_idx].offset = right_idx as u32;
    node_idx
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 40,000 random boxes, one in ten of them in a cluster with one
    /// centroid (which the build splits by count): enough for parallel
    /// halves several levels deep.
    fn test_boxes() -> Vec<Aabb> {
        let mut s = crate::math::Sampler::new(3, 0, 0);
        (0..40_000)
            .map(|i| {
                let c = if i % 10 == 0 {
                    Vec3A::splat(0.25)
                } else {
                    Vec3A::new(s.next_1d(), s.next_1d(), s.next_1d() * 0.1)
                };
                let h = Vec3A::new(s.next_1d(), s.next_1d(), s.next_1d()) * 0.01;
                Aabb {
                    min: c - h,
                    max: c + h,
                }
            })
            .collect()
    }

    /// The binary tree over `bounds` and the order of the primitives,
    /// halves of `par_min` primitives or more built in parallel.
    fn build_tree(bounds: &[Aabb], par_min: usize) -> (Vec<Node>, Vec<u32>) {
        let mut order: Vec<u32> = (0..bounds.len() as u32).collect();
        let mut nodes = Vec::new();
        let mut refs = bounds.to_vec();
        build_rec(&mut refs, &mut order, 0, None, par_min, &mut nodes);
        (nodes, order)
    }

    /// The build on two threads makes the tree of the build on one, node
    /// for node and in the same order, with the same order of primitives.
    #[test]
    fn parallel_build_makes_the_serial_tree() {
        let bounds = test_boxes();
        let (serial, serial_order) = build_tree(&bounds, usize::MAX);
        for par_min in [PAR_MIN, 64] {
            let (nodes, order) = build_tree(&bounds, par_min);
            assert_eq!(order, serial_order, "par_min {par_min}");
            assert!(nodes == serial, "par_min {par_min}: the trees differ");
        }
        assert!(serial.len() > 2 * bounds.len() / PACK);
    }

    /// Every node's box is the union of its primitives' boxes, whether
    /// the node found it from them or was given it by its parent (from the
    /// parent's bins), and every leaf holds at most `MAX_LEAF`.
    #[test]
    fn node_boxes_are_their_primitives_unions() {
        let bounds = test_boxes();
        let (nodes, order) = build_tree(&bounds, PAR_MIN);
        // The union of the subtree at `i`, checked against its node.
        fn check(i: usize, nodes: &[Node], order: &[u32], bounds: &[Aabb]) -> Aabb {
            let node = nodes[i];
            let union = if node.count > 0 {
                assert!(node.count as usize <= MAX_LEAF);
                let prims = &order[node.offset as usize..][..node.count as usize];
                prims
                    .iter()
                    .fold(Aabb::EMPTY, |a, &p| a.union(bounds[p as usize]))
            } else {
                let l = check(i + 1, nodes, order, bounds);
                l.union(check(node.offset as usize, nodes, order, bounds))
            };
            assert!(union.min == node.min && union.max == node.max, "node {i}");
            union
        }
        let all = check(0, &nodes, &order, &bounds);
        assert!(all.min.x < 0.01 && all.max.x > 0.99);
    }

    /// A ray with a zero direction component whose origin lies on one of
    /// the box's planes along that axis touches the box's face: both slab
    /// tests count it as a hit (the slab is ignored), on either plane and
    /// for either sign of the zero; off the planes, inside the slab it
    /// hits and outside it misses.
    #[test]
    fn slab_tests_ignore_a_slab_the_ray_runs_in() {
        let b = Aabb {
            min: Vec3A::new(0.0, 0.0, 0.0),
            max: Vec3A::new(1.0, 1.0, 1.0),
        };
        for (x, want) in [
            (0.0, true),
            (1.0, true),
            (0.5, true),
            (-0.5, false),
            (1.5, false),
        ] {
            for zero in [0.0f32, -0.0] {
                let o = Vec3A::new(x, 0.5, -1.0);
                let inv = Vec3A::new(zero, 0.0, 1.0).recip();
                let msg = format!("x {x}, zero {zero}");
                assert_eq!(slab_hit(b.min, b.max, o, inv, f32::INFINITY), want, "{msg}");
                assert_eq!(b.intersect(o, inv, f32::INFINITY).is_some(), want, "{msg}");
            }
        }
    }

    /// The slab test of eight rays at once gives each lane the answer of
    /// that ray's own test, also for boxes the rays only graze (random
    /// boxes, rays aimed at a box's corner or at a point just beside it,
    /// some limits that end before the box): a beam's rays skip exactly
    /// the leaves they would skip alone.
    #[test]
    fn slab_test_of_eight_rays_is_each_rays_own() {
        let mut s = crate::math::Sampler::new(11, 0, 0);
        let mut v = || Vec3A::new(s.next_1d(), s.next_1d(), s.next_1d());
        let (mut hits, mut misses) = (0, 0);
        for k in 0..4000 {
            let (c, h) = (v() * 4.0, v() * 0.5 + Vec3A::splat(1e-3));
            let (min, max) = (c - h, c + h);
            let (mut o, mut inv, mut lim) = ([[0f32; 8]; 3], [[0f32; 8]; 3], [0f32; 8]);
            let mut want = 0u32;
            for l in 0..8 {
                let origin = v() * 8.0 - Vec3A::splat(2.0);
                // A corner, or a point near the box, give or take an ulp-sized nudge.
                let corner = Vec3A::select(v().cmplt(Vec3A::splat(0.5)), min, max);
                let aim = if l % 2 == 0 {
                    corner
                } else {
                    c + (v() - 0.5) * 2.2 * h
                };
                let aim = aim + (v() - 0.5) * 1e-6 * (k % 3) as f32;
                let d = (aim - origin).normalize();
                let i = d.recip();
                if !i.is_finite() {
                    continue;
                }
                let t_max = if l % 3 == 0 {
                    (aim - origin).length() * (0.5 + v().x)
                } else {
                    1e4
                };
                for a in 0..3 {
                    (o[a][l], inv[a][l]) = (origin[a], i[a]);
                }
                lim[l] = t_max;
                want |= u32::from(slab_hit(min, max, origin, i, t_max)) << l;
            }
            let got = slab_hit_finite8(
                min,
                max,
                &o.map(F8::from_array),
                &inv.map(F8::from_array),
                F8::from_array(lim),
            );
            // Lanes left empty (a direction with no finite inverse) have
            // a limit of 0 and an origin of 0; only compare the filled ones.
            let filled = (0..8).filter(|&l| lim[l] > 0.0).fold(0, |m, l| m | 1 << l);
            assert_eq!(got & filled, want, "box {k}");
            hits += want.count_ones();
            misses += (filled & !want).count_ones();
        }
        assert!(hits > 8000 && misses > 8000, "hits {hits}, misses {misses}");
    }

    /// Every primitive whose box the ray crosses is visited (compared with
    /// brute force over random boxes and rays).
    #[test]
    fn traversal_visits_every_hit_box() {
        let mut s = crate::math::Sampler::new(7, 0, 0);
        let boxes: Vec<Aabb> = (0..500)
            .map(|_| {
                let c = Vec3A::new(s.next_1d(), s.next_1d(), s.next_1d()) * 10.0;
                let h = Vec3A::new(s.next_1d(), s.next_1d(), s.next_1d()) * 0.3;
                Aabb {
                    min: c - h,
                    max: c + h,
                }
            })
            .collect();
        let (bvh, order) = Bvh::build(boxes.clone());
        // Every primitive is in the order once; leaves start at pack boundaries.
        let mut listed: Vec<u32> = order.iter().flatten().copied().collect();
        listed.sort_unstable();
        assert_eq!(listed, (0..boxes.len() as u32).collect::<Vec<_>>());
        assert_eq!(order.len() % PACK, 0);
        for _ in 0..200 {
            let o = Vec3A::new(s.next_1d(), s.next_1d(), s.next_1d()) * 10.0;
            let d = crate::math::sample_uniform_sphere(s.next_2d());
            let mut visited = vec![false; boxes.len()];
            bvh.traverse_leaves::<true>(o, d, f32::INFINITY, |start, count, t| {
                assert_eq!(start as usize % PACK, 0);
                for p in order[start as usize..(start + count) as usize].iter() {
                    visited[p.expect("no padding inside a leaf") as usize] = true;
                }
                t
            });
            for (i, b) in boxes.iter().enumerate() {
                if b.intersect(o, d.recip(), f32::INFINITY).is_some() {
                    assert!(visited[i], "box {i} missed");
                }
            }
            // The heap stack of deep trees visits the same leaves.
            let leaves = |bvh: &Bvh| {
                let mut v = Vec::new();
                bvh.traverse_leaves::<true>(o, d, f32::INFINITY, |start, count, t| {
                    v.push((start, count));
                    t
                });
                v
            };
            let deep = Bvh {
                stack_need: STACK + 1,
                ..bvh.clone()
            };
            assert_eq!(leaves(&bvh), leaves(&deep));
            // In lane order instead of nearest first, the same leaves.
            let mut unordered = Vec::new();
            bvh.traverse_leaves::<false>(o, d, f32::INFINITY, |start, count, t| {
                unordered.push((start, count));
                t
            });
            let mut ordered = leaves(&bvh);
            ordered.sort_unstable();
            unordered.sort_unstable();
            assert_eq!(ordered, unordered);
        }
    }

    /// The 8-wide tree over thousands of boxes (several levels of full
    /// nodes): every box the ray crosses before `t_max` is visited, for
    /// random rays and for rays along an axis (zero direction components)
    /// starting on a box's corner (origin on slab planes).
    #[test]
    fn wide_traversal_visits_every_hit_box() {
        let mut s = crate::math::Sampler::new(17, 0, 0);
        let mut r3 = || Vec3A::new(s.next_1d(), s.next_1d(), s.next_1d());
        let boxes: Vec<Aabb> = (0..5000)
            .map(|_| {
                let c = r3() * 20.0;
                let h = r3() * 0.4;
                Aabb {
                    min: c - h,
                    max: c + h,
                }
            })
            .collect();
        let (bvh, order) = Bvh::build(boxes.clone());
        assert!(
            bvh.nodes.len() > 1 + WIDTH,
            "the tree should be several levels deep"
        );
        let full = bvh.nodes.iter().filter(|n| n.child[WIDTH - 1] != 0).count();
        assert!(full > 0, "some nodes should have {WIDTH} children");
        let mut visits = 0;
        for k in 0..2000 {
            let (o, d) = if k % 2 == 0 {
                (
                    r3() * 20.0,
                    crate::math::sample_uniform_sphere([r3().x, r3().y]),
                )
            } else {
                let b = boxes[k * 7 % boxes.len()];
                let mut d = Vec3A::ZERO;
                d[k / 2 % 3] = if k / 6 % 2 == 0 { 1.0 } else { -1.0 };
                (if k % 4 == 1 { b.min } else { b.max }, d)
            };
            let t_max = if k % 3 == 0 {
                f32::INFINITY
            } else {
                15.0 * r3().x
            };
            let mut visited = vec![false; boxes.len()];
            bvh.traverse_leaves::<true>(o, d, t_max, |start, count, t| {
                for p in order[start as usize..(start + count) as usize].iter() {
                    visited[p.expect("no padding inside a leaf") as usize] = true;
                }
                t
            });
            for (i, b) in boxes.iter().enumerate() {
                if b.intersect(o, d.recip(), t_max).is_some() {
                    visits += 1;
                    assert!(visited[i], "ray {k}: box {i} missed");
                }
            }
        }
        assert!(visits > 2000, "the rays should hit boxes ({visits})");
    }
}
