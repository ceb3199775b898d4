//! Transport tests of the non-exponential media (`docs/theory.md` §3–4):
//! furnace, uncollided slab, free-flight distributions (KS), single
//! scattering against quadrature, segment restarts at null boundaries,
//! macro density, reciprocity.
//!
//! Monte Carlo tolerances are `z · SE` with the standard error estimated
//! from the samples and fixed seeds. Each test states its `z` and the number
//! of comparisons it makes. With `z = 4.5` a single two-sided comparison
//! fails by chance with probability 6.8e-6: the 277 z-tests of the
//! path-level tests have a family error rate below 2e-3 (Bonferroni), the
//! 768 per-pixel tests of the camera-inside furnace below 5.3e-3, and the 28
//! Kolmogorov–Smirnov tests at the 0.1 % level below 0.03.
//!
//! The scenes disable Russian roulette (`rr_depth` 100000): with albedo 1
//! every path ends by leaving the medium, and each sample stays bounded.
//! Roulette capped at a survival probability of 0.95 would make the sample
//! values of deep furnace paths heavy-tailed (the throughput grows as
//! 0.95^-n), and the estimated standard errors unreliable.

mod common;

use common::{assert_close, load_xml, medium_xml};
use fgf_core::transmittance::{Davis, DavisWeinstein, Exponential, Fgf, Model, Transmittance};
use fgf_render::math::{sample_uniform_sphere, Sampler};
use fgf_render::medium::{DistanceEvent, Medium, SegmentEnd, SegmentStart};
use fgf_render::ray::Ray;
use fgf_render::spectrum::Spectrum;
use fgf_render::world::World;
use fgf_scene::{MediumDesc, SceneDesc};
use glam::Vec3A;

const Z: f64 = 4.5;

/// The media under test: (label, XML body of a `<medium>` without sigma_t,
/// albedo and kernel).
fn models() -> Vec<(&'static str, &'static str, &'static str)> {
    vec![
        (
            "fgf white",
            "fgf",
            r#"<float name="hurst" value="-0.5"/><float name="sw" value="4"/>"#,
        ),
        (
            "fgf pink",
            "fgf",
            r#"<float name="hurst" value="-0.1"/><float name="sw" value="4"/>"#,
        ),
        (
            "fgf 1-fBm",
            "fgf",
            r#"<float name="hurst" value="0.2"/><float name="sw" value="4"/><float name="length" value="1"/>"#,
        ),
        (
            "fgf 2-fBm",
            "fgf",
            r#"<float name="hurst" value="1.2"/><float name="sw" value="34"/><float name="length" value="1"/>"#,
        ),
        (
            "exponential",
            "nonexponential",
            r#"<string name="transmittance" value="exponential"/>"#,
        ),
        (
            "davis",
            "nonexponential",
            r#"<string name="transmittance" value="davis"/><float name="alpha" value="1.5"/>"#,
        ),
        (
            "davis_weinstein",
            "nonexponential",
            r#"<string name="transmittance" value="davis_weinstein"/><float name="h" value="0.8"/><float name="c" value="0.8"/>"#,
        ),
    ]
}

fn scene(body: &str) -> SceneDesc {
    load_xml(&format!(
        r#"<scene version="3.0.0">
        <integrator type="volpath"><integer name="max_depth" value="-1"/><integer name="rr_depth" value="100000"/></integrator>
        <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film></sensor>
        {body}
        </scene>"#
    ))
}

/// Mean and standard error of `n` samples of `f`, per channel.
fn estimate(
    n: u64,
    seed: u64,
    mut f: impl FnMut(&mut Sampler) -> Spectrum,
) -> ([f64; 3], [f64; 3]) {
    let (mut s1, mut s2) = ([0.0f64; 3], [0.0f64; 3]);
    for i in 0..n {
        let mut s = Sampler::new(seed, 0, i);
        let v = f(&mut s);
        for c in 0..3 {
            s1[c] += v[c] as f64;
            s2[c] += (v[c] as f64).powi(2);
        }
    }
    let nf = n as f64;
    let mean = s1.map(|x| x / nf);
    let se = [0, 1, 2]
        .map(|c| (((s2[c] / nf - mean[c] * mean[c]) * nf / (nf - 1.0)).max(0.0) / nf).sqrt());
    (mean, se)
}

/// The model a scene medium uses in channel `c` (for analytic targets).
fn model_of(d: &MediumDesc, c: usize) -> Model {
    use fgf_scene::TransmittanceDesc as T;
    let MediumDesc::NonExponential { sigma_t, model, .. } = d else {
        panic!("not non-exponential")
    };
    let s = sigma_t[c] as f64;
    match *model {
        T::Fgf { hurst, sw, length } => Fgf::new(s, hurst, sw, length).unwrap().into(),
        T::Exponential => Exponential::new(s).unwrap().into(),
        T::Davis { alpha } => Davis::new(s, alpha).unwrap().into(),
        T::DavisWeinstein { h, c } => DavisWeinstein::new(s, h, c).unwrap().into(),
    }
}

/// Furnace: a closed sphere of an albedo-1 medium under a constant
/// environment of radiance 1 returns radiance 1 along every ray, from inside
/// (camera in the medium) and from outside, under both kernels and every
/// model, grey and chromatic. 7 models × 2 kernels × 2 colours × 3 channels
/// = 84 comparisons, z = 4.5.
#[test]
fn furnace_returns_the_environment_radiance() {
    for kernel in ["energy_conserving", "reciprocal"] {
        for (label, ty, body) in models() {
            for sigma in ["2", "1, 2, 4"] {
                let m = medium_xml(ty, body, sigma, "1", kernel, r#"name="interior""#);
                let sc = scene(&format!(
                    r#"<emitter type="constant"/><shape type="sphere"><bsdf type="null"/>{m}</shape>"#
                ));
                let mut world = World::build(&sc).unwrap();
                world.camera_medium = Some(0);
                let (mean, se) = estimate(4000, 1, |s| {
                    let d = sample_uniform_sphere(s.next_2d());
                    let o = Vec3A::new(0.3, -0.2, 0.1);
                    world.li(Ray { o, d }, f32::INFINITY, s)
                });
                assert_close(
                    &format!("furnace {label} {kernel} sigma_t={sigma} inside"),
                    mean,
                    se,
                    [1.0; 3],
                    Z,
                );
            }
        }
    }
}

/// Uncollided transmission of a slab of thickness `d` seen from outside
/// (albedo 0, environment behind): `Tr(d)` under the energy-conserving
/// kernel, `T_ss(d)` under the reciprocal one (the same function: a segment
/// from a surface). A null plane inside the slab (same medium on both
/// sides) restarts the segment: `Tr(d/2)²`, not `Tr(d)` (`docs/theory.md` §4).
/// 7 models × 2 kernels × 2 setups × 3 channels = 84 comparisons, z = 4.5.
#[test]
fn slab_uncollided_transmission_is_t_ss() {
    let d = 0.6f32;
    for kernel in ["energy_conserving", "reciprocal"] {
        for (label, ty, body) in models() {
            for split in [false, true] {
                let m = medium_xml(ty, body, "1, 2, 4", "0", kernel, r#"id="m""#);
                let plane = if split {
                    r#"<shape type="rectangle"><transform name="to_world"><scale value="50"/></transform><bsdf type="null"/><ref name="interior" id="m"/><ref name="exterior" id="m"/></shape>"#
                } else {
                    ""
                };
                let sc = scene(&format!(
                    r#"<emitter type="constant"/>{m}
                    <shape type="cube"><transform name="to_world"><scale x="50" y="50" z="{}"/></transform><bsdf type="null"/><ref name="interior" id="m"/></shape>{plane}"#,
                    d / 2.0
                ));
                let world = World::build(&sc).unwrap();
                let (mean, se) = estimate(20000, 2, |s| {
                    world.li(
                        Ray {
                            o: Vec3A::new(0.0, 0.0, -2.0),
                            d: Vec3A::Z,
                        },
                        f32::INFINITY,
                        s,
                    )
                });
                let expected = [0, 1, 2].map(|c| {
                    let mo = model_of(&sc.media[0], c);
                    if split {
                        mo.surface_surface(d as f64 / 2.0).powi(2)
                    } else {
                        mo.surface_surface(d as f64)
                    }
                });
                assert_close(
                    &format!("slab {label} {kernel} split={split}"),
                    mean,
                    se,
                    expected,
                    Z,
                );
            }
        }
    }
}

/// The free flights and shadow transmittances of the medium itself, for
/// both segment starts: the probability of reaching `t_max` is `Tr`
/// (energy-conserving, either start), `T_ss` (reciprocal, surface start) or
/// `T_ms` (reciprocal, medium start); `transmittance` returns the same
/// functions; and the sampled distances follow `1 - T` (Kolmogorov–Smirnov,
/// grey media, critical value 1.95/√n for a 0.1% level per test).
/// 7 models × 2 kernels × 2 starts: 28 KS tests and 84 z-tests (z = 4.5),
/// family error rate < 0.03 + 6e-4.
#[test]
fn free_flights_follow_the_kernel() {
    let n = 20000u64;
    for kernel in ["energy_conserving", "reciprocal"] {
        for (label, ty, body) in models() {
            for start in [SegmentStart::Surface, SegmentStart::Medium] {
                let sc = scene(&format!(
                    r#"<shape type="sphere"><bsdf type="null"/>{}</shape>"#,
                    medium_xml(ty, body, "1, 2, 4", "0.5", kernel, r#"name="interior""#)
                ));
                let med = Medium::from_desc(&sc.media[0], 0).unwrap();
                let reciprocal_medium = kernel == "reciprocal" && start == SegmentStart::Medium;
                let ray = Ray {
                    o: Vec3A::ZERO,
                    d: Vec3A::X,
                };
                let t_max = 0.4f32;
                let expected = [0, 1, 2].map(|c| {
                    let mo = model_of(&sc.media[0], c);
                    if reciprocal_medium {
                        mo.medium_surface(t_max as f64)
                    } else {
                        mo.tr(t_max as f64)
                    }
                });
                let (mean, se) = estimate(n, 3, |s| {
                    let ds = med.sample_distance(&ray, t_max, start, s);
                    if ds.event == DistanceEvent::Surface {
                        ds.weight
                    } else {
                        Spectrum::ZERO
                    }
                });
                assert_close(
                    &format!("P(surface) {label} {kernel} {start:?}"),
                    mean,
                    se,
                    expected,
                    Z,
                );
                let mut s = Sampler::new(0, 0, 0);
                let tr = med.transmittance(&ray, t_max, start, SegmentEnd::Surface, &mut s);
                for c in 0..3 {
                    assert!(
                        (tr[c] as f64 - expected[c]).abs() <= 1e-5 * expected[c].max(1e-3),
                        "transmittance {label} {kernel} {start:?}"
                    );
                }

                // KS on a grey medium (one channel: the flight is that model's).
                let sc = scene(&format!(
                    r#"<shape type="sphere"><bsdf type="null"/>{}</shape>"#,
                    medium_xml(ty, body, "2", "0.5", kernel, r#"name="interior""#)
                ));
                let med = Medium::from_desc(&sc.media[0], 0).unwrap();
                let mo = model_of(&sc.media[0], 0);
                let mut ts: Vec<f64> = (0..n)
                    .map(|i| {
                        let mut s = Sampler::new(4, 0, i);
                        let ds = med.sample_distance(&ray, f32::INFINITY, start, &mut s);
                        if ds.event == DistanceEvent::Scatter {
                            ds.t as f64
                        } else {
                            f64::INFINITY
                        }
                    })
                    .collect();
                ts.sort_by(|a, b| a.partial_cmp(b).unwrap());
                let cdf = |t: f64| {
                    if reciprocal_medium {
                        1.0 - mo.medium_surface(t)
                    } else {
                        1.0 - mo.tr(t)
                    }
                };
                let mut dmax = 0.0f64;
                for (i, &t) in ts.iter().enumerate() {
                    let f = if t.is_finite() { cdf(t) } else { 1.0 };
                    dmax = dmax
                        .max((f - i as f64 / n as f64).abs())
                        .max((f - (i + 1) as f64 / n as f64).abs());
                }
                assert!(
                    dmax * (n as f64).sqrt() < 1.95,
                    "KS {label} {kernel} {start:?}: D = {dmax}"
                );
            }
        }
    }
}

/// Composite Gauss–Legendre (4 nodes per panel) of `f` over `[a, b]`.
fn quad(a: f64, b: f64, panels: usize, f: impl Fn(f64) -> f64) -> f64 {
    const X: [f64; 4] = [
        -0.861_136_311_594_052_6,
        -0.339_981_043_584_856_3,
        0.339_981_043_584_856_3,
        0.861_136_311_594_052_6,
    ];
    const W: [f64; 4] = [
        0.347_854_845_137_453_9,
        0.652_145_154_862_546_1,
        0.652_145_154_862_546_1,
        0.347_854_845_137_453_9,
    ];
    let h = (b - a) / panels as f64;
    let mut sum = 0.0;
    for p in 0..panels {
        let m = a + (p as f64 + 0.5) * h;
        for k in 0..4 {
            sum += W[k] * f(m + 0.5 * h * X[k]);
        }
    }
    sum * 0.5 * h
}

/// Single scattering in a slab (`max_depth = 2`: uncollided + one isotropic
/// scattering event, environment radiance 1), against quadrature of the
/// kernel: `Tr(d) + Λ ∫_0^d p(t) ½∫_0^1 [S((d-t)/μ) + S(t/μ)] dμ dt` with
/// `S = Tr` (energy-conserving) or `T_ms` (reciprocal). 4 models × 2
/// kernels × 1 channel = 8 comparisons, z = 4.5; the quadrature is
/// converged to < 1e-6.
#[test]
fn single_scattering_slab_matches_quadrature() {
    let (d, albedo) = (0.8f64, 0.9f64);
    let picks = [1usize, 3, 5, 6];
    for kernel in ["energy_conserving", "reciprocal"] {
        for &i in &picks {
            let (label, ty, body) = models()[i];
            let m = medium_xml(
                ty,
                body,
                "2",
                &albedo.to_string(),
                kernel,
                r#"name="interior""#,
            );
            let mut sc = scene(&format!(
                r#"<emitter type="constant"/><shape type="cube"><transform name="to_world"><scale x="1000" y="1000" z="{}"/></transform><bsdf type="null"/>{m}</shape>"#,
                d / 2.0
            ));
            sc.integrator.max_depth = 2;
            let world = World::build(&sc).unwrap();
            let (mean, se) = estimate(40000, 5, |s| {
                world.li(
                    Ray {
                        o: Vec3A::new(0.0, 0.0, -2.0),
                        d: Vec3A::Z,
                    },
                    f32::INFINITY,
                    s,
                )
            });
            let mo = model_of(&sc.media[0], 0);
            let s_fn = |l: f64| {
                if kernel == "reciprocal" {
                    mo.medium_surface(l)
                } else {
                    mo.tr(l)
                }
            };
            let inner = |t: f64| 0.5 * quad(0.0, 1.0, 200, |mu| s_fn((d - t) / mu) + s_fn(t / mu));
            let expected = mo.tr(d) + albedo * quad(0.0, d, 200, |t| mo.pdf(t) * inner(t));
            assert_close(
                &format!("single scatter {label} {kernel}"),
                mean,
                se,
                [expected; 3],
                Z,
            );
        }
    }
}

/// A macro density on a trilinear ramp `ρ = 2 N u_x` (voxel centres
/// `(i+½)/N` hold `2i+1`), clamped to `ρ(½/N)` and `ρ(1-½/N)` at the
/// borders: the shadow transmittance is `Tr(s)` with the exact
/// `s = ∫ρ`, and the probability of reaching `t_max` matches it
/// (3 z-tests, z = 4.5).
#[test]
fn macro_density_uses_the_exact_optical_path() {
    let n = 8usize;
    let dir = tempfile::tempdir().unwrap();
    let data: Vec<f32> = (0..n).map(|i| (2 * i + 1) as f32).collect();
    let grid = fgf_io::vol::VolGrid {
        shape: [n, 1, 1],
        channels: 1,
        bbox: [0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
        data,
    };
    let path = dir.path().join("ramp.vol");
    fgf_io::vol::write_vol(&path, &grid).unwrap();
    let m = format!(
        r#"<medium type="fgf" name="interior"><float name="hurst" value="-0.2"/><float name="sw" value="2"/><float name="sigma_t" value="1.5"/><float name="albedo" value="0.5"/>
        <volume type="gridvolume" name="density"><string name="filename" value="{}"/></volume></medium>"#,
        path.display()
    );
    let sc = scene(&format!(
        r#"<shape type="cube"><transform name="to_world"><scale value="3"/></transform><bsdf type="null"/>{m}</shape>"#
    ));
    let med = Medium::from_desc(&sc.media[0], 0).unwrap();
    let mo = model_of(&sc.media[0], 0);
    // Along x through the middle of the unit cube, from outside (x = -0.5).
    let ray = Ray {
        o: Vec3A::new(-0.5, 0.5, 0.5),
        d: Vec3A::X,
    };
    let h = 0.5 / n as f64;
    // s(x) for the clamped ramp ρ(u) = 2 N clamp(u, h, 1-h), u in [0, 1].
    let s_of = |x: f64| {
        let rho = |u: f64| 2.0 * n as f64 * u.clamp(h, 1.0 - h);
        quad(0.0, x.clamp(0.0, 1.0), 64, rho)
    };
    for t_end in [0.7f64, 1.2, 3.0] {
        let mut s = Sampler::new(0, 0, 0);
        let tr = med
            .transmittance(
                &ray,
                t_end as f32,
                SegmentStart::Surface,
                SegmentEnd::Surface,
                &mut s,
            )
            .x as f64;
        let expected = mo.tr(s_of(t_end - 0.5));
        assert!(
            (tr - expected).abs() < 1e-5 * expected.max(1e-3),
            "t_end {t_end}: {tr} vs {expected}"
        );
        let (mean, se) = estimate(20000, 6, |s| {
            let ds = med.sample_distance(&ray, t_end as f32, SegmentStart::Surface, s);
            if ds.event == DistanceEvent::Surface {
                ds.weight
            } else {
                Spectrum::ZERO
            }
        });
        assert_close(
            &format!("density P(surface) t_end {t_end}"),
            mean,
            se,
            [expected; 3],
            Z,
        );
    }
}

/// Reciprocity: two small black spheres inside a sphere of medium; one is a
/// Lambertian emitter (radiance 1), the other a probe measuring the
/// cosine-weighted incident radiance averaged over its surface (the
/// normalised flux it receives); then the roles are swapped. Both ends are
/// surfaces, so under the reciprocal kernel the two values are equal; they
/// are compared within z · SE (z = 4.5, 2 comparisons). The
/// energy-conserving kernel's difference is printed: it is expected to
/// exist (`docs/theory.md` §4). Area lights (not point lights) keep the
/// variance finite: next-event estimation towards a point light from
/// scattering vertices near it has infinite variance.
#[test]
fn reciprocal_kernel_is_reciprocal() {
    // One sphere at the centre, the other near the medium's boundary: the
    // energy-conserving kernel's asymmetry comes from the boundary (in an
    // unbounded homogeneous medium both directions integrate to the same
    // value).
    let (a, b, r) = (
        Vec3A::new(0.0, 0.0, 0.0),
        Vec3A::new(0.7, 0.0, 0.0),
        0.25f32,
    );
    let davis = r#"<string name="transmittance" value="davis"/><float name="alpha" value="0.5"/>"#;
    for (label, ty, body) in [models()[1], ("davis alpha=0.5", "nonexponential", davis)] {
        for kernel in ["reciprocal", "energy_conserving"] {
            let run = |light: Vec3A, probe: Vec3A| {
                let m = medium_xml(ty, body, "1.5", "0.9", kernel, r#"id="m""#);
                let ball = |c: Vec3A, emit: bool| {
                    format!(
                        r#"<shape type="sphere"><point name="center" x="{}" y="{}" z="{}"/><float name="radius" value="{r}"/><bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf><ref name="exterior" id="m"/>{}</shape>"#,
                        c.x,
                        c.y,
                        c.z,
                        if emit {
                            r#"<emitter type="area"/>"#
                        } else {
                            ""
                        }
                    )
                };
                let sc = scene(&format!(
                    r#"{m}<shape type="sphere"><bsdf type="null"/><ref name="interior" id="m"/></shape>{}{}"#,
                    ball(light, true),
                    ball(probe, false)
                ));
                let mut world = World::build(&sc).unwrap();
                world.camera_medium = Some(0);
                estimate(100000, 7, |s| {
                    let n = sample_uniform_sphere(s.next_2d());
                    let d = fgf_render::math::Frame::from_normal(n)
                        .to_world(fgf_render::math::sample_cosine_hemisphere(s.next_2d()));
                    let o = fgf_render::ray::offset_point(probe + n * r, n, d);
                    world.li(Ray { o, d }, f32::INFINITY, s)
                })
            };
            let (m1, se1) = run(a, b);
            let (m2, se2) = run(b, a);
            let diff = m1[0] - m2[0];
            let se = (se1[0].powi(2) + se2[0].powi(2)).sqrt();
            eprintln!("reciprocity {label} {kernel}: light a → probe b {:.5} ± {:.5}, swapped {:.5} ± {:.5}, difference {:.2} SE", m1[0], se1[0], m2[0], se2[0], diff / se);
            if kernel == "reciprocal" {
                assert!(
                    diff.abs() <= Z * se,
                    "{label}: not reciprocal: {} vs {} (SE {se})",
                    m1[0],
                    m2[0]
                );
            }
        }
    }
}

/// A camera inside the medium (the sensor's nested `medium`), through the
/// whole renderer: the furnace image is 1 in every pixel. 2 models × 2
/// kernels × 8·8·3 values, z = 4.5 each (family error rate < 6e-3).
/// Russian roulette is off, as in the other furnace.
#[test]
fn camera_inside_a_medium_renders_the_furnace() {
    for (label, ty, body) in [models()[1], models()[5]] {
        for kernel in ["energy_conserving", "reciprocal"] {
            let m = medium_xml(ty, body, "1, 2, 4", "1", kernel, r#"id="m""#);
            let xml = format!(
                r#"<scene version="3.0.0">
                <integrator type="volpath"><integer name="max_depth" value="-1"/><integer name="rr_depth" value="100000"/></integrator>
                {m}
                <sensor type="perspective"><float name="fov" value="60"/><ref name="medium" id="m"/>
                    <sampler type="independent"><integer name="sample_count" value="256"/></sampler>
                    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
                <emitter type="constant"/>
                <shape type="sphere"><float name="radius" value="2"/><bsdf type="null"/><ref name="interior" id="m"/></shape>
                </scene>"#
            );
            let sc = fgf_scene::load_str(&xml, "t.xml", std::path::Path::new("."), &[]).unwrap();
            let opts = fgf_render::RenderOptions {
                seed: Some(3),
                variance: true,
                ..Default::default()
            };
            let out = fgf_render::render(&sc, &opts, &fgf_core::NoProgress).unwrap();
            let var = out.variance.unwrap();
            for (i, (&v, &s2)) in out.image.iter().zip(&var).enumerate() {
                let se = (s2 as f64).sqrt();
                assert!(
                    (v as f64 - 1.0).abs() <= Z * se + 1e-5,
                    "{label} {kernel} value {i}: {v} (SE {se})"
                );
            }
        }
    }
}

/// Furnace with a macro density: an albedo-1 medium whose density grid
/// (random values in [0, 3], trilinear, filling the sphere's box) varies
/// along every ray still returns radiance 1, under both kernels, for pink
/// noise and Davis, chromatic. 2 × 2 × 3 = 12 comparisons, z = 4.5.
#[test]
fn furnace_with_a_macro_density() {
    let dir = tempfile::tempdir().unwrap();
    let n = 6usize;
    let mut s = Sampler::new(9, 0, 0);
    let data: Vec<f32> = (0..n * n * n).map(|_| 3.0 * s.next_1d()).collect();
    let grid = fgf_io::vol::VolGrid {
        shape: [n, n, n],
        channels: 1,
        bbox: [-1.0, -1.0, -1.0, 1.0, 1.0, 1.0],
        data,
    };
    let path = dir.path().join("rho.vol");
    fgf_io::vol::write_vol(&path, &grid).unwrap();
    let density = format!(
        r#"<volume type="gridvolume" name="density"><string name="filename" value="{}"/><boolean name="use_grid_bbox" value="true"/></volume>"#,
        path.display()
    );
    for (label, ty, body) in [models()[1], models()[5]] {
        for kernel in ["energy_conserving", "reciprocal"] {
            let m = format!(
                r#"<medium type="{ty}" name="interior">{body}{density}<rgb name="sigma_t" value="1, 2, 3"/><float name="albedo" value="1"/><string name="kernel" value="{kernel}"/></medium>"#
            );
            let sc = scene(&format!(
                r#"<emitter type="constant"/><shape type="sphere"><bsdf type="null"/>{m}</shape>"#
            ));
            let mut world = World::build(&sc).unwrap();
            world.camera_medium = Some(0);
            let (mean, se) = estimate(4000, 10, |s| {
                let d = sample_uniform_sphere(s.next_2d());
                world.li(
                    Ray {
                        o: Vec3A::new(0.1, 0.2, -0.3),
                        d,
                    },
                    f32::INFINITY,
                    s,
                )
            });
            assert_close(
                &format!("density furnace {label} {kernel}"),
                mean,
                se,
                [1.0; 3],
                Z,
            );
        }
    }
}
