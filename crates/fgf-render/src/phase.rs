//! Phase functions. Angles are measured between the propagation direction
//! of the incoming ray `d` and the scattered direction `wo` (so `g > 0`
//! scatters forward). Both models are sampled exactly, so the sampling
//! weight `p/pdf` is 1.
//!
//! The user documentation (parameters, units, ranges, defaults, an XML and
//! a Python example) is the table at the head of [`fgf_scene::xml::phase`];
//! this module implements it.

use crate::math::{sample_uniform_sphere, sin_cos_2pi, Frame, UNIFORM_SPHERE_PDF};
use fgf_scene::PhaseDesc;
use glam::Vec3A;
use std::f32::consts::PI;

#[derive(Debug, Clone, Copy)]
pub enum Phase {
    Isotropic,
    Hg { g: f32 },
}

impl Phase {
    pub fn from_desc(d: &PhaseDesc) -> Phase {
        match *d {
            PhaseDesc::Isotropic => Phase::Isotropic,
            PhaseDesc::Hg { g } => Phase::Hg { g },
        }
    }

    /// Phase function value (= pdf) for propagation direction `d` and outgoing `wo`.
    #[inline]
    pub fn eval(&self, d: Vec3A, wo: Vec3A) -> f32 {
        match *self {
            Phase::Isotropic => UNIFORM_SPHERE_PDF,
            Phase::Hg { g } => hg(d.dot(wo), g),
        }
    }

    /// Sample `wo`; returns it with its pdf (= value).
    #[inline]
    pub fn sample(&self, d: Vec3A, u: [f32; 2]) -> (Vec3A, f32) {
        match *self {
            Phase::Isotropic => (sample_uniform_sphere(u), UNIFORM_SPHERE_PDF),
            Phase::Hg { g } => {
                // Invert the HG CDF in cos θ; the isotropic limit below |g| = 1e-3
                // avoids the 0/0 of the closed form.
                let cos = if g.abs() < 1e-3 {
                    1.0 - 2.0 * u[0]
                } else {
                    let s = (1.0 - g * g) / (1.0 + g - 2.0 * g * u[0]);
                    ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
                };
                let sin = (1.0 - cos * cos).max(0.0).sqrt();
                let (sin_phi, cos_phi) = sin_cos_2pi(u[1]);
                let wo =
                    Frame::from_normal(d).to_world(Vec3A::new(sin * cos_phi, sin * sin_phi, cos));
                (wo, hg(cos, g))
            }
        }
    }
}

/// Henyey–Greenstein density in solid angle for `cos θ` and mean cosine `g`.
#[inline]
pub fn hg(cos: f32, g: f32) -> f32 {
    let denom = 1.0 + g * g - 2.0 * g * cos;
    (1.0 - g * g) / (4.0 * PI * denom * denom.max(1e-12).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫ p dω = 1 and E[cos θ] = g, by midpoint quadrature in cos θ.
    #[test]
    fn hg_normalised_with_mean_cosine_g() {
        for &g in &[-0.7f32, 0.0, 0.3, 0.9] {
            let n = 200_000;
            let (mut int, mut mean) = (0f64, 0f64);
            for i in 0..n {
                let c = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
                let p = hg(c as f32, g) as f64 * 2.0 * std::f64::consts::PI * (2.0 / n as f64);
                int += p;
                mean += p * c;
            }
            assert!((int - 1.0).abs() < 1e-3, "g={g}: {int}");
            assert!((mean - g as f64).abs() < 2e-3, "g={g}: {mean}");
        }
    }

    /// Sampling is the inverse of the CDF: the sampled cosine's empirical mean is g.
    #[test]
    fn hg_sampling_mean_cosine() {
        let g = 0.6f32;
        let d = Vec3A::new(0.0, 0.6, 0.8);
        let n = 20_000;
        let mut sum = 0.0f64;
        for i in 0..n {
            let u = [
                (i as f32 + 0.5) / n as f32,
                ((i * 7919) % n) as f32 / n as f32,
            ];
            let (wo, pdf) = Phase::Hg { g }.sample(d, u);
            assert!((pdf - Phase::Hg { g }.eval(d, wo)).abs() <= 1e-3 * pdf);
            sum += d.dot(wo) as f64;
        }
        // Stratified in cos θ: the error is O(1/n), far below 1e-3.
        assert!((sum / n as f64 - g as f64).abs() < 1e-3);
    }
}
