#[test]
fn probe() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes/cube-homogeneous.xml");
    let s = fgf_render::scene::load_file(&path, &[]).unwrap();
    let w = fgf_render::integrator::World::build(&s).unwrap();
    let g = &w.geom;
    println!("{}", g.debug_layout());
    let mut smp = fgf_render::math::Sampler::new(1, 2, 3);
    let t0 = std::time::Instant::now();
    let n = 2_000_000;
    let mut hits = 0;
    for _ in 0..n {
        let o = glam::Vec3::new(smp.next_1d() - 0.5, 0.25 + smp.next_1d(), smp.next_1d() - 0.5);
        let d = fgf_render::math::sample_uniform_sphere(smp.next_2d());
        if g.intersect(&fgf_render::geometry::Ray { o, d }, f32::INFINITY).is_some() { hits += 1; }
    }
    println!("{} ns per intersect ({hits} hits)", t0.elapsed().as_nanos() as f64 / n as f64);
}
