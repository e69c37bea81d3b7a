//! Ctrl-C for long commands that can stop cleanly (`gspn simulate`): the
//! first Ctrl-C raises a flag the command polls (it stops at its next check,
//! some milliseconds later, and says where it was); a second one ends the
//! process at once. Commands that never ask for the flag keep the default:
//! Ctrl-C ends them at once (lab batches resume where they stopped).

use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, Ordering};

static FLAG: AtomicBool = AtomicBool::new(false);
static INSTALLED: OnceLock<bool> = OnceLock::new();

/// The flag Ctrl-C raises, installing the handler on first use; `None` if
/// the handler could not be installed (Ctrl-C then ends the process, as by
/// default).
pub fn flag() -> Option<&'static AtomicBool> {
    let installed = *INSTALLED.get_or_init(|| {
        ctrlc::set_handler(|| {
            if FLAG.swap(true, Ordering::Relaxed) {
                // Second Ctrl-C: the user does not want to wait.
                std::process::exit(130);
            }
        })
        .is_ok()
    });
    installed.then_some(&FLAG)
}
