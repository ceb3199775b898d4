//! Progress reporting and cancellation for long jobs (rendering, synthesis,
//! ensembles). Physics code reports through this trait; the front ends decide
//! how to show it (an indicatif bar on stderr for the CLI, a tqdm-compatible
//! callback in Python) and when to cancel (Ctrl-C).

use crate::error::Cancelled;

/// Implemented by front ends. All methods are called from worker threads and
/// must be cheap (an atomic add), so call `inc` per tile or per row, not per
/// sample.
pub trait Progress: Sync {
    /// Work units finished since the last call.
    fn inc(&self, n: u64);
    /// True once the user asked to stop; long jobs check it between work
    /// units, finish the unit in flight and return what they have.
    fn cancelled(&self) -> bool {
        false
    }
    /// `Err(Cancelled)` once [`Progress::cancelled`] is true, for `?` at
    /// the end of a work stage.
    fn check_cancelled(&self) -> Result<(), Cancelled> {
        if self.cancelled() {
            Err(Cancelled)
        } else {
            Ok(())
        }
    }
}

/// Reports nothing and never cancels.
pub struct NoProgress;

impl Progress for NoProgress {
    fn inc(&self, _n: u64) {}
}
