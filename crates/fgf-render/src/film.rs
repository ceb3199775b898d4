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
//! Each pixel keeps exact fixed-point sums of its samples ([`Fixed`] in a
//! [`FilmState`]), from which [`FilmState::finish`] takes the pixel means
//! and, if asked, their variances: the sums do not depend on how the samples
//! were split into passes, chunks or machines (`docs/theory.md` §7.17).

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

/// Fractional bits of [`Fixed`]: the accumulator's unit is `2⁻⁹⁶`.
pub const FIXED_FRAC_BITS: i32 = 96;
/// Limbs (64-bit words, least significant first) of [`Fixed`].
pub const FIXED_LIMBS: usize = 3;

/// An exact fixed-point number: a 192-bit two's-complement integer in units
/// of `2⁻⁹⁶` (`docs/theory.md` §7.17).
///
/// Adding values to it is exact integer arithmetic, hence associative and
/// commutative: a pixel's sum does not depend on the order of its samples,
/// on how they were split into passes or chunks, or on the order in which
/// chunks are merged. An f64 is added exactly when its lowest set bit is at
/// or above `2⁻⁹⁶` (every f32 sample ≥ 2⁻⁷³ ≈ 1e-22, every square of an f32
/// ≥ 2⁻²⁵); smaller bits are rounded to the nearest unit (an absolute error
/// ≤ 2⁻⁹⁷ ≈ 6e-30 per value). The range is `|sum| < 2⁹⁵ ≈ 4e28`; leaving it
/// is reported by [`Fixed::add_f64`] and [`Fixed::merge`] returning `false`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Fixed(pub [u64; FIXED_LIMBS]);

impl Fixed {
    #[inline]
    fn negative(&self) -> bool {
        (self.0[FIXED_LIMBS - 1] >> 63) != 0
    }

    /// `self += other` (wrapping); returns `false` on signed overflow.
    #[inline]
    pub fn merge(&mut self, other: &Fixed) -> bool {
        let (sa, sb) = (self.negative(), other.negative());
        let mut carry = false;
        for i in 0..FIXED_LIMBS {
            let (t, c1) = self.0[i].overflowing_add(other.0[i]);
            let (t, c2) = t.overflowing_add(carry as u64);
            self.0[i] = t;
            carry = c1 || c2;
        }
        // Two's complement overflows iff both operands have the same sign
        // and the result has the other.
        !(sa == sb && self.negative() != sa)
    }

    /// The fixed-point value of a finite `v`, rounded to the nearest unit
    /// (ties away from zero); `None` if `|v| ≥ 2⁹⁵` or `v` is not finite.
    #[inline]
    pub fn from_f64(v: f64) -> Option<Fixed> {
        if !v.is_finite() {
            return None;
        }
        if v == 0.0 {
            return Some(Fixed::default());
        }
        let bits = v.to_bits();
        let exp = ((bits >> 52) & 0x7ff) as i32;
        let frac = bits & ((1u64 << 52) - 1);
        // v = m · 2^e with a 53-bit integer m.
        let (m, e) = if exp == 0 {
            (frac, -1074)
        } else {
            (frac | (1u64 << 52), exp - 1075)
        };
        // In units: m · 2^(e + 96).
        let shift = e + FIXED_FRAC_BITS;
        let mut mag = [0u64; FIXED_LIMBS];
        if shift < 0 {
            let r = (-shift) as u32;
            // m < 2^53: below half a unit it rounds to 0.
            if r > 53 {
                return Some(Fixed::default());
            }
            // Round half away from zero: add half a unit before shifting.
            mag[0] = (m + (1u64 << (r - 1))) >> r;
        } else {
            // Keep the magnitude below 2^191 so that it is positive as a
            // 192-bit two's-complement number.
            if shift + 53 > 64 * FIXED_LIMBS as i32 - 1 {
                return None;
            }
            let (word, bit) = ((shift / 64) as usize, (shift % 64) as u32);
            mag[word] = m << bit;
            if bit > 0 && word + 1 < FIXED_LIMBS {
                mag[word + 1] = m >> (64 - bit);
            }
        }
        let mut out = Fixed(mag);
        if v < 0.0 {
            // Two's-complement negation: invert, add one.
            let mut carry = true;
            for w in out.0.iter_mut() {
                let (t, c) = (!*w).overflowing_add(carry as u64);
                *w = t;
                carry = c;
            }
        }
        Some(out)
    }

    /// `self += v` exactly (up to the rounding of bits below `2⁻⁹⁶`);
    /// returns `false` if `v` is not finite or the sum leaves the range.
    #[inline]
    pub fn add_f64(&mut self, v: f64) -> bool {
        match Fixed::from_f64(v) {
            Some(f) => self.merge(&f),
            None => false,
        }
    }

    /// The value as an f64 (a fixed function of the bits, so the same sum
    /// always gives the same f64).
    pub fn to_f64(&self) -> f64 {
        let neg = self.negative();
        let mut mag = self.0;
        if neg {
            let mut carry = true;
            for w in mag.iter_mut() {
                let (t, c) = (!*w).overflowing_add(carry as u64);
                *w = t;
                carry = c;
            }
        }
        // Most significant limb first; each term is exact in f64 up to one
        // rounding of its 64 bits, and the sum is taken in a fixed order.
        let mut x = 0.0f64;
        for (i, &w) in mag.iter().enumerate().rev() {
            x += (w as f64) * f64::powi(2.0, 64 * i as i32 - FIXED_FRAC_BITS);
        }
        if neg {
            -x
        } else {
            x
        }
    }
}

/// The exact per-pixel sums of a set of camera samples: what a render of a
/// sample range returns, what chunks merge into, and what a checkpoint
/// holds (`docs/theory.md` §7.17). `sum` (and `sum_sq` if the variance is
/// kept) has `width·height·3` entries, row-major from the top-left, RGB
/// interleaved.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FilmState {
    pub width: usize,
    pub height: usize,
    /// Samples per pixel the sums hold.
    pub samples: u64,
    pub sum: Vec<Fixed>,
    pub sum_sq: Option<Vec<Fixed>>,
}

/// A sample or a merge that leaves the exact accumulator's range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutOfRange {
    /// Flat index `(y·width + x)·3 + channel`.
    pub index: usize,
    /// The offending sample value (NaN for a merge).
    pub value: f64,
}

impl FilmState {
    /// Empty sums for a `width × height` film.
    pub fn new(width: usize, height: usize, variance: bool) -> FilmState {
        let n = width * height * 3;
        FilmState {
            width,
            height,
            samples: 0,
            sum: vec![Fixed::default(); n],
            sum_sq: variance.then(|| vec![Fixed::default(); n]),
        }
    }

    /// Add `other`'s sums to these (the same film and variance setting, which
    /// the caller checks; the result is independent of the merge order).
    pub fn merge(&mut self, other: &FilmState) -> Result<(), OutOfRange> {
        debug_assert_eq!(self.sum.len(), other.sum.len());
        let bad = |index| OutOfRange {
            index,
            value: f64::NAN,
        };
        for (i, (a, b)) in self.sum.iter_mut().zip(&other.sum).enumerate() {
            if !a.merge(b) {
                return Err(bad(i));
            }
        }
        if let (Some(a), Some(b)) = (self.sum_sq.as_mut(), other.sum_sq.as_ref()) {
            for (i, (a, b)) in a.iter_mut().zip(b).enumerate() {
                if !a.merge(b) {
                    return Err(bad(i));
                }
            }
        }
        self.samples += other.samples;
        Ok(())
    }

    /// The image of these sums (pixel means over `samples`), with the
    /// variances of the means if the squares were kept.
    pub fn finish(&self, spp_requested: u32) -> RenderOutput {
        let done = self.samples;
        let nf = done.max(1) as f64;
        let image: Vec<f32> = self.sum.iter().map(|s| (s.to_f64() / nf) as f32).collect();
        let variance = self.sum_sq.as_ref().map(|sq| {
            self.sum
                .iter()
                .zip(sq)
                .map(|(s, s2)| {
                    if done < 2 {
                        return f32::NAN;
                    }
                    let m = s.to_f64() / nf;
                    // Unbiased sample variance, divided by n for the mean.
                    let var = ((s2.to_f64() - nf * m * m) / (nf - 1.0)).max(0.0);
                    (var / nf) as f32
                })
                .collect()
        });
        RenderOutput {
            width: self.width,
            height: self.height,
            image,
            variance,
            spp_done: done.min(u32::MAX as u64) as u32,
            spp_requested,
        }
    }
}

/// Add one sample's radiance `l` to a pixel's three sums (and squares);
/// `Err(channel, value)` if a channel leaves the accumulator's range.
#[inline]
pub fn accumulate(
    sum: &mut [Fixed],
    sum_sq: Option<&mut [Fixed]>,
    l: Spectrum,
) -> Result<(), (usize, f64)> {
    for c in 0..3 {
        let v = l[c] as f64;
        if !sum[c].add_f64(v) {
            return Err((c, v));
        }
    }
    if let Some(sq) = sum_sq {
        for c in 0..3 {
            let v = l[c] as f64;
            // Exact: an f32 squared fits in an f64.
            if !sq[c].add_f64(v * v) {
                return Err((c, v));
            }
        }
    }
    Ok(())
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
