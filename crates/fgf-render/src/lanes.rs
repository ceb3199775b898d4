//! Eight lanes per instruction: `F8` (`f32`), `I8` (`i32`, also used as
//! unsigned indices), `D8` (`f64`, two registers) and the lane masks `M8`
//! (of `F8` and `I8`) and `MD8` (of `D8`).
//! The BVH's 8-wide nodes and leaf packs use `F8`; the kernels that shade
//! eight paths at once (the environment map's sampler, see
//! [`crate::emitter::envmap`]) use all four.
//!
//! Where the build enables AVX2 (the default native build) each operation
//! is one AVX2 instruction (two for `D8`, kept apart where the build also
//! has AVX-512, see `apart_pd`); elsewhere (the portable wheel,
//! other architectures) the same operations are written out lane by lane.
//! Both give the same bits in every lane, including the rules of x86 that
//! the callers rely on, which the portable code follows:
//!
//! * `min`/`max`: if either operand is NaN, the second one (`minps`/`maxps`);
//! * `F8::trunc`: toward zero, and `i32::MIN` for NaN and out-of-range lanes
//!   (`cvttps2dq`);
//! * comparisons are false for NaN (ordered, quiet).
//!
//! Every operation is exact IEEE arithmetic on each lane, with no fused
//! multiply–add, so a kernel written with these types gives each lane the
//! bits of the scalar code that performs the same operations in the same
//! order. The one exception, `F8::mul_sub_bound`, is fused where the build
//! has FMA and is only for bounds proven either way (the tree's node test).
//! Gathers clamp their indices to the table, so they read no memory
//! outside it whatever the indices.
//!
//! The AVX2 intrinsics are `unsafe` to call even when the build enables
//! AVX2 (Rust asks the calling function to enable it itself, which
//! `#[inline(always)]` functions cannot); that module is compiled only
//! when it does.

#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
pub(crate) use avx::{D8, F8, I8, M8};
#[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
pub(crate) use portable::{D8, F8, I8, M8};

/// Ask the CPU to start loading the cache lines of `*r` (its first and
/// last byte: a value of up to 64 bytes may straddle two lines), without
/// waiting for them. A hint: it changes no value, and does nothing off
/// x86-64.
#[inline(always)]
pub(crate) fn prefetch<T>(r: &T) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let p = (r as *const T).cast::<i8>();
        // SAFETY: a prefetch reads nothing into the program and never
        // faults; the pointers are within (or one before the end of) `*r`.
        unsafe {
            _mm_prefetch::<_MM_HINT_T0>(p);
            _mm_prefetch::<_MM_HINT_T0>(p.add(std::mem::size_of::<T>().saturating_sub(1)));
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = r;
}

/// The largest index a gather accepts for a table of `len` entries:
/// `len - 1`, which must fit an `i32` (the gathers' signed offsets).
#[inline(always)]
fn last_index(len: usize) -> i32 {
    assert!(
        len > 0 && len <= i32::MAX as usize,
        "gather from a table of {len} entries"
    );
    (len - 1) as i32
}

#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
mod avx {
    // SAFETY (every `unsafe` block below): the intrinsics need AVX2, which
    // this module is only compiled with (`cfg(target_feature = "avx2")`).
    // The gathers read `table[i]` only for indices clamped to
    // `0..=last_index(table.len())`; nothing else touches memory but
    // stores into local arrays of the right size.
    use super::last_index;
    use std::arch::x86_64::*;

    #[derive(Clone, Copy, Debug)]
    #[repr(transparent)]
    pub(crate) struct F8(__m256);

    /// A lane mask (all bits set or clear per 32-bit lane).
    #[derive(Clone, Copy, Debug)]
    #[repr(transparent)]
    pub(crate) struct M8(__m256);

    #[derive(Clone, Copy, Debug)]
    #[repr(transparent)]
    pub(crate) struct I8(__m256i);

    /// Eight `f64` lanes: lanes 0–3 in the first register, 4–7 in the second.
    #[derive(Clone, Copy, Debug)]
    pub(crate) struct D8([__m256d; 2]);

    impl F8 {
        #[inline(always)]
        pub fn splat(x: f32) -> F8 {
            F8(unsafe { _mm256_set1_ps(x) })
        }
        #[inline(always)]
        pub fn from_array(a: [f32; 8]) -> F8 {
            F8(unsafe { _mm256_loadu_ps(a.as_ptr()) })
        }
        #[inline(always)]
        pub fn to_array(self) -> [f32; 8] {
            let mut a = [0f32; 8];
            unsafe { _mm256_storeu_ps(a.as_mut_ptr(), self.0) };
            a
        }
        /// `self - b` lane by lane.
        #[inline(always)]
        pub fn sub(self, b: F8) -> F8 {
            F8(unsafe { _mm256_sub_ps(self.0, b.0) })
        }
        #[inline(always)]
        pub fn mul(self, b: F8) -> F8 {
            F8(unsafe { _mm256_mul_ps(self.0, b.0) })
        }
        /// `self * b - c`, rounded once where the build has FMA, else
        /// twice. Only for bounds whose proof allows either (the tree's
        /// slab test), never where a lane must have the scalar code's bits.
        #[inline(always)]
        pub fn mul_sub_bound(self, b: F8, c: F8) -> F8 {
            #[cfg(target_feature = "fma")]
            return F8(unsafe { _mm256_fmsub_ps(self.0, b.0, c.0) });
            #[cfg(not(target_feature = "fma"))]
            return self.mul(b).sub(c);
        }
        /// Lane minimum; `b` if either is NaN.
        #[inline(always)]
        pub fn min(self, b: F8) -> F8 {
            F8(unsafe { _mm256_min_ps(self.0, b.0) })
        }
        /// Lane maximum; `b` if either is NaN.
        #[inline(always)]
        pub fn max(self, b: F8) -> F8 {
            F8(unsafe { _mm256_max_ps(self.0, b.0) })
        }
        /// The least lane (of lanes without NaN).
        #[inline(always)]
        pub fn hmin(self) -> f32 {
            unsafe {
                let m = _mm_min_ps(
                    _mm256_castps256_ps128(self.0),
                    _mm256_extractf128_ps::<1>(self.0),
                );
                let m = _mm_min_ps(m, _mm_movehl_ps(m, m));
                _mm_cvtss_f32(_mm_min_ss(m, _mm_shuffle_ps::<1>(m, m)))
            }
        }
        #[inline(always)]
        pub fn add(self, b: F8) -> F8 {
            F8(unsafe { _mm256_add_ps(self.0, b.0) })
        }
        #[inline(always)]
        pub fn div(self, b: F8) -> F8 {
            F8(unsafe { _mm256_div_ps(self.0, b.0) })
        }
        #[inline(always)]
        pub fn sqrt(self) -> F8 {
            F8(unsafe { _mm256_sqrt_ps(self.0) })
        }
        /// The lanes where `self <= b` (false for NaN).
        #[inline(always)]
        pub fn le(self, b: F8) -> M8 {
            M8(unsafe { _mm256_cmp_ps::<_CMP_LE_OQ>(self.0, b.0) })
        }
        /// The lanes where `self < b` (false for NaN).
        #[inline(always)]
        pub fn lt(self, b: F8) -> M8 {
            M8(unsafe { _mm256_cmp_ps::<_CMP_LT_OQ>(self.0, b.0) })
        }
        /// `-self` (the sign bit flipped).
        #[inline(always)]
        pub fn neg(self) -> F8 {
            F8(unsafe { _mm256_xor_ps(self.0, _mm256_set1_ps(-0.0)) })
        }
        /// The lanes whose sign bit is set (`-0.0` and negative NaNs
        /// included).
        #[inline(always)]
        pub fn sign_mask(self) -> M8 {
            M8(
                unsafe {
                    _mm256_castsi256_ps(_mm256_srai_epi32::<31>(_mm256_castps_si256(self.0)))
                },
            )
        }
        /// `self` with the sign of `sign`.
        #[inline(always)]
        pub fn copysign(self, sign: F8) -> F8 {
            unsafe {
                let m = _mm256_set1_ps(-0.0);
                F8(_mm256_or_ps(
                    _mm256_andnot_ps(m, self.0),
                    _mm256_and_ps(m, sign.0),
                ))
            }
        }
        #[inline(always)]
        pub fn floor(self) -> F8 {
            F8(unsafe { _mm256_floor_ps(self.0) })
        }
        /// Toward zero; `i32::MIN` for NaN and lanes outside the `i32` range.
        #[inline(always)]
        pub fn trunc(self) -> I8 {
            I8(unsafe { _mm256_cvttps_epi32(self.0) })
        }
        /// Each lane widened to `f64` (exact).
        #[inline(always)]
        pub fn to_f64(self) -> D8 {
            unsafe {
                D8([
                    apart_pd(_mm256_cvtps_pd(_mm256_castps256_ps128(self.0))),
                    apart_pd(_mm256_cvtps_pd(_mm256_extractf128_ps::<1>(self.0))),
                ])
            }
        }
        /// `table[i]` in each lane, `i` clamped to the table.
        #[inline(always)]
        pub fn gather(table: &[f32], i: I8) -> F8 {
            let i = i.clamp_index(last_index(table.len()));
            F8(unsafe { _mm256_i32gather_ps::<4>(table.as_ptr(), i.0) })
        }
    }

    impl M8 {
        #[inline(always)]
        pub fn and(self, b: M8) -> M8 {
            M8(unsafe { _mm256_and_ps(self.0, b.0) })
        }
        /// Bit `i` set where lane `i` holds.
        #[inline(always)]
        pub fn bitmask(self) -> u32 {
            (unsafe { _mm256_movemask_ps(self.0) }) as u32
        }
        /// `a` where the mask holds, else `b`.
        #[inline(always)]
        pub fn select(self, a: F8, b: F8) -> F8 {
            F8(unsafe { _mm256_blendv_ps(b.0, a.0, self.0) })
        }
        /// [`Self::select`] of integer lanes.
        #[inline(always)]
        pub fn select_i8(self, a: I8, b: I8) -> I8 {
            I8(unsafe { _mm256_blendv_epi8(b.0, a.0, _mm256_castps_si256(self.0)) })
        }
    }

    impl I8 {
        #[inline(always)]
        pub fn splat(x: i32) -> I8 {
            I8(unsafe { _mm256_set1_epi32(x) })
        }
        #[cfg(test)]
        pub fn to_array(self) -> [i32; 8] {
            let mut a = [0i32; 8];
            unsafe { _mm256_storeu_si256(a.as_mut_ptr().cast(), self.0) };
            a
        }
        #[cfg(test)]
        pub fn from_array(a: [i32; 8]) -> I8 {
            I8(unsafe { _mm256_loadu_si256(a.as_ptr().cast()) })
        }
        /// Wrapping.
        #[inline(always)]
        pub fn add(self, b: I8) -> I8 {
            I8(unsafe { _mm256_add_epi32(self.0, b.0) })
        }
        /// Wrapping (the low 32 bits of the product).
        #[inline(always)]
        pub fn mul(self, b: I8) -> I8 {
            I8(unsafe { _mm256_mullo_epi32(self.0, b.0) })
        }
        #[inline(always)]
        pub fn max(self, b: I8) -> I8 {
            I8(unsafe { _mm256_max_epi32(self.0, b.0) })
        }
        #[inline(always)]
        pub fn min(self, b: I8) -> I8 {
            I8(unsafe { _mm256_min_epi32(self.0, b.0) })
        }
        /// Each lane as `f32` (rounded to nearest).
        #[inline(always)]
        pub fn to_f32(self) -> F8 {
            F8(unsafe { _mm256_cvtepi32_ps(self.0) })
        }
        /// Each lane clamped to `0..=last`, as unsigned: a negative lane is
        /// above `last`.
        #[inline(always)]
        fn clamp_index(self, last: i32) -> I8 {
            I8(unsafe { _mm256_min_epu32(self.0, _mm256_set1_epi32(last)) })
        }
        /// `table[i]` in each lane (its bits), `i` clamped to the table.
        #[inline(always)]
        pub fn gather(table: &[u32], i: I8) -> I8 {
            let i = i.clamp_index(last_index(table.len()));
            I8(unsafe { _mm256_i32gather_epi32::<4>(table.as_ptr().cast(), i.0) })
        }
        /// The lanes' bits as `f32`.
        #[inline(always)]
        pub fn to_bits_f32(self) -> F8 {
            F8(unsafe { _mm256_castsi256_ps(self.0) })
        }
    }

    /// `x`, which the compiler may not join with the other half of a
    /// [`D8`] into one 512-bit operation. Where the build has AVX-512, LLVM
    /// would otherwise fuse a `D8`'s two halves, and the whole chain of
    /// `f64` arithmetic before or after them, into 512-bit instructions
    /// (the environment map's `atan2`, `acos` and the conductors' Fresnel
    /// terms). On an Intel Xeon the mesh render then took 8 % longer, spread
    /// over every part of it, the tree walks included: most likely the core's
    /// clock lowered for 512-bit floating-point work (docs/benchmarks.md,
    /// "What AVX-512 gives Mitsuba on an Intel Xeon"). On a Zen 5 the fused
    /// kernels were no faster (docs/benchmarks.md, "A Zen 5 EPYC"), so the
    /// barrier holds on every CPU. An empty `asm!` block is the barrier: it
    /// emits no instruction and changes no bit.
    #[inline(always)]
    fn apart_pd(x: __m256d) -> __m256d {
        #[cfg(target_feature = "avx512f")]
        {
            let mut x = x;
            // SAFETY: the block is empty; it only keeps `x` in a 256-bit register.
            unsafe {
                std::arch::asm!("/* {0} */", inout(ymm_reg) x, options(pure, nomem, nostack))
            };
            x
        }
        #[cfg(not(target_feature = "avx512f"))]
        x
    }

    /// [`apart_pd`] for the `f32` half of a [`D8`] narrowed to `f32`.
    #[inline(always)]
    fn apart_ps(x: __m128) -> __m128 {
        #[cfg(target_feature = "avx512f")]
        {
            let mut x = x;
            // SAFETY: the block is empty; it only keeps `x` in a 128-bit register.
            unsafe {
                std::arch::asm!("/* {0} */", inout(xmm_reg) x, options(pure, nomem, nostack))
            };
            x
        }
        #[cfg(not(target_feature = "avx512f"))]
        x
    }

    /// A mask of `D8` lanes (all bits set or clear per 64-bit lane).
    #[derive(Clone, Copy, Debug)]
    pub(crate) struct MD8([__m256d; 2]);

    impl MD8 {
        /// `a` where the mask holds, else `b`.
        #[inline(always)]
        pub fn select(self, a: D8, b: D8) -> D8 {
            unsafe {
                D8([
                    _mm256_blendv_pd(b.0[0], a.0[0], self.0[0]),
                    _mm256_blendv_pd(b.0[1], a.0[1], self.0[1]),
                ])
            }
        }
        /// Bit `i` set where lane `i` holds.
        #[cfg(test)]
        pub fn bitmask(self) -> u32 {
            unsafe { (_mm256_movemask_pd(self.0[0]) | _mm256_movemask_pd(self.0[1]) << 4) as u32 }
        }
    }

    impl D8 {
        #[inline(always)]
        pub fn splat(x: f64) -> D8 {
            D8([unsafe { _mm256_set1_pd(x) }; 2])
        }
        #[inline(always)]
        fn zip(self, b: D8, f: impl Fn(__m256d, __m256d) -> __m256d) -> D8 {
            D8([f(self.0[0], b.0[0]), f(self.0[1], b.0[1])])
        }
        #[inline(always)]
        pub fn add(self, b: D8) -> D8 {
            self.zip(b, |x, y| unsafe { _mm256_add_pd(x, y) })
        }
        #[inline(always)]
        pub fn sub(self, b: D8) -> D8 {
            self.zip(b, |x, y| unsafe { _mm256_sub_pd(x, y) })
        }
        #[inline(always)]
        pub fn mul(self, b: D8) -> D8 {
            self.zip(b, |x, y| unsafe { _mm256_mul_pd(x, y) })
        }
        #[inline(always)]
        pub fn div(self, b: D8) -> D8 {
            self.zip(b, |x, y| unsafe { _mm256_div_pd(x, y) })
        }
        #[inline(always)]
        pub fn sqrt(self) -> D8 {
            let s = |x| unsafe { _mm256_sqrt_pd(x) };
            D8([s(self.0[0]), s(self.0[1])])
        }
        /// `|self|` (the sign bit cleared).
        #[inline(always)]
        pub fn abs(self) -> D8 {
            let a = |x| unsafe { _mm256_andnot_pd(_mm256_set1_pd(-0.0), x) };
            D8([a(self.0[0]), a(self.0[1])])
        }
        /// `self` with the sign of `sign`.
        #[inline(always)]
        pub fn copysign(self, sign: D8) -> D8 {
            self.zip(sign, |x, y| unsafe {
                let m = _mm256_set1_pd(-0.0);
                _mm256_or_pd(_mm256_andnot_pd(m, x), _mm256_and_pd(m, y))
            })
        }
        #[inline(always)]
        fn cmp<const C: i32>(self, b: D8) -> MD8 {
            unsafe {
                MD8([
                    _mm256_cmp_pd::<C>(self.0[0], b.0[0]),
                    _mm256_cmp_pd::<C>(self.0[1], b.0[1]),
                ])
            }
        }
        /// The lanes where `self > b` (false for NaN).
        #[inline(always)]
        pub fn gt(self, b: D8) -> MD8 {
            self.cmp::<_CMP_GT_OQ>(b)
        }
        /// The lanes where `self < b` (false for NaN).
        #[inline(always)]
        pub fn lt(self, b: D8) -> MD8 {
            self.cmp::<_CMP_LT_OQ>(b)
        }
        /// The lanes where `self == b` (false for NaN).
        #[inline(always)]
        pub fn eq(self, b: D8) -> MD8 {
            self.cmp::<_CMP_EQ_OQ>(b)
        }
        /// The lanes with the sign bit set.
        #[inline(always)]
        pub fn sign_negative(self) -> MD8 {
            // The sign bit is the blend's selector: lanes of -0.0 and negative NaNs too.
            let s = |x| unsafe {
                _mm256_blendv_pd(
                    _mm256_setzero_pd(),
                    _mm256_castsi256_pd(_mm256_set1_epi64x(-1)),
                    x,
                )
            };
            MD8([s(self.0[0]), s(self.0[1])])
        }
        /// Each lane narrowed to `f32` (rounded to nearest).
        #[inline(always)]
        pub fn to_f32(self) -> F8 {
            unsafe {
                let (lo, hi) = (
                    apart_ps(_mm256_cvtpd_ps(self.0[0])),
                    apart_ps(_mm256_cvtpd_ps(self.0[1])),
                );
                F8(_mm256_insertf128_ps::<1>(_mm256_castps128_ps256(lo), hi))
            }
        }
        /// The quarter turns of [`crate::math::sin_cos_2pi`]: with `q` the
        /// bits of `turns` (an integer held in its low bits), `(s, c)`
        /// swapped where `q` is odd, then the sine negated where `q & 2`
        /// and the cosine where `(q + 1) & 2`.
        #[inline(always)]
        pub fn quarter_turns(turns: D8, s: D8, c: D8) -> (D8, D8) {
            let mut out = (s, c);
            for h in 0..2 {
                unsafe {
                    let q = _mm256_castpd_si256(turns.0[h]);
                    let one = _mm256_set1_epi64x(1);
                    let two = _mm256_set1_epi64x(2);
                    let odd =
                        _mm256_castsi256_pd(_mm256_cmpeq_epi64(_mm256_and_si256(q, one), one));
                    let (s, c) = (
                        _mm256_blendv_pd(s.0[h], c.0[h], odd),
                        _mm256_blendv_pd(c.0[h], s.0[h], odd),
                    );
                    let sign_s = _mm256_slli_epi64::<62>(_mm256_and_si256(q, two));
                    let sign_c =
                        _mm256_slli_epi64::<62>(_mm256_and_si256(_mm256_add_epi64(q, one), two));
                    out.0 .0[h] = _mm256_xor_pd(s, _mm256_castsi256_pd(sign_s));
                    out.1 .0[h] = _mm256_xor_pd(c, _mm256_castsi256_pd(sign_c));
                }
            }
            out
        }
    }
}

/// The lanes written out (always compiled, so that the tests can compare
/// them with the AVX2 ones). `F8` and `M8` hold SSE vectors (glam's) on
/// x86-64, so that the BVH of the portable wheel still tests four boxes
/// per instruction.
#[cfg_attr(all(target_arch = "x86_64", target_feature = "avx2"), allow(dead_code))]
mod portable {
    use super::last_index;
    use glam::{BVec4A, Vec4};

    #[derive(Clone, Copy, Debug)]
    pub(crate) struct F8([Vec4; 2]);

    /// A lane mask, the result of a comparison.
    #[derive(Clone, Copy, Debug)]
    pub(crate) struct M8([BVec4A; 2]);

    #[derive(Clone, Copy, Debug)]
    pub(crate) struct I8([i32; 8]);

    #[derive(Clone, Copy, Debug)]
    pub(crate) struct D8([f64; 8]);

    impl M8 {
        #[inline(always)]
        pub fn and(self, b: M8) -> M8 {
            M8([self.0[0] & b.0[0], self.0[1] & b.0[1]])
        }
        #[inline(always)]
        pub fn bitmask(self) -> u32 {
            self.0[0].bitmask() | self.0[1].bitmask() << 4
        }
        #[inline(always)]
        fn lane(self, l: usize) -> bool {
            self.bitmask() >> l & 1 == 1
        }
        #[inline(always)]
        fn from_fn(f: impl Fn(usize) -> bool) -> M8 {
            M8([
                BVec4A::new(f(0), f(1), f(2), f(3)),
                BVec4A::new(f(4), f(5), f(6), f(7)),
            ])
        }
        #[inline(always)]
        pub fn select(self, a: F8, b: F8) -> F8 {
            F8([
                Vec4::select(self.0[0], a.0[0], b.0[0]),
                Vec4::select(self.0[1], a.0[1], b.0[1]),
            ])
        }
        #[inline(always)]
        pub fn select_i8(self, a: I8, b: I8) -> I8 {
            I8(std::array::from_fn(|l| {
                if self.lane(l) {
                    a.0[l]
                } else {
                    b.0[l]
                }
            }))
        }
    }

    impl F8 {
        #[inline(always)]
        pub fn splat(x: f32) -> F8 {
            F8([Vec4::splat(x); 2])
        }
        #[inline(always)]
        pub fn from_array(a: [f32; 8]) -> F8 {
            F8([
                Vec4::new(a[0], a[1], a[2], a[3]),
                Vec4::new(a[4], a[5], a[6], a[7]),
            ])
        }
        #[inline(always)]
        pub fn to_array(self) -> [f32; 8] {
            let (lo, hi) = (self.0[0].to_array(), self.0[1].to_array());
            [lo[0], lo[1], lo[2], lo[3], hi[0], hi[1], hi[2], hi[3]]
        }
        #[inline(always)]
        pub fn sub(self, b: F8) -> F8 {
            F8([self.0[0] - b.0[0], self.0[1] - b.0[1]])
        }
        #[inline(always)]
        pub fn mul(self, b: F8) -> F8 {
            F8([self.0[0] * b.0[0], self.0[1] * b.0[1]])
        }
        /// `self * b - c`, rounded twice (see the AVX2 version).
        #[inline(always)]
        pub fn mul_sub_bound(self, b: F8, c: F8) -> F8 {
            self.mul(b).sub(c)
        }
        /// Lane minimum; `b` if either is NaN: `minps` (glam's SSE `min`) on
        /// x86-64, written out elsewhere (NEON's `min` returns the NaN).
        #[inline(always)]
        pub fn min(self, b: F8) -> F8 {
            #[cfg(target_arch = "x86_64")]
            let m = |x: Vec4, y: Vec4| x.min(y);
            #[cfg(not(target_arch = "x86_64"))]
            let m = |x: Vec4, y: Vec4| Vec4::select(x.cmplt(y), x, y);
            F8([m(self.0[0], b.0[0]), m(self.0[1], b.0[1])])
        }
        /// Lane maximum; `b` if either is NaN (`maxps` on x86-64).
        #[inline(always)]
        pub fn max(self, b: F8) -> F8 {
            #[cfg(target_arch = "x86_64")]
            let m = |x: Vec4, y: Vec4| x.max(y);
            #[cfg(not(target_arch = "x86_64"))]
            let m = |x: Vec4, y: Vec4| Vec4::select(x.cmpgt(y), x, y);
            F8([m(self.0[0], b.0[0]), m(self.0[1], b.0[1])])
        }
        /// The least lane (of lanes without NaN).
        #[inline(always)]
        pub fn hmin(self) -> f32 {
            self.min(F8([self.0[1], self.0[0]])).0[0].min_element()
        }
        #[inline(always)]
        pub fn add(self, b: F8) -> F8 {
            F8([self.0[0] + b.0[0], self.0[1] + b.0[1]])
        }
        #[inline(always)]
        pub fn div(self, b: F8) -> F8 {
            F8([self.0[0] / b.0[0], self.0[1] / b.0[1]])
        }
        #[inline(always)]
        pub fn sqrt(self) -> F8 {
            F8::from_array(self.to_array().map(f32::sqrt))
        }
        #[inline(always)]
        pub fn le(self, b: F8) -> M8 {
            M8([self.0[0].cmple(b.0[0]), self.0[1].cmple(b.0[1])])
        }
        #[inline(always)]
        pub fn lt(self, b: F8) -> M8 {
            M8([self.0[0].cmplt(b.0[0]), self.0[1].cmplt(b.0[1])])
        }
        #[inline(always)]
        pub fn neg(self) -> F8 {
            F8::from_array(self.to_array().map(|x| -x))
        }
        #[inline(always)]
        pub fn sign_mask(self) -> M8 {
            let a = self.to_array();
            M8::from_fn(|l| a[l].is_sign_negative())
        }
        #[inline(always)]
        pub fn copysign(self, sign: F8) -> F8 {
            let (a, b) = (self.to_array(), sign.to_array());
            F8::from_array(std::array::from_fn(|l| a[l].copysign(b[l])))
        }
        #[inline(always)]
        pub fn floor(self) -> F8 {
            F8::from_array(self.to_array().map(f32::floor))
        }
        #[inline(always)]
        pub fn trunc(self) -> I8 {
            I8(self.to_array().map(|x| {
                // `cvttps2dq`: the range is [-2^31, 2^31).
                if (-2_147_483_648.0..2_147_483_648.0).contains(&x) {
                    x as i32
                } else {
                    i32::MIN
                }
            }))
        }
        #[inline(always)]
        pub fn to_f64(self) -> D8 {
            D8(self.to_array().map(f64::from))
        }
        #[inline(always)]
        pub fn gather(table: &[f32], i: I8) -> F8 {
            let last = last_index(table.len()) as u32;
            F8::from_array(i.0.map(|i| table[(i as u32).min(last) as usize]))
        }
    }

    impl I8 {
        #[inline(always)]
        pub fn splat(x: i32) -> I8 {
            I8([x; 8])
        }
        #[cfg(test)]
        pub fn to_array(self) -> [i32; 8] {
            self.0
        }
        #[cfg(test)]
        pub fn from_array(a: [i32; 8]) -> I8 {
            I8(a)
        }
        #[inline(always)]
        fn zip(self, b: I8, f: impl Fn(i32, i32) -> i32) -> I8 {
            I8(std::array::from_fn(|l| f(self.0[l], b.0[l])))
        }
        #[inline(always)]
        pub fn add(self, b: I8) -> I8 {
            self.zip(b, i32::wrapping_add)
        }
        #[inline(always)]
        pub fn mul(self, b: I8) -> I8 {
            self.zip(b, i32::wrapping_mul)
        }
        #[inline(always)]
        pub fn max(self, b: I8) -> I8 {
            self.zip(b, i32::max)
        }
        #[inline(always)]
        pub fn min(self, b: I8) -> I8 {
            self.zip(b, i32::min)
        }
        #[inline(always)]
        pub fn to_f32(self) -> F8 {
            F8::from_array(self.0.map(|x| x as f32))
        }
        #[inline(always)]
        pub fn gather(table: &[u32], i: I8) -> I8 {
            let last = last_index(table.len()) as u32;
            I8(i.0.map(|i| table[(i as u32).min(last) as usize] as i32))
        }
        #[inline(always)]
        pub fn to_bits_f32(self) -> F8 {
            F8::from_array(self.0.map(|x| f32::from_bits(x as u32)))
        }
    }

    #[derive(Clone, Copy, Debug)]
    pub(crate) struct MD8([bool; 8]);

    impl MD8 {
        #[inline(always)]
        pub fn select(self, a: D8, b: D8) -> D8 {
            D8(std::array::from_fn(
                |l| if self.0[l] { a.0[l] } else { b.0[l] },
            ))
        }
        #[cfg(test)]
        pub fn bitmask(self) -> u32 {
            (0..8).map(|l| (self.0[l] as u32) << l).sum()
        }
    }

    impl D8 {
        #[inline(always)]
        pub fn splat(x: f64) -> D8 {
            D8([x; 8])
        }
        #[inline(always)]
        fn zip(self, b: D8, f: impl Fn(f64, f64) -> f64) -> D8 {
            D8(std::array::from_fn(|l| f(self.0[l], b.0[l])))
        }
        #[inline(always)]
        pub fn add(self, b: D8) -> D8 {
            self.zip(b, |x, y| x + y)
        }
        #[inline(always)]
        pub fn sub(self, b: D8) -> D8 {
            self.zip(b, |x, y| x - y)
        }
        #[inline(always)]
        pub fn mul(self, b: D8) -> D8 {
            self.zip(b, |x, y| x * y)
        }
        #[inline(always)]
        pub fn div(self, b: D8) -> D8 {
            self.zip(b, |x, y| x / y)
        }
        #[inline(always)]
        pub fn sqrt(self) -> D8 {
            D8(self.0.map(f64::sqrt))
        }
        #[inline(always)]
        pub fn abs(self) -> D8 {
            D8(self.0.map(f64::abs))
        }
        #[inline(always)]
        pub fn copysign(self, sign: D8) -> D8 {
            self.zip(sign, f64::copysign)
        }
        #[inline(always)]
        fn cmp(self, b: D8, f: impl Fn(f64, f64) -> bool) -> MD8 {
            MD8(std::array::from_fn(|l| f(self.0[l], b.0[l])))
        }
        #[inline(always)]
        pub fn gt(self, b: D8) -> MD8 {
            self.cmp(b, |x, y| x > y)
        }
        #[inline(always)]
        pub fn lt(self, b: D8) -> MD8 {
            self.cmp(b, |x, y| x < y)
        }
        #[inline(always)]
        pub fn eq(self, b: D8) -> MD8 {
            self.cmp(b, |x, y| x == y)
        }
        #[inline(always)]
        pub fn sign_negative(self) -> MD8 {
            MD8(self.0.map(f64::is_sign_negative))
        }
        #[inline(always)]
        pub fn to_f32(self) -> F8 {
            F8::from_array(self.0.map(|x| x as f32))
        }
        #[inline(always)]
        pub fn quarter_turns(turns: D8, s: D8, c: D8) -> (D8, D8) {
            let mut out = (s, c);
            for l in 0..8 {
                let q = turns.0[l].to_bits();
                let (s, c) = if q & 1 == 0 {
                    (s.0[l], c.0[l])
                } else {
                    (c.0[l], s.0[l])
                };
                out.0 .0[l] = f64::from_bits(s.to_bits() ^ ((q & 2) << 62));
                out.1 .0[l] = f64::from_bits(c.to_bits() ^ ((q.wrapping_add(1) & 2) << 62));
            }
            out
        }
    }
}

#[cfg(test)]
mod tests {
    /// The portable lanes give the same bits as the ones the build uses
    /// (AVX2 in the native build), NaN and infinities included.
    #[test]
    fn portable_lanes_match() {
        use super::portable::{D8 as PD, F8 as P, I8 as PI};
        use super::{D8, F8, I8};
        let special = [
            0.0,
            -0.0,
            1.5,
            -2.25,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            3e-39,
        ];
        let table: Vec<f32> = (0..37).map(|i| i as f32 * 0.5 - 3.0).collect();
        let itable: Vec<u32> = (0..37).map(|i| (i * 7 - 100) as u32).collect();
        let mut s = crate::math::Sampler::new(3, 0, 0);
        let bits = |x: [f32; 8]| x.map(f32::to_bits);
        for round in 0..400 {
            let pick = |s: &mut crate::math::Sampler| -> [f32; 8] {
                std::array::from_fn(|_| {
                    let r = s.next_1d();
                    match round % 4 {
                        0 => special[(r * 8.0) as usize % 8],
                        1 => (r - 0.5) * 100.0,
                        2 => (r - 0.5) * 6e9,
                        _ => r * 2.0 - 0.5,
                    }
                })
            };
            let (a, b) = (pick(&mut s), pick(&mut s));
            let (fa, fb, pa, pb) = (
                F8::from_array(a),
                F8::from_array(b),
                P::from_array(a),
                P::from_array(b),
            );
            assert_eq!(fa.to_array().map(f32::to_bits), bits(a));
            assert_eq!(bits(fa.sub(fb).to_array()), bits(pa.sub(pb).to_array()));
            assert_eq!(bits(fa.mul(fb).to_array()), bits(pa.mul(pb).to_array()));
            assert_eq!(bits(fa.min(fb).to_array()), bits(pa.min(pb).to_array()));
            assert_eq!(bits(fa.max(fb).to_array()), bits(pa.max(pb).to_array()));
            assert_eq!(bits(fa.add(fb).to_array()), bits(pa.add(pb).to_array()));
            assert_eq!(bits(fa.div(fb).to_array()), bits(pa.div(pb).to_array()));
            assert_eq!(bits(fa.sqrt().to_array()), bits(pa.sqrt().to_array()));
            if !a.iter().any(|x| x.is_nan()) {
                // (The least lane as a value: of 0 and -0 either may come.)
                let least = a.iter().copied().fold(f32::INFINITY, f32::min);
                assert!(fa.hmin() == least && pa.hmin() == least, "{a:?}");
            }
            assert_eq!(fa.le(fb).bitmask(), pa.le(pb).bitmask());
            assert_eq!(fa.sign_mask().bitmask(), pa.sign_mask().bitmask());
            assert_eq!(fa.lt(fb).bitmask(), pa.lt(pb).bitmask());
            let (m, pm) = (fa.le(fb).and(fb.lt(fa)), pa.le(pb).and(pb.lt(pa)));
            assert_eq!(m.bitmask(), pm.bitmask());
            let (m, pm) = (fa.lt(fb), pa.lt(pb));
            assert_eq!(
                bits(m.select(fa, fb).to_array()),
                bits(pm.select(pa, pb).to_array())
            );
            // Integers: truncation, arithmetic, comparisons, selects, gathers.
            let (ia, pia) = (fa.trunc(), pa.trunc());
            assert_eq!(ia.to_array(), pia.to_array());
            let (ib, pib) = (fb.trunc(), pb.trunc());
            assert_eq!(ia.add(ib).to_array(), pia.add(pib).to_array());
            assert_eq!(ia.mul(ib).to_array(), pia.mul(pib).to_array());
            assert_eq!(ia.max(ib).to_array(), pia.max(pib).to_array());
            assert_eq!(ia.min(ib).to_array(), pia.min(pib).to_array());
            assert_eq!(
                m.select_i8(ia, ib).to_array(),
                pm.select_i8(pia, pib).to_array()
            );
            assert_eq!(bits(ia.to_f32().to_array()), bits(pia.to_f32().to_array()));
            let (g, pg) = (F8::gather(&table, ia), P::gather(&table, pia));
            assert_eq!(bits(g.to_array()), bits(pg.to_array()));
            let (g, pg) = (I8::gather(&itable, ia), PI::gather(&itable, pia));
            assert_eq!(g.to_array(), pg.to_array());
            assert_eq!(
                bits(g.to_bits_f32().to_array()),
                bits(pg.to_bits_f32().to_array())
            );
            assert_eq!(
                I8::from_array(ia.to_array()).add(I8::splat(7)).to_array(),
                I8::splat(7).add(ia).to_array()
            );
            // Doubles, through their round trip to f32.
            let (da, db, pda, pdb) = (fa.to_f64(), fb.to_f64(), pa.to_f64(), pb.to_f64());
            let f = |d: D8| bits(d.to_f32().to_array());
            let pf = |d: PD| bits(d.to_f32().to_array());
            assert_eq!(f(da.add(db)), pf(pda.add(pdb)));
            assert_eq!(f(da.sub(db)), pf(pda.sub(pdb)));
            assert_eq!(
                f(da.mul(db).mul(D8::splat(1e-3))),
                pf(pda.mul(pdb).mul(PD::splat(1e-3)))
            );
            let t = da
                .mul(D8::splat(4.0))
                .add(D8::splat(6_755_399_441_055_744.0));
            let pt = pda
                .mul(PD::splat(4.0))
                .add(PD::splat(6_755_399_441_055_744.0));
            let (qs, qc) = D8::quarter_turns(t, da, db);
            let (pqs, pqc) = PD::quarter_turns(pt, pda, pdb);
            assert_eq!((f(qs), f(qc)), (pf(pqs), pf(pqc)));
            // Signs, rounding down, and the doubles' comparisons and selects.
            assert_eq!(bits(fa.neg().to_array()), bits(pa.neg().to_array()));
            assert_eq!(
                bits(fa.copysign(fb).to_array()),
                bits(pa.copysign(pb).to_array())
            );
            assert_eq!(bits(fa.floor().to_array()), bits(pa.floor().to_array()));
            assert_eq!(f(da.div(db)), pf(pda.div(pdb)));
            assert_eq!(f(da.sqrt()), pf(pda.sqrt()));
            assert_eq!(f(da.abs()), pf(pda.abs()));
            assert_eq!(f(da.copysign(db)), pf(pda.copysign(pdb)));
            for (m, pm) in [
                (da.gt(db), pda.gt(pdb)),
                (da.lt(db), pda.lt(pdb)),
                (da.eq(db), pda.eq(pdb)),
                (da.sign_negative(), pda.sign_negative()),
            ] {
                assert_eq!(m.bitmask(), pm.bitmask());
                assert_eq!(f(m.select(da, db)), pf(pm.select(pda, pdb)));
            }
            assert_eq!(
                da.eq(da).bitmask(),
                fa.le(fa).bitmask(),
                "NaN lanes are unequal"
            );
            // The NaN rule itself: the second operand.
            for l in 0..8 {
                let (x, y) = (a[l], b[l]);
                if x.is_nan() || y.is_nan() {
                    assert_eq!(fa.min(fb).to_array()[l].to_bits(), y.to_bits());
                    assert_eq!(fa.max(fb).to_array()[l].to_bits(), y.to_bits());
                }
            }
            assert_eq!(
                F8::splat(a[0]).to_array().map(f32::to_bits),
                [a[0].to_bits(); 8]
            );
        }
    }
}
