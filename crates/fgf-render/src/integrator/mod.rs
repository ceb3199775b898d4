//! The volumetric path tracer: [`World::li`], the radiance of one camera
//! sample. Next-event estimation and shadow rays are in `direct.rs`.
//!
//! `volpath` (and `path`, the same code on scenes without media) follows
//! Mitsuba 3's semantics, so both renderers converge to the same image:
//!
//! * `max_depth` counts scattering events in media and interactions with
//!   non-null surfaces; crossing a `null` boundary does not count. A path
//!   with `d` such events contributes only if `d < max_depth`, so
//!   `max_depth = 1` shows emitters seen directly (also through media and
//!   null boundaries), `max_depth = 2` adds single scattering and direct
//!   lighting of surfaces; `-1` is unbounded.
//! * Next-event estimation at every scattering event and at every
//!   non-delta surface, combined with phase/BSDF sampling by multiple
//!   importance sampling (power heuristic). Emitters hit by a path after a
//!   delta surface (or directly from the camera) count fully. A medium with
//!   `sample_emitters = false` has no next-event estimation at its
//!   scattering events, and emission found after one counts fully.
//! * Shadow rays pass through `null` boundaries and media (transmittance
//!   estimates) and, under `volpath`, through `mask` and `thindielectric`
//!   surfaces with their null transmission; any other surface blocks them.
//! * Russian roulette once the depth exceeds `rr_depth`: survival probability
//!   `min(max(throughput)·η², 0.95)`.
//! * `direct` (Mitsuba's direct-illumination integrator) is a separate
//!   routine, [`World::li_direct`] in `direct_lighting.rs`.
//! * RGB throughput; media sample free flights with spectral MIS (see
//!   [`crate::medium`]).

mod direct;
mod direct_lighting;

use crate::bsdf::Bsdf;
use crate::geometry::Hit;
use crate::math::{bin_index, mis_power, Frame, Sampler};
use crate::medium::{DistanceEvent, SegmentStart};
use crate::ray::{offset_point, Ray};
use crate::spectrum::{max_comp, Spectrum};
use crate::world::World;
use direct::{MediumVertex, SurfaceVertex};
use std::borrow::Cow;

/// What an earlier query already says about the nearest hit of a ray.
#[derive(Debug, Clone, Copy)]
enum Known<T> {
    /// Nothing: the geometry must be asked.
    Unknown,
    /// The ray hits nothing.
    Miss,
    Hit(T),
}

impl World {
    /// The BSDF at hit `h`: a textured BSDF is made concrete at the hit's
    /// texture coordinates, which are computed only then.
    #[inline(always)]
    pub(crate) fn bsdf_at<'a>(&'a self, bsdf: &'a Bsdf, h: &Hit) -> Cow<'a, Bsdf> {
        match bsdf.textures {
            None => Cow::Borrowed(bsdf),
            Some(_) => Cow::Owned(bsdf.at(self.geom.uv(h))),
        }
    }

    /// The local frame of `bsdf` at hit `h`: Mitsuba's shading frame,
    /// oriented by the surface tangent ([`crate::geometry::Geometry::shading_frame`]),
    /// for an anisotropic BSDF; for the others, whose values do not change
    /// under a rotation about the normal, the cheaper
    /// [`Frame::from_normal`].
    #[inline(always)]
    pub(crate) fn frame_at(&self, bsdf: &Bsdf, h: &Hit) -> Frame {
        if bsdf.is_anisotropic() {
            self.geom.shading_frame(h)
        } else {
            Frame::from_normal(h.ns)
        }
    }

    /// Radiance arriving at the camera along `ray` (one sample).
    #[inline]
    pub fn li(&self, ray: Ray, t_max_primary: f32, s: &mut Sampler) -> Spectrum {
        if let Some((n_e, n_b)) = self.direct_samples {
            return self.li_direct(ray, t_max_primary, n_e, n_b, s);
        }
        self.li_path(ray, t_max_primary, Known::Unknown, s)
    }

    /// Whether [`Self::li_seen`] may be given the camera ray's nearest hit:
    /// the path integrators need no more of the first query than that
    /// unless some surface is a `null` boundary, whose query also asks for
    /// the hit beyond it.
    pub(crate) fn takes_first_hit(&self) -> bool {
        self.direct_samples.is_none() && !self.any_null
    }

    /// [`Self::li`] with the nearest hit of `ray` below `t_max_primary`
    /// already found (`None`: it hits nothing there), as the beam query
    /// of the camera rays of a pixel finds it; only where
    /// [`Self::takes_first_hit`]. The first query consumes no random
    /// numbers, so the sample is the one `li` would give.
    pub(crate) fn li_seen(
        &self,
        ray: Ray,
        t_max_primary: f32,
        first: Option<Hit>,
        s: &mut Sampler,
    ) -> Spectrum {
        debug_assert!(self.takes_first_hit());
        let known = match first {
            Some(h) => Known::Hit(h),
            None => Known::Miss,
        };
        self.li_path(ray, t_max_primary, known, s)
    }

    /// The path tracer behind [`Self::li`] and [`Self::li_seen`], with
    /// what is already known of the first ray's nearest hit.
    #[inline(never)]
    fn li_path(
        &self,
        mut ray: Ray,
        t_max_primary: f32,
        mut known: Known<Hit>,
        s: &mut Sampler,
    ) -> Spectrum {
        let mut l = Spectrum::ZERO;
        let mut thr = Spectrum::ONE;
        if self.max_depth == 0 {
            return l;
        }
        let mut medium = self.camera_medium;
        let mut depth = 0u32;
        // The path so far is the camera followed by delta interactions only:
        // emission found by continuation then counts without MIS.
        let mut specular = true;
        let mut prev_pdf = 1.0f32;
        let mut prev_p = ray.o;
        let mut eta = 1.0f32;
        let mut start = SegmentStart::Surface;
        let mut t_max = t_max_primary;
        // Path-level spectral MIS (see `Medium::sample_distance_spectral`):
        // free flights use the hero channel's pdf; `r_u` holds each channel's
        // path pdf over the hero's, and a contribution is `thr·L / mean(r_u)`.
        let hero = bin_index(s.next_1d() * 3.0, 3);
        let mut r_u = Spectrum::ONE;
        let mut inv_mis = 1.0f32;
        // `known`: the nearest hit of `ray`, when a previous query already found it.
        loop {
            // Invariant loads from the world are made here, at their use,
            // not hoisted before the loop: hoisted, they were spilled to the
            // stack in the prologue of every call (~90 instructions per
            // sample), while most paths make only a few iterations.
            let world = std::hint::black_box(self);
            // `after`: what the query says of the ray continued through `hit`.
            let (hit, after) = match std::mem::replace(&mut known, Known::Unknown) {
                Known::Hit(h) => (Some(h), Known::Unknown),
                Known::Miss => (None, Known::Unknown),
                Known::Unknown if world.any_null => {
                    let (h1, h2) = world.geom.intersect2(&ray, t_max);
                    let after = match h2 {
                        Some(r) => Known::Hit(r),
                        None if t_max == f32::INFINITY => Known::Miss,
                        // No second hit below a finite t_max says nothing
                        // of what lies beyond it.
                        None => Known::Unknown,
                    };
                    (h1, after)
                }
                Known::Unknown => (world.geom.intersect(&ray, t_max), Known::Unknown),
            };
            let t_surf = hit.map_or(t_max, |h| h.t);
            if let Some(m) = medium {
                let med = &world.media[m as usize];
                let (ds, r) = med.sample_distance_spectral(&ray, t_surf, start, hero, s);
                thr *= ds.weight;
                r_u *= r;
                // Only ratios matter: rescale thr and r_u together so that
                // neither under- nor overflows on long paths.
                let rm = max_comp(r_u);
                if !(1e-4..=1e4).contains(&rm) && rm > 0.0 {
                    r_u /= rm;
                    thr /= rm;
                }
                inv_mis = 1.0 / crate::spectrum::mean(r_u);
                if ds.event == DistanceEvent::Scatter {
                    depth += 1;
                    if depth >= world.max_depth || thr == Spectrum::ZERO {
                        break;
                    }
                    let p = ray.at(ds.t);
                    let phase = med.phase();
                    // Next-event estimation from the medium vertex, unless
                    // the medium turns it off (`sample_emitters = false`):
                    // then phase sampling alone finds the light, and the
                    // emission it finds counts fully, as after a delta
                    // interaction (Mitsuba's semantics).
                    let nee = world.media_sample_emitters[m as usize];
                    if nee {
                        let vertex = MediumVertex {
                            p,
                            d: ray.d,
                            phase,
                            medium,
                        };
                        if let Some((le, f, w)) = world.direct(&vertex, s) {
                            l += thr * le * (f * w * inv_mis);
                        }
                    }
                    let (wo, pdf) = phase.sample(ray.d, s.next_2d());
                    prev_pdf = pdf;
                    prev_p = p;
                    specular = !nee;
                    ray = Ray { o: p, d: wo };
                    start = SegmentStart::Medium;
                    t_max = f32::INFINITY;
                    if !world.roulette(depth, &mut thr, inv_mis, eta, s) {
                        break;
                    }
                    continue;
                }
                if thr == Spectrum::ZERO {
                    break;
                }
            }
            t_max = f32::INFINITY;
            let Some(h) = hit else {
                // Escaped: the environment, if any.
                if let Some(e) = world.env {
                    if !(depth == 0 && world.hide_emitters) {
                        if let Some((radiance, env_pdf)) =
                            world.emitters[e as usize].environment(ray.d)
                        {
                            let w = if specular {
                                1.0
                            } else {
                                mis_power(prev_pdf, env_pdf * world.select_pdf())
                            };
                            l += thr * radiance * (w * inv_mis);
                        }
                    }
                }
                break;
            };
            let info = world.shapes[h.shape as usize];
            // Emission of an area light seen from its front side (that of
            // the shading normal, as in `Emitter::sample`).
            if let Some(e) = info.emitter {
                if !(depth == 0 && world.hide_emitters) && h.ns.dot(ray.d) < 0.0 {
                    let em = &world.emitters[e as usize];
                    if let Some(shape) = em.area_shape() {
                        let radiance = em.area_radiance(&world.geom, &h);
                        let w = if specular {
                            1.0
                        } else {
                            let d2 = (h.p - prev_p).length_squared();
                            let cos_l = -h.ns.dot(ray.d);
                            let light_pdf = world.select_pdf() * d2
                                / (cos_l * world.geom.areas[shape as usize]);
                            mis_power(prev_pdf, light_pdf)
                        };
                        l += thr * radiance * (w * inv_mis);
                    }
                }
            }
            let bsdf = &world.bsdfs[info.bsdf as usize];
            if bsdf.is_null() {
                // Index-matched boundary: continue straight on; a new segment starts.
                medium = info.target_medium(h.n, ray.d, medium);
                let o = offset_point(h.p, h.n, ray.d);
                // The second hit of the query is the continued ray's first,
                // if it lies ahead of the offset origin (else ask again).
                known = match after {
                    Known::Unknown => Known::Unknown,
                    Known::Miss => Known::Miss,
                    Known::Hit(h2) => {
                        let h2 = world.geom.make_hit(&ray, h2);
                        let t = (h2.p - o).dot(ray.d);
                        if t > 0.0 {
                            Known::Hit(Hit { t, ..h2 })
                        } else {
                            Known::Unknown
                        }
                    }
                };
                ray = Ray { o, d: ray.d };
                start = SegmentStart::Surface;
                continue;
            }
            // This interaction would be event number depth + 1: nothing it
            // leads to can contribute unless depth + 1 < max_depth (tested
            // before the BSDF is made concrete at the hit, which a path
            // ending here does not need). A null-lobe sample may not count
            // (see below), so its sample is drawn first and the test made
            // after it.
            let null_crossings = world.thin_is_crossing && bsdf.has_null_lobe();
            if depth + 1 >= world.max_depth && !null_crossings {
                break;
            }
            let bsdf = world.bsdf_at(bsdf, &h);
            let bsdf = &*bsdf;
            let frame = world.frame_at(bsdf, &h);
            let wi_local = frame.to_local(-ray.d);
            if bsdf.is_smooth() && depth + 1 < world.max_depth {
                // Next-event estimation from the surface.
                let vertex = SurfaceVertex {
                    hit: &h,
                    info: &info,
                    bsdf,
                    frame: &frame,
                    wi_local,
                    medium,
                };
                if let Some((le, f, w)) = world.direct(&vertex, s) {
                    l += thr * le * f * (w * inv_mis);
                }
            }
            let Some(bs) = bsdf.sample(wi_local, s.next_1d(), s.next_2d()) else {
                break;
            };
            // A null-lobe sample (thin dielectric transmission, a mask's
            // transparent part) keeps the direction: under volpath an
            // index-matched crossing, not a scattering event (Mitsuba's
            // volpath gives it no depth, and emission found beyond it is
            // weighted against light sampling from the vertex before, whose
            // shadow rays pass the surface); under path a bounce, as in
            // Mitsuba's path.
            let crossing = null_crossings && bs.null;
            if !crossing && depth + 1 >= world.max_depth {
                break;
            }
            let wo = frame.to_world(bs.wo);
            thr *= bs.weight;
            eta *= bs.eta;
            if !crossing {
                depth += 1;
                specular = bs.delta;
                prev_pdf = bs.pdf;
                prev_p = h.p;
            }
            medium = info.target_medium(h.n, wo, medium);
            ray = Ray {
                o: offset_point(h.p, h.n, wo),
                d: wo,
            };
            start = SegmentStart::Surface;
            if thr == Spectrum::ZERO || !world.roulette(depth, &mut thr, inv_mis, eta, s) {
                break;
            }
        }
        l
    }

    /// `thr·inv_mis` is the path weight, the same whichever channel is the
    /// hero, so the survival probability does not depend on the hero.
    fn roulette(
        &self,
        depth: u32,
        thr: &mut Spectrum,
        inv_mis: f32,
        eta: f32,
        s: &mut Sampler,
    ) -> bool {
        // Like Mitsuba: roulette once the depth exceeds rr_depth.
        if depth <= self.rr_depth {
            return true;
        }
        // η² undoes the radiance scaling at refractions so that a path
        // inside glass is not killed for a weight it will regain on exit.
        let q = (max_comp(*thr) * inv_mis * eta * eta).min(0.95);
        if !(q > 0.0) || s.next_1d() >= q {
            return false;
        }
        *thr /= q;
        true
    }
}
