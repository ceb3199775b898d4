//! [`SceneDesc::validate`]: the rules every scene description obeys.
//!
//! A description is valid when every index refers to an existing BSDF or
//! medium, every number lies in its range, every matrix the renderer
//! inverts is invertible in f32, every grid and mesh is consistent, and the
//! transmittance model of each non-exponential medium is accepted by the
//! `fgf_core::transmittance` constructor for every colour channel. That
//! last rule is fgf-core's own, so the mean extinction of a non-exponential
//! medium must be finite and `> 0` in every channel (a zero channel is
//! refused, not made transparent), whichever model it uses.
//!
//! The XML loader calls [`SceneDesc::validate`] on the description it
//! produced, and `fgf_render`'s `World::build` calls it on the one it is
//! given, so a scene built in code meets the same rules as a loaded one.
//! The loader also checks each parameter where it reads it, with the same
//! ranges, so that the message points at the parameter's own line and
//! shows the value as written (before `scale`, before rounding to f32);
//! what only this module checks (the models, references between objects,
//! the integrator against the media) it reports at the line of the plugin,
//! or of the parameter when the rule is about one.

use crate::desc::*;
use crate::error::{SceneError, SceneErrorKind};
use fgf_core::transmittance::{Davis, DavisWeinstein, Exponential, Fgf};
use glam::{DMat4, DVec4, Mat4};
use std::fmt::Display;

/// The valid values of one parameter: a predicate and its description in
/// messages. Every predicate refuses NaN and infinities.
#[derive(Clone, Copy)]
pub(crate) struct Range<T> {
    pub ok: fn(T) -> bool,
    pub text: &'static str,
}

pub(crate) const UNIT: Range<f64> = Range {
    ok: |v| (0.0..=1.0).contains(&v),
    text: "in [0, 1]",
};
pub(crate) const NON_NEGATIVE: Range<f64> = Range {
    ok: |v| v.is_finite() && v >= 0.0,
    text: ">= 0",
};
pub(crate) const POSITIVE: Range<f64> = Range {
    ok: |v| v.is_finite() && v > 0.0,
    text: "> 0",
};
pub(crate) const MAX_DEPTH: Range<i64> = Range {
    ok: |v| v == -1 || (0..=i32::MAX as i64).contains(&v),
    text: "-1 (unbounded) or 0 <= max_depth <= 2^31-1",
};
pub(crate) const RR_DEPTH: Range<i64> = Range {
    ok: |v| (1..=u32::MAX as i64).contains(&v),
    text: "1 <= rr_depth <= 2^32-1",
};
pub(crate) const SAMPLE_COUNT: Range<i64> = Range {
    ok: |v| (1..=u32::MAX as i64).contains(&v),
    text: "1 <= sample_count <= 2^32-1",
};
/// Largest film side (pixels).
pub(crate) const MAX_FILM_SIDE: i64 = 65_536;
pub(crate) const FILM_SIDE: Range<i64> = Range {
    ok: |v| (1..=MAX_FILM_SIDE).contains(&v),
    text: "1 <= value <= 65536",
};
/// Largest film area: 2^26 pixels = 64 Mpixel. The renderer keeps float32
/// RGB plus variance per pixel (about 24 bytes), so this bounds the frame
/// buffers to about 1.6 GB; a typo like width="1e9" is refused, not an OOM.
pub(crate) const MAX_FILM_PIXELS: i64 = 1 << 26;
pub(crate) const FOV: Range<f64> = Range {
    ok: |v| v > 0.0 && v < 180.0,
    text: "0 < fov < 180 degrees",
};
pub(crate) const NEAR_CLIP: Range<f64> = Range {
    ok: |v| v.is_finite() && v > 0.0,
    text: "near_clip > 0",
};
/// `far_clip > near_clip` (a range that depends on another parameter).
pub(crate) const FAR_CLIP: &str = "far_clip > near_clip";
pub(crate) const GAUSSIAN_STDDEV: Range<f64> = Range {
    ok: |v| v > 0.0 && v <= 64.0,
    text: "0 < stddev <= 64 pixels",
};
pub(crate) const TENT_RADIUS: Range<f64> = Range {
    ok: |v| v > 0.0 && v <= 256.0,
    text: "0 < radius <= 256 pixels",
};
pub(crate) const SPHERE_RADIUS: Range<f64> = Range {
    ok: |v| v.is_finite() && v > 0.0,
    text: "radius > 0",
};
pub(crate) const IOR: Range<f64> = Range {
    ok: |v| v.is_finite() && v > 0.0,
    text: "a number > 0",
};
/// Microfacet roughness: below 1e-4 the lobes are too narrow for f32
/// sampling (use the smooth plugin).
pub(crate) const ALPHA: Range<f64> = Range {
    ok: |v| v.is_finite() && (1e-4..=4.0).contains(&v),
    text: "1e-4 <= alpha <= 4",
};
pub(crate) const CUTOFF_ANGLE: Range<f64> = Range {
    ok: |v| v > 0.0 && v < 180.0,
    text: "0 < cutoff_angle < 180 degrees",
};
/// `0 <= beam_width <= cutoff_angle` (depends on another parameter).
pub(crate) const BEAM_WIDTH: &str = "0 <= beam_width <= cutoff_angle degrees";
pub(crate) const HG_G: Range<f64> = Range {
    ok: |g| g > -1.0 && g < 1.0,
    text: "-1 < g < 1",
};
pub(crate) const SCALE: Range<f64> = Range {
    ok: |v| v.is_finite() && v >= 0.0,
    text: "scale >= 0",
};

/// `invalid name = v (valid: range)`, the message of a value out of range.
pub(crate) fn out_of_range(name: &str, v: impl Display, range: &str) -> String {
    format!("invalid {name} = {v} (valid: {range})")
}

/// [`out_of_range`] for a colour, every channel checked.
pub(crate) fn out_of_range_rgb<T: Display>(name: &str, c: &[T; 3], range: &str) -> String {
    format!(
        "invalid {name} = ({}, {}, {}) (valid: each channel {range})",
        c[0], c[1], c[2]
    )
}

/// A rigid transform (rotation and translation): unit, orthogonal axes to
/// 1e-3, which a matrix written with 6 digits meets.
pub(crate) fn is_rigid(m: &DMat4) -> bool {
    let cols = [
        m.x_axis.truncate(),
        m.y_axis.truncate(),
        m.z_axis.truncate(),
    ];
    cols.iter().all(|c| (c.length() - 1.0).abs() < 1e-3)
        && cols[0].dot(cols[1]).abs() < 1e-3
        && cols[0].dot(cols[2]).abs() < 1e-3
        && cols[1].dot(cols[2]).abs() < 1e-3
        && m.row(3) == DVec4::new(0.0, 0.0, 0.0, 1.0)
}
pub(crate) const NOT_RIGID: &str =
    "a sensor's to_world must be a rigid transform (rotation and translation, no scale or shear)";

/// A similarity (a scaled rotation plus a translation): `MᵀM = s² I` to
/// 1e-4 relative (6-digit matrices pass), so that a sphere stays round.
pub(crate) fn is_similarity(m: &DMat4) -> bool {
    let cols = [
        m.x_axis.truncate(),
        m.y_axis.truncate(),
        m.z_axis.truncate(),
    ];
    let s2 = cols[0].length_squared();
    let tol = 1e-4 * s2;
    (cols[1].length_squared() - s2).abs() <= tol
        && (cols[2].length_squared() - s2).abs() <= tol
        && cols[0].dot(cols[1]).abs() <= tol
        && cols[0].dot(cols[2]).abs() <= tol
        && cols[1].dot(cols[2]).abs() <= tol
}
pub(crate) const NOT_SIMILARITY: &str = "a sphere's to_world must not contain non-uniform scale or shear (use the 'radius' parameter, or a mesh for an ellipsoid)";

/// Invertible in single precision: the renderer maps rays to local space
/// with the inverse.
pub(crate) fn is_invertible(m: &Mat4) -> bool {
    m.is_finite() && m.determinant() != 0.0 && m.inverse().is_finite()
}

/// The message of a matrix that [`is_invertible`] refuses.
pub(crate) fn singular(det: f64) -> String {
    format!(
        "to_world is singular or nearly so (determinant {det:e}); the renderer needs its inverse: give every axis a nonzero scale (a flat rectangle or disk keeps z scale 1)"
    )
}

/// What is wrong with a triangle mesh.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum MeshProblem {
    NoFaces,
    Position(usize),
    Index([u32; 3], usize),
    NormalCount(usize, usize),
    Normal(usize),
    TexcoordCount(usize, usize),
    Texcoord(usize),
}

impl Display for MeshProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            MeshProblem::NoFaces => write!(f, "the mesh has no faces"),
            MeshProblem::Position(i) => write!(f, "vertex #{i} position is not finite"),
            MeshProblem::Index(t, n) => write!(
                f,
                "face index {t:?} is out of range (the mesh has {n} vertices)"
            ),
            MeshProblem::NormalCount(n, v) => {
                write!(f, "the mesh has {n} vertex normals for {v} vertices")
            }
            MeshProblem::Normal(i) => write!(f, "vertex normal #{i} is zero or not finite"),
            MeshProblem::TexcoordCount(n, v) => {
                write!(f, "the mesh has {n} texture coordinates for {v} vertices")
            }
            MeshProblem::Texcoord(i) => write!(f, "texture coordinate #{i} is not finite"),
        }
    }
}

/// The first problem of `m`, in the order faces, positions, indices, normals.
pub(crate) fn mesh_problem(m: &TriangleMesh) -> Option<MeshProblem> {
    if m.indices.is_empty() {
        return Some(MeshProblem::NoFaces);
    }
    if let Some(i) = m.positions.iter().position(|p| !p.is_finite()) {
        return Some(MeshProblem::Position(i));
    }
    let n = m.positions.len();
    if let Some(t) = m
        .indices
        .iter()
        .find(|t| t.iter().any(|&i| i as usize >= n))
    {
        return Some(MeshProblem::Index(*t, n));
    }
    let normals = m.normals.as_deref().unwrap_or_default();
    if m.normals.is_some() && normals.len() != n {
        return Some(MeshProblem::NormalCount(normals.len(), n));
    }
    let uvs = m.texcoords.as_deref().unwrap_or_default();
    if m.texcoords.is_some() && uvs.len() != n {
        return Some(MeshProblem::TexcoordCount(uvs.len(), n));
    }
    if let Some(i) = uvs.iter().position(|t| !t.is_finite()) {
        return Some(MeshProblem::Texcoord(i));
    }
    normals
        .iter()
        .position(|v| {
            let len = v.length();
            !(len.is_finite() && len > 0.0)
        })
        .map(MeshProblem::Normal)
}

/// The object of a description that a rule is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Subject {
    Integrator,
    Sensor,
    /// A shape (its area emitter included), by index.
    Shape(usize),
    Bsdf(usize),
    /// A shape-less emitter, by index into [`SceneDesc::emitters`].
    Emitter(usize),
    Medium(usize),
}

/// A broken rule: what it is about, the parameter (as the XML names it)
/// when it is about one, and the message.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Invalid {
    pub subject: Subject,
    pub param: Option<String>,
    pub message: String,
}

/// The result of one object's rules: the message and its parameter.
type Check = Result<(), (Option<String>, String)>;

fn range<T: Copy + Display>(name: &str, v: T, r: Range<T>) -> Check {
    if (r.ok)(v) {
        Ok(())
    } else {
        Err((Some(name.into()), out_of_range(name, v, r.text)))
    }
}

fn range_rgb(name: &str, c: &Rgb, r: Range<f64>) -> Check {
    if c.iter().all(|&v| (r.ok)(v as f64)) {
        Ok(())
    } else {
        Err((Some(name.into()), out_of_range_rgb(name, c, r.text)))
    }
}

fn fail(param: Option<&str>, message: impl Into<String>) -> Check {
    Err((param.map(str::to_string), message.into()))
}

fn invertible(m: &Mat4) -> Check {
    if is_invertible(m) {
        Ok(())
    } else {
        fail(Some("to_world"), singular(m.determinant() as f64))
    }
}

fn medium_index(what: &str, m: Option<MediumId>, media: usize) -> Check {
    match m {
        Some(i) if i >= media => fail(
            None,
            format!("{what} refers to medium {i}, but the scene has {media}"),
        ),
        _ => Ok(()),
    }
}

impl SceneDesc {
    /// Check every rule of the module docs; the error names the object
    /// (`medium 1: ...`, `shape 0 (...): ...`) and, for a loaded scene, the
    /// scene file.
    pub fn validate(&self) -> Result<(), SceneError> {
        self.check(&|s| self.label(s)).map_err(|e| {
            SceneError::new(
                SceneErrorKind::Invalid,
                &self.source,
                format!("{}: {}", self.label(e.subject), e.message),
            )
        })
    }

    /// How [`Self::validate`] names an object.
    fn label(&self, s: Subject) -> String {
        match s {
            Subject::Integrator => "the integrator".into(),
            Subject::Sensor => "the sensor".into(),
            Subject::Shape(i) => format!("shape {i} ({})", self.shapes[i].name),
            Subject::Bsdf(i) => format!("bsdf {i}"),
            Subject::Emitter(i) => format!("emitter {i}"),
            Subject::Medium(i) => format!("medium {i}"),
        }
    }

    /// The rules, in the order integrator, sensor, shapes, BSDFs, emitters,
    /// media; `name` names the objects a message refers to (the loader
    /// names them by file and line).
    pub(crate) fn check(&self, name: &dyn Fn(Subject) -> String) -> Result<(), Invalid> {
        let at = |subject: Subject| {
            move |(param, message): (Option<String>, String)| Invalid {
                subject,
                param,
                message,
            }
        };
        self.check_integrator(name)
            .map_err(at(Subject::Integrator))?;
        self.check_sensor().map_err(at(Subject::Sensor))?;
        for (i, s) in self.shapes.iter().enumerate() {
            self.check_shape(s).map_err(at(Subject::Shape(i)))?;
        }
        for (i, b) in self.bsdfs.iter().enumerate() {
            check_bsdf(b).map_err(at(Subject::Bsdf(i)))?;
        }
        let mut environment = None;
        for (i, e) in self.emitters.iter().enumerate() {
            check_emitter(e).map_err(at(Subject::Emitter(i)))?;
            if let EmitterDesc::Constant { .. } | EmitterDesc::Envmap { .. } = e {
                if let Some(first) = environment {
                    return Err(at(Subject::Emitter(i))((
                        None,
                        format!(
                            "more than one constant environment emitter or envmap (the first: {})",
                            name(Subject::Emitter(first))
                        ),
                    )));
                }
                environment = Some(i);
            }
        }
        for (i, m) in self.media.iter().enumerate() {
            check_medium(m).map_err(at(Subject::Medium(i)))?;
        }
        Ok(())
    }

    fn check_integrator(&self, name: &dyn Fn(Subject) -> String) -> Check {
        let d = &self.integrator;
        range("max_depth", d.max_depth as i64, MAX_DEPTH)?;
        range("rr_depth", d.rr_depth as i64, RR_DEPTH)?;
        if d.kind != IntegratorKind::Volpath && !self.media.is_empty() {
            let ty = if d.kind == IntegratorKind::Path {
                "path"
            } else {
                "direct"
            };
            return fail(
                None,
                format!(
                    "the '{ty}' integrator ignores participating media, but this scene has {} (the first: {}); use <integrator type=\"volpath\">",
                    self.media.len(),
                    name(Subject::Medium(0))
                ),
            );
        }
        Ok(())
    }

    fn check_sensor(&self) -> Check {
        let s = &self.sensor;
        range("fov", s.fov as f64, FOV)?;
        range("near_clip", s.near_clip as f64, NEAR_CLIP)?;
        let far_beyond_near = s.far_clip > s.near_clip; // false for NaN too
        if !far_beyond_near {
            return fail(
                Some("far_clip"),
                out_of_range("far_clip", s.far_clip, FAR_CLIP),
            );
        }
        if !is_rigid(&s.to_world.as_dmat4()) {
            return fail(Some("to_world"), NOT_RIGID);
        }
        let (w, h) = (s.width as i64, s.height as i64);
        range("width", w, FILM_SIDE)?;
        range("height", h, FILM_SIDE)?;
        if w * h > MAX_FILM_PIXELS {
            return fail(None, film_too_large(w, h));
        }
        range("sample_count", s.spp as i64, SAMPLE_COUNT)?;
        match s.rfilter {
            FilterDesc::Box => {}
            FilterDesc::Gaussian { stddev } => range("stddev", stddev as f64, GAUSSIAN_STDDEV)?,
            FilterDesc::Tent { radius } => range("radius", radius as f64, TENT_RADIUS)?,
        }
        medium_index("the sensor", s.medium, self.media.len())
    }

    fn check_shape(&self, s: &ShapeDesc) -> Check {
        invertible(&s.to_world)?;
        match &s.geometry {
            GeometryDesc::Cube | GeometryDesc::Rectangle | GeometryDesc::Disk => {}
            GeometryDesc::Sphere { center, radius } => {
                if !is_similarity(&s.to_world.as_dmat4()) {
                    return fail(Some("to_world"), NOT_SIMILARITY);
                }
                if !center.is_finite() {
                    return fail(Some("center"), "the sphere's center is not finite");
                }
                range("radius", *radius as f64, SPHERE_RADIUS)?;
            }
            GeometryDesc::Mesh(m) => {
                if let Some(p) = mesh_problem(m) {
                    return fail(None, format!("invalid mesh: {p}"));
                }
            }
        }
        if s.bsdf >= self.bsdfs.len() {
            return fail(
                None,
                format!(
                    "refers to BSDF {}, but the scene has {}",
                    s.bsdf,
                    self.bsdfs.len()
                ),
            );
        }
        medium_index("the interior", s.interior, self.media.len())?;
        medium_index("the exterior", s.exterior, self.media.len())?;
        match &s.emitter {
            None => Ok(()),
            Some(EmitterDesc::Area { radiance, texture }) => {
                range_rgb("radiance", radiance, NON_NEGATIVE)?;
                match texture {
                    None => Ok(()),
                    Some(t) => check_emission_texture(t),
                }
            }
            Some(_) => fail(
                None,
                "a shape's emitter must be an area emitter (the others are not attached to shapes)",
            ),
        }
    }
}

/// The message of a film larger than [`MAX_FILM_PIXELS`].
pub(crate) fn film_too_large(w: i64, h: i64) -> String {
    format!(
        "film of {w}x{h} = {} pixels is larger than the limit of {MAX_FILM_PIXELS} pixels",
        w * h
    )
}

/// The message of a `twosided` BSDF around a `mask`.
pub(crate) const TWOSIDED_MASK: &str =
    "twosided cannot hold a mask (it transmits; Mitsuba refuses it too): put the twosided BSDF inside the mask";

fn check_bsdf(b: &BsdfDesc) -> Check {
    match b {
        BsdfDesc::Diffuse { reflectance } => range_rgb("reflectance", reflectance, UNIT),
        BsdfDesc::Null => Ok(()),
        BsdfDesc::Dielectric {
            int_ior,
            ext_ior,
            specular_reflectance,
            specular_transmittance,
        } => {
            range("int_ior", *int_ior as f64, IOR)?;
            range("ext_ior", *ext_ior as f64, IOR)?;
            range_rgb("specular_reflectance", specular_reflectance, UNIT)?;
            range_rgb("specular_transmittance", specular_transmittance, UNIT)
        }
        BsdfDesc::Conductor {
            eta,
            k,
            specular_reflectance,
            ..
        } => {
            range_rgb("eta", eta, NON_NEGATIVE)?;
            range_rgb("k", k, NON_NEGATIVE)?;
            range_rgb("specular_reflectance", specular_reflectance, UNIT)
        }
        BsdfDesc::TwoSided(inner) => {
            let mask = match &**inner {
                BsdfDesc::Mask { .. } => true,
                BsdfDesc::Textured { base, .. } => matches!(**base, BsdfDesc::Mask { .. }),
                _ => false,
            };
            if matches!(**inner, BsdfDesc::TwoSided(_)) {
                fail(None, "twosided BSDFs cannot be nested")
            } else if mask {
                fail(None, TWOSIDED_MASK)
            } else if matches!(&**inner, BsdfDesc::Principled(d) if d.has_spec_trans)
                || matches!(&**inner, BsdfDesc::Textured { base, .. } if matches!(&**base, BsdfDesc::Principled(d) if d.has_spec_trans))
            {
                fail(
                    None,
                    "twosided cannot hold a principled BSDF with spec_trans (it transmits; Mitsuba refuses it too)",
                )
            } else {
                check_bsdf(inner)
            }
        }
        BsdfDesc::Principled(d) => {
            range_rgb("base_color", &d.base_color, UNIT)?;
            for (name, v) in [
                ("roughness", d.roughness),
                ("metallic", d.metallic),
                ("spec_trans", d.spec_trans),
                ("spec_tint", d.spec_tint),
                ("sheen", d.sheen),
                ("sheen_tint", d.sheen_tint),
                ("flatness", d.flatness),
                ("clearcoat", d.clearcoat),
                ("clearcoat_gloss", d.clearcoat_gloss),
            ] {
                range(name, v as f64, UNIT)?;
            }
            range("eta", d.eta as f64, IOR)?;
            range("main_specular_sampling_rate", d.spec_rate as f64, POSITIVE)?;
            range(
                "clearcoat_sampling_rate",
                d.clearcoat_rate as f64,
                NON_NEGATIVE,
            )?;
            range(
                "diffuse_reflectance_sampling_rate",
                d.diffuse_rate as f64,
                NON_NEGATIVE,
            )
        }
        BsdfDesc::Mask { opacity, nested } => {
            range("opacity", *opacity as f64, UNIT)?;
            check_bsdf(nested)
        }
        BsdfDesc::Textured { base, textures } => {
            check_bsdf(base)?;
            for (param, t) in textures {
                check_texture(base, *param, t)?;
            }
            Ok(())
        }
        BsdfDesc::ThinDielectric {
            int_ior,
            ext_ior,
            specular_reflectance,
            specular_transmittance,
        }
        | BsdfDesc::RoughDielectric {
            int_ior,
            ext_ior,
            specular_reflectance,
            specular_transmittance,
            ..
        } => {
            range("int_ior", *int_ior as f64, IOR)?;
            range("ext_ior", *ext_ior as f64, IOR)?;
            range_rgb("specular_reflectance", specular_reflectance, UNIT)?;
            range_rgb("specular_transmittance", specular_transmittance, UNIT)?;
            if let BsdfDesc::RoughDielectric { microfacet, .. } = b {
                check_microfacet(microfacet)?;
            }
            Ok(())
        }
        BsdfDesc::RoughConductor {
            eta,
            k,
            specular_reflectance,
            microfacet,
            ..
        } => {
            range_rgb("eta", eta, NON_NEGATIVE)?;
            range_rgb("k", k, NON_NEGATIVE)?;
            range_rgb("specular_reflectance", specular_reflectance, UNIT)?;
            check_microfacet(microfacet)
        }
        BsdfDesc::Plastic {
            int_ior,
            ext_ior,
            diffuse_reflectance,
            specular_reflectance,
            microfacet,
            ..
        } => {
            range("int_ior", *int_ior as f64, IOR)?;
            range("ext_ior", *ext_ior as f64, IOR)?;
            if int_ior == ext_ior {
                return fail(None, "int_ior and ext_ior must differ");
            }
            range_rgb("diffuse_reflectance", diffuse_reflectance, UNIT)?;
            range_rgb("specular_reflectance", specular_reflectance, UNIT)?;
            if let Some(m) = microfacet {
                check_microfacet(m)?;
                if m.alpha_u != m.alpha_v {
                    return fail(
                        None,
                        "roughplastic needs an isotropic roughness (alpha_u = alpha_v)",
                    );
                }
            }
            Ok(())
        }
    }
}

/// Roughness in the range of [`ALPHA`].
/// The name of a textured parameter, if `base` has it.
pub(crate) fn textured_param_name(base: &BsdfDesc, p: TexturedParam) -> Option<&'static str> {
    use TexturedParam as P;
    Some(match (base, p) {
        (BsdfDesc::Diffuse { .. }, P::Reflectance) => "reflectance",
        (BsdfDesc::Plastic { .. }, P::DiffuseReflectance) => "diffuse_reflectance",
        (
            BsdfDesc::Dielectric { .. }
            | BsdfDesc::ThinDielectric { .. }
            | BsdfDesc::RoughDielectric { .. }
            | BsdfDesc::Conductor { .. }
            | BsdfDesc::RoughConductor { .. }
            | BsdfDesc::Plastic { .. },
            P::SpecularReflectance,
        ) => "specular_reflectance",
        (
            BsdfDesc::Dielectric { .. }
            | BsdfDesc::ThinDielectric { .. }
            | BsdfDesc::RoughDielectric { .. },
            P::SpecularTransmittance,
        ) => "specular_transmittance",
        (BsdfDesc::RoughConductor { .. } | BsdfDesc::RoughDielectric { .. }, P::Alpha) => "alpha",
        (BsdfDesc::RoughConductor { .. } | BsdfDesc::RoughDielectric { .. }, P::AlphaU) => {
            "alpha_u"
        }
        (BsdfDesc::RoughConductor { .. } | BsdfDesc::RoughDielectric { .. }, P::AlphaV) => {
            "alpha_v"
        }
        (BsdfDesc::Conductor { .. } | BsdfDesc::RoughConductor { .. }, P::Eta) => "eta",
        (BsdfDesc::Conductor { .. } | BsdfDesc::RoughConductor { .. }, P::K) => "k",
        (BsdfDesc::Mask { .. }, P::Opacity) => "opacity",
        (BsdfDesc::Principled(_), P::BaseColor) => "base_color",
        (BsdfDesc::Principled(_), P::Roughness) => "roughness",
        (BsdfDesc::Principled(_), P::Metallic) => "metallic",
        (BsdfDesc::Principled(_), P::SpecTrans) => "spec_trans",
        (BsdfDesc::Principled(_), P::SpecTint) => "spec_tint",
        (BsdfDesc::Principled(_), P::Sheen) => "sheen",
        (BsdfDesc::Principled(_), P::SheenTint) => "sheen_tint",
        (BsdfDesc::Principled(_), P::Flatness) => "flatness",
        (BsdfDesc::Principled(_), P::Clearcoat) => "clearcoat",
        (BsdfDesc::Principled(_), P::ClearcoatGloss) => "clearcoat_gloss",
        (BsdfDesc::Principled(_), P::Anisotropic) => "anisotropic",
        _ => return None,
    })
}

/// A texture as parameter `param` of `base`: a parameter `base` has, a
/// finite `to_uv`, an image whose size matches its data, and values in the
/// parameter's range.
fn check_texture(base: &BsdfDesc, param: TexturedParam, t: &TextureDesc) -> Check {
    let Some(name) = textured_param_name(base, param) else {
        return fail(
            None,
            format!("this BSDF has no textured parameter {param:?}"),
        );
    };
    let r = match param {
        TexturedParam::Alpha | TexturedParam::AlphaU | TexturedParam::AlphaV => ALPHA,
        TexturedParam::Eta | TexturedParam::K => NON_NEGATIVE,
        _ => UNIT,
    };
    check_texture_values(name, t, r)
}

/// A textured area-emitter `radiance`: a finite `to_uv`, an image whose
/// size matches its data, values ≥ 0.
fn check_emission_texture(t: &TextureDesc) -> Check {
    check_texture_values("radiance", t, NON_NEGATIVE)
}

/// Texture `t` as parameter `name`: a finite `to_uv`, an image whose size
/// matches its data, and values in range `r`.
fn check_texture_values(name: &str, t: &TextureDesc, r: Range<f64>) -> Check {
    let to_uv = match t {
        TextureDesc::Checkerboard { to_uv, .. } => to_uv,
        TextureDesc::Bitmap { image, to_uv, .. } => {
            if image.width == 0
                || image.height == 0
                || image.data.len() != 3 * image.width * image.height
            {
                return fail(
                    Some(name),
                    "the texture's image is empty or its size does not match its data",
                );
            }
            to_uv
        }
    };
    if !to_uv.is_finite() {
        return fail(Some(name), "the texture's to_uv has non-finite entries");
    }
    let (lo, hi) = t.range();
    for v in [lo, hi] {
        if !(r.ok)(v as f64) {
            return fail(
                Some(name),
                format!(
                    "the texture for '{name}' has a value {v}, outside the parameter's range ({})",
                    r.text
                ),
            );
        }
    }
    Ok(())
}

fn check_microfacet(m: &MicrofacetDesc) -> Check {
    range("alpha_u", m.alpha_u as f64, ALPHA)?;
    range("alpha_v", m.alpha_v as f64, ALPHA)
}

fn check_emitter(e: &EmitterDesc) -> Check {
    match e {
        EmitterDesc::Area { .. } => fail(None, "an area emitter must be attached to a shape"),
        EmitterDesc::Point {
            position,
            intensity,
        } => {
            if !position.is_finite() {
                return fail(Some("position"), "the light's position is not finite");
            }
            range_rgb("intensity", intensity, NON_NEGATIVE)
        }
        EmitterDesc::Spot {
            to_world,
            intensity,
            cutoff_angle,
            beam_width,
        } => {
            invertible(to_world)?;
            range_rgb("intensity", intensity, NON_NEGATIVE)?;
            range("cutoff_angle", *cutoff_angle as f64, CUTOFF_ANGLE)?;
            if !(*beam_width >= 0.0 && beam_width <= cutoff_angle) {
                return fail(
                    Some("beam_width"),
                    out_of_range("beam_width", beam_width, BEAM_WIDTH),
                );
            }
            Ok(())
        }
        EmitterDesc::Directional {
            direction,
            irradiance,
        } => {
            let len = direction.length();
            if !(len.is_finite() && len > 0.0) {
                return fail(Some("direction"), "the light direction is zero");
            }
            range_rgb("irradiance", irradiance, NON_NEGATIVE)
        }
        EmitterDesc::Constant { radiance } => range_rgb("radiance", radiance, NON_NEGATIVE),
        EmitterDesc::Envmap { image, to_world } => {
            if image.width < 2
                || image.height < 3
                || image.data.len() != image.width * image.height * 3
            {
                return fail(
                    None,
                    "the environment map must be at least 2x3 pixels of RGB",
                );
            }
            if !image.data.iter().all(|v| v.is_finite() && *v >= 0.0) {
                return fail(
                    None,
                    "the environment map has negative or non-finite pixels",
                );
            }
            if !to_world.is_finite() || to_world.determinant().abs() <= 1e-12 {
                return fail(None, "the envmap's to_world must be invertible");
            }
            Ok(())
        }
    }
}

fn check_phase(p: &PhaseDesc) -> Check {
    match p {
        PhaseDesc::Isotropic => Ok(()),
        PhaseDesc::Hg { g } => range("g", *g as f64, HG_G),
    }
}

fn check_medium(m: &MediumDesc) -> Check {
    match m {
        MediumDesc::Homogeneous {
            sigma_t,
            albedo,
            phase,
            ..
        } => {
            range_rgb("sigma_t", sigma_t, NON_NEGATIVE)?;
            range_rgb("albedo", albedo, UNIT)?;
            check_phase(phase)
        }
        MediumDesc::Heterogeneous {
            sigma_t,
            albedo,
            scale,
            phase,
            ..
        } => {
            range("scale", *scale as f64, SCALE)?;
            check_volume(sigma_t, "sigma_t", NON_NEGATIVE)?;
            check_volume(albedo, "albedo", UNIT)?;
            // The renderer's majorants are scale * max(sigma_t): keep them finite.
            let max = match sigma_t {
                VolumeDesc::Constant(c) => c.iter().cloned().fold(0.0, f32::max),
                VolumeDesc::Grid(g) => g.grid.data.iter().cloned().fold(0.0, f32::max),
            } as f64;
            if max * *scale as f64 > f32::MAX as f64 {
                return fail(
                    None,
                    format!("scale * max(sigma_t) = {scale} * {max} overflows single precision"),
                );
            }
            check_phase(phase)
        }
        MediumDesc::NonExponential {
            sigma_t,
            albedo,
            phase,
            model,
            density,
            ..
        } => {
            for &s in sigma_t {
                let s = s as f64;
                let r = match *model {
                    TransmittanceDesc::Fgf { hurst, sw, length } => {
                        Fgf::new(s, hurst, sw, length).map(|_| ())
                    }
                    TransmittanceDesc::Exponential => Exponential::new(s).map(|_| ()),
                    TransmittanceDesc::Davis { alpha } => Davis::new(s, alpha).map(|_| ()),
                    TransmittanceDesc::DavisWeinstein { h, c } => {
                        DavisWeinstein::new(s, h, c).map(|_| ())
                    }
                };
                r.map_err(|e| (Some(e.name.clone()), e.to_string()))?;
            }
            range_rgb("albedo", albedo, UNIT)?;
            check_phase(phase)?;
            match density {
                Some(g) if g.grid.channels != 1 => fail(
                    Some("density"),
                    format!(
                        "'density' grid must have 1 channel (it has {})",
                        g.grid.channels
                    ),
                ),
                Some(g) => check_grid(g, "density", NON_NEGATIVE),
                None => Ok(()),
            }
        }
    }
}

fn check_volume(v: &VolumeDesc, name: &str, r: Range<f64>) -> Check {
    match v {
        VolumeDesc::Constant(c) => range_rgb(name, c, r),
        VolumeDesc::Grid(g) => check_grid(g, name, r),
    }
}

fn check_grid(g: &GridVolumeDesc, name: &str, r: Range<f64>) -> Check {
    let v = &g.grid;
    if !(v.channels == 1 || v.channels == 3) {
        return fail(
            Some(name),
            format!(
                "'{name}' grid has {} channels; it needs 1 (scalar) or 3 (rgb)",
                v.channels
            ),
        );
    }
    if v.shape.contains(&0) || v.data.len() != v.shape.iter().product::<usize>() * v.channels {
        return fail(
            Some(name),
            format!(
                "'{name}' grid holds {} values, which does not match its {:?} shape with {} channel(s)",
                v.data.len(),
                v.shape,
                v.channels
            ),
        );
    }
    if let Some(i) = v.data.iter().position(|&x| !(r.ok)(x as f64)) {
        return fail(
            Some(name),
            format!(
                "'{name}' grid value #{i} = {} is out of range (valid: {})",
                v.data[i], r.text
            ),
        );
    }
    invertible(&g.to_world)?;
    let b = v.bbox;
    if g.use_grid_bbox && !(b[3] > b[0] && b[4] > b[1] && b[5] > b[2]) {
        return fail(
            Some("use_grid_bbox"),
            format!("use_grid_bbox is true but the '{name}' grid's bounding box {b:?} is empty"),
        );
    }
    Ok(())
}
