//! The synthesis plan of each `fgf` medium of an ensemble: its grid, its
//! macro density at the voxel centres, and (gamma marginals) the
//! calibration of the Gaussian copula to the model's line-average
//! variance (`docs/theory.md` §1.8).

use super::{EnsembleOptions, Marginal};
use crate::error::RenderError;
use crate::medium::grid::GridTex;
use fgf_core::transmittance::Fgf;
use fgf_field::copula::{calibrate_gamma, Calibration, GammaCopula};
use fgf_field::line_variance::{axis_covariance, log_lengths, segment_variance};
use fgf_field::{
    discrete_spectral_variance, padded_shape, sw_3d_for_ray_statistics, Anchor, Precision,
    SynthParams,
};
use fgf_scene::{MediumDesc, Rgb, SceneDesc, TransmittanceDesc};
use glam::DVec3;

/// Number of segment lengths of the variance comparison (log-spaced from
/// one voxel to the grid's x side).
const LENGTHS: usize = 12;

/// How the voxels of one realization are made from the synthesized field.
pub(super) enum Voxels {
    /// `σ_t = ρ · max(0, σ_m + σ_u)`, `σ_u` the field with `S_w3`.
    Gaussian,
    /// `σ_t = ρ · σ_m · G⁻¹(Φ(u / sd))`, `u` the field with `S_w = 1`.
    Gamma {
        copula: Box<GammaCopula>,
        sd: f64,
        calibration: Calibration,
    },
}

/// One `fgf` medium's synthesis plan.
pub(super) struct Plan {
    pub(super) medium: usize,
    pub(super) sigma_t: Rgb,
    pub(super) grey: bool,
    pub(super) params: SynthParams,
    pub(super) padded: Vec<usize>,
    pub(super) shape: [usize; 3],
    pub(super) lo: DVec3,
    pub(super) extent: DVec3,
    /// `ρ` at each voxel centre (x fastest), or `None` for `ρ = 1`.
    pub(super) rho: Option<Vec<f32>>,
    pub(super) mean_rho: f64,
    pub(super) voxels: Voxels,
    /// Segment of the Monte Carlo variance check, in voxels.
    pub(super) segment: usize,
    pub(super) continuum_variance: f64,
    /// Segment lengths of the exact comparison, in voxels.
    pub(super) lengths: Vec<usize>,
    pub(super) model_variances: Vec<f64>,
    pub(super) grid_variances: Vec<f64>,
}

pub(super) fn plan(scene: &SceneDesc, opts: &EnsembleOptions) -> Result<Vec<Plan>, RenderError> {
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
        params.padding = Some(opts.padding);
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
                            v.push(tex.eval_world(p.as_vec3a()).x);
                        }
                    }
                }
                Some(v)
            }
        };
        let mean_rho = rho.as_ref().map_or(1.0, |v| {
            v.iter().map(|&r| r as f64).sum::<f64>() / v.len() as f64
        });
        let sigma_mean =
            (sigma_t.iter().map(|&s| s as f64).sum::<f64>() / 3.0).max(f64::MIN_POSITIVE);
        // Monte Carlo check over about one mean free path, in whole voxels.
        let segment = ((1.0 / sigma_mean / dx).round() as usize).clamp(1, n[0]);
        let model = Fgf::new(sigma_mean, hurst, sw, length)
            .map_err(|source| RenderError::Param { medium: i, source })?;
        let lengths = log_lengths(n[0], LENGTHS);
        let model_variances: Vec<f64> = lengths
            .iter()
            .map(|&m| model.variance(m as f64 * dx))
            .collect();
        let field_err = |source: fgf_core::ParamError| RenderError::Field {
            medium: i,
            source: source.into(),
        };
        let gamma = match opts.marginal {
            Marginal::Gamma => true,
            Marginal::Gaussian => false,
            Marginal::Auto => hurst < 0.0,
        };
        // The realizations' synthesis is the largest allocation the request
        // implies: refuse it (naming the GiB) before the calibration, whose
        // spectral sums are sized by the same padded grid.
        fgf_field::check_synthesis_memory(&params)
            .map_err(|source| RenderError::Field { medium: i, source })?;
        let (voxels, grid_variances) = if gamma {
            let (calibration, copula) =
                calibrate_gamma(&params, sigma_mean, &lengths, &model_variances)
                    .map_err(field_err)?;
            params.hurst = calibration.hurst_gauss;
            params.sw = 1.0;
            params.anchor = Anchor::None;
            let sd = calibration.gaussian_variance.sqrt();
            let achieved = calibration.achieved.clone();
            (
                Voxels::Gamma {
                    copula: Box::new(copula),
                    sd,
                    calibration,
                },
                achieved,
            )
        } else {
            // The Gaussian field's own spectral sum (for a k-fBm: of the
            // periodic field before the anchor's Taylor subtraction).
            let cov = axis_covariance(&params).map_err(field_err)?;
            let v = lengths.iter().map(|&m| segment_variance(&cov, m)).collect();
            debug_assert!(discrete_spectral_variance(&params).is_ok());
            (Voxels::Gaussian, v)
        };
        let padded = padded_shape(&params).map_err(field_err)?;
        plans.push(Plan {
            medium: i,
            sigma_t: *sigma_t,
            grey: sigma_t[0] == sigma_t[1] && sigma_t[1] == sigma_t[2],
            params,
            padded,
            shape: n,
            lo,
            extent,
            rho,
            mean_rho,
            voxels,
            segment,
            continuum_variance: model.variance(segment as f64 * dx),
            lengths,
            model_variances,
            grid_variances,
        });
    }
    if plans.is_empty() {
        return Err(RenderError::InvalidScene(
            "the scene has no 'fgf' medium: there is nothing to realise".into(),
        ));
    }
    Ok(plans)
}
