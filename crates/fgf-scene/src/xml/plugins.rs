//! Stage 2 of the loader: instantiate the plugins. Parameters, defaults and
//! valid ranges follow Mitsuba 3.9 unless said otherwise.
//!
//! | element | types | parameters (default) |
//! |---|---|---|
//! | `integrator` | `volpath`, `path` | `max_depth` (-1 = unbounded, else ≥ 0), `rr_depth` (5, ≥ 1), `hide_emitters` (false). `path` in a scene with media is an error (use `volpath`). Default integrator: `path`. |
//! | `sensor` | `perspective` | `fov` (degrees, 0 < fov < 180) or `focal_length` (`"50mm"`, 35 mm film equivalent, the default), `fov_axis` (`x`, `y`, `smaller`, `larger`; `x`), `near_clip` (0.01), `far_clip` (10000), `to_world` (rigid); nested `sampler`, `film` and one `medium` (the camera's). |
//! | `sampler` | `independent` | `sample_count` (4, ≥ 1), `seed` (0, ≥ 0) |
//! | `film` | `hdrfilm` | `width` (768), `height` (576): 1..=65536 each and at most 2^26 pixels; `pixel_format` (`rgb`, `rgba`); `component_format` and `file_format` accepted and ignored (output is float32 EXR); cropping is not supported; nested `rfilter`. |
//! | `rfilter` | `box`, `gaussian`, `tent` | gaussian `stddev` (0.5, > 0); tent `radius` (1, > 0). Default: gaussian. |
//! | `shape` | `cube`, `rectangle`, `disk`, `sphere`, `obj`, `ply` | `to_world`, `flip_normals` (false); sphere `center` (0,0,0), `radius` (1, > 0); obj/ply `filename` (required), `face_normals` (false: a mesh without vertex normals gets Mitsuba's smooth, angle-weighted ones, see below; true: flat shading, the file's normals are ignored). Nested: one `bsdf` (default: diffuse 0.5, but diffuse 0 — black — on a shape with an `area` emitter, as in Mitsuba), one `area` emitter, media named `interior` / `exterior`. |
//! | `bsdf` | `diffuse`, `null`, `dielectric`, `conductor`, `twosided` | diffuse `reflectance` (0.5, in \[0, 1\]); dielectric `int_ior` ("bk7"), `ext_ior` ("air"), numbers > 0 or names from Mitsuba's table, `specular_reflectance` (1), `specular_transmittance` (1); conductor `material` ("none" = perfect mirror, or a Mitsuba name such as "Au") or `eta` (0) and `k` (1), `specular_reflectance` (1); twosided: one nested BSDF. |
//! | `emitter` | `area` (in a shape), `point`, `spot`, `directional`, `constant` | area `radiance` (1); point `intensity` (1), `position` or `to_world`; spot `intensity` (1), `to_world`, `cutoff_angle` (20°, in (0, 180)), `beam_width` (0.75·cutoff, in [0, cutoff]); directional `irradiance` (1), `direction` or `to_world` (local +z); constant `radiance` (1). Colours ≥ 0. |
//!
//! Media, volumes and phase functions: see [`super::media`].
//!
//! # Two shape defaults that change images (as in Mitsuba 3.9)
//!
//! **Emitters are black.** A shape without a `bsdf` gets a `diffuse` BSDF
//! of reflectance 0.5, except when it carries an `area` emitter: then the
//! reflectance is 0, so the light source emits but reflects nothing. Give
//! the emitter an explicit `bsdf` to make it reflect.
//!
//! ```xml
//! <shape type="rectangle">
//!     <emitter type="area"><rgb name="radiance" value="10"/></emitter>
//!     <!-- no <bsdf>: black diffuse (reflectance 0) -->
//! </shape>
//! ```
//!
//! **Meshes without normals are smooth.** An `obj`/`ply` whose file has no
//! vertex normals gets computed ones, unless `face_normals="true"` (flat
//! shading; then the file's normals are ignored too). The normal at a
//! vertex is the normalised sum of the unit normals of the faces around
//! it, each weighted by the face's interior angle at that vertex (angle
//! weighting, not area weighting), computed on the world-space positions
//! (after `to_world`). Degenerate faces (zero area) are skipped; a vertex
//! with only degenerate faces gets the normal (1, 0, 0) in world space,
//! like Mitsuba's placeholder. An OBJ vertex is a distinct `v/vt/vn`
//! triple, so a texture seam splits the smoothing as in Mitsuba.
//!
//! ```xml
//! <shape type="obj">
//!     <string name="filename" value="meshes/octahedron.obj"/>
//!     <boolean name="face_normals" value="true"/>  <!-- keep it faceted -->
//! </shape>
//! ```

use super::document::XNode;
use super::media;
use super::mesh;
use super::props::{check, Entry, Props, OBJECT_TAGS};
use super::tables;
use crate::desc::*;
use crate::error::SceneError;
use glam::{DMat4, DVec3, Mat4, Vec3};
use std::collections::HashMap;
use std::sync::Arc;

/// Largest film side (pixels).
const MAX_FILM_SIDE: i64 = 65_536;
/// Largest film area: 2^26 pixels = 64 Mpixel. The renderer keeps float32
/// RGB plus variance per pixel (about 24 bytes), so this bounds the frame
/// buffers to about 1.6 GB; a typo like width="1e9" is refused, not an OOM.
const MAX_FILM_PIXELS: i64 = 1 << 26;

/// Loader state shared by the plugin constructors.
pub(crate) struct Ctx<'a> {
    pub ids: HashMap<String, &'a XNode>,
    pub bsdfs: Vec<BsdfDesc>,
    bsdf_by_id: HashMap<String, BsdfId>,
    default_bsdf: Option<BsdfId>,
    /// The black diffuse BSDF of emitters without a BSDF (shared, like
    /// `default_bsdf`).
    default_emitter_bsdf: Option<BsdfId>,
    pub media: Vec<MediumDesc>,
    pub medium_by_id: HashMap<String, MediumId>,
    /// The element each medium was defined by (for deferred errors).
    pub medium_nodes: Vec<&'a XNode>,
    /// Ids being instantiated (reference cycle detection).
    resolving: Vec<String>,
}

fn collect_ids<'a>(n: &'a XNode, ids: &mut HashMap<String, &'a XNode>) -> Result<(), SceneError> {
    if let Some(id) = n.attr("id") {
        if n.tag != "ref" {
            if !OBJECT_TAGS.contains(&n.tag.as_str()) {
                return Err(n.err(format!(
                    "an 'id' is only allowed on objects ({}), not on <{}>",
                    OBJECT_TAGS.join(", "),
                    n.tag
                )));
            }
            if id.is_empty() {
                return Err(n.err("empty id"));
            }
            if let Some(prev) = ids.get(id) {
                return Err(n.err(format!(
                    "duplicate id '{id}' (first defined at {}:{})",
                    prev.file.display(),
                    prev.line
                )));
            }
            ids.insert(id.to_string(), n);
        }
    }
    for c in &n.children {
        collect_ids(c, ids)?;
    }
    Ok(())
}

const TOP_LEVEL: &[&str] = &["integrator", "sensor", "shape", "bsdf", "emitter", "medium"];

pub(crate) fn instantiate(nodes: &[XNode], source: &str) -> Result<SceneDesc, SceneError> {
    let mut ids = HashMap::new();
    for n in nodes {
        collect_ids(n, &mut ids)?;
    }
    let mut ctx = Ctx {
        ids,
        bsdfs: Vec::new(),
        bsdf_by_id: HashMap::new(),
        default_bsdf: None,
        default_emitter_bsdf: None,
        media: Vec::new(),
        medium_by_id: HashMap::new(),
        medium_nodes: Vec::new(),
        resolving: Vec::new(),
    };
    let mut integrator: Option<(IntegratorDesc, &XNode)> = None;
    let mut sensor: Option<(SensorDesc, &XNode)> = None;
    let mut shapes = Vec::new();
    let mut emitters = Vec::new();
    for n in nodes {
        match n.tag.as_str() {
            "integrator" => {
                if let Some((_, prev)) = &integrator {
                    return Err(n.err(format!(
                        "a second <integrator> (the first is at line {})",
                        prev.line
                    )));
                }
                integrator = Some((integrator_desc(&ctx, n)?, n));
            }
            "sensor" => {
                if let Some((_, prev)) = &sensor {
                    return Err(n.err(format!(
                        "a second <sensor> (the first is at line {}); only one sensor is supported",
                        prev.line
                    )));
                }
                sensor = Some((sensor_desc(&mut ctx, n)?, n));
            }
            "shape" => shapes.push(shape_desc(&mut ctx, n)?),
            "bsdf" => {
                bsdf_id(&mut ctx, n)?;
            }
            "emitter" => emitters.push(emitter_desc(&ctx, n, false)?),
            "medium" => {
                media::medium_id(&mut ctx, n)?;
            }
            other => {
                return Err(n.err(format!(
                    "unsupported element <{other}> in <scene> (supported: {}, default, include)",
                    TOP_LEVEL.join(", ")
                )))
            }
        }
    }
    // Mitsuba's defaults: a `path` integrator and a default perspective camera.
    let integrator = match integrator {
        Some((d, n)) => {
            if d.kind == IntegratorKind::Path && !ctx.media.is_empty() {
                return Err(n.err(format!(
                    "the 'path' integrator ignores participating media, but this scene has {} (first at {}:{}); use <integrator type=\"volpath\">",
                    ctx.media.len(),
                    ctx.medium_nodes[0].file.display(),
                    ctx.medium_nodes[0].line
                )));
            }
            d
        }
        None => {
            if !ctx.media.is_empty() {
                return Err(SceneError::new(
                    crate::error::SceneErrorKind::Invalid,
                    source,
                    "the scene has participating media but no <integrator>; Mitsuba's default integrator 'path' ignores media: add <integrator type=\"volpath\"/>",
                ));
            }
            IntegratorDesc {
                kind: IntegratorKind::Path,
                max_depth: -1,
                rr_depth: 5,
                hide_emitters: false,
            }
        }
    };
    let sensor = match sensor {
        Some((s, _)) => s,
        None => default_sensor(),
    };
    media::resolve_default_lengths(&mut ctx, &shapes)?;
    Ok(SceneDesc {
        source: source.to_string(),
        integrator,
        sensor,
        shapes,
        bsdfs: ctx.bsdfs,
        emitters,
        media: ctx.media,
    })
}

/// Round a composed f64 matrix to f32, refusing overflow.
pub(crate) fn to_mat4(node: &XNode, m: DMat4) -> Result<Mat4, SceneError> {
    let f = m.as_mat4();
    if !f.is_finite() {
        return Err(node.err("the transform overflows single precision"));
    }
    Ok(f)
}

/// Round to f32 and require an invertible matrix (the renderer maps rays
/// to local space with the inverse): the determinant must be nonzero and
/// the inverse finite in single precision.
pub(crate) fn to_invertible_mat4(node: &XNode, m: DMat4) -> Result<Mat4, SceneError> {
    let f = to_mat4(node, m)?;
    let det = m.determinant();
    if det == 0.0 || !det.is_finite() || f.determinant() == 0.0 || !f.inverse().is_finite() {
        return Err(node.err(format!(
            "to_world is singular or nearly so (determinant {det:e}); the renderer needs its inverse: give every axis a nonzero scale (a flat rectangle or disk keeps z scale 1)"
        )));
    }
    Ok(f)
}

pub(crate) fn rgb(v: [f64; 3]) -> Rgb {
    [v[0] as f32, v[1] as f32, v[2] as f32]
}

fn plugin_type<'a>(n: &'a XNode, kind: &str, supported: &[&str]) -> Result<&'a str, SceneError> {
    let ty = n.attr("type").ok_or_else(|| {
        n.err(format!(
            "missing attribute 'type' (supported {kind} types: {})",
            supported.join(", ")
        ))
    })?;
    if !supported.contains(&ty) {
        return Err(n.err(format!(
            "unknown {kind} type '{ty}' (supported: {})",
            supported.join(", ")
        )));
    }
    Ok(ty)
}

/// Attributes an object element may carry.
pub(crate) fn check_object_attrs(n: &XNode) -> Result<(), SceneError> {
    n.check_attrs(&["type", "id", "name"])
}

// ---------------------------------------------------------------- integrator

fn integrator_desc(ctx: &Ctx, n: &XNode) -> Result<IntegratorDesc, SceneError> {
    check_object_attrs(n)?;
    let ty = plugin_type(n, "integrator", &["volpath", "path"])?;
    let p = Props::new(n, &ctx.ids, &["max_depth", "rr_depth", "hide_emitters"])?;
    let max_depth = p.int_in(
        "max_depth",
        -1,
        |v| v == -1 || (0..=i32::MAX as i64).contains(&v),
        "-1 (unbounded) or 0 <= max_depth <= 2^31-1",
    )? as i32;
    let rr_depth = p.int_in(
        "rr_depth",
        5,
        |v| (1..=u32::MAX as i64).contains(&v),
        "1 <= rr_depth <= 2^32-1",
    )? as u32;
    let hide_emitters = p.bool_or("hide_emitters", false)?;
    p.finish()?;
    Ok(IntegratorDesc {
        kind: if ty == "volpath" {
            IntegratorKind::Volpath
        } else {
            IntegratorKind::Path
        },
        max_depth,
        rr_depth,
        hide_emitters,
    })
}

// -------------------------------------------------------------------- sensor

/// 35 mm film: the focal length → field of view conversion uses its
/// diagonal, as Mitsuba does.
const FILM_35MM_DIAGONAL: f64 = 43.266_615_305_567_87; // sqrt(36² + 24²)

/// Horizontal field of view (degrees) for a focal length in mm on a film of
/// `width`×`height` pixels: Mitsuba maps the 35 mm diagonal to the film's
/// diagonal, `tan(fov_x/2) = d/(2 f) · width / sqrt(width² + height²)`.
fn fov_from_focal_length(f_mm: f64, width: u32, height: u32) -> f64 {
    let (w, h) = (width as f64, height as f64);
    let t = FILM_35MM_DIAGONAL / (2.0 * f_mm) * w / (w * w + h * h).sqrt();
    2.0 * t.atan().to_degrees()
}

fn default_sensor() -> SensorDesc {
    let (width, height) = (768, 576);
    SensorDesc {
        to_world: Mat4::IDENTITY,
        fov: fov_from_focal_length(50.0, width, height) as f32,
        fov_axis: FovAxis::X,
        near_clip: 0.01,
        far_clip: 10_000.0,
        width,
        height,
        rfilter: FilterDesc::Gaussian { stddev: 0.5 },
        spp: 4,
        seed: 0,
        medium: None,
    }
}

fn sensor_desc<'a>(ctx: &mut Ctx<'a>, n: &'a XNode) -> Result<SensorDesc, SceneError> {
    check_object_attrs(n)?;
    plugin_type(n, "sensor", &["perspective"])?;
    let p = Props::new(
        n,
        &ctx.ids,
        &[
            "fov",
            "fov_axis",
            "focal_length",
            "near_clip",
            "far_clip",
            "to_world",
        ],
    )?;
    let mut s = default_sensor();
    // Film first: the focal length conversion needs its aspect ratio.
    let films = p.take_objects("film");
    if films.len() > 1 {
        return Err(films[1].node.err("a sensor takes one <film>"));
    }
    if let Some(f) = films.first() {
        film(ctx, f.target, &mut s)?;
    }
    let samplers = p.take_objects("sampler");
    if samplers.len() > 1 {
        return Err(samplers[1].node.err("a sensor takes one <sampler>"));
    }
    if let Some(e) = samplers.first() {
        sampler(ctx, e.target, &mut s)?;
    }
    let fov = p.float("fov")?;
    let focal = p.string("focal_length")?;
    s.fov = match (fov, focal) {
        (Some(_), Some((_, fnode))) => {
            return Err(fnode.err("give either 'fov' or 'focal_length', not both"))
        }
        (Some((v, node)), None) => check(
            node,
            "fov",
            v,
            v > 0.0 && v < 180.0,
            "0 < fov < 180 degrees",
        )? as f32,
        (None, Some((text, node))) => {
            let num = text.trim().strip_suffix("mm").unwrap_or(text).trim();
            let f = super::props::parse_f64(node, "focal_length", num)?;
            check(node, "focal_length", f, f > 0.0, "> 0 mm, e.g. \"50mm\"")?;
            s.fov_axis = FovAxis::X;
            fov_from_focal_length(f, s.width, s.height) as f32
        }
        // Mitsuba's default is a 50 mm focal length, on this film's aspect.
        (None, None) => fov_from_focal_length(50.0, s.width, s.height) as f32,
    };
    if focal.is_some() {
        // Mitsuba converts a focal length through the film diagonal and
        // never reads fov_axis then.
        if let Some(e) = p.take("fov_axis") {
            return Err(e
                .node
                .err("'fov_axis' only applies with 'fov', not with 'focal_length'"));
        }
    } else {
        s.fov_axis = match p
            .choice("fov_axis", "x", &["x", "y", "smaller", "larger"])?
            .as_str()
        {
            "y" => FovAxis::Y,
            "smaller" => FovAxis::Smaller,
            "larger" => FovAxis::Larger,
            _ => FovAxis::X,
        };
    }
    let near = p.float_in("near_clip", 0.01, |v| v > 0.0, "near_clip > 0")?;
    let far = p.float_in("far_clip", 10_000.0, |v| v > near, "far_clip > near_clip")?;
    s.near_clip = near as f32;
    s.far_clip = far as f32;
    if let Some((m, node)) = p.transform("to_world")? {
        // Mitsuba refuses scale in a camera transform; we check that the
        // three axes are unit length and orthogonal (to 1e-3, which a
        // matrix written with 6 digits meets).
        let cols = [
            m.x_axis.truncate(),
            m.y_axis.truncate(),
            m.z_axis.truncate(),
        ];
        let rigid = cols.iter().all(|c| (c.length() - 1.0).abs() < 1e-3)
            && cols[0].dot(cols[1]).abs() < 1e-3
            && cols[0].dot(cols[2]).abs() < 1e-3
            && cols[1].dot(cols[2]).abs() < 1e-3
            && m.row(3) == glam::DVec4::new(0.0, 0.0, 0.0, 1.0);
        if !rigid {
            return Err(node.err(
                "a sensor's to_world must be a rigid transform (rotation and translation, no scale or shear)",
            ));
        }
        s.to_world = to_mat4(node, m)?;
    }
    let media_e = p.take_objects("medium");
    if media_e.len() > 1 {
        return Err(media_e[1].node.err("a sensor takes at most one medium"));
    }
    if let Some(e) = media_e.first() {
        s.medium = Some(media::medium_ref(ctx, e)?);
    }
    p.finish()?;
    Ok(s)
}

fn sampler(ctx: &Ctx, n: &XNode, s: &mut SensorDesc) -> Result<(), SceneError> {
    check_object_attrs(n)?;
    plugin_type(n, "sampler", &["independent"])?;
    let p = Props::new(n, &ctx.ids, &["sample_count", "seed"])?;
    s.spp = p.int_in(
        "sample_count",
        4,
        |v| (1..=u32::MAX as i64).contains(&v),
        "1 <= sample_count <= 2^32-1",
    )? as u32;
    s.seed = p.int_in("seed", 0, |v| v >= 0, "seed >= 0")? as u64;
    p.finish()
}

fn film(ctx: &Ctx, n: &XNode, s: &mut SensorDesc) -> Result<(), SceneError> {
    check_object_attrs(n)?;
    plugin_type(n, "film", &["hdrfilm"])?;
    let p = Props::new(
        n,
        &ctx.ids,
        &[
            "width",
            "height",
            "pixel_format",
            "component_format",
            "file_format",
            "crop_offset_x",
            "crop_offset_y",
            "crop_width",
            "crop_height",
        ],
    )?;
    let range = format!("1 <= value <= {MAX_FILM_SIDE}");
    let w = p.int_in("width", 768, |v| (1..=MAX_FILM_SIDE).contains(&v), &range)?;
    let h = p.int_in("height", 576, |v| (1..=MAX_FILM_SIDE).contains(&v), &range)?;
    if w * h > MAX_FILM_PIXELS {
        return Err(n.err(format!(
            "film of {w}x{h} = {} pixels is larger than the limit of {MAX_FILM_PIXELS} pixels",
            w * h
        )));
    }
    s.width = w as u32;
    s.height = h as u32;
    p.choice("pixel_format", "rgb", &["rgb", "rgba"])?;
    // The output is always float32 EXR; these are accepted so that Mitsuba
    // scenes load unchanged.
    p.choice(
        "component_format",
        "float16",
        &["float16", "float32", "uint32"],
    )?;
    p.choice("file_format", "openexr", &["openexr", "exr"])?;
    for k in [
        "crop_offset_x",
        "crop_offset_y",
        "crop_width",
        "crop_height",
    ] {
        if let Some(e) = p.take(k) {
            return Err(e.node.err(format!(
                "'{k}': film cropping is not supported (render the full film)"
            )));
        }
    }
    let filters = p.take_objects("rfilter");
    if filters.len() > 1 {
        return Err(filters[1].node.err("a film takes one <rfilter>"));
    }
    if let Some(e) = filters.first() {
        s.rfilter = rfilter(ctx, e.target)?;
    }
    p.finish()
}

fn rfilter(ctx: &Ctx, n: &XNode) -> Result<FilterDesc, SceneError> {
    check_object_attrs(n)?;
    let ty = plugin_type(n, "rfilter", &["box", "gaussian", "tent"])?;
    let known: &'static [&'static str] = match ty {
        "gaussian" => &["stddev"],
        "tent" => &["radius"],
        _ => &[],
    };
    let p = Props::new(n, &ctx.ids, known)?;
    let f = match ty {
        "gaussian" => FilterDesc::Gaussian {
            stddev: p.float_in(
                "stddev",
                0.5,
                |v| v > 0.0 && v <= 64.0,
                "0 < stddev <= 64 pixels",
            )? as f32,
        },
        "tent" => FilterDesc::Tent {
            radius: p.float_in(
                "radius",
                1.0,
                |v| v > 0.0 && v <= 256.0,
                "0 < radius <= 256 pixels",
            )? as f32,
        },
        _ => FilterDesc::Box,
    };
    p.finish()?;
    Ok(f)
}

// -------------------------------------------------------------------- shapes

const SHAPES: &[&str] = &["cube", "rectangle", "disk", "sphere", "obj", "ply"];

fn shape_desc<'a>(ctx: &mut Ctx<'a>, n: &'a XNode) -> Result<ShapeDesc, SceneError> {
    check_object_attrs(n)?;
    let ty = plugin_type(n, "shape", SHAPES)?;
    let known: &'static [&'static str] = match ty {
        "sphere" => &["to_world", "flip_normals", "center", "radius"],
        "obj" | "ply" => &["to_world", "flip_normals", "filename", "face_normals"],
        _ => &["to_world", "flip_normals"],
    };
    let p = Props::new(n, &ctx.ids, known)?;
    // A sphere checks its own to_world below.
    let mut to_world = match ty {
        "sphere" => Mat4::IDENTITY,
        _ => match p.transform("to_world")? {
            Some((m, node)) => to_invertible_mat4(node, m)?,
            None => Mat4::IDENTITY,
        },
    };
    let flip_normals = p.bool_or("flip_normals", false)?;
    let geometry = match ty {
        "cube" => GeometryDesc::Cube,
        "rectangle" => GeometryDesc::Rectangle,
        "disk" => GeometryDesc::Disk,
        "sphere" => {
            if let Some(e) = p.take("to_world") {
                // Mitsuba keeps a sphere round whatever the to_world (it
                // warns and drops non-uniform scale); we refuse it instead.
                // The linear part must be a scaled rotation: M^T M = s² I,
                // to 1e-4 relative (6-digit matrices pass).
                let m = e.transform()?;
                let cols = [
                    m.x_axis.truncate(),
                    m.y_axis.truncate(),
                    m.z_axis.truncate(),
                ];
                let s2 = cols[0].length_squared();
                let tol = 1e-4 * s2;
                let similar = (cols[1].length_squared() - s2).abs() <= tol
                    && (cols[2].length_squared() - s2).abs() <= tol
                    && cols[0].dot(cols[1]).abs() <= tol
                    && cols[0].dot(cols[2]).abs() <= tol
                    && cols[1].dot(cols[2]).abs() <= tol;
                if !similar {
                    return Err(e.node.err(
                        "a sphere's to_world must not contain non-uniform scale or shear (use the 'radius' parameter, or a mesh for an ellipsoid)",
                    ));
                }
                to_world = to_invertible_mat4(e.node, m)?;
            }
            let center = p.vec3("center")?.map(|(v, _)| v).unwrap_or([0.0; 3]);
            let radius = p.float_in("radius", 1.0, |v| v > 0.0, "radius > 0")?;
            GeometryDesc::Sphere {
                center: DVec3::from(center).as_vec3(),
                radius: radius as f32,
            }
        }
        _ => {
            let (file, fnode) = p.string("filename")?.ok_or_else(|| {
                n.err("missing required parameter 'filename' (the mesh file, relative to the scene file)")
            })?;
            let face_normals = p.bool_or("face_normals", false)?;
            let path = fnode.resolve(file);
            let mut m = if ty == "obj" {
                mesh::load_obj(fnode, &path)?
            } else {
                mesh::load_ply(fnode, &path)?
            };
            if face_normals {
                m.normals = None;
            } else if m.normals.is_none() {
                // Mitsuba's smooth normals (angle-weighted, world space).
                m.normals = Some(mesh::smooth_vertex_normals(
                    &m.positions,
                    &m.indices,
                    &to_world,
                ));
            }
            GeometryDesc::Mesh(Arc::new(m))
        }
    };
    let bsdfs = p.take_objects("bsdf");
    if bsdfs.len() > 1 {
        return Err(bsdfs[1].node.err(format!(
            "a shape takes one BSDF (the first is at line {})",
            bsdfs[0].node.line
        )));
    }
    let bsdf = match bsdfs.first() {
        Some(e) => Some(bsdf_ref(ctx, e)?),
        None => None,
    };
    let emitters = p.take_objects("emitter");
    if emitters.len() > 1 {
        return Err(emitters[1].node.err("a shape takes one emitter"));
    }
    let emitter = match emitters.first() {
        Some(e) => {
            if e.node.tag == "ref" {
                return Err(e
                    .node
                    .err("an area emitter must be nested in its shape, not referenced"));
            }
            Some(emitter_desc(ctx, e.target, true)?)
        }
        None => None,
    };
    // The default depends on whether the shape emits (see `default_bsdf`).
    let bsdf = bsdf.unwrap_or_else(|| default_bsdf(ctx, emitter.is_some()));
    let interior = match p.take_object_named("medium", "interior") {
        Some(e) => Some(media::medium_ref(ctx, e)?),
        None => None,
    };
    let exterior = match p.take_object_named("medium", "exterior") {
        Some(e) => Some(media::medium_ref(ctx, e)?),
        None => None,
    };
    if let Some(e) = p.take_objects("medium").first() {
        return Err(e.node.err(format!(
            "a medium in a shape needs name=\"interior\" or name=\"exterior\" (got {})",
            e.name
                .map(|s| format!("name=\"{s}\""))
                .unwrap_or("no name".into())
        )));
    }
    p.finish()?;
    let mut name = format!("shape type=\"{ty}\"");
    if let Some(id) = n.attr("id") {
        name.push_str(&format!(" id=\"{id}\""));
    }
    name.push_str(&format!(" ({}:{})", n.file.display(), n.line));
    Ok(ShapeDesc {
        name,
        geometry,
        to_world,
        flip_normals,
        bsdf,
        emitter,
        interior,
        exterior,
    })
}

/// The BSDF of a shape without one, as Mitsuba 3.9's `Shape` constructor
/// chooses it: a diffuse BSDF of reflectance 0.5, except on a shape with an
/// (area) emitter, which gets reflectance 0 so that a light source does not
/// also reflect light. All such shapes share one entry per kind.
fn default_bsdf(ctx: &mut Ctx, emits: bool) -> BsdfId {
    let (slot, reflectance) = if emits {
        (&mut ctx.default_emitter_bsdf, 0.0)
    } else {
        (&mut ctx.default_bsdf, 0.5)
    };
    *slot.get_or_insert_with(|| {
        ctx.bsdfs.push(BsdfDesc::Diffuse {
            reflectance: [reflectance; 3],
        });
        ctx.bsdfs.len() - 1
    })
}

// --------------------------------------------------------------------- BSDFs

const BSDFS: &[&str] = &["diffuse", "null", "dielectric", "conductor", "twosided"];

/// A BSDF reference or nested BSDF, as an index (shared for the same id).
fn bsdf_ref<'a>(ctx: &mut Ctx<'a>, e: &Entry<'a>) -> Result<BsdfId, SceneError> {
    bsdf_id(ctx, e.target)
}

fn bsdf_id<'a>(ctx: &mut Ctx<'a>, n: &'a XNode) -> Result<BsdfId, SceneError> {
    if let Some(id) = n.attr("id") {
        if let Some(&i) = ctx.bsdf_by_id.get(id) {
            return Ok(i);
        }
    }
    let d = bsdf_desc(ctx, n, 0)?;
    ctx.bsdfs.push(d);
    let i = ctx.bsdfs.len() - 1;
    if let Some(id) = n.attr("id") {
        ctx.bsdf_by_id.insert(id.to_string(), i);
    }
    Ok(i)
}

fn ior(e: &Entry) -> Result<f64, SceneError> {
    let name = e.name.unwrap_or("?");
    if e.node.tag == "string" {
        let s = e.string()?;
        return tables::IOR
            .iter()
            .find(|(k, _)| *k == s)
            .map(|(_, v)| *v)
            .ok_or_else(|| {
                e.node.err(format!(
                    "unknown material '{s}' for {name} (give a number > 0 or one of: {})",
                    tables::IOR
                        .iter()
                        .map(|(k, _)| *k)
                        .collect::<Vec<_>>()
                        .join(", ")
                ))
            });
    }
    let v = e.float()?;
    check(
        e.node,
        name,
        v,
        v > 0.0,
        "a number > 0 or a material name such as \"bk7\"",
    )
}

fn bsdf_desc<'a>(ctx: &mut Ctx<'a>, n: &'a XNode, depth: usize) -> Result<BsdfDesc, SceneError> {
    check_object_attrs(n)?;
    let ty = plugin_type(n, "BSDF", BSDFS)?;
    if let Some(id) = n.attr("id") {
        if ctx.resolving.iter().any(|r| r == id) {
            return Err(n.err(format!("reference cycle through id '{id}'")));
        }
    }
    let known: &'static [&'static str] = match ty {
        "diffuse" => &["reflectance"],
        "dielectric" => &[
            "int_ior",
            "ext_ior",
            "specular_reflectance",
            "specular_transmittance",
        ],
        "conductor" => &["material", "eta", "k", "specular_reflectance"],
        _ => &[],
    };
    let p = Props::new(n, &ctx.ids, known)?;
    let unit = |v: f64| (0.0..=1.0).contains(&v);
    let d = match ty {
        "diffuse" => BsdfDesc::Diffuse {
            reflectance: rgb(p.color_in("reflectance", [0.5; 3], unit, "in [0, 1]")?),
        },
        "null" => BsdfDesc::Null,
        "dielectric" => {
            let int_ior = match p.take("int_ior") {
                Some(e) => ior(e)?,
                None => 1.5046,
            };
            let ext_ior = match p.take("ext_ior") {
                Some(e) => ior(e)?,
                None => 1.000277,
            };
            BsdfDesc::Dielectric {
                int_ior: int_ior as f32,
                ext_ior: ext_ior as f32,
                specular_reflectance: rgb(p.color_in(
                    "specular_reflectance",
                    [1.0; 3],
                    unit,
                    "in [0, 1]",
                )?),
                specular_transmittance: rgb(p.color_in(
                    "specular_transmittance",
                    [1.0; 3],
                    unit,
                    "in [0, 1]",
                )?),
            }
        }
        "conductor" => {
            let material = p.string("material")?;
            let eta = p.color("eta")?;
            let k = p.color("k")?;
            let (eta, k) = match material {
                Some((m, mnode)) if m != "none" => {
                    if eta.is_some() || k.is_some() {
                        return Err(mnode.err("give either 'material' or 'eta'/'k', not both"));
                    }
                    let (_, e, k) = tables::CONDUCTORS
                        .iter()
                        .find(|(name, _, _)| *name == m)
                        .ok_or_else(|| {
                            mnode.err(format!(
                                "unknown conductor material '{m}' (valid: none, {})",
                                tables::CONDUCTORS
                                    .iter()
                                    .map(|(k, _, _)| *k)
                                    .collect::<Vec<_>>()
                                    .join(", ")
                            ))
                        })?;
                    (*e, *k)
                }
                _ => {
                    let nonneg = |v: Option<([f64; 3], &XNode)>, name: &str, def: f64| match v {
                        None => Ok([def; 3]),
                        Some((c, node)) => {
                            if c.iter().all(|&x| x >= 0.0) {
                                Ok(c)
                            } else {
                                Err(node.err(format!(
                                    "invalid {name} = ({}, {}, {}) (valid: each channel >= 0)",
                                    c[0], c[1], c[2]
                                )))
                            }
                        }
                    };
                    // Mitsuba's defaults eta = 0, k = 1: a perfect mirror.
                    (nonneg(eta, "eta", 0.0)?, nonneg(k, "k", 1.0)?)
                }
            };
            BsdfDesc::Conductor {
                eta: rgb(eta),
                k: rgb(k),
                specular_reflectance: rgb(p.color_in(
                    "specular_reflectance",
                    [1.0; 3],
                    unit,
                    "in [0, 1]",
                )?),
                perfect_mirror: eta == [0.0; 3] && k == [1.0; 3],
            }
        }
        _ => {
            let nested = p.take_objects("bsdf");
            match nested.len() {
                1 => {}
                0 => return Err(n.err("twosided needs one nested BSDF")),
                _ => {
                    return Err(nested[1].node.err(
                        "twosided with two different BSDFs (front/back) is not supported; give one nested BSDF",
                    ))
                }
            }
            let target = nested[0].target;
            if target.attr("type") == Some("twosided") {
                return Err(nested[0].node.err("twosided BSDFs cannot be nested"));
            }
            if depth > 4 {
                return Err(n.err("BSDFs nested too deep"));
            }
            let pushed = n
                .attr("id")
                .map(|id| ctx.resolving.push(id.to_string()))
                .is_some();
            let inner = bsdf_desc(ctx, target, depth + 1);
            if pushed {
                ctx.resolving.pop();
            }
            BsdfDesc::TwoSided(Box::new(inner?))
        }
    };
    p.finish()?;
    Ok(d)
}

// ------------------------------------------------------------------ emitters

fn emitter_desc(ctx: &Ctx, n: &XNode, on_shape: bool) -> Result<EmitterDesc, SceneError> {
    check_object_attrs(n)?;
    let ty = if on_shape {
        let ty = n.req_attr("type")?;
        if ty != "area" {
            return Err(n.err(format!(
                "emitter type '{ty}' cannot be attached to a shape (only 'area'); put it at the top level"
            )));
        }
        ty
    } else {
        let ty = plugin_type(
            n,
            "emitter",
            &["area", "point", "spot", "directional", "constant"],
        )?;
        if ty == "area" {
            return Err(n.err("an 'area' emitter must be nested inside the <shape> that emits"));
        }
        ty
    };
    let known: &'static [&'static str] = match ty {
        "area" | "constant" => &["radiance"],
        "point" => &["intensity", "position", "to_world"],
        "spot" => &["intensity", "to_world", "cutoff_angle", "beam_width"],
        _ => &["irradiance", "direction", "to_world"],
    };
    let p = Props::new(n, &ctx.ids, known)?;
    let nonneg = |v: f64| v >= 0.0;
    let d = match ty {
        "area" => EmitterDesc::Area {
            radiance: rgb(p.color_in("radiance", [1.0; 3], nonneg, ">= 0")?),
        },
        "constant" => EmitterDesc::Constant {
            radiance: rgb(p.color_in("radiance", [1.0; 3], nonneg, ">= 0")?),
        },
        "point" => {
            let intensity = rgb(p.color_in("intensity", [1.0; 3], nonneg, ">= 0")?);
            let position = match (p.vec3("position")?, p.transform("to_world")?) {
                (Some(_), Some((_, node))) => {
                    return Err(node.err("give either 'position' or 'to_world', not both"))
                }
                (Some((v, _)), None) => DVec3::from(v).as_vec3(),
                (None, Some((m, node))) => to_mat4(node, m)?.transform_point3(Vec3::ZERO),
                (None, None) => Vec3::ZERO,
            };
            EmitterDesc::Point {
                position,
                intensity,
            }
        }
        "spot" => {
            let intensity = rgb(p.color_in("intensity", [1.0; 3], nonneg, ">= 0")?);
            let to_world = match p.transform("to_world")? {
                Some((m, node)) => to_invertible_mat4(node, m)?,
                None => Mat4::IDENTITY,
            };
            let cutoff = p.float_in(
                "cutoff_angle",
                20.0,
                |v| v > 0.0 && v < 180.0,
                "0 < cutoff_angle < 180 degrees",
            )?;
            let beam = p.float_in(
                "beam_width",
                0.75 * cutoff,
                |v| v >= 0.0 && v <= cutoff,
                "0 <= beam_width <= cutoff_angle degrees",
            )?;
            EmitterDesc::Spot {
                to_world,
                intensity,
                cutoff_angle: cutoff as f32,
                beam_width: beam as f32,
            }
        }
        _ => {
            let irradiance = rgb(p.color_in("irradiance", [1.0; 3], nonneg, ">= 0")?);
            let dir = match (p.vec3("direction")?, p.transform("to_world")?) {
                (Some(_), Some((_, node))) => {
                    return Err(node.err("give either 'direction' or 'to_world', not both"))
                }
                (Some((v, node)), None) => (DVec3::from(v), node),
                (None, Some((m, node))) => (m.transform_vector3(DVec3::Z), node),
                (None, None) => (DVec3::Z, n),
            };
            let len = dir.0.length();
            if len == 0.0 || !len.is_finite() {
                return Err(dir.1.err("the light direction is zero"));
            }
            EmitterDesc::Directional {
                direction: (dir.0 / len).as_vec3(),
                irradiance,
            }
        }
    };
    p.finish()?;
    Ok(d)
}
