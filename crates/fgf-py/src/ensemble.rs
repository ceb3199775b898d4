//! Python binding of the explicit-realization ensemble (issue 5):
//! `ensemble_scene` behind `fgf.ensemble` and `fgf ensemble`.

use crate::errors::{ParameterError, SceneError};
use crate::progress::run_job;
use fgf_render::ensemble::{ensemble, total_samples, EnsembleOptions};
use fgf_render::scene::SceneErrorKind;
use fgf_render::RenderError;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::PyOSError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// Average classical renders of `realizations` explicit 3D realizations of
/// the scene's `fgf` media. Returns `(mean, stderr, info, interrupted)`
/// where `info` is a dict (`realizations_done`, `spp`, and `media`: one dict
/// per medium with its grid and variance report); the typed wrapper is
/// `fgf.ensemble`.
#[pyfunction]
#[pyo3(signature = (scene, realizations, resolution=None, spp=None, seed=0, threads=None, defines=None, progress=None))]
#[allow(clippy::too_many_arguments)]
fn ensemble_scene<'py>(
    py: Python<'py>,
    scene: PathBuf,
    realizations: u32,
    resolution: Option<usize>,
    spp: Option<u32>,
    seed: u64,
    threads: Option<usize>,
    defines: Option<Vec<(String, String)>>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<(
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Bound<'py, PyDict>,
    bool,
)> {
    if realizations == 0 {
        return Err(ParameterError::new_err(
            "realizations = 0; need at least 1 (2 for a standard error)",
        ));
    }
    if spp == Some(0) {
        return Err(ParameterError::new_err(
            "spp = 0; need at least 1 sample per pixel",
        ));
    }
    if resolution.is_some_and(|r| r < 2) {
        return Err(ParameterError::new_err(format!(
            "resolution = {}; need at least 2 voxels along the longest side",
            resolution.unwrap_or(0)
        )));
    }
    if threads == Some(0) {
        return Err(ParameterError::new_err(
            "threads = 0; need at least 1 thread (or None for all cores)",
        ));
    }
    let defines = defines.unwrap_or_default();
    let desc = py
        .detach(|| fgf_render::scene::load_file(&scene, &defines))
        .map_err(|e| match e.kind {
            SceneErrorKind::Io => PyOSError::new_err(e.to_string()),
            _ => SceneError::new_err(e.to_string()),
        })?;
    let opts = EnsembleOptions {
        realizations,
        resolution: resolution.unwrap_or(fgf_render::ensemble::DEFAULT_RESOLUTION),
        spp,
        seed,
    };
    let total = total_samples(&desc, &opts);
    let source = scene.display().to_string();
    let job = run_job(py, total, "ensemble", progress.as_ref(), |counter| {
        let go = || ensemble(&desc, &opts, counter);
        match threads {
            Some(t) => match rayon::ThreadPoolBuilder::new().num_threads(t).build() {
                Ok(pool) => pool.install(go),
                Err(e) => Err(RenderError::InvalidOption(format!(
                    "cannot start {t} threads: {e}"
                ))),
            },
            None => go(),
        }
    })?;
    let interrupted = job.interrupted;
    let out = job.value.map_err(|e| match e {
        RenderError::InvalidOption(_) => ParameterError::new_err(e.to_string()),
        _ => SceneError::new_err(format!("{source}: {e}")),
    })?;
    let (h, w) = (out.height, out.width);
    let mean = PyArray1::from_vec(py, out.mean)
        .reshape([h, w, 3])?
        .into_any();
    let stderr = PyArray1::from_vec(py, out.stderr)
        .reshape([h, w, 3])?
        .into_any();
    let info = PyDict::new(py);
    info.set_item("realizations_done", out.realizations_done)?;
    info.set_item("realizations_requested", out.realizations_requested)?;
    info.set_item("spp", out.spp)?;
    let media = pyo3::types::PyList::empty(py);
    for m in &out.media {
        let d = PyDict::new(py);
        d.set_item("medium", m.medium)?;
        d.set_item("shape", m.shape.to_vec())?;
        d.set_item("spacing", m.spacing)?;
        d.set_item("bbox", m.bbox.to_vec())?;
        d.set_item("sw_3d", m.sw_3d)?;
        d.set_item("clamped_fraction", m.clamped_fraction)?;
        d.set_item("variance_length", m.variance_length)?;
        d.set_item("realized_variance", m.realized_variance)?;
        d.set_item("continuum_variance", m.continuum_variance)?;
        media.append(d)?;
    }
    info.set_item("media", media)?;
    Ok((mean, stderr, info, interrupted || out.interrupted))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(ensemble_scene, m)?)?;
    Ok(())
}
