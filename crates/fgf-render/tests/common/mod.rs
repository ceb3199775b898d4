//! Helpers shared by the renderer's integration tests: scenes from XML
//! snippets, the reference scenes, `<medium>` snippets and the z-test of a
//! Monte Carlo estimate. Each test file uses a subset.
#![allow(dead_code)]

use fgf_scene::SceneDesc;

/// A scene from its XML text (relative paths against the working directory).
pub fn load_xml(xml: &str) -> SceneDesc {
    fgf_scene::load_str(xml, "test.xml", std::path::Path::new("."), &[])
        .unwrap_or_else(|e| panic!("{e}\n{xml}"))
}

/// A reference scene with its `res` and `spp` defaults overridden.
pub fn reference_scene(name: &str, res: u32, spp: u32) -> SceneDesc {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes/reference")
        .join(name);
    let defines = [
        ("res".to_string(), res.to_string()),
        ("spp".to_string(), spp.to_string()),
    ];
    fgf_scene::load_file(&path, &defines).unwrap_or_else(|e| panic!("{e}"))
}

/// The small side light of the reference cube scenes (an area emitter of
/// radiance 150 on a black rectangle).
pub const SIDE_LIGHT: &str = r#"<shape type="rectangle">
        <transform name="to_world"><matrix value="-0.0490290338 0.107919143 0.880450906 -2.5 0 0.224471818 -0.440225453 2 -0.245145169 -0.0215838286 -0.176090181 0.5 0 0 0 1"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
        <emitter type="area"><rgb name="radiance" value="150.0"/></emitter>
    </shape>"#;

/// A uniform white environment of radiance 1.
pub const WHITE_SKY: &str =
    r#"<emitter type="constant"><rgb name="radiance" value="1"/></emitter>"#;

/// The reference cube scene in small: a cube (`scale` is the attribute
/// list of its `<scale>`, e.g. `value="0.5"`) holding `medium` as its
/// interior behind a null boundary, over a diffuse ground, lit by `lights`,
/// seen on a `res`² box-filtered film with `spp` samples per pixel.
pub fn cube_on_ground(
    medium: &str,
    scale: &str,
    lights: &str,
    max_depth: i32,
    res: u32,
    spp: u32,
) -> SceneDesc {
    load_xml(&format!(
        r#"<scene version="3.0.0">
    <integrator type="volpath"><integer name="max_depth" value="{max_depth}"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="40.0"/>
        <transform name="to_world"><lookat origin="0.0, 1.6, 4.0" target="0.0, 0.6, 0.0" up="0.0, 1.0, 0.0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>
        <film type="hdrfilm"><integer name="width" value="{res}"/><integer name="height" value="{res}"/><rfilter type="box"/></film>
    </sensor>
    <shape type="cube">
        <transform name="to_world"><scale {scale}/><translate value="0.0, 0.75, 0.0"/></transform>
        <bsdf type="null"/>
        {medium}
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale value="4.0"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf>
    </shape>
    {lights}
</scene>"#
    ))
}

/// A `<medium>` of plugin `ty` with the parameters `params` (XML), the
/// given `sigma_t` and `albedo` (rgb values) and `kernel`, and `attrs`
/// (`name="interior"` or `id="m"`).
pub fn medium_xml(
    ty: &str,
    params: &str,
    sigma_t: &str,
    albedo: &str,
    kernel: &str,
    attrs: &str,
) -> String {
    format!(
        r#"<medium type="{ty}" {attrs}>{params}<rgb name="sigma_t" value="{sigma_t}"/><rgb name="albedo" value="{albedo}"/><string name="kernel" value="{kernel}"/></medium>"#
    )
}

/// Per channel, `|got - expected| ≤ z·SE`, plus `1e-5·max(|expected|,
/// 1e-3)` for the f32 rounding of an estimate whose samples are all equal
/// (SE 0).
pub fn assert_close(label: &str, got: [f64; 3], se: [f64; 3], expected: [f64; 3], z: f64) {
    for c in 0..3 {
        let err = (got[c] - expected[c]).abs();
        let tol = z * se[c] + 1e-5 * expected[c].abs().max(1e-3);
        assert!(
            err <= tol,
            "{label}, channel {c}: {} vs expected {} (SE {}, z = {:.2})",
            got[c],
            expected[c],
            se[c],
            err / se[c]
        );
    }
}
