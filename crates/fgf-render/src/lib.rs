//! # fgf-render
//!
//! A CPU volumetric path tracer for a subset of the Mitsuba 3 XML scene
//! format, with classical (homogeneous, grid) and non-exponential (FGF,
//! Bitterli 2018) media.
//!
//! * [`scene::desc`]: the plain-data scene description. The XML loader
//!   produces it; the renderer consumes it. It is the only contract between
//!   the two halves.
//! * [`scene::xml`]: the Mitsuba 3 XML loader.
//! * [`render`](mod@render): the renderer's entry point, from a `SceneDesc` to pixels;
//!   [`integrator`] (volumetric path tracing), [`medium`] (the medium
//!   interface, homogeneous and grid media), [`geometry`] (shapes, BVH),
//!   [`bsdf`], [`emitter`], [`phase`], [`camera`], [`film`], [`math`].

pub mod scene;

pub mod bsdf;
pub mod camera;
pub mod emitter;
/// Ground truth from explicit realizations of `fgf` media.
pub mod ensemble;
pub mod error;
pub mod film;
pub mod geometry;
pub mod integrator;
pub mod math;
pub mod medium;
pub mod phase;
pub mod ray;
pub mod render;
pub mod spectrum;
pub mod world;

pub use error::RenderError;
pub use film::RenderOutput;
pub use render::{render, RenderOptions};
