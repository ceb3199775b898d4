//! `roughconductor` and `roughdielectric`: microfacet reflection and
//! refraction (Walter et al. 2007) over a [`Microfacet`] distribution,
//! sampled through the distribution's normals and combined with light
//! sampling by MIS. Values include `|wo.z|`; transmitted radiance carries
//! Mitsuba's radiance-mode factor `(η_i/η_t)²`, which cancels the `η_t²`
//! of Walter's eq. 21.

use super::fresnel::{fresnel_conductor_rgb, fresnel_dielectric};
use super::microfacet::{reflect, Microfacet};
use super::BsdfSample;
use crate::spectrum::Spectrum;
use glam::Vec3A;

/// A rough metal: `F(wi·m) D(m) G / (4 cos θ_i)` per channel.
#[derive(Debug, Clone, Copy)]
pub struct RoughConductor {
    pub eta: Spectrum,
    pub k: Spectrum,
    pub r: Spectrum,
    pub mirror: bool,
    pub distr: Microfacet,
}

impl RoughConductor {
    #[inline]
    fn fresnel(&self, cos_i: f32) -> Spectrum {
        if self.mirror {
            Spectrum::ONE
        } else {
            fresnel_conductor_rgb(cos_i, self.eta, self.k)
        }
    }

    pub fn eval_pdf(&self, wi: Vec3A, wo: Vec3A) -> (Spectrum, f32) {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return (Spectrum::ZERO, 0.0);
        }
        let Some(h) = (wi + wo).try_normalize() else {
            return (Spectrum::ZERO, 0.0);
        };
        let d = self.distr.d(h);
        if d == 0.0 {
            return (Spectrum::ZERO, 0.0);
        }
        let g = self.distr.g(wi, wo, h);
        let f = self.r * self.fresnel(wi.dot(h)) * (d * g / (4.0 * wi.z));
        let pdf = self.distr.pdf(wi, h) / (4.0 * wo.dot(h));
        (f, pdf)
    }

    pub fn sample(&self, wi: Vec3A, u: [f32; 2]) -> Option<BsdfSample> {
        let wo = self.sample_wo(wi, u)?;
        let (f, pdf) = self.eval_pdf(wi, wo);
        BsdfSample::glossy(wo, f, pdf)
    }

    /// The direction of [`Self::sample`] (`None` where it gives none
    /// before evaluating the BSDF there).
    #[inline]
    pub fn sample_wo(&self, wi: Vec3A, u: [f32; 2]) -> Option<Vec3A> {
        if wi.z <= 0.0 {
            return None;
        }
        let wo = reflect(wi, self.distr.sample(wi, u));
        (wo.z > 0.0).then_some(wo)
    }
}

/// A rough interface between two dielectrics, `eta = int_ior / ext_ior`
/// (the inside is the `-z` side). Reflection is chosen with probability
/// `F(wi·m)`, as for the smooth interface.
#[derive(Debug, Clone, Copy)]
pub struct RoughDielectric {
    pub eta: f32,
    pub r: Spectrum,
    pub t: Spectrum,
    pub distr: Microfacet,
}

impl RoughDielectric {
    /// `wi` and `wo` seen from the side of `wi` (both negated if `wi` is
    /// inside) and the relative index `η_t/η_i` for that side.
    #[inline]
    fn upper(&self, wi: Vec3A, wo: Vec3A) -> (Vec3A, Vec3A, f32) {
        if wi.z >= 0.0 {
            (wi, wo, self.eta)
        } else {
            (-wi, -wo, 1.0 / self.eta)
        }
    }

    pub fn eval_pdf(&self, wi: Vec3A, wo: Vec3A) -> (Spectrum, f32) {
        if wi.z == 0.0 || wo.z == 0.0 {
            return (Spectrum::ZERO, 0.0);
        }
        let (wi, wo, eta) = self.upper(wi, wo);
        let reflection = wo.z > 0.0;
        let h = if reflection { wi + wo } else { wi + eta * wo };
        let Some(mut m) = h.try_normalize() else {
            return (Spectrum::ZERO, 0.0);
        };
        if m.z < 0.0 {
            m = -m;
        }
        let d = self.distr.d(m);
        let g = self.distr.g(wi, wo, m);
        if d == 0.0 || g == 0.0 {
            return (Spectrum::ZERO, 0.0);
        }
        let (ci_m, co_m) = (wi.dot(m), wo.dot(m));
        let fr = fresnel_dielectric(ci_m, eta).r;
        let pdf_m = self.distr.pdf(wi, m);
        if reflection {
            let f = self.r * (fr * d * g / (4.0 * wi.z));
            (f, fr * pdf_m / (4.0 * co_m.abs()))
        } else {
            let denom = (ci_m + eta * co_m).powi(2);
            let f = self.t * ((1.0 - fr) * d * g * (ci_m * co_m).abs() / (wi.z * denom));
            let pdf = (1.0 - fr) * pdf_m * eta * eta * co_m.abs() / denom;
            (f, pdf)
        }
    }

    pub fn sample(&self, wi_in: Vec3A, u1: f32, u: [f32; 2]) -> Option<BsdfSample> {
        if wi_in.z == 0.0 {
            return None;
        }
        let sign = wi_in.z.signum();
        let (wi, _, eta) = self.upper(wi_in, Vec3A::Z);
        let m = self.distr.sample(wi, u);
        let ci_m = wi.dot(m);
        if ci_m <= 0.0 {
            return None;
        }
        let f = fresnel_dielectric(ci_m, eta);
        let (wo, eta_crossed) = if u1 < f.r {
            let wo = reflect(wi, m);
            if wo.z <= 0.0 {
                return None;
            }
            (wo, 1.0)
        } else {
            // Refraction about m: cos_t = |f.cos_t|, tangential part scaled by η_i/η_t.
            let wo = -f.eta_ti * wi + (f.eta_ti * ci_m - f.cos_t.abs()) * m;
            if wo.z >= 0.0 {
                return None;
            }
            (wo, f.eta_it)
        };
        let wo = wo * sign;
        let (value, pdf) = self.eval_pdf(wi_in, wo);
        (pdf > 0.0).then(|| BsdfSample {
            wo,
            weight: value / pdf,
            pdf,
            delta: false,
            eta: eta_crossed,
            null: false,
        })
    }
}
