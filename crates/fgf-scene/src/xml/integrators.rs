//! `<integrator>`.
//!
//! | element | types | parameters (default) |
//! |---|---|---|
//! | `integrator` | `volpath`, `path` | `max_depth` (-1 = unbounded, else ≥ 0), `rr_depth` (5, ≥ 1), `hide_emitters` (false). `path` in a scene with media is an error (use `volpath`). Default integrator: `path`. |

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
