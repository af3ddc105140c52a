//! A request to stop, as a signal handler makes it: the analyses check it at every point and
//! end there, with the stop reason "interrupted", so that what was found is still written.
//!
//! Test hook: with the environment variable `MEMSTAB_INTERRUPT_AFTER_STEPS=k` (read once), the
//! request is made from inside the process right after the k-th step any continuation driver
//! accepts (counted over the whole process: a path's steps, then its branches', a curve's or a
//! surface's), as a signal arriving at that moment would make it. It lets the tests interrupt
//! a run at a chosen point of its work without timing a signal.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::OnceLock;

static REQUESTED: AtomicBool = AtomicBool::new(false);
static ACCEPTED: AtomicUsize = AtomicUsize::new(0);

/// The environment variable of the test hook.
pub const AFTER_STEPS: &str = "MEMSTAB_INTERRUPT_AFTER_STEPS";

/// Asks every running analysis to stop at its next point (safe from a signal handler).
pub fn request() {
    REQUESTED.store(true, Ordering::SeqCst);
}

/// Whether a stop was requested.
pub fn requested() -> bool {
    REQUESTED.load(Ordering::SeqCst)
}

/// Counts one accepted continuation step; makes the request after the k-th when the test hook
/// [`AFTER_STEPS`] asks for it.
pub fn step_accepted() {
    static AFTER: OnceLock<Option<usize>> = OnceLock::new();
    let after = AFTER.get_or_init(|| {
        std::env::var(AFTER_STEPS)
            .ok()
            .and_then(|v| v.trim().parse().ok())
    });
    if let Some(k) = *after {
        if ACCEPTED.fetch_add(1, Ordering::SeqCst) + 1 == k {
            request();
        }
    }
}
