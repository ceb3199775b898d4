//! `<bsdf>`: `diffuse` (Lambertian, one-sided: black seen from the back),
//! `null` (an index-matched boundary that paths cross unchanged, for media
//! boundaries), `dielectric` (smooth), `thindielectric` (a thin smooth slab:
//! reflects and passes straight through), `roughdielectric`, `conductor` (a
//! smooth metal), `roughconductor`, `plastic` (a diffuse base under a
//! dielectric coating, Mitsuba 3's model), `roughplastic` (the same under a
//! rough coating), `twosided` (the nested BSDF on both sides), `mask`
//! (the nested BSDF where the surface is opaque, a straight-through
//! crossing elsewhere: cut-out leaves, fences) and `principled` (Mitsuba 3's
//! Disney-style BSDF: diffuse with retro-reflection and sheen, a GGX
//! specular lobe blending dielectric and metal, rough transmission and a
//! clearcoat; formulas in `crates/fgf-render/src/bsdf/principled.rs`). The rough plugins use a microfacet
//! distribution (Walter et al. 2007) sampled through its visible normals
//! (Heitz 2018) unless `sample_visible` is false. A colour parameter, and
//! a rough plugin's `alpha` (`alpha_u`, `alpha_v`), may be a `checkerboard` or `bitmap` texture
//! where Mitsuba 3 allows one (which parameters, and how: [`super::textures`]).
//! Anisotropic roughness follows Mitsuba's shading frame: `alpha_u` along
//! the surface tangent `∂p/∂u` (each shape's parameterisation, see
//! `fgf_render::geometry::frame`), `alpha_v` across it.
//! `principled`'s `anisotropic` uses the same frame. `principledthin` is refused with a message naming it. A `<bsdf>` at the top level
//! with an `id` can be shared by `<ref id="..."/>`. The default BSDF of a
//! shape is described in [`super::shapes`].
//!
//! | plugin | parameter | type | units | range | default | meaning |
//! |---|---|---|---|---|---|---|
//! | `diffuse` | `reflectance` | float, rgb or texture | – | in [0, 1] | 0.5 | |
//! | `dielectric` | `int_ior`, `ext_ior` | float or string | – | a number > 0 or a name of Mitsuba's table (`"water"`, `"bk7"`, `"diamond"`, ...) | `"bk7"` (1.5046), `"air"` (1.000277) | index of refraction inside and outside |
//! | `dielectric` | `specular_reflectance`, `specular_transmittance` | float, rgb or texture | – | in [0, 1] | 1, 1 | |
//! | `conductor` | `material` | string | – | `"none"` or a name of Mitsuba's table (`"Au"`, `"Ag"`, `"Cu"`, `"Al"`, ...) | `"none"` | `"none"` is a perfect mirror; not together with `eta`, `k` |
//! | `conductor` | `eta`, `k` | float, rgb or texture | – | ≥ 0 | 0, 1 (a perfect mirror) | complex index of refraction `eta + i k` |
//! | `conductor` | `specular_reflectance` | float, rgb or texture | – | in [0, 1] | 1 | |
//! | `thindielectric` | `int_ior`, `ext_ior`, `specular_reflectance`, `specular_transmittance` | as `dielectric` | | | as `dielectric` | reflectance `2R/(1+R)` of the two faces; the rest is transmitted undeviated |
//! | `roughdielectric` | `int_ior`, `ext_ior`, `specular_reflectance`, `specular_transmittance` | as `dielectric` | | | as `dielectric` | |
//! | `roughconductor` | `material`, `eta`, `k`, `specular_reflectance` | as `conductor` | | | as `conductor` | |
//! | rough plugins | `distribution` | string | – | `"beckmann"`, `"ggx"` | `"beckmann"` | microfacet normal distribution |
//! | rough plugins | `alpha` | float, or texture (`roughconductor`, `roughdielectric`) | – | 1e-4 ≤ alpha ≤ 4 | 0.1 | roughness (Beckmann: RMS slope) |
//! | `roughconductor`, `roughdielectric` | `alpha_u`, `alpha_v` | float or texture | – | 1e-4 ≤ alpha ≤ 4 | – | instead of `alpha` (both or neither): anisotropic roughness along the surface tangent `∂p/∂u` and across it |
//! | rough plugins | `sample_visible` | boolean | – | – | true | sample only the normals visible from the incident direction |
//! | `plastic`, `roughplastic` | `int_ior`, `ext_ior` | float or string | – | as `dielectric`, not equal | `"polypropylene"` (1.49), `"air"` | the coating's indices |
//! | `plastic`, `roughplastic` | `diffuse_reflectance` | float, rgb or texture | – | in [0, 1] | 0.5 | the base |
//! | `plastic`, `roughplastic` | `specular_reflectance` | float, rgb or texture | – | in [0, 1] | 1 | scales the coating's reflection |
//! | `plastic`, `roughplastic` | `nonlinear` | boolean | – | – | false | account for the colour shift of internal scattering (`ρ/(1 - ρ F_int)` instead of `ρ/(1 - F_int)`) |
//! | `twosided` | nested `bsdf` | – | – | one, not `twosided` or `mask` | required | |
//! | `mask` | `opacity` | float or texture | – | in [0, 1] | 0.5 | the probability that a path scatters off the nested BSDF; otherwise it goes straight through (a `Null` interaction: under `volpath`/`volpathmis` it costs no depth and shadow rays pass with weight `1 − opacity`; under `path` a bounce, and shadow rays stop there, as in Mitsuba). A texture is read as a textured `alpha` ([`super::textures`]) |
//! | `mask` | nested `bsdf` | – | – | one (a `twosided` one for a surface seen from both sides) | required | |
//! | `principled` | `base_color` | float, rgb or texture | – | in [0, 1] | 0.5 | the diffuse colour, the metal's reflectance at normal incidence, the tint of `spec_tint`/`sheen_tint` and (as `√base_color`) of the transmission |
//! | `principled` | `roughness` | float or texture | – | in [0, 1] | 0.5 | GGX `α = max(0.001, roughness²)` of the main lobes (see `anisotropic`); also scales the diffuse retro-reflection |
//! | `principled` | `metallic` | float or texture | – | in [0, 1] | 0 | blends toward a Schlick metal of reflectance `base_color` (no diffuse, sheen or transmission) |
//! | `principled` | `spec_trans` | float or texture | – | in [0, 1] | 0 | weight of the rough (GGX) transmission through an interface of index `eta`; with it, the surface transmits (not inside `twosided`) |
//! | `principled` | `eta` | float | – | > 0 (1 becomes 1.001 when `spec_trans` is given) | from `specular` | interior over exterior index of refraction; not together with `specular` |
//! | `principled` | `specular` | float | – | in [0, 1] (0 becomes 1e-3 when `spec_trans` is given) | 0.5 | sets `eta = 2/(1 − √(0.08·specular)) − 1` (0.5: 1.5) |
//! | `principled` | `spec_tint` | float or texture | – | in [0, 1] | 0 | tints the dielectric reflection toward `base_color` |
//! | `principled` | `sheen`, `sheen_tint` | float or texture | – | in [0, 1] | 0, 0 | grazing-angle sheen, and its tint toward `base_color` |
//! | `principled` | `flatness` | float or texture | – | in [0, 1] | 0 | blends the diffuse lobe toward the "fake subsurface" one |
//! | `principled` | `clearcoat`, `clearcoat_gloss` | float or texture | – | in [0, 1] | 0, 0 | a second, GTR1 reflection lobe (roughness from 0.1 at gloss 0 to 0.001 at gloss 1) |
//! | `principled` | `anisotropic` | float or texture | – | in [0, 1] | 0 | stretches the GGX lobes along the surface tangent `∂p/∂u`: `α_u = max(0.001, roughness²/a)`, `α_v = max(0.001, roughness²·a)` with `a = √(1 − 0.9·anisotropic)`, in Mitsuba's shading frame (as `alpha_u`/`alpha_v`) |
//! | `principled` | `main_specular_sampling_rate`, `clearcoat_sampling_rate`, `diffuse_reflectance_sampling_rate` | float | – | > 0, ≥ 0, ≥ 0 | 1, 1, 1 | relative rates at which sampling picks the main GGX lobes, the clearcoat and the diffuse lobe (they change the noise, not the image) |
//!
//! ```xml
//! <bsdf type="twosided" id="gold">
//!     <bsdf type="conductor"><string name="material" value="Au"/></bsdf>
//! </bsdf>
//! <shape type="sphere"><ref id="gold"/></shape>
//! <shape type="rectangle">
//!     <bsdf type="diffuse"><rgb name="reflectance" value="$albedo"/></bsdf>
//! </shape>
//! <shape type="sphere">
//!     <bsdf type="roughconductor">
//!         <string name="distribution" value="ggx"/>
//!         <float name="alpha" value="0.2"/>
//!         <string name="material" value="Cu"/>
//!     </bsdf>
//! </shape>
//! <shape type="sphere">
//!     <bsdf type="roughconductor">
//!         <string name="material" value="Al"/>
//!         <float name="alpha_u" value="0.05"/>
//!         <float name="alpha_v" value="0.3"/>
//!     </bsdf>
//! </shape>
//! <shape type="rectangle">
//!     <bsdf type="mask">
//!         <texture type="bitmap" name="opacity">
//!             <string name="filename" value="textures/leaf-alpha.png"/>
//!         </texture>
//!         <bsdf type="twosided"><bsdf type="diffuse"/></bsdf>
//!     </bsdf>
//! </shape>
//! <shape type="sphere">
//!     <bsdf type="principled">
//!         <rgb name="base_color" value="0.9, 0.6, 0.2"/>
//!         <float name="metallic" value="0.8"/>
//!         <float name="roughness" value="0.3"/>
//!         <float name="clearcoat" value="0.5"/>
//!     </bsdf>
//! </shape>
//! <default name="albedo" value="0.2, 0.25, 0.7"/>
//! ```
//!
//! ```python
//! import fgf
//! img = fgf.render("scene.xml", defines={"albedo": "0.8, 0.8, 0.8"})
//! ```

use super::context::{check_object_attrs, plugin_type, rgb, Ctx};
use super::document::XNode;
use super::props::{check, check_if, check_rgb, Entry, Props};
use super::tables;
use super::textures::{self, ColorOrTexture};
use crate::desc::*;
use crate::error::SceneError;
use crate::validate::{ALPHA, IOR, NON_NEGATIVE, POSITIVE, UNIT};

/// The BSDF of a shape without one, as Mitsuba 3.9's `Shape` constructor
/// chooses it: a diffuse BSDF of reflectance 0.5, except on a shape with an
/// (area) emitter, which gets reflectance 0 so that a light source does not
/// also reflect light. All such shapes share one entry per kind.
pub(crate) fn default_bsdf(ctx: &mut Ctx, emits: bool) -> BsdfId {
    let (slot, reflectance) = if emits {
        (&mut ctx.default_emitter_bsdf, 0.0)
    } else {
        (&mut ctx.default_bsdf, 0.5)
    };
    *slot.get_or_insert_with(|| {
        ctx.bsdfs.push(BsdfDesc::Diffuse {
            reflectance: [reflectance; 3],
        });
        ctx.bsdf_nodes.push(None);
        ctx.bsdfs.len() - 1
    })
}

const BSDFS: &[&str] = &[
    "diffuse",
    "null",
    "dielectric",
    "thindielectric",
    "roughdielectric",
    "conductor",
    "roughconductor",
    "plastic",
    "roughplastic",
    "twosided",
    "mask",
    "principled",
];

/// `distribution`, `alpha` or `alpha_u`/`alpha_v`, `sample_visible`, with
/// Mitsuba's defaults (Beckmann, 0.1, true). `isotropic` refuses
/// `alpha_u`/`alpha_v` (roughplastic). `alpha_u` is the roughness along the
/// shading frame's tangent (`∂p/∂u`), `alpha_v` across it.
fn microfacet_desc<'a>(
    ctx: &mut Ctx<'a>,
    p: &Props<'a>,
    isotropic: bool,
    textures: &mut Vec<(TexturedParam, TextureDesc)>,
) -> Result<MicrofacetDesc, SceneError> {
    let kind = match p
        .choice("distribution", "beckmann", &["beckmann", "ggx"])?
        .as_str()
    {
        "ggx" => MicrofacetKind::Ggx,
        _ => MicrofacetKind::Beckmann,
    };
    // A texture roughness: the description keeps its mean (see `textures`).
    let mut alpha_of =
        |name: &str, param: TexturedParam| -> Result<Option<(f64, &'a XNode)>, SceneError> {
            match p.peek(name).filter(|e| e.target.tag == "texture") {
                Some(e) => {
                    if isotropic && name != "alpha" {
                        return Err(e.node.err(format!(
                            "this BSDF takes an isotropic 'alpha' only (no {name})"
                        )));
                    }
                    Ok(
                        match textures::color_or_texture(ctx, p, name, [0.1; 3], ALPHA)? {
                            ColorOrTexture::Texture(t) => {
                                let mean = (t.mean() as f64).clamp(1e-4, 4.0);
                                textures.push((param, t));
                                Some((mean, e.node))
                            }
                            ColorOrTexture::Color(c) => Some((c[0], e.node)),
                        },
                    )
                }
                None => p.float(name),
            }
        };
    let alpha = alpha_of("alpha", TexturedParam::Alpha)?;
    let au = alpha_of("alpha_u", TexturedParam::AlphaU)?;
    let av = alpha_of("alpha_v", TexturedParam::AlphaV)?;
    let chk = |v: Option<(f64, &XNode)>, name: &str| -> Result<Option<f64>, SceneError> {
        v.map(|(v, node)| check(node, name, v, ALPHA)).transpose()
    };
    let (a, u, v) = (
        chk(alpha, "alpha")?,
        chk(au, "alpha_u")?,
        chk(av, "alpha_v")?,
    );
    let (alpha_u, alpha_v) = match (a, u, v) {
        (Some(_), Some(_), _) | (Some(_), _, Some(_)) => {
            return Err(p
                .node
                .err("give either 'alpha' or 'alpha_u'/'alpha_v', not both"))
        }
        (Some(a), None, None) => (a, a),
        (None, None, None) => (0.1, 0.1),
        (None, Some(u), Some(v)) if !isotropic => (u, v),
        (None, _, _) if isotropic => {
            return Err(p
                .node
                .err("this BSDF takes an isotropic 'alpha' only (no alpha_u/alpha_v)"))
        }
        _ => return Err(p.node.err("give both 'alpha_u' and 'alpha_v'")),
    };
    Ok(MicrofacetDesc {
        kind,
        alpha_u: alpha_u as f32,
        alpha_v: alpha_v as f32,
        sample_visible: p.bool_or("sample_visible", true)?,
    })
}

/// A scalar parameter of `principled`: a float in [0, 1] or a texture
/// (read by `eval_1`), with whether it was given as Mitsuba's
/// `get_flag` says (a texture, or a float other than 0).
fn principled_scalar<'a>(
    ctx: &mut Ctx<'a>,
    p: &Props<'a>,
    name: &str,
    default: f32,
    param: TexturedParam,
    tex: &mut Vec<(TexturedParam, TextureDesc)>,
) -> Result<(f32, bool), SceneError> {
    if p.peek(name).is_some_and(|e| e.target.tag == "texture") {
        return Ok(
            match textures::color_or_texture(ctx, p, name, [default as f64; 3], UNIT)? {
                ColorOrTexture::Texture(t) => {
                    let m = t.mean().clamp(0.0, 1.0);
                    tex.push((param, t));
                    (m, true)
                }
                ColorOrTexture::Color(c) => (c[0] as f32, c[0] != 0.0),
            },
        );
    }
    Ok(match p.float(name)? {
        Some((v, node)) => {
            let v = check(node, name, v, UNIT)?;
            (v as f32, v != 0.0)
        }
        None => (default, false),
    })
}

/// `principled`'s parameters, with Mitsuba 3.9.1's defaults and its
/// adjustments of `eta` (1 becomes 1.001, and `specular` 0 becomes 1e-3,
/// when `spec_trans` is given).
fn principled_desc<'a>(
    ctx: &mut Ctx<'a>,
    p: &Props<'a>,
    tex: &mut Vec<(TexturedParam, TextureDesc)>,
) -> Result<PrincipledDesc, SceneError> {
    use TexturedParam as T;
    let base_color = match textures::color_or_texture(ctx, p, "base_color", [0.5; 3], UNIT)? {
        ColorOrTexture::Color(c) => rgb(c),
        ColorOrTexture::Texture(t) => {
            let m = t.mean();
            tex.push((T::BaseColor, t));
            [m; 3]
        }
    };
    let mut s = |name, default, param| principled_scalar(ctx, p, name, default, param, tex);
    let (roughness, _) = s("roughness", 0.5, T::Roughness)?;
    let (metallic, _) = s("metallic", 0.0, T::Metallic)?;
    let (spec_trans, has_spec_trans) = s("spec_trans", 0.0, T::SpecTrans)?;
    let (spec_tint, _) = s("spec_tint", 0.0, T::SpecTint)?;
    let (sheen, _) = s("sheen", 0.0, T::Sheen)?;
    let (sheen_tint, _) = s("sheen_tint", 0.0, T::SheenTint)?;
    let (flatness, _) = s("flatness", 0.0, T::Flatness)?;
    let (clearcoat, has_clearcoat) = s("clearcoat", 0.0, T::Clearcoat)?;
    let (clearcoat_gloss, _) = s("clearcoat_gloss", 0.0, T::ClearcoatGloss)?;
    let (anisotropic, _) = s("anisotropic", 0.0, T::Anisotropic)?;
    let eta = match (p.float("eta")?, p.float("specular")?) {
        (Some(_), Some((_, node))) => {
            return Err(node.err("principled: give either 'eta' or 'specular', not both"))
        }
        (Some((v, node)), None) => {
            let v = check(node, "eta", v, IOR)? as f32;
            if has_spec_trans && v == 1.0 {
                1.001
            } else {
                v
            }
        }
        (None, sp) => {
            let mut v = match sp {
                Some((v, node)) => check(node, "specular", v, UNIT)? as f32,
                None => 0.5,
            };
            if has_spec_trans && v == 0.0 {
                v = 1e-3;
            }
            2.0 / (1.0 - (0.08 * v).sqrt()) - 1.0
        }
    };
    let rate = |name: &str, positive: bool| -> Result<f32, SceneError> {
        Ok(match p.float(name)? {
            None => 1.0,
            Some((v, node)) => check(
                node,
                name,
                v,
                if positive { POSITIVE } else { NON_NEGATIVE },
            )? as f32,
        })
    };
    Ok(PrincipledDesc {
        base_color,
        roughness,
        metallic,
        spec_trans,
        spec_tint,
        sheen,
        sheen_tint,
        flatness,
        clearcoat,
        clearcoat_gloss,
        anisotropic,
        eta,
        spec_rate: rate("main_specular_sampling_rate", true)?,
        clearcoat_rate: rate("clearcoat_sampling_rate", false)?,
        diffuse_rate: rate("diffuse_reflectance_sampling_rate", false)?,
        has_spec_trans,
        has_clearcoat,
    })
}

/// `int_ior`, `ext_ior` (numbers or Mitsuba's material names), with the
/// plugin's default interior.
fn iors(p: &Props, int_default: f64) -> Result<(f32, f32), SceneError> {
    let int_ior = match p.take("int_ior") {
        Some(e) => ior(e)?,
        None => int_default,
    };
    let ext_ior = match p.take("ext_ior") {
        Some(e) => ior(e)?,
        None => 1.000277,
    };
    Ok((int_ior as f32, ext_ior as f32))
}

/// A conductor's `material` or `eta`/`k` (Mitsuba's defaults: a perfect
/// mirror), as `(eta, k)`. A textured `eta` or `k` is pushed to `tex`; the
/// description keeps its mean.
fn conductor_eta_k<'a>(
    ctx: &mut Ctx<'a>,
    p: &Props<'a>,
    tex: &mut Vec<(TexturedParam, TextureDesc)>,
) -> Result<([f64; 3], [f64; 3]), SceneError> {
    let material = p.string("material")?;
    let textured = |name: &str| p.peek(name).filter(|e| e.target.tag == "texture").is_some();
    let (eta_tex, k_tex) = (textured("eta"), textured("k"));
    let (eta, k) = (
        if eta_tex { None } else { p.color("eta")? },
        if k_tex { None } else { p.color("k")? },
    );
    Ok(match material {
        Some((m, mnode)) if m != "none" => {
            if eta.is_some() || k.is_some() || eta_tex || k_tex {
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
            let mut value = |v: Option<([f64; 3], &XNode)>,
                             is_tex: bool,
                             name: &str,
                             param: TexturedParam,
                             def: f64|
             -> Result<[f64; 3], SceneError> {
                if is_tex {
                    return Ok(
                        match textures::color_or_texture(ctx, p, name, [def; 3], NON_NEGATIVE)? {
                            ColorOrTexture::Texture(t) => {
                                let m = t.mean() as f64;
                                tex.push((param, t));
                                [m; 3]
                            }
                            ColorOrTexture::Color(c) => c,
                        },
                    );
                }
                match v {
                    None => Ok([def; 3]),
                    Some((c, node)) => check_rgb(node, name, c, NON_NEGATIVE),
                }
            };
            // Mitsuba's defaults eta = 0, k = 1: a perfect mirror.
            (
                value(eta, eta_tex, "eta", TexturedParam::Eta, 0.0)?,
                value(k, k_tex, "k", TexturedParam::K, 1.0)?,
            )
        }
    })
}

/// A BSDF reference or nested BSDF, as an index (shared for the same id).
pub(crate) fn bsdf_ref<'a>(ctx: &mut Ctx<'a>, e: &Entry<'a>) -> Result<BsdfId, SceneError> {
    bsdf_id(ctx, e.target)
}

pub(crate) fn bsdf_id<'a>(ctx: &mut Ctx<'a>, n: &'a XNode) -> Result<BsdfId, SceneError> {
    if let Some(id) = n.attr("id") {
        if let Some(&i) = ctx.bsdf_by_id.get(id) {
            return Ok(i);
        }
    }
    let d = bsdf_desc(ctx, n, 0)?;
    ctx.bsdfs.push(d);
    ctx.bsdf_nodes.push(Some(n));
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
                    "unknown material '{}' for {name} (give a number > 0 or one of: {})",
                    crate::error::clip(s),
                    tables::IOR
                        .iter()
                        .map(|(k, _)| *k)
                        .collect::<Vec<_>>()
                        .join(", ")
                ))
            });
    }
    let v = e.float()?;
    check_if(
        e.node,
        name,
        v,
        (IOR.ok)(v),
        &format!("{} or a material name such as \"bk7\"", IOR.text),
    )
}

/// The BSDF nested in wrapper `n` (`twosided`, `mask`) at nesting `depth`,
/// with `n`'s id on the resolving stack so that a reference cycle is an
/// error.
fn nested_bsdf<'a>(
    ctx: &mut Ctx<'a>,
    n: &'a XNode,
    target: &'a XNode,
    depth: usize,
) -> Result<BsdfDesc, SceneError> {
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
    inner
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
        "thindielectric" => &[
            "int_ior",
            "ext_ior",
            "specular_reflectance",
            "specular_transmittance",
        ],
        "roughdielectric" => &[
            "int_ior",
            "ext_ior",
            "specular_reflectance",
            "specular_transmittance",
            "distribution",
            "alpha",
            "alpha_u",
            "alpha_v",
            "sample_visible",
        ],
        "conductor" => &["material", "eta", "k", "specular_reflectance"],
        "mask" => &["opacity"],
        "principled" => &[
            "base_color",
            "roughness",
            "metallic",
            "spec_trans",
            "spec_tint",
            "sheen",
            "sheen_tint",
            "flatness",
            "clearcoat",
            "clearcoat_gloss",
            "anisotropic",
            "eta",
            "specular",
            "main_specular_sampling_rate",
            "clearcoat_sampling_rate",
            "diffuse_reflectance_sampling_rate",
        ],
        "roughconductor" => &[
            "material",
            "eta",
            "k",
            "specular_reflectance",
            "distribution",
            "alpha",
            "alpha_u",
            "alpha_v",
            "sample_visible",
        ],
        "plastic" => &[
            "int_ior",
            "ext_ior",
            "diffuse_reflectance",
            "specular_reflectance",
            "nonlinear",
        ],
        "roughplastic" => &[
            "int_ior",
            "ext_ior",
            "diffuse_reflectance",
            "specular_reflectance",
            "nonlinear",
            "distribution",
            "alpha",
            "sample_visible",
        ],
        _ => &[],
    };
    let p = Props::new(n, &ctx.ids, known)?;
    // Parameters given by textures; the description keeps their means.
    let mut tex: Vec<(TexturedParam, TextureDesc)> = Vec::new();
    let col = |ctx: &mut Ctx<'a>,
               name: &str,
               param: TexturedParam,
               default: f64,
               tex: &mut Vec<(TexturedParam, TextureDesc)>|
     -> Result<Rgb, SceneError> {
        Ok(
            match textures::color_or_texture(ctx, &p, name, [default; 3], UNIT)? {
                ColorOrTexture::Color(c) => rgb(c),
                ColorOrTexture::Texture(t) => {
                    let m = t.mean();
                    tex.push((param, t));
                    [m; 3]
                }
            },
        )
    };
    use TexturedParam as T;
    let d = match ty {
        "diffuse" => BsdfDesc::Diffuse {
            reflectance: col(ctx, "reflectance", T::Reflectance, 0.5, &mut tex)?,
        },
        "null" => BsdfDesc::Null,
        "dielectric" | "thindielectric" | "roughdielectric" => {
            let (int_ior, ext_ior) = iors(&p, 1.5046)?;
            let specular_reflectance = col(
                ctx,
                "specular_reflectance",
                T::SpecularReflectance,
                1.0,
                &mut tex,
            )?;
            let specular_transmittance = col(
                ctx,
                "specular_transmittance",
                T::SpecularTransmittance,
                1.0,
                &mut tex,
            )?;
            match ty {
                "dielectric" => BsdfDesc::Dielectric {
                    int_ior,
                    ext_ior,
                    specular_reflectance,
                    specular_transmittance,
                },
                "thindielectric" => BsdfDesc::ThinDielectric {
                    int_ior,
                    ext_ior,
                    specular_reflectance,
                    specular_transmittance,
                },
                _ => BsdfDesc::RoughDielectric {
                    int_ior,
                    ext_ior,
                    specular_reflectance,
                    specular_transmittance,
                    microfacet: microfacet_desc(ctx, &p, false, &mut tex)?,
                },
            }
        }
        "conductor" | "roughconductor" => {
            let (eta, k) = conductor_eta_k(ctx, &p, &mut tex)?;
            let specular_reflectance = col(
                ctx,
                "specular_reflectance",
                T::SpecularReflectance,
                1.0,
                &mut tex,
            )?;
            let perfect_mirror = eta == [0.0; 3]
                && k == [1.0; 3]
                && !tex.iter().any(|(p, _)| matches!(p, T::Eta | T::K));
            if ty == "conductor" {
                BsdfDesc::Conductor {
                    eta: rgb(eta),
                    k: rgb(k),
                    specular_reflectance,
                    perfect_mirror,
                }
            } else {
                BsdfDesc::RoughConductor {
                    eta: rgb(eta),
                    k: rgb(k),
                    specular_reflectance,
                    perfect_mirror,
                    microfacet: microfacet_desc(ctx, &p, false, &mut tex)?,
                }
            }
        }
        "plastic" | "roughplastic" => {
            // Mitsuba's default interior: polypropylene.
            let (int_ior, ext_ior) = iors(&p, 1.49)?;
            if int_ior == ext_ior {
                return Err(n.err("int_ior and ext_ior must differ"));
            }
            BsdfDesc::Plastic {
                int_ior,
                ext_ior,
                diffuse_reflectance: col(
                    ctx,
                    "diffuse_reflectance",
                    T::DiffuseReflectance,
                    0.5,
                    &mut tex,
                )?,
                specular_reflectance: col(
                    ctx,
                    "specular_reflectance",
                    T::SpecularReflectance,
                    1.0,
                    &mut tex,
                )?,
                nonlinear: p.bool_or("nonlinear", false)?,
                microfacet: if ty == "roughplastic" {
                    Some(microfacet_desc(ctx, &p, true, &mut tex)?)
                } else {
                    None
                },
            }
        }
        "principled" => BsdfDesc::Principled(principled_desc(ctx, &p, &mut tex)?),
        "mask" => {
            let opacity = match p.peek("opacity").filter(|e| e.target.tag == "texture") {
                Some(_) => match textures::color_or_texture(ctx, &p, "opacity", [0.5; 3], UNIT)? {
                    ColorOrTexture::Texture(t) => {
                        let mean = t.mean().clamp(0.0, 1.0);
                        tex.push((T::Opacity, t));
                        mean
                    }
                    ColorOrTexture::Color(c) => c[0] as f32,
                },
                None => match p.float("opacity")? {
                    Some((v, node)) => check(node, "opacity", v, UNIT)? as f32,
                    None => 0.5,
                },
            };
            let nested = p.take_objects("bsdf");
            match nested.len() {
                1 => {}
                0 => return Err(n.err("mask needs one nested BSDF")),
                _ => return Err(nested[1].node.err("mask takes one nested BSDF")),
            }
            let inner = nested_bsdf(ctx, n, nested[0].target, depth);
            BsdfDesc::Mask {
                opacity,
                nested: Box::new(inner?),
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
            if target.attr("type") == Some("mask") {
                return Err(nested[0].node.err(crate::validate::TWOSIDED_MASK));
            }
            let inner = nested_bsdf(ctx, n, target, depth);
            BsdfDesc::TwoSided(Box::new(inner?))
        }
    };
    p.finish()?;
    Ok(if tex.is_empty() {
        d
    } else {
        BsdfDesc::Textured {
            base: Box::new(d),
            textures: tex,
        }
    })
}
