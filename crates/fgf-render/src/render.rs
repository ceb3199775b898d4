//! The public entry point: [`render`] a [`SceneDesc`] into an RGB image.
//!
//! * Samples are taken in *passes*: each pass adds the same number of
//!   samples to every pixel, over rows rendered in parallel by rayon. Between
//!   passes the job checks [`Progress::cancelled`]; on cancellation it returns
//!   the image of the passes completed, with the number of samples per pixel
//!   it holds (`spp_done`, equal for all pixels).
//! * Sample `k` of pixel `i` uses a random stream derived from
//!   `(seed, i, k)` only and each pixel accumulates its samples in order, so
//!   the image is bit-identical for any number of threads.
//! * Progress is reported in samples (pixels × samples per pixel).
//!
//! ```no_run
//! use fgf_render::render::{render, RenderOptions};
//! let scene = fgf_scene::load_file("scene.xml".as_ref(), &[]).unwrap();
//! let out = render(&scene, &RenderOptions::default(), &fgf_core::NoProgress).unwrap();
//! fgf_io::image::write_exr("out.exr".as_ref(), out.width, out.height, 3, &out.image).unwrap();
//! ```

use crate::film::Filter;
use crate::integrator::World;
use crate::math::Sampler;
use fgf_core::Progress;
use fgf_scene::SceneDesc;
use rayon::prelude::*;

/// Errors of the renderer (scene errors found when compiling the scene, and
/// features outside the supported subset).
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The description breaks a rule of `SceneDesc::validate`.
    #[error(transparent)]
    Scene(#[from] fgf_scene::SceneError),
    #[error("invalid scene: {0}")]
    InvalidScene(String),
    #[error("not supported: {0}")]
    Unsupported(String),
    #[error("invalid render option: {0}")]
    InvalidOption(String),
}

/// Overrides of the scene's sampler settings.
#[derive(Debug, Clone, Default)]
pub struct RenderOptions {
    /// Samples per pixel (default: the scene's `sample_count`).
    pub spp: Option<u32>,
    /// Seed (default: the scene's sampler `seed`).
    pub seed: Option<u64>,
    /// Also return the per-pixel variance of the pixel mean.
    pub variance: bool,
    /// Samples per pixel per pass (default: chosen so a pass holds about
    /// 2¹⁸ samples; it does not change the image, only how often
    /// cancellation is checked).
    pub spp_per_pass: Option<u32>,
}

/// A rendered image: row-major from the top-left, RGB interleaved.
#[derive(Debug, Clone)]
pub struct RenderOutput {
    pub width: usize,
    pub height: usize,
    /// `height·width·3` linear radiance values (the pixel means).
    pub image: Vec<f32>,
    /// Variance of each pixel mean (sample variance / n), if asked for.
    pub variance: Option<Vec<f32>>,
    /// Samples per pixel in the image (less than asked if cancelled).
    pub spp_done: u32,
    pub spp_requested: u32,
    pub interrupted: bool,
}

/// Per-pixel running sums (f64 so that millions of samples add exactly enough).
#[derive(Clone, Copy, Default)]
struct Accum {
    sum: [f64; 3],
    sum_sq: [f64; 3],
}

/// Render `scene`; see the module docs.
pub fn render(
    scene: &SceneDesc,
    opts: &RenderOptions,
    progress: &dyn Progress,
) -> Result<RenderOutput, RenderError> {
    let world = World::build(scene)?;
    let spp = opts.spp.unwrap_or(scene.sensor.spp);
    if spp == 0 {
        return Err(RenderError::InvalidOption(
            "spp = 0; need at least 1 sample per pixel".into(),
        ));
    }
    let seed = opts.seed.unwrap_or(scene.sensor.seed);
    let filter = Filter::new(&scene.sensor.rfilter);
    let (w, h) = (world.camera.width as usize, world.camera.height as usize);
    let per_pass = opts
        .spp_per_pass
        .unwrap_or_else(|| ((1usize << 18) / (w * h)).clamp(1, 64) as u32)
        .clamp(1, spp);
    let mut acc = vec![Accum::default(); w * h];
    let mut done = 0u32;
    let seed_key = Sampler::seed_key(seed);
    let mut interrupted = false;
    while done < spp {
        if progress.cancelled() {
            interrupted = true;
            break;
        }
        let n = per_pass.min(spp - done);
        let first = done;
        acc.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
            for (x, a) in row.iter_mut().enumerate() {
                let pixel_key = Sampler::pixel_key(seed_key, (y * w + x) as u64);
                for k in first..first + n {
                    let mut s = Sampler::for_sample(pixel_key, k as u64);
                    let (fx, fy, weight) =
                        filter.sample_position(x as u32, y as u32, w as u32, h as u32, &mut s);
                    let (ray, t_max) = world.camera.generate_ray(fx, fy);
                    let mut l = world.li(ray, t_max, &mut s) * weight;
                    // A NaN or infinite sample (a numerical failure, e.g. a
                    // zero pdf) would poison the pixel forever: drop it to 0.
                    if !l.is_finite() {
                        l = crate::math::Spectrum::ZERO;
                    }
                    for c in 0..3 {
                        let v = l[c] as f64;
                        a.sum[c] += v;
                        if opts.variance {
                            a.sum_sq[c] += v * v;
                        }
                    }
                }
            }
            progress.inc((w as u64) * n as u64);
        });
        done += n;
    }
    let nf = done.max(1) as f64;
    let image: Vec<f32> = acc
        .iter()
        .flat_map(|a| a.sum.map(|s| (s / nf) as f32))
        .collect();
    let variance = opts.variance.then(|| {
        acc.iter()
            .flat_map(|a| {
                [0, 1, 2].map(|c| {
                    if done < 2 {
                        return f32::NAN;
                    }
                    let m = a.sum[c] / nf;
                    // Unbiased sample variance, divided by n for the mean.
                    let var = ((a.sum_sq[c] - nf * m * m) / (nf - 1.0)).max(0.0);
                    (var / nf) as f32
                })
            })
            .collect()
    });
    Ok(RenderOutput {
        width: w,
        height: h,
        image,
        variance,
        spp_done: done,
        spp_requested: spp,
        interrupted,
    })
}
