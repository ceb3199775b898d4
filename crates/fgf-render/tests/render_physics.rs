//! Physical checks of the renderer with analytic answers: furnace tests,
//! uncollided slab transmittance, single scattering of a thin slab against
//! quadrature, `max_depth` semantics, determinism across thread counts and
//! cancellation.
//!
//! Monte Carlo tolerances: each statistical assertion checks
//! `|estimate - expected| ≤ z·SE` with `z = 4` (two-sided false-alarm rate
//! 6.3e-5 per assertion under a normal approximation) and SE taken from the
//! renderer's own per-pixel variance of the mean (`RenderOptions::variance`).
//! This file makes 23 such assertions (channels included), so the family
//! error rate is below 23 × 6.3e-5 ≈ 1.5e-3 (Bonferroni). Seeds are fixed,
//! so a pass is reproducible.

mod common;

use common::{assert_close, reference_scene};
use fgf_core::{NoProgress, Progress};
use fgf_io::vol::VolGrid;
use fgf_render::{render, RenderError, RenderOptions};
use fgf_scene::*;
use glam::{Mat4, Vec3};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

const Z: f64 = 4.0;

fn sensor(origin: Vec3, target: Vec3, up: Vec3, fov: f32, res: u32, spp: u32) -> SensorDesc {
    // Mitsuba's lookat: z = dir, x = normalize(cross(up, dir)), y = cross(z, x).
    let dir = (target - origin).normalize();
    let left = up.cross(dir).normalize();
    let new_up = dir.cross(left);
    let to_world = Mat4::from_cols(
        left.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        origin.extend(1.0),
    );
    SensorDesc {
        to_world,
        fov,
        fov_axis: FovAxis::X,
        principal_point: [0.0, 0.0],
        near_clip: 1e-3,
        far_clip: 1e4,
        width: res,
        height: res,
        rfilter: FilterDesc::Box,
        spp,
        seed: 7,
        medium: None,
    }
}

fn scene(max_depth: i32, sensor: SensorDesc) -> SceneDesc {
    SceneDesc {
        source: "test".into(),
        integrator: IntegratorDesc {
            kind: IntegratorKind::Volpath,
            max_depth,
            rr_depth: 5,
            hide_emitters: false,
        },
        sensor,
        shapes: Vec::new(),
        bsdfs: vec![
            BsdfDesc::Null,
            BsdfDesc::Diffuse {
                reflectance: [0.5; 3],
            },
        ],
        emitters: Vec::new(),
        media: Vec::new(),
    }
}

fn cube(to_world: Mat4, interior: Option<MediumId>) -> ShapeDesc {
    ShapeDesc {
        name: "cube".into(),
        geometry: GeometryDesc::Cube,
        to_world,
        flip_normals: false,
        bsdf: 0,
        emitter: None,
        interior,
        exterior: None,
    }
}

/// Render `s` and return the mean over all pixels per channel and its
/// standard error (pixels are independent, so the variances of the pixel
/// means add).
fn image_mean(s: &SceneDesc) -> ([f64; 3], [f64; 3]) {
    let out = render(s, &opts(), &NoProgress).unwrap();
    let n = (out.width * out.height) as f64;
    let var = out.variance.as_ref().expect("variance requested");
    let mut m = [0.0; 3];
    let mut se = [0.0; 3];
    for c in 0..3 {
        m[c] = out
            .image
            .iter()
            .skip(c)
            .step_by(3)
            .map(|&v| v as f64)
            .sum::<f64>()
            / n;
        se[c] = (var
            .iter()
            .skip(c)
            .step_by(3)
            .map(|&v| v as f64)
            .sum::<f64>())
        .sqrt()
            / n;
    }
    (m, se)
}

fn opts() -> RenderOptions {
    RenderOptions {
        variance: true,
        ..Default::default()
    }
}

fn constant_env(s: &mut SceneDesc, l: f32) {
    s.emitters.push(EmitterDesc::Constant { radiance: [l; 3] });
}

/// A furnace: under a `constant` environment of radiance `l` the image
/// mean of `s` (whose media have albedo 1) is `l`.
fn assert_furnace(label: &str, s: &mut SceneDesc, l: f32) {
    constant_env(s, l);
    let (m, se) = image_mean(s);
    assert_close(label, m, se, [l as f64; 3], Z);
}

fn random_grid(res: usize, seed: u64, max: f32) -> Arc<VolGrid> {
    let mut x = seed;
    let data = (0..res * res * res)
        .map(|_| {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((x >> 40) as f32 / (1u64 << 24) as f32).powi(2) * max
        })
        .collect();
    Arc::new(VolGrid {
        shape: [res; 3],
        channels: 1,
        bbox: [0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
        data,
    })
}

/// Albedo-1 homogeneous medium (chromatic extinction, HG phase) in a
/// `constant` environment of radiance 0.7: every pixel's expected value is
/// 0.7 (no absorption anywhere, and the environment is the only emitter).
#[test]
fn furnace_homogeneous_returns_environment_radiance() {
    let mut s = scene(
        -1,
        sensor(Vec3::new(0.0, 0.5, 4.0), Vec3::ZERO, Vec3::Y, 35.0, 24, 64),
    );
    s.media.push(MediumDesc::Homogeneous {
        sigma_t: [2.0, 4.0, 8.0],
        albedo: [1.0; 3],
        phase: PhaseDesc::Hg { g: 0.4 },
        sample_emitters: true,
    });
    s.shapes.push(cube(Mat4::IDENTITY, Some(0)));
    assert_furnace("homogeneous furnace", &mut s, 0.7);
}

/// The same with the camera inside the medium (the sensor's medium).
#[test]
fn furnace_with_camera_inside_medium() {
    let mut sen = sensor(
        Vec3::new(0.1, 0.2, 0.3),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::Y,
        60.0,
        16,
        64,
    );
    sen.medium = Some(0);
    let mut s = scene(-1, sen);
    s.media.push(MediumDesc::Homogeneous {
        sigma_t: [1.5; 3],
        albedo: [1.0; 3],
        phase: PhaseDesc::Isotropic,
        sample_emitters: true,
    });
    s.shapes.push(cube(Mat4::IDENTITY, Some(0)));
    assert_furnace("furnace, camera inside", &mut s, 1.3);
}

/// Albedo-1 grid medium with a high-contrast random density (delta tracking
/// on the majorant grid, ratio tracking for shadow rays).
#[test]
fn furnace_heterogeneous_returns_environment_radiance() {
    let mut s = scene(
        -1,
        sensor(Vec3::new(0.3, 0.8, 3.5), Vec3::ZERO, Vec3::Y, 40.0, 24, 32),
    );
    let grid = GridVolumeDesc {
        grid: random_grid(20, 3, 12.0),
        // The unit cube [0,1]³ onto the shape's [-1,1]³.
        to_world: Mat4::from_translation(Vec3::splat(-1.0)) * Mat4::from_scale(Vec3::splat(2.0)),
        use_grid_bbox: false,
        filter: GridFilter::Trilinear,
        wrap: fgf_scene::WrapMode::Clamp,
    };
    s.media.push(MediumDesc::Heterogeneous {
        sigma_t: VolumeDesc::Grid(grid),
        albedo: VolumeDesc::Constant([1.0; 3]),
        scale: 1.0,
        phase: PhaseDesc::Isotropic,
        sample_emitters: true,
    });
    s.shapes.push(cube(Mat4::IDENTITY, Some(0)));
    assert_furnace("heterogeneous furnace", &mut s, 0.9);
}

/// A purely absorbing slab of thickness `d` (z ∈ [0, d]) in front of a
/// `constant` environment: seen along the slab normal with a 0.5° field of
/// view, each pixel is `L·exp(-σ_t d / cos θ)`; cos θ ≥ 0.99999 so using
/// `cos θ = 1` errs by < 1e-5 relative, far below the tolerance.
fn slab_transmittance(medium: MediumDesc, sigma_t: [f64; 3]) {
    let d = 0.5f32;
    let mut s = scene(
        -1,
        sensor(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, Vec3::Y, 0.5, 8, 256),
    );
    s.media.push(medium);
    let slab = Mat4::from_translation(Vec3::new(0.0, 0.0, d / 2.0))
        * Mat4::from_scale(Vec3::new(10.0, 10.0, d / 2.0));
    s.shapes.push(cube(slab, Some(0)));
    constant_env(&mut s, 2.0);
    let (m, se) = image_mean(&s);
    let expected = sigma_t.map(|st| 2.0 * (-st * d as f64).exp());
    assert_close("slab transmittance", m, se, expected, Z);
}

#[test]
fn uncollided_slab_transmittance_homogeneous_chromatic() {
    let st = [0.5f32, 2.0, 5.0];
    slab_transmittance(
        MediumDesc::Homogeneous {
            sigma_t: st,
            albedo: [0.0; 3],
            phase: PhaseDesc::Isotropic,
            sample_emitters: true,
        },
        st.map(|v| v as f64),
    );
}

#[test]
fn uncollided_slab_transmittance_grid() {
    // A constant grid of 3 through delta tracking (the albedo-0 medium makes
    // every real collision absorb).
    let grid = GridVolumeDesc {
        grid: Arc::new(VolGrid {
            shape: [4, 4, 4],
            channels: 1,
            bbox: [0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
            data: vec![3.0; 64],
        }),
        to_world: Mat4::from_translation(Vec3::new(-10.0, -10.0, 0.0))
            * Mat4::from_scale(Vec3::new(20.0, 20.0, 0.5)),
        use_grid_bbox: false,
        filter: GridFilter::Nearest,
        wrap: fgf_scene::WrapMode::Clamp,
    };
    slab_transmittance(
        MediumDesc::Heterogeneous {
            sigma_t: VolumeDesc::Grid(grid),
            albedo: VolumeDesc::Constant([0.0; 3]),
            scale: 1.0,
            phase: PhaseDesc::Isotropic,
            sample_emitters: true,
        },
        [3.0; 3],
    );
}

/// Single scattering (`max_depth = 2`) of a slab z ∈ [0, d] lit by a
/// directional light, seen from above along -z: with `μ_l` the cosine of
/// the light direction,
/// `L = ∫_0^d σ_s p(cos θ) E exp(-σ_t s / μ_l) exp(-σ_t s) ds`
/// (depth `s` below the top face), integrated here by the midpoint rule.
///
/// Above the slab, `absorbers` purely absorbing slabs of thickness `h` and
/// extinction `σ_a` (z ∈ [0.5 + 0.2k, 0.6 + 0.2k], each its own medium in
/// its own null-bounded cube) dim the camera ray and the light by
/// `T = exp(-Σ σ_a h / μ)`, so the expected radiance is
/// `T_cam · T_light · L`.
fn thin_slab_single_scattering(absorbers: usize) {
    let (d, sigma_t, albedo, g, e) = (0.3f64, 2.0f64, 0.8f64, 0.5f32, 3.0f64);
    let (h_abs, sigma_abs) = (0.1f64, 1.5f64);
    let light_dir = Vec3::new(0.6, 0.0, -0.8); // travels down and sideways
    let mut s = scene(
        2,
        sensor(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, Vec3::Y, 0.5, 8, 512),
    );
    s.media.push(MediumDesc::Homogeneous {
        sigma_t: [sigma_t as f32; 3],
        albedo: [albedo as f32; 3],
        phase: PhaseDesc::Hg { g },
        sample_emitters: true,
    });
    let slab = |z0: f32, h: f32| {
        Mat4::from_translation(Vec3::new(0.0, 0.0, z0 + h / 2.0))
            * Mat4::from_scale(Vec3::new(50.0, 50.0, h / 2.0))
    };
    s.shapes.push(cube(slab(0.0, d as f32), Some(0)));
    for k in 0..absorbers {
        s.media.push(MediumDesc::Homogeneous {
            sigma_t: [sigma_abs as f32; 3],
            albedo: [0.0; 3],
            phase: PhaseDesc::Isotropic,
            sample_emitters: true,
        });
        s.shapes
            .push(cube(slab(0.5 + 0.2 * k as f32, h_abs as f32), Some(k + 1)));
    }
    s.emitters.push(EmitterDesc::Directional {
        direction: light_dir,
        irradiance: [e as f32; 3],
    });
    let (m, se) = image_mean(&s);
    let mu_l = 0.8f64;
    // Propagation -z against the direction toward the light, -light_dir.
    let cos = Vec3::new(0.0, 0.0, -1.0).dot(-light_dir) as f64;
    let p = fgf_render::phase::hg(cos as f32, g) as f64;
    let n = 100_000;
    let h = d / n as f64;
    let l: f64 = (0..n)
        .map(|i| {
            let s = (i as f64 + 0.5) * h;
            albedo * sigma_t * p * e * (-sigma_t * s / mu_l).exp() * (-sigma_t * s).exp() * h
        })
        .sum();
    let tau = absorbers as f64 * sigma_abs * h_abs;
    let expected = (-tau).exp() * (-tau / mu_l).exp() * l;
    let what = format!("single scattering under {absorbers} absorbers");
    assert_close(&what, m, se, [expected; 3], Z);
}

#[test]
fn single_scattering_of_thin_slab_matches_quadrature() {
    thin_slab_single_scattering(0);
}

/// Six absorbers: light reaches the scattering slab through 12 null
/// boundaries, so its shadow rays cross 14, more than one query keeps
/// (`MAX_CROSSINGS` = 8): the crossings are resumed.
#[test]
fn single_scattering_under_a_stack_of_absorbers() {
    thin_slab_single_scattering(6);
}

/// `max_depth = 1`: only emitters seen directly. A lit diffuse floor is black.
#[test]
fn max_depth_one_shows_only_direct_emission() {
    let mut s = scene(
        1,
        sensor(Vec3::new(0.0, 2.0, 2.0), Vec3::ZERO, Vec3::Y, 50.0, 8, 4),
    );
    s.shapes.push(ShapeDesc {
        name: "floor".into(),
        geometry: GeometryDesc::Rectangle,
        to_world: Mat4::from_rotation_x(-std::f32::consts::FRAC_PI_2)
            * Mat4::from_scale(Vec3::splat(5.0)),
        flip_normals: false,
        bsdf: 1,
        emitter: None,
        interior: None,
        exterior: None,
    });
    s.emitters.push(EmitterDesc::Point {
        position: Vec3::new(0.0, 1.0, 0.0),
        intensity: [10.0; 3],
    });
    let out = render(&s, &RenderOptions::default(), &NoProgress).unwrap();
    assert!(out.image.iter().all(|&v| v == 0.0));
    // With max_depth = 2 the floor is lit.
    s.integrator.max_depth = 2;
    let out = render(&s, &RenderOptions::default(), &NoProgress).unwrap();
    assert!(out.image.iter().all(|&v| v > 0.0));
}

/// Bit-identical images for 1 and 2 threads.
#[test]
fn one_and_two_threads_give_identical_images() {
    let s = reference_scene("cube-heterogeneous.xml", 24, 4);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| render(&s, &opts(), &NoProgress).unwrap())
    };
    let a = run(1);
    let b = run(2);
    assert_eq!(a.image, b.image);
    assert_eq!(a.variance, b.variance);
    assert!(a.image.iter().any(|&v| v > 0.0));
}

/// Cancels once the first pass has reported progress.
struct CancelAfterFirstPass(AtomicU64);
impl Progress for CancelAfterFirstPass {
    fn inc(&self, n: u64) {
        self.0.fetch_add(n, Ordering::Relaxed);
    }
    fn cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed) > 0
    }
}

/// Cancellation returns the image of whole passes, with their sample count,
/// equal to an uninterrupted render with that many samples.
#[test]
fn cancellation_returns_completed_passes() {
    let s = reference_scene("cube-homogeneous.xml", 16, 8);
    let o = RenderOptions {
        spp_per_pass: Some(2),
        ..Default::default()
    };
    let p = CancelAfterFirstPass(AtomicU64::new(0));
    let Err(RenderError::Cancelled { partial: out }) = render(&s, &o, &p) else {
        panic!("a cancelled render must return RenderError::Cancelled");
    };
    assert_eq!(out.spp_done, 2);
    let full = render(&s, &RenderOptions { spp: Some(2), ..o }, &NoProgress).unwrap();
    assert_eq!(out.image, full.image);
}

/// Direct lighting (`max_depth = 2`) of a diffuse ground by a one-sided disk
/// light, at a near and at a distant, grazing ground point, against
/// quadrature of the irradiance over the disk. The distant point guards the
/// shadow-ray offsets: a light must not shadow itself at grazing angles.
#[test]
fn disk_light_on_ground_matches_quadrature() {
    use fgf_render::math::Sampler;
    use fgf_render::ray::Ray;
    use fgf_render::world::World;
    let ground = ShapeDesc {
        name: "ground".into(),
        geometry: GeometryDesc::Rectangle,
        to_world: Mat4::from_rotation_x(-std::f32::consts::FRAC_PI_2)
            * Mat4::from_scale(Vec3::splat(5.0)),
        flip_normals: false,
        bsdf: 1,
        emitter: None,
        interior: None,
        exterior: None,
    };
    let (center, radius, le) = (Vec3::new(0.3, 2.5, 0.3), 0.4f32, 12.0f32);
    let disk = ShapeDesc {
        name: "light".into(),
        geometry: GeometryDesc::Disk,
        // Unit disk in xy, normal +z, turned to face down (-y).
        to_world: Mat4::from_translation(center)
            * Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2)
            * Mat4::from_scale(Vec3::splat(radius)),
        flip_normals: false,
        bsdf: 2,
        emitter: Some(EmitterDesc::Area {
            radiance: [le; 3],
            texture: None,
        }),
        interior: None,
        exterior: None,
    };
    let mut s = scene(
        2,
        sensor(Vec3::new(0.0, 1.0, 3.0), Vec3::ZERO, Vec3::Y, 30.0, 4, 1),
    );
    s.bsdfs.push(BsdfDesc::Diffuse {
        reflectance: [0.0; 3],
    });
    s.shapes = vec![ground, disk];
    let world = World::build(&s).unwrap();
    let o = Vec3::new(0.5, 1.8, 4.2);
    for d in [
        Vec3::new(-0.48, -0.2, -0.85),
        Vec3::new(-0.480598, -0.1737596, -0.859554),
    ] {
        let d = d.normalize();
        let p = o + d * (-o.y / d.y);
        // Quadrature over the disk in polar coordinates (midpoint rule).
        let n = 400;
        let mut e = 0.0f64;
        for i in 0..n {
            for j in 0..n {
                let r = radius as f64 * ((i as f64 + 0.5) / n as f64).sqrt();
                let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / n as f64;
                let q = [
                    center.x as f64 + r * phi.cos(),
                    center.y as f64,
                    center.z as f64 + r * phi.sin(),
                ];
                let v = [q[0] - p.x as f64, q[1] - p.y as f64, q[2] - p.z as f64];
                let d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
                let cos = v[1] / d2.sqrt(); // at the ground (normal +y) and at the light (normal -y)
                e += le as f64 * cos * cos / d2
                    * (std::f64::consts::PI * (radius as f64).powi(2) / (n * n) as f64);
            }
        }
        let expected = 0.5 / std::f64::consts::PI * e;
        let m = 100_000u64;
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        for k in 0..m {
            let mut smp = Sampler::new(5, 0, k);
            let v = world
                .li(
                    Ray {
                        o: o.into(),
                        d: d.into(),
                    },
                    1e4,
                    &mut smp,
                )
                .x as f64;
            sum += v;
            sum2 += v * v;
        }
        let mean = sum / m as f64;
        let se = ((sum2 / m as f64 - mean * mean) / (m as f64 - 1.0)).sqrt();
        assert!(
            (mean - expected).abs() <= Z * se,
            "point {p:?}: {mean} vs {expected} (SE {se})"
        );
    }
}

/// `hide_emitters`: emitters seen directly by the camera are black, their
/// light still reaches the scene.
#[test]
fn hide_emitters_hides_only_directly_visible_emitters() {
    let mut s = scene(
        -1,
        sensor(Vec3::new(0.0, 2.0, 2.0), Vec3::ZERO, Vec3::Y, 90.0, 8, 4),
    );
    constant_env(&mut s, 1.0);
    s.shapes.push(ShapeDesc {
        name: "floor".into(),
        geometry: GeometryDesc::Rectangle,
        to_world: Mat4::from_rotation_x(-std::f32::consts::FRAC_PI_2)
            * Mat4::from_scale(Vec3::splat(1.0)),
        flip_normals: false,
        bsdf: 1,
        emitter: None,
        interior: None,
        exterior: None,
    });
    s.integrator.hide_emitters = true;
    let out = render(&s, &RenderOptions::default(), &NoProgress).unwrap();
    // The top row sees only the sky; the centre sees the lit floor.
    assert!(out.image[..8 * 3].iter().all(|&v| v == 0.0));
    let centre = ((4 * 8 + 4) * 3) as usize;
    assert!(out.image[centre] > 0.0);
}
