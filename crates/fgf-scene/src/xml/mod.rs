//! The Mitsuba 3 XML loader: a scene file to a validated
//! [`SceneDesc`].
//!
//! ```no_run
//! use std::path::Path;
//! let scene = fgf_scene::load_file(
//!     Path::new("scene.xml"),
//!     &[("spp".to_string(), "16".to_string())],
//! )?;
//! println!("{}x{} at {} spp", scene.sensor.width, scene.sensor.height, scene.sensor.spp);
//! # Ok::<(), fgf_scene::SceneError>(())
//! ```
//!
//! # The subset
//!
//! Everything listed here follows Mitsuba 3.9 (defaults included); anything
//! else is an error naming the file, line, tag and the supported names, and
//! an unknown or duplicated parameter of a known plugin is an error too.
//!
//! * Document: `<scene version="3.x">`, `<default name value>` with `$name`
//!   substitution in every attribute value (overridden by the caller's
//!   defines; a define without a `<default>` is substituted too),
//!   `<include filename>` and `<path value>` (file lookup below; cycles
//!   are errors), `id` attributes and `<ref id>` / `<ref name="interior" id>`.
//! * Properties: `float`, `integer`, `boolean`, `string`, `rgb` (`"0.8"`,
//!   `"0.1, 0.2, 0.3"` or `"0.1 0.2 0.3"`), `spectrum` (one uniform value,
//!   or wavelength:value pairs converted to RGB as Mitsuba's RGB variants
//!   convert them; see `spectrum.rs`), `point`/`vector` (`x y z` attributes or `value`), `transform`
//!   (`translate`, `rotate`, `scale`, `matrix`, `lookat`; the composed
//!   matrix is `M_last · … · M_first`; see `transform.rs`).
//! * Plugins: one module per family, each opening with the family's
//!   parameter table (units, valid range, default) and an XML and a Python
//!   example: [`integrators`], [`sensors`] (sensor, film, sampler, filters),
//!   [`shapes`], [`bsdfs`], [`textures`], [`emitters`], [`media`] (`homogeneous`,
//!   `heterogeneous`), [`nonexp`] (fgf's non-exponential `fgf` and
//!   `nonexponential`), [`volumes`] and [`phase`].
//! * Mitsuba defaults that change images and are easy to miss: a shape
//!   with an `area` emitter and no `bsdf` is black (diffuse reflectance 0,
//!   not 0.5); an `obj`/`ply` without vertex normals is smooth-shaded with
//!   computed angle-weighted normals unless `face_normals="true"` (both in
//!   [`shapes`]); a `rotate` axis is not normalised.
//!
//! # Finding files
//!
//! As in Mitsuba 3, a relative file name (a mesh, a grid, an include) is
//! looked up in the `<path value="dir"/>` directories (the last declared
//! first; a relative `dir` is taken from the file it is written in), then
//! the scene file's directory, then the working directory; an `<include>`
//! is looked up in the including file's directory first. fgf also tries the
//! directory of the file an element is written in (for includes kept next
//! to their meshes) before the working directory.
//!
//! # Scene versions
//!
//! `version="3.x"` and `"2.x"` files are read as written (Mitsuba 3 does
//! not change 2.x files). Files older than 2.0 are upgraded as Mitsuba 3
//! upgrades them: every parameter name goes from camelCase to snake_case
//! (`intIOR` → `int_ior`, `toWorld` → `to_world`) and a `diffuse` BSDF's
//! `diffuse_reflectance` becomes `reflectance`; each included file is
//! upgraded by its own version.
//!
//! # Units
//!
//! The tables use the same units everywhere. Distances are in the scene's
//! unit of length, written `length` (positions, radii, clip distances,
//! `length` itself), so extinction coefficients are in `1/length`. Angles
//! are in degrees, film sizes and filter radii in pixels, and colours are
//! linear RGB. The renderer has no physical power unit: radiance is in
//! `power/(length² sr)`, intensity in `power/sr` and irradiance in
//! `power/length²` of one arbitrary power unit, as in Mitsuba. A float
//! where a colour is expected is a grey colour.
//!
//! # Stages
//!
//! 1. `document.rs`: parse the XML with `roxmltree`, expand `<include>`,
//!    apply `<default>`s and `$name` substitution, into an owned tree of
//!    `XNode`s that remember their file and line.
//! 2. The plugin families instantiate each plugin from its children
//!    through `props.rs`, which type-checks every parameter, reports the
//!    unknown ones, and checks each value against the range of
//!    [`validate`](crate::validate) that applies to it, at its own line.
//! 3. [`SceneDesc::validate`](crate::desc::SceneDesc::validate)'s rules on
//!    the whole description (references, the integrator against the media,
//!    the transmittance models), reported at the plugin's or parameter's
//!    line.

pub mod bsdfs;
mod cie;
mod context;
mod document;
pub mod emitters;
pub mod integrators;
pub mod media;
mod mesh;
pub mod nonexp;
mod parse;
pub mod phase;
mod props;
pub mod sensors;
pub mod shapes;
mod spectrum;
mod tables;
pub mod textures;
mod transform;
pub mod volumes;

use crate::desc::*;
use crate::error::{SceneError, SceneErrorKind};
use crate::validate::{Invalid, Subject};
use context::Ctx;
use document::XNode;
use std::path::Path;

/// Load a scene file. `defines` override `<default>` values (`-D spp=256`).
pub fn load_file(path: &Path, defines: &[(String, String)]) -> Result<SceneDesc, SceneError> {
    load_file_cancellable(path, defines, None)
}

/// [`load_file`] that stops with a [`SceneErrorKind::Cancelled`] error soon
/// after `cancel` is set (it is polled at every element and include).
pub fn load_file_cancellable(
    path: &Path,
    defines: &[(String, String)],
    cancel: Option<&std::sync::atomic::AtomicBool>,
) -> Result<SceneDesc, SceneError> {
    let text = fgf_io::read_regular(path).map_err(|e| {
        SceneError::new(
            SceneErrorKind::Io,
            path,
            format!("cannot read the scene file: {e}"),
        )
    })?;
    let text = String::from_utf8(text).map_err(|e| {
        SceneError::new(
            SceneErrorKind::Syntax,
            path,
            format!(
                "the scene file is not valid UTF-8 (byte {})",
                e.utf8_error().valid_up_to()
            ),
        )
    })?;
    let base_dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    load_str_cancellable(
        &text,
        &path.display().to_string(),
        &base_dir,
        defines,
        cancel,
    )
}

/// Load a scene from a string. `source_name` names it in messages and
/// `base_dir` resolves relative file names (meshes, grids, includes).
pub fn load_str(
    xml: &str,
    source_name: &str,
    base_dir: &Path,
    defines: &[(String, String)],
) -> Result<SceneDesc, SceneError> {
    load_str_cancellable(xml, source_name, base_dir, defines, None)
}

fn load_str_cancellable(
    xml: &str,
    source_name: &str,
    base_dir: &Path,
    defines: &[(String, String)],
    cancel: Option<&std::sync::atomic::AtomicBool>,
) -> Result<SceneDesc, SceneError> {
    let (nodes, unused_define) = document::build(xml, source_name, base_dir, defines, cancel)?;
    let desc = instantiate(&nodes, source_name)?;
    // A define the scene never declares nor uses is a typo (`-D kernal=...`);
    // it is reported after the scene's own errors, which are more specific.
    match unused_define {
        Some(e) => Err(e),
        None => Ok(desc),
    }
}

const TOP_LEVEL: &[&str] = &[
    "integrator",
    "sensor",
    "shape",
    "bsdf",
    "emitter",
    "medium",
    "texture",
];

/// Stage 2: instantiate the top-level elements, in file order (a shape's
/// nested objects are instantiated with it), fill in Mitsuba's defaults for
/// what the scene leaves out, and validate the result.
fn instantiate(nodes: &[XNode], source: &str) -> Result<SceneDesc, SceneError> {
    let mut ctx = Ctx::new(nodes)?;
    let mut integrator: Option<(IntegratorDesc, &XNode)> = None;
    let mut sensor: Option<(SensorDesc, &XNode)> = None;
    let mut shapes = Vec::new();
    let mut shape_nodes = Vec::new();
    let mut emitters = Vec::new();
    let mut emitter_nodes = Vec::new();
    let mut area_decls = Vec::new();
    for n in nodes {
        match n.tag.as_str() {
            "integrator" => {
                if let Some((_, prev)) = &integrator {
                    return Err(n.err(format!(
                        "a second <integrator> (the first is at line {})",
                        prev.line
                    )));
                }
                integrator = Some((integrators::integrator_desc(&ctx, n)?, n));
            }
            "sensor" => {
                if let Some((_, prev)) = &sensor {
                    return Err(n.err(format!(
                        "a second <sensor> (the first is at line {}); only one sensor is supported",
                        prev.line
                    )));
                }
                sensor = Some((sensors::sensor_desc(&mut ctx, n)?, n));
            }
            "shape" => {
                shapes.push(shapes::shape_desc(&mut ctx, n)?);
                shape_nodes.push(n);
            }
            "bsdf" => {
                bsdfs::bsdf_id(&mut ctx, n)?;
            }
            // A top-level area emitter with an id is instantiated by the
            // shape that references it (checked below).
            "emitter" if n.attr("type") == Some("area") && n.attr("id").is_some() => {
                area_decls.push(n);
            }
            "emitter" => {
                emitters.push(emitters::emitter_desc(&mut ctx, n, false)?);
                emitter_nodes.push(n);
            }
            "medium" => {
                media::medium_id(&mut ctx, n)?;
            }
            // Instantiated here so that its errors are reported even if
            // nothing uses it; shared by `<ref>` afterwards.
            "texture" => {
                textures::texture_node(&mut ctx, n)?;
            }
            // A sampler, film or filter declared at the top level is used
            // where a <ref> names it (Mitsuba's documentation scenes do this).
            "sampler" | "film" | "rfilter" if n.attr("id").is_some() => {}
            other => {
                return Err(n.err(format!(
                    "unsupported element <{other}> in <scene> (supported: {}, default, include)",
                    TOP_LEVEL.join(", ")
                )))
            }
        }
    }
    for n in area_decls {
        if !ctx.area_refs.contains_key(n.attr("id").unwrap_or("")) {
            // Unreferenced: the emitter's own message (it needs a shape).
            emitters::emitter_desc(&mut ctx, n, false)?;
        }
    }
    nonexp::resolve_default_lengths(&mut ctx, &shapes)?;
    let places = Places {
        source,
        integrator: integrator.as_ref().map(|(_, n)| *n),
        sensor: sensor.as_ref().map(|(_, n)| *n),
        shapes: shape_nodes,
        bsdfs: ctx.bsdf_nodes,
        emitters: emitter_nodes,
        media: ctx.medium_nodes,
    };
    // Mitsuba's defaults: a `path` integrator and a default perspective camera.
    let desc = SceneDesc {
        source: source.to_string(),
        integrator: integrator.map_or_else(integrators::default_integrator, |(d, _)| d),
        sensor: sensor.map_or_else(sensors::default_sensor, |(s, _)| s),
        shapes,
        bsdfs: ctx.bsdfs,
        emitters,
        media: ctx.media,
    };
    desc.check(&|s| places.name(s))
        .map_err(|e| places.error(e))?;
    Ok(desc)
}

/// Where each object of the description was written, to place the
/// validator's messages: at the parameter the rule is about when the
/// plugin's element (or one nested in it) gives it, else at the plugin.
struct Places<'a> {
    source: &'a str,
    integrator: Option<&'a XNode>,
    sensor: Option<&'a XNode>,
    shapes: Vec<&'a XNode>,
    /// `None` for the default BSDFs.
    bsdfs: Vec<Option<&'a XNode>>,
    emitters: Vec<&'a XNode>,
    media: Vec<&'a XNode>,
}

impl<'a> Places<'a> {
    fn node(&self, s: Subject) -> Option<&'a XNode> {
        match s {
            Subject::Integrator => self.integrator,
            Subject::Sensor => self.sensor,
            Subject::Shape(i) => self.shapes.get(i).copied(),
            Subject::Bsdf(i) => self.bsdfs.get(i).copied().flatten(),
            Subject::Emitter(i) => self.emitters.get(i).copied(),
            Subject::Medium(i) => self.media.get(i).copied(),
        }
    }

    /// An object named in another one's message: `<medium type="fgf"> at scene.xml:12`.
    fn name(&self, s: Subject) -> String {
        match self.node(s) {
            Some(n) => format!("{} at {}:{}", n.label(), n.file.display(), n.line),
            None => format!("{s:?}"),
        }
    }

    fn error(&self, e: Invalid) -> SceneError {
        match self.node(e.subject) {
            Some(n) => {
                let at = e
                    .param
                    .as_deref()
                    .and_then(|p| find_param(n, p))
                    .unwrap_or(n);
                at.err(e.message)
            }
            // Only Mitsuba's default integrator can break a rule (with media).
            None if e.subject == Subject::Integrator => SceneError::new(
                SceneErrorKind::Invalid,
                self.source,
                format!(
                    "the scene has no <integrator>, so it gets Mitsuba's default 'path': {}",
                    e.message
                ),
            ),
            None => SceneError::new(SceneErrorKind::Invalid, self.source, e.message),
        }
    }
}

/// The element inside `n` that sets parameter `name`: a child of `n`, else
/// (for a sensor's film and sampler, a shape's emitter, a medium's volumes)
/// the first one deeper down.
fn find_param<'a>(n: &'a XNode, name: &str) -> Option<&'a XNode> {
    n.children
        .iter()
        .find(|c| c.attr("name") == Some(name))
        .or_else(|| n.children.iter().find_map(|c| find_param(c, name)))
}
