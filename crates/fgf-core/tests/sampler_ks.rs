//! Kolmogorov–Smirnov tests of the free-flight samplers against their exact
//! cdfs, `1 - T_ss` (`sample_surface`) and `1 - T_ms` (`sample_medium`),
//! for every model kind and regime.
//!
//! Significance: each test rejects at p < 1e-4; with the 30 (model,
//! sampler) pairs of one run, the family-wise false-alarm rate is at most
//! 0.3% (Bonferroni). Seeds are fixed, so a run is deterministic.
//! The fast test uses 10^5 samples per pair; the `#[ignore]`d one (slow
//! step) 2·10^6, which detects cdf errors down to about 1.5e-3.

mod common;

use common::{ks_p_value, ks_statistic};
use fgf_core::transmittance::{Davis, DavisWeinstein, Exponential, Fgf, Model, Transmittance};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

const P_REJECT: f64 = 1e-4;

fn models() -> Vec<(&'static str, Model)> {
    vec![
        ("exponential", Exponential::new(4.0).unwrap().into()),
        ("white", Fgf::new(4.0, -0.5, 4.0, None).unwrap().into()),
        ("pink -0.1", Fgf::new(4.0, -0.1, 4.0, None).unwrap().into()),
        ("pink -0.4", Fgf::new(2.0, -0.4, 10.0, None).unwrap().into()),
        (
            "pink -0.02",
            Fgf::new(1.0, -0.02, 3.0, None).unwrap().into(),
        ),
        ("1-fBm", Fgf::new(4.0, 0.2, 4.0, Some(1.0)).unwrap().into()),
        ("2-fBm", Fgf::new(4.0, 1.2, 34.0, Some(1.0)).unwrap().into()),
        ("davis 4", Davis::new(4.0, 4.0).unwrap().into()),
        ("davis 0.5", Davis::new(1.0, 0.5).unwrap().into()),
        (
            "dw 0.9",
            DavisWeinstein::new(4.0, 0.9, 0.78).unwrap().into(),
        ),
        (
            "dw 0.55",
            DavisWeinstein::new(2.0, 0.55, 2.0).unwrap().into(),
        ),
        (
            "dw 0.5",
            DavisWeinstein::new(4.0, 0.5, 0.78).unwrap().into(),
        ),
        ("dw 1", DavisWeinstein::new(4.0, 1.0, 0.78).unwrap().into()),
        (
            "dw 0.99 c5",
            DavisWeinstein::new(0.5, 0.99, 5.0).unwrap().into(),
        ),
        (
            "dw 0.7 c0.01",
            DavisWeinstein::new(3.0, 0.7, 0.01).unwrap().into(),
        ),
    ]
}

fn run(n: usize, seed: u64) {
    let mut failures = Vec::new();
    for (i, (name, m)) in models().into_iter().enumerate() {
        for medium in [false, true] {
            let mut rng = Pcg64::seed_from_u64(seed + 2 * i as u64 + medium as u64);
            let mut xs: Vec<f64> = (0..n)
                .map(|_| {
                    let u: f64 = rng.random();
                    if medium {
                        m.sample_medium(u)
                    } else {
                        m.sample_surface(u)
                    }
                })
                .collect();
            assert!(xs.iter().all(|x| x.is_finite() && *x >= 0.0), "{name}");
            let d = if medium {
                ks_statistic(&mut xs, |t| 1.0 - m.medium_surface(t))
            } else {
                ks_statistic(&mut xs, |t| 1.0 - m.tr(t))
            };
            let p = ks_p_value(d, n);
            if p < P_REJECT {
                failures.push(format!(
                    "{name} (medium = {medium}): D = {d:.3e}, p = {p:.2e}"
                ));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "KS rejections at p < {P_REJECT}: {failures:#?}"
    );
}

/// Power check: the same machinery must reject a wrong target, here pink
/// surface samples against the medium cdf `1 - T_ms` (a different law).
#[test]
fn ks_rejects_a_wrong_cdf() {
    let m: Model = Fgf::new(4.0, -0.1, 4.0, None).unwrap().into();
    let mut rng = Pcg64::seed_from_u64(1);
    let mut xs: Vec<f64> = (0..100_000)
        .map(|_| m.sample_surface(rng.random()))
        .collect();
    let d = ks_statistic(&mut xs, |t| 1.0 - m.medium_surface(t));
    assert!(ks_p_value(d, xs.len()) < 1e-10, "D = {d}");
}

#[test]
fn samplers_pass_ks_against_exact_cdfs() {
    run(100_000, 20190701);
}

#[test]
#[ignore = "slow statistical test: run with --ignored in release mode"]
fn samplers_pass_ks_against_exact_cdfs_large() {
    run(2_000_000, 7);
}
