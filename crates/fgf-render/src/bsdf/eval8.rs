//! [`Bsdf::eval_pdf`] of eight directions at once, for the paths that go on
//! in step ([`crate::world::World`]'s `li_beam`): the value and pdf of the
//! BSDF of up to eight surface interactions at the same scene BSDF, toward
//! their light samples and at the directions their BSDF samples draw, for
//! the models that take most of a glossy scene's shading,
//! `roughconductor` and `roughplastic` on GGX; and the directions those
//! samples draw, eight at once, where they sample visible normals
//! ([`sample_wo8_lanes`]).
//!
//! Each lane performs the scalar code's operations in its order (see
//! [`crate::lanes`]), so it gives the bits of [`Bsdf::eval_pdf`] and
//! [`Bsdf::sample_wo8`]: the dot products as glam computes them
//! (`(x·x' + y·y') + z·z'`), the normalisation of the half vector by the
//! reciprocal of its length (and of other vectors by their length, as
//! glam's `normalize` does), the conductor's Fresnel term in `f64`, and the
//! concentric disk map through `sin_cos_2pi`.

use super::microfacet::{Distribution, Microfacet};
use super::plastic::{RoughPlastic, TABLE_RES};
use super::rough::RoughConductor;
use super::{Bsdf, BsdfKind};
use crate::lanes::{D8, F8, I8, M8};
use crate::math::sample_concentric_disk8;
use crate::spectrum::Spectrum;
use fgf_scene::TexturedParam;
use glam::Vec3A;
use std::f32::consts::PI;

/// Eight 3-vectors (or spectra), one per lane: x, y, z.
type V8 = [F8; 3];

#[inline(always)]
fn dot8(a: V8, b: V8) -> F8 {
    a[0].mul(b[0]).add(a[1].mul(b[1])).add(a[2].mul(b[2]))
}

/// Lanes of `mask` set to zero.
#[inline(always)]
fn zero_where(mask: M8, x: F8) -> F8 {
    mask.select(F8::splat(0.0), x)
}

/// Eight lanes of a spectrum per lane.
#[inline(always)]
fn spectra8(s: [Spectrum; 8]) -> V8 {
    std::array::from_fn(|c| F8::from_array(s.map(|v| v[c])))
}

impl Bsdf {
    /// Whether [`eval_pdf8`] evaluates this scene BSDF (as it is before
    /// [`Bsdf::at`]): `roughconductor` or `roughplastic` on GGX, whose
    /// textures, if any, give only the reflectances that vary per lane.
    pub(crate) fn has_eval8(&self) -> bool {
        let (ggx, per_lane): (bool, &[TexturedParam]) = match &self.kind {
            BsdfKind::RoughConductor(c) => (
                c.distr.kind == Distribution::Ggx,
                &[TexturedParam::SpecularReflectance],
            ),
            BsdfKind::RoughPlastic(p) => (
                p.distr.kind == Distribution::Ggx,
                &[
                    TexturedParam::DiffuseReflectance,
                    TexturedParam::SpecularReflectance,
                ],
            ),
            _ => return false,
        };
        ggx && self
            .textures
            .iter()
            .flat_map(|t| t.iter())
            .all(|(p, _)| per_lane.contains(p))
    }

    /// Whether [`sample_wo8_lanes`] draws this scene BSDF's directions:
    /// those of [`Bsdf::has_eval8`] that sample GGX's visible normals.
    pub(crate) fn has_sample8(&self) -> bool {
        self.has_eval8()
            && match &self.kind {
                BsdfKind::RoughConductor(c) => c.distr.visible,
                BsdfKind::RoughPlastic(p) => p.distr.visible,
                _ => false,
            }
    }

    /// For a BSDF for which [`Bsdf::has_eval8`] holds (made concrete at a
    /// hit): the direction [`Bsdf::sample`] draws with these variates, as
    /// `(wi, wo, flipped)` in the frame where it samples (`wi.z > 0`;
    /// `flipped` for the back side of a two-sided BSDF, whose sample is
    /// `wo` with its `z` negated); its sample is then
    /// [`super::BsdfSample::glossy`] of [`eval_pdf8`] at `(wi, wo)`. `None`
    /// where `sample` gives none before evaluating the BSDF.
    #[inline]
    pub(crate) fn sample_wo8(
        &self,
        mut wi: Vec3A,
        u1: f32,
        u2: [f32; 2],
    ) -> Option<(Vec3A, Vec3A, bool)> {
        let flipped = self.twosided && wi.z < 0.0;
        if flipped {
            wi.z = -wi.z;
        }
        let wo = match &self.kind {
            BsdfKind::RoughConductor(c) => c.sample_wo(wi, u2),
            BsdfKind::RoughPlastic(p) => p.sample_wo(wi, u1, u2),
            _ => unreachable!("sample_wo8 of a BSDF without has_eval8"),
        }?;
        Some((wi, wo, flipped))
    }
}

/// [`Bsdf::eval_pdf`] of lane `l` of `bsdfs` at `(wi[l], wo[l])` (local
/// directions), for lanes that are instances of one scene BSDF for which
/// [`Bsdf::has_eval8`] holds ([`Bsdf::at`] of it at each lane's hit; lanes
/// beyond `bsdfs.len()` repeat its last). Returns the values and pdfs.
#[inline(never)]
pub(crate) fn eval_pdf8(
    bsdfs: &[&Bsdf],
    wi: [Vec3A; 8],
    wo: [Vec3A; 8],
) -> ([Spectrum; 8], [f32; 8]) {
    let n = bsdfs.len();
    debug_assert!((1..=8).contains(&n));
    let lane = |l: usize| bsdfs[l.min(n - 1)];
    let b0 = lane(0);
    let (mut wi, mut wo) = (to8(wi), to8(wo));
    let zero = F8::splat(0.0);
    if b0.twosided {
        let flip = wi[2].lt(zero);
        wi[2] = flip.select(wi[2].neg(), wi[2]);
        wo[2] = flip.select(wo[2].neg(), wo[2]);
    }
    let (f, pdf) = match &b0.kind {
        BsdfKind::RoughConductor(c) => {
            let r = spectra8(std::array::from_fn(|l| match &lane(l).kind {
                BsdfKind::RoughConductor(c) => c.r,
                _ => unreachable!("lanes of one scene BSDF"),
            }));
            conductor8(c, r, wi, wo)
        }
        BsdfKind::RoughPlastic(p) => {
            let (base, spec): ([Spectrum; 8], [Spectrum; 8]) = (
                std::array::from_fn(|l| match &lane(l).kind {
                    BsdfKind::RoughPlastic(p) => p.c.base(),
                    _ => unreachable!("lanes of one scene BSDF"),
                }),
                std::array::from_fn(|l| match &lane(l).kind {
                    BsdfKind::RoughPlastic(p) => p.c.specular,
                    _ => unreachable!("lanes of one scene BSDF"),
                }),
            );
            plastic8(p, spectra8(base), spectra8(spec), wi, wo)
        }
        _ => unreachable!("eval_pdf8 of a BSDF without has_eval8"),
    };
    (from8(f), pdf.to_array())
}

/// [`Bsdf::sample_wo8`] of eight lanes at once, with the variates `u1`,
/// `u2` of each: for lanes that are instances of one scene BSDF `b` for
/// which [`Bsdf::has_sample8`] holds (what sampling reads, the microfacet
/// distribution and a plastic's lobe weights and table, is then the same in
/// all). Returns per lane `wi` (flipped to the front), `wo`, and the masks
/// of the lanes that have a direction and of those flipped. Each lane gives
/// the scalar code's bits: the disk through the same `sin_cos_2pi`, glam's
/// normalisation (a division by the length) and cross product.
#[inline(never)]
pub(crate) fn sample_wo8_lanes(
    b: &Bsdf,
    wi: [Vec3A; 8],
    u1: [f32; 8],
    u2: [[f32; 2]; 8],
) -> ([Vec3A; 8], [Vec3A; 8], u32, u32) {
    let zero = F8::splat(0.0);
    let mut wi = to8(wi);
    let flipped = if b.twosided {
        wi[2].lt(zero)
    } else {
        zero.lt(zero)
    };
    wi[2] = flipped.select(wi[2].neg(), wi[2]);
    let disk = sample_concentric_disk8([
        F8::from_array(u2.map(|u| u[0])),
        F8::from_array(u2.map(|u| u[1])),
    ]);
    let wo = match &b.kind {
        BsdfKind::RoughConductor(c) => reflect8(wi, ggx_visible8(&c.distr, wi, disk)),
        BsdfKind::RoughPlastic(p) => {
            let specular = F8::from_array(u1).lt(prob_specular8(p, t8(p, wi[2])));
            let glossy = reflect8(wi, ggx_visible8(&p.distr, wi, disk));
            // `sample_cosine_hemisphere` on the same disk.
            let one = F8::splat(1.0);
            let z = one
                .sub(disk[0].mul(disk[0]))
                .sub(disk[1].mul(disk[1]))
                .max(zero)
                .sqrt();
            [
                specular.select(glossy[0], disk[0]),
                specular.select(glossy[1], disk[1]),
                specular.select(glossy[2], z),
            ]
        }
        _ => unreachable!("sample_wo8_lanes of a BSDF without has_sample8"),
    };
    let ok = zero.lt(wi[2]).and(zero.lt(wo[2]));
    (from8(wi), from8(wo), ok.bitmask(), flipped.bitmask())
}

/// Eight vectors as lanes.
#[inline(always)]
fn to8(v: [Vec3A; 8]) -> V8 {
    std::array::from_fn(|c| F8::from_array(v.map(|x| x[c])))
}

/// Lanes as eight vectors.
#[inline(always)]
fn from8(v: V8) -> [Vec3A; 8] {
    let v = v.map(F8::to_array);
    std::array::from_fn(|l| Vec3A::new(v[0][l], v[1][l], v[2][l]))
}

/// [`super::microfacet::reflect`]: `2 (wi·m) m − wi`.
#[inline(always)]
fn reflect8(wi: V8, m: V8) -> V8 {
    let d2 = F8::splat(2.0).mul(dot8(wi, m));
    std::array::from_fn(|c| d2.mul(m[c]).sub(wi[c]))
}

/// The visible GGX normal of `Microfacet::sample` (`visible`) for `wi`,
/// from the point `disk` of the concentric disk map of its variates.
#[inline(always)]
fn ggx_visible8(distr: &Microfacet, wi: V8, disk: [F8; 2]) -> V8 {
    let (zero, one) = (F8::splat(0.0), F8::splat(1.0));
    let (ax, ay) = (F8::splat(distr.ax), F8::splat(distr.ay));
    let normalize = |v: V8| {
        let len = dot8(v, v).sqrt();
        v.map(|x| x.div(len))
    };
    let vh = normalize([ax.mul(wi[0]), ay.mul(wi[1]), wi[2]]);
    let len2 = vh[0].mul(vh[0]).add(vh[1].mul(vh[1]));
    let (tilted, len) = (zero.lt(len2), len2.sqrt());
    let t1 = [
        tilted.select(vh[1].neg().div(len), one),
        tilted.select(vh[0].div(len), zero),
        zero,
    ];
    let t2 = [
        vh[1].mul(t1[2]).sub(vh[2].mul(t1[1])),
        vh[2].mul(t1[0]).sub(vh[0].mul(t1[2])),
        vh[0].mul(t1[1]).sub(vh[1].mul(t1[0])),
    ];
    let [p1, q] = disk;
    let s = F8::splat(0.5).mul(one.add(vh[2]));
    let p2 = one
        .sub(s)
        .mul(one.sub(p1.mul(p1)).max(zero).sqrt())
        .add(s.mul(q));
    let k = one.sub(p1.mul(p1)).sub(p2.mul(p2)).max(zero).sqrt();
    let nh: V8 = std::array::from_fn(|c| p1.mul(t1[c]).add(p2.mul(t2[c])).add(k.mul(vh[c])));
    normalize([ax.mul(nh[0]), ay.mul(nh[1]), nh[2].max(F8::splat(1e-6))])
}

/// `(wi + wo).try_normalize()`: the half vector, and the lanes where it
/// exists.
#[inline(always)]
fn half8(wi: V8, wo: V8) -> (V8, M8) {
    let h: V8 = std::array::from_fn(|c| wi[c].add(wo[c]));
    let rcp = F8::splat(1.0).div(dot8(h, h).sqrt());
    let ok = F8::splat(0.0).lt(rcp).and(rcp.lt(F8::splat(f32::INFINITY)));
    (h.map(|x| x.mul(rcp)), ok)
}

/// [`Microfacet::d`] of GGX.
#[inline(always)]
fn d8(distr: &Microfacet, m: V8) -> F8 {
    let zero = F8::splat(0.0);
    let c2 = m[2].mul(m[2]);
    let sq = |x: F8| x.mul(x);
    let e = sq(m[0].div(F8::splat(distr.ax))).add(sq(m[1].div(F8::splat(distr.ay))));
    let r = F8::splat(1.0).div(F8::splat(PI * distr.ax * distr.ay).mul(sq(c2.add(e))));
    let finite = r.lt(F8::splat(f32::INFINITY));
    zero_where(m[2].le(zero), finite.select(r, zero))
}

/// [`Microfacet::g1`] of GGX (also its `g1_exact`).
#[inline(always)]
fn g1_8(distr: &Microfacet, v: V8, m: V8) -> F8 {
    let zero = F8::splat(0.0);
    let sq = |x: F8| x.mul(x);
    let t = sq(v[0].mul(F8::splat(distr.ax)))
        .add(sq(v[1].mul(F8::splat(distr.ay))))
        .div(v[2].mul(v[2]));
    let one = F8::splat(1.0);
    let g = F8::splat(2.0).div(one.add(one.add(t).sqrt()));
    zero_where(dot8(v, m).mul(v[2]).le(zero), t.le(zero).select(one, g))
}

/// [`Microfacet::pdf`] of GGX, given `d = D(m)`.
#[inline(always)]
fn pdf8(distr: &Microfacet, wi: V8, m: V8, d: F8) -> F8 {
    if distr.visible {
        g1_8(distr, wi, m)
            .mul(dot8(wi, m).max(F8::splat(0.0)))
            .mul(d)
            .div(wi[2])
    } else {
        d.mul(m[2])
    }
}

/// [`RoughConductor::eval_pdf`] with the reflectance `r` of each lane.
#[inline(always)]
fn conductor8(c: &RoughConductor, r: V8, wi: V8, wo: V8) -> (V8, F8) {
    let zero = F8::splat(0.0);
    let (h, ok) = half8(wi, wo);
    let d = d8(&c.distr, h);
    let live = ok.and(zero.lt(wi[2])).and(zero.lt(wo[2])).and(zero.lt(d));
    let g = g1_8(&c.distr, wi, h).mul(g1_8(&c.distr, wo, h));
    let s = d.mul(g).div(F8::splat(4.0).mul(wi[2]));
    let fr: V8 = if c.mirror {
        [F8::splat(1.0); 3]
    } else {
        fresnel_conductor8(dot8(wi, h), c.eta, c.k)
    };
    let f = std::array::from_fn(|k| zero_where_not(live, r[k].mul(fr[k]).mul(s)));
    let pdf = pdf8(&c.distr, wi, h, d).div(F8::splat(4.0).mul(dot8(wo, h)));
    (f, zero_where_not(live, pdf))
}

/// Lanes outside `mask` set to zero.
#[inline(always)]
fn zero_where_not(mask: M8, x: F8) -> F8 {
    mask.select(x, F8::splat(0.0))
}

/// [`super::fresnel_conductor_rgb`] of eight cosines: each channel through
/// the same `f64` operations as the scalar code.
#[inline(always)]
fn fresnel_conductor8(cos_i: F8, eta: Spectrum, k: Spectrum) -> V8 {
    let ci = cos_i.to_f64();
    let sin2 = D8::splat(1.0).sub(ci.mul(ci));
    std::array::from_fn(|c| {
        let (eta, k) = (eta[c] as f64, k[c] as f64);
        // The constants of the channel, computed as the scalar code does.
        let e2 = (eta * eta - k * k, 2.0 * eta * k);
        let dd = e2.0 * e2.0 + e2.1 * e2.1;
        let inv = (e2.0 / dd, -e2.1 / dd);
        let z = (
            D8::splat(1.0).sub(sin2.mul(D8::splat(inv.0))),
            // (-sin2)·inv.1, the negation exact.
            sin2.mul(D8::splat(-1.0)).mul(D8::splat(inv.1)),
        );
        // csqrt
        let zero = D8::splat(0.0);
        let pos = |x: D8| x.gt(zero).select(x, zero);
        let rr = z.0.mul(z.0).add(z.1.mul(z.1)).sqrt();
        let half = D8::splat(0.5);
        let ct = (
            pos(half.mul(rr.add(z.0))).sqrt(),
            pos(half.mul(rr.sub(z.0))).sqrt().copysign(z.1),
        );
        let (de, dk) = (D8::splat(eta), D8::splat(k));
        let ect = (
            de.mul(ct.0).sub(dk.mul(ct.1)),
            de.mul(ct.1).add(dk.mul(ct.0)),
        );
        let abs2 = |a: D8, b: D8| a.mul(a).add(b.mul(b));
        // (The scalar code squares -ect.1: the same bits as ect.1 squared.)
        let rs = abs2(ci.sub(ect.0), ect.1).div(abs2(ci.add(ect.0), ect.1));
        let eci = (de.mul(ci), dk.mul(ci));
        let rp = abs2(eci.0.sub(ct.0), eci.1.sub(ct.1)).div(abs2(eci.0.add(ct.0), eci.1.add(ct.1)));
        half.mul(rs.add(rp)).to_f32()
    })
}

/// [`super::fresnel_dielectric`]`(cos_i, eta).r`.
#[inline(always)]
fn fresnel_dielectric_r8(cos_i: F8, eta: f32) -> F8 {
    let zero = F8::splat(0.0);
    let one = F8::splat(1.0);
    let front = zero.le(cos_i);
    let eta_it = front.select(F8::splat(eta), F8::splat(1.0 / eta));
    let eta_ti = one.div(eta_it);
    let ci = cos_i.copysign(one);
    let cos_t_sq = one.sub(eta_ti.mul(eta_ti).mul(one.sub(ci.mul(ci))));
    let ct = cos_t_sq.sqrt();
    let rs = ci.sub(eta_it.mul(ct)).div(ci.add(eta_it.mul(ct)));
    let rp = eta_it.mul(ci).sub(ct).div(eta_it.mul(ci).add(ct));
    let r = F8::splat(0.5).mul(rs.mul(rs).add(rp.mul(rp)));
    cos_t_sq.le(zero).select(one, r)
}

/// `RoughPlastic::t`, the coating's transmittance table at cosine `mu`.
#[inline(always)]
fn t8(p: &RoughPlastic, mu: F8) -> F8 {
    let x = mu.mul(F8::splat((TABLE_RES - 1) as f32));
    let i = x
        .trunc()
        .max(I8::splat(0))
        .min(I8::splat(TABLE_RES as i32 - 2));
    let w = x.sub(i.to_f32());
    let at = |i: I8| F8::gather(&p.t_ext[..], i);
    F8::splat(1.0)
        .sub(w)
        .mul(at(i))
        .add(w.mul(at(i.add(I8::splat(1)))))
}

/// `Coated::prob_specular`: the probability of sampling the coating's
/// specular lobe, given the transmittance `ti` toward `wi`.
#[inline(always)]
fn prob_specular8(p: &RoughPlastic, ti: F8) -> F8 {
    let (zero, one) = (F8::splat(0.0), F8::splat(1.0));
    let sw = p.c.spec_weight;
    let ps = one.sub(ti).mul(F8::splat(sw));
    let pd = ti.mul(F8::splat(1.0 - sw));
    let sum = ps.add(pd);
    zero.lt(sum).select(ps.div(sum), zero)
}

/// [`RoughPlastic::eval_pdf`] with `c.base()` and `c.specular` of each lane.
#[inline(always)]
fn plastic8(p: &RoughPlastic, base: V8, spec: V8, wi: V8, wo: V8) -> (V8, F8) {
    let zero = F8::splat(0.0);
    let one = F8::splat(1.0);
    let live = zero.lt(wi[2]).and(zero.lt(wo[2]));
    let (ti, to) = (t8(p, wi[2]), t8(p, wo[2]));
    let s = ti.mul(to).mul(wo[2]);
    let mut f: V8 = std::array::from_fn(|c| base[c].mul(s));
    let ps = prob_specular8(p, ti);
    let mut pdf = one.sub(ps).mul(wo[2].max(zero).mul(F8::splat(1.0 / PI)));
    let (h, ok) = half8(wi, wo);
    let d = d8(&p.distr, h);
    let spec_on = ok.and(zero.lt(d));
    let fr = fresnel_dielectric_r8(dot8(wi, h), p.c.eta);
    let g = g1_8(&p.distr, wi, h).mul(g1_8(&p.distr, wo, h));
    let sv = fr.mul(d).mul(g).div(F8::splat(4.0).mul(wi[2]));
    for (fc, sc) in f.iter_mut().zip(spec) {
        *fc = spec_on.select(fc.add(sc.mul(sv)), *fc);
    }
    let sp = ps
        .mul(pdf8(&p.distr, wi, h, d))
        .div(F8::splat(4.0).mul(dot8(wo, h)));
    pdf = spec_on.select(pdf.add(sp), pdf);
    (
        f.map(|x| zero_where_not(live, x)),
        zero_where_not(live, pdf),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    /// A direction: mostly on the sphere, some grazing or on the horizon,
    /// some equal to (or the mirror of) another, so that every early exit
    /// of the scalar code is taken by some lanes.
    fn direction(rng: &mut Pcg64) -> Vec3A {
        let v = Vec3A::new(
            rng.random::<f32>() * 2.0 - 1.0,
            rng.random::<f32>() * 2.0 - 1.0,
            rng.random::<f32>() * 2.0 - 1.0,
        )
        .normalize();
        match rng.random_range(0..10) {
            0 => Vec3A::new(v.x, v.y, 0.0).normalize(),
            1 => Vec3A::new(v.x, v.y, 1e-7),
            2 => Vec3A::Z,
            _ => v,
        }
    }

    fn distr(rng: &mut Pcg64) -> Microfacet {
        let ax = [0.001, 0.05, 0.3, 1.0][rng.random_range(0..4)];
        // (Few distinct values: each plastic computes its coating table once.)
        let ay = if rng.random::<bool>() { ax } else { 0.15 };
        Microfacet {
            kind: Distribution::Ggx,
            ax,
            ay,
            visible: rng.random_range(0..4) != 0,
        }
    }

    fn spectrum(rng: &mut Pcg64) -> Spectrum {
        Vec3A::new(rng.random(), rng.random(), rng.random())
    }

    /// Each lane draws the scalar `sample_wo8`'s direction, bit for bit:
    /// conductors and plastics (both lobes), one- and two-sided (seen from
    /// either side), anisotropic or not, with variates on the disk map's
    /// special points (its centre, axes and diagonals) among random ones.
    #[test]
    fn sample_wo8_lanes_is_sample_wo8() {
        let mut rng = Pcg64::seed_from_u64(29);
        let special = [0.0, 0.25, 0.5, 0.75, 1.0 - f32::EPSILON / 2.0];
        for round in 0..3000 {
            let twosided = rng.random::<bool>();
            let d = Microfacet {
                visible: true,
                ..distr(&mut rng)
            };
            let kind = if round % 2 == 0 {
                BsdfKind::RoughConductor(RoughConductor {
                    eta: Vec3A::new(1.66, 0.88, 0.52),
                    k: Vec3A::new(9.22, 6.27, 4.84),
                    r: Vec3A::ONE,
                    mirror: false,
                    distr: d,
                })
            } else {
                BsdfKind::RoughPlastic(RoughPlastic::new(
                    [1.5, 1.33][round / 2 % 2],
                    spectrum(&mut rng),
                    spectrum(&mut rng),
                    round % 4 == 1,
                    d,
                ))
            };
            let b = Bsdf {
                kind,
                twosided,
                textures: None,
            };
            assert!(b.has_sample8());
            let mut variate = || {
                if rng.random_range(0..4) == 0 {
                    special[rng.random_range(0..special.len())]
                } else {
                    rng.random::<f32>()
                }
            };
            let u1: [f32; 8] = std::array::from_fn(|_| variate());
            let u2: [[f32; 2]; 8] = std::array::from_fn(|_| [variate(), variate()]);
            let wi: [Vec3A; 8] = std::array::from_fn(|_| direction(&mut rng));
            let (wi8, wo8, ok, flipped) = sample_wo8_lanes(&b, wi, u1, u2);
            for l in 0..8 {
                let bits = |v: Vec3A| v.to_array().map(f32::to_bits);
                let lane =
                    (ok >> l & 1 == 1).then(|| (bits(wi8[l]), bits(wo8[l]), flipped >> l & 1 == 1));
                let scalar = b
                    .sample_wo8(wi[l], u1[l], u2[l])
                    .map(|(wi, wo, f)| (bits(wi), bits(wo), f));
                assert_eq!(
                    lane, scalar,
                    "round {round} lane {l}: wi {} u1 {} u2 {:?}",
                    wi[l], u1[l], u2[l]
                );
            }
        }
    }

    /// Each lane gives the bits of the scalar `eval_pdf`, for conductors
    /// (with and without Fresnel, one- and two-sided) and plastics (linear
    /// and not), anisotropic or not, with per-lane reflectances.
    #[test]
    fn eval_pdf8_is_eval_pdf() {
        let mut rng = Pcg64::seed_from_u64(23);
        let eta_k = [
            (Vec3A::new(1.66, 0.88, 0.52), Vec3A::new(9.22, 6.27, 4.84)),
            (Vec3A::new(0.2, 0.92, 1.1), Vec3A::new(3.9, 2.45, 2.14)),
        ];
        for round in 0..3000 {
            let twosided = rng.random::<bool>();
            let d = distr(&mut rng);
            let n = rng.random_range(1..=8);
            // Lanes as `Bsdf::at` makes them of one scene BSDF: its
            // reflectances replaced per lane, all else the same.
            let scene = if round % 2 == 0 {
                let (eta, k) = eta_k[round / 2 % 2];
                BsdfKind::RoughConductor(RoughConductor {
                    eta,
                    k,
                    r: Vec3A::ONE,
                    mirror: round % 7 == 0,
                    distr: d,
                })
            } else {
                let eta = [1.5, 1.33, 2.4][round % 3];
                let nonlinear = round % 4 == 1;
                BsdfKind::RoughPlastic(RoughPlastic::new(
                    eta,
                    spectrum(&mut rng),
                    spectrum(&mut rng),
                    nonlinear,
                    d,
                ))
            };
            let bsdfs: Vec<Bsdf> = (0..n)
                .map(|l| {
                    let mut kind = scene.clone();
                    if l > 0 {
                        match &mut kind {
                            BsdfKind::RoughConductor(c) => c.r = spectrum(&mut rng),
                            BsdfKind::RoughPlastic(p) => {
                                p.c.diffuse = spectrum(&mut rng);
                                p.c.specular = spectrum(&mut rng);
                            }
                            _ => unreachable!(),
                        }
                    }
                    Bsdf {
                        kind,
                        twosided,
                        textures: None,
                    }
                })
                .collect();
            let refs: Vec<&Bsdf> = bsdfs.iter().collect();
            let wi: [Vec3A; 8] = std::array::from_fn(|_| direction(&mut rng));
            let wo: [Vec3A; 8] = std::array::from_fn(|l| match rng.random_range(0..12) {
                0 => wi[l],
                1 => Vec3A::new(-wi[l].x, -wi[l].y, wi[l].z),
                2 => -wi[l],
                _ => direction(&mut rng),
            });
            let (f, pdf) = eval_pdf8(&refs, wi, wo);
            for l in 0..8 {
                let (sf, sp) = refs[l.min(n - 1)].eval_pdf(wi[l], wo[l]);
                let bits = |v: Vec3A| v.to_array().map(f32::to_bits);
                assert_eq!(
                    (bits(f[l]), pdf[l].to_bits()),
                    (bits(sf), sp.to_bits()),
                    "round {round} lane {l}: wi {} wo {}: {:?} {} vs {:?} {}",
                    wi[l],
                    wo[l],
                    f[l],
                    pdf[l],
                    sf,
                    sp
                );
            }
        }
    }
}
