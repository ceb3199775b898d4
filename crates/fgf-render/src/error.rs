//! The renderer's error. Errors of the crates below (a model parameter that
//! `fgf-core` rejects, a field synthesis that `fgf-field` refuses) are kept
//! as their [`source`](std::error::Error::source), with the medium they
//! concern, not flattened into text.
//!
//! A cancelled job is an error too, [`RenderError::Cancelled`], which
//! carries the image of the passes finished so that a front end can still
//! write it (the ensemble's `EnsembleError` does the same with the
//! realizations finished).

use crate::film::RenderOutput;
use fgf_core::ParamError;
use fgf_field::FieldError;

/// Errors of `render()` and the modules it builds on: the scene problems
/// found when compiling a scene, features outside the supported subset, bad
/// options, and cancellation.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The description breaks a rule of [`fgf_scene::SceneDesc::validate`].
    #[error(transparent)]
    Scene(#[from] fgf_scene::SceneError),
    /// The scene description is invalid in a way only compiling it shows.
    #[error("invalid scene: {0}")]
    InvalidScene(String),
    /// A parameter of medium `medium` that its `fgf-core` model rejects.
    #[error("invalid scene: medium {medium}: {source}")]
    Param {
        medium: usize,
        #[source]
        source: ParamError,
    },
    /// A feature outside the supported subset.
    #[error("not supported: {0}")]
    Unsupported(String),
    /// A parameter of medium `medium` that is valid for the model but not
    /// for the feature asked for; `why` says what to do instead.
    #[error("not supported: medium {medium}: {source} ({why})")]
    UnsupportedParam {
        medium: usize,
        #[source]
        source: ParamError,
        why: &'static str,
    },
    /// A render (or ensemble) option out of range.
    #[error("invalid render option: {0}")]
    InvalidOption(String),
    /// The random field of medium `medium` could not be synthesized.
    #[error("invalid render option: medium {medium}: field synthesis: {source}")]
    Field {
        medium: usize,
        #[source]
        source: FieldError,
    },
    /// A sample (or a pixel's sum of samples, or of their squares) outside
    /// the exact accumulator's range (`docs/theory.md` §7.17).
    #[error(
        "pixel ({x}, {y}) channel {channel}: sample value {value:e} takes the pixel's sum (or sum of \
         squares) outside the exact accumulator's range |sum| < {limit:e}; the image would be wrong, \
         so the render stops (check the scene's emitter and medium scales)"
    )]
    OutOfRange {
        x: usize,
        y: usize,
        channel: usize,
        value: f64,
        limit: f64,
    },
    /// [`fgf_core::Progress::cancelled`] asked the render to stop: `partial`
    /// is the image of the passes finished (`spp_done` samples per pixel,
    /// possibly 0).
    #[error("interrupted after {} of {} samples per pixel", .partial.spp_done, .partial.spp_requested)]
    Cancelled { partial: Box<RenderOutput> },
}
