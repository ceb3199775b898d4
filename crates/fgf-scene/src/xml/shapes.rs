//! `<shape>`: `cube` (`[-1, 1]³` in local space), `rectangle` (`[-1, 1]²`
//! in the local xy plane, normal +z), `disk` (the unit disk in the local xy
//! plane, normal +z), `sphere`, and the triangle meshes `obj` and `ply`
//! and Mitsuba's `serialized` (read by `mesh/`). A shape is a medium boundary when it names an
//! `interior` or `exterior` medium (the exterior is on the normal's side).
//!
//! | plugin | parameter | type | units | range | default | meaning |
//! |---|---|---|---|---|---|---|
//! | all | `to_world` | transform | – | invertible; a `sphere`'s: rotation, uniform scale and translation | identity | local to world |
//! | all | `flip_normals` | boolean | – | – | false | turn the normals around |
//! | `sphere` | `center` | point | length | – | (0, 0, 0) | in local space |
//! | `sphere` | `radius` | float | length | > 0 | 1 | in local space |
//! | `obj`, `ply` | `filename` | string | – | a file, relative to the scene file | required | OBJ (`v` with an optional `w`, `vt`, `vn`, `f`; any `o`/`g` groups, merged; `l` polylines, materials and vertex colours ignored) or PLY (ascii or binary); n-gons fan-triangulated |
//! | `obj`, `ply`, `serialized` | `face_normals` | boolean | – | – | false | flat shading: the file's normals are ignored and none are computed (see below); a `serialized` mesh flagged for face normals is flat too |
//! | `serialized` | `filename` | string | – | a Mitsuba `.serialized` file (format versions 3 and 4), found like every file (see [`super`]) | required | |
//! | `serialized` | `shape_index` | integer | – | 0 … meshes in the file − 1 | 0 | which mesh of the file |
//! | all | nested `bsdf` | – | – | one, or a `<ref>` | diffuse 0.5; diffuse 0 on a shape with an area emitter | see below |
//! | all | nested `emitter` | – | – | one `area` emitter, nested or a `<ref>` to one declared at the top level with an `id` (used by one shape only) | none | see [`super::emitters`] |
//! | all | nested `medium` | – | – | `name="interior"` and/or `name="exterior"` | none | see [`super::media`] |
//!
//! **Texture coordinates** (for [`super::textures`]) are Mitsuba 3's: a
//! mesh's per-vertex `(u, v)` (an OBJ's `vt` stored as `(u, 1 − v)`; a
//! PLY's `u v`, `s t` or `texture_u texture_v`; a `serialized` mesh's)
//! interpolated across each triangle, or the triangle's barycentrics if the
//! file has none; `rectangle`: `((x + 1)/2, (y + 1)/2)` of the local point;
//! `disk`: `(r, φ/2π)`; `sphere`: `(φ/2π, θ/π)` of the local direction (φ
//! from +x toward +y in [0, 2π), θ from +z); `cube`: each face mapped
//! affinely onto the unit square as Mitsuba's cube mesh maps it.
//!
//! ```xml
//! <shape type="sphere">
//!     <float name="radius" value="0.5"/>
//!     <transform name="to_world"><translate y="0.5"/></transform>
//!     <bsdf type="dielectric"/>
//! </shape>
//! <shape type="obj">
//!     <string name="filename" value="meshes/octahedron.obj"/>
//! </shape>
//! ```
//!
//! ```python
//! import fgf
//! img = fgf.render("scenes/spot-sphere.xml", spp=16)  # a sphere and a mesh
//! ```
//!
//! # Two shape defaults that change images (as in Mitsuba 3.9)
//!
//! **Emitters are black.** A shape without a `bsdf` gets a `diffuse` BSDF
//! of reflectance 0.5, except when it carries an `area` emitter: then the
//! reflectance is 0, so the light source emits but reflects nothing. Give
//! the emitter an explicit `bsdf` to make it reflect.
//!
//! ```xml
//! <shape type="rectangle">
//!     <emitter type="area"><rgb name="radiance" value="10"/></emitter>
//!     <!-- no <bsdf>: black diffuse (reflectance 0) -->
//! </shape>
//! ```
//!
//! **Meshes without normals are smooth.** An `obj`/`ply` whose file has no
//! vertex normals gets computed ones, unless `face_normals="true"` (flat
//! shading; then the file's normals are ignored too). The normal at a
//! vertex is the normalised sum of the unit normals of the faces around
//! it, each weighted by the face's interior angle at that vertex (angle
//! weighting, not area weighting), computed on the world-space positions
//! (after `to_world`). Degenerate faces (zero area) are skipped; a vertex
//! with only degenerate faces gets the normal (1, 0, 0) in world space,
//! like Mitsuba's placeholder. An OBJ vertex is a distinct `v/vt/vn`
//! triple, so a texture seam splits the smoothing as in Mitsuba.
//!
//! ```xml
//! <shape type="obj">
//!     <string name="filename" value="meshes/octahedron.obj"/>
//!     <boolean name="face_normals" value="true"/>  <!-- keep it faceted -->
//! </shape>
//! ```

use super::bsdfs;
use super::context::{check_object_attrs, plugin_type, to_invertible_mat4, Ctx};
use super::document::XNode;
use super::emitters;
use super::media;
use super::mesh;
use super::props::Props;
use crate::desc::*;
use crate::error::SceneError;
use crate::validate::{is_similarity, NOT_SIMILARITY, SPHERE_RADIUS};
use glam::{DVec3, Mat4};
use std::sync::Arc;

const SHAPES: &[&str] = &[
    "cube",
    "rectangle",
    "disk",
    "sphere",
    "obj",
    "ply",
    "serialized",
];
/// Mitsuba's `shape_index` of a `serialized` file.
const SHAPE_INDEX: crate::validate::Range<i64> = crate::validate::Range {
    ok: |v| (0..=u32::MAX as i64).contains(&v),
    text: ">= 0",
};

pub(crate) fn shape_desc<'a>(ctx: &mut Ctx<'a>, n: &'a XNode) -> Result<ShapeDesc, SceneError> {
    check_object_attrs(n)?;
    let ty = plugin_type(n, "shape", SHAPES)?;
    let known: &'static [&'static str] = match ty {
        "sphere" => &["to_world", "flip_normals", "center", "radius"],
        "obj" | "ply" => &["to_world", "flip_normals", "filename", "face_normals"],
        "serialized" => &[
            "to_world",
            "flip_normals",
            "filename",
            "face_normals",
            "shape_index",
        ],
        _ => &["to_world", "flip_normals"],
    };
    let p = Props::new(n, &ctx.ids, known)?;
    // A sphere checks its own to_world below.
    let mut to_world = match ty {
        "sphere" => Mat4::IDENTITY,
        _ => match p.transform("to_world")? {
            Some((m, node)) => to_invertible_mat4(node, m)?,
            None => Mat4::IDENTITY,
        },
    };
    let flip_normals = p.bool_or("flip_normals", false)?;
    let geometry = match ty {
        "cube" => GeometryDesc::Cube,
        "rectangle" => GeometryDesc::Rectangle,
        "disk" => GeometryDesc::Disk,
        "sphere" => {
            if let Some(e) = p.take("to_world") {
                // Mitsuba keeps a sphere round whatever the to_world (it
                // warns and drops non-uniform scale); we refuse it instead.
                let m = e.transform()?;
                if !is_similarity(&m) {
                    return Err(e.node.err(NOT_SIMILARITY));
                }
                to_world = to_invertible_mat4(e.node, m)?;
            }
            let center = p.vec3("center")?.map(|(v, _)| v).unwrap_or([0.0; 3]);
            let radius = p.float_in("radius", 1.0, SPHERE_RADIUS)?;
            GeometryDesc::Sphere {
                center: DVec3::from(center).as_vec3(),
                radius: radius as f32,
            }
        }
        _ => {
            let (file, fnode) = p.string("filename")?.ok_or_else(|| {
                n.err("missing required parameter 'filename' (the mesh file, relative to the scene file)")
            })?;
            let mut face_normals = p.bool_or("face_normals", false)?;
            let path = fnode.resolve(file);
            let mut m = match ty {
                "obj" => mesh::load_obj(fnode, &path)?,
                "ply" => mesh::load_ply(fnode, &path)?,
                _ => {
                    let index = p.int_in("shape_index", 0, SHAPE_INDEX)? as u32;
                    let s = mesh::load_serialized(fnode, &path, index)?;
                    face_normals |= s.face_normals;
                    s.mesh
                }
            };
            if face_normals {
                m.normals = None;
            } else if m.normals.is_none() {
                // Mitsuba's smooth normals (angle-weighted, world space).
                m.normals = Some(mesh::smooth_vertex_normals(
                    &m.positions,
                    &m.indices,
                    &to_world,
                ));
            }
            GeometryDesc::Mesh(Arc::new(m))
        }
    };
    let bsdfs = p.take_objects("bsdf");
    if bsdfs.len() > 1 {
        return Err(bsdfs[1].node.err(format!(
            "a shape takes one BSDF (the first is at line {})",
            bsdfs[0].node.line
        )));
    }
    let bsdf = match bsdfs.first() {
        Some(e) => Some(bsdfs::bsdf_ref(ctx, e)?),
        None => None,
    };
    let emitters = p.take_objects("emitter");
    if emitters.len() > 1 {
        return Err(emitters[1].node.err("a shape takes one emitter"));
    }
    let emitter = match emitters.first() {
        Some(e) => {
            if e.node.tag == "ref" {
                // An area emitter declared at the top level with an id.
                if let Some(id) = e.target.attr("id") {
                    if let Some(prev) = ctx.area_refs.insert(id.to_string(), n) {
                        return Err(e.node.err(format!(
                            "area emitter '{id}' is already attached to the shape at {}:{} (an emitter belongs to one shape)",
                            prev.file.display(),
                            prev.line
                        )));
                    }
                }
            }
            let d = emitters::emitter_desc(ctx, e.target, true)?;
            if let EmitterDesc::Area {
                texture: Some(_), ..
            } = &d
            {
                // Mitsuba samples a textured emitter through the shape's
                // (u, v) parameterisation, which covers a cube's faces (all
                // mapped onto one square) and a mesh's triangles only as
                // their texture coordinates do.
                if !matches!(ty, "rectangle" | "disk" | "sphere") {
                    return Err(e.node.err(format!(
                        "a textured area-emitter 'radiance' on a '{ty}' shape is not supported (only on rectangle, disk and sphere)"
                    )));
                }
            }
            Some(d)
        }
        None => None,
    };
    // The default depends on whether the shape emits (see `default_bsdf`).
    let bsdf = bsdf.unwrap_or_else(|| bsdfs::default_bsdf(ctx, emitter.is_some()));
    let interior = match p.take_object_named("medium", "interior") {
        Some(e) => Some(media::medium_ref(ctx, e)?),
        None => None,
    };
    let exterior = match p.take_object_named("medium", "exterior") {
        Some(e) => Some(media::medium_ref(ctx, e)?),
        None => None,
    };
    if let Some(e) = p.take_objects("medium").first() {
        return Err(e.node.err(format!(
            "a medium in a shape needs name=\"interior\" or name=\"exterior\" (got {})",
            e.name
                .map(|s| format!("name=\"{s}\""))
                .unwrap_or("no name".into())
        )));
    }
    p.finish()?;
    let mut name = format!("shape type=\"{ty}\"");
    if let Some(id) = n.attr("id") {
        name.push_str(&format!(" id=\"{id}\""));
    }
    name.push_str(&format!(" ({}:{})", n.file.display(), n.line));
    Ok(ShapeDesc {
        name,
        geometry,
        to_world,
        flip_normals,
        bsdf,
        emitter,
        interior,
        exterior,
    })
}
