//! Scene geometry in world space (f32, like Mitsuba's `scalar_rgb`):
//! triangles (meshes), parallelograms (`cube` faces, `rectangle`), analytic
//! spheres and disks, one BVH over all of them with three queries (nearest
//! hit, two nearest hits, every hit of a segment), ray spawning with robust
//! offsets, and uniform area sampling of a shape (for area lights).
//!
//! Normal conventions follow Mitsuba 3: a shape's geometric normal `n` is
//! the side an area light emits toward and decides `interior`/`exterior`
//! (a ray leaving along `n` enters the exterior); `flip_normals` negates it.
//! `rectangle` and `disk` transform their local `+z` as a normal (inverse
//! transpose), so a mirroring `to_world` keeps the orientation; meshes and
//! `cube` use the winding of the transformed triangles (faces).

pub mod bvh;

use crate::render::RenderError;
use bvh::{Aabb, Bvh};
use fgf_scene::{GeometryDesc, ShapeDesc};
use glam::{Affine3A, Mat3, Mat4, Vec3, Vec3A, Vec4};
use std::f32::consts::PI;

/// A ray `o + t d` with unit `d`.
#[derive(Debug, Clone, Copy)]
pub struct Ray {
    pub o: Vec3,
    pub d: Vec3,
}

impl Ray {
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.o + t * self.d
    }
}

/// A surface hit.
#[derive(Debug, Clone, Copy)]
pub struct Hit {
    pub t: f32,
    pub p: Vec3,
    /// Unit geometric normal, oriented as described in the module docs.
    pub n: Vec3,
    /// Unit shading normal (interpolated vertex normals, else `n`).
    pub ns: Vec3,
    pub shape: u32,
}

/// A hit found by a query but not yet made into a [`Hit`]: primitive,
/// distance and barycentrics.
#[derive(Debug, Clone, Copy)]
pub struct HitRecord((u32, f32, f32, f32));

/// Relative size of the offset that moves a spawned ray off its surface:
/// `(1 + max|p|)·2⁻¹⁶`. Triangle and sphere hit points carry a rounding
/// error of a few ulps of `|p|` (≈ 1e-7·|p|); the offset is two orders of
/// magnitude above that, and still far below any feature of a scene in
/// metre-ish units. (Mitsuba uses a comparable `mint` of ≈ 9e-5·(1 + max|p|).)
const OFFSET_SCALE: f32 = 1.0 / 65536.0;

/// Offset of the hit point `p` along `n`, to the side `d` points to.
#[inline]
pub fn offset_point(p: Vec3, n: Vec3, d: Vec3) -> Vec3 {
    let eps = (1.0 + p.abs().max_element()) * OFFSET_SCALE;
    if d.dot(n) >= 0.0 {
        p + eps * n
    } else {
        p - eps * n
    }
}

/// Distance to stop a shadow ray short of a sampled light point `q`, so that
/// it does not hit the light's own surface.
#[inline]
pub fn shadow_epsilon(q: Vec3) -> f32 {
    4.0 * (1.0 + q.abs().max_element()) * OFFSET_SCALE
}

/// A triangle `v0 + u e1 + v e2` (`u, v ≥ 0`, `u + v ≤ 1`) or, with
/// `quad`, a parallelogram (`0 ≤ u, v ≤ 1`). `cube` faces and `rectangle`s
/// are parallelograms: one primitive instead of two triangles halves their
/// intersection tests (the reference scenes are made of nothing else).
#[derive(Debug, Clone, Copy)]
struct Tri {
    // SIMD vectors for the intersection test.
    v0: Vec3A,
    e1: Vec3A,
    e2: Vec3A,
    /// Oriented unit geometric normal.
    n: Vec3,
    shape: u32,
    /// Index into `Geometry::vertex_normals`, or `u32::MAX` without normals.
    normals: u32,
    quad: bool,
}

/// Faces of a mesh: triangles, or parallelograms given by their corners in
/// order around the boundary (the fourth corner is implied by the others).
enum Faces<'a> {
    Tris(&'a [[u32; 3]]),
    Quads(&'a [[u32; 4]]),
}

#[derive(Debug, Clone, Copy)]
struct Sphere {
    center: Vec3,
    radius: f32,
    /// -1 with `flip_normals` (normals point inward), else 1.
    sign: f32,
    shape: u32,
}

#[derive(Debug, Clone, Copy)]
struct Disk {
    to_local: Affine3A,
    to_world: Affine3A,
    n: Vec3,
    shape: u32,
}

/// What is needed to sample a point uniformly on one shape.
#[derive(Debug, Clone)]
enum ShapeSampling {
    /// Triangles `first..first+cdf.len()`, `cdf` the running area fraction.
    Tris {
        first: u32,
        cdf: Vec<f32>,
    },
    Sphere(u32),
    Disk(u32),
}

/// A point sampled on a shape.
#[derive(Debug, Clone, Copy)]
pub struct PositionSample {
    pub p: Vec3,
    pub n: Vec3,
}

// Primitive references pack the kind in the top two bits.
const KIND_SHIFT: u32 = 30;
const KIND_TRI: u32 = 0;
const KIND_SPHERE: u32 = 1;
const KIND_DISK: u32 = 2;
const INDEX_MASK: u32 = (1 << KIND_SHIFT) - 1;
/// Padding entry of `Geometry::prims` (never intersected).
const PAD: u32 = u32::MAX;

/// Four triangles in structure-of-arrays form, intersected at once with
/// SSE (glam's `Vec4`) by projection onto precomputed planes: with
/// `N = e1 × e2`, a point `P` of the plane is `v0 + u e1 + v e2` for
/// `u = (P - v0)·a`, `v = (P - v0)·b`, where `a = (e2 × N)/|N|²` and
/// `b = (N × e1)/|N|²`. That is about 35 operations per pack against
/// Möller–Trumbore's 55, which derives the equivalent of `N`, `a`, `b` per
/// ray. Lanes without a triangle have `N = 0`, so `t` is NaN and they never
/// hit.
#[derive(Debug, Clone, Copy)]
struct TriPack {
    v0: [Vec4; 3],
    n: [Vec4; 3],
    a: [Vec4; 3],
    b: [Vec4; 3],
    /// Per lane: 1 for a triangle (`u + v ≤ 1`), 0 for a parallelogram
    /// (`v ≤ 1`); `u ≤ 1` is tested for both.
    tri_k: Vec4,
    /// Lanes holding triangles / other primitives (spheres, disks).
    tri_mask: u32,
    other_mask: u32,
}

impl TriPack {
    /// The 4 triangles against one ray: the mask of lanes among `lanes` hit
    /// with `0 < t < t_max`, and every lane's `t`, `u`, `v`.
    #[inline(always)]
    fn hits(&self, o: [Vec4; 3], d: [Vec4; 3], t_max: f32, lanes: u32) -> (u32, Vec4, Vec4, Vec4) {
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
        (ok.bitmask() & lanes & self.tri_mask, t, u, v)
    }
}

/// All surfaces of a scene and their acceleration structure.
pub struct Geometry {
    tris: Vec<Tri>,
    vertex_normals: Vec<[Vec3; 3]>,
    spheres: Vec<Sphere>,
    disks: Vec<Disk>,
    /// Primitive references in BVH leaf order, each leaf starting at a
    /// multiple of 4 (padded with [`PAD`]).
    prims: Vec<u32>,
    /// `packs[k]` holds the triangles among `prims[4k..4k+4]` for 4-wide tests.
    packs: Vec<TriPack>,
    bvh: Bvh,
    sampling: Vec<ShapeSampling>,
    /// Surface area of each shape, world space.
    pub areas: Vec<f32>,
}

fn tri_area(t: &Tri) -> f32 {
    let a = t.e1.cross(t.e2).length();
    if t.quad {
        a
    } else {
        0.5 * a
    }
}

impl Geometry {
    pub fn build(shapes: &[ShapeDesc]) -> Result<Geometry, RenderError> {
        let mut g = Geometry {
            tris: Vec::new(),
            vertex_normals: Vec::new(),
            spheres: Vec::new(),
            disks: Vec::new(),
            prims: Vec::new(),
            packs: Vec::new(),
            bvh: Bvh::build(&[]),
            sampling: Vec::new(),
            areas: Vec::new(),
        };
        for (si, shape) in shapes.iter().enumerate() {
            let sid = si as u32;
            let m = shape.to_world;
            let flip = if shape.flip_normals { -1.0 } else { 1.0 };
            if !m.is_finite() {
                return Err(RenderError::InvalidScene(format!(
                    "{}: to_world has non-finite entries",
                    shape.name
                )));
            }
            match &shape.geometry {
                GeometryDesc::Cube => {
                    let mut pos = Vec::new();
                    let mut idx = Vec::new();
                    for axis in 0..3 {
                        for s in [1.0f32, -1.0] {
                            let mut nrm = Vec3::ZERO;
                            nrm[axis] = s;
                            let mut u = Vec3::ZERO;
                            let mut v = Vec3::ZERO;
                            u[(axis + 1) % 3] = 1.0;
                            v[(axis + 2) % 3] = 1.0;
                            // u × v = +e_axis; swap for the negative face so
                            // the winding stays outward.
                            if s < 0.0 {
                                std::mem::swap(&mut u, &mut v);
                            }
                            let base = pos.len() as u32;
                            pos.extend([nrm - u - v, nrm + u - v, nrm + u + v, nrm - u + v]);
                            idx.push([base, base + 1, base + 2, base + 3]);
                        }
                    }
                    g.add_mesh(sid, &m, &pos, None, Faces::Quads(&idx), flip);
                }
                GeometryDesc::Rectangle => {
                    let pos = [
                        Vec3::new(-1.0, -1.0, 0.0),
                        Vec3::new(1.0, -1.0, 0.0),
                        Vec3::new(1.0, 1.0, 0.0),
                        Vec3::new(-1.0, 1.0, 0.0),
                    ];
                    // Analytic in Mitsuba: its normal is the transformed +z
                    // normal, which differs from the winding when det < 0.
                    let det_sign = if m.determinant() < 0.0 { -1.0 } else { 1.0 };
                    g.add_mesh(
                        sid,
                        &m,
                        &pos,
                        None,
                        Faces::Quads(&[[0, 1, 2, 3]]),
                        flip * det_sign,
                    );
                }
                GeometryDesc::Mesh(mesh) => {
                    for (k, t) in mesh.indices.iter().enumerate() {
                        if t.iter().any(|&i| i as usize >= mesh.positions.len()) {
                            return Err(RenderError::InvalidScene(format!(
                                "{}: face {k} refers to a missing vertex",
                                shape.name
                            )));
                        }
                    }
                    g.add_mesh(
                        sid,
                        &m,
                        &mesh.positions,
                        mesh.normals.as_deref(),
                        Faces::Tris(&mesh.indices),
                        flip,
                    );
                }
                GeometryDesc::Sphere { center, radius } => {
                    // Mitsuba's sphere stays a sphere: `to_world` must be a
                    // similarity (rotation, uniform scale, translation).
                    let l = Mat3::from_mat4(m);
                    let sx = l.x_axis.length();
                    let (sy, sz) = (l.y_axis.length(), l.z_axis.length());
                    let ortho = l.x_axis.dot(l.y_axis).abs()
                        + l.y_axis.dot(l.z_axis).abs()
                        + l.x_axis.dot(l.z_axis).abs();
                    if (sx - sy).abs() > 1e-4 * sx
                        || (sx - sz).abs() > 1e-4 * sx
                        || ortho > 1e-4 * sx * sx
                    {
                        return Err(RenderError::InvalidScene(format!(
                            "{}: a sphere's to_world must be a rotation, uniform scale and translation",
                            shape.name
                        )));
                    }
                    let r = radius * sx;
                    if !(r > 0.0 && r.is_finite()) {
                        return Err(RenderError::InvalidScene(format!(
                            "{}: sphere radius must be positive and finite",
                            shape.name
                        )));
                    }
                    let c = m.transform_point3(*center);
                    g.areas.push(4.0 * PI * r * r);
                    g.sampling
                        .push(ShapeSampling::Sphere(g.spheres.len() as u32));
                    g.prims
                        .push((KIND_SPHERE << KIND_SHIFT) | g.spheres.len() as u32);
                    g.spheres.push(Sphere {
                        center: c,
                        radius: r,
                        sign: flip,
                        shape: sid,
                    });
                }
                GeometryDesc::Disk => {
                    let to_world = Affine3A::from_mat4(m);
                    if m.determinant().abs() < 1e-20 {
                        return Err(RenderError::InvalidScene(format!(
                            "{}: disk to_world is singular",
                            shape.name
                        )));
                    }
                    let to_local = to_world.inverse();
                    let n = (to_local.matrix3.transpose() * Vec3::Z).normalize() * flip;
                    let area = PI
                        * to_world
                            .matrix3
                            .x_axis
                            .cross(to_world.matrix3.y_axis)
                            .length();
                    g.areas.push(area);
                    g.sampling.push(ShapeSampling::Disk(g.disks.len() as u32));
                    g.prims
                        .push((KIND_DISK << KIND_SHIFT) | g.disks.len() as u32);
                    g.disks.push(Disk {
                        to_local,
                        to_world,
                        n,
                        shape: sid,
                    });
                }
            }
        }
        let bounds: Vec<Aabb> = g.prims.iter().map(|&p| g.prim_bounds(p)).collect();
        g.bvh = Bvh::build(&bounds);
        // Store primitives in leaf order so traversal reads them contiguously,
        // each leaf starting a pack of 4.
        g.bvh.pad_leaves(4, PAD);
        let order = std::mem::take(&mut g.bvh.order);
        let prims: Vec<u32> = order
            .iter()
            .map(|&i| if i == PAD { PAD } else { g.prims[i as usize] })
            .collect();
        g.bvh.order = (0..prims.len() as u32).collect();
        g.prims = prims;
        g.packs = g
            .prims
            .chunks(4)
            .map(|chunk| {
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
                        let t = &g.tris[(p & INDEX_MASK) as usize];
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
            })
            .collect();
        Ok(g)
    }

    fn add_mesh(
        &mut self,
        sid: u32,
        m: &Mat4,
        pos: &[Vec3],
        normals: Option<&[Vec3]>,
        faces: Faces,
        sign: f32,
    ) {
        let wp: Vec<Vec3> = pos.iter().map(|&p| m.transform_point3(p)).collect();
        let nm = Mat3::from_mat4(*m).inverse().transpose();
        let wn: Option<Vec<Vec3>> = normals.map(|ns| {
            ns.iter()
                .map(|&n| (nm * n).normalize_or_zero() * sign)
                .collect()
        });
        let first = self.tris.len() as u32;
        let mut cdf = Vec::new();
        let mut total = 0.0f32;
        // Each face as (v0, edge to u = 1, edge to v = 1, parallelogram?,
        // its vertex indices if a triangle: they index the vertex normals).
        let face = |i0: u32, i1: u32, i2: u32| {
            let v0 = wp[i0 as usize];
            (v0, wp[i1 as usize] - v0, wp[i2 as usize] - v0)
        };
        type Face = (Vec3, Vec3, Vec3, bool, Option<[u32; 3]>);
        let corners: Vec<Face> = match faces {
            Faces::Tris(idx) => idx
                .iter()
                .map(|t| {
                    let (v0, e1, e2) = face(t[0], t[1], t[2]);
                    (v0, e1, e2, false, Some(*t))
                })
                .collect(),
            Faces::Quads(idx) => idx
                .iter()
                .map(|q| {
                    let (v0, e1, e2) = face(q[0], q[1], q[3]);
                    (v0, e1, e2, true, None)
                })
                .collect(),
        };
        for (v0, e1, e2, quad, tri_idx) in corners {
            let c = e1.cross(e2);
            // Degenerate faces can never be hit and have no area.
            if !(c.length_squared() > 0.0) || !c.is_finite() {
                continue;
            }
            let normals_idx = match (&wn, tri_idx) {
                (Some(wn), Some(t)) if t.iter().all(|&i| (i as usize) < wn.len()) => {
                    self.vertex_normals.push([
                        wn[t[0] as usize],
                        wn[t[1] as usize],
                        wn[t[2] as usize],
                    ]);
                    (self.vertex_normals.len() - 1) as u32
                }
                _ => u32::MAX,
            };
            let tri = Tri {
                v0: v0.into(),
                e1: e1.into(),
                e2: e2.into(),
                n: c.normalize() * sign,
                shape: sid,
                normals: normals_idx,
                quad,
            };
            total += tri_area(&tri);
            cdf.push(total);
            self.prims
                .push((KIND_TRI << KIND_SHIFT) | self.tris.len() as u32);
            self.tris.push(tri);
        }
        if total > 0.0 {
            for c in &mut cdf {
                *c /= total;
            }
        }
        self.areas.push(total);
        self.sampling.push(ShapeSampling::Tris { first, cdf });
    }

    fn prim_bounds(&self, p: u32) -> Aabb {
        let i = (p & INDEX_MASK) as usize;
        match p >> KIND_SHIFT {
            KIND_TRI => {
                let t = &self.tris[i];
                let b = Aabb::EMPTY
                    .grow(t.v0.into())
                    .grow((t.v0 + t.e1).into())
                    .grow((t.v0 + t.e2).into());
                if t.quad {
                    b.grow((t.v0 + t.e1 + t.e2).into())
                } else {
                    b
                }
            }
            KIND_SPHERE => {
                let s = &self.spheres[i];
                Aabb {
                    min: s.center - Vec3::splat(s.radius),
                    max: s.center + Vec3::splat(s.radius),
                }
            }
            _ => {
                let d = &self.disks[i];
                let mut b = Aabb::EMPTY;
                for (x, y) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                    b = b.grow(d.to_world.transform_point3(Vec3::new(x, y, 0.0)));
                }
                b
            }
        }
    }

    /// World bounds of all surfaces.
    pub fn bounds(&self) -> Aabb {
        self.bvh.bounds()
    }

    /// Calls `f(prim, t, u, v)` for every hit with `0 < t < t_max` of the
    /// primitives of the leaf `start..start + count` (both crossings of a
    /// sphere), where `f` returns the new `t_max`: smaller to look only for
    /// nearer hits, negative to stop (then this returns `false`).
    #[inline(always)]
    fn leaf_hits(
        &self,
        ray: &Ray,
        od: &([Vec4; 3], [Vec4; 3]),
        start: u32,
        count: u32,
        t_max: &mut f32,
        mut f: impl FnMut(u32, f32, f32, f32) -> f32,
    ) -> bool {
        // Leaves start at multiples of 4 (see `Bvh::pad_leaves`).
        let end = start + count;
        let mut k = start;
        while k < end {
            let pack = &self.packs[(k / 4) as usize];
            let lanes = if end - k >= 4 {
                0xF
            } else {
                (1u32 << (end - k)) - 1
            };
            if pack.tri_mask & lanes != 0 {
                let (mut mask, t, u, v) = pack.hits(od.0, od.1, *t_max, lanes);
                if mask != 0 {
                    let (t, u, v) = (t.to_array(), u.to_array(), v.to_array());
                    while mask != 0 {
                        let l = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        // A lane may have been overtaken by an earlier one.
                        if t[l] < *t_max {
                            *t_max = f(self.prims[k as usize + l], t[l], u[l], v[l]);
                            if *t_max < 0.0 {
                                return false;
                            }
                        }
                    }
                }
            }
            let mut other = pack.other_mask & lanes;
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
                    if t > 0.0 && t < *t_max {
                        *t_max = f(p, t, 0.0, 0.0);
                        if *t_max < 0.0 {
                            return false;
                        }
                    }
                }
            }
            k += 4;
        }
        true
    }

    /// The ray's origin and direction splatted for the 4-wide tests.
    #[inline(always)]
    fn splat_ray(ray: &Ray) -> ([Vec4; 3], [Vec4; 3]) {
        (
            ray.o.to_array().map(Vec4::splat),
            ray.d.to_array().map(Vec4::splat),
        )
    }

    /// Nearest hit with `t < t_max`, if any.
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        // (primitive, t, barycentric u, v) of the nearest hit so far.
        let mut best: Option<(u32, f32, f32, f32)> = None;
        let od = Self::splat_ray(ray);
        self.bvh
            .traverse_leaves(ray.o, ray.d, t_max, |start, count, mut t_max| {
                self.leaf_hits(ray, &od, start, count, &mut t_max, |p, t, u, v| {
                    best = Some((p, t, u, v));
                    t
                });
                t_max
            });
        best.map(|b| self.make_hit(ray, HitRecord(b)))
    }

    /// The two nearest hits with `t < t_max`, nearer first. Used where the
    /// nearest is likely a `null` boundary the path crosses: the second is
    /// then the next hit of the continued ray, without a second traversal.
    /// The second comes as a [`HitRecord`], made into a [`Hit`] by
    /// [`Self::make_hit`] only if needed.
    #[inline(always)]
    pub fn intersect2(&self, ray: &Ray, t_max: f32) -> (Option<Hit>, Option<HitRecord>) {
        let mut best: [Option<(u32, f32, f32, f32)>; 2] = [None, None];
        let od = Self::splat_ray(ray);
        self.bvh
            .traverse_leaves(ray.o, ray.d, t_max, |start, count, mut t_leaf| {
                self.leaf_hits(ray, &od, start, count, &mut t_leaf, |p, t, u, v| {
                    // t is below the current second-nearest (t_leaf).
                    match best[0] {
                        Some(b) if b.1 <= t => best[1] = Some((p, t, u, v)),
                        _ => {
                            best[1] = best[0];
                            best[0] = Some((p, t, u, v));
                        }
                    }
                    best[1].map_or(t_max, |b| b.1)
                });
                t_leaf
            });
        (
            best[0].map(|b| self.make_hit(ray, HitRecord(b))),
            best[1].map(HitRecord),
        )
    }

    /// The [`Hit`] of primitive `p` hit at `t` (barycentrics `u, v`).
    #[inline(always)]
    pub fn make_hit(&self, ray: &Ray, HitRecord((p, t, u, v)): HitRecord) -> Hit {
        let i = (p & INDEX_MASK) as usize;
        match p >> KIND_SHIFT {
            KIND_TRI => {
                let tri = &self.tris[i];
                let ns = if tri.normals != u32::MAX {
                    let vn = &self.vertex_normals[tri.normals as usize];
                    let n = (1.0 - u - v) * vn[0] + u * vn[1] + v * vn[2];
                    n.try_normalize().unwrap_or(tri.n)
                } else {
                    tri.n
                };
                // The hit point from barycentrics is more accurate than o + t d.
                Hit {
                    t,
                    p: (tri.v0 + u * tri.e1 + v * tri.e2).into(),
                    n: tri.n,
                    ns,
                    shape: tri.shape,
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
                }
            }
        }
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
    pub fn for_each_hit(
        &self,
        ray: &Ray,
        t_max: f32,
        mut visit: impl FnMut(u32, u32, f32, Vec3) -> bool,
    ) -> bool {
        let od = Self::splat_ray(ray);
        let mut go = true;
        self.bvh
            .traverse_leaves(ray.o, ray.d, t_max, |start, count, mut t| {
                go = self.leaf_hits(ray, &od, start, count, &mut t, |p, t, _, _| {
                    let i = (p & INDEX_MASK) as usize;
                    let (shape, n) = match p >> KIND_SHIFT {
                        KIND_TRI => (self.tris[i].shape, self.tris[i].n),
                        KIND_SPHERE => {
                            let s = &self.spheres[i];
                            (s.shape, (ray.at(t) - s.center).normalize() * s.sign)
                        }
                        _ => (self.disks[i].shape, self.disks[i].n),
                    };
                    if visit(p, shape, t, n) {
                        t_max
                    } else {
                        -1.0
                    }
                });
                t
            });
        go
    }

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
                    crate::math::sample_uniform_triangle(u)
                };
                PositionSample {
                    p: (t.v0 + b[0] * t.e1 + b[1] * t.e2).into(),
                    n: t.n,
                }
            }
            ShapeSampling::Sphere(i) => {
                let s = &self.spheres[*i as usize];
                let d = crate::math::sample_uniform_sphere(u);
                PositionSample {
                    p: s.center + s.radius * d,
                    n: d * s.sign,
                }
            }
            ShapeSampling::Disk(i) => {
                let d = &self.disks[*i as usize];
                let q = crate::math::sample_concentric_disk(u);
                PositionSample {
                    p: d.to_world.transform_point3(Vec3::new(q[0], q[1], 0.0)),
                    n: d.n,
                }
            }
        }
    }
}

/// Möller–Trumbore, one triangle or parallelogram; returns `(t, u, v)`
/// with `0 < t < t_max`.
/// The reference the 4-wide [`TriPack::hits`] is tested against.
#[cfg(test)]
fn intersect_tri(tri: &Tri, o: Vec3A, d: Vec3A, t_max: f32) -> Option<(f32, f32, f32)> {
    let pvec = d.cross(tri.e2);
    let det = tri.e1.dot(pvec);
    if det == 0.0 {
        return None;
    }
    let inv_det = 1.0 / det;
    let tvec = o - tri.v0;
    let u = tvec.dot(pvec) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let qvec = tvec.cross(tri.e1);
    let v = d.dot(qvec) * inv_det;
    if v < 0.0 || (if tri.quad { v > 1.0 } else { u + v > 1.0 }) {
        return None;
    }
    let t = tri.e2.dot(qvec) * inv_det;
    if t > 0.0 && t < t_max {
        Some((t, u, v))
    } else {
        None
    }
}

/// Both ray parameters where the ray's line meets the sphere (NaN if it
/// misses), nearer first.
#[inline]
fn sphere_roots(s: &Sphere, ray: &Ray) -> [f32; 2] {
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
fn disk_root(d: &Disk, ray: &Ray) -> f32 {
    let o = d.to_local.transform_point3(ray.o);
    let dir = d.to_local.transform_vector3(ray.d);
    // Affine maps keep the ray parameter, so the local t is the world t.
    let t = -o.z / dir.z;
    let p = o + t * dir;
    if p.x * p.x + p.y * p.y <= 1.0 {
        t
    } else {
        f32::NAN
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fgf_scene::TriangleMesh;
    use std::sync::Arc;

    /// A shape with BSDF 0 and no emitter or media.
    fn plain_shape(geometry: GeometryDesc, to_world: Mat4) -> ShapeDesc {
        ShapeDesc {
            name: "shape".into(),
            geometry,
            to_world,
            flip_normals: false,
            bsdf: 0,
            emitter: None,
            interior: None,
            exterior: None,
        }
    }

    /// `n` random triangles of about `size` scattered over `[0, 4]³`.
    fn triangle_soup(s: &mut crate::math::Sampler, n: u32, size: f32) -> Arc<TriangleMesh> {
        let mut r3 = || Vec3::new(s.next_1d(), s.next_1d(), s.next_1d());
        let mut positions = Vec::new();
        let mut indices = Vec::new();
        for i in 0..n {
            let c = r3() * 4.0;
            for _ in 0..3 {
                positions.push(c + (r3() - Vec3::splat(0.5)) * size);
            }
            indices.push([3 * i, 3 * i + 1, 3 * i + 2]);
        }
        Arc::new(TriangleMesh {
            positions,
            normals: None,
            indices,
        })
    }

    /// The BVH with 4-wide leaf packs finds the same nearest hit as a brute
    /// force loop over all triangles (random triangle soup, random rays).
    #[test]
    fn packed_bvh_matches_brute_force() {
        let mut s = crate::math::Sampler::new(11, 0, 0);
        let r3 = |s: &mut crate::math::Sampler| Vec3::new(s.next_1d(), s.next_1d(), s.next_1d());
        let mesh = triangle_soup(&mut s, 300, 0.6);
        let g = Geometry::build(&[plain_shape(GeometryDesc::Mesh(mesh), Mat4::IDENTITY)]).unwrap();
        for _ in 0..2000 {
            let o = r3(&mut s) * 6.0 - Vec3::ONE;
            let d = crate::math::sample_uniform_sphere(s.next_2d());
            let ray = Ray { o, d };
            let got = g.intersect(&ray, f32::INFINITY).map(|h| h.t);
            let want = g
                .tris
                .iter()
                .filter_map(|t| intersect_tri(t, o.into(), d.into(), f32::INFINITY).map(|r| r.0))
                .fold(None, |m: Option<f32>, t| Some(m.map_or(t, |m| m.min(t))));
            match (got, want) {
                (None, None) => {}
                (Some(a), Some(b)) => assert!((a - b).abs() <= 1e-5 * (1.0 + b), "{a} vs {b}"),
                other => panic!("{other:?}"),
            }
        }
    }

    /// A scene of every primitive kind (a triangle soup, cubes and
    /// rectangles as parallelograms, spheres, disks): the nearest, the two
    /// nearest and the all-hits queries agree with brute force over the
    /// primitives, for random rays and random segment lengths.
    #[test]
    fn queries_match_brute_force_on_mixed_primitives() {
        use glam::Quat;
        let mut s = crate::math::Sampler::new(12, 0, 0);
        let r3 = |s: &mut crate::math::Sampler| Vec3::new(s.next_1d(), s.next_1d(), s.next_1d());
        let mut shapes = Vec::new();
        let mut push =
            |geometry: GeometryDesc, to_world: Mat4| shapes.push(plain_shape(geometry, to_world));
        push(
            GeometryDesc::Mesh(triangle_soup(&mut s, 40, 0.8)),
            Mat4::IDENTITY,
        );
        for _ in 0..6 {
            let rot = Quat::from_axis_angle(
                (r3(&mut s) - Vec3::splat(0.5)).normalize(),
                3.0 * s.next_1d(),
            );
            let m = Mat4::from_scale_rotation_translation(
                0.2 + r3(&mut s) * 0.6,
                rot,
                r3(&mut s) * 4.0,
            );
            push(GeometryDesc::Cube, m);
            push(
                GeometryDesc::Rectangle,
                m * Mat4::from_translation(Vec3::Z * 0.3),
            );
            push(
                GeometryDesc::Disk,
                m * Mat4::from_translation(Vec3::X * 0.5),
            );
            let c = r3(&mut s) * 4.0;
            push(
                GeometryDesc::Sphere {
                    center: c,
                    radius: 0.1 + 0.5 * s.next_1d(),
                },
                Mat4::IDENTITY,
            );
        }
        let g = Geometry::build(&shapes).unwrap();
        assert!(g.tris.iter().any(|t| t.quad) && !g.spheres.is_empty() && !g.disks.is_empty());
        let mut n_hits = 0usize;
        for _ in 0..3000 {
            let o = r3(&mut s) * 6.0 - Vec3::ONE;
            let d = crate::math::sample_uniform_sphere(s.next_2d());
            let ray = Ray { o, d };
            let t_max = if s.next_1d() < 0.5 {
                f32::INFINITY
            } else {
                6.0 * s.next_1d()
            };
            let mut want: Vec<(f32, u32)> = Vec::new();
            for t in &g.tris {
                if let Some((th, _, _)) = intersect_tri(t, o.into(), d.into(), t_max) {
                    want.push((th, t.shape));
                }
            }
            for sp in &g.spheres {
                for th in sphere_roots(sp, &ray) {
                    if th > 0.0 && th < t_max {
                        want.push((th, sp.shape));
                    }
                }
            }
            for dk in &g.disks {
                let th = disk_root(dk, &ray);
                if th > 0.0 && th < t_max {
                    want.push((th, dk.shape));
                }
            }
            want.sort_by(|a, b| a.0.total_cmp(&b.0));
            n_hits += want.len();
            let close = |a: f32, b: f32| (a - b).abs() <= 1e-5 * (1.0 + b);
            let near = g.intersect(&ray, t_max).map(|h| h.t);
            match (near, want.first()) {
                (None, None) => {}
                (Some(a), Some(b)) => assert!(close(a, b.0), "nearest {a} vs {}", b.0),
                other => panic!("nearest: {other:?}"),
            }
            let (h1, h2) = g.intersect2(&ray, t_max);
            assert_eq!(h1.map(|h| h.t), near);
            match (h2.map(|r| g.make_hit(&ray, r).t), want.get(1)) {
                (None, None) => {}
                (Some(a), Some(b)) => assert!(close(a, b.0), "second {a} vs {}", b.0),
                other => panic!("second: {other:?}"),
            }
            let mut all = Vec::new();
            assert!(g.for_each_hit(&ray, t_max, |_, shape, t, n| {
                assert!((n.length() - 1.0).abs() < 1e-4);
                all.push((t, shape));
                true
            }));
            all.sort_by(|a, b| a.0.total_cmp(&b.0));
            assert_eq!(all.len(), want.len());
            for (a, b) in all.iter().zip(&want) {
                assert!(close(a.0, b.0) && a.1 == b.1, "{a:?} vs {b:?}");
            }
            // Stopping at the first hit visits exactly one.
            if !want.is_empty() {
                let mut visits = 0;
                assert!(!g.for_each_hit(&ray, t_max, |_, _, _, _| {
                    visits += 1;
                    false
                }));
                assert_eq!(visits, 1);
            }
        }
        assert!(n_hits > 1000, "too few hits to test anything: {n_hits}");
    }

    /// Parallelograms sample points uniformly over their whole area, and a
    /// cube's area is that of its six faces.
    #[test]
    fn cube_area_and_sampling() {
        let cube = plain_shape(
            GeometryDesc::Cube,
            Mat4::from_scale(Vec3::new(1.0, 2.0, 3.0)),
        );
        let g = Geometry::build(&[cube]).unwrap();
        // Faces 2x4, 4x6, 2x6 (two of each).
        assert!((g.areas[0] - 2.0 * (8.0 + 24.0 + 12.0)).abs() < 1e-4);
        let mut s = crate::math::Sampler::new(5, 0, 0);
        let n = 40_000;
        let mut on_top_far_corner = 0;
        for _ in 0..n {
            let ps = g.sample_shape(0, s.next_1d(), s.next_2d());
            // On the surface of the box, normal pointing out of the face.
            let q = ps.p / Vec3::new(1.0, 2.0, 3.0);
            assert!((q.abs().max_element() - 1.0).abs() < 1e-5);
            let axis = (0..3)
                .max_by(|&a, &b| q[a].abs().total_cmp(&q[b].abs()))
                .unwrap();
            let mut face_n = Vec3::ZERO;
            face_n[axis] = q[axis].signum();
            assert!((ps.n - face_n).length() < 1e-6, "{:?} at {:?}", ps.n, ps.p);
            if ps.n.y > 0.5 && ps.p.x > 0.0 && ps.p.z > 0.0 {
                on_top_far_corner += 1;
            }
        }
        // The quarter x, z > 0 of the +y face (2 x 6): area 3 of 88; 4 SE.
        let p = 3.0 / 88.0;
        let se = (p * (1.0 - p) / n as f64).sqrt();
        let got = on_top_far_corner as f64 / n as f64;
        assert!((got - p).abs() < 4.0 * se, "{got} vs {p}");
    }
}
