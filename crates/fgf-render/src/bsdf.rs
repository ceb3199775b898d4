//! Surface scattering (BSDFs), evaluated in the local shading frame where
//! `+z` is the shading normal. `wi` points from the surface toward the
//! previous vertex, `wo` toward the next one (Mitsuba's convention).
//! Values include the cosine `|wo.z|`, so a sampled weight is
//! `eval / pdf` and a delta lobe returns its weight directly.
//!
//! The user documentation (parameters, units, ranges, defaults, an XML and
//! a Python example) is the table at the head of [`fgf_scene::xml::bsdfs`];
//! the notes here are about the implementation.
//!
//! * `diffuse`: one-sided: black seen from the back
//! * `null`: index-matched boundary: the path passes straight through; it neither counts toward `max_depth` nor is lit
//! * `dielectric`: smooth, both sides; transmitted radiance is scaled by `(η_i/η_t)²` (Mitsuba's non-symmetric transport in radiance mode)
//! * `conductor`: smooth, complex Fresnel per channel; one-sided
//! * `twosided`: the nested BSDF on both sides

use crate::math::{cosine_hemisphere_pdf, sample_cosine_hemisphere};
use crate::spectrum::Spectrum;
use fgf_scene::BsdfDesc;
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// The closed set of BSDF models.
#[derive(Debug, Clone, Copy)]
pub enum BsdfKind {
    Diffuse {
        reflectance: Spectrum,
    },
    Null,
    /// `eta = int_ior / ext_ior`.
    Dielectric {
        eta: f32,
        r: Spectrum,
        t: Spectrum,
    },
    Conductor {
        eta: Spectrum,
        k: Spectrum,
        r: Spectrum,
        mirror: bool,
    },
}

/// A BSDF and whether it is mirrored to the back side (`twosided`).
#[derive(Debug, Clone, Copy)]
pub struct Bsdf {
    pub kind: BsdfKind,
    pub twosided: bool,
}

/// The result of sampling a BSDF.
#[derive(Debug, Clone, Copy)]
pub struct BsdfSample {
    /// Sampled direction in the local frame.
    pub wo: Vec3,
    /// `f·|cos| / pdf` (for a delta lobe, the lobe weight over its choice probability).
    pub weight: Spectrum,
    /// Solid-angle pdf; for delta lobes the discrete choice probability.
    pub pdf: f32,
    pub delta: bool,
    /// Relative index of refraction crossed (1 for reflection), for Russian roulette.
    pub eta: f32,
}

impl Bsdf {
    pub fn from_desc(d: &BsdfDesc) -> Bsdf {
        let c = crate::spectrum::from_rgb;
        match d {
            BsdfDesc::Diffuse { reflectance } => Bsdf {
                kind: BsdfKind::Diffuse {
                    reflectance: c(*reflectance),
                },
                twosided: false,
            },
            BsdfDesc::Null => Bsdf {
                kind: BsdfKind::Null,
                twosided: false,
            },
            BsdfDesc::Dielectric {
                int_ior,
                ext_ior,
                specular_reflectance,
                specular_transmittance,
            } => Bsdf {
                kind: BsdfKind::Dielectric {
                    eta: int_ior / ext_ior,
                    r: c(*specular_reflectance),
                    t: c(*specular_transmittance),
                },
                twosided: false,
            },
            BsdfDesc::Conductor {
                eta,
                k,
                specular_reflectance,
                perfect_mirror,
            } => Bsdf {
                kind: BsdfKind::Conductor {
                    eta: c(*eta),
                    k: c(*k),
                    r: c(*specular_reflectance),
                    mirror: *perfect_mirror,
                },
                twosided: false,
            },
            BsdfDesc::TwoSided(inner) => Bsdf {
                twosided: true,
                ..Bsdf::from_desc(inner)
            },
        }
    }

    #[inline]
    pub fn is_null(&self) -> bool {
        matches!(self.kind, BsdfKind::Null)
    }

    /// True if the BSDF has a non-delta lobe, so light sampling helps.
    #[inline]
    pub fn is_smooth(&self) -> bool {
        matches!(self.kind, BsdfKind::Diffuse { .. })
    }

    /// `f(wi, wo)·|wo.z|` and the pdf of sampling `wo` (zero for delta lobes).
    pub fn eval_pdf(&self, mut wi: Vec3, mut wo: Vec3) -> (Spectrum, f32) {
        if self.twosided && wi.z < 0.0 {
            wi.z = -wi.z;
            wo.z = -wo.z;
        }
        match self.kind {
            BsdfKind::Diffuse { reflectance } => {
                if wi.z <= 0.0 || wo.z <= 0.0 {
                    return (Spectrum::ZERO, 0.0);
                }
                (
                    reflectance * (FRAC_1_PI * wo.z),
                    cosine_hemisphere_pdf(wo.z),
                )
            }
            _ => (Spectrum::ZERO, 0.0),
        }
    }

    /// Sample `wo` given `wi`; `u1` picks a lobe, `u2` the direction.
    pub fn sample(&self, mut wi: Vec3, u1: f32, u2: [f32; 2]) -> Option<BsdfSample> {
        let flipped = self.twosided && wi.z < 0.0;
        if flipped {
            wi.z = -wi.z;
        }
        let mut s = match self.kind {
            BsdfKind::Diffuse { reflectance } => {
                if wi.z <= 0.0 {
                    return None;
                }
                let wo = sample_cosine_hemisphere(u2);
                if wo.z <= 0.0 {
                    return None;
                }
                BsdfSample {
                    wo,
                    weight: reflectance,
                    pdf: cosine_hemisphere_pdf(wo.z),
                    delta: false,
                    eta: 1.0,
                }
            }
            BsdfKind::Null => BsdfSample {
                wo: -wi,
                weight: Spectrum::ONE,
                pdf: 1.0,
                delta: true,
                eta: 1.0,
            },
            BsdfKind::Dielectric { eta, r, t } => {
                let f = fresnel_dielectric(wi.z, eta);
                if u1 < f.r {
                    BsdfSample {
                        wo: Vec3::new(-wi.x, -wi.y, wi.z),
                        weight: r,
                        pdf: f.r,
                        delta: true,
                        eta: 1.0,
                    }
                } else {
                    // Refracted direction: tangential part scaled by η_i/η_t.
                    let wo = Vec3::new(-f.eta_ti * wi.x, -f.eta_ti * wi.y, f.cos_t);
                    // Radiance is compressed into the smaller solid angle on
                    // the denser side: scale by (η_i/η_t)².
                    BsdfSample {
                        wo,
                        weight: t * (f.eta_ti * f.eta_ti),
                        pdf: 1.0 - f.r,
                        delta: true,
                        eta: f.eta_it,
                    }
                }
            }
            BsdfKind::Conductor { eta, k, r, mirror } => {
                if wi.z <= 0.0 {
                    return None;
                }
                let fr = if mirror {
                    Spectrum::ONE
                } else {
                    Spectrum::new(
                        fresnel_conductor(wi.z, eta.x, k.x),
                        fresnel_conductor(wi.z, eta.y, k.y),
                        fresnel_conductor(wi.z, eta.z, k.z),
                    )
                };
                BsdfSample {
                    wo: Vec3::new(-wi.x, -wi.y, wi.z),
                    weight: r * fr,
                    pdf: 1.0,
                    delta: true,
                    eta: 1.0,
                }
            }
        };
        if flipped {
            s.wo.z = -s.wo.z;
        }
        Some(s)
    }
}

/// Fresnel reflectance of a smooth dielectric interface.
#[derive(Debug, Clone, Copy)]
pub struct FresnelDielectric {
    /// Unpolarised reflectance.
    pub r: f32,
    /// Signed cosine of the transmitted direction (opposite side to `wi`); 0 at total internal reflection.
    pub cos_t: f32,
    /// `η_t/η_i` for this side.
    pub eta_it: f32,
    /// `η_i/η_t`.
    pub eta_ti: f32,
}

/// Fresnel equations for `cos_i = wi.z` and `eta = η_inside/η_outside`
/// (the inside is the `-z` side).
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> FresnelDielectric {
    let eta_it = if cos_i >= 0.0 { eta } else { 1.0 / eta };
    let eta_ti = 1.0 / eta_it;
    let ci = cos_i.abs();
    let cos_t_sq = 1.0 - eta_ti * eta_ti * (1.0 - ci * ci);
    if cos_t_sq <= 0.0 {
        return FresnelDielectric {
            r: 1.0,
            cos_t: 0.0,
            eta_it,
            eta_ti,
        };
    }
    let ct = cos_t_sq.sqrt();
    let rs = (ci - eta_it * ct) / (ci + eta_it * ct);
    let rp = (eta_it * ci - ct) / (eta_it * ci + ct);
    let r = 0.5 * (rs * rs + rp * rp);
    FresnelDielectric {
        r,
        cos_t: if cos_i >= 0.0 { -ct } else { ct },
        eta_it,
        eta_ti,
    }
}

/// Unpolarised Fresnel reflectance of a conductor with complex index
/// `eta + i k` relative to the outside, at incidence cosine `cos_i > 0`.
pub fn fresnel_conductor(cos_i: f32, eta: f32, k: f32) -> f32 {
    // Complex arithmetic in f64: the magnitudes |eta + ik|² can reach 1e2 and
    // the differences below cancel.
    let (ci, eta, k) = (cos_i as f64, eta as f64, k as f64);
    let sin2 = 1.0 - ci * ci;
    // η² = (eta + ik)², then cos_t = sqrt(1 - sin²θ/η²) (principal root).
    let e2 = (eta * eta - k * k, 2.0 * eta * k);
    let inv = {
        let d = e2.0 * e2.0 + e2.1 * e2.1;
        (e2.0 / d, -e2.1 / d)
    };
    let z = (1.0 - sin2 * inv.0, -sin2 * inv.1);
    let ct = csqrt(z);
    let e = (eta, k);
    let mul = |a: (f64, f64), b: (f64, f64)| (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0);
    let abs2 = |a: (f64, f64)| a.0 * a.0 + a.1 * a.1;
    // r_s = (cos_i - η cos_t)/(cos_i + η cos_t), r_p = (η cos_i - cos_t)/(η cos_i + cos_t).
    let ect = mul(e, ct);
    let rs = abs2((ci - ect.0, -ect.1)) / abs2((ci + ect.0, ect.1));
    let eci = (eta * ci, k * ci);
    let rp = abs2((eci.0 - ct.0, eci.1 - ct.1)) / abs2((eci.0 + ct.0, eci.1 + ct.1));
    (0.5 * (rs + rp)) as f32
}

fn csqrt(z: (f64, f64)) -> (f64, f64) {
    let r = (z.0 * z.0 + z.1 * z.1).sqrt();
    let re = (0.5 * (r + z.0)).max(0.0).sqrt();
    let im = (0.5 * (r - z.0)).max(0.0).sqrt().copysign(z.1);
    (re, im)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dielectric_fresnel_normal_incidence() {
        // ((η-1)/(η+1))² = 0.04 for η = 1.5, from both sides.
        assert!((fresnel_dielectric(1.0, 1.5).r - 0.04).abs() < 1e-6);
        assert!((fresnel_dielectric(-1.0, 1.5).r - 0.04).abs() < 1e-6);
        // Total internal reflection beyond the critical angle (inside, η = 1.5).
        assert_eq!(fresnel_dielectric(-0.3, 1.5).r, 1.0);
    }

    #[test]
    fn conductor_reduces_to_dielectric_for_k0() {
        for &c in &[0.1f32, 0.5, 0.9, 1.0] {
            let a = fresnel_conductor(c, 1.5, 0.0);
            let b = fresnel_dielectric(c, 1.5).r;
            assert!((a - b).abs() < 1e-5, "{a} vs {b}");
        }
        // Normal incidence: |(η - 1)/(η + 1)|² with η = eta + ik.
        let (eta, k) = (0.2f32, 3.0f32);
        let exp = ((eta - 1.0).powi(2) + k * k) / ((eta + 1.0).powi(2) + k * k);
        assert!((fresnel_conductor(1.0, eta, k) - exp).abs() < 1e-5);
    }

    #[test]
    fn refraction_obeys_snell() {
        let b = Bsdf {
            kind: BsdfKind::Dielectric {
                eta: 1.5,
                r: Spectrum::ONE,
                t: Spectrum::ONE,
            },
            twosided: false,
        };
        let wi = Vec3::new(0.6, 0.0, 0.8);
        let s = b.sample(wi, 0.999, [0.0, 0.0]).unwrap();
        let sin_i = 0.6f32;
        let sin_t = (s.wo.x * s.wo.x + s.wo.y * s.wo.y).sqrt();
        assert!((sin_i - 1.5 * sin_t).abs() < 1e-5);
        assert!(s.wo.z < 0.0 && (s.wo.length() - 1.0).abs() < 1e-5);
        assert!((s.weight.x - 1.0 / 2.25).abs() < 1e-6);
    }
}
