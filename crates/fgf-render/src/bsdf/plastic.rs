//! `plastic` and `roughplastic`: a diffuse base under a dielectric coating
//! (index `eta = int_ior/ext_ior`), with Mitsuba 3's model.
//!
//! * The coating reflects specularly (`plastic`: a delta lobe of weight
//!   `F(cos θ_i)`; `roughplastic`: the microfacet lobe of
//!   [`super::rough::RoughConductor`] with the dielectric `F`).
//! * Light entering the coating reaches the base and leaves diffusely,
//!   `ρ/(1 - F_int)` (or `ρ/(1 - ρ F_int)` with `nonlinear`) times
//!   `(1/π) η⁻² t(θ_i) t(θ_o) cos θ_o`, where `t` is the transmittance of the
//!   coating (`1 - F` smooth; rough: one minus the microfacet lobe's
//!   albedo, tabulated on 64 cosines and interpolated linearly as Mitsuba
//!   does) and `F_int` the coating's internal diffuse reflectance.
//! * The lobe is chosen with probabilities proportional to
//!   `(1 - t_i)·w_s` and `t_i·(1 - w_s)`, `w_s = s̄/(s̄ + d̄)` from the means
//!   of the specular and diffuse reflectances.

use super::fresnel::{fresnel_dielectric, fresnel_diffuse_reflectance_fit};
use super::microfacet::{reflect, Microfacet};
use super::BsdfSample;
use crate::math::{cosine_hemisphere_pdf, sample_cosine_hemisphere};
use crate::spectrum::{mean, Spectrum};
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// Cosines at which the rough coating's transmittance is tabulated.
pub const TABLE_RES: usize = 64;

/// The diffuse base and coating parameters shared by both plugins.
#[derive(Debug, Clone, Copy)]
pub struct Coated {
    pub eta: f32,
    pub inv_eta2: f32,
    pub diffuse: Spectrum,
    pub specular: Spectrum,
    pub nonlinear: bool,
    /// Internal diffuse reflectance of the coating.
    pub f_int: f32,
    /// `w_s` of the lobe choice.
    pub spec_weight: f32,
}

impl Coated {
    fn new(eta: f32, diffuse: Spectrum, specular: Spectrum, nonlinear: bool, f_int: f32) -> Self {
        let (d, s) = (mean(diffuse), mean(specular));
        Coated {
            eta,
            inv_eta2: 1.0 / (eta * eta),
            diffuse,
            specular,
            nonlinear,
            f_int,
            spec_weight: if d + s > 0.0 { s / (d + s) } else { 0.5 },
        }
    }

    /// `ρ/(1 - F_int)` or `ρ/(1 - ρ F_int)` times `η⁻²/π`.
    #[inline]
    fn base(&self) -> Spectrum {
        let denom = if self.nonlinear {
            Spectrum::ONE - self.diffuse * self.f_int
        } else {
            Spectrum::splat(1.0 - self.f_int)
        };
        self.diffuse / denom * (self.inv_eta2 * FRAC_1_PI)
    }

    /// Probability of the specular lobe given the coating transmittance `t_i`.
    #[inline]
    fn prob_specular(&self, t_i: f32) -> f32 {
        let ps = (1.0 - t_i) * self.spec_weight;
        let pd = t_i * (1.0 - self.spec_weight);
        if ps + pd > 0.0 {
            ps / (ps + pd)
        } else {
            0.0
        }
    }
}

/// `plastic`: smooth coating.
#[derive(Debug, Clone, Copy)]
pub struct Plastic {
    pub c: Coated,
}

impl Plastic {
    pub fn new(eta: f32, diffuse: Spectrum, specular: Spectrum, nonlinear: bool) -> Self {
        Plastic {
            c: Coated::new(
                eta,
                diffuse,
                specular,
                nonlinear,
                fresnel_diffuse_reflectance_fit(eta),
            ),
        }
    }

    /// The diffuse lobe only (the specular one is a delta).
    pub fn eval_pdf(&self, wi: Vec3, wo: Vec3) -> (Spectrum, f32) {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return (Spectrum::ZERO, 0.0);
        }
        let fi = fresnel_dielectric(wi.z, self.c.eta).r;
        let fo = fresnel_dielectric(wo.z, self.c.eta).r;
        let f = self.c.base() * ((1.0 - fi) * (1.0 - fo) * wo.z);
        let pd = 1.0 - self.c.prob_specular(1.0 - fi);
        (f, pd * cosine_hemisphere_pdf(wo.z))
    }

    pub fn sample(&self, wi: Vec3, u1: f32, u: [f32; 2]) -> Option<BsdfSample> {
        if wi.z <= 0.0 {
            return None;
        }
        let fi = fresnel_dielectric(wi.z, self.c.eta).r;
        let ps = self.c.prob_specular(1.0 - fi);
        if u1 < ps {
            return Some(BsdfSample {
                wo: Vec3::new(-wi.x, -wi.y, wi.z),
                weight: self.c.specular * (fi / ps),
                pdf: ps,
                delta: true,
                eta: 1.0,
            });
        }
        let wo = sample_cosine_hemisphere(u);
        if wo.z <= 0.0 {
            return None;
        }
        let fo = fresnel_dielectric(wo.z, self.c.eta).r;
        let pd = 1.0 - ps;
        // f·cos/pdf with pdf = pd·cos/π.
        let weight = self.c.base() * (std::f32::consts::PI * (1.0 - fi) * (1.0 - fo) / pd);
        Some(BsdfSample {
            wo,
            weight,
            pdf: pd * cosine_hemisphere_pdf(wo.z),
            delta: false,
            eta: 1.0,
        })
    }
}

/// `roughplastic`: rough coating (isotropic roughness).
#[derive(Debug, Clone)]
pub struct RoughPlastic {
    pub c: Coated,
    pub distr: Microfacet,
    /// Coating transmittance `1 - E(μ)` at `μ_i = max(1e-6, i/63)`.
    pub t_ext: Box<[f32; TABLE_RES]>,
}

/// Albedo `E(μ)` of the microfacet reflection lobe with dielectric Fresnel
/// (relative index `eta`) at incidence cosine `mu`: `E = ∫ F(wi·m) G1(wo, m)
/// dD_wi(m)` over the visible normals, by a midpoint rule on the
/// visible-normal sampler's unit square (`n × n` nodes).
fn lobe_albedo(distr: &Microfacet, mu: f32, eta: f32, n: usize) -> f32 {
    let visible = Microfacet {
        visible: true,
        ..*distr
    };
    let wi = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let mut sum = 0.0f64;
    for i in 0..n {
        for j in 0..n {
            let u = [(i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32];
            let m = visible.sample(wi, u);
            let wo = reflect(wi, m);
            if wo.z <= 0.0 {
                continue;
            }
            let f = fresnel_dielectric(wi.dot(m), eta).r;
            sum += (f * visible.g1(wo, m)) as f64;
        }
    }
    (sum / (n * n) as f64) as f32
}

impl RoughPlastic {
    pub fn new(
        eta: f32,
        diffuse: Spectrum,
        specular: Spectrum,
        nonlinear: bool,
        distr: Microfacet,
    ) -> Self {
        const N: usize = 40;
        let mut t_ext = Box::new([0.0f32; TABLE_RES]);
        let mut internal = 0.0f64;
        for (i, t) in t_ext.iter_mut().enumerate() {
            let mu = (i as f32 / (TABLE_RES - 1) as f32).max(1e-6);
            *t = 1.0 - lobe_albedo(&distr, mu, eta, N);
            internal += (lobe_albedo(&distr, mu, 1.0 / eta, N) * mu) as f64;
        }
        // Mitsuba's internal reflectance: 2·mean(E_{1/η}(μ_i)·μ_i).
        let f_int = (2.0 * internal / TABLE_RES as f64) as f32;
        RoughPlastic {
            c: Coated::new(eta, diffuse, specular, nonlinear, f_int),
            distr,
            t_ext,
        }
    }

    #[inline]
    fn t(&self, mu: f32) -> f32 {
        let x = mu * (TABLE_RES - 1) as f32;
        let i = (x as usize).min(TABLE_RES - 2);
        let w = x - i as f32;
        (1.0 - w) * self.t_ext[i] + w * self.t_ext[i + 1]
    }

    pub fn eval_pdf(&self, wi: Vec3, wo: Vec3) -> (Spectrum, f32) {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return (Spectrum::ZERO, 0.0);
        }
        let (ti, to) = (self.t(wi.z), self.t(wo.z));
        let mut f = self.c.base() * (ti * to * wo.z);
        let ps = self.c.prob_specular(ti);
        let mut pdf = (1.0 - ps) * cosine_hemisphere_pdf(wo.z);
        if let Some(h) = (wi + wo).try_normalize() {
            let d = self.distr.d(h);
            if d > 0.0 {
                let fr = fresnel_dielectric(wi.dot(h), self.c.eta).r;
                let g = self.distr.g(wi, wo, h);
                f += self.c.specular * (fr * d * g / (4.0 * wi.z));
                pdf += ps * self.distr.pdf(wi, h) / (4.0 * wo.dot(h));
            }
        }
        (f, pdf)
    }

    pub fn sample(&self, wi: Vec3, u1: f32, u: [f32; 2]) -> Option<BsdfSample> {
        if wi.z <= 0.0 {
            return None;
        }
        let ps = self.c.prob_specular(self.t(wi.z));
        let wo = if u1 < ps {
            reflect(wi, self.distr.sample(wi, u))
        } else {
            sample_cosine_hemisphere(u)
        };
        if wo.z <= 0.0 {
            return None;
        }
        let (f, pdf) = self.eval_pdf(wi, wo);
        (pdf > 0.0).then(|| BsdfSample {
            wo,
            weight: f / pdf,
            pdf,
            delta: false,
            eta: 1.0,
        })
    }
}
