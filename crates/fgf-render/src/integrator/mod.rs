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
//!   routine, `World::li_direct` in `direct_lighting.rs`.
//! * RGB throughput; media sample free flights with spectral MIS (see
//!   [`crate::medium`]).
//!
//! `li_path` traces one path from start to end and is the reference. In
//! scenes lit by an environment map alone and without media,
//! `World::li_beam` runs a batch of camera samples in step, as stages
//! over a `PathState`, so that some stages work on eight paths at once (the
//! light samples, the environment's radiance, and the values of GGX
//! `roughconductor` and `roughplastic` BSDFs), with each sample's bits
//! unchanged (ARCHITECTURE.md, "Rendering").

mod direct;
mod direct_lighting;

use crate::bsdf::{eval_pdf8, sample_wo8_lanes, Bsdf, BsdfSample, HitBsdf};
use crate::emitter::envmap::Envmap;
use crate::emitter::{Emitter, LightSample};
use crate::geometry::{Hit, HitRecord};
use crate::lanes::F8;
use crate::math::{bin_index, mis_power, Frame, Sampler};
use crate::medium::{DistanceEvent, SegmentStart};
use crate::ray::{offset_point, Ray};
use crate::spectrum::{max_comp, Spectrum};
use crate::world::{ShapeInfo, World};
use direct::{MediumVertex, SurfaceVertex};
use glam::Vec3A;

/// What an earlier query already says about the nearest hit of a ray.
#[derive(Debug, Clone, Copy)]
enum Known<T> {
    /// Nothing: the geometry must be asked.
    Unknown,
    /// The ray hits nothing.
    Miss,
    Hit(T),
}

/// A placeholder for the hits of paths whose next hit is not found yet.
const NO_HIT: Hit = Hit {
    t: 0.0,
    p: Vec3A::ZERO,
    n: Vec3A::ZERO,
    ns: Vec3A::ZERO,
    shape: 0,
    prim: 0,
    bary: [0.0; 2],
};

/// A path between its interactions: what the stages of
/// [`World::li_beam`] carry from one to the next. (Without media, the
/// spectral MIS factor `1 / mean(r_u)` of [`World::li_path`] is 1 and is
/// left out.)
struct PathState {
    ray: Ray,
    /// The limit of `ray` (finite only for the camera ray, at `far_clip`).
    t_max: f32,
    /// Whether a query already found the nearest hit of `ray` (a hit is
    /// kept apart from the path, in the hits of [`World::li_beam`]).
    known: Known<()>,
    /// The radiance gathered so far.
    l: Spectrum,
    thr: Spectrum,
    /// The medium `ray` travels in.
    medium: Option<u32>,
    depth: u32,
    /// The path so far is the camera followed by delta interactions only:
    /// emission found by continuation then counts without MIS.
    specular: bool,
    /// The pdf of the last scattering's sample and where it was made.
    prev_pdf: f32,
    prev_p: Vec3A,
    eta: f32,
}

/// The surface interactions at which the paths of a round of
/// [`World::li_beam`] scatter, lane `j` for path `j`: the shape hit, its
/// BSDF made concrete there and its local frame, as
/// [`World::path_advance`] finds them and the stages after it use them
/// (with the hit). Each field is an array of its own, written in place: a
/// whole interaction is some 250 bytes, which a value per path would build
/// and then copy.
struct Stops<'w> {
    info: [ShapeInfo; STEP],
    bsdf: [Option<HitBsdf<'w>>; STEP],
    frame: [Frame; STEP],
    /// The direction toward the previous vertex, in `frame`.
    wi_local: [Vec3A; STEP],
    /// The lanes where a null-lobe sample is a crossing, not a scattering
    /// event.
    null_crossings: u64,
    /// The lanes where next-event estimation is made: its light sample
    /// comes first.
    nee: u64,
}

impl<'w> Stops<'w> {
    fn new() -> Self {
        const NO_INFO: ShapeInfo = ShapeInfo {
            bsdf: 0,
            null: false,
            partial: false,
            emitter: None,
            interior: None,
            exterior: None,
        };
        const NO_FRAME: Frame = Frame {
            s: Vec3A::X,
            t: Vec3A::Y,
            n: Vec3A::Z,
        };
        Stops {
            info: [NO_INFO; STEP],
            bsdf: std::array::from_fn(|_| None),
            frame: [NO_FRAME; STEP],
            wi_local: [Vec3A::ZERO; STEP],
            null_crossings: 0,
            nee: 0,
        }
    }

    /// The BSDF at the surface interaction of lane `j`.
    #[inline(always)]
    fn bsdf(&self, j: usize) -> &Bsdf {
        match &self.bsdf[j] {
            Some(b) => b,
            None => unreachable!("a path at a surface"),
        }
    }
}

/// Where [`World::path_advance`] leaves a path.
enum Advance {
    /// The path ends; its radiance is complete.
    End,
    /// At a surface interaction (in the round's [`Stops`]), to scatter there.
    Surface,
    /// Escaped to the environment map, whose radiance is yet to be added.
    Escaped,
}

/// The fewest paths at one BSDF whose values (toward their light samples,
/// at their sampled directions) are computed together ([`eval_pdf8`]), and
/// whose sampled directions are ([`sample_wo8_lanes`]); fewer are computed
/// one by one. (By instructions an 8-lane evaluation costs about three
/// scalar ones, and 3 was also the best of 1, 2 and 3 for the directions;
/// docs/benchmarks.md.)
const EVAL8_LANES_MIN: usize = 3;

/// Most paths that [`World::li_beam`] runs in step (their lanes are bits
/// of a `u64`). More paths at a stage fill more of the eight-lane kernels'
/// groups and overlap more walks; the renderer gives it batches of up to
/// this many camera samples (docs/benchmarks.md).
pub(crate) const STEP: usize = 64;

/// Calls `f(lanes, n)` with the paths of `todo` (a mask of lanes) in
/// groups at one scene BSDF (`bsdf_id`), in lane order, up to eight at a
/// time: the `n` lanes of the group, then its last repeated to fill
/// eight. Groups of fewer than [`EVAL8_LANES_MIN`] are left out.
#[inline(always)]
fn groups8(mut todo: u64, bsdf_id: &[u32; STEP], mut f: impl FnMut([usize; 8], usize)) {
    while todo != 0 {
        let id = bsdf_id[todo.trailing_zeros() as usize];
        let (mut lanes, mut n, mut rest) = ([0usize; 8], 0, todo);
        while rest != 0 && n < 8 {
            let j = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            if bsdf_id[j] == id {
                lanes[n] = j;
                n += 1;
                todo &= !(1 << j);
            }
        }
        if n >= EVAL8_LANES_MIN {
            for k in n..8 {
                lanes[k] = lanes[n - 1];
            }
            f(lanes, n);
        }
    }
}

/// The lanes of the mask `mask`, in increasing order.
#[inline(always)]
fn lanes_of(mut mask: u64) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        let j = mask.trailing_zeros() as usize;
        mask &= mask.wrapping_sub(1);
        (j < 64).then_some(j)
    })
}

/// Lanes `c..c + 8` of `a` (wrapped around), as eight lanes.
#[inline(always)]
pub(crate) fn lanes8(a: &[f32; STEP], c: usize) -> F8 {
    F8::from_array(std::array::from_fn(|l| a[(c + l) % STEP]))
}

/// The light sample of a surface's next-event estimation.
enum NeeLight {
    /// To be drawn from the path's sampler when it is needed.
    Draw,
    /// Drawn already, by the sampler's next draws (`None`: the light gave no sample).
    Drawn(Option<LightSample>),
    /// Drawn already, with the BSDF's value and pdf toward it evaluated
    /// (`None` where the value is zero).
    Evaluated(LightSample, Option<(Spectrum, f32)>),
}

impl World {
    /// The BSDF at hit `h`: a textured BSDF is made concrete at the hit's
    /// texture coordinates, which are computed only then.
    #[inline(always)]
    pub(crate) fn bsdf_at<'a>(&'a self, bsdf: &'a Bsdf, h: &Hit) -> HitBsdf<'a> {
        HitBsdf::new(bsdf, || self.geom.uv(h))
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

    /// The scene's only emitter, if it is an environment map and the scene
    /// has no media: then [`Self::li_beam`] draws the light samples of its
    /// paths eight at a time.
    pub(crate) fn lone_envmap(&self) -> Option<&Envmap> {
        match self.emitters.as_slice() {
            [Emitter::Envmap(e)] if self.media.is_empty() => Some(e),
            _ => None,
        }
    }

    /// [`Self::li_seen`] of each of up to [`STEP`] camera samples (`rays`,
    /// `t_max`, `first` and `s` per sample), written to `out`, for a scene
    /// lit by the environment map `env` alone, without media
    /// ([`Self::lone_envmap`]). The paths go on in step, a surface
    /// interaction each per round, so that the light samples of their
    /// next-event estimations are drawn together ([`Envmap::sample8`]), the
    /// radiance of the environment found by those that escape is looked up
    /// together ([`Envmap::eval_pdf8`]), and the values of the BSDFs that
    /// have an 8-lane evaluation ([`Bsdf::has_eval8`]) toward the light
    /// samples and at the BSDF samples' directions are computed together
    /// ([`eval_pdf8`]), as are those directions where the BSDF samples
    /// visible normals ([`sample_wo8_lanes`]). Each path draws from its own
    /// sampler in the order [`Self::li_path`] does, and the lanes give the
    /// scalar functions' bits: each sample is the one `li_seen` gives.
    pub(crate) fn li_beam(
        &self,
        env: &Envmap,
        rays: &[Ray],
        t_max: &[f32],
        first: &[Option<Hit>],
        s: &mut [Sampler],
        out: &mut [Spectrum],
    ) {
        debug_assert!(self.takes_first_hit() && self.lone_envmap().is_some());
        let m = rays.len().min(STEP);
        let mut paths: [Option<PathState>; STEP] = std::array::from_fn(|_| None);
        // Each path's next hit, where its `known` says it is found.
        let mut hits = [NO_HIT; STEP];
        // The paths that go on (a mask of lanes: the loops below visit
        // only those, not all 64 while the last few paths finish).
        let mut live = 0u64;
        for j in 0..m {
            let known = match first[j] {
                Some(h) => {
                    hits[j] = h;
                    Known::Hit(())
                }
                None => Known::Miss,
            };
            paths[j] = self.path_start(rays[j], t_max[j], known, &mut s[j]);
            live |= u64::from(paths[j].is_some()) << j;
            out[j] = Spectrum::ZERO;
        }
        // Per round: each live path's next stop; the lanes (and variates)
        // of those whose next-event estimation needs a light sample, with the
        // samples drawn for them; the lanes of those that escaped.
        let mut stops = Stops::new();
        let mut need = [0usize; STEP];
        // The scene BSDF of each path at a surface.
        let mut bsdf_id = [0u32; STEP];
        let mut u = [[0f32; STEP]; 2];
        let mut light: [Option<LightSample>; STEP] = [None; STEP];
        let mut escaped = [0usize; STEP];
        let mut dirs = [[0f32; STEP]; 3];
        // Per round, of the paths at a surface: their BSDFs' values and
        // pdfs toward the light samples, their BSDF samples' variates and
        // directions (with the local incident direction and whether the
        // sample was flipped), and the samples. Each entry is written in the
        // round that reads it (made here, not per round: their 5 KiB were
        // zeroed every round).
        let (mut tf, mut tp) = ([Spectrum::ZERO; STEP], [0f32; STEP]);
        let mut us = [(0f32, [0f32; 2]); STEP];
        let mut sdir = [(Vec3A::ZERO, Vec3A::ZERO, false); STEP];
        let mut bs: [Option<BsdfSample>; STEP] = [None; STEP];
        // The walks' records of the paths' next hits ([`Self::walk_all`]).
        let mut rec: [Option<HitRecord>; STEP] = [None; STEP];
        while live != 0 {
            // `surface`: the paths at a surface interaction this round.
            let (mut n_need, mut n_escaped, mut surface) = (0, 0, 0u64);
            (stops.nee, stops.null_crossings) = (0, 0);
            self.walk_all(&mut paths, &mut hits, &mut rec, live);
            for j in lanes_of(live) {
                let Some(st) = &mut paths[j] else { continue };
                match self.path_advance(st, &hits[j], &mut stops, j) {
                    Advance::End => {
                        out[j] = st.l;
                        paths[j] = None;
                        live &= !(1 << j);
                    }
                    Advance::Escaped => {
                        for (c, d) in dirs.iter_mut().enumerate() {
                            d[n_escaped] = st.ray.d[c];
                        }
                        escaped[n_escaped] = j;
                        n_escaped += 1;
                    }
                    Advance::Surface => {
                        surface |= 1 << j;
                        bsdf_id[j] = stops.info[j].bsdf;
                        if stops.nee >> j & 1 != 0 {
                            let (_, _, uj) = self.draw_emitter(&mut s[j]);
                            (u[0][n_need], u[1][n_need]) = (uj[0], uj[1]);
                            need[n_need] = j;
                            n_need += 1;
                        }
                    }
                }
            }
            // The escaped paths end with the environment's radiance.
            for c in (0..n_escaped).step_by(8) {
                let (v, pdf) = env.eval_pdf8(dirs.each_ref().map(|d| lanes8(d, c)));
                let (v, pdf) = (v.map(F8::to_array), pdf.to_array());
                for l in 0..(n_escaped - c).min(8) {
                    let j = escaped[c + l];
                    if let Some(st) = &mut paths[j] {
                        self.add_environment(st, Vec3A::new(v[0][l], v[1][l], v[2][l]), pdf[l]);
                        out[j] = st.l;
                    }
                    paths[j] = None;
                    live &= !(1 << j);
                }
            }
            if surface == 0 {
                break;
            }
            for c in (0..n_need).step_by(8) {
                let r = env.sample8(lanes8(&u[0], c), lanes8(&u[1], c));
                let (ok, d, v, p) = (
                    r.ok.bitmask(),
                    r.d.map(F8::to_array),
                    r.value.map(F8::to_array),
                    r.pdf.to_array(),
                );
                for l in 0..(n_need - c).min(8) {
                    let at = |a: [[f32; 8]; 3]| Vec3A::new(a[0][l], a[1][l], a[2][l]);
                    light[need[c + l]] =
                        (ok >> l & 1 == 1).then(|| LightSample::environment(at(d), at(v), p[l]));
                }
            }
            // The BSDFs' values toward the light samples, eight paths at a
            // time at the same scene BSDF where it has an 8-lane
            // evaluation (`evaluated`: the paths that have them).
            let mut todo = 0u64;
            for &j in &need[..n_need] {
                if light[j].is_some() && self.bsdf_eval8[bsdf_id[j] as usize] {
                    todo |= 1 << j;
                }
            }
            let mut evaluated = 0u64;
            groups8(todo, &bsdf_id, |lanes, n| {
                let wi = lanes.map(|j| stops.wi_local[j]);
                let wo = lanes.map(|j| match &light[j] {
                    Some(ls) => stops.frame[j].to_local(ls.wi),
                    None => unreachable!("a path with a light sample"),
                });
                let (f, pdf) = eval_pdf8(&lanes.map(|j| stops.bsdf(j))[..n], wi, wo);
                for k in 0..n {
                    (tf[lanes[k]], tp[lanes[k]]) = (f[k], pdf[k]);
                    evaluated |= 1 << lanes[k];
                }
            });
            // The BSDF samples of the paths at such BSDFs: their variates
            // drawn now (the shadow rays, traced before in `li_path`'s
            // order, draw none in scenes without media), then their
            // directions, eight at a time where the scene BSDF draws them so
            // ([`sample_wo8_lanes`]; `draw8`), else one by one, and the
            // values there eight at a time (`sampled`: the paths whose
            // sample is made here; `todo`: those that have a direction).
            let (mut sampled, mut draw8, mut todo) = (0u64, 0u64, 0u64);
            for j in lanes_of(surface) {
                if !self.bsdf_eval8[bsdf_id[j] as usize] {
                    continue;
                }
                // (No sample unless a direction is found below.)
                bs[j] = None;
                us[j] = (s[j].next_1d(), s[j].next_2d());
                sampled |= 1 << j;
                draw8 |= u64::from(self.bsdf_sample8[bsdf_id[j] as usize]) << j;
            }
            let mut draw_alone = sampled;
            groups8(draw8, &bsdf_id, |lanes, n| {
                let (wi, wo, ok, flipped) = sample_wo8_lanes(
                    stops.bsdf(lanes[0]),
                    lanes.map(|j| stops.wi_local[j]),
                    lanes.map(|j| us[j].0),
                    lanes.map(|j| us[j].1),
                );
                for (k, &j) in lanes[..n].iter().enumerate() {
                    if ok >> k & 1 != 0 {
                        sdir[j] = (wi[k], wo[k], flipped >> k & 1 != 0);
                        todo |= 1 << j;
                    }
                    draw_alone &= !(1 << j);
                }
            });
            for j in lanes_of(draw_alone) {
                if let Some(d) = stops
                    .bsdf(j)
                    .sample_wo8(stops.wi_local[j], us[j].0, us[j].1)
                {
                    sdir[j] = d;
                    todo |= 1 << j;
                }
            }
            let mut alone = todo;
            groups8(todo, &bsdf_id, |lanes, n| {
                let (f, pdf) = eval_pdf8(
                    &lanes.map(|j| stops.bsdf(j))[..n],
                    lanes.map(|j| sdir[j].0),
                    lanes.map(|j| sdir[j].1),
                );
                for k in 0..n {
                    let (j, (_, wo, flipped)) = (lanes[k], sdir[lanes[k]]);
                    bs[j] = BsdfSample::glossy(wo, f[k], pdf[k]).map(|mut b| {
                        if flipped {
                            b.wo.z = -b.wo.z;
                        }
                        b
                    });
                    alone &= !(1 << j);
                }
            });
            for j in lanes_of(alone) {
                bs[j] = stops.bsdf(j).sample(stops.wi_local[j], us[j].0, us[j].1);
            }
            for j in lanes_of(surface) {
                let Some(st) = &mut paths[j] else {
                    continue;
                };
                let nee = match light[j] {
                    _ if stops.nee >> j & 1 == 0 => NeeLight::Draw,
                    Some(ls) if evaluated >> j & 1 != 0 => {
                        NeeLight::Evaluated(ls, (tf[j] != Spectrum::ZERO).then_some((tf[j], tp[j])))
                    }
                    ls => NeeLight::Drawn(ls),
                };
                let sample = (sampled >> j & 1 != 0).then_some(bs[j]);
                if !self.path_scatter(st, &hits[j], (&stops, j), nee, sample, &mut s[j]) {
                    out[j] = st.l;
                    paths[j] = None;
                    live &= !(1 << j);
                }
            }
        }
    }

    /// The nearest hits of the paths `live` whose next hit is not yet
    /// known, into `hits`, all walked before any is made into a [`Hit`]: each walk
    /// starts the load of what its hit reads first (the triangle's
    /// corners), and once all have walked, the loads of their vertices,
    /// normals and texture coordinates start together, so that these
    /// cache misses overlap with each other and
    /// with the walks instead of stalling each path in turn. (The same
    /// hits as [`Self::li_path`]'s queries; its queries of two hits, which
    /// scenes with `null` boundaries need, [`Self::li_beam`] does not
    /// serve.) `rec` holds the walks' records; each lane walked is written
    /// before it is read.
    #[inline(always)]
    fn walk_all(
        &self,
        paths: &mut [Option<PathState>; STEP],
        hits: &mut [Hit; STEP],
        rec: &mut [Option<HitRecord>; STEP],
        live: u64,
    ) {
        let geom = &self.geom;
        let mut walked = 0u64;
        for j in lanes_of(live) {
            let Some(st) = &paths[j] else { continue };
            if let Known::Unknown = st.known {
                rec[j] = geom.nearest(&st.ray, st.t_max);
                if let Some(r) = &rec[j] {
                    geom.prefetch_hit(r);
                }
                walked |= 1 << j;
            }
        }
        for j in lanes_of(walked) {
            if let Some(r) = &rec[j] {
                geom.prefetch_shading(r);
            }
        }
        for j in lanes_of(walked) {
            let Some(st) = &mut paths[j] else { continue };
            st.known = match rec[j] {
                Some(r) => {
                    hits[j] = geom.make_hit(&st.ray, r);
                    Known::Hit(())
                }
                None => Known::Miss,
            };
        }
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
                // (Grey media give ratios of exactly 1: nothing to update.)
                if r != Spectrum::ONE {
                    r_u *= r;
                    // Only ratios matter: rescale thr and r_u together so
                    // that neither under- nor overflows on long paths.
                    let rm = max_comp(r_u);
                    if !(1e-4..=1e4).contains(&rm) && rm > 0.0 {
                        r_u /= rm;
                        thr /= rm;
                    }
                    inv_mis = 1.0 / crate::spectrum::mean(r_u);
                }
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

    /// A path leaving the camera along `ray` (`None`: with `max_depth = 0`
    /// it carries nothing).
    #[inline(always)]
    fn path_start(
        &self,
        ray: Ray,
        t_max_primary: f32,
        known: Known<()>,
        s: &mut Sampler,
    ) -> Option<PathState> {
        if self.max_depth == 0 {
            return None;
        }
        // `li_path` first draws the hero channel of its spectral MIS, which
        // only media use: drawn here too, so that the streams stay in step.
        s.next_1d();
        Some(PathState {
            ray,
            t_max: t_max_primary,
            known,
            l: Spectrum::ZERO,
            thr: Spectrum::ONE,
            medium: self.camera_medium,
            depth: 0,
            specular: true,
            prev_pdf: 1.0,
            prev_p: ray.o,
            eta: 1.0,
        })
    }

    /// Follow a path of [`Self::li_beam`] to its next scattering at a
    /// surface, at its hit `h` if its `known` says there is one, and write
    /// that interaction into lane `j` of `stops`. [`Advance::End`] when the
    /// path ends first; then `st.l` is its radiance. A path that escapes
    /// to the environment map stops with [`Advance::Escaped`], before its
    /// radiance is looked up. (The same steps as [`Self::li_path`]'s
    /// in the scenes `li_beam` renders, which have no media, no `null`
    /// boundaries and no emitter but the environment map.)
    #[inline(always)]
    fn path_advance<'w>(
        &'w self,
        st: &mut PathState,
        h: &Hit,
        stops: &mut Stops<'w>,
        j: usize,
    ) -> Advance {
        // Invariant loads from the world are made here, at their use,
        // not hoisted out of `li_beam`'s loops: hoisted, they were spilled
        // to the stack (~90 instructions per sample).
        let world = std::hint::black_box(self);
        debug_assert!(!world.any_null && world.media.is_empty());
        st.t_max = f32::INFINITY;
        match std::mem::replace(&mut st.known, Known::Unknown) {
            Known::Hit(()) => {}
            Known::Miss => {
                // Escaped: the environment, if any.
                if world.env.is_some() && !(st.depth == 0 && world.hide_emitters) {
                    return Advance::Escaped;
                }
                return Advance::End;
            }
            Known::Unknown => unreachable!("`walk_all` finds every live path's next hit"),
        }
        let info = world.shapes[h.shape as usize];
        debug_assert!(info.emitter.is_none() && !info.null);
        let bsdf = &world.bsdfs[info.bsdf as usize];
        // This interaction would be event number depth + 1: nothing it
        // leads to can contribute unless depth + 1 < max_depth (tested
        // before the BSDF is made concrete at the hit, which a path
        // ending here does not need). A null-lobe sample may not count
        // (see `path_scatter`), so its sample is drawn first and the
        // test made after it.
        let null_crossings = world.thin_is_crossing && bsdf.has_null_lobe();
        if st.depth + 1 >= world.max_depth && !null_crossings {
            return Advance::End;
        }
        let bsdf = stops.bsdf[j].insert(world.bsdf_at(bsdf, h));
        let frame = world.frame_at(bsdf, h);
        stops.wi_local[j] = frame.to_local(-st.ray.d);
        stops.frame[j] = frame;
        stops.info[j] = info;
        // Next-event estimation from the surface, in `path_scatter`.
        let nee = bsdf.is_smooth() && st.depth + 1 < world.max_depth;
        stops.nee |= u64::from(nee) << j;
        stops.null_crossings |= u64::from(null_crossings) << j;
        Advance::Surface
    }

    /// Add the radiance `radiance` of the environment, which the path
    /// escaped to and whose light sampling picks its direction with pdf
    /// `env_pdf`, weighted against the path's own sample (MIS).
    #[inline(always)]
    fn add_environment(&self, st: &mut PathState, radiance: Spectrum, env_pdf: f32) {
        let w = if st.specular {
            1.0
        } else {
            mis_power(st.prev_pdf, env_pdf * self.select_pdf())
        };
        st.l += st.thr * radiance * w;
    }

    /// Scatter the path at its surface interaction, lane `j` of `stops`, at its hit `h`: next-event
    /// estimation (with the light sample `light`, if it was drawn
    /// before), then the BSDF's sample and Russian roulette. `false` when
    /// the path ends here; then `st.l` is its radiance.
    #[inline(always)]
    fn path_scatter(
        &self,
        st: &mut PathState,
        h: &Hit,
        (stops, j): (&Stops<'_>, usize),
        light: NeeLight,
        sample: Option<Option<BsdfSample>>,
        s: &mut Sampler,
    ) -> bool {
        let world = self;
        let (info, bsdf, frame) = (&stops.info[j], stops.bsdf(j), &stops.frame[j]);
        let wi_local = stops.wi_local[j];
        let null_crossings = stops.null_crossings >> j & 1 != 0;
        if stops.nee >> j & 1 != 0 {
            let vertex = SurfaceVertex {
                hit: h,
                info,
                bsdf,
                frame,
                wi_local,
                medium: st.medium,
            };
            let direct = match light {
                NeeLight::Draw => world
                    .sample_emitter(h.p, s)
                    .and_then(|ls| world.direct_from(&vertex, ls, s)),
                NeeLight::Drawn(ls) => ls.and_then(|ls| world.direct_from(&vertex, ls, s)),
                NeeLight::Evaluated(ls, toward) => world.direct_toward(&vertex, ls, toward, s),
            };
            if let Some((le, f, w)) = direct {
                st.l += st.thr * le * f * w;
            }
        }
        let bs = match sample {
            Some(bs) => bs,
            None => bsdf.sample(wi_local, s.next_1d(), s.next_2d()),
        };
        let Some(bs) = bs else {
            return false;
        };
        // A null-lobe sample (thin dielectric transmission, a mask's
        // transparent part) keeps the direction: under volpath an
        // index-matched crossing, not a scattering event (Mitsuba's
        // volpath gives it no depth, and emission found beyond it is
        // weighted against light sampling from the vertex before, whose
        // shadow rays pass the surface); under path a bounce, as in
        // Mitsuba's path.
        let crossing = null_crossings && bs.null;
        if !crossing && st.depth + 1 >= world.max_depth {
            return false;
        }
        let wo = frame.to_world(bs.wo);
        st.thr *= bs.weight;
        st.eta *= bs.eta;
        if !crossing {
            st.depth += 1;
            st.specular = bs.delta;
            st.prev_pdf = bs.pdf;
            st.prev_p = h.p;
        }
        st.medium = info.target_medium(h.n, wo, st.medium);
        st.ray = Ray {
            o: offset_point(h.p, h.n, wo),
            d: wo,
        };
        st.thr != Spectrum::ZERO && world.roulette(st.depth, &mut st.thr, 1.0, st.eta, s)
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
