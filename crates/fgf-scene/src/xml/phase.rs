//! `<phase>`: the phase function of a medium, nested in the `<medium>`
//! (see [`super::media`] and [`super::nonexp`]): `isotropic`, the default,
//! or `hg` (Henyey–Greenstein).
//!
//! | plugin | parameter | type | units | range | default | meaning |
//! |---|---|---|---|---|---|---|
//! | `hg` | `g` | float | – | −1 < g < 1 | 0.8 | mean cosine of the scattering angle: > 0 forward, < 0 backward |
//!
//! ```xml
//! <medium type="homogeneous" name="interior">
//!     <phase type="hg"><float name="g" value="$g"/></phase>
//! </medium>
//! <default name="g" value="0.3"/>
//! ```
//!
//! ```python
//! import fgf
//! img = fgf.render("scene.xml", defines={"g": -0.5})  # backward scattering
//! ```

use super::context::{check_object_attrs, Ctx};
use super::props::Props;
use crate::desc::*;
use crate::error::SceneError;
use crate::validate::HG_G;

pub(crate) fn phase_of(ctx: &Ctx, p: &Props) -> Result<PhaseDesc, SceneError> {
    let phases = p.take_objects("phase");
    if phases.len() > 1 {
        return Err(phases[1].node.err("a medium takes one phase function"));
    }
    let Some(e) = phases.first() else {
        return Ok(PhaseDesc::Isotropic);
    };
    let n = e.target;
    check_object_attrs(n)?;
    let ty = n.attr("type").unwrap_or("");
    let known: &'static [&'static str] = match ty {
        "isotropic" => &[],
        "hg" => &["g"],
        _ => {
            return Err(n.err(format!(
                "unknown phase function type '{ty}' (supported: isotropic, hg)"
            )))
        }
    };
    let q = Props::new(n, &ctx.ids, known)?;
    let d = if ty == "hg" {
        PhaseDesc::Hg {
            g: q.float_in("g", 0.8, HG_G)? as f32,
        }
    } else {
        PhaseDesc::Isotropic
    };
    q.finish()?;
    Ok(d)
}
