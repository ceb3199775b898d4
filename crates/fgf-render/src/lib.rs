//! # fgf-render
//!
//! A CPU volumetric path tracer for a subset of the Mitsuba 3 XML scene
//! format, with classical (homogeneous, grid) and non-exponential (FGF,
//! Bitterli 2018) media.
//!
//! The renderer consumes a [`fgf_scene::SceneDesc`], the plain-data scene
//! description of the `fgf-scene` crate (which also holds its validator and
//! the XML loader): that description is the only contract between the two.
//!
//! * [`render`](mod@render): the renderer's entry point, from a `SceneDesc` to
//!   pixels ([`film`] holds the image it returns), [`error`] its error;
//!   [`world`] (the scene compiled for rendering), [`integrator`]
//!   (volumetric path tracing), [`medium`] (the medium interface,
//!   homogeneous, grid and non-exponential media), [`geometry`] (shapes,
//!   BVH, texture coordinates), [`ray`], [`bsdf`], [`texture`], [`emitter`], [`phase`], [`camera`],
//!   [`spectrum`] (the colour type), [`math`]; `lanes`, the 8-lane vectors
//!   of the BVH and of the kernels that shade 8 paths at once.
//! * [`ensemble`]: ground truth from explicit realizations of `fgf` media.
//! * [`truth`]: exact ground truth for constant-α media by quadrature over
//!   the level of homogeneous realizations.

// `!(x > 0.0)` is used on purpose: it is true for NaN, which must take the
// degenerate branch (as in fgf-core); `partial_cmp` would only obscure that.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod bsdf;
pub mod camera;
pub mod emitter;
pub mod ensemble;
pub mod error;
pub mod film;
pub mod geometry;
mod huge;
pub use huge::HugePages;
pub mod integrator;
mod lanes;
pub mod math;
pub mod medium;
pub mod phase;
pub mod ray;
pub mod render;
pub mod spectrum;
pub mod texture;
pub mod truth;
pub mod world;

pub use error::RenderError;
pub use film::RenderOutput;
pub use render::{render, render_owned, RenderOptions};
