//! `<medium>`: the classical (exponential) media `homogeneous` and
//! `heterogeneous`, as in Mitsuba 3.9; the non-exponential `fgf` and
//! `nonexponential` are in [`super::nonexp`]. A medium is nested in a
//! `<shape>` as its `interior` or `exterior`, or in the `<sensor>` (the
//! camera's medium), or defined at the top level with an `id` and used by
//! `<ref>`; it needs `<integrator type="volpath">`. Mitsuba 3 media have
//! no `sigma_s`/`sigma_a`: give `sigma_t = sigma_s + sigma_a` and
//! `albedo = sigma_s / sigma_t` instead.
//!
//! | plugin | parameter | type | units | range | default | meaning |
//! |---|---|---|---|---|---|---|
//! | both | `sigma_t` | float or rgb; `heterogeneous`: or a nested `volume` | 1/length | ≥ 0 | 1 | extinction, times `scale` |
//! | both | `albedo` | float or rgb; `heterogeneous`: or a nested `volume` | – | in [0, 1] | 0.75 | single-scattering albedo |
//! | both | `scale` | float | – | ≥ 0 | 1 | multiplies `sigma_t` |
//! | both | `sample_emitters` | boolean | – | – | true | next-event estimation at scattering events in the medium; `false`: phase sampling alone there, and emission found after such an event counts fully (as in Mitsuba); the expected image is the same |
//! | both | `has_spectral_extinction` | boolean | – | – | true | accepted; in Mitsuba's RGB variants it does not change the expected image (fgf always samples an RGB `sigma_t` per channel) |
//! | both | nested `phase` | – | – | one, see [`super::phase`] | isotropic | |
//!
//! `homogeneous` takes a constant `sigma_t` (a `constvolume` too) and fills
//! its whole shape; its `albedo` may also be a `gridvolume` (a 3D texture
//! evaluated at each scattering point). `heterogeneous` takes the volumes of
//! [`super::volumes`] for both, and, as in Mitsuba 3, **exists only inside
//! the bounding box of its `sigma_t` volume**: a grid's box, and for a
//! constant `sigma_t` (a float, an rgb or a `constvolume`) the unit cube
//! `[0, 1]³`, moved by the `constvolume`'s `to_world`. A heterogeneous
//! cube over `[-1, 1]³` with a float `sigma_t` is thus filled only in its
//! positive octant.
//!
//! ```xml
//! <shape type="cube">
//!     <bsdf type="null"/>
//!     <medium type="heterogeneous" name="interior">
//!         <volume type="gridvolume" name="sigma_t">
//!             <string name="filename" value="density64.vol"/>
//!             <!-- the grid's unit cube onto the shape's [-1, 1]^3 -->
//!             <transform name="to_world">
//!                 <scale value="2"/><translate value="-1, -1, -1"/>
//!             </transform>
//!         </volume>
//!         <float name="scale" value="$density"/>
//!         <rgb name="albedo" value="0.8"/>
//!     </medium>
//! </shape>
//! <default name="density" value="4"/>
//! ```
//!
//! ```python
//! import fgf
//! img = fgf.render("scenes/reference/cube-heterogeneous.xml", spp=16, defines={"res": 64})
//! ```

use super::context::{check_object_attrs, rgb, Ctx};
use super::document::XNode;
use super::nonexp;
use super::phase;
use super::props::{Entry, Props};
use super::volumes;
use crate::desc::*;
use crate::error::SceneError;
use crate::validate::{Range, NON_NEGATIVE, SCALE, UNIT};

const MEDIA: &[&str] = &["homogeneous", "heterogeneous", "fgf", "nonexponential"];

/// A medium reference or nested medium, as an index (shared for the same id).
pub(crate) fn medium_ref<'a>(ctx: &mut Ctx<'a>, e: &Entry<'a>) -> Result<MediumId, SceneError> {
    medium_id(ctx, e.target)
}

pub(crate) fn medium_id<'a>(ctx: &mut Ctx<'a>, n: &'a XNode) -> Result<MediumId, SceneError> {
    let id = n.attr("id");
    if let Some(id) = id {
        if let Some(&i) = ctx.medium_by_id.get(id) {
            return Ok(i);
        }
    }
    let d = medium_desc(ctx, n)?;
    ctx.media.push(d);
    ctx.medium_nodes.push(n);
    let i = ctx.media.len() - 1;
    if let Some(id) = id {
        ctx.medium_by_id.insert(id.to_string(), i);
    }
    Ok(i)
}

fn medium_desc<'a>(ctx: &mut Ctx<'a>, n: &'a XNode) -> Result<MediumDesc, SceneError> {
    check_object_attrs(n)?;
    let ty = n.attr("type").ok_or_else(|| {
        n.err(format!(
            "missing attribute 'type' (supported medium types: {})",
            MEDIA.join(", ")
        ))
    })?;
    let known: &'static [&'static str] = match ty {
        "homogeneous" | "heterogeneous" => &[
            "sigma_t",
            "albedo",
            "scale",
            "sample_emitters",
            "has_spectral_extinction",
            "sigma_s",
            "sigma_a",
        ],
        "fgf" => &[
            "sigma_t", "albedo", "scale", "hurst", "sw", "length", "kernel",
        ],
        "nonexponential" => &[
            "sigma_t",
            "albedo",
            "scale",
            "transmittance",
            "alpha",
            "h",
            "c",
            "kernel",
        ],
        _ => {
            return Err(n.err(format!(
                "unknown medium type '{ty}' (supported: {})",
                MEDIA.join(", ")
            )))
        }
    };
    let p = Props::new(n, &ctx.ids, known)?;
    for k in ["sigma_s", "sigma_a"] {
        if let Some(e) = p.take(k) {
            return Err(e.node.err(format!(
                "Mitsuba 3 media take 'sigma_t' and 'albedo', not '{k}': use sigma_t = sigma_s + sigma_a and albedo = sigma_s / sigma_t"
            )));
        }
    }
    let phase = phase::phase_of(ctx, &p)?;
    let scale = p.float_in("scale", 1.0, SCALE)?;
    let d = match ty {
        "homogeneous" => {
            let sigma_t = constant_of(ctx, &p, "sigma_t", 1.0, NON_NEGATIVE)?;
            let albedo = volumes::volume_of(ctx, &p, "albedo", 0.75, UNIT)?;
            let sample_emitters = p.bool_or("sample_emitters", true)?;
            p.bool_or("has_spectral_extinction", true)?;
            let sigma_t = sigma_t.map(|c| c * scale);
            if sigma_t.iter().any(|&c| c > f32::MAX as f64) {
                return Err(n.err(format!(
                    "sigma_t * scale = {} overflows single precision",
                    sigma_t.iter().cloned().fold(0.0, f64::max)
                )));
            }
            match albedo {
                VolumeDesc::Constant(albedo) => MediumDesc::Homogeneous {
                    sigma_t: rgb(sigma_t),
                    albedo,
                    phase,
                    sample_emitters,
                },
                // A 3D texture albedo (Mitsuba evaluates it at each
                // scattering point): the same transport as a heterogeneous
                // medium whose constant sigma_t fills all of space.
                albedo @ VolumeDesc::Grid(_) => MediumDesc::Heterogeneous {
                    sigma_t: VolumeDesc::Grid(volumes::constant_grid(
                        rgb(sigma_t),
                        volumes::everywhere(),
                    )),
                    albedo,
                    scale: 1.0,
                    phase,
                    sample_emitters,
                },
            }
        }
        "heterogeneous" => {
            let sigma_t = volumes::volume_of(ctx, &p, "sigma_t", 1.0, NON_NEGATIVE)?;
            let albedo = volumes::volume_of(ctx, &p, "albedo", 0.75, UNIT)?;
            let sample_emitters = p.bool_or("sample_emitters", true)?;
            p.bool_or("has_spectral_extinction", true)?;
            MediumDesc::Heterogeneous {
                sigma_t,
                albedo,
                scale: scale as f32,
                phase,
                sample_emitters,
            }
        }
        _ => nonexp::nonexponential(ctx, n, &p, ty, scale, phase)?,
    };
    p.finish()?;
    Ok(d)
}

/// A float/rgb parameter, or a `constvolume` (Mitsuba's media take volumes).
fn constant_of(
    ctx: &Ctx,
    p: &Props,
    name: &str,
    default: f64,
    r: Range<f64>,
) -> Result<[f64; 3], SceneError> {
    match volumes::volume_of(ctx, p, name, default, r)? {
        VolumeDesc::Constant(c) => Ok(c.map(|x| x as f64)),
        // A constvolume with a to_world: a homogeneous medium fills its
        // shape whatever the volume's box, as in Mitsuba.
        VolumeDesc::Grid(g) if volumes::constant_value(&g).is_some() => Ok(volumes::constant_value(&g)
            .unwrap_or_default()
            .map(|x| x as f64)),
        VolumeDesc::Grid(_) => Err(p.node.err(format!(
            "'{name}' of a homogeneous medium must be a constant; use a heterogeneous medium for a grid"
        ))),
    }
}
