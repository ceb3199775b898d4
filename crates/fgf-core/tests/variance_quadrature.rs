//! `docs/theory.md` §2 closed forms against independent numerical integrals of
//! the covariance.

mod common;

use common::tanh_sinh;
use fgf_core::stats::{c_const, kfbm_point_variance, line_average_variance, s_kf};

/// Pink noise: `var[σ̄_t] = (1/t²) ∫_0^t ∫_0^t C(H,1) S_w |x-y|^(2H) dy dx`,
/// integrated numerically over the triangle `y < x` (times 2). The inner
/// integral has the singularity `(x-y)^(2H)` at `y = x`, handled by
/// tanh-sinh with the exact distance to the end. Target: 1e-6 relative.
#[test]
fn pink_variance_matches_double_integral_of_covariance() {
    // S_w only scales both sides, so one value pairs with each H.
    for (&h, &sw) in [-0.45, -0.3, -0.1, -0.02].iter().zip(&[0.5, 4.0, 1.0, 2.5]) {
        for &t in &[0.1, 1.0, 7.0] {
            let c = c_const(h, 1);
            let outer = tanh_sinh(
                |x, _, _| tanh_sinh(|_y, _, dist_to_x| dist_to_x.powf(2.0 * h), 0.0, x),
                0.0,
                t,
            );
            let want = 2.0 * c * sw * outer / (t * t);
            let got = line_average_variance(h, sw, t, None).unwrap();
            let rel = ((got - want) / want).abs();
            assert!(
                rel < 1e-6,
                "H = {h}, sw = {sw}, t = {t}: {got} vs {want} ({rel:e})"
            );
        }
    }
}

/// k-fBm: `S_kf L^(2H)` is the mean over `[0, L]` of the anchored k-fBm
/// point variance. The point variance is taken here from its independent
/// Taylor-sum form `-2 C S_w x^(2H) Σ_{j<k} (-1)^j binom(2H, j)` (the
/// variance of `M` minus its Taylor polynomial through the generalised
/// covariance `C S_w |h|^(2H)`, derivatives at 0 of order < 2H vanish) and
/// averaged by quadrature.
#[test]
fn kfbm_variance_is_mean_point_variance_over_length() {
    for &h in &[0.2f64, 0.5, 0.85, 1.2, 1.8, 2.4] {
        let k = h.ceil() as u32;
        let mut sum = 0.0;
        let mut b = 1.0; // binom(2H, j)
        for j in 0..k {
            if j > 0 {
                b *= (2.0 * h - (j - 1) as f64) / j as f64;
            }
            sum += if j % 2 == 0 { b } else { -b };
        }
        for &sw in &[1.0, 34.0] {
            for &l in &[0.3, 1.0, 5.0] {
                let pv = |x: f64| -2.0 * c_const(h, 1) * sw * x.powf(2.0 * h) * sum;
                let mean = tanh_sinh(|x, _, _| pv(x), 0.0, l) / l;
                let got = line_average_variance(h, sw, 1.0, Some(l)).unwrap();
                let rel = ((got - mean) / mean).abs();
                assert!(rel < 1e-9, "H = {h}, L = {l}: {got} vs {mean}");
                // And through the library's own point variance.
                let mean2 = tanh_sinh(|x, _, _| kfbm_point_variance(h, sw, x), 0.0, l) / l;
                assert!(((mean2 - got) / got).abs() < 1e-9);
                assert!(((s_kf(h, sw) * l.powf(2.0 * h) - got) / got).abs() < 1e-12);
            }
        }
    }
}

/// White noise: the limit `H → -1/2` of the pink law, and `S_w / t`.
#[test]
fn white_variance_is_the_pink_limit() {
    let white = line_average_variance(-0.5, 2.0, 3.0, None).unwrap();
    assert!((white - 2.0 / 3.0).abs() < 1e-15);
    let near = line_average_variance(-0.5 + 1e-8, 2.0, 3.0, None).unwrap();
    assert!(((near - white) / white).abs() < 1e-6);
}
