//! The loader's state while it instantiates the plugins ([`Ctx`]) and the
//! helpers every plugin family uses: the `type` and attribute checks, colour
//! and matrix conversion.

use super::document::XNode;
use super::props::OBJECT_TAGS;
use crate::desc::*;
use crate::error::SceneError;
use crate::validate::{is_invertible, singular};
use glam::{DMat4, Mat4};
use std::collections::HashMap;

/// Loader state shared by the plugin constructors.
pub(crate) struct Ctx<'a> {
    pub ids: HashMap<String, &'a XNode>,
    pub bsdfs: Vec<BsdfDesc>,
    /// The element each BSDF was defined by (`None` for the defaults).
    pub bsdf_nodes: Vec<Option<&'a XNode>>,
    pub bsdf_by_id: HashMap<String, BsdfId>,
    pub default_bsdf: Option<BsdfId>,
    /// The black diffuse BSDF of emitters without a BSDF (shared, like
    /// `default_bsdf`).
    pub default_emitter_bsdf: Option<BsdfId>,
    pub media: Vec<MediumDesc>,
    pub medium_by_id: HashMap<String, MediumId>,
    /// The element each medium was defined by.
    pub medium_nodes: Vec<&'a XNode>,
    /// Ids being instantiated (reference cycle detection).
    pub resolving: Vec<String>,
    /// Top-level `area` emitters referenced by a shape, with that shape.
    pub area_refs: HashMap<String, &'a XNode>,
    /// Textures with an id, instantiated once (a bitmap is read once).
    pub texture_by_id: HashMap<String, TextureDesc>,
}

impl<'a> Ctx<'a> {
    /// The state for instantiating the top-level elements `nodes`, with
    /// every `id` in them collected first (a `<ref>` may come before the
    /// object it names).
    pub fn new(nodes: &'a [XNode]) -> Result<Self, SceneError> {
        let mut ids = HashMap::new();
        for n in nodes {
            collect_ids(n, &mut ids)?;
        }
        Ok(Ctx {
            ids,
            bsdfs: Vec::new(),
            bsdf_nodes: Vec::new(),
            bsdf_by_id: HashMap::new(),
            default_bsdf: None,
            default_emitter_bsdf: None,
            media: Vec::new(),
            medium_by_id: HashMap::new(),
            medium_nodes: Vec::new(),
            resolving: Vec::new(),
            area_refs: HashMap::new(),
            texture_by_id: HashMap::new(),
        })
    }
}

fn collect_ids<'a>(n: &'a XNode, ids: &mut HashMap<String, &'a XNode>) -> Result<(), SceneError> {
    if let Some(id) = n.attr("id") {
        if n.tag != "ref" {
            if !OBJECT_TAGS.contains(&n.tag.as_str()) {
                return Err(n.err(format!(
                    "an 'id' is only allowed on objects ({}), not on <{}>",
                    OBJECT_TAGS.join(", "),
                    n.tag
                )));
            }
            if id.is_empty() {
                return Err(n.err("empty id"));
            }
            if let Some(prev) = ids.get(id) {
                return Err(n.err(format!(
                    "duplicate id '{id}' (first defined at {}:{})",
                    prev.file.display(),
                    prev.line
                )));
            }
            ids.insert(id.to_string(), n);
        }
    }
    for c in &n.children {
        collect_ids(c, ids)?;
    }
    Ok(())
}

/// Round a composed f64 matrix to f32, refusing overflow.
pub(crate) fn to_mat4(node: &XNode, m: DMat4) -> Result<Mat4, SceneError> {
    let f = m.as_mat4();
    if !f.is_finite() {
        return Err(node.err("the transform overflows single precision"));
    }
    Ok(f)
}

/// Round to f32 and require an invertible matrix (the renderer maps rays
/// to local space with the inverse): the determinant must be nonzero and
/// the inverse finite in single precision.
pub(crate) fn to_invertible_mat4(node: &XNode, m: DMat4) -> Result<Mat4, SceneError> {
    let f = to_mat4(node, m)?;
    let det = m.determinant();
    if det == 0.0 || !det.is_finite() || !is_invertible(&f) {
        return Err(node.err(singular(det)));
    }
    Ok(f)
}

pub(crate) fn rgb(v: [f64; 3]) -> Rgb {
    [v[0] as f32, v[1] as f32, v[2] as f32]
}

pub(crate) fn plugin_type<'a>(
    n: &'a XNode,
    kind: &str,
    supported: &[&str],
) -> Result<&'a str, SceneError> {
    let ty = n.attr("type").ok_or_else(|| {
        n.err(format!(
            "missing attribute 'type' (supported {kind} types: {})",
            supported.join(", ")
        ))
    })?;
    if !supported.contains(&ty) {
        return Err(n.err(format!(
            "unknown {kind} type '{ty}' (supported: {})",
            supported.join(", ")
        )));
    }
    Ok(ty)
}

/// Attributes an object element may carry.
pub(crate) fn check_object_attrs(n: &XNode) -> Result<(), SceneError> {
    n.check_attrs(&["type", "id", "name"])
}
