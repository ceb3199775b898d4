//! Spectral synthesis of fractional Gaussian fields on regular grids
//! (`docs/theory.md` §1, "Synthesis on a grid" and "Synthesis of k-fBm").
//!
//! Algorithm, in the order the code runs it (see the crate docs for the
//! conventions):
//!
//! 1. **Noise + FFT along x.** Each row of the (padded) grid gets unit normal
//!    noise from its own counter-based stream `(seed, row index)` and is
//!    transformed by a real-to-complex FFT into its own slot of one buffer
//!    that holds the half spectrum in place (`nx/2+1` complex per row).
//! 2. **FFT along y**, blocks of 16 columns gathered into a scratch buffer.
//! 3. **Per y-plane: FFT along z, filter, inverse FFT along z.** The filter is
//!    `sqrt(S_w/dx^d) |k|^(-s) / N` (the unit noise becomes cell-averaged
//!    white noise of variance `S_w/dx^d`, and `1/N` is the inverse-FFT
//!    normalisation); `k = 0` is dropped. For an anchored k-fBm the Taylor
//!    coefficients at the anchor are summed here, in f64, per plane.
//! 4. **Inverse FFT along y**, then **complex-to-real along x**, cropping the
//!    padding away and subtracting the Taylor polynomial.
//!
//! Every step is a parallel loop over disjoint rows/columns/planes whose
//! result does not depend on scheduling; the only reduction (the Taylor
//! sums) is collected per plane and added in plane order, so the output is
//! bit-identical for any number of threads.
//!
//! Memory: the whole computation runs in one buffer holding the half
//! spectrum of the periodic domain (`Nz·Ny·(Nx+2)` values), which is then
//! cropped and compacted in place into the output and shrunk. Without
//! padding the peak is the output plus ~2/nx and per-thread scratch; with
//! padding `p` it is `p^d` times the output (a 3D k-fBm at the default
//! `p = 2`: ~8× the output array).

mod anchor;
mod filter;
mod plan;
#[cfg(test)]
mod tests;
mod transform;

use crate::error::{check_memory, FieldError};
use fgf_core::{ParamError, Progress};
use filter::Filter;
use plan::Plan;
use rayon::prelude::*;
use rustfft::FftNum;
use std::f64::consts::PI;

/// Floating-point types the synthesis runs in (f32 or f64). The whole FFT
/// pipeline runs in the output precision; filters, Taylor sums and
/// polynomials are computed in f64.
pub trait Real: FftNum + Default {
    fn of(v: f64) -> Self;
    fn as_f64(self) -> f64;
}
impl Real for f32 {
    #[inline]
    fn of(v: f64) -> Self {
        v as f32
    }
    #[inline]
    fn as_f64(self) -> f64 {
        self as f64
    }
}
impl Real for f64 {
    #[inline]
    fn of(v: f64) -> Self {
        v
    }
    #[inline]
    fn as_f64(self) -> f64 {
        self
    }
}

/// Where an anchored k-fBm (H > 0) is pinned to zero together with its
/// first k-1 derivatives. Pink and white noise are stationary and are never
/// anchored (the anchor is ignored for H < 0).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Anchor {
    /// No Taylor subtraction: the raw periodic field of the padded domain
    /// (with `padding = 1`, a seamlessly tileable texture).
    None,
    /// Sample `(0, 0, 0)`, the grid's origin corner (the default).
    Corner,
    /// Sample `(n_z/2, n_y/2, n_x/2)` (integer division), the centre sample.
    Center,
    /// Any sample, indices in the order of `shape` (`[z][y][x]`).
    Index(Vec<usize>),
}

/// Output sample type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Precision {
    F32,
    F64,
}

/// Parameters of [`synthesize`]. Build with [`SynthParams::new`] and set the
/// public fields.
#[derive(Debug, Clone)]
pub struct SynthParams {
    /// Grid shape, 1 to 3 axes, C order: `[x]`, `[y, x]` or `[z, y, x]`.
    pub shape: Vec<usize>,
    /// Grid spacing `dx` in scene units, the same on every axis (default 1).
    pub spacing: f64,
    /// Hurst parameter `H`, `-d/2 <= H < 3`, not 0, 1 or 2. `H = -d/2` is
    /// white noise, `-d/2 < H < 0` pink noise, `k-1 < H < k` a k-fBm.
    pub hurst: f64,
    /// White-noise strength `S_w > 0` (default 1): `P(k) = S_w |k|^(-2s)`.
    pub sw: f64,
    /// Seed of the counter-based noise streams.
    pub seed: u64,
    /// Anchor of a k-fBm (ignored for pink/white noise). Default: corner.
    pub anchor: Anchor,
    /// Size factor of the periodic domain per axis (>= 1). `None`: 1 for
    /// pink/white noise, 2 for k-fBm. Padded axes are rounded up to a size
    /// with prime factors 2, 3, 5 and 7 only.
    pub padding: Option<f64>,
    /// Output type (default f32).
    pub precision: Precision,
}

impl SynthParams {
    /// Defaults: `spacing = 1`, `sw = 1`, `seed = 0`, corner anchor,
    /// automatic padding, f32.
    pub fn new(shape: &[usize], hurst: f64) -> Self {
        SynthParams {
            shape: shape.to_vec(),
            spacing: 1.0,
            hurst,
            sw: 1.0,
            seed: 0,
            anchor: Anchor::Corner,
            padding: None,
            precision: Precision::F32,
        }
    }
}

/// Samples of a field, in the requested precision.
#[derive(Debug, Clone, PartialEq)]
pub enum FieldData {
    F32(Vec<f32>),
    F64(Vec<f64>),
}

impl FieldData {
    pub fn len(&self) -> usize {
        match self {
            FieldData::F32(v) => v.len(),
            FieldData::F64(v) => v.len(),
        }
    }
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Value `i` as f64.
    #[inline]
    pub fn get(&self, i: usize) -> f64 {
        match self {
            FieldData::F32(v) => v[i] as f64,
            FieldData::F64(v) => v[i],
        }
    }
    /// A copy as f32 (what the file formats store).
    pub fn to_f32(&self) -> Vec<f32> {
        match self {
            FieldData::F32(v) => v.clone(),
            FieldData::F64(v) => v.iter().map(|&x| x as f32).collect(),
        }
    }
}

/// A synthesized field: C-order samples, `data[(z*ny + y)*nx + x]`, sample
/// `i` along an axis at position `i·spacing` from the origin corner.
#[derive(Debug, Clone)]
pub struct Field {
    pub shape: Vec<usize>,
    /// Shape of the periodic domain it was cut from.
    pub padded_shape: Vec<usize>,
    pub spacing: f64,
    pub hurst: f64,
    pub sw: f64,
    pub seed: u64,
    /// Indices of the anchor sample (k-fBm only; `None` if not anchored).
    pub anchor: Option<Vec<usize>>,
    pub data: FieldData,
}

/// The `S_w` a 3D field needs so that its restriction to any line has the
/// covariance of the 1D model with `sw_1d` (`docs/theory.md` §1, caveat for 3D
/// grids): `S_w3 = S_w · 2π(2H+1)`, from `C(H,3) = C(H,1) / (2π(2H+1))`.
/// Valid for `H > -1/2` (the rendering range).
///
/// ```
/// let sw3 = fgf_field::sw_3d_for_ray_statistics(-0.1, 1.0).unwrap();
/// assert!((sw3 - 2.0 * std::f64::consts::PI * 0.8).abs() < 1e-12);
/// ```
pub fn sw_3d_for_ray_statistics(hurst: f64, sw_1d: f64) -> Result<f64, ParamError> {
    ParamError::check_positive("sw", sw_1d)?;
    if !(hurst.is_finite() && hurst > -0.5) {
        return Err(ParamError::new(
            "hurst",
            hurst,
            "the 1D ray model needs H > -1/2",
            "-0.5 < hurst",
        ));
    }
    Ok(sw_1d * 2.0 * PI * (2.0 * hurst + 1.0))
}

/// Expected variance of every sample of an unanchored synthesized field (the
/// discrete spectral sum `S_w/dx^d · (1/N) Σ_{k≠0} |k|^(-2s)` over the padded
/// periodic domain, Nyquist modes excluded for k-fBm). This, not the
/// continuum variance, is what grid fields must be validated against.
pub fn discrete_spectral_variance(params: &SynthParams) -> Result<f64, ParamError> {
    let plan = Plan::new(params)?;
    let filter = Filter::new(&plan);
    let [n0, n1, n2] = plan.pad;
    let n = (n0 * n1 * n2) as f64;
    // field = Σ_m filter(m) W_m e^{ikx} with E|W_m|² = N: var = N Σ filter².
    // Half spectrum: x-index 0 (and Nyquist for even n2) once, others twice.
    let per_z: Vec<f64> = (0..n0)
        .into_par_iter()
        .map(|iz| {
            let mut acc = 0.0;
            for iy in 0..n1 {
                for ix in 0..n2 / 2 + 1 {
                    let w = if ix == 0 || (n2 % 2 == 0 && ix == n2 / 2) {
                        1.0
                    } else {
                        2.0
                    };
                    acc += w * filter.at(iz, iy, ix).powi(2);
                }
            }
            acc
        })
        .collect();
    Ok(n * per_z.iter().sum::<f64>())
}

/// Shape of the periodic domain a request will be synthesized on (after
/// defaults and rounding of the padding), in the order of `shape`.
pub fn padded_shape(params: &SynthParams) -> Result<Vec<usize>, ParamError> {
    let plan = Plan::new(params)?;
    Ok(plan.pad[3 - plan.d..].to_vec())
}

/// Bytes [`synthesize`] allocates at its peak, excluding per-thread scratch.
pub fn estimate_memory(params: &SynthParams) -> Result<Option<u64>, ParamError> {
    let plan = Plan::new(params)?;
    Ok(plan.bytes(elem_size(params.precision)))
}

/// The memory check [`synthesize`] makes before it allocates, for callers
/// that do other work sized by the same request first (an ensemble's
/// calibration): an error naming the shape and the GiB needed.
pub fn check_synthesis_memory(params: &SynthParams) -> Result<(), FieldError> {
    check_plan_memory(params, &Plan::new(params)?)
}

fn check_plan_memory(params: &SynthParams, plan: &Plan) -> Result<(), FieldError> {
    check_memory(
        &format!(
            "a field of shape {:?} (periodic domain {:?})",
            params.shape,
            &plan.pad[3 - plan.d..]
        ),
        plan.bytes(elem_size(params.precision)),
    )
}

/// Work units [`synthesize`] reports through [`Progress::inc`].
pub fn work_units(params: &SynthParams) -> Result<u64, ParamError> {
    Ok(Plan::new(params)?.work_units())
}

fn elem_size(p: Precision) -> usize {
    match p {
        Precision::F32 => 4,
        Precision::F64 => 8,
    }
}

/// Synthesize one realization. See the module docs for the algorithm and
/// the crate docs for conventions.
///
/// ```
/// use fgf_field::{synthesize, SynthParams, FieldData};
/// let mut p = SynthParams::new(&[32, 48], -0.3);
/// p.seed = 7;
/// let f = synthesize(&p, &fgf_core::NoProgress).unwrap();
/// assert_eq!(f.data.len(), 32 * 48);
/// ```
pub fn synthesize(params: &SynthParams, progress: &dyn Progress) -> Result<Field, FieldError> {
    let plan = Plan::new(params)?;
    check_plan_memory(params, &plan)?;
    let data = match params.precision {
        Precision::F32 => FieldData::F32(transform::run::<f32>(&plan, params.seed, progress)?),
        Precision::F64 => FieldData::F64(transform::run::<f64>(&plan, params.seed, progress)?),
    };
    // The filter is sqrt(S_w / dx^d) |k|^(-s): extreme sw or spacing
    // overflow (or underflow into 0 * inf) the requested precision. Name
    // the parameters, not a later writer.
    if let Some(i) = (0..data.len()).find(|&i| !data.get(i).is_finite()) {
        let g = |v: f64| {
            if v != 0.0 && !(1e-4..1e16).contains(&v.abs()) {
                format!("{v:e}")
            } else {
                format!("{v}")
            }
        };
        return Err(ParamError::new(
            "sw",
            g(params.sw),
            format!(
                "the field is not finite (sample #{i} is {}) with spacing = {}, hurst = {}: sw / spacing^d and spacing^(2H) must keep the values inside the {} range",
                data.get(i),
                g(params.spacing),
                params.hurst,
                match params.precision { Precision::F32 => "float32", Precision::F64 => "float64" }
            ),
            "a finite field: moderate sw and spacing (or float64)",
        )
        .into());
    }
    Ok(Field {
        shape: params.shape.clone(),
        padded_shape: plan.pad[3 - plan.d..].to_vec(),
        spacing: params.spacing,
        hurst: params.hurst,
        sw: params.sw,
        seed: params.seed,
        anchor: plan.anchor.map(|a| a[3 - plan.d..].to_vec()),
        data,
    })
}
