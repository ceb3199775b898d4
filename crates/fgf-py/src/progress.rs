//! Progress bars and Ctrl-C for long jobs.
//!
//! [`run_job`] runs a job with the GIL released on a scoped worker thread
//! (which may itself use rayon); the calling thread wakes every 100 ms,
//! takes the GIL, forwards progress to the front end and checks for
//! Ctrl-C. On Ctrl-C the job is asked to stop through
//! [`fgf_core::Progress::cancelled`], and its (partial) result is returned
//! with `interrupted = true`; the caller reports how much was done.
//!
//! Front ends (`progress=` in the Python API):
//! * `None` / `False`: quiet;
//! * `"bar"`: an indicatif bar on stderr (the CLI's; hidden when stderr is
//!   not a terminal);
//! * an object with `update(n)` (a `tqdm` instance): `update` is called with
//!   the units finished since the last call;
//! * any other callable: called as `progress(done, total)`.

use fgf_core::Progress;
use pyo3::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Duration;

/// Shared between the worker and the polling thread.
pub struct Counter {
    done: AtomicU64,
    cancel: AtomicBool,
}

impl Progress for Counter {
    fn inc(&self, n: u64) {
        self.done.fetch_add(n, Ordering::Relaxed);
    }
    fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }
}

enum Sink {
    Quiet,
    Bar(indicatif::ProgressBar),
    Update(Py<PyAny>),
    Call(Py<PyAny>),
}

impl Sink {
    fn new(
        py: Python<'_>,
        progress: Option<&Bound<'_, PyAny>>,
        total: u64,
        label: &str,
    ) -> PyResult<Self> {
        let Some(obj) = progress else {
            return Ok(Sink::Quiet);
        };
        if obj.is_none() {
            return Ok(Sink::Quiet);
        }
        if let Ok(b) = obj.extract::<bool>() {
            if !b {
                return Ok(Sink::Quiet);
            }
        }
        if let Ok(s) = obj.extract::<String>() {
            if s == "bar" {
                let bar = indicatif::ProgressBar::with_draw_target(
                    Some(total),
                    indicatif::ProgressDrawTarget::stderr(),
                );
                bar.set_style(
                    indicatif::ProgressStyle::with_template(
                        "{msg} [{elapsed_precise}] {wide_bar} {pos}/{len} (ETA {eta})",
                    )
                    .expect("valid template"),
                );
                bar.set_message(label.to_string());
                return Ok(Sink::Bar(bar));
            }
            return Err(pyo3::exceptions::PyValueError::new_err(format!(
                "progress={s:?}: expected None, a bool, \"bar\", a tqdm-like object or a callable"
            )));
        }
        if obj.hasattr("update")? {
            return Ok(Sink::Update(obj.clone().unbind()));
        }
        if obj.is_callable() {
            return Ok(Sink::Call(obj.clone().unbind()));
        }
        let _ = py;
        Err(pyo3::exceptions::PyTypeError::new_err(
            "progress must be None, a bool, \"bar\", a tqdm-like object with update(n), or a callable(done, total)",
        ))
    }

    fn report(&self, py: Python<'_>, done: u64, last: u64, total: u64) -> PyResult<()> {
        match self {
            Sink::Quiet => Ok(()),
            Sink::Bar(b) => {
                b.set_position(done);
                Ok(())
            }
            Sink::Update(o) => {
                if done > last {
                    o.call_method1(py, "update", (done - last,))?;
                }
                Ok(())
            }
            Sink::Call(o) => {
                if done > last {
                    o.call1(py, (done, total))?;
                }
                Ok(())
            }
        }
    }

    fn finish(&self) {
        if let Sink::Bar(b) = self {
            b.finish_and_clear();
        }
    }
}

/// Outcome of [`run_job`].
pub struct JobResult<R> {
    pub value: R,
    /// True if the user pressed Ctrl-C and the job stopped early.
    pub interrupted: bool,
}

/// Run `job` with the GIL released, reporting progress in `total` units.
/// A Python exception raised by the progress callback cancels the job and is
/// re-raised after it stops.
pub fn run_job<R, F>(
    py: Python<'_>,
    total: u64,
    label: &str,
    progress: Option<&Bound<'_, PyAny>>,
    job: F,
) -> PyResult<JobResult<R>>
where
    R: Send,
    F: FnOnce(&Counter) -> R + Send,
{
    let sink = Sink::new(py, progress, total, label)?;
    let counter = Counter {
        done: AtomicU64::new(0),
        cancel: AtomicBool::new(false),
    };
    let mut interrupted = false;
    let mut callback_error: Option<PyErr> = None;
    let ended = AtomicBool::new(false);
    let value = py.detach(|| {
        std::thread::scope(|s| {
            // The job wakes the polling thread when it ends, so a short job
            // does not wait out the 100 ms poll interval. It raises `ended`
            // before the wake-up: `is_finished` alone becomes true only once
            // the thread has returned, which may be after the poller has
            // woken, seen it still running and gone back to sleep for the
            // whole interval. (`is_finished` still ends the loop if the job
            // panics.)
            let poller = std::thread::current();
            let counter_ref = &counter;
            let ended_ref = &ended;
            let handle = s.spawn(move || {
                let value = job(counter_ref);
                ended_ref.store(true, Ordering::Release);
                poller.unpark();
                value
            });
            let mut last = 0u64;
            while !ended.load(Ordering::Acquire) && !handle.is_finished() {
                std::thread::park_timeout(Duration::from_millis(100));
                Python::attach(|py| {
                    if let Err(e) = py.check_signals() {
                        if e.is_instance_of::<pyo3::exceptions::PyKeyboardInterrupt>(py) {
                            interrupted = true;
                        } else if callback_error.is_none() {
                            callback_error = Some(e);
                        }
                        counter.cancel.store(true, Ordering::Relaxed);
                    }
                    let done = counter.done.load(Ordering::Relaxed);
                    if callback_error.is_none() {
                        if let Err(e) = sink.report(py, done, last, total) {
                            callback_error = Some(e);
                            counter.cancel.store(true, Ordering::Relaxed);
                        }
                    }
                    last = done;
                });
            }
            let value = handle.join();
            Python::attach(|py| {
                let done = counter.done.load(Ordering::Relaxed);
                if callback_error.is_none() {
                    if let Err(e) = sink.report(py, done, last, total) {
                        callback_error = Some(e);
                    }
                }
            });
            value
        })
    });
    sink.finish();
    let value = match value {
        Ok(v) => v,
        Err(panic) => {
            let msg = panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "unknown panic".into());
            return Err(pyo3::exceptions::PyRuntimeError::new_err(format!(
                "internal error in fgf (please report): {msg}"
            )));
        }
    };
    if let Some(e) = callback_error {
        return Err(e);
    }
    Ok(JobResult { value, interrupted })
}

/// Run a short job that may block (loading a scene: reading files, parsing
/// includes) on its own thread, with the GIL released, checking for Ctrl-C
/// every 50 ms. On Ctrl-C the job's `cancel` flag is set (a loader polls it
/// and stops soon after) and the `KeyboardInterrupt` is returned at once,
/// without waiting for the job: a read that blocks in the kernel must not
/// keep the interrupt from working.
pub fn run_interruptible<R, F>(py: Python<'_>, job: F) -> PyResult<R>
where
    R: Send + 'static,
    F: FnOnce(&AtomicBool) -> R + Send + 'static,
{
    use std::sync::mpsc::{channel, RecvTimeoutError};
    use std::sync::Arc;
    let cancel = Arc::new(AtomicBool::new(false));
    let (tx, rx) = channel();
    let flag = cancel.clone();
    std::thread::Builder::new()
        .name("fgf-load".into())
        .spawn(move || {
            let _ = tx.send(job(&flag));
        })
        .map_err(|e| pyo3::exceptions::PyOSError::new_err(format!("cannot start a thread: {e}")))?;
    let mut rx = rx;
    loop {
        let (got, back) = py.detach(move || (rx.recv_timeout(Duration::from_millis(50)), rx));
        rx = back;
        match got {
            Ok(value) => return Ok(value),
            Err(RecvTimeoutError::Disconnected) => {
                return Err(pyo3::exceptions::PyRuntimeError::new_err(
                    "internal error: the scene loader stopped without a result",
                ))
            }
            Err(RecvTimeoutError::Timeout) => {
                if let Err(e) = py.check_signals() {
                    cancel.store(true, Ordering::Relaxed);
                    return Err(e);
                }
            }
        }
    }
}
