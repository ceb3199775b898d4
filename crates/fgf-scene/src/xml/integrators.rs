//! `<integrator>`: `volpath` (volumetric path tracing: surfaces and media),
//! `volpathmis` (Mitsuba's spectral-MIS variant of `volpath`: the same
//! expectation, rendered by `volpath`), `path` (surfaces only), `direct`
//! (direct illumination only) and `moment` (a wrapper). A scene without an
//! `<integrator>` gets Mitsuba's default, `path`, so a scene with media
//! needs `<integrator type="volpath">`; `path` or `direct` in a scene with
//! media is an error. All follow Mitsuba 3's semantics (see
//! `fgf_render::integrator`).
//!
//! | plugin | parameter | type | units | range | default | meaning |
//! |---|---|---|---|---|---|---|
//! | `volpath`, `volpathmis`, `path` | `max_depth` | integer | – | −1, or 0 … 2³¹−1 | −1 (unbounded) | a path with `d` scattering events and non-null surface interactions contributes if `d < max_depth`: 1 shows the emitters seen directly, 2 adds direct lighting |
//! | `volpath`, `volpathmis`, `path` | `rr_depth` | integer | – | 1 … 2³²−1 | 5 | Russian roulette once the depth exceeds it |
//! | all but `moment` | `hide_emitters` | boolean | – | – | false | emitters seen directly (also through media and null boundaries) are black |
//! | `direct` | `shading_samples` | integer | – | 0 … 2¹⁶ | 1 | the default of the two below |
//! | `direct` | `emitter_samples`, `bsdf_samples` | integer | – | 0 … 2¹⁶, not both 0 | `shading_samples` | light and BSDF samples at the first surface, combined by the power heuristic with the sample counts as weights (Mitsuba's `direct`; as there, a delta light's sample is added with weight 1, once per light sample) |
//! | `moment` | nested `integrator`s | – | – | at least one | – | the image is the first nested integrator's; Mitsuba's moment AOVs (the other integrators, second moments) are not produced |
//!
//! ```xml
//! <default name="max_depth" value="64"/>
//! <integrator type="volpath">
//!     <integer name="max_depth" value="$max_depth"/>
//! </integrator>
//! <!-- or: <integrator type="direct"><integer name="emitter_samples" value="4"/></integrator> -->
//! ```
//!
//! ```python
//! import fgf
//! img = fgf.render("scene.xml", defines={"max_depth": 2})  # single scattering
//! ```

use super::context::{check_object_attrs, plugin_type, Ctx};
use super::document::XNode;
use super::props::Props;
use crate::desc::*;
use crate::error::SceneError;
use crate::validate::{Range, MAX_DEPTH, RR_DEPTH};

/// Light or BSDF samples of the `direct` integrator.
const SHADING_SAMPLES: Range<i64> = Range {
    ok: |v| (0..=1 << 16).contains(&v),
    text: "0 ... 65536",
};

pub(crate) fn integrator_desc(ctx: &Ctx, n: &XNode) -> Result<IntegratorDesc, SceneError> {
    check_object_attrs(n)?;
    let ty = plugin_type(
        n,
        "integrator",
        &["volpath", "volpathmis", "path", "direct", "moment"],
    )?;
    if ty == "moment" {
        // Mitsuba's image is the first nested integrator's.
        let p = Props::new(n, &ctx.ids, &[])?;
        let inner = p.take_objects("integrator");
        p.finish()?;
        let first = inner.first().ok_or_else(|| {
            n.err(
                "'moment' needs a nested <integrator> (its image is the first nested integrator's)",
            )
        })?;
        if first.target.attr("type") == Some("moment") {
            return Err(first
                .node
                .err("a 'moment' integrator nested in a 'moment' integrator is not supported"));
        }
        for e in &inner[1..] {
            // Checked, though only the first one renders.
            integrator_desc(ctx, e.target)?;
        }
        return integrator_desc(ctx, first.target);
    }
    if ty == "direct" {
        let p = Props::new(
            n,
            &ctx.ids,
            &[
                "shading_samples",
                "emitter_samples",
                "bsdf_samples",
                "hide_emitters",
            ],
        )?;
        let shading = p.int_in("shading_samples", 1, SHADING_SAMPLES)?;
        let emitter_samples = p.int_in("emitter_samples", shading, SHADING_SAMPLES)? as u32;
        let bsdf_samples = p.int_in("bsdf_samples", shading, SHADING_SAMPLES)? as u32;
        if emitter_samples + bsdf_samples == 0 {
            return Err(n.err("'direct' needs at least one emitter or BSDF sample (emitter_samples + bsdf_samples >= 1)"));
        }
        let hide_emitters = p.bool_or("hide_emitters", false)?;
        p.finish()?;
        return Ok(IntegratorDesc {
            kind: IntegratorKind::Direct {
                emitter_samples,
                bsdf_samples,
            },
            max_depth: -1,
            rr_depth: 5,
            hide_emitters,
        });
    }
    let p = Props::new(n, &ctx.ids, &["max_depth", "rr_depth", "hide_emitters"])?;
    let max_depth = p.int_in("max_depth", -1, MAX_DEPTH)? as i32;
    let rr_depth = p.int_in("rr_depth", 5, RR_DEPTH)? as u32;
    let hide_emitters = p.bool_or("hide_emitters", false)?;
    p.finish()?;
    Ok(IntegratorDesc {
        kind: if ty == "path" {
            IntegratorKind::Path
        } else {
            IntegratorKind::Volpath
        },
        max_depth,
        rr_depth,
        hide_emitters,
    })
}

/// Mitsuba's default when a scene has no `<integrator>`: `path`.
pub(crate) fn default_integrator() -> IntegratorDesc {
    IntegratorDesc {
        kind: IntegratorKind::Path,
        max_depth: -1,
        rr_depth: 5,
        hide_emitters: false,
    }
}
