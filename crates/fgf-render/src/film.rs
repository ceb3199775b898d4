//! The film: pixel reconstruction and the image the render returns.
//!
//! Pixel reconstruction is by filter importance sampling: each camera sample of
//! pixel `(x, y)` is placed at `(x + 0.5 + δx, y + 0.5 + δy)` with `δ` drawn
//! from the (separable) reconstruction filter, and all samples have weight
//! 1, so a pixel is the plain mean of its samples and its variance is the
//! sample variance over `n`. In expectation this is
//! `∫ f(x - p) L(x) dx / ∫ f`, the value Mitsuba's splatting converges to.
//! Offsets falling outside the film are redrawn, which samples the filter
//! truncated to the film — the normalisation Mitsuba's weighted splats get
//! at the border (it never samples outside the film).
//!
//! Filters (Mitsuba 3, checked against 3.9.1):
//! * `box`: uniform over the pixel (radius 0.5);
//! * `tent`: `1 - |x|/r` on `[-r, r]` (default `r = 1`);
//! * `gaussian`: `exp(-x²/2σ²) - exp(-r²/2σ²)` on `[-r, r]`, `r = 4σ`
//!   (default `σ = 0.5`); sampled from a 1024-bin tabulated CDF with a
//!   weight `f/pdf` relative to the normalised filter, so the tabulation does
//!   not bias the result.
//!
//! Each pixel keeps running sums of its samples ([`Accum`]), from which
//! [`RenderOutput`] takes the pixel means and, if asked, their variances.

use crate::math::Sampler;
use crate::spectrum::Spectrum;
use fgf_scene::FilterDesc;

const GAUSS_BINS: usize = 1024;

#[derive(Debug, Clone)]
pub enum Filter {
    Box,
    Tent {
        radius: f32,
    },
    Gaussian {
        stddev: f32,
        radius: f32,
        cdf: Vec<f32>,
        integral: f32,
    },
}

impl Filter {
    pub fn new(d: &FilterDesc) -> Filter {
        match *d {
            FilterDesc::Box => Filter::Box,
            FilterDesc::Tent { radius } => Filter::Tent { radius },
            FilterDesc::Gaussian { stddev } => {
                let radius = 4.0 * stddev;
                let f = |x: f32| gaussian(x, stddev, radius);
                // Piecewise-constant table on [-r, r] with the value at each bin centre.
                let h = 2.0 * radius / GAUSS_BINS as f32;
                let mut cdf = Vec::with_capacity(GAUSS_BINS + 1);
                cdf.push(0.0);
                let mut acc = 0.0f64;
                for i in 0..GAUSS_BINS {
                    acc += f(-radius + (i as f32 + 0.5) * h) as f64 * h as f64;
                    cdf.push(acc as f32);
                }
                let integral = acc as f32;
                for c in &mut cdf {
                    *c /= integral;
                }
                Filter::Gaussian {
                    stddev,
                    radius,
                    cdf,
                    integral,
                }
            }
        }
    }

    /// Sample a 1D offset from the pixel centre; returns `(δ, weight)`.
    fn sample_1d(&self, u: f32) -> (f32, f32) {
        match self {
            Filter::Box => (u - 0.5, 1.0),
            Filter::Tent { radius } => {
                // Inverse CDF of the triangle on [-r, r].
                let x = if u < 0.5 {
                    -1.0 + (2.0 * u).sqrt()
                } else {
                    1.0 - (2.0 - 2.0 * u).sqrt()
                };
                (x * radius, 1.0)
            }
            Filter::Gaussian {
                stddev,
                radius,
                cdf,
                integral,
            } => {
                let k = cdf.partition_point(|&c| c <= u).clamp(1, GAUSS_BINS) - 1;
                let w = cdf[k + 1] - cdf[k];
                let frac = if w > 0.0 { (u - cdf[k]) / w } else { 0.5 };
                let h = 2.0 * radius / GAUSS_BINS as f32;
                let x = -radius + (k as f32 + frac) * h;
                // pdf of the table at x vs the normalised filter f(x)/∫f.
                let pdf = w / h;
                let target = gaussian(x, *stddev, *radius) / integral;
                (x, if pdf > 0.0 { target / pdf } else { 0.0 })
            }
        }
    }

    /// A film position for a sample of pixel `(px, py)` and its weight.
    pub fn sample_position(
        &self,
        px: u32,
        py: u32,
        width: u32,
        height: u32,
        s: &mut Sampler,
    ) -> (f32, f32, f32) {
        if let Filter::Box = self {
            let u = s.next_2d();
            return (px as f32 + u[0], py as f32 + u[1], 1.0);
        }
        let axis = |s: &mut Sampler, p: u32, n: u32| {
            // At most 64 redraws: at least a quarter of the filter mass lies
            // inside the film (the pixel centre is inside), so running out
            // has probability < 0.75^64 ≈ 1e-8; we then clamp.
            for _ in 0..64 {
                let (d, w) = self.sample_1d(s.next_1d());
                let x = p as f32 + 0.5 + d;
                if x >= 0.0 && x < n as f32 {
                    return (x, w);
                }
            }
            (p as f32 + 0.5, 1.0)
        };
        let (x, wx) = axis(s, px, width);
        let (y, wy) = axis(s, py, height);
        (x, y, wx * wy)
    }
}

/// Per-pixel running sums (f64 so that millions of samples add exactly enough).
#[derive(Debug, Clone, Copy, Default)]
pub struct Accum {
    sum: [f64; 3],
    sum_sq: [f64; 3],
}

impl Accum {
    /// Add one sample; its square too if `variance`.
    #[inline]
    pub fn add(&mut self, l: Spectrum, variance: bool) {
        for c in 0..3 {
            let v = l[c] as f64;
            self.sum[c] += v;
            if variance {
                self.sum_sq[c] += v * v;
            }
        }
    }
}

/// A rendered image: row-major from the top-left, RGB interleaved.
#[derive(Debug, Clone)]
pub struct RenderOutput {
    pub width: usize,
    pub height: usize,
    /// `height·width·3` linear radiance values (the pixel means).
    pub image: Vec<f32>,
    /// Variance of each pixel mean (sample variance / n), if asked for.
    pub variance: Option<Vec<f32>>,
    /// Samples per pixel in the image (less than asked if cancelled).
    pub spp_done: u32,
    pub spp_requested: u32,
}

impl RenderOutput {
    /// The image of `acc` (`width·height` pixels of `done` samples each),
    /// with the variances of the pixel means if `variance`.
    pub fn from_sums(
        acc: &[Accum],
        width: usize,
        height: usize,
        done: u32,
        spp_requested: u32,
        variance: bool,
    ) -> RenderOutput {
        let nf = done.max(1) as f64;
        let image: Vec<f32> = acc
            .iter()
            .flat_map(|a| a.sum.map(|s| (s / nf) as f32))
            .collect();
        let variance = variance.then(|| {
            acc.iter()
                .flat_map(|a| {
                    [0, 1, 2].map(|c| {
                        if done < 2 {
                            return f32::NAN;
                        }
                        let m = a.sum[c] / nf;
                        // Unbiased sample variance, divided by n for the mean.
                        let var = ((a.sum_sq[c] - nf * m * m) / (nf - 1.0)).max(0.0);
                        (var / nf) as f32
                    })
                })
                .collect()
        });
        RenderOutput {
            width,
            height,
            image,
            variance,
            spp_done: done,
            spp_requested,
        }
    }
}

fn gaussian(x: f32, stddev: f32, radius: f32) -> f32 {
    let a = 1.0 / (2.0 * stddev * stddev);
    ((-x * x * a).exp() - (-radius * radius * a).exp()).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The weighted histogram of sampled offsets reproduces the normalised
    /// filter (binned; the sampling is exact up to the 1024-bin table, which
    /// the weights correct).
    #[test]
    fn filter_sampling_reproduces_the_filter() {
        let tent = |x: f32| (1.0 - x.abs()).max(0.0);
        let gauss = |x: f32| gaussian(x, 0.5, 2.0);
        let cases: [(FilterDesc, &dyn Fn(f32) -> f32); 2] = [
            (FilterDesc::Tent { radius: 1.0 }, &tent),
            (FilterDesc::Gaussian { stddev: 0.5 }, &gauss),
        ];
        for (desc, f) in cases {
            let filter = Filter::new(&desc);
            let r = match desc {
                FilterDesc::Tent { radius } => radius,
                FilterDesc::Gaussian { stddev } => 4.0 * stddev,
                FilterDesc::Box => 0.5,
            };
            let bins = 16;
            let mut hist = vec![0f64; bins];
            let n = 400_000;
            for i in 0..n {
                // Stratified variates: the histogram error is O(1/n).
                let u = (i as f32 + 0.5) / n as f32;
                let (x, w) = filter.sample_1d(u);
                let b =
                    (((x + r) / (2.0 * r)) * bins as f32).clamp(0.0, bins as f32 - 1.0) as usize;
                hist[b] += w as f64 / n as f64;
            }
            // Expected mass per bin by the midpoint rule on a fine grid.
            let fine = 4000;
            let h = 2.0 * r / fine as f32;
            let total: f64 = (0..fine).map(|i| f(-r + (i as f32 + 0.5) * h) as f64).sum();
            for (b, &got) in hist.iter().enumerate() {
                let expect: f64 = (0..fine)
                    .filter(|i| (i * bins / fine) == b)
                    .map(|i| f(-r + (i as f32 + 0.5) * h) as f64)
                    .sum::<f64>()
                    / total;
                assert!(
                    (got - expect).abs() < 2e-3,
                    "{desc:?} bin {b}: {got} vs {expect}"
                );
            }
        }
    }
}
