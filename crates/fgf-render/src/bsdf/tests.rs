//! Unit tests of the BSDFs: Fresnel, Snell, and per model a check that
//! sampling, `eval` and `pdf` agree.

use super::*;
use crate::math::sample_cosine_hemisphere;

#[test]
fn dielectric_fresnel_normal_incidence() {
    // ((η-1)/(η+1))² = 0.04 for η = 1.5, from both sides.
    assert!((fresnel_dielectric(1.0, 1.5).r - 0.04).abs() < 1e-6);
    assert!((fresnel_dielectric(-1.0, 1.5).r - 0.04).abs() < 1e-6);
    // Total internal reflection beyond the critical angle (inside, η = 1.5).
    assert_eq!(fresnel_dielectric(-0.3, 1.5).r, 1.0);
}

#[test]
fn conductor_reduces_to_dielectric_for_k0() {
    for &c in &[0.1f32, 0.5, 0.9, 1.0] {
        let a = fresnel_conductor(c, 1.5, 0.0);
        let b = fresnel_dielectric(c, 1.5).r;
        assert!((a - b).abs() < 1e-5, "{a} vs {b}");
    }
    // Normal incidence: |(η - 1)/(η + 1)|² with η = eta + ik.
    let (eta, k) = (0.2f32, 3.0f32);
    let exp = ((eta - 1.0).powi(2) + k * k) / ((eta + 1.0).powi(2) + k * k);
    assert!((fresnel_conductor(1.0, eta, k) - exp).abs() < 1e-5);
}

#[test]
fn refraction_obeys_snell() {
    let b = Bsdf {
        kind: BsdfKind::Dielectric {
            eta: 1.5,
            r: Spectrum::ONE,
            t: Spectrum::ONE,
        },
        twosided: false,
        textures: None,
    };
    let wi = Vec3A::new(0.6, 0.0, 0.8);
    let s = b.sample(wi, 0.999, [0.0, 0.0]).unwrap();
    let sin_i = 0.6f32;
    let sin_t = (s.wo.x * s.wo.x + s.wo.y * s.wo.y).sqrt();
    assert!((sin_i - 1.5 * sin_t).abs() < 1e-5);
    assert!(s.wo.z < 0.0 && (s.wo.length() - 1.0).abs() < 1e-5);
    assert!((s.weight.x - 1.0 / 2.25).abs() < 1e-6);
}

use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

fn md(kind: Distribution, a: f32, visible: bool) -> Microfacet {
    Microfacet {
        kind,
        ax: a,
        ay: a,
        visible,
    }
}

fn bsdf(kind: BsdfKind) -> Bsdf {
    Bsdf {
        kind,
        twosided: false,
        textures: None,
    }
}

/// The BSDFs under test: every rough model with both distributions and
/// both sampling modes (the metal and the dielectric also anisotropic), plus the smooth plastic's diffuse lobe.
fn cases() -> Vec<(String, Bsdf)> {
    let mut v = Vec::new();
    for kind in [Distribution::Beckmann, Distribution::Ggx] {
        for visible in [true, false] {
            for a in [0.2f32, 0.6] {
                let d = md(kind, a, visible);
                let tag = format!("{kind:?} a={a} visible={visible}");
                let mut distrs = vec![(tag.clone(), d)];
                if a == 0.2 {
                    // Anisotropic: rougher along y than along x.
                    distrs.push((
                        format!("{kind:?} ax=0.2 ay=0.7 visible={visible}"),
                        Microfacet { ay: 0.7, ..d },
                    ));
                }
                for (tag, d) in distrs {
                    v.push((
                        format!("roughconductor {tag}"),
                        bsdf(BsdfKind::RoughConductor(RoughConductor {
                            eta: Spectrum::new(0.2, 0.9, 1.1),
                            k: Spectrum::new(3.9, 2.4, 2.2),
                            r: Spectrum::ONE,
                            mirror: false,
                            distr: d,
                        })),
                    ));
                    v.push((
                        format!("roughdielectric {tag}"),
                        bsdf(BsdfKind::RoughDielectric(RoughDielectric {
                            eta: 1.5,
                            r: Spectrum::ONE,
                            t: Spectrum::ONE,
                            distr: d,
                        })),
                    ));
                }
                v.push((
                    format!("roughplastic {tag}"),
                    bsdf(BsdfKind::RoughPlastic(RoughPlastic::new(
                        1.49,
                        Spectrum::splat(0.5),
                        Spectrum::ONE,
                        false,
                        d,
                    ))),
                ));
            }
        }
    }
    v.push((
        "plastic".into(),
        bsdf(BsdfKind::Plastic(Plastic::new(
            1.49,
            Spectrum::new(0.2, 0.5, 0.8),
            Spectrum::ONE,
            false,
        ))),
    ));
    v
}

fn incident() -> [Vec3A; 4] {
    [
        Vec3A::new(0.0, 0.0, 1.0),
        Vec3A::new(0.5, 0.1, 0.86).normalize(),
        Vec3A::new(0.9, -0.2, 0.25).normalize(),
        // From inside (only the dielectric answers).
        Vec3A::new(0.3, 0.2, -0.9).normalize(),
    ]
}

/// A sampled direction's weight and pdf are those `eval_pdf` gives for it.
#[test]
fn sample_agrees_with_eval_pdf() {
    let mut rng = Pcg64::seed_from_u64(1);
    for (name, b) in cases() {
        for wi in incident() {
            for _ in 0..2000 {
                let Some(s) = b.sample(wi, rng.random(), [rng.random(), rng.random()]) else {
                    continue;
                };
                if s.delta {
                    continue;
                }
                let (f, pdf) = b.eval_pdf(wi, s.wo);
                assert!(
                    (pdf - s.pdf).abs() <= 1e-3 * pdf.max(1e-3),
                    "{name} wi={wi}: pdf {pdf} vs sampled {}",
                    s.pdf
                );
                let w = f / pdf;
                assert!(
                    (w - s.weight).abs().max_element() <= 1e-3 * w.max_element().max(1e-2),
                    "{name}: weight {w} vs {}",
                    s.weight
                );
            }
        }
    }
}

/// Chi-square test of the sampled directions against the pdf: 18 bins in
/// `θ` (both hemispheres) × 8 in `φ`, expected counts by a 32×12
/// midpoint rule inside each bin; bins expecting fewer than 5 are pooled.
/// Reject at a p-value of 1e-4 (Wilson–Hilferty approximation).
#[test]
fn sampling_matches_pdf_chi_square() {
    let (nz, nphi, sub_t, sub_p) = (18usize, 8usize, 32usize, 12usize);
    let n = 100_000usize;
    let mut rng = Pcg64::seed_from_u64(2);
    let mut failures = Vec::new();
    for (name, b) in cases() {
        for wi in incident() {
            let mut obs = vec![0f64; nz * nphi + 1];
            for _ in 0..n {
                match b.sample(wi, rng.random(), [rng.random(), rng.random()]) {
                    Some(s) if !s.delta => {
                        let theta = s.wo.z.clamp(-1.0, 1.0).acos();
                        let iz = ((theta / std::f32::consts::PI * nz as f32) as usize).min(nz - 1);
                        let phi = s.wo.y.atan2(s.wo.x).rem_euclid(std::f32::consts::TAU);
                        let ip =
                            ((phi / std::f32::consts::TAU * nphi as f32) as usize).min(nphi - 1);
                        obs[iz * nphi + ip] += 1.0;
                    }
                    _ => obs[nz * nphi] += 1.0,
                }
            }
            let mut exp = vec![0f64; nz * nphi + 1];
            let (dt, dphi) = (
                std::f64::consts::PI / nz as f64,
                std::f64::consts::TAU / nphi as f64,
            );
            for iz in 0..nz {
                for ip in 0..nphi {
                    let mut acc = 0.0f64;
                    for a in 0..sub_t {
                        let theta = dt * (iz as f64 + (a as f64 + 0.5) / sub_t as f64);
                        let (st, ct) = theta.sin_cos();
                        for c in 0..sub_p {
                            let phi = dphi * (ip as f64 + (c as f64 + 0.5) / sub_p as f64);
                            let wo = Vec3A::new(
                                (st * phi.cos()) as f32,
                                (st * phi.sin()) as f32,
                                ct as f32,
                            );
                            acc += b.eval_pdf(wi, wo).1 as f64 * st;
                        }
                    }
                    exp[iz * nphi + ip] = acc * dt * dphi / (sub_t * sub_p) as f64 * n as f64;
                }
            }
            // The pdf integrates to the fraction of non-delta samples (to
            // the accuracy of the quadrature, which resolves narrow lobes
            // to ~0.5 %); the cells are then compared given that fraction.
            let total: f64 = exp[..nz * nphi].iter().sum();
            let succ = n as f64 - obs[nz * nphi];
            if (total - succ).abs() > 0.01 * n as f64 {
                failures.push(format!(
                    "{name} wi={wi}: ∫pdf = {} but {} of the samples are non-delta",
                    total / n as f64,
                    succ / n as f64
                ));
            }
            for e in &mut exp[..nz * nphi] {
                *e *= succ / total;
            }
            exp[nz * nphi] = obs[nz * nphi];
            // Pool small cells.
            let (mut chi2, mut dof) = (0.0f64, 0i64);
            let (mut po, mut pe) = (0.0, 0.0);
            for (o, e) in obs.iter().zip(&exp) {
                if *e < 5.0 {
                    po += o;
                    pe += e;
                } else {
                    chi2 += (o - e).powi(2) / e;
                    dof += 1;
                }
            }
            if pe >= 5.0 {
                chi2 += (po - pe).powi(2) / pe;
                dof += 1;
            } else {
                // Unexpected mass where the pdf has almost none.
                assert!(
                    po < 20.0 + 4.0 * pe,
                    "{name} wi={wi}: {po} samples in cells expecting {pe}"
                );
            }
            let k = (dof - 1).max(1) as f64;
            // Wilson–Hilferty: (chi2/k)^(1/3) ~ N(1 - 2/(9k), 2/(9k)); z(1e-4) = 3.72.
            let zc = ((chi2 / k).cbrt() - (1.0 - 2.0 / (9.0 * k))) / (2.0 / (9.0 * k)).sqrt();
            if zc >= 3.72 {
                failures.push(format!(
                    "{name} wi={wi}: chi2 = {chi2:.1} for {k} dof (z = {zc:.2})"
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// With white reflectances, no model reflects more than it receives (from
/// outside, where the radiance scaling of refraction is below 1), and the
/// reflection lobes are reciprocal: `f(wi, wo)/cos θ_o = f(wo, wi)/cos θ_i`.
#[test]
fn energy_and_reciprocity() {
    let mut rng = Pcg64::seed_from_u64(3);
    let n = 40_000;
    for (name, b) in cases() {
        for wi in &incident()[..3] {
            let mut sum = Spectrum::ZERO;
            let mut sum2 = Spectrum::ZERO;
            for _ in 0..n {
                if let Some(s) = b.sample(*wi, rng.random(), [rng.random(), rng.random()]) {
                    sum += s.weight;
                    sum2 += s.weight * s.weight;
                }
            }
            let m = sum / n as f32;
            let se = ((sum2 / n as f32 - m * m) / n as f32).max(Spectrum::ZERO);
            let se = Spectrum::new(se.x.sqrt(), se.y.sqrt(), se.z.sqrt());
            assert!(
                (m - 3.0 * se).max_element() <= 1.0 + 1e-4,
                "{name} wi={wi}: albedo {m} (SE {se})"
            );
        }
        for _ in 0..500 {
            let a = sample_cosine_hemisphere([rng.random(), rng.random()]);
            let c = sample_cosine_hemisphere([rng.random(), rng.random()]);
            if a.z < 1e-2 || c.z < 1e-2 {
                continue;
            }
            let f1 = b.eval_pdf(a, c).0 / c.z;
            let f2 = b.eval_pdf(c, a).0 / a.z;
            assert!(
                (f1 - f2).abs().max_element() <= 1e-3 * f1.max_element().max(1e-3),
                "{name}: f({a}, {c}) = {f1} but f({c}, {a}) = {f2}"
            );
        }
    }
}

/// The visible-normal samplers produce `D_wi(m)`: the mean of `wi·m/cos θ_i`
/// over them is `∫ D_wi (wi·m)/cos θ_i dm`, which by the projected-area
/// identity equals `1/(G1(wi)·...)`; checked simply as: the density of
/// sampled normals integrates `D_wi` to 1 in a chi-square sense is covered
/// above; here the Beckmann slope inversion is checked against `erf`.
#[test]
fn beckmann_visible_normals_have_unit_projected_area() {
    // ∫ D(m) max(0, wi·m) dω_m = cos θ_i / G1(wi): the visible pdf integrates to 1.
    for a in [0.1f32, 0.3, 1.0] {
        let d = md(Distribution::Beckmann, a, true);
        for wi in &incident()[..3] {
            let n = 400usize;
            let mut acc = 0.0f64;
            for i in 0..n {
                for j in 0..n {
                    // Hemisphere by z uniform in (0,1], φ uniform.
                    let z = (i as f64 + 0.5) / n as f64;
                    let phi = std::f64::consts::TAU * (j as f64 + 0.5) / n as f64;
                    let r = (1.0 - z * z).sqrt();
                    let m = Vec3A::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
                    acc += d.pdf(*wi, m) as f64;
                }
            }
            let integral = acc * std::f64::consts::TAU / (n * n) as f64;
            // Sharp lobes are under-resolved by the grid at a = 0.1.
            let tol = if a < 0.2 { 2e-2 } else { 2e-3 };
            assert!(
                (integral - 1.0).abs() < tol,
                "a={a} wi={wi}: ∫pdf = {integral}"
            );
        }
    }
}

/// The fit of the internal diffuse reflectance is within 2e-3 of the exact
/// hemispherical average.
#[test]
fn diffuse_reflectance_fit_is_close_to_exact() {
    for eta in [1.2f32, 1.33, 1.49, 1.7, 2.0] {
        let fit = fresnel::fresnel_diffuse_reflectance_fit(eta);
        let exact = fresnel::fresnel_diffuse_reflectance(1.0 / eta);
        assert!(
            (fit - exact).abs() < 2e-3,
            "eta {eta}: fit {fit} exact {exact}"
        );
    }
}

/// `mask`: value and pdf are the nested ones times `opacity`; sampling
/// goes straight through with probability `1 − opacity` (weight 1, flagged
/// null) and otherwise samples the nested BSDF; a shadow ray keeps
/// `1 − opacity`, and `1 − opacity·(1 − T')` around a thin dielectric.
#[test]
fn mask_scales_the_nested_bsdf() {
    let diffuse = Bsdf::from_desc(&fgf_scene::BsdfDesc::Diffuse {
        reflectance: [0.6, 0.3, 0.2],
    });
    let m = Bsdf::from_desc(&fgf_scene::BsdfDesc::Mask {
        opacity: 0.3,
        nested: Box::new(fgf_scene::BsdfDesc::Diffuse {
            reflectance: [0.6, 0.3, 0.2],
        }),
    });
    assert!(m.is_smooth() && m.has_null_lobe() && !m.is_null());
    let wi = Vec3A::new(0.6, 0.0, 0.8);
    let wo = Vec3A::new(-0.3, 0.4, (1.0f32 - 0.25).sqrt());
    let (f, p) = m.eval_pdf(wi, wo);
    let (fd, pd) = diffuse.eval_pdf(wi, wo);
    assert!((f - 0.3 * fd).abs().max_element() < 1e-7 && (p - 0.3 * pd).abs() < 1e-7);
    let n = 10_000;
    let mut nulls = 0;
    for i in 0..n {
        let u1 = (i as f32 + 0.5) / n as f32;
        let s = m.sample(wi, u1, [0.37, 0.61]).unwrap();
        if s.null {
            nulls += 1;
            assert_eq!(s.wo, -wi);
            assert_eq!(s.weight, Spectrum::ONE);
            assert!((s.pdf - 0.7).abs() < 1e-6);
        } else {
            // The nested sample's weight, its pdf times the opacity.
            let (f, p) = m.eval_pdf(wi, s.wo);
            assert!((s.pdf - p).abs() < 1e-5 * p && (s.weight - f / p).abs().max_element() < 1e-5);
        }
    }
    assert_eq!(nulls, 7000);
    assert!(
        (m.null_transmission(wi) - Spectrum::splat(0.7))
            .abs()
            .max_element()
            < 1e-7
    );
    let thin = fgf_scene::BsdfDesc::ThinDielectric {
        int_ior: 1.5,
        ext_ior: 1.0,
        specular_reflectance: [1.0; 3],
        specular_transmittance: [1.0; 3],
    };
    let t = Bsdf::from_desc(&thin).null_transmission(wi);
    let r = fresnel_dielectric(0.8, 1.5).r;
    assert!(
        (t - Spectrum::splat(1.0 - 2.0 * r / (1.0 + r)))
            .abs()
            .max_element()
            < 1e-6
    );
    let mt = Bsdf::from_desc(&fgf_scene::BsdfDesc::Mask {
        opacity: 0.3,
        nested: Box::new(thin),
    });
    let exp = Spectrum::ONE - 0.3 * (Spectrum::ONE - t);
    assert!((mt.null_transmission(wi) - exp).abs().max_element() < 1e-6);
}

/// A textured BSDF made concrete at a hit without reference counts
/// ([`Bsdf::at_shared`]) has the values and samples of the owned copy
/// ([`Bsdf::at`]), and leaves the shared tables' counts as they were; a
/// `mask` (boxed nested BSDF) gets the owned copy.
#[test]
fn shared_copy_at_a_hit_is_the_owned_one() {
    use crate::texture::Texture;
    use fgf_scene::TexturedParam;
    let checker = Texture::Checkerboard {
        color0: Spectrum::new(0.8, 0.2, 0.1),
        color1: Spectrum::new(0.1, 0.3, 0.7),
        to_uv: glam::Affine2::from_scale(glam::Vec2::new(24.0, 6.0)),
    };
    let plastic = RoughPlastic::new(
        1.49,
        Spectrum::splat(0.5),
        Spectrum::ONE,
        false,
        md(Distribution::Ggx, 0.2, true),
    );
    let tables = plastic.t_ext.clone();
    let b = Bsdf {
        kind: BsdfKind::RoughPlastic(plastic),
        twosided: false,
        textures: Some(Arc::from([(TexturedParam::DiffuseReflectance, checker)])),
    };
    let count = Arc::strong_count(&tables);
    let wi = Vec3A::new(0.6, 0.0, 0.8);
    let wo = Vec3A::new(-0.3, 0.4, (1.0f32 - 0.25).sqrt());
    let mut colours = std::collections::HashSet::new();
    for i in 0..200 {
        let uv = glam::Vec2::new(i as f32 * 0.0173, i as f32 * 0.0311);
        let owned = b.at(uv);
        assert_eq!(Arc::strong_count(&tables), count + 1);
        let shared = b.at_shared(uv).expect("not a mask");
        assert!(shared.textures.is_none());
        let (f, p) = shared.eval_pdf(wi, wo);
        assert_eq!((f, p), owned.eval_pdf(wi, wo), "uv {uv}");
        colours.insert(f.x.to_bits());
        let (a, c) = (
            shared.sample(wi, 0.3, [0.7, 0.2]),
            owned.sample(wi, 0.3, [0.7, 0.2]),
        );
        assert_eq!(
            a.map(|s| (s.wo, s.weight, s.pdf)),
            c.map(|s| (s.wo, s.weight, s.pdf))
        );
        let hit = HitBsdf::new(&b, || uv);
        assert!(matches!(hit, HitBsdf::Shared(_)));
        assert_eq!(hit.eval_pdf(wi, wo), (f, p));
    }
    // Both checker colours were seen; no count was taken or released.
    assert_eq!(colours.len(), 2);
    assert_eq!(Arc::strong_count(&tables), count);
    let mask = Bsdf {
        kind: BsdfKind::Mask(Box::new(Mask {
            opacity: 0.5,
            smooth: false,
            nested: b.clone(),
        })),
        twosided: false,
        textures: Some(Arc::from([])),
    };
    assert!(mask.at_shared(glam::Vec2::ZERO).is_none());
    assert!(matches!(
        HitBsdf::new(&mask, || glam::Vec2::ZERO),
        HitBsdf::Owned(_)
    ));
}
