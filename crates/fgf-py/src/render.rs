//! Python bindings for the render area: `render_scene` (behind
//! `fgf.render`), `write_exr`, `write_png`.

use crate::errors::{io_err, ParameterError, SceneError};
use crate::progress::run_job;
use fgf_render::{RenderError, RenderOptions};
use fgf_scene::SceneErrorKind;
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::exceptions::PyOSError;
use pyo3::prelude::*;
use std::path::PathBuf;

pub(crate) fn scene_err(e: fgf_scene::SceneError) -> PyErr {
    match e.kind {
        SceneErrorKind::Io => PyOSError::new_err(e.to_string()),
        _ => SceneError::new_err(e.to_string()),
    }
}

pub(crate) fn render_err(e: RenderError, source: &str) -> PyErr {
    match e {
        RenderError::Scene(e) => scene_err(e),
        RenderError::InvalidOption(_) | RenderError::Field { .. } => {
            ParameterError::new_err(e.to_string())
        }
        _ => SceneError::new_err(format!("{source}: {e}")),
    }
}

pub(crate) fn to_hw3<'py>(
    py: Python<'py>,
    data: Vec<f32>,
    h: usize,
    w: usize,
) -> PyResult<Bound<'py, PyAny>> {
    Ok(PyArray1::from_vec(py, data).reshape([h, w, 3])?.into_any())
}

/// Reject `spp = 0` and `threads = 0` (shared by render and ensemble).
pub(crate) fn check_spp_threads(spp: Option<u32>, threads: Option<usize>) -> PyResult<()> {
    if spp == Some(0) {
        return Err(ParameterError::new_err(
            "spp = 0; need at least 1 sample per pixel",
        ));
    }
    if threads == Some(0) {
        return Err(ParameterError::new_err(
            "threads = 0; need at least 1 thread (or None for all cores)",
        ));
    }
    Ok(())
}

/// Load a scene with the GIL released; loader errors become `OSError` or
/// `fgf.SceneError`.
pub(crate) fn load_scene(
    py: Python<'_>,
    scene: &std::path::Path,
    defines: Option<Vec<(String, String)>>,
) -> PyResult<fgf_scene::SceneDesc> {
    let defines = defines.unwrap_or_default();
    let scene = scene.to_path_buf();
    crate::progress::run_interruptible(py, move |cancel| {
        fgf_scene::load_file_cancellable(&scene, &defines, Some(cancel))
    })?
    .map_err(scene_err)
}

/// Run `go` on a local rayon pool of `threads` workers (all cores if
/// `None`); the global pool is left alone.
pub(crate) fn in_pool<R: Send, E: From<RenderError> + Send>(
    threads: Option<usize>,
    go: impl FnOnce() -> Result<R, E> + Send,
) -> Result<R, E> {
    match threads {
        Some(t) => match rayon::ThreadPoolBuilder::new().num_threads(t).build() {
            Ok(pool) => pool.install(go),
            Err(e) => {
                Err(RenderError::InvalidOption(format!("cannot start {t} threads: {e}")).into())
            }
        },
        None => go(),
    }
}

/// What `render_scene` returns: `(image, variance or None, spp_done,
/// interrupted)`.
type RenderResult<'py> = (Bound<'py, PyAny>, Option<Bound<'py, PyAny>>, u32, bool);

/// Render a Mitsuba 3 XML scene. Returns `(image, variance or None,
/// spp_done, interrupted)`; the typed wrapper is `fgf.render`.
#[pyfunction]
#[pyo3(signature = (scene, spp=None, seed=None, threads=None, defines=None, progress=None, return_variance=false))]
#[allow(clippy::too_many_arguments)]
fn render_scene<'py>(
    py: Python<'py>,
    scene: PathBuf,
    spp: Option<u32>,
    seed: Option<u64>,
    threads: Option<usize>,
    defines: Option<Vec<(String, String)>>,
    progress: Option<Bound<'py, PyAny>>,
    return_variance: bool,
) -> PyResult<RenderResult<'py>> {
    check_spp_threads(spp, threads)?;
    let desc = load_scene(py, &scene, defines)?;
    let opts = RenderOptions {
        spp,
        seed,
        variance: return_variance,
        spp_per_pass: None,
    };
    let total_spp = spp.unwrap_or(desc.sensor.spp) as u64;
    let total = desc.sensor.width as u64 * desc.sensor.height as u64 * total_spp;
    let source = scene.display().to_string();
    let job = run_job(py, total, "render", progress.as_ref(), |counter| {
        in_pool(threads, || fgf_render::render(&desc, &opts, counter))
    })?;
    // A cancelled render still returns the image of the passes finished.
    let (out, cancelled) = match job.value {
        Ok(out) => (out, false),
        Err(RenderError::Cancelled { partial }) => (*partial, true),
        Err(e) => return Err(render_err(e, &source)),
    };
    let img = to_hw3(py, out.image, out.height, out.width)?;
    let var = match out.variance {
        Some(v) => Some(to_hw3(py, v, out.height, out.width)?),
        None => None,
    };
    Ok((img, var, out.spp_done, job.interrupted || cancelled))
}

fn image_data(img: &PyReadonlyArray3<'_, f32>) -> PyResult<(usize, usize, Vec<f32>)> {
    let shape = img.shape();
    if shape[2] != 3 {
        return Err(ParameterError::new_err(format!(
            "image has shape {shape:?}; expected (H, W, 3)"
        )));
    }
    let data: Vec<f32> = img.as_array().iter().copied().collect();
    Ok((shape[0], shape[1], data))
}

/// Write an `(H, W, 3)` float32 image as a linear float32 EXR (atomically).
#[pyfunction]
fn write_exr(py: Python<'_>, path: PathBuf, img: PyReadonlyArray3<'_, f32>) -> PyResult<()> {
    let (h, w, data) = image_data(&img)?;
    py.detach(|| fgf_io::image::write_exr(&path, w, h, 3, &data))
        .map_err(io_err)
}

/// Write an `(H, W, 3)` float32 linear image as an 8-bit sRGB PNG preview
/// (`exposure` in stops), atomically.
#[pyfunction]
#[pyo3(signature = (path, img, exposure=0.0))]
fn write_png(
    py: Python<'_>,
    path: PathBuf,
    img: PyReadonlyArray3<'_, f32>,
    exposure: f32,
) -> PyResult<()> {
    if !exposure.is_finite() {
        return Err(ParameterError::new_err(format!(
            "invalid exposure = {exposure}: must be a finite number of stops (|exposure| < 3.4e38)"
        )));
    }
    let (h, w, data) = image_data(&img)?;
    py.detach(|| fgf_io::image::write_png_preview(&path, w, h, 3, &data, exposure))
        .map_err(io_err)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(render_scene, m)?)?;
    m.add_function(wrap_pyfunction!(write_exr, m)?)?;
    m.add_function(wrap_pyfunction!(write_png, m)?)?;
    Ok(())
}
