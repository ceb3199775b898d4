//! The explicit-realization ensemble (`fgf_render::ensemble`): grid
//! placement, the limit `S_w → 0` (the realizations become the homogeneous
//! medium), and clear errors for what it cannot realise.

mod common;

use common::{cube_on_ground, medium_xml, WHITE_SKY};
use fgf_render::ensemble::{ensemble, EnsembleError, EnsembleOptions};
use fgf_render::{render, RenderError, RenderOptions};
use fgf_scene::SceneDesc;

/// The reference cube (scaled by `scale`) holding `medium`, under a white
/// sky, on a 16² film with 8 samples per pixel.
fn scene(medium: &str, scale: &str) -> SceneDesc {
    cube_on_ground(medium, scale, WHITE_SKY, 8, 16, 8)
}

fn fgf_medium(hurst: f64, sw: f64) -> String {
    let params = format!(r#"<float name="hurst" value="{hurst}"/><float name="sw" value="{sw}"/>"#);
    medium_xml(
        "fgf",
        &params,
        "4",
        "0.8",
        "energy_conserving",
        r#"name="interior""#,
    )
}

#[test]
fn grid_covers_the_medium_box_with_cubic_voxels() {
    let sc = scene(&fgf_medium(-0.2, 1.0), r#"x="0.5" y="0.25" z="1""#);
    let opts = EnsembleOptions {
        realizations: 2,
        resolution: 16,
        spp: Some(1),
        seed: 0,
        ..Default::default()
    };
    let out = ensemble(&sc, &opts, &fgf_core::NoProgress).unwrap();
    let m = &out.media[0];
    assert_eq!(m.shape, [8, 4, 16]);
    assert!((m.spacing - 2.0 / 16.0).abs() < 1e-12);
    let expected = [-0.5, 0.5, -1.0, 0.5, 1.0, 1.0];
    for (got, want) in m.bbox.iter().zip(expected) {
        assert!((got - want).abs() < 1e-9, "{:?}", m.bbox);
    }
    assert_eq!(out.realizations_done, 2);
    assert!(out.stderr.iter().all(|v| v.is_finite()));
}

/// With a vanishing `S_w` every realization is the homogeneous medium, so
/// the ensemble mean equals the homogeneous render: the image means agree
/// within z = 4.5 times the sum of their standard errors (each the sum of
/// per-pixel SEs / pixel count, a conservative bound for correlated
/// pixels); 1 comparison. No value is clamped.
#[test]
fn vanishing_sw_ensemble_equals_homogeneous() {
    let sc = scene(&fgf_medium(-0.2, 1e-8), r#"value="0.5""#);
    let opts = EnsembleOptions {
        realizations: 8,
        resolution: 16,
        spp: Some(8),
        seed: 1,
        ..Default::default()
    };
    let out = ensemble(&sc, &opts, &fgf_core::NoProgress).unwrap();
    assert_eq!(out.media[0].clamped_fraction, 0.0);
    let hom = scene(
        r#"<medium type="homogeneous" name="interior"><float name="sigma_t" value="4"/><rgb name="albedo" value="0.8"/></medium>"#,
        r#"value="0.5""#,
    );
    let r = render(
        &hom,
        &RenderOptions {
            spp: Some(64),
            seed: Some(2),
            variance: true,
            ..Default::default()
        },
        &fgf_core::NoProgress,
    )
    .unwrap();
    let n = out.mean.len() as f64;
    let mean_e = out.mean.iter().map(|&v| v as f64).sum::<f64>() / n;
    let mean_h = r.image.iter().map(|&v| v as f64).sum::<f64>() / n;
    let se_e = out.stderr.iter().map(|&v| v as f64).sum::<f64>() / n;
    let se_h = r
        .variance
        .unwrap()
        .iter()
        .map(|&v| (v as f64).sqrt())
        .sum::<f64>()
        / n;
    eprintln!("ensemble {mean_e:.5} ± {se_e:.5}, homogeneous {mean_h:.5} ± {se_h:.5}");
    assert!((mean_e - mean_h).abs() <= 4.5 * (se_e + se_h));
}

#[test]
fn what_cannot_be_realised_is_a_clear_error() {
    let opts = EnsembleOptions {
        realizations: 1,
        resolution: 8,
        spp: Some(1),
        seed: 0,
        ..Default::default()
    };
    let davis = scene(
        r#"<medium type="nonexponential" name="interior"><string name="transmittance" value="davis"/><float name="alpha" value="2"/></medium>"#,
        r#"value="0.5""#,
    );
    let e = ensemble(&davis, &opts, &fgf_core::NoProgress).unwrap_err();
    assert!(
        matches!(e, EnsembleError::Render(RenderError::Unsupported(_)))
            && e.to_string().contains("nonexponential"),
        "{e}"
    );
    let white = scene(&fgf_medium(-0.5, 1.0), r#"value="0.5""#);
    let e = ensemble(&white, &opts, &fgf_core::NoProgress).unwrap_err();
    assert!(e.to_string().contains("white noise"), "{e}");
    let none = scene(
        r#"<medium type="homogeneous" name="interior"/>"#,
        r#"value="0.5""#,
    );
    let e = ensemble(&none, &opts, &fgf_core::NoProgress).unwrap_err();
    assert!(e.to_string().contains("no 'fgf' medium"), "{e}");
    let zero = EnsembleOptions {
        realizations: 0,
        ..opts.clone()
    };
    assert!(matches!(
        ensemble(&white, &zero, &fgf_core::NoProgress),
        Err(EnsembleError::Render(RenderError::InvalidOption(_)))
    ));
}
