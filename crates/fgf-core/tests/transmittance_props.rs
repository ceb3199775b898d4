//! Properties of every transmittance model (`docs/theory.md` §3–4): Tr(0) = 1,
//! monotone Tr, ∫p = 1, p(0) = σ̄, the derivative identities of the four
//! reciprocal functions by finite differences, limits, the Davis and
//! Davis–Weinstein equivalences, sampler round trips, finiteness over
//! extreme parameters, and parameter validation.

mod common;

use common::{integrate_0_inf, tanh_sinh};
use fgf_core::stats::s_p;
use fgf_core::transmittance::{Davis, DavisWeinstein, Exponential, Fgf, Model, Transmittance};

/// A representative set of models: every kind, every regime, mild and
/// extreme parameters.
fn models() -> Vec<(String, Model)> {
    let mut v: Vec<(String, Model)> = vec![
        ("exp".into(), Exponential::new(4.0).unwrap().into()),
        (
            "white".into(),
            Fgf::new(4.0, -0.5, 4.0, None).unwrap().into(),
        ),
        (
            "pink -0.1".into(),
            Fgf::new(4.0, -0.1, 4.0, None).unwrap().into(),
        ),
        (
            "pink -0.45".into(),
            Fgf::new(2.0, -0.45, 10.0, None).unwrap().into(),
        ),
        (
            "pink -0.01".into(),
            Fgf::new(0.5, -0.01, 0.2, None).unwrap().into(),
        ),
        (
            "1-fBm".into(),
            Fgf::new(4.0, 0.2, 4.0, Some(1.0)).unwrap().into(),
        ),
        (
            "2-fBm".into(),
            Fgf::new(4.0, 1.2, 34.0, Some(1.0)).unwrap().into(),
        ),
        ("davis 4".into(), Davis::new(4.0, 4.0).unwrap().into()),
        ("davis 0.7".into(), Davis::new(1.5, 0.7).unwrap().into()),
        (
            "dw 0.9".into(),
            DavisWeinstein::new(4.0, 0.9, 0.78).unwrap().into(),
        ),
        (
            "dw 0.5".into(),
            DavisWeinstein::new(4.0, 0.5, 0.78).unwrap().into(),
        ),
        (
            "dw 1".into(),
            DavisWeinstein::new(4.0, 1.0, 0.78).unwrap().into(),
        ),
        (
            "dw 0.6 c3".into(),
            DavisWeinstein::new(3.0, 0.6, 3.0).unwrap().into(),
        ),
    ];
    v.push(("davis 1e3".into(), Davis::new(2.0, 1e3).unwrap().into()));
    v.push((
        "dw 0.99 c5".into(),
        DavisWeinstein::new(0.5, 0.99, 5.0).unwrap().into(),
    ));
    v
}

fn rel(a: f64, b: f64) -> f64 {
    if a == b {
        0.0
    } else {
        ((a - b) / b).abs()
    }
}

/// Distances spanning the short, typical and long ranges (in units of the
/// mean free path 1/σ).
fn ts(m: &Model) -> Vec<f64> {
    let mfp = 1.0 / m.sigma_t();
    [1e-3, 0.02, 0.1, 0.5, 1.0, 2.0, 5.0, 12.0]
        .iter()
        .map(|s| s * mfp)
        .collect()
}

#[test]
fn tr_is_one_at_zero_and_zero_at_infinity() {
    for (name, m) in models() {
        assert_eq!(m.tr(0.0), 1.0, "{name}");
        assert_eq!(m.medium_surface(0.0), 1.0, "{name}");
        assert_eq!(m.tr(f64::INFINITY), 0.0, "{name}");
        assert_eq!(m.pdf(f64::INFINITY), 0.0, "{name}");
        assert_eq!(m.medium_surface(f64::INFINITY), 0.0, "{name}");
        assert_eq!(m.medium_medium(f64::INFINITY), 0.0, "{name}");
        assert!(m.tr(-1.0).is_nan(), "{name}");
    }
}

#[test]
fn pdf_at_zero_is_sigma_bar_and_sigma_m_except_white() {
    for (name, m) in models() {
        assert!(rel(m.pdf(0.0), m.sigma_bar()) < 1e-15, "{name}");
        let white = name == "white" || name == "dw 0.5";
        if !white {
            assert!(rel(m.pdf(0.0), m.sigma_t()) < 1e-15, "{name}");
        }
    }
    // White noise: p(0) = σ_eff = (σ²/S_w) ln(1 + S_w/σ).
    let w = Fgf::new(4.0, -0.5, 4.0, None).unwrap();
    assert!(rel(w.pdf(0.0), 4.0 * 2f64.ln()) < 1e-15);
}

#[test]
fn tr_is_monotone_decreasing() {
    for (name, m) in models() {
        let mut prev = 1.0;
        for i in 1..=4000 {
            let t = (i as f64 / 4000.0).powi(3) * 30.0 / m.sigma_t();
            let tr = m.tr(t);
            assert!(tr <= prev, "{name}: Tr({t}) = {tr} > {prev}");
            assert!(
                m.pdf(t) >= 0.0 && m.medium_medium(t) >= 0.0,
                "{name} at {t}"
            );
            prev = tr;
        }
    }
}

/// `∫_0^∞ T_sm = 1` and `∫_0^∞ T_mm = 1` by quadrature (the latter has an
/// integrable `t^(2H)` singularity at 0 for pink noise), and the partial
/// integrals `∫_0^T T_sm = 1 - Tr(T)`, `∫_0^T T_mm = 1 - T_ms(T)`.
#[test]
fn pdfs_integrate_to_one() {
    for (name, m) in models() {
        // Davis with α < 1 has a heavy tail ~ t^(-α-1): still integrable.
        let split = 2.0 / m.sigma_t();
        let i_sm = integrate_0_inf(|t| m.pdf(t), split);
        let i_mm = integrate_0_inf(|t| m.medium_medium(t), split);
        assert!((i_sm - 1.0).abs() < 1e-8, "{name}: ∫T_sm = {i_sm}");
        assert!((i_mm - 1.0).abs() < 1e-8, "{name}: ∫T_mm = {i_mm}");
        for big_t in [0.3 / m.sigma_t(), split] {
            let p = tanh_sinh(|t, _, _| m.pdf(t), 0.0, big_t);
            assert!((p - (1.0 - m.tr(big_t))).abs() < 1e-10, "{name}");
            let p = tanh_sinh(|t, _, _| m.medium_medium(t), 0.0, big_t);
            assert!(
                (p - (1.0 - m.medium_surface(big_t))).abs() < 1e-10,
                "{name}"
            );
        }
    }
}

/// Five-point central differences `f' ≈ (f(t-2h) - 8f(t-h) + 8f(t+h) - f(t+2h)) / 12h`
/// with `h = 1e-3 t`: truncation O((h/t)^4) ~ 1e-12 (the pink terms vary on
/// the scale t) and rounding O(ε / (σ h)) ≤ 1e-12 for `t ≥ 1e-3/σ`, so 1e-7
/// relative is a safe bound that still catches any wrong term.
fn deriv(f: impl Fn(f64) -> f64, t: f64) -> f64 {
    let h = 1e-3 * t;
    (f(t - 2.0 * h) - 8.0 * f(t - h) + 8.0 * f(t + h) - f(t + 2.0 * h)) / (12.0 * h)
}

#[test]
fn derivative_identities_by_finite_differences() {
    for (name, m) in models() {
        let sb = m.sigma_bar();
        for t in ts(&m) {
            let d_tr = deriv(|t| m.tr(t), t);
            let d_ms = deriv(|t| m.medium_surface(t), t);
            let scale = m.pdf(t).max(1e-300);
            assert!(
                (m.surface_medium(t) + d_tr).abs() <= 1e-7 * scale,
                "{name}: T_sm at {t}"
            );
            assert!(
                rel(m.medium_surface(t), m.surface_medium(t) / sb) < 1e-14,
                "{name}"
            );
            let scale = m.medium_medium(t).max(1e-300);
            assert!(
                (m.medium_medium(t) + d_ms).abs() <= 1e-7 * scale,
                "{name}: T_mm at {t}"
            );
            assert_eq!(m.surface_surface(t), m.tr(t));
        }
    }
}

#[test]
fn white_noise_is_exponential_with_sigma_eff() {
    let (sigma, sw) = (4.0f64, 4.0f64);
    let sigma_eff = sigma * sigma / sw * (1.0 + sw / sigma).ln();
    let w = Fgf::new(sigma, -0.5, sw, None).unwrap();
    let dw = DavisWeinstein::new(sigma, 0.5, sw / sigma).unwrap();
    for t in [0.0, 0.01, 0.3, 1.0, 4.0] {
        let want = (-sigma_eff * t).exp();
        assert!(rel(w.tr(t), want) < 1e-14);
        assert!(rel(w.pdf(t), sigma_eff * want) < 1e-14);
        assert!(rel(w.medium_surface(t), want) < 1e-14);
        assert!(rel(w.medium_medium(t), sigma_eff * want) < 1e-14);
        assert!(rel(dw.tr(t), want) < 1e-12);
    }
    // Continuity: H slightly above -1/2 is close to white noise.
    let near = Fgf::new(sigma, -0.5 + 1e-7, sw, None).unwrap();
    for t in [0.01, 0.3, 1.0] {
        assert!(rel(near.tr(t), w.tr(t)) < 1e-5);
    }
    let u = 0.3f64;
    assert!(rel(w.sample_surface(u), -(1.0 - u).ln() / sigma_eff) < 1e-14);
}

#[test]
fn alpha_to_infinity_is_exponential_and_to_zero_is_transparent() {
    let e = Exponential::new(3.0).unwrap();
    // α = 1e14: the model differs from the exponential by O(σt/α) ~ 1e-13.
    let big = Davis::new(3.0, 1e14).unwrap();
    let tiny = Davis::new(3.0, 1e-12).unwrap();
    for t in [0.0, 1e-3, 0.1, 1.0, 5.0] {
        assert!(rel(big.tr(t), e.tr(t)) < 1e-10, "t = {t}");
        assert!(rel(big.pdf(t), e.pdf(t)) < 1e-10, "t = {t}");
        assert!(
            rel(big.medium_medium(t), e.medium_medium(t)) < 1e-10,
            "t = {t}"
        );
        // α ln(1 + σt/α) ≈ 1e-12 ln(3e12 t): Tr within 1e-10 of 1.
        assert!((tiny.tr(t) - 1.0).abs() < 1e-10, "t = {t}");
    }
    assert!(rel(big.sample_surface(0.7), e.sample_surface(0.7)) < 1e-10);
    assert!(rel(big.sample_medium(0.7), e.sample_medium(0.7)) < 1e-10);
    // α → 0: flights from a surface escape (inf or astronomically far).
    assert!(tiny.sample_surface(0.5) > 1e100);
    // k-fBm with a huge variance (α underflows): transparent, no NaN.
    let f = Fgf::new(1.0, 1.9, 1e300, Some(1e10)).unwrap();
    assert!(f.tr(1.0) == 1.0 && f.sample_surface(0.5) == f64::INFINITY);
    assert!(!f.medium_medium(1.0).is_nan() && !f.sample_medium(0.5).is_nan());
}

/// Pink white-noise-side limits: Tr ≈ exp(-σt) as t → 0 (α → 0 while
/// α log1p(σt/α) → σt).
#[test]
fn pink_short_distance_limit() {
    let m = Fgf::new(4.0, -0.1, 4.0, None).unwrap();
    for t in [1e-300, 1e-100, 1e-20, 1e-12] {
        assert!(rel(m.tr(t), (-4.0 * t).exp()) < 1e-11, "t = {t}");
        assert!(rel(m.pdf(t), 4.0) < 1e-2, "t = {t}");
        assert!(m.alpha(t) < 1e-2 && m.alpha(t) >= 0.0);
    }
    assert_eq!(m.alpha(0.0), 0.0);
    assert_eq!(m.variance(0.0), f64::INFINITY);
    assert_eq!(m.medium_medium(0.0), f64::INFINITY);
}

/// Independent Davis formula `(1 + σt/α)^(-α)` written out with `powf`.
#[test]
fn davis_matches_kfbm_mapping() {
    for &(sigma, h, sw, l) in &[
        (4.0, 1.2, 34.0, 1.0),
        (4.0, 0.2, 4.0, 1.0),
        (1.0, 0.7, 0.5, 3.0),
        (10.0, 2.5, 2.0, 0.5),
    ] {
        let f = Fgf::new(sigma, h, sw, Some(l)).unwrap();
        let d = f.to_davis().unwrap();
        let alpha =
            sigma * sigma / fgf_core::stats::line_average_variance(h, sw, 1.0, Some(l)).unwrap();
        assert!(rel(d.alpha(), alpha) < 1e-13);
        for t in [0.0, 1e-4, 0.05, 0.3, 1.0, 3.0, 10.0] {
            let base = 1.0 + sigma * t / alpha;
            let tr = base.powf(-alpha);
            let pdf = sigma * base.powf(-alpha - 1.0);
            let tmm = sigma * (alpha + 1.0) / alpha * base.powf(-alpha - 2.0);
            for (a, b) in [
                (f.tr(t), tr),
                (f.pdf(t), pdf),
                (f.medium_surface(t), pdf / sigma),
                (f.medium_medium(t), tmm),
                (d.tr(t), tr),
                (d.medium_medium(t), tmm),
            ] {
                assert!(rel(a, b) < 1e-10, "H = {h}, t = {t}: {a} vs {b}");
            }
            assert!(rel(f.variance(t), sigma * sigma / alpha) < 1e-13);
        }
        for u in [1e-9, 0.1, 0.5, 0.99] {
            assert!(rel(f.sample_surface(u), d.sample_surface(u)) < 1e-10);
            assert!(rel(f.sample_medium(u), d.sample_medium(u)) < 1e-10);
            if u >= 0.1 {
                // Independent closed form. `(1-u)^(-1/α) - 1` cancels to a
                // relative error ~ε α / ln(1/(1-u)), hence the α in the bound;
                // tiny u is covered by the round-trip test.
                let want = alpha / sigma * ((1.0 - u).powf(-1.0 / alpha) - 1.0);
                assert!(rel(d.sample_surface(u), want) < 1e-13 * (1.0 + alpha));
            }
        }
    }
}

/// Independent Davis–Weinstein formulas in optical depth (Bitterli 2018):
/// `α(τ) = τ^(2-2h)/c^(2h)`, `T = (1+τ/α)^(-α)`,
/// `T_sm(τ) = T (β/(1+τ/α) - (β-1)(α/τ) ln(1+τ/α))`, `β = 2h-1`,
/// against Fgf pink noise mapped by `h = H+1`, `c = S_p^(1/(2H+2))/σ_m`.
#[test]
fn davis_weinstein_matches_pink_mapping() {
    for &(sigma, hurst, sw) in &[
        (4.0, -0.1, 4.0),
        (2.0, -0.45, 10.0),
        (0.5, -0.25, 0.3),
        (7.0, -0.01, 1.0),
    ] {
        let f = Fgf::new(sigma, hurst, sw, None).unwrap();
        let h = hurst + 1.0;
        let c = s_p(hurst, sw).powf(1.0 / (2.0 * hurst + 2.0)) / sigma;
        let dw = DavisWeinstein::new(sigma, h, c).unwrap();
        let mapped = f.to_davis_weinstein().unwrap();
        assert!(rel(mapped.h(), h) < 1e-15 && rel(mapped.c(), c) < 1e-13);
        for t in [1e-4, 0.05, 0.3, 1.0, 3.0, 10.0] {
            let tau = sigma * t;
            let beta = 2.0 * h - 1.0;
            let alpha = tau.powf(2.0 - 2.0 * h) / c.powf(2.0 * h);
            let base = 1.0 + tau / alpha;
            let tr = base.powf(-alpha);
            let tsm_tau = tr * (beta / base - (beta - 1.0) * alpha / tau * base.ln());
            for (a, b) in [
                (f.tr(t), tr),
                (dw.tr(t), tr),
                (f.pdf(t), sigma * tsm_tau),
                (dw.pdf(t), sigma * tsm_tau),
                (f.medium_surface(t), tsm_tau),
                (f.medium_medium(t), dw.medium_medium(t)),
            ] {
                assert!(rel(a, b) < 1e-10, "H = {hurst}, t = {t}: {a} vs {b}");
            }
            // Fgf α(t) is the DW α(τ) at τ = σ t.
            assert!(rel(f.alpha(t), alpha) < 1e-10);
        }
        for u in [1e-9, 0.1, 0.5, 0.99] {
            assert!(rel(f.sample_surface(u), dw.sample_surface(u)) < 1e-10);
            assert!(rel(f.sample_medium(u), dw.sample_medium(u)) < 1e-10);
        }
    }
}

/// Samplers invert their cdfs: `1 - T_ss(sample_surface(u)) = u` and
/// `1 - T_ms(sample_medium(u)) = u`, checked in the tail form
/// `-ln T(t) = -ln(1-u)` to 1e-12 relative (the Newton tolerance gives
/// ~1e-15 on t).
#[test]
fn samplers_invert_their_cdfs() {
    for (name, m) in models() {
        for i in 0..=200 {
            let u = if i == 0 {
                1e-15
            } else {
                (i as f64 - 0.5) / 200.0
            };
            let y = -(-u).ln_1p();
            let t = m.sample_surface(u);
            assert!(t.is_finite() && t > 0.0, "{name}: u = {u} -> {t}");
            // |Δ(-ln T)| ≤ 1e-11 y + 4ε: T is rounded to ε near 1.
            let tol = 1e-11 * y + 4.0 * f64::EPSILON;
            assert!(
                (-m.tr(t).ln() - y).abs() < tol,
                "{name}: surface u = {u}: t = {t}"
            );
            let t = m.sample_medium(u);
            assert!(t.is_finite() && t > 0.0, "{name}: u = {u} -> {t}");
            let got = -m.medium_surface(t).ln();
            assert!((got - y).abs() < tol, "{name}: medium u = {u}: t = {t}");
        }
        assert_eq!(m.sample_surface(0.0), 0.0);
        assert_eq!(m.sample_medium(0.0), 0.0);
        let u_max = 1.0 - f64::EPSILON / 2.0;
        assert!(!m.sample_surface(u_max).is_nan() && !m.sample_medium(u_max).is_nan());
    }
}

/// No NaN anywhere over a grid of extreme but valid parameters, distances
/// and variates.
#[test]
fn no_nan_for_extreme_valid_inputs() {
    let mut ms: Vec<Model> = Vec::new();
    for &sigma in &[1e-8, 1e-3, 1.0, 1e3, 1e8] {
        ms.push(Exponential::new(sigma).unwrap().into());
        for &alpha in &[1e-12, 1e-3, 1.0, 1e3, 1e12] {
            ms.push(Davis::new(sigma, alpha).unwrap().into());
        }
        for &h in &[0.5, 0.5 + 1e-9, 0.6, 0.9, 1.0 - 1e-9, 1.0] {
            for &c in &[1e-6, 0.1, 1.0, 10.0, 1e6] {
                ms.push(DavisWeinstein::new(sigma, h, c).unwrap().into());
            }
        }
        for &hurst in &[
            -0.5, -0.4999, -0.3, -0.1, -1e-6, 1e-6, 0.5, 0.999, 1.5, 7.3, 999.5,
        ] {
            for &sw in &[1e-6, 1.0, 1e6] {
                let l = if hurst > 0.0 { Some(1.0) } else { None };
                ms.push(Fgf::new(sigma, hurst, sw, l).unwrap().into());
            }
        }
    }
    let t_over_mfp = [
        0.0,
        1e-300,
        1e-12,
        1e-3,
        1.0,
        30.0,
        1e6,
        1e200,
        f64::INFINITY,
    ];
    let us = [0.0, 1e-16, 1e-6, 0.5, 0.999999, 1.0 - f64::EPSILON / 2.0];
    for m in &ms {
        let mfp = 1.0 / m.sigma_t();
        for &s in &t_over_mfp {
            let t = s * mfp;
            for v in [m.tr(t), m.pdf(t), m.medium_surface(t), m.medium_medium(t)] {
                assert!(!v.is_nan() && v >= 0.0, "{m:?} at t = {t}: {v}");
            }
        }
        assert!(m.sigma_bar() >= 0.0 && m.sigma_bar().is_finite(), "{m:?}");
        for &u in &us {
            for v in [m.sample_surface(u), m.sample_medium(u)] {
                assert!(!v.is_nan() && v >= 0.0, "{m:?} at u = {u}: {v}");
            }
            // Round trip wherever the result is representable: t finite and
            // positive, T(t) not underflowed. 1e-9 (looser than the main
            // round-trip test) because the extreme branches (x < 1.5e-8,
            // ln x > 700) use truncated expansions.
            let y = -(-u).ln_1p();
            let tol = 1e-9 * y + 4.0 * f64::EPSILON;
            let t = m.sample_surface(u);
            if t.is_finite() && t > 0.0 && m.tr(t) > 1e-300 {
                let err = (-m.tr(t).ln() - y).abs();
                assert!(err <= tol, "{m:?} at u = {u}: t = {t}, err {err:e}");
            }
            let t = m.sample_medium(u);
            if t.is_finite() && t > 0.0 && m.medium_surface(t) > 1e-300 {
                let err = (-m.medium_surface(t).ln() - y).abs();
                assert!(err <= tol, "{m:?} medium at u = {u}: t = {t}, err {err:e}");
            }
        }
    }
}

#[test]
fn invalid_parameters_are_rejected_by_name() {
    let name = |e: fgf_core::ParamError| e.name;
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert_eq!(name(Exponential::new(bad).unwrap_err()), "sigma_t");
        assert_eq!(name(Fgf::new(bad, -0.1, 1.0, None).unwrap_err()), "sigma_t");
        assert_eq!(name(Fgf::new(1.0, -0.1, bad, None).unwrap_err()), "sw");
        assert_eq!(
            name(Fgf::new(1.0, 1.2, 1.0, Some(bad)).unwrap_err()),
            "length"
        );
        assert_eq!(name(Davis::new(bad, 1.0).unwrap_err()), "sigma_t");
        assert_eq!(name(Davis::new(1.0, bad).unwrap_err()), "alpha");
        assert_eq!(
            name(DavisWeinstein::new(bad, 0.8, 1.0).unwrap_err()),
            "sigma_t"
        );
        assert_eq!(name(DavisWeinstein::new(1.0, 0.8, bad).unwrap_err()), "c");
    }
    for bad_h in [0.0, 1.0, 2.0, -0.51, f64::NAN] {
        assert_eq!(
            name(Fgf::new(1.0, bad_h, 1.0, Some(1.0)).unwrap_err()),
            "hurst"
        );
    }
    for bad_h in [0.49, 1.01, f64::NAN, -1.0] {
        assert_eq!(name(DavisWeinstein::new(1.0, bad_h, 1.0).unwrap_err()), "h");
    }
    // length is required for k-fBm and refused for white/pink.
    assert_eq!(name(Fgf::new(1.0, 1.2, 1.0, None).unwrap_err()), "length");
    assert_eq!(
        name(Fgf::new(1.0, -0.1, 1.0, Some(1.0)).unwrap_err()),
        "length"
    );
    // Messages name the valid range.
    let msg = Fgf::new(1.0, 0.0, 1.0, None).unwrap_err().to_string();
    assert!(msg.contains("hurst") && msg.contains("valid:"), "{msg}");
    let msg = DavisWeinstein::new(1.0, 1.5, 1.0).unwrap_err().to_string();
    assert!(msg.contains("0.5 <= h <= 1"), "{msg}");
    // Mappings refuse the wrong regime.
    assert!(Fgf::new(1.0, -0.1, 1.0, None).unwrap().to_davis().is_err());
    assert!(Fgf::new(1.0, 1.2, 1.0, Some(1.0))
        .unwrap()
        .to_davis_weinstein()
        .is_err());
}

#[test]
fn models_are_copy_and_small() {
    fn is_copy<T: Copy>() {}
    is_copy::<Model>();
    // The pink samplers' fitted starting points dominate: 14 f64 coefficients
    // for surface starts (`StartGuess`) and 12 f32 for medium starts
    // (`MediumGuess`); the model sits exactly at 256 bytes. The renderer keeps one `Model`
    // per channel, so a few hundred bytes is fine, a heap table would not be.
    let size = std::mem::size_of::<Model>();
    assert!(size <= 256, "size_of::<Model>() = {size}");
}
