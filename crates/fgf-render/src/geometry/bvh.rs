//! A bounding volume hierarchy over every primitive of the scene (triangles
//! of all meshes, spheres, disks): a binned surface-area-heuristic build
//! (12 bins per axis, leaves of at most 16 primitives, tested in
//! SIMD packs of 4, with the SAH cost counted in packs) flattened in
//! depth-first order, traversed front-to-back with a small stack.
//!
//! We wrote our own rather than depend on a crate: it is a few hundred
//! lines without unsafe code, its leaves mix triangles with analytic spheres
//! and disks, and it tests leaf triangles 4 at a time (`TriPack` in
//! `geometry/pack.rs`), which is what matters for scenes of a handful of
//! primitives like the reference ones. On the homogeneous reference scene,
//! SIMD slab tests and 4-wide leaf packs made the whole renderer 15 % faster
//! than per-triangle tests; counting a node visit as 2 pack tests in the SAH
//! (one leaf for its 8 primitives) another 9 % (see `docs/benchmarks.md`).

use glam::{Vec3, Vec3A};

/// Axis-aligned bounding box.
#[derive(Debug, Clone, Copy)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    #[inline]
    pub fn union(self, o: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }
    #[inline]
    pub fn grow(self, p: Vec3) -> Aabb {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }
    #[inline]
    pub fn centroid(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }
    pub fn surface_area(&self) -> f32 {
        let d = (self.max - self.min).max(Vec3::ZERO);
        2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
    }
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x
    }

    /// Slab test; returns the entry and exit distances clipped to `[0, t_max]`.
    #[inline]
    pub fn intersect(&self, o: Vec3, inv_d: Vec3, t_max: f32) -> Option<(f32, f32)> {
        let t0 = (self.min - o) * inv_d;
        let t1 = (self.max - o) * inv_d;
        // `min`/`max` of glam ignore NaN operands the way we want when a
        // direction component is 0 and the origin lies on a slab plane.
        let tn = t0.min(t1).max_element().max(0.0);
        let tf = t0.max(t1).min_element().min(t_max);
        // The factor 1 + 2γ(3) (pbrt) makes the test conservative against
        // the rounding of the two products above.
        if tn <= tf * 1.000_000_4 {
            Some((tn, tf))
        } else {
            None
        }
    }
}

#[derive(Debug, Clone, Copy)]
struct Node {
    /// Bounds as SIMD vectors (glam's `Vec3A`): the slab test is the
    /// hottest code of the renderer.
    min: Vec3A,
    max: Vec3A,
    /// Leaf: first primitive in `order`; interior: index of the second child
    /// (the first child follows the node directly).
    offset: u32,
    /// Number of primitives of a leaf, 0 for an interior node.
    count: u16,
    /// Split axis of an interior node (to visit the nearer child first).
    axis: u8,
}

/// The hierarchy. Its leaves are ranges of the primitive order that
/// [`Bvh::build`] returns.
#[derive(Debug, Clone)]
pub struct Bvh {
    nodes: Vec<Node>,
}

const BINS: usize = 12;
/// Leaves are tested in SIMD packs of 4 primitives; a leaf holds at most
/// `MAX_LEAF` (4 packs) and the SAH counts cost in packs, not primitives.
pub const PACK: usize = 4;
const MAX_LEAF: usize = 16;
/// Cost of visiting a node (slab test, stack, branch) relative to one 4-wide
/// pack test. Measured, not derived: 2 made renders faster than 0.5 or 1 both
/// on the reference scenes (+9 %: their 8 primitives become one leaf of two
/// packs instead of three leaves) and on an 80k-triangle mesh (+5 %).
const TRAVERSAL_COST: f32 = 2.0;

#[inline]
fn packs(n: usize) -> f32 {
    n.div_ceil(PACK) as f32
}

impl Bvh {
    /// Build over primitives given by their bounds. Returns the hierarchy
    /// and the order it puts the primitives in: every leaf is a range of
    /// that order starting at a multiple of [`PACK`], the gaps between
    /// leaves filled with `None`, so that a leaf's primitives can be stored
    /// contiguously and tested in SIMD packs.
    pub fn build(bounds: &[Aabb]) -> (Bvh, Vec<Option<u32>>) {
        let mut order: Vec<u32> = (0..bounds.len() as u32).collect();
        let centroids: Vec<Vec3> = bounds.iter().map(|b| b.centroid()).collect();
        let mut nodes = Vec::with_capacity(2 * bounds.len().max(1));
        if !bounds.is_empty() {
            build_rec(bounds, &centroids, &mut order, 0, bounds.len(), &mut nodes);
        }
        let mut bvh = Bvh { nodes };
        let padded = bvh.pad_leaves(&order);
        (bvh, padded)
    }

    /// Re-lay `order` so that every leaf starts at a multiple of [`PACK`],
    /// with `None` in the gaps, and point the leaves at their new ranges.
    fn pad_leaves(&mut self, order: &[u32]) -> Vec<Option<u32>> {
        let mut padded = Vec::with_capacity(order.len() * 2);
        for node in self.nodes.iter_mut().filter(|n| n.count > 0) {
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

    /// Bounds of the whole scene (empty if there is nothing).
    pub fn bounds(&self) -> Aabb {
        self.nodes
            .first()
            .map(|n| Aabb {
                min: n.min.into(),
                max: n.max.into(),
            })
            .unwrap_or(Aabb::EMPTY)
    }

    /// Visit the leaves whose boxes the ray `o + t d`, `t ∈ [0, t_max]`,
    /// may hit, nearest subtree first: `hit(start, count, t_max)` is called
    /// once per leaf with its range in the order [`Self::build`] returned,
    /// and returns the new `t_max` (smaller if it hit something). A
    /// negative `t_max` returned by `hit` ends the traversal.
    #[inline]
    pub fn traverse_leaves(
        &self,
        o: Vec3,
        d: Vec3,
        mut t_max: f32,
        mut hit: impl FnMut(u32, u32, f32) -> f32,
    ) -> f32 {
        if self.nodes.is_empty() {
            return t_max;
        }
        let inv_d = Vec3A::from(d).recip();
        let o = Vec3A::from(o);
        // A root that is a leaf (scenes of a few primitives, such as the
        // reference ones) needs no stack, whose zeroing would cost about as
        // much as the box test.
        let root = &self.nodes[0];
        if root.count > 0 {
            if slab_hit(root.min, root.max, o, inv_d, t_max) {
                t_max = hit(root.offset, root.count as u32, t_max);
            }
            return t_max;
        }
        let neg = [inv_d.x < 0.0, inv_d.y < 0.0, inv_d.z < 0.0];
        let mut stack = [0u32; 64];
        let mut sp = 0usize;
        let mut idx = 0u32;
        loop {
            let node = &self.nodes[idx as usize];
            if slab_hit(node.min, node.max, o, inv_d, t_max) {
                if node.count > 0 {
                    t_max = hit(node.offset, node.count as u32, t_max);
                    if t_max < 0.0 {
                        break;
                    }
                } else {
                    // Visit the child on the near side of the split first.
                    let (first, second) = if neg[node.axis as usize] {
                        (node.offset, idx + 1)
                    } else {
                        (idx + 1, node.offset)
                    };
                    stack[sp] = second;
                    sp += 1;
                    idx = first;
                    continue;
                }
            }
            if sp == 0 {
                break;
            }
            sp -= 1;
            idx = stack[sp];
        }
        t_max
    }
}

/// The slab test of [`Aabb::intersect`] on SIMD vectors, hit or miss only.
#[inline(always)]
fn slab_hit(min: Vec3A, max: Vec3A, o: Vec3A, inv_d: Vec3A, t_max: f32) -> bool {
    let t0 = (min - o) * inv_d;
    let t1 = (max - o) * inv_d;
    // Plain comparisons instead of f32::max/min: those handle NaN operands,
    // which costs extra instructions in this innermost test; a NaN here (a
    // zero direction component with the origin on a slab plane) makes the
    // comparison false, i.e. a conservative hit.
    let tn = t0.min(t1).max_element();
    let tf = t0.max(t1).min_element();
    let tn = if tn > 0.0 { tn } else { 0.0 };
    let tf = if tf < t_max { tf } else { t_max };
    !(tn > tf * 1.000_000_4)
}

fn build_rec(
    bounds: &[Aabb],
    centroids: &[Vec3],
    order: &mut [u32],
    start: usize,
    end: usize,
    nodes: &mut Vec<Node>,
) -> usize {
    let node_idx = nodes.len();
    let mut bb = Aabb::EMPTY;
    let mut cb = Aabb::EMPTY;
    for &p in &order[start..end] {
        bb = bb.union(bounds[p as usize]);
        cb = cb.grow(centroids[p as usize]);
    }
    nodes.push(Node {
        min: bb.min.into(),
        max: bb.max.into(),
        offset: start as u32,
        count: (end - start) as u16,
        axis: 0,
    });
    let n = end - start;
    if n <= PACK {
        return node_idx;
    }
    // Choose the axis and bin boundary of least SAH cost.
    let extent = cb.max - cb.min;
    let mut best: Option<(f32, usize, usize)> = None;
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let mut bin_bounds = [Aabb::EMPTY; BINS];
        let mut bin_count = [0usize; BINS];
        let scale = BINS as f32 / extent[axis];
        for &p in &order[start..end] {
            let b = (((centroids[p as usize][axis] - cb.min[axis]) * scale) as usize).min(BINS - 1);
            bin_count[b] += 1;
            bin_bounds[b] = bin_bounds[b].union(bounds[p as usize]);
        }
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
    let mid = match best {
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
            let scale = BINS as f32 / extent[axis];
            let slice = &mut order[start..end];
            let mut i = 0;
            for j in 0..slice.len() {
                let c = centroids[slice[j] as usize][axis];
                let b = (((c - cb.min[axis]) * scale) as usize).min(BINS - 1);
                if b < split {
                    slice.swap(i, j);
                    i += 1;
                }
            }
            nodes[node_idx].axis = axis as u8;
            start + i
        }
        None => {
            // All centroids coincide: split by count so leaves stay small.
            if n <= MAX_LEAF {
                return node_idx;
            }
            start + n / 2
        }
    };
    nodes[node_idx].count = 0;
    build_rec(bounds, centroids, order, start, mid, nodes);
    let right = build_rec(bounds, centroids, order, mid, end, nodes);
    nodes[node_idx].offset = right as u32;
    node_idx
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every primitive whose box the ray crosses is visited (compared with
    /// brute force over random boxes and rays).
    #[test]
    fn traversal_visits_every_hit_box() {
        let mut s = crate::math::Sampler::new(7, 0, 0);
        let boxes: Vec<Aabb> = (0..500)
            .map(|_| {
                let c = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 10.0;
                let h = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 0.3;
                Aabb {
                    min: c - h,
                    max: c + h,
                }
            })
            .collect();
        let (bvh, order) = Bvh::build(&boxes);
        // Every primitive is in the order once; leaves start at pack boundaries.
        let mut listed: Vec<u32> = order.iter().flatten().copied().collect();
        listed.sort_unstable();
        assert_eq!(listed, (0..boxes.len() as u32).collect::<Vec<_>>());
        assert_eq!(order.len() % PACK, 0);
        for _ in 0..200 {
            let o = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 10.0;
            let d = crate::math::sample_uniform_sphere(s.next_2d());
            let mut visited = vec![false; boxes.len()];
            bvh.traverse_leaves(o, d, f32::INFINITY, |start, count, t| {
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
        }
    }
}
