//! Trace a file of rays against a PLY mesh with fgf's BVH, on one thread:
//! the fgf side of `benchmarks/bench_rays.py`, which traces the same rays
//! with Mitsuba 3 (Embree).
//!
//! ```text
//! cargo run --release -p fgf-render --example trace_rays -- mesh.ply rays.f32 nearest|any [passes]
//! ```
//!
//! `rays.f32` holds 6 little-endian `f32` per ray: origin and unit
//! direction; every ray is unbounded. `nearest` asks for each ray's nearest
//! hit, `any` only whether it hits anything (a shadow ray). After one
//! untimed pass, `passes` (default 5) timed passes over all rays; prints
//! one JSON line: the seconds of each timed pass, the number of rays that
//! hit and, for `nearest`, the sum of the hit distances (for comparing the
//! answers with Mitsuba's).

use fgf_render::geometry::Geometry;
use fgf_render::ray::Ray;
use glam::Vec3A;
use std::process::ExitCode;
use std::time::Instant;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: trace_rays mesh.ply rays.f32 nearest|any [passes >= 1]";
    let (Some(mesh), Some(rays), Some(query)) = (args.get(1), args.get(2), args.get(3)) else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    let any = match query.as_str() {
        "nearest" => false,
        "any" => true,
        _ => {
            eprintln!("{usage}");
            return ExitCode::from(2);
        }
    };
    let passes = match args.get(4).map_or(Ok(5), |s| s.parse::<usize>()) {
        Ok(p) if p >= 1 => p,
        _ => {
            eprintln!("{usage}");
            return ExitCode::from(2);
        }
    };
    // The path comes in as a define, substituted after the XML is parsed,
    // so that no character of it needs escaping.
    let xml = r#"<scene version="3.0.0"><shape type="ply"><string name="filename" value="$mesh"/></shape></scene>"#;
    let defines = [("mesh".to_string(), mesh.clone())];
    let geom = match fgf_scene::load_str(xml, "trace_rays.xml", ".".as_ref(), &defines)
        .map_err(|e| e.to_string())
        .and_then(|d| Geometry::build(&d.shapes).map_err(|e| e.to_string()))
    {
        Ok(g) => g,
        Err(e) => {
            eprintln!("trace_rays: {e}");
            return ExitCode::from(2);
        }
    };
    let bytes = match std::fs::read(rays) {
        Ok(b) if b.len() % 24 == 0 => b,
        Ok(_) => {
            eprintln!("trace_rays: {rays}: the size is not a multiple of 24 bytes (6 f32 per ray)");
            return ExitCode::from(2);
        }
        Err(e) => {
            eprintln!("trace_rays: {rays}: {e}");
            return ExitCode::from(2);
        }
    };
    let f: Vec<f32> = bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    let rays: Vec<Ray> = f
        .chunks_exact(6)
        .map(|r| Ray {
            o: Vec3A::new(r[0], r[1], r[2]),
            d: Vec3A::new(r[3], r[4], r[5]),
        })
        .collect();
    let pass = || {
        let (mut hits, mut sum_t) = (0u64, 0f64);
        for r in &rays {
            if any {
                hits += geom.occluded(r, f32::INFINITY) as u64;
            } else if let Some(h) = geom.intersect(r, f32::INFINITY) {
                hits += 1;
                sum_t += h.t as f64;
            }
        }
        (hits, sum_t)
    };
    pass();
    let mut seconds = Vec::with_capacity(passes);
    let mut result = (0, 0.0);
    for _ in 0..passes {
        let t0 = Instant::now();
        result = std::hint::black_box(pass());
        seconds.push(t0.elapsed().as_secs_f64());
    }
    println!(
        r#"{{"seconds": {seconds:?}, "rays": {}, "hits": {}, "sum_t": {}}}"#,
        rays.len(),
        result.0,
        result.1
    );
    ExitCode::SUCCESS
}
