//! The geometry's queries: the nearest hit, the two nearest hits and every
//! hit of a segment, all by one BVH traversal that tests each leaf's
//! triangles 8 at a time and its spheres and disks analytically. In a scene
//! of one pack of triangles (a medium's box, a floor and a light), the
//! nearest and the two nearest hits are picked from the pack's 8 lanes with
//! lane minimums instead of a branch per hit, and every hit of a segment
//! comes from the pack test alone: the same answers.

use super::bvh::{Aabb, Beam, BEAM, PACK};
use super::pack::splat_ray;
use super::types::{
    Corners, Disk, Hit, HitRecord, Sphere, Tri, INDEX_MASK, KIND_SHIFT, KIND_SPHERE, KIND_TRI,
};
use super::Geometry;
use crate::lanes::{prefetch, F8};
use crate::ray::Ray;
use glam::Vec3A;

impl Geometry {
    /// World bounds of all surfaces.
    pub fn bounds(&self) -> Aabb {
        self.bvh.bounds()
    }

    /// Where the lone pack's references start ([`Geometry::lone_pack`])
    /// and the pack's 8 references.
    #[inline(always)]
    fn lone_prims(&self) -> (usize, &[u32]) {
        let start = self.bvh.root_leaf().0 as usize;
        (start, &self.prims[start..start + PACK])
    }

    /// Calls `f(prim, t, u, v)` for every hit with `0 < t < t_max` (with
    /// `TIES`, `0 < t <= t_max`) of the primitives of the leaf
    /// `start..start + count` (both crossings of a sphere), where `f`
    /// returns the new `t_max`: smaller to look only for nearer hits,
    /// negative to stop (then this returns `false`).
    #[inline(always)]
    fn leaf_hits<const TIES: bool>(
        &self,
        ray: &Ray,
        start: u32,
        count: u32,
        t_max: &mut f32,
        mut f: impl FnMut(u32, f32, f32, f32) -> f32,
    ) -> bool {
        // Leaves start at multiples of PACK and the lanes after a leaf's last
        // primitive are padding (see `Bvh::build`), which is in neither
        // mask of its pack and never hit: the leaf is its whole packs.
        // The ray splatted here, not by the caller: a reference to it
        // captured by the leaf closure would keep it (six 8-lane vectors)
        // in memory for every query, even on the root-leaf path.
        let od = splat_ray(ray);
        let end = start + count;
        let mut k = start;
        while k < end {
            let i = (k / PACK as u32) as usize;
            // (Lanes of spheres, disks and padding hold N = 0: never hit.)
            let (mut mask, t, u, v) = self.packs[i].hits::<TIES>(od.0, od.1, *t_max);
            if mask != 0 {
                let (t, u, v) = (t.to_array(), u.to_array(), v.to_array());
                while mask != 0 {
                    let l = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    // A lane may have been overtaken by an earlier one.
                    if t[l] < *t_max || (TIES && t[l] == *t_max) {
                        *t_max = f(self.prims[k as usize + l], t[l], u[l], v[l]);
                        if *t_max < 0.0 {
                            return false;
                        }
                    }
                }
            }
            // (Empty in scenes of triangles and parallelograms only.)
            let mut other = self.pack_other.get(i).map_or(0, |&o| u32::from(o));
            while other != 0 {
                let lane = other.trailing_zeros();
                other &= other - 1;
                let p = self.prims[(k + lane) as usize];
                let i = (p & INDEX_MASK) as usize;
                let roots = if p >> KIND_SHIFT == KIND_SPHERE {
                    sphere_roots(&self.spheres[i], ray)
                } else {
                    [disk_root(&self.disks[i], ray), f32::NAN]
                };
                for t in roots {
                    if t > 0.0 && (t < *t_max || (TIES && t == *t_max)) {
                        *t_max = f(p, t, 0.0, 0.0);
                        if *t_max < 0.0 {
                            return false;
                        }
                    }
                }
            }
            k += PACK as u32;
        }
        true
    }

    /// Nearest hit with `t < t_max`, if any; of several at the nearest
    /// distance, that of the least primitive id (`keep_nearest`).
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        self.nearest(ray, t_max).map(|r| self.make_hit(ray, r))
    }

    /// The walk of [`Self::intersect`]: its nearest hit as a
    /// [`HitRecord`], made into a [`Hit`] by [`Self::make_hit`].
    #[inline(always)]
    pub fn nearest(&self, ray: &Ray, t_max: f32) -> Option<HitRecord> {
        if self.lone_pack {
            let (start, prims) = self.lone_prims();
            let (o, d) = splat_ray(ray);
            return self.packs[start / PACK]
                .nearest(o, d, t_max, prims)
                .map(|(l, t, u, v)| HitRecord((prims[l], t, u, v)));
        }
        // (primitive, t, barycentric u, v) of the nearest hit so far.
        let mut best: Option<(u32, f32, f32, f32)> = None;
        self.bvh.traverse_leaves::<true>(
            ray.o,
            ray.d,
            t_max,
            #[inline(always)]
            |start, count, mut limit| {
                self.leaf_hits::<true>(
                    ray,
                    start,
                    count,
                    &mut limit,
                    #[inline(always)]
                    |p, t, u, v| keep_nearest(&mut best, t_max, (p, t, u, v)),
                );
                limit
            },
        );
        best.map(HitRecord)
    }

    /// Start loading what [`Self::make_hit`] reads first for `r`: the hit
    /// triangle's `Corners`. With [`Self::prefetch_shading`] once that
    /// has arrived, this lets the cache misses of several paths' hits
    /// overlap (`World::li_beam`).
    #[inline(always)]
    pub fn prefetch_hit(&self, r: &HitRecord) {
        if let Some(c) = self.hit_corners(r) {
            prefetch(c);
        }
    }

    /// Start loading the rest of what [`Self::make_hit`] and
    /// [`Self::uv`] read for `r`: the hit triangle's vertices, their
    /// normals and texture coordinates (its `Corners` are read here).
    #[inline(always)]
    pub fn prefetch_shading(&self, r: &HitRecord) {
        let Some(c) = self.hit_corners(r) else {
            return;
        };
        for k in c.v {
            let k = k as usize;
            if let Some(p) = self.positions.get(k) {
                prefetch(p);
            }
            if let (true, Some(n)) = (c.has_normals(), self.normals.get(k)) {
                prefetch(n);
            }
            if let (true, Some(uv)) = (c.has_uvs(), self.uvs.get(k)) {
                prefetch(uv);
            }
        }
    }

    /// The corners of the triangle hit in `r` (`None` for other primitives).
    #[inline(always)]
    fn hit_corners(&self, HitRecord((prim, ..)): &HitRecord) -> Option<&Corners> {
        match prim >> KIND_SHIFT {
            KIND_TRI => self.corners.get((prim & INDEX_MASK) as usize),
            _ => None,
        }
    }

    /// The nearest hits of a bundle of up to [`BEAM`] nearly parallel
    /// rays (`rays[j]` below `t_max[j]` into `out[j]`), as
    /// [`Self::intersect`] finds them one by one, by one traversal for all
    /// (`bvh/beam.rs`): every ray gets the hit its own query gives, the
    /// tie rule of `keep_nearest` included. Rays that form no beam
    /// (directions of both signs along an axis) are traced one by one.
    pub fn intersect_beam(&self, rays: &[Ray], t_max: &[f32], out: &mut [Option<Hit>]) {
        let n = rays.len();
        assert!(n <= BEAM && t_max.len() == n && out.len() == n);
        let mut inv_d = [Vec3A::ZERO; BEAM];
        for (inv, r) in inv_d.iter_mut().zip(rays) {
            *inv = r.d.recip();
        }
        let beam = if n > 1 {
            Beam::new(rays, &inv_d[..n])
        } else {
            None
        };
        let Some(beam) = beam else {
            for ((r, &t), o) in rays.iter().zip(t_max).zip(out.iter_mut()) {
                *o = self.intersect(r, t);
            }
            return;
        };
        // Lanes past the last ray hold a limit of 0 and are masked off.
        let mut limit = [0f32; BEAM];
        limit[..n].copy_from_slice(t_max);
        let mut best: [Option<(u32, f32, f32, f32)>; BEAM] = [None; BEAM];
        let greatest = |limit: &[f32]| limit.iter().fold(0f32, |a, &b| a.max(b));
        // The rays eight to a group, their origins and inverse directions
        // in lanes, for the leaf box tests.
        const G: usize = BEAM / 8;
        const _: () = assert!(BEAM % 8 == 0);
        let (mut o, mut inv) = ([[[0f32; 8]; 3]; G], [[[0f32; 8]; 3]; G]);
        for j in 0..n {
            for c in 0..3 {
                (o[j / 8][c][j % 8], inv[j / 8][c][j % 8]) = (rays[j].o[c], inv_d[j][c]);
            }
        }
        let (o8, inv8) = (
            o.map(|g| g.map(F8::from_array)),
            inv.map(|g| g.map(F8::from_array)),
        );
        let groups = n.div_ceil(8);
        self.bvh.traverse_leaves_beam(
            &beam,
            greatest(&limit[..n]),
            #[inline(always)]
            |start, count, _| {
                for g in 0..groups {
                    // The rays of the beam that miss the leaf's box skip it.
                    let mut lim = [0f32; 8];
                    lim.copy_from_slice(&limit[g * 8..g * 8 + 8]);
                    let lim = F8::from_array(lim);
                    let valid = (1u32 << (n - g * 8).min(8)) - 1;
                    let mut may = self.bvh.leaf_may_hit8(start, &o8[g], &inv8[g], lim) & valid;
                    while may != 0 {
                        let j = g * 8 + may.trailing_zeros() as usize;
                        may &= may - 1;
                        self.leaf_hits::<true>(
                            &rays[j],
                            start,
                            count,
                            &mut limit[j],
                            #[inline(always)]
                            |p, t, u, v| keep_nearest(&mut best[j], t_max[j], (p, t, u, v)),
                        );
                    }
                }
                greatest(&limit[..n])
            },
        );
        for j in 0..n {
            out[j] = best[j].map(|b| self.make_hit(&rays[j], HitRecord(b)));
        }
    }

    /// The two nearest hits with `t < t_max`, nearer first. Used where the
    /// nearest is likely a `null` boundary the path crosses: the second is
    /// then the next hit of the continued ray, without a second traversal.
    /// The second comes as a [`HitRecord`], made into a [`Hit`] by
    /// [`Self::make_hit`] only if needed.
    #[inline(always)]
    pub fn intersect2(&self, ray: &Ray, t_max: f32) -> (Option<Hit>, Option<HitRecord>) {
        if self.lone_pack {
            // The same two hits as the walk's below, which visits this
            // pack's hits in lane order.
            let (start, prims) = self.lone_prims();
            let (o, d) = splat_ray(ray);
            let rec = |(l, t, u, v): (usize, f32, f32, f32)| HitRecord((prims[l], t, u, v));
            let [a, b] = self.packs[start / PACK].two_nearest(o, d, t_max);
            return (a.map(|a| self.make_hit(ray, rec(a))), b.map(rec));
        }
        let mut best: [Option<(u32, f32, f32, f32)>; 2] = [None, None];
        self.bvh.traverse_leaves::<true>(
            ray.o,
            ray.d,
            t_max,
            #[inline(always)]
            |start, count, mut t_leaf| {
                self.leaf_hits::<false>(
                    ray,
                    start,
                    count,
                    &mut t_leaf,
                    #[inline(always)]
                    |p, t, u, v| {
                        // t is below the current second-nearest (t_leaf).
                        match best[0] {
                            Some(b) if b.1 <= t => best[1] = Some((p, t, u, v)),
                            _ => {
                                best[1] = best[0];
                                best[0] = Some((p, t, u, v));
                            }
                        }
                        best[1].map_or(t_max, |b| b.1)
                    },
                );
                t_leaf
            },
        );
        (
            best[0].map(|b| self.make_hit(ray, HitRecord(b))),
            best[1].map(HitRecord),
        )
    }

    /// The [`Hit`] of primitive `p` hit at `t` (barycentrics `u, v`).
    #[inline(always)]
    pub fn make_hit(&self, ray: &Ray, HitRecord((prim, t, u, v)): HitRecord) -> Hit {
        let i = (prim & INDEX_MASK) as usize;
        match prim >> KIND_SHIFT {
            KIND_TRI => {
                let c = &self.corners[i];
                let Tri { v0, e1, e2, n, .. } = self.tri(i);
                let ns = self.shading_normal(c, [u, v], n);
                // The hit point from barycentrics is more accurate than o + t d.
                Hit {
                    t,
                    p: v0 + u * e1 + v * e2,
                    n,
                    ns,
                    shape: c.shape(),
                    prim,
                    bary: [u, v],
                }
            }
            KIND_SPHERE => {
                let s = &self.spheres[i];
                let pt = ray.at(t);
                let n = (pt - s.center).normalize() * s.sign;
                // Re-project onto the sphere to cancel the error of o + t d.
                let p = s.center + (pt - s.center) * (s.radius / (pt - s.center).length());
                Hit {
                    t,
                    p,
                    n,
                    ns: n,
                    shape: s.shape,
                    prim,
                    bary: [0.0; 2],
                }
            }
            _ => {
                let d = &self.disks[i];
                Hit {
                    t,
                    p: ray.at(t),
                    n: d.n,
                    ns: d.n,
                    shape: d.shape,
                    prim,
                    bary: [0.0; 2],
                }
            }
        }
    }

    /// The [`Hit`] of primitive `prim` (as [`Self::for_each_hit`] names it)
    /// at distance `t` along `ray`, its barycentrics recovered from the
    /// point: for the few crossings a shadow ray must look at closely (the
    /// texture coordinates of a `mask`).
    pub(crate) fn hit_at(&self, ray: &Ray, prim: u32, t: f32) -> Hit {
        let (mut u, mut v) = (0.0, 0.0);
        if prim >> KIND_SHIFT == KIND_TRI {
            let tri = self.tri((prim & INDEX_MASK) as usize);
            let w = ray.at(t) - tri.v0;
            let (d00, d01, d11) = (tri.e1.dot(tri.e1), tri.e1.dot(tri.e2), tri.e2.dot(tri.e2));
            let (d20, d21) = (w.dot(tri.e1), w.dot(tri.e2));
            let det = d00 * d11 - d01 * d01;
            if det > 0.0 {
                u = (d11 * d20 - d01 * d21) / det;
                v = (d00 * d21 - d01 * d20) / det;
            }
        }
        self.make_hit(ray, HitRecord((prim, t, u, v)))
    }

    /// Every crossing of the segment `o + t d`, `0 < t < t_max`, with a
    /// surface, in no particular order: `visit(prim, shape, t, n)` gets a
    /// primitive id (unique within the scene), the shape, the distance and
    /// the geometric normal there. Returning `false` from `visit` ends the
    /// query (an occluder was found), and then this returns `false`.
    ///
    /// One traversal answers a shadow ray that crosses any number of `null`
    /// medium boundaries, where [`Self::intersect`] would be called once per
    /// crossing.
    #[inline(always)]
    pub fn for_each_hit(
        &self,
        ray: &Ray,
        t_max: f32,
        mut visit: impl FnMut(u32, u32, f32, Vec3A) -> bool,
    ) -> bool {
        self.for_each_crossing(
            ray,
            t_max,
            #[inline(always)]
            |p, t| {
                let (shape, n) = self.shape_normal(ray, p, t);
                visit(p, shape, t, n)
            },
        )
    }

    /// The shape and the geometric normal of primitive `p` crossed at `t`
    /// along `ray`.
    #[inline(always)]
    fn shape_normal(&self, ray: &Ray, p: u32, t: f32) -> (u32, Vec3A) {
        let i = (p & INDEX_MASK) as usize;
        match p >> KIND_SHIFT {
            KIND_TRI => {
                let tri = self.tri(i);
                (tri.shape, tri.n)
            }
            KIND_SPHERE => {
                let s = &self.spheres[i];
                (s.shape, (ray.at(t) - s.center).normalize() * s.sign)
            }
            _ => (self.disks[i].shape, self.disks[i].n),
        }
    }

    /// [`Self::for_each_hit`] with `visit(prim, t)` given only the
    /// primitive and the distance.
    #[inline(always)]
    fn for_each_crossing(
        &self,
        ray: &Ray,
        t_max: f32,
        mut visit: impl FnMut(u32, f32) -> bool,
    ) -> bool {
        if self.lone_pack {
            // The walk's visits below, in the same (lane) order.
            let (start, prims) = self.lone_prims();
            let (o, d) = splat_ray(ray);
            let (mut mask, t, _, _) = self.packs[start / PACK].hits::<false>(o, d, t_max);
            if mask == 0 {
                return true;
            }
            let t = t.to_array();
            while mask != 0 {
                let l = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                if !visit(prims[l], t[l]) {
                    return false;
                }
            }
            return true;
        }
        let mut go = true;
        self.bvh.traverse_leaves::<false>(
            ray.o,
            ray.d,
            t_max,
            #[inline(always)]
            |start, count, mut t| {
                go = self.leaf_hits::<false>(
                    ray,
                    start,
                    count,
                    &mut t,
                    #[inline(always)]
                    |p, t, _, _| {
                        if visit(p, t) {
                            t_max
                        } else {
                            -1.0
                        }
                    },
                );
                t
            },
        );
        go
    }

    /// Whether any surface crosses the segment `o + t d`, `0 < t < t_max`:
    /// the walk of [`Self::for_each_hit`] ended at the first crossing,
    /// without reading the crossed primitive's record or vertices (a shadow
    /// ray in a scene where every surface blocks).
    #[inline(always)]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        !self.for_each_crossing(ray, t_max, |_, _| false)
    }
}

/// Keep the candidate hit `c` (primitive, distance, barycentrics) in
/// `best` if it is nearer than the hit there or, at the same distance, of a
/// smaller primitive id, and is below the query's `t_max`; returns the
/// limit for further candidates (`t_max` while there is no hit, then the
/// best distance, which a candidate may equal). The tie rule makes the
/// nearest hit a function of the ray alone, whatever order the leaves are
/// visited in: a ray of a beam (`intersect_beam`) and a ray alone find the
/// same primitive even where two lie at exactly the same distance (a shared
/// edge).
#[inline(always)]
fn keep_nearest(
    best: &mut Option<(u32, f32, f32, f32)>,
    t_max: f32,
    c: (u32, f32, f32, f32),
) -> f32 {
    let keep = match *best {
        None => c.1 < t_max,
        Some(b) => c.1 < b.1 || (c.1 == b.1 && c.0 < b.0),
    };
    if keep {
        *best = Some(c);
    }
    best.map_or(t_max, |b| b.1)
}

/// Both ray parameters where the ray's line meets the sphere (NaN if it
/// misses), nearer first.
#[inline]
pub(super) fn sphere_roots(s: &Sphere, ray: &Ray) -> [f32; 2] {
    let oc = ray.o - s.center;
    let b = oc.dot(ray.d);
    // r² - |oc - b d|² is the discriminant computed without the catastrophic
    // cancellation of b² - (|oc|² - r²) for distant origins.
    let perp = oc - b * ray.d;
    let disc = s.radius * s.radius - perp.length_squared();
    if disc < 0.0 {
        return [f32::NAN; 2];
    }
    let sq = disc.sqrt();
    [-b - sq, -b + sq]
}

/// Where the ray meets a disk (NaN if it misses).
#[inline]
pub(super) fn disk_root(d: &Disk, ray: &Ray) -> f32 {
    let o = d.to_local.transform_point3a(ray.o);
    let dir = d.to_local.transform_vector3a(ray.d);
    // Affine maps keep the ray parameter, so the local t is the world t.
    let t = -o.z / dir.z;
    let p = o + t * dir;
    if p.x * p.x + p.y * p.y <= 1.0 {
        t
    } else {
        f32::NAN
    }
}
