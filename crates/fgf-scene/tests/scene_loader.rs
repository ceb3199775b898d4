//! The Mitsuba 3 XML loader: the reference scenes, the subset's semantics
//! (defaults, overrides, includes, references, transform order, Mitsuba's
//! default values) and one test per class of malformed input, each asserting
//! the message names the file, the line and the parameter.

mod common;

use common::{data_dir, has, meshes_dir, reference_scene};
use fgf_scene::*;
use glam::{Mat4, Vec3, Vec4};
use std::path::Path;

/// Wrap `body` in a `<scene>` whose first body line is line 2.
fn wrap(body: &str) -> String {
    format!("<scene version=\"3.0.0\">\n{body}\n</scene>\n")
}

fn load(body: &str) -> Result<SceneDesc, SceneError> {
    load_str(&wrap(body), "test.xml", &data_dir(), &[])
}

fn ok(body: &str) -> SceneDesc {
    load(body).unwrap_or_else(|e| panic!("expected the scene to load, got: {e}"))
}

/// The error message of a scene that must fail.
fn err(body: &str) -> String {
    match load(body) {
        Ok(_) => panic!("expected an error for:\n{body}"),
        Err(e) => e.to_string(),
    }
}

fn close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol
}

fn mat_close(a: Mat4, b: Mat4, tol: f32) {
    for (x, y) in a.to_cols_array().iter().zip(b.to_cols_array()) {
        assert!(close(*x, y, tol), "matrices differ:\n{a}\n{b}");
    }
}

/// World-space bounding box of a unit-square rectangle or cube corners.
fn bbox(m: Mat4, corners: &[Vec3]) -> (Vec3, Vec3) {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for c in corners {
        let p = m.transform_point3(*c);
        lo = lo.min(p);
        hi = hi.max(p);
    }
    (lo, hi)
}

fn square() -> Vec<Vec3> {
    vec![
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(-1.0, 1.0, 0.0),
    ]
}

fn vec_close(a: Vec3, b: Vec3, tol: f32) {
    assert!((a - b).abs().max_element() <= tol, "{a} vs {b}");
}

// ------------------------------------------------------------ reference scenes

// The matrix literals are copied digit for digit from the scene file.
#[allow(clippy::excessive_precision)]
/// Checks shared by both reference scenes; the expected numbers are Mitsuba
/// 3.9.1's (`scalar_rgb`: `sensor.world_transform()` and `shape.bbox()`).
fn check_reference_common(s: &SceneDesc) {
    assert_eq!(s.integrator.kind, IntegratorKind::Volpath);
    assert_eq!(s.integrator.max_depth, 64);
    assert_eq!(s.integrator.rr_depth, 5);
    assert!(!s.integrator.hide_emitters);
    let c = &s.sensor;
    assert_eq!((c.width, c.height, c.spp, c.seed), (256, 256, 64, 0));
    assert_eq!(c.fov, 40.0);
    assert_eq!(c.fov_axis, FovAxis::X);
    assert_eq!((c.near_clip, c.far_clip), (0.01, 1000.0));
    assert_eq!(c.rfilter, FilterDesc::Box);
    assert_eq!(c.medium, None);
    // lookat origin (0,1.6,4), target (0,0.6,0), up +y: left = (-1,0,0),
    // up' = (0,4,-1)/sqrt(17), dir = (0,-1,-4)/sqrt(17).
    let r = 17f32.sqrt();
    let expected = Mat4::from_cols(
        Vec4::new(-1.0, 0.0, 0.0, 0.0),
        Vec4::new(0.0, 4.0 / r, -1.0 / r, 0.0),
        Vec4::new(0.0, -1.0 / r, -4.0 / r, 0.0),
        Vec4::new(0.0, 1.6, 4.0, 1.0),
    );
    mat_close(c.to_world, expected, 1e-6);
    // Mitsuba prints [[-1,0,0,0],[0,0.970142,-0.242536,1.6],[0,-0.242536,-0.970142,4]].
    assert!(close(c.to_world.y_axis.y, 0.970142, 1e-6));

    assert_eq!(s.shapes.len(), 3);
    let cube = &s.shapes[0];
    assert!(matches!(cube.geometry, GeometryDesc::Cube));
    assert_eq!(s.bsdfs[cube.bsdf], BsdfDesc::Null);
    let corners: Vec<Vec3> = (0..8)
        .map(|i| {
            Vec3::new(
                if i & 1 == 0 { -1.0 } else { 1.0 },
                if i & 2 == 0 { -1.0 } else { 1.0 },
                if i & 4 == 0 { -1.0 } else { 1.0 },
            )
        })
        .collect();
    let (lo, hi) = bbox(cube.to_world, &corners);
    vec_close(lo, Vec3::new(-0.5, 0.25, -0.5), 1e-6);
    vec_close(hi, Vec3::new(0.5, 1.25, 0.5), 1e-6);
    assert_eq!(cube.interior, Some(0));
    assert_eq!(cube.exterior, None);
    assert_eq!(s.media.len(), 1);

    let ground = &s.shapes[1];
    assert!(matches!(ground.geometry, GeometryDesc::Rectangle));
    assert_eq!(
        s.bsdfs[ground.bsdf],
        BsdfDesc::Diffuse {
            reflectance: [0.5; 3]
        }
    );
    // normal +z rotated to +y
    vec_close(
        ground.to_world.transform_vector3(Vec3::Z).normalize(),
        Vec3::Y,
        1e-6,
    );
    let (lo, hi) = bbox(ground.to_world, &square());
    vec_close(lo, Vec3::new(-4.0, 0.0, -4.0), 1e-6);
    vec_close(hi, Vec3::new(4.0, 0.0, 4.0), 1e-6);

    let light = &s.shapes[2];
    assert_eq!(
        light.emitter,
        Some(EmitterDesc::Area {
            radiance: [150.0; 3],
            texture: None,
        })
    );
    assert_eq!(
        s.bsdfs[light.bsdf],
        BsdfDesc::Diffuse {
            reflectance: [0.0; 3]
        }
    );
    // The row-major matrix from the file, element by element.
    let m = light.to_world;
    assert!(close(m.col(0).x, -0.0490290338, 1e-7));
    assert!(close(m.col(1).x, 0.107919143, 1e-7));
    assert!(close(m.col(3).x, -2.5, 0.0));
    assert!(close(m.col(2).y, -0.440225453, 1e-7));
    assert!(close(m.col(0).z, -0.245145169, 1e-7));
    // Mitsuba's bbox of that rectangle.
    let (lo, hi) = bbox(m, &square());
    vec_close(lo, Vec3::new(-2.65695, 1.77553, 0.233271), 2e-5);
    vec_close(hi, Vec3::new(-2.34305, 2.22447, 0.766729), 2e-5);
    // It faces the cube: its normal points toward the cube's centre.
    let n = m.transform_vector3(Vec3::Z);
    let to_cube = Vec3::new(0.0, 0.75, 0.0) - m.transform_point3(Vec3::ZERO);
    assert!(n.dot(to_cube) > 0.0);
}

#[test]
fn reference_homogeneous_scene_loads_with_mitsubas_values() {
    let s = load_file(&reference_scene("cube-homogeneous.xml"), &[]).unwrap();
    check_reference_common(&s);
    match &s.media[0] {
        MediumDesc::Homogeneous {
            sigma_t,
            albedo,
            phase,
            ..
        } => {
            assert_eq!(*sigma_t, [4.0; 3]);
            assert_eq!(*albedo, [0.8; 3]);
            assert_eq!(*phase, PhaseDesc::Isotropic);
        }
        m => panic!("expected a homogeneous medium, got {m:?}"),
    }
}

#[test]
fn reference_heterogeneous_scene_loads_its_grid() {
    let s = load_file(&reference_scene("cube-heterogeneous.xml"), &[]).unwrap();
    check_reference_common(&s);
    match &s.media[0] {
        MediumDesc::Heterogeneous {
            sigma_t: VolumeDesc::Grid(g),
            albedo: VolumeDesc::Constant(albedo),
            scale,
            phase,
            ..
        } => {
            assert_eq!(*scale, 4.0);
            assert_eq!(*albedo, [0.8; 3]);
            assert_eq!(*phase, PhaseDesc::Isotropic);
            assert_eq!(g.grid.shape, [64, 64, 64]);
            assert_eq!(g.grid.channels, 1);
            assert_eq!(g.filter, GridFilter::Trilinear);
            assert!(!g.use_grid_bbox && g.wrap == fgf_scene::WrapMode::Clamp);
            let mean =
                g.grid.data.iter().map(|&v| v as f64).sum::<f64>() / g.grid.data.len() as f64;
            assert!(
                (mean - 1.0).abs() < 1e-3,
                "density64.vol has mean 1, got {mean}"
            );
            // Unit cube -> scale 1, translate (-0.5, 0.25, -0.5): the cube's volume.
            vec_close(
                g.to_world.transform_point3(Vec3::ZERO),
                Vec3::new(-0.5, 0.25, -0.5),
                0.0,
            );
            vec_close(
                g.to_world.transform_point3(Vec3::ONE),
                Vec3::new(0.5, 1.25, 0.5),
                0.0,
            );
        }
        m => panic!("expected a heterogeneous grid medium, got {m:?}"),
    }
}

#[test]
fn defines_override_defaults() {
    let d = [
        ("spp".to_string(), "7".to_string()),
        ("res".to_string(), "32".to_string()),
    ];
    let s = load_file(&reference_scene("cube-homogeneous.xml"), &d).unwrap();
    assert_eq!((s.sensor.spp, s.sensor.width, s.sensor.height), (7, 32, 32));
    assert_eq!(s.integrator.max_depth, 64);
}

// --------------------------------------------------------------- document

#[test]
fn defaults_substitute_anywhere_and_a_define_without_default_is_used() {
    let xml = wrap(
        r#"<default name="r" value="0.25"/>
<shape type="sphere"><float name="radius" value="$r"/><point name="center" value="$x, 0, 0"/></shape>"#,
    );
    let s = load_str(&xml, "t.xml", &data_dir(), &[("x".into(), "3".into())]).unwrap();
    match s.shapes[0].geometry {
        GeometryDesc::Sphere { center, radius } => {
            assert_eq!(radius, 0.25);
            assert_eq!(center, Vec3::new(3.0, 0.0, 0.0));
        }
        _ => panic!(),
    }
}

#[test]
fn undefined_dollar_name_is_an_error_naming_it() {
    let m = err(r#"<shape type="sphere">
    <float name="radius" value="$radius"/>
</shape>"#);
    has(
        &m,
        &[
            "test.xml:3:",
            "$radius",
            "<float name=\"radius\">",
            "no <default",
        ],
    );
}

#[test]
fn include_is_relative_to_the_including_file_and_refs_share_an_index() {
    let s = ok(r#"<include filename="include_bsdf.xml"/>
<shape type="cube"><ref id="included_grey"/></shape>
<shape type="sphere"><ref id="included_grey"/></shape>"#);
    assert_eq!(s.shapes[0].bsdf, s.shapes[1].bsdf);
    assert_eq!(
        s.bsdfs[s.shapes[0].bsdf],
        BsdfDesc::Diffuse {
            reflectance: [0.25; 3]
        }
    );
}

#[test]
fn include_cycle_is_an_error() {
    let m = load_file(&data_dir().join("cycle_a.xml"), &[])
        .unwrap_err()
        .to_string();
    has(&m, &["include cycle", "cycle_a.xml", "<include>"]);
}

#[test]
fn missing_include_names_both_files() {
    let m = err(r#"<include filename="nowhere.xml"/>"#);
    has(
        &m,
        &["test.xml:2:", "nowhere.xml", "cannot read included file"],
    );
}

#[test]
fn shared_medium_by_ref_for_shape_and_sensor() {
    let s = ok(r#"<integrator type="volpath"/>
<medium type="homogeneous" id="fog"><float name="sigma_t" value="0.5"/></medium>
<sensor type="perspective"><ref name="medium" id="fog"/></sensor>
<shape type="cube"><bsdf type="null"/><ref name="interior" id="fog"/></shape>
<shape type="sphere"><medium type="homogeneous" name="exterior"/><ref name="interior" id="fog"/></shape>"#);
    assert_eq!(s.media.len(), 2);
    assert_eq!(s.sensor.medium, Some(0));
    assert_eq!(s.shapes[0].interior, Some(0));
    assert_eq!(s.shapes[1].interior, Some(0));
    assert_eq!(s.shapes[1].exterior, Some(1));
    match &s.media[1] {
        // Mitsuba's defaults: sigma_t 1, albedo 0.75, isotropic.
        MediumDesc::Homogeneous {
            sigma_t,
            albedo,
            phase,
            ..
        } => {
            assert_eq!(
                (*sigma_t, *albedo, *phase),
                ([1.0; 3], [0.75; 3], PhaseDesc::Isotropic)
            );
        }
        m => panic!("{m:?}"),
    }
}

#[test]
fn transform_elements_compose_last_times_first() {
    // Mitsuba 3.9 gives this rectangle the bbox [-3,4,-3] - [5,4,21].
    let s = ok(r#"<shape type="rectangle"><transform name="to_world">
    <scale value="4.0"/><rotate x="1" angle="-90"/><translate x="1" y="2" z="3"/><scale x="1" y="2" z="3"/>
</transform></shape>"#);
    let (lo, hi) = bbox(s.shapes[0].to_world, &square());
    vec_close(lo, Vec3::new(-3.0, 4.0, -3.0), 1e-5);
    vec_close(hi, Vec3::new(5.0, 4.0, 21.0), 1e-5);
    // rotate with a value axis, translate with a value (sphere: Mitsuba bbox [-0.5,0.5,0.5]-[0.5,1.5,1.5]).
    let s = ok(
        r#"<shape type="sphere"><point name="center" x="1" y="0" z="0"/><float name="radius" value="0.5"/>
<transform name="to_world"><rotate value="0,0,1" angle="90"/><translate value="0 0 1"/></transform></shape>"#,
    );
    let GeometryDesc::Sphere { center, radius } = s.shapes[0].geometry else {
        panic!()
    };
    vec_close(
        s.shapes[0].to_world.transform_point3(center),
        Vec3::new(0.0, 1.0, 1.0),
        1e-6,
    );
    assert_eq!(radius, 0.5);
    // matrix is row-major
    let s = ok(
        r#"<shape type="cube"><transform name="to_world"><matrix value="1 0 0 5  0 1 0 6  0 0 1 7  0 0 0 1"/></transform></shape>"#,
    );
    vec_close(
        s.shapes[0].to_world.transform_point3(Vec3::ZERO),
        Vec3::new(5.0, 6.0, 7.0),
        0.0,
    );
}

#[test]
fn mitsuba_defaults_without_sensor_integrator_or_bsdf() {
    let s = ok(r#"<shape type="cube"/>"#);
    assert_eq!(s.integrator.kind, IntegratorKind::Path);
    assert_eq!(s.integrator.max_depth, -1);
    // 768x576, gaussian 0.5, 4 spp, fov from the default 50mm focal length:
    // Mitsuba reports x_fov = 38.1848.
    let c = &s.sensor;
    assert_eq!((c.width, c.height, c.spp), (768, 576, 4));
    assert_eq!(c.rfilter, FilterDesc::Gaussian { stddev: 0.5 });
    assert!(close(c.fov, 38.1848, 1e-4), "{}", c.fov);
    assert_eq!((c.near_clip, c.far_clip), (0.01, 10000.0));
    assert_eq!(
        s.bsdfs[s.shapes[0].bsdf],
        BsdfDesc::Diffuse {
            reflectance: [0.5; 3]
        }
    );
}

#[test]
fn bsdfs_named_materials_and_defaults() {
    let s = ok(
        r#"<shape type="cube"><bsdf type="dielectric"><string name="int_ior" value="water"/></bsdf></shape>
<shape type="cube"><bsdf type="dielectric"/></shape>
<shape type="cube"><bsdf type="conductor"><string name="material" value="Au"/></bsdf></shape>
<shape type="cube"><bsdf type="conductor"/></shape>
<shape type="cube"><bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.1 0.2 0.3"/></bsdf></bsdf></shape>
<shape type="cube"><bsdf type="diffuse"><spectrum name="reflectance" value="0.4"/></bsdf></shape>"#,
    );
    let b = |i: usize| &s.bsdfs[s.shapes[i].bsdf];
    // Mitsuba: eta = 1.3326307 = 1.333 / 1.000277 for water in air.
    match b(0) {
        BsdfDesc::Dielectric {
            int_ior, ext_ior, ..
        } => {
            assert!(close(int_ior / ext_ior, 1.3326307, 1e-6));
        }
        d => panic!("{d:?}"),
    }
    match b(1) {
        BsdfDesc::Dielectric {
            int_ior, ext_ior, ..
        } => {
            assert!(close(int_ior / ext_ior, 1.5041833, 1e-6));
        }
        d => panic!("{d:?}"),
    }
    match b(2) {
        BsdfDesc::Conductor {
            eta,
            k,
            perfect_mirror,
            ..
        } => {
            assert_eq!(*eta, [0.143036, 0.375307, 1.44205]);
            assert_eq!(*k, [3.983, 2.38556, 1.60336]);
            assert!(!perfect_mirror);
        }
        d => panic!("{d:?}"),
    }
    assert_eq!(
        *b(3),
        BsdfDesc::Conductor {
            eta: [0.0; 3],
            k: [1.0; 3],
            specular_reflectance: [1.0; 3],
            perfect_mirror: true
        }
    );
    assert_eq!(
        *b(4),
        BsdfDesc::TwoSided(Box::new(BsdfDesc::Diffuse {
            reflectance: [0.1, 0.2, 0.3]
        }))
    );
    assert_eq!(
        *b(5),
        BsdfDesc::Diffuse {
            reflectance: [0.4; 3]
        }
    );
}

#[test]
fn emitters_and_their_defaults() {
    let s = ok(
        r#"<emitter type="point"><point name="position" x="1" y="2" z="3"/><rgb name="intensity" value="5"/></emitter>
<emitter type="point"><transform name="to_world"><translate x="4"/></transform></emitter>
<emitter type="spot"><float name="cutoff_angle" value="30"/><transform name="to_world"><lookat origin="0,5,0" target="0,0,0" up="0,0,1"/></transform></emitter>
<emitter type="directional"><vector name="direction" value="0, -2, 0"/></emitter>
<emitter type="constant"/>"#,
    );
    assert_eq!(
        s.emitters[0],
        EmitterDesc::Point {
            position: Vec3::new(1.0, 2.0, 3.0),
            intensity: [5.0; 3]
        }
    );
    assert_eq!(
        s.emitters[1],
        EmitterDesc::Point {
            position: Vec3::new(4.0, 0.0, 0.0),
            intensity: [1.0; 3]
        }
    );
    match &s.emitters[2] {
        EmitterDesc::Spot {
            to_world,
            cutoff_angle,
            beam_width,
            intensity,
        } => {
            assert_eq!(
                (*cutoff_angle, *beam_width, *intensity),
                (30.0, 22.5, [1.0; 3])
            );
            vec_close(to_world.transform_vector3(Vec3::Z), -Vec3::Y, 1e-6);
        }
        e => panic!("{e:?}"),
    }
    assert_eq!(
        s.emitters[3],
        EmitterDesc::Directional {
            direction: -Vec3::Y,
            irradiance: [1.0; 3]
        }
    );
    assert_eq!(s.emitters[4], EmitterDesc::Constant { radiance: [1.0; 3] });
}

#[test]
fn focal_length_converts_like_mitsuba() {
    // Mitsuba 3.9.1 reports x_fov = 57.8712 for 35mm on a 100x50 film.
    let s = ok(
        r#"<sensor type="perspective"><string name="focal_length" value="35mm"/>
<film type="hdrfilm"><integer name="width" value="100"/><integer name="height" value="50"/></film></sensor>"#,
    );
    assert!(close(s.sensor.fov, 57.8712, 1e-4), "{}", s.sensor.fov);
    // Without fov or focal_length: 50mm on the film's own aspect; Mitsuba
    // reports x_fov = 34.0221 for a 256x256 film.
    let s = ok(r#"<sensor type="perspective">
<film type="hdrfilm"><integer name="width" value="256"/><integer name="height" value="256"/></film></sensor>"#);
    assert!(close(s.sensor.fov, 34.0221, 1e-4), "{}", s.sensor.fov);
    assert_eq!(s.sensor.fov_axis, FovAxis::X);
    has(
        &err(
            r#"<sensor type="perspective"><string name="focal_length" value="35mm"/><string name="fov_axis" value="y"/></sensor>"#,
        ),
        &["'fov_axis' only applies with 'fov'"],
    );
    has(
        &err(r#"<sensor type="perspective"><string name="focal_length" value="wide"/></sensor>"#),
        &["cannot parse 'wide' as a number", "focal_length"],
    );
}

#[test]
fn sensor_film_sampler_filter_options() {
    let s = ok(r#"<sensor type="perspective">
    <float name="fov" value="30"/><string name="fov_axis" value="smaller"/>
    <sampler type="independent"><integer name="sample_count" value="3"/><integer name="seed" value="9"/></sampler>
    <film type="hdrfilm"><integer name="width" value="10"/><integer name="height" value="5"/>
        <string name="pixel_format" value="rgba"/><string name="component_format" value="float32"/>
        <rfilter type="tent"><float name="radius" value="2"/></rfilter></film>
    <medium type="homogeneous"/>
</sensor>
<integrator type="volpath"><integer name="max_depth" value="2"/><integer name="rr_depth" value="3"/><boolean name="hide_emitters" value="true"/></integrator>"#);
    let c = &s.sensor;
    assert_eq!(
        (c.fov, c.fov_axis, c.spp, c.seed, c.width, c.height),
        (30.0, FovAxis::Smaller, 3, 9, 10, 5)
    );
    assert_eq!(c.rfilter, FilterDesc::Tent { radius: 2.0 });
    assert_eq!(c.medium, Some(0));
    assert_eq!(s.integrator.max_depth, 2);
    assert_eq!(s.integrator.rr_depth, 3);
    assert!(s.integrator.hide_emitters);
}

#[test]
fn meshes_obj_and_ply_load_with_normals_and_fan_triangulation() {
    let s = ok(
        r#"<shape type="obj"><string name="filename" value="quad.obj"/></shape>
<shape type="obj"><string name="filename" value="quad.obj"/><boolean name="face_normals" value="true"/><boolean name="flip_normals" value="true"/></shape>
<shape type="ply"><string name="filename" value="tri.ply"/></shape>"#,
    );
    let mesh = |i: usize| match &s.shapes[i].geometry {
        GeometryDesc::Mesh(m) => m.clone(),
        _ => panic!(),
    };
    let q = mesh(0);
    assert_eq!(q.positions.len(), 4);
    assert_eq!(q.indices.len(), 2);
    assert_eq!(q.normals.as_ref().unwrap()[0], Vec3::Z);
    assert!(mesh(1).normals.is_none());
    assert!(s.shapes[1].flip_normals);
    assert_eq!(mesh(2).indices, vec![[0, 1, 2]]);
}

/// A shape's world-space vertex normals as the renderer sees them
/// (`normalize(M^{-T} n)`), paired with the world-space positions.
fn world_normals(s: &ShapeDesc) -> Vec<(Vec3, Vec3)> {
    let GeometryDesc::Mesh(m) = &s.geometry else {
        panic!("not a mesh: {}", s.name)
    };
    let nm = glam::Mat3::from_mat4(s.to_world).inverse().transpose();
    let ns = m.normals.as_ref().expect("the mesh has vertex normals");
    assert_eq!(ns.len(), m.positions.len());
    m.positions
        .iter()
        .zip(ns)
        .map(|(&p, &n)| (s.to_world.transform_point3(p), (nm * n).normalize()))
        .collect()
}

/// Each expected (world position, world normal) matches the vertex at that
/// position to `tol`. Vertices are found by position (the vertex order is
/// the loader's business), and the count must agree.
fn check_normals(s: &ShapeDesc, expected: &[([f32; 3], Vec3)], tol: f32) {
    let got = world_normals(s);
    assert_eq!(got.len(), expected.len(), "{}", s.name);
    for (p, n) in expected {
        let p = Vec3::from(*p);
        let (_, g) = got
            .iter()
            .find(|(q, _)| (*q - p).abs().max_element() <= 1e-5)
            .unwrap_or_else(|| panic!("no vertex at {p} in {got:?}"));
        assert!(
            (*g - *n).abs().max_element() <= tol,
            "vertex {p}: normal {g} vs expected {n}"
        );
    }
}

/// Tolerance for unit normals computed in float32 (ours and Mitsuba's):
/// a few hundred ulps of 1 (6e-8) covers the differently ordered crosses,
/// square roots and asin of the two implementations; a wrong weighting or
/// space is off by 1e-2 or more in every case below.
const NORMAL_TOL: f32 = 2e-6;

// Mitsuba's printed digits, copied as printed.
#[allow(clippy::excessive_precision)]
#[test]
fn meshes_without_normals_get_angle_weighted_smooth_normals_by_hand() {
    let dir = tempfile::tempdir().unwrap();
    // Faces A = (0,1,2) in z = 0 (normal +z) and B = (0,3,1) in y = 0
    // (normal +y) meet at right angles along the edge 0-1; B is 5 times
    // larger than A. Face (0,1,4) is degenerate (collinear).
    std::fs::write(
        dir.path().join("fan.ply"),
        "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\nelement face 3\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n0 0 5\n2 0 0\n3 0 1 2\n3 0 3 1\n3 0 1 4\n",
    )
    .unwrap();
    // Two `o` groups sharing the edge 2-3 of the file: Mitsuba shares the
    // vertices, so both faces contribute to them.
    std::fs::write(
        dir.path().join("groups.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 1\no first\nf 1 2 3\no second\nf 2 4 3\n",
    )
    .unwrap();
    let xml = wrap(
        r#"<shape type="ply"><string name="filename" value="fan.ply"/></shape>
<shape type="obj"><string name="filename" value="groups.obj"/></shape>
<shape type="ply"><string name="filename" value="fan.ply"/><boolean name="face_normals" value="true"/></shape>"#,
    );
    let s = load_str(&xml, "n.xml", dir.path(), &[]).unwrap();
    let pi = std::f32::consts::PI;
    // Vertex 0: angle π/2 in both faces, so the normal bisects +y and +z
    // whatever the areas (area weighting would give (0, 5, 1)/√26).
    // Vertex 1: angle π/4 in A and atan(5) in B. Vertices 2 and 3: one face
    // each. Vertex 4: only the degenerate face, Mitsuba's placeholder +x.
    let v1 = (pi / 4.0 * Vec3::Z + 5f32.atan() * Vec3::Y).normalize();
    check_normals(
        &s.shapes[0],
        &[
            ([0.0, 0.0, 0.0], Vec3::new(0.0, 1.0, 1.0).normalize()),
            ([1.0, 0.0, 0.0], v1),
            ([0.0, 1.0, 0.0], Vec3::Z),
            ([0.0, 0.0, 5.0], Vec3::Y),
            ([2.0, 0.0, 0.0], Vec3::X),
        ],
        NORMAL_TOL,
    );
    // Mitsuba 3.9.1 gives (0, 0.868080378, 0.496423692) for vertex 1.
    vec_close(v1, Vec3::new(0.0, 0.868080378, 0.496423692), 1e-6);
    // groups.obj: face (1,2,3) has normal +z and angle π/4 at vertices 2
    // and 3; face (2,4,3) has normal (-1,-1,1)/√3 and angle π/3 there.
    let shared =
        (pi / 4.0 * Vec3::Z + pi / 3.0 * Vec3::new(-1.0, -1.0, 1.0).normalize()).normalize();
    check_normals(
        &s.shapes[1],
        &[
            ([0.0, 0.0, 0.0], Vec3::Z),
            ([1.0, 0.0, 0.0], shared),
            ([0.0, 1.0, 0.0], shared),
            ([1.0, 1.0, 1.0], Vec3::new(-1.0, -1.0, 1.0).normalize()),
        ],
        NORMAL_TOL,
    );
    // Mitsuba 3.9.1 gives (-0.370482773, -0.370482773, 0.851754069).
    vec_close(
        shared,
        Vec3::new(-0.370482773, -0.370482773, 0.851754069),
        1e-6,
    );
    // face_normals=true keeps the mesh flat.
    match &s.shapes[2].geometry {
        GeometryDesc::Mesh(m) => assert!(m.normals.is_none()),
        _ => panic!(),
    }
}

// Mitsuba's printed digits, copied as printed.
#[allow(clippy::excessive_precision)]
#[test]
fn smooth_normals_match_mitsuba_in_world_space_under_nonuniform_transforms() {
    let dir = meshes_dir();
    // A to_world with non-uniform scale and shear (row-major, as in the file).
    let m = r#"<transform name="to_world"><matrix value="2 0.7 0 0.1  0 0.5 0.3 0  0.2 0 1 -0.4  0 0 0 1"/></transform>"#;
    let xml = wrap(&format!(
        r#"<shape type="obj"><string name="filename" value="octahedron.obj"/></shape>
<shape type="obj"><string name="filename" value="octahedron.obj"/>{m}</shape>
<shape type="ply"><string name="filename" value="tetrahedron.ply"/>{m}</shape>
<shape type="obj"><string name="filename" value="octahedron.obj"/><boolean name="face_normals" value="true"/></shape>"#
    ));
    let s = load_str(&xml, "m.xml", &dir, &[]).unwrap();
    // The unit octahedron: by symmetry each vertex normal is its axis.
    let axes: Vec<([f32; 3], Vec3)> = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z]
        .iter()
        .map(|&a| (a.to_array(), a))
        .collect();
    check_normals(&s.shapes[0], &axes, NORMAL_TOL);
    // Under shear the face angles change, so the result depends on where
    // they are measured. Expected values: Mitsuba 3.9.1 (scalar_rgb),
    // mi.traverse(shape)['vertex_positions'] / ['vertex_normals'] for the
    // same XML. For these meshes, angle weighting in local space (mapped
    // by M^{-T}) and area weighting in world space are both off by > 0.5.
    check_normals(
        &s.shapes[1],
        &[
            (
                [2.1, 0.0, -0.2],
                Vec3::new(0.993214011, -0.066452704, 0.095445469),
            ),
            (
                [0.8, 0.5, -0.4],
                Vec3::new(0.190346405, 0.953892589, -0.232071325),
            ),
            (
                [0.1, 0.3, 0.6],
                Vec3::new(-0.081554338, 0.261868387, 0.961651623),
            ),
            (
                [0.1, -0.3, -1.4],
                Vec3::new(0.081554376, -0.261868507, -0.961651683),
            ),
            (
                [-0.6, -0.5, -0.4],
                Vec3::new(-0.190346405, -0.953892648, 0.232071295),
            ),
            (
                [-1.9, 0.0, -0.6],
                Vec3::new(-0.993214130, 0.066452540, -0.095445633),
            ),
        ],
        NORMAL_TOL,
    );
    check_normals(
        &s.shapes[2],
        &[
            (
                [0.8, 0.5, -0.4],
                Vec3::new(0.480751365, 0.876531124, -0.023898905),
            ),
            (
                [-1.78, -0.35, -1.06],
                Vec3::new(-0.917068422, -0.170265839, -0.360548288),
            ),
            (
                [1.42, -0.35, -0.74],
                Vec3::new(0.881173790, -0.367383897, -0.297593683),
            ),
            (
                [-0.18, 0.07, 0.5],
                Vec3::new(-0.258974165, 0.059595168, 0.964044034),
            ),
        ],
        NORMAL_TOL,
    );
    match &s.shapes[3].geometry {
        GeometryDesc::Mesh(m) => assert!(m.normals.is_none()),
        _ => panic!(),
    }
}

// Mitsuba's printed digits, copied as printed.
#[allow(clippy::excessive_precision)]
#[test]
fn rotate_uses_the_axis_unnormalised_like_mitsuba() {
    // Mitsuba 3.9.1: mi.ScalarTransform4f().rotate([0.3, -1.7, 2.2], 37),
    // which is what <rotate> builds (a unit-axis rotation only if |a| = 1).
    let s = ok(
        r#"<shape type="cube"><transform name="to_world"><rotate x="0.3" y="-1.7" z="2.2" angle="37"/></transform></shape>
<shape type="cube"><transform name="to_world"><rotate y="1" angle="30"/></transform></shape>"#,
    );
    let expected = Mat4::from_cols(
        Vec4::new(0.8167583, 1.221297, 1.1559861, 0.0),
        Vec4::new(-1.4266889, 1.380579, -0.5725588, 0.0),
        Vec4::new(-0.8901849, -0.9336478, 1.7732397, 0.0),
        Vec4::W,
    );
    mat_close(s.shapes[0].to_world, expected, 1e-6);
    // A unit axis is an ordinary rotation.
    mat_close(
        s.shapes[1].to_world,
        Mat4::from_rotation_y(30f32.to_radians()),
        1e-6,
    );
}

#[test]
fn shapes_with_an_area_emitter_and_no_bsdf_are_black() {
    // Mitsuba 3.9.1: shape.bsdf() is SmoothDiffuse with reflectance 0.0 on
    // the emitter and 0.5 on the plain shape.
    let s = ok(r#"<shape type="rectangle"><emitter type="area"/></shape>
<shape type="rectangle"/>
<shape type="sphere"><emitter type="area"><rgb name="radiance" value="3"/></emitter></shape>
<shape type="disk"><emitter type="area"/><bsdf type="diffuse"><rgb name="reflectance" value="0.7"/></bsdf></shape>"#);
    let bsdf = |i: usize| &s.bsdfs[s.shapes[i].bsdf];
    assert_eq!(
        bsdf(0),
        &BsdfDesc::Diffuse {
            reflectance: [0.0; 3]
        }
    );
    assert_eq!(
        bsdf(1),
        &BsdfDesc::Diffuse {
            reflectance: [0.5; 3]
        }
    );
    // Both emitters share the one black entry.
    assert_eq!(s.shapes[2].bsdf, s.shapes[0].bsdf);
    // An explicit BSDF on an emitter is kept, whatever the child order.
    assert_eq!(
        bsdf(3),
        &BsdfDesc::Diffuse {
            reflectance: [0.7; 3]
        }
    );
}

#[test]
fn heterogeneous_constvolume_albedo_and_hg_phase() {
    let s = ok(r#"<integrator type="volpath"/>
<shape type="cube"><medium type="heterogeneous" name="interior">
    <float name="sigma_t" value="2"/>
    <volume type="constvolume" name="albedo"><rgb name="value" value="0.1, 0.2, 0.3"/></volume>
    <phase type="hg"><float name="g" value="-0.3"/></phase>
</medium></shape>
<shape type="cube"><medium type="homogeneous" name="interior"><phase type="hg"/></medium></shape>"#);
    match &s.media[0] {
        MediumDesc::Heterogeneous {
            sigma_t,
            albedo,
            scale,
            phase,
            ..
        } => {
            assert!(matches!(sigma_t, VolumeDesc::Constant(c) if *c == [2.0; 3]));
            assert!(matches!(albedo, VolumeDesc::Constant(c) if *c == [0.1, 0.2, 0.3]));
            assert_eq!((*scale, *phase), (1.0, PhaseDesc::Hg { g: -0.3 }));
        }
        m => panic!("{m:?}"),
    }
    // Mitsuba's hg default g = 0.8.
    match &s.media[1] {
        MediumDesc::Homogeneous { phase, .. } => assert_eq!(*phase, PhaseDesc::Hg { g: 0.8 }),
        m => panic!("{m:?}"),
    }
}

// ------------------------------------------------------------------ fgf media

#[test]
fn fgf_medium_parses_and_kfbm_length_defaults_to_bbox_diagonal() {
    let s = ok(r#"<integrator type="volpath"/>
<shape type="cube"><transform name="to_world"><scale value="0.5"/></transform>
<medium type="fgf" name="interior">
    <float name="sigma_t" value="4.0"/><float name="scale" value="2"/><rgb name="albedo" value="0.8"/>
    <float name="hurst" value="1.2"/><float name="sw" value="4.0"/>
    <string name="kernel" value="reciprocal"/><phase type="isotropic"/>
</medium></shape>
<shape type="sphere"><medium type="fgf" name="interior">
    <float name="hurst" value="-0.1"/><float name="sw" value="2"/>
</medium></shape>"#);
    match &s.media[0] {
        MediumDesc::NonExponential {
            sigma_t,
            albedo,
            model,
            kernel,
            density,
            ..
        } => {
            assert_eq!(*sigma_t, [8.0; 3]);
            assert_eq!(*albedo, [0.8; 3]);
            assert_eq!(*kernel, KernelDesc::Reciprocal);
            assert!(density.is_none());
            // The cube [-0.5, 0.5]^3 has diagonal sqrt(3).
            match model {
                TransmittanceDesc::Fgf { hurst, sw, length } => {
                    assert_eq!((*hurst, *sw), (1.2, 4.0));
                    assert!((length.unwrap() - 3f64.sqrt()).abs() < 1e-6);
                }
                m => panic!("{m:?}"),
            }
        }
        m => panic!("{m:?}"),
    }
    match &s.media[1] {
        MediumDesc::NonExponential {
            model,
            kernel,
            sigma_t,
            albedo,
            ..
        } => {
            assert_eq!(
                *model,
                TransmittanceDesc::Fgf {
                    hurst: -0.1,
                    sw: 2.0,
                    length: None
                }
            );
            assert_eq!(*kernel, KernelDesc::EnergyConserving);
            assert_eq!((*sigma_t, *albedo), ([1.0; 3], [0.75; 3]));
        }
        m => panic!("{m:?}"),
    }
}

#[test]
fn nonexponential_models_and_density_grid() {
    let s = ok(r#"<integrator type="volpath"/>
<medium type="nonexponential" id="a"><string name="transmittance" value="davis"/><float name="alpha" value="2"/></medium>
<medium type="nonexponential" id="b"><string name="transmittance" value="davis_weinstein"/><float name="h" value="0.9"/><float name="c" value="0.5"/>
    <volume type="gridvolume" name="density"><string name="filename" value="../../../../scenes/reference/density64.vol"/></volume></medium>
<medium type="nonexponential" id="c"><string name="transmittance" value="exponential"/></medium>"#);
    let model = |i: usize| match &s.media[i] {
        MediumDesc::NonExponential { model, .. } => *model,
        m => panic!("{m:?}"),
    };
    assert_eq!(model(0), TransmittanceDesc::Davis { alpha: 2.0 });
    assert_eq!(
        model(1),
        TransmittanceDesc::DavisWeinstein { h: 0.9, c: 0.5 }
    );
    assert_eq!(model(2), TransmittanceDesc::Exponential);
    match &s.media[1] {
        MediumDesc::NonExponential {
            density: Some(g), ..
        } => assert_eq!(g.grid.shape, [64, 64, 64]),
        m => panic!("{m:?}"),
    }
}

#[test]
fn fgf_parameter_errors() {
    let base = |extra: &str| {
        format!(
            "<integrator type=\"volpath\"/>\n<shape type=\"cube\"><medium type=\"fgf\" name=\"interior\">\n{extra}\n</medium></shape>"
        )
    };
    for (extra, parts) in [
        (
            r#"<float name="hurst" value="0"/><float name="sw" value="1"/>"#,
            &[
                "test.xml:4:",
                "hurst = 0",
                "must not be 0",
                "valid: hurst = -0.5 (white)",
            ][..],
        ),
        (
            r#"<float name="hurst" value="1"/><float name="sw" value="1"/>"#,
            &["hurst = 1"][..],
        ),
        (
            r#"<float name="hurst" value="-0.7"/><float name="sw" value="1"/>"#,
            &["hurst = -0.7"][..],
        ),
        (
            // The model's own rule (fgf-core's constructor, through
            // `SceneDesc::validate`), reported at the parameter.
            r#"<float name="hurst" value="-0.2"/><float name="sw" value="-1"/>"#,
            &["test.xml:4:", "<float name=\"sw\">", "sw = -1", "> 0"][..],
        ),
        (
            r#"<float name="hurst" value="-0.2"/>"#,
            &["missing required parameter 'sw'"][..],
        ),
        (
            r#"<float name="hurst" value="-0.2"/><float name="sw" value="1"/><float name="length" value="2"/>"#,
            &["'length' only applies to k-fBm", "pink"][..],
        ),
        (
            r#"<float name="hurst" value="0.3"/><float name="sw" value="1"/><float name="length" value="0"/>"#,
            &["length = 0"][..],
        ),
        (
            r#"<float name="hurst" value="0.3"/><float name="sw" value="1"/><string name="kernel" value="gbe"/>"#,
            &["kernel = 'gbe'", "energy_conserving, reciprocal"][..],
        ),
        (
            r#"<float name="hurst" value="0.3"/><float name="sw" value="1"/><float name="alpha" value="1"/>"#,
            &[
                "unknown parameter 'alpha'",
                "known: sigma_t, albedo, scale, hurst, sw, length, kernel",
            ][..],
        ),
        (
            r#"<float name="hurst" value="nan"/><float name="sw" value="1"/>"#,
            &["not a finite number", "hurst"][..],
        ),
        (
            r#"<float name="hurst" value="0.3"/><float name="sw" value="1"/><float name="sigma_t" value="0"/>"#,
            &["sigma_t", "> 0"][..],
        ),
    ] {
        has(&err(&base(extra)), parts);
    }
    // A k-fBm medium used by no shape has no default length.
    has(
        &err(r#"<integrator type="volpath"/>
<medium type="fgf" id="m"><float name="hurst" value="0.5"/><float name="sw" value="1"/></medium>"#),
        &["test.xml:3:", "needs a 'length'"],
    );
    has(
        &err(r#"<integrator type="volpath"/>
<medium type="nonexponential"><string name="transmittance" value="davis"/><float name="h" value="0.7"/><float name="alpha" value="1"/></medium>"#),
        &["'h' does not apply to transmittance 'davis'"],
    );
    has(
        &err(r#"<integrator type="volpath"/>
<medium type="nonexponential"><string name="transmittance" value="davis_weinstein"/><float name="h" value="0.3"/><float name="c" value="1"/></medium>"#),
        &["h = 0.3", "0.5 <= h <= 1"],
    );
    has(
        &err(r#"<integrator type="volpath"/>
<medium type="nonexponential"><string name="transmittance" value="power"/></medium>"#),
        &["unknown transmittance 'power'", "davis_weinstein"],
    );
}

// ----------------------------------------------------------- malformed input

#[test]
fn truncated_xml_names_the_file_and_position() {
    let full = std::fs::read_to_string(reference_scene("cube-homogeneous.xml")).unwrap();
    let cut = &full[..full.len() / 2];
    let e = load_str(cut, "cut.xml", &data_dir(), &[]).unwrap_err();
    assert_eq!(e.kind, SceneErrorKind::Syntax);
    has(&e.to_string(), &["cut.xml:", "malformed XML"]);
    assert!(e.pos.is_some());
    let e = load_str("", "empty.xml", &data_dir(), &[]).unwrap_err();
    has(&e.to_string(), &["empty.xml", "malformed XML"]);
}

#[test]
fn missing_scene_file_is_an_io_error() {
    let e = load_file(Path::new("/nonexistent/scene.xml"), &[]).unwrap_err();
    assert_eq!(e.kind, SceneErrorKind::Io);
    has(
        &e.to_string(),
        &["/nonexistent/scene.xml", "cannot read the scene file"],
    );
}

#[test]
fn unknown_plugin_lists_the_supported_ones() {
    has(
        &err("<shape type=\"cube\">\n<bsdf type=\"principledthin\"/>\n</shape>"),
        &[
            "test.xml:3:1: <bsdf type=\"principledthin\"> unknown BSDF type 'principledthin' (supported: diffuse, null, dielectric, thindielectric, roughdielectric, conductor, roughconductor, plastic, roughplastic, twosided, mask, principled)",
        ],
    );
    has(
        &err(r#"<shape type="teapot"/>"#),
        &[
            "test.xml:2:1",
            "unknown shape type 'teapot'",
            "cube, rectangle, disk, sphere, obj, ply",
        ],
    );
    has(
        &err(r#"<integrator type="bdpt"/>"#),
        &[
            "unknown integrator type 'bdpt'",
            "volpath, volpathmis, path, direct, moment",
        ],
    );
    has(
        &err(r#"<emitter type="projector"/>"#),
        &["unknown emitter type 'projector'"],
    );
    has(
        &err(r#"<sensor type="orthographic"/>"#),
        &["unknown sensor type 'orthographic'", "perspective"],
    );
    has(
        &err(r#"<medium type="foggy"/>"#),
        &[
            "unknown medium type 'foggy'",
            "homogeneous, heterogeneous, fgf, nonexponential",
        ],
    );
    has(
        &err(r#"<texture type="mesh_attribute" id="t"/>"#),
        &[
            "test.xml:2:1",
            "texture type 'mesh_attribute' is not supported",
            "checkerboard, bitmap",
        ],
    );
    has(
        &err(r#"<sensor type="perspective"><sampler type="sobol"/></sensor>"#),
        &["unknown sampler type 'sobol'", "independent"],
    );
    has(
        &err(
            r#"<sensor type="perspective"><film type="hdrfilm"><rfilter type="mitchell"/></film></sensor>"#,
        ),
        &["unknown rfilter type 'mitchell'", "box, gaussian, tent"],
    );
    has(
        &err(r#"<shape type="cube"><wobble/></shape>"#),
        &["unknown element <wobble>"],
    );
    has(
        &err(r#"<shape type="cube"><emitter type="point"/></shape>"#),
        &["cannot be attached to a shape"],
    );
    has(
        &err(r#"<emitter type="area"/>"#),
        &["must be nested inside the <shape>"],
    );
    has(
        &err(
            r#"<integrator type="volpath"/><shape type="cube"><medium type="homogeneous" name="interior"><phase type="rayleigh"/></medium></shape>"#,
        ),
        &["unknown phase function type 'rayleigh'"],
    );
}

#[test]
fn unknown_and_duplicate_parameters() {
    has(
        &err("<shape type=\"cube\">\n  <float name=\"radius\" value=\"1\"/>\n</shape>"),
        &[
            "test.xml:3:3",
            "unknown parameter 'radius'",
            "known: to_world, flip_normals",
        ],
    );
    has(
        &err(
            r#"<shape type="sphere"><float name="radius" value="1"/><float name="radius" value="2"/></shape>"#,
        ),
        &["parameter 'radius' is given twice"],
    );
    has(
        &err(
            r#"<bsdf type="diffuse"><rgb name="reflectance" value="0.5"/><boolean name="x" value="true"/></bsdf>"#,
        ),
        &["unknown parameter 'x'", "known: reflectance"],
    );
    has(
        &err(r#"<shape type="cube" colour="red"/>"#),
        &["unknown attribute 'colour'"],
    );
    has(
        &err(r#"<bsdf type="null"><float name="x" value="1"/></bsdf>"#),
        &["unknown parameter 'x'", "known: none"],
    );
}

#[test]
fn wrong_types_and_bad_numbers_name_parameter_and_range() {
    let cases: &[(&str, &[&str])] = &[
        (
            r#"<shape type="sphere"><string name="radius" value="big"/></shape>"#,
            &["'radius' must be a <float>", "not <string>"],
        ),
        (
            r#"<shape type="sphere"><float name="radius" value="abc"/></shape>"#,
            &["cannot parse 'abc' as a number", "'radius'"],
        ),
        (
            r#"<shape type="sphere"><float name="radius" value="-1"/></shape>"#,
            &["invalid radius = -1", "radius > 0"],
        ),
        (
            r#"<shape type="sphere"><float name="radius" value="NaN"/></shape>"#,
            &["'radius' = NaN is not a finite number"],
        ),
        (
            r#"<shape type="sphere"><float name="radius" value="inf"/></shape>"#,
            &["not a finite number"],
        ),
        (
            r#"<shape type="sphere"><rgb name="radius" value="1"/></shape>"#,
            &["must be a <float>"],
        ),
        (
            r#"<integrator type="volpath"><float name="max_depth" value="3"/></integrator>"#,
            &["'max_depth' must be an <integer>"],
        ),
        (
            r#"<integrator type="volpath"><integer name="max_depth" value="3.5"/></integrator>"#,
            &["cannot parse '3.5' as an integer"],
        ),
        (
            r#"<integrator type="volpath"><integer name="max_depth" value="-2"/></integrator>"#,
            &["invalid max_depth = -2", "-1 (unbounded)"],
        ),
        (
            r#"<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="0"/></film></sensor>"#,
            &["invalid width = 0", "1 <= value <= 65536"],
        ),
        (
            r#"<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="-5"/></film></sensor>"#,
            &["invalid width = -5"],
        ),
        (
            r#"<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="1000000000"/><integer name="height" value="1000000000"/></film></sensor>"#,
            &["invalid width = 1000000000"],
        ),
        (
            r#"<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="65536"/><integer name="height" value="65536"/></film></sensor>"#,
            &["larger than the limit"],
        ),
        (
            r#"<sensor type="perspective"><film type="hdrfilm"><integer name="crop_width" value="5"/></film></sensor>"#,
            &["cropping is not supported"],
        ),
        (
            r#"<sensor type="perspective"><film type="hdrfilm"><string name="pixel_format" value="luminance"/></film></sensor>"#,
            &["pixel_format = 'luminance'", "rgb, rgba"],
        ),
        (
            r#"<sensor type="perspective"><float name="fov" value="180"/></sensor>"#,
            &["invalid fov = 180", "0 < fov < 180"],
        ),
        (
            r#"<sensor type="perspective"><float name="near_clip" value="10"/><float name="far_clip" value="1"/></sensor>"#,
            &["invalid far_clip = 1", "far_clip > near_clip"],
        ),
        (
            r#"<sensor type="perspective"><string name="fov_axis" value="diagonal"/></sensor>"#,
            &["fov_axis = 'diagonal'", "x, y, smaller, larger"],
        ),
        (
            r#"<sensor type="perspective"><sampler type="independent"><integer name="sample_count" value="0"/></sampler></sensor>"#,
            &["sample_count = 0"],
        ),
        (
            r#"<sensor type="perspective"><transform name="to_world"><scale value="2"/></transform></sensor>"#,
            &["rigid transform"],
        ),
        (
            r#"<sensor type="perspective"><float name="fov" value="40"/><string name="focal_length" value="50mm"/></sensor>"#,
            &["either 'fov' or 'focal_length'"],
        ),
        (
            r#"<bsdf type="diffuse"><rgb name="reflectance" value="0.1, 0.2"/></bsdf>"#,
            &["has 2 values, expected 1 (grey) or 3"],
        ),
        (
            r#"<bsdf type="diffuse"><rgb name="reflectance" value="1.5"/></bsdf>"#,
            &["invalid reflectance", "in [0, 1]"],
        ),
        (
            r#"<bsdf type="diffuse"><spectrum name="reflectance" value="700:0.1, 400:0.5"/></bsdf>"#,
            &["spectrum 'reflectance': wavelengths must increase"],
        ),
        (
            r#"<bsdf type="diffuse"><boolean name="reflectance" value="yes"/></bsdf>"#,
            &["must be a <float>, <rgb> or uniform <spectrum>"],
        ),
        (
            r#"<bsdf type="dielectric"><string name="int_ior" value="unobtainium"/></bsdf>"#,
            &["unknown material 'unobtainium'", "bk7"],
        ),
        (
            r#"<bsdf type="dielectric"><float name="int_ior" value="-1.5"/></bsdf>"#,
            &["invalid int_ior = -1.5"],
        ),
        (
            r#"<bsdf type="conductor"><string name="material" value="Au"/><float name="eta" value="2"/></bsdf>"#,
            &["either 'material' or 'eta'/'k'"],
        ),
        (
            r#"<bsdf type="conductor"><string name="material" value="Kryptonite"/></bsdf>"#,
            &["unknown conductor material 'Kryptonite'", "Au"],
        ),
        (
            r#"<bsdf type="twosided"/>"#,
            &["twosided needs one nested BSDF"],
        ),
        (
            r#"<bsdf type="twosided"><bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf>"#,
            &["two different BSDFs"],
        ),
        (
            r#"<emitter type="spot"><float name="cutoff_angle" value="20"/><float name="beam_width" value="30"/></emitter>"#,
            &["invalid beam_width = 30"],
        ),
        (
            r#"<emitter type="point"><rgb name="intensity" value="-1"/></emitter>"#,
            &["invalid intensity", ">= 0"],
        ),
        (
            r#"<emitter type="point"><point name="position" value="1,2"/></emitter>"#,
            &["'position' value has 2 numbers, expected 3"],
        ),
        (
            r#"<emitter type="point"><point name="position" x="1"/><transform name="to_world"/></emitter>"#,
            &["either 'position' or 'to_world'"],
        ),
        (
            r#"<emitter type="directional"><vector name="direction" value="0,0,0"/></emitter>"#,
            &["direction is zero"],
        ),
        (
            r#"<shape type="cube"><transform name="to_world"><scale value="0"/></transform></shape>"#,
            &["singular"],
        ),
        (
            r#"<shape type="cube"><transform name="to_world"><rotate angle="30"/></transform></shape>"#,
            &["rotation axis is zero"],
        ),
        (
            r#"<shape type="sphere"><transform name="to_world"><scale x="1" y="2" z="3"/></transform></shape>"#,
            &["non-uniform scale or shear"],
        ),
        (
            r#"<shape type="cube"><transform name="to_world"><matrix value="1 0 0 0 1"/></transform></shape>"#,
            &["matrix has 5 numbers, expected 16"],
        ),
        (
            r#"<shape type="cube"><transform name="to_world"><shear value="1"/></transform></shape>"#,
            &["unknown transform element <shear>"],
        ),
        (
            r#"<shape type="cube"><transform name="to_world"><scale value="1 2"/></transform></shape>"#,
            &["scale value has 2 numbers"],
        ),
        (
            r#"<shape type="cube"><transform name="to_world"><translate x="1e39"/></transform></shape>"#,
            &["outside single precision"],
        ),
        (
            r#"<shape type="sphere"><float name="radius" value="1e-39"/></shape>"#,
            &["outside single precision"],
        ),
        (
            r#"<shape type="cube"><transform name="to_world"><scale value="1e-20"/></transform></shape>"#,
            &["singular or nearly so"],
        ),
        (
            r#"<shape type="cube"><transform name="to_world"><scale value="1e20"/><scale value="1e20"/></transform></shape>"#,
            &["overflows single precision"],
        ),
        (
            r#"<sensor type="perspective"><transform name="to_world"><lookat origin="0,0,0" target="0,0,0" up="0,1,0"/></transform></sensor>"#,
            &["origin and target are the same"],
        ),
        (
            r#"<sensor type="perspective"><transform name="to_world"><lookat origin="0,0,0" target="0,1,0" up="0,1,0"/></transform></sensor>"#,
            &["parallel to the viewing direction"],
        ),
        (
            r#"<sensor type="perspective"><transform name="to_world"><lookat origin="0,0,0" target="0,0,1"/></transform></sensor>"#,
            &["missing attribute 'up'"],
        ),
        (
            r#"<shape type="cube"><boolean name="flip_normals" value="maybe"/></shape>"#,
            &["cannot parse 'maybe' as a boolean", "true, false"],
        ),
        (
            r#"<shape type="cube"><float name="flip_normals"/></shape>"#,
            &["must be a <boolean>"],
        ),
        (
            r#"<shape type="cube"><boolean name="flip_normals"/></shape>"#,
            &["missing attribute 'value'"],
        ),
        (
            r#"<shape type="cube"><float value="1"/></shape>"#,
            &["missing attribute 'name'"],
        ),
        (
            r#"<shape/>"#,
            &["missing attribute 'type'", "cube, rectangle"],
        ),
        (
            r#"<shape type="cube">text</shape>"#,
            &["unexpected text 'text'"],
        ),
    ];
    for (body, parts) in cases {
        let m = err(body);
        has(&m, &["test.xml:2:"]);
        has(&m, parts);
    }
}

#[test]
fn references_and_ids() {
    has(
        &err(r#"<shape type="cube"><ref id="nope"/></shape>"#),
        &["test.xml:2:", "reference to unknown id 'nope'"],
    );
    has(
        &err("<bsdf type=\"null\" id=\"a\"/>\n<bsdf type=\"null\" id=\"a\"/>"),
        &[
            "test.xml:3:",
            "duplicate id 'a'",
            "first defined at test.xml:2",
        ],
    );
    has(
        &err(r#"<bsdf type="twosided" id="loop"><ref id="loop"/></bsdf>"#),
        &["twosided BSDFs cannot be nested"],
    );
    has(
        &err(
            r#"<integrator type="volpath"/><shape type="cube"><medium type="homogeneous" name="inside"/></shape>"#,
        ),
        &["name=\"interior\" or name=\"exterior\"", "name=\"inside\""],
    );
    has(
        &err(r#"<shape type="cube"><bsdf type="null"/><bsdf type="null"/></shape>"#),
        &["a shape takes one BSDF"],
    );
    has(
        &err(r#"<shape type="cube"><float name="x" value="1" id="y"/></shape>"#),
        &["an 'id' is only allowed on objects"],
    );
}

#[test]
fn media_errors() {
    let cases: &[(&str, &[&str])] = &[
        (
            r#"<medium type="homogeneous"><float name="sigma_s" value="1"/></medium>"#,
            &["not 'sigma_s'", "sigma_t = sigma_s + sigma_a"],
        ),
        (
            r#"<medium type="homogeneous"><float name="sigma_t" value="1e38"/><float name="scale" value="10"/></medium>"#,
            &["sigma_t * scale", "overflows single precision"],
        ),
        (
            r#"<medium type="homogeneous"><float name="sigma_t" value="-1"/></medium>"#,
            &["invalid sigma_t", ">= 0"],
        ),
        (
            r#"<medium type="homogeneous"><rgb name="albedo" value="1.2"/></medium>"#,
            &["invalid albedo", "in [0, 1]"],
        ),
        (
            r#"<medium type="homogeneous"><phase type="hg"><float name="g" value="1"/></phase></medium>"#,
            &["invalid g = 1", "-1 < g < 1"],
        ),
        (
            r#"<medium type="heterogeneous"><volume type="gridvolume" name="sigma_t"/></medium>"#,
            &["missing required parameter 'filename'"],
        ),
        (
            r#"<medium type="heterogeneous"><volume type="gridvolume" name="sigma_t"><string name="filename" value="missing.vol"/></volume></medium>"#,
            &["cannot read grid", "missing.vol"],
        ),
        (
            r#"<medium type="heterogeneous"><volume type="gridvolume" name="sigma_t"><string name="filename" value="bad_header.vol"/></volume></medium>"#,
            &[
                "cannot load grid",
                "bad_header.vol",
                "shorter than the 48-byte header",
            ],
        ),
        (
            r#"<medium type="heterogeneous"><volume type="perlin" name="sigma_t"/></medium>"#,
            &["unknown volume type 'perlin'"],
        ),
        (
            r#"<medium type="homogeneous"><phase type="hg"/><phase type="isotropic"/></medium>"#,
            &["one phase function"],
        ),
    ];
    for (body, parts) in cases {
        let m = err(&format!("<integrator type=\"volpath\"/>{body}"));
        has(&m, &["test.xml:2:"]);
        has(&m, parts);
    }
    has(
        &err(r#"<shape type="cube"><medium type="homogeneous" name="interior"/></shape>"#),
        &["no <integrator>", "volpath"],
    );
    has(
        &err("<integrator type=\"path\"/>\n<medium type=\"homogeneous\"/>"),
        &[
            "test.xml:2:",
            "'path' integrator ignores participating media",
            "test.xml:3",
            "volpath",
        ],
    );
}

#[test]
fn grid_header_errors_from_temp_files() {
    let dir = tempfile::tempdir().unwrap();
    // A header claiming a 1e9^3 grid in a 48-byte file: an error, not an allocation.
    let mut b = Vec::new();
    b.extend(b"VOL");
    b.push(3);
    b.extend(1i32.to_le_bytes());
    for v in [1_000_000_000i32, 1_000_000_000, 1_000_000_000, 1] {
        b.extend(v.to_le_bytes());
    }
    for v in [0f32, 0., 0., 1., 1., 1.] {
        b.extend(v.to_le_bytes());
    }
    std::fs::write(dir.path().join("huge.vol"), &b).unwrap();
    // A valid 1x1x1 grid with a negative value, and a 6-channel one.
    let small = |vals: &[f32], ch: i32| {
        let mut b = Vec::new();
        b.extend(b"VOL");
        b.push(3);
        b.extend(1i32.to_le_bytes());
        for v in [1i32, 1, 1, ch] {
            b.extend(v.to_le_bytes());
        }
        for v in [0f32, 0., 0., 1., 1., 1.] {
            b.extend(v.to_le_bytes());
        }
        for v in vals {
            b.extend(v.to_le_bytes());
        }
        b
    };
    std::fs::write(dir.path().join("neg.vol"), small(&[-1.0], 1)).unwrap();
    std::fs::write(dir.path().join("six.vol"), small(&[1.0; 6], 6)).unwrap();
    let scene = |file: &str| {
        wrap(&format!(
            "<integrator type=\"volpath\"/>\n<medium type=\"heterogeneous\">\n<volume type=\"gridvolume\" name=\"sigma_t\"><string name=\"filename\" value=\"{file}\"/></volume></medium>"
        ))
    };
    for (file, part) in [
        ("huge.vol", "needs"),
        ("neg.vol", "out of range for 'sigma_t'"),
        ("six.vol", "6 channels"),
    ] {
        let e = load_str(&scene(file), "g.xml", dir.path(), &[]).unwrap_err();
        assert_eq!(e.kind, SceneErrorKind::Format, "{e}");
        has(&e.to_string(), &["g.xml:4:", file, part]);
    }
}

#[test]
fn mesh_file_errors_name_the_mesh_and_the_scene_line() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("bad.ply"), "ply\nformat ascii 1.0\nelement vertex 1000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n").unwrap();
    std::fs::write(dir.path().join("empty.obj"), "# nothing\n").unwrap();
    std::fs::write(
        dir.path().join("nan.obj"),
        "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    for (ty, file, part) in [
        ("ply", "bad.ply", "more than the file's remaining"),
        ("obj", "empty.obj", "no faces"),
        ("obj", "nan.obj", "not finite"),
        ("ply", "absent.ply", "cannot read PLY file"),
        ("obj", "absent.obj", "cannot read OBJ file"),
    ] {
        let xml = wrap(&format!(
            "<shape type=\"{ty}\">\n<string name=\"filename\" value=\"{file}\"/></shape>"
        ));
        let e = load_str(&xml, "m.xml", dir.path(), &[]).unwrap_err();
        has(&e.to_string(), &["m.xml:3:", file, part]);
    }
}

#[test]
fn document_level_errors() {
    let e = |xml: &str| {
        load_str(xml, "d.xml", &data_dir(), &[])
            .unwrap_err()
            .to_string()
    };
    has(
        &e("<scene><shape type=\"cube\"/></scene>"),
        &["missing attribute 'version'"],
    );
    has(
        &e("<scene version=\"4.0.0\"/>"),
        &["version \"4.0.0\" is newer than this loader"],
    );
    has(
        &e("<scenery version=\"3.0.0\"/>"),
        &["root element must be <scene"],
    );
    has(&e("<scene version=\"3.0.0\"><shape type=\"cube\"><default name=\"a\" value=\"1\"/></shape></scene>"), &["only allowed directly inside <scene>"]);
    has(
        &e("<scene version=\"3.0.0\"><default name=\"1a\" value=\"1\"/></scene>"),
        &["invalid default name '1a'"],
    );
    has(
        &e("<?xml version=\"1.0\"?><!DOCTYPE x [<!ENTITY a \"b\">]><scene version=\"3.0.0\"/>"),
        &["malformed XML"],
    );
    has(
        &e("<scene version=\"3.0.0\">hello</scene>"),
        &["unexpected text inside <scene>"],
    );
    let deep = format!(
        "<scene version=\"3.0.0\">{}{}</scene>",
        "<shape type=\"cube\">".repeat(40),
        "</shape>".repeat(40)
    );
    has(&e(&deep), &["nested more than 32 deep"]);
    assert!(load_str(
        "<scene version=\"3.0.0\"/>",
        "d.xml",
        &data_dir(),
        &[("bad name".into(), "1".into())]
    )
    .is_err());
}

/// Random chains of transform elements: the loader's matrix equals the
/// product `M_last · … · M_first` of the elements built independently here.
#[test]
fn random_transform_chains_compose_in_mitsuba_order() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
    for _ in 0..200 {
        let mut xml = String::new();
        let mut expected = glam::DMat4::IDENTITY;
        for _ in 0..rng.random_range(1..6) {
            let v: [f64; 3] = [
                rng.random_range(-3.0..3.0),
                rng.random_range(-3.0..3.0),
                rng.random_range(-3.0..3.0),
            ];
            let step = match rng.random_range(0..4) {
                0 => {
                    xml += &format!("<translate x=\"{}\" y=\"{}\" z=\"{}\"/>", v[0], v[1], v[2]);
                    glam::DMat4::from_translation(v.into())
                }
                1 => {
                    let s = v.map(|c| c.abs() + 0.5);
                    xml += &format!("<scale value=\"{}, {}, {}\"/>", s[0], s[1], s[2]);
                    glam::DMat4::from_scale(s.into())
                }
                2 => {
                    let angle: f64 = rng.random_range(-180.0..180.0);
                    let axis = glam::DVec3::from(v) + glam::DVec3::splat(0.1);
                    xml += &format!(
                        "<rotate value=\"{} {} {}\" angle=\"{angle}\"/>",
                        axis.x, axis.y, axis.z
                    );
                    // Mitsuba does not normalise the axis: c I + (1-c) a a^T + s [a]x.
                    let (sn, cs) = angle.to_radians().sin_cos();
                    let outer = glam::DMat3::from_cols(axis * axis.x, axis * axis.y, axis * axis.z);
                    let cross = glam::DMat3::from_cols(
                        glam::DVec3::new(0.0, axis.z, -axis.y),
                        glam::DVec3::new(-axis.z, 0.0, axis.x),
                        glam::DVec3::new(axis.y, -axis.x, 0.0),
                    );
                    glam::DMat4::from_mat3(
                        glam::DMat3::IDENTITY * cs + outer * (1.0 - cs) + cross * sn,
                    )
                }
                _ => {
                    let m: Vec<f64> = (0..12).map(|_| rng.random_range(-2.0..2.0)).collect();
                    let rows = [&m[0..4], &m[4..8], &m[8..12], &[0.0, 0.0, 0.0, 1.0][..]];
                    xml += &format!(
                        "<matrix value=\"{}\"/>",
                        rows.iter()
                            .flat_map(|r| r.iter().map(|x| x.to_string()))
                            .collect::<Vec<_>>()
                            .join(" ")
                    );
                    glam::DMat4::from_cols_array_2d(&[
                        [rows[0][0], rows[1][0], rows[2][0], rows[3][0]],
                        [rows[0][1], rows[1][1], rows[2][1], rows[3][1]],
                        [rows[0][2], rows[1][2], rows[2][2], rows[3][2]],
                        [rows[0][3], rows[1][3], rows[2][3], rows[3][3]],
                    ])
                }
            };
            expected = step * expected;
        }
        if expected.determinant().abs() < 1e-3 {
            continue;
        }
        let s = ok(&format!(
            "<shape type=\"cube\"><transform name=\"to_world\">{xml}</transform></shape>"
        ));
        let got = s.shapes[0].to_world.as_dmat4();
        let scale = expected
            .to_cols_array()
            .iter()
            .fold(1.0f64, |a, b| a.max(b.abs()));
        for (a, b) in got.to_cols_array().iter().zip(expected.to_cols_array()) {
            // f32 rounding of the composed matrix: a few ulps of its largest entry.
            assert!((a - b).abs() <= 1e-6 * scale, "{xml}\n{got}\n{expected}");
        }
    }
}

#[test]
fn a_define_the_scene_never_uses_is_an_error_naming_it() {
    let xml = r#"<scene version="3.0.0"><default name="spp" value="4"/>
        <sensor type="perspective"><sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
        <film type="hdrfilm"><integer name="width" value="$w"/><integer name="height" value="8"/></film></sensor></scene>"#;
    let dir = std::path::Path::new(".");
    let ok = [
        ("spp".to_string(), "2".to_string()),
        ("w".to_string(), "8".to_string()),
    ];
    assert!(fgf_scene::load_str(xml, "t.xml", dir, &ok).is_ok());
    let typo = [
        ("w".to_string(), "8".to_string()),
        ("sps".to_string(), "2".to_string()),
    ];
    let e = fgf_scene::load_str(xml, "t.xml", dir, &typo)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("t.xml") && e.contains("'sps'") && e.contains("spp"),
        "{e}"
    );
}

#[test]
fn sample_emitters_is_read_per_medium_and_defaults_to_true() {
    let s = ok(r#"<integrator type="volpath"/>
<shape type="cube"><medium type="homogeneous" name="interior">
    <boolean name="sample_emitters" value="false"/>
</medium></shape>
<shape type="cube"><medium type="heterogeneous" name="interior">
    <boolean name="sample_emitters" value="false"/>
</medium></shape>
<shape type="cube"><medium type="homogeneous" name="interior"/></shape>"#);
    let flags: Vec<bool> = s
        .media
        .iter()
        .map(|m| match m {
            MediumDesc::Homogeneous {
                sample_emitters, ..
            }
            | MediumDesc::Heterogeneous {
                sample_emitters, ..
            } => *sample_emitters,
            m => panic!("{m:?}"),
        })
        .collect();
    assert_eq!(flags, [false, false, true]);
}
