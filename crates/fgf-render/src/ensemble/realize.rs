//! One realization of an ensemble: synthesize each planned medium's field,
//! turn it into extinction voxels and render the scene classically. The
//! result depends only on the prepared plan, the realization index and the
//! options' seed and spp (`docs/theory.md` §7.15).

use super::plan::{Plan, Voxels};
use super::{CancelOnly, Prepared};
use crate::error::RenderError;
use crate::render::{render, RenderOptions};
use fgf_core::rng::{mix64, stream_key};
use fgf_core::Progress;
use fgf_field::{synthesize, FieldError};
use fgf_scene::{GridFilter, GridVolumeDesc, MediumDesc, VolumeDesc};
use glam::Mat4;
use std::sync::Arc;

/// Per-medium counts of one realization.
#[derive(Debug, Clone, Default)]
pub struct MediumStats {
    /// Voxel values (all channels) set to 0 by the Gaussian clamp.
    pub clamped: u64,
    /// Voxel values written (all channels).
    pub values: u64,
    /// Second moment of the segment averages of the fluctuation (Monte
    /// Carlo check over the plan's segment along x).
    pub segment_second_moment: f64,
    /// Sum of `σ_t` over voxels, channel mean.
    pub sigma_sum: f64,
    /// Number of voxels.
    pub voxels: u64,
}

/// One rendered realization.
#[derive(Debug, Clone)]
pub struct Realization {
    /// Row-major RGB image.
    pub image: Vec<f32>,
    pub spp: u32,
    pub media: Vec<MediumStats>,
}

/// The voxels of one medium for the field `u` (`docs/theory.md` §1.8):
/// `ρ · max(0, σ_m + u)` (Gaussian) or `ρ · σ_m · G⁻¹(Φ(u/sd))` (gamma), the
/// density always a factor of the whole extinction. Returns the data (x
/// fastest, `channels` interleaved), the fluctuation without `ρ` (for the
/// variance check) and the counts.
pub(super) fn voxels(p: &Plan, u: &[f32]) -> (Vec<f32>, Vec<f32>, MediumStats) {
    let channels = if p.grey { 1 } else { 3 };
    let mut data = Vec::with_capacity(u.len() * channels);
    let mut fluct = Vec::with_capacity(u.len());
    let mut st = MediumStats {
        voxels: u.len() as u64,
        ..Default::default()
    };
    let sigma_mean = p.sigma_t.iter().sum::<f32>() as f64 / 3.0;
    for (j, &uj) in u.iter().enumerate() {
        let rho = p.rho.as_ref().map_or(1.0, |v| v[j]);
        let mut sum = 0.0f64;
        match &p.voxels {
            Voxels::Gaussian => {
                fluct.push(uj);
                for c in 0..channels {
                    let v = p.sigma_t[c] + uj;
                    if v < 0.0 {
                        st.clamped += 1;
                    }
                    let s = rho * v.max(0.0);
                    sum += s as f64;
                    data.push(s);
                }
            }
            Voxels::Gamma { copula, sd, .. } => {
                let x = copula.map(uj as f64 / sd) as f32;
                fluct.push((sigma_mean * (x as f64 - 1.0)) as f32);
                for c in 0..channels {
                    let s = rho * p.sigma_t[c] * x;
                    sum += s as f64;
                    data.push(s);
                }
            }
        }
        st.sigma_sum += if channels == 1 {
            sum
        } else {
            sum / channels as f64
        };
    }
    st.values = data.len() as u64;
    (data, fluct, st)
}

/// Render realization `r` of the prepared ensemble (see the module docs of
/// [`super`]). Its output depends only on the scene, the options' `seed`
/// and `spp`, and `r`: realizations can be rendered in any order, on any
/// machine, and merged in index order ([`Accumulator`](super::Accumulator)).
pub fn render_realization(
    prep: &Prepared,
    r: u32,
    progress: &dyn Progress,
) -> Result<Realization, RealizationError> {
    let base = stream_key(mix64(prep.opts.seed), r as u64);
    let mut sc = prep.scene.clone();
    let cancel_only = CancelOnly(progress);
    let mut stats = Vec::with_capacity(prep.plans.len());
    for p in &prep.plans {
        let mut params = p.params.clone();
        params.seed = stream_key(base, 0x100 + p.medium as u64);
        let field = match synthesize(&params, &cancel_only) {
            Ok(f) => f,
            Err(FieldError::Cancelled(_)) => return Err(RealizationError::Cancelled),
            Err(source) => {
                return Err(RealizationError::Render(RenderError::Field {
                    medium: p.medium,
                    source,
                }))
            }
        };
        let u = field.data.to_f32();
        let (data, fluct, mut st) = voxels(p, &u);
        let lv = fgf_field::estimators::line_average_second_moment(
            &fluct,
            &params.shape,
            2,
            &[p.segment],
        )
        .map_err(|e| {
            RealizationError::Render(RenderError::Field {
                medium: p.medium,
                source: e.into(),
            })
        })?;
        st.segment_second_moment = lv[0];
        let channels = if p.grey { 1 } else { 3 };
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
        let MediumDesc::NonExponential { albedo, phase, .. } = &prep.scene.media[p.medium] else {
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
                wrap: fgf_scene::WrapMode::Clamp,
            }),
            albedo: VolumeDesc::Constant(*albedo),
            scale: 1.0,
            phase: *phase,
            sample_emitters: true,
        };
        stats.push(st);
    }
    let ropts = RenderOptions {
        spp: prep.opts.spp,
        seed: Some(stream_key(base, 0x5EED)),
        variance: false,
        spp_per_pass: None,
    };
    match render(&sc, &ropts, progress) {
        Ok(out) => Ok(Realization {
            image: out.image,
            spp: out.spp_done,
            media: stats,
        }),
        // A partial realization is not one of the N: drop it.
        Err(RenderError::Cancelled { .. }) => Err(RealizationError::Cancelled),
        Err(e) => Err(RealizationError::Render(e)),
    }
}

/// Why [`render_realization`] returned no realization.
#[derive(Debug, thiserror::Error)]
pub enum RealizationError {
    /// [`Progress::cancelled`] asked to stop; the realization is dropped.
    #[error("cancelled")]
    Cancelled,
    #[error(transparent)]
    Render(#[from] RenderError),
}
