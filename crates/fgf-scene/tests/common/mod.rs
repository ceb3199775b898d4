//! Helpers shared by the loader tests: where the reference scenes and the
//! test data are, and small assertions.

#![allow(dead_code)] // each test file uses a subset

use std::path::PathBuf;

/// `scenes/reference/` of the repository: the two reference scenes and
/// their `density64.vol`, also used by the renderer's tests, pytest and the
/// benchmarks.
pub fn reference_dir() -> PathBuf {
    PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenes/reference"
    ))
}

/// A file of [`reference_dir`].
pub fn reference_scene(name: &str) -> PathBuf {
    let p = reference_dir().join(name);
    assert!(p.exists(), "reference scene {} is missing", p.display());
    p
}

/// `tests/data/` of this crate: small meshes, grids and includes.
pub fn data_dir() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data"))
}

/// `scenes/meshes/` of the repository (the meshes the user scenes use).
pub fn meshes_dir() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/meshes"))
}

/// Assert `msg` contains every one of `parts`.
pub fn has(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "message lacks {p:?}:\n{msg}");
    }
}

/// A valid scene built in code: `volpath`, a 32×24 camera at the origin,
/// one unit cube (diffuse 0.5) and no media or emitters.
pub fn minimal_scene() -> fgf_scene::SceneDesc {
    use fgf_scene::*;
    SceneDesc {
        source: "in-code scene".into(),
        integrator: IntegratorDesc {
            kind: IntegratorKind::Volpath,
            max_depth: -1,
            rr_depth: 5,
            hide_emitters: false,
        },
        sensor: SensorDesc {
            to_world: glam::Mat4::IDENTITY,
            fov: 45.0,
            fov_axis: FovAxis::X,
            principal_point: [0.0, 0.0],
            near_clip: 0.01,
            far_clip: 100.0,
            width: 32,
            height: 24,
            rfilter: FilterDesc::Box,
            spp: 4,
            seed: 0,
            medium: None,
        },
        shapes: vec![cube(0, None)],
        bsdfs: vec![BsdfDesc::Diffuse {
            reflectance: [0.5; 3],
        }],
        emitters: Vec::new(),
        media: Vec::new(),
    }
}

/// A unit cube at `z = 5` with BSDF `bsdf` and medium `interior`.
pub fn cube(bsdf: usize, interior: Option<usize>) -> fgf_scene::ShapeDesc {
    fgf_scene::ShapeDesc {
        name: "cube".into(),
        geometry: fgf_scene::GeometryDesc::Cube,
        to_world: glam::Mat4::from_translation(glam::Vec3::new(0.0, 0.0, 5.0)),
        flip_normals: false,
        bsdf,
        emitter: None,
        interior,
        exterior: None,
    }
}
