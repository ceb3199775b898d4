//! Exact ground truth for constant-α media (`docs/theory.md` §6.1, §6.3).
//!
//! # What it computes
//!
//! A k-fBm `fgf` medium, a `nonexponential` Davis medium (and
//! Davis–Weinstein with `h = 1`) has one gamma shape `α` for segments of
//! every length. The random medium behind it is homogeneous along rays in
//! each realization: `σ(x) = X σ_m ρ(x)` with `X ~ Gamma(shape α, mean 1)`
//! and `ρ` the macro density (1 without one; §6.5). The ensemble average of
//! an image is then
//!
//! ```text
//! E_X[I(X)] ≈ Σ_i w_i I(x_i),
//! ```
//!
//! where `I(x)` is a *classical* render (a `homogeneous` medium, or a
//! `heterogeneous` one with `σ_t = x σ_m ρ` if the medium has a density)
//! and `(x_i, w_i)` is the generalised Gauss–Laguerre rule of
//! `Gamma(α, mean 1)` ([`gamma_nodes`]). The truth is deterministic in the
//! nodes and Monte Carlo only within each node's render; no non-exponential
//! kernel is involved, so the scene's `kernel` is ignored.
//!
//! # Node count
//!
//! The rule's error grows with the optical depth `τ` over `α` (§6.3). By
//! default [`plan`] takes the smallest count of [`NODE_COUNTS`] for which
//! the rule reproduces the closed form `E[e^(-Xτ)] = (1 + τ/α)^(-α)` to a
//! relative [`NODE_TOLERANCE`] at `τ_max` and at `τ_max/2, τ_max/4,
//! τ_max/8`, with `τ_max` the diagonal of the media's bounding box times the
//! largest mean extinction (`max_c σ_c · max ρ`), and at least
//! [`MIN_NODES`].
//!
//! # What is refused
//!
//! One level `X` must drive every non-exponential medium of the scene
//! (§6.4): media whose `α` differ, RGB `σ_t` whose channels have different
//! `α` (k-fBm with a single `S_w`), and media without a constant `α` (white
//! and pink noise, Davis–Weinstein with `h < 1`) are refused with one line
//! ([`RenderError::Unsupported`]). Media with the same `α` share one `X`:
//! they are taken as pieces of one random medium.
//!
//! # Determinism
//!
//! Node `i` is rendered with the seed [`node_seed`]`(seed, i)`; [`truth`]
//! sums the nodes in index order in f64, so the result depends only on the
//! scene, the node count, `spp` and `seed`, never on the thread count, and
//! a front end that renders the nodes elsewhere ([`render_node`]) and sums
//! them in the same order gets the same image.
//!
//! ```no_run
//! use fgf_render::truth::{plan, truth, TruthOptions};
//! let scene = fgf_scene::load_file("scenes/fgf-cube-2fbm.xml".as_ref(), &[]).unwrap();
//! let p = plan(&scene, None).unwrap();
//! println!("alpha = {}, {} nodes", p.alpha, p.nodes.len());
//! let out = truth(&scene, &p, &TruthOptions::default(), &fgf_core::NoProgress).unwrap();
//! assert_eq!(out.image.len(), out.width * out.height * 3);
//! ```

use crate::error::RenderError;
use crate::film::RenderOutput;
use crate::render::{render, RenderOptions};
use fgf_core::rng::{mix64, stream_key};
use fgf_core::transmittance::Fgf;
use fgf_core::Progress;
use fgf_scene::{GridVolumeDesc, MediumDesc, SceneDesc, TransmittanceDesc, VolumeDesc};
use glam::DVec3;
use std::sync::Arc;

/// Relative accuracy of the closed form that the default node count reaches.
pub const NODE_TOLERANCE: f64 = 1e-4;
/// Fewest nodes of the default rule (a render also has multiple-scattering
/// terms `X^n e^(-Xτ)`, which a very short rule would miss).
pub const MIN_NODES: usize = 8;
/// Node counts the default rule tries, in order.
pub const NODE_COUNTS: [usize; 15] = [
    8, 12, 16, 24, 32, 48, 64, 96, 128, 192, 256, 384, 512, 768, 1024,
];
/// Largest node count accepted (explicitly or by the rule).
pub const MAX_NODES: usize = 4096;

/// Purpose key of the node seeds under the user's seed.
const TRUTH_STREAM: u64 = 0x7275_7468; // "ruth"

/// One node of the quadrature of `Gamma(α, mean 1)`: `E[f(X)] ≈ Σ w f(x)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Node {
    /// Level `x_i` (the realization's extinction is `x_i σ_m ρ`).
    pub x: f64,
    /// Weight `w_i` (the weights sum to 1).
    pub weight: f64,
}

/// Number of eigenvalues below `lambda` of the symmetric tridiagonal matrix
/// with diagonal `d` and off-diagonal `e` (`e[k]` couples `k-1` and `k`):
/// the negative pivots of the LDLᵀ factorisation of `T - λI` (Sylvester's
/// law of inertia).
fn count_below(d: &[f64], e: &[f64], lambda: f64) -> usize {
    let mut count = 0;
    let mut q = 1.0;
    for k in 0..d.len() {
        let coupling = if k == 0 { 0.0 } else { e[k] * e[k] / q };
        q = d[k] - lambda - coupling;
        if q == 0.0 {
            // An exact zero pivot: perturb it to the smallest magnitude that
            // keeps the next division finite.
            q = -f64::EPSILON * (d[k].abs() + lambda.abs()).max(f64::MIN_POSITIVE);
        }
        if q < 0.0 {
            count += 1;
        }
    }
    count
}

/// The generalised Gauss–Laguerre rule with `n` nodes for `X ~ Gamma(shape
/// α, mean 1)` (`docs/theory.md` §6.3): exact for polynomials of degree
/// `< 2n` in `X`.
///
/// The nodes are `y_i/α`, with `y_i` the eigenvalues of the Jacobi matrix
/// of the Laguerre polynomials `L^(α-1)` (diagonal `2k + α`, off-diagonal
/// `√(k(k + α - 1))`), found by bisection on the Sturm count; the weight of
/// a node is `1/Σ_k p_k(y_i)²` with `p_k` the polynomials orthonormal for
/// `Gamma(α, 1)` (the Christoffel numbers), evaluated by their three-term
/// recurrence with rescaling so that no value overflows.
pub fn gamma_nodes(alpha: f64, n: usize) -> Result<Vec<Node>, RenderError> {
    if !(alpha.is_finite() && alpha > 0.0) {
        return Err(RenderError::InvalidOption(format!(
            "alpha = {alpha}: the gamma shape must be finite and > 0"
        )));
    }
    if !(1..=MAX_NODES).contains(&n) {
        return Err(RenderError::InvalidOption(format!(
            "nodes = {n}; need 1 <= nodes <= {MAX_NODES}"
        )));
    }
    let d: Vec<f64> = (0..n).map(|k| 2.0 * k as f64 + alpha).collect();
    let e: Vec<f64> = (0..n)
        .map(|k| (k as f64 * (k as f64 + alpha - 1.0)).max(0.0).sqrt())
        .collect();
    // Gershgorin: every eigenvalue lies in [0, max_k d_k + e_k + e_{k+1}].
    let upper = (0..n)
        .map(|k| d[k] + e[k] + if k + 1 < n { e[k + 1] } else { 0.0 })
        .fold(0.0, f64::max);
    let mut nodes = Vec::with_capacity(n);
    for j in 0..n {
        // Bisect for the (j+1)-th smallest eigenvalue: count(lo) <= j < count(hi).
        let (mut lo, mut hi) = (0.0f64, upper);
        for _ in 0..2000 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if count_below(&d, &e, mid) > j {
                hi = mid;
            } else {
                lo = mid;
            }
            if hi - lo <= 4.0 * f64::EPSILON * hi {
                break;
            }
        }
        let y = 0.5 * (lo + hi);
        // Σ_k p_k(y)² with p_0 = 1, √(b_{k+1}) p_{k+1} = (y - a_k) p_k - √b_k p_{k-1}
        // (a_k = d_k, √b_k = e_k); `log_scale` keeps p_k and the sum in range.
        let (mut p_prev, mut p) = (0.0f64, 1.0f64);
        let mut sum = 1.0f64;
        let mut log_scale = 0.0f64; // true values = stored · exp(log_scale)
        for k in 0..n - 1 {
            let next = ((y - d[k]) * p - e[k] * p_prev) / e[k + 1];
            p_prev = p;
            p = next;
            sum += p * p;
            if p.abs() > 1e100 {
                p *= 1e-100;
                p_prev *= 1e-100;
                sum *= 1e-200;
                log_scale += 100.0 * std::f64::consts::LN_10;
            }
        }
        let weight = (-(sum.ln() + 2.0 * log_scale)).exp();
        nodes.push(Node {
            x: y / alpha,
            weight,
        });
    }
    // The Christoffel numbers sum to 1 up to rounding; normalise so that the
    // rule reproduces the mean exactly for a constant integrand.
    let total: f64 = nodes.iter().map(|q| q.weight).sum();
    for q in &mut nodes {
        q.weight /= total;
    }
    Ok(nodes)
}

/// The rule's relative error for the closed form `E[e^(-Xτ)] = (1 +
/// τ/α)^(-α)`.
pub fn closed_form_error(nodes: &[Node], alpha: f64, tau: f64) -> f64 {
    let quad: f64 = nodes.iter().map(|q| q.weight * (-q.x * tau).exp()).sum();
    let exact = (-alpha * (tau / alpha).ln_1p()).exp();
    (quad / exact - 1.0).abs()
}

/// Largest relative error of [`closed_form_error`] at `τ_max` and
/// `τ_max/2, /4, /8`.
fn worst_error(nodes: &[Node], alpha: f64, tau_max: f64) -> f64 {
    [1.0, 0.5, 0.25, 0.125]
        .iter()
        .map(|f| closed_form_error(nodes, alpha, tau_max * f))
        .fold(0.0, f64::max)
}

/// The default node count for `α` and the scene's largest optical depth
/// `tau_max` (see the module docs), or `None` if even [`NODE_COUNTS`]'s
/// largest does not reach [`NODE_TOLERANCE`].
pub fn default_node_count(alpha: f64, tau_max: f64) -> Result<Option<usize>, RenderError> {
    for &n in NODE_COUNTS.iter().filter(|&&n| n >= MIN_NODES) {
        if worst_error(&gamma_nodes(alpha, n)?, alpha, tau_max) <= NODE_TOLERANCE {
            return Ok(Some(n));
        }
    }
    Ok(None)
}

/// The quadrature of a scene: its `α`, nodes and the classical media that
/// replace its non-exponential ones.
#[derive(Debug, Clone)]
pub struct TruthPlan {
    /// The common gamma shape of the scene's constant-α media.
    pub alpha: f64,
    /// `(x_i, w_i)`, in node order.
    pub nodes: Vec<Node>,
    /// The largest optical depth of the node rule (box diagonal times the
    /// largest mean extinction).
    pub tau_max: f64,
    /// Whether the node count came from the default rule (`false`: given).
    pub auto_nodes: bool,
    /// The rule's worst relative error for the closed form at `tau_max`,
    /// `tau_max/2`, `/4`, `/8` (see the module docs).
    pub closed_form_error: f64,
    /// Indices of the media scaled by `X` (the constant-α media).
    pub media: Vec<usize>,
    /// Classical media at level `x = 1`, by medium index: `homogeneous`
    /// with `σ_m` or `heterogeneous` with `σ_m ρ` (scale 1). Exponential
    /// `nonexponential` media are here too, and are not scaled.
    replaced: Vec<(usize, MediumDesc, bool)>,
}

/// The constant `α` of a non-exponential medium's channel `sigma`, or why
/// it has none.
fn constant_alpha(i: usize, sigma: f64, model: &TransmittanceDesc) -> Result<f64, RenderError> {
    match *model {
        TransmittanceDesc::Davis { alpha } => Ok(alpha),
        TransmittanceDesc::DavisWeinstein { h: 1.0, c } => Ok(1.0 / (c * c)),
        TransmittanceDesc::DavisWeinstein { h, .. } => Err(RenderError::Unsupported(format!(
            "medium {i}: a Davis-Weinstein medium with h = {h} < 1 has no constant alpha, so no mixture of homogeneous media to average (docs/theory.md §6.6); the truth covers k-fBm 'fgf' and 'davis' media"
        ))),
        TransmittanceDesc::Fgf { hurst, sw, length } => {
            if !(hurst > 0.0) {
                let kind = if hurst == -0.5 { "white noise" } else { "pink noise" };
                return Err(RenderError::Unsupported(format!(
                    "medium {i}: an 'fgf' medium with hurst = {hurst} ({kind}) has no constant alpha, so no mixture of homogeneous media to average (docs/theory.md §6.6); the truth covers k-fBm (hurst > 0) and 'davis' media"
                )));
            }
            let m = Fgf::new(sigma, hurst, sw, length)
                .map_err(|source| RenderError::Param { medium: i, source })?;
            Ok(m.alpha(1.0))
        }
        TransmittanceDesc::Exponential => unreachable!("exponential media have no alpha"),
    }
}

/// Whether two shapes `α` agree to rounding.
fn same_alpha(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(b.abs())
}

/// The bounding box of the shapes that have medium `i` as interior; all
/// shapes if none does (a medium around the camera).
fn medium_box(scene: &SceneDesc, i: usize) -> Option<(DVec3, DVec3)> {
    let bound = |only_interior: bool| {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for s in &scene.shapes {
            if only_interior && s.interior != Some(i) {
                continue;
            }
            let (a, b) = s.world_bbox();
            lo = lo.min(a);
            hi = hi.max(b);
        }
        ((hi - lo).is_finite() && (hi - lo).max_element() >= 0.0).then_some((lo, hi))
    };
    bound(true).or_else(|| bound(false))
}

/// Plan the truth of `scene`: its `α`, the nodes (`nodes` of them, or the
/// default rule's count) and the classical replacement of each
/// non-exponential medium. Errors are one line: an unsupported medium (see
/// the module docs), a bad node count, or an invalid scene.
pub fn plan(scene: &SceneDesc, nodes: Option<usize>) -> Result<TruthPlan, RenderError> {
    scene.validate()?;
    let mut alpha: Option<(usize, f64)> = None;
    let mut media = Vec::new();
    let mut replaced = Vec::new();
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    let mut sigma_max = 0.0f64;
    for (i, m) in scene.media.iter().enumerate() {
        let MediumDesc::NonExponential {
            sigma_t,
            albedo,
            phase,
            model,
            density,
            ..
        } = m
        else {
            continue;
        };
        let exponential = matches!(model, TransmittanceDesc::Exponential);
        if !exponential {
            for &s in sigma_t {
                let a = constant_alpha(i, s as f64, model)?;
                match alpha {
                    None => alpha = Some((i, a)),
                    Some((j, b)) if !same_alpha(a, b) => {
                        return Err(RenderError::Unsupported(if j == i {
                            format!(
                                "medium {i}: its RGB sigma_t channels have different alpha ({b:.6} and {a:.6}): no single level X drives them (docs/theory.md §6.4); use a grey sigma_t or a 'davis' medium"
                            )
                        } else {
                            format!(
                                "media {j} and {i} have different alpha ({b:.6} and {a:.6}): no single level X drives both (docs/theory.md §6.4)"
                            )
                        }))
                    }
                    Some(_) => {}
                }
            }
            media.push(i);
            if let Some((a, b)) = medium_box(scene, i) {
                lo = lo.min(a);
                hi = hi.max(b);
            }
            let rho_max = density
                .as_ref()
                .map_or(1.0, |g| g.grid.data.iter().cloned().fold(0.0f32, f32::max))
                as f64;
            let s = sigma_t.iter().cloned().fold(0.0f32, f32::max) as f64;
            sigma_max = sigma_max.max(s * rho_max);
        }
        let classical = match density {
            None => MediumDesc::Homogeneous {
                sigma_t: *sigma_t,
                albedo: *albedo,
                phase: *phase,
                sample_emitters: true,
            },
            Some(g) => {
                let grey = sigma_t[0] == sigma_t[1] && sigma_t[1] == sigma_t[2];
                let (grid, scale) = if grey {
                    (g.clone(), sigma_t[0])
                } else {
                    // σ_c ρ per channel in one 3-channel grid (scale 1).
                    let mut rgb = (*g.grid).clone();
                    rgb.channels = 3;
                    rgb.data = g
                        .grid
                        .data
                        .iter()
                        .flat_map(|&r| sigma_t.map(|s| s * r))
                        .collect();
                    (
                        GridVolumeDesc {
                            grid: Arc::new(rgb),
                            ..g.clone()
                        },
                        1.0,
                    )
                };
                MediumDesc::Heterogeneous {
                    sigma_t: VolumeDesc::Grid(grid),
                    albedo: VolumeDesc::Constant(*albedo),
                    scale,
                    phase: *phase,
                    sample_emitters: true,
                }
            }
        };
        replaced.push((i, classical, !exponential));
    }
    let Some((_, alpha)) = alpha else {
        return Err(RenderError::Unsupported(
            "the scene has no constant-alpha medium (k-fBm 'fgf' or 'davis'): there is no level X to average over; render it with fgf render".into(),
        ));
    };
    let tau_max = if (hi - lo).is_finite() {
        (hi - lo).length() * sigma_max
    } else {
        0.0
    };
    let (n, auto_nodes) = match nodes {
        Some(n) => (n, false),
        None => match default_node_count(alpha, tau_max)? {
            Some(n) => (n, true),
            None => {
                return Err(RenderError::Unsupported(format!(
                    "alpha = {alpha:.4} with optical depth {tau_max:.4} needs more than {} quadrature nodes for a relative accuracy of {NODE_TOLERANCE:e}; give the node count explicitly (nodes <= {MAX_NODES})",
                    NODE_COUNTS[NODE_COUNTS.len() - 1]
                )))
            }
        },
    };
    let nodes = gamma_nodes(alpha, n)?;
    Ok(TruthPlan {
        alpha,
        closed_form_error: worst_error(&nodes, alpha, tau_max),
        nodes,
        tau_max,
        auto_nodes,
        media,
        replaced,
    })
}

impl TruthPlan {
    /// The classical scene of node `i`: every constant-α medium replaced by
    /// its classical counterpart with extinction `x_i σ_m ρ`, exponential
    /// `nonexponential` media by their classical form.
    pub fn node_scene(&self, scene: &SceneDesc, i: usize) -> Result<SceneDesc, RenderError> {
        let node = self.nodes.get(i).ok_or_else(|| {
            RenderError::InvalidOption(format!("node = {i}; need 0 <= node < {}", self.nodes.len()))
        })?;
        let x = node.x as f32;
        let mut sc = scene.clone();
        for (k, m, scaled) in &self.replaced {
            let mut m = m.clone();
            if *scaled {
                match &mut m {
                    MediumDesc::Homogeneous { sigma_t, .. } => *sigma_t = sigma_t.map(|s| s * x),
                    MediumDesc::Heterogeneous { scale, .. } => *scale *= x,
                    MediumDesc::NonExponential { .. } => {
                        unreachable!("replaced media are classical")
                    }
                }
            }
            sc.media[*k] = m;
        }
        Ok(sc)
    }
}

/// The render seed of node `i` under the user's `seed`.
pub fn node_seed(seed: u64, i: usize) -> u64 {
    stream_key(stream_key(mix64(seed), TRUTH_STREAM), i as u64)
}

/// Options of [`render_node`] and [`truth`].
#[derive(Debug, Clone, Default)]
pub struct TruthOptions {
    /// Samples per pixel of each node's render (default: the scene's).
    pub spp: Option<u32>,
    /// Master seed; node `i` renders with [`node_seed`]`(seed, i)`.
    pub seed: u64,
    /// Also return the per-pixel variance of each node's pixel means.
    pub variance: bool,
}

/// Render node `i` of `plan` classically. Its output depends only on the
/// scene, the plan's node count, `i`, `spp` and `seed`.
pub fn render_node(
    scene: &SceneDesc,
    plan: &TruthPlan,
    i: usize,
    opts: &TruthOptions,
    progress: &dyn Progress,
) -> Result<RenderOutput, RenderError> {
    let sc = plan.node_scene(scene, i)?;
    let ropts = RenderOptions {
        spp: opts.spp,
        seed: Some(node_seed(opts.seed, i)),
        variance: opts.variance,
        spp_per_pass: None,
    };
    render(&sc, &ropts, progress)
}

/// Total samples [`truth`] renders (nodes × pixels × spp), for progress bars.
pub fn total_samples(scene: &SceneDesc, plan: &TruthPlan, opts: &TruthOptions) -> u64 {
    let spp = opts.spp.unwrap_or(scene.sensor.spp) as u64;
    scene.sensor.width as u64 * scene.sensor.height as u64 * spp * plan.nodes.len() as u64
}

/// The truth image: `Σ_i w_i I_i` (row-major from the top-left, RGB
/// interleaved) and, if asked, its standard error `√(Σ_i w_i² var_i)`.
#[derive(Debug, Clone)]
pub struct TruthOutput {
    pub width: usize,
    pub height: usize,
    pub image: Vec<f32>,
    pub stderr: Option<Vec<f32>>,
    pub spp: u32,
}

/// Errors of [`truth`]: the renderer's, and cancellation (a partial
/// quadrature sum is no truth, so nothing of it is returned).
#[derive(Debug, thiserror::Error)]
pub enum TruthError {
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error("interrupted after {done} of {nodes} quadrature nodes")]
    Cancelled { done: usize, nodes: usize },
}

/// Render every node of `plan` and sum them in node order (see the module
/// docs).
pub fn truth(
    scene: &SceneDesc,
    plan: &TruthPlan,
    opts: &TruthOptions,
    progress: &dyn Progress,
) -> Result<TruthOutput, TruthError> {
    if opts.spp == Some(0) {
        return Err(
            RenderError::InvalidOption("spp = 0; need at least 1 sample per pixel".into()).into(),
        );
    }
    let (w, h) = (scene.sensor.width as usize, scene.sensor.height as usize);
    let mut sum = vec![0f64; w * h * 3];
    let mut var = opts.variance.then(|| vec![0f64; w * h * 3]);
    let mut spp = opts.spp.unwrap_or(scene.sensor.spp);
    for (i, node) in plan.nodes.iter().enumerate() {
        let out = match render_node(scene, plan, i, opts, progress) {
            Ok(out) => out,
            Err(RenderError::Cancelled { .. }) => {
                return Err(TruthError::Cancelled {
                    done: i,
                    nodes: plan.nodes.len(),
                })
            }
            Err(e) => return Err(e.into()),
        };
        spp = out.spp_done;
        for (s, &v) in sum.iter_mut().zip(&out.image) {
            *s += node.weight * v as f64;
        }
        if let (Some(acc), Some(v)) = (var.as_mut(), out.variance.as_ref()) {
            for (a, &v) in acc.iter_mut().zip(v) {
                *a += node.weight * node.weight * v as f64;
            }
        }
    }
    Ok(TruthOutput {
        width: w,
        height: h,
        image: sum.iter().map(|&s| s as f32).collect(),
        stderr: var.map(|v| v.iter().map(|&s| s.max(0.0).sqrt() as f32).collect()),
        spp,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `E[Y^k] = Γ(α+k)/Γ(α)` for `Y ~ Gamma(α, 1)`, so `E[X^k] = Π_{j<k}
    /// (α+j)/α` for `X = Y/α`.
    fn moment(alpha: f64, k: u32) -> f64 {
        (0..k).map(|j| (alpha + j as f64) / alpha).product()
    }

    #[test]
    fn nodes_integrate_gamma_moments_exactly() {
        for &alpha in &[0.3, 0.7, 1.0, 1.14, 2.0, 8.0, 40.0] {
            for &n in &[1usize, 2, 5, 12, 24] {
                let q = gamma_nodes(alpha, n).unwrap();
                assert_eq!(q.len(), n);
                assert!(q.windows(2).all(|p| p[0].x < p[1].x), "nodes ascending");
                assert!(q.iter().all(|p| p.x > 0.0 && p.weight > 0.0));
                for k in 0..(2 * n as u32).min(16) {
                    let quad: f64 = q.iter().map(|p| p.weight * p.x.powi(k as i32)).sum();
                    let exact = moment(alpha, k);
                    assert!(
                        (quad / exact - 1.0).abs() < 1e-10,
                        "alpha {alpha}, n {n}, k {k}: {quad} vs {exact}"
                    );
                }
            }
        }
    }

    #[test]
    fn large_rules_keep_finite_weights_that_sum_to_one() {
        for &alpha in &[0.5, 3.0] {
            let q = gamma_nodes(alpha, 1024).unwrap();
            assert!(q.iter().all(|p| p.weight.is_finite() && p.weight >= 0.0));
            let mean: f64 = q.iter().map(|p| p.weight * p.x).sum();
            assert!((mean - 1.0).abs() < 1e-9, "mean {mean}");
        }
    }

    #[test]
    fn default_rule_reaches_its_tolerance_and_is_adaptive() {
        // docs/theory.md §6.3: 24 nodes miss (1+τ/α)^-α by 1.7 % at α = 0.7, τ = 12.
        let q24 = gamma_nodes(0.7, 24).unwrap();
        let e24 = closed_form_error(&q24, 0.7, 12.0);
        assert!(e24 > 1e-2 && e24 < 3e-2, "{e24}");
        let n = default_node_count(0.7, 12.0).unwrap().unwrap();
        assert!(n > 24);
        assert!(worst_error(&gamma_nodes(0.7, n).unwrap(), 0.7, 12.0) <= NODE_TOLERANCE);
        // A thin, nearly exponential medium needs only the minimum.
        assert_eq!(default_node_count(8.0, 1.0).unwrap(), Some(MIN_NODES));
    }

    fn scene(medium: &str) -> SceneDesc {
        let xml = format!(
            r#"<scene version="3.0.0">
  <integrator type="volpath"/>
  <sensor type="perspective"><float name="fov" value="10"/>
    <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
    <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
    <film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film>
  </sensor>
  {medium}
  <shape type="cube"><bsdf type="null"/><ref name="interior" id="m"/></shape>
  <emitter type="constant"/>
</scene>"#
        );
        fgf_scene::load_str(&xml, "test.xml", std::path::Path::new("."), &[]).unwrap()
    }

    #[test]
    fn plan_rewrites_the_medium_as_homogeneous_levels() {
        let sc = scene(
            r#"<medium type="nonexponential" id="m"><string name="transmittance" value="davis"/>
               <float name="alpha" value="1.5"/><float name="sigma_t" value="2"/></medium>"#,
        );
        let p = plan(&sc, None).unwrap();
        assert_eq!(p.alpha, 1.5);
        assert_eq!(p.media, vec![0]);
        // The cube [-1, 1]^3: diagonal 2√3, σ_m = 2.
        assert!((p.tau_max - 4.0 * 3f64.sqrt()).abs() < 1e-6);
        assert!(p.auto_nodes && p.closed_form_error <= NODE_TOLERANCE);
        for (i, q) in p.nodes.iter().enumerate() {
            let MediumDesc::Homogeneous { sigma_t, .. } = &p.node_scene(&sc, i).unwrap().media[0]
            else {
                panic!("node {i}: not homogeneous")
            };
            assert!((sigma_t[0] as f64 - 2.0 * q.x).abs() < 1e-5 * (1.0 + q.x));
        }
        assert!(p.node_scene(&sc, p.nodes.len()).is_err());
        assert_eq!(plan(&sc, Some(3)).unwrap().nodes.len(), 3);
        assert_ne!(node_seed(0, 0), node_seed(0, 1));
        assert_ne!(node_seed(0, 1), node_seed(1, 1));
    }

    #[test]
    fn truth_is_the_weighted_sum_of_the_node_renders() {
        let sc = scene(
            r#"<medium type="fgf" id="m"><float name="hurst" value="1.2"/><float name="sw" value="3"/>
               <float name="sigma_t" value="1.5"/><rgb name="albedo" value="0.5"/></medium>"#,
        );
        let p = plan(&sc, Some(4)).unwrap();
        let opts = TruthOptions {
            spp: Some(2),
            seed: 9,
            variance: true,
        };
        let out = truth(&sc, &p, &opts, &fgf_core::NoProgress).unwrap();
        let mut sum = vec![0f64; out.image.len()];
        for (i, q) in p.nodes.iter().enumerate() {
            let node = render_node(&sc, &p, i, &opts, &fgf_core::NoProgress).unwrap();
            for (s, &v) in sum.iter_mut().zip(&node.image) {
                *s += q.weight * v as f64;
            }
        }
        let want: Vec<f32> = sum.iter().map(|&s| s as f32).collect();
        assert_eq!(out.image, want);
        assert!(out
            .stderr
            .unwrap()
            .iter()
            .all(|s| s.is_finite() && *s >= 0.0));
    }

    #[test]
    fn media_without_a_constant_alpha_are_refused() {
        let pink = scene(
            r#"<medium type="fgf" id="m"><float name="hurst" value="-0.2"/><float name="sw" value="1"/></medium>"#,
        );
        let e = plan(&pink, None).unwrap_err().to_string();
        assert!(
            e.contains("pink noise") && e.contains("no constant alpha"),
            "{e}"
        );
        let rgb = scene(
            r#"<medium type="fgf" id="m"><rgb name="sigma_t" value="1, 2, 3"/><float name="hurst" value="0.5"/>
               <float name="sw" value="1"/></medium>"#,
        );
        let e = plan(&rgb, None).unwrap_err().to_string();
        assert!(
            e.contains("RGB sigma_t channels have different alpha"),
            "{e}"
        );
    }

    #[test]
    fn bad_rules_are_refused() {
        assert!(gamma_nodes(0.0, 4).is_err());
        assert!(gamma_nodes(f64::NAN, 4).is_err());
        assert!(gamma_nodes(1.0, 0).is_err());
        assert!(gamma_nodes(1.0, MAX_NODES + 1).is_err());
    }
}
