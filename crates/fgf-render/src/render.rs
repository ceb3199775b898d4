//! The public entry point: [`render`] a [`SceneDesc`] into an RGB image.
//!
//! * Samples are taken in *passes*: each pass adds the same number of
//!   samples to every pixel, over rows rendered in parallel by rayon. Between
//!   passes the job checks [`Progress::cancelled`]; on cancellation it returns
//!   [`RenderError::Cancelled`] with the image of the passes completed and
//!   the number of samples per pixel it holds (`spp_done`, equal for all
//!   pixels).
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

use crate::error::RenderError;
use crate::film::{Accum, Filter, RenderOutput};
use crate::math::Sampler;
use crate::world::World;
use fgf_core::Progress;
use fgf_scene::SceneDesc;
use rayon::prelude::*;

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
    while done < spp {
        if progress.cancelled() {
            let partial = RenderOutput::from_sums(&acc, w, h, done, spp, opts.variance);
            return Err(RenderError::Cancelled {
                partial: Box::new(partial),
            });
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
                        l = crate::spectrum::Spectrum::ZERO;
                    }
                    a.add(l, opts.variance);
                }
            }
            progress.inc((w as u64) * n as u64);
        });
        done += n;
    }
    Ok(RenderOutput::from_sums(
        &acc,
        w,
        h,
        done,
        spp,
        opts.variance,
    ))
}
