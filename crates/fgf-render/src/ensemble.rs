//! Ground truth from explicit realizations: the ensemble average
//! of classical renders of random 3D media, to compare with the `fgf`
//! model's render (`docs/theory.md` §1, §3 "against explicit Gaussian
//! realizations").
//!
//! # What it does
//!
//! Every `fgf` medium of the scene is replaced, in each realization, by an
//! explicit grid `σ_t(x) = max(0, σ_m ρ(x) + σ_u(x))`:
//!
//! * `σ_u` is a 3D fractional Gaussian field synthesised by
//!   [`fgf_field::synthesize`] with the medium's `hurst` and
//!   `S_w3 = S_w · 2π(2H+1)` ([`fgf_field::sw_3d_for_ray_statistics`]), so
//!   that its restriction to any line has the 1D statistics of the model.
//!   k-fBm fields are anchored at the grid's corner (the medium's
//!   `length` defaults to the box diagonal, its extent from that anchor).
//! * `ρ` is the medium's macro density (1 without one), sampled at the voxel
//!   centres; `σ_m` is per RGB channel (the same `σ_u` in every channel).
//! * The grid covers the bounding box of the shapes that have the medium as
//!   `interior`, with `resolution` cubic voxels along its longest side
//!   (`dx = longest / resolution`, the other sides rounded up); it is looked
//!   up with `nearest` filtering, since each synthesized sample is the
//!   average of the field over its cell.
//! * Negative extinction is clamped to 0; the fraction of clamped values is
//!   reported. Compare with the model only where it is small (`docs/theory.md`
//!   §3).
//!
//! Each realization is rendered classically (a `heterogeneous` medium:
//! delta tracking and ratio tracking), and the images are averaged. The
//! per-pixel standard error is that of the mean over realizations (it
//! includes each render's Monte Carlo noise, as it must).
//!
//! # Caveat: grid variance
//!
//! A 3D grid misses the field's variance above its Nyquist frequency, and
//! for pink noise the missing fraction of the line-average variance decays
//! slowly with resolution (`docs/theory.md` §1). The report therefore gives, per
//! medium, the line-average variance along x over one mean free path
//! `1/σ_m` measured on the realizations, next to the continuum value of the
//! model; their ratio is how much of the model's fluctuation the grids
//! carry.
//!
//! # Determinism
//!
//! Realization `r` uses field seed and render seed derived from
//! `(seed, r)` (and the medium index) only; realizations are rendered one
//! after the other and accumulated in order, so the result is identical for
//! any number of threads.
//!
//! ```no_run
//! use fgf_render::ensemble::{ensemble, EnsembleOptions};
//! let scene = fgf_scene::load_file("scenes/fgf-cube-pink.xml".as_ref(), &[]).unwrap();
//! let opts = EnsembleOptions { realizations: 16, ..Default::default() };
//! let out = ensemble(&scene, &opts, &fgf_core::NoProgress).unwrap();
//! println!("{:?}", out.media[0]);
//! ```

use crate::error::RenderError;
use crate::medium::grid::GridTex;
use crate::render::{render, RenderOptions};
use fgf_core::rng::{mix64, stream_key};
use fgf_core::transmittance::Fgf;
use fgf_core::Progress;
use fgf_field::{sw_3d_for_ray_statistics, synthesize, Anchor, FieldError, Precision, SynthParams};
use fgf_scene::{
    GridFilter, GridVolumeDesc, MediumDesc, Rgb, SceneDesc, TransmittanceDesc, VolumeDesc,
};
use glam::{DVec3, Mat4};
use std::sync::Arc;

/// Default voxels along the longest side of a medium's box: 64³ fields
/// synthesize in well under a second and keep each realization's render
/// cost close to a homogeneous one.
pub const DEFAULT_RESOLUTION: usize = 64;

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
}

impl Default for EnsembleOptions {
    fn default() -> Self {
        EnsembleOptions {
            realizations: 16,
            resolution: DEFAULT_RESOLUTION,
            spp: None,
            seed: 0,
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
    /// Voxel size `dx` (scene units).
    pub spacing: f64,
    /// Grid box `[xmin, ymin, zmin, xmax, ymax, zmax]`.
    pub bbox: [f64; 6],
    /// `S_w3` given to the 3D synthesis.
    pub sw_3d: f64,
    /// Fraction of grid values (all channels, all realizations) where
    /// `σ_m ρ + σ_u < 0` was clamped to 0.
    pub clamped_fraction: f64,
    /// Segment length `ℓ` of the variance comparison (a whole number of
    /// voxels near one mean free path `1/mean(σ_m)`).
    pub variance_length: f64,
    /// `var[σ̄_u]` over segments of length `ℓ` along x, measured on the
    /// realizations (mean of the squared segment averages).
    pub realized_variance: f64,
    /// The model's continuum `var[σ̄_t](ℓ)` (`docs/theory.md` §2).
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

/// One `fgf` medium's synthesis plan.
struct Plan {
    medium: usize,
    sigma_t: Rgb,
    grey: bool,
    params: SynthParams,
    shape: [usize; 3],
    lo: DVec3,
    extent: DVec3,
    /// `ρ` at each voxel centre (x fastest), or `None` for `ρ = 1`.
    rho: Option<Vec<f32>>,
    segment: usize,
    continuum_variance: f64,
}

/// Total number of samples [`ensemble`] renders (for progress bars).
pub fn total_samples(scene: &SceneDesc, opts: &EnsembleOptions) -> u64 {
    let spp = opts.spp.unwrap_or(scene.sensor.spp) as u64;
    scene.sensor.width as u64 * scene.sensor.height as u64 * spp * opts.realizations as u64
}

fn plan(scene: &SceneDesc, opts: &EnsembleOptions) -> Result<Vec<Plan>, RenderError> {
    let mut plans = Vec::new();
    for (i, m) in scene.media.iter().enumerate() {
        let MediumDesc::NonExponential {
            sigma_t,
            model,
            density,
            ..
        } = m
        else {
            continue;
        };
        let TransmittanceDesc::Fgf { hurst, sw, length } = *model else {
            return Err(RenderError::Unsupported(format!(
                "medium {i}: a 'nonexponential' medium has no underlying random field to realise; the ensemble replaces 'fgf' media only"
            )));
        };
        let sw3 = sw_3d_for_ray_statistics(hurst, sw).map_err(|source| {
            RenderError::UnsupportedParam {
                medium: i,
                source,
                why: "white noise, hurst = -0.5, has no 3D field whose line averages are finite: render it as 'homogeneous' with sigma_eff instead",
            }
        })?;
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for s in scene.shapes.iter().filter(|s| s.interior == Some(i)) {
            let (a, b) = s.world_bbox();
            lo = lo.min(a);
            hi = hi.max(b);
        }
        let ext = hi - lo;
        if !(ext.is_finite() && ext.max_element() > 0.0) {
            return Err(RenderError::InvalidScene(format!(
                "medium {i}: the ensemble needs the box of the shapes that have this medium as interior, and there are none (a medium only used as exterior or by the sensor is unbounded)"
            )));
        }
        let dx = ext.max_element() / opts.resolution as f64;
        // Round each side up to whole voxels (at least one).
        let n = [0, 1, 2].map(|k| ((ext[k] / dx - 1e-9).ceil() as usize).max(1));
        let extent = DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64) * dx;
        let mut params = SynthParams::new(&[n[2], n[1], n[0]], hurst);
        params.spacing = dx;
        params.sw = sw3;
        params.anchor = Anchor::Corner;
        params.precision = Precision::F32;
        let rho = match density {
            None => None,
            Some(g) => {
                let tex = GridTex::new(g, &format!("medium {i} density"))?;
                let mut v = Vec::with_capacity(n[0] * n[1] * n[2]);
                for z in 0..n[2] {
                    for y in 0..n[1] {
                        for x in 0..n[0] {
                            let p = lo
                                + DVec3::new(x as f64 + 0.5, y as f64 + 0.5, z as f64 + 0.5) * dx;
                            v.push(tex.eval_world(p.as_vec3()).x);
                        }
                    }
                }
                Some(v)
            }
        };
        // Variance comparison over about one mean free path of the mean
        // extinction, in whole voxels within the grid.
        let sigma_mean =
            (sigma_t.iter().map(|&s| s as f64).sum::<f64>() / 3.0).max(f64::MIN_POSITIVE);
        let segment = ((1.0 / sigma_mean / dx).round() as usize).clamp(1, n[0]);
        let model = Fgf::new(sigma_mean, hurst, sw, length)
            .map_err(|source| RenderError::Param { medium: i, source })?;
        plans.push(Plan {
            medium: i,
            sigma_t: *sigma_t,
            grey: sigma_t[0] == sigma_t[1] && sigma_t[1] == sigma_t[2],
            params,
            shape: n,
            lo,
            extent,
            rho,
            segment,
            continuum_variance: model.variance(segment as f64 * dx),
        });
    }
    if plans.is_empty() {
        return Err(RenderError::InvalidScene(
            "the scene has no 'fgf' medium: there is nothing to realise".into(),
        ));
    }
    Ok(plans)
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

/// [`ensemble`] of the realizations `first..first + opts.realizations`
/// (realization `r` is a fixed function of `(seed, r)`), so that a
/// distributed ensemble can render each realization apart and merge them
/// in index order.
pub fn ensemble_from(
    scene: &SceneDesc,
    opts: &EnsembleOptions,
    first: u32,
    progress: &dyn Progress,
) -> Result<EnsembleOutput, EnsembleError> {
    scene.validate().map_err(RenderError::from)?;
    if opts.realizations == 0 {
        return Err(RenderError::InvalidOption(
            "realizations = 0; need at least 1 (2 for a standard error)".into(),
        )
        .into());
    }
    if opts.resolution < 2 {
        return Err(RenderError::InvalidOption(format!(
            "resolution = {}; need at least 2 voxels along the longest side",
            opts.resolution
        ))
        .into());
    }
    if opts.spp == Some(0) {
        return Err(
            RenderError::InvalidOption("spp = 0; need at least 1 sample per pixel".into()).into(),
        );
    }
    let plans = plan(scene, opts)?;
    let (w, h) = (scene.sensor.width as usize, scene.sensor.height as usize);
    let mut sum = vec![0f64; w * h * 3];
    let mut sum_sq = vec![0f64; w * h * 3];
    let mut clamped = vec![0u64; plans.len()];
    let mut values = vec![0u64; plans.len()];
    let mut var_sum = vec![0f64; plans.len()];
    let mut done = 0u32;
    let mut interrupted = false;
    let mut spp_done = opts.spp.unwrap_or(scene.sensor.spp);
    let cancel_only = CancelOnly(progress);
    for r in first..first.saturating_add(opts.realizations) {
        if progress.cancelled() {
            interrupted = true;
            break;
        }
        let base = stream_key(mix64(opts.seed), r as u64);
        let mut sc = scene.clone();
        let mut cancelled = false;
        for (k, p) in plans.iter().enumerate() {
            let mut params = p.params.clone();
            params.seed = stream_key(base, 0x100 + p.medium as u64);
            let field = match synthesize(&params, &cancel_only) {
                Ok(f) => f,
                Err(FieldError::Cancelled(_)) => {
                    cancelled = true;
                    break;
                }
                Err(source) => {
                    return Err(RenderError::Field {
                        medium: p.medium,
                        source,
                    }
                    .into())
                }
            };
            let u = field.data.to_f32();
            let lv = fgf_field::estimators::line_average_second_moment(
                &u,
                &params.shape,
                2,
                &[p.segment],
            )
            .map_err(|e| RenderError::Field {
                medium: p.medium,
                source: e.into(),
            })?;
            var_sum[k] += lv[0];
            let channels = if p.grey { 1 } else { 3 };
            let mut data = Vec::with_capacity(u.len() * channels);
            for (j, &uj) in u.iter().enumerate() {
                let rho = p.rho.as_ref().map_or(1.0, |v| v[j]);
                for c in 0..channels {
                    let v = p.sigma_t[c] * rho + uj;
                    if v < 0.0 {
                        clamped[k] += 1;
                    }
                    data.push(v.max(0.0));
                }
            }
            values[k] += data.len() as u64;
            let hi = p.lo + p.extent;
            let grid = fgf_io::vol::VolGrid {
                shape: p.shape,
                channels,
                bbox: [
                    p.lo.x as f32,
                    p.lo.y as f32,
                    p.lo.z as f32,
                    hi.x as f32,
                    hi.y as f32,
                    hi.z as f32,
                ],
                data,
            };
            let MediumDesc::NonExponential { albedo, phase, .. } = &scene.media[p.medium] else {
                unreachable!("planned media are fgf")
            };
            // The unit cube of volume space onto the grid's box.
            let to_world =
                Mat4::from_translation(p.lo.as_vec3()) * Mat4::from_scale(p.extent.as_vec3());
            sc.media[p.medium] = MediumDesc::Heterogeneous {
                sigma_t: VolumeDesc::Grid(GridVolumeDesc {
                    grid: Arc::new(grid),
                    to_world,
                    use_grid_bbox: false,
                    filter: GridFilter::Nearest,
                    wrap_clamp: true,
                }),
                albedo: VolumeDesc::Constant(*albedo),
                scale: 1.0,
                phase: *phase,
            };
        }
        if cancelled {
            interrupted = true;
            break;
        }
        let ropts = RenderOptions {
            spp: opts.spp,
            seed: Some(stream_key(base, 0x5EED)),
            variance: false,
            spp_per_pass: None,
        };
        let out = match render(&sc, &ropts, progress) {
            Ok(out) => out,
            // A partial realization would bias nothing but is not one of the
            // N: drop it.
            Err(RenderError::Cancelled { .. }) => {
                interrupted = true;
                break;
            }
            Err(e) => return Err(e.into()),
        };
        spp_done = out.spp_done;
        for (j, &v) in out.image.iter().enumerate() {
            let v = v as f64;
            sum[j] += v;
            sum_sq[j] += v * v;
        }
        done += 1;
    }
    let nf = done as f64;
    let mean: Vec<f32> = sum
        .iter()
        .map(|&s| if done > 0 { (s / nf) as f32 } else { f32::NAN })
        .collect();
    let stderr: Vec<f32> = sum
        .iter()
        .zip(&sum_sq)
        .map(|(&s, &s2)| {
            if done < 2 {
                return f32::NAN;
            }
            let m = s / nf;
            // Unbiased sample variance across realizations, over n for the mean.
            (((s2 - nf * m * m) / (nf - 1.0)).max(0.0) / nf).sqrt() as f32
        })
        .collect();
    let media = plans
        .iter()
        .enumerate()
        .map(|(k, p)| MediumReport {
            medium: p.medium,
            shape: p.shape,
            spacing: p.params.spacing,
            bbox: [
                p.lo.x,
                p.lo.y,
                p.lo.z,
                p.lo.x + p.extent.x,
                p.lo.y + p.extent.y,
                p.lo.z + p.extent.z,
            ],
            sw_3d: p.params.sw,
            clamped_fraction: if values[k] > 0 {
                clamped[k] as f64 / values[k] as f64
            } else {
                f64::NAN
            },
            variance_length: p.segment as f64 * p.params.spacing,
            realized_variance: if done > 0 { var_sum[k] / nf } else { f64::NAN },
            continuum_variance: p.continuum_variance,
        })
        .collect();
    let out = EnsembleOutput {
        width: w,
        height: h,
        mean,
        stderr,
        realizations_done: done,
        realizations_requested: opts.realizations,
        spp: spp_done,
        media,
    };
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
    use super::*;
    use glam::Vec3;

    #[test]
    fn unit_cube_maps_onto_the_grid_box() {
        let (lo, ext) = (DVec3::new(-0.5, 0.25, -0.5), DVec3::new(1.0, 1.0, 2.0));
        let m = Mat4::from_translation(lo.as_vec3()) * Mat4::from_scale(ext.as_vec3());
        assert!((m.transform_point3(Vec3::ZERO) - lo.as_vec3()).length() < 1e-6);
        assert!((m.transform_point3(Vec3::ONE) - (lo + ext).as_vec3()).length() < 1e-6);
    }
}
