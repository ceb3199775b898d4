//! Python bindings for the transmittance area: one native class `_Model`
//! wrapping `fgf_core::transmittance::Model` (its `eval` takes a
//! [`ModelFunction`] member), and the statistics functions
//! of `fgf_core::stats`. The typed public classes (`fgf.Fgf`, ...) live in
//! `python/fgf/transmittance.py`; this file only converts types, releases
//! the GIL for large arrays and maps `ParamError` to `fgf.ParameterError`.

use crate::errors::{param_err, ParameterError};
use fgf_core::stats::{self, Regime};
use fgf_core::transmittance::{Davis, DavisWeinstein, Exponential, Fgf, Model, Transmittance};
use fgf_core::ParamError;
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Arrays at least this long are processed with the GIL released; below it
/// the release/re-acquire overhead (~1 µs) is not worth it.
const DETACH_LEN: usize = 4096;

/// Map `f` over a contiguous float64 array, releasing the GIL when large.
fn map_array<'py>(
    py: Python<'py>,
    x: &PyReadonlyArray1<'py, f64>,
    f: impl Fn(f64) -> f64 + Sync,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let xs = x.as_slice()?;
    let out: Vec<f64> = if xs.len() >= DETACH_LEN {
        py.detach(|| xs.iter().map(|&v| f(v)).collect())
    } else {
        xs.iter().map(|&v| f(v)).collect()
    };
    Ok(PyArray1::from_vec(py, out))
}

/// Check that every variate lies in `[0, 1)`.
fn check_unit(us: &[f64]) -> PyResult<()> {
    if let Some(&bad) = us.iter().find(|&&u| !(0.0..1.0).contains(&u)) {
        return Err(ParameterError::new_err(format!(
            "invalid u = {bad}: sampler variates must lie in [0, 1) (valid: 0 <= u < 1)"
        )));
    }
    Ok(())
}

/// The function of a model that `_Model.eval` maps over an array. The
/// Python layer picks the member once per method (`fgf.transmittance`), so
/// no string is parsed per call.
#[pyclass(name = "ModelFunction", module = "fgf._core", eq, eq_int, frozen)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModelFunction {
    /// `Tr = T_ss`.
    #[pyo3(name = "TR")]
    Tr,
    /// `p = T_sm = -dTr/dt`.
    #[pyo3(name = "PDF")]
    Pdf,
    /// `T_ms = T_sm / σ̄`.
    #[pyo3(name = "MEDIUM_SURFACE")]
    MediumSurface,
    /// `T_mm = -dT_ms/dt`.
    #[pyo3(name = "MEDIUM_MEDIUM")]
    MediumMedium,
    /// Inverse of the cdf `1 - T_ss` (variates in `[0, 1)`).
    #[pyo3(name = "SAMPLE_SURFACE")]
    SampleSurface,
    /// Inverse of the cdf `1 - T_ms` (variates in `[0, 1)`).
    #[pyo3(name = "SAMPLE_MEDIUM")]
    SampleMedium,
    /// `var[σ̄_t]` (Fgf models only).
    #[pyo3(name = "VARIANCE")]
    Variance,
    /// `α(t) = σ_m² / var[σ̄_t]` (Fgf models only).
    #[pyo3(name = "ALPHA")]
    Alpha,
}

/// A transmittance model (native part of `fgf.Exponential`, `fgf.Fgf`,
/// `fgf.Davis`, `fgf.DavisWeinstein`).
#[pyclass(name = "_Model", module = "fgf._core", frozen)]
pub struct PyModel {
    m: Model,
}

#[pymethods]
impl PyModel {
    #[staticmethod]
    fn exponential(sigma_t: f64) -> PyResult<Self> {
        let m = Exponential::new(sigma_t).map_err(param_err)?;
        Ok(PyModel { m: m.into() })
    }

    #[staticmethod]
    #[pyo3(signature = (sigma_t, hurst, sw, length=None))]
    fn fgf(sigma_t: f64, hurst: f64, sw: f64, length: Option<f64>) -> PyResult<Self> {
        let m = Fgf::new(sigma_t, hurst, sw, length).map_err(param_err)?;
        Ok(PyModel { m: m.into() })
    }

    #[staticmethod]
    fn davis(sigma_t: f64, alpha: f64) -> PyResult<Self> {
        let m = Davis::new(sigma_t, alpha).map_err(param_err)?;
        Ok(PyModel { m: m.into() })
    }

    #[staticmethod]
    fn davis_weinstein(sigma_t: f64, h: f64, c: f64) -> PyResult<Self> {
        let m = DavisWeinstein::new(sigma_t, h, c).map_err(param_err)?;
        Ok(PyModel { m: m.into() })
    }

    /// Evaluate `what` elementwise over a 1-D contiguous float64 array.
    fn eval<'py>(
        &self,
        py: Python<'py>,
        what: ModelFunction,
        x: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let m = self.m;
        match what {
            ModelFunction::Tr => map_array(py, &x, |t| m.tr(t)),
            ModelFunction::Pdf => map_array(py, &x, |t| m.pdf(t)),
            ModelFunction::MediumSurface => map_array(py, &x, |t| m.medium_surface(t)),
            ModelFunction::MediumMedium => map_array(py, &x, |t| m.medium_medium(t)),
            ModelFunction::SampleSurface => {
                check_unit(x.as_slice()?)?;
                map_array(py, &x, |u| m.sample_surface(u))
            }
            ModelFunction::SampleMedium => {
                check_unit(x.as_slice()?)?;
                map_array(py, &x, |u| m.sample_medium(u))
            }
            ModelFunction::Variance | ModelFunction::Alpha => match m {
                Model::Fgf(f) if what == ModelFunction::Variance => {
                    map_array(py, &x, |t| f.variance(t))
                }
                Model::Fgf(f) => map_array(py, &x, |t| f.alpha(t)),
                _ => Err(pyo3::exceptions::PyTypeError::new_err(format!(
                    "{} is defined for Fgf models only",
                    if what == ModelFunction::Variance {
                        "variance"
                    } else {
                        "alpha"
                    }
                ))),
            },
        }
    }

    #[getter]
    fn sigma_bar(&self) -> f64 {
        self.m.sigma_bar()
    }

    /// The model's kind and parameters, as given to its constructor.
    fn params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("sigma_t", self.m.sigma_t())?;
        match self.m {
            Model::Exponential(_) => d.set_item("kind", "exponential")?,
            Model::Fgf(f) => {
                d.set_item("kind", "fgf")?;
                d.set_item("hurst", f.hurst())?;
                d.set_item("sw", f.sw())?;
                d.set_item("length", f.length())?;
                let (regime, k) = match f.regime() {
                    Regime::White => ("white", 0),
                    Regime::Pink => ("pink", 0),
                    Regime::KFbm { k } => ("k-fbm", k),
                };
                d.set_item("regime", regime)?;
                d.set_item("k", k)?;
            }
            Model::Davis(m) => {
                d.set_item("kind", "davis")?;
                d.set_item("alpha", m.alpha())?;
            }
            Model::DavisWeinstein(m) => {
                d.set_item("kind", "davis_weinstein")?;
                d.set_item("h", m.h())?;
                d.set_item("c", m.c())?;
            }
        }
        Ok(d)
    }

    /// `Fgf.to_davis()` (k-fBm only).
    fn to_davis(&self) -> PyResult<Self> {
        match self.m {
            Model::Fgf(f) => Ok(PyModel {
                m: f.to_davis().map_err(param_err)?.into(),
            }),
            _ => Err(pyo3::exceptions::PyTypeError::new_err(
                "to_davis is defined for Fgf models only",
            )),
        }
    }

    /// `Fgf.to_davis_weinstein()` (white or pink noise only).
    fn to_davis_weinstein(&self) -> PyResult<Self> {
        match self.m {
            Model::Fgf(f) => Ok(PyModel {
                m: f.to_davis_weinstein().map_err(param_err)?.into(),
            }),
            _ => Err(pyo3::exceptions::PyTypeError::new_err(
                "to_davis_weinstein is defined for Fgf models only",
            )),
        }
    }
}

fn check_sw(sw: f64) -> PyResult<f64> {
    ParamError::check_positive("sw", sw).map_err(param_err)
}

/// `C(H, d)`; errors for non-finite `hurst`, `hurst` a non-negative
/// integer (pole), or `d = 0`.
#[pyfunction]
#[pyo3(signature = (hurst, d=1))]
fn c_const(hurst: f64, d: u32) -> PyResult<f64> {
    if !hurst.is_finite() || (hurst >= 0.0 && hurst.fract() == 0.0) {
        return Err(param_err(ParamError::new(
            "hurst",
            hurst,
            "must be finite and not a non-negative integer (pole of Γ(-H))",
            "finite, hurst not in {0, 1, 2, ...}",
        )));
    }
    if d == 0 {
        return Err(param_err(ParamError::new(
            "d",
            d,
            "must be >= 1",
            "d in {1, 2, 3, ...}",
        )));
    }
    Ok(stats::c_const(hurst, d))
}

/// `S_p(H)` for white or pink noise.
#[pyfunction]
fn s_p(hurst: f64, sw: f64) -> PyResult<f64> {
    match Regime::from_hurst(hurst).map_err(param_err)? {
        Regime::White | Regime::Pink => Ok(stats::s_p(hurst, check_sw(sw)?)),
        Regime::KFbm { .. } => Err(param_err(ParamError::new(
            "hurst",
            hurst,
            "S_p is defined for white or pink noise",
            "-0.5 <= hurst < 0",
        ))),
    }
}

/// `S_kf(H)` for k-fBm.
#[pyfunction]
fn s_kf(hurst: f64, sw: f64) -> PyResult<f64> {
    match Regime::from_hurst(hurst).map_err(param_err)? {
        Regime::KFbm { .. } => Ok(stats::s_kf(hurst, check_sw(sw)?)),
        _ => Err(param_err(ParamError::new(
            "hurst",
            hurst,
            "S_kf is defined for k-fBm",
            "1e-15 <= hurst < 1000, not an integer",
        ))),
    }
}

/// Generalised binomial coefficient `binom(a, k)`.
#[pyfunction]
fn binom(a: f64, k: u32) -> f64 {
    stats::binom(a, k)
}

/// Anchored k-fBm point variance over an array of positions.
#[pyfunction]
fn kfbm_point_variance<'py>(
    py: Python<'py>,
    hurst: f64,
    sw: f64,
    x: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    if !matches!(
        Regime::from_hurst(hurst).map_err(param_err)?,
        Regime::KFbm { .. }
    ) {
        return Err(param_err(ParamError::new(
            "hurst",
            hurst,
            "the k-fBm point variance needs hurst > 0",
            "1e-15 <= hurst < 1000, not an integer",
        )));
    }
    check_sw(sw)?;
    map_array(py, &x, |x| stats::kfbm_point_variance(hurst, sw, x))
}

/// `var[σ̄_t]` over an array of segment lengths `t`.
#[pyfunction]
#[pyo3(signature = (hurst, sw, t, length=None))]
fn line_average_variance<'py>(
    py: Python<'py>,
    hurst: f64,
    sw: f64,
    t: PyReadonlyArray1<'py, f64>,
    length: Option<f64>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let ts = t.as_slice()?;
    // Validate the parameters once, then the first invalid t (if any).
    stats::line_average_variance(hurst, sw, 1.0, length).map_err(param_err)?;
    if let Some(&bad) = ts.iter().find(|v| v.is_nan() || **v <= 0.0) {
        stats::line_average_variance(hurst, sw, bad, length).map_err(param_err)?;
    }
    map_array(py, &t, |tv| {
        stats::line_average_variance(hurst, sw, tv, length).unwrap_or(f64::NAN)
    })
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyModel>()?;
    m.add_class::<ModelFunction>()?;
    m.add_function(wrap_pyfunction!(c_const, m)?)?;
    m.add_function(wrap_pyfunction!(s_p, m)?)?;
    m.add_function(wrap_pyfunction!(s_kf, m)?)?;
    m.add_function(wrap_pyfunction!(binom, m)?)?;
    m.add_function(wrap_pyfunction!(kfbm_point_variance, m)?)?;
    m.add_function(wrap_pyfunction!(line_average_variance, m)?)?;
    Ok(())
}
