//! Fresnel equations: a smooth dielectric interface, a conductor with a
//! complex index, and the hemispherical average of the dielectric one.

use crate::spectrum::Spectrum;

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
    conductor(cos_i as f64, eta as f64, k as f64) as f32
}

/// [`fresnel_conductor`] of the three channels of `eta` and `k` at once.
/// The channels go through the same operations side by side (as four f64
/// lanes, the last a copy of the third), which the compiler turns into
/// vector instructions; each lane gives the bits of `fresnel_conductor`.
#[inline]
pub fn fresnel_conductor_rgb(cos_i: f32, eta: Spectrum, k: Spectrum) -> Spectrum {
    let ci = cos_i as f64;
    let lanes = |v: Spectrum| [v.x as f64, v.y as f64, v.z as f64, v.z as f64];
    let (eta, k) = (lanes(eta), lanes(k));
    let mut r = [0f64; 4];
    for c in 0..4 {
        r[c] = conductor(ci, eta[c], k[c]);
    }
    Spectrum::new(r[0] as f32, r[1] as f32, r[2] as f32)
}

/// The body of [`fresnel_conductor`], in f64: the magnitudes |eta + ik|²
/// can reach 1e2 and the differences below cancel.
#[inline(always)]
fn conductor(ci: f64, eta: f64, k: f64) -> f64 {
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
    0.5 * (rs + rp)
}

#[inline(always)]
fn csqrt(z: (f64, f64)) -> (f64, f64) {
    let r = (z.0 * z.0 + z.1 * z.1).sqrt();
    let re = (0.5 * (r + z.0)).max(0.0).sqrt();
    let im = (0.5 * (r - z.0)).max(0.0).sqrt().copysign(z.1);
    (re, im)
}

/// Hemispherical average of the dielectric reflectance seen from the side
/// where the relative index is `eta` (η_t/η_i):
/// `F_dr = ∫₀¹ F(μ, eta) 2μ dμ = ∫₀¹ F(√s, eta) ds`, by the composite
/// midpoint rule in `s = μ²` with 4096 nodes (computed once per BSDF).
pub fn fresnel_diffuse_reflectance(eta: f32) -> f32 {
    let n = 4096;
    let mut sum = 0.0f64;
    for i in 0..n {
        let s = (i as f64 + 0.5) / n as f64;
        sum += fresnel_dielectric(s.sqrt() as f32, eta).r as f64;
    }
    (sum / n as f64) as f32
}

/// The internal diffuse reflectance of a coating of relative index `eta`
/// (inside over outside), by the polynomial fits of Egan & Hilgeman (1973)
/// that Mitsuba 3's `plastic` uses (within ~1e-3 of
/// [`fresnel_diffuse_reflectance`]`(1/eta)`, the exact average, which
/// would make fgf's `plastic` differ from Mitsuba's by ~0.1 %).
pub fn fresnel_diffuse_reflectance_fit(eta: f32) -> f32 {
    if eta >= 1.0 {
        -1.4399 / (eta * eta) + 0.7099 / eta + 0.6681 + 0.0636 * eta
    } else {
        -0.4399 + 0.7099 / eta - 0.3319 / (eta * eta) + 0.0636 / (eta * eta * eta)
    }
}
