//! `principled`: Mitsuba 3's Disney-style principled BSDF (Burley 2012,
//! 2015), with Mitsuba's formulas and sampling so that renders converge to
//! the same image (user docs: the table at the head of
//! [`fgf_scene::xml::bsdfs`]).
//!
//! The value (times `|cos θ_o|`) is the sum of
//!
//! * a GGX reflection lobe (`α = max(0.001, roughness²)`, stretched along
//!   the tangent by `anisotropic` as in Mitsuba) with
//!   the principled Fresnel term: on the front side `(1 − metallic)(1 −
//!   spec_tint)·F_d + metallic·S(base_color) + (1 − metallic)·spec_tint·
//!   S(c_tint R₀(η))`, where `F_d` is the exact dielectric Fresnel term
//!   of `eta` at the half vector, `S(R₀)` Schlick's approximation and
//!   `c_tint` the base colour over its luminance; from the back side
//!   `(1 − metallic)·spec_trans·F_d`;
//! * a GGX transmission lobe weighted by `(1 − metallic)·spec_trans·
//!   √base_color·(1 − F_d)` (radiance transport);
//! * a clearcoat lobe `0.25·clearcoat·F_s(0.04)·D_GTR1·G·|cos θ_o|` (GTR1
//!   of roughness `lerp(0.1, 0.001, clearcoat_gloss)`, separable Smith GGX
//!   masking of roughness 0.25; written as Mitsuba writes it, without the
//!   `1/(4 cos θ_i cos θ_o)` of a microfacet lobe);
//! * a diffuse lobe with Burley's retro-reflection, blended with the
//!   Hanrahan–Krueger-like "fake subsurface" by `flatness`, weighted by
//!   `(1 − metallic)(1 − spec_trans)`, and the sheen `sheen·(1 −
//!   metallic)·F_S(θ_d)·lerp(1, c_tint, sheen_tint)` (only where the
//!   diffuse lobe is present, as Mitsuba's `scalar_rgb` adds it).
//!
//! Sampling picks the diffuse, clearcoat, transmission or reflection lobe
//! with probabilities proportional to `(1 − metallic)(1 − spec_trans)·r_d`,
//! `0.25·clearcoat·r_c`, `(1 − metallic)·spec_trans·(1 − F_d)·r_s` and `(1 −
//! (1 − metallic)·spec_trans·(1 − F_d))·r_s` (the `r` are the sampling
//! rates; from the back side only transmission and reflection, `1 − F_d`
//! and `F_d`), where `F_d` is taken at a GGX visible normal drawn from the
//! same two random numbers that then sample the chosen lobe, and the weight
//! is the value over the pdf of all lobes (as Mitsuba computes it, at the
//! half vector of the sampled direction). Reproducing those steps exactly,
//! with the same warps (concentric disk for the cosine lobe and the
//! visible normals), gives the same expectation as Mitsuba even where that
//! pdf is not the exact density of the samples.

use super::microfacet::{reflect, Distribution, Microfacet};
use super::{fresnel_dielectric, BsdfSample};
use crate::math::sample_cosine_hemisphere;
use crate::spectrum::Spectrum;
use glam::Vec3A;
use std::f32::consts::{FRAC_1_PI, PI};

/// The principled BSDF's parameters at one surface point.
#[derive(Debug, Clone)]
pub struct Principled {
    pub base_color: Spectrum,
    pub roughness: f32,
    pub metallic: f32,
    pub spec_trans: f32,
    pub spec_tint: f32,
    pub sheen: f32,
    pub sheen_tint: f32,
    pub flatness: f32,
    pub clearcoat: f32,
    pub clearcoat_gloss: f32,
    pub anisotropic: f32,
    /// Interior over exterior index of refraction.
    pub eta: f32,
    /// `main_specular_sampling_rate`, `clearcoat_sampling_rate`,
    /// `diffuse_reflectance_sampling_rate`.
    pub spec_rate: f32,
    pub clearcoat_rate: f32,
    pub diffuse_rate: f32,
    /// `spec_trans` was given (Mitsuba's `m_has_spec_trans`: from the back
    /// side the transmission lobe is then sampled even if its weight is 0).
    pub has_spec_trans: bool,
    /// `clearcoat` was given.
    pub has_clearcoat: bool,
}

/// `clamp(1 − c, 0, 1)⁵`.
#[inline]
fn schlick_weight(c: f32) -> f32 {
    let m = (1.0 - c).clamp(0.0, 1.0);
    let m2 = m * m;
    m2 * m2 * m
}

/// Schlick's Fresnel approximation `R₀ + (1 − R₀)·w`, with the cosine on
/// the side of the smaller index (`cos_i` at the microfacet, signed).
#[inline]
fn schlick(r0: Spectrum, cos_i: f32, eta: f32) -> Spectrum {
    let eta_it = if cos_i >= 0.0 { eta } else { 1.0 / eta };
    let w = if eta_it > 1.0 {
        schlick_weight(cos_i.abs())
    } else {
        let eta_ti = 1.0 / eta_it;
        let ct2 = 1.0 - (1.0 - cos_i * cos_i) * eta_ti * eta_ti;
        schlick_weight(ct2.max(0.0).sqrt())
    };
    r0 + (Spectrum::ONE - r0) * w
}

/// The GTR1 distribution of the clearcoat (roughness `a`).
#[inline]
fn gtr1(a: f32, cos_m: f32) -> f32 {
    let a2 = a * a;
    let r = (a2 - 1.0) / (PI * a2.ln() * (1.0 + (a2 - 1.0) * cos_m * cos_m));
    if r * cos_m > 1e-20 {
        r
    } else {
        0.0
    }
}

/// Smith's GGX `G1` of roughness `a` for the clearcoat.
#[inline]
fn smith_ggx1(v: Vec3A, m: Vec3A, a: f32) -> f32 {
    if v.dot(m) * v.z <= 0.0 {
        return 0.0;
    }
    if v.z == 1.0 {
        return 1.0;
    }
    let c2 = v.z * v.z;
    let t2 = (1.0 - c2) / c2;
    2.0 / (1.0 + (1.0 + a * a * t2).sqrt())
}

/// `m` turned to the side of `s` (`m·sign(s)`, as Drjit's `mulsign`: a
/// negative zero counts as negative).
#[inline]
fn mulsign(m: Vec3A, s: f32) -> Vec3A {
    if s.is_sign_negative() {
        -m
    } else {
        m
    }
}

/// Both `wi` and `wo` on the side of the microfacet `m` that faces the
/// macro surface's incident side (reflection), or `wo` on the other side
/// (refraction).
#[inline]
fn compatible(m: Vec3A, wi: Vec3A, wo: Vec3A, cos_i: f32, reflection: bool) -> bool {
    let m = mulsign(m, cos_i);
    wi.dot(m) > 0.0
        && if reflection {
            wo.dot(m) > 0.0
        } else {
            wo.dot(-m) > 0.0
        }
}

/// The probabilities of choosing each lobe.
struct Lobes {
    diffuse: f32,
    clearcoat: f32,
    trans: f32,
    reflect: f32,
}

impl Principled {
    /// The main lobes' GGX: `α = max(0.001, roughness²)`, stretched by
    /// `anisotropic` along the frame's tangent as Mitsuba stretches it.
    #[inline]
    fn ggx(&self) -> Microfacet {
        let r2 = self.roughness * self.roughness;
        let (ax, ay) = if self.anisotropic > 0.0 {
            let aspect = (1.0 - 0.9 * self.anisotropic).sqrt();
            ((r2 / aspect).max(0.001), (r2 * aspect).max(0.001))
        } else {
            (r2.max(0.001), r2.max(0.001))
        };
        Microfacet {
            kind: Distribution::Ggx,
            ax,
            ay,
            visible: true,
        }
    }

    #[inline]
    fn clearcoat_alpha(&self) -> f32 {
        0.1 + (0.001 - 0.1) * self.clearcoat_gloss
    }

    /// The weight of the reflection-only part, `(1 − metallic)(1 − spec_trans)`,
    /// and of the transmissive part, `(1 − metallic)·spec_trans`.
    #[inline]
    fn weights(&self) -> (f32, f32) {
        let brdf = (1.0 - self.metallic) * (1.0 - self.spec_trans);
        let bsdf = if self.has_spec_trans {
            (1.0 - self.metallic) * self.spec_trans
        } else {
            0.0
        };
        (brdf, bsdf)
    }

    fn lobes(&self, front: bool, f: f32) -> Lobes {
        let (brdf, bsdf) = self.weights();
        let mut l = if front {
            Lobes {
                diffuse: brdf * self.diffuse_rate,
                clearcoat: if self.has_clearcoat {
                    0.25 * self.clearcoat * self.clearcoat_rate
                } else {
                    0.0
                },
                trans: if self.has_spec_trans {
                    self.spec_rate * bsdf * (1.0 - f)
                } else {
                    0.0
                },
                reflect: self.spec_rate * (1.0 - bsdf * (1.0 - f)),
            }
        } else {
            Lobes {
                diffuse: 0.0,
                clearcoat: 0.0,
                trans: if self.has_spec_trans { 1.0 - f } else { 0.0 },
                reflect: f,
            }
        };
        let r = 1.0 / (l.diffuse + l.clearcoat + l.trans + l.reflect);
        l.diffuse *= r;
        l.clearcoat *= r;
        l.trans *= r;
        l.reflect *= r;
        l
    }

    /// `f(wi, wo)·|cos θ_o|` and the pdf of [`Self::sample`] as Mitsuba
    /// computes it.
    pub fn eval_pdf(&self, wi: Vec3A, wo: Vec3A) -> (Spectrum, f32) {
        let cos_i = wi.z;
        if cos_i == 0.0 {
            return (Spectrum::ZERO, 0.0);
        }
        let cos_o = wo.z;
        let (brdf, bsdf) = self.weights();
        let front = cos_i > 0.0;
        let reflect = cos_i * cos_o > 0.0;
        let refract = cos_i * cos_o < 0.0;
        let eta_path = if front { self.eta } else { 1.0 / self.eta };
        let wh = (wi + wo * if reflect { 1.0 } else { eta_path }).normalize();
        let wh = mulsign(wh, wh.z);
        let (hi, ho) = (wi.dot(wh), wo.dot(wh));
        let f = fresnel_dielectric(hi, self.eta).r;
        let refl_ok = compatible(wh, wi, wo, cos_i, true);
        let refr_ok = compatible(wh, wi, wo, cos_i, false);
        let ggx = self.ggx();
        let d = ggx.d(wh);
        let g = ggx.g(wi, wo, wh);
        let mut value = Spectrum::ZERO;
        let base = self.base_color;
        let lum = fgf_scene::luminance(&base.to_array());
        let c_tint = if lum > 0.0 { base / lum } else { Spectrum::ONE };
        // Main reflection.
        if reflect && refl_ok && f > 0.0 {
            let fp = if front {
                let eta_it = if hi >= 0.0 { self.eta } else { 1.0 / self.eta };
                let r0 = ((eta_it - 1.0) / (eta_it + 1.0)).powi(2);
                Spectrum::splat((1.0 - self.metallic) * (1.0 - self.spec_tint) * f)
                    + self.metallic * schlick(base, hi, self.eta)
                    + (1.0 - self.metallic) * self.spec_tint * schlick(c_tint * r0, hi, self.eta)
            } else {
                Spectrum::splat(bsdf * f)
            };
            value += fp * (d * g / (4.0 * cos_i.abs()));
        }
        // Main transmission (radiance transport: the (1/η)² of the
        // solid-angle compression cancels the η² of the Jacobian).
        if bsdf > 0.0 && refract && refr_ok && f < 1.0 {
            let t = ((1.0 - f) * d * g * hi * ho / (cos_i * (hi + eta_path * ho).powi(2))).abs();
            value += Spectrum::new(base.x.sqrt(), base.y.sqrt(), base.z.sqrt()) * (bsdf * t);
        }
        // Clearcoat.
        let ca = self.clearcoat_alpha();
        if self.has_clearcoat && self.clearcoat > 0.0 && reflect && refl_ok && front {
            let fcc = schlick(Spectrum::splat(0.04), hi, self.eta).x;
            let gcc = smith_ggx1(wi, wh, 0.25) * smith_ggx1(wo, wh, 0.25);
            value +=
                Spectrum::splat(0.25 * self.clearcoat * fcc * gtr1(ca, wh.z) * gcc * cos_o.abs());
        }
        // Diffuse, retro-reflection, fake subsurface, sheen.
        if brdf > 0.0 && reflect && front {
            let (fo, fi) = (schlick_weight(cos_o.abs()), schlick_weight(cos_i.abs()));
            let f_diff = (1.0 - 0.5 * fi) * (1.0 - 0.5 * fo);
            let cos_d = wh.dot(wo);
            let rr = 2.0 * self.roughness * cos_d * cos_d;
            let f_retro = rr * (fo + fi + fo * fi * (rr - 1.0));
            let mut lobe = f_diff + f_retro;
            if self.flatness != 0.0 {
                let fss90 = 0.5 * rr;
                let fss = (1.0 + (fss90 - 1.0) * fo) * (1.0 + (fss90 - 1.0) * fi);
                let f_ss = 1.25 * (fss * (1.0 / (cos_o.abs() + cos_i.abs()) - 0.5) + 0.5);
                lobe += (f_ss - lobe) * self.flatness;
            }
            value += base * (brdf * cos_o.abs() * FRAC_1_PI * lobe);
            if self.sheen > 0.0 && self.metallic < 1.0 {
                let fd = schlick_weight(cos_d.abs());
                let c_sheen = Spectrum::ONE + (c_tint - Spectrum::ONE) * self.sheen_tint;
                value += c_sheen * (self.sheen * (1.0 - self.metallic) * fd * cos_o.abs());
            }
        }
        // The pdf, with the lobe probabilities at this half vector.
        let l = self.lobes(front, f);
        let dwh_dwo = if self.has_spec_trans && !reflect {
            (eta_path * eta_path * ho / (hi + eta_path * ho).powi(2)).abs()
        } else {
            (1.0 / (4.0 * ho)).abs()
        };
        let mut pdf = 0.0;
        let spec_pdf = ggx.pdf(mulsign(wi, cos_i), wh);
        if refl_ok && reflect {
            pdf += l.reflect * spec_pdf * dwh_dwo;
            if self.has_clearcoat {
                let c = if wh.z < 0.0 {
                    0.0
                } else {
                    wh.z * gtr1(ca, wh.z)
                };
                pdf += l.clearcoat * c * dwh_dwo;
            }
        }
        if reflect {
            pdf += l.diffuse * FRAC_1_PI * cos_o;
        }
        if self.has_spec_trans && refr_ok && refract {
            pdf += l.trans * spec_pdf * dwh_dwo;
        }
        (value, pdf)
    }

    /// Mitsuba's sampling: a lobe by `u1` with probabilities from the
    /// Fresnel term at a visible normal drawn from `u2`, then a direction of
    /// that lobe from the same `u2`.
    pub fn sample(&self, wi: Vec3A, u1: f32, u2: [f32; 2]) -> Option<BsdfSample> {
        let cos_i = wi.z;
        if cos_i == 0.0 {
            return None;
        }
        let front = cos_i > 0.0;
        let (_, bsdf) = self.weights();
        if !(front || bsdf > 0.0) {
            return None;
        }
        let m = self.ggx().sample(mulsign(wi, cos_i), u2);
        let fr = fresnel_dielectric(wi.dot(m), self.eta);
        let l = self.lobes(front, fr.r);
        let mut eta = 1.0;
        let wo = if u1 < l.diffuse {
            let wo = sample_cosine_hemisphere(u2);
            if cos_i * wo.z <= 0.0 {
                return None;
            }
            wo
        } else if self.has_clearcoat && u1 < l.diffuse + l.clearcoat {
            let a2 = self.clearcoat_alpha().powi(2);
            let cos2 = (1.0 - a2.powf(1.0 - u2[1])) / (1.0 - a2);
            let (sin_t, cos_t) = ((1.0 - cos2).max(0.0).sqrt(), cos2.max(0.0).sqrt());
            let phi = 2.0 * PI * u2[0];
            let mc = Vec3A::new(phi.cos() * sin_t, phi.sin() * sin_t, cos_t);
            let wo = reflect(wi, mc);
            if !(compatible(mc, wi, wo, cos_i, true) && cos_i * wo.z > 0.0) {
                return None;
            }
            wo
        } else if self.has_spec_trans && u1 < l.diffuse + l.clearcoat + l.trans {
            // Refraction about m (total internal reflection gives cos_t = 0
            // and a direction that fails the side test below).
            let wo = m * (wi.dot(m) * fr.eta_ti + fr.cos_t) - wi * fr.eta_ti;
            if !(compatible(m, wi, wo, cos_i, false) && cos_i * wo.z < 0.0) {
                return None;
            }
            eta = fr.eta_it;
            wo
        } else {
            let wo = reflect(wi, m);
            if !(compatible(m, wi, wo, cos_i, true) && cos_i * wo.z > 0.0) {
                return None;
            }
            wo
        };
        let (f, pdf) = self.eval_pdf(wi, wo);
        if !(pdf > 0.0) {
            return None;
        }
        Some(BsdfSample {
            wo,
            weight: f / pdf,
            pdf,
            delta: false,
            eta,
            null: false,
        })
    }
}
