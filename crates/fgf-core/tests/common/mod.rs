//! Test helpers: an independent quadrature (tanh-sinh) and the
//! Kolmogorov–Smirnov test. Nothing here calls the code under test.

#![allow(dead_code)]

use std::f64::consts::FRAC_PI_2;

/// `∫_a^b f` by tanh-sinh (double-exponential) quadrature, which converges
/// exponentially also for integrable algebraic singularities at the end
/// points. `f` receives `(t, dist_a, dist_b)`: the node and its distances to
/// both ends, computed without cancellation so that `f` can evaluate
/// `|t - a|^p` accurately next to a singular end.
pub fn tanh_sinh(f: impl Fn(f64, f64, f64) -> f64, a: f64, b: f64) -> f64 {
    // Step 2^-7 over |u| ≤ 6.5: nodes closer than 1e-300 to an end carry
    // negligible weight for the integrands used here.
    let h = 1.0 / 128.0;
    let half = 0.5 * (b - a);
    let mut sum = 0.0;
    let n = (6.5 / h) as i64;
    for i in -n..=n {
        let u = i as f64 * h;
        let v = FRAC_PI_2 * u.sinh();
        let w = FRAC_PI_2 * u.cosh() / (v.cosh() * v.cosh());
        // 1 - |tanh v| = 2 / (exp(2|v|) + 1), exact to rounding.
        let one_minus = 2.0 / ((2.0 * v.abs()).exp() + 1.0);
        let (da, db) = if v < 0.0 {
            (half * one_minus, half * (2.0 - one_minus))
        } else {
            (half * (2.0 - one_minus), half * one_minus)
        };
        if da <= 0.0 || db <= 0.0 {
            continue;
        }
        let t = if da < db { a + da } else { b - db };
        let fx = f(t, da, db);
        if fx.is_finite() {
            sum += w * fx;
        }
    }
    sum * half * h
}

/// `∫_0^∞ f` = `∫_0^T f + ∫_0^1 f(T/w) T/w² dw`.
pub fn integrate_0_inf(f: impl Fn(f64) -> f64, split: f64) -> f64 {
    let head = tanh_sinh(|t, _, _| f(t), 0.0, split);
    let tail = tanh_sinh(|w, _, _| f(split / w) * split / (w * w), 0.0, 1.0);
    head + tail
}

/// Kolmogorov–Smirnov statistic `D_n` of `samples` against the cdf.
pub fn ks_statistic(samples: &mut [f64], cdf: impl Fn(f64) -> f64) -> f64 {
    samples.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let n = samples.len() as f64;
    let mut d: f64 = 0.0;
    for (i, &x) in samples.iter().enumerate() {
        let f = cdf(x);
        d = d.max(f - i as f64 / n).max((i as f64 + 1.0) / n - f);
    }
    d
}

/// Asymptotic p-value of `D_n` (Kolmogorov distribution with Stephens'
/// finite-n correction `λ = (√n + 0.12 + 0.11/√n) D`).
pub fn ks_p_value(d: f64, n: usize) -> f64 {
    let sn = (n as f64).sqrt();
    let lambda = (sn + 0.12 + 0.11 / sn) * d;
    let mut q = 0.0;
    for j in 1..=100 {
        let j = j as f64;
        let term = 2.0 * (-1f64).powi(j as i32 - 1) * (-2.0 * j * j * lambda * lambda).exp();
        q += term;
        if term.abs() < 1e-16 {
            break;
        }
    }
    q.clamp(0.0, 1.0)
}
