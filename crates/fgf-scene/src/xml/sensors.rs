//! `<sensor type="perspective">` with its nested `<film type="hdrfilm">`,
//! `<sampler type="independent">` and the film's `<rfilter>` (`box`: a
//! pixel-wide box; `gaussian`, the default; `tent`). A scene without a
//! `<sensor>` gets Mitsuba's default camera: at the origin looking down +z,
//! 768 × 576 pixels, 50 mm focal length, 4 samples per pixel. The camera
//! looks down its local +z with local +y up (what `lookat` builds).
//!
//! | plugin | parameter | type | units | range | default | meaning |
//! |---|---|---|---|---|---|---|
//! | `perspective` | `fov` | float | degrees | 0 < fov < 180 | from `focal_length` | field of view along `fov_axis` |
//! | `perspective` | `focal_length` | string | mm | > 0, written `"50mm"` | `"50mm"` | 35 mm film equivalent, converted through the film diagonal to the x field of view, as Mitsuba does; not together with `fov` or `fov_axis` |
//! | `perspective` | `fov_axis` | string | – | `x`, `y`, `smaller`, `larger` | `x` | the film axis `fov` applies to |
//! | `perspective` | `near_clip`, `far_clip` | float | length | 0 < near_clip < far_clip | 0.01, 10000 | |
//! | `perspective` | `to_world` | transform | – | rigid (rotation and translation) | identity | camera to world |
//! | `perspective` | `principal_point_offset_x`, `principal_point_offset_y` | float | film width, height | finite | 0 | the optical axis's offset from the film centre as a fraction of the film (x to the right, y down), as in Mitsuba: the image shifts by that fraction |
//! | `perspective` | `focus_distance` | float | length | > 0 | `far_clip` | accepted: Mitsuba's `perspective` is a pinhole, so it has no effect (it matters to `thinlens`, which is not supported) |
//! | `independent`, `stratified`, `multijitter`, `orthogonal`, `ldsampler` | `sample_count` | integer | – | 1 … 2³²−1 | 4 | samples per pixel, rounded up as Mitsuba rounds it: `stratified` to a square, `multijitter` to `⌊√n⌋·⌈n/⌊√n⌋⌉`, `orthogonal` to the square of a prime, `ldsampler` to the square of a power of two (at least 4) |
//! | `stratified`, `multijitter`, `orthogonal` | `jitter` | boolean | – | – | true | accepted; `orthogonal`'s `strength` too |
//! | `perspective` | nested `medium` | – | – | at most one | none | the medium the camera sits in |
//! | all samplers | `seed` | integer | – | ≥ 0 | 0 | |
//!
//! **Samplers.** Every sampler type renders with fgf's independent
//! sampler: Mitsuba's stratified and low-discrepancy samplers change the
//! noise, not the expected image, so the image agrees with Mitsuba's within
//! the standard error at the same (rounded) sample count.
//! | `hdrfilm` | `width`, `height` | integer | pixels | 1 … 65536, at most 2²⁶ pixels in all | 768, 576 | |
//! | `hdrfilm` | `pixel_format` | string | – | `rgb`, `rgba` | `rgb` | the output is RGB either way |
//! | `hdrfilm` | `component_format`, `file_format` | string | – | Mitsuba's | – | accepted and ignored: the output is float32 EXR; `crop_*` (cropping) is refused |
//! | `gaussian` | `stddev` | float | pixels | 0 < stddev ≤ 64 | 0.5 | support 4 · stddev |
//! | `tent` | `radius` | float | pixels | 0 < radius ≤ 256 | 1 | |
//!
//! ```xml
//! <default name="res" value="256"/>
//! <sensor type="perspective">
//!     <float name="fov" value="40"/>
//!     <transform name="to_world">
//!         <lookat origin="0, 1, -6" target="0, 0, 0" up="0, 1, 0"/>
//!     </transform>
//!     <sampler type="independent"><integer name="sample_count" value="64"/></sampler>
//!     <film type="hdrfilm">
//!         <integer name="width" value="$res"/>
//!         <integer name="height" value="$res"/>
//!         <rfilter type="tent"/>
//!     </film>
//! </sensor>
//! ```
//!
//! ```python
//! import fgf
//! # spp and seed override sample_count and seed; res is the scene's <default>.
//! img = fgf.render("scene.xml", spp=16, seed=1, defines={"res": 64})  # (64, 64, 3)
//! ```

use super::context::{check_object_attrs, plugin_type, to_mat4, Ctx};
use super::document::XNode;
use super::media;
use super::props::{check, check_if, Props};
use crate::desc::*;
use crate::error::SceneError;
use crate::validate::{
    film_too_large, is_rigid, Range, FAR_CLIP, FILM_SIDE, FOV, GAUSSIAN_STDDEV, MAX_FILM_PIXELS,
    NEAR_CLIP, NOT_RIGID, SAMPLE_COUNT, TENT_RADIUS,
};
use glam::Mat4;

/// A focal length in mm (only the loader sees it: the description holds
/// the field of view).
const FOCAL_LENGTH: Range<f64> = Range {
    ok: |v| v > 0.0,
    text: "> 0 mm, e.g. \"50mm\"",
};
/// Mitsuba's `focus_distance` (which a pinhole ignores).
const FOCUS_DISTANCE: Range<f64> = Range {
    ok: |v| v > 0.0,
    text: "> 0",
};
/// Mitsuba's sampler plugins; all render as the independent sampler.
const SAMPLERS: &[&str] = &[
    "independent",
    "stratified",
    "multijitter",
    "orthogonal",
    "ldsampler",
];
/// The sampler's seed (the description holds it as a u64).
const SEED: Range<i64> = Range {
    ok: |v| v >= 0,
    text: "seed >= 0",
};

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

pub(crate) fn default_sensor() -> SensorDesc {
    let (width, height) = (768, 576);
    SensorDesc {
        to_world: Mat4::IDENTITY,
        fov: fov_from_focal_length(50.0, width, height) as f32,
        fov_axis: FovAxis::X,
        principal_point: [0.0, 0.0],
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

pub(crate) fn sensor_desc<'a>(ctx: &mut Ctx<'a>, n: &'a XNode) -> Result<SensorDesc, SceneError> {
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
            "principal_point_offset_x",
            "principal_point_offset_y",
            "focus_distance",
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
        (Some((v, node)), None) => {
            let written = node.attr("value").unwrap_or("?");
            let fov = check(node, "fov", v, FOV)? as f32;
            // The description stores single precision: a value just below
            // 180 (or above 0) may round onto the open range's end.
            if !(FOV.ok)(fov as f64) {
                return Err(node.err(format!(
                    "invalid fov = '{}': it rounds to {fov} in single precision (valid: {})",
                    crate::error::clip(written),
                    FOV.text
                )));
            }
            fov
        }
        (None, Some((text, node))) => {
            let num = text.trim().strip_suffix("mm").unwrap_or(text).trim();
            let f = super::parse::parse_f64(node, "focal_length", num)?;
            check(node, "focal_length", f, FOCAL_LENGTH)?;
            s.fov_axis = FovAxis::X;
            let fov = fov_from_focal_length(f, s.width, s.height) as f32;
            if !(FOV.ok)(fov as f64) {
                return Err(node.err(format!(
                    "focal_length = '{}' gives a field of view of {fov} degrees in single precision (valid: {})",
                    crate::error::clip(text),
                    FOV.text
                )));
            }
            fov
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
    let near = p.float_in("near_clip", 0.01, NEAR_CLIP)?;
    let far = match p.float("far_clip")? {
        None => 10_000.0,
        Some((v, node)) => check_if(node, "far_clip", v, v > near, FAR_CLIP)?,
    };
    s.near_clip = near as f32;
    s.far_clip = far as f32;
    s.principal_point = [
        p.float("principal_point_offset_x")?
            .map_or(0.0, |(v, _)| v as f32),
        p.float("principal_point_offset_y")?
            .map_or(0.0, |(v, _)| v as f32),
    ];
    // A pinhole camera has no focus: accepted (and range-checked) only.
    p.float_in("focus_distance", far, FOCUS_DISTANCE)?;
    if let Some((m, node)) = p.transform("to_world")? {
        // Mitsuba refuses scale in a camera transform.
        if !is_rigid(&m) {
            return Err(node.err(NOT_RIGID));
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
    let ty = plugin_type(n, "sampler", SAMPLERS)?;
    let known: &'static [&'static str] = match ty {
        "stratified" | "multijitter" => &["sample_count", "seed", "jitter"],
        "orthogonal" => &["sample_count", "seed", "jitter", "strength"],
        _ => &["sample_count", "seed"],
    };
    let p = Props::new(n, &ctx.ids, known)?;
    let spp = p.int_in("sample_count", 4, SAMPLE_COUNT)? as u64;
    s.spp = rounded_sample_count(ty, spp).min(u32::MAX as u64) as u32;
    s.seed = p.int_in("seed", 0, SEED)? as u64;
    p.bool_or("jitter", true)?;
    if let Some((v, node)) = p.int("strength")? {
        if v < 2 {
            return Err(node.err(format!(
                "parameter 'strength' = {v} is out of range (valid: >= 2)"
            )));
        }
    }
    p.finish()
}

/// The sample count Mitsuba's sampler `ty` uses when asked for `n`.
fn rounded_sample_count(ty: &str, n: u64) -> u64 {
    match ty {
        "stratified" => {
            let mut r = 1u64;
            while r * r < n {
                r += 1;
            }
            r * r
        }
        "multijitter" => {
            let r1 = ((n as f64).sqrt() as u64).max(1);
            let r0 = n.div_ceil(r1);
            r0 * r1
        }
        "orthogonal" => {
            let is_prime = |p: u64| p >= 2 && (2..).take_while(|d| d * d <= p).all(|d| p % d != 0);
            let mut r = 2u64;
            while r * r < n || !is_prime(r) {
                r += 1;
            }
            r * r
        }
        "ldsampler" => {
            let mut r = 2u64;
            while r * r < n {
                r = (r + 1).next_power_of_two();
            }
            r * r
        }
        _ => n,
    }
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
    let w = p.int_in("width", 768, FILM_SIDE)?;
    let h = p.int_in("height", 576, FILM_SIDE)?;
    if w * h > MAX_FILM_PIXELS {
        return Err(n.err(film_too_large(w, h)));
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
            stddev: p.float_in("stddev", 0.5, GAUSSIAN_STDDEV)? as f32,
        },
        "tent" => FilterDesc::Tent {
            radius: p.float_in("radius", 1.0, TENT_RADIUS)? as f32,
        },
        _ => FilterDesc::Box,
    };
    p.finish()?;
    Ok(f)
}
