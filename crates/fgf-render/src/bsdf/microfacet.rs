//! Microfacet normal distributions (Beckmann and GGX, anisotropic) with
//! Smith's separable shadowing–masking, after Walter et al. 2007
//! ("Microfacet models for refraction through rough surfaces"), and their
//! sampling: the whole distribution `D(m) cos θ_m`, or only the normals
//! visible from `wi` (`sample_visible`, the default), `D_wi(m) =
//! G1(wi, m) max(0, wi·m) D(m) / cos θ_i`.
//!
//! Visible normals are sampled for GGX by Heitz 2018 ("Sampling the GGX
//! distribution of visible normals": the stretched hemisphere projected on
//! a disk), and for Beckmann by inverting, in the stretched slope space,
//! the marginal of the visible slopes along the incident direction
//! (`C(x) = a·√π/2·(1 + erf x) + e^{-x²}/2` with `a = cot θ_i`) and the
//! Gaussian slope across it.
//!
//! For Beckmann the value of `G1` in [`Microfacet::g`] is the rational
//! approximation of Walter et al. (what Mitsuba 3 evaluates), while the
//! sampling pdf uses the exact Smith `G1 = 1/(1 + Λ)`: the pdf is then the
//! exact density of the sampled normals, and estimators stay unbiased with
//! respect to the value.

use crate::math::sample_concentric_disk;
use glam::Vec3A;
use std::f32::consts::PI;

/// Which distribution of microfacet normals.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Distribution {
    Beckmann,
    Ggx,
}

/// A microfacet distribution with roughness `ax` (along the frame's x)
/// and `ay` (along y).
#[derive(Debug, Clone, Copy)]
pub struct Microfacet {
    pub kind: Distribution,
    pub ax: f32,
    pub ay: f32,
    pub visible: bool,
}

impl Microfacet {
    /// `D(m)`, normalised so that `∫ D(m) cos θ_m dω = 1`.
    #[inline]
    pub fn d(&self, m: Vec3A) -> f32 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let c2 = m.z * m.z;
        // tan²θ·(cos²φ/ax² + sin²φ/ay²)·cos²θ.
        let e = (m.x / self.ax).powi(2) + (m.y / self.ay).powi(2);
        let r = match self.kind {
            Distribution::Beckmann => (-e / c2).exp() / (PI * self.ax * self.ay * c2 * c2),
            Distribution::Ggx => 1.0 / (PI * self.ax * self.ay * (c2 + e).powi(2)),
        };
        if r.is_finite() {
            r
        } else {
            0.0
        }
    }

    /// `α(φ_v)² tan²θ_v` of direction `v`.
    #[inline]
    fn a2tan2(&self, v: Vec3A) -> f32 {
        ((v.x * self.ax).powi(2) + (v.y * self.ay).powi(2)) / (v.z * v.z)
    }

    /// Smith's `G1(v, m)` as evaluated in the BSDF value (Beckmann: the
    /// rational approximation of Walter et al. 2007, eq. 27).
    #[inline]
    pub fn g1(&self, v: Vec3A, m: Vec3A) -> f32 {
        if v.dot(m) * v.z <= 0.0 {
            return 0.0;
        }
        let t = self.a2tan2(v);
        if t <= 0.0 {
            return 1.0;
        }
        match self.kind {
            Distribution::Ggx => 2.0 / (1.0 + (1.0 + t).sqrt()),
            Distribution::Beckmann => {
                let a = 1.0 / t.sqrt();
                if a >= 1.6 {
                    1.0
                } else {
                    (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
                }
            }
        }
    }

    /// The exact Smith `G1(v, m) = 1 / (1 + Λ(v))`, the normalisation of
    /// the distribution of visible normals.
    #[inline]
    pub fn g1_exact(&self, v: Vec3A, m: Vec3A) -> f32 {
        match self.kind {
            Distribution::Ggx => self.g1(v, m),
            Distribution::Beckmann => {
                if v.dot(m) * v.z <= 0.0 {
                    return 0.0;
                }
                let t = self.a2tan2(v) as f64;
                if t <= 0.0 {
                    return 1.0;
                }
                let a = 1.0 / t.sqrt();
                let lambda = 0.5 * (libm::erf(a) - 1.0)
                    + (-a * a).exp() / (2.0 * a * std::f64::consts::PI.sqrt());
                (1.0 / (1.0 + lambda)) as f32
            }
        }
    }

    /// Separable shadowing–masking `G1(wi, m) G1(wo, m)`.
    #[inline]
    pub fn g(&self, wi: Vec3A, wo: Vec3A, m: Vec3A) -> f32 {
        self.g1(wi, m) * self.g1(wo, m)
    }

    /// Density of [`Self::sample`] at normal `m` (solid angle of `m`), for
    /// `wi.z > 0`.
    #[inline]
    pub fn pdf(&self, wi: Vec3A, m: Vec3A) -> f32 {
        if self.visible {
            self.g1_exact(wi, m) * wi.dot(m).max(0.0) * self.d(m) / wi.z
        } else {
            self.d(m) * m.z
        }
    }

    /// Sample a microfacet normal for `wi.z > 0`.
    pub fn sample(&self, wi: Vec3A, u: [f32; 2]) -> Vec3A {
        if self.visible {
            match self.kind {
                Distribution::Ggx => self.sample_visible_ggx(wi, u),
                Distribution::Beckmann => self.sample_visible_beckmann(wi, u),
            }
        } else {
            self.sample_all(u)
        }
    }

    /// `D(m) cos θ_m`: φ from the anisotropic ellipse, then θ by inversion.
    fn sample_all(&self, u: [f32; 2]) -> Vec3A {
        let psi = 2.0 * PI * u[1];
        let (sp, cp) = (self.ay * psi.sin(), self.ax * psi.cos());
        let r = (sp * sp + cp * cp).sqrt();
        let (sin_phi, cos_phi) = (sp / r, cp / r);
        let a = (cos_phi / self.ax).powi(2) + (sin_phi / self.ay).powi(2);
        let tan2 = match self.kind {
            Distribution::Beckmann => -(1.0 - u[0]).max(1e-30).ln() / a,
            Distribution::Ggx => u[0] / ((1.0 - u[0]).max(1e-30) * a),
        };
        let cos_t = 1.0 / (1.0 + tan2).sqrt();
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        Vec3A::new(sin_t * cos_phi, sin_t * sin_phi, cos_t)
    }

    fn sample_visible_ggx(&self, wi: Vec3A, u: [f32; 2]) -> Vec3A {
        let vh = Vec3A::new(self.ax * wi.x, self.ay * wi.y, wi.z).normalize();
        let len2 = vh.x * vh.x + vh.y * vh.y;
        let t1 = if len2 > 0.0 {
            Vec3A::new(-vh.y, vh.x, 0.0) / len2.sqrt()
        } else {
            Vec3A::X
        };
        let t2 = vh.cross(t1);
        // A uniform point on the unit disk (concentric map, as Mitsuba 3:
        // the same distribution as the polar map, and the coating tables of
        // `plastic.rs`, quadratures through this map, then agree with
        // Mitsuba's to rounding), then squeezed onto the visible half.
        let [p1, q] = sample_concentric_disk(u);
        let s = 0.5 * (1.0 + vh.z);
        let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * q;
        let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
        Vec3A::new(self.ax * nh.x, self.ay * nh.y, nh.z.max(1e-6)).normalize()
    }

    fn sample_visible_beckmann(&self, wi: Vec3A, u: [f32; 2]) -> Vec3A {
        // Stretch to the unit-roughness configuration.
        let vh = Vec3A::new(self.ax * wi.x, self.ay * wi.y, wi.z).normalize();
        let sin_t = (vh.x * vh.x + vh.y * vh.y).sqrt();
        let (cos_phi, sin_phi) = if sin_t > 1e-7 {
            (vh.x / sin_t, vh.y / sin_t)
        } else {
            (1.0, 0.0)
        };
        let a = if sin_t > 1e-7 {
            (vh.z / sin_t) as f64
        } else {
            f64::INFINITY
        };
        let x = visible_slope_x(a, u[0] as f64);
        let y = erf_inv(2.0 * u[1] as f64 - 1.0);
        // Rotate back to φ_i and unstretch.
        let (x, y) = (x as f32, y as f32);
        let sx = (cos_phi * x - sin_phi * y) * self.ax;
        let sy = (sin_phi * x + cos_phi * y) * self.ay;
        Vec3A::new(-sx, -sy, 1.0).normalize()
    }
}

/// Inverse of the marginal CDF of the visible slope `x < a` of the
/// unit Beckmann distribution, density ∝ `e^{-x²}(a - x)`.
fn visible_slope_x(a: f64, u: f64) -> f64 {
    let sqrt_pi = std::f64::consts::PI.sqrt();
    if !a.is_finite() || a > 1e6 {
        // Normal incidence (or within 1e-6 of it): the slopes are Gaussian.
        return erf_inv(2.0 * u - 1.0);
    }
    let c = |x: f64| a * 0.5 * sqrt_pi * (1.0 + libm::erf(x)) + 0.5 * (-x * x).exp();
    let target = u * c(a);
    let (mut lo, mut hi) = (-8.0f64, a);
    let mut x = 0.5 * (lo.max(-3.0) + hi);
    for _ in 0..60 {
        let f = c(x) - target;
        if f.abs() < 1e-12 {
            break;
        }
        if f > 0.0 {
            hi = x;
        } else {
            lo = x;
        }
        let dens = (-x * x).exp() * (a - x);
        let mut next = x - f / dens;
        if !(next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        if (next - x).abs() < 1e-12 {
            x = next;
            break;
        }
        x = next;
    }
    x
}

/// `erf⁻¹(y)` for `y` in (-1, 1), by safeguarded Newton on `erf`.
fn erf_inv(y: f64) -> f64 {
    let y = y.clamp(-1.0 + 1e-15, 1.0 - 1e-15);
    let (mut lo, mut hi) = (-6.0f64, 6.0f64);
    let mut x = 0.0f64;
    for _ in 0..60 {
        let f = libm::erf(x) - y;
        if f.abs() < 1e-14 {
            break;
        }
        if f > 0.0 {
            hi = x;
        } else {
            lo = x;
        }
        let d = 2.0 / std::f64::consts::PI.sqrt() * (-x * x).exp();
        let mut next = x - f / d;
        if !(next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        if (next - x).abs() < 1e-14 {
            x = next;
            break;
        }
        x = next;
    }
    x
}

/// Mirror `wi` about the normal `m`.
#[inline]
pub fn reflect(wi: Vec3A, m: Vec3A) -> Vec3A {
    2.0 * wi.dot(m) * m - wi
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mean of the sampled visible slope against its closed form
    /// `E[x] = -(√π/4)(1 + erf a)/C(a)`.
    #[test]
    fn visible_slope_mean() {
        for a in [0.1f64, 0.7, 1.7, 4.0, 7.3, 12.0, 50.0] {
            let n = 20000;
            let m: f64 = (0..n)
                .map(|i| visible_slope_x(a, (i as f64 + 0.5) / n as f64))
                .sum::<f64>()
                / n as f64;
            let sp = std::f64::consts::PI.sqrt();
            let c = a * 0.5 * sp * (1.0 + libm::erf(a)) + 0.5 * (-a * a).exp();
            let e = -(sp / 4.0) * (1.0 + libm::erf(a)) / c;
            assert!((m - e).abs() < 2e-3, "a={a}: mean {m} vs {e}");
        }
    }
}
