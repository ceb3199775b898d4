//! The public entry point: [`render`] a [`SceneDesc`] into an RGB image.
//!
//! * Samples are taken in *passes*: each pass adds the same number of
//!   samples to every pixel, over rows rendered in parallel by rayon. The
//!   job checks [`Progress::cancelled`] between passes, and within the long
//!   passes of small films before each unit of work (a pass cut short is
//!   undone); on cancellation it returns [`RenderError::Cancelled`] with the
//!   image of the passes completed and the number of samples per pixel it
//!   holds (`spp_done`, equal for all pixels).
//! * Sample `k` of pixel `i` uses a random stream derived from
//!   `(seed, i, k)` only, and pixels sum their samples exactly in fixed
//!   point ([`crate::film::Fixed`], `docs/theory.md` §7.17), so the image is
//!   bit-identical for any number of threads, any pass size, and any split of
//!   the samples into ranges rendered apart ([`Prepared::render_range`]) and
//!   merged ([`FilmState::merge`]) in any order — the basis of distributed
//!   renders and of checkpoints.
//! * Progress is reported in samples (pixels × samples per pixel).
//!
//! ```no_run
//! use fgf_render::render::{render, RenderOptions};
//! let scene = fgf_scene::load_file("scene.xml".as_ref(), &[]).unwrap();
//! let out = render(&scene, &RenderOptions::default(), &fgf_core::NoProgress).unwrap();
//! fgf_io::image::write_exr("out.exr".as_ref(), out.width, out.height, 3, &out.image).unwrap();
//! ```

use crate::emitter::envmap::Envmap;
use crate::error::RenderError;
use crate::film::{
    accumulate_sample, flush_pending, FilmState, Filter, Fixed, RenderOutput, FIXED_FRAC_BITS,
};
use crate::geometry::bvh::BEAM;
use crate::geometry::Hit;
use crate::integrator::{lanes8, STEP};
use crate::lanes::F8;
use crate::math::Sampler;
use crate::ray::Ray;
use crate::spectrum::Spectrum;
use crate::world::World;
use fgf_core::Progress;
use fgf_scene::SceneDesc;
use glam::Vec3A;
use rayon::prelude::*;
use std::ops::Range;

/// Overrides of the scene's sampler settings.
#[derive(Debug, Clone, Default)]
pub struct RenderOptions {
    /// Samples per pixel (default: the scene's `sample_count`).
    pub spp: Option<u32>,
    /// Seed (default: the scene's sampler `seed`).
    pub seed: Option<u64>,
    /// Also return the per-pixel variance of the pixel mean.
    pub variance: bool,
    /// Samples per pixel per pass (default: on films of up to 2¹⁸ pixels
    /// a short first pass, then passes of up to 256 samples a pixel; on
    /// larger films passes of one sample a pixel).
    /// It does not change the image, only how often cancellation is
    /// checked, how many samples of a pixel are traced one after another,
    /// and whether the camera rays traced as one beam are a pixel's or
    /// those of neighbouring pixels.
    pub spp_per_pass: Option<u32>,
}

/// A compiled scene, ready to render any range of samples.
pub struct Prepared {
    world: World,
    filter: Filter,
    /// Camera rays are queried up to [`BEAM`] at a time, a pixel's or
    /// neighbouring pixels' ([`crate::geometry::Geometry::intersect_beam`]),
    /// where the integrator allows it; off, each alone (the reference the
    /// tests compare with).
    beams: bool,
    /// The paths of a batch of camera samples go on in step where the
    /// scene is lit by an environment map alone ([`World::li_beam`]); off,
    /// each alone (the reference the tests compare with). On by default
    /// where the 8-lane kernels are vector instructions ([`crate::lanes`]);
    /// the portable build, where they are written out lane by lane, keeps
    /// each path alone (the same image either way).
    lockstep: bool,
    /// The scene's `sample_count`.
    pub spp: u32,
    /// The scene's sampler seed.
    pub seed: u64,
    pub width: usize,
    pub height: usize,
}

impl Prepared {
    /// Validate and compile `scene` (its BVH, media and emitters).
    pub fn new(scene: &SceneDesc) -> Result<Prepared, RenderError> {
        Ok(Self::around(World::build(scene)?, scene))
    }

    /// [`Prepared::new`] of a scene given up to it: its meshes' own arrays
    /// are let go of before the tree is built
    /// ([`World::build_releasing_meshes`]), which lowers the peak memory of
    /// a large mesh's preparation.
    pub fn new_owned(mut scene: SceneDesc) -> Result<Prepared, RenderError> {
        Ok(Self::around(
            World::build_releasing_meshes(&mut scene)?,
            &scene,
        ))
    }

    /// The prepared scene of `world`, compiled from `scene`.
    fn around(world: World, scene: &SceneDesc) -> Prepared {
        let (width, height) = (world.camera.width as usize, world.camera.height as usize);
        Prepared {
            beams: world.takes_first_hit(),
            lockstep: cfg!(all(target_arch = "x86_64", target_feature = "avx2")),
            world,
            filter: Filter::new(&scene.sensor.rfilter),
            spp: scene.sensor.spp,
            seed: scene.sensor.seed,
            width,
            height,
        }
    }

    /// The exact sums of samples `samples` (`s0..s1`, indices from 0) of
    /// every pixel with `seed`, their squares too if `variance`. Merging the
    /// states of disjoint ranges gives the bits of one render of their union.
    ///
    /// On cancellation (checked between passes, and within the long passes
    /// of `Passes`) the state of the passes finished is returned: its
    /// `samples` is then less than the range's length, and it holds the
    /// samples `s0..s0 + samples`.
    pub fn render_range(
        &self,
        seed: u64,
        samples: Range<u32>,
        variance: bool,
        spp_per_pass: Option<u32>,
        progress: &dyn Progress,
    ) -> Result<FilmState, RenderError> {
        let passes = match spp_per_pass {
            Some(n) => Passes::even(n),
            None => Passes::default_for(self.width * self.height),
        };
        self.render_passes(seed, samples, variance, passes, progress)
    }

    /// [`Self::render_range`] in the passes `passes`.
    fn render_passes(
        &self,
        seed: u64,
        samples: Range<u32>,
        variance: bool,
        passes: Passes,
        progress: &dyn Progress,
    ) -> Result<FilmState, RenderError> {
        if samples.start >= samples.end {
            return Err(RenderError::InvalidOption(format!(
                "sample range {}..{} is empty; need s0 < s1",
                samples.start, samples.end
            )));
        }
        let (w, h) = (self.width, self.height);
        let mut state = FilmState::new(w, h, variance);
        // Exact f64 partial sums of the samples not yet in `state`
        // (`film::accumulate_pending`), moved into it at the end.
        let mut pending = vec![[0f64; 3]; w * h];
        let mut pending_sq = vec![[0f64; 3]; if variance { w * h } else { 0 }];
        let seed_key = Sampler::seed_key(seed);
        let beams = self.beams;
        let lone_envmap = if self.lockstep {
            self.world.lone_envmap()
        } else {
            None
        };
        // Paths in step gain from more of them at each stage; paths alone
        // from batches no larger than a beam (docs/benchmarks.md).
        let batch_max = match lone_envmap {
            Some(_) if beams => STEP,
            _ => BEAM,
        };
        let mut next = samples.start;
        let out_of_range =
            |x: usize, y: usize, (channel, value): (usize, f64)| RenderError::OutOfRange {
                x,
                y,
                channel,
                value,
                limit: f64::powi(2.0, 191 - FIXED_FRAC_BITS),
            };
        while next < samples.end {
            if progress.cancelled() {
                break;
            }
            let per_pass = if next == samples.start {
                passes.first
            } else {
                passes.rest
            };
            let n = per_pass.clamp(1, samples.end - next);
            let first = next;
            // A long pass is cancellable before each unit of work; cut
            // short, it is undone from this copy of the sums.
            let within = passes.within(w * h, n);
            let saved = within.then(|| {
                (
                    state.sum.clone(),
                    state.sum_sq.clone(),
                    pending.clone(),
                    pending_sq.clone(),
                )
            });
            // Each row in segments of about `UNIT` samples, the units of
            // work, split within the row's task: a pass ends when its last
            // unit does, and small units leave a thread idle for less at
            // its end. (The gain on the mesh is larger than that wait, and
            // one flat list of the image's segments was slower; why is not
            // established: docs/benchmarks.md.)
            let seg = (UNIT / n as usize).clamp(1, w);
            let pass = rows(&mut state, &mut pending, &mut pending_sq, w).try_for_each(
                |(y, (row, pend), sq)| {
                    let sq_segs: Vec<_> = match sq {
                        Some((a, b)) => a
                            .chunks_mut(3 * seg)
                            .zip(b.chunks_mut(seg))
                            .map(Some)
                            .collect(),
                        None => (0..w.div_ceil(seg)).map(|_| None).collect(),
                    };
                    row.par_chunks_mut(3 * seg)
                        .zip(pend.par_chunks_mut(seg))
                        .zip(sq_segs.into_par_iter())
                        .enumerate()
                        .try_for_each(|(i, ((row, pend), sq))| {
                            if within && progress.cancelled() {
                                return Err(PassEnd::Cancelled);
                            }
                            let x0 = i * seg;
                            self.render_segment(
                                (seed_key, first, n),
                                (x0, y),
                                (row, pend, sq),
                                (lone_envmap, beams, batch_max),
                            )
                            .map_err(|(x, e)| PassEnd::Failed(out_of_range(x, y, e)))?;
                            progress.inc((pend.len() as u64) * n as u64);
                            Ok(())
                        })
                },
            );
            match pass {
                Ok(()) => {}
                Err(PassEnd::Failed(e)) => return Err(e),
                Err(PassEnd::Cancelled) => {
                    if let Some((sum, sum_sq, p, p_sq)) = saved {
                        (state.sum, state.sum_sq, pending, pending_sq) = (sum, sum_sq, p, p_sq);
                    }
                    break;
                }
            }
            next += n;
            state.samples += n as u64;
        }
        rows(&mut state, &mut pending, &mut pending_sq, w).try_for_each(
            |(y, (row, pend), mut sq)| {
                for x in 0..w {
                    let q = sq
                        .as_mut()
                        .map(|(a, b)| (&mut a[3 * x..3 * x + 3], &mut b[x]));
                    let (px, pp) = (&mut row[3 * x..3 * x + 3], &mut pend[x]);
                    flush_pending(px, pp, q, Spectrum::ZERO).map_err(|e| out_of_range(x, y, e))?;
                }
                Ok::<(), RenderError>(())
            },
        )?;
        Ok(state)
    }
}

/// How a pass of [`Prepared::render_passes`] ends early.
enum PassEnd {
    Failed(RenderError),
    /// Cancelled within a long pass ([`Passes::within`]).
    Cancelled,
}

/// How [`Prepared::render_range`] splits its samples into passes: `first`
/// samples a pixel in the first pass, `rest` in each later one (the last
/// may hold fewer); on films of up to [`LONG_PASS_PIXELS`], a pass of more
/// than `within_over` samples is cancellable within.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Passes {
    first: u32,
    rest: u32,
    within_over: usize,
}

/// Films of at most this many pixels take long passes by default, and a
/// pass of theirs holding more than [`SHORT_PASS_MAX`] samples is
/// cancellable within: it keeps a copy of the sums (at most about 25 MB,
/// 50 MB with variances) to undo a pass cut short.
const LONG_PASS_PIXELS: usize = 1 << 18;
/// Samples a default long pass holds at most (as much work as a
/// cancellation within it can throw away: about 5 s of the mesh scene on
/// two cores).
const LONG_PASS: usize = 1 << 24;
/// Samples of a pixel a default long pass takes at most: a pixel's samples
/// traced one after another (a unit of work is then two pixels,
/// [`UNIT`]) find more of what they read in the caches. Passes of 256
/// against 16 took the mesh scene at 256² 0.935–0.978 of the time, and
/// beyond 256 gained nothing more (docs/benchmarks.md).
const LOCAL_SPP: usize = 256;
/// The most samples of a short pass, which is cancelled only between
/// passes.
const SHORT_PASS_MAX: usize = 1 << 20;

impl Passes {
    /// Every pass `n` samples a pixel.
    fn even(n: u32) -> Passes {
        Passes {
            first: n,
            rest: n,
            within_over: SHORT_PASS_MAX,
        }
    }

    /// The default for a film of `pixels` pixels. Films of up to
    /// [`LONG_PASS_PIXELS`]: a short first pass ([`short_pass`], so that
    /// an early interrupt still leaves an image), then long passes of
    /// `2²⁴ / pixels` samples a pixel, at most [`LOCAL_SPP`] (256 at 256²,
    /// 64 at 512²). Larger films: short passes only.
    fn default_for(pixels: usize) -> Passes {
        let short = short_pass(pixels);
        let rest = if pixels <= LONG_PASS_PIXELS {
            (LONG_PASS / pixels.max(1)).min(LOCAL_SPP) as u32
        } else {
            short
        };
        Passes {
            first: short,
            rest,
            within_over: SHORT_PASS_MAX,
        }
    }

    /// A pass of `n` samples a pixel over `pixels` pixels is cancellable
    /// within (and undone if cut short).
    fn within(self, pixels: usize, n: u32) -> bool {
        pixels <= LONG_PASS_PIXELS && n as usize * pixels > self.within_over
    }
}

/// Samples per pixel of a short pass for `pixels` pixels: about 2¹⁸
/// samples, so that cancellation between passes is checked often, but a
/// full beam of camera rays per pixel ([`BEAM`]) where that keeps a pass
/// within [`SHORT_PASS_MAX`].
fn short_pass(pixels: usize) -> u32 {
    let fit = (1usize << 18) / pixels.max(1);
    if fit < BEAM && BEAM * pixels <= SHORT_PASS_MAX {
        BEAM as u32
    } else {
        fit.clamp(1, 64) as u32
    }
}

/// Samples in a unit of work of a pass: a segment of a row of
/// `UNIT / n` pixels for `n` samples a pixel (a whole row where that is
/// wider; one pixel where `n >= UNIT`). Chosen by paired timings: 1024,
/// 512, 256 and 128 took the mesh scene at 256² about 0.95, 0.92, 0.90 and
/// 0.90 of the time of whole rows (paired ratios chained), but 256 made the heterogeneous cube
/// 1 % slower than 1024 and 512 did not (docs/benchmarks.md).
const UNIT: usize = 512;

impl Prepared {
    /// Samples `first..first + n` of the pixels `x0..x0 + pend.len()` of
    /// row `y`, added to their sums (`row`, `pend`, `sq`: the segment's).
    /// The camera samples are made a batch of up to `batch_max` at a time
    /// (whole runs of up to `BEAM` samples of a pixel), then traced
    /// (`Prepared::trace_batch`) and added to their pixels in the batch's
    /// order: each pixel's in the order of `k`. A sample's start (its
    /// stream's keys and film position) is a chain of dependent
    /// multiplies; made together, the chains overlap; the rays, with their
    /// divisions and square roots, are then made eight at a time
    /// (`Prepared::camera_rays`). `Err((x, (channel, value)))` if a sum of pixel
    /// `x` leaves the fixed-point range.
    #[allow(clippy::type_complexity)]
    fn render_segment(
        &self,
        (seed_key, first, n): (u64, u32, u32),
        (x0, y): (usize, usize),
        (row, pend, mut sq): (
            &mut [Fixed],
            &mut [[f64; 3]],
            Option<(&mut [Fixed], &mut [[f64; 3]])>,
        ),
        (lone_envmap, beams, batch_max): (Option<&Envmap>, bool, usize),
    ) -> Result<(), (usize, (usize, f64))> {
        let (w, len) = (self.width, pend.len());
        let mut batch = Batch::new();
        let mut flush = |batch: &mut Batch| {
            self.trace_batch(batch, lone_envmap, beams);
            for (j, l) in batch.l[..batch.len].iter().enumerate() {
                let x = batch.x[j];
                let (px, pp) = (&mut row[3 * x..3 * x + 3], &mut pend[x]);
                add_sample(px, pp, &mut sq, x, *l * batch.weight[j]).map_err(|e| (x0 + x, e))?;
            }
            batch.len = 0;
            Ok(())
        };
        for x in 0..len {
            let pixel_key = Sampler::pixel_key(seed_key, (y * w + x0 + x) as u64);
            let mut k = first;
            while k < first + n {
                let m = ((first + n - k) as usize).min(BEAM);
                if batch.len + m > batch_max {
                    flush(&mut batch)?;
                }
                for j in 0..m {
                    let b = batch.len;
                    let (s, [fx, fy], weight) =
                        self.camera_sample(pixel_key, x0 + x, y, k + j as u32);
                    (batch.s[b], batch.weight[b]) = (s, weight);
                    (batch.film[0][b], batch.film[1][b]) = (fx, fy);
                    batch.x[b] = x;
                    batch.len += 1;
                }
                k += m as u32;
            }
        }
        if batch.len > 0 {
            flush(&mut batch)?;
        }
        Ok(())
    }
}

impl Prepared {
    /// Sample `k` of pixel `(x, y)` (whose key is `pixel_key`): its random
    /// stream, film position and filter weight. (Its camera ray is made
    /// with seven others', [`Prepared::camera_rays`].)
    #[inline(always)]
    fn camera_sample(
        &self,
        pixel_key: u64,
        x: usize,
        y: usize,
        k: u32,
    ) -> (Sampler, [f32; 2], f32) {
        let mut s = Sampler::for_sample(pixel_key, k as u64);
        let (w, h) = (self.width as u32, self.height as u32);
        let (fx, fy, weight) = self
            .filter
            .sample_position(x as u32, y as u32, w, h, &mut s);
        (s, [fx, fy], weight)
    }

    /// The camera rays of the samples of `batch` and their limits, from
    /// their film positions, eight at a time: each the ray
    /// [`crate::camera::Camera::generate_ray`] gives.
    #[inline(always)]
    fn camera_rays(&self, batch: &mut Batch) {
        // (Lanes past the batch's end read other positions of the arrays:
        // finite, and their rays are not used.)
        for c in (0..batch.len).step_by(8) {
            let n = (batch.len - c).min(8);
            let [fx, fy] = &batch.film;
            let (o, d, t_max) = self
                .world
                .camera
                .generate_rays8(lanes8(fx, c), lanes8(fy, c));
            let (o, d, t_max) = (o.map(F8::to_array), d.map(F8::to_array), t_max.to_array());
            for l in 0..n {
                batch.rays[c + l] = Ray {
                    o: Vec3A::new(o[0][l], o[1][l], o[2][l]),
                    d: Vec3A::new(d[0][l], d[1][l], d[2][l]),
                };
                batch.t_max[c + l] = t_max[l];
            }
        }
    }
}

/// Camera samples waiting to be traced: pixel `x[j]` of a row, its random
/// stream, film position, camera ray, the ray's limit and filter weight, for `j < len`;
/// and, once traced, their first hits (with beams) and radiance `l`.
struct Batch {
    len: usize,
    x: [usize; STEP],
    s: [Sampler; STEP],
    /// Film positions, x and y.
    film: [[f32; STEP]; 2],
    rays: [Ray; STEP],
    t_max: [f32; STEP],
    weight: [f32; STEP],
    hits: [Option<Hit>; STEP],
    l: [Spectrum; STEP],
}

impl Batch {
    fn new() -> Batch {
        Batch {
            len: 0,
            x: [0; STEP],
            s: std::array::from_fn(|_| Sampler::idle()),
            film: [[0.0; STEP]; 2],
            rays: [Ray {
                o: Vec3A::ZERO,
                d: Vec3A::Z,
            }; STEP],
            t_max: [0.0; STEP],
            weight: [0.0; STEP],
            hits: [None; STEP],
            l: [Spectrum::ZERO; STEP],
        }
    }
}

impl Prepared {
    /// The radiance `batch.l` of each sample of `batch`. With `beams`, its
    /// camera rays find their first hits `BEAM` at a time by one beam query
    /// (rays of one pixel or of neighbouring pixels, nearly parallel); then
    /// each path goes on alone, or all in step where the scene is lit by an
    /// environment map alone (`env`; [`World::li_beam`]). Each sample's
    /// value is the one [`World::li`] gives it.
    #[inline(never)]
    fn trace_batch(&self, batch: &mut Batch, env: Option<&Envmap>, beams: bool) {
        self.camera_rays(batch);
        let m = batch.len;
        let b = batch;
        if beams {
            for c in (0..m).step_by(BEAM) {
                let e = (c + BEAM).min(m);
                let geom = &self.world.geom;
                geom.intersect_beam(&b.rays[c..e], &b.t_max[c..e], &mut b.hits[c..e]);
            }
        }
        match env {
            Some(env) if beams => self.world.li_beam(
                env,
                &b.rays[..m],
                &b.t_max[..m],
                &b.hits[..m],
                &mut b.s[..m],
                &mut b.l[..m],
            ),
            _ => {
                for j in 0..m {
                    let (ray, t_max, s) = (b.rays[j], b.t_max[j], &mut b.s[j]);
                    b.l[j] = if beams {
                        self.world.li_seen(ray, t_max, b.hits[j], s)
                    } else {
                        self.world.li(ray, t_max, s)
                    };
                }
            }
        }
    }
}

/// Add sample `l` of pixel `x` of a row to its sums `px`, pending sums
/// `pp` and, if kept, the sums of squares (`sq`: the row's).
/// A NaN or infinite sample counts as 0 (`accumulate_sample`).
#[inline(always)]
#[allow(clippy::type_complexity)]
fn add_sample(
    px: &mut [Fixed],
    pp: &mut [f64; 3],
    sq: &mut Option<(&mut [Fixed], &mut [[f64; 3]])>,
    x: usize,
    l: Spectrum,
) -> Result<(), (usize, f64)> {
    let q = sq
        .as_mut()
        .map(|(a, b)| (&mut a[3 * x..3 * x + 3], &mut b[x]));
    accumulate_sample(px, pp, q, l)
}

/// The rows of `state`'s sums with their pending partial sums, in parallel:
/// `(y, (sums, pending), Some((sums of squares, pending squares)))`.
#[allow(clippy::type_complexity)]
fn rows<'a>(
    state: &'a mut FilmState,
    pending: &'a mut [[f64; 3]],
    pending_sq: &'a mut [[f64; 3]],
    w: usize,
) -> impl IndexedParallelIterator<
    Item = (
        usize,
        (&'a mut [Fixed], &'a mut [[f64; 3]]),
        Option<(&'a mut [Fixed], &'a mut [[f64; 3]])>,
    ),
> {
    let sq_rows: Vec<Option<(&mut [Fixed], &mut [[f64; 3]])>> = match state.sum_sq.as_mut() {
        Some(v) => v
            .chunks_mut(w * 3)
            .zip(pending_sq.chunks_mut(w))
            .map(Some)
            .collect(),
        None => (0..state.height).map(|_| None).collect(),
    };
    state
        .sum
        .par_chunks_mut(w * 3)
        .zip(pending.par_chunks_mut(w))
        .zip(sq_rows.into_par_iter())
        .enumerate()
        .map(|(y, (row, sq))| (y, row, sq))
}

/// Render `scene`; see the module docs.
pub fn render(
    scene: &SceneDesc,
    opts: &RenderOptions,
    progress: &dyn Progress,
) -> Result<RenderOutput, RenderError> {
    render_prepared(Prepared::new(scene)?, opts, progress)
}

/// [`render`] of a scene given up to it, in less memory for large meshes
/// ([`Prepared::new_owned`]): the same image.
pub fn render_owned(
    scene: SceneDesc,
    opts: &RenderOptions,
    progress: &dyn Progress,
) -> Result<RenderOutput, RenderError> {
    render_prepared(Prepared::new_owned(scene)?, opts, progress)
}

fn render_prepared(
    prepared: Prepared,
    opts: &RenderOptions,
    progress: &dyn Progress,
) -> Result<RenderOutput, RenderError> {
    let spp = opts.spp.unwrap_or(prepared.spp);
    if spp == 0 {
        return Err(RenderError::InvalidOption(
            "spp = 0; need at least 1 sample per pixel".into(),
        ));
    }
    let seed = opts.seed.unwrap_or(prepared.seed);
    let state = prepared.render_range(seed, 0..spp, opts.variance, opts.spp_per_pass, progress)?;
    let out = state.finish(spp);
    if state.samples < spp as u64 {
        return Err(RenderError::Cancelled {
            partial: Box::new(out),
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::Prepared;
    use crate::film::Fixed;
    use fgf_core::NoProgress;
    use fgf_scene::{GeometryDesc, ShapeDesc};
    use glam::Mat4;

    /// The scene `xml` with a `k × k` height field over `[0, 4]²` (y ≈ 0)
    /// added, which takes the BSDF of the scene's second shape.
    fn with_height_field(xml: &str, k: u32) -> fgf_scene::SceneDesc {
        let mut desc = fgf_scene::load_str(xml, "test.xml", ".".as_ref(), &[]).unwrap();
        let bsdf = desc.shapes[1].bsdf;
        desc.shapes.push(ShapeDesc {
            name: "height field".into(),
            geometry: GeometryDesc::Mesh(crate::geometry::tests::height_field(k)),
            to_world: Mat4::IDENTITY,
            flip_normals: false,
            bsdf,
            emitter: None,
            interior: None,
            exterior: None,
        });
        desc
    }

    /// The paths of a batch in step (a scene lit by an environment map
    /// alone) give each sample the bits of the paths traced one at a time:
    /// a textured rough-plastic height field, a rough conductor and a
    /// two-sided rough plastic seen from both sides (all GGX: their values
    /// toward light samples and sampled directions in eight lanes), and a
    /// smooth conductor and a dielectric sphere (no next-event estimation
    /// there), under an environment map with a bright spot. The batches of
    /// paths in step hold the samples of four pixels (passes of 16), of
    /// two (passes of 32), of up to twenty-one (passes of 7, and the runs of
    /// 5 and 3 of split sample ranges: beams span pixels, batches end
    /// within rows), and of a whole row of 36 pixels (passes of 1). With a
    /// medium, the paths go on alone.
    #[test]
    fn paths_in_step_match_paths_alone() {
        let xml = r#"<scene version="3.0.0">
            <integrator type="volpath"><integer name="max_depth" value="12"/></integrator>
            <sensor type="perspective">
                <float name="fov" value="55"/>
                <transform name="to_world">
                    <lookat origin="2, 2.4, -1.6" target="2, 0, 2" up="0, 1, 0"/>
                </transform>
                <sampler type="independent"><integer name="sample_count" value="32"/></sampler>
                <film type="hdrfilm">
                    <integer name="width" value="36"/><integer name="height" value="28"/>
                    <rfilter type="box"/>
                </film>
            </sensor>
            <shape type="rectangle">
                <transform name="to_world">
                    <rotate x="1" angle="-90"/><translate value="2, -0.05, 2"/><scale value="3"/>
                </transform>
                <bsdf type="roughconductor">
                    <string name="distribution" value="ggx"/><float name="alpha" value="0.3"/>
                </bsdf>
            </shape>
            <shape type="disk">
                <transform name="to_world"><translate value="-9, -9, -9"/></transform>
                <bsdf type="roughplastic">
                    <texture type="checkerboard" name="diffuse_reflectance">
                        <transform name="to_uv"><scale x="12" y="12"/></transform>
                    </texture>
                    <string name="distribution" value="ggx"/><float name="alpha" value="0.15"/>
                </bsdf>
            </shape>
            <shape type="sphere">
                <point name="center" x="1.4" y="0.6" z="2.2"/><float name="radius" value="0.5"/>
                <bsdf type="dielectric"/>
            </shape>
            <shape type="sphere">
                <point name="center" x="2.7" y="0.5" z="1.6"/><float name="radius" value="0.35"/>
                <bsdf type="conductor"/>
            </shape>
            <shape type="rectangle">
                <transform name="to_world">
                    <scale x="0.6" y="0.4"/><rotate y="1" angle="20"/><translate value="2.3, 0.45, 2.6"/>
                </transform>
                <bsdf type="twosided">
                    <bsdf type="roughplastic">
                        <string name="distribution" value="ggx"/><float name="alpha" value="0.25"/>
                    </bsdf>
                </bsdf>
            </shape>
        </scene>"#;
        let mut desc = with_height_field(xml, 48);
        let (w, h) = (32, 16);
        let data = (0..w * h)
            .flat_map(|i| {
                let (x, y) = (i % w, i / w);
                let sun = if (x, y) == (20, 5) || (x, y) == (21, 5) {
                    400.0
                } else {
                    0.0
                };
                [
                    0.3 + sun + 0.02 * x as f32,
                    0.5 + sun,
                    0.9 + sun - 0.04 * y as f32,
                ]
            })
            .collect();
        desc.emitters = vec![fgf_scene::EmitterDesc::Envmap {
            image: std::sync::Arc::new(fgf_scene::RgbImage {
                width: w,
                height: h,
                data,
            }),
            to_world: Mat4::from_rotation_y(0.4),
        }];
        let mut in_step = Prepared::new(&desc).unwrap();
        // (Also in the portable build, whose lanes are written out.)
        in_step.lockstep = true;
        assert!(in_step.beams && in_step.world.lone_envmap().is_some());
        let mut alone = Prepared::new(&desc).unwrap();
        alone.lockstep = false;
        let render = |p: &Prepared, pass: u32| {
            let mut state = p
                .render_range(7, 0..5, true, Some(pass), &NoProgress)
                .unwrap();
            for r in [5..8, 8..32] {
                let part = p.render_range(7, r, true, Some(pass), &NoProgress).unwrap();
                state.merge(&part).unwrap();
            }
            state.finish(32)
        };
        let (a, b) = (render(&in_step, 16), render(&alone, 16));
        assert!(
            a.image.iter().any(|&v| v > 0.0),
            "the image should not be black"
        );
        assert_eq!(a.image, b.image, "paths in step against paths alone");
        assert_eq!(a.variance, b.variance);
        for pass in [7, 32, 1] {
            let c = render(&in_step, pass);
            assert_eq!(a.image, c.image, "passes of {pass} against passes of 16");
        }
        assert_eq!(a.image, render(&alone, 1).image, "paths alone, passes of 1");
        // Passes of 29 samples make units of work of 17 pixels (`UNIT`):
        // each row of 36 three segments, the last of two pixels.
        assert_eq!(super::UNIT / 29, 17);
        let rows = |pass: u32| {
            let st = in_step
                .render_range(7, 0..40, true, Some(pass), &NoProgress)
                .unwrap();
            st.finish(40)
        };
        let (whole, split) = (rows(1), rows(29));
        assert_eq!(whole.image, split.image, "rows in segments");
        assert_eq!(whole.variance, split.variance, "rows in segments");
        // In a scene with a medium, the paths go on alone.
        desc.media.push(fgf_scene::MediumDesc::Homogeneous {
            sigma_t: [1.5; 3],
            albedo: [0.9; 3],
            phase: fgf_scene::PhaseDesc::Isotropic,
            sample_emitters: true,
        });
        assert!(Prepared::new(&desc).unwrap().world.lone_envmap().is_none());
    }

    /// A textured rough-plastic height field under an environment and an
    /// area light (with [`with_height_field`]).
    const LIT_FIELD: &str = r#"<scene version="3.0.0">
            <integrator type="path"><integer name="max_depth" value="6"/></integrator>
            <sensor type="perspective">
                <float name="fov" value="50"/>
                <transform name="to_world">
                    <lookat origin="2, 2.2, -1.8" target="2, 0, 2" up="0, 1, 0"/>
                </transform>
                <sampler type="independent"><integer name="sample_count" value="24"/></sampler>
                <film type="hdrfilm">
                    <integer name="width" value="40"/><integer name="height" value="32"/>
                    <rfilter type="box"/>
                </film>
            </sensor>
            <emitter type="constant"><rgb name="radiance" value="0.4"/></emitter>
            <shape type="rectangle">
                <transform name="to_world">
                    <rotate x="1" angle="90"/><translate value="2, 3, 2"/>
                </transform>
                <emitter type="area"><rgb name="radiance" value="6"/></emitter>
            </shape>
            <shape type="disk">
                <transform name="to_world"><translate value="-9, -9, -9"/></transform>
                <bsdf type="roughplastic">
                    <texture type="checkerboard" name="diffuse_reflectance">
                        <transform name="to_uv"><scale x="12" y="12"/></transform>
                    </texture>
                    <float name="alpha" value="0.15"/>
                </bsdf>
            </shape>
        </scene>"#;

    /// A scene given up to the render ([`super::render_owned`]) gives the
    /// image of the same scene lent to it ([`super::render`]) bit for bit,
    /// and its meshes' arrays are freed once compiled, before the tree is
    /// built.
    #[test]
    fn owned_scenes_render_alike_and_let_go_of_their_meshes() {
        let opts = super::RenderOptions {
            spp: Some(4),
            seed: Some(5),
            ..Default::default()
        };
        let desc = with_height_field(LIT_FIELD, 96);
        let lent = super::render(&desc, &opts, &NoProgress).unwrap();
        assert!(
            lent.image.iter().any(|&v| v > 0.0),
            "the image should not be black"
        );
        let given = super::render_owned(desc.clone(), &opts, &NoProgress).unwrap();
        assert_eq!(lent.image, given.image);
        let mut desc = desc;
        let GeometryDesc::Mesh(mesh) = &desc.shapes.last().unwrap().geometry else {
            panic!("the height field is a mesh")
        };
        let mesh = std::sync::Arc::downgrade(mesh);
        let world = crate::world::World::build_releasing_meshes(&mut desc).unwrap();
        assert!(mesh.upgrade().is_none(), "the mesh should be freed");
        assert_eq!(world.geom.areas.len(), desc.shapes.len());
        assert!((world.geom.areas.last().unwrap() - 16.0).abs() < 1.0);
    }

    /// The beam query of a pixel's camera rays changes no path: a textured
    /// rough-plastic height field of 18,432 triangles under an environment
    /// and an area light, rendered with beams and with every camera ray
    /// queried alone (the reference), gives the same image bit for bit, and
    /// so does the beam render split into sample ranges that cut the beams
    /// differently (rendered apart and merged).
    #[test]
    fn camera_beams_match_single_ray_queries() {
        let xml = LIT_FIELD;
        let desc = with_height_field(xml, 96);
        let with = Prepared::new(&desc).unwrap();
        assert!(with.beams, "the scene should take beams");
        let mut without = Prepared::new(&desc).unwrap();
        without.beams = false;
        let render = |p: &Prepared| {
            p.render_range(1, 0..24, true, Some(24), &NoProgress)
                .unwrap()
                .finish(24)
        };
        let (a, b) = (render(&with), render(&without));
        assert!(
            a.image.iter().any(|&v| v > 0.0),
            "the image should not be black"
        );
        assert_eq!(a.image, b.image, "beams against single rays");
        assert_eq!(a.variance, b.variance);
        // Ranges 0..5, 5..19, 19..24 with passes of 8: beams (or batches of
        // camera samples, without beams) of 5, 8, 6, 5.
        for p in [&with, &without] {
            let mut split = p.render_range(1, 0..5, true, Some(8), &NoProgress).unwrap();
            for r in [5..19, 19..24] {
                let part = p.render_range(1, r, true, Some(8), &NoProgress).unwrap();
                split.merge(&part).unwrap();
            }
            let c = split.finish(24);
            assert_eq!(a.image, c.image, "one range against three");
        }
    }

    /// Shadow rays in a scene where every surface blocks take one any-hit
    /// query (`Geometry::occluded`) and the transmittance of the medium
    /// they start in; the general walk over null crossings, forced on the
    /// same scene, gives the same image bit for bit. The camera sits in a
    /// homogeneous medium, so the fast path's medium segment is exercised,
    /// and a height field shadows part of the floor.
    #[test]
    fn occlusion_queries_match_the_crossing_walk() {
        let xml = r#"<scene version="3.0.0">
            <integrator type="volpath"><integer name="max_depth" value="5"/></integrator>
            <medium type="homogeneous" id="fog">
                <float name="sigma_t" value="0.15"/><rgb name="albedo" value="0.7"/>
            </medium>
            <sensor type="perspective">
                <ref id="fog"/>
                <float name="fov" value="50"/>
                <transform name="to_world">
                    <lookat origin="2, 2.2, -1.8" target="2, 0, 2" up="0, 1, 0"/>
                </transform>
                <sampler type="independent"><integer name="sample_count" value="8"/></sampler>
                <film type="hdrfilm">
                    <integer name="width" value="24"/><integer name="height" value="20"/>
                    <rfilter type="box"/>
                </film>
            </sensor>
            <shape type="rectangle">
                <transform name="to_world">
                    <rotate x="1" angle="90"/><translate value="2, 3, 2"/>
                </transform>
                <emitter type="area"><rgb name="radiance" value="6"/></emitter>
            </shape>
            <shape type="rectangle">
                <transform name="to_world">
                    <scale value="6"/><rotate x="1" angle="-90"/><translate value="2, -0.5, 2"/>
                </transform>
                <bsdf type="diffuse"/>
            </shape>
        </scene>"#;
        let desc = with_height_field(xml, 24);
        let fast = Prepared::new(&desc).unwrap();
        assert!(
            !fast.world.any_passable,
            "every surface of the scene blocks"
        );
        assert!(fast.world.camera_medium.is_some());
        let mut walk = Prepared::new(&desc).unwrap();
        walk.world.any_passable = true;
        let render = |p: &Prepared| {
            p.render_range(3, 0..8, false, None, &NoProgress)
                .unwrap()
                .finish(8)
        };
        let (a, b) = (render(&fast), render(&walk));
        assert!(
            a.image.iter().any(|&v| v > 0.0),
            "the image should not be black"
        );
        assert_eq!(
            a.image, b.image,
            "any-hit queries against the crossing walk"
        );
    }

    #[test]
    fn fixed_point_sums_are_exact_and_order_free() {
        let vals = [0.1f64, 1e-20, 3.5e7, -2.25, 1e-30, 7.0 / 3.0, 1e28];
        let mut a = Fixed::default();
        for v in vals {
            assert!(a.add_f64(v));
        }
        let mut b = Fixed::default();
        for v in vals.iter().rev() {
            assert!(b.add_f64(*v));
        }
        assert_eq!(a, b);
        let mut c = Fixed::default();
        let mut d = Fixed::default();
        for v in &vals[..3] {
            c.add_f64(*v);
        }
        for v in &vals[3..] {
            d.add_f64(*v);
        }
        assert!(d.merge(&c));
        assert_eq!(a, d);
        // Round trip of values on the unit grid.
        for v in [0.5f64, -0.75, 12345.0, 1.0 / 1024.0, -3e20] {
            assert_eq!(Fixed::from_f64(v).unwrap().to_f64(), v);
        }
        // Out of range and non-finite values are refused.
        assert!(Fixed::from_f64(f64::powi(2.0, 95)).is_none());
        assert!(Fixed::from_f64(f64::NAN).is_none());
        let mut big = Fixed::from_f64(f64::powi(2.0, 94)).unwrap();
        assert!(!big.merge(&Fixed::from_f64(f64::powi(2.0, 94)).unwrap()));
        // Below half a unit rounds to zero; half a unit rounds away.
        assert_eq!(
            Fixed::from_f64(f64::powi(2.0, -98)).unwrap(),
            Fixed::default()
        );
        assert_eq!(Fixed::from_f64(f64::powi(2.0, -97)).unwrap().0, [1, 0, 0]);
        assert_eq!(
            Fixed::from_f64(-f64::powi(2.0, -96)).unwrap().0,
            [u64::MAX; 3]
        );
    }

    /// The default passes by film size: a short first pass, then long
    /// passes of `2²⁴ / pixels` samples a pixel up to 256 on films of up to
    /// 2¹⁸ pixels, cancellable within where they hold more than 2²⁰
    /// samples; short passes alone on larger films.
    #[test]
    fn default_passes_by_film_size() {
        use super::Passes;
        let p = |pixels: usize| {
            let d = Passes::default_for(pixels);
            (d.first, d.rest, d.within(pixels, d.rest))
        };
        assert_eq!(p(36 * 28), (64, 256, false));
        assert_eq!(p(64 * 64), (64, 256, false));
        assert_eq!(p(256 * 256), (16, 256, true));
        assert_eq!(p(512 * 512), (1, 64, true));
        assert_eq!(p(1024 * 1024), (1, 1, false));
        assert_eq!(p(4096 * 4096), (1, 1, false));
        assert!(!Passes::even(4).within(256 * 256, 16));
        assert!(!Passes::even(4).within(1024 * 1024, 16));
    }

    /// Cancels once more than `after` samples have been reported.
    struct CancelAfter(std::sync::atomic::AtomicU64, u64);
    impl fgf_core::Progress for CancelAfter {
        fn inc(&self, n: u64) {
            self.0.fetch_add(n, std::sync::atomic::Ordering::Relaxed);
        }
        fn cancelled(&self) -> bool {
            self.0.load(std::sync::atomic::Ordering::Relaxed) > self.1
        }
    }

    /// A pass cancelled within, after some of its units of work, is undone:
    /// the state holds the passes finished before it, bit for bit those of
    /// an uninterrupted render of their samples, and a cut first pass
    /// leaves none.
    #[test]
    fn a_pass_cut_short_is_undone() {
        let xml = r#"<scene version="3.0.0">
            <integrator type="path"><integer name="max_depth" value="4"/></integrator>
            <sensor type="perspective">
                <float name="fov" value="50"/>
                <transform name="to_world"><lookat origin="0, 2, -3" target="0, 0, 0" up="0, 1, 0"/></transform>
                <sampler type="independent"><integer name="sample_count" value="8"/></sampler>
                <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="8"/></film>
            </sensor>
            <emitter type="constant"><rgb name="radiance" value="0.7"/></emitter>
            <shape type="rectangle">
                <transform name="to_world"><rotate x="1" angle="-90"/><scale value="2"/></transform>
                <bsdf type="diffuse"/>
            </shape>
            <shape type="sphere"><float name="radius" value="0.5"/><bsdf type="roughplastic"/></shape>
        </scene>"#;
        let desc = fgf_scene::load_str(xml, "test.xml", ".".as_ref(), &[]).unwrap();
        let p = Prepared::new(&desc).unwrap();
        // Every pass cancellable within; a pass of 8 samples is one unit
        // of work a row (8 units), of 2 samples too.
        let passes = super::Passes {
            first: 2,
            rest: 8,
            within_over: 0,
        };
        let pixels = 16 * 8;
        let done = |after: u64| {
            let c = CancelAfter(std::sync::atomic::AtomicU64::new(0), after);
            let st = p.render_passes(5, 0..26, true, passes, &c).unwrap();
            (st, c.0.into_inner())
        };
        // Cut after one unit of the second pass: the first pass's samples.
        let (cut, reported) = done(2 * pixels);
        assert_eq!(cut.samples, 2);
        assert!(
            reported > 2 * pixels && reported < 10 * pixels,
            "{reported}"
        );
        let first = p.render_range(5, 0..2, true, None, &NoProgress).unwrap();
        assert_eq!((cut.sum, cut.sum_sq), (first.sum.clone(), first.sum_sq));
        // Cut after one unit of the first pass: nothing.
        let (none, _) = done(0);
        assert_eq!(none.samples, 0);
        assert!(none.sum.iter().all(|v| *v == Fixed::default()));
        // Not cut: all 26, as in passes of 1.
        let (all, _) = done(u64::MAX);
        let ones = p
            .render_range(5, 0..26, true, Some(1), &NoProgress)
            .unwrap();
        assert_eq!((all.samples, all.sum), (26, ones.sum));
    }
}
