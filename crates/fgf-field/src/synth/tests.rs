//! Tests of the whole synthesis against a plain FFT reference, across
//! thread counts and precisions, and of its validation.

use super::plan::next_smooth;
use super::*;
use crate::noise::{stream, Purpose};
use fgf_core::{Cancelled, NoProgress};
use rand::Rng;
use rand_distr::StandardNormal;
use rustfft::num_complex::Complex;
use rustfft::FftPlanner;

/// Straightforward reference: full complex FFT of the same noise on the
/// padded grid, filter, inverse, crop. Independent of the blocked,
/// in-place pipeline.
fn reference(p: &SynthParams) -> Vec<f64> {
    let plan = Plan::new(p).unwrap();
    let [n0, n1, n2] = plan.pad;
    let mut a: Vec<Complex<f64>> = Vec::with_capacity(n0 * n1 * n2);
    for r in 0..n0 * n1 {
        let mut rng = stream(p.seed, Purpose::GridRow, r as u64);
        for _ in 0..n2 {
            a.push(Complex::new(rng.sample::<f64, _>(StandardNormal), 0.0));
        }
    }
    let dims = [n0, n1, n2];
    let transform = |a: &mut Vec<Complex<f64>>, inverse: bool| {
        let mut planner = FftPlanner::<f64>::new();
        for ax in 0..3 {
            let n = dims[ax];
            let fft = if inverse {
                planner.plan_fft_inverse(n)
            } else {
                planner.plan_fft_forward(n)
            };
            let stride: usize = dims[ax + 1..].iter().product();
            let outer: usize = dims[..ax].iter().product();
            for o in 0..outer {
                for i in 0..stride {
                    let s = o * n * stride + i;
                    let mut line: Vec<_> = (0..n).map(|j| a[s + j * stride]).collect();
                    fft.process(&mut line);
                    for j in 0..n {
                        a[s + j * stride] = line[j];
                    }
                }
            }
        }
    };
    transform(&mut a, false);
    for iz in 0..n0 {
        for iy in 0..n1 {
            for ix in 0..n2 {
                let k2: f64 = [(iz, n0), (iy, n1), (ix, n2)]
                    .iter()
                    .map(|&(i, n)| plan.wavenumber(i, n).powi(2))
                    .sum();
                let nyq = plan.zero_nyquist
                    && [(iz, n0), (iy, n1), (ix, n2)]
                        .iter()
                        .any(|&(i, n)| Plan::is_nyquist(i, n));
                let f = if k2 == 0.0 || nyq {
                    0.0
                } else {
                    plan.amp * k2.powf(-plan.s / 2.0)
                };
                a[(iz * n1 + iy) * n2 + ix] *= f;
            }
        }
    }
    transform(&mut a, true);
    let [o0, o1, o2] = plan.out;
    let mut out = Vec::new();
    for z in 0..o0 {
        for y in 0..o1 {
            for x in 0..o2 {
                out.push(a[(z * n1 + y) * n2 + x].re);
            }
        }
    }
    out
}

fn f64_data(f: &Field) -> Vec<f64> {
    (0..f.data.len()).map(|i| f.data.get(i)).collect()
}

#[test]
fn pipeline_matches_plain_fft_reference() {
    let cases: Vec<(Vec<usize>, f64, Option<f64>)> = vec![
        (vec![9], -0.3, None),
        (vec![4, 7], -0.6, None),
        (vec![5, 6, 7], -0.4, None),
        (vec![6, 5, 40], -1.5, None),
        (vec![3, 4, 5], 0.7, Some(1.7)),
        (vec![7, 3], 1.4, Some(2.0)),
        // Enough z-slabs for the slab-fused passes (n0 >= 4 threads).
        (vec![40, 6, 10], -0.3, None),
        (vec![24, 4, 6], 0.7, Some(1.7)),
        // Cubic 3D grids use the |k|^(-s) table.
        (vec![8, 8, 8], -0.4, None),
        (vec![6, 6, 6], 1.3, Some(2.0)),
    ];
    for (shape, h, padding) in cases {
        let mut p = SynthParams::new(&shape, h);
        p.seed = 11;
        p.spacing = 0.37;
        p.sw = 2.5;
        p.padding = padding;
        p.anchor = Anchor::None;
        p.precision = Precision::F64;
        let got = f64_data(&synthesize(&p, &NoProgress).unwrap());
        let want = reference(&p);
        let scale = want.iter().map(|v| v * v).sum::<f64>().sqrt() / (want.len() as f64).sqrt();
        for (g, w) in got.iter().zip(&want) {
            assert!(
                (g - w).abs() <= 1e-12 * scale.max(1e-300) * 10.0,
                "{shape:?} H={h}: {g} vs {w}"
            );
        }
    }
}

#[test]
fn bit_identical_for_any_thread_count() {
    // n0 = 10: slab-fused with 1 thread, not with 3 (see fuse_slabs).
    for (shape, h) in [
        (vec![12usize, 10, 33], -0.2),
        (vec![17, 20], 1.3),
        (vec![8, 9, 10], 2.5),
        (vec![10, 9, 8], -0.7),
    ] {
        let mut p = SynthParams::new(&shape, h);
        p.seed = 5;
        p.anchor = Anchor::Center;
        let runs: Vec<FieldData> = [1, 2, 3]
            .iter()
            .map(|&t| {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(t)
                    .build()
                    .unwrap();
                pool.install(|| synthesize(&p, &NoProgress).unwrap().data)
            })
            .collect();
        assert_eq!(runs[0], runs[1], "{shape:?}");
        assert_eq!(runs[0], runs[2], "{shape:?}");
    }
}

#[test]
fn f32_and_f64_agree_to_f32_rounding() {
    let mut p = SynthParams::new(&[16, 12, 10], -0.3);
    p.seed = 2;
    let a = f64_data(&synthesize(&p, &NoProgress).unwrap());
    p.precision = Precision::F64;
    let b = f64_data(&synthesize(&p, &NoProgress).unwrap());
    let rms = (b.iter().map(|v| v * v).sum::<f64>() / b.len() as f64).sqrt();
    let err = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    // f32 round-off of a few FFT passes: ~1e-7 relative per pass.
    assert!(err < 1e-5 * rms, "err {err} rms {rms}");
}

#[test]
fn anchored_field_vanishes_at_anchor_and_differs_by_a_polynomial() {
    for (shape, h, anchor) in [
        (vec![40usize], 0.6, Anchor::Corner),
        (vec![24, 20], 1.5, Anchor::Center),
        (vec![10, 12, 9], 2.4, Anchor::Index(vec![3, 4, 5])),
    ] {
        let mut p = SynthParams::new(&shape, h);
        p.precision = Precision::F64;
        p.seed = 9;
        p.anchor = anchor;
        let f = synthesize(&p, &NoProgress).unwrap();
        p.anchor = Anchor::None;
        let g = synthesize(&p, &NoProgress).unwrap();
        let a = f.anchor.clone().unwrap();
        let mut idx = 0;
        for (ax, &i) in a.iter().enumerate() {
            idx = idx * shape[ax] + i;
        }
        let rms = (f64_data(&g).iter().map(|v| v * v).sum::<f64>() / g.data.len() as f64).sqrt();
        assert!(
            f.data.get(idx).abs() < 1e-10 * rms,
            "{shape:?}: value at anchor {}",
            f.data.get(idx)
        );
        // g - f is the Taylor polynomial of degree k-1: its k-th finite
        // differences along the last axis vanish.
        let k = h.ceil() as usize;
        let diff: Vec<f64> = (0..f.data.len())
            .map(|i| g.data.get(i) - f.data.get(i))
            .collect();
        let nx = *shape.last().unwrap();
        for row in diff.chunks(nx) {
            let mut d = row.to_vec();
            for _ in 0..k {
                d = d.windows(2).map(|w| w[1] - w[0]).collect();
            }
            assert!(d.iter().all(|v| v.abs() < 1e-9 * rms), "{shape:?}: {d:?}");
        }
    }
}

#[test]
fn invalid_parameters_are_named() {
    let bad = |f: &dyn Fn(&mut SynthParams), name: &str| {
        let mut p = SynthParams::new(&[8, 8], -0.3);
        f(&mut p);
        let e = synthesize(&p, &NoProgress).unwrap_err().to_string();
        assert!(e.contains(name), "{e}");
    };
    bad(&|p| p.hurst = -1.2, "hurst");
    bad(&|p| p.hurst = 1.0, "hurst");
    bad(&|p| p.hurst = 3.0, "hurst");
    bad(&|p| p.hurst = f64::NAN, "hurst");
    bad(&|p| p.sw = 0.0, "sw");
    bad(&|p| p.spacing = -1.0, "spacing");
    bad(&|p| p.shape = vec![], "shape");
    bad(&|p| p.shape = vec![2, 2, 2, 2], "shape");
    bad(&|p| p.shape = vec![0, 4], "shape");
    bad(&|p| p.padding = Some(0.5), "padding");
    bad(
        &|p| {
            p.hurst = 0.5;
            p.anchor = Anchor::Index(vec![8, 0])
        },
        "anchor",
    );
    // White noise at exactly H = -d/2 is valid.
    let p = SynthParams::new(&[8, 8], -1.0);
    assert!(synthesize(&p, &NoProgress).is_ok());
}

#[test]
fn impossible_allocation_is_refused_before_allocating() {
    let p = SynthParams::new(&[100_000, 100_000, 100_000], -0.3);
    match synthesize(&p, &NoProgress) {
        Err(FieldError::OutOfMemory { needed, .. }) => assert!(needed > 1 << 40),
        other => panic!("expected OutOfMemory, got {other:?}"),
    }
    let msg = synthesize(&p, &NoProgress).unwrap_err().to_string();
    assert!(msg.contains("MemAvailable") && msg.contains("GiB"), "{msg}");
}

/// A cancelled job returns the shared `Cancelled` error, and an invalid
/// parameter keeps its structured `ParamError`.
#[test]
fn cancellation_and_parameter_errors_keep_their_types() {
    struct Stop;
    impl Progress for Stop {
        fn inc(&self, _n: u64) {}
        fn cancelled(&self) -> bool {
            true
        }
    }
    let p = SynthParams::new(&[16, 16], -0.3);
    match synthesize(&p, &Stop) {
        Err(e @ FieldError::Cancelled(Cancelled)) => assert_eq!(e.to_string(), "interrupted"),
        other => panic!("expected Cancelled, got {other:?}"),
    }
    let mut p = SynthParams::new(&[16, 16], -0.3);
    p.sw = -1.0;
    match synthesize(&p, &NoProgress) {
        Err(FieldError::Param(e)) => assert_eq!(e.name, "sw"),
        other => panic!("expected Param, got {other:?}"),
    }
}

#[test]
fn next_smooth_sizes() {
    assert_eq!(next_smooth(1), 1);
    assert_eq!(next_smooth(11), 12);
    assert_eq!(next_smooth(97), 98);
    assert_eq!(next_smooth(512), 512);
}
