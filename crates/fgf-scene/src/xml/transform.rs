//! `<transform>`: a list of `translate`, `rotate`, `scale`, `matrix` and
//! `lookat` elements. Each applies after the previous ones, so the composed
//! matrix is `M_last · … · M_first` (as in Mitsuba 3). Computed in f64 and
//! rounded to f32 once, in the description.
//!
//! * `<translate x y z/>` (missing components 0) or `value="x, y, z"`.
//! * `<rotate x y z angle/>` or `value="ax, ay, az" angle`: a rotation by
//!   `angle` degrees, counter-clockwise about the axis (right-hand rule).
//!   Give a unit axis: like Mitsuba 3.9, the axis `a` is *not* normalised,
//!   the matrix is `cos θ·I + (1 − cos θ)·a aᵀ + sin θ·[a]×`, which for a
//!   non-unit axis also scales and shears (Mitsuba maps (1, 0, 0) by
//!   `rotate x="1" y="1" angle="30"` to (1, 0.134, −0.5)).
//! * `<scale value="s"/>` (uniform), `value="sx, sy, sz"`, or `x y z`
//!   (missing components 1).
//! * `<matrix value="16 numbers, row-major"/>`.
//! * `<lookat origin target up/>`: `dir = normalize(target − origin)`,
//!   `left = normalize(cross(up, dir))`, `up' = cross(dir, left)`; the
//!   columns of the matrix are `left, up', dir, origin`.

use super::document::XNode;
use super::parse::{parse_f64, parse_list, xyz_or_value};
use crate::error::SceneError;
use glam::{DMat4, DVec3, DVec4};

/// Mitsuba 3.9's rotation matrix about `a` by `theta` radians, with `a` used
/// as given (not normalised): `cos θ·I + (1 − cos θ)·a aᵀ + sin θ·[a]×`. For
/// a unit axis this is the usual rotation.
fn mitsuba_rotate(a: DVec3, theta: f64) -> DMat4 {
    let (s, c) = theta.sin_cos();
    let k = 1.0 - c;
    // Columns of the 3x3 part: column j is c·e_j + k·a_j·a + s·(a × e_j).
    let col = |e: DVec3, aj: f64| (c * e + k * aj * a + s * a.cross(e)).extend(0.0);
    DMat4::from_cols(
        col(DVec3::X, a.x),
        col(DVec3::Y, a.y),
        col(DVec3::Z, a.z),
        DVec4::W,
    )
}

pub(crate) fn compose(node: &XNode) -> Result<DMat4, SceneError> {
    let mut m = DMat4::IDENTITY;
    for c in &node.children {
        if !c.children.is_empty() {
            return Err(c.err(format!("<{}> takes no children", c.tag)));
        }
        let step = match c.tag.as_str() {
            "translate" => {
                c.check_attrs(&["x", "y", "z", "value"])?;
                DMat4::from_translation(DVec3::from(xyz_or_value(c, "translate", 0.0)?))
            }
            "scale" => {
                c.check_attrs(&["x", "y", "z", "value"])?;
                let s = match c.attr("value") {
                    Some(v) if ["x", "y", "z"].iter().all(|k| c.attr(k).is_none()) => {
                        let v = parse_list(c, "scale", v)?;
                        match v.len() {
                            1 => [v[0]; 3],
                            3 => [v[0], v[1], v[2]],
                            n => {
                                return Err(c.err(format!(
                                    "scale value has {n} numbers, expected 1 (uniform) or 3 (x, y, z)"
                                )))
                            }
                        }
                    }
                    _ => xyz_or_value(c, "scale", 1.0)?,
                };
                DMat4::from_scale(DVec3::from(s))
            }
            "rotate" => {
                c.check_attrs(&["x", "y", "z", "value", "angle"])?;
                let axis = DVec3::from(xyz_or_value(c, "rotate", 0.0)?);
                let angle = parse_f64(c, "angle", c.req_attr("angle")?)?;
                let len = axis.length();
                if len == 0.0 || !len.is_finite() {
                    return Err(c.err(
                        "rotation axis is zero or not finite (give x, y, z or value=\"ax, ay, az\")",
                    ));
                }
                mitsuba_rotate(axis, angle.to_radians())
            }
            "matrix" => {
                c.check_attrs(&["value"])?;
                let v = parse_list(c, "matrix", c.req_attr("value")?)?;
                if v.len() != 16 {
                    return Err(c.err(format!(
                        "matrix has {} numbers, expected 16 (4x4, row-major)",
                        v.len()
                    )));
                }
                // Row-major in the file; glam stores columns.
                DMat4::from_cols_array(&[
                    v[0], v[4], v[8], v[12], v[1], v[5], v[9], v[13], v[2], v[6], v[10], v[14],
                    v[3], v[7], v[11], v[15],
                ])
            }
            "lookat" => {
                c.check_attrs(&["origin", "target", "up"])?;
                let get = |k: &str| -> Result<DVec3, SceneError> {
                    let v = parse_list(c, k, c.req_attr(k)?)?;
                    if v.len() != 3 {
                        return Err(c.err(format!(
                            "lookat {k} has {} numbers, expected 3",
                            v.len()
                        )));
                    }
                    Ok(DVec3::new(v[0], v[1], v[2]))
                };
                let origin = get("origin")?;
                let target = get("target")?;
                // Mitsuba picks an arbitrary frame when `up` is omitted; we
                // require it so that the camera roll is never a surprise.
                let up = get("up")?;
                lookat(c, origin, target, up)?
            }
            other => {
                return Err(c.err(format!(
                    "unknown transform element <{other}> (supported: translate, rotate, scale, matrix, lookat)"
                )))
            }
        };
        m = step * m;
    }
    if !m.is_finite() {
        return Err(node.err("the composed transform is not finite"));
    }
    Ok(m)
}

fn lookat(c: &XNode, origin: DVec3, target: DVec3, up: DVec3) -> Result<DMat4, SceneError> {
    let d = target - origin;
    if d.length() == 0.0 {
        return Err(c.err("lookat origin and target are the same point"));
    }
    let dir = d.normalize();
    let l = up.cross(dir);
    // A relative threshold: `up` (any length) must not be parallel to `dir`.
    if l.length() <= 1e-9 * up.length().max(f64::MIN_POSITIVE) {
        return Err(c.err("lookat up is zero or parallel to the viewing direction"));
    }
    let left = l.normalize();
    let new_up = dir.cross(left);
    Ok(DMat4::from_cols(
        left.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        DVec4::new(origin.x, origin.y, origin.z, 1.0),
    ))
}
