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

pub mod scene;
