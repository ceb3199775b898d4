//! Non-exponential media: the `fgf` and `nonexponential` plugins
//! (`docs/theory.md` §3–4).
//!
//! # Overview
//!
//! Both plugins are usable wherever `homogeneous` is (shape `interior` /
//! `exterior`, the sensor's medium). The extinction along a ray is a random
//! field with mean `σ_m`; its ensemble-averaged transmittance `Tr(t)` is not
//! exponential. The user documentation (parameters, units, ranges, defaults,
//! an XML and a Python example) is the table at the head of
//! [`fgf_scene::xml::nonexp`], and `SceneDesc::validate` checks the
//! parameters; this module implements the media.
//!
//! # Transport
//!
//! Each RGB channel `c` has its own model `M_c` built with mean extinction
//! `σ_c` (the same `hurst`, `sw`, `length`, `alpha`, `h`, `c` for all
//! channels). With a macro density `ρ(x)` the models are evaluated on the
//! equivalent distance `s(t) = ∫_0^t ρ = τ_m(t)/σ_m` (`t_eq` of `docs/theory.md`
//! §4); without one `s = t`.
//!
//! * Free flights draw `s` from one channel's flight distribution and
//!   invert `s(t)` along the ray. The flight distribution is `p = -dTr/ds`
//!   for the energy-conserving kernel whatever the segment start, and for
//!   the reciprocal kernel `T_sm` after a [`SegmentStart::Surface`] and
//!   `T_mm` after a [`SegmentStart::Medium`]. Pink-noise and Davis–Weinstein
//!   flights come from a table of the exact inverse built with the medium
//!   (`medium/flight_table.rs`: cubic Hermite in `ln y`, checked to 1e-7
//!   on `ln t`, i.e. about one f32 ulp of the distance), which takes the
//!   reciprocal pink render from 1.36× to 1.2× the cost of an exponential one.
//! * RGB: the integrator's path-level spectral MIS
//!   ([`NonExp::sample_distance_hero`]): every flight of a camera sample
//!   uses the pdf of one *hero* channel, picked uniformly per path, and
//!   reports each channel's pdf over the hero's; the integrator weighs the
//!   path by the balance heuristic over the three channels' whole-path pdfs.
//!   Scatter weight `Λ ⊙ K(s)/K_hero(s)` with `K` the flight density (`ρ(t)`
//!   is common to all channels and cancels); reaching the surface
//!   `S(s_max)/S_hero(s_max)` with `S = Tr` (energy-conserving, reciprocal
//!   from a surface) or `T_ms` (reciprocal from a medium vertex). A grey
//!   medium gets the albedo and 1. [`NonExp::sample_distance`] is the
//!   per-flight variant (a channel picked per flight, weights over the
//!   mixture `mean_c K_c`), unbiased too but with weights whose products
//!   grow with the path depth.
//! * Shadow segments: energy-conserving `Tr` to a surface or light; reciprocal
//!   `T_ss` (surface start) or `T_ms` (medium start). Segments ending at a
//!   medium vertex (not used by the path tracer, offered for probes) give
//!   `pdf/σ_m` (energy-conserving), `T_sm/σ̄ = T_ms` or `T_mm/σ̄`
//!   (reciprocal); the vertex itself then contributes `σ_s(x)`.
//!
//! The integrator ends a segment at every surface crossing, null boundaries
//! included, and a camera or light starts on a "surface"
//! ([`super::SegmentStart`]).
//!
//! # Macro density
//!
//! `s(t)` is computed exactly, not by ray marching: the ray is cut at every
//! plane where the interpolant changes polynomial piece (voxel centres for
//! `trilinear`, voxel faces for `nearest`, and the grid's box). Inside a
//! piece a trilinear interpolant restricted to a line is a cubic in `t`, so
//! the two-point Gauss–Legendre rule integrates it exactly; inverting
//! `s(t) = s*` inside the piece is a safeguarded Newton iteration. Outside
//! the grid's box `ρ = 0` (the medium is empty there, as for Mitsuba's
//! `heterogeneous`).

use super::dda::{self, Lattice};
use super::flight_table::{exact_sample, Flight, FlightTable};
use super::{DistanceEvent, DistanceSample, SegmentEnd, SegmentStart};
use crate::error::RenderError;
use crate::math::{bin_index, Sampler};
use crate::medium::grid::GridTex;
use crate::phase::Phase;
use crate::ray::Ray;
use crate::spectrum::Spectrum;
use fgf_core::transmittance::{Davis, DavisWeinstein, Exponential, Fgf, Model, Transmittance};
use fgf_scene::{GridFilter, GridVolumeDesc, KernelDesc, MediumDesc, TransmittanceDesc};
use glam::{DVec3, Vec3A};
use std::ops::ControlFlow;

/// A non-exponential medium; see the module docs.
#[derive(Debug, Clone)]
pub struct NonExp {
    /// Per-channel model; `None` for a channel with `σ_c = 0` (transparent).
    models: [Option<Model>; 3],
    /// All three channels hold the same model: one evaluation suffices.
    grey: bool,
    /// Per channel, tabulated flight samplers (surface, medium) for models
    /// without a closed-form inverse (see [`super::flight_table`]).
    tables: [[Option<FlightTable>; 2]; 3],
    albedo: Spectrum,
    kernel: KernelDesc,
    pub phase: Phase,
    density: Option<Density>,
}

impl NonExp {
    /// Build from a `MediumDesc::NonExponential`; `index` names the medium in
    /// messages.
    pub fn from_desc(d: &MediumDesc, index: usize) -> Result<NonExp, RenderError> {
        let MediumDesc::NonExponential {
            sigma_t,
            albedo,
            phase,
            model,
            kernel,
            density,
        } = d
        else {
            return Err(RenderError::InvalidScene(format!(
                "medium {index}: not a non-exponential medium"
            )));
        };
        let mut models = [None; 3];
        for c in 0..3 {
            let s = sigma_t[c] as f64;
            if s == 0.0 {
                continue;
            }
            let m: Result<Model, fgf_core::ParamError> = match *model {
                TransmittanceDesc::Fgf { hurst, sw, length } => {
                    Fgf::new(s, hurst, sw, length).map(Model::from)
                }
                TransmittanceDesc::Exponential => Exponential::new(s).map(Model::from),
                TransmittanceDesc::Davis { alpha } => Davis::new(s, alpha).map(Model::from),
                TransmittanceDesc::DavisWeinstein { h, c } => {
                    DavisWeinstein::new(s, h, c).map(Model::from)
                }
            };
            models[c] = Some(m.map_err(|source| RenderError::Param {
                medium: index,
                source,
            })?);
        }
        let grey = models[0] == models[1] && models[1] == models[2];
        let tables_of = |m: &Option<Model>| {
            [Flight::Surface, Flight::Medium]
                .map(|f| m.as_ref().and_then(|m| FlightTable::new(m, f)))
        };
        let tables = if grey {
            let t = tables_of(&models[0]);
            [t.clone(), t.clone(), t]
        } else {
            [0, 1, 2].map(|c| tables_of(&models[c]))
        };
        let density = match density {
            Some(g) => Some(Density::new(g, index)?),
            None => None,
        };
        Ok(NonExp {
            models,
            grey,
            tables,
            albedo: crate::spectrum::from_rgb(*albedo),
            kernel: *kernel,
            phase: Phase::from_desc(phase),
            density,
        })
    }

    /// `f(M_c)` for each channel (in f64, made a [`Spectrum`] only as the
    /// ratios below), `empty` for a transparent channel; computed once for a
    /// grey medium.
    #[inline]
    fn per_channel(&self, empty: f64, f: impl Fn(&Model) -> f64) -> [f64; 3] {
        let g = |m: &Option<Model>| m.as_ref().map_or(empty, &f);
        if self.grey {
            let v = g(&self.models[0]);
            [v; 3]
        } else {
            [g(&self.models[0]), g(&self.models[1]), g(&self.models[2])]
        }
    }

    /// Draw the equivalent distance `s*` of channel `c` from `u` (from
    /// `T_mm` for a reciprocal medium start, else from `p = T_sm`; infinite
    /// for a transparent channel, which never collides) and invert
    /// `s(t) = s*` along the ray. Returns `(s*, the hit distance if before
    /// t_max, s(t_max))`, as [`Density::invert`] does.
    #[inline]
    fn draw_flight(
        &self,
        ray: &Ray,
        t_max: f32,
        c: usize,
        u: f64,
        from_medium: bool,
    ) -> (f64, Option<f64>, f64) {
        let flight = if from_medium {
            Flight::Medium
        } else {
            Flight::Surface
        };
        let s_star = match (&self.models[c], &self.tables[c][flight as usize]) {
            (Some(m), Some(table)) => table.sample(m, flight, u),
            (Some(m), None) => exact_sample(m, flight, u),
            (None, _) => f64::INFINITY,
        };
        let t_max64 = t_max as f64;
        let (hit, s_max) = match &self.density {
            None => (if s_star < t_max64 { Some(s_star) } else { None }, t_max64),
            Some(d) => d.invert(ray, t_max64, s_star),
        };
        (s_star, hit, s_max)
    }

    /// Sample a free flight over `[0, t_max]`; see the module docs.
    pub fn sample_distance(
        &self,
        ray: &Ray,
        t_max: f32,
        start: SegmentStart,
        s: &mut Sampler,
    ) -> DistanceSample {
        // Same variate order as the homogeneous medium (channel, then
        // distance), so a white-noise medium reproduces `homogeneous` with
        // `σ_eff` sample for sample.
        let c = bin_index(s.next_1d() * 3.0, 3);
        let u = s.next_1d() as f64;
        let from_medium = self.kernel == KernelDesc::Reciprocal && start == SegmentStart::Medium;
        let (s_star, hit, s_max) = self.draw_flight(ray, t_max, c, u, from_medium);
        match hit {
            Some(t) if (t as f32) < t_max => {
                // Flight density of each channel at the sampled point.
                let k = if from_medium {
                    self.per_channel(0.0, |m| m.medium_medium(s_star))
                } else {
                    self.per_channel(0.0, |m| m.pdf(s_star))
                };
                let weight = if self.grey {
                    self.albedo
                } else {
                    self.albedo * ratio_to_mean(k, 1.0)
                };
                DistanceSample {
                    t: t as f32,
                    weight,
                    event: DistanceEvent::Scatter,
                }
            }
            _ => {
                let weight = if self.grey {
                    Spectrum::ONE
                } else {
                    let sv = if from_medium {
                        self.per_channel(1.0, |m| m.medium_surface(s_max))
                    } else {
                        self.per_channel(1.0, |m| m.tr(s_max))
                    };
                    ratio_to_mean(sv, 0.0)
                };
                DistanceSample {
                    t: t_max,
                    weight,
                    event: DistanceEvent::Surface,
                }
            }
        }
    }

    /// Free flight sampled with channel `hero`'s distribution only, for the
    /// integrator's path-level spectral MIS (`Medium::sample_distance_spectral`):
    /// returns the sample, whose weight is the integrand over the hero's
    /// pdf, and `r`, every channel's flight pdf over the hero's (the
    /// flight density `K` at a scattering event, the probability `S` of
    /// reaching `t_max` otherwise). `ρ(t)` is common to all channels and
    /// cancels in both. A grey medium returns weight `Λ` (or 1) and `r = 1`.
    pub fn sample_distance_hero(
        &self,
        ray: &Ray,
        t_max: f32,
        start: SegmentStart,
        hero: usize,
        s: &mut Sampler,
    ) -> (DistanceSample, Spectrum) {
        let u = s.next_1d() as f64;
        let from_medium = self.kernel == KernelDesc::Reciprocal && start == SegmentStart::Medium;
        let (s_star, hit, s_max) = self.draw_flight(ray, t_max, hero, u, from_medium);
        match hit {
            Some(t) if (t as f32) < t_max => {
                let sample = |weight| DistanceSample {
                    t: t as f32,
                    weight,
                    event: DistanceEvent::Scatter,
                };
                if self.grey {
                    return (sample(self.albedo), Spectrum::ONE);
                }
                let k = if from_medium {
                    self.per_channel(0.0, |m| m.medium_medium(s_star))
                } else {
                    self.per_channel(0.0, |m| m.pdf(s_star))
                };
                // A zero or infinite hero density has probability zero
                // (`T_mm(0) = ∞` for pink noise needs u = 0 exactly): the
                // grey-medium answer avoids a NaN there.
                let r = ratio_to(k, hero).unwrap_or(Spectrum::ONE);
                (sample(self.albedo * r), r)
            }
            _ => {
                let sample = |weight| DistanceSample {
                    t: t_max,
                    weight,
                    event: DistanceEvent::Surface,
                };
                if self.grey {
                    return (sample(Spectrum::ONE), Spectrum::ONE);
                }
                let sv = if from_medium {
                    self.per_channel(1.0, |m| m.medium_surface(s_max))
                } else {
                    self.per_channel(1.0, |m| m.tr(s_max))
                };
                match ratio_to(sv, hero) {
                    Some(r) => (sample(r), r),
                    // The hero's probability underflowed: so did this event's.
                    None => (sample(Spectrum::ZERO), Spectrum::ONE),
                }
            }
        }
    }

    /// Transmittance of a shadow segment over `[0, t_end]`; see the module
    /// docs. Deterministic (no random numbers are drawn).
    pub fn transmittance(
        &self,
        ray: &Ray,
        t_end: f32,
        start: SegmentStart,
        end: SegmentEnd,
    ) -> Spectrum {
        let s_end = match &self.density {
            None => t_end as f64,
            Some(d) => d.optical_path(ray, t_end as f64),
        };
        let v = match (self.kernel, start, end) {
            (KernelDesc::EnergyConserving, _, SegmentEnd::Surface) => {
                self.per_channel(1.0, |m| m.tr(s_end))
            }
            (KernelDesc::EnergyConserving, _, SegmentEnd::Medium) => {
                self.per_channel(1.0, |m| m.pdf(s_end) / m.sigma_t())
            }
            (KernelDesc::Reciprocal, SegmentStart::Surface, SegmentEnd::Surface) => {
                self.per_channel(1.0, |m| m.surface_surface(s_end))
            }
            // T_ms, and T_sm/σ̄ which is the same function (reciprocity).
            (KernelDesc::Reciprocal, SegmentStart::Medium, SegmentEnd::Surface)
            | (KernelDesc::Reciprocal, SegmentStart::Surface, SegmentEnd::Medium) => {
                self.per_channel(1.0, |m| m.medium_surface(s_end))
            }
            (KernelDesc::Reciprocal, SegmentStart::Medium, SegmentEnd::Medium) => {
                self.per_channel(1.0, |m| m.medium_medium(s_end) / m.sigma_bar())
            }
        };
        Spectrum::new(v[0] as f32, v[1] as f32, v[2] as f32)
    }
}

/// `v / mean(v)` per channel. When the mean is 0 or not finite (only at a
/// zero-probability event, e.g. `T_mm(0) = ∞` for pink noise at `u = 0`, or
/// an underflowed `T_ms` far away) it returns `fallback` in every channel,
/// the grey-medium value of the ratio, instead of a NaN.
#[inline]
fn ratio_to_mean(v: [f64; 3], fallback: f64) -> Spectrum {
    let m = (v[0] + v[1] + v[2]) / 3.0;
    if m > 0.0 && m.is_finite() {
        Spectrum::new((v[0] / m) as f32, (v[1] / m) as f32, (v[2] / m) as f32)
    } else {
        Spectrum::splat(fallback as f32)
    }
}

/// `v / v[hero]` per channel, or `None` when `v[hero]` is 0 or not finite.
#[inline]
fn ratio_to(v: [f64; 3], hero: usize) -> Option<Spectrum> {
    let h = v[hero];
    (h > 0.0 && h.is_finite())
        .then(|| Spectrum::new((v[0] / h) as f32, (v[1] / h) as f32, (v[2] / h) as f32))
}

/// Relative tolerance of the in-piece inversion of `s(t)`, on `t` scaled by
/// the piece length: 1e-9 of a voxel is far below the f32 precision of the
/// returned distance.
const INVERT_TOL: f64 = 1e-9;
/// Iteration cap of that inversion: bisection alone reaches 1e-9 in 30
/// halvings, so 60 is never hit by a converging Newton-bisection.
const INVERT_MAX_ITER: u32 = 60;

/// A macro-scale density `ρ(x)` on a grid: exact line integrals and their
/// inversion (see the module docs).
#[derive(Debug, Clone)]
struct Density {
    tex: GridTex,
    /// The planes where the interpolant changes polynomial piece: voxel
    /// centres (offset 0.5) for trilinear, voxel faces (0) for nearest.
    pieces: Lattice<f64>,
}

impl Density {
    fn new(g: &GridVolumeDesc, index: usize) -> Result<Density, RenderError> {
        let what = format!("medium {index} density");
        let tex = GridTex::new(g, &what)?;
        let offset = match tex.filter() {
            GridFilter::Trilinear => 0.5,
            GridFilter::Nearest => 0.0,
        };
        let pieces = Lattice {
            res: tex.res(),
            offset,
        };
        Ok(Density { tex, pieces })
    }

    #[inline]
    fn rho(&self, o: DVec3, d: DVec3, t: f64) -> f64 {
        let p = o + d * t;
        self.tex
            .eval_unit(Vec3A::new(p.x as f32, p.y as f32, p.z as f32))
            .x as f64
    }

    /// `∫_a^b ρ` over one polynomial piece: two-point Gauss–Legendre, exact
    /// for the cubic a trilinear interpolant is along a line.
    #[inline]
    fn piece_integral(&self, o: DVec3, d: DVec3, a: f64, b: f64) -> f64 {
        // Nodes at the midpoint ± half-width / √3.
        const G: f64 = 0.577_350_269_189_625_8;
        let (m, h) = (0.5 * (a + b), 0.5 * (b - a));
        h * (self.rho(o, d, m - h * G) + self.rho(o, d, m + h * G))
    }

    /// The ray in unit-cube coordinates (same parameter `t` as the world
    /// ray), in f64 for the piece boundaries.
    #[inline]
    fn unit_ray(&self, ray: &Ray) -> (DVec3, DVec3) {
        let (o, d) = self.tex.unit_ray(ray);
        (o.as_dvec3(), d.as_dvec3())
    }

    /// `s(t_end) = ∫_0^t_end ρ` along `ray` (world parameter).
    fn optical_path(&self, ray: &Ray, t_end: f64) -> f64 {
        let (o, d) = self.unit_ray(ray);
        let mut sum = 0.0;
        let _: ControlFlow<()> = dda::walk(o, d, t_end, &self.pieces, |a, b, _| {
            sum += self.piece_integral(o, d, a, b);
            ControlFlow::Continue(())
        });
        sum
    }

    /// Solve `s(t) = s_star` for `t < t_max`: `(Some(t), s_star)`, or
    /// `(None, s(t_max))` when the ray leaves `[0, t_max]` first.
    fn invert(&self, ray: &Ray, t_max: f64, s_star: f64) -> (Option<f64>, f64) {
        let (o, d) = self.unit_ray(ray);
        let mut sum = 0.0;
        let hit = dda::walk(o, d, t_max, &self.pieces, |a, b, _| {
            let piece = self.piece_integral(o, d, a, b);
            if sum + piece < s_star {
                sum += piece;
                return ControlFlow::Continue(());
            }
            // The root lies in [a, b]: F(t) = ∫_a^t ρ - r is increasing
            // (ρ ≥ 0) with F' = ρ(t). Newton from the linear guess, kept in
            // a shrinking bracket, bisection when a step leaves it.
            let r = s_star - sum;
            let (mut lo, mut hi) = (a, b);
            let mut t = if piece > 0.0 {
                a + (b - a) * (r / piece)
            } else {
                0.5 * (a + b)
            };
            for _ in 0..INVERT_MAX_ITER {
                let fv = self.piece_integral(o, d, a, t) - r;
                if fv < 0.0 {
                    lo = t;
                } else {
                    hi = t;
                }
                let rho = self.rho(o, d, t);
                let newton = t - fv / rho;
                let next = if rho > 0.0 && newton > lo && newton < hi {
                    newton
                } else {
                    0.5 * (lo + hi)
                };
                if (next - t).abs() <= INVERT_TOL * (b - a) || hi - lo <= INVERT_TOL * (b - a) {
                    return ControlFlow::Break(next);
                }
                t = next;
            }
            ControlFlow::Break(t)
        });
        match hit {
            ControlFlow::Break(t) => (Some(t), s_star),
            ControlFlow::Continue(()) => (None, sum),
        }
    }
}
