//! Small numerical helpers shared by the renderer: orthonormal frames, the
//! per-sample random stream, the warping functions and the MIS heuristic.
//!
//! Sampling routines take their uniform variates `u ∈ [0,1)` as arguments
//! and come with their pdf (pbrt-v4's habit), so they can be tested alone.

use crate::lanes::{D8, F8};
use fgf_core::rng::{mix64, stream_key, SECOND_WORD};
use glam::{Mat3, Vec3A};
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

    /// A stream for a slot that no sample uses (cheap to make).
    #[inline]
    pub fn idle() -> Self {
        Sampler {
            rng: Pcg32::new(0, 1),
        }
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

/// Shirley–Chiu concentric map of the unit square to the unit disk. Its
/// angle, `(π/4)·(oy/ox)` from the x axis or `π/2 − (π/4)·(ox/oy)`, is
/// `1/8` of the ratio in turns from an axis: its sine and cosine come from
/// [`sin_cos_2pi`] (and `sample_concentric_disk8` gives the same bits on
/// eight lanes).
pub fn sample_concentric_disk(u: [f32; 2]) -> [f32; 2] {
    let ox = 2.0 * u[0] - 1.0;
    let oy = 2.0 * u[1] - 1.0;
    if ox == 0.0 && oy == 0.0 {
        return [0.0, 0.0];
    }
    if ox.abs() > oy.abs() {
        let (s, c) = sin_cos_2pi(0.125 * (oy / ox));
        [ox * c, ox * s]
    } else {
        // cos(π/2 − φ) = sin φ, sin(π/2 − φ) = cos φ.
        let (s, c) = sin_cos_2pi(0.125 * (ox / oy));
        [oy * s, oy * c]
    }
}

/// [`sample_concentric_disk`] of eight lanes, each with the scalar
/// function's bits.
#[inline(always)]
pub(crate) fn sample_concentric_disk8(u: [F8; 2]) -> [F8; 2] {
    let (zero, one, two) = (F8::splat(0.0), F8::splat(1.0), F8::splat(2.0));
    let ox = two.mul(u[0]).sub(one);
    let oy = two.mul(u[1]).sub(one);
    let x_major = oy.copysign(one).lt(ox.copysign(one));
    let r = x_major.select(ox, oy);
    let ratio = x_major.select(oy, ox).div(r);
    let (s, c) = sin_cos_2pi8(F8::splat(0.125).mul(ratio));
    let centre = ox
        .le(zero)
        .and(zero.le(ox))
        .and(oy.le(zero))
        .and(zero.le(oy));
    [
        centre.select(zero, r.mul(x_major.select(c, s))),
        centre.select(zero, r.mul(x_major.select(s, c))),
    ]
}

/// Uniform direction on the unit sphere; pdf `1/(4π)`.
pub fn sample_uniform_sphere(u: [f32; 2]) -> Vec3A {
    let z = 1.0 - 2.0 * u[0];
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (sin_phi, cos_phi) = sin_cos_2pi(u[1]);
    Vec3A::new(r * cos_phi, r * sin_phi, z)
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

/// `1.5·2^52`: adding it to an f64 of magnitude below `2^51` rounds that
/// value to an integer (ties to even) held in the low bits of the sum.
const ROUND_SHIFT: f64 = 6_755_399_441_055_744.0;

/// `e^x` for f32 `x`, inline (the renderer's transmittances `e^{-σt}`).
///
/// Domain: every f32. `exp(0) = 1` exactly, `exp(x) = 0` for
/// `x ≤ -104` (and `-∞`), `+∞` for `x ≥ 89`, NaN stays NaN. Method: in f64,
/// `x·log2 e = n + f` with integer `n` and `|f| ≤ ½`, `2^f` by a degree-6
/// polynomial (Chebyshev fit, relative error 2.8e-9), times `2^n` built from
/// its bits. Measured max error 0.53 ulp against f64 `exp` over every 64th f32
/// in `[-104, 89]` (normal and subnormal results, see the tests).
#[inline]
pub fn exp(x: f32) -> f32 {
    // Beyond these bounds the f32 result is 0 or ∞ (e^-104 is below half the
    // least subnormal, e^89 above f32::MAX); clamp passes NaN through.
    let y = x.clamp(-104.0, 89.0) as f64 * std::f64::consts::LOG2_E;
    let t = y + ROUND_SHIFT;
    let f = y - (t - ROUND_SHIFT);
    const C: [f64; 6] = [
        0.6931472067028326,
        0.24022650922288757,
        0.05550327226670302,
        0.009618056678524637,
        0.0013400428177615838,
        0.0001546144469856913,
    ];
    let p = 1.0 + f * (C[0] + f * (C[1] + f * (C[2] + f * (C[3] + f * (C[4] + f * C[5])))));
    // n ∈ [-151, 129]: 2^n is a normal f64 whose biased exponent is n + 1023
    // (the low bits of t hold n in two's complement).
    let scale = f64::from_bits(t.to_bits().wrapping_add(1023) << 52);
    (p * scale) as f32
}

/// Natural logarithm of an f32, inline (free-flight sampling `-ln(1 - u)`).
///
/// Domain: every f32: `ln(1) = 0` exactly, `ln(±0) = -∞`, `ln(+∞) = +∞`,
/// negative or NaN gives NaN, subnormals are exact inputs. Method: `x = 2^k·m`
/// with `m ∈ [√½, √2)`, and in f64 `ln m = 2 atanh s` with `s = (m-1)/(m+1)`,
/// `|s| ≤ 0.172`, by `s·R(s²)` with a cubic `R` (Chebyshev fit, relative
/// error 7e-10). Measured max error 0.51 ulp against f64 `ln` over every 64th
/// positive f32 and every `1 - u` of a 24-bit `u` (see the tests).
#[inline]
pub fn ln(x: f32) -> f32 {
    let ix = x.to_bits();
    // Positive normal finite x only; 0, subnormals, negatives, ∞, NaN below.
    if ix.wrapping_sub(0x0080_0000) >= 0x7f00_0000 {
        return ln_special(x);
    }
    ln_normal(ix, 0)
}

/// [`ln`] of a positive normal f32 with bits `ix`, plus `k0·ln 2`.
#[inline(always)]
fn ln_normal(ix: u32, k0: i32) -> f32 {
    // 0x3f3504f3 is the bits of √½: t's exponent field is k (signed), and
    // subtracting it from ix's leaves m = x/2^k in [√½, √2).
    let t = ix.wrapping_sub(0x3f35_04f3);
    let k = (t as i32 >> 23) + k0;
    let m = f32::from_bits(ix.wrapping_sub(t & 0xff80_0000)) as f64;
    let s = (m - 1.0) / (m + 1.0);
    let z = s * s;
    const R: [f64; 4] = [
        1.9999999986313182,
        0.6666681533815119,
        0.3997485051751905,
        0.29924390479144986,
    ];
    let ln_m = s * (R[0] + z * (R[1] + z * (R[2] + z * R[3])));
    (k as f64 * std::f64::consts::LN_2 + ln_m) as f32
}

#[cold]
fn ln_special(x: f32) -> f32 {
    if x == 0.0 {
        f32::NEG_INFINITY
    } else if x.is_nan() || x < 0.0 {
        f32::NAN
    } else if x == f32::INFINITY {
        x
    } else {
        // Subnormal: scale by 2^23 into the normal range.
        ln_normal((x * 8_388_608.0).to_bits(), -23)
    }
}

/// `(sin 2πu, cos 2πu)` for f32 `u`, inline (azimuths `φ = 2πu` of sampled
/// directions): more accurate than `(2π·u).sin_cos()` since the turn is
/// reduced exactly (`u = q/4 + r`, `|r| ≤ ⅛`, no rounding) and `2π` is never
/// rounded to f32, and exact at multiples of ¼ (`sin_cos_2pi(0) = (0, 1)`).
///
/// Domain: finite `|u| < 2^50` (the callers pass `[0, 1]`). Method: in f64,
/// `sin 2πr = r·S(r²)`, `cos 2πr = 1 + r²·C(r²)` with cubic `S` and `C`
/// (Chebyshev fits, errors 3.4e-9 relative and 1.9e-10 absolute), then the
/// quadrant `q` swaps and negates. Measured max error 0.55 ulp against f64
/// over every 64th f32 in `[0, 1]` and every 24-bit `u` (see the tests).
#[inline]
pub fn sin_cos_2pi(u: f32) -> (f32, f32) {
    let ud = u as f64;
    let t = ud * 4.0 + ROUND_SHIFT;
    let r = ud - (t - ROUND_SHIFT) * 0.25;
    let q = t.to_bits();
    let z = r * r;
    let s = r * (SIN_2PI[0] + z * (SIN_2PI[1] + z * (SIN_2PI[2] + z * SIN_2PI[3])));
    let c = 1.0 + z * (COS_2PI[0] + z * (COS_2PI[1] + z * (COS_2PI[2] + z * COS_2PI[3])));
    // Quarter turns: (sin, cos) → (cos, -sin) → (-sin, -cos) → (-cos, sin).
    let (s, c) = if q & 1 == 0 { (s, c) } else { (c, s) };
    let sin = f64::from_bits(s.to_bits() ^ ((q & 2) << 62));
    let cos = f64::from_bits(c.to_bits() ^ ((q.wrapping_add(1) & 2) << 62));
    (sin as f32, cos as f32)
}

/// [`sin_cos_2pi`] of eight lanes, each with the scalar function's bits.
#[inline(always)]
pub(crate) fn sin_cos_2pi8(u: F8) -> (F8, F8) {
    let ud = u.to_f64();
    let shift = D8::splat(ROUND_SHIFT);
    let t = ud.mul(D8::splat(4.0)).add(shift);
    let r = ud.sub(t.sub(shift).mul(D8::splat(0.25)));
    let z = r.mul(r);
    let s = r.mul(poly8(&SIN_2PI, z));
    let c = D8::splat(1.0).add(z.mul(poly8(&COS_2PI, z)));
    let (s, c) = D8::quarter_turns(t, s, c);
    (s.to_f32(), c.to_f32())
}

/// [`sin_cos_2pi`]'s polynomials: `sin 2πr = r·S(r²)`, `cos 2πr = 1 + r²·C(r²)`.
const SIN_2PI: [f64; 4] = [
    6.283185287812946,
    -41.34166257054795,
    81.59254287130155,
    -75.40161270274746,
];
const COS_2PI: [f64; 4] = [
    -19.739208789987508,
    64.93936905141977,
    -85.44882008965106,
    59.424105981756476,
];

/// `atan2(y, x)` in radians for f32, inline (the environment map's
/// longitude), with IEEE's signs: `(-π, π]`, `atan2(±0, +0) = ±0`,
/// `atan2(±0, -0) = ±π`.
///
/// Domain: finite `x`, `y` (NaN gives NaN; infinities are not handled).
/// Method: in f64, `a = min/max` of `|x|, |y|`, or `(min - max)/(min + max)`
/// and `π/4` added when `a > tan(π/8)`, so one division leaves `|r| ≤ tan(π/8)`;
/// `atan r = r·A(r²)` with a degree-5 `A` (Chebyshev fit, relative error
/// 6.2e-10); then the octant's reflections. Measured max error 0.51 ulp
/// against f64 `atan2` (see the tests).
#[inline]
pub fn atan2(y: f32, x: f32) -> f32 {
    let (ay, ax) = (y.abs() as f64, x.abs() as f64);
    // (Not min/max, which would drop a NaN.)
    let (lo, hi) = if ay > ax { (ax, ay) } else { (ay, ax) };
    let big = lo > TAN_PI_8 * hi;
    let (num, den, base) = if big {
        (lo - hi, lo + hi, std::f64::consts::FRAC_PI_4)
    } else {
        (lo, hi, 0.0)
    };
    // x = y = 0 (both ±0): r = 0, not 0/0.
    let r = num / if den == 0.0 { 1.0 } else { den };
    let z = r * r;
    const A: [f64; 6] = ATAN;
    let mut a = base + r * (A[0] + z * (A[1] + z * (A[2] + z * (A[3] + z * (A[4] + z * A[5])))));
    if ay > ax {
        a = std::f64::consts::FRAC_PI_2 - a;
    }
    if x.is_sign_negative() {
        a = std::f64::consts::PI - a;
    }
    (a as f32).copysign(y)
}

/// [`atan2`]'s polynomial: `atan r = r·A(r²)` for `|r| ≤ tan(π/8)`.
const ATAN: [f64; 6] = [
    0.9999999993712282,
    -0.33333306893048514,
    0.19998183041083206,
    -0.14239532669648974,
    0.10569828806414448,
    -0.06026305227658459,
];

/// Horner's scheme of `k` at `z` in eight lanes, in the scalar functions'
/// order: `k₀ + z·(k₁ + z·(… + z·k₅))`.
#[inline(always)]
fn poly8<const N: usize>(k: &[f64; N], z: D8) -> D8 {
    let mut p = D8::splat(k[N - 1]);
    for &c in k[..N - 1].iter().rev() {
        p = D8::splat(c).add(z.mul(p));
    }
    p
}

/// [`atan2`] of eight lanes, each with the scalar function's bits.
#[inline(always)]
pub(crate) fn atan2_8(y: F8, x: F8) -> F8 {
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};
    let (xd, yd) = (x.to_f64(), y.to_f64());
    let (ay, ax) = (yd.abs(), xd.abs());
    let swap = ay.gt(ax);
    let (lo, hi) = (swap.select(ax, ay), swap.select(ay, ax));
    let big = lo.gt(D8::splat(TAN_PI_8).mul(hi));
    let num = big.select(lo.sub(hi), lo);
    let den = big.select(lo.add(hi), hi);
    let base = big.select(D8::splat(FRAC_PI_4), D8::splat(0.0));
    let r = num.div(den.eq(D8::splat(0.0)).select(D8::splat(1.0), den));
    let a = base.add(r.mul(poly8(&ATAN, r.mul(r))));
    let a = swap.select(D8::splat(FRAC_PI_2).sub(a), a);
    let a = xd.sign_negative().select(D8::splat(PI).sub(a), a);
    a.to_f32().copysign(y)
}

/// `tan(π/8) = √2 - 1`, [`atan2`]'s split.
const TAN_PI_8: f64 = 0.414_213_562_373_095_05;

/// `acos x` in radians for f32, inline (the environment map's colatitude).
///
/// Domain: `[-1, 1]` (outside gives NaN, as NaN does); `acos 1 = 0`
/// exactly. Method: in f64, `acos x = π/2 - asin x` for `|x| ≤ ½`, and
/// `2 asin √((1-|x|)/2)` (reflected to `π - …` for `x < 0`) above, with
/// `asin s = s·B(s²)` on `s² ≤ ¼` by a degree-5 `B` (Chebyshev fit, relative
/// error 5.1e-9). Measured max error 0.58 ulp against f64 `acos` over
/// every 16th f32 in `[-1, 1]` (see the tests).
#[inline]
pub fn acos(x: f32) -> f32 {
    let xd = x as f64;
    let ax = xd.abs();
    let big = ax > 0.5;
    let w = if big { 0.5 - 0.5 * ax } else { xd * xd };
    let s = if big { w.sqrt() } else { ax };
    const B: [f64; 6] = ASIN;
    let asin_s = s * (B[0] + w * (B[1] + w * (B[2] + w * (B[3] + w * (B[4] + w * B[5])))));
    let a = if big {
        let a = 2.0 * asin_s;
        if xd < 0.0 {
            std::f64::consts::PI - a
        } else {
            a
        }
    } else {
        std::f64::consts::FRAC_PI_2 - asin_s.copysign(xd)
    };
    a as f32
}

/// [`acos`]'s polynomial: `asin s = s·B(s²)` for `s² ≤ ¼`.
const ASIN: [f64; 6] = [
    0.999999995983738,
    0.16666782005775338,
    0.07494696687423973,
    0.045520635631714566,
    0.02399399965364759,
    0.04241737375979984,
];

/// [`acos`] of eight lanes, each with the scalar function's bits.
#[inline(always)]
pub(crate) fn acos8(x: F8) -> F8 {
    use std::f64::consts::{FRAC_PI_2, PI};
    let xd = x.to_f64();
    let ax = xd.abs();
    let half = D8::splat(0.5);
    let big = ax.gt(half);
    let w = big.select(half.sub(half.mul(ax)), xd.mul(xd));
    let s = big.select(w.sqrt(), ax);
    let asin_s = s.mul(poly8(&ASIN, w));
    let a_big = D8::splat(2.0).mul(asin_s);
    let a_big = xd
        .lt(D8::splat(0.0))
        .select(D8::splat(PI).sub(a_big), a_big);
    let a_small = D8::splat(FRAC_PI_2).sub(asin_s.copysign(xd));
    big.select(a_big, a_small).to_f32()
}

/// `(m · v).normalize()` of eight vectors `v` (x, y, z), as glam computes
/// it for a `Vec3A`: the columns of `m` scaled and summed in order, then
/// divided by the square root of `(x² + y²) + z²`.
#[inline(always)]
pub(crate) fn mul_normalize8(m: Mat3, v: [F8; 3]) -> [F8; 3] {
    let m = m.to_cols_array_2d();
    let w: [F8; 3] = std::array::from_fn(|r| {
        let c = |k: usize| F8::splat(m[k][r]).mul(v[k]);
        c(0).add(c(1)).add(c(2))
    });
    let len = w[0]
        .mul(w[0])
        .add(w[1].mul(w[1]))
        .add(w[2].mul(w[2]))
        .sqrt();
    w.map(|x| x.div(len))
}

#[cfg(test)]
mod tests {
    /// Error of an f32 result against an f64 reference, in units in the last
    /// place of the f32 binade holding the reference: `|got - exact| / ulp`
    /// (a correctly rounded result scores ≤ ½; 0 when `got` is the reference
    /// rounded, ±0 and overflow to ∞ included; subnormals count in the
    /// subnormal ulp).
    fn ulp_err(got: f32, exact: f64) -> f64 {
        let r = exact as f32;
        if got as f64 == exact || got == r {
            return 0.0;
        }
        if !r.is_finite() || !got.is_finite() {
            return f64::INFINITY;
        }
        let a = r.abs();
        let ulp = if a < f32::MIN_POSITIVE {
            f32::from_bits(1) as f64
        } else {
            // ulp of the binade holding |exact| (the lower one at a power of 2)
            let e = f32::from_bits(a.to_bits() & 0x7f80_0000) as f64;
            e * f32::EPSILON as f64
        };
        (got as f64 - exact).abs() / ulp
    }

    /// f32 values from `lo` to `hi` (same sign), every `step`-th bit pattern,
    /// plus both ends.
    fn sweep(lo: f32, hi: f32, step: u32) -> impl Iterator<Item = f32> {
        let (a, b) = (
            lo.to_bits().min(hi.to_bits()),
            lo.to_bits().max(hi.to_bits()),
        );
        (a..=b)
            .step_by(step as usize)
            .chain([a, b])
            .map(f32::from_bits)
    }

    /// The largest of `err` over `args`: printed, and asserted to be at
    /// most one ulp (the inline functions' documented bound is lower).
    fn assert_within_one_ulp<T: std::fmt::Debug + Copy>(
        name: &str,
        args: impl IntoIterator<Item = T>,
        err: impl Fn(T) -> f64,
    ) {
        let mut worst: Option<(f64, T)> = None;
        for a in args {
            let e = err(a);
            if worst.is_none_or(|(w, _)| e > w) {
                worst = Some((e, a));
            }
        }
        let (e, a) = worst.expect("no arguments");
        eprintln!("{name}: max {e} ulp at {a:?}");
        assert!(e <= 1.0, "{name}: {e} ulp at {a:?}");
    }

    #[test]
    fn exp_is_within_one_ulp() {
        assert_within_one_ulp(
            "exp",
            sweep(-0.0, -104.0, 64).chain(sweep(0.0, 89.0, 64)),
            |x| ulp_err(exp(x), (x as f64).exp()),
        );
        assert_eq!(exp(0.0), 1.0);
        assert_eq!(exp(-0.0), 1.0);
        assert_eq!(exp(-104.0), 0.0);
        assert_eq!(exp(-1e30), 0.0);
        assert_eq!(exp(f32::NEG_INFINITY), 0.0);
        assert_eq!(exp(89.0), f32::INFINITY);
        assert_eq!(exp(f32::INFINITY), f32::INFINITY);
        assert!(exp(f32::NAN).is_nan());
        assert!(exp(-103.9) > 0.0 && exp(88.7) < f32::INFINITY);
        // The smallest argument: tiny denormal of x.
        assert_eq!(exp(-f32::from_bits(1)), 1.0);
    }

    #[test]
    fn ln_is_within_one_ulp() {
        // All positive binades, and the free-flight domain (0, 1] densely:
        // every 1 - u of a 24-bit u.
        let dense = (0..(1u32 << 24)).map(|i| 1.0 - i as f32 * (1.0 / (1u32 << 24) as f32));
        assert_within_one_ulp(
            "ln",
            sweep(f32::from_bits(1), f32::MAX, 64).chain(dense),
            |x| ulp_err(ln(x), (x as f64).ln()),
        );
        assert_eq!(ln(1.0), 0.0);
        assert_eq!(ln(0.0), f32::NEG_INFINITY);
        assert_eq!(ln(-0.0), f32::NEG_INFINITY);
        assert_eq!(ln(f32::INFINITY), f32::INFINITY);
        assert!(ln(-1.0).is_nan() && ln(f32::NAN).is_nan() && ln(f32::NEG_INFINITY).is_nan());
        assert_eq!(
            ln(f32::from_bits(1)),
            (f32::from_bits(1) as f64).ln() as f32
        );
        assert_eq!(ln(2.0), std::f32::consts::LN_2);
    }

    #[test]
    fn lanes_are_the_scalar_functions() {
        use crate::lanes::F8;
        let mut s = Sampler::new(9, 1, 2);
        let special = [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            0.414_213_57,
            f32::NAN,
            1e-30,
            -3e-39,
            0.999_999_94,
            -0.707_106_77,
        ];
        let bits = |x: [f32; 8]| x.map(f32::to_bits);
        for round in 0..20_000 {
            let mut pick = || -> [f32; 8] {
                std::array::from_fn(|_| {
                    let r = s.next_1d();
                    match round % 3 {
                        0 => special[(r * 12.0) as usize % 12],
                        1 => r * 2.0 - 1.0,
                        _ => (r - 0.5) * 40.0,
                    }
                })
            };
            let (a, b) = (pick(), pick());
            let (sin, cos) = sin_cos_2pi8(F8::from_array(a));
            let (at, ac) = (
                atan2_8(F8::from_array(a), F8::from_array(b)).to_array(),
                acos8(F8::from_array(a)).to_array(),
            );
            let scalar_sc = a.map(sin_cos_2pi);
            assert_eq!(
                bits(sin.to_array()),
                bits(scalar_sc.map(|x| x.0)),
                "sin {a:?}"
            );
            assert_eq!(
                bits(cos.to_array()),
                bits(scalar_sc.map(|x| x.1)),
                "cos {a:?}"
            );
            let scalar_at: [f32; 8] = std::array::from_fn(|l| atan2(a[l], b[l]));
            assert_eq!(bits(at), bits(scalar_at), "atan2 {a:?} {b:?}");
            assert_eq!(bits(ac), bits(a.map(acos)), "acos {a:?}");
        }
    }

    #[test]
    fn sin_cos_2pi_is_within_one_ulp() {
        // Reference: the exact quarter-turn reduction, then f64 sin/cos of
        // the small remainder (f64 sin(2πu) itself is off by 1e-16 at
        // u = ½, where the answer is 0).
        let reference = |u: f32| {
            let q = (u as f64 * 4.0).round();
            let x = (u as f64 - q * 0.25) * std::f64::consts::TAU;
            let (s, c) = x.sin_cos();
            match q as i64 & 3 {
                0 => (s, c),
                1 => (c, -s),
                2 => (-s, -c),
                _ => (-c, s),
            }
        };
        // A sweep of both signs, and every 24-bit variate u ∈ [0, 1) of the
        // sampler.
        let variates = (0..(1u32 << 24)).map(|i| i as f32 * (1.0 / (1u32 << 24) as f32));
        assert_within_one_ulp(
            "sin_cos_2pi",
            sweep(0.0, 1.0, 64)
                .chain(sweep(-0.0, -1.0, 1024))
                .chain(variates),
            |u| {
                let (s, c) = sin_cos_2pi(u);
                let (rs, rc) = reference(u);
                ulp_err(s, rs).max(ulp_err(c, rc))
            },
        );
        assert_eq!(sin_cos_2pi(0.0), (0.0, 1.0));
        assert_eq!(sin_cos_2pi(0.25), (1.0, 0.0));
        assert_eq!(sin_cos_2pi(0.5).1, -1.0);
        assert_eq!(sin_cos_2pi(0.5).0, 0.0);
        assert_eq!(sin_cos_2pi(0.75), (-1.0, 0.0));
        assert_eq!(sin_cos_2pi(1.0).1, 1.0);
        let tiny = f32::from_bits(1);
        assert_eq!(
            sin_cos_2pi(tiny),
            ((tiny as f64 * std::f64::consts::TAU) as f32, 1.0)
        );
    }

    use super::*;

    /// Each lane of the disk map gives the scalar map's bits, on its
    /// centre, axes and diagonals as well as elsewhere.
    #[test]
    fn concentric_disk8_is_concentric_disk() {
        let mut rng = Pcg32::new(31, 7);
        let special = [0.0, 0.25, 0.5, 0.75, 1.0 - f32::EPSILON / 2.0];
        for _ in 0..20_000 {
            let mut u = || {
                let x = rng.next_u32();
                if x % 3 == 0 {
                    special[(x >> 8) as usize % special.len()]
                } else {
                    (x >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
                }
            };
            let u: [[f32; 2]; 8] = std::array::from_fn(|_| [u(), u()]);
            let d = sample_concentric_disk8([
                F8::from_array(u.map(|u| u[0])),
                F8::from_array(u.map(|u| u[1])),
            ])
            .map(F8::to_array);
            for l in 0..8 {
                let s = sample_concentric_disk(u[l]);
                assert_eq!(
                    [d[0][l].to_bits(), d[1][l].to_bits()],
                    s.map(f32::to_bits),
                    "u {:?}",
                    u[l]
                );
                assert!(
                    s[0] * s[0] + s[1] * s[1] <= 1.0 + 1e-6,
                    "u {:?}: {s:?}",
                    u[l]
                );
            }
        }
    }

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

    #[test]
    fn atan2_is_within_one_ulp() {
        let xs = [
            1.0f32,
            0.3,
            1e-3,
            7.0,
            1e3,
            1e-20,
            0.0,
            std::f32::consts::FRAC_1_SQRT_2,
            2.4142137,
            0.41421357,
        ];
        let ys = sweep(1e-30, 1e4, 2048).chain([0.0, 1.0, 0.41421356, 0.41421357, 1e-45]);
        let pairs = ys.flat_map(|y| {
            xs.iter()
                .flat_map(move |&x| [(y, x), (-y, x), (y, -x), (-y, -x), (x, y), (-x, -y)])
        });
        assert_within_one_ulp("atan2", pairs, |(y, x)| {
            ulp_err(atan2(y, x), (y as f64).atan2(x as f64))
        });
        let pi = std::f32::consts::PI;
        assert_eq!(atan2(0.0, 1.0).to_bits(), 0f32.to_bits());
        assert_eq!(atan2(-0.0, 1.0).to_bits(), (-0f32).to_bits());
        assert_eq!(atan2(0.0, 0.0).to_bits(), 0f32.to_bits());
        assert_eq!(atan2(0.0, -0.0), pi);
        assert_eq!(atan2(-0.0, -0.0), -pi);
        assert_eq!(atan2(0.0, -1.0), pi);
        assert_eq!(atan2(1.0, 0.0), std::f32::consts::FRAC_PI_2);
        assert_eq!(atan2(1.0, 1.0), std::f32::consts::FRAC_PI_4);
        assert!(atan2(f32::NAN, 1.0).is_nan() && atan2(1.0, f32::NAN).is_nan());
    }

    #[test]
    fn acos_is_within_one_ulp() {
        assert_within_one_ulp(
            "acos",
            sweep(0.0, 1.0, 16).chain(sweep(-0.0, -1.0, 16)),
            |x| ulp_err(acos(x), (x as f64).acos()),
        );
        assert_eq!(acos(1.0), 0.0);
        assert_eq!(acos(-1.0), std::f32::consts::PI);
        assert_eq!(acos(0.0), std::f32::consts::FRAC_PI_2);
        assert_eq!(acos(-0.0), std::f32::consts::FRAC_PI_2);
        assert_eq!(acos(0.5), (0.5f64.acos()) as f32);
        assert!(acos(1.0 + f32::EPSILON).is_nan() && acos(f32::NAN).is_nan());
    }
}
