//! One process-wide stop request, set by SIGINT/SIGTERM in the command line and polled by every
//! loop whose length an input decides (scene build, sewing, recording), so a signal ends every
//! phase of a run.

use std::sync::atomic::{AtomicBool, Ordering};

static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Asks every long loop to stop at its next check.
pub fn request() {
    REQUESTED.store(true, Ordering::Relaxed);
}

/// Whether a stop was requested.
pub fn requested() -> bool {
    REQUESTED.load(Ordering::Relaxed)
}

/// The flag itself, for APIs that take an `&AtomicBool` (e.g. the recorder's `stop`).
pub fn flag() -> &'static AtomicBool {
    &REQUESTED
}
