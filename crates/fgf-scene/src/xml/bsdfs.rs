//! `<bsdf>`: `diffuse` (Lambertian, one-sided: black seen from the back),
//! `null` (an index-matched boundary that paths cross unchanged, for media
//! boundaries), `dielectric` (smooth), `conductor` (a smooth metal) and
//! `twosided` (the nested BSDF on both sides). A `<bsdf>` at the top level
//! with an `id` can be shared by `<ref id="..."/>`. The default BSDF of a
//! shape is described in [`super::shapes`].
//!
//! | plugin | parameter | type | units | range | default | meaning |
//! |---|---|---|---|---|---|---|
//! | `diffuse` | `reflectance` | float or rgb | – | in [0, 1] | 0.5 | |
//! | `dielectric` | `int_ior`, `ext_ior` | float or string | – | a number > 0 or a name of Mitsuba's table (`"water"`, `"bk7"`, `"diamond"`, ...) | `"bk7"` (1.5046), `"air"` (1.000277) | index of refraction inside and outside |
//! | `dielectric` | `specular_reflectance`, `specular_transmittance` | float or rgb | – | in [0, 1] | 1, 1 | |
//! | `conductor` | `material` | string | – | `"none"` or a name of Mitsuba's table (`"Au"`, `"Ag"`, `"Cu"`, `"Al"`, ...) | `"none"` | `"none"` is a perfect mirror; not together with `eta`, `k` |
//! | `conductor` | `eta`, `k` | float or rgb | – | ≥ 0 | 0, 1 (a perfect mirror) | complex index of refraction `eta + i k` |
//! | `conductor` | `specular_reflectance` | float or rgb | – | in [0, 1] | 1 | |
//! | `twosided` | nested `bsdf` | – | – | one, not `twosided` | required | |
//!
//! ```xml
//! <bsdf type="twosided" id="gold">
//!     <bsdf type="conductor"><string name="material" value="Au"/></bsdf>
//! </bsdf>
//! <shape type="sphere"><ref id="gold"/></shape>
//! <shape type="rectangle">
//!     <bsdf type="diffuse"><rgb name="reflectance" value="$albedo"/></bsdf>
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
use super::props::{check_if, check_rgb, Entry, Props};
use super::tables;
use crate::desc::*;
use crate::error::SceneError;
use crate::validate::{IOR, NON_NEGATIVE, UNIT};

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

const BSDFS: &[&str] = &["diffuse", "null", "dielectric", "conductor", "twosided"];

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
    let d = match ty {
        "diffuse" => BsdfDesc::Diffuse {
            reflectance: rgb(p.color_in("reflectance", [0.5; 3], UNIT)?),
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
                specular_reflectance: rgb(p.color_in("specular_reflectance", [1.0; 3], UNIT)?),
                specular_transmittance: rgb(p.color_in(
                    "specular_transmittance",
                    [1.0; 3],
                    UNIT,
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
                        Some((c, node)) => check_rgb(node, name, c, NON_NEGATIVE),
                    };
                    // Mitsuba's defaults eta = 0, k = 1: a perfect mirror.
                    (nonneg(eta, "eta", 0.0)?, nonneg(k, "k", 1.0)?)
                }
            };
            BsdfDesc::Conductor {
                eta: rgb(eta),
                k: rgb(k),
                specular_reflectance: rgb(p.color_in("specular_reflectance", [1.0; 3], UNIT)?),
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
