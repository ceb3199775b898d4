//! The scene compiled for rendering: [`World::build`] turns a [`SceneDesc`]
//! into the geometry with its BVH, the BSDFs, emitters, media and camera
//! the path tracer (`integrator`) reads.

use crate::bsdf::Bsdf;
use crate::camera::Camera;
use crate::emitter::Emitter;
use crate::error::RenderError;
use crate::geometry::Geometry;
use crate::medium::Medium;
use crate::scene::desc::{EmitterDesc, IntegratorKind, SceneDesc};
use glam::Vec3;

/// Per-shape data the integrator needs at a hit.
#[derive(Debug, Clone, Copy)]
pub struct ShapeInfo {
    pub bsdf: u32,
    /// The BSDF is `null` (shadow rays pass through).
    pub null: bool,
    /// Index into `World::emitters` of its area emitter.
    pub emitter: Option<u32>,
    pub interior: Option<u32>,
    pub exterior: Option<u32>,
}

impl ShapeInfo {
    /// The medium a ray leaving the surface (geometric normal `n`) along `d`
    /// enters, if the shape is a medium boundary (Mitsuba: exterior on the
    /// normal side).
    #[inline]
    pub fn target_medium(&self, n: Vec3, d: Vec3, current: Option<u32>) -> Option<u32> {
        if self.interior.is_none() && self.exterior.is_none() {
            current
        } else if d.dot(n) > 0.0 {
            self.exterior
        } else {
            self.interior
        }
    }
}

/// The scene compiled for rendering.
pub struct World {
    pub geom: Geometry,
    pub shapes: Vec<ShapeInfo>,
    pub bsdfs: Vec<Bsdf>,
    pub emitters: Vec<Emitter>,
    /// Index of the `constant` environment emitter, if any.
    pub env: Option<u32>,
    pub media: Vec<Medium>,
    pub camera: Camera,
    pub camera_medium: Option<u32>,
    pub max_depth: u32,
    pub rr_depth: u32,
    pub hide_emitters: bool,
    /// Some shape has a `null` BSDF: paths then ask for the two nearest
    /// hits, so that crossing the boundary needs no second traversal.
    pub(crate) any_null: bool,
}

/// The checks of a scene description's structure that compiling it relies
/// on: the integrator can handle the scene's media, every index refers to
/// an existing BSDF or medium, area emitters sit on shapes and there is at
/// most one environment emitter.
///
/// **To be replaced by the scene crate's single validator**
/// (`SceneDesc::validate`), which also covers these; until then this is
/// where the renderer checks them, all in one place. (Checks that need
/// compiled data, such as a shape's area, stay in [`World::build`]; the
/// range checks of the camera, the shapes and the media stay in their
/// constructors.)
fn validate_structure(desc: &SceneDesc) -> Result<(), RenderError> {
    if desc.integrator.kind == IntegratorKind::Path
        && (!desc.media.is_empty() || desc.sensor.medium.is_some())
    {
        return Err(RenderError::InvalidScene(
            "the 'path' integrator does not handle media; use 'volpath'".into(),
        ));
    }
    let n_media = desc.media.len();
    let check_medium = |m: Option<usize>, what: &str| match m {
        Some(i) if i >= n_media => Err(RenderError::InvalidScene(format!(
            "{what} refers to medium {i}, but there are {n_media}"
        ))),
        _ => Ok(()),
    };
    for s in &desc.shapes {
        if s.bsdf >= desc.bsdfs.len() {
            return Err(RenderError::InvalidScene(format!(
                "{}: BSDF index {} out of range",
                s.name, s.bsdf
            )));
        }
        check_medium(s.interior, &s.name)?;
        check_medium(s.exterior, &s.name)?;
    }
    let mut n_env = 0;
    for e in &desc.emitters {
        match e {
            EmitterDesc::Area { .. } => {
                return Err(RenderError::InvalidScene(
                    "an area emitter must be attached to a shape".into(),
                ))
            }
            EmitterDesc::Constant { .. } => n_env += 1,
            _ => {}
        }
        if n_env > 1 {
            return Err(RenderError::InvalidScene(
                "more than one constant environment emitter".into(),
            ));
        }
    }
    check_medium(desc.sensor.medium, "the sensor")
}

impl World {
    /// Compile `desc` (checked first by `validate_structure`).
    pub fn build(desc: &SceneDesc) -> Result<World, RenderError> {
        validate_structure(desc)?;
        let geom = Geometry::build(&desc.shapes)?;
        let bsdfs: Vec<Bsdf> = desc.bsdfs.iter().map(Bsdf::from_desc).collect();
        let media = desc
            .media
            .iter()
            .enumerate()
            .map(|(i, m)| Medium::from_desc(m, i))
            .collect::<Result<Vec<_>, _>>()?;
        let mut emitters = Vec::new();
        let mut shapes = Vec::new();
        let index = |m: Option<usize>| m.map(|i| i as u32);
        for (i, s) in desc.shapes.iter().enumerate() {
            let emitter = match &s.emitter {
                Some(e) => {
                    if geom.areas[i] <= 0.0 {
                        return Err(RenderError::InvalidScene(format!(
                            "{}: an area emitter on a shape of zero area",
                            s.name
                        )));
                    }
                    emitters.push(Emitter::from_desc(e, Some(i as u32)));
                    Some((emitters.len() - 1) as u32)
                }
                None => None,
            };
            shapes.push(ShapeInfo {
                bsdf: s.bsdf as u32,
                null: bsdfs[s.bsdf].is_null(),
                emitter,
                interior: index(s.interior),
                exterior: index(s.exterior),
            });
        }
        let mut env = None;
        for e in &desc.emitters {
            let em = Emitter::from_desc(e, None);
            if let Emitter::Constant { .. } = em {
                env = Some(emitters.len() as u32);
            }
            emitters.push(em);
        }
        let camera = Camera::new(&desc.sensor)?;
        let any_null = shapes.iter().any(|s| s.null);
        Ok(World {
            any_null,
            geom,
            shapes,
            bsdfs,
            emitters,
            env,
            media,
            camera,
            camera_medium: index(desc.sensor.medium),
            // Mitsuba stores max_depth as unsigned: -1 means unbounded.
            max_depth: if desc.integrator.max_depth < 0 {
                u32::MAX
            } else {
                desc.integrator.max_depth as u32
            },
            rr_depth: desc.integrator.rr_depth,
            hide_emitters: desc.integrator.hide_emitters,
        })
    }

    /// Probability of picking one given emitter for next-event estimation
    /// (uniform selection, see [`crate::emitter`]).
    #[inline]
    pub fn select_pdf(&self) -> f32 {
        1.0 / self.emitters.len() as f32
    }
}
