//! `plastic` and `roughplastic`: a diffuse base under a dielectric coating
//! (index `eta = int_ior/ext_ior`), with Mitsuba 3's model.
//!
//! * The coating reflects specularly (`plastic`: a delta lobe of weight
//!   `F(cos θ_i)`; `roughplastic`: the microfacet lobe of
//!   [`super::rough::RoughConductor`] with the dielectric `F`).
//! * Light entering the coating reaches the base and leaves diffusely,
//!   `ρ/(1 - F_int)` (or `ρ/(1 - ρ F_int)` with `nonlinear`) times
//!   `(1/π) η⁻² t(θ_i) t(θ_o) cos θ_o`, where `t` is the transmittance of the
//!   coating (`1 - F` smooth; rough: the refracted part of the rough
//!   dielectric interface that is not masked, which is less than one minus
//!   the reflection lobe's albedo, see `lobe_transmittance`; tabulated on
//!   64 cosines and interpolated linearly as Mitsuba does) and `F_int` the
//!   coating's internal diffuse reflectance.
//! * The lobe is chosen with probabilities proportional to
//!   `(1 - t_i)·w_s` and `t_i·(1 - w_s)`, `w_s = s̄/(s̄ + d̄)` from the means
//!   of the specular and diffuse reflectances.

use super::fresnel::{fresnel_dielectric, fresnel_diffuse_reflectance_fit};
use super::microfacet::{reflect, Microfacet};
use super::BsdfSample;
use crate::math::{bin_index, cosine_hemisphere_pdf, sample_cosine_hemisphere};
use crate::spectrum::{mean, Spectrum};
use glam::Vec3A;
use rayon::prelude::*;
use std::f32::consts::FRAC_1_PI;

/// Cosines at which the rough coating's transmittance is tabulated.
pub const TABLE_RES: usize = 64;

/// Order of the Gauss–Legendre rule (per axis) of the coating integrals:
/// 32 for light entering a denser medium, 128 otherwise (total internal
/// reflection makes the integrand discontinuous), as Mitsuba 3.
fn quadrature_order(eta: f32) -> usize {
    if eta > 1.0 {
        32
    } else {
        128
    }
}

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
    pub(super) fn base(&self) -> Spectrum {
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
    pub fn eval_pdf(&self, wi: Vec3A, wo: Vec3A) -> (Spectrum, f32) {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return (Spectrum::ZERO, 0.0);
        }
        let fi = fresnel_dielectric(wi.z, self.c.eta).r;
        let fo = fresnel_dielectric(wo.z, self.c.eta).r;
        let f = self.c.base() * ((1.0 - fi) * (1.0 - fo) * wo.z);
        let pd = 1.0 - self.c.prob_specular(1.0 - fi);
        (f, pd * cosine_hemisphere_pdf(wo.z))
    }

    pub fn sample(&self, wi: Vec3A, u1: f32, u: [f32; 2]) -> Option<BsdfSample> {
        if wi.z <= 0.0 {
            return None;
        }
        let fi = fresnel_dielectric(wi.z, self.c.eta).r;
        let ps = self.c.prob_specular(1.0 - fi);
        if u1 < ps {
            return Some(BsdfSample {
                wo: Vec3A::new(-wi.x, -wi.y, wi.z),
                weight: self.c.specular * (fi / ps),
                pdf: ps,
                delta: true,
                eta: 1.0,
                null: false,
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
            null: false,
        })
    }
}

/// `roughplastic`: rough coating (isotropic roughness).
#[derive(Debug, Clone)]
pub struct RoughPlastic {
    pub c: Coated,
    pub distr: Microfacet,
    /// Coating transmittance `T(μ)` (`lobe_transmittance`) at
    /// `μ_i = max(1e-6, i/63)`. Shared, so that a textured BSDF's
    /// per-hit copy ([`super::Bsdf::at`]) does not allocate.
    pub t_ext: std::sync::Arc<[f32; TABLE_RES]>,
}

/// Gauss–Legendre nodes and weights of order `n` on `[0, 1]` (Newton on
/// the Legendre recurrence in f64).
fn gauss_legendre_01(n: usize) -> Vec<(f64, f64)> {
    let mut out = vec![(0.0, 0.0); n];
    for i in 0..n.div_ceil(2) {
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0f64, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            // p1 = P_n(x), p0 = P_{n-1}(x).
            dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let dx = p1 / dp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        // Map [-1, 1] to [0, 1].
        out[i] = (0.5 - 0.5 * x, 0.5 * w);
        out[n - 1 - i] = (0.5 + 0.5 * x, 0.5 * w);
    }
    out
}

/// `∫ g(m) dD_wi(m)` over the normals visible from `wi = (√(1-μ²), 0, μ)`,
/// by an `n × n` Gauss–Legendre rule on the visible-normal sampler's unit
/// square (the integrand is `g(wi, m)`).
fn visible_average(
    distr: &Microfacet,
    mu: f32,
    n: usize,
    g: impl Fn(Vec3A, Vec3A, &Microfacet) -> f32,
) -> f32 {
    let visible = Microfacet {
        visible: true,
        ..*distr
    };
    let wi = Vec3A::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let nodes = gauss_legendre_01(n);
    let mut sum = 0.0f64;
    for &(x, wx) in &nodes {
        for &(y, wy) in &nodes {
            let m = visible.sample(wi, [x as f32, y as f32]);
            sum += wx * wy * g(wi, m, &visible) as f64;
        }
    }
    sum as f32
}

/// Albedo `E(μ)` of the microfacet reflection lobe with dielectric Fresnel
/// (relative index `eta`): `∫ F(wi·m) G1(wo, m) dD_wi(m)`, `wo` the mirror
/// direction of `wi` about `m`.
fn lobe_reflectance(distr: &Microfacet, mu: f32, eta: f32, n: usize) -> f32 {
    visible_average(distr, mu, n, |wi, m, d| {
        let wo = reflect(wi, m);
        if wo.z <= 0.0 {
            return 0.0;
        }
        fresnel_dielectric(wi.dot(m), eta).r * d.g1(wo, m)
    })
}

/// Transmittance `T(μ)` into the rough coating (relative index `eta`):
/// `∫ (1 - F(wi·m)) G1(wt, m) dD_wi(m)`, `wt` the direction refracted
/// about `m`. The refracted light masked on its way in is lost, so `T` is
/// below `1 - E(μ)`: the gap is the coating's single-scattering energy
/// loss, large at grazing incidence (Mitsuba 3 tabulates this `T`).
fn lobe_transmittance(distr: &Microfacet, mu: f32, eta: f32, n: usize) -> f32 {
    visible_average(distr, mu, n, |wi, m, d| {
        let ci = wi.dot(m);
        if ci <= 0.0 {
            return 0.0;
        }
        let f = fresnel_dielectric(ci, eta);
        let wt = -f.eta_ti * wi + (f.eta_ti * ci + f.cos_t) * m;
        if wt.z >= 0.0 {
            return 0.0;
        }
        (1.0 - f.r) * d.g1(wt, m)
    })
}

/// The coating's tables depend only on the distribution and `eta`: the key
/// of [`COATING_TABLES`] (the exact bit patterns, so a cached table is the
/// one that would be computed).
type CoatingKey = (bool, u32, u32, u32);

/// `T(μ_i)` on the table's cosines, shared, and the internal reflectance.
type CoatingTables = (std::sync::Arc<[f32; TABLE_RES]>, f32);

/// Coating tables already computed in this process, shared by every
/// `roughplastic` with the same parameters: a scene loaded again (one load
/// per render, e.g. per seed) or many BSDFs alike build each table once.
/// Bounded: cleared when it holds [`COATING_CACHE_MAX`] entries.
static COATING_TABLES: std::sync::Mutex<
    Option<std::collections::HashMap<CoatingKey, CoatingTables>>,
> = std::sync::Mutex::new(None);
const COATING_CACHE_MAX: usize = 256;

/// `T(μ_i)` on the table's cosines and the internal reflectance `F_int`.
fn coating_tables(distr: &Microfacet, eta: f32) -> CoatingTables {
    let key = (
        distr.kind == super::microfacet::Distribution::Beckmann,
        distr.ax.to_bits(),
        distr.ay.to_bits(),
        eta.to_bits(),
    );
    // A poisoned lock only means another thread panicked mid-insert of a
    // complete value: the map is still consistent.
    let lock = || COATING_TABLES.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(hit) = lock().as_ref().and_then(|m| m.get(&key)) {
        return hit.clone();
    }
    // The cosines in parallel (about 1 s of Beckmann visible-normal
    // inversions on one core), summed in index order: deterministic.
    let rows: Vec<(f32, f64)> = (0..TABLE_RES)
        .into_par_iter()
        .map(|i| {
            let mu = (i as f32 / (TABLE_RES - 1) as f32).max(1e-6);
            let t = lobe_transmittance(distr, mu, eta, quadrature_order(eta));
            let r = lobe_reflectance(distr, mu, 1.0 / eta, quadrature_order(1.0 / eta));
            (t, (r * mu) as f64)
        })
        .collect();
    let mut t_ext = Box::new([0.0f32; TABLE_RES]);
    let mut internal = 0.0f64;
    for (t, (ti, ri)) in t_ext.iter_mut().zip(&rows) {
        *t = *ti;
        internal += ri;
    }
    // Mitsuba's internal reflectance: 2·mean(E_{1/η}(μ_i)·μ_i).
    let f_int = (2.0 * internal / TABLE_RES as f64) as f32;
    let value: CoatingTables = (t_ext.into(), f_int);
    let mut guard = lock();
    let map = guard.get_or_insert_with(Default::default);
    if map.len() >= COATING_CACHE_MAX {
        map.clear();
    }
    map.insert(key, value.clone());
    value
}

impl RoughPlastic {
    pub fn new(
        eta: f32,
        diffuse: Spectrum,
        specular: Spectrum,
        nonlinear: bool,
        distr: Microfacet,
    ) -> Self {
        let (t_ext, f_int) = coating_tables(&distr, eta);
        RoughPlastic {
            c: Coated::new(eta, diffuse, specular, nonlinear, f_int),
            distr,
            t_ext,
        }
    }

    #[inline]
    fn t(&self, mu: f32) -> f32 {
        let x = mu * (TABLE_RES - 1) as f32;
        let i = bin_index(x, TABLE_RES - 1);
        let w = x - i as f32;
        (1.0 - w) * self.t_ext[i] + w * self.t_ext[i + 1]
    }

    pub fn eval_pdf(&self, wi: Vec3A, wo: Vec3A) -> (Spectrum, f32) {
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

    pub fn sample(&self, wi: Vec3A, u1: f32, u: [f32; 2]) -> Option<BsdfSample> {
        let wo = self.sample_wo(wi, u1, u)?;
        let (f, pdf) = self.eval_pdf(wi, wo);
        BsdfSample::glossy(wo, f, pdf)
    }

    /// The direction of [`Self::sample`] (`None` where it gives none
    /// before evaluating the BSDF there).
    #[inline]
    pub fn sample_wo(&self, wi: Vec3A, u1: f32, u: [f32; 2]) -> Option<Vec3A> {
        if wi.z <= 0.0 {
            return None;
        }
        let ps = self.c.prob_specular(self.t(wi.z));
        let wo = if u1 < ps {
            reflect(wi, self.distr.sample(wi, u))
        } else {
            sample_cosine_hemisphere(u)
        };
        (wo.z > 0.0).then_some(wo)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::microfacet::Distribution;

    /// Equal parameters share one table (a second build is a cache hit,
    /// the same allocation), equal to the table computed directly; other
    /// parameters get their own.
    #[test]
    fn coating_tables_are_shared_between_equal_parameters() {
        let d = Microfacet {
            kind: Distribution::Beckmann,
            ax: 0.2345,
            ay: 0.2345,
            visible: true,
        };
        let s = Spectrum::splat(0.5);
        let a = RoughPlastic::new(1.49, s, s, false, d);
        let b = RoughPlastic::new(
            1.49,
            s * 0.5,
            s,
            true,
            Microfacet {
                visible: false,
                ..d
            },
        );
        assert!(std::sync::Arc::ptr_eq(&a.t_ext, &b.t_ext));
        assert_eq!(a.c.f_int, b.c.f_int);
        for i in [0usize, 17, TABLE_RES - 1] {
            let mu = (i as f32 / (TABLE_RES - 1) as f32).max(1e-6);
            assert_eq!(
                a.t_ext[i],
                lobe_transmittance(&d, mu, 1.49, quadrature_order(1.49))
            );
        }
        let c = RoughPlastic::new(1.5, s, s, false, d);
        assert!(!std::sync::Arc::ptr_eq(&a.t_ext, &c.t_ext));
        assert_ne!(a.t_ext[TABLE_RES / 2], c.t_ext[TABLE_RES / 2]);
    }

    /// An order-n Gauss–Legendre rule integrates polynomials of degree
    /// 2n - 1 exactly: `∫_0^1 x^k dx = 1/(k + 1)`.
    #[test]
    fn gauss_legendre_is_exact_to_degree_2n_minus_1() {
        for n in [1usize, 2, 5, 32, 128] {
            let rule = gauss_legendre_01(n);
            for k in [0, 1, 2 * n - 1] {
                let q: f64 = rule.iter().map(|&(x, w)| w * x.powi(k as i32)).sum();
                let exact = 1.0 / (k + 1) as f64;
                assert!((q - exact).abs() < 1e-12, "n={n} k={k}: {q} vs {exact}");
            }
        }
    }

    /// At normal incidence on a nearly smooth coating `T = 1 - F(1)`; on a
    /// rough one at grazing incidence, the quadrature through the visible
    /// normals equals a direct integral over the hemisphere of normals,
    /// `∫ (1 - F) G1(wt, m) G1(wi) max(0, wi·m) D(m) / cos θ_i dω_m`
    /// (midpoint rule, 1000 × 1000 in `(cos θ_m, φ_m)`), and is well below
    /// `1 - E`: the light masked after refraction is lost.
    #[test]
    fn transmittance_limits() {
        let eta = 1.5f32;
        let f0 = ((eta - 1.0) / (eta + 1.0)).powi(2);
        for kind in [Distribution::Beckmann, Distribution::Ggx] {
            let d = Microfacet {
                kind,
                ax: 1e-3,
                ay: 1e-3,
                visible: true,
            };
            let t = lobe_transmittance(&d, 1.0, eta, 32);
            assert!((t - (1.0 - f0)).abs() < 1e-4, "{kind:?}: {t}");
            let rough = Microfacet {
                ax: 0.5,
                ay: 0.5,
                ..d
            };
            let mu = 0.05f32;
            let wi = Vec3A::new((1.0 - mu * mu).sqrt(), 0.0, mu);
            let n = 1000usize;
            let mut direct = 0.0f64;
            for i in 0..n {
                let z = (i as f64 + 0.5) / n as f64;
                let r = (1.0 - z * z).sqrt();
                for j in 0..n {
                    let phi = std::f64::consts::TAU * (j as f64 + 0.5) / n as f64;
                    let m = Vec3A::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
                    let ci = wi.dot(m);
                    if ci <= 0.0 {
                        continue;
                    }
                    let f = fresnel_dielectric(ci, eta);
                    let wt = -f.eta_ti * wi + (f.eta_ti * ci + f.cos_t) * m;
                    let density = rough.g1_exact(wi, m) * ci * rough.d(m) / mu;
                    direct += ((1.0 - f.r) * rough.g1(wt, m) * density) as f64;
                }
            }
            direct *= std::f64::consts::TAU / (n * n) as f64;
            let (t, e) = (
                lobe_transmittance(&rough, mu, eta, 32),
                lobe_reflectance(&rough, mu, eta, 32),
            );
            assert!(
                (t as f64 - direct).abs() < 1e-3,
                "{kind:?}: T {t} by the visible normals, {direct} directly"
            );
            assert!(t < 1.0 - e - 0.02, "{kind:?}: T {t}, 1 - E {}", 1.0 - e);
        }
    }
}
