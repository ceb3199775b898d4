//! Scene description and loading.

pub mod desc;
pub mod xml;

pub use desc::*;
