//! Scene description and loading.

pub mod desc;
pub mod error;
pub mod xml;

pub use desc::*;
pub use error::{SceneError, SceneErrorKind};
pub use xml::{load_file, load_str};
