//! A request to stop, as a signal handler makes it: the analyses check it at every point and
//! end there, with the stop reason "interrupted", so that what was found is still written.
//!
//! Every long loop checks the one flag [`requested`]: the path driver at every point, a
//! linear-buckling sweep at every sample, the localisation of a crossing between trial points,
//! every Newton solve at a fixed control (the start, a carried state, a deflated solve)
//! between its iterations ([`SolveError::Interrupted`](super::SolveError::Interrupted)) — not
//! inside one factorisation —, a comparison between its meshes and levels, the benchmark
//! between its studies, a spectrum between its blocks.
//!
//! Test hooks (each read once): with `MEMSTAB_INTERRUPT_AFTER_STEPS=k` the request is made from
//! inside the process right after the k-th step accepted (counted over the whole process: a
//! path's steps, then its branches', a curve's or a surface's, a linear-buckling sweep's
//! samples), and with `MEMSTAB_INTERRUPT_AFTER_ITERATIONS=k` right after the k-th Newton
//! iteration at a fixed control (a start solve's), and with `MEMSTAB_INTERRUPT_AFTER_BLOCKS=k`
//! right after the k-th block of a one-point spectrum (`memstab spectrum`) is done, as a signal
//! arriving at that moment would make it. They let the tests interrupt a command at a chosen point of its work without timing
//! a signal.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::OnceLock;

static REQUESTED: AtomicBool = AtomicBool::new(false);
static ACCEPTED: AtomicUsize = AtomicUsize::new(0);
static ITERATIONS: AtomicUsize = AtomicUsize::new(0);
static BLOCKS: AtomicUsize = AtomicUsize::new(0);

/// The environment variable of the test hook counting accepted steps.
pub const AFTER_STEPS: &str = "MEMSTAB_INTERRUPT_AFTER_STEPS";
/// The environment variable of the test hook counting Newton iterations at a fixed control.
pub const AFTER_ITERATIONS: &str = "MEMSTAB_INTERRUPT_AFTER_ITERATIONS";
/// The environment variable of the test hook counting the blocks of a one-point spectrum.
pub const AFTER_BLOCKS: &str = "MEMSTAB_INTERRUPT_AFTER_BLOCKS";

/// Asks every running analysis to stop at its next point (safe from a signal handler).
pub fn request() {
    REQUESTED.store(true, Ordering::SeqCst);
}

/// Whether a stop was requested.
pub fn requested() -> bool {
    REQUESTED.load(Ordering::SeqCst)
}

/// Withdraws the request once the work it stopped has returned, so that a process that goes
/// on (a Python session after a `KeyboardInterrupt`) can start new work; the test hooks'
/// counts go on.
pub fn clear() {
    REQUESTED.store(false, Ordering::SeqCst);
}

/// Counts one accepted continuation step; makes the request after the k-th when the test hook
/// [`AFTER_STEPS`] asks for it.
pub fn step_accepted() {
    static AFTER: OnceLock<Option<usize>> = OnceLock::new();
    count(&AFTER, AFTER_STEPS, &ACCEPTED);
}

/// Counts one Newton iteration at a fixed control; makes the request after the k-th when the
/// test hook [`AFTER_ITERATIONS`] asks for it.
pub fn iteration_done() {
    static AFTER: OnceLock<Option<usize>> = OnceLock::new();
    count(&AFTER, AFTER_ITERATIONS, &ITERATIONS);
}

/// Counts one block of a one-point spectrum done; makes the request after the k-th when the
/// test hook [`AFTER_BLOCKS`] asks for it.
pub fn block_done() {
    static AFTER: OnceLock<Option<usize>> = OnceLock::new();
    count(&AFTER, AFTER_BLOCKS, &BLOCKS);
}

/// Counts one event in `counter`; requests a stop at the k-th when `var` is k.
fn count(after: &OnceLock<Option<usize>>, var: &str, counter: &AtomicUsize) {
    let after = after.get_or_init(|| std::env::var(var).ok().and_then(|v| v.trim().parse().ok()));
    if let Some(k) = *after {
        if counter.fetch_add(1, Ordering::SeqCst) + 1 == k {
            request();
        }
    }
}
