//! Nanoseconds per transmittance evaluation and per free-flight sample, for
//! each model, through the `Model` enum the renderer uses.
//!
//! Run: `bash benchmarks/transmittance.sh` (or
//! `cargo bench -p fgf-core --bench transmittance`). Each iteration
//! processes a batch of 1024 distances or variates, so divan's per-iteration
//! time divided by 1024 is the cost of one call; the script prints that.

use divan::black_box;
use fgf_core::transmittance::{Davis, DavisWeinstein, Exponential, Fgf, Model, Transmittance};

const BATCH: usize = 1024;

fn main() {
    divan::main();
}

fn model(name: &str) -> Model {
    match name {
        "exponential" => Exponential::new(4.0).unwrap().into(),
        "fgf_white" => Fgf::new(4.0, -0.5, 4.0, None).unwrap().into(),
        "fgf_pink" => Fgf::new(4.0, -0.1, 4.0, None).unwrap().into(),
        "fgf_2fbm" => Fgf::new(4.0, 1.2, 34.0, Some(1.0)).unwrap().into(),
        "davis" => Davis::new(4.0, 4.0).unwrap().into(),
        "davis_weinstein" => DavisWeinstein::new(4.0, 0.9, 0.78).unwrap().into(),
        _ => unreachable!(),
    }
}

const MODELS: &[&str] = &[
    "exponential",
    "fgf_white",
    "fgf_pink",
    "fgf_2fbm",
    "davis",
    "davis_weinstein",
];

/// Distances spread over a few mean free paths, and variates on a
/// low-discrepancy grid in [0, 1).
fn inputs() -> (Vec<f64>, Vec<f64>) {
    let ts = (0..BATCH)
        .map(|i| 3.0 * (i as f64 + 0.5) / BATCH as f64)
        .collect();
    let us = (0..BATCH)
        .map(|i| ((i as f64) * 0.618_033_988_749_895).fract())
        .collect();
    (ts, us)
}

/// Times `f(model, x)` summed over a batch of inputs (a generic closure, so
/// it is inlined as a hand-written loop would be).
fn bench_batch(
    bencher: divan::Bencher,
    name: &str,
    xs: Vec<f64>,
    f: impl Fn(&Model, f64) -> f64 + Sync,
) {
    let m = model(name);
    bencher.bench(|| {
        let m = black_box(m);
        xs.iter().map(|&x| f(&m, black_box(x))).sum::<f64>()
    });
}

#[divan::bench(args = MODELS)]
fn tr(bencher: divan::Bencher, name: &str) {
    bench_batch(bencher, name, inputs().0, |m, t| m.tr(t));
}

#[divan::bench(args = MODELS)]
fn pdf(bencher: divan::Bencher, name: &str) {
    bench_batch(bencher, name, inputs().0, |m, t| m.pdf(t));
}

#[divan::bench(args = MODELS)]
fn sample_surface(bencher: divan::Bencher, name: &str) {
    bench_batch(bencher, name, inputs().1, |m, u| m.sample_surface(u));
}

#[divan::bench(args = MODELS)]
fn sample_medium(bencher: divan::Bencher, name: &str) {
    bench_batch(bencher, name, inputs().1, |m, u| m.sample_medium(u));
}
