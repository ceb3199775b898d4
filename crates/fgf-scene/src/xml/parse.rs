//! Parsing of the numbers in attribute values, shared by the properties
//! ([`super::props`]) and the transform elements ([`super::transform`]).
//! Every number is finite and representable in single precision, and every
//! message names the parameter.

use super::document::XNode;
use crate::error::SceneError;

/// Parse a finite float; the message names the parameter.
pub(crate) fn parse_f64(node: &XNode, name: &str, s: &str) -> Result<f64, SceneError> {
    let v: f64 = s.trim().parse().map_err(|_| {
        node.err(format!(
            "cannot parse '{}' as a number for parameter '{name}'",
            crate::error::clip(s)
        ))
    })?;
    if !v.is_finite() {
        return Err(node.err(format!("parameter '{name}' = {s} is not a finite number")));
    }
    // The description stores single precision: refuse what would overflow
    // to inf or flush to 0 there, instead of changing the value silently.
    if v.abs() > f32::MAX as f64 || (v != 0.0 && v.abs() < f32::MIN_POSITIVE as f64) {
        return Err(node.err(format!(
            "parameter '{name}' = {s} is outside single precision (|value| must be 0 or between 1.2e-38 and 3.4e38)"
        )));
    }
    Ok(v)
}

/// Parse `"a, b, c"` or `"a b c"` into finite floats.
pub(crate) fn parse_list(node: &XNode, name: &str, s: &str) -> Result<Vec<f64>, SceneError> {
    let v = s
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
        .map(|t| parse_f64(node, name, t))
        .collect::<Result<Vec<_>, _>>()?;
    if v.is_empty() {
        return Err(node.err(format!("parameter '{name}' has an empty value")));
    }
    Ok(v)
}

/// `x`/`y`/`z` attributes (missing ones are `default`) or `value` with 3
/// numbers, not both.
pub(crate) fn xyz_or_value(node: &XNode, name: &str, default: f64) -> Result<[f64; 3], SceneError> {
    let has_xyz = ["x", "y", "z"].iter().any(|k| node.attr(k).is_some());
    match node.attr("value") {
        Some(s) => {
            if has_xyz {
                return Err(node.err(format!(
                    "'{name}' gives both value and x/y/z attributes; use one form"
                )));
            }
            let v = parse_list(node, name, s)?;
            if v.len() != 3 {
                return Err(node.err(format!(
                    "'{name}' value has {} numbers, expected 3 (x, y, z)",
                    v.len()
                )));
            }
            Ok([v[0], v[1], v[2]])
        }
        None => {
            let mut out = [default; 3];
            for (i, k) in ["x", "y", "z"].iter().enumerate() {
                if let Some(s) = node.attr(k) {
                    out[i] = parse_f64(node, &format!("{name}.{k}"), s)?;
                }
            }
            Ok(out)
        }
    }
}
