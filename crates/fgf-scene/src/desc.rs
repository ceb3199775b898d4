//! The plain-data scene description: what the XML loader produces and the
//! renderer consumes. Everything is already resolved: `$name` defaults are
//! substituted, references are indices, file paths are loaded, transforms
//! are composed. Units are those of the loader's tables (see
//! [`crate::xml`]: lengths in scene units, angles in degrees). A
//! description built in code must pass [`SceneDesc::validate`], which the
//! renderer calls before it compiles one.
//!
//! Colours are linear RGB (`[f32; 3]`); a float in the XML becomes a grey RGB.
//! Matrices are `glam::Mat4` (column-major in memory, `M * p` convention);
//! a `to_world` maps the plugin's local space to world space.

use glam::{DVec3, Mat4, Vec3};
use std::sync::Arc;

pub type Rgb = [f32; 3];

/// Index into [`SceneDesc::media`].
pub type MediumId = usize;
/// Index into [`SceneDesc::bsdfs`].
pub type BsdfId = usize;

#[derive(Debug, Clone)]
pub struct SceneDesc {
    /// The scene file this was loaded from (for messages).
    pub source: String,
    pub integrator: IntegratorDesc,
    pub sensor: SensorDesc,
    pub shapes: Vec<ShapeDesc>,
    /// Every BSDF; shapes refer to them by index (shared `<ref>` gives the same index).
    pub bsdfs: Vec<BsdfDesc>,
    /// Emitters that are not attached to a shape: point, spot, directional, constant.
    pub emitters: Vec<EmitterDesc>,
    pub media: Vec<MediumDesc>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IntegratorKind {
    /// Volumetric path tracing (`volpath`, and `volpathmis`, which has the same expectation).
    Volpath,
    /// Path tracing without media (`path`).
    Path,
    /// Mitsuba's `direct`: emission seen directly plus direct illumination
    /// at the first surface, from `emitter_samples` light samples and
    /// `bsdf_samples` BSDF samples combined by the power heuristic; no media.
    Direct {
        emitter_samples: u32,
        bsdf_samples: u32,
    },
}

#[derive(Debug, Clone, PartialEq)]
pub struct IntegratorDesc {
    pub kind: IntegratorKind,
    /// Mitsuba's `max_depth`: -1 is unbounded; 1 = directly visible emission only.
    pub max_depth: i32,
    /// Russian roulette starts at this depth (Mitsuba default 5).
    pub rr_depth: u32,
    /// Mitsuba's `hide_emitters` (default false).
    pub hide_emitters: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FovAxis {
    X,
    Y,
    Smaller,
    Larger,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FilterDesc {
    /// Box of radius 0.5 pixel.
    Box,
    /// Gaussian with `stddev` (Mitsuba default 0.5) and radius 4·stddev.
    Gaussian { stddev: f32 },
    /// Tent of `radius` (Mitsuba default 1).
    Tent { radius: f32 },
}

#[derive(Debug, Clone, PartialEq)]
pub struct SensorDesc {
    /// Camera-to-world; the camera looks down local +z, local +y is up, and
    /// image x grows toward local -x (Mitsuba's `lookat` convention).
    pub to_world: Mat4,
    /// Field of view in degrees, along `fov_axis` (a `focal_length` in the
    /// XML is converted to the x field of view, with `fov_axis = X`).
    pub fov: f32,
    pub fov_axis: FovAxis,
    /// Mitsuba's `principal_point_offset_x/y`: the film position of the
    /// optical axis, as a fraction of the film's width and height (x to the
    /// right, y down), relative to its centre.
    pub principal_point: [f32; 2],
    pub near_clip: f32,
    pub far_clip: f32,
    pub width: u32,
    pub height: u32,
    pub rfilter: FilterDesc,
    /// Samples per pixel (`independent.sample_count`).
    pub spp: u32,
    /// Sampler seed (`independent.seed`, default 0).
    pub seed: u64,
    /// The medium the camera sits in.
    pub medium: Option<MediumId>,
}

#[derive(Debug, Clone)]
pub enum GeometryDesc {
    /// `cube`: `[-1,1]^3` in local space.
    Cube,
    /// `rectangle`: `[-1,1]^2` in local xy, normal +z.
    Rectangle,
    /// `sphere`: `center` and `radius` in local space (then `to_world`),
    /// kept explicit so the renderer can intersect analytically.
    Sphere { center: Vec3, radius: f32 },
    /// `disk`: unit disk in local xy, normal +z.
    Disk,
    /// `obj` / `ply`: a triangle mesh, in local space (apply `to_world`).
    Mesh(Arc<TriangleMesh>),
}

#[derive(Debug, Clone, PartialEq)]
pub struct TriangleMesh {
    pub positions: Vec<Vec3>,
    /// Per-vertex normals: the file's, else smooth normals computed by the
    /// loader as Mitsuba does; `None` with `face_normals=true`.
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex texture coordinates `(u, v)` as Mitsuba 3 stores them
    /// (an OBJ's `vt` with `v` turned into `1 - v`; PLY and `serialized`
    /// as written); `None` if the file has none, and then a triangle's
    /// texture coordinates are its barycentrics, as in Mitsuba.
    pub texcoords: Option<Vec<glam::Vec2>>,
    pub indices: Vec<[u32; 3]>,
}

#[derive(Debug, Clone)]
pub struct ShapeDesc {
    /// `type`, `id` and the file/line for messages.
    pub name: String,
    pub geometry: GeometryDesc,
    pub to_world: Mat4,
    pub flip_normals: bool,
    /// Mitsuba gives a shape with no BSDF a diffuse BSDF of reflectance 0.5,
    /// or 0 if the shape carries an area emitter; the loader makes that
    /// explicit, so this is always set.
    pub bsdf: BsdfId,
    /// An `area` emitter attached to this shape.
    pub emitter: Option<EmitterDesc>,
    pub interior: Option<MediumId>,
    pub exterior: Option<MediumId>,
}

impl ShapeDesc {
    /// World-space bounding box (conservative for disks), in f64. The
    /// loader's default `length` of a k-fBm medium and the ensemble's
    /// realization grid are both taken from it.
    pub fn world_bbox(&self) -> (DVec3, DVec3) {
        let m = self.to_world.as_dmat4();
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        let mut add = |p: DVec3| {
            let q = m.transform_point3(p);
            lo = lo.min(q);
            hi = hi.max(q);
        };
        let corners = |a: DVec3, b: DVec3, add: &mut dyn FnMut(DVec3)| {
            for i in 0..8 {
                add(DVec3::new(
                    if i & 1 == 0 { a.x } else { b.x },
                    if i & 2 == 0 { a.y } else { b.y },
                    if i & 4 == 0 { a.z } else { b.z },
                ));
            }
        };
        match &self.geometry {
            GeometryDesc::Cube => corners(DVec3::splat(-1.0), DVec3::splat(1.0), &mut add),
            GeometryDesc::Rectangle | GeometryDesc::Disk => corners(
                DVec3::new(-1.0, -1.0, 0.0),
                DVec3::new(1.0, 1.0, 0.0),
                &mut add,
            ),
            GeometryDesc::Sphere { center, radius } => {
                let c = center.as_dvec3();
                let r = DVec3::splat(*radius as f64);
                corners(c - r, c + r, &mut add)
            }
            GeometryDesc::Mesh(mesh) => {
                for p in &mesh.positions {
                    add(p.as_dvec3());
                }
            }
        }
        (lo, hi)
    }
}

#[derive(Debug, Clone, PartialEq)]
pub enum BsdfDesc {
    Diffuse {
        reflectance: Rgb,
    },
    /// Index-matched boundary: rays pass straight through.
    Null,
    /// Smooth dielectric (`int_ior`, `ext_ior` as numbers; named materials resolved).
    Dielectric {
        int_ior: f32,
        ext_ior: f32,
        specular_reflectance: Rgb,
        specular_transmittance: Rgb,
    },
    /// Smooth conductor: complex index `eta + i k` per channel (a named
    /// `material` resolved to RGB; Mitsuba's `none` is a perfect mirror,
    /// encoded as `eta = 0, k = 1` with `perfect_mirror = true`).
    Conductor {
        eta: Rgb,
        k: Rgb,
        specular_reflectance: Rgb,
        perfect_mirror: bool,
    },
    /// `twosided`: the nested BSDF on both sides.
    TwoSided(Box<BsdfDesc>),
    /// `mask`: the nested BSDF with probability `opacity` (in [0, 1]; a
    /// texture's mean if textured), else a straight-through (null)
    /// interaction.
    Mask {
        opacity: f32,
        nested: Box<BsdfDesc>,
    },
    /// `principled`: Mitsuba 3's Disney-style principled BSDF.
    Principled(PrincipledDesc),
    /// `thindielectric`: a thin slab with two smooth faces.
    ThinDielectric {
        int_ior: f32,
        ext_ior: f32,
        specular_reflectance: Rgb,
        specular_transmittance: Rgb,
    },
    /// `roughconductor`: as [`BsdfDesc::Conductor`] on a microfacet distribution.
    RoughConductor {
        eta: Rgb,
        k: Rgb,
        specular_reflectance: Rgb,
        perfect_mirror: bool,
        microfacet: MicrofacetDesc,
    },
    /// `roughdielectric`: as [`BsdfDesc::Dielectric`] on a microfacet distribution.
    RoughDielectric {
        int_ior: f32,
        ext_ior: f32,
        specular_reflectance: Rgb,
        specular_transmittance: Rgb,
        microfacet: MicrofacetDesc,
    },
    /// A BSDF some of whose parameters are textures (`xml::textures`):
    /// `base` holds each textured parameter's mean (what Mitsuba's
    /// `plastic` uses for its lobe-sampling weight), and at a surface point
    /// each parameter of `textures` takes the texture's value there.
    /// `base` is never `Textured` or `TwoSided` (a `twosided` BSDF wraps
    /// the `Textured` one).
    Textured {
        base: Box<BsdfDesc>,
        textures: Vec<(TexturedParam, TextureDesc)>,
    },
    /// `plastic` (`microfacet: None`) and `roughplastic` (isotropic
    /// distribution): a diffuse base under a dielectric coating.
    Plastic {
        int_ior: f32,
        ext_ior: f32,
        diffuse_reflectance: Rgb,
        specular_reflectance: Rgb,
        nonlinear: bool,
        microfacet: Option<MicrofacetDesc>,
    },
}

/// The BSDF parameters a texture may give (as in Mitsuba 3.9).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TexturedParam {
    /// `diffuse`'s `reflectance`.
    Reflectance,
    /// `plastic`'s `diffuse_reflectance`.
    DiffuseReflectance,
    SpecularReflectance,
    SpecularTransmittance,
    /// A rough BSDF's `alpha` (Mitsuba's `eval_1`: the mean of a
    /// checkerboard colour's channels, with the colours' roles swapped as
    /// Mitsuba 3.9.1 swaps them; the luminance of a bitmap's value).
    Alpha,
    /// A rough BSDF's `alpha_u` (roughness along the shading frame's
    /// tangent `s`), evaluated as `Alpha`.
    AlphaU,
    /// A rough BSDF's `alpha_v` (along the bitangent `t`).
    AlphaV,
    /// A conductor's `eta` (real part of the index of refraction).
    Eta,
    /// A conductor's `k` (imaginary part).
    K,
    /// `mask`'s `opacity` (Mitsuba's `eval_1`, as [`TexturedParam::Alpha`]).
    Opacity,
    /// `principled`'s `base_color` (a colour) and its scalar parameters
    /// (`eval_1`, as [`TexturedParam::Alpha`]).
    BaseColor,
    Roughness,
    Metallic,
    SpecTrans,
    SpecTint,
    Sheen,
    SheenTint,
    Flatness,
    Clearcoat,
    ClearcoatGloss,
    Anisotropic,
}

/// `principled`'s parameters (textured ones hold their textures' means).
#[derive(Debug, Clone, PartialEq)]
pub struct PrincipledDesc {
    pub base_color: Rgb,
    pub roughness: f32,
    pub metallic: f32,
    pub spec_trans: f32,
    pub spec_tint: f32,
    pub sheen: f32,
    pub sheen_tint: f32,
    pub flatness: f32,
    pub clearcoat: f32,
    pub clearcoat_gloss: f32,
    /// In [0, 1]: the main lobes' roughness along the tangent over that
    /// across it is `1/(1 − 0.9 anisotropic)`.
    pub anisotropic: f32,
    /// Interior over exterior index (from `eta`, or from `specular` by
    /// `η = 2/(1 − √(0.08 specular)) − 1`).
    pub eta: f32,
    pub spec_rate: f32,
    pub clearcoat_rate: f32,
    pub diffuse_rate: f32,
    /// `spec_trans` given (a texture, or a float other than 0).
    pub has_spec_trans: bool,
    /// `clearcoat` given (a texture, or a float other than 0).
    pub has_clearcoat: bool,
}

/// A 2D texture, looked up at a surface point's texture coordinates after
/// `to_uv` (the upper-left 2×2 block and translation of the XML's 4×4
/// `to_uv`, as Mitsuba reads it).
#[derive(Debug, Clone, PartialEq)]
pub enum TextureDesc {
    /// `checkerboard`: `color0` where the fractional parts of `u` and `v`
    /// are both below or both above 1/2, else `color1`.
    Checkerboard {
        color0: Rgb,
        color1: Rgb,
        to_uv: glam::Affine2,
    },
    /// `bitmap`: an image (linear RGB), `v = 0` at its top row.
    Bitmap {
        image: Arc<RgbImage>,
        filter: BitmapFilter,
        wrap: WrapMode,
        to_uv: glam::Affine2,
    },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BitmapFilter {
    Bilinear,
    Nearest,
}

/// What a bitmap or grid lookup does outside `[0, 1)²` / `[0, 1)³`
/// (Mitsuba's `wrap_mode`, with Dr.Jit's texture semantics).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WrapMode {
    Repeat,
    Mirror,
    Clamp,
}

impl WrapMode {
    /// Texel index `i` (any integer) wrapped into `0..n` (`n > 0`):
    /// `repeat` is periodic, `mirror` reflects about each edge (period
    /// `2n`, the edge texel repeated), `clamp` holds the edge texel.
    #[inline]
    pub fn index(self, i: i64, n: i64) -> usize {
        (match self {
            WrapMode::Repeat => i.rem_euclid(n),
            WrapMode::Clamp => i.clamp(0, n - 1),
            WrapMode::Mirror => {
                let j = i.rem_euclid(2 * n);
                if j >= n {
                    2 * n - 1 - j
                } else {
                    j
                }
            }
        }) as usize
    }

    /// Mitsuba's `wrap_mode` string.
    pub fn parse(s: &str) -> Option<WrapMode> {
        match s {
            "repeat" => Some(WrapMode::Repeat),
            "mirror" => Some(WrapMode::Mirror),
            "clamp" => Some(WrapMode::Clamp),
            _ => None,
        }
    }
}

impl TextureDesc {
    /// Mitsuba's `Texture::mean`: the mean of the two colours' channel
    /// means for a checkerboard, the mean luminance of a bitmap's pixels.
    pub fn mean(&self) -> f32 {
        match self {
            TextureDesc::Checkerboard { color0, color1, .. } => {
                let m = |c: &Rgb| (c[0] + c[1] + c[2]) / 3.0;
                0.5 * (m(color0) + m(color1))
            }
            TextureDesc::Bitmap { image, .. } => {
                let n = image.width * image.height;
                let sum: f64 = image
                    .data
                    .chunks_exact(3)
                    .map(|c| luminance(c) as f64)
                    .sum();
                if n == 0 {
                    0.0
                } else {
                    (sum / n as f64) as f32
                }
            }
        }
    }

    /// The smallest and largest channel value the texture can return.
    pub fn range(&self) -> (f32, f32) {
        let vals: Box<dyn Iterator<Item = f32> + '_> = match self {
            TextureDesc::Checkerboard { color0, color1, .. } => {
                Box::new(color0.iter().chain(color1.iter()).copied())
            }
            TextureDesc::Bitmap { image, .. } => Box::new(image.data.iter().copied()),
        };
        vals.fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        })
    }
}

/// The luminance of a linear sRGB colour (Rec. 709 weights, as Mitsuba).
pub fn luminance(c: &[f32]) -> f32 {
    0.212671 * c[0] + 0.715160 * c[1] + 0.072169 * c[2]
}

/// Mitsuba's `distribution` of a rough BSDF.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MicrofacetKind {
    Beckmann,
    Ggx,
}

/// A microfacet distribution: `distribution`, `alpha_u`/`alpha_v` (both
/// `alpha` when isotropic) and `sample_visible`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MicrofacetDesc {
    pub kind: MicrofacetKind,
    pub alpha_u: f32,
    pub alpha_v: f32,
    pub sample_visible: bool,
}

#[derive(Debug, Clone, PartialEq)]
pub enum EmitterDesc {
    /// On a shape; emits toward the side the normal points to. `texture`:
    /// a textured `radiance` (then `radiance` holds its mean).
    Area {
        radiance: Rgb,
        texture: Option<TextureDesc>,
    },
    /// `point`: `position` (or the translation of `to_world`), `intensity` in W/sr.
    Point { position: Vec3, intensity: Rgb },
    /// `spot`: `to_world` (looks down local +z), `intensity`, `cutoff_angle`
    /// and `beam_width` in degrees (Mitsuba defaults 20 and 0.75·cutoff).
    Spot {
        to_world: Mat4,
        intensity: Rgb,
        cutoff_angle: f32,
        beam_width: f32,
    },
    /// `directional`: unit `direction` the light travels along, `irradiance`.
    Directional { direction: Vec3, irradiance: Rgb },
    /// `constant`: environment radiance from every direction.
    Constant { radiance: Rgb },
    /// `envmap`: a latitude–longitude image of the environment radiance
    /// (already multiplied by `scale`); `to_world` rotates it (local +y is
    /// up, the image's top row).
    Envmap {
        image: Arc<RgbImage>,
        to_world: Mat4,
    },
}

/// A linear RGB image, row-major from the top row, 3 floats per pixel.
#[derive(Debug, Clone, PartialEq)]
pub struct RgbImage {
    pub width: usize,
    pub height: usize,
    pub data: Vec<f32>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PhaseDesc {
    Isotropic,
    /// Henyey–Greenstein with mean cosine `g` in (-1, 1).
    Hg {
        g: f32,
    },
}

/// A 3D texture: a constant or a `gridvolume`.
#[derive(Debug, Clone)]
pub enum VolumeDesc {
    Constant(Rgb),
    Grid(GridVolumeDesc),
}

#[derive(Debug, Clone)]
pub struct GridVolumeDesc {
    /// The grid: 1 or 3 channels (1 for a `density`), its values finite and
    /// `>= 0` (`sigma_t`, `density`) or in [0, 1] (`albedo`); `to_world` is
    /// invertible in f32 (see [`SceneDesc::validate`]).
    pub grid: Arc<fgf_io::vol::VolGrid>,
    /// Volume-space to world. Unless `use_grid_bbox`, the grid spans the unit
    /// cube `[0,1]^3` in volume space; with it, the file's bounding box.
    pub to_world: Mat4,
    pub use_grid_bbox: bool,
    pub filter: GridFilter,
    /// Mitsuba's `wrap_mode` (default `clamp`): what a lookup near or
    /// beyond the grid's faces reads.
    pub wrap: WrapMode,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GridFilter {
    Trilinear,
    Nearest,
}

/// Which transport kernel a non-exponential medium uses (`docs/theory.md` §4).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KernelDesc {
    /// Guo 2019 / Jarabo 2018: free flights from p = -dTr/dt, shadow rays use Tr.
    EnergyConserving,
    /// Bitterli 2018: T_ss, T_sm, T_ms, T_mm by segment start/end kind.
    Reciprocal,
}

/// The statistical transmittance model of a non-exponential medium.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TransmittanceDesc {
    /// `fgf` plugin: `hurst`, `sw`, optional `length` (k-fBm only; default:
    /// the diagonal of the bounding box of the shapes bounding this medium).
    /// The loader resolves the default: `length` is `Some` for k-fBm
    /// (`hurst > 0`) and `None` for white and pink noise, as
    /// `fgf_core::transmittance::Fgf::new` requires of every channel's model
    /// (see [`SceneDesc::validate`]).
    Fgf {
        hurst: f64,
        sw: f64,
        length: Option<f64>,
    },
    /// `nonexponential` with `transmittance="exponential"`.
    Exponential,
    /// `nonexponential` with `transmittance="davis"`, parameter `alpha`.
    Davis { alpha: f64 },
    /// `nonexponential` with `transmittance="davis_weinstein"`, `h`, `c`.
    DavisWeinstein { h: f64, c: f64 },
}

#[derive(Debug, Clone)]
pub enum MediumDesc {
    /// `homogeneous`: `sigma_t` already multiplied by `scale`.
    Homogeneous {
        sigma_t: Rgb,
        albedo: Rgb,
        phase: PhaseDesc,
        /// Mitsuba's `sample_emitters`: next-event estimation at scattering
        /// events in this medium (default true); false leaves phase sampling
        /// alone there.
        sample_emitters: bool,
    },
    /// `heterogeneous`: `sigma_t(x) = scale * sigma_t_volume(x)`.
    Heterogeneous {
        sigma_t: VolumeDesc,
        albedo: VolumeDesc,
        scale: f32,
        phase: PhaseDesc,
        /// As for `Homogeneous`.
        sample_emitters: bool,
    },
    /// `fgf` and `nonexponential`: mean extinction `sigma_t` (already scaled),
    /// optional macro-scale `density` grid multiplying it.
    NonExponential {
        sigma_t: Rgb,
        albedo: Rgb,
        phase: PhaseDesc,
        model: TransmittanceDesc,
        kernel: KernelDesc,
        density: Option<GridVolumeDesc>,
    },
}
