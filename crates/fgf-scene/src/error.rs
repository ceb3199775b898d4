//! The error of the scene loader. It always names the scene file and, when
//! the problem sits in the XML, the line, column and tag:
//!
//! ```text
//! scenes/cube.xml:31:9: <bsdf type="principledthin"> unknown BSDF type 'principledthin' (supported: diffuse, null, dielectric, thindielectric, roughdielectric, conductor, roughconductor, plastic, roughplastic, twosided, mask, principled)
//! ```
//!
//! Errors in a file that the scene references (a mesh, a `.vol` grid, an
//! included XML file) name both: the scene line that references it and the
//! referenced file with its own problem.

use std::fmt;
use std::path::PathBuf;

/// What went wrong, for callers that map errors to their own kinds (the
/// Python binding maps [`SceneErrorKind::Io`] to `OSError`, the rest to
/// `fgf.SceneError`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SceneErrorKind {
    /// The XML is not well formed (truncated, mismatched tags, ...).
    Syntax,
    /// Well-formed XML that is outside the supported subset or has invalid
    /// values (unknown plugin, unknown parameter, wrong type, out of range).
    Invalid,
    /// A file (the scene itself or one it references) cannot be read.
    Io,
    /// A referenced file has invalid content (bad `.vol` header, bad mesh).
    Format,
    /// The caller asked the load to stop (Ctrl-C).
    Cancelled,
}

/// Longest user value that a message quotes in full.
pub const CLIP_CHARS: usize = 80;

/// `value`, cut to [`CLIP_CHARS`] characters with its length said, for
/// quoting user input (a `-D` value, an attribute) in a one-line message.
pub fn clip(value: &str) -> String {
    let n = value.chars().count();
    if n <= CLIP_CHARS {
        value.to_string()
    } else {
        let head: String = value.chars().take(CLIP_CHARS).collect();
        format!("{head}... ({n} characters)")
    }
}

/// A scene-loading error; see the module docs for its display form.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct SceneError {
    pub kind: SceneErrorKind,
    /// The scene (or included) file where the problem is.
    pub file: PathBuf,
    /// 1-based line and column; `None` when the error is not tied to a
    /// position (for example the scene file itself cannot be read).
    pub pos: Option<(u32, u32)>,
    /// The tag, as written: `<shape type="obj">`, `<float name="fov">`.
    pub tag: Option<String>,
    pub message: String,
}

impl SceneError {
    pub fn new(kind: SceneErrorKind, file: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        SceneError {
            kind,
            file: file.into(),
            pos: None,
            tag: None,
            message: message.into(),
        }
    }
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if let Some((line, col)) = self.pos {
            write!(f, ":{line}:{col}")?;
        }
        write!(f, ": ")?;
        if let Some(tag) = &self.tag {
            write!(f, "{tag} ")?;
        }
        write!(f, "{}", self.message)
    }
}
