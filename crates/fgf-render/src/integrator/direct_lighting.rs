//! Mitsuba's `direct` integrator: [`World::li_direct`], the emission seen
//! along the camera ray plus the direct illumination of the first surface,
//! with no media (the loader refuses `direct` in a scene with media).
//!
//! At the first non-emitting (or emitting) surface hit:
//!
//! * if the BSDF is smooth (not purely delta), `n_e = emitter_samples`
//!   light samples, each contributing `f·Le·Tr / p_e` with the power
//!   heuristic weight `w(p_e·c_e, p_b·c_b) / n_e`, where `c_e = n_e/(n_e+n_b)`
//!   and `c_b = n_b/(n_e+n_b)` (a delta light's sample is added with weight
//!   1 and no division by `n_e`, as Mitsuba does);
//! * `n_b = bsdf_samples` BSDF samples, each tracing one ray and adding the
//!   emission it finds (an area light's front side, or the environment)
//!   with weight `w(p_b·c_b, p_e·c_e) / n_b` (1 after a delta lobe).
//!
//! Shadow rays use the volumetric path tracer's routine, so they also pass
//! through `null` surfaces (Mitsuba's `direct` stops at them; a scene with
//! `null` surfaces and no media renders the same unless a `null` surface
//! lies between a light and a lit surface).

use super::direct::{Scatterer, SurfaceVertex};
use crate::emitter::Emitter;
use crate::math::{mis_power, Sampler};
use crate::ray::{offset_point, Ray};
use crate::spectrum::Spectrum;
use crate::world::World;

impl World {
    /// Radiance along `ray` with direct illumination only (one camera
    /// sample); `n_e`/`n_b` are the light and BSDF sample counts.
    pub(super) fn li_direct(
        &self,
        mut ray: Ray,
        mut t_max: f32,
        n_e: u32,
        n_b: u32,
        s: &mut Sampler,
    ) -> Spectrum {
        let mut l = Spectrum::ZERO;
        // The first hit; with hide_emitters, area emitters are skipped.
        let h = loop {
            let Some(h) = self.geom.intersect(&ray, t_max) else {
                if !self.hide_emitters {
                    if let Some(e) = self.env {
                        if let Emitter::Constant { radiance } = self.emitters[e as usize] {
                            l += radiance;
                        }
                    }
                }
                return l;
            };
            let info = self.shapes[h.shape as usize];
            if let Some(e) = info.emitter {
                if self.hide_emitters {
                    ray = Ray {
                        o: offset_point(h.p, h.n, ray.d),
                        d: ray.d,
                    };
                    t_max = (t_max - h.t).max(0.0);
                    continue;
                }
                // The front side is the shading normal's (see `Emitter::sample`).
                if h.ns.dot(ray.d) < 0.0 {
                    let em = &self.emitters[e as usize];
                    if em.area_shape().is_some() {
                        l += em.area_radiance(&self.geom, &h);
                    }
                }
            }
            break h;
        };
        let info = self.shapes[h.shape as usize];
        let bsdf = &self.bsdfs[info.bsdf as usize];
        let bsdf = self.bsdf_at(bsdf, &h);
        let bsdf = &*bsdf;
        let total = (n_e + n_b) as f32;
        let (c_e, c_b) = (n_e as f32 / total, n_b as f32 / total);
        let frame = self.frame_at(bsdf, &h);
        let wi_local = frame.to_local(-ray.d);
        if bsdf.is_smooth() && !self.emitters.is_empty() {
            let vertex = SurfaceVertex {
                hit: &h,
                info: &info,
                bsdf,
                frame: &frame,
                wi_local,
                medium: None,
            };
            for _ in 0..n_e {
                let Some(ls) = self.sample_emitter(h.p, s) else {
                    continue;
                };
                let Some((f, bsdf_pdf)) = vertex.toward(ls.wi) else {
                    continue;
                };
                let pdf = ls.pdf * self.select_pdf();
                if !(pdf > 0.0) {
                    continue;
                }
                let tr = self.shadow(&vertex.shadow_origin(ls.wi), ls.wi, ls.dist, s);
                if tr == Spectrum::ZERO {
                    continue;
                }
                let w = if ls.delta {
                    1.0
                } else {
                    mis_power(pdf * c_e, bsdf_pdf * c_b) / n_e as f32
                };
                l += ls.value * tr * f * (w / pdf);
            }
        }
        for _ in 0..n_b {
            let Some(bs) = bsdf.sample(wi_local, s.next_1d(), s.next_2d()) else {
                continue;
            };
            if bs.weight == Spectrum::ZERO {
                continue;
            }
            let wo = frame.to_world(bs.wo);
            let r = Ray {
                o: offset_point(h.p, h.n, wo),
                d: wo,
            };
            // The emission the sampled direction finds, and its light pdf.
            let (le, light_pdf) = match self.geom.intersect(&r, f32::INFINITY) {
                None => match self
                    .env
                    .and_then(|e| self.emitters[e as usize].environment(wo))
                {
                    Some((radiance, env_pdf)) => (radiance, env_pdf * self.select_pdf()),
                    None => continue,
                },
                Some(h2) => {
                    let Some(e) = self.shapes[h2.shape as usize].emitter else {
                        continue;
                    };
                    let em = &self.emitters[e as usize];
                    let Some(shape) = em.area_shape() else {
                        continue;
                    };
                    let radiance = em.area_radiance(&self.geom, &h2);
                    let cos_l = -h2.ns.dot(wo);
                    if !(cos_l > 0.0) {
                        continue;
                    }
                    let d2 = (h2.p - h.p).length_squared();
                    let pdf = self.select_pdf() * d2 / (cos_l * self.geom.areas[shape as usize]);
                    (radiance, pdf)
                }
            };
            let w = if bs.delta {
                1.0
            } else {
                mis_power(bs.pdf * c_b, light_pdf * c_e)
            };
            l += bs.weight * le * (w / n_b as f32);
        }
        l
    }
}
