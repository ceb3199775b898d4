//! Next-event estimation: one routine, [`World::direct`], samples a light
//! from a scattering vertex in a medium or on a surface and traces the
//! shadow ray. The two kinds of vertex differ only in what [`Scatterer`]
//! says: the scattering value toward the light (the phase function, or the
//! BSDF times the cosine) with its sampling pdf for MIS, and where the
//! shadow ray starts (in the medium, or offset off the surface into the
//! medium on the side it leaves toward).

use crate::bsdf::Bsdf;
use crate::emitter::LightSample;
use crate::geometry::Hit;
use crate::math::{bin_index, mis_power, Frame, Sampler};
use crate::medium::{SegmentEnd, SegmentStart};
use crate::phase::Phase;
use crate::ray::{offset_point, shadow_epsilon, Ray};
use crate::spectrum::Spectrum;
use crate::world::{ShapeInfo, World};
use glam::Vec3A;

/// Null-boundary crossings a shadow ray keeps per query (see
/// [`World::shadow`]).
const MAX_CROSSINGS: usize = 8;

/// Where a shadow ray starts.
#[derive(Debug, Clone, Copy)]
pub(super) struct ShadowOrigin {
    pub p: Vec3A,
    /// The geometric normal of the surface `p` lies on (`None` in a medium).
    pub n: Option<Vec3A>,
    /// The medium the ray starts in.
    pub medium: Option<u32>,
    pub start: SegmentStart,
}

/// A vertex that scatters light toward the path, as next-event estimation
/// sees it.
pub(super) trait Scatterer {
    /// The scattering value: the phase function (`f32`, grey) or the BSDF
    /// times `|cos|` (RGB).
    type Value: Copy;
    /// The vertex position.
    fn point(&self) -> Vec3A;
    /// The scattering value toward world direction `wi` and the pdf with
    /// which the vertex itself samples `wi` (for MIS); `None` where it is
    /// zero, and then no shadow ray is traced.
    fn toward(&self, wi: Vec3A) -> Option<(Self::Value, f32)>;
    /// Where a shadow ray toward `wi` starts.
    fn shadow_origin(&self, wi: Vec3A) -> ShadowOrigin;
}

/// A scattering event in a medium; `d` is the direction the path arrived
/// along.
pub(super) struct MediumVertex {
    pub p: Vec3A,
    pub d: Vec3A,
    pub phase: Phase,
    pub medium: Option<u32>,
}

impl Scatterer for MediumVertex {
    type Value = f32;
    #[inline]
    fn point(&self) -> Vec3A {
        self.p
    }
    #[inline]
    fn toward(&self, wi: Vec3A) -> Option<(f32, f32)> {
        // The phase function is sampled exactly: its value is its pdf.
        let f = self.phase.eval(self.d, wi);
        Some((f, f))
    }
    #[inline]
    fn shadow_origin(&self, _wi: Vec3A) -> ShadowOrigin {
        ShadowOrigin {
            p: self.p,
            n: None,
            medium: self.medium,
            start: SegmentStart::Medium,
        }
    }
}

/// A hit on a non-null surface, with the shading frame and the direction
/// toward the previous vertex in it; `medium` is the medium the path
/// arrived through.
pub(super) struct SurfaceVertex<'a> {
    pub hit: &'a Hit,
    pub info: &'a ShapeInfo,
    pub bsdf: &'a Bsdf,
    pub frame: &'a Frame,
    pub wi_local: Vec3A,
    pub medium: Option<u32>,
}

impl Scatterer for SurfaceVertex<'_> {
    type Value = Spectrum;
    #[inline]
    fn point(&self) -> Vec3A {
        self.hit.p
    }
    #[inline(always)]
    fn toward(&self, wi: Vec3A) -> Option<(Spectrum, f32)> {
        let (f, pdf) = self.bsdf.eval_pdf(self.wi_local, self.frame.to_local(wi));
        (f != Spectrum::ZERO).then_some((f, pdf))
    }
    #[inline]
    fn shadow_origin(&self, wi: Vec3A) -> ShadowOrigin {
        let h = self.hit;
        ShadowOrigin {
            p: h.p,
            n: Some(h.n),
            // The shadow ray starts in the medium on the side it leaves toward.
            medium: self.info.target_medium(h.n, wi, self.medium),
            start: SegmentStart::Surface,
        }
    }
}

impl World {
    /// Pick an emitter uniformly and sample it as seen from `p`.
    #[inline]
    pub(super) fn sample_emitter(&self, p: Vec3A, s: &mut Sampler) -> Option<LightSample> {
        if self.emitters.is_empty() {
            return None;
        }
        let (k, u_sel, u) = self.draw_emitter(s);
        self.emitters[k].sample(&self.geom, p, u_sel, u)
    }

    /// The draws of [`Self::sample_emitter`], in its order: the emitter
    /// (uniformly; there must be one), then its two variates.
    #[inline(always)]
    pub(super) fn draw_emitter(&self, s: &mut Sampler) -> (usize, f32, [f32; 2]) {
        let n_em = self.emitters.len();
        let k = bin_index(s.next_1d() * n_em as f32, n_em);
        let u_sel = s.next_1d();
        (k, u_sel, s.next_2d())
    }

    /// Next-event estimation from `vertex`: pick and sample a light, and
    /// trace the shadow ray (through null boundaries and media) if the
    /// vertex scatters toward it. Returns `(Le·Tr/pdf, the scattering value,
    /// the MIS weight)`, where the pdf includes the light's selection and
    /// the weight is the power heuristic against the vertex's own sampling
    /// (1 for a delta light); the caller multiplies them into the path.
    #[inline]
    pub(super) fn direct<V: Scatterer>(
        &self,
        vertex: &V,
        s: &mut Sampler,
    ) -> Option<(Spectrum, V::Value, f32)> {
        let ls = self.sample_emitter(vertex.point(), s)?;
        self.direct_from(vertex, ls, s)
    }

    /// [`Self::direct`] with its light sample `ls` drawn already.
    #[inline(always)]
    pub(super) fn direct_from<V: Scatterer>(
        &self,
        vertex: &V,
        ls: LightSample,
        s: &mut Sampler,
    ) -> Option<(Spectrum, V::Value, f32)> {
        self.direct_toward(vertex, ls, vertex.toward(ls.wi), s)
    }

    /// [`Self::direct_from`] with the vertex's value and pdf toward the
    /// light sample computed already (`toward`, as [`Scatterer::toward`]
    /// gives them).
    #[inline(always)]
    pub(super) fn direct_toward<V: Scatterer>(
        &self,
        vertex: &V,
        ls: LightSample,
        toward: Option<(V::Value, f32)>,
        s: &mut Sampler,
    ) -> Option<(Spectrum, V::Value, f32)> {
        let (f, scatter_pdf) = toward?;
        let pdf = ls.pdf * self.select_pdf();
        let tr = self.shadow(&vertex.shadow_origin(ls.wi), ls.wi, ls.dist, s);
        if tr == Spectrum::ZERO {
            return None;
        }
        let w = if ls.delta {
            1.0
        } else {
            mis_power(pdf, scatter_pdf)
        };
        Some((ls.value * tr / pdf, f, w))
    }

    /// The null transmission of a mask or thin dielectric (volpath) that
    /// `ray` crosses at distance `t` on primitive `prim`, at the hit's
    /// texture coordinates. Out of line: [`World::shadow`]'s loop stays as
    /// small as in scenes without such surfaces.
    #[cold]
    #[inline(never)]
    fn partial_transmission(&self, ray: &Ray, prim: u32, t: f32, bsdf: u32) -> Spectrum {
        let h = self.geom.hit_at(ray, prim, t);
        let b = self.bsdf_at(&self.bsdfs[bsdf as usize], &h);
        b.null_transmission(Frame::from_normal(h.ns).to_local(-ray.d))
    }

    /// Transmittance from `from.p` (offset off the surface with normal
    /// `from.n`, if on one) toward direction `wi` over `dist`, through null
    /// boundaries, media and the surfaces marked [`ShapeInfo::partial`]
    /// (times their null transmission); zero if any other surface blocks it.
    ///
    /// One traversal ([`Geometry::for_each_hit`]) finds every surface on the
    /// segment: it stops at the first blocker, and otherwise returns the
    /// null-boundary crossings, which are walked in order to apply each
    /// medium's transmittance to its piece of the segment. Crossings are
    /// kept [`MAX_CROSSINGS`] at a time, nearest first; a segment crossing
    /// more boundaries than that is resumed with a further query past the
    /// last crossing handled. In a scene where every surface blocks
    /// (none `null` or partial), the query is a plain any-hit one
    /// ([`crate::geometry::Geometry::occluded`]), which reads no record of
    /// the surface hit.
    pub(super) fn shadow(
        &self,
        from: &ShadowOrigin,
        wi: Vec3A,
        dist: f32,
        s: &mut Sampler,
    ) -> Spectrum {
        let ShadowOrigin {
            p,
            n,
            mut medium,
            mut start,
        } = *from;
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
        // Transmittance of medium `m` over [t0, t1].
        let segment = |world: &World, m: u32, start, t0: f32, t1: f32, s: &mut Sampler| {
            let seg = Ray { o: ray.at(t0), d };
            let t_seg = (t1 - t0).max(0.0);
            world.media[m as usize].transmittance(&seg, t_seg, start, SegmentEnd::Surface, s)
        };
        if !self.any_passable {
            // Every surface blocks: one any-hit query, then the medium the
            // whole segment lies in.
            if self.geom.occluded(&ray, t_end) {
                return Spectrum::ZERO;
            }
            return match medium {
                Some(m) => segment(self, m, start, 0.0, t_end, s),
                None => Spectrum::ONE,
            };
        }
        let mut tr = Spectrum::ONE;
        // Distance and primitive of the last crossing handled: a resumed
        // query skips everything up to it, in (t, primitive) order.
        let mut done = (0.0f32, 0u32);
        loop {
            // Loads from the world at their use, not hoisted before the loop
            // (and spilled) for the rare second pass (see `World::li`).
            let world = std::hint::black_box(self);
            let mut xs = [(0.0f32, 0u32, 0u32, Vec3A::ZERO); MAX_CROSSINGS];
            let mut len = 0usize;
            let mut more = false;
            let open = world.geom.for_each_hit(
                &ray,
                t_end,
                #[inline(always)]
                |prim, shape, t, n| {
                    if (t, prim) <= done {
                        return true;
                    }
                    let info = &world.shapes[shape as usize];
                    if !info.null && !info.partial {
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
                },
            );
            if !open {
                return Spectrum::ZERO;
            }
            // Segments [done.0, t] up to each crossing, then (if all
            // crossings are in hand) the last one up to t_end.
            for &(t, prim, shape, n) in &xs[..len] {
                if let Some(m) = medium {
                    tr *= segment(world, m, start, done.0, t, s);
                    if tr == Spectrum::ZERO {
                        return tr;
                    }
                }
                let info = &world.shapes[shape as usize];
                if info.partial {
                    tr *= world.partial_transmission(&ray, prim, t, info.bsdf);
                    if tr == Spectrum::ZERO {
                        return tr;
                    }
                }
                medium = info.target_medium(n, d, medium);
                start = SegmentStart::Surface;
                done = (t, prim);
            }
            if !more {
                if let Some(m) = medium {
                    tr *= segment(world, m, start, done.0, t_end, s);
                }
                return tr;
            }
        }
    }
}
