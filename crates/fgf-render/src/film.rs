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

/// Add one sample's radiance `l` to a pixel's three sums (and squares)
/// directly in [`Fixed`]; `Err(channel, value)` if a channel leaves the
/// accumulator's range. [`accumulate_pending`] gives the same sums, cheaper.
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

/// The smallest f32 magnitude whose bits all lie at or above [`Fixed`]'s
/// unit `2⁻⁹⁶` (24-bit mantissa): smaller nonzero samples are rounded.
const ON_GRID: f32 = 1.0 / (1u128 << 73) as f32;
/// The same for squares (48-bit mantissa, bits down to `2⁻⁹⁶`).
const SQUARE_ON_GRID: f32 = 1.0 / (1u64 << 25) as f32;
/// [`Fixed`]'s range, `|sum| < 2⁹⁵`.
const FIXED_RANGE: f64 = (1u128 << 95) as f64;

/// `s + v` and whether the f64 sum is exact and inside [`Fixed`]'s range:
/// `t = fl(s + v)` is exact iff `t − s = v` and `t − v = s` in floating
/// point (whichever of `s`, `v` is larger in magnitude, the difference
/// from it is computed exactly: Dekker's Fast2Sum).
#[cfg(any(test, not(all(target_arch = "x86_64", target_feature = "avx"))))]
#[inline(always)]
fn exact_add(s: f64, v: f64) -> (f64, bool) {
    let t = s + v;
    // `&`, not `&&`: three compares without branches.
    (t, (t - s == v) & (t - v == s) & (t.abs() < FIXED_RANGE))
}

/// [`exact_add`] per channel: the three sums, and whether all three are
/// exact and every sample `x` (whose f64 value, or square, is `v`) lies on
/// the grid (`0` or `|x| ≥ min`).
#[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
#[inline(always)]
fn exact_add3(pending: &[f64; 3], v: [f64; 3], x: [f32; 3], min: f32) -> ([f64; 3], bool) {
    exact_add3_scalar(pending, v, x, min)
}

/// [`exact_add3`] channel by channel with [`exact_add`].
#[cfg(any(test, not(all(target_arch = "x86_64", target_feature = "avx"))))]
#[inline(always)]
fn exact_add3_scalar(pending: &[f64; 3], v: [f64; 3], x: [f32; 3], min: f32) -> ([f64; 3], bool) {
    let on_grid = |x: f32| (x == 0.0) | (x.abs() >= min);
    let (t0, e0) = exact_add(pending[0], v[0]);
    let (t1, e1) = exact_add(pending[1], v[1]);
    let (t2, e2) = exact_add(pending[2], v[2]);
    (
        [t0, t1, t2],
        e0 & e1 & e2 & on_grid(x[0]) & on_grid(x[1]) & on_grid(x[2]),
    )
}

/// The same tests in four AVX lanes (the fourth adds 0 to 0, exact and on
/// the grid): the same comparisons, ordered (false for NaN) as the scalar
/// ones, so the same result, in a few instructions instead of some fifty.
#[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
#[inline(always)]
fn exact_add3(pending: &[f64; 3], v: [f64; 3], x: [f32; 3], min: f32) -> ([f64; 3], bool) {
    use std::arch::x86_64::*;
    // SAFETY: the intrinsics need AVX, which this function is only
    // compiled with; the only memory they touch is `out`, a local array.
    unsafe {
        let s = _mm256_set_pd(0.0, pending[2], pending[1], pending[0]);
        let v = _mm256_set_pd(0.0, v[2], v[1], v[0]);
        let t = _mm256_add_pd(s, v);
        let exact = _mm256_and_pd(
            _mm256_cmp_pd::<_CMP_EQ_OQ>(_mm256_sub_pd(t, s), v),
            _mm256_cmp_pd::<_CMP_EQ_OQ>(_mm256_sub_pd(t, v), s),
        );
        let abs_t = _mm256_andnot_pd(_mm256_set1_pd(-0.0), t);
        let exact = _mm256_and_pd(
            exact,
            _mm256_cmp_pd::<_CMP_LT_OQ>(abs_t, _mm256_set1_pd(FIXED_RANGE)),
        );
        let x = _mm_set_ps(0.0, x[2], x[1], x[0]);
        let abs_x = _mm_andnot_ps(_mm_set1_ps(-0.0), x);
        let on_grid = _mm_or_ps(
            _mm_cmp_ps::<_CMP_EQ_OQ>(x, _mm_setzero_ps()),
            _mm_cmp_ps::<_CMP_GE_OQ>(abs_x, _mm_set1_ps(min)),
        );
        let ok = _mm256_movemask_pd(exact) & _mm_movemask_ps(on_grid);
        let mut out = [0f64; 4];
        _mm256_storeu_pd(out.as_mut_ptr(), t);
        ([out[0], out[1], out[2]], ok == 0b1111)
    }
}

/// Add the pending partial sum `p` to `f` (exact: `p` is a multiple of the
/// unit below the range); `false` if `f` leaves the range.
#[inline]
fn flush_one(f: &mut Fixed, p: &mut f64) -> bool {
    let v = std::mem::replace(p, 0.0);
    // Shortcuts for the common final flush of a render: nothing pending
    // (a black pixel), or nothing in `f` yet (every sample took the fast
    // path), where the sum is the pending value itself.
    if v == 0.0 {
        return true;
    }
    match Fixed::from_f64(v) {
        Some(x) if *f == Fixed::default() => {
            *f = x;
            true
        }
        Some(x) => f.merge(&x),
        None => false,
    }
}

/// Add one sample's radiance `l` to a pixel's sums through f64 partial sums
/// kept exact (`docs/theory.md` §7.17): `pending` (RGB, and
/// `pending_sq` for the squares) hold the exact sum of the samples not yet
/// in `sum` (`sum_sq`). A sample goes into `pending` when the f64 addition
/// is exact and the sample lies on [`Fixed`]'s grid (`|v| ≥ 2⁻⁷³`, squares
/// `≥ 2⁻²⁵`, or 0) — then `pending` is a multiple of the unit and moves to
/// `sum` exactly; otherwise `pending` moves to `sum` and the sample is added
/// by [`accumulate`], with its rounding. The sums are the integers
/// [`accumulate`] alone would give, grouped differently, so their bits are
/// the same. [`flush_pending`] must follow the last sample.
///
/// `Err(channel, value)` as [`accumulate`]'s if a channel leaves the range.
#[inline]
pub fn accumulate_pending(
    sum: &mut [Fixed],
    pending: &mut [f64; 3],
    sq: Option<(&mut [Fixed], &mut [f64; 3])>,
    l: Spectrum,
) -> Result<(), (usize, f64)> {
    add_pending::<false>(sum, pending, sq, l)
}

/// [`accumulate_pending`] for a renderer's sample, where a NaN or infinite
/// `l` (a numerical failure, e.g. a zero pdf) would poison the pixel for
/// ever: such a sample counts as 0 (it leaves the sums as they are). The
/// test costs nothing on the fast path, which only finite samples pass
/// (`inf - inf` and NaN fail its exactness test).
#[inline]
pub fn accumulate_sample(
    sum: &mut [Fixed],
    pending: &mut [f64; 3],
    sq: Option<(&mut [Fixed], &mut [f64; 3])>,
    l: Spectrum,
) -> Result<(), (usize, f64)> {
    add_pending::<true>(sum, pending, sq, l)
}

/// [`accumulate_pending`], and with `DROP_NON_FINITE` [`accumulate_sample`].
#[inline(always)]
fn add_pending<const DROP_NON_FINITE: bool>(
    sum: &mut [Fixed],
    pending: &mut [f64; 3],
    sq: Option<(&mut [Fixed], &mut [f64; 3])>,
    l: Spectrum,
) -> Result<(), (usize, f64)> {
    let v = l.to_array();
    let (t, fast) = exact_add3(pending, v.map(f64::from), v, ON_GRID);
    match sq {
        None if fast => {
            *pending = t;
            Ok(())
        }
        Some((sum_sq, pending_sq)) => {
            let w = v.map(|x| x as f64 * x as f64);
            let (q, fast_sq) = exact_add3(pending_sq, w, v, SQUARE_ON_GRID);
            if fast & fast_sq {
                *pending = t;
                *pending_sq = q;
                return Ok(());
            }
            if DROP_NON_FINITE && !l.is_finite() {
                return Ok(());
            }
            flush_pending(sum, pending, Some((&mut *sum_sq, &mut *pending_sq)), l)?;
            accumulate(sum, Some(sum_sq), l)
        }
        None => {
            if DROP_NON_FINITE && !l.is_finite() {
                return Ok(());
            }
            flush_pending(sum, pending, None, l)?;
            accumulate(sum, None, l)
        }
    }
}

/// Move a pixel's pending partial sums (see [`accumulate_pending`]) into its
/// [`Fixed`] sums; `Err(channel, value)` with `value` the pending sum (or
/// the sample `l` being added, if not zero) if a sum leaves the range.
#[cold]
pub fn flush_pending(
    sum: &mut [Fixed],
    pending: &mut [f64; 3],
    sq: Option<(&mut [Fixed], &mut [f64; 3])>,
    l: Spectrum,
) -> Result<(), (usize, f64)> {
    let report = |c: usize, p: f64| if l[c] != 0.0 { l[c] as f64 } else { p };
    for c in 0..3 {
        let p = pending[c];
        if !flush_one(&mut sum[c], &mut pending[c]) {
            return Err((c, report(c, p)));
        }
    }
    if let Some((sum_sq, pending_sq)) = sq {
        for c in 0..3 {
            let p = pending_sq[c];
            if !flush_one(&mut sum_sq[c], &mut pending_sq[c]) {
                return Err((c, report(c, p.sqrt())));
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

    /// f32 values over every exponent (normal and subnormal, both signs),
    /// with mantissas from a fixed hash: the edge ones and 64 others each.
    fn f32_values() -> Vec<f32> {
        let mut out = vec![0.0, -0.0, f32::MIN_POSITIVE, f32::MAX];
        let mut h = 0x9e37_79b9_7f4a_7c15u64;
        for e8 in 0..255u32 {
            for j in 0..68u32 {
                h = fgf_core::rng::mix64(h);
                let frac = match j {
                    0 => 0,
                    1 => 1,
                    2 => 0x7f_ffff,
                    3 => 0x40_0000,
                    _ => (h as u32) & 0x7f_ffff,
                };
                let sign = ((h >> 40) as u32 & 1) << 31;
                out.push(f32::from_bits(sign | (e8 << 23) | frac));
            }
        }
        out
    }

    /// Samples drawn from `vals` by a fixed hash, `len` of them.
    fn spectra(vals: &[f32], len: usize, mut h: u64) -> Vec<Spectrum> {
        (0..len)
            .map(|_| {
                let mut c = [0f32; 3];
                for x in &mut c {
                    h = fgf_core::rng::mix64(h);
                    *x = vals[(h % vals.len() as u64) as usize];
                }
                Spectrum::from_array(c)
            })
            .collect()
    }

    /// Sums through the f64 partial sums, flushed every `pass` samples.
    fn pending_sums(spectra: &[Spectrum], pass: usize, squares: bool) -> ([Fixed; 3], [Fixed; 3]) {
        let (mut s, mut q) = ([Fixed::default(); 3], [Fixed::default(); 3]);
        let (mut p, mut pq) = ([0f64; 3], [0f64; 3]);
        for part in spectra.chunks(pass) {
            for &l in part {
                let sq = squares.then_some((&mut q[..], &mut pq));
                accumulate_pending(&mut s, &mut p, sq, l).unwrap();
            }
            let sq = squares.then_some((&mut q[..], &mut pq));
            flush_pending(&mut s, &mut p, sq, Spectrum::ZERO).unwrap();
        }
        (s, q)
    }

    /// Sums (squares too) through the exact f64 partial sums are
    /// bit-identical to sample-by-sample ones, for samples on and off the
    /// grid and of any magnitude, and any flush points.
    #[test]
    fn pending_sums_are_the_fixed_sums() {
        let all: Vec<f32> = f32_values()
            .into_iter()
            .filter(|v| v.abs() < 1e12)
            .collect();
        // Radiance-like: nonnegative, within a few decades (the fast path).
        let typical: Vec<f32> = all
            .iter()
            .map(|v| v.abs())
            .filter(|v| *v == 0.0 || (1e-6..1e3).contains(v))
            .collect();
        for (vals, seed) in [(&all, 1u64), (&typical, 2)] {
            for len in [1usize, 2, 63, 64, 65, 1000] {
                let spectra = spectra(vals, len, seed ^ len as u64);
                let (mut s0, mut q0) = ([Fixed::default(); 3], [Fixed::default(); 3]);
                for &l in &spectra {
                    accumulate(&mut s0, Some(&mut q0), l).unwrap();
                }
                for pass in [1usize, 2, 7, 64, 1000] {
                    assert_eq!(
                        pending_sums(&spectra, pass, true),
                        (s0, q0),
                        "{len}, {pass}"
                    );
                    assert_eq!(pending_sums(&spectra, pass, false).0, s0, "{len}, {pass}");
                }
            }
        }
    }

    /// The fast path's test (vector lanes in the AVX build) gives the sums
    /// and the verdict of the scalar one, for values and squares of any
    /// magnitude and sign, on and off the grid, exact sums or not.
    #[test]
    fn exact_add3_is_the_scalar_test() {
        let vals = f32_values();
        let samples = spectra(&vals, 20_000, 3);
        let mut pending = [0f64; 3];
        let mut fast = [0usize; 2];
        for (i, l) in samples.iter().enumerate() {
            let x = l.to_array();
            for (v, min) in [
                (x.map(f64::from), ON_GRID),
                (x.map(|x| x as f64 * x as f64), SQUARE_ON_GRID),
            ] {
                let (t, ok) = exact_add3(&pending, v, x, min);
                let (t0, ok0) = exact_add3_scalar(&pending, v, x, min);
                assert_eq!(t.map(f64::to_bits), t0.map(f64::to_bits), "{i}");
                assert_eq!(ok, ok0, "{i}: {pending:?} + {v:?}");
                fast[ok as usize] += 1;
            }
            // Pending sums of all kinds: restart now and then, else carry on.
            pending = if i % 5 == 0 {
                [0.0; 3]
            } else {
                exact_add3_scalar(&pending, x.map(f64::from), x, ON_GRID).0
            };
        }
        // Both verdicts were seen often.
        assert!(fast[0] > 1000 && fast[1] > 1000, "{fast:?}");
    }

    /// A renderer's NaN or infinite sample leaves the sums as a zero
    /// sample would, with or without squares, and finite ones are added as
    /// by `accumulate_pending`.
    #[test]
    fn accumulate_sample_counts_non_finite_samples_as_zero() {
        let bad = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY];
        let vals: Vec<f32> = f32_values()
            .into_iter()
            .filter(|v| v.abs() < 1e12)
            .collect();
        let samples = spectra(&vals, 200, 4);
        for squares in [false, true] {
            let (mut s0, mut p0, mut q0, mut pq0) = (
                [Fixed::default(); 3],
                [0f64; 3],
                [Fixed::default(); 3],
                [0f64; 3],
            );
            let (mut s1, mut p1, mut q1, mut pq1) = (s0, p0, q0, pq0);
            for (i, &l) in samples.iter().enumerate() {
                let mut x = l;
                x[i % 3] = bad[i % 3];
                for (l0, l1) in [(l, l), (Spectrum::ZERO, x)] {
                    let sq0 = squares.then_some((&mut q0[..], &mut pq0));
                    let sq1 = squares.then_some((&mut q1[..], &mut pq1));
                    accumulate_pending(&mut s0, &mut p0, sq0, l0).unwrap();
                    accumulate_sample(&mut s1, &mut p1, sq1, l1).unwrap();
                    assert_eq!(p0.map(f64::to_bits), p1.map(f64::to_bits), "{i}");
                    assert_eq!(pq0.map(f64::to_bits), pq1.map(f64::to_bits), "{i}");
                    assert_eq!((s0, q0), (s1, q1), "{i}");
                }
            }
        }
    }

    /// A sum leaving the range is an error naming the sample that took it
    /// there, as sample by sample.
    #[test]
    fn pending_sums_report_out_of_range() {
        let big = Spectrum::splat(1e28);
        let (mut s, mut p) = ([Fixed::default(); 3], [0f64; 3]);
        let mut err = None;
        for _ in 0..8 {
            if let Err(e) = accumulate_pending(&mut s, &mut p, None, big) {
                err = Some(e);
                break;
            }
        }
        assert_eq!(err, Some((0, 1e28f32 as f64)));
        // Squares: 2^48 squared is 2^96, over the range at once.
        let (mut s, mut p) = ([Fixed::default(); 3], [0f64; 3]);
        let (mut q, mut pq) = ([Fixed::default(); 3], [0f64; 3]);
        let l = Spectrum::splat(f32::powi(2.0, 48));
        let r = accumulate_pending(&mut s, &mut p, Some((&mut q, &mut pq)), l);
        assert_eq!(r, Err((0, f64::powi(2.0, 48))));
    }

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
