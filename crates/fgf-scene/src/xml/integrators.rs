//! `<integrator>`: `volpath` (volumetric path tracing: surfaces and media)
//! and `path` (surfaces only). A scene without an `<integrator>` gets
//! Mitsuba's default, `path`, so a scene with media needs
//! `<integrator type="volpath">`; `path` in a scene with media is an error.
//! Both follow Mitsuba 3's semantics (see `fgf_render::integrator`).
//!
//! | plugin | parameter | type | units | range | default | meaning |
//! |---|---|---|---|---|---|---|
//! | both | `max_depth` | integer | – | −1, or 0 … 2³¹−1 | −1 (unbounded) | a path with `d` scattering events and non-null surface interactions contributes if `d < max_depth`: 1 shows the emitters seen directly, 2 adds direct lighting |
//! | both | `rr_depth` | integer | – | 1 … 2³²−1 | 5 | Russian roulette once the depth exceeds it |
//! | both | `hide_emitters` | boolean | – | – | false | emitters seen directly (also through media and null boundaries) are black |
//!
//! ```xml
//! <default name="max_depth" value="64"/>
//! <integrator type="volpath">
//!     <integer name="max_depth" value="$max_depth"/>
//! </integrator>
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
use crate::validate::{MAX_DEPTH, RR_DEPTH};

pub(crate) fn integrator_desc(ctx: &Ctx, n: &XNode) -> Result<IntegratorDesc, SceneError> {
    check_object_attrs(n)?;
    let ty = plugin_type(n, "integrator", &["volpath", "path"])?;
    let p = Props::new(n, &ctx.ids, &["max_depth", "rr_depth", "hide_emitters"])?;
    let max_depth = p.int_in("max_depth", -1, MAX_DEPTH)? as i32;
    let rr_depth = p.int_in("rr_depth", 5, RR_DEPTH)? as u32;
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

/// Mitsuba's default when a scene has no `<integrator>`: `path`.
pub(crate) fn default_integrator() -> IntegratorDesc {
    IntegratorDesc {
        kind: IntegratorKind::Path,
        max_depth: -1,
        rr_depth: 5,
        hide_emitters: false,
    }
}
