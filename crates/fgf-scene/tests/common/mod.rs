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
