//! Render a scene file from Rust, for profiling the renderer without Python:
//!
//! ```text
//! cargo run --release -p fgf-render --example render_scene -- scene.xml [spp] [threads] [name=value]...
//! ```
//!
//! The `name=value` arguments are the scene's `-D` defines. Prints the wall
//! time, samples per second, the image mean and a hash of the image's bits
//! (to check that a change keeps images bit-identical);
//! `benchmarks/callgrind.sh` runs it under callgrind.

use std::process::ExitCode;

/// The allocator of the Python package's native module, so that timings
/// here are those of `fgf render`.
#[global_allocator]
static ALLOC: fgf_render::HugePages = fgf_render::HugePages;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: render_scene scene.xml [spp >= 1] [threads, 0 = all] [name=value]...";
    let Some(path) = args.get(1) else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    let (Ok(spp), Ok(threads)) = (
        args.get(2).map(|s| s.parse::<u32>()).transpose(),
        args.get(3).map_or(Ok(0), |s| s.parse::<usize>()),
    ) else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    let Some(defines) = args
        .iter()
        .skip(4)
        .map(|d| {
            d.split_once('=')
                .map(|(k, v)| (k.to_string(), v.to_string()))
        })
        .collect::<Option<Vec<_>>>()
    else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    let scene = match fgf_scene::load_file(path.as_ref(), &defines) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let pool = match rayon::ThreadPoolBuilder::new().num_threads(threads).build() {
        Ok(p) => p,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(1);
        }
    };
    let opts = fgf_render::RenderOptions {
        spp,
        seed: Some(0),
        ..Default::default()
    };
    let t0 = std::time::Instant::now();
    let out = match pool.install(|| fgf_render::render_owned(scene, &opts, &fgf_core::NoProgress)) {
        Ok(o) => o,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(1);
        }
    };
    let t = t0.elapsed().as_secs_f64();
    let n = (out.width * out.height) as f64 * out.spp_done as f64;
    let mean = out.image.iter().map(|&v| v as f64).sum::<f64>() / out.image.len() as f64;
    // FNV-1a over the pixel bits.
    let hash = out.image.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, v| {
        (h ^ v.to_bits() as u64).wrapping_mul(0x0100_0000_01b3)
    });
    println!(
        "{t:.3} s  {:.3} M samples/s  mean {mean:.6}  hash {hash:016x}  samples {n}",
        n / t / 1e6
    );
    ExitCode::SUCCESS
}
