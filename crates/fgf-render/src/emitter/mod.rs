//! Light sources. Next-event estimation picks one emitter uniformly
//! (Mitsuba's default `sampling_weight` of 1 for all) and samples it.
//!
//! The user documentation (parameters, units, ranges, defaults, an XML and
//! a Python example) is the table at the head of [`fgf_scene::xml::emitters`];
//! the notes here are about the implementation.
//!
//! * `area` (inside a shape): one-sided: emits toward the side of the
//!   shading normal (the interpolated vertex normal of a smooth mesh, else
//!   the geometric one), and the light pdf converts area to solid angle
//!   with that normal's cosine, as Mitsuba 3 does (its emitter and position
//!   samples carry the shading frame). Near the silhouette of a
//!   smooth-normal mesh this is not the geometric cosine, so the light's
//!   expected contribution depends on the convention; fgf follows Mitsuba's
//!   so that its scenes render to the same image
//! * `spot`: full intensity inside `beam_width`, then falling linearly in the angle to 0 at `cutoff_angle` (measured against Mitsuba 3.9.1)
//! * `constant`: uniform environment
//! * `envmap`: an image of the environment, sampled by luminance ([`envmap`])

pub mod envmap;

use crate::geometry::{Geometry, Hit, PositionSample};
use crate::math::{sample_uniform_sphere, UNIFORM_SPHERE_PDF};
use crate::spectrum::{from_rgb, Spectrum};
use crate::texture::Texture;
use envmap::Envmap;
use fgf_scene::EmitterDesc;
use glam::{Mat3, Vec3A};
use std::sync::Arc;

#[derive(Debug, Clone)]
pub enum Emitter {
    Area {
        shape: u32,
        radiance: Spectrum,
    },
    /// An area emitter whose `radiance` is a texture, looked up at the
    /// emitting point's texture coordinates ([`Emitter::area_radiance`]);
    /// a variant of its own so that untextured emitters pay nothing for it.
    TexturedArea {
        shape: u32,
        texture: Arc<Texture>,
    },
    Point {
        p: Vec3A,
        intensity: Spectrum,
    },
    Spot {
        p: Vec3A,
        to_local: Mat3,
        intensity: Spectrum,
        cutoff: f32,
        beam: f32,
    },
    Directional {
        d: Vec3A,
        irradiance: Spectrum,
    },
    Constant {
        radiance: Spectrum,
    },
    Envmap(Arc<Envmap>),
}

/// A light sample seen from a reference point.
#[derive(Debug, Clone, Copy)]
pub struct LightSample {
    /// Unit direction from the reference point toward the light.
    pub wi: Vec3A,
    /// Distance to the sampled point (infinite for directional and environment lights).
    pub dist: f32,
    /// Emitted radiance (area, environment), intensity/dist² (point, spot),
    /// or irradiance (directional) arriving along `-wi`.
    pub value: Spectrum,
    /// Solid-angle pdf of `wi` for this emitter (1 for delta lights).
    pub pdf: f32,
    pub delta: bool,
}

impl LightSample {
    /// A sample of an environment map: direction `wi`, radiance `value`.
    #[inline(always)]
    pub fn environment(wi: Vec3A, value: Spectrum, pdf: f32) -> LightSample {
        LightSample {
            wi,
            dist: f32::INFINITY,
            value,
            pdf,
            delta: false,
        }
    }
}

/// A textured area emitter's radiance at a hit (out of line: untextured
/// emitters do not pay for it).
#[inline(never)]
fn texture_at_hit(t: &Texture, geom: &Geometry, hit: &Hit) -> Spectrum {
    t.eval(geom.uv(hit))
}

/// The light sample of an area emitter at the point `ps` of its shape,
/// seen from `p`, emitting `value(ps)` (nothing toward its back).
#[inline(always)]
fn area_sample(
    geom: &Geometry,
    shape: u32,
    p: Vec3A,
    ps: PositionSample,
    value: impl FnOnce(&PositionSample) -> Spectrum,
) -> Option<LightSample> {
    let v = ps.p - p;
    let d2 = v.length_squared();
    if !(d2 > 0.0) {
        return None;
    }
    let dist = d2.sqrt();
    let wi = v / dist;
    // One-sided (shading normal): nothing toward the back.
    let cos_l = -ps.ns.dot(wi);
    if cos_l <= 0.0 {
        return None;
    }
    let pdf = d2 / (cos_l * geom.areas[shape as usize]);
    Some(LightSample {
        wi,
        dist,
        value: value(&ps),
        pdf,
        delta: false,
    })
}

/// [`area_sample`] for a textured emitter: the texture at the sampled
/// point's texture coordinates (out of line: untextured emitters do not pay
/// for it).
#[inline(never)]
fn textured_area_sample(
    t: &Texture,
    geom: &Geometry,
    shape: u32,
    p: Vec3A,
    u_sel: f32,
    u: [f32; 2],
) -> Option<LightSample> {
    let hit = geom.sample_shape_hit(shape as usize, u_sel, u);
    let ps = PositionSample {
        p: hit.p,
        n: hit.n,
        ns: hit.ns,
    };
    area_sample(geom, shape, p, ps, |_| t.eval(geom.uv(&hit)))
}

impl Emitter {
    pub fn from_desc(d: &EmitterDesc, shape: Option<u32>) -> Emitter {
        match d {
            EmitterDesc::Area { radiance, texture } => {
                let shape = shape.expect("area emitter on a shape");
                match texture {
                    None => Emitter::Area {
                        shape,
                        radiance: from_rgb(*radiance),
                    },
                    Some(t) => Emitter::TexturedArea {
                        shape,
                        texture: Arc::new(Texture::from_desc(t)),
                    },
                }
            }
            EmitterDesc::Point {
                position,
                intensity,
            } => Emitter::Point {
                p: (*position).into(),
                intensity: from_rgb(*intensity),
            },
            EmitterDesc::Spot {
                to_world,
                intensity,
                cutoff_angle,
                beam_width,
            } => {
                let l = Mat3::from_mat4(*to_world);
                // Directions only: the inverse of the linear part maps a world
                // direction to the light's frame (normalised where used).
                let to_local = l.inverse();
                let cutoff = cutoff_angle.to_radians();
                Emitter::Spot {
                    p: to_world.w_axis.truncate().into(),
                    to_local,
                    intensity: from_rgb(*intensity),
                    cutoff,
                    beam: beam_width.to_radians().min(cutoff),
                }
            }
            EmitterDesc::Directional {
                direction,
                irradiance,
            } => Emitter::Directional {
                d: direction.normalize().into(),
                irradiance: from_rgb(*irradiance),
            },
            EmitterDesc::Constant { radiance } => Emitter::Constant {
                radiance: from_rgb(*radiance),
            },
            EmitterDesc::Envmap { image, to_world } => {
                Emitter::Envmap(Arc::new(Envmap::new(image, *to_world)))
            }
        }
    }

    /// For an environment emitter: the radiance arriving along a ray that
    /// escapes in direction `d`, and the solid-angle pdf with which
    /// [`Self::sample`] picks `d` (for MIS).
    #[inline(always)]
    pub fn environment(&self, d: Vec3A) -> Option<(Spectrum, f32)> {
        match self {
            Emitter::Constant { radiance } => Some((*radiance, UNIFORM_SPHERE_PDF)),
            Emitter::Envmap(e) => Some(e.eval_pdf(d)),
            _ => None,
        }
    }

    /// The radiance an area emitter emits at `hit` (on its shape) toward
    /// its front side: its `radiance`, or its texture at the hit's texture
    /// coordinates. Mitsuba samples a textured emitter through the texture
    /// and the shape's `(u, v)` map; fgf keeps sampling by area, an
    /// estimator of the same expectation on the shapes that accept a
    /// textured emitter (rectangle, disk, sphere, whose `(u, v)` cover them
    /// once).
    #[inline]
    pub fn area_radiance(&self, geom: &Geometry, hit: &Hit) -> Spectrum {
        match self {
            Emitter::Area { radiance, .. } => *radiance,
            Emitter::TexturedArea { texture, .. } => texture_at_hit(texture, geom, hit),
            _ => Spectrum::ZERO,
        }
    }

    /// The shape of an area emitter (textured or not).
    #[inline]
    pub fn area_shape(&self) -> Option<u32> {
        match *self {
            Emitter::Area { shape, .. } | Emitter::TexturedArea { shape, .. } => Some(shape),
            _ => None,
        }
    }

    /// Whether this is an environment emitter (`constant`, `envmap`).
    #[inline]
    pub fn is_environment(&self) -> bool {
        matches!(self, Emitter::Constant { .. } | Emitter::Envmap(_))
    }

    /// Sample a direction toward the light from `p`.
    pub fn sample(
        &self,
        geom: &Geometry,
        p: Vec3A,
        u_sel: f32,
        u: [f32; 2],
    ) -> Option<LightSample> {
        match *self {
            Emitter::Area { shape, radiance } => area_sample(
                geom,
                shape,
                p,
                geom.sample_shape(shape as usize, u_sel, u),
                |_| radiance,
            ),
            Emitter::TexturedArea { shape, ref texture } => {
                textured_area_sample(texture, geom, shape, p, u_sel, u)
            }
            Emitter::Point { p: lp, intensity } => {
                let v = lp - p;
                let d2 = v.length_squared();
                let dist = d2.sqrt();
                Some(LightSample {
                    wi: v / dist,
                    dist,
                    value: intensity / d2,
                    pdf: 1.0,
                    delta: true,
                })
            }
            Emitter::Spot {
                p: lp,
                to_local,
                intensity,
                cutoff,
                beam,
            } => {
                let v = lp - p;
                let d2 = v.length_squared();
                let dist = d2.sqrt();
                let local = (to_local * (-v)).normalize();
                let f = spot_falloff(local.z, cutoff, beam);
                if f <= 0.0 {
                    return None;
                }
                Some(LightSample {
                    wi: v / dist,
                    dist,
                    value: intensity * (f / d2),
                    pdf: 1.0,
                    delta: true,
                })
            }
            Emitter::Directional { d, irradiance } => Some(LightSample {
                wi: -d,
                dist: f32::INFINITY,
                value: irradiance,
                pdf: 1.0,
                delta: true,
            }),
            Emitter::Constant { radiance } => Some(LightSample {
                wi: sample_uniform_sphere(u),
                dist: f32::INFINITY,
                value: radiance,
                pdf: UNIFORM_SPHERE_PDF,
                delta: false,
            }),
            Emitter::Envmap(ref e) => {
                let (wi, value, pdf) = e.sample(u)?;
                Some(LightSample::environment(wi, value, pdf))
            }
        }
    }
}

/// Spot profile: 1 inside `beam`, linear in the angle down to 0 at `cutoff`.
pub fn spot_falloff(cos_theta: f32, cutoff: f32, beam: f32) -> f32 {
    let theta = cos_theta.clamp(-1.0, 1.0).acos();
    if theta >= cutoff {
        0.0
    } else if theta <= beam {
        1.0
    } else {
        (cutoff - theta) / (cutoff - beam)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Values measured with Mitsuba 3.9.1 (cutoff 20°, beam 10°).
    #[test]
    fn spot_falloff_matches_mitsuba() {
        let (c, b) = (20f32.to_radians(), 10f32.to_radians());
        for (deg, expect) in [
            (0.0f32, 1.0f32),
            (9.9, 1.0),
            (12.0, 0.8),
            (15.0, 0.5),
            (18.0, 0.2),
            (20.5, 0.0),
        ] {
            let f = spot_falloff(deg.to_radians().cos(), c, b);
            assert!((f - expect).abs() < 2e-3, "{deg}: {f}");
        }
    }
}
