//! # fgf-io
//!
//! File formats shared by the field synthesis and the renderer:
//!
//! * [`vol`]: Mitsuba 3 `.vol` grids (read and write; layout in `formats.md`).
//! * [`vdb`]: OpenVDB float grids (write one, read one densely; `docs/vdb.md`).
//! * [`image`]: linear float32 RGB/greyscale EXR (scanlines) and 8-bit PNG.
//! * [`atomic_write`]: every writer goes through a temporary file in the
//!   target directory and a rename, so a failed or interrupted write never
//!   leaves a half-written file and never clobbers the user's old file.

pub mod image;
pub mod vdb;
pub mod vol;

use std::io::Write;
use std::path::{Path, PathBuf};

/// Check that `path` is a regular file (following symlinks) before anyone
/// opens it: opening a FIFO blocks until a writer appears, and a device or a
/// directory is never a scene, mesh or grid.
pub fn check_regular(path: &Path) -> std::io::Result<std::fs::Metadata> {
    let meta = std::fs::metadata(path)?;
    if meta.is_file() {
        return Ok(meta);
    }
    let what = if meta.is_dir() {
        "a directory"
    } else {
        "not a regular file (a FIFO, socket or device)"
    };
    Err(std::io::Error::new(std::io::ErrorKind::InvalidInput, what))
}

/// A regular file (see [`check_regular`]) opened for reading, and its size.
pub fn open_regular(path: &Path) -> std::io::Result<(std::fs::File, u64)> {
    check_regular(path)?;
    let file = std::fs::File::open(path)?;
    let len = file.metadata()?.len();
    Ok((file, len))
}

/// [`std::fs::read`] of a regular file only (see [`check_regular`]).
pub fn read_regular(path: &Path) -> std::io::Result<Vec<u8>> {
    check_regular(path)?;
    std::fs::read(path)
}

/// An I/O or format error, always naming the file.
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {msg}")]
    Format { path: PathBuf, msg: String },
}

impl IoError {
    pub fn io(path: &Path, source: std::io::Error) -> Self {
        IoError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
    pub fn format(path: &Path, msg: impl Into<String>) -> Self {
        IoError::Format {
            path: path.to_path_buf(),
            msg: msg.into(),
        }
    }
}

pub type Result<T, E = IoError> = std::result::Result<T, E>;

/// Write a file atomically: `fill` writes into a temporary file created next
/// to `path`; only if it succeeds is the temporary file renamed over `path`.
/// On any error the temporary file is removed and `path` is untouched.
pub fn atomic_write<F>(path: &Path, fill: F) -> Result<()>
where
    F: FnOnce(&mut std::io::BufWriter<&std::fs::File>) -> std::result::Result<(), String>,
{
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !dir.is_dir() {
        return Err(IoError::format(
            path,
            format!("output directory {} does not exist", dir.display()),
        ));
    }
    let mut builder = tempfile::Builder::new();
    builder.prefix(".fgf-tmp-");
    // tempfile creates private (0600) files; ask for 0666 instead, which the
    // OS reduces by the umask, so the result has the permissions a plain
    // `File::create` would give.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let tmp = builder
        .tempfile_in(&dir)
        .map_err(|e| IoError::io(path, e))?;
    {
        let mut w = std::io::BufWriter::new(tmp.as_file());
        fill(&mut w).map_err(|msg| IoError::format(path, msg))?;
        w.flush().map_err(|e| IoError::io(path, e))?;
    }
    tmp.as_file().sync_all().map_err(|e| IoError::io(path, e))?;
    tmp.persist(path).map_err(|e| IoError::io(path, e.error))?;
    Ok(())
}
