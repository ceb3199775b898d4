//! # fgf-scene
//!
//! The scene side of fgf's renderer, and the only crate that knows XML:
//!
//! * [`desc`]: the plain-data [`SceneDesc`] the renderer consumes; scenes
//!   can be built in code as well as loaded;
//! * [`validate`](mod@validate): [`SceneDesc::validate`], the one set of
//!   rules every description obeys, whether it was loaded or built in code
//!   (the loader and `fgf_render`'s `World::build` both call it);
//! * [`xml`]: the Mitsuba 3 XML loader ([`load_file`], [`load_str`]), with
//!   the user documentation of every supported plugin, one table per
//!   plugin family;
//! * [`error`]: [`SceneError`], which names the file, line and tag.

pub mod desc;
pub mod error;
pub mod validate;
pub mod xml;

pub use desc::*;
pub use error::{SceneError, SceneErrorKind};
pub use xml::{load_file, load_file_cancellable, load_str};
