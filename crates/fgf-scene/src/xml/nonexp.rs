//! fgf's non-exponential media, `fgf` and `nonexponential`: usable wherever
//! a classical medium is (see [`super::media`]), with
//! `<integrator type="volpath">`.
//!
//! * `fgf`: extinction `σ_t(x) = σ_m + σ_u(x)`, where `σ_u` is a zero-mean
//!   fractional Gaussian field of Hurst parameter `H` and white-noise
//!   strength `S_w` (`docs/theory.md` §1–2). The renderer uses its
//!   ensemble-averaged, non-exponential transmittance, the gamma closure of
//!   `docs/theory.md` §3, with the transport kernel chosen by `kernel`
//!   (`docs/theory.md` §4).
//! * `nonexponential`: a named transmittance model of optical depth
//!   `τ = σ_m t`: `exponential`, `exp(−τ)`; `davis`, the Davis power law
//!   `(1 + τ/α)^(−α)` (`docs/theory.md` §3, the form of k-fBm); or
//!   `davis_weinstein` (Bitterli 2018; `docs/theory.md` §3, the form of pink
//!   noise with `h = H + 1`).
//!
//! The model parameters are those of `fgf_core::transmittance` (`Fgf`,
//! `Exponential`, `Davis`, `DavisWeinstein`), whose constructors accept or
//! refuse them for every colour channel's `σ_m`.
//!
//! | plugin | parameter | type | units | range | default | meaning |
//! |---|---|---|---|---|---|---|
//! | both | `sigma_t` | float or rgb | 1/length | > 0 | 1 | mean extinction `σ_m`, times `scale` |
//! | both | `albedo` | float or rgb | – | in [0, 1] | 0.75 | single-scattering albedo `Λ` |
//! | both | `scale` | float | – | > 0 | 1 | multiplies `sigma_t` |
//! | both | `kernel` | string | – | `energy_conserving` (Guo 2019 / Jarabo 2018), `reciprocal` (Bitterli 2018) | `energy_conserving` | transport kernel |
//! | both | nested `phase` | – | – | one, see [`super::phase`] | isotropic | |
//! | both | nested `volume name="density"` | `gridvolume` | – | 1 channel, values ≥ 0 | none (`ρ = 1`) | macro-scale density `ρ(x)`: `σ_m(x) = σ_m ρ(x)` (`docs/theory.md` §4); see [`super::volumes`] |
//! | `fgf` | `hurst` | float | – | −0.5 (white noise), (−0.5, 0) (pink noise), or (0, 1000) not an integer (k-fBm, `k = ⌈H⌉`) | required | Hurst parameter `H` |
//! | `fgf` | `sw` | float | length^(−2H−2) (so that `var[σ̄_t]` is in 1/length²) | > 0 | required | white-noise strength `S_w` |
//! | `fgf` | `length` | float | length | > 0; k-fBm only (an error for white and pink noise) | the diagonal of the bounding box of the shapes that have the medium as `interior` | characteristic length `L`: `var[σ̄_t] = S_kf L^(2H)` |
//! | `nonexponential` | `transmittance` | string | – | `exponential`, `davis`, `davis_weinstein` | required | the model |
//! | `nonexponential` | `alpha` | float | – | > 0 | required by `davis` | Davis exponent `α` |
//! | `nonexponential` | `h`, `c` | float | – | 0.5 ≤ h ≤ 1, c > 0 | required by `davis_weinstein` | Davis–Weinstein parameters |
//!
//! ```xml
//! <default name="hurst" value="-0.1"/>
//! <shape type="cube">
//!     <bsdf type="null"/>
//!     <medium type="fgf" name="interior">
//!         <float  name="sigma_t" value="4.0"/>
//!         <rgb    name="albedo"  value="0.8"/>
//!         <float  name="hurst"   value="$hurst"/>   <!-- pink noise -->
//!         <float  name="sw"      value="4.0"/>
//!         <string name="kernel"  value="energy_conserving"/>
//!     </medium>
//! </shape>
//! <medium type="nonexponential" id="cloud">
//!     <string name="transmittance" value="davis"/>
//!     <float  name="alpha"   value="2.0"/>
//!     <float  name="sigma_t" value="4.0"/>
//!     <string name="kernel"  value="reciprocal"/>
//! </medium>
//! ```
//!
//! A sweep needs no edit of the file (`fgf render scene.xml -o out.exr
//! -D hurst=0.2` on the command line):
//!
//! ```python
//! import fgf
//! for hurst in ["-0.1", "0.2", "1.2"]:
//!     img = fgf.render("scene.xml", spp=64, seed=0, defines={"hurst": hurst})
//! mean, se = fgf.ensemble("scenes/fgf-cube-pink.xml", realizations=16)  # ground truth
//! ```

use super::context::{rgb, Ctx};
use super::document::XNode;
use super::props::{check, Props};
use super::volumes;
use crate::desc::*;
use crate::error::SceneError;
use crate::validate::{Range, NON_NEGATIVE, UNIT};
use fgf_core::stats::{Regime, HURST_RANGE};
use glam::DVec3;

/// The `sigma_t` parameter as written, before `scale`. The description's
/// `sigma_t` must be accepted by the fgf-core model constructors, which
/// require it finite and `> 0`: so must this and `scale`.
const MEAN_EXTINCTION: Range<f64> = Range {
    ok: |v| v.is_finite() && v > 0.0,
    text: "> 0; it is the mean extinction σ_m",
};
const POSITIVE_SCALE: Range<f64> = Range {
    ok: |v| v.is_finite() && v > 0.0,
    text: "scale > 0 for a non-exponential medium",
};

fn is_kfbm(hurst: f64) -> bool {
    matches!(Regime::from_hurst(hurst), Ok(Regime::KFbm { .. }))
}

pub(crate) fn nonexponential<'a>(
    ctx: &Ctx<'a>,
    n: &'a XNode,
    p: &Props<'a>,
    ty: &str,
    scale: f64,
    phase: PhaseDesc,
) -> Result<MediumDesc, SceneError> {
    let sigma_m = p.color_in("sigma_t", [1.0; 3], MEAN_EXTINCTION)?;
    check(n, "scale", scale, POSITIVE_SCALE)?;
    let sigma_t = sigma_m.map(|c| c * scale);
    if !sigma_t
        .iter()
        .all(|c| (c * c).is_finite() && *c as f32 > 0.0)
    {
        return Err(n.err("sigma_t * scale is outside the representable range"));
    }
    let albedo = p.color_in("albedo", [0.75; 3], UNIT)?;
    let kernel = match p
        .choice(
            "kernel",
            "energy_conserving",
            &["energy_conserving", "reciprocal"],
        )?
        .as_str()
    {
        "reciprocal" => KernelDesc::Reciprocal,
        _ => KernelDesc::EnergyConserving,
    };
    let model = if ty == "fgf" {
        let hurst = match p.float("hurst")? {
            None => {
                return Err(n.err(format!(
                    "missing required parameter 'hurst' (valid: {HURST_RANGE})"
                )))
            }
            Some((h, node)) => {
                Regime::from_hurst(h).map_err(|e| node.err(e.to_string()))?;
                h
            }
        };
        let sw = p.float_required("sw")?;
        let length =
            match p.float("length")? {
                None => None,
                Some((l, node)) => {
                    if !is_kfbm(hurst) {
                        return Err(node.err(format!(
                        "'length' only applies to k-fBm media (hurst > 0); hurst = {hurst} is {}",
                        if hurst == -0.5 { "white noise" } else { "pink noise" }
                    )));
                    }
                    Some(l)
                }
            };
        TransmittanceDesc::Fgf { hurst, sw, length }
    } else {
        let (t, tnode) = p.string("transmittance")?.ok_or_else(|| {
            n.err("missing required parameter 'transmittance' (valid: exponential, davis, davis_weinstein)")
        })?;
        let model = match t {
            "exponential" => TransmittanceDesc::Exponential,
            "davis" => TransmittanceDesc::Davis {
                alpha: p.float_required("alpha")?,
            },
            "davis_weinstein" => TransmittanceDesc::DavisWeinstein {
                h: p.float_required("h")?,
                c: p.float_required("c")?,
            },
            _ => {
                return Err(tnode.err(format!(
                    "unknown transmittance '{t}' (valid: exponential, davis, davis_weinstein)"
                )))
            }
        };
        // Parameters of the other models are errors, not silently ignored.
        for k in ["alpha", "h", "c"] {
            if let Some(e) = p.take(k) {
                return Err(e.node.err(format!(
                    "parameter '{k}' does not apply to transmittance '{t}' (davis: alpha; davis_weinstein: h, c; exponential: none)"
                )));
            }
        }
        model
    };
    let density = match p.take_object_named("volume", "density") {
        None => None,
        Some(e) => {
            let t = e.target;
            if t.attr("type") != Some("gridvolume") {
                return Err(e
                    .node
                    .err("'density' must be a <volume type=\"gridvolume\">"));
            }
            Some(volumes::gridvolume(ctx, t, "density", NON_NEGATIVE)?)
        }
    };
    Ok(MediumDesc::NonExponential {
        sigma_t: rgb(sigma_t),
        albedo: rgb(albedo),
        phase,
        model,
        kernel,
        density,
    })
}

/// Fill in the default `length` of k-fBm `fgf` media: the diagonal of the
/// bounding box of the shapes that have the medium as interior.
pub(crate) fn resolve_default_lengths(
    ctx: &mut Ctx,
    shapes: &[ShapeDesc],
) -> Result<(), SceneError> {
    for i in 0..ctx.media.len() {
        let MediumDesc::NonExponential {
            model: TransmittanceDesc::Fgf { hurst, length, .. },
            ..
        } = &mut ctx.media[i]
        else {
            continue;
        };
        if length.is_some() || !is_kfbm(*hurst) {
            continue;
        }
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for s in shapes.iter().filter(|s| s.interior == Some(i)) {
            let (a, b) = s.world_bbox();
            lo = lo.min(a);
            hi = hi.max(b);
        }
        let diag = (hi - lo).length();
        if !(diag.is_finite() && diag > 0.0) {
            return Err(ctx.medium_nodes[i].err(format!(
                "this k-fBm medium (hurst = {hurst}) needs a 'length': it is the interior of no shape, so the default (the diagonal of its shapes' bounding box) is undefined"
            )));
        }
        *length = Some(diag);
    }
    Ok(())
}
