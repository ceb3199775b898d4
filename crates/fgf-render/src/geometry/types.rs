//! The geometry's types: hits, the primitives (triangles and
//! parallelograms, spheres, disks) and how a shape is sampled.

use glam::{Affine3A, Vec3A};

/// A surface hit.
#[derive(Debug, Clone, Copy)]
pub struct Hit {
    pub t: f32,
    pub p: Vec3A,
    /// Unit geometric normal, oriented as described in the module docs.
    pub n: Vec3A,
    /// Unit shading normal (interpolated vertex normals, else `n`).
    pub ns: Vec3A,
    pub shape: u32,
    /// The primitive hit and its barycentrics `(u, v)` there (zero for
    /// spheres and disks), from which [`super::Geometry::uv`] computes the
    /// texture coordinates only when a texture asks for them.
    pub(crate) prim: u32,
    pub(crate) bary: [f32; 2],
}

/// A hit found by a query but not yet made into a [`Hit`]: primitive,
/// distance and barycentrics.
#[derive(Debug, Clone, Copy)]
pub struct HitRecord(pub(super) (u32, f32, f32, f32));

/// A triangle `v0 + u e1 + v e2` (`u, v ≥ 0`, `u + v ≤ 1`) or, with
/// `quad`, a parallelogram (`0 ≤ u, v ≤ 1`). `cube` faces and `rectangle`s
/// are parallelograms: one primitive instead of two triangles halves their
/// intersection tests (the reference scenes are made of nothing else).
#[derive(Debug, Clone, Copy)]
pub(super) struct Tri {
    // SIMD vectors for the intersection test.
    pub(super) v0: Vec3A,
    pub(super) e1: Vec3A,
    pub(super) e2: Vec3A,
    /// Oriented unit geometric normal.
    pub(super) n: Vec3A,
    pub(super) shape: u32,
    pub(super) quad: bool,
}

/// A triangle or parallelogram as the geometry keeps it
/// ([`super::Geometry::make_hit`], [`super::Geometry::uv`]), in 16 bytes:
/// the indices of the vertices at `v0`, `v0 + e1`, `v0 + e2` into the
/// geometry's vertex arrays (which it shares with its neighbours), its
/// shape and four flags. Its [`Tri`] is made from them
/// ([`Corners::tri`]) wherever it is needed, and kept only for scenes of
/// few triangles. The 80-byte [`Tri`]s, plus per-triangle copies of the
/// vertex normals and texture coordinates, made some 140 bytes per
/// triangle that every hit read: on a 120,000-triangle mesh about 17 MB,
/// beyond what this kind of machine keeps in its last-level cache; on a
/// 4M-triangle mesh the `Tri`s alone took 320 MB of fresh pages
/// (`docs/benchmarks.md`).
#[derive(Debug, Clone, Copy)]
pub(super) struct Corners {
    pub(super) v: [u32; 3],
    /// The shape (below [`Corners::FLAGS`]) and the flags.
    shape_flags: u32,
}

impl Corners {
    /// The bits of `shape_flags` that hold flags; shapes are fewer.
    pub(super) const FLAGS: u32 = 0b1111 << 28;
    const QUAD: u32 = 1 << 28;
    const NORMALS: u32 = 1 << 29;
    const UVS: u32 = 1 << 30;
    const FLIP: u32 = 1 << 31;

    /// `normals`: the vertices have normals; `uvs`: texture coordinates
    /// (without them, the barycentrics are the texture coordinates, as for
    /// Mitsuba's meshes without any); `flip`: the geometric normal is
    /// `-(e1 × e2)` normalised rather than `e1 × e2`; `quad`: a
    /// parallelogram.
    pub(super) fn new(
        v: [u32; 3],
        shape: u32,
        normals: bool,
        uvs: bool,
        flip: bool,
        quad: bool,
    ) -> Self {
        debug_assert!(shape & Self::FLAGS == 0);
        let flag = |b: bool, f: u32| if b { f } else { 0 };
        Corners {
            v,
            shape_flags: shape
                | flag(normals, Self::NORMALS)
                | flag(uvs, Self::UVS)
                | flag(flip, Self::FLIP)
                | flag(quad, Self::QUAD),
        }
    }
    /// The face's [`Tri`], its corners at `positions` (the geometry's
    /// vertices). Every `Tri` is made by these operations, so a `Tri` made
    /// again has the same bits as one made before. The normal of a
    /// degenerate face (`e1 × e2` zero, which the geometry drops) is NaN.
    #[inline(always)]
    pub(super) fn tri(&self, positions: &[glam::Vec3]) -> Tri {
        let (v0, e1, e2) = self.edges(positions);
        let n = e1.cross(e2).normalize();
        Tri {
            v0,
            e1,
            e2,
            n: if self.flip() { -n } else { n },
            shape: self.shape(),
            quad: self.quad(),
        }
    }
    /// The face's `v0`, `e1` and `e2` (of [`Corners::tri`]).
    #[inline(always)]
    pub(super) fn edges(&self, positions: &[glam::Vec3]) -> (Vec3A, Vec3A, Vec3A) {
        // (The three corners written out: `array::map` is not always inlined.)
        let p = |k: u32| Vec3A::from(positions[k as usize]);
        let v0 = p(self.v[0]);
        (v0, p(self.v[1]) - v0, p(self.v[2]) - v0)
    }
    #[inline(always)]
    pub(super) fn shape(&self) -> u32 {
        self.shape_flags & !Self::FLAGS
    }
    #[inline(always)]
    pub(super) fn has_normals(&self) -> bool {
        self.shape_flags & Self::NORMALS != 0
    }
    #[inline(always)]
    pub(super) fn has_uvs(&self) -> bool {
        self.shape_flags & Self::UVS != 0
    }
    #[inline(always)]
    pub(super) fn flip(&self) -> bool {
        self.shape_flags & Self::FLIP != 0
    }
    #[inline(always)]
    pub(super) fn quad(&self) -> bool {
        self.shape_flags & Self::QUAD != 0
    }
}

impl Tri {
    /// World-space area.
    pub(super) fn area(&self) -> f32 {
        let a = self.e1.cross(self.e2).length();
        if self.quad {
            a
        } else {
            0.5 * a
        }
    }
}

/// A sphere (a `sphere` shape under a similarity `to_world`).
#[derive(Debug, Clone, Copy)]
pub(super) struct Sphere {
    pub(super) center: Vec3A,
    pub(super) radius: f32,
    /// -1 with `flip_normals` (normals point inward), else 1.
    pub(super) sign: f32,
    pub(super) shape: u32,
}

/// A `disk`: the unit disk of its local xy plane.
#[derive(Debug, Clone, Copy)]
pub(super) struct Disk {
    pub(super) to_local: Affine3A,
    pub(super) to_world: Affine3A,
    pub(super) n: Vec3A,
    pub(super) shape: u32,
}

/// What is needed to sample a point uniformly on one shape.
#[derive(Debug, Clone)]
pub(super) enum ShapeSampling {
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
    pub p: Vec3A,
    /// Unit geometric normal.
    pub n: Vec3A,
    /// Unit shading normal (interpolated vertex normals, else `n`), as
    /// [`Hit::ns`].
    pub ns: Vec3A,
}

// Primitive references pack the kind in the top two bits.
pub(super) const KIND_SHIFT: u32 = 30;
pub(super) const KIND_TRI: u32 = 0;
pub(super) const KIND_SPHERE: u32 = 1;
pub(super) const KIND_DISK: u32 = 2;
pub(super) const INDEX_MASK: u32 = (1 << KIND_SHIFT) - 1;
/// Padding entry of `Geometry::prims` (never intersected).
pub(super) const PAD: u32 = u32::MAX;
