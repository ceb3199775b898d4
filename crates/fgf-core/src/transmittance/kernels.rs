//! Numeric kernels of the gamma closure (`docs/theory.md` §7): a fast `ln(1+x)`,
//! `g(x) = ln(1+x)/x` with its two cancellation-free companions `g - 1` and
//! `x (-g'(x))`, and the terms of the pink-noise surface equation. Plain
//! functions of `f64`, no model state.

/// `ln(1 + x)` through the fast `ln`: with `u = 1 + x` rounded, `u - 1` is
/// exact and `ln(u) · x/(u - 1)` corrects the rounding of `u` (Goldberg 1991,
/// "What every computer scientist should know about floating-point
/// arithmetic", Theorem 4: relative error below 5 ε). glibc's `log1p` is
/// about three times slower than its `log`, and this is on the renderer's
/// hot path.
#[inline]
pub(crate) fn ln_1p(x: f64) -> f64 {
    let u = 1.0 + x;
    if u == 1.0 {
        x
    } else if u == f64::INFINITY {
        u
    } else {
        u.ln() * (x / (u - 1.0))
    }
}

/// `g(x) = ln(1+x)/x`, `g(0) = 1`, `g(∞) = 0`. `ln_1p` keeps full relative
/// accuracy for small `x`, so no series is needed here.
#[inline]
pub(crate) fn g(x: f64) -> f64 {
    if x == 0.0 {
        1.0
    } else if x.is_infinite() {
        0.0
    } else {
        ln_1p(x) / x
    }
}

/// Below this `x`, `g - 1` and `-g'` use their Taylor series: the direct forms
/// lose about `ε / x` relative accuracy by cancellation (4e-15 at `x = 0.1`),
/// the 17-term series truncates at `0.1^17`.
pub(crate) const SERIES_X: f64 = 0.1;
const SERIES_TERMS: usize = 17;

/// Signed coefficients of the two series, `(-1)^(m+1)/(m+2)` and
/// `(-1)^m (m+1)/(m+2)` for `m = 0..17`, divided at compile time (the same
/// IEEE divisions the loops used to do on every call, so the same values).
#[rustfmt::skip]
const G_MINUS_1_COEF: [f64; SERIES_TERMS] = [
    -1.0 / 2.0, 1.0 / 3.0, -1.0 / 4.0, 1.0 / 5.0, -1.0 / 6.0, 1.0 / 7.0, -1.0 / 8.0, 1.0 / 9.0,
    -1.0 / 10.0, 1.0 / 11.0, -1.0 / 12.0, 1.0 / 13.0, -1.0 / 14.0, 1.0 / 15.0, -1.0 / 16.0,
    1.0 / 17.0, -1.0 / 18.0,
];
#[rustfmt::skip]
const X_NEG_DG_COEF: [f64; SERIES_TERMS] = [
    1.0 / 2.0, -2.0 / 3.0, 3.0 / 4.0, -4.0 / 5.0, 5.0 / 6.0, -6.0 / 7.0, 7.0 / 8.0, -8.0 / 9.0,
    9.0 / 10.0, -10.0 / 11.0, 11.0 / 12.0, -12.0 / 13.0, 13.0 / 14.0, -14.0 / 15.0,
    15.0 / 16.0, -16.0 / 17.0, 17.0 / 18.0,
];

/// `g(x) - 1 = Σ_{n≥1} (-1)^n x^n / (n+1)`, without cancellation at small `x`.
#[inline]
pub(crate) fn g_minus_1(x: f64) -> f64 {
    if x < SERIES_X {
        // Horner on Σ_{m≥0} (-1)^(m+1) x^m / (m+2), times x.
        G_MINUS_1_COEF.iter().rev().fold(0.0, |s, &c| s * x + c) * x
    } else {
        g(x) - 1.0
    }
}

/// `x (-g'(x)) = g(x) - 1/(1+x) ≥ 0`, series `Σ_{m≥0} (-1)^m (m+1) x^(m+1) / (m+2)`
/// below [`SERIES_X`]; tends to 0 as `x → ∞`.
#[inline]
pub(crate) fn x_neg_dg(x: f64) -> f64 {
    if x < SERIES_X {
        X_NEG_DG_COEF.iter().rev().fold(0.0, |s, &c| s * x + c) * x
    } else if x.is_infinite() {
        0.0
    } else {
        g(x) - 1.0 / (1.0 + x)
    }
}

/// Terms of the pink surface equation at `ln x`: `(ln g, a, b, x b')` with
/// `g = L/x`, `L = ln(1+x)`, `a = x / ((1+x) L)` and `b = x a'(x)`; see
/// `GammaCore::sample_surface`.
#[inline]
pub(crate) fn pink_terms(ln_x: f64) -> (f64, f64, f64, f64) {
    if ln_x < -18.0 {
        // x < 1.5e-8: ln g = -x/2, a = 1 - x/2, b = -x/2, x b' = -x/2,
        // each to O(x²) < 1e-16.
        let x = ln_x.exp();
        (-0.5 * x, 1.0 - 0.5 * x, -0.5 * x, -0.5 * x)
    } else if ln_x > 700.0 {
        // 1 + x overflows soon: L = ln x to 1e-304, a = 1/L, g = 0,
        // and x b' = O(1/L²) is negligible against φ'.
        let a = 1.0 / ln_x;
        (ln_x.ln() - ln_x, a, -a * a, 0.0)
    } else {
        let x = ln_x.exp();
        let l = ln_1p(x);
        // Two divisions only: a = x / ((1+x) L), b = x a'(x) =
        // (x L - x²) / ((1+x)² L²) = a (L - x) / ((1+x) L), and
        // x b'(x) = x (N' - b D') / D by the quotient rule with
        // N = x L - x², D = (1+x)² L², so x/D = a / ((1+x) L).
        let inv_1px = 1.0 / (1.0 + x);
        let inv_l = 1.0 / l;
        let a = x * inv_1px * inv_l;
        let r = a * inv_1px * inv_l;
        let b = r * (l - x);
        let dn = l + x * inv_1px - 2.0 * x;
        let dden = 2.0 * (1.0 + x) * l * (l + 1.0);
        (l.ln() - ln_x, a, b, r * (dn - b * dden))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fast `ln_1p` stays within Goldberg's bound (5 ε relative) of the
    /// standard library's over 60 decades of `x` on both sides of 0, and
    /// keeps the special values.
    #[test]
    fn fast_ln_1p_matches_std() {
        let mut worst = 0.0f64;
        for k in 0..=6000 {
            let mag = 10f64.powf(-300.0 + 0.1 * k as f64);
            for x in [mag, -mag * 0.999_999_9] {
                if x <= -1.0 || !x.is_finite() {
                    continue;
                }
                let (a, b) = (ln_1p(x), x.ln_1p());
                worst = worst.max(((a - b) / b).abs());
            }
        }
        assert!(
            worst <= 5.0 * f64::EPSILON,
            "worst relative error {worst:e}"
        );
        assert_eq!(ln_1p(0.0), 0.0);
        assert_eq!(ln_1p(-1.0), f64::NEG_INFINITY);
        assert_eq!(ln_1p(f64::INFINITY), f64::INFINITY);
        assert!(
            ln_1p(-2.0).is_nan() && ln_1p(f64::NAN).is_nan() && ln_1p(f64::NEG_INFINITY).is_nan()
        );
    }

    #[test]
    fn series_match_direct_forms_at_the_switch() {
        let x = SERIES_X * (1.0 - 1e-12);
        let direct_gm1 = x.ln_1p() / x - 1.0;
        assert!(((g_minus_1(x) - direct_gm1) / direct_gm1).abs() < 1e-13);
        let direct = x.ln_1p() / x - 1.0 / (1.0 + x);
        assert!(((x_neg_dg(x) - direct) / direct).abs() < 1e-13);
        // Small x: leading terms.
        let x = 1e-8;
        assert!(((g_minus_1(x) + x / 2.0) / (x / 2.0)).abs() < 1e-7);
        assert!(((x_neg_dg(x) - x / 2.0) / (x / 2.0)).abs() < 1e-7);
    }
}
