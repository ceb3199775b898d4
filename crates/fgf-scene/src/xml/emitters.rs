//! `<emitter>`: `area` (nested in the `<shape>` that emits; it emits toward
//! the side its normal points to: on a mesh with vertex normals, the
//! interpolated shading normal, as in Mitsuba 3), and at the top level `point`, `spot`,
//! `directional`, `constant` (a uniform environment) and `envmap` (an image
//! of the environment; at most one environment emitter). Every
//! colour is `≥ 0` in each channel; radiometric units are described in
//! [`super`].
//!
//! | plugin | parameter | type | units | range | default | meaning |
//! |---|---|---|---|---|---|---|
//! | `area`, `constant` | `radiance` | float or rgb | power/(length² sr) | ≥ 0 | 1 | |
//! | `area` | `radiance` | `checkerboard` or `bitmap` texture | power/(length² sr) | ≥ 0 | – | on a `rectangle`, `disk` or `sphere` only: the texture at the emitting point's texture coordinates (seen directly and in light sampling; [`super::textures`]) |
//! | `point` | `intensity` | float or rgb | power/sr | ≥ 0 | 1 | |
//! | `point` | `position` or `to_world` | point or transform | length | – | the origin | the light's position (the translation of `to_world`); not both |
//! | `spot` | `intensity` | float or rgb | power/sr | ≥ 0 | 1 | on the axis |
//! | `spot` | `to_world` | transform | – | invertible | identity | the spot shines down its local +z |
//! | `spot` | `cutoff_angle` | float | degrees | 0 < cutoff_angle < 180 | 20 | no light beyond it |
//! | `spot` | `beam_width` | float | degrees | 0 ≤ beam_width ≤ cutoff_angle | 0.75 · cutoff_angle | full intensity within it, then falling linearly in the angle to 0 at `cutoff_angle` |
//! | `directional` | `irradiance` | float or rgb | power/length² | ≥ 0 | 1 | on a surface facing the light |
//! | `directional` | `direction` or `to_world` | vector or transform | – | a nonzero vector | +z (the local +z of `to_world`) | the direction the light travels in; not both |
//! | `envmap` | `filename` | string | – | an OpenEXR (`.exr`) or Radiance RGBE (`.hdr`) latitude–longitude image of at least 2x3 pixels, relative to the scene file | required | linear RGB radiance; the top row is local +y, `u = atan2(x, -z)/2π` |
//! | `envmap` | `scale` | float | – | ≥ 0 | 1 | multiplies the image |
//! | `envmap` | `to_world` | transform | – | invertible | identity | orients the map (usually a rotation) |
//!
//! ```xml
//! <emitter type="spot">
//!     <rgb name="intensity" value="$power"/>
//!     <float name="cutoff_angle" value="30"/>
//!     <transform name="to_world">
//!         <lookat origin="0, 4, 0" target="0, 0, 0" up="0, 0, 1"/>
//!     </transform>
//! </emitter>
//! <shape type="rectangle">
//!     <emitter type="area"><rgb name="radiance" value="10"/></emitter>
//! </shape>
//! <shape type="disk">
//!     <emitter type="area">
//!         <texture type="bitmap" name="radiance">
//!             <string name="filename" value="textures/window.exr"/>
//!         </texture>
//!     </emitter>
//! </shape>
//! <emitter type="envmap">
//!     <string name="filename" value="sky.exr"/>
//!     <float name="scale" value="0.5"/>
//!     <transform name="to_world"><rotate y="1" angle="90"/></transform>
//! </emitter>
//! <default name="power" value="50"/>
//! ```
//!
//! ```python
//! import fgf
//! img = fgf.render("scene.xml", defines={"power": 200})
//! ```

use super::context::{check_object_attrs, plugin_type, rgb, to_invertible_mat4, to_mat4, Ctx};
use super::document::XNode;
use super::props::{check_if, Props};
use super::textures::{self, ColorOrTexture};
use crate::desc::*;
use crate::error::SceneError;
use crate::validate::{BEAM_WIDTH, CUTOFF_ANGLE, NON_NEGATIVE, SCALE};
use glam::{DVec3, Mat4, Vec3};

pub(crate) fn emitter_desc<'a>(
    ctx: &mut Ctx<'a>,
    n: &'a XNode,
    on_shape: bool,
) -> Result<EmitterDesc, SceneError> {
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
            &["area", "point", "spot", "directional", "constant", "envmap"],
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
        "envmap" => &["filename", "scale", "to_world"],
        _ => &["irradiance", "direction", "to_world"],
    };
    let p = Props::new(n, &ctx.ids, known)?;
    let d = match ty {
        "area" => match p.peek("radiance").filter(|e| e.target.tag == "texture") {
            Some(_) => {
                match textures::color_or_texture(ctx, &p, "radiance", [1.0; 3], NON_NEGATIVE)? {
                    ColorOrTexture::Texture(t) => EmitterDesc::Area {
                        radiance: [t.mean(); 3],
                        texture: Some(t),
                    },
                    ColorOrTexture::Color(c) => EmitterDesc::Area {
                        radiance: rgb(c),
                        texture: None,
                    },
                }
            }
            None => EmitterDesc::Area {
                radiance: rgb(p.color_in("radiance", [1.0; 3], NON_NEGATIVE)?),
                texture: None,
            },
        },
        "constant" => EmitterDesc::Constant {
            radiance: rgb(p.color_in("radiance", [1.0; 3], NON_NEGATIVE)?),
        },
        "envmap" => {
            let (file, fnode) = p.string("filename")?.ok_or_else(|| {
                n.err("missing required parameter 'filename' (a lat-long .exr or .hdr image, relative to the scene file)")
            })?;
            let path = fnode.resolve(file);
            let ext = path
                .extension()
                .and_then(|e| e.to_str())
                .map(|e| e.to_ascii_lowercase());
            let read = match ext.as_deref() {
                Some("exr") => fgf_io::image::read_exr_rgb(&path),
                Some("hdr") | Some("rgbe") | Some("pic") => fgf_io::image::read_hdr_rgb(&path),
                _ => {
                    return Err(fnode.err(format!(
                        "envmap image '{file}': only OpenEXR (.exr) and Radiance RGBE (.hdr) images are supported"
                    )))
                }
            };
            let (width, height, mut data) =
                read.map_err(|e| fnode.err(format!("cannot read envmap image: {e}")))?;
            if width < 2 || height < 3 {
                return Err(fnode.err(format!(
                    "envmap image '{file}' is {width}x{height}; it must be at least 2x3 pixels"
                )));
            }
            if let Some(bad) = data.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
                return Err(fnode.err(format!(
                    "envmap image '{file}' has a pixel value {bad} (valid: finite and >= 0)"
                )));
            }
            let scale = p.float_in("scale", 1.0, SCALE)? as f32;
            data.iter_mut().for_each(|v| *v *= scale);
            let to_world = match p.transform("to_world")? {
                Some((m, node)) => to_invertible_mat4(node, m)?,
                None => Mat4::IDENTITY,
            };
            EmitterDesc::Envmap {
                image: std::sync::Arc::new(RgbImage {
                    width,
                    height,
                    data,
                }),
                to_world,
            }
        }
        "point" => {
            let intensity = rgb(p.color_in("intensity", [1.0; 3], NON_NEGATIVE)?);
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
            let intensity = rgb(p.color_in("intensity", [1.0; 3], NON_NEGATIVE)?);
            let to_world = match p.transform("to_world")? {
                Some((m, node)) => to_invertible_mat4(node, m)?,
                None => Mat4::IDENTITY,
            };
            let cutoff = p.float_in("cutoff_angle", 20.0, CUTOFF_ANGLE)?;
            let beam = match p.float("beam_width")? {
                None => 0.75 * cutoff,
                Some((v, node)) => {
                    check_if(node, "beam_width", v, v >= 0.0 && v <= cutoff, BEAM_WIDTH)?
                }
            };
            EmitterDesc::Spot {
                to_world,
                intensity,
                cutoff_angle: cutoff as f32,
                beam_width: beam as f32,
            }
        }
        _ => {
            let irradiance = rgb(p.color_in("irradiance", [1.0; 3], NON_NEGATIVE)?);
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
