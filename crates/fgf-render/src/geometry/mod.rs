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
//! * [`bvh`]: the hierarchy; `pack`: the 4-wide leaf test;
//! * `query`: [`Geometry::intersect`], [`Geometry::intersect2`],
//!   [`Geometry::for_each_hit`]; `sample`: [`Geometry::sample_shape`].

mod build;
pub mod bvh;
mod pack;
mod query;
mod sample;
#[cfg(test)]
mod tests;
mod types;

pub use types::{Hit, HitRecord, PositionSample};

use bvh::Bvh;
use glam::Vec3;
use pack::TriPack;
use types::{Disk, ShapeSampling, Sphere, Tri};

/// All surfaces of a scene and their acceleration structure.
pub struct Geometry {
    tris: Vec<Tri>,
    vertex_normals: Vec<[Vec3; 3]>,
    spheres: Vec<Sphere>,
    disks: Vec<Disk>,
    /// Primitive references in BVH leaf order, each leaf starting at a
    /// multiple of 4 (padded with `types::PAD`).
    prims: Vec<u32>,
    /// `packs[k]` holds the triangles among `prims[4k..4k+4]` for 4-wide tests.
    packs: Vec<TriPack>,
    bvh: Bvh,
    sampling: Vec<ShapeSampling>,
    /// Surface area of each shape, world space.
    pub areas: Vec<f32>,
}
