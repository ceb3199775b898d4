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

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
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
