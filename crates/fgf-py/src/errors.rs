//! Python exceptions. All are `ValueError` subclasses so that callers who
//! only know the standard library still catch them; I/O errors on output
//! files become `OSError`.

use pyo3::create_exception;
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::PyErr;

create_exception!(
    _core,
    FgfError,
    PyValueError,
    "Base class of every fgf error."
);
create_exception!(
    _core,
    ParameterError,
    FgfError,
    "A parameter is outside its valid range; the message names it and the range."
);
create_exception!(
    _core,
    SceneError,
    FgfError,
    "A scene file (or a file it references) is invalid; the message names the file and line."
);

/// `fgf_core::ParamError` -> `fgf.ParameterError`.
pub fn param_err(e: fgf_core::ParamError) -> PyErr {
    ParameterError::new_err(e.to_string())
}

/// `fgf_io::IoError` -> `OSError` (missing files, permissions) or
/// `fgf.FgfError` (bad content).
pub fn io_err(e: fgf_io::IoError) -> PyErr {
    match e {
        fgf_io::IoError::Io { .. } => PyOSError::new_err(e.to_string()),
        fgf_io::IoError::Format { .. } => FgfError::new_err(e.to_string()),
    }
}
