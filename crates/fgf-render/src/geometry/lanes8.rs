//! `F8`, eight `f32` lanes for the 8-wide BVH nodes and leaf packs: one AVX register where
//! the build enables AVX (the default native build), else two SSE `Vec4`s
//! (the portable wheel). Both give the same bits in every lane, including
//! the NaN rule of `min`/`max` that the slab test relies on: if either
//! operand is NaN, the second one is returned (x86 `minps`/`maxps`).
//!
//! Only the handful of operations the slab and leaf tests need. The AVX intrinsics
//! are `unsafe` to call even when the build enables AVX (Rust asks the
//! calling function to enable it itself, which `#[inline(always)]`
//! functions cannot); this module is compiled only when it does.

#[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
pub(super) use avx::F8;
#[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
pub(super) use pairs::F8;

#[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
mod avx {
    // SAFETY (every `unsafe` block below): the intrinsics need AVX, which
    // this module is only compiled with (`cfg(target_feature = "avx")`);
    // none of them touches memory.
    use glam::Vec4;
    use std::arch::x86_64::*;

    #[derive(Clone, Copy, Debug)]
    #[repr(transparent)]
    pub(in super::super) struct F8(__m256);

    impl F8 {
        #[inline(always)]
        pub fn splat(x: f32) -> F8 {
            F8(unsafe { _mm256_set1_ps(x) })
        }
        #[inline(always)]
        pub fn from_array(a: [f32; 8]) -> F8 {
            F8(unsafe { _mm256_setr_ps(a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7]) })
        }
        #[inline(always)]
        pub fn to_array(self) -> [f32; 8] {
            let lo = Vec4::from(unsafe { _mm256_castps256_ps128(self.0) }).to_array();
            let hi = Vec4::from(unsafe { _mm256_extractf128_ps::<1>(self.0) }).to_array();
            [lo[0], lo[1], lo[2], lo[3], hi[0], hi[1], hi[2], hi[3]]
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
        #[inline(always)]
        pub fn add(self, b: F8) -> F8 {
            F8(unsafe { _mm256_add_ps(self.0, b.0) })
        }
        #[inline(always)]
        pub fn div(self, b: F8) -> F8 {
            F8(unsafe { _mm256_div_ps(self.0, b.0) })
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
    }

    /// A lane mask, the result of a comparison.
    #[derive(Clone, Copy, Debug)]
    #[repr(transparent)]
    pub(in super::super) struct M8(__m256);

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
    }
}

/// The portable `F8` (always compiled, so that its tests can compare it
/// with the AVX one).
#[cfg_attr(all(target_arch = "x86_64", target_feature = "avx"), allow(dead_code))]
mod pairs {
    use glam::{BVec4A, Vec4};

    #[derive(Clone, Copy, Debug)]
    pub(in super::super) struct F8([Vec4; 2]);

    /// A lane mask, the result of a comparison.
    #[derive(Clone, Copy, Debug)]
    pub(in super::super) struct M8([BVec4A; 2]);

    impl M8 {
        #[inline(always)]
        pub fn and(self, b: M8) -> M8 {
            M8([self.0[0] & b.0[0], self.0[1] & b.0[1]])
        }
        #[inline(always)]
        pub fn bitmask(self) -> u32 {
            self.0[0].bitmask() | self.0[1].bitmask() << 4
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
        #[inline(always)]
        pub fn add(self, b: F8) -> F8 {
            F8([self.0[0] + b.0[0], self.0[1] + b.0[1]])
        }
        #[inline(always)]
        pub fn div(self, b: F8) -> F8 {
            F8([self.0[0] / b.0[0], self.0[1] / b.0[1]])
        }
        #[inline(always)]
        pub fn le(self, b: F8) -> M8 {
            M8([self.0[0].cmple(b.0[0]), self.0[1].cmple(b.0[1])])
        }
        #[inline(always)]
        pub fn lt(self, b: F8) -> M8 {
            M8([self.0[0].cmplt(b.0[0]), self.0[1].cmplt(b.0[1])])
        }
    }
}

#[cfg(test)]
mod tests {
    /// The portable lanes give the same bits as the ones the build uses
    /// (AVX in the native build), NaN and infinities included.
    #[test]
    fn portable_lanes_match() {
        use super::pairs::F8 as P;
        use super::F8;
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
        let mut s = crate::math::Sampler::new(3, 0, 0);
        for round in 0..200 {
            let pick = |s: &mut crate::math::Sampler| -> [f32; 8] {
                std::array::from_fn(|_| {
                    let r = s.next_1d();
                    if round % 2 == 0 {
                        special[(r * 8.0) as usize % 8]
                    } else {
                        (r - 0.5) * 100.0
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
            let bits = |x: [f32; 8]| x.map(f32::to_bits);
            assert_eq!(fa.to_array().map(f32::to_bits), bits(a));
            assert_eq!(bits(fa.sub(fb).to_array()), bits(pa.sub(pb).to_array()));
            assert_eq!(bits(fa.mul(fb).to_array()), bits(pa.mul(pb).to_array()));
            assert_eq!(bits(fa.min(fb).to_array()), bits(pa.min(pb).to_array()));
            assert_eq!(bits(fa.max(fb).to_array()), bits(pa.max(pb).to_array()));
            assert_eq!(bits(fa.add(fb).to_array()), bits(pa.add(pb).to_array()));
            assert_eq!(bits(fa.div(fb).to_array()), bits(pa.div(pb).to_array()));
            assert_eq!(fa.le(fb).bitmask(), pa.le(pb).bitmask());
            assert_eq!(fa.lt(fb).bitmask(), pa.lt(pb).bitmask());
            let (m, pm) = (fa.le(fb).and(fb.lt(fa)), pa.le(pb).and(pb.lt(pa)));
            assert_eq!(m.bitmask(), pm.bitmask());
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
