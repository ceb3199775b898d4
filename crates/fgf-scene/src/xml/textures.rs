//! `<texture>`: 2D textures for BSDF parameters, looked up at a surface
//! point's texture coordinates `(u, v)` (each shape's parameterisation is
//! Mitsuba 3's: see [`super::shapes`]). `checkerboard` alternates two
//! colours; `bitmap` reads an image. A texture is written inside the BSDF
//! with the parameter's `name`, or at the top level with an `id` and used by
//! `<ref name="..." id="..."/>` (one texture may serve several BSDFs).
//!
//! | plugin | parameter | type | units | range | default | meaning |
//! |---|---|---|---|---|---|---|
//! | both | `to_uv` | transform | – | finite | identity | maps `(u, v)` before the lookup: the upper-left 2×2 block and the x, y translation of the 4×4 transform (`<scale x="8" y="8"/>` repeats a texture 8 times) |
//! | `checkerboard` | `color0`, `color1` | float or rgb | – | the parameter's range | 0.4, 0.2 | `color0` where the fractional parts of `u` and `v` are both below 1/2 or both above, else `color1` |
//! | `bitmap` | `filename` | string | – | a PNG (`.png`, 1–16 bits, grey or colour; alpha is ignored), OpenEXR (`.exr`) or Radiance (`.hdr`) image of at most 2^25 pixels, found like every file | required | the top row is `v = 0`, the left column `u = 0` |
//! | `bitmap` | `raw` | boolean | – | – | false | false: a PNG's values (`v/255`, or `v/65535` for 16 bits) are sRGB-encoded and turned into linear values, whatever the file's gAMA, sRGB or iCCP chunk says (as Mitsuba does); true: used as stored. A 16-bit PNG's texels are then rounded to half precision, as Mitsuba stores them. EXR and HDR images are linear either way |
//! | `bitmap` | `filter_type` | string | – | `bilinear`, `nearest` | `bilinear` | bilinear interpolation between pixel centres, or the pixel containing `(u, v)` |
//! | `bitmap` | `wrap_mode` | string | – | `repeat`, `mirror`, `clamp` | `repeat` | lookups outside `[0, 1)²` (also the neighbours of a bilinear lookup near an edge) |
//!
//! Where a texture may stand (as in Mitsuba 3.9): `diffuse`'s
//! `reflectance`; `specular_reflectance` of `dielectric`, `thindielectric`,
//! `roughdielectric`, `conductor`, `roughconductor` and `plastic`;
//! `specular_transmittance` of the dielectrics; `plastic`'s
//! `diffuse_reflectance`; `mask`'s `opacity`; `eta` and `k` of `conductor` and
//! `roughconductor` (values ≥ 0; the Fresnel term per channel of the
//! texture's value at the hit; Mitsuba 3.9.1 itself refuses checkerboard
//! colours above 1 there, as it reads them as reflectances); and `alpha`, `alpha_u`, `alpha_v` of
//! `roughconductor` and `roughdielectric` (the roughness, or opacity, is then the mean of
//! a checkerboard colour's channels — of `color1` where the colour would be
//! `color0`, as Mitsuba 3.9.1 does — or the luminance of a bitmap's value;
//! the whole texture must lie in the `alpha` range). Values must lie in the
//! parameter's range everywhere (reflectances in [0, 1]).
//!
//! An `area` emitter's `radiance` may also be a texture (values ≥ 0), on a
//! `rectangle`, `disk` or `sphere` ([`super::emitters`]): the emitted
//! radiance is the texture at the emitting point's `(u, v)`, for hits and
//! for light sampling. Mitsuba samples such an emitter through the texture
//! (a checkerboard uniformly in `(u, v)`, a bitmap by its pixel values)
//! mapped by the shape's `(u, v)` parameterisation; fgf samples by area:
//! the same expectation on these three shapes, whose `(u, v)` cover them
//! once. On a `cube` (six faces on one `(u, v)` square) or a mesh (covered
//! as its texture coordinates are) Mitsuba's light sampling is not that
//! estimator, so fgf refuses a textured emitter there.
//!
//! fgf refuses, in one line naming the feature: textures nested in a
//! `checkerboard`, and the texture plugins fgf lacks (`mesh_attribute`,
//! `volume`, ...).
//!
//! `plastic` chooses between its lobes with the texture's mean, as Mitsuba:
//! the mean of a checkerboard's two colours, the mean luminance of a bitmap.
//!
//! ```xml
//! <texture type="checkerboard" id="floor">
//!     <rgb name="color0" value="0.2"/>
//!     <rgb name="color1" value="0.4"/>
//!     <transform name="to_uv"><scale x="8" y="8"/></transform>
//! </texture>
//! <bsdf type="diffuse" id="floor-bsdf"><ref name="reflectance" id="floor"/></bsdf>
//! <bsdf type="plastic">
//!     <texture type="bitmap" name="diffuse_reflectance">
//!         <string name="filename" value="textures/wood.png"/>
//!         <string name="wrap_mode" value="mirror"/>
//!     </texture>
//! </bsdf>
//! ```
//!
//! ```python
//! import fgf
//! img = fgf.render("scene.xml", spp=64)  # the textures are part of the scene file
//! ```

use super::context::{check_object_attrs, plugin_type, rgb, Ctx};
use super::document::XNode;
use super::props::{check_rgb, Entry, Props};
use crate::desc::*;
use crate::error::SceneError;
use crate::validate::Range;
use glam::{Affine2, Mat2, Vec2};
use std::sync::Arc;

const TEXTURES: &[&str] = &["checkerboard", "bitmap"];

/// A parameter that is a constant colour or a texture.
pub(crate) enum ColorOrTexture {
    Color([f64; 3]),
    Texture(TextureDesc),
}

/// The parameter `name`: a colour (default `default`) or a `<texture>`
/// (nested or by `<ref>`), its values checked against `r`.
pub(crate) fn color_or_texture<'a>(
    ctx: &mut Ctx<'a>,
    p: &Props<'a>,
    name: &str,
    default: [f64; 3],
    r: Range<f64>,
) -> Result<ColorOrTexture, SceneError> {
    match p.take(name) {
        None => Ok(ColorOrTexture::Color(default)),
        Some(e) if e.target.tag == "texture" => {
            let t = texture(ctx, e)?;
            let (lo, hi) = t.range();
            for v in [lo, hi] {
                if !(r.ok)(v as f64) {
                    return Err(e.node.err(format!(
                        "the texture for '{name}' has a value {v}, outside the parameter's range ({})",
                        r.text
                    )));
                }
            }
            Ok(ColorOrTexture::Texture(t))
        }
        Some(e) => Ok(ColorOrTexture::Color(check_rgb(
            e.node,
            name,
            e.color()?,
            r,
        )?)),
    }
}

/// The texture of an entry (nested or referenced), shared by id.
fn texture<'a>(ctx: &mut Ctx<'a>, e: &Entry<'a>) -> Result<TextureDesc, SceneError> {
    texture_node(ctx, e.target)
}

/// Instantiate a `<texture>` (a top-level one with an id once, then shared).
pub(crate) fn texture_node<'a>(ctx: &mut Ctx<'a>, n: &'a XNode) -> Result<TextureDesc, SceneError> {
    if let Some(id) = n.attr("id") {
        if let Some(t) = ctx.texture_by_id.get(id) {
            return Ok(t.clone());
        }
    }
    let t = texture_desc(ctx, n)?;
    if let Some(id) = n.attr("id") {
        ctx.texture_by_id.insert(id.to_string(), t.clone());
    }
    Ok(t)
}

/// Mitsuba's reading of a 4×4 `to_uv`: the 2×2 linear block and the x, y
/// translation.
fn to_uv(p: &Props) -> Result<Affine2, SceneError> {
    Ok(match p.transform("to_uv")? {
        None => Affine2::IDENTITY,
        Some((m, node)) => {
            let a = Affine2::from_mat2_translation(
                Mat2::from_cols(
                    Vec2::new(m.x_axis.x as f32, m.x_axis.y as f32),
                    Vec2::new(m.y_axis.x as f32, m.y_axis.y as f32),
                ),
                Vec2::new(m.w_axis.x as f32, m.w_axis.y as f32),
            );
            if !a.is_finite() {
                return Err(node.err("to_uv has entries that overflow single precision"));
            }
            a
        }
    })
}

fn texture_desc<'a>(ctx: &Ctx<'a>, n: &'a XNode) -> Result<TextureDesc, SceneError> {
    check_object_attrs(n)?;
    let ty = match n.attr("type") {
        Some(t) if !TEXTURES.contains(&t) => {
            return Err(n.err(format!(
                "texture type '{t}' is not supported (supported: {})",
                TEXTURES.join(", ")
            )))
        }
        _ => plugin_type(n, "texture", TEXTURES)?,
    };
    let ids = &ctx.ids;
    let d = match ty {
        "checkerboard" => {
            let p = Props::new(n, ids, &["color0", "color1", "to_uv"])?;
            let color = |name: &str, default: f64| -> Result<Rgb, SceneError> {
                match p.take(name) {
                    None => Ok([default as f32; 3]),
                    Some(e) if e.target.tag == "texture" => Err(e.node.err(format!(
                        "a texture as a checkerboard's '{name}' is not supported; give a colour"
                    ))),
                    Some(e) => {
                        let c = e.color()?;
                        if c.iter().any(|v| !v.is_finite()) {
                            return Err(e.node.err(format!("'{name}' must be finite")));
                        }
                        Ok(rgb(c))
                    }
                }
            };
            let d = TextureDesc::Checkerboard {
                color0: color("color0", 0.4)?,
                color1: color("color1", 0.2)?,
                to_uv: to_uv(&p)?,
            };
            p.finish()?;
            d
        }
        _ => {
            let p = Props::new(
                n,
                ids,
                &["filename", "raw", "filter_type", "wrap_mode", "to_uv"],
            )?;
            let (file, fnode) = p.string("filename")?.ok_or_else(|| {
                n.err("missing required parameter 'filename' (a .png, .exr or .hdr image, relative to the scene file)")
            })?;
            let raw = p.bool_or("raw", false)?;
            let filter = match p
                .choice("filter_type", "bilinear", &["bilinear", "nearest"])?
                .as_str()
            {
                "nearest" => BitmapFilter::Nearest,
                _ => BitmapFilter::Bilinear,
            };
            let wrap = WrapMode::parse(&p.choice(
                "wrap_mode",
                "repeat",
                &["repeat", "mirror", "clamp"],
            )?)
            .unwrap_or(WrapMode::Repeat);
            let to_uv = to_uv(&p)?;
            let image = read_bitmap(fnode, file, raw)?;
            p.finish()?;
            TextureDesc::Bitmap {
                image: Arc::new(image),
                filter,
                wrap,
                to_uv,
            }
        }
    };
    Ok(d)
}

/// A bitmap's image as linear RGB (PNG decoded from sRGB unless `raw`).
/// As Mitsuba 3.9.1's `bitmap` (its default storage format, `auto`), a
/// 16-bit PNG's texels, once linear, are kept in half precision: rounded to
/// the nearest IEEE half (a relative step of 2⁻¹¹), so that fgf's texture
/// has Mitsuba's values, not the file's exact ones.
fn read_bitmap(fnode: &XNode, file: &str, raw: bool) -> Result<RgbImage, SceneError> {
    let path = fnode.resolve(file);
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    let with_depth =
        |r: Result<(usize, usize, Vec<f32>), fgf_io::IoError>| r.map(|(w, h, d)| (w, h, d, 32u8));
    let (read, srgb) = match ext.as_deref() {
        Some("png") => (fgf_io::image::read_png_rgb(&path), !raw),
        Some("exr") => (with_depth(fgf_io::image::read_exr_rgb(&path)), false),
        Some("hdr") | Some("rgbe") | Some("pic") => (with_depth(fgf_io::image::read_hdr_rgb(&path)), false),
        _ => {
            return Err(fnode.err(format!(
                "bitmap image '{}': only PNG (.png), OpenEXR (.exr) and Radiance RGBE (.hdr) images are supported",
                crate::error::clip(file)
            )))
        }
    };
    let (width, height, mut data, depth) =
        read.map_err(|e| fnode.err(format!("cannot read bitmap image: {e}")))?;
    if let Some(bad) = data.iter().find(|v| !v.is_finite()) {
        return Err(fnode.err(format!(
            "bitmap image '{}' has a pixel value {bad} (valid: finite)",
            crate::error::clip(file)
        )));
    }
    if srgb {
        data.iter_mut()
            .for_each(|v| *v = fgf_io::image::srgb_decode(*v));
    }
    if depth == 16 {
        data.iter_mut()
            .for_each(|v| *v = half::f16::from_f32(*v).to_f32());
    }
    Ok(RgbImage {
        width,
        height,
        data,
    })
}
