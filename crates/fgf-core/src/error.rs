//! The two errors every crate of the workspace shares: an invalid parameter
//! ([`ParamError`]) and a job stopped by the user ([`Cancelled`]). The
//! other crates' error enums carry them as their `Param` and `Cancelled`
//! variants (`#[from]`), so a parameter error keeps its fields all the way
//! to the front ends.

/// A parameter outside its valid range. The message names the parameter,
/// the value given and the valid range, e.g.
/// `invalid hurst = 0: must not be 0 or an integer (valid: -0.5 <= hurst, non-integer, hurst != 0)`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("invalid {name} = {value}: {reason} (valid: {range})")]
pub struct ParamError {
    /// Parameter name as the user spells it (`sigma_t`, `hurst`, `sw`, ...).
    pub name: String,
    /// The offending value, formatted.
    pub value: String,
    /// Why it is rejected.
    pub reason: String,
    /// The valid range, in words or interval notation.
    pub range: String,
}

impl ParamError {
    pub fn new(
        name: impl Into<String>,
        value: impl std::fmt::Display,
        reason: impl Into<String>,
        range: impl Into<String>,
    ) -> Self {
        ParamError {
            name: name.into(),
            value: value.to_string(),
            reason: reason.into(),
            range: range.into(),
        }
    }

    /// Check `value` is finite and strictly positive.
    pub fn check_positive(name: &str, value: f64) -> Result<f64> {
        if value.is_finite() && value > 0.0 {
            Ok(value)
        } else {
            Err(ParamError::new(
                name,
                value,
                "must be finite and > 0",
                "0 < value < inf",
            ))
        }
    }

    /// Check `value` is finite and >= 0.
    pub fn check_non_negative(name: &str, value: f64) -> Result<f64> {
        if value.is_finite() && value >= 0.0 {
            Ok(value)
        } else {
            Err(ParamError::new(
                name,
                value,
                "must be finite and >= 0",
                "0 <= value < inf",
            ))
        }
    }
}

/// A long job (rendering, synthesis, an ensemble) stopped because its
/// [`Progress`](crate::Progress) asked it to. A job that can hand back a
/// partial result carries it in its own error variant next to this one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, thiserror::Error)]
#[error("interrupted")]
pub struct Cancelled;

pub type Result<T, E = ParamError> = std::result::Result<T, E>;
