//! Small numerical helpers shared by the renderer: orthonormal frames, the
//! per-sample random stream, the warping functions and the MIS heuristic.
//!
//! Sampling routines take their uniform variates `u ∈ [0,1)` as arguments
//! and come with their pdf (pbrt-v4's habit), so they can be tested alone.

use fgf_core::rng::{mix64, stream_key, SECOND_WORD};
use glam::Vec3A;
use rand::RngCore;
use rand_pcg::Pcg32;
use std::f32::consts::PI;

/// The random stream of one camera sample. It is derived from
/// `(seed, pixel index, sample index)` only, so an image does not depend on
/// the number of threads or on the order in which pixels are rendered, and a
/// single sample can be re-run alone.
pub struct Sampler {
    rng: Pcg32,
}

impl Sampler {
    pub fn new(seed: u64, pixel: u64, sample: u64) -> Self {
        Self::for_sample(Self::pixel_key(Self::seed_key(seed), pixel), sample)
    }

    /// The first step of [`Self::new`], which a renderer computes once per
    /// image; then [`Self::pixel_key`] once per pixel and
    /// [`Self::for_sample`] once per sample give the same stream as `new`.
    #[inline]
    pub fn seed_key(seed: u64) -> u64 {
        mix64(seed)
    }

    #[inline]
    pub fn pixel_key(seed_key: u64, pixel: u64) -> u64 {
        // Chained keys (docs/theory.md §7.15): (a, b, c) and (b, a, c) give
        // unrelated streams.
        stream_key(seed_key, pixel)
    }

    #[inline]
    pub fn for_sample(pixel_key: u64, sample: u64) -> Self {
        let h = stream_key(pixel_key, sample);
        // PCG's stream selector is also hashed so neighbouring pixels do not
        // get the related increments that nearby stream ids would give.
        Sampler {
            rng: Pcg32::new(h, stream_key(h, SECOND_WORD)),
        }
    }

    /// A uniform variate in `[0, 1)` with 24 random bits (every value is an
    /// exact f32 below 1).
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        (self.rng.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    #[inline]
    pub fn next_2d(&mut self) -> [f32; 2] {
        [self.next_1d(), self.next_1d()]
    }
}

/// An orthonormal frame around a unit normal `n` (Duff et al. 2017's
/// branchless construction).
#[derive(Debug, Clone, Copy)]
pub struct Frame {
    pub s: Vec3A,
    pub t: Vec3A,
    pub n: Vec3A,
}

impl Frame {
    pub fn from_normal(n: Vec3A) -> Self {
        let sign = 1f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3A::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3A::new(b, sign + n.y * n.y * a, -n.y);
        Frame { s, t, n }
    }
    #[inline]
    pub fn to_local(&self, v: Vec3A) -> Vec3A {
        Vec3A::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }
    #[inline]
    pub fn to_world(&self, v: Vec3A) -> Vec3A {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

/// Cosine-weighted hemisphere around +z (Malley's method on a concentric disk).
pub fn sample_cosine_hemisphere(u: [f32; 2]) -> Vec3A {
    let d = sample_concentric_disk(u);
    let z = (1.0 - d[0] * d[0] - d[1] * d[1]).max(0.0).sqrt();
    Vec3A::new(d[0], d[1], z)
}

/// Pdf (solid angle) of [`sample_cosine_hemisphere`].
#[inline]
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * (1.0 / PI)
}

/// Shirley–Chiu concentric map of the unit square to the unit disk.
pub fn sample_concentric_disk(u: [f32; 2]) -> [f32; 2] {
    let ox = 2.0 * u[0] - 1.0;
    let oy = 2.0 * u[1] - 1.0;
    if ox == 0.0 && oy == 0.0 {
        return [0.0, 0.0];
    }
    let (r, theta) = if ox.abs() > oy.abs() {
        (ox, (PI / 4.0) * (oy / ox))
    } else {
        (oy, PI / 2.0 - (PI / 4.0) * (ox / oy))
    };
    [r * theta.cos(), r * theta.sin()]
}

/// Uniform direction on the unit sphere; pdf `1/(4π)`.
pub fn sample_uniform_sphere(u: [f32; 2]) -> Vec3A {
    let z = 1.0 - 2.0 * u[0];
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    Vec3A::new(r * phi.cos(), r * phi.sin(), z)
}

pub const UNIFORM_SPHERE_PDF: f32 = 1.0 / (4.0 * PI);

/// Uniform barycentrics `(b1, b2)` on a triangle (the square-root map).
pub fn sample_uniform_triangle(u: [f32; 2]) -> [f32; 2] {
    let su = u[0].sqrt();
    [1.0 - su, u[1] * su]
}

/// `⌊x⌋` clamped to `0..n` (`n ≥ 1`, at most 2³²): the index of the bin
/// that `x` falls in, 0 for a negative or NaN `x`; the same as
/// `(x as usize).min(n - 1)`, but converted through `u32`, whose saturating
/// conversion takes a few instructions where `usize`'s takes some fifteen.
#[inline(always)]
pub fn bin_index(x: f32, n: usize) -> usize {
    (x as u32 as usize).min(n - 1)
}

/// Power heuristic with exponent 2 for two strategies with pdfs `a` (the one
/// that was used) and `b`.
#[inline]
pub fn mis_power(a: f32, b: f32) -> f32 {
    let a2 = a * a;
    let b2 = b * b;
    if a2 + b2 > 0.0 && a2.is_finite() {
        a2 / (a2 + b2)
    } else if a.is_infinite() {
        1.0
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal() {
        for n in [
            Vec3A::Z,
            -Vec3A::Z,
            Vec3A::new(0.3, -0.4, 0.866).normalize(),
            Vec3A::X,
        ] {
            let f = Frame::from_normal(n);
            assert!((f.s.length() - 1.0).abs() < 1e-5);
            assert!((f.t.length() - 1.0).abs() < 1e-5);
            assert!(
                f.s.dot(f.t).abs() < 1e-5 && f.s.dot(n).abs() < 1e-5 && f.t.dot(n).abs() < 1e-5
            );
            let v = Vec3A::new(0.2, 0.5, -0.7);
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-5);
        }
    }

    #[test]
    fn sampler_streams_are_deterministic_and_distinct() {
        let a: Vec<f32> = {
            let mut s = Sampler::new(1, 2, 3);
            (0..4).map(|_| s.next_1d()).collect()
        };
        let b: Vec<f32> = {
            let mut s = Sampler::new(1, 2, 3);
            (0..4).map(|_| s.next_1d()).collect()
        };
        let c: Vec<f32> = {
            let mut s = Sampler::new(1, 3, 2);
            (0..4).map(|_| s.next_1d()).collect()
        };
        assert_eq!(a, b);
        assert_ne!(a, c);
        assert!(a.iter().all(|&x| (0.0..1.0).contains(&x)));
    }

    #[test]
    fn cosine_samples_lie_in_upper_hemisphere() {
        for i in 0..100 {
            let u = [(i as f32 + 0.5) / 100.0, ((i * 37) % 100) as f32 / 100.0];
            let d = sample_cosine_hemisphere(u);
            assert!(d.z >= 0.0 && (d.length() - 1.0).abs() < 1e-4);
        }
    }
}
