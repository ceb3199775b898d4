//! Homogeneous medium: analytic free flights with one-sample spectral MIS.
//!
//! A flight picks a channel `c` uniformly and samples `t ~ σ_c e^{-σ_c t}`.
//! The flight's density is then the mixture `p(t) = (1/3) Σ_c σ_c e^{-σ_c t}`
//! (and `P(t ≥ t_max) = (1/3) Σ_c e^{-σ_c t_max}` for reaching the surface),
//! and the weight is the RGB integrand over that mixture (balance heuristic
//! over channels, as in pbrt-v4 and Mitsuba's spectral `volpath`). For a grey
//! medium it reduces to the albedo at a scattering event and 1 at a surface.
//!
//! The integrator uses the path-level variant instead
//! ([`Homogeneous::sample_distance_hero`]): one hero channel per path and
//! the channel pdf ratios `r`, combined over the whole path; the
//! per-segment mixture is kept for callers that sample a single flight.

use super::{DistanceEvent, DistanceSample};
use crate::math::{self, bin_index, Sampler};
use crate::phase::Phase;
use crate::ray::Ray;
use crate::spectrum::{mean, Spectrum};

#[derive(Debug, Clone)]
pub struct Homogeneous {
    pub sigma_t: Spectrum,
    /// `albedo · sigma_t`.
    pub sigma_s: Spectrum,
    pub phase: Phase,
    /// The three channels of `sigma_t` are equal: one exponential per
    /// transmittance, none per free flight, and the hero weights' channel
    /// ratios are exactly 1.
    grey: bool,
    /// The single-scattering albedo `sigma_s / sigma_t`: the weight of a
    /// grey medium's free flights at a scattering event.
    albedo: Spectrum,
}

/// `e^{-σ t}` per channel with `0·∞ = 0` (a channel without extinction
/// transmits everything, even over an infinite distance).
#[inline]
fn tr(sigma_t: Spectrum, t: f32) -> Spectrum {
    Spectrum::new(tr1(sigma_t.x, t), tr1(sigma_t.y, t), tr1(sigma_t.z, t))
}

/// [`tr`] of one channel.
#[inline(always)]
fn tr1(sigma: f32, t: f32) -> f32 {
    if sigma == 0.0 {
        1.0
    } else {
        math::exp(-sigma * t)
    }
}

impl Homogeneous {
    pub fn new(sigma_t: Spectrum, albedo: Spectrum, phase: Phase) -> Self {
        Homogeneous {
            sigma_t,
            sigma_s: sigma_t * albedo,
            phase,
            grey: sigma_t.x == sigma_t.y && sigma_t.y == sigma_t.z,
            albedo,
        }
    }

    /// [`tr`] of this medium; a grey one needs one exponential, not three.
    #[inline]
    fn tr(&self, t: f32) -> Spectrum {
        if self.grey {
            return Spectrum::splat(tr1(self.sigma_t.x, t));
        }
        tr(self.sigma_t, t)
    }

    pub fn sample_distance(&self, _ray: &Ray, t_max: f32, s: &mut Sampler) -> DistanceSample {
        let c = bin_index(s.next_1d() * 3.0, 3);
        let sigma_c = self.sigma_t[c];
        // Inversion of the exponential CDF; 1 - u ∈ (0, 1] keeps ln finite.
        let t = if sigma_c > 0.0 {
            -math::ln(1.0 - s.next_1d()) / sigma_c
        } else {
            f32::INFINITY
        };
        if t < t_max {
            let trv = self.tr(t);
            let pdf = mean(self.sigma_t * trv);
            DistanceSample {
                t,
                weight: self.sigma_s * trv / pdf,
                event: DistanceEvent::Scatter,
            }
        } else {
            let trv = self.tr(t_max);
            let p = mean(trv);
            let weight = if p > 0.0 { trv / p } else { Spectrum::ZERO };
            DistanceSample {
                t: t_max,
                weight,
                event: DistanceEvent::Surface,
            }
        }
    }

    /// Free flight sampled with the pdf of channel `hero` only; returns the
    /// sample (weight = integrand / hero pdf) and the ratio `r` of every
    /// channel's pdf to the hero's (see `Medium::sample_distance_spectral`).
    #[inline]
    pub fn sample_distance_hero(
        &self,
        t_max: f32,
        hero: usize,
        s: &mut Sampler,
    ) -> (DistanceSample, Spectrum) {
        let sigma_h = self.sigma_t[hero];
        let t = if sigma_h > 0.0 {
            -math::ln(1.0 - s.next_1d()) / sigma_h
        } else {
            f32::INFINITY
        };
        if self.grey {
            // Every channel is the hero: the ratios σ·Tr / (σ_h·Tr_h) and
            // Tr / Tr_h are 1, and the weights need no exponential. At a
            // scattering event σ_s·Tr / (σ·Tr) is the albedo. At the surface
            // Tr / Tr = 1: Tr(t_max) > 0, because t ≥ t_max and σ·t =
            // -ln(1 - u) ≤ 24·ln 2 (or σ = 0, where Tr = 1).
            if t < t_max {
                return (
                    DistanceSample {
                        t,
                        weight: self.albedo,
                        event: DistanceEvent::Scatter,
                    },
                    Spectrum::ONE,
                );
            }
            return (
                DistanceSample {
                    t: t_max,
                    weight: Spectrum::ONE,
                    event: DistanceEvent::Surface,
                },
                Spectrum::ONE,
            );
        }
        if t < t_max {
            let trv = tr(self.sigma_t, t);
            // σ_h t ≤ -ln(2⁻²⁴) ≈ 16.6, so the hero pdf is ≥ σ_h·6e-8: no underflow.
            let pdf_h = sigma_h * trv[hero];
            let r = self.sigma_t * trv / pdf_h;
            (
                DistanceSample {
                    t,
                    weight: self.sigma_s * trv / pdf_h,
                    event: DistanceEvent::Scatter,
                },
                r,
            )
        } else {
            let trv = tr(self.sigma_t, t_max);
            let p_h = trv[hero];
            if !(p_h > 0.0) {
                return (
                    DistanceSample {
                        t: t_max,
                        weight: Spectrum::ZERO,
                        event: DistanceEvent::Surface,
                    },
                    Spectrum::ONE,
                );
            }
            (
                DistanceSample {
                    t: t_max,
                    weight: trv / p_h,
                    event: DistanceEvent::Surface,
                },
                trv / p_h,
            )
        }
    }

    #[inline]
    pub fn transmittance(&self, t_end: f32) -> Spectrum {
        self.tr(t_end)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A grey medium's hero flights: the albedo at every scattering event,
    /// 1 at every surface (never 0, even for the longest flights), and the
    /// surface reached with probability `e^{-σ t_max}` (within 5 standard
    /// errors, fixed seed).
    #[test]
    fn grey_hero_flights_weigh_the_albedo_and_reach_the_surface_at_the_rate_of_tr() {
        let (sigma, albedo, t_max) = (4.0f32, 0.8f32, 0.3f32);
        let m = Homogeneous::new(
            Spectrum::splat(sigma),
            Spectrum::splat(albedo),
            Phase::Isotropic,
        );
        let n = 200_000u64;
        let mut surface = 0u64;
        for i in 0..n {
            let mut s = Sampler::new(11, i, 0);
            let (ds, r) = m.sample_distance_hero(t_max, (i % 3) as usize, &mut s);
            assert_eq!(r, Spectrum::ONE);
            match ds.event {
                DistanceEvent::Scatter => {
                    assert!(ds.t < t_max);
                    assert_eq!(ds.weight, Spectrum::splat(albedo));
                }
                DistanceEvent::Surface => {
                    assert_eq!((ds.t, ds.weight), (t_max, Spectrum::ONE));
                    surface += 1;
                }
            }
        }
        let p = (-(sigma * t_max) as f64).exp();
        let se = (p * (1.0 - p) / n as f64).sqrt();
        let got = surface as f64 / n as f64;
        assert!(
            (got - p).abs() < 5.0 * se,
            "P(surface) {got} against {p} ± {se}"
        );
    }
}
