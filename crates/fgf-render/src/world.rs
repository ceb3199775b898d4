//! The scene compiled for rendering: [`World::build`] turns a [`SceneDesc`]
//! into the geometry with its BVH, the BSDFs, emitters, media and camera
//! the path tracer (`integrator`) reads.

use crate::bsdf::Bsdf;
use crate::camera::Camera;
use crate::emitter::Emitter;
use crate::error::RenderError;
use crate::geometry::Geometry;
use crate::medium::Medium;
use fgf_scene::{GeometryDesc, SceneDesc, TriangleMesh};
use glam::Vec3A;
use std::sync::Arc;

/// Per-shape data the integrator needs at a hit.
#[derive(Debug, Clone, Copy)]
pub struct ShapeInfo {
    pub bsdf: u32,
    /// The BSDF is `null` (shadow rays pass through).
    pub null: bool,
    /// Shadow rays pass with the BSDF's null transmission (a `mask` or
    /// `thindielectric` under `volpath`, see [`World::thin_is_crossing`]).
    pub partial: bool,
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
    pub fn target_medium(&self, n: Vec3A, d: Vec3A, current: Option<u32>) -> Option<u32> {
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
    /// Index of the environment emitter (`constant` or `envmap`), if any.
    pub env: Option<u32>,
    pub media: Vec<Medium>,
    /// Per medium, Mitsuba's `sample_emitters`: whether scattering events in
    /// it estimate direct light by light sampling (else phase sampling alone).
    pub media_sample_emitters: Vec<bool>,
    pub camera: Camera,
    pub camera_medium: Option<u32>,
    pub max_depth: u32,
    pub rr_depth: u32,
    pub hide_emitters: bool,
    /// `Some((emitter_samples, bsdf_samples))` for Mitsuba's `direct`
    /// integrator; `None` for `path` and `volpath`.
    pub direct_samples: Option<(u32, u32)>,
    /// A null-lobe sample (a `thindielectric`'s straight-through
    /// transmission, a `mask`'s transparent part) is an index-matched
    /// crossing that costs no depth and leaves the path's last scattering
    /// vertex as it was, and shadow rays pass such surfaces with their null
    /// transmission (`volpath`, as Mitsuba's volpath and volpathmis treat
    /// null interactions); under `path` and `direct` it is a bounce like any
    /// other and the surfaces block shadow rays, as in Mitsuba's `path` and
    /// `direct`.
    pub thin_is_crossing: bool,
    /// Some shape has a `null` BSDF: paths then ask for the two nearest
    /// hits, so that crossing the boundary needs no second traversal.
    pub(crate) any_null: bool,
    /// Some shape lets shadow rays through (`null`, or
    /// [`ShapeInfo::partial`]): shadow rays then collect the crossings;
    /// otherwise any hit blocks them ([`crate::geometry::Geometry::occluded`]).
    pub(crate) any_passable: bool,
    /// Per BSDF of `bsdfs`: [`Bsdf::has_eval8`], whether paths in step
    /// evaluate it toward their light samples eight at a time.
    pub(crate) bsdf_eval8: Vec<bool>,
    /// Per scene BSDF, [`Bsdf::has_sample8`].
    pub(crate) bsdf_sample8: Vec<bool>,
}

impl World {
    /// Compile `desc`, which is checked first by [`SceneDesc::validate`]
    /// (scenes built in code pass through the same rules as loaded ones).
    pub fn build(desc: &SceneDesc) -> Result<World, RenderError> {
        desc.validate()?;
        let geom = Geometry::build(&desc.shapes)?;
        Self::assemble(desc, geom)
    }

    /// [`World::build`], which also lets go of `desc`'s meshes (each is
    /// left empty) once the geometry has its own copies of their data and
    /// before it builds its tree, the step that takes the most memory: a
    /// 4M-triangle mesh's positions, normals, texture coordinates and
    /// faces are 112 MB (`docs/benchmarks.md`, "Large meshes without their
    /// `Tri`s"). Their memory is freed if `desc` held the only references.
    pub fn build_releasing_meshes(desc: &mut SceneDesc) -> Result<World, RenderError> {
        desc.validate()?;
        let compiled = Geometry::compile(&desc.shapes)?;
        let empty = Arc::new(TriangleMesh {
            positions: Vec::new(),
            normals: None,
            texcoords: None,
            indices: Vec::new(),
        });
        for s in &mut desc.shapes {
            if let GeometryDesc::Mesh(mesh) = &mut s.geometry {
                *mesh = empty.clone();
            }
        }
        Self::assemble(desc, compiled.finish())
    }

    /// The world of `desc` around its geometry `geom` (which reads only
    /// what is not geometry of `desc.shapes`).
    fn assemble(desc: &SceneDesc, geom: Geometry) -> Result<World, RenderError> {
        let bsdfs: Vec<Bsdf> = desc.bsdfs.iter().map(Bsdf::from_desc).collect();
        let media = desc
            .media
            .iter()
            .enumerate()
            .map(|(i, m)| Medium::from_desc(m, i))
            .collect::<Result<Vec<_>, _>>()?;
        let media_sample_emitters = desc
            .media
            .iter()
            .map(|m| match m {
                fgf_scene::MediumDesc::Homogeneous {
                    sample_emitters, ..
                }
                | fgf_scene::MediumDesc::Heterogeneous {
                    sample_emitters, ..
                } => *sample_emitters,
                fgf_scene::MediumDesc::NonExponential { .. } => true,
            })
            .collect();
        let mut emitters = Vec::new();
        let mut shapes = Vec::new();
        let index = |m: Option<usize>| m.map(|i| i as u32);
        let volpath = desc.integrator.kind == fgf_scene::IntegratorKind::Volpath;
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
                partial: volpath && bsdfs[s.bsdf].has_null_lobe(),
                emitter,
                interior: index(s.interior),
                exterior: index(s.exterior),
            });
        }
        let mut env = None;
        for e in &desc.emitters {
            let em = Emitter::from_desc(e, None);
            if em.is_environment() {
                env = Some(emitters.len() as u32);
            }
            emitters.push(em);
        }
        let camera = Camera::new(&desc.sensor)?;
        let any_null = shapes.iter().any(|s| s.null);
        let any_passable = shapes.iter().any(|s| s.null || s.partial);
        Ok(World {
            any_null,
            any_passable,
            bsdf_eval8: bsdfs.iter().map(Bsdf::has_eval8).collect(),
            bsdf_sample8: bsdfs.iter().map(Bsdf::has_sample8).collect(),
            geom,
            shapes,
            bsdfs,
            emitters,
            env,
            media,
            media_sample_emitters,
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
            direct_samples: match desc.integrator.kind {
                fgf_scene::IntegratorKind::Direct {
                    emitter_samples,
                    bsdf_samples,
                } => Some((emitter_samples, bsdf_samples)),
                _ => None,
            },
            thin_is_crossing: volpath,
        })
    }

    /// Probability of picking one given emitter for next-event estimation
    /// (uniform selection, see [`crate::emitter`]).
    #[inline]
    pub fn select_pdf(&self) -> f32 {
        1.0 / self.emitters.len() as f32
    }
}
