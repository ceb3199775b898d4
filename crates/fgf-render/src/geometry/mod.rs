//! Scene geometry in world space (f32, like Mitsuba's `scalar_rgb`):
//! triangles (meshes), parallelograms (`cube` faces, `rectangle`), analytic
//! spheres and disks, one BVH over all of them with three queries (nearest
//! hit, two nearest hits, every hit of a segment), and uniform area sampling
//! of a shape (for area lights).
//!
//! Normal conventions follow Mitsuba 3: a shape's geometric normal `n` is
//! the side an area light emits toward and decides `interior`/`exterior`
//! (a ray leaving along `n` enters the exterior); `flip_normals` negates it.
//! `rectangle` and `disk` transform their local `+z` as a normal (inverse
//! transpose), so a mirroring `to_world` keeps the orientation; meshes and
//! `cube` use the winding of the transformed triangles (faces).
//!
//! * `types`: hits and primitives;
//! * `build`: [`Geometry::build`], validation and compilation of the shapes;
//! * [`bvh`]: the hierarchy; `pack`: the 8-wide leaf test (with the
//!   8-lane vectors of `crate::lanes`);
//! * `query`: [`Geometry::intersect`], [`Geometry::intersect2`],
//!   [`Geometry::for_each_hit`]; `sample`: [`Geometry::sample_shape`];
//!   `uv`: [`Geometry::uv`], a hit's texture coordinates, computed only
//!   when a texture asks for them (untextured scenes never pay for them).
//!
//! Texture coordinates follow Mitsuba 3's parameterisations: a mesh's
//! per-vertex `(u, v)` interpolated by barycentrics (the barycentrics
//! themselves for a mesh without any); `rectangle`: `(x + 1)/2, (y + 1)/2`
//! of the local point; `disk`: `(r, φ/2π)`; `sphere`: `(φ/2π, θ/π)` of the
//! local direction (φ in [0, 2π) from +x toward +y, θ from +z); `cube`: an
//! affine map per face, the one Mitsuba's cube mesh interpolates.

mod build;
pub mod bvh;
mod frame;
mod pack;
mod query;
mod sample;
#[cfg(test)]
pub(crate) mod tests;
mod types;
mod uv;

pub use types::{Hit, HitRecord, PositionSample};

use bvh::Bvh;
use glam::{Mat3, Vec2, Vec3, Vec3A};
use pack::TriPack;
use types::{Corners, Disk, ShapeSampling, Sphere, Tri};

/// All surfaces of a scene and their acceleration structure.
pub struct Geometry {
    /// The triangles and parallelograms: their vertices and flags.
    corners: Vec<Corners>,
    /// Their [`Tri`]s (same indices), for a scene of few triangles; empty
    /// for one of many ([`Geometry::tri`]).
    tris: Vec<Tri>,
    /// Few triangles ([`Geometry::SMALL`] or fewer): `tris` holds their
    /// records, which then stay in cache, and queries read them rather
    /// than compute from the corners what they hold (some 40 instructions
    /// per hit).
    small: bool,
    /// The whole scene is one pack of triangles and parallelograms (the
    /// root is a leaf, without spheres or disks): queries test it alone.
    lone_pack: bool,
    /// The vertices of all meshes, world space (12-byte `Vec3`s), and
    /// where a mesh has them, their normals and texture coordinates (same
    /// indices; zero for the vertices of meshes without, and empty while
    /// no mesh has any).
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Vec<Vec2>,
    spheres: Vec<Sphere>,
    /// Each sphere's world-to-local linear map (about its centre), for its
    /// texture coordinates.
    sphere_to_local: Vec<Mat3>,
    disks: Vec<Disk>,
    /// Primitive references in BVH leaf order, each leaf starting at a
    /// multiple of `bvh::PACK` (padded with `types::PAD`).
    prims: Vec<u32>,
    /// `packs[k]` holds the triangles among `prims[8k..8k+8]` for 8-wide tests.
    packs: Vec<TriPack>,
    /// `pack_other[k]`: the lanes of `packs[k]` that hold spheres or
    /// disks (empty if no pack has any).
    pack_other: Vec<u8>,
    bvh: Bvh,
    sampling: Vec<ShapeSampling>,
    /// Surface area of each shape, world space.
    pub areas: Vec<f32>,
}

impl Geometry {
    /// The most triangles for which hits read the `Tri` records (256 KiB
    /// of them, a quarter of a 1 MiB L2).
    const SMALL: usize = 256 * 1024 / std::mem::size_of::<Tri>();

    /// Triangle `i`'s [`Tri`]: its record in a scene of few triangles,
    /// else made from its corners, with the same bits ([`Corners::tri`]).
    #[inline(always)]
    fn tri(&self, i: usize) -> Tri {
        if self.small {
            self.tris[i]
        } else {
            self.corners[i].tri(&self.positions)
        }
    }

    // (The three corners written out: `array::map` is not always inlined.)

    /// The normals at a triangle's corners, if its mesh has them.
    #[inline(always)]
    fn corner_normals(&self, c: &Corners) -> Option<[Vec3A; 3]> {
        let n = |k: u32| Vec3A::from(self.normals[k as usize]);
        c.has_normals().then(|| [n(c.v[0]), n(c.v[1]), n(c.v[2])])
    }

    /// The shading normal at barycentrics `[u, v]` of a triangle: its
    /// vertex normals interpolated and normalised, else (no normals, or
    /// they cancel) its geometric normal `n`.
    #[inline(always)]
    fn shading_normal(&self, c: &Corners, [u, v]: [f32; 2], n: Vec3A) -> Vec3A {
        match self.corner_normals(c) {
            Some(vn) => ((1.0 - u - v) * vn[0] + u * vn[1] + v * vn[2])
                .try_normalize()
                .unwrap_or(n),
            None => n,
        }
    }

    /// The texture coordinates at a triangle's corners, if its mesh has
    /// them.
    #[inline(always)]
    fn corner_uvs(&self, c: &Corners) -> Option<[Vec2; 3]> {
        let uv = |k: u32| self.uvs[k as usize];
        c.has_uvs().then(|| [uv(c.v[0]), uv(c.v[1]), uv(c.v[2])])
    }
}
