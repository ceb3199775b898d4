//! The error of the field crate and the memory check every large
//! allocation goes through.

use fgf_core::{Cancelled, ParamError};

/// Errors of the field crate. An invalid parameter carries the shared
/// [`ParamError`] (its name, value and valid range), a cancelled job the
/// shared [`Cancelled`].
#[derive(Debug, thiserror::Error)]
pub enum FieldError {
    #[error(transparent)]
    Param(#[from] ParamError),
    /// Refused before allocating anything.
    #[error("{what} needs about {} but only {} is available (MemAvailable in /proc/meminfo, or what the address-space limit leaves); use a smaller shape, less padding or float32", fmt_bytes(*.needed), fmt_bytes(*.available))]
    OutOfMemory {
        what: String,
        needed: u64,
        available: u64,
    },
    /// The [`Progress`](fgf_core::Progress) asked to stop.
    #[error(transparent)]
    Cancelled(#[from] Cancelled),
}

fn fmt_bytes(b: u64) -> String {
    let gib = b as f64 / (1u64 << 30) as f64;
    if gib >= 1.0 {
        format!("{gib:.2} GiB")
    } else {
        format!("{:.1} MiB", b as f64 / (1u64 << 20) as f64)
    }
}

/// `MemAvailable` from `/proc/meminfo`, in bytes; `None` where it cannot be
/// read (non-Linux), in which case no refusal happens.
pub fn mem_available() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = s.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    let system = kib * 1024;
    // Under an address-space limit (`ulimit -v`) an allocation past it fails
    // and Rust aborts: what counts is the room left below the limit.
    Some(match address_space_left() {
        Some(left) => system.min(left),
        None => system,
    })
}

/// The process's address-space limit (RLIMIT_AS, from /proc/self/limits)
/// minus its current virtual size; `None` when unlimited or unknown.
fn address_space_left() -> Option<u64> {
    let limits = std::fs::read_to_string("/proc/self/limits").ok()?;
    let line = limits
        .lines()
        .find(|l| l.starts_with("Max address space"))?;
    let soft: u64 = line.split_whitespace().nth(3)?.parse().ok()?;
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let vm = status.lines().find(|l| l.starts_with("VmSize:"))?;
    let used_kib: u64 = vm.split_whitespace().nth(1)?.parse().ok()?;
    Some(soft.saturating_sub(used_kib * 1024))
}

/// Refuse `needed` bytes if they exceed what the system has available.
pub(crate) fn check_memory(what: &str, needed: Option<u64>) -> Result<(), FieldError> {
    let available = mem_available().unwrap_or(u64::MAX);
    match needed {
        Some(n) if n <= available => Ok(()),
        n => Err(FieldError::OutOfMemory {
            what: what.to_string(),
            needed: n.unwrap_or(u64::MAX),
            available,
        }),
    }
}
