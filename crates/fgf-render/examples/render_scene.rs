//! Render a scene file from Rust, for profiling the renderer without Python:
//! `cargo run --release -p fgf-render --example render_scene -- scene.xml [spp] [threads]`.
//! Prints wall time and samples per second.

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).expect("usage: render_scene scene.xml [spp] [threads]");
    let spp: Option<u32> = args.get(2).map(|s| s.parse().expect("spp"));
    let threads: usize = args.get(3).map_or(0, |s| s.parse().expect("threads"));
    let scene = fgf_render::scene::xml::load_file(path.as_ref(), &[]).expect("scene");
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    let opts = fgf_render::render::RenderOptions { spp, seed: Some(0), ..Default::default() };
    let t0 = std::time::Instant::now();
    let out = pool.install(|| fgf_render::render::render(&scene, &opts, &fgf_core::NoProgress)).expect("render");
    let t = t0.elapsed().as_secs_f64();
    let n = (out.width * out.height) as f64 * out.spp_done as f64;
    let mean: f64 = out.image.iter().map(|&v| v as f64).sum::<f64>() / out.image.len() as f64;
    println!("{:.3} s  {:.3} M samples/s  mean {:.6}", t, n / t / 1e6, mean);
}

