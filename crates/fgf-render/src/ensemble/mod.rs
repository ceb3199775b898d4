//! Ground truth from explicit realizations: the ensemble average of
//! classical renders of random 3D media, to compare with the `fgf` model's
//! render (`docs/theory.md` §1.6–§1.8, §3.7, §6.6).
//!
//! # What it does
//!
//! Every `fgf` medium of the scene is replaced, in each realization, by an
//! explicit grid of extinction whose macro density `ρ` (1 without one,
//! sampled at the voxel centres) multiplies the whole field, as the model
//! scales the fluctuations with `ρ` (`t_eq = τ_m/σ_m`, §4.5):
//!
//! * **gamma marginals** ([`Marginal::Gamma`], the default for pink noise):
//!   `σ_t(x) = ρ(x) σ_m X(x)`, `X = G_α⁻¹(Φ(Z))` a Gaussian copula with
//!   gamma marginals of mean 1, non-negative by construction. The Hurst
//!   parameter of the Gaussian field `Z` and the shape `α` are calibrated
//!   ([`fgf_field::copula::calibrate_gamma`]) so that the grid's exact
//!   line-average variance along x follows the model's `var[σ̄_t]` from one
//!   voxel to the grid's side; the residual is reported per length.
//! * **Gaussian** ([`Marginal::Gaussian`], the default for k-fBm):
//!   `σ_t = ρ · max(0, σ_m + σ_u)`, `σ_u` the 3D field with
//!   `S_w3 = S_w · 2π(2H+1)` (§1.7), k-fBm anchored at the grid's corner.
//!   Negative values are clamped and counted.
//!
//! The field is synthesized on a periodic domain `padding` times the grid
//! per axis (default 4) and cropped, so that scales up to the grid's size
//! are not wrapped. The grid covers the bounding box of the shapes that
//! have the medium as `interior`, with `resolution` cubic voxels along its
//! longest side, looked up with `nearest` filtering. `σ_m` is per RGB
//! channel; with gamma marginals every channel shares `X` (the calibration
//! uses the channel mean of `σ_m`).
//!
//! Each realization is rendered classically (delta and ratio tracking) and
//! the images are averaged. The per-pixel standard error is that of the
//! mean over realizations (it includes each render's Monte Carlo noise).
//!
//! # Grid variance
//!
//! [`MediumReport`] gives, per medium, the model's `var[σ̄_t]` and the grid's
//! exact line-average variance (discrete spectral sum, through the copula's
//! Mehler transfer for gamma marginals; `docs/theory.md` §1.8) at
//! log-spaced segment lengths, and a Monte Carlo check on the realizations.
//!
//! # Determinism and distribution
//!
//! [`prepare`] plans and calibrates once; [`render_realization`] renders
//! realization `r` from `(plan, r)` only (field and render seeds derived from
//! `(seed, r)` and the medium index); an [`Accumulator`] merges realizations
//! in index order. The result is identical for any number of threads.
//!
//! ```no_run
//! use fgf_render::ensemble::{ensemble, EnsembleOptions};
//! let scene = fgf_scene::load_file("scenes/fgf-cube-pink.xml".as_ref(), &[]).unwrap();
//! let opts = EnsembleOptions { realizations: 16, ..Default::default() };
//! let out = ensemble(&scene, &opts, &fgf_core::NoProgress).unwrap();
//! println!("{:?}", out.media[0]);
//! ```

mod plan;
mod realize;

use crate::error::RenderError;
use fgf_core::Progress;
use fgf_scene::SceneDesc;
use plan::{Plan, Voxels};
pub use realize::{render_realization, MediumStats, Realization, RealizationError};

/// Default voxels along the longest side of a medium's box.
pub const DEFAULT_RESOLUTION: usize = 64;
/// Default size of the periodic synthesis domain, per axis, in grid sides.
pub const DEFAULT_PADDING: f64 = 4.0;

/// The one-point law of the realized extinction.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Marginal {
    /// Gamma for pink noise, Gaussian for k-fBm.
    Auto,
    /// Calibrated Gaussian copula with gamma marginals.
    Gamma,
    /// Clamped Gaussian.
    Gaussian,
}

impl Marginal {
    /// `"auto"`, `"gamma"` or `"gaussian"`.
    pub fn parse(s: &str) -> Option<Marginal> {
        match s {
            "auto" => Some(Marginal::Auto),
            "gamma" => Some(Marginal::Gamma),
            "gaussian" => Some(Marginal::Gaussian),
            _ => None,
        }
    }
}

/// Options of [`ensemble`].
#[derive(Debug, Clone)]
pub struct EnsembleOptions {
    /// Number of realizations `N ≥ 1` (a standard error needs `N ≥ 2`).
    pub realizations: u32,
    /// Voxels along the longest side of each medium's box (≥ 2).
    pub resolution: usize,
    /// Samples per pixel of each realization's render (default: the scene's).
    pub spp: Option<u32>,
    /// Master seed of the fields and the renders.
    pub seed: u64,
    /// Periodic synthesis domain per axis, in grid sides (≥ 1).
    pub padding: f64,
    pub marginal: Marginal,
    /// Keep every realization's image in [`EnsembleOutput::realization_images`]
    /// (for standard errors of region means, which the per-pixel ones do
    /// not give: one realization moves many pixels together).
    pub keep_realizations: bool,
}

impl Default for EnsembleOptions {
    fn default() -> Self {
        EnsembleOptions {
            realizations: 16,
            resolution: DEFAULT_RESOLUTION,
            spp: None,
            seed: 0,
            padding: DEFAULT_PADDING,
            marginal: Marginal::Auto,
            keep_realizations: false,
        }
    }
}

/// What was realised for one `fgf` medium.
#[derive(Debug, Clone)]
pub struct MediumReport {
    /// Index into the scene's media.
    pub medium: usize,
    /// Grid resolution `[nx, ny, nz]`.
    pub shape: [usize; 3],
    /// Periodic synthesis domain `[nz, ny, nx]`.
    pub padded_shape: Vec<usize>,
    /// Voxel size `dx` (scene units).
    pub spacing: f64,
    /// Grid box `[xmin, ymin, zmin, xmax, ymax, zmax]`.
    pub bbox: [f64; 6],
    /// `"gamma"` or `"gaussian"`.
    pub marginal: &'static str,
    /// `S_w` given to the 3D synthesis (`S_w3` for Gaussian, 1 for gamma).
    pub sw_3d: f64,
    /// Hurst parameter of the synthesized Gaussian field.
    pub hurst_field: f64,
    /// Gamma shape of the voxel marginal (NaN for Gaussian).
    pub alpha_voxel: f64,
    /// Fraction of grid values (all channels, all realizations) clamped to 0
    /// (always 0 for gamma marginals).
    pub clamped_fraction: f64,
    /// Mean `σ_t` over voxels and realizations (channel mean), and the
    /// model's `mean(σ_m ρ)` over the voxels.
    pub mean_sigma_t: f64,
    pub model_mean_sigma_t: f64,
    /// Segment lengths `t = m dx` of the exact comparison (scene units).
    pub lengths: Vec<f64>,
    /// The model's `var[σ̄_t]` at those lengths (`docs/theory.md` §2).
    pub model_variances: Vec<f64>,
    /// The grid's exact line-average variance along x at those lengths.
    pub grid_variances: Vec<f64>,
    /// Segment length `ℓ` of the Monte Carlo check (a whole number of voxels
    /// near one mean free path `1/mean(σ_m)`).
    pub variance_length: f64,
    /// `var[σ̄]` of the fluctuation over `ℓ` along x, measured on the
    /// realizations.
    pub realized_variance: f64,
    /// The model's continuum `var[σ̄_t](ℓ)`.
    pub continuum_variance: f64,
}

/// The result of [`ensemble`]: images are row-major from the top-left, RGB
/// interleaved.
#[derive(Debug, Clone)]
pub struct EnsembleOutput {
    pub width: usize,
    pub height: usize,
    /// Mean over the realizations done.
    pub mean: Vec<f32>,
    /// Standard error of that mean (NaN with fewer than 2 realizations).
    pub stderr: Vec<f32>,
    pub realizations_done: u32,
    pub realizations_requested: u32,
    pub spp: u32,
    pub media: Vec<MediumReport>,
    /// Each realization's image, in index order (empty unless
    /// [`EnsembleOptions::keep_realizations`]).
    pub realization_images: Vec<Vec<f32>>,
}

/// Errors of [`ensemble`]: the renderer's, and cancellation with the
/// average of the realizations finished.
#[derive(Debug, thiserror::Error)]
pub enum EnsembleError {
    #[error(transparent)]
    Render(#[from] RenderError),
    /// [`Progress::cancelled`] asked the ensemble to stop: `partial` holds
    /// the realizations finished (possibly none; a realization being
    /// rendered is dropped, it would not be one of the `N`).
    #[error("interrupted after {} of {} realizations", .partial.realizations_done, .partial.realizations_requested)]
    Cancelled { partial: Box<EnsembleOutput> },
}

/// Forwards cancellation but not the units of the field synthesis: the
/// progress of an ensemble is counted in rendered samples only.
struct CancelOnly<'a>(&'a dyn Progress);

impl Progress for CancelOnly<'_> {
    fn inc(&self, _n: u64) {}
    fn cancelled(&self) -> bool {
        self.0.cancelled()
    }
}

/// Total number of samples [`ensemble`] renders (for progress bars).
pub fn total_samples(scene: &SceneDesc, opts: &EnsembleOptions) -> u64 {
    let spp = opts.spp.unwrap_or(scene.sensor.spp) as u64;
    scene.sensor.width as u64 * scene.sensor.height as u64 * spp * opts.realizations as u64
}

/// A validated, planned and calibrated ensemble, ready to render
/// realizations ([`render_realization`]).
pub struct Prepared {
    scene: SceneDesc,
    opts: EnsembleOptions,
    plans: Vec<Plan>,
}

/// Validate the scene and options, plan every `fgf` medium's grid and
/// calibrate its marginal (deterministic; a few seconds per medium).
pub fn prepare(scene: &SceneDesc, opts: &EnsembleOptions) -> Result<Prepared, RenderError> {
    scene.validate()?;
    if opts.realizations == 0 {
        return Err(RenderError::InvalidOption(
            "realizations = 0; need at least 1 (2 for a standard error)".into(),
        ));
    }
    if opts.resolution < 2 {
        return Err(RenderError::InvalidOption(format!(
            "resolution = {}; need at least 2 voxels along the longest side",
            opts.resolution
        )));
    }
    if !(opts.padding.is_finite() && (1.0..=16.0).contains(&opts.padding)) {
        return Err(RenderError::InvalidOption(format!(
            "padding = {}; the periodic synthesis domain must be 1 to 16 grid sides per axis",
            opts.padding
        )));
    }
    if opts.spp == Some(0) {
        return Err(RenderError::InvalidOption(
            "spp = 0; need at least 1 sample per pixel".into(),
        ));
    }
    let plans = plan::plan(scene, opts)?;
    Ok(Prepared {
        scene: scene.clone(),
        opts: opts.clone(),
        plans,
    })
}

/// Merges realizations, in realization index order, into the mean image,
/// its standard error and the medium report.
pub struct Accumulator {
    sum: Vec<f64>,
    sum_sq: Vec<f64>,
    media: Vec<MediumStats>,
    done: u32,
    spp: u32,
    keep: bool,
    images: Vec<Vec<f32>>,
}

impl Accumulator {
    pub fn new(prep: &Prepared) -> Accumulator {
        let n = prep.scene.sensor.width as usize * prep.scene.sensor.height as usize * 3;
        Accumulator {
            sum: vec![0.0; n],
            sum_sq: vec![0.0; n],
            media: vec![MediumStats::default(); prep.plans.len()],
            done: 0,
            spp: prep.opts.spp.unwrap_or(prep.scene.sensor.spp),
            keep: prep.opts.keep_realizations,
            images: Vec::new(),
        }
    }

    /// Add the next realization (call in index order for bit-identical
    /// results).
    pub fn add(&mut self, r: &Realization) {
        for (j, &v) in r.image.iter().enumerate() {
            let v = v as f64;
            self.sum[j] += v;
            self.sum_sq[j] += v * v;
        }
        for (acc, m) in self.media.iter_mut().zip(&r.media) {
            acc.clamped += m.clamped;
            acc.values += m.values;
            acc.segment_second_moment += m.segment_second_moment;
            acc.sigma_sum += m.sigma_sum;
            acc.voxels += m.voxels;
        }
        self.spp = r.spp;
        self.done += 1;
        if self.keep {
            self.images.push(r.image.clone());
        }
    }

    pub fn finish(&self, prep: &Prepared) -> EnsembleOutput {
        let done = self.done;
        let nf = done as f64;
        let mean = self
            .sum
            .iter()
            .map(|&s| if done > 0 { (s / nf) as f32 } else { f32::NAN })
            .collect();
        let stderr = self
            .sum
            .iter()
            .zip(&self.sum_sq)
            .map(|(&s, &s2)| {
                if done < 2 {
                    return f32::NAN;
                }
                let m = s / nf;
                // Unbiased sample variance across realizations, over n for the mean.
                (((s2 - nf * m * m) / (nf - 1.0)).max(0.0) / nf).sqrt() as f32
            })
            .collect();
        let media = prep
            .plans
            .iter()
            .zip(&self.media)
            .map(|(p, st)| report(p, st, done))
            .collect();
        EnsembleOutput {
            width: prep.scene.sensor.width as usize,
            height: prep.scene.sensor.height as usize,
            mean,
            stderr,
            realizations_done: done,
            realizations_requested: prep.opts.realizations,
            spp: self.spp,
            media,
            realization_images: self.images.clone(),
        }
    }
}

fn report(p: &Plan, st: &MediumStats, done: u32) -> MediumReport {
    let nf = done as f64;
    let ratio = |a: f64, b: f64| if b > 0.0 { a / b } else { f64::NAN };
    let sigma_mean = p.sigma_t.iter().sum::<f32>() as f64 / 3.0;
    let (marginal, alpha_voxel) = match &p.voxels {
        Voxels::Gaussian => ("gaussian", f64::NAN),
        Voxels::Gamma { calibration, .. } => ("gamma", calibration.alpha_voxel),
    };
    let dx = p.params.spacing;
    MediumReport {
        medium: p.medium,
        shape: p.shape,
        padded_shape: p.padded.clone(),
        spacing: dx,
        bbox: [
            p.lo.x,
            p.lo.y,
            p.lo.z,
            p.lo.x + p.extent.x,
            p.lo.y + p.extent.y,
            p.lo.z + p.extent.z,
        ],
        marginal,
        sw_3d: p.params.sw,
        hurst_field: p.params.hurst,
        alpha_voxel,
        clamped_fraction: ratio(st.clamped as f64, st.values as f64),
        mean_sigma_t: ratio(st.sigma_sum, st.voxels as f64),
        model_mean_sigma_t: sigma_mean * p.mean_rho,
        lengths: p.lengths.iter().map(|&m| m as f64 * dx).collect(),
        model_variances: p.model_variances.clone(),
        grid_variances: p.grid_variances.clone(),
        variance_length: p.segment as f64 * dx,
        realized_variance: ratio(st.segment_second_moment, nf),
        continuum_variance: p.continuum_variance,
    }
}

/// Render the ensemble average; see the module docs. Progress is counted in
/// rendered samples ([`total_samples`]); on cancellation the realizations
/// finished so far come with [`EnsembleError::Cancelled`].
pub fn ensemble(
    scene: &SceneDesc,
    opts: &EnsembleOptions,
    progress: &dyn Progress,
) -> Result<EnsembleOutput, EnsembleError> {
    ensemble_from(scene, opts, 0, progress)
}

/// [`ensemble`] over the realizations `first..first + opts.realizations`:
/// the same per-realization renders and the same in-order merge (a cluster
/// task or a resumed run renders a later range).
pub fn ensemble_from(
    scene: &SceneDesc,
    opts: &EnsembleOptions,
    first: u32,
    progress: &dyn Progress,
) -> Result<EnsembleOutput, EnsembleError> {
    let prep = prepare(scene, opts)?;
    let mut acc = Accumulator::new(&prep);
    let mut interrupted = false;
    for r in first..first.saturating_add(opts.realizations) {
        if progress.cancelled() {
            interrupted = true;
            break;
        }
        match render_realization(&prep, r, progress) {
            Ok(real) => acc.add(&real),
            Err(RealizationError::Cancelled) => {
                interrupted = true;
                break;
            }
            Err(RealizationError::Render(e)) => return Err(e.into()),
        }
    }
    let out = acc.finish(&prep);
    if interrupted {
        Err(EnsembleError::Cancelled {
            partial: Box::new(out),
        })
    } else {
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use glam::{DVec3, Mat4, Vec3A};

    #[test]
    fn unit_cube_maps_onto_the_grid_box() {
        let (lo, ext) = (DVec3::new(-0.5, 0.25, -0.5), DVec3::new(1.0, 1.0, 2.0));
        let m = Mat4::from_translation(lo.as_vec3()) * Mat4::from_scale(ext.as_vec3());
        assert!((m.transform_point3a(Vec3A::ZERO) - lo.as_vec3a()).length() < 1e-6);
        assert!((m.transform_point3a(Vec3A::ONE) - (lo + ext).as_vec3a()).length() < 1e-6);
    }
}
