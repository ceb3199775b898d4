//! The loader's rough and coated BSDFs and the envmap: Mitsuba's defaults,
//! and one-line refusals of what is not supported.

use fgf_scene::{
    load_str, BsdfDesc, EmitterDesc, MicrofacetDesc, MicrofacetKind, SceneDesc, TexturedParam,
};
use std::path::Path;

fn load(body: &str) -> Result<SceneDesc, String> {
    let xml = format!("<scene version=\"3.0.0\">\n{body}\n</scene>\n");
    load_str(&xml, "test.xml", Path::new("."), &[]).map_err(|e| e.to_string())
}

fn bsdf(xml: &str) -> BsdfDesc {
    let s = load(&format!("<shape type=\"sphere\">{xml}</shape>")).unwrap();
    s.bsdfs[s.shapes[0].bsdf].clone()
}

#[test]
fn rough_defaults_are_mitsubas() {
    let beckmann = MicrofacetDesc {
        kind: MicrofacetKind::Beckmann,
        alpha_u: 0.1,
        alpha_v: 0.1,
        sample_visible: true,
    };
    match bsdf(r#"<bsdf type="roughdielectric"/>"#) {
        BsdfDesc::RoughDielectric {
            int_ior,
            ext_ior,
            microfacet,
            ..
        } => {
            assert_eq!((int_ior, ext_ior), (1.5046, 1.000277));
            assert_eq!(microfacet, beckmann);
        }
        d => panic!("{d:?}"),
    }
    assert!(matches!(
        bsdf(r#"<bsdf type="plastic"/>"#),
        BsdfDesc::Plastic {
            microfacet: None,
            ..
        }
    ));
    match bsdf(r#"<bsdf type="roughplastic"><boolean name="nonlinear" value="true"/></bsdf>"#) {
        BsdfDesc::Plastic {
            int_ior,
            ext_ior,
            nonlinear,
            microfacet,
            ..
        } => {
            assert_eq!((int_ior, ext_ior), (1.49, 1.000277));
            assert!(nonlinear);
            assert_eq!(microfacet, Some(beckmann));
        }
        d => panic!("{d:?}"),
    }
    assert!(matches!(
        bsdf(r#"<bsdf type="roughconductor"><string name="material" value="Au"/></bsdf>"#),
        BsdfDesc::RoughConductor {
            perfect_mirror: false,
            ..
        }
    ));
    assert!(matches!(
        bsdf(r#"<bsdf type="thindielectric"/>"#),
        BsdfDesc::ThinDielectric { .. }
    ));
}

/// `alpha_u`/`alpha_v` (floats or textures): the roughness along the
/// tangent and across it.
#[test]
fn anisotropic_roughness() {
    match bsdf(
        r#"<bsdf type="roughdielectric"><float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.3"/></bsdf>"#,
    ) {
        BsdfDesc::RoughDielectric { microfacet: m, .. } => {
            assert_eq!((m.alpha_u, m.alpha_v), (0.1, 0.3));
        }
        other => panic!("{other:?}"),
    }
    match bsdf(
        r#"<bsdf type="roughconductor"><float name="alpha_u" value="0.2"/><texture type="checkerboard" name="alpha_v"><float name="color0" value="0.1"/><float name="color1" value="0.3"/></texture></bsdf>"#,
    ) {
        BsdfDesc::Textured { base, textures } => {
            assert!(matches!(*base, BsdfDesc::RoughConductor { .. }));
            assert_eq!(textures.len(), 1);
            assert_eq!(textures[0].0, TexturedParam::AlphaV);
        }
        other => panic!("{other:?}"),
    }
}

/// A conductor's `eta`/`k` from textures: not a perfect mirror, and not
/// together with `material`.
#[test]
fn textured_conductor_eta_k() {
    match bsdf(
        r#"<bsdf type="conductor"><texture type="checkerboard" name="k"><float name="color0" value="0.5"/><float name="color1" value="1"/></texture></bsdf>"#,
    ) {
        BsdfDesc::Textured { base, textures } => {
            assert!(matches!(
                *base,
                BsdfDesc::Conductor {
                    perfect_mirror: false,
                    ..
                }
            ));
            assert_eq!(textures[0].0, TexturedParam::K);
        }
        other => panic!("{other:?}"),
    }
    let e = load(r#"<shape type="sphere"><bsdf type="roughconductor"><string name="material" value="Au"/><texture type="checkerboard" name="eta"/></bsdf></shape>"#).unwrap_err();
    assert!(e.contains("not both"), "{e}");
}

#[test]
fn refusals_name_the_parameter() {
    let e = load(r#"<shape type="sphere"><bsdf type="roughconductor"><float name="alpha_u" value="0.1"/></bsdf></shape>"#).unwrap_err();
    assert!(e.contains("give both 'alpha_u' and 'alpha_v'"), "{e}");
    let e = load(r#"<shape type="sphere"><bsdf type="roughconductor"><float name="alpha" value="0.1"/><float name="alpha_v" value="0.3"/></bsdf></shape>"#).unwrap_err();
    assert!(e.contains("not both"), "{e}");
    let e = load(r#"<shape type="sphere"><bsdf type="roughdielectric"><float name="alpha" value="0"/></bsdf></shape>"#).unwrap_err();
    assert!(e.contains("invalid alpha = 0"), "{e}");
    let e = load(r#"<shape type="sphere"><bsdf type="roughconductor"><string name="distribution" value="phong"/></bsdf></shape>"#).unwrap_err();
    assert!(
        e.contains("invalid distribution = 'phong' (valid: beckmann, ggx)"),
        "{e}"
    );
    let e = load(r#"<shape type="sphere"><bsdf type="roughplastic"><float name="alpha_u" value="0.2"/></bsdf></shape>"#).unwrap_err();
    assert!(e.contains("alpha_u"), "{e}");
    assert_eq!(e.lines().count(), 1, "{e}");
    let e = load(r#"<emitter type="envmap"><string name="filename" value="sky.png"/></emitter>"#)
        .unwrap_err();
    assert!(
        e.contains("only OpenEXR (.exr) and Radiance RGBE (.hdr)"),
        "{e}"
    );
    let e =
        load(r#"<emitter type="envmap"><string name="filename" value="missing.exr"/></emitter>"#)
            .unwrap_err();
    assert!(e.contains("cannot read envmap image"), "{e}");
}

#[test]
fn envmap_reads_an_exr_and_applies_scale() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sky.exr");
    let (w, h) = (4usize, 3usize);
    let data: Vec<f32> = (0..w * h * 3).map(|i| i as f32 * 0.1).collect();
    fgf_io::image::write_exr(&path, w, h, 3, &data).unwrap();
    let xml = r#"<scene version="3.0.0"><emitter type="envmap"><string name="filename" value="sky.exr"/><float name="scale" value="2"/></emitter></scene>"#;
    let s = load_str(xml, "test.xml", dir.path(), &[]).unwrap();
    match &s.emitters[0] {
        EmitterDesc::Envmap { image, .. } => {
            assert_eq!((image.width, image.height), (w, h));
            for (a, b) in image.data.iter().zip(&data) {
                assert!((a - 2.0 * b).abs() < 1e-5);
            }
        }
        e => panic!("{e:?}"),
    }
}
