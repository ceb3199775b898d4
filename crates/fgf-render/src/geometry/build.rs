//! Compiling the shapes of a scene: validation, world-space primitives,
//! area-sampling tables, then the BVH and the leaf packs in its order.

use super::bvh::{Aabb, Bvh};
use super::pack::TriPack;
use super::types::{
    Corners, Disk, ShapeSampling, Sphere, INDEX_MASK, KIND_DISK, KIND_SHIFT, KIND_SPHERE, KIND_TRI,
    PAD,
};
use super::uv::cube_uv;
use super::Geometry;
use crate::error::RenderError;
use fgf_scene::{GeometryDesc, ShapeDesc};
use glam::{Affine3A, Mat3, Mat4, Vec2, Vec3A};
use rayon::prelude::*;
use std::f32::consts::PI;

/// Faces of a mesh: triangles, or parallelograms given by their corners in
/// order around the boundary (the fourth corner is implied by the others).
enum Faces<'a> {
    Tris(&'a [[u32; 3]]),
    Quads(&'a [[u32; 4]]),
}

/// Inputs of fewer elements than this are mapped on the calling thread:
/// a rayon call from outside the pool wakes its workers, which costs more
/// than mapping a few hundred elements (a scene of 20,000 cubes and
/// rectangles spent 2.5 s of system time in such wake-ups).
const PAR_MIN_ITEMS: usize = 4096;

/// Append `f` of each of `items` to `dst`, in order: for many items made on
/// the rayon pool and written straight into `dst`'s spare capacity.
fn extend_mapped<S: Sync, T: Send>(
    dst: &mut Vec<T>,
    items: &[S],
    f: impl Fn(&S) -> T + Sync + Send,
) {
    if items.len() >= PAR_MIN_ITEMS {
        dst.par_extend(items.par_iter().map(f));
    } else {
        dst.extend(items.iter().map(f));
    }
}

/// Append to `dst` the value `f(v, quad)` of each face of `faces`, in face
/// order ([`extend_mapped`]): a triangle's `v` its vertex indices, a
/// parallelogram's its first, second and fourth corners (`quad`).
fn extend_faces<T: Send>(
    dst: &mut Vec<T>,
    faces: &Faces,
    f: impl Fn([u32; 3], bool) -> T + Sync + Send,
) {
    match faces {
        Faces::Tris(idx) => extend_mapped(dst, idx, |t| f(*t, false)),
        Faces::Quads(idx) => extend_mapped(dst, idx, |q| f([q[0], q[1], q[3]], true)),
    }
}

/// Whether `c`, the cross product of a face's edges, makes it a face that
/// can be hit: nonzero and finite.
fn is_face(c: Vec3A) -> bool {
    c.length_squared() > 0.0 && c.is_finite()
}

/// Keep the elements of `v` before `first` and those after where `keep`
/// (one flag per element from `first` on), in order.
fn retain_after<T>(v: &mut Vec<T>, first: usize, keep: &[bool]) {
    let mut i = 0;
    v.retain(|_| {
        let k = i < first || keep[i - first];
        i += 1;
        k
    });
}

/// Give the vertices `base..end` of the geometry, a new mesh's, their
/// entries in `dst`, one of its per-vertex arrays (normals, uvs): `f` of
/// the mesh's `data` where it has them (as many as it has, up to its
/// vertex count; [`extend_mapped`], straight into `dst`), zero for the rest
/// and for earlier meshes without; nothing while no mesh has any. Returns
/// how many of the mesh's vertices have data.
fn extend_vertex_data<S: Sync, T: Copy + Default + Send>(
    dst: &mut Vec<T>,
    base: usize,
    end: usize,
    data: Option<&[S]>,
    f: impl Fn(&S) -> T + Sync + Send,
) -> usize {
    let data = data.unwrap_or_default();
    let n = data.len().min(end - base);
    if n > 0 || !dst.is_empty() {
        dst.resize(base, T::default());
        extend_mapped(dst, &data[..n], f);
        dst.resize(end, T::default());
    }
    n
}

/// The scale of `m` along x, and whether its linear part is a similarity
/// (rotation and uniform scale), which a sphere's `to_world` must be for it
/// to stay a sphere, as in Mitsuba.
fn similarity_scale(m: &Mat4) -> (f32, bool) {
    let l = Mat3::from_mat4(*m);
    let sx = l.x_axis.length();
    let (sy, sz) = (l.y_axis.length(), l.z_axis.length());
    let ortho =
        l.x_axis.dot(l.y_axis).abs() + l.y_axis.dot(l.z_axis).abs() + l.x_axis.dot(l.z_axis).abs();
    let similar =
        (sx - sy).abs() <= 1e-4 * sx && (sx - sz).abs() <= 1e-4 * sx && ortho <= 1e-4 * sx * sx;
    (sx, similar)
}

/// The checks a shape must pass to be compiled: a finite `to_world`, mesh
/// faces that refer to existing vertices, a sphere under a similarity with
/// a positive finite radius, a disk under an invertible map.
fn validate(shape: &ShapeDesc) -> Result<(), RenderError> {
    let m = shape.to_world;
    let invalid = |what: String| Err(RenderError::InvalidScene(format!("{}: {what}", shape.name)));
    if !m.is_finite() {
        return invalid("to_world has non-finite entries".into());
    }
    match &shape.geometry {
        GeometryDesc::Mesh(mesh) => {
            for (k, t) in mesh.indices.iter().enumerate() {
                if t.iter().any(|&i| i as usize >= mesh.positions.len()) {
                    return invalid(format!("face {k} refers to a missing vertex"));
                }
            }
        }
        GeometryDesc::Sphere { radius, .. } => {
            let (sx, similar) = similarity_scale(&m);
            if !similar {
                return invalid(
                    "a sphere's to_world must be a rotation, uniform scale and translation".into(),
                );
            }
            let r = radius * sx;
            if !(r > 0.0 && r.is_finite()) {
                return invalid("sphere radius must be positive and finite".into());
            }
        }
        GeometryDesc::Disk => {
            if m.determinant().abs() < 1e-20 {
                return invalid("disk to_world is singular".into());
            }
        }
        GeometryDesc::Cube | GeometryDesc::Rectangle => {}
    }
    Ok(())
}

/// The primitives of the shapes compiled so far, in shape order.
#[derive(Default)]
pub(crate) struct Builder {
    corners: Vec<Corners>,
    positions: Vec<glam::Vec3>,
    normals: Vec<glam::Vec3>,
    uvs: Vec<Vec2>,
    spheres: Vec<Sphere>,
    sphere_to_local: Vec<Mat3>,
    disks: Vec<Disk>,
    /// Primitive references, in the order they were added.
    prims: Vec<u32>,
    sampling: Vec<ShapeSampling>,
    areas: Vec<f32>,
}

impl Geometry {
    /// Compile `shapes` (each checked by `validate` first) and build the
    /// BVH over all their primitives.
    pub fn build(shapes: &[ShapeDesc]) -> Result<Geometry, RenderError> {
        Ok(Self::compile(shapes)?.finish())
    }

    /// The first half of [`Geometry::build`]: `shapes` checked and their
    /// primitives made, in world space, with copies of the meshes' vertex
    /// data. [`Builder::finish`] builds the tree; `shapes` are not needed
    /// for it.
    pub(crate) fn compile(shapes: &[ShapeDesc]) -> Result<Builder, RenderError> {
        let mut g = Builder::default();
        if shapes.len() as u64 > u64::from(!Corners::FLAGS) {
            return Err(RenderError::InvalidScene(format!(
                "{} shapes: at most {} are supported",
                shapes.len(),
                !Corners::FLAGS
            )));
        }
        g.reserve(shapes)?;
        for (si, shape) in shapes.iter().enumerate() {
            validate(shape)?;
            g.add_shape(si as u32, shape);
        }
        Ok(g)
    }
}

impl Builder {
    /// Room for the faces and vertices of all `shapes` at once, or an
    /// error if there are more primitives than a reference can index or
    /// the memory cannot be had. (Grown shape by shape, a large mesh's
    /// arrays were copied whole whenever a later shape overflowed them,
    /// each copy into new pages.)
    fn reserve(&mut self, shapes: &[ShapeDesc]) -> Result<(), RenderError> {
        let (mut faces, mut vertices, mut others) = (0usize, 0usize, 0usize);
        let (mut normals, mut uvs) = (false, false);
        for shape in shapes {
            let (f, v) = match &shape.geometry {
                GeometryDesc::Mesh(mesh) => {
                    normals |= mesh.normals.is_some();
                    uvs |= mesh.texcoords.is_some();
                    (mesh.indices.len(), mesh.positions.len())
                }
                // Six faces or one, each four corners with their uvs.
                GeometryDesc::Cube => {
                    uvs = true;
                    (6, 24)
                }
                GeometryDesc::Rectangle => {
                    uvs = true;
                    (1, 4)
                }
                GeometryDesc::Sphere { .. } | GeometryDesc::Disk => {
                    others += 1;
                    (0, 0)
                }
            };
            faces = faces.saturating_add(f);
            vertices = vertices.saturating_add(v);
        }
        let prims = faces.saturating_add(others);
        if prims > INDEX_MASK as usize + 1 {
            return Err(RenderError::InvalidScene(format!(
                "{prims} primitives (faces, spheres and disks): at most {} are supported",
                INDEX_MASK as usize + 1
            )));
        }
        let too_large = |_| {
            RenderError::InvalidScene(format!(
                "{faces} faces and {vertices} vertices: not enough memory for the geometry"
            ))
        };
        self.corners.try_reserve_exact(faces).map_err(too_large)?;
        self.prims.try_reserve_exact(prims).map_err(too_large)?;
        self.positions
            .try_reserve_exact(vertices)
            .map_err(too_large)?;
        if normals {
            self.normals
                .try_reserve_exact(vertices)
                .map_err(too_large)?;
        }
        if uvs {
            self.uvs.try_reserve_exact(vertices).map_err(too_large)?;
        }
        Ok(())
    }

    /// Add one (validated) shape.
    fn add_shape(&mut self, sid: u32, shape: &ShapeDesc) {
        let m = shape.to_world;
        let flip = if shape.flip_normals { -1.0 } else { 1.0 };
        match &shape.geometry {
            GeometryDesc::Cube => {
                let mut pos = Vec::new();
                let mut uvs = Vec::new();
                let mut idx = Vec::new();
                for axis in 0..3 {
                    for s in [1.0f32, -1.0] {
                        let mut nrm = Vec3A::ZERO;
                        nrm[axis] = s;
                        let mut u = Vec3A::ZERO;
                        let mut v = Vec3A::ZERO;
                        u[(axis + 1) % 3] = 1.0;
                        v[(axis + 2) % 3] = 1.0;
                        // u × v = +e_axis; swap for the negative face so
                        // the winding stays outward.
                        if s < 0.0 {
                            std::mem::swap(&mut u, &mut v);
                        }
                        let base = pos.len() as u32;
                        let corners = [nrm - u - v, nrm + u - v, nrm + u + v, nrm - u + v];
                        pos.extend(corners);
                        uvs.extend(corners.map(|c| cube_uv(axis, s, c)));
                        idx.push([base, base + 1, base + 2, base + 3]);
                    }
                }
                let faces = Faces::Quads(&idx);
                self.add_mesh(sid, &m, &pos, None, Some(&uvs), faces, flip);
            }
            GeometryDesc::Rectangle => {
                let pos = [
                    Vec3A::new(-1.0, -1.0, 0.0),
                    Vec3A::new(1.0, -1.0, 0.0),
                    Vec3A::new(1.0, 1.0, 0.0),
                    Vec3A::new(-1.0, 1.0, 0.0),
                ];
                // Analytic in Mitsuba: its normal is the transformed +z
                // normal, which differs from the winding when det < 0.
                let det_sign = if m.determinant() < 0.0 { -1.0 } else { 1.0 };
                let quad = Faces::Quads(&[[0, 1, 2, 3]]);
                let uvs = pos.map(|p| Vec2::new(0.5 * (p.x + 1.0), 0.5 * (p.y + 1.0)));
                self.add_mesh(sid, &m, &pos, None, Some(&uvs), quad, flip * det_sign);
            }
            GeometryDesc::Mesh(mesh) => {
                let faces = Faces::Tris(&mesh.indices);
                let normals = mesh.normals.as_deref();
                let uvs = mesh.texcoords.as_deref();
                self.add_mesh(sid, &m, &mesh.positions, normals, uvs, faces, flip);
            }
            GeometryDesc::Sphere { center, radius } => {
                let (sx, _) = similarity_scale(&m);
                let r = radius * sx;
                self.areas.push(4.0 * PI * r * r);
                let i = self.spheres.len() as u32;
                self.sampling.push(ShapeSampling::Sphere(i));
                self.prims.push((KIND_SPHERE << KIND_SHIFT) | i);
                self.sphere_to_local.push(Mat3::from_mat4(m).inverse());
                self.spheres.push(Sphere {
                    center: m.transform_point3a((*center).into()),
                    radius: r,
                    sign: flip,
                    shape: sid,
                });
            }
            GeometryDesc::Disk => {
                let to_world = Affine3A::from_mat4(m);
                let to_local = to_world.inverse();
                let n = (to_local.matrix3.transpose() * Vec3A::Z).normalize() * flip;
                let (x, y) = (to_world.matrix3.x_axis, to_world.matrix3.y_axis);
                self.areas.push(PI * x.cross(y).length());
                let i = self.disks.len() as u32;
                self.sampling.push(ShapeSampling::Disk(i));
                self.prims.push((KIND_DISK << KIND_SHIFT) | i);
                self.disks.push(Disk {
                    to_local,
                    to_world,
                    n,
                    shape: sid,
                });
            }
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn add_mesh<P: Copy + Into<Vec3A> + Sync>(
        &mut self,
        sid: u32,
        m: &Mat4,
        pos: &[P],
        normals: Option<&[glam::Vec3]>,
        uvs: Option<&[Vec2]>,
        faces: Faces,
        sign: f32,
    ) {
        // (Each element's work on its own, on the rayon pool for a large
        // mesh: the same values in the same order as one thread's.) The
        // vertices join the geometry's arrays after those of the meshes
        // before, with their normals (in world space) and uvs.
        let base = self.positions.len() as u32;
        extend_mapped(&mut self.positions, pos, |&p| {
            glam::Vec3::from(m.transform_point3a(p.into()))
        });
        let end = self.positions.len();
        let nm = Mat3::from_mat4(*m).inverse().transpose();
        let n_normals = extend_vertex_data(&mut self.normals, base as usize, end, normals, |&n| {
            (Vec3A::from(nm * n).normalize_or_zero() * sign).into()
        });
        let n_uvs = extend_vertex_data(&mut self.uvs, base as usize, end, uvs, |&t| t);
        let first = self.corners.len();
        // Each face given by its vertices at v0, v0 + e1 (u = 1) and v0 + e2
        // (v = 1), which index the uvs and, for a triangle, the vertex
        // normals; `quad`: a parallelogram. The records go straight into
        // the geometry's (reserved) array, in face order, with no
        // intermediate copy, and no `Tri` is kept for them (made from them
        // where needed, [`Corners::tri`]): a 4M-triangle mesh's took 320 MB
        // of fresh pages each (`docs/benchmarks.md`, "Large scenes on a
        // Zen 4 without AVX-512" and "Large meshes without their `Tri`s").
        extend_faces(&mut self.corners, &faces, |v, quad| {
            // Vertex normals only for triangles (not the parallelograms of
            // cubes and rectangles), as Mitsuba.
            let with_normals = !quad && v.iter().all(|&i| (i as usize) < n_normals);
            let with_uvs = v.iter().all(|&i| (i as usize) < n_uvs);
            let v = v.map(|i| base + i);
            Corners::new(v, sid, with_normals, with_uvs, sign < 0.0, quad)
        });
        // Degenerate faces can never be hit and have no area: dropped, the
        // others kept in order.
        let positions = &self.positions;
        let kept = |c: &Corners| {
            let (_, e1, e2) = c.edges(positions);
            is_face(e1.cross(e2))
        };
        let new = &self.corners[first..];
        let all_kept = if new.len() >= PAR_MIN_ITEMS {
            new.par_iter().all(kept)
        } else {
            new.iter().all(kept)
        };
        if !all_kept {
            let keep: Vec<bool> = new.iter().map(kept).collect();
            retain_after(&mut self.corners, first, &keep);
        }
        let faces_end = self.corners.len();
        self.prims
            .extend((first..faces_end).map(|i| (KIND_TRI << KIND_SHIFT) | i as u32));
        // The running sum of the areas, in face order.
        let mut cdf = Vec::with_capacity(faces_end - first);
        extend_mapped(&mut cdf, &self.corners[first..], |c| {
            c.tri(positions).area()
        });
        let mut total = 0.0f32;
        for c in &mut cdf {
            total += *c;
            *c = total;
        }
        if total > 0.0 {
            for c in &mut cdf {
                *c /= total;
            }
        }
        self.areas.push(total);
        self.sampling.push(ShapeSampling::Tris {
            first: first as u32,
            cdf,
        });
    }

    fn prim_bounds(&self, p: u32) -> Aabb {
        let i = (p & INDEX_MASK) as usize;
        match p >> KIND_SHIFT {
            KIND_TRI => {
                let c = &self.corners[i];
                let (v0, e1, e2) = c.edges(&self.positions);
                let b = Aabb::EMPTY.grow(v0).grow(v0 + e1).grow(v0 + e2);
                if c.quad() {
                    b.grow(v0 + e1 + e2)
                } else {
                    b
                }
            }
            KIND_SPHERE => {
                let s = &self.spheres[i];
                Aabb {
                    min: s.center - Vec3A::splat(s.radius),
                    max: s.center + Vec3A::splat(s.radius),
                }
            }
            _ => {
                let d = &self.disks[i];
                let mut b = Aabb::EMPTY;
                for (x, y) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                    b = b.grow(d.to_world.transform_point3a(Vec3A::new(x, y, 0.0)));
                }
                b
            }
        }
    }

    /// The BVH over every primitive, the primitives stored in its leaf
    /// order (each leaf starting a pack of `bvh::PACK`) and the packs.
    pub(crate) fn finish(self) -> Geometry {
        let bounds: Vec<Aabb> = self
            .prims
            .par_iter()
            .map(|&p| self.prim_bounds(p))
            .collect();
        let (bvh, order) = Bvh::build(bounds);
        // Store primitives in leaf order so traversal reads them contiguously.
        let prims: Vec<u32> = order
            .par_iter()
            .map(|i| i.map_or(PAD, |i| self.prims[i as usize]))
            .collect();
        let (packs, mut pack_other): (Vec<TriPack>, Vec<u8>) = prims
            .par_chunks(super::bvh::PACK)
            .map(|chunk| TriPack::new(chunk, |i| self.corners[i].tri(&self.positions)))
            .unzip();
        if pack_other.iter().all(|&o| o == 0) {
            pack_other = Vec::new();
        }
        // What queries and hits read, scattered (the BVH advises its own).
        crate::huge::advise(&packs);
        crate::huge::advise(&prims);
        crate::huge::advise(&self.corners);
        crate::huge::advise(&self.positions);
        crate::huge::advise(&self.normals);
        crate::huge::advise(&self.uvs);
        let lone_pack = bvh.root_leaf().1 > 0 && pack_other.is_empty();
        let small = self.corners.len() <= Geometry::SMALL;
        let tris = if small {
            let tri = |c: &Corners| c.tri(&self.positions);
            self.corners.iter().map(tri).collect()
        } else {
            Vec::new()
        };
        Geometry {
            small,
            lone_pack,
            tris,
            corners: self.corners,
            positions: self.positions,
            normals: self.normals,
            uvs: self.uvs,
            spheres: self.spheres,
            sphere_to_local: self.sphere_to_local,
            disks: self.disks,
            prims,
            packs,
            pack_other,
            bvh,
            sampling: self.sampling,
            areas: self.areas,
        }
    }
}
