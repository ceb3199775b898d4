//! Python bindings for the render area: `render_scene` (behind
//! `fgf.render`), `write_exr`, `write_png`, and the sample-range API behind
//! `fgf.cluster`: `prepare_scene` (a compiled scene kept by a worker),
//! `render_range` (the exact sums of samples `s0..s1`), `film_merge` and
//! `film_finish` (`docs/theory.md` §7.17); and `bsdf_eval_pdf`, a shape's
//! BSDF evaluated in its local frame (for the tests against Mitsuba 3's
//! `BSDF.eval`/`pdf`).

use crate::errors::{io_err, ParameterError, SceneError};
use crate::progress::run_job;
use fgf_render::film::{FilmState, Fixed, FIXED_LIMBS};
use fgf_render::render::Prepared;
use fgf_render::{RenderError, RenderOptions};
use fgf_scene::SceneErrorKind;
use numpy::{
    PyArray1, PyArrayMethods, PyReadonlyArray2, PyReadonlyArray3, PyReadonlyArrayDyn,
    PyReadwriteArrayDyn, PyUntypedArrayMethods,
};
use pyo3::exceptions::PyOSError;
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::Arc;

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
    // The scene is given up to the render, which lets go of its meshes'
    // own arrays once they are compiled.
    let job = run_job(py, total, "render", progress.as_ref(), |counter| {
        in_pool(threads, || fgf_render::render_owned(desc, &opts, counter))
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

/// A compiled scene (BVH, media, emitters), kept by a worker so that each
/// chunk of samples does not load and build the scene again.
#[pyclass(frozen, name = "PreparedScene", module = "fgf._core")]
pub struct PyPrepared {
    inner: Arc<Prepared>,
    source: String,
}

#[pymethods]
impl PyPrepared {
    /// Film width in pixels.
    #[getter]
    fn width(&self) -> usize {
        self.inner.width
    }
    /// Film height in pixels.
    #[getter]
    fn height(&self) -> usize {
        self.inner.height
    }
    /// The scene's `sample_count`.
    #[getter]
    fn spp(&self) -> u32 {
        self.inner.spp
    }
    /// The scene's sampler seed.
    #[getter]
    fn seed(&self) -> u64 {
        self.inner.seed
    }
}

/// Load and compile a scene for [`render_range`].
#[pyfunction]
#[pyo3(signature = (scene, defines=None))]
fn prepare_scene(
    py: Python<'_>,
    scene: PathBuf,
    defines: Option<Vec<(String, String)>>,
) -> PyResult<PyPrepared> {
    let desc = load_scene(py, &scene, defines)?;
    let source = scene.display().to_string();
    let inner = py
        .detach(|| Prepared::new_owned(desc))
        .map_err(|e| render_err(e, &source))?;
    Ok(PyPrepared {
        inner: Arc::new(inner),
        source,
    })
}

/// `(H, W, 3, FIXED_LIMBS)` uint64 limbs of exact sums.
fn limbs_to_py<'py>(
    py: Python<'py>,
    v: &[Fixed],
    h: usize,
    w: usize,
) -> PyResult<Bound<'py, PyAny>> {
    let flat: Vec<u64> = v.iter().flat_map(|f| f.0).collect();
    Ok(PyArray1::from_vec(py, flat)
        .reshape([h, w, 3, FIXED_LIMBS])?
        .into_any())
}

fn limbs_from_py(a: &[u64]) -> Vec<Fixed> {
    a.chunks_exact(FIXED_LIMBS)
        .map(|c| {
            let mut f = Fixed::default();
            f.0.copy_from_slice(c);
            f
        })
        .collect()
}

/// What `render_range` returns: `(sum, sum_sq or None, samples_done,
/// interrupted)`.
type RangeResult<'py> = (Bound<'py, PyAny>, Option<Bound<'py, PyAny>>, u64, bool);

/// The exact per-pixel sums of samples `s0..s1` of a prepared scene:
/// `(sum, sum_sq or None, samples_done, interrupted)`, sums as
/// `(H, W, 3, limbs)` uint64 fixed-point limbs holding samples
/// `s0..s0 + samples_done` (fewer than asked only if interrupted).
#[pyfunction]
#[pyo3(signature = (prepared, s0, s1, seed=None, variance=false, threads=None, progress=None))]
#[allow(clippy::too_many_arguments)]
fn render_range<'py>(
    py: Python<'py>,
    prepared: &PyPrepared,
    s0: u32,
    s1: u32,
    seed: Option<u64>,
    variance: bool,
    threads: Option<usize>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<RangeResult<'py>> {
    check_spp_threads(None, threads)?;
    if s0 >= s1 {
        return Err(ParameterError::new_err(format!(
            "sample range [{s0}, {s1}) is empty; need s0 < s1"
        )));
    }
    let p = prepared.inner.clone();
    let seed = seed.unwrap_or(p.seed);
    let total = (p.width * p.height) as u64 * (s1 - s0) as u64;
    let job = run_job(py, total, "render", progress.as_ref(), |counter| {
        in_pool(threads, || {
            p.render_range(seed, s0..s1, variance, None, counter)
        })
    })?;
    let state = job.value.map_err(|e| render_err(e, &prepared.source))?;
    let (h, w) = (state.height, state.width);
    let sum = limbs_to_py(py, &state.sum, h, w)?;
    let sq = match &state.sum_sq {
        Some(v) => Some(limbs_to_py(py, v, h, w)?),
        None => None,
    };
    let interrupted = job.interrupted || state.samples < (s1 - s0) as u64;
    Ok((sum, sq, state.samples, interrupted))
}

fn check_limbs(name: &str, shape: &[usize]) -> PyResult<(usize, usize)> {
    if shape.len() != 4 || shape[2] != 3 || shape[3] != FIXED_LIMBS {
        return Err(ParameterError::new_err(format!(
            "{name} has shape {shape:?}; expected (H, W, 3, {FIXED_LIMBS}) uint64 limbs"
        )));
    }
    Ok((shape[0], shape[1]))
}

/// `dst += src` for exact sums (`(H, W, 3, limbs)` uint64), in place; an
/// `fgf.ParameterError` if a sum leaves the accumulator's range.
#[pyfunction]
fn film_merge(
    mut dst: PyReadwriteArrayDyn<'_, u64>,
    src: PyReadonlyArrayDyn<'_, u64>,
) -> PyResult<()> {
    let dshape = check_limbs("dst", dst.shape())?;
    let sshape = check_limbs("src", src.shape())?;
    if dshape != sshape {
        return Err(ParameterError::new_err(format!(
            "cannot merge sums of a {}x{} film into a {}x{} one",
            sshape.1, sshape.0, dshape.1, dshape.0
        )));
    }
    let s = src.as_slice()?;
    let d = dst.as_slice_mut()?;
    for (i, (dc, sc)) in d
        .chunks_exact_mut(FIXED_LIMBS)
        .zip(s.chunks_exact(FIXED_LIMBS))
        .enumerate()
    {
        let mut a = Fixed::default();
        a.0.copy_from_slice(dc);
        let mut b = Fixed::default();
        b.0.copy_from_slice(sc);
        if !a.merge(&b) {
            let (px, c) = (i / 3, i % 3);
            return Err(ParameterError::new_err(format!(
                "pixel ({}, {}) channel {c}: merged sum leaves the exact accumulator's range \
                 |sum| < 2^95",
                px % dshape.1,
                px / dshape.1
            )));
        }
        dc.copy_from_slice(&a.0);
    }
    Ok(())
}

/// What `film_finish` returns: `(image, variance or None)`.
type FinishResult<'py> = (Bound<'py, PyAny>, Option<Bound<'py, PyAny>>);

/// The image (pixel means over `samples`) of exact sums, with the variance
/// of the means if `sum_sq` is given: the same bits as a single render.
#[pyfunction]
#[pyo3(signature = (sum, sum_sq, samples, spp_requested))]
fn film_finish<'py>(
    py: Python<'py>,
    sum: PyReadonlyArrayDyn<'py, u64>,
    sum_sq: Option<PyReadonlyArrayDyn<'py, u64>>,
    samples: u64,
    spp_requested: u32,
) -> PyResult<FinishResult<'py>> {
    let (h, w) = check_limbs("sum", sum.shape())?;
    let sq = match &sum_sq {
        Some(a) => {
            if check_limbs("sum_sq", a.shape())? != (h, w) {
                return Err(ParameterError::new_err("sum_sq and sum differ in shape"));
            }
            Some(limbs_from_py(a.as_slice()?))
        }
        None => None,
    };
    let state = FilmState {
        width: w,
        height: h,
        samples,
        sum: limbs_from_py(sum.as_slice()?),
        sum_sq: sq,
    };
    let out = py.detach(|| state.finish(spp_requested));
    let img = to_hw3(py, out.image, h, w)?;
    let var = match out.variance {
        Some(v) => Some(to_hw3(py, v, h, w)?),
        None => None,
    };
    Ok((img, var))
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

/// `f(wi, wo)·|cos θ_o|` and the sampling pdf of `wo` for the BSDF of
/// shape `shape` of a scene, at `n` pairs of local-frame directions
/// (`(n, 3)` arrays; the normal is `+z`).
#[pyfunction]
#[pyo3(signature = (scene, shape, wi, wo, defines=None))]
fn bsdf_eval_pdf<'py>(
    py: Python<'py>,
    scene: PathBuf,
    shape: usize,
    wi: PyReadonlyArray2<'py, f32>,
    wo: PyReadonlyArray2<'py, f32>,
    defines: Option<Vec<(String, String)>>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let desc = load_scene(py, &scene, defines)?;
    let Some(s) = desc.shapes.get(shape) else {
        return Err(ParameterError::new_err(format!(
            "shape = {shape}; the scene has {} shapes",
            desc.shapes.len()
        )));
    };
    let (wi, wo) = (wi.as_array(), wo.as_array());
    if wi.ncols() != 3 || wo.shape() != wi.shape() {
        return Err(ParameterError::new_err(format!(
            "wi and wo must be (n, 3) arrays of the same shape, got {:?} and {:?}",
            wi.shape(),
            wo.shape()
        )));
    }
    let bsdf = fgf_render::bsdf::Bsdf::from_desc(&desc.bsdfs[s.bsdf]);
    let n = wi.nrows();
    let (mut f, mut pdf) = (Vec::with_capacity(3 * n), Vec::with_capacity(n));
    for k in 0..n {
        let v =
            |a: &numpy::ndarray::ArrayView2<f32>| glam::Vec3A::new(a[[k, 0]], a[[k, 1]], a[[k, 2]]);
        let (fk, pk) = bsdf.eval_pdf(v(&wi), v(&wo));
        f.extend_from_slice(&[fk.x, fk.y, fk.z]);
        pdf.push(pk);
    }
    Ok((
        PyArray1::from_vec(py, f).reshape([n, 3])?.into_any(),
        PyArray1::from_vec(py, pdf).into_any(),
    ))
}

/// The shading frame `(s, t, n)` (an `(n, 9)` array, NaN for a miss) at
/// the first hits of `n` rays `o + t d` (`(n, 3)` arrays) in a scene: the
/// frame anisotropic BSDFs are evaluated in
/// ([`fgf_render::geometry::Geometry::shading_frame`]), and the shape hit
/// (-1 for a miss).
#[pyfunction]
#[pyo3(signature = (scene, origins, directions, defines=None))]
fn shading_frame<'py>(
    py: Python<'py>,
    scene: PathBuf,
    origins: PyReadonlyArray2<'py, f32>,
    directions: PyReadonlyArray2<'py, f32>,
    defines: Option<Vec<(String, String)>>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let desc = load_scene(py, &scene, defines)?;
    let world = fgf_render::world::World::build(&desc)
        .map_err(|e| render_err(e, &scene.display().to_string()))?;
    let (o, d) = (origins.as_array(), directions.as_array());
    if o.ncols() != 3 || d.shape() != o.shape() {
        return Err(ParameterError::new_err(format!(
            "origins and directions must be (n, 3) arrays of the same shape, got {:?} and {:?}",
            o.shape(),
            d.shape()
        )));
    }
    let n = o.nrows();
    let (mut out, mut shapes) = (Vec::with_capacity(9 * n), Vec::with_capacity(n));
    for k in 0..n {
        let v =
            |a: &numpy::ndarray::ArrayView2<f32>| glam::Vec3A::new(a[[k, 0]], a[[k, 1]], a[[k, 2]]);
        let ray = fgf_render::ray::Ray {
            o: v(&o),
            d: v(&d).normalize(),
        };
        match world.geom.intersect(&ray, f32::INFINITY) {
            Some(h) => {
                let f = world.geom.shading_frame(&h);
                for a in [f.s, f.t, f.n] {
                    out.extend_from_slice(&[a.x, a.y, a.z]);
                }
                shapes.push(h.shape as i64);
            }
            None => {
                out.extend_from_slice(&[f32::NAN; 9]);
                shapes.push(-1);
            }
        }
    }
    Ok((
        PyArray1::from_vec(py, out).reshape([n, 9])?.into_any(),
        PyArray1::from_vec(py, shapes).into_any(),
    ))
}

/// `Bsdf::sample` of a shape's BSDF for each row of `wi` (local frame)
/// with the random numbers `u` (`(n, 3)`: `u1`, then `u2`): the sampled
/// directions, weights and pdfs (zero weight and pdf where no sample).
#[pyfunction]
#[pyo3(signature = (scene, shape, wi, u, defines=None))]
#[allow(clippy::type_complexity)]
fn bsdf_sample<'py>(
    py: Python<'py>,
    scene: PathBuf,
    shape: usize,
    wi: PyReadonlyArray2<'py, f32>,
    u: PyReadonlyArray2<'py, f32>,
    defines: Option<Vec<(String, String)>>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let desc = load_scene(py, &scene, defines)?;
    let Some(s) = desc.shapes.get(shape) else {
        return Err(ParameterError::new_err(format!(
            "shape = {shape}; the scene has {} shapes",
            desc.shapes.len()
        )));
    };
    let (wi, u) = (wi.as_array(), u.as_array());
    if wi.ncols() != 3 || u.shape() != wi.shape() {
        return Err(ParameterError::new_err(format!(
            "wi and u must be (n, 3) arrays of the same shape, got {:?} and {:?}",
            wi.shape(),
            u.shape()
        )));
    }
    let bsdf = fgf_render::bsdf::Bsdf::from_desc(&desc.bsdfs[s.bsdf]);
    let n = wi.nrows();
    let (mut wo, mut w, mut pdf) = (
        Vec::with_capacity(3 * n),
        Vec::with_capacity(3 * n),
        Vec::with_capacity(n),
    );
    for k in 0..n {
        let v = glam::Vec3A::new(wi[[k, 0]], wi[[k, 1]], wi[[k, 2]]);
        match bsdf.sample(v, u[[k, 0]], [u[[k, 1]], u[[k, 2]]]) {
            Some(bs) => {
                wo.extend_from_slice(&[bs.wo.x, bs.wo.y, bs.wo.z]);
                w.extend_from_slice(&[bs.weight.x, bs.weight.y, bs.weight.z]);
                pdf.push(bs.pdf);
            }
            None => {
                wo.extend_from_slice(&[0.0; 3]);
                w.extend_from_slice(&[0.0; 3]);
                pdf.push(0.0);
            }
        }
    }
    Ok((
        PyArray1::from_vec(py, wo).reshape([n, 3])?.into_any(),
        PyArray1::from_vec(py, w).reshape([n, 3])?.into_any(),
        PyArray1::from_vec(py, pdf).into_any(),
    ))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(bsdf_eval_pdf, m)?)?;
    m.add_function(wrap_pyfunction!(shading_frame, m)?)?;
    m.add_function(wrap_pyfunction!(bsdf_sample, m)?)?;
    m.add_function(wrap_pyfunction!(render_scene, m)?)?;
    m.add_function(wrap_pyfunction!(write_exr, m)?)?;
    m.add_function(wrap_pyfunction!(write_png, m)?)?;
    m.add_class::<PyPrepared>()?;
    m.add_function(wrap_pyfunction!(prepare_scene, m)?)?;
    m.add_function(wrap_pyfunction!(render_range, m)?)?;
    m.add_function(wrap_pyfunction!(film_merge, m)?)?;
    m.add_function(wrap_pyfunction!(film_finish, m)?)?;
    Ok(())
}
