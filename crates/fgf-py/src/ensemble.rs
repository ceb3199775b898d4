//! Python binding of the explicit-realization ensemble:
//! `ensemble_scene` behind `fgf.ensemble` and `fgf ensemble`.

use crate::errors::ParameterError;
use crate::progress::run_job;
use crate::render::{check_spp_threads, in_pool, load_scene, render_err, to_hw3};
use fgf_render::ensemble::{
    ensemble_from, total_samples, EnsembleError, EnsembleOptions, Marginal,
};
use numpy::PyArrayMethods;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// What `ensemble_scene` returns: `(mean, stderr, info, interrupted)`.
type EnsembleResult<'py> = (
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Bound<'py, PyDict>,
    bool,
);

/// Average classical renders of `realizations` explicit 3D realizations of
/// the scene's `fgf` media. Returns `(mean, stderr, info, interrupted)`
/// where `info` is a dict (`realizations_done`, `spp`, and `media`: one dict
/// per medium with its grid and variance report); the typed wrapper is
/// `fgf.ensemble`. `first` selects the realizations
/// `first..first + realizations` (a distributed ensemble renders each one
/// as its own task and merges them in index order).
#[pyfunction]
#[pyo3(signature = (scene, realizations, resolution=None, spp=None, seed=0, threads=None, defines=None, progress=None, padding=None, marginal=None, keep_realizations=false, first=0))]
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
    padding: Option<f64>,
    marginal: Option<String>,
    keep_realizations: bool,
    first: u32,
) -> PyResult<EnsembleResult<'py>> {
    let marginal = match marginal.as_deref() {
        None => Marginal::Auto,
        Some(m) => Marginal::parse(m).ok_or_else(|| {
            ParameterError::new_err(format!(
                "marginal = {m:?}; must be 'auto', 'gamma' or 'gaussian'"
            ))
        })?,
    };
    let padding = padding.unwrap_or(fgf_render::ensemble::DEFAULT_PADDING);
    if !(padding.is_finite() && (1.0..=16.0).contains(&padding)) {
        return Err(ParameterError::new_err(format!(
            "padding = {padding}; the periodic synthesis domain must be 1 to 16 grid sides per axis"
        )));
    }
    if realizations == 0 {
        return Err(ParameterError::new_err(
            "realizations = 0; need at least 1 (2 for a standard error)",
        ));
    }
    check_spp_threads(spp, threads)?;
    if resolution.is_some_and(|r| r < 2) {
        return Err(ParameterError::new_err(format!(
            "resolution = {}; need at least 2 voxels along the longest side",
            resolution.unwrap_or(0)
        )));
    }
    let desc = load_scene(py, &scene, defines)?;
    let opts = EnsembleOptions {
        realizations,
        resolution: resolution.unwrap_or(fgf_render::ensemble::DEFAULT_RESOLUTION),
        spp,
        seed,
        padding,
        marginal,
        keep_realizations,
    };
    let total = total_samples(&desc, &opts);
    let source = scene.display().to_string();
    let job = run_job(py, total, "ensemble", progress.as_ref(), |counter| {
        in_pool(threads, || ensemble_from(&desc, &opts, first, counter))
    })?;
    // A cancelled ensemble still returns the realizations finished.
    let (out, cancelled) = match job.value {
        Ok(out) => (out, false),
        Err(EnsembleError::Cancelled { partial }) => (*partial, true),
        Err(EnsembleError::Render(e)) => return Err(render_err(e, &source)),
    };
    let (h, w) = (out.height, out.width);
    let mean = to_hw3(py, out.mean, h, w)?;
    let stderr = to_hw3(py, out.stderr, h, w)?;
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
        d.set_item("padded_shape", m.padded_shape.clone())?;
        d.set_item("marginal", m.marginal)?;
        d.set_item("sw_3d", m.sw_3d)?;
        d.set_item("hurst_field", m.hurst_field)?;
        d.set_item("alpha_voxel", m.alpha_voxel)?;
        d.set_item("mean_sigma_t", m.mean_sigma_t)?;
        d.set_item("model_mean_sigma_t", m.model_mean_sigma_t)?;
        d.set_item("lengths", m.lengths.clone())?;
        d.set_item("model_variances", m.model_variances.clone())?;
        d.set_item("grid_variances", m.grid_variances.clone())?;
        d.set_item("clamped_fraction", m.clamped_fraction)?;
        d.set_item("variance_length", m.variance_length)?;
        d.set_item("realized_variance", m.realized_variance)?;
        d.set_item("continuum_variance", m.continuum_variance)?;
        media.append(d)?;
    }
    info.set_item("media", media)?;
    if keep_realizations {
        let n = out.realization_images.len();
        let flat: Vec<f32> = out.realization_images.concat();
        let arr = numpy::PyArray1::from_vec(py, flat).reshape([n, h, w, 3])?;
        info.set_item("realizations", arr)?;
    }
    Ok((mean, stderr, info, job.interrupted || cancelled))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(ensemble_scene, m)?)?;
    Ok(())
}
