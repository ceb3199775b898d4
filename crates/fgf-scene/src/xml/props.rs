//! The children of a plugin element, type-checked on demand.
//!
//! A plugin asks for each parameter it knows by name and type; whatever is
//! left when it calls [`Props::finish`] is an unknown parameter or an
//! unexpected nested object, and is reported with the list of the plugin's
//! parameters. Duplicate names are reported when the bag is built.

use super::document::XNode;
use super::parse::{parse_f64, parse_list, xyz_or_value};
use super::spectrum::{parse_pairs, to_srgb, SpectrumUse};
use super::transform;
use crate::error::SceneError;
use crate::validate::{out_of_range, out_of_range_rgb, Range};
use glam::DMat4;
use std::cell::Cell;
use std::collections::HashMap;

/// Property tags (values); everything else that may appear inside a plugin
/// is an object tag or `<ref>`.
pub(crate) const PROPERTY_TAGS: &[&str] = &[
    "float",
    "integer",
    "boolean",
    "string",
    "rgb",
    "spectrum",
    "point",
    "vector",
    "transform",
];
/// Object tags that may appear nested in a plugin.
pub(crate) const OBJECT_TAGS: &[&str] = &[
    "bsdf",
    "emitter",
    "medium",
    "phase",
    "volume",
    "rfilter",
    "sampler",
    "film",
    "shape",
    "sensor",
    "integrator",
    "texture",
];

/// One child of a plugin: a property, a nested object, or a `<ref>` (then
/// `target` is the referenced object and `node` the `<ref>` itself).
pub(crate) struct Entry<'a> {
    pub node: &'a XNode,
    pub target: &'a XNode,
    pub name: Option<&'a str>,
    /// The plugin this entry belongs to is an `<emitter>` (Mitsuba converts
    /// a uniform spectrum differently there).
    in_emitter: bool,
    used: Cell<bool>,
}

/// Linear sRGB of the equal-energy spectrum of value 1 (XYZ = (1, 1, 1)):
/// the row sums of the XYZ → linear sRGB matrix of IEC 61966-2-1. Mitsuba's
/// RGB variants give a uniform `<spectrum>` in an emitter this colour (its
/// spectral variants' D65 white point makes the equal-energy spectrum
/// slightly purple), and every other uniform spectrum a grey.
const EQUAL_ENERGY_SRGB: [f64; 3] = [
    3.240479 - 1.537150 - 0.498535,
    -0.969256 + 1.875991 + 0.041556,
    0.055648 - 0.204043 + 1.057311,
];

impl<'a> Entry<'a> {
    pub fn is_property(&self) -> bool {
        PROPERTY_TAGS.contains(&self.node.tag.as_str())
    }

    fn value_attr(&self) -> Result<&'a str, SceneError> {
        self.node.check_attrs(&["name", "value"])?;
        if !self.node.children.is_empty() {
            return Err(self.node.err("a property takes no children"));
        }
        self.node.req_attr("value")
    }

    fn expect(&self, what: &str) -> SceneError {
        let name = self.name.unwrap_or("?");
        if self.target.tag == "texture" {
            return self.node.err(format!(
                "a texture ({}) as parameter '{name}' is not supported here (it must be {what})",
                self.target.attr("type").unwrap_or("?")
            ));
        }
        self.node.err(format!(
            "parameter '{name}' must be {what}, not <{}>",
            self.node.tag
        ))
    }

    /// `<float>` or `<integer>` (Mitsuba accepts an integer where a float is
    /// expected), finite.
    pub fn float(&self) -> Result<f64, SceneError> {
        if !matches!(self.node.tag.as_str(), "float" | "integer") {
            return Err(self.expect("a <float>"));
        }
        let s = self.value_attr()?;
        parse_f64(self.node, self.name.unwrap_or("?"), s)
    }

    pub fn int(&self) -> Result<i64, SceneError> {
        if self.node.tag != "integer" {
            return Err(self.expect("an <integer>"));
        }
        let s = self.value_attr()?;
        s.trim().parse::<i64>().map_err(|_| {
            self.node.err(format!(
                "cannot parse '{}' as an integer for parameter '{}'",
                crate::error::clip(s),
                self.name.unwrap_or("?")
            ))
        })
    }

    pub fn bool(&self) -> Result<bool, SceneError> {
        if self.node.tag != "boolean" {
            return Err(self.expect("a <boolean>"));
        }
        let s = self.value_attr()?;
        match s.trim().to_ascii_lowercase().as_str() {
            "true" => Ok(true),
            "false" => Ok(false),
            _ => Err(self.node.err(format!(
                "cannot parse '{}' as a boolean for parameter '{}' (valid: true, false)",
                crate::error::clip(s),
                self.name.unwrap_or("?")
            ))),
        }
    }

    pub fn string(&self) -> Result<&'a str, SceneError> {
        if self.node.tag != "string" {
            return Err(self.expect("a <string>"));
        }
        self.value_attr()
    }

    /// A colour: `<float>`/`<integer>` (grey), `<rgb>` (1 or 3 values) or a
    /// uniform `<spectrum>` (one value: grey, or in an emitter the linear
    /// sRGB of the equal-energy spectrum, as in Mitsuba's RGB variants).
    pub fn color(&self) -> Result<[f64; 3], SceneError> {
        let name = self.name.unwrap_or("?");
        match self.node.tag.as_str() {
            "float" | "integer" => {
                let v = self.float()?;
                Ok([v; 3])
            }
            "rgb" => {
                let s = self.value_attr()?;
                let v = parse_list(self.node, name, s)?;
                match v.len() {
                    1 => Ok([v[0]; 3]),
                    3 => Ok([v[0], v[1], v[2]]),
                    n => Err(self.node.err(format!(
                        "<rgb> parameter '{name}' has {n} values, expected 1 (grey) or 3 (r, g, b)"
                    ))),
                }
            }
            "spectrum" => {
                let s = self.value_attr()?;
                if s.contains(':') {
                    let (w, v) = parse_pairs(s).map_err(|m| {
                        self.node.err(format!(
                            "spectrum '{name}': {m} (write value=\"400:0.2, 500:0.5, 700:0.9\", wavelengths in nm)"
                        ))
                    })?;
                    let usage = if self.in_emitter {
                        SpectrumUse::Emission
                    } else if matches!(name, "eta" | "k") {
                        SpectrumUse::Unbounded
                    } else {
                        SpectrumUse::Bounded
                    };
                    return Ok(to_srgb(&w, &v, usage));
                }
                let v = parse_list(self.node, name, s)?;
                if v.len() != 1 {
                    return Err(self.node.err(format!(
                        "spectrum '{name}' has {} values; only a single uniform value is supported (use <rgb> for colours)",
                        v.len()
                    )));
                }
                if self.in_emitter {
                    Ok(EQUAL_ENERGY_SRGB.map(|c| c * v[0]))
                } else {
                    Ok([v[0]; 3])
                }
            }
            _ => Err(self.expect("a <float>, <rgb> or uniform <spectrum>")),
        }
    }

    /// `<point>` or `<vector>`: `x`, `y`, `z` attributes (default 0) or a
    /// 3-value `value`.
    pub fn vec3(&self) -> Result<[f64; 3], SceneError> {
        if !matches!(self.node.tag.as_str(), "point" | "vector") {
            return Err(self.expect("a <point> or <vector>"));
        }
        self.node.check_attrs(&["name", "value", "x", "y", "z"])?;
        if !self.node.children.is_empty() {
            return Err(self.node.err("a property takes no children"));
        }
        xyz_or_value(self.node, self.name.unwrap_or("?"), 0.0)
    }

    pub fn transform(&self) -> Result<DMat4, SceneError> {
        if self.node.tag != "transform" {
            return Err(self.expect("a <transform>"));
        }
        self.node.check_attrs(&["name"])?;
        transform::compose(self.node)
    }
}

/// The children of a plugin element.
pub(crate) struct Props<'a> {
    pub node: &'a XNode,
    entries: Vec<Entry<'a>>,
    /// The parameter names this plugin knows, for messages.
    known: &'static [&'static str],
}

impl<'a> Props<'a> {
    /// Collect `node`'s children. `ids` resolves `<ref id>`; `known` lists
    /// the plugin's parameter names (for the unknown-parameter message).
    pub fn new(
        node: &'a XNode,
        ids: &HashMap<String, &'a XNode>,
        known: &'static [&'static str],
    ) -> Result<Self, SceneError> {
        let mut entries: Vec<Entry<'a>> = Vec::new();
        for c in &node.children {
            let tag = c.tag.as_str();
            let (target, name) = if tag == "ref" {
                c.check_attrs(&["id", "name"])?;
                if !c.children.is_empty() {
                    return Err(c.err("<ref> takes no children"));
                }
                let id = c.req_attr("id")?;
                let target = *ids.get(id).ok_or_else(|| {
                    let mut all: Vec<&str> = ids.keys().map(|s| s.as_str()).collect();
                    all.sort_unstable();
                    c.err(format!(
                        "reference to unknown id '{id}' (ids in this scene: {})",
                        if all.is_empty() {
                            "none".to_string()
                        } else {
                            all.join(", ")
                        }
                    ))
                })?;
                (target, c.attr("name"))
            } else if PROPERTY_TAGS.contains(&tag) {
                let name = c.req_attr("name")?;
                if !known.contains(&name) {
                    return Err(c.err(format!(
                        "unknown parameter '{name}' of {} (known: {})",
                        node.label(),
                        list_or_none(known)
                    )));
                }
                (c, Some(name))
            } else if OBJECT_TAGS.contains(&tag) {
                (c, c.attr("name"))
            } else {
                return Err(c.err(format!(
                    "unknown element <{tag}> inside {} (supported: <ref>, {}, {})",
                    node.label(),
                    PROPERTY_TAGS
                        .iter()
                        .map(|t| format!("<{t}>"))
                        .collect::<Vec<_>>()
                        .join(", "),
                    OBJECT_TAGS
                        .iter()
                        .map(|t| format!("<{t}>"))
                        .collect::<Vec<_>>()
                        .join(", ")
                )));
            };
            if let Some(n) = name {
                if let Some(prev) = entries.iter().find(|e| e.name == Some(n)) {
                    return Err(c.err(format!(
                        "parameter '{n}' is given twice (first at line {})",
                        prev.node.line
                    )));
                }
            }
            entries.push(Entry {
                node: c,
                target,
                name,
                in_emitter: node.tag == "emitter",
                used: Cell::new(false),
            });
        }
        Ok(Props {
            node,
            entries,
            known,
        })
    }

    /// The named entry, if present and not yet taken, without taking it.
    pub fn peek(&self, name: &str) -> Option<&Entry<'a>> {
        self.entries
            .iter()
            .find(|e| e.name == Some(name) && !e.used.get())
    }

    /// Take the named entry, if present.
    pub fn take(&self, name: &str) -> Option<&Entry<'a>> {
        let e = self
            .entries
            .iter()
            .find(|e| e.name == Some(name) && !e.used.get())?;
        e.used.set(true);
        Some(e)
    }

    /// Take every not-yet-used nested object (or reference) whose target tag is
    /// `tag`, whatever its name.
    pub fn take_objects(&self, tag: &str) -> Vec<&Entry<'a>> {
        self.entries
            .iter()
            .filter(|e| !e.used.get() && !e.is_property() && e.target.tag == tag)
            .inspect(|e| e.used.set(true))
            .collect()
    }

    /// Take the named nested object of tag `tag`, if present.
    pub fn take_object_named(&self, tag: &str, name: &str) -> Option<&Entry<'a>> {
        let e = self.entries.iter().find(|e| {
            !e.used.get() && !e.is_property() && e.target.tag == tag && e.name == Some(name)
        })?;
        e.used.set(true);
        Some(e)
    }

    pub fn float(&self, name: &str) -> Result<Option<(f64, &'a XNode)>, SceneError> {
        self.take(name)
            .map(|e| Ok((e.float()?, e.node)))
            .transpose()
    }
    pub fn int(&self, name: &str) -> Result<Option<(i64, &'a XNode)>, SceneError> {
        self.take(name).map(|e| Ok((e.int()?, e.node))).transpose()
    }
    pub fn bool_or(&self, name: &str, default: bool) -> Result<bool, SceneError> {
        Ok(self
            .take(name)
            .map(|e| e.bool())
            .transpose()?
            .unwrap_or(default))
    }
    pub fn string(&self, name: &str) -> Result<Option<(&'a str, &'a XNode)>, SceneError> {
        self.take(name)
            .map(|e| Ok((e.string()?, e.node)))
            .transpose()
    }
    pub fn color(&self, name: &str) -> Result<Option<([f64; 3], &'a XNode)>, SceneError> {
        self.take(name)
            .map(|e| Ok((e.color()?, e.node)))
            .transpose()
    }
    pub fn vec3(&self, name: &str) -> Result<Option<([f64; 3], &'a XNode)>, SceneError> {
        self.take(name).map(|e| Ok((e.vec3()?, e.node))).transpose()
    }
    pub fn transform(&self, name: &str) -> Result<Option<(DMat4, &'a XNode)>, SceneError> {
        self.take(name)
            .map(|e| Ok((e.transform()?, e.node)))
            .transpose()
    }

    /// A float with a default, checked against `r`.
    pub fn float_in(&self, name: &str, default: f64, r: Range<f64>) -> Result<f64, SceneError> {
        match self.float(name)? {
            None => Ok(default),
            Some((v, node)) => check(node, name, v, r),
        }
    }

    /// A required float (its range is checked where it is used).
    pub fn float_required(&self, name: &str) -> Result<f64, SceneError> {
        match self.float(name)? {
            None => Err(self
                .node
                .err(format!("missing required parameter '{name}'"))),
            Some((v, _)) => Ok(v),
        }
    }

    /// An integer with a default, checked against `r`.
    pub fn int_in(&self, name: &str, default: i64, r: Range<i64>) -> Result<i64, SceneError> {
        match self.int(name)? {
            None => Ok(default),
            Some((v, _)) if (r.ok)(v) => Ok(v),
            Some((v, node)) => Err(node.err(out_of_range(name, v, r.text))),
        }
    }

    /// A colour with a default, every channel checked against `r`.
    pub fn color_in(
        &self,
        name: &str,
        default: [f64; 3],
        r: Range<f64>,
    ) -> Result<[f64; 3], SceneError> {
        match self.color(name)? {
            None => Ok(default),
            Some((v, node)) => check_rgb(node, name, v, r),
        }
    }

    /// A string among `choices`, with a default.
    pub fn choice(
        &self,
        name: &str,
        default: &'static str,
        choices: &[&str],
    ) -> Result<String, SceneError> {
        match self.string(name)? {
            None => Ok(default.to_string()),
            Some((v, node)) => {
                if choices.contains(&v) {
                    Ok(v.to_string())
                } else {
                    Err(node.err(format!(
                        "invalid {name} = '{}' (valid: {})",
                        crate::error::clip(v),
                        choices.join(", ")
                    )))
                }
            }
        }
    }

    /// Error on anything not taken.
    pub fn finish(&self) -> Result<(), SceneError> {
        if let Some(e) = self.entries.iter().find(|e| !e.used.get()) {
            if e.is_property() {
                return Err(e.node.err(format!(
                    "parameter '{}' of {} cannot be used here (known: {})",
                    e.name.unwrap_or("?"),
                    self.node.label(),
                    list_or_none(self.known)
                )));
            }
            return Err(e.node.err(format!(
                "a nested <{}> is not allowed inside {}",
                e.target.tag,
                self.node.label(),
            )));
        }
        Ok(())
    }
}

/// `v`, or the error that it is outside `r`.
pub(crate) fn check(node: &XNode, name: &str, v: f64, r: Range<f64>) -> Result<f64, SceneError> {
    check_if(node, name, v, (r.ok)(v), r.text)
}

/// `v` if `ok`, else the error that it is outside `range` (for ranges that
/// depend on another parameter).
pub(crate) fn check_if(
    node: &XNode,
    name: &str,
    v: f64,
    ok: bool,
    range: &str,
) -> Result<f64, SceneError> {
    if ok {
        Ok(v)
    } else {
        Err(node.err(out_of_range(name, v, range)))
    }
}

/// A colour, or the error that a channel is outside `r`.
pub(crate) fn check_rgb(
    node: &XNode,
    name: &str,
    c: [f64; 3],
    r: Range<f64>,
) -> Result<[f64; 3], SceneError> {
    if c.iter().all(|&v| (r.ok)(v)) {
        Ok(c)
    } else {
        Err(node.err(out_of_range_rgb(name, &c, r.text)))
    }
}

fn list_or_none(v: &[&str]) -> String {
    if v.is_empty() {
        "none".to_string()
    } else {
        v.join(", ")
    }
}
