//! Surface scattering (BSDFs), evaluated in the local shading frame where
//! `+z` is the shading normal. `wi` points from the surface toward the
//! previous vertex, `wo` toward the next one (Mitsuba's convention).
//! Values include the cosine `|wo.z|`, so a sampled weight is
//! `eval / pdf` and a delta lobe returns its weight directly.
//!
//! The user documentation (parameters, units, ranges, defaults, an XML and
//! a Python example) is the table at the head of [`fgf_scene::xml::bsdfs`];
//! the notes here are about the implementation.
//!
//! * `diffuse`: one-sided: black seen from the back
//! * `null`: index-matched boundary: the path passes straight through; it neither counts toward `max_depth` nor is lit
//! * `dielectric`: smooth, both sides; transmitted radiance is scaled by `(η_i/η_t)²` (Mitsuba's non-symmetric transport in radiance mode)
//! * `conductor`: smooth, complex Fresnel per channel; one-sided
//! * `twosided`: the nested BSDF on both sides
//! * `principled` ([`principled`]): Mitsuba 3's Disney-style BSDF, its
//!   formulas and lobe sampling reproduced step by step
//! * `mask`: the nested BSDF with probability `opacity` (`u1 < opacity`
//!   picks it, and `u1/opacity` is passed on), else a straight-through
//!   sample flagged [`BsdfSample::null`]; value and pdf are the nested
//!   ones times `opacity`, and [`Bsdf::null_transmission`] is what a
//!   shadow ray keeps when crossing it (under `volpath`)
//! * `thindielectric`: a thin slab: `R' = 2R/(1+R)` (all inter-reflections
//!   of the two faces), the rest passes straight through; delta, both sides
//! * `roughconductor`, `roughdielectric` ([`rough`]), `plastic`,
//!   `roughplastic` ([`plastic`]): microfacet models on the distributions of
//!   [`microfacet`]; their non-delta lobes take part in light sampling and MIS
//!
//! One file per family: [`fresnel`], [`microfacet`], [`rough`], [`plastic`];
//! the dispatch is one `match` on the closed [`BsdfKind`] here.

mod eval8;
pub mod fresnel;
pub mod microfacet;
pub mod plastic;
pub mod principled;
pub mod rough;
#[cfg(test)]
mod tests;

pub(crate) use eval8::{eval_pdf8, sample_wo8_lanes};
pub use fresnel::{
    fresnel_conductor, fresnel_conductor_rgb, fresnel_dielectric, FresnelDielectric,
};

use crate::math::{cosine_hemisphere_pdf, sample_cosine_hemisphere};
use crate::spectrum::Spectrum;
use crate::texture::Texture;
use fgf_scene::{BsdfDesc, MicrofacetDesc, MicrofacetKind, TexturedParam};
use glam::{Vec2, Vec3A};
use microfacet::{Distribution, Microfacet};
use plastic::{Plastic, RoughPlastic};
use principled::Principled;
use rough::{RoughConductor, RoughDielectric};
use std::f32::consts::FRAC_1_PI;
use std::marker::PhantomData;
use std::mem::ManuallyDrop;
use std::sync::Arc;

/// The closed set of BSDF models.
#[derive(Debug, Clone)]
pub enum BsdfKind {
    Diffuse {
        reflectance: Spectrum,
    },
    Null,
    /// `eta = int_ior / ext_ior`.
    Dielectric {
        eta: f32,
        r: Spectrum,
        t: Spectrum,
    },
    Conductor {
        eta: Spectrum,
        k: Spectrum,
        r: Spectrum,
        mirror: bool,
    },
    /// `eta = int_ior / ext_ior`.
    ThinDielectric {
        eta: f32,
        r: Spectrum,
        t: Spectrum,
    },
    RoughConductor(RoughConductor),
    RoughDielectric(RoughDielectric),
    Plastic(Plastic),
    RoughPlastic(RoughPlastic),
    Mask(Box<Mask>),
    Principled(Principled),
}

/// `mask`: the nested BSDF with probability `opacity`, else a null
/// interaction (straight through, weight 1).
#[derive(Debug, Clone)]
pub struct Mask {
    pub opacity: f32,
    pub nested: Bsdf,
    /// `nested.is_smooth()`, kept so that [`Bsdf::is_smooth`] stays a
    /// flat test.
    pub smooth: bool,
}

/// The renderer's microfacet distribution of a description.
fn microfacet(m: &MicrofacetDesc) -> Microfacet {
    Microfacet {
        kind: match m.kind {
            MicrofacetKind::Beckmann => Distribution::Beckmann,
            MicrofacetKind::Ggx => Distribution::Ggx,
        },
        ax: m.alpha_u,
        ay: m.alpha_v,
        visible: m.sample_visible,
    }
}

/// A BSDF and whether it is mirrored to the back side (`twosided`).
#[derive(Debug, Clone)]
pub struct Bsdf {
    pub kind: BsdfKind,
    pub twosided: bool,
    /// Parameters given by textures (`kind` holds their means): a path
    /// that hits this BSDF asks [`Bsdf::at`] for the BSDF at the hit's
    /// texture coordinates. `None` for untextured BSDFs, which pay one
    /// branch per hit for this.
    pub textures: Option<Arc<[(TexturedParam, Texture)]>>,
}

/// A textured BSDF made concrete at one hit by [`Bsdf::at_shared`]: reads
/// as a [`Bsdf`], shares the scene BSDF's tables, and releases nothing when
/// it goes.
pub struct SharedAt<'a> {
    bsdf: ManuallyDrop<Bsdf>,
    _scene: PhantomData<&'a Bsdf>,
}

impl std::ops::Deref for SharedAt<'_> {
    type Target = Bsdf;
    #[inline(always)]
    fn deref(&self) -> &Bsdf {
        &self.bsdf
    }
}

/// The BSDF at a hit: the scene's own, or a textured one made concrete
/// there (shared, or owned for a `mask`).
pub enum HitBsdf<'a> {
    Scene(&'a Bsdf),
    Shared(SharedAt<'a>),
    Owned(Bsdf),
}

impl HitBsdf<'_> {
    /// The BSDF `bsdf` at texture coordinates `uv`, computed (by `uv`)
    /// only if it is textured.
    #[inline(always)]
    pub fn new(bsdf: &Bsdf, uv: impl FnOnce() -> Vec2) -> HitBsdf<'_> {
        match bsdf.textures {
            None => HitBsdf::Scene(bsdf),
            Some(_) => {
                let uv = uv();
                match bsdf.at_shared(uv) {
                    Some(b) => HitBsdf::Shared(b),
                    None => HitBsdf::Owned(bsdf.at(uv)),
                }
            }
        }
    }
}

impl std::ops::Deref for HitBsdf<'_> {
    type Target = Bsdf;
    #[inline(always)]
    fn deref(&self) -> &Bsdf {
        match self {
            HitBsdf::Scene(b) => b,
            HitBsdf::Shared(b) => b,
            HitBsdf::Owned(b) => b,
        }
    }
}

/// The result of sampling a BSDF.
#[derive(Debug, Clone, Copy)]
pub struct BsdfSample {
    /// Sampled direction in the local frame.
    pub wo: Vec3A,
    /// `f·|cos| / pdf` (for a delta lobe, the lobe weight over its choice probability).
    pub weight: Spectrum,
    /// Solid-angle pdf; for delta lobes the discrete choice probability.
    pub pdf: f32,
    pub delta: bool,
    /// Relative index of refraction crossed (1 for reflection), for Russian roulette.
    pub eta: f32,
    /// A null interaction (Mitsuba's `BSDFFlags::Null`): the path went
    /// straight through (a `thindielectric`'s transmission, a `mask`'s
    /// transparent part).
    pub null: bool,
}

impl BsdfSample {
    /// The sample of a non-delta reflection toward `wo`, where the BSDF's
    /// value is `f` and its pdf `pdf` (`None` unless `pdf > 0`).
    #[inline]
    pub(crate) fn glossy(wo: Vec3A, f: Spectrum, pdf: f32) -> Option<BsdfSample> {
        (pdf > 0.0).then(|| BsdfSample {
            wo,
            weight: f / pdf,
            pdf,
            delta: false,
            eta: 1.0,
            null: false,
        })
    }
}

impl Bsdf {
    pub fn from_desc(d: &BsdfDesc) -> Bsdf {
        let c = crate::spectrum::from_rgb;
        match d {
            BsdfDesc::Diffuse { reflectance } => Bsdf {
                kind: BsdfKind::Diffuse {
                    reflectance: c(*reflectance),
                },
                twosided: false,
                textures: None,
            },
            BsdfDesc::Null => Bsdf {
                kind: BsdfKind::Null,
                twosided: false,
                textures: None,
            },
            BsdfDesc::Dielectric {
                int_ior,
                ext_ior,
                specular_reflectance,
                specular_transmittance,
            } => Bsdf {
                kind: BsdfKind::Dielectric {
                    eta: int_ior / ext_ior,
                    r: c(*specular_reflectance),
                    t: c(*specular_transmittance),
                },
                twosided: false,
                textures: None,
            },
            BsdfDesc::Conductor {
                eta,
                k,
                specular_reflectance,
                perfect_mirror,
            } => Bsdf {
                kind: BsdfKind::Conductor {
                    eta: c(*eta),
                    k: c(*k),
                    r: c(*specular_reflectance),
                    mirror: *perfect_mirror,
                },
                twosided: false,
                textures: None,
            },
            BsdfDesc::ThinDielectric {
                int_ior,
                ext_ior,
                specular_reflectance,
                specular_transmittance,
            } => Bsdf {
                kind: BsdfKind::ThinDielectric {
                    eta: int_ior / ext_ior,
                    r: c(*specular_reflectance),
                    t: c(*specular_transmittance),
                },
                twosided: false,
                textures: None,
            },
            BsdfDesc::RoughConductor {
                eta,
                k,
                specular_reflectance,
                perfect_mirror,
                microfacet: m,
            } => Bsdf {
                kind: BsdfKind::RoughConductor(RoughConductor {
                    eta: c(*eta),
                    k: c(*k),
                    r: c(*specular_reflectance),
                    mirror: *perfect_mirror,
                    distr: microfacet(m),
                }),
                twosided: false,
                textures: None,
            },
            BsdfDesc::RoughDielectric {
                int_ior,
                ext_ior,
                specular_reflectance,
                specular_transmittance,
                microfacet: m,
            } => Bsdf {
                kind: BsdfKind::RoughDielectric(RoughDielectric {
                    eta: int_ior / ext_ior,
                    r: c(*specular_reflectance),
                    t: c(*specular_transmittance),
                    distr: microfacet(m),
                }),
                twosided: false,
                textures: None,
            },
            BsdfDesc::Plastic {
                int_ior,
                ext_ior,
                diffuse_reflectance,
                specular_reflectance,
                nonlinear,
                microfacet: m,
            } => {
                let eta = int_ior / ext_ior;
                let (d, sp) = (c(*diffuse_reflectance), c(*specular_reflectance));
                Bsdf {
                    kind: match m {
                        None => BsdfKind::Plastic(Plastic::new(eta, d, sp, *nonlinear)),
                        Some(m) => BsdfKind::RoughPlastic(RoughPlastic::new(
                            eta,
                            d,
                            sp,
                            *nonlinear,
                            microfacet(m),
                        )),
                    },
                    twosided: false,
                    textures: None,
                }
            }
            BsdfDesc::Principled(d) => Bsdf {
                kind: BsdfKind::Principled(Principled {
                    base_color: c(d.base_color),
                    roughness: d.roughness,
                    metallic: d.metallic,
                    spec_trans: d.spec_trans,
                    spec_tint: d.spec_tint,
                    sheen: d.sheen,
                    sheen_tint: d.sheen_tint,
                    flatness: d.flatness,
                    clearcoat: d.clearcoat,
                    clearcoat_gloss: d.clearcoat_gloss,
                    anisotropic: d.anisotropic,
                    eta: d.eta,
                    spec_rate: d.spec_rate,
                    clearcoat_rate: d.clearcoat_rate,
                    diffuse_rate: d.diffuse_rate,
                    has_spec_trans: d.has_spec_trans,
                    has_clearcoat: d.has_clearcoat,
                }),
                twosided: false,
                textures: None,
            },
            BsdfDesc::Mask { opacity, nested } => {
                let nested = Bsdf::from_desc(nested);
                Bsdf {
                    // A textured nested BSDF makes the mask textured too
                    // (`at` then makes the nested one concrete).
                    textures: nested.textures.as_ref().map(|_| Arc::from([])),
                    kind: BsdfKind::Mask(Box::new(Mask {
                        opacity: *opacity,
                        smooth: nested.is_smooth(),
                        nested,
                    })),
                    twosided: false,
                }
            }
            BsdfDesc::TwoSided(inner) => Bsdf {
                twosided: true,
                ..Bsdf::from_desc(inner)
            },
            BsdfDesc::Textured { base, textures } => Bsdf {
                textures: Some(
                    textures
                        .iter()
                        .map(|(p, t)| (*p, Texture::from_desc(t)))
                        .collect(),
                ),
                ..Bsdf::from_desc(base)
            },
        }
    }

    /// This BSDF at texture coordinates `uv`: each textured parameter takes
    /// its texture's value there (Mitsuba's lobe-sampling weights of
    /// `plastic` keep the textures' means, as Mitsuba's do).
    #[inline(never)]
    pub fn at(&self, uv: Vec2) -> Bsdf {
        let mut b = Bsdf {
            kind: self.kind.clone(),
            twosided: self.twosided,
            textures: None,
        };
        self.set_textured(&mut b.kind, uv);
        if let BsdfKind::Mask(m) = &mut b.kind {
            if m.nested.textures.is_some() {
                m.nested = m.nested.at(uv);
            }
        }
        b
    }

    /// Write the textured parameters' values at `uv` into `kind` (a copy
    /// of `self.kind`). Only plain values are written: nothing that owns
    /// memory is replaced or dropped ([`Bsdf::at_shared`] relies on it).
    #[inline(always)]
    fn set_textured(&self, kind: &mut BsdfKind, uv: Vec2) {
        use TexturedParam as P;
        for (param, tex) in self.textures.iter().flat_map(|t| t.iter()) {
            match (param, &mut *kind) {
                (P::Reflectance, BsdfKind::Diffuse { reflectance }) => *reflectance = tex.eval(uv),
                (
                    P::SpecularReflectance,
                    BsdfKind::Dielectric { r, .. }
                    | BsdfKind::ThinDielectric { r, .. }
                    | BsdfKind::Conductor { r, .. },
                ) => *r = tex.eval(uv),
                (P::SpecularReflectance, BsdfKind::RoughConductor(c)) => c.r = tex.eval(uv),
                (P::SpecularReflectance, BsdfKind::RoughDielectric(c)) => c.r = tex.eval(uv),
                (
                    P::SpecularTransmittance,
                    BsdfKind::Dielectric { t, .. } | BsdfKind::ThinDielectric { t, .. },
                ) => *t = tex.eval(uv),
                (P::SpecularTransmittance, BsdfKind::RoughDielectric(c)) => c.t = tex.eval(uv),
                (P::DiffuseReflectance, BsdfKind::Plastic(p)) => p.c.diffuse = tex.eval(uv),
                (P::DiffuseReflectance, BsdfKind::RoughPlastic(p)) => p.c.diffuse = tex.eval(uv),
                (P::SpecularReflectance, BsdfKind::Plastic(p)) => p.c.specular = tex.eval(uv),
                (P::SpecularReflectance, BsdfKind::RoughPlastic(p)) => p.c.specular = tex.eval(uv),
                (P::Alpha, BsdfKind::RoughConductor(c)) => {
                    let a = tex.eval_1(uv);
                    (c.distr.ax, c.distr.ay) = (a, a);
                }
                (P::Alpha, BsdfKind::RoughDielectric(c)) => {
                    let a = tex.eval_1(uv);
                    (c.distr.ax, c.distr.ay) = (a, a);
                }
                (P::Eta, BsdfKind::Conductor { eta, .. }) => *eta = tex.eval(uv),
                (P::Eta, BsdfKind::RoughConductor(c)) => c.eta = tex.eval(uv),
                (P::K, BsdfKind::Conductor { k, .. }) => *k = tex.eval(uv),
                (P::K, BsdfKind::RoughConductor(c)) => c.k = tex.eval(uv),
                (P::AlphaU, BsdfKind::RoughConductor(c)) => c.distr.ax = tex.eval_1(uv),
                (P::AlphaU, BsdfKind::RoughDielectric(c)) => c.distr.ax = tex.eval_1(uv),
                (P::AlphaV, BsdfKind::RoughConductor(c)) => c.distr.ay = tex.eval_1(uv),
                (P::AlphaV, BsdfKind::RoughDielectric(c)) => c.distr.ay = tex.eval_1(uv),
                (P::Opacity, BsdfKind::Mask(m)) => m.opacity = tex.eval_1(uv).clamp(0.0, 1.0),
                (P::BaseColor, BsdfKind::Principled(b)) => b.base_color = tex.eval(uv),
                (P::Roughness, BsdfKind::Principled(b)) => b.roughness = tex.eval_1(uv),
                (P::Metallic, BsdfKind::Principled(b)) => b.metallic = tex.eval_1(uv),
                (P::SpecTrans, BsdfKind::Principled(b)) => b.spec_trans = tex.eval_1(uv),
                (P::SpecTint, BsdfKind::Principled(b)) => b.spec_tint = tex.eval_1(uv),
                (P::Sheen, BsdfKind::Principled(b)) => b.sheen = tex.eval_1(uv),
                (P::SheenTint, BsdfKind::Principled(b)) => b.sheen_tint = tex.eval_1(uv),
                (P::Flatness, BsdfKind::Principled(b)) => b.flatness = tex.eval_1(uv),
                (P::Clearcoat, BsdfKind::Principled(b)) => b.clearcoat = tex.eval_1(uv),
                (P::ClearcoatGloss, BsdfKind::Principled(b)) => b.clearcoat_gloss = tex.eval_1(uv),
                (P::Anisotropic, BsdfKind::Principled(b)) => b.anisotropic = tex.eval_1(uv),
                // The validator refuses other pairs.
                _ => {}
            }
        }
    }

    /// [`Bsdf::at`] without the reference counts: the copy shares this
    /// BSDF's tables (a `roughplastic`'s, behind an `Arc`) instead of
    /// owning them, so a textured hit takes and releases no count, whose
    /// atomic updates the render's threads would contend for. `None` for a
    /// `mask`, whose nested BSDF is boxed (use [`Bsdf::at`]).
    #[inline(never)]
    pub fn at_shared(&self, uv: Vec2) -> Option<SharedAt<'_>> {
        if matches!(self.kind, BsdfKind::Mask(_)) {
            return None;
        }
        // SAFETY: a bitwise copy of `self` that is never dropped
        // (`ManuallyDrop`) and lives no longer than `self` (the lifetime of
        // `SharedAt`): the `Arc`s it holds are `self`'s, used only to read
        // what `self` keeps alive, and never released. It holds no `Box`
        // (a `mask` is refused above), so no unique pointer is duplicated.
        // `set_textured` writes plain values only; `textures` is replaced
        // by `ptr::write`, which drops nothing.
        let mut b = unsafe {
            let mut b = ManuallyDrop::new(std::ptr::read(self));
            std::ptr::write(&mut b.textures, None);
            b
        };
        self.set_textured(&mut b.kind, uv);
        Some(SharedAt {
            bsdf: b,
            _scene: PhantomData,
        })
    }

    /// True if the BSDF's value changes under a rotation about the normal
    /// (different roughness along the tangent and the bitangent): it is
    /// then evaluated in the tangent-oriented shading frame.
    #[inline]
    pub fn is_anisotropic(&self) -> bool {
        match &self.kind {
            BsdfKind::Diffuse { .. } => false,
            BsdfKind::RoughConductor(b) => b.distr.ax != b.distr.ay,
            BsdfKind::RoughDielectric(b) => b.distr.ax != b.distr.ay,
            BsdfKind::Principled(b) => b.anisotropic > 0.0,
            _ => false,
        }
    }

    #[inline]
    pub fn is_null(&self) -> bool {
        matches!(self.kind, BsdfKind::Null)
    }

    /// True if the BSDF has a null lobe besides its others (see
    /// [`BsdfSample::null`]): `thindielectric`, `mask`. Under `volpath`
    /// the path tracer counts a sample of it as an index-matched crossing
    /// (no depth), as Mitsuba 3's volpath counts a `Null` lobe
    /// ([`crate::world::World::thin_is_crossing`]).
    #[inline]
    pub fn has_null_lobe(&self) -> bool {
        matches!(
            self.kind,
            BsdfKind::ThinDielectric { .. } | BsdfKind::Mask(_)
        )
    }

    /// The weight with which a shadow ray arriving along `wi` (local frame)
    /// passes straight through (Mitsuba's `eval_null_transmission`): 1 for
    /// `null`, `(1 − R')·T` for `thindielectric`, `1 − opacity·(1 − nested)`
    /// for `mask`, 0 for the others.
    pub fn null_transmission(&self, wi: Vec3A) -> Spectrum {
        match &self.kind {
            BsdfKind::Null => Spectrum::ONE,
            &BsdfKind::ThinDielectric { eta, t, .. } => {
                let f = fresnel_dielectric(wi.z.abs(), eta).r;
                t * (1.0 - 2.0 * f / (1.0 + f))
            }
            BsdfKind::Mask(m) => {
                Spectrum::ONE - m.opacity * (Spectrum::ONE - m.nested.null_transmission(wi))
            }
            _ => Spectrum::ZERO,
        }
    }

    /// True if the BSDF has a non-delta lobe, so light sampling helps.
    #[inline]
    pub fn is_smooth(&self) -> bool {
        match &self.kind {
            BsdfKind::Diffuse { .. }
            | BsdfKind::RoughConductor(_)
            | BsdfKind::RoughDielectric(_)
            | BsdfKind::Plastic(_)
            | BsdfKind::RoughPlastic(_)
            | BsdfKind::Principled(_) => true,
            BsdfKind::Mask(m) => m.smooth,
            _ => false,
        }
    }

    /// `f(wi, wo)·|wo.z|` and the pdf of sampling `wo` (zero for delta lobes).
    ///
    /// The diffuse case stays inline (the hot path of the reference scenes);
    /// the other models are evaluated out of line.
    #[inline]
    pub fn eval_pdf(&self, mut wi: Vec3A, mut wo: Vec3A) -> (Spectrum, f32) {
        if self.twosided && wi.z < 0.0 {
            wi.z = -wi.z;
            wo.z = -wo.z;
        }
        if let BsdfKind::Diffuse { reflectance } = &self.kind {
            if wi.z <= 0.0 || wo.z <= 0.0 {
                return (Spectrum::ZERO, 0.0);
            }
            return (
                *reflectance * (FRAC_1_PI * wo.z),
                cosine_hemisphere_pdf(wo.z),
            );
        }
        self.eval_pdf_glossy(wi, wo)
    }

    #[inline(never)]
    fn eval_pdf_glossy(&self, wi: Vec3A, wo: Vec3A) -> (Spectrum, f32) {
        match &self.kind {
            BsdfKind::RoughConductor(b) => b.eval_pdf(wi, wo),
            BsdfKind::RoughDielectric(b) => b.eval_pdf(wi, wo),
            BsdfKind::Plastic(b) => b.eval_pdf(wi, wo),
            BsdfKind::RoughPlastic(b) => b.eval_pdf(wi, wo),
            BsdfKind::Principled(b) => b.eval_pdf(wi, wo),
            BsdfKind::Mask(m) => {
                let (f, pdf) = m.nested.eval_pdf(wi, wo);
                (f * m.opacity, pdf * m.opacity)
            }
            _ => (Spectrum::ZERO, 0.0),
        }
    }

    /// Sample `wo` given `wi`; `u1` picks a lobe, `u2` the direction.
    ///
    /// As in [`Self::eval_pdf`], the diffuse case stays inline and the other
    /// models are sampled out of line.
    #[inline]
    pub fn sample(&self, mut wi: Vec3A, u1: f32, u2: [f32; 2]) -> Option<BsdfSample> {
        let BsdfKind::Diffuse { reflectance } = &self.kind else {
            return self.sample_other(wi, u1, u2);
        };
        let flipped = self.twosided && wi.z < 0.0;
        if flipped {
            wi.z = -wi.z;
        }
        if wi.z <= 0.0 {
            return None;
        }
        let mut wo = sample_cosine_hemisphere(u2);
        if wo.z <= 0.0 {
            return None;
        }
        let pdf = cosine_hemisphere_pdf(wo.z);
        if flipped {
            wo.z = -wo.z;
        }
        Some(BsdfSample {
            wo,
            weight: *reflectance,
            pdf,
            delta: false,
            eta: 1.0,
            null: false,
        })
    }

    /// [`Self::sample`] for every model but the diffuse one.
    #[inline(never)]
    fn sample_other(&self, mut wi: Vec3A, u1: f32, u2: [f32; 2]) -> Option<BsdfSample> {
        let flipped = self.twosided && wi.z < 0.0;
        if flipped {
            wi.z = -wi.z;
        }
        let mut s = match &self.kind {
            BsdfKind::Diffuse { .. } => unreachable!("diffuse is sampled inline"),
            BsdfKind::Null => BsdfSample {
                wo: -wi,
                weight: Spectrum::ONE,
                pdf: 1.0,
                delta: true,
                eta: 1.0,
                null: true,
            },
            &BsdfKind::Dielectric { eta, r, t } => {
                let f = fresnel_dielectric(wi.z, eta);
                if u1 < f.r {
                    BsdfSample {
                        wo: Vec3A::new(-wi.x, -wi.y, wi.z),
                        weight: r,
                        pdf: f.r,
                        delta: true,
                        eta: 1.0,
                        null: false,
                    }
                } else {
                    // Refracted direction: tangential part scaled by η_i/η_t.
                    let wo = Vec3A::new(-f.eta_ti * wi.x, -f.eta_ti * wi.y, f.cos_t);
                    // Radiance is compressed into the smaller solid angle on
                    // the denser side: scale by (η_i/η_t)².
                    BsdfSample {
                        wo,
                        weight: t * (f.eta_ti * f.eta_ti),
                        pdf: 1.0 - f.r,
                        delta: true,
                        eta: f.eta_it,
                        null: false,
                    }
                }
            }
            &BsdfKind::ThinDielectric { eta, r, t } => {
                let f = fresnel_dielectric(wi.z.abs(), eta).r;
                // All inter-reflections between the two faces of the slab.
                let rr = if f < 1.0 { 2.0 * f / (1.0 + f) } else { 1.0 };
                if u1 < rr {
                    BsdfSample {
                        wo: Vec3A::new(-wi.x, -wi.y, wi.z),
                        weight: r,
                        pdf: rr,
                        delta: true,
                        eta: 1.0,
                        null: false,
                    }
                } else {
                    BsdfSample {
                        wo: -wi,
                        weight: t,
                        pdf: 1.0 - rr,
                        delta: true,
                        eta: 1.0,
                        null: true,
                    }
                }
            }
            BsdfKind::RoughConductor(b) => b.sample(wi, u2)?,
            BsdfKind::RoughDielectric(b) => b.sample(wi, u1, u2)?,
            BsdfKind::Plastic(b) => b.sample(wi, u1, u2)?,
            BsdfKind::RoughPlastic(b) => b.sample(wi, u1, u2)?,
            BsdfKind::Principled(b) => b.sample(wi, u1, u2)?,
            BsdfKind::Mask(m) => {
                if u1 < m.opacity {
                    let mut s = m.nested.sample(wi, u1 / m.opacity, u2)?;
                    s.pdf *= m.opacity;
                    s
                } else {
                    BsdfSample {
                        wo: -wi,
                        weight: Spectrum::ONE,
                        pdf: 1.0 - m.opacity,
                        delta: true,
                        eta: 1.0,
                        null: true,
                    }
                }
            }
            &BsdfKind::Conductor { eta, k, r, mirror } => {
                if wi.z <= 0.0 {
                    return None;
                }
                let fr = if mirror {
                    Spectrum::ONE
                } else {
                    fresnel_conductor_rgb(wi.z, eta, k)
                };
                BsdfSample {
                    wo: Vec3A::new(-wi.x, -wi.y, wi.z),
                    weight: r * fr,
                    pdf: 1.0,
                    delta: true,
                    eta: 1.0,
                    null: false,
                }
            }
        };
        if flipped {
            s.wo.z = -s.wo.z;
        }
        Some(s)
    }
}
