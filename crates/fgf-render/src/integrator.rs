//! The compiled scene ([`World`]) and the volumetric path tracer.
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
//!   delta surface (or directly from the camera) count fully.
//! * Shadow rays pass through `null` boundaries and media (transmittance
//!   estimates); any other surface blocks them.
//! * Russian roulette once the depth exceeds `rr_depth`: survival probability
//!   `min(max(throughput)·η², 0.95)`.
//! * RGB throughput; media sample free flights with spectral MIS (see
//!   [`crate::medium`]).

use crate::bsdf::Bsdf;
use crate::camera::Camera;
use crate::emitter::Emitter;
use crate::geometry::{offset_point, shadow_epsilon, Geometry, Hit, Ray};
use crate::math::{max_comp, mis_power, Frame, Sampler, Spectrum, UNIFORM_SPHERE_PDF};
use crate::medium::{DistanceEvent, Medium, SegmentEnd, SegmentStart};
use crate::render::RenderError;
use fgf_scene::SceneDesc;
use glam::Vec3;

/// Null-boundary crossings a shadow ray keeps per query (see
/// [`World::shadow`]).
const MAX_CROSSINGS: usize = 8;

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
    fn target_medium(&self, n: Vec3, d: Vec3, current: Option<u32>) -> Option<u32> {
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
    any_null: bool,
}

impl World {
    pub fn build(desc: &SceneDesc) -> Result<World, RenderError> {
        desc.validate()?;
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
        let medium_index = |m: Option<usize>| m.map(|i| i as u32);
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
                interior: medium_index(s.interior),
                exterior: medium_index(s.exterior),
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
        let camera_medium = medium_index(desc.sensor.medium);
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
            camera_medium,
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

    /// Probability of picking one given emitter for next-event estimation.
    #[inline]
    fn select_pdf(&self) -> f32 {
        1.0 / self.emitters.len() as f32
    }

    /// Transmittance from `p` (offset off the surface with normal `n`, if on
    /// one) toward direction `wi` over `dist`, through null boundaries and
    /// media; zero if any other surface blocks it.
    ///
    /// One traversal ([`Geometry::for_each_hit`]) finds every surface on the
    /// segment: it stops at the first blocker, and otherwise returns the
    /// null-boundary crossings, which are walked in order to apply each
    /// medium's transmittance to its piece of the segment. Crossings are
    /// kept [`MAX_CROSSINGS`] at a time, nearest first; a segment crossing
    /// more boundaries than that is resumed with a further query past the
    /// last crossing handled.
    #[allow(clippy::too_many_arguments)]
    fn shadow(
        &self,
        p: Vec3,
        n: Option<Vec3>,
        wi: Vec3,
        dist: f32,
        mut medium: Option<u32>,
        mut start: SegmentStart,
        s: &mut Sampler,
    ) -> Spectrum {
        let o = match n {
            Some(n) => offset_point(p, n, wi),
            None => p,
        };
        // Aim at the target from the offset origin: keeping `wi` from the
        // un-offset point would reach the light's surface earlier by
        // offset/cos, more than the shadow epsilon at grazing angles, and the
        // light would shadow itself.
        let (d, t_end) = if n.is_none() {
            (
                wi,
                dist - if dist.is_finite() {
                    shadow_epsilon(p + wi * dist)
                } else {
                    0.0
                },
            )
        } else if dist.is_finite() {
            let q = p + wi * dist;
            let v = q - o;
            let len = v.length();
            (v / len, len - shadow_epsilon(q))
        } else {
            (wi, f32::INFINITY)
        };
        if !(t_end > 0.0) {
            return Spectrum::ONE;
        }
        let ray = Ray { o, d };
        let mut tr = Spectrum::ONE;
        // Distance and primitive of the last crossing handled: a resumed
        // query skips everything up to it, in (t, primitive) order.
        let mut done = (0.0f32, 0u32);
        loop {
            let mut xs = [(0.0f32, 0u32, 0u32, Vec3::ZERO); MAX_CROSSINGS];
            let mut len = 0usize;
            let mut more = false;
            let open = self.geom.for_each_hit(&ray, t_end, |prim, shape, t, n| {
                if (t, prim) <= done {
                    return true;
                }
                if !self.shapes[shape as usize].null {
                    return false;
                }
                // Insert in (t, prim) order, keeping the nearest MAX_CROSSINGS.
                let key = (t, prim);
                if len == MAX_CROSSINGS {
                    more = true;
                    if key >= (xs[len - 1].0, xs[len - 1].1) {
                        return true;
                    }
                    len -= 1;
                }
                let mut i = len;
                while i > 0 && key < (xs[i - 1].0, xs[i - 1].1) {
                    xs[i] = xs[i - 1];
                    i -= 1;
                }
                xs[i] = (t, prim, shape, n);
                len += 1;
                true
            });
            if !open {
                return Spectrum::ZERO;
            }
            // Segments [done.0, x.t] for each crossing x, then (if all
            // crossings are in hand) the last one up to t_end.
            let last = (!more).then_some(None);
            for x in xs[..len].iter().map(Some).chain(last) {
                if let Some(m) = medium {
                    let t_next = x.map_or(t_end, |x| x.0);
                    let seg = Ray {
                        o: ray.at(done.0),
                        d,
                    };
                    let t_seg = (t_next - done.0).max(0.0);
                    tr *= self.media[m as usize].transmittance(
                        &seg,
                        t_seg,
                        start,
                        SegmentEnd::Surface,
                        s,
                    );
                    if tr == Spectrum::ZERO {
                        return tr;
                    }
                }
                let Some(&(t, prim, shape, n)) = x else {
                    break;
                };
                medium = self.shapes[shape as usize].target_medium(n, d, medium);
                start = SegmentStart::Surface;
                done = (t, prim);
            }
            if !more {
                return tr;
            }
        }
    }

    /// Pick an emitter and sample it from `p`; returns the direction, the
    /// unoccluded-and-transmitted `Le/pdf` and the light pdf for MIS.
    #[inline]
    fn sample_light(
        &self,
        p: Vec3,
        n: Option<Vec3>,
        medium: Option<u32>,
        start: SegmentStart,
        s: &mut Sampler,
    ) -> Option<(Vec3, Spectrum, f32, bool)> {
        if self.emitters.is_empty() {
            return None;
        }
        let n_em = self.emitters.len();
        let k = ((s.next_1d() * n_em as f32) as usize).min(n_em - 1);
        let u_sel = s.next_1d();
        let u = s.next_2d();
        let ls = self.emitters[k].sample(&self.geom, p, u_sel, u)?;
        let pdf = ls.pdf * self.select_pdf();
        let tr = self.shadow(p, n, ls.wi, ls.dist, medium, start, s);
        if tr == Spectrum::ZERO {
            return None;
        }
        Some((ls.wi, ls.value * tr / pdf, pdf, ls.delta))
    }

    /// Radiance arriving at the camera along `ray` (one sample).
    pub fn li(&self, mut ray: Ray, t_max_primary: f32, s: &mut Sampler) -> Spectrum {
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
        let hero = ((s.next_1d() * 3.0) as usize).min(2);
        let mut r_u = Spectrum::ONE;
        let mut inv_mis = 1.0f32;
        // The nearest hit of `ray`, when a previous query already found it.
        let mut known: Option<Option<Hit>> = None;
        loop {
            // `after`: what the query says of the ray continued through `hit`.
            let (hit, after) = match known.take() {
                Some(h) => (h, None),
                None if self.any_null => {
                    let (h1, h2) = self.geom.intersect2(&ray, t_max);
                    // No second hit below a finite t_max says nothing of
                    // what lies beyond it.
                    (h1, (h2.is_some() || t_max == f32::INFINITY).then_some(h2))
                }
                None => (self.geom.intersect(&ray, t_max), None),
            };
            let t_surf = hit.map_or(t_max, |h| h.t);
            if let Some(m) = medium {
                let med = &self.media[m as usize];
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
                inv_mis = 1.0 / crate::math::mean(r_u);
                if ds.event == DistanceEvent::Scatter {
                    depth += 1;
                    if depth >= self.max_depth || thr == Spectrum::ZERO {
                        break;
                    }
                    let p = ray.at(ds.t);
                    let phase = med.phase();
                    // Next-event estimation from the medium vertex.
                    if let Some((wi, le, light_pdf, delta)) =
                        self.sample_light(p, None, medium, SegmentStart::Medium, s)
                    {
                        let f = phase.eval(ray.d, wi);
                        let w = if delta { 1.0 } else { mis_power(light_pdf, f) };
                        l += thr * le * (f * w * inv_mis);
                    }
                    let (wo, pdf) = phase.sample(ray.d, s.next_2d());
                    prev_pdf = pdf;
                    prev_p = p;
                    specular = false;
                    ray = Ray { o: p, d: wo };
                    start = SegmentStart::Medium;
                    t_max = f32::INFINITY;
                    if !self.roulette(depth, &mut thr, inv_mis, eta, s) {
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
                if let Some(e) = self.env {
                    if !(depth == 0 && self.hide_emitters) {
                        if let Emitter::Constant { radiance } = self.emitters[e as usize] {
                            let w = if specular {
                                1.0
                            } else {
                                mis_power(prev_pdf, UNIFORM_SPHERE_PDF * self.select_pdf())
                            };
                            l += thr * radiance * (w * inv_mis);
                        }
                    }
                }
                break;
            };
            let info = self.shapes[h.shape as usize];
            // Emission of an area light seen from its front side.
            if let Some(e) = info.emitter {
                if !(depth == 0 && self.hide_emitters) && h.n.dot(ray.d) < 0.0 {
                    if let Emitter::Area { radiance, shape } = self.emitters[e as usize] {
                        let w = if specular {
                            1.0
                        } else {
                            let d2 = (h.p - prev_p).length_squared();
                            let cos_l = -h.n.dot(ray.d);
                            let light_pdf =
                                self.select_pdf() * d2 / (cos_l * self.geom.areas[shape as usize]);
                            mis_power(prev_pdf, light_pdf)
                        };
                        l += thr * radiance * (w * inv_mis);
                    }
                }
            }
            let bsdf = self.bsdfs[info.bsdf as usize];
            if bsdf.is_null() {
                // Index-matched boundary: continue straight on; a new segment starts.
                medium = info.target_medium(h.n, ray.d, medium);
                let o = offset_point(h.p, h.n, ray.d);
                // The second hit of the query is the continued ray's first,
                // if it lies ahead of the offset origin (else ask again).
                known = after.and_then(|h2| match h2 {
                    None => Some(None),
                    Some(h2) => {
                        let h2 = self.geom.make_hit(&ray, h2);
                        let t = (h2.p - o).dot(ray.d);
                        (t > 0.0).then_some(Some(Hit { t, ..h2 }))
                    }
                });
                ray = Ray { o, d: ray.d };
                start = SegmentStart::Surface;
                continue;
            }
            // This interaction would be event number depth + 1: nothing it
            // leads to can contribute unless depth + 1 < max_depth.
            if depth + 1 >= self.max_depth {
                break;
            }
            let frame = Frame::from_normal(h.ns);
            let wi_local = frame.to_local(-ray.d);
            if bsdf.is_smooth() {
                // Next-event estimation from the surface.
                if let Some((le, f, w)) =
                    self.sample_light_surface(&h, &info, &bsdf, &frame, wi_local, medium, s)
                {
                    l += thr * le * f * (w * inv_mis);
                }
            }
            let Some(bs) = bsdf.sample(wi_local, s.next_1d(), s.next_2d()) else {
                break;
            };
            let wo = frame.to_world(bs.wo);
            thr *= bs.weight;
            eta *= bs.eta;
            depth += 1;
            specular = bs.delta;
            prev_pdf = bs.pdf;
            prev_p = h.p;
            medium = info.target_medium(h.n, wo, medium);
            ray = Ray {
                o: offset_point(h.p, h.n, wo),
                d: wo,
            };
            start = SegmentStart::Surface;
            if thr == Spectrum::ZERO || !self.roulette(depth, &mut thr, inv_mis, eta, s) {
                break;
            }
        }
        l
    }

    /// Light sampling from a surface point: like [`Self::sample_light`], but
    /// the shadow ray starts in the medium on the side it leaves toward, and
    /// it is only traced if the BSDF is non-zero for the sampled direction.
    /// Returns `(Le·Tr/pdf, f·|cos|, MIS weight)`.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    fn sample_light_surface(
        &self,
        h: &Hit,
        info: &ShapeInfo,
        bsdf: &Bsdf,
        frame: &Frame,
        wi_local: Vec3,
        medium: Option<u32>,
        s: &mut Sampler,
    ) -> Option<(Spectrum, Spectrum, f32)> {
        if self.emitters.is_empty() {
            return None;
        }
        let n_em = self.emitters.len();
        let k = ((s.next_1d() * n_em as f32) as usize).min(n_em - 1);
        let u_sel = s.next_1d();
        let u = s.next_2d();
        let ls = self.emitters[k].sample(&self.geom, h.p, u_sel, u)?;
        let (f, bsdf_pdf) = bsdf.eval_pdf(wi_local, frame.to_local(ls.wi));
        if f == Spectrum::ZERO {
            return None;
        }
        let pdf = ls.pdf * self.select_pdf();
        let m = info.target_medium(h.n, ls.wi, medium);
        let tr = self.shadow(h.p, Some(h.n), ls.wi, ls.dist, m, SegmentStart::Surface, s);
        if tr == Spectrum::ZERO {
            return None;
        }
        let w = if ls.delta {
            1.0
        } else {
            mis_power(pdf, bsdf_pdf)
        };
        Some((ls.value * tr / pdf, f, w))
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
