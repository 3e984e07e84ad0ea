//! The version recorded in a configuration and the limits on the sizes of a run.

use crate::error::{Error, Result};

/// The version of sepg recorded in every configuration.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// Largest horizon H (steps per trajectory) a run, an estimate or an exact evaluation
/// accepts: the exact dynamic programme of a clipped preset takes about 60 µs per step, so
/// 10⁵ steps cost seconds per evaluation (docs/RELIABILITY.md, "Sizes").
pub const MAX_HORIZON: usize = 100_000;

/// Largest number of iterations of a run (docs/RELIABILITY.md, "Sizes").
pub const MAX_ITERATIONS: u64 = 1_000_000_000;

/// Largest memory, in bytes, one batch of trajectories may need (8 GiB): sizes beyond are
/// refused before anything is allocated (docs/RELIABILITY.md, "Sizes"). The limit does not
/// depend on the machine, so a configuration resolves the same everywhere.
pub const MAX_BATCH_BYTES: u64 = 8 << 30;

/// Bytes a batch of `n` trajectories of `horizon` steps takes, with `dim_v` mean and `dim_w`
/// log-standard-deviation parameters: per step the discounted reward and the cumulative
/// scores (`1 + dim_v + dim_w` numbers of 8 bytes), per trajectory its length (8 bytes);
/// `None` when the count overflows `u64`.
///
/// ```
/// // 100 trajectories of 20 steps, one parameter of each kind: 100 · (20 · 3 + 1) · 8.
/// assert_eq!(sepg_runs::spec::batch_bytes(100, 20, 1, 1), Some(48_800));
/// assert_eq!(sepg_runs::spec::batch_bytes(usize::MAX, 20, 1, 1), None);
/// ```
pub fn batch_bytes(n: usize, horizon: usize, dim_v: usize, dim_w: usize) -> Option<u64> {
    let per_step = 1u64.checked_add(dim_v as u64)?.checked_add(dim_w as u64)?;
    let per_trajectory = (horizon as u64).checked_mul(per_step)?.checked_add(1)?;
    (n as u64).checked_mul(per_trajectory)?.checked_mul(8)
}

/// Checks that a batch of `n` trajectories of `horizon` steps fits [`MAX_BATCH_BYTES`]
/// (see [`batch_bytes`]); `what` names the option for the message.
///
/// # Errors
/// [`Error::Invalid`] naming the size and the limit.
pub fn check_batch_memory(
    what: &str,
    n: usize,
    horizon: usize,
    dims: (usize, usize),
) -> Result<()> {
    match batch_bytes(n, horizon, dims.0, dims.1) {
        Some(b) if b <= MAX_BATCH_BYTES => Ok(()),
        b => Err(Error::invalid(format!(
            "{what} N = {n} trajectories of H = {horizon} steps need {} of memory, more than \
             the limit of {} GiB",
            b.map_or_else(
                || "more than 2^64 bytes".to_owned(),
                |b| format!("{} GiB", b.div_ceil(1 << 30))
            ),
            MAX_BATCH_BYTES >> 30
        ))),
    }
}

/// Checks `1 ≤ horizon ≤` [`MAX_HORIZON`].
///
/// # Errors
/// [`Error::Invalid`] naming the limit.
pub fn check_horizon(horizon: usize) -> Result<()> {
    if horizon == 0 {
        return Err(Error::invalid("horizon H must be at least 1"));
    }
    if horizon > MAX_HORIZON {
        return Err(Error::invalid(format!(
            "horizon H = {horizon} is above the limit of {MAX_HORIZON} steps"
        )));
    }
    Ok(())
}
