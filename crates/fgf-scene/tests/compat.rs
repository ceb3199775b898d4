//! Mitsuba 3 compatibility of the loader: file lookup (`<path>`, includes),
//! the upgrade of old scene versions, and the parameters Mitsuba accepts
//! that the subset takes with Mitsuba's meaning. The images are compared
//! with the `mitsuba` package in `tests/test_compat*.py`.

mod common;

use common::has;
use fgf_scene::*;
use std::fs;
use std::path::Path;

fn write(dir: &Path, name: &str, text: &str) {
    let p = dir.join(name);
    fs::create_dir_all(p.parent().unwrap()).unwrap();
    fs::write(p, text).unwrap();
}

const QUAD_OBJ: &str = "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3 4\n";

#[test]
fn path_element_adds_a_search_directory_for_meshes_and_includes() {
    let t = tempfile::tempdir().unwrap();
    write(t.path(), "assets/meshes/quad.obj", QUAD_OBJ);
    write(
        t.path(),
        "assets/bsdfs.xml",
        r#"<scene version="3.0.0"><bsdf type="diffuse" id="grey"><rgb name="reflectance" value="0.25"/></bsdf></scene>"#,
    );
    write(
        t.path(),
        "scene.xml",
        r#"<scene version="3.0.0">
    <path value="assets"/>
    <path value="assets/meshes"/>
    <include filename="bsdfs.xml"/>
    <shape type="obj"><string name="filename" value="quad.obj"/><ref id="grey"/></shape>
</scene>"#,
    );
    let s = load_file(&t.path().join("scene.xml"), &[]).unwrap();
    assert_eq!(s.shapes.len(), 1);
    assert_eq!(
        s.bsdfs[s.shapes[0].bsdf],
        BsdfDesc::Diffuse {
            reflectance: [0.25; 3]
        }
    );
}

#[test]
fn mesh_in_an_included_file_is_found_relative_to_the_scene_directory() {
    // Mitsuba resolves a mesh named in an included file against the
    // scene's directory (its file resolver), not the included file's.
    let t = tempfile::tempdir().unwrap();
    write(t.path(), "meshes/quad.obj", QUAD_OBJ);
    write(
        t.path(),
        "parts/geometry.xml",
        r#"<scene version="3.0.0"><shape type="obj"><string name="filename" value="meshes/quad.obj"/></shape></scene>"#,
    );
    write(
        t.path(),
        "scene.xml",
        r#"<scene version="3.0.0"><include filename="parts/geometry.xml"/></scene>"#,
    );
    let s = load_file(&t.path().join("scene.xml"), &[]).unwrap();
    assert_eq!(s.shapes.len(), 1);
}

#[test]
fn missing_path_directory_is_one_line_naming_it() {
    let t = tempfile::tempdir().unwrap();
    write(
        t.path(),
        "scene.xml",
        "<scene version=\"3.0.0\">\n<path value=\"nowhere\"/>\n</scene>",
    );
    let m = load_file(&t.path().join("scene.xml"), &[])
        .unwrap_err()
        .to_string();
    has(&m, &["scene.xml:2:", "<path>", "nowhere", "not found"]);
    assert!(!m.contains('\n'));
}

#[test]
fn path_is_only_allowed_at_the_top_level() {
    let m = load_str(
        "<scene version=\"3.0.0\"><shape type=\"cube\"><path value=\".\"/></shape></scene>",
        "p.xml",
        Path::new("."),
        &[],
    )
    .unwrap_err()
    .to_string();
    has(&m, &["<path> is only allowed directly inside <scene>"]);
}

#[test]
fn camel_case_names_of_pre_2_0_scenes_are_upgraded() {
    let xml = r#"<scene version="0.6.0">
    <integrator type="path"><integer name="maxDepth" value="3"/></integrator>
    <shape type="sphere">
        <bsdf type="dielectric"><float name="intIOR" value="1.3"/></bsdf>
    </shape>
    <shape type="cube">
        <transform name="toWorld"><translate x="3"/></transform>
        <bsdf type="diffuse"><rgb name="diffuseReflectance" value="0.2"/></bsdf>
    </shape>
</scene>"#;
    let s = load_str(xml, "v1.xml", Path::new("."), &[]).unwrap();
    assert_eq!(s.integrator.max_depth, 3);
    match &s.bsdfs[s.shapes[0].bsdf] {
        BsdfDesc::Dielectric { int_ior, .. } => assert!((int_ior - 1.3).abs() < 1e-6),
        b => panic!("{b:?}"),
    }
    assert_eq!(
        s.bsdfs[s.shapes[1].bsdf],
        BsdfDesc::Diffuse {
            reflectance: [0.2; 3]
        }
    );
    assert_eq!(s.shapes[1].to_world.w_axis.x, 3.0);
}

#[test]
fn version_2_scenes_load_as_written() {
    // Mitsuba 3 reads 2.x files unchanged: snake_case names load, and a
    // camelCase name is an unknown parameter, as in Mitsuba.
    let ok = r#"<scene version="2.1.0"><integrator type="path"><integer name="max_depth" value="2"/></integrator></scene>"#;
    assert_eq!(
        load_str(ok, "v2.xml", Path::new("."), &[])
            .unwrap()
            .integrator
            .max_depth,
        2
    );
    let bad = r#"<scene version="2.0.0"><integrator type="path"><integer name="maxDepth" value="2"/></integrator></scene>"#;
    let m = load_str(bad, "v2.xml", Path::new("."), &[])
        .unwrap_err()
        .to_string();
    has(&m, &["unknown parameter 'maxDepth'"]);
}

#[test]
fn invalid_version_is_an_error() {
    let m = load_str("<scene version=\"three\"/>", "v.xml", Path::new("."), &[])
        .unwrap_err()
        .to_string();
    has(&m, &["invalid version number \"three\""]);
}
