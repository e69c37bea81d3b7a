//! Running Rust work for Python: panics caught, the GIL released during
//! long calls, Ctrl-C honoured.
//!
//! A long call ([`detached`]) runs on a worker thread while the calling
//! thread, without the GIL, waits for it and every 50 ms takes the GIL
//! back to run Python's signal handlers (`PyErr_CheckSignals`). When they
//! raise (Ctrl-C: `KeyboardInterrupt`), the stop flag handed to the work
//! is raised; the work ends at its next checkpoint (see
//! `petri::interrupt` and `lab::runner::BatchParams::stop`), the worker is
//! joined — nothing is left running — and the `KeyboardInterrupt` is
//! raised. Other Python threads run meanwhile.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Condvar, Mutex, PoisonError};
use std::time::Duration;

use pyo3::prelude::*;

use crate::errors::{self, Kind};

/// How often the waiting thread looks for signals.
const POLL: Duration = Duration::from_millis(50);

/// The worker's stack: the expression parser and the readers recurse
/// (bounded by their own limits), as on the command line's main thread.
const STACK_BYTES: usize = 64 << 20;

/// Runs `f` on this thread with the GIL held, a panic turned into
/// `PanicError` and an error into its exception (`default` when no
/// cause's type says better). For quick calls.
pub(crate) fn guarded<T>(
    py: Python<'_>,
    default: Kind,
    f: impl FnOnce() -> anyhow::Result<T>,
) -> PyResult<T> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(v)) => Ok(v),
        Ok(Err(e)) => Err(errors::to_py(py, &e, default)),
        Err(payload) => Err(errors::panic_to_py(py, payload)),
    }
}

/// Runs `work` on a worker thread without the GIL; Ctrl-C raises the flag
/// it is handed and, once it has returned, `KeyboardInterrupt` (module
/// docs). Errors and panics as in [`guarded`].
pub(crate) fn detached<T, F>(py: Python<'_>, default: Kind, work: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce(&Arc<AtomicBool>) -> anyhow::Result<T> + Send,
{
    let stop = Arc::new(AtomicBool::new(false));
    // Set by the worker as it ends, whatever the outcome.
    let done = (Mutex::new(false), Condvar::new());
    std::thread::scope(|scope| {
        let (flag, done) = (&stop, &done);
        let handle = std::thread::Builder::new()
            .name("petrinav".into())
            .stack_size(STACK_BYTES)
            .spawn_scoped(scope, move || {
                let r = catch_unwind(AssertUnwindSafe(|| work(flag)));
                *done.0.lock().unwrap_or_else(PoisonError::into_inner) = true;
                done.1.notify_all();
                r
            })
            .map_err(|e| errors::raise(py, Kind::Error, format!("cannot start a worker thread: {e}")))?;
        let mut interrupted: Option<PyErr> = None;
        loop {
            let finished = py.detach(|| {
                let guard = done.0.lock().unwrap_or_else(PoisonError::into_inner);
                let (guard, _) = done
                    .1
                    .wait_timeout_while(guard, POLL, |finished| !*finished)
                    .unwrap_or_else(PoisonError::into_inner);
                *guard
            });
            if finished {
                break;
            }
            if interrupted.is_none()
                && let Err(e) = py.check_signals()
            {
                stop.store(true, Ordering::Relaxed);
                interrupted = Some(e);
            }
        }
        let joined = py.detach(|| handle.join());
        if let Some(e) = interrupted {
            return Err(e);
        }
        match joined {
            Ok(Ok(Ok(v))) => Ok(v),
            Ok(Ok(Err(e))) => Err(errors::to_py(py, &e, default)),
            Ok(Err(payload)) | Err(payload) => Err(errors::panic_to_py(py, payload)),
        }
    })
}
