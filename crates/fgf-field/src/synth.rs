//! Spectral synthesis of fractional Gaussian fields on regular grids
//! (`theory.md` §1, "Synthesis on a grid" and "Synthesis of k-fBm").
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

use crate::noise::{stream, Purpose};
use fgf_core::{Cancelled, ParamError, Progress};
use rand::Rng;
use rand_distr::StandardNormal;
use rayon::prelude::*;
use realfft::RealFftPlanner;
use rustfft::num_complex::Complex;
use rustfft::num_traits::Zero;
use rustfft::{Fft, FftNum, FftPlanner};
use std::f64::consts::PI;
use std::sync::Arc;

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

/// Errors of the field crate.
#[derive(Debug, thiserror::Error)]
pub enum FieldError {
    #[error(transparent)]
    Param(#[from] ParamError),
    /// Refused before allocating anything.
    #[error("{what} needs about {} but only {} is available (MemAvailable in /proc/meminfo); use a smaller shape, less padding or float32", fmt_bytes(*.needed), fmt_bytes(*.available))]
    OutOfMemory {
        what: String,
        needed: u64,
        available: u64,
    },
    /// The [`Progress`] asked to stop.
    #[error(transparent)]
    Cancelled(#[from] Cancelled),
}

pub(crate) fn fmt_bytes(b: u64) -> String {
    let gib = b as f64 / (1u64 << 30) as f64;
    if gib >= 1.0 {
        format!("{gib:.2} GiB")
    } else {
        format!("{:.1} MiB", b as f64 / (1u64 << 20) as f64)
    }
}

/// `MemAvailable` from `/proc/meminfo`, in bytes; `None` where it cannot be
/// read (non-Linux), in which case no refusal happens.
pub fn mem_available() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = s.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Refuse `needed` bytes if they exceed what the system has available.
pub(crate) fn check_memory(what: &str, needed: Option<u64>) -> Result<(), FieldError> {
    let available = mem_available().unwrap_or(u64::MAX);
    match needed {
        Some(n) if n <= available => Ok(()),
        n => Err(FieldError::OutOfMemory {
            what: what.to_string(),
            needed: n.unwrap_or(u64::MAX),
            available,
        }),
    }
}

/// The `S_w` a 3D field needs so that its restriction to any line has the
/// covariance of the 1D model with `sw_1d` (`theory.md` §1, caveat for 3D
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

/// Number of (z, y, x) axes used; shapes are stored as `[z, y, x]` with 1
/// for missing leading axes.
const B: usize = 16; // columns per gathered block: 128-256 contiguous bytes per row read

/// Validated synthesis plan.
#[derive(Debug, Clone)]
pub(crate) struct Plan {
    d: usize,
    out: [usize; 3],
    pad: [usize; 3],
    s: f64,
    dx: f64,
    amp: f64,
    /// True for k-fBm: Nyquist modes are dropped so that the band-limited
    /// interpolant (whose derivatives we subtract) is real and unique.
    zero_nyquist: bool,
    anchor: Option<[usize; 3]>,
    /// Multi-indices `[az, ay, ax]` of the Taylor terms, `|a| <= k-1`.
    terms: Vec<[u32; 3]>,
}

/// Smallest `m >= n` whose prime factors are all in {2, 3, 5, 7}: fast sizes
/// for the mixed-radix FFT.
fn next_smooth(n: usize) -> usize {
    let mut m = n.max(1);
    loop {
        let mut r = m;
        for p in [2, 3, 5, 7] {
            while r % p == 0 {
                r /= p;
            }
        }
        if r == 1 {
            return m;
        }
        m += 1;
    }
}

impl Plan {
    pub(crate) fn new(p: &SynthParams) -> Result<Plan, ParamError> {
        let d = p.shape.len();
        if !(1..=3).contains(&d) {
            return Err(ParamError::new(
                "shape",
                format!("{:?}", p.shape),
                "must have 1, 2 or 3 axes",
                "shape = (nx,), (ny, nx) or (nz, ny, nx)",
            ));
        }
        if p.shape.contains(&0) || p.shape.iter().product::<usize>() < 2 {
            return Err(ParamError::new(
                "shape",
                format!("{:?}", p.shape),
                "every axis needs >= 1 sample and the grid >= 2 samples",
                "each n >= 1, product >= 2",
            ));
        }
        let dx = ParamError::check_positive("spacing", p.spacing)?;
        let sw = ParamError::check_positive("sw", p.sw)?;
        let h = p.hurst;
        let hmin = -(d as f64) / 2.0;
        if !h.is_finite() || h < hmin || h >= 3.0 || (h >= 0.0 && h.fract() == 0.0) {
            return Err(ParamError::new(
                "hurst",
                h,
                format!("outside the range of a {d}D field (white noise at -d/2, pink noise below 0, k-fBm in (k-1, k) for k = 1, 2, 3)"),
                format!("{hmin} <= hurst < 3, hurst not 0, 1 or 2"),
            ));
        }
        let kfbm = if h > 0.0 { h.ceil() as u32 } else { 0 };
        let padding = match p.padding {
            None => {
                if kfbm > 0 {
                    2.0
                } else {
                    1.0
                }
            }
            Some(x) if x.is_finite() && x >= 1.0 => x,
            Some(x) => {
                return Err(ParamError::new(
                    "padding",
                    x,
                    "the periodic domain cannot be smaller than the grid",
                    "1 <= padding < inf",
                ))
            }
        };
        let mut out = [1usize; 3];
        out[3 - d..].copy_from_slice(&p.shape);
        let mut pad = out;
        for ax in 3 - d..3 {
            if padding > 1.0 {
                let want = (out[ax] as f64 * padding).ceil();
                if want > 1e12 {
                    return Err(ParamError::new(
                        "padding",
                        padding,
                        "padded grid too large",
                        "1 <= padding, padded axis < 1e12",
                    ));
                }
                pad[ax] = next_smooth(want as usize);
            }
        }
        let anchor = if kfbm == 0 {
            None
        } else {
            match &p.anchor {
                Anchor::None => None,
                Anchor::Corner => Some([0, 0, 0]),
                Anchor::Center => Some([out[0] / 2, out[1] / 2, out[2] / 2]),
                Anchor::Index(idx) => {
                    if idx.len() != d || idx.iter().zip(&p.shape).any(|(i, n)| i >= n) {
                        return Err(ParamError::new(
                            "anchor",
                            format!("{idx:?}"),
                            format!("must be one index per axis inside the grid {:?}", p.shape),
                            "0 <= anchor[i] < shape[i]",
                        ));
                    }
                    let mut a = [0usize; 3];
                    a[3 - d..].copy_from_slice(idx);
                    Some(a)
                }
            }
        };
        let mut terms = Vec::new();
        if anchor.is_some() {
            let used = |ax: usize| ax >= 3 - d;
            for az in 0..kfbm {
                for ay in 0..kfbm {
                    for ax in 0..kfbm {
                        if az + ay + ax < kfbm
                            && (az == 0 || used(0))
                            && (ay == 0 || used(1))
                            && (ax == 0 || used(2))
                        {
                            terms.push([az, ay, ax]);
                        }
                    }
                }
            }
        }
        let n_pad: f64 = pad.iter().map(|&n| n as f64).product();
        Ok(Plan {
            d,
            out,
            pad,
            s: h + d as f64 / 2.0,
            dx,
            amp: (sw / dx.powi(d as i32)).sqrt() / n_pad,
            zero_nyquist: kfbm > 0,
            anchor,
            terms,
        })
    }

    /// Bytes the synthesis allocates at its peak (the one buffer holding
    /// the padded half spectrum, later the output; not scratch).
    pub(crate) fn bytes(&self, elem: usize) -> Option<u64> {
        let [n0, n1, n2] = self.pad;
        (n0 as u64)
            .checked_mul(n1 as u64)?
            .checked_mul(2 * (n2 as u64 / 2 + 1))?
            .checked_mul(elem as u64)
    }

    /// Work units reported to [`Progress`].
    pub(crate) fn work_units(&self) -> u64 {
        let [n0, n1, n2] = self.pad;
        let nblk = (n2 / 2 + 1).div_ceil(B);
        let y_pass = |nz: usize| if n1 > 1 { (nz * nblk) as u64 } else { 0 };
        (n0 * n1) as u64
            + y_pass(n0)
            + n1 as u64
            + y_pass(self.out[0])
            + (self.out[0] * self.out[1]) as u64
    }

    /// Signed wavenumber of index `i` on an axis of `n` samples.
    fn wavenumber(&self, i: usize, n: usize) -> f64 {
        let m = if i <= n / 2 {
            i as f64
        } else {
            i as f64 - n as f64
        };
        2.0 * PI * m / (n as f64 * self.dx)
    }

    fn is_nyquist(i: usize, n: usize) -> bool {
        n % 2 == 0 && n > 1 && i == n / 2
    }
}

/// The spectral filter `amp |k|^(-s)`, 0 at k = 0 (and at Nyquist for k-fBm).
/// On 3D grids whose axes all have the same length, `|k|²` is
/// `(2π/(n dx))²` times an integer, and the power comes from a table.
struct Filter {
    keep: [Vec<bool>; 3],
    m2: [Vec<usize>; 3],
    k2: [Vec<f64>; 3],
    lut: Option<Vec<f64>>,
    amp: f64,
    s: f64,
}

impl Filter {
    fn new(plan: &Plan) -> Filter {
        let [n0, n1, n2] = plan.pad;
        let lens = [n0, n1, n2 / 2 + 1];
        let mut keep: [Vec<bool>; 3] = Default::default();
        let mut m2: [Vec<usize>; 3] = Default::default();
        let mut k2: [Vec<f64>; 3] = Default::default();
        for ax in 0..3 {
            let n = plan.pad[ax];
            for i in 0..lens[ax] {
                keep[ax].push(!(plan.zero_nyquist && Plan::is_nyquist(i, n)));
                let m = if i <= n / 2 { i } else { n - i };
                m2[ax].push(m * m);
                k2[ax].push(plan.wavenumber(i, n).powi(2));
            }
        }
        let used: Vec<usize> = plan.pad[3 - plan.d..].to_vec();
        let n = used[0];
        let qmax = plan.d * (n / 2) * (n / 2);
        // The table has d·(n/2)² entries: it only pays off when it is much
        // smaller than the number of stored modes (3D grids, not 1D/2D).
        let modes = lens.iter().product::<usize>();
        let lut = if used.iter().all(|&m| m == n) && plan.s != 0.0 && 4 * (qmax + 1) <= modes {
            let unit = (2.0 * PI / (n as f64 * plan.dx)).powi(2);
            Some(
                (0..=qmax)
                    .map(|q| {
                        if q == 0 {
                            0.0
                        } else {
                            plan.amp * (unit * q as f64).powf(-plan.s / 2.0)
                        }
                    })
                    .collect(),
            )
        } else {
            None
        };
        Filter {
            keep,
            m2,
            k2,
            lut,
            amp: plan.amp,
            s: plan.s,
        }
    }

    #[inline]
    fn at(&self, iz: usize, iy: usize, ix: usize) -> f64 {
        if !(self.keep[0][iz] && self.keep[1][iy] && self.keep[2][ix]) {
            return 0.0;
        }
        match &self.lut {
            Some(lut) => lut[self.m2[0][iz] + self.m2[1][iy] + self.m2[2][ix]],
            None => {
                let k2 = self.k2[0][iz] + self.k2[1][iy] + self.k2[2][ix];
                if k2 == 0.0 {
                    0.0
                } else if self.s == 0.0 {
                    self.amp
                } else {
                    self.amp * k2.powf(-self.s / 2.0)
                }
            }
        }
    }
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
    check_memory(
        &format!(
            "a field of shape {:?} (periodic domain {:?})",
            params.shape,
            &plan.pad[3 - plan.d..]
        ),
        plan.bytes(elem_size(params.precision)),
    )?;
    let data = match params.precision {
        Precision::F32 => FieldData::F32(run::<f32>(&plan, params.seed, progress)?),
        Precision::F64 => FieldData::F64(run::<f64>(&plan, params.seed, progress)?),
    };
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

/// A raw pointer shared by parallel jobs that touch disjoint elements.
#[derive(Clone, Copy)]
struct SyncPtr<T>(*mut T);
unsafe impl<T> Send for SyncPtr<T> {}
unsafe impl<T> Sync for SyncPtr<T> {}
impl<T> SyncPtr<T> {
    #[inline]
    fn get(self) -> *mut T {
        self.0
    }
}

/// View a row of `2m` reals as `m` complex numbers (`Complex` is `repr(C)`).
fn as_complex_mut<T>(row: &mut [T]) -> &mut [Complex<T>] {
    debug_assert!(row.len() % 2 == 0);
    // SAFETY: Complex<T> is repr(C) { re: T, im: T }: same alignment as T,
    // size 2·size_of::<T>(); the length is halved.
    unsafe { std::slice::from_raw_parts_mut(row.as_mut_ptr() as *mut Complex<T>, row.len() / 2) }
}

/// FFT along y of one contiguous z-slab (`n1` rows of `nxh` complex), in
/// blocks of `B` columns gathered into `tmp`.
fn y_fft_slab<T: Real>(
    slab: &mut [Complex<T>],
    n1: usize,
    nxh: usize,
    fft: &Arc<dyn Fft<T>>,
    tmp: &mut [Complex<T>],
    scr: &mut [Complex<T>],
) {
    for x0 in (0..nxh).step_by(B) {
        let bw = B.min(nxh - x0);
        for y in 0..n1 {
            for j in 0..bw {
                tmp[j * n1 + y] = slab[y * nxh + x0 + j];
            }
        }
        fft.process_with_scratch(&mut tmp[..bw * n1], scr);
        for y in 0..n1 {
            for j in 0..bw {
                slab[y * nxh + x0 + j] = tmp[j * n1 + y];
            }
        }
    }
}

/// Slab-fused passes (noise + x + y in one z-slab while it is in cache) are
/// used when there are enough slabs to keep every thread busy.
fn fuse_slabs(n0: usize) -> bool {
    n0 >= 4 * rayon::current_num_threads()
}

/// FFT along y of every (z, x-block) of slabs `0..nz`, in place.
fn y_pass<T: Real>(
    spec: SyncPtr<Complex<T>>,
    dims: [usize; 3],
    nz: usize,
    fft: &Arc<dyn Fft<T>>,
    progress: &dyn Progress,
) {
    let [_, n1, n2] = dims;
    let nxh = n2 / 2 + 1;
    let nblk = nxh.div_ceil(B);
    (0..nz * nblk).into_par_iter().for_each_init(
        || {
            (
                vec![Complex::<T>::zero(); B * n1],
                vec![Complex::<T>::zero(); fft.get_inplace_scratch_len()],
            )
        },
        |(tmp, scr), job| {
            if progress.cancelled() {
                return;
            }
            let (z, x0) = (job / nblk, (job % nblk) * B);
            let bw = B.min(nxh - x0);
            let base = spec.get();
            for y in 0..n1 {
                // SAFETY: job (z, block) owns elements [z][*][x0..x0+bw].
                let src =
                    unsafe { std::slice::from_raw_parts(base.add((z * n1 + y) * nxh + x0), bw) };
                for (j, v) in src.iter().enumerate() {
                    tmp[j * n1 + y] = *v;
                }
            }
            fft.process_with_scratch(&mut tmp[..bw * n1], scr);
            for y in 0..n1 {
                let dst = unsafe {
                    std::slice::from_raw_parts_mut(base.add((z * n1 + y) * nxh + x0), bw)
                };
                for (j, v) in dst.iter_mut().enumerate() {
                    *v = tmp[j * n1 + y];
                }
            }
            progress.inc(1);
        },
    );
}

/// Per-axis `e^{i k a}` and wavenumbers for the Taylor sums.
struct Taylor {
    k: [Vec<f64>; 3],
    phase: [Vec<Complex<f64>>; 3],
    terms: Vec<[u32; 3]>,
}

impl Taylor {
    fn new(plan: &Plan, a: [usize; 3]) -> Taylor {
        let [n0, n1, n2] = plan.pad;
        let lens = [n0, n1, n2 / 2 + 1];
        let mut k: [Vec<f64>; 3] = Default::default();
        let mut phase: [Vec<Complex<f64>>; 3] = Default::default();
        for ax in 0..3 {
            for i in 0..lens[ax] {
                let kk = plan.wavenumber(i, plan.pad[ax]);
                k[ax].push(kk);
                phase[ax].push(Complex::from_polar(1.0, kk * a[ax] as f64 * plan.dx));
            }
        }
        Taylor {
            k,
            phase,
            terms: plan.terms.clone(),
        }
    }

    /// Highest derivative order along z plus one (the number of z-line sums).
    fn kz_orders(&self) -> usize {
        self.terms
            .iter()
            .map(|t| t[0] as usize + 1)
            .max()
            .unwrap_or(0)
    }

    /// Add the z-line `(*, iy, ix)` to the derivative sums
    /// `∂^a field(anchor) = Σ_modes c · Re(F (ik)^a e^{ik·anchor})`, given
    /// `line[p] = Σ_z F e^{i kz z_a} kz^p`. `c = 2` for modes whose conjugate
    /// is not stored in the half spectrum. Splitting the sum per line keeps
    /// the per-mode work to one complex multiply-add per z-order.
    fn add_line(&self, acc: &mut [f64], line: &[Complex<f64>], iy: usize, ix: usize) {
        let c = if ix == 0 { 1.0 } else { 2.0 };
        let lp = self.phase[1][iy] * self.phase[2][ix] * c;
        for (t, a) in self.terms.iter().zip(acc.iter_mut()) {
            let g = line[t[0] as usize]
                * lp
                * (self.k[1][iy].powi(t[1] as i32) * self.k[2][ix].powi(t[2] as i32));
            // Re(i^n g): the power of i from (ik)^a.
            *a += match (t[0] + t[1] + t[2]) % 4 {
                0 => g.re,
                1 => -g.im,
                2 => -g.re,
                _ => g.im,
            };
        }
    }
}

/// The Taylor polynomial `Σ_a D_a Π (x - x_anchor)^a / a!` at sample (z, y, x).
struct Poly {
    terms: Vec<([u32; 3], f64)>,
    a: [usize; 3],
    dx: f64,
}

impl Poly {
    #[inline]
    fn at(&self, z: usize, y: usize, x: usize) -> f64 {
        let r = [
            (z as f64 - self.a[0] as f64) * self.dx,
            (y as f64 - self.a[1] as f64) * self.dx,
            (x as f64 - self.a[2] as f64) * self.dx,
        ];
        let mut p = 0.0;
        for (t, c) in &self.terms {
            let mut m = *c;
            for ax in 0..3 {
                m *= r[ax].powi(t[ax] as i32) / FACT[t[ax] as usize];
            }
            p += m;
        }
        p
    }
}

const FACT: [f64; 4] = [1.0, 1.0, 2.0, 6.0];

fn run<T: Real>(plan: &Plan, seed: u64, progress: &dyn Progress) -> Result<Vec<T>, FieldError> {
    let [n0, n1, n2] = plan.pad;
    let nxh = n2 / 2 + 1;
    let row_len = 2 * nxh;
    let mut buf: Vec<T> = vec![T::zero(); n0 * n1 * row_len];
    let mut rplanner = RealFftPlanner::<T>::new();
    let r2c = rplanner.plan_fft_forward(n2);
    let c2r = rplanner.plan_fft_inverse(n2);
    let mut planner = FftPlanner::<T>::new();
    let (fy, iy) = (planner.plan_fft_forward(n1), planner.plan_fft_inverse(n1));
    let (fz, iz) = (planner.plan_fft_forward(n0), planner.plan_fft_inverse(n0));

    // 1. Noise and real-to-complex FFT along x, row by row; 2. FFT along y.
    // With many z-slabs both run per slab while it is in cache.
    let noise_row = |inp: &mut [T], r: usize| {
        let mut rng = stream(seed, Purpose::GridRow, r as u64);
        for v in inp.iter_mut() {
            *v = T::of(rng.sample::<f64, _>(StandardNormal));
        }
    };
    let nblk = nxh.div_ceil(B);
    if n1 > 1 && fuse_slabs(n0) {
        buf.par_chunks_mut(n1 * row_len).enumerate().for_each_init(
            || {
                (
                    r2c.make_input_vec(),
                    r2c.make_scratch_vec(),
                    vec![Complex::<T>::zero(); B * n1],
                    vec![Complex::<T>::zero(); fy.get_inplace_scratch_len()],
                )
            },
            |(inp, rscr, tmp, yscr), (z, slab)| {
                if progress.cancelled() {
                    return;
                }
                for (y, row) in slab.chunks_mut(row_len).enumerate() {
                    noise_row(inp, z * n1 + y);
                    r2c.process_with_scratch(inp, as_complex_mut(row), rscr)
                        .expect("FFT lengths match");
                }
                y_fft_slab(as_complex_mut(slab), n1, nxh, &fy, tmp, yscr);
                progress.inc((n1 + nblk) as u64);
            },
        );
        progress.check_cancelled()?;
    } else {
        buf.par_chunks_mut(row_len).enumerate().for_each_init(
            || (r2c.make_input_vec(), r2c.make_scratch_vec()),
            |(inp, scr), (r, row)| {
                if progress.cancelled() {
                    return;
                }
                noise_row(inp, r);
                r2c.process_with_scratch(inp, as_complex_mut(row), scr)
                    .expect("FFT lengths match");
                progress.inc(1);
            },
        );
        progress.check_cancelled()?;
        if n1 > 1 {
            y_pass(
                SyncPtr(buf.as_mut_ptr() as *mut Complex<T>),
                plan.pad,
                n0,
                &fy,
                progress,
            );
            progress.check_cancelled()?;
        }
    }
    let spec = SyncPtr(buf.as_mut_ptr() as *mut Complex<T>);

    // 3. Per y-plane: FFT along z, filter (and Taylor sums), inverse FFT along z.
    let filter = Filter::new(plan);
    let taylor = plan.anchor.map(|a| Taylor::new(plan, a));
    let n_terms = plan.terms.len();
    let kz_orders = taylor.as_ref().map_or(0, |t| t.kz_orders());
    let sums: Vec<Vec<f64>> = (0..n1)
        .into_par_iter()
        .map_init(
            || {
                let scr = fz
                    .get_inplace_scratch_len()
                    .max(iz.get_inplace_scratch_len());
                (
                    vec![Complex::<T>::zero(); B * n0],
                    vec![Complex::<T>::zero(); scr],
                )
            },
            |(tmp, scr), y| {
                let mut acc = vec![0.0f64; n_terms];
                if progress.cancelled() {
                    return acc;
                }
                let base = spec.get();
                for blk in 0..nblk {
                    let x0 = blk * B;
                    let bw = B.min(nxh - x0);
                    for z in 0..n0 {
                        // SAFETY: job y owns elements [*][y][*].
                        let src = unsafe {
                            std::slice::from_raw_parts(base.add((z * n1 + y) * nxh + x0), bw)
                        };
                        for (j, v) in src.iter().enumerate() {
                            tmp[j * n0 + z] = *v;
                        }
                    }
                    if n0 > 1 {
                        fz.process_with_scratch(&mut tmp[..bw * n0], scr);
                    }
                    for j in 0..bw {
                        let ix = x0 + j;
                        let line = &mut tmp[j * n0..(j + 1) * n0];
                        for (z, v) in line.iter_mut().enumerate() {
                            *v = *v * T::of(filter.at(z, y, ix));
                        }
                        if let Some(t) = &taylor {
                            let mut sums = [Complex::new(0.0f64, 0.0); 3];
                            for (z, v) in line.iter().enumerate() {
                                let f = Complex::new(v.re.as_f64(), v.im.as_f64()) * t.phase[0][z];
                                let kz = t.k[0][z];
                                sums[0] += f;
                                if kz_orders > 1 {
                                    sums[1] += f * kz;
                                }
                                if kz_orders > 2 {
                                    sums[2] += f * (kz * kz);
                                }
                            }
                            t.add_line(&mut acc, &sums, y, ix);
                        }
                    }
                    if n0 > 1 {
                        iz.process_with_scratch(&mut tmp[..bw * n0], scr);
                    }
                    for z in 0..n0 {
                        let dst = unsafe {
                            std::slice::from_raw_parts_mut(base.add((z * n1 + y) * nxh + x0), bw)
                        };
                        for (j, v) in dst.iter_mut().enumerate() {
                            *v = tmp[j * n0 + z];
                        }
                    }
                }
                progress.inc(1);
                acc
            },
        )
        .collect();
    progress.check_cancelled()?;
    // Fixed-order reduction over planes: thread-count independent.
    let poly = plan.anchor.map(|a| {
        let mut d = vec![0.0f64; n_terms];
        for s in &sums {
            for (di, si) in d.iter_mut().zip(s) {
                *di += si;
            }
        }
        Poly {
            terms: plan.terms.iter().copied().zip(d).collect(),
            a,
            dx: plan.dx,
        }
    });

    // 4. Inverse FFT along y (only the slabs that are kept), then
    //    complex-to-real along x with cropping and the Taylor subtraction;
    //    slab-fused like steps 1-2 when there are enough slabs.
    let [o0, o1, o2] = plan.out;
    let fused = n1 > 1 && fuse_slabs(o0);
    if n1 > 1 && !fused {
        y_pass(spec, plan.pad, o0, &iy, progress);
        progress.check_cancelled()?;
    }
    let finish_row = |c: &mut [Complex<T>],
                      o: &mut [T],
                      scr: &mut [Complex<T>],
                      dst: &mut [T],
                      z: usize,
                      y: usize| {
        // The imaginary parts of the x = 0 and Nyquist bins are zero up to
        // rounding (Hermitian symmetry); realfft wants them exactly zero.
        c[0].im = T::zero();
        if n2 % 2 == 0 {
            c[nxh - 1].im = T::zero();
        }
        c2r.process_with_scratch(c, o, scr)
            .expect("FFT lengths match");
        match &poly {
            Some(p) => {
                for (x, v) in dst.iter_mut().enumerate() {
                    *v = T::of(o[x].as_f64() - p.at(z, y, x));
                }
            }
            None => dst.copy_from_slice(&o[..dst.len()]),
        }
    };
    let y_init = || {
        (
            vec![Complex::<T>::zero(); B * n1],
            vec![Complex::<T>::zero(); iy.get_inplace_scratch_len()],
        )
    };
    // Each kept row's values go to its own first o2 reals; the rows are then
    // compacted to the front of the buffer, so the output never needs a
    // second allocation, with or without padding.
    if fused {
        buf.par_chunks_mut(n1 * row_len)
            .take(o0)
            .enumerate()
            .for_each_init(
                || {
                    (
                        c2r.make_output_vec(),
                        c2r.make_scratch_vec(),
                        vec![Complex::<T>::zero(); nxh],
                        y_init(),
                    )
                },
                |(o, scr, c, (tmp, yscr)), (z, slab)| {
                    if progress.cancelled() {
                        return;
                    }
                    y_fft_slab(as_complex_mut(slab), n1, nxh, &iy, tmp, yscr);
                    for (y, row) in slab.chunks_mut(row_len).take(o1).enumerate() {
                        c.copy_from_slice(as_complex_mut(row));
                        finish_row(c, o, scr, &mut row[..o2], z, y);
                    }
                    progress.inc((nblk + o1) as u64);
                },
            );
    } else {
        buf.par_chunks_mut(row_len).enumerate().for_each_init(
            || {
                (
                    c2r.make_output_vec(),
                    c2r.make_scratch_vec(),
                    vec![Complex::<T>::zero(); nxh],
                )
            },
            |(o, scr, c), (r, row)| {
                let (z, y) = (r / n1, r % n1);
                if z >= o0 || y >= o1 || progress.cancelled() {
                    return;
                }
                c.copy_from_slice(as_complex_mut(row));
                finish_row(c, o, scr, &mut row[..o2], z, y);
                progress.inc(1);
            },
        );
    }
    progress.check_cancelled()?;
    // Front to back, each row moves to a lower or equal offset
    // ((z·o1 + y)·o2 <= (z·n1 + y)·row_len), so nothing unread is overwritten.
    for z in 0..o0 {
        for y in 0..o1 {
            let (src, dst) = ((z * n1 + y) * row_len, (z * o1 + y) * o2);
            if src != dst {
                buf.copy_within(src..src + o2, dst);
            }
        }
    }
    buf.truncate(o0 * o1 * o2);
    buf.shrink_to_fit();
    Ok(buf)
}

#[cfg(test)]
mod tests {
    use super::*;
    use fgf_core::NoProgress;

    /// Straightforward reference: full complex FFT of the same noise on the
    /// padded grid, filter, inverse, crop. Independent of the blocked,
    /// in-place pipeline.
    fn reference(p: &SynthParams) -> Vec<f64> {
        let plan = Plan::new(p).unwrap();
        let [n0, n1, n2] = plan.pad;
        let mut a: Vec<Complex<f64>> = Vec::with_capacity(n0 * n1 * n2);
        for r in 0..n0 * n1 {
            let mut rng = stream(p.seed, Purpose::GridRow, r as u64);
            for _ in 0..n2 {
                a.push(Complex::new(rng.sample::<f64, _>(StandardNormal), 0.0));
            }
        }
        let dims = [n0, n1, n2];
        let transform = |a: &mut Vec<Complex<f64>>, inverse: bool| {
            let mut planner = FftPlanner::<f64>::new();
            for ax in 0..3 {
                let n = dims[ax];
                let fft = if inverse {
                    planner.plan_fft_inverse(n)
                } else {
                    planner.plan_fft_forward(n)
                };
                let stride: usize = dims[ax + 1..].iter().product();
                let outer: usize = dims[..ax].iter().product();
                for o in 0..outer {
                    for i in 0..stride {
                        let s = o * n * stride + i;
                        let mut line: Vec<_> = (0..n).map(|j| a[s + j * stride]).collect();
                        fft.process(&mut line);
                        for j in 0..n {
                            a[s + j * stride] = line[j];
                        }
                    }
                }
            }
        };
        transform(&mut a, false);
        for iz in 0..n0 {
            for iy in 0..n1 {
                for ix in 0..n2 {
                    let k2: f64 = [(iz, n0), (iy, n1), (ix, n2)]
                        .iter()
                        .map(|&(i, n)| plan.wavenumber(i, n).powi(2))
                        .sum();
                    let nyq = plan.zero_nyquist
                        && [(iz, n0), (iy, n1), (ix, n2)]
                            .iter()
                            .any(|&(i, n)| Plan::is_nyquist(i, n));
                    let f = if k2 == 0.0 || nyq {
                        0.0
                    } else {
                        plan.amp * k2.powf(-plan.s / 2.0)
                    };
                    a[(iz * n1 + iy) * n2 + ix] *= f;
                }
            }
        }
        transform(&mut a, true);
        let [o0, o1, o2] = plan.out;
        let mut out = Vec::new();
        for z in 0..o0 {
            for y in 0..o1 {
                for x in 0..o2 {
                    out.push(a[(z * n1 + y) * n2 + x].re);
                }
            }
        }
        out
    }

    fn f64_data(f: &Field) -> Vec<f64> {
        (0..f.data.len()).map(|i| f.data.get(i)).collect()
    }

    #[test]
    fn pipeline_matches_plain_fft_reference() {
        let cases: Vec<(Vec<usize>, f64, Option<f64>)> = vec![
            (vec![9], -0.3, None),
            (vec![4, 7], -0.6, None),
            (vec![5, 6, 7], -0.4, None),
            (vec![6, 5, 40], -1.5, None),
            (vec![3, 4, 5], 0.7, Some(1.7)),
            (vec![7, 3], 1.4, Some(2.0)),
            // Enough z-slabs for the slab-fused passes (n0 >= 4 threads).
            (vec![40, 6, 10], -0.3, None),
            (vec![24, 4, 6], 0.7, Some(1.7)),
            // Cubic 3D grids use the |k|^(-s) table.
            (vec![8, 8, 8], -0.4, None),
            (vec![6, 6, 6], 1.3, Some(2.0)),
        ];
        for (shape, h, padding) in cases {
            let mut p = SynthParams::new(&shape, h);
            p.seed = 11;
            p.spacing = 0.37;
            p.sw = 2.5;
            p.padding = padding;
            p.anchor = Anchor::None;
            p.precision = Precision::F64;
            let got = f64_data(&synthesize(&p, &NoProgress).unwrap());
            let want = reference(&p);
            let scale = want.iter().map(|v| v * v).sum::<f64>().sqrt() / (want.len() as f64).sqrt();
            for (g, w) in got.iter().zip(&want) {
                assert!(
                    (g - w).abs() <= 1e-12 * scale.max(1e-300) * 10.0,
                    "{shape:?} H={h}: {g} vs {w}"
                );
            }
        }
    }

    #[test]
    fn bit_identical_for_any_thread_count() {
        // n0 = 10: slab-fused with 1 thread, not with 3 (see fuse_slabs).
        for (shape, h) in [
            (vec![12usize, 10, 33], -0.2),
            (vec![17, 20], 1.3),
            (vec![8, 9, 10], 2.5),
            (vec![10, 9, 8], -0.7),
        ] {
            let mut p = SynthParams::new(&shape, h);
            p.seed = 5;
            p.anchor = Anchor::Center;
            let runs: Vec<FieldData> = [1, 2, 3]
                .iter()
                .map(|&t| {
                    let pool = rayon::ThreadPoolBuilder::new()
                        .num_threads(t)
                        .build()
                        .unwrap();
                    pool.install(|| synthesize(&p, &NoProgress).unwrap().data)
                })
                .collect();
            assert_eq!(runs[0], runs[1], "{shape:?}");
            assert_eq!(runs[0], runs[2], "{shape:?}");
        }
    }

    #[test]
    fn f32_and_f64_agree_to_f32_rounding() {
        let mut p = SynthParams::new(&[16, 12, 10], -0.3);
        p.seed = 2;
        let a = f64_data(&synthesize(&p, &NoProgress).unwrap());
        p.precision = Precision::F64;
        let b = f64_data(&synthesize(&p, &NoProgress).unwrap());
        let rms = (b.iter().map(|v| v * v).sum::<f64>() / b.len() as f64).sqrt();
        let err = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        // f32 round-off of a few FFT passes: ~1e-7 relative per pass.
        assert!(err < 1e-5 * rms, "err {err} rms {rms}");
    }

    #[test]
    fn anchored_field_vanishes_at_anchor_and_differs_by_a_polynomial() {
        for (shape, h, anchor) in [
            (vec![40usize], 0.6, Anchor::Corner),
            (vec![24, 20], 1.5, Anchor::Center),
            (vec![10, 12, 9], 2.4, Anchor::Index(vec![3, 4, 5])),
        ] {
            let mut p = SynthParams::new(&shape, h);
            p.precision = Precision::F64;
            p.seed = 9;
            p.anchor = anchor;
            let f = synthesize(&p, &NoProgress).unwrap();
            p.anchor = Anchor::None;
            let g = synthesize(&p, &NoProgress).unwrap();
            let a = f.anchor.clone().unwrap();
            let mut idx = 0;
            for (ax, &i) in a.iter().enumerate() {
                idx = idx * shape[ax] + i;
            }
            let rms =
                (f64_data(&g).iter().map(|v| v * v).sum::<f64>() / g.data.len() as f64).sqrt();
            assert!(
                f.data.get(idx).abs() < 1e-10 * rms,
                "{shape:?}: value at anchor {}",
                f.data.get(idx)
            );
            // g - f is the Taylor polynomial of degree k-1: its k-th finite
            // differences along the last axis vanish.
            let k = h.ceil() as usize;
            let diff: Vec<f64> = (0..f.data.len())
                .map(|i| g.data.get(i) - f.data.get(i))
                .collect();
            let nx = *shape.last().unwrap();
            for row in diff.chunks(nx) {
                let mut d = row.to_vec();
                for _ in 0..k {
                    d = d.windows(2).map(|w| w[1] - w[0]).collect();
                }
                assert!(d.iter().all(|v| v.abs() < 1e-9 * rms), "{shape:?}: {d:?}");
            }
        }
    }

    #[test]
    fn invalid_parameters_are_named() {
        let bad = |f: &dyn Fn(&mut SynthParams), name: &str| {
            let mut p = SynthParams::new(&[8, 8], -0.3);
            f(&mut p);
            let e = synthesize(&p, &NoProgress).unwrap_err().to_string();
            assert!(e.contains(name), "{e}");
        };
        bad(&|p| p.hurst = -1.2, "hurst");
        bad(&|p| p.hurst = 1.0, "hurst");
        bad(&|p| p.hurst = 3.0, "hurst");
        bad(&|p| p.hurst = f64::NAN, "hurst");
        bad(&|p| p.sw = 0.0, "sw");
        bad(&|p| p.spacing = -1.0, "spacing");
        bad(&|p| p.shape = vec![], "shape");
        bad(&|p| p.shape = vec![2, 2, 2, 2], "shape");
        bad(&|p| p.shape = vec![0, 4], "shape");
        bad(&|p| p.padding = Some(0.5), "padding");
        bad(
            &|p| {
                p.hurst = 0.5;
                p.anchor = Anchor::Index(vec![8, 0])
            },
            "anchor",
        );
        // White noise at exactly H = -d/2 is valid.
        let p = SynthParams::new(&[8, 8], -1.0);
        assert!(synthesize(&p, &NoProgress).is_ok());
    }

    #[test]
    fn impossible_allocation_is_refused_before_allocating() {
        let p = SynthParams::new(&[100_000, 100_000, 100_000], -0.3);
        match synthesize(&p, &NoProgress) {
            Err(FieldError::OutOfMemory { needed, .. }) => assert!(needed > 1 << 40),
            other => panic!("expected OutOfMemory, got {other:?}"),
        }
        let msg = synthesize(&p, &NoProgress).unwrap_err().to_string();
        assert!(msg.contains("MemAvailable") && msg.contains("GiB"), "{msg}");
    }

    /// A cancelled job returns the shared `Cancelled` error, and an invalid
    /// parameter keeps its structured `ParamError`.
    #[test]
    fn cancellation_and_parameter_errors_keep_their_types() {
        struct Stop;
        impl Progress for Stop {
            fn inc(&self, _n: u64) {}
            fn cancelled(&self) -> bool {
                true
            }
        }
        let p = SynthParams::new(&[16, 16], -0.3);
        match synthesize(&p, &Stop) {
            Err(e @ FieldError::Cancelled(Cancelled)) => assert_eq!(e.to_string(), "interrupted"),
            other => panic!("expected Cancelled, got {other:?}"),
        }
        let mut p = SynthParams::new(&[16, 16], -0.3);
        p.sw = -1.0;
        match synthesize(&p, &NoProgress) {
            Err(FieldError::Param(e)) => assert_eq!(e.name, "sw"),
            other => panic!("expected Param, got {other:?}"),
        }
    }

    #[test]
    fn next_smooth_sizes() {
        assert_eq!(next_smooth(1), 1);
        assert_eq!(next_smooth(11), 12);
        assert_eq!(next_smooth(97), 98);
        assert_eq!(next_smooth(512), 512);
    }
}
