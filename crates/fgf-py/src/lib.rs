//! `fgf._core`: the private native module behind the Python package `fgf`.
//!
//! This crate only converts types, releases the GIL around heavy work and
//! maps core errors to Python exceptions; the physics lives in the other
//! crates. Each area registers its functions from its own file.

use pyo3::prelude::*;

mod ensemble;
mod errors;
mod field;
mod progress;
mod render;
mod transmittance;
mod truth;
mod vdb;

pub use errors::{FgfError, ParameterError, SceneError};

/// Large blocks backed by huge pages from their first touch
/// ([`fgf_render::HugePages`]).
#[global_allocator]
static ALLOC: fgf_render::HugePages = fgf_render::HugePages;

/// The widest vector instructions this build of the module was compiled
/// for (`fgf._core.simd`; `fgf --version` prints it): `avx512` and `avx2`
/// for builds for a given CPU, `sse2` for the portable x86-64 build.
const SIMD: &str = if cfg!(target_feature = "avx512f") {
    "avx512"
} else if cfg!(target_feature = "avx2") {
    "avx2"
} else if cfg!(target_feature = "sse2") {
    "sse2"
} else if cfg!(target_feature = "neon") {
    "neon"
} else {
    "scalar"
};

/// 1 if this CPU, with its operating system, runs code compiled for
/// x86-64-v3 (`-C target-cpu=x86-64-v3`: every feature that level adds to
/// the portable build's, AVX2 and FMA among them), else 0. A wheel carries
/// such a build of the module beside the portable one; `fgf/_native.py`
/// calls this function of the portable build through `ctypes`, before
/// either is imported, to choose which to load. Plain C, no Python: it runs
/// without the module being initialised.
#[no_mangle]
pub extern "C" fn fgf_runs_x86_64_v3() -> i32 {
    #[cfg(target_arch = "x86_64")]
    {
        let all = is_x86_feature_detected!("avx")
            && is_x86_feature_detected!("avx2")
            && is_x86_feature_detected!("bmi1")
            && is_x86_feature_detected!("bmi2")
            && is_x86_feature_detected!("cmpxchg16b")
            && is_x86_feature_detected!("f16c")
            && is_x86_feature_detected!("fma")
            && is_x86_feature_detected!("lzcnt")
            && is_x86_feature_detected!("movbe")
            && is_x86_feature_detected!("popcnt")
            && is_x86_feature_detected!("sse3")
            && is_x86_feature_detected!("sse4.1")
            && is_x86_feature_detected!("sse4.2")
            && is_x86_feature_detected!("ssse3")
            && is_x86_feature_detected!("xsave");
        i32::from(all)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        0
    }
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("simd", SIMD)?;
    m.add("FgfError", py.get_type::<FgfError>())?;
    m.add("ParameterError", py.get_type::<ParameterError>())?;
    m.add("SceneError", py.get_type::<SceneError>())?;
    transmittance::register(m)?;
    field::register(m)?;
    render::register(m)?;
    ensemble::register(m)?;
    truth::register(m)?;
    vdb::register(m)?;
    Ok(())
}
