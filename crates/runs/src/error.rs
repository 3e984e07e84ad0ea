//! The error type of every operation on run folders, sweeps, audits and reproductions.

use std::path::PathBuf;

/// Why an operation on a run, sweep, audit or reproduction failed.
///
/// The message of each variant is one complete sentence fragment meant for a user: the
/// command line prints it as is. [`Error::Invalid`] is the caller's to fix (a bad option,
/// file or folder); the other variants happened while running.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Bad input: an invalid or inapplicable option, a malformed file, a folder that is not
    /// what the operation needs.
    #[error("{0}")]
    Invalid(String),
    /// The operation ran and failed: an I/O error, an iteration of the algorithm that
    /// failed, an oracle that could not evaluate a policy, a figure that could not be drawn.
    #[error("{0}")]
    Failed(String),
    /// The stop flag was raised; the run stopped after `iteration` of `total` iterations and
    /// its folder holds a checkpoint to resume from.
    #[error(
        "interrupted after iteration {iteration} of {total}; resume with: sepg run --resume {}",
        dir.display()
    )]
    Interrupted {
        /// Iterations completed and checkpointed.
        iteration: u64,
        /// Iterations of the whole run.
        total: u64,
        /// The run folder.
        dir: PathBuf,
    },
    /// The stop flag was raised during a sweep; every unfinished run of it stopped at a
    /// checkpoint, and the sweep resumes with `sepg sweep --resume`.
    #[error(
        "interrupted with {complete} of {runs} runs complete; resume with: sepg sweep --resume {}",
        dir.display()
    )]
    SweepInterrupted {
        /// Runs of the shard that are complete.
        complete: usize,
        /// Runs of the shard.
        runs: usize,
        /// The sweep folder.
        dir: PathBuf,
    },
}

impl Error {
    /// Bad input (see [`Error::Invalid`]).
    pub(crate) fn invalid(message: impl Into<String>) -> Self {
        Error::Invalid(message.into())
    }

    /// A failure while running (see [`Error::Failed`]).
    pub(crate) fn failed(message: impl Into<String>) -> Self {
        Error::Failed(message.into())
    }

    /// Whether the error is bad input rather than a failure while running.
    pub fn is_invalid_input(&self) -> bool {
        matches!(self, Error::Invalid(_))
    }
}

/// Result of the operations of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;
