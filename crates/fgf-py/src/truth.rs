//! Python binding of the constant-α ground truth (`fgf_render::truth`):
//! `truth_plan` and `render_truth_node` behind `fgf.truth` and `fgf truth`,
//! and `TruthBar`, one indicatif bar over all the nodes of the CLI.

use crate::errors::ParameterError;
use crate::progress::run_job;
use crate::render::{check_spp_threads, in_pool, load_scene, render_err, to_hw3};
use fgf_render::truth::{plan, render_node, TruthOptions, TruthPlan, MAX_NODES};
use fgf_render::RenderError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

fn check_nodes(nodes: Option<usize>) -> PyResult<()> {
    match nodes {
        Some(n) if !(1..=MAX_NODES).contains(&n) => Err(ParameterError::new_err(format!(
            "nodes = {n}; need 1 <= nodes <= {MAX_NODES}"
        ))),
        _ => Ok(()),
    }
}

fn load_plan(
    py: Python<'_>,
    scene: &std::path::Path,
    nodes: Option<usize>,
    defines: Option<Vec<(String, String)>>,
) -> PyResult<(fgf_scene::SceneDesc, TruthPlan)> {
    check_nodes(nodes)?;
    let desc = load_scene(py, scene, defines)?;
    let source = scene.display().to_string();
    let p = py
        .detach(|| plan(&desc, nodes))
        .map_err(|e| render_err(e, &source))?;
    Ok((desc, p))
}

/// The quadrature of a scene's truth, as a dict: `alpha`, `x` and `weights`
/// (lists in node order), `tau_max`, `auto_nodes`, `closed_form_error`,
/// `media`, `width`, `height`, `spp` (the scene's).
#[pyfunction]
#[pyo3(signature = (scene, nodes=None, defines=None))]
fn truth_plan<'py>(
    py: Python<'py>,
    scene: PathBuf,
    nodes: Option<usize>,
    defines: Option<Vec<(String, String)>>,
) -> PyResult<Bound<'py, PyDict>> {
    let (desc, p) = load_plan(py, &scene, nodes, defines)?;
    let d = PyDict::new(py);
    d.set_item("alpha", p.alpha)?;
    d.set_item("x", p.nodes.iter().map(|q| q.x).collect::<Vec<_>>())?;
    d.set_item(
        "weights",
        p.nodes.iter().map(|q| q.weight).collect::<Vec<_>>(),
    )?;
    d.set_item("tau_max", p.tau_max)?;
    d.set_item("auto_nodes", p.auto_nodes)?;
    d.set_item("closed_form_error", p.closed_form_error)?;
    d.set_item("media", p.media.clone())?;
    d.set_item("width", desc.sensor.width)?;
    d.set_item("height", desc.sensor.height)?;
    d.set_item("spp", desc.sensor.spp)?;
    Ok(d)
}

/// What `render_truth_node` returns: `(image or None, variance or None,
/// interrupted)`.
type NodeResult<'py> = (Option<Bound<'py, PyAny>>, Option<Bound<'py, PyAny>>, bool);

/// Render node `node` of the scene's truth quadrature (of `nodes` nodes, or
/// the default count) classically, with the seed derived from `(seed,
/// node)`. Returns `(image, variance or None, interrupted)`; the image is
/// `None` if interrupted (a partial node is not used).
#[pyfunction]
#[pyo3(signature = (scene, node, nodes=None, spp=None, seed=0, threads=None, defines=None, progress=None, return_variance=false))]
#[allow(clippy::too_many_arguments)]
fn render_truth_node<'py>(
    py: Python<'py>,
    scene: PathBuf,
    node: usize,
    nodes: Option<usize>,
    spp: Option<u32>,
    seed: u64,
    threads: Option<usize>,
    defines: Option<Vec<(String, String)>>,
    progress: Option<Bound<'py, PyAny>>,
    return_variance: bool,
) -> PyResult<NodeResult<'py>> {
    check_spp_threads(spp, threads)?;
    let (desc, p) = load_plan(py, &scene, nodes, defines)?;
    if node >= p.nodes.len() {
        return Err(ParameterError::new_err(format!(
            "node = {node}; need 0 <= node < {} (the number of nodes)",
            p.nodes.len()
        )));
    }
    let opts = TruthOptions {
        spp,
        seed,
        variance: return_variance,
    };
    let total = desc.sensor.width as u64
        * desc.sensor.height as u64
        * spp.unwrap_or(desc.sensor.spp) as u64;
    let source = scene.display().to_string();
    let job = run_job(py, total, "truth", progress.as_ref(), |counter| {
        in_pool(threads, || render_node(&desc, &p, node, &opts, counter))
    })?;
    let out = match job.value {
        Ok(out) => out,
        Err(RenderError::Cancelled { .. }) => return Ok((None, None, true)),
        Err(e) => return Err(render_err(e, &source)),
    };
    if job.interrupted {
        return Ok((None, None, true));
    }
    let img = to_hw3(py, out.image, out.height, out.width)?;
    let var = match out.variance {
        Some(v) => Some(to_hw3(py, v, out.height, out.width)?),
        None => None,
    };
    Ok((Some(img), var, false))
}

/// One indicatif progress bar on stderr (hidden when stderr is not a
/// terminal) that several calls can advance: `update(n)`, `close()`.
#[pyclass]
struct TruthBar {
    bar: indicatif::ProgressBar,
}

#[pymethods]
impl TruthBar {
    #[new]
    #[pyo3(signature = (total, label="truth"))]
    fn new(total: u64, label: &str) -> Self {
        let bar = indicatif::ProgressBar::with_draw_target(
            Some(total),
            indicatif::ProgressDrawTarget::stderr(),
        );
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{msg} [{elapsed_precise}] {wide_bar} {pos}/{len} (ETA {eta})",
            )
            .expect("valid template"),
        );
        bar.set_message(label.to_string());
        TruthBar { bar }
    }

    /// Advance by `n` units.
    fn update(&self, n: u64) {
        self.bar.inc(n);
    }

    /// Set the message shown before the bar.
    fn set_message(&self, msg: String) {
        self.bar.set_message(msg);
    }

    /// Remove the bar.
    fn close(&self) {
        self.bar.finish_and_clear();
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(truth_plan, m)?)?;
    m.add_function(wrap_pyfunction!(render_truth_node, m)?)?;
    m.add_class::<TruthBar>()?;
    Ok(())
}
