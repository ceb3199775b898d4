//! `SceneDesc::validate` on scenes built in code: each family of rules
//! refuses what the renderer cannot compile, with a message naming the
//! object, and a loaded scene and a built one obey the same rule.

mod common;

use common::{cube, has, minimal_scene, reference_scene};
use fgf_scene::*;
use std::sync::Arc;

/// The message of a scene that must be refused.
fn refused(s: &SceneDesc) -> String {
    match s.validate() {
        Ok(()) => panic!("expected {s:#?} to be refused"),
        Err(e) => {
            assert_eq!(e.kind, SceneErrorKind::Invalid);
            e.to_string()
        }
    }
}

fn fgf_medium(sigma_t: Rgb, hurst: f64, length: Option<f64>) -> MediumDesc {
    MediumDesc::NonExponential {
        sigma_t,
        albedo: [0.8; 3],
        phase: PhaseDesc::Isotropic,
        model: TransmittanceDesc::Fgf {
            hurst,
            sw: 4.0,
            length,
        },
        kernel: KernelDesc::EnergyConserving,
        density: None,
    }
}

#[test]
fn loaded_and_minimal_scenes_are_valid() {
    minimal_scene().validate().unwrap();
    for name in ["cube-homogeneous.xml", "cube-heterogeneous.xml"] {
        load_file(&reference_scene(name), &[])
            .unwrap()
            .validate()
            .unwrap();
    }
}

#[test]
fn references_must_exist() {
    let mut s = minimal_scene();
    s.shapes[0].bsdf = 3;
    has(
        &refused(&s),
        &["shape 0 (cube)", "refers to BSDF 3", "has 1"],
    );
    let mut s = minimal_scene();
    s.integrator.kind = IntegratorKind::Volpath;
    s.shapes[0].interior = Some(0);
    has(&refused(&s), &["shape 0", "interior refers to medium 0"]);
    let mut s = minimal_scene();
    s.sensor.medium = Some(2);
    has(&refused(&s), &["the sensor", "refers to medium 2"]);
}

#[test]
fn the_path_integrator_refuses_media() {
    let mut s = minimal_scene();
    s.integrator.kind = IntegratorKind::Path;
    s.media.push(fgf_medium([4.0; 3], -0.1, None));
    s.shapes[0].interior = Some(0);
    has(
        &refused(&s),
        &[
            "the integrator",
            "'path' integrator ignores",
            "medium 0",
            "volpath",
        ],
    );
    s.integrator.kind = IntegratorKind::Volpath;
    s.validate().unwrap();
}

#[test]
fn non_exponential_media_follow_fgf_cores_constructors() {
    // fgf-core's models need sigma_t > 0, so a zero channel is refused
    // (it is not taken as a transparent channel), for every model.
    let mut s = minimal_scene();
    s.media.push(fgf_medium([4.0, 0.0, 4.0], -0.1, None));
    s.shapes[0].interior = Some(0);
    has(&refused(&s), &["medium 0", "invalid sigma_t = 0", "> 0"]);
    if let MediumDesc::NonExponential { model, .. } = &mut s.media[0] {
        *model = TransmittanceDesc::Exponential;
    }
    has(&refused(&s), &["medium 0", "invalid sigma_t = 0"]);
    // k-fBm needs its length, white and pink noise refuse one.
    s.media[0] = fgf_medium([4.0; 3], 1.2, None);
    has(&refused(&s), &["medium 0", "length", "required for k-fBm"]);
    s.media[0] = fgf_medium([4.0; 3], -0.1, Some(1.0));
    has(&refused(&s), &["medium 0", "length", "only used by k-fBm"]);
    s.media[0] = fgf_medium([4.0; 3], 1.2, Some(1.0));
    s.validate().unwrap();
    if let MediumDesc::NonExponential { model, .. } = &mut s.media[0] {
        *model = TransmittanceDesc::DavisWeinstein { h: 0.3, c: 1.0 };
    }
    has(&refused(&s), &["invalid h = 0.3", "0.5 <= h <= 1"]);
}

#[test]
fn numbers_out_of_range_name_the_parameter_and_range() {
    let mut s = minimal_scene();
    s.sensor.fov = 180.0;
    has(
        &refused(&s),
        &["the sensor", "invalid fov = 180", "0 < fov < 180 degrees"],
    );
    let mut s = minimal_scene();
    s.sensor.width = 0;
    has(&refused(&s), &["invalid width = 0", "1 <= value <= 65536"]);
    let mut s = minimal_scene();
    s.sensor.width = 65_536;
    s.sensor.height = 65_536;
    has(&refused(&s), &["larger than the limit"]);
    let mut s = minimal_scene();
    s.bsdfs[0] = BsdfDesc::Diffuse {
        reflectance: [0.5, 1.5, 0.5],
    };
    has(
        &refused(&s),
        &[
            "bsdf 0",
            "invalid reflectance = (0.5, 1.5, 0.5)",
            "in [0, 1]",
        ],
    );
    let mut s = minimal_scene();
    s.media.push(MediumDesc::Homogeneous {
        sigma_t: [1.0, f32::NAN, 1.0],
        albedo: [0.5; 3],
        phase: PhaseDesc::Hg { g: 0.5 },
        sample_emitters: true,
    });
    has(&refused(&s), &["medium 0", "invalid sigma_t", ">= 0"]);
    s.media[0] = MediumDesc::Homogeneous {
        sigma_t: [1.0; 3],
        albedo: [0.5; 3],
        phase: PhaseDesc::Hg { g: -1.0 },
        sample_emitters: true,
    };
    has(&refused(&s), &["medium 0", "invalid g = -1", "-1 < g < 1"]);
}

#[test]
fn a_loaded_and_a_built_scene_get_the_same_rule() {
    // The loader checks `fov` where it reads it, with the validator's range.
    let xml = "<scene version=\"3.0.0\"><sensor type=\"perspective\"><float name=\"fov\" value=\"200\"/></sensor></scene>";
    let loaded = load_str(xml, "t.xml", std::path::Path::new("."), &[]).unwrap_err();
    let mut s = minimal_scene();
    s.sensor.fov = 200.0;
    let built = refused(&s);
    let rule = "invalid fov = 200 (valid: 0 < fov < 180 degrees)";
    has(&loaded.to_string(), &["t.xml:1:", rule]);
    has(&built, &[rule]);
}

#[test]
fn transforms_meshes_and_grids_must_be_usable() {
    let mut s = minimal_scene();
    s.shapes[0].to_world = glam::Mat4::from_scale(glam::Vec3::new(1.0, 0.0, 1.0));
    has(&refused(&s), &["shape 0", "singular"]);
    let mut s = minimal_scene();
    s.shapes[0].geometry = GeometryDesc::Sphere {
        center: glam::Vec3::ZERO,
        radius: 1.0,
    };
    s.shapes[0].to_world = glam::Mat4::from_scale(glam::Vec3::new(1.0, 2.0, 1.0));
    has(&refused(&s), &["non-uniform scale"]);
    let mut s = minimal_scene();
    s.shapes[0].geometry = GeometryDesc::Mesh(Arc::new(TriangleMesh {
        positions: vec![glam::Vec3::ZERO, glam::Vec3::X, glam::Vec3::Y],
        normals: Some(vec![glam::Vec3::Z; 2]),
        texcoords: None,
        indices: vec![[0, 1, 2]],
    }));
    has(
        &refused(&s),
        &["invalid mesh", "2 vertex normals for 3 vertices"],
    );
    let mut s = minimal_scene();
    s.shapes[0].geometry = GeometryDesc::Mesh(Arc::new(TriangleMesh {
        positions: vec![glam::Vec3::ZERO, glam::Vec3::X, glam::Vec3::Y],
        normals: None,
        texcoords: None,
        indices: vec![[0, 1, 3]],
    }));
    has(&refused(&s), &["face index [0, 1, 3] is out of range"]);
    let grid = |data: Vec<f32>| {
        VolumeDesc::Grid(GridVolumeDesc {
            grid: Arc::new(fgf_io::vol::VolGrid {
                shape: [2, 2, 2],
                channels: 1,
                bbox: [0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
                data,
            }),
            to_world: glam::Mat4::IDENTITY,
            use_grid_bbox: false,
            filter: GridFilter::Trilinear,
            wrap: fgf_scene::WrapMode::Clamp,
        })
    };
    let mut s = minimal_scene();
    s.shapes[0].interior = Some(0);
    s.media.push(MediumDesc::Heterogeneous {
        sigma_t: grid(vec![1.0; 7]),
        albedo: VolumeDesc::Constant([0.5; 3]),
        scale: 1.0,
        phase: PhaseDesc::Isotropic,
        sample_emitters: true,
    });
    has(&refused(&s), &["medium 0", "holds 7 values", "[2, 2, 2]"]);
    let mut bad = vec![1.0; 8];
    bad[5] = f32::INFINITY;
    if let MediumDesc::Heterogeneous { sigma_t, .. } = &mut s.media[0] {
        *sigma_t = grid(bad);
    }
    has(&refused(&s), &["'sigma_t' grid value #5 = inf", ">= 0"]);
}

#[test]
fn emitters_area_only_on_shapes_and_one_environment() {
    let mut s = minimal_scene();
    s.emitters.push(EmitterDesc::Area {
        radiance: [1.0; 3],
        texture: None,
    });
    has(&refused(&s), &["emitter 0", "must be attached to a shape"]);
    let mut s = minimal_scene();
    s.emitters
        .push(EmitterDesc::Constant { radiance: [1.0; 3] });
    s.emitters
        .push(EmitterDesc::Constant { radiance: [2.0; 3] });
    has(
        &refused(&s),
        &[
            "emitter 1",
            "more than one constant environment emitter",
            "emitter 0",
        ],
    );
    let mut s = minimal_scene();
    s.shapes.push(cube(0, None));
    s.shapes[1].emitter = Some(EmitterDesc::Point {
        position: glam::Vec3::ZERO,
        intensity: [1.0; 3],
    });
    has(&refused(&s), &["shape 1", "must be an area emitter"]);
}
