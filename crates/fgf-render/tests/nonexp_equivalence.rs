//! The `fgf` medium against its closed-form equivalents (`docs/theory.md` §3):
//! k-fBm is Davis with `α = σ_m²/(S_kf L^(2H))`, pink noise is
//! Davis–Weinstein with `h = H+1`, `c = S_p^(1/(2H+2))/σ_m`, white noise is
//! `homogeneous` with `σ_eff`. With the same seed the renders consume the
//! same random numbers, so they agree pixel for pixel up to float rounding
//! of the model parameters (a few ulps in `α`, `c`), which can flip a rare
//! sample; the tests allow that rounding and nothing more. And `S_w → 0`
//! converges to the classical `homogeneous` render.

mod common;

use common::{cube_on_ground, medium_xml, SIDE_LIGHT};
use fgf_core::transmittance::Fgf;
use fgf_render::{render, RenderOptions, RenderOutput};
use fgf_scene::SceneDesc;

/// The reference cube scene in small (a 24² film, 16 samples per pixel).
fn scene(medium: &str) -> SceneDesc {
    cube_on_ground(medium, r#"value="0.5""#, SIDE_LIGHT, 16, 24, 16)
}

fn run(medium: &str) -> RenderOutput {
    let opts = RenderOptions {
        seed: Some(11),
        variance: true,
        ..Default::default()
    };
    render(&scene(medium), &opts, &fgf_core::NoProgress).unwrap()
}

fn medium(ty: &str, sigma_t: &str, kernel: &str, params: &str) -> String {
    medium_xml(ty, params, sigma_t, "0.8", kernel, r#"name="interior""#)
}

/// Pixel-for-pixel agreement: at least 97% of the values agree to 1e-3
/// relative (the rest are samples flipped by parameter rounding), and the
/// image means agree to 1e-3.
fn assert_same(label: &str, a: &RenderOutput, b: &RenderOutput) {
    let n = a.image.len();
    let close = a
        .image
        .iter()
        .zip(&b.image)
        .filter(|(x, y)| (*x - *y).abs() <= 1e-3 * x.abs().max(y.abs()).max(1e-3))
        .count();
    let (ma, mb) = (
        a.image.iter().map(|&v| v as f64).sum::<f64>() / n as f64,
        b.image.iter().map(|&v| v as f64).sum::<f64>() / n as f64,
    );
    eprintln!("{label}: {close}/{n} values equal to 1e-3, image means {ma:.6} vs {mb:.6}");
    assert!(
        close as f64 >= 0.97 * n as f64,
        "{label}: only {close}/{n} values agree"
    );
    assert!(
        (ma - mb).abs() <= 1e-3 * ma.abs(),
        "{label}: means {ma} vs {mb}"
    );
}

#[test]
fn kfbm_equals_davis_with_the_mapped_alpha() {
    for kernel in ["energy_conserving", "reciprocal"] {
        for (hurst, sw) in [(0.2, 4.0), (1.2, 34.0)] {
            let fgf = run(&medium(
                "fgf",
                "4",
                kernel,
                &format!(
                    r#"<float name="hurst" value="{hurst}"/><float name="sw" value="{sw}"/><float name="length" value="1.5"/>"#
                ),
            ));
            let alpha = Fgf::new(4.0, hurst, sw, Some(1.5))
                .unwrap()
                .to_davis()
                .unwrap()
                .alpha();
            let davis = run(&medium(
                "nonexponential",
                "4",
                kernel,
                &format!(
                    r#"<string name="transmittance" value="davis"/><float name="alpha" value="{alpha:.17e}"/>"#
                ),
            ));
            assert_same(
                &format!("k-fBm H={hurst} vs davis alpha={alpha} ({kernel})"),
                &fgf,
                &davis,
            );
        }
    }
}

#[test]
fn pink_equals_davis_weinstein_with_the_mapped_h_and_c() {
    for kernel in ["energy_conserving", "reciprocal"] {
        for (hurst, sw) in [(-0.1, 4.0), (-0.35, 2.0)] {
            let fgf = run(&medium(
                "fgf",
                "4",
                kernel,
                &format!(r#"<float name="hurst" value="{hurst}"/><float name="sw" value="{sw}"/>"#),
            ));
            let dw = Fgf::new(4.0, hurst, sw, None)
                .unwrap()
                .to_davis_weinstein()
                .unwrap();
            let other = run(&medium(
                "nonexponential",
                "4",
                kernel,
                &format!(
                    r#"<string name="transmittance" value="davis_weinstein"/><float name="h" value="{:.17e}"/><float name="c" value="{:.17e}"/>"#,
                    dw.h(),
                    dw.c()
                ),
            ));
            assert_same(
                &format!("pink H={hurst} vs davis_weinstein ({kernel})"),
                &fgf,
                &other,
            );
        }
    }
}

#[test]
fn white_noise_equals_homogeneous_with_sigma_eff() {
    let (sigma, sw) = (4.0f64, 3.0f64);
    let sigma_eff = sigma * sigma / sw * (sw / sigma).ln_1p();
    let homogeneous = run(&format!(
        r#"<medium type="homogeneous" name="interior"><float name="sigma_t" value="{sigma_eff:.9}"/><rgb name="albedo" value="0.8"/></medium>"#
    ));
    for kernel in ["energy_conserving", "reciprocal"] {
        let white = run(&medium(
            "fgf",
            &sigma.to_string(),
            kernel,
            &format!(r#"<float name="hurst" value="-0.5"/><float name="sw" value="{sw}"/>"#),
        ));
        assert_same(
            &format!("white vs homogeneous sigma_eff={sigma_eff} ({kernel})"),
            &white,
            &homogeneous,
        );
    }
}

/// `S_w → 0`: the gamma closure tends to the exponential, so the `fgf`
/// render tends to the `homogeneous` one with `σ_m`. The mean absolute
/// pixel difference must shrink as `S_w` decreases, and at `S_w = 1e-6`
/// every value must agree within z · (SE₁ + SE₂), the sum of the two
/// renders' standard errors (a conservative bound on the SE of their
/// difference, whatever their correlation through the shared seed):
/// z = 4.5 over 24·24·3 = 1728 values for each of 4 (model, kernel) cases,
/// family error rate < 0.05.
#[test]
fn vanishing_sw_converges_to_homogeneous() {
    let reference = run(
        r#"<medium type="homogeneous" name="interior"><rgb name="sigma_t" value="1, 2, 4"/><rgb name="albedo" value="0.8"/></medium>"#,
    );
    for kernel in ["energy_conserving", "reciprocal"] {
        for (hurst, length) in [(-0.1, ""), (1.2, r#"<float name="length" value="1.5"/>"#)] {
            let mut last = f64::INFINITY;
            for sw in [1.0, 1e-2, 1e-4, 1e-6] {
                let img = run(&medium(
                    "fgf",
                    "1, 2, 4",
                    kernel,
                    &format!(
                        r#"<float name="hurst" value="{hurst}"/><float name="sw" value="{sw}"/>{length}"#
                    ),
                ));
                let n = img.image.len();
                let diff = img
                    .image
                    .iter()
                    .zip(&reference.image)
                    .map(|(a, b)| (*a - *b).abs() as f64)
                    .sum::<f64>()
                    / n as f64;
                eprintln!("H={hurst} sw={sw} ({kernel}): mean |fgf - homogeneous| = {diff:.3e}");
                assert!(
                    diff <= last,
                    "H={hurst} {kernel}: the difference grew at sw={sw}: {diff} > {last}"
                );
                last = diff;
                if sw == 1e-6 {
                    let var = img.variance.as_ref().unwrap();
                    let rvar = reference.variance.as_ref().unwrap();
                    for i in 0..n {
                        let se = (var[i] as f64).sqrt() + (rvar[i] as f64).sqrt();
                        let d = (img.image[i] - reference.image[i]).abs() as f64;
                        assert!(
                            d <= 4.5 * se + 1e-5,
                            "H={hurst} {kernel} value {i}: {} vs {} (SE {se})",
                            img.image[i],
                            reference.image[i]
                        );
                    }
                }
            }
        }
    }
}
