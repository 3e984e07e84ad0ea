//! A process-wide request to cancel long computations: the rollout engine checks it once per
//! chunk of 64 trajectories and the clipped dynamic programme once per horizon step, and both
//! return a `Cancelled` error once it is raised, so that a program can stop within a fraction
//! of a second in the middle of an iteration (the `sepg` command line raises it on Ctrl-C). A
//! computation that completes returns exactly what it returns without the check: the request
//! only ever discards work.

use std::sync::atomic::{AtomicBool, Ordering};

static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Raises the request: every rollout and dynamic programme running or started afterwards
/// returns its `Cancelled` error, until [`clear`].
pub fn request() {
    REQUESTED.store(true, Ordering::SeqCst);
}

/// Withdraws the request.
pub fn clear() {
    REQUESTED.store(false, Ordering::SeqCst);
}

/// Whether the request is raised.
///
/// ```
/// use sepg_mdp::cancel;
/// assert!(!cancel::requested());
/// ```
#[inline]
pub fn requested() -> bool {
    REQUESTED.load(Ordering::Relaxed)
}
