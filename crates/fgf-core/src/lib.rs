//! # fgf-core
//!
//! The analytic heart of fgf: constants of fractional Gaussian fields, the
//! variance of the line-averaged extinction, and the gamma-closure
//! transmittance models with their free-flight samplers (`docs/theory.md` §1–4).
//!
//! Conventions used throughout the workspace:
//! * distances `t` are in scene units, extinctions `sigma_t` in 1/unit,
//!   optical depth `tau = sigma_t * t` is dimensionless;
//! * every sampler takes its uniform variate `u ∈ [0,1)` as an argument;
//! * constructors validate and return [`ParamError`] naming the parameter and
//!   its valid range; nothing is silently clamped.

// `!(t >= 0.0)` is used on purpose: it is true for NaN, which must take
// the invalid-input branch; `partial_cmp` would only obscure that.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod error;
pub mod progress;
pub mod rng;
pub mod stats;
pub mod transmittance;

pub use error::{Cancelled, ParamError, Result};
pub use progress::{NoProgress, Progress};
