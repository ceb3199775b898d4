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
//! * [`render`](mod@render): the renderer's entry point, from a `SceneDesc` to pixels;
//!   [`integrator`] (volumetric path tracing), [`medium`] (the medium
//!   interface, homogeneous and grid media), [`geometry`] (shapes, BVH),
//!   [`bsdf`], [`emitter`], [`phase`], [`camera`], [`film`], [`math`].

pub mod bsdf;
pub mod camera;
pub mod emitter;
/// Ground truth from explicit realizations of `fgf` media (issue 5).
pub mod ensemble;
pub mod film;
pub mod geometry;
pub mod integrator;
pub mod math;
pub mod medium;
pub mod phase;
pub mod render;

pub use render::{render, RenderError, RenderOptions, RenderOutput};
