//! Python bindings for the field area (`fgf_field`): synthesis, exact 1D
//! samplers, estimators and exports. Only type conversion, GIL release and
//! error mapping here; the typed, documented API is `python/fgf/field.py`.

use crate::errors::{io_err, param_err, FgfError};
use crate::progress::run_job;
use fgf_field::export::{Density, ExportError, ExportOptions, FieldView};
use fgf_field::{Anchor, FieldData, FieldError, Precision, SynthParams};
use numpy::ndarray::{Array, IxDyn};
use numpy::{IntoPyArray, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::{PyKeyboardInterrupt, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

fn field_err(e: FieldError) -> PyErr {
    match e {
        FieldError::Param(p) => param_err(p),
        FieldError::OutOfMemory { .. } => FgfError::new_err(e.to_string()),
        FieldError::Cancelled(_) => PyKeyboardInterrupt::new_err("interrupted"),
    }
}

fn export_err(e: ExportError) -> PyErr {
    match e {
        ExportError::Io(e) => io_err(e),
        ExportError::Param(p) => param_err(p),
        ExportError::Unsupported { .. } => FgfError::new_err(e.to_string()),
    }
}

/// Jobs smaller than this many values run without [`run_job`] when no
/// progress is asked for: `run_job` polls every 100 ms, which would dominate
/// the time of small fields synthesized in a loop (ensembles in tests), and a
/// job this small finishes well before Ctrl-C matters.
const SMALL_JOB: usize = 1 << 21;

/// Run `job` through [`run_job`], or directly (GIL released) if it is small
/// and quiet. Returns the value and whether the user interrupted.
fn run<R: Send>(
    py: Python<'_>,
    size: usize,
    total: u64,
    label: &str,
    progress: Option<&Bound<'_, PyAny>>,
    job: impl FnOnce(&dyn fgf_core::Progress) -> R + Send,
) -> PyResult<R> {
    let quiet = progress.is_none_or(|p| p.is_none() || p.extract::<bool>().is_ok_and(|b| !b));
    if quiet && size < SMALL_JOB {
        return Ok(py.detach(|| job(&fgf_core::NoProgress)));
    }
    let r = run_job(py, total, label, progress, |c| job(c))?;
    if r.interrupted {
        return Err(PyKeyboardInterrupt::new_err(format!("{label} interrupted")));
    }
    Ok(r.value)
}

fn parse_anchor(anchor: Option<&Bound<'_, PyAny>>) -> PyResult<Anchor> {
    let Some(a) = anchor else {
        return Ok(Anchor::None);
    };
    if a.is_none() {
        return Ok(Anchor::None);
    }
    if let Ok(s) = a.extract::<String>() {
        return match s.as_str() {
            "corner" => Ok(Anchor::Corner),
            "center" | "centre" => Ok(Anchor::Center),
            "none" => Ok(Anchor::None),
            _ => Err(crate::errors::ParameterError::new_err(format!(
                "invalid anchor = {s:?}: unknown anchor (valid: \"corner\", \"center\", \"none\"/None, or one index per axis)"
            ))),
        };
    }
    if let Ok(idx) = a.extract::<Vec<usize>>() {
        return Ok(Anchor::Index(idx));
    }
    Err(PyTypeError::new_err(
        "anchor must be \"corner\", \"center\", \"none\", None or a sequence of ints",
    ))
}

fn parse_precision(dtype: &str) -> PyResult<Precision> {
    match dtype {
        "float32" | "f4" | "<f4" => Ok(Precision::F32),
        "float64" | "f8" | "<f8" => Ok(Precision::F64),
        _ => Err(crate::errors::ParameterError::new_err(format!(
            "invalid dtype = {dtype:?}: only float32 and float64 are produced (valid: \"float32\", \"float64\")"
        ))),
    }
}

#[allow(clippy::too_many_arguments)]
fn params(
    shape: Vec<usize>,
    hurst: f64,
    sw: f64,
    spacing: f64,
    seed: u64,
    anchor: Option<&Bound<'_, PyAny>>,
    padding: Option<f64>,
    dtype: &str,
) -> PyResult<SynthParams> {
    let mut p = SynthParams::new(&shape, hurst);
    p.sw = sw;
    p.spacing = spacing;
    p.seed = seed;
    p.anchor = parse_anchor(anchor)?;
    p.padding = padding;
    p.precision = parse_precision(dtype)?;
    Ok(p)
}

/// Synthesize one field; returns `(array, interrupted)`.
#[pyfunction]
#[pyo3(signature = (shape, hurst, sw, spacing, seed, anchor, padding, dtype, progress))]
#[allow(clippy::too_many_arguments)]
fn synthesize<'py>(
    py: Python<'py>,
    shape: Vec<usize>,
    hurst: f64,
    sw: f64,
    spacing: f64,
    seed: u64,
    anchor: Option<&Bound<'py, PyAny>>,
    padding: Option<f64>,
    dtype: &str,
    progress: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let p = params(shape, hurst, sw, spacing, seed, anchor, padding, dtype)?;
    let total = fgf_field::work_units(&p).map_err(param_err)?;
    let size = fgf_field::padded_shape(&p)
        .map_err(param_err)?
        .iter()
        .product();
    let f = run(py, size, total, "synthesize", progress, |c| {
        fgf_field::synthesize(&p, c)
    })?
    .map_err(field_err)?;
    let dims = IxDyn(&f.shape);
    let arr = match f.data {
        FieldData::F32(v) => Array::from_shape_vec(dims, v)
            .expect("shape matches")
            .into_pyarray(py)
            .into_any(),
        FieldData::F64(v) => Array::from_shape_vec(dims, v)
            .expect("shape matches")
            .into_pyarray(py)
            .into_any(),
    };
    Ok(arr)
}

/// `(discrete spectral variance, padded shape, peak bytes or None, work units)`.
#[pyfunction]
#[pyo3(signature = (shape, hurst, sw, spacing, padding, dtype))]
fn synthesis_info(
    shape: Vec<usize>,
    hurst: f64,
    sw: f64,
    spacing: f64,
    padding: Option<f64>,
    dtype: &str,
) -> PyResult<(f64, Vec<usize>, Option<u64>)> {
    let p = params(shape, hurst, sw, spacing, 0, None, padding, dtype)?;
    Ok((
        fgf_field::discrete_spectral_variance(&p).map_err(param_err)?,
        fgf_field::padded_shape(&p).map_err(param_err)?,
        fgf_field::estimate_memory(&p).map_err(param_err)?,
    ))
}

fn samples_to_numpy(
    py: Python<'_>,
    s: fgf_field::Samples1d,
) -> (Bound<'_, PyAny>, Bound<'_, PyAny>) {
    let cols = s.t.len();
    let values = Array::from_shape_vec(IxDyn(&[s.n_paths, cols]), s.values).expect("shape matches");
    (
        values.into_pyarray(py).into_any(),
        s.t.into_pyarray(py).into_any(),
    )
}

#[pyfunction]
#[pyo3(signature = (n_rays, n_steps, t_max, hurst, sw, seed, progress))]
#[allow(clippy::too_many_arguments)]
fn sample_optical_depth<'py>(
    py: Python<'py>,
    n_rays: usize,
    n_steps: usize,
    t_max: f64,
    hurst: f64,
    sw: f64,
    seed: u64,
    progress: Option<&Bound<'py, PyAny>>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let size = n_rays.saturating_mul(n_steps.saturating_add(1));
    let s = run(
        py,
        size,
        n_rays.div_ceil(2) as u64,
        "optical depth",
        progress,
        |c| fgf_field::sample_optical_depth(n_rays, n_steps, t_max, hurst, sw, seed, c),
    )?;
    Ok(samples_to_numpy(py, s.map_err(field_err)?))
}

#[pyfunction]
#[pyo3(signature = (n_samples, n_steps, length, hurst, sw, seed, progress))]
#[allow(clippy::too_many_arguments)]
fn sample_kfbm_1d<'py>(
    py: Python<'py>,
    n_samples: usize,
    n_steps: usize,
    length: f64,
    hurst: f64,
    sw: f64,
    seed: u64,
    progress: Option<&Bound<'py, PyAny>>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    // Cholesky is O(n^3): count its cost, not only the output size.
    let size = n_samples
        .saturating_mul(n_steps.saturating_add(1))
        .saturating_add(n_steps.saturating_pow(3) / 64);
    let s = run(py, size, n_samples as u64, "k-fBm", progress, |c| {
        fgf_field::sample_kfbm_1d(n_samples, n_steps, length, hurst, sw, seed, c)
    })?;
    Ok(samples_to_numpy(py, s.map_err(field_err)?))
}

#[pyfunction]
fn sw_3d_for_ray_statistics(hurst: f64, sw: f64) -> PyResult<f64> {
    fgf_field::sw_3d_for_ray_statistics(hurst, sw).map_err(param_err)
}

/// A contiguous f32 or f64 array, borrowed.
enum Data<'py> {
    F32(PyReadonlyArrayDyn<'py, f32>),
    F64(PyReadonlyArrayDyn<'py, f64>),
}

impl<'py> Data<'py> {
    fn new(a: &Bound<'py, PyAny>) -> PyResult<Self> {
        if let Ok(x) = a.extract::<PyReadonlyArrayDyn<'py, f64>>() {
            return Ok(Data::F64(x));
        }
        if let Ok(x) = a.extract::<PyReadonlyArrayDyn<'py, f32>>() {
            return Ok(Data::F32(x));
        }
        Err(PyTypeError::new_err(
            "field must be a float32 or float64 numpy array",
        ))
    }
    fn shape(&self) -> Vec<usize> {
        match self {
            Data::F32(x) => x.shape().to_vec(),
            Data::F64(x) => x.shape().to_vec(),
        }
    }
    fn view(&self) -> PyResult<FieldView<'_>> {
        let err =
            |_| PyValueError::new_err("field must be C-contiguous (use np.ascontiguousarray)");
        Ok(match self {
            Data::F32(x) => FieldView::F32(x.as_slice().map_err(err)?),
            Data::F64(x) => FieldView::F64(x.as_slice().map_err(err)?),
        })
    }
}

macro_rules! with_slice {
    ($view:expr, |$s:ident| $body:expr) => {
        match $view {
            FieldView::F32($s) => $body,
            FieldView::F64($s) => $body,
        }
    };
}

#[pyfunction]
fn variogram(
    py: Python<'_>,
    field: &Bound<'_, PyAny>,
    axis: usize,
    max_lag: usize,
) -> PyResult<Vec<f64>> {
    let d = Data::new(field)?;
    let shape = d.shape();
    let v = d.view()?;
    py.detach(|| {
        with_slice!(v, |s| fgf_field::estimators::variogram_along_axis(
            s, &shape, axis, max_lag
        ))
    })
    .map_err(param_err)
}

#[pyfunction]
fn covariance(
    py: Python<'_>,
    field: &Bound<'_, PyAny>,
    axis: usize,
    max_lag: usize,
) -> PyResult<Vec<f64>> {
    let d = Data::new(field)?;
    let shape = d.shape();
    let v = d.view()?;
    py.detach(|| {
        with_slice!(v, |s| fgf_field::estimators::covariance_along_axis(
            s, &shape, axis, max_lag
        ))
    })
    .map_err(param_err)
}

#[pyfunction]
fn radial_power_spectrum(
    py: Python<'_>,
    field: &Bound<'_, PyAny>,
    spacing: f64,
    n_bins: usize,
) -> PyResult<(Vec<f64>, Vec<f64>, Vec<usize>)> {
    let d = Data::new(field)?;
    let shape = d.shape();
    let v = d.view()?;
    let r = py
        .detach(|| {
            with_slice!(v, |s| fgf_field::estimators::radial_power_spectrum(
                s, &shape, spacing, n_bins
            ))
        })
        .map_err(param_err)?;
    Ok((r.k, r.power, r.count))
}

#[pyfunction]
fn line_average_second_moment(
    py: Python<'_>,
    field: &Bound<'_, PyAny>,
    axis: usize,
    lengths: Vec<usize>,
) -> PyResult<Vec<f64>> {
    let d = Data::new(field)?;
    let shape = d.shape();
    let v = d.view()?;
    py.detach(|| {
        with_slice!(v, |s| fgf_field::estimators::line_average_second_moment(
            s, &shape, axis, &lengths
        ))
    })
    .map_err(param_err)
}

/// Write a field; returns a dict `{format, min, max, n_negative}`.
#[pyfunction]
#[pyo3(signature = (path, field, spacing, mean, scale, clamp_min, png_percentiles))]
#[allow(clippy::too_many_arguments)]
fn write_field<'py>(
    py: Python<'py>,
    path: PathBuf,
    field: &Bound<'py, PyAny>,
    spacing: f64,
    mean: f64,
    scale: f64,
    clamp_min: Option<f64>,
    png_percentiles: (f64, f64),
) -> PyResult<Bound<'py, PyDict>> {
    let d = Data::new(field)?;
    let shape = d.shape();
    let v = d.view()?;
    let opts = ExportOptions {
        density: Density {
            mean,
            scale,
            clamp_min,
        },
        png_percentiles,
    };
    let s = py
        .detach(|| fgf_field::export::write_field(&path, v, &shape, spacing, &opts))
        .map_err(export_err)?;
    let out = PyDict::new(py);
    out.set_item("format", format!("{:?}", s.format).to_lowercase())?;
    out.set_item("min", s.min)?;
    out.set_item("max", s.max)?;
    out.set_item("n_negative", s.n_negative)?;
    Ok(out)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(synthesize, m)?)?;
    m.add_function(wrap_pyfunction!(synthesis_info, m)?)?;
    m.add_function(wrap_pyfunction!(sample_optical_depth, m)?)?;
    m.add_function(wrap_pyfunction!(sample_kfbm_1d, m)?)?;
    m.add_function(wrap_pyfunction!(sw_3d_for_ray_statistics, m)?)?;
    m.add_function(wrap_pyfunction!(variogram, m)?)?;
    m.add_function(wrap_pyfunction!(covariance, m)?)?;
    m.add_function(wrap_pyfunction!(radial_power_spectrum, m)?)?;
    m.add_function(wrap_pyfunction!(line_average_second_moment, m)?)?;
    m.add_function(wrap_pyfunction!(write_field, m)?)?;
    Ok(())
}
