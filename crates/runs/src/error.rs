//! The error type of every operation on run folders, sweeps, audits and reproductions.

use std::path::PathBuf;

/// The error another operation failed with, kept as the [`std::error::Error::source`] of an
/// [`Error`].
pub type Source = Box<dyn std::error::Error + Send + Sync + 'static>;

/// What [`Error::Invalid`] and [`Error::Failed`] carry: the message for the user and, when
/// the failure came from another error (an I/O error, a malformed file, an oracle that
/// failed), that error as its source.
///
/// The message is complete on its own (it already quotes the source where the command line
/// shows it), so printing the message alone loses nothing; its
/// [`source`](std::error::Error::source) lets a caller walk the chain to the original error.
#[derive(Debug, thiserror::Error)]
#[error("{text}")]
pub struct Message {
    text: String,
    #[source]
    source: Option<Source>,
}

impl Message {
    /// The message as the command line prints it.
    pub fn text(&self) -> &str {
        &self.text
    }
}

impl From<String> for Message {
    fn from(text: String) -> Self {
        Message { text, source: None }
    }
}

/// Why an operation on a run, sweep, audit or reproduction failed.
///
/// The message of each variant is one complete sentence fragment meant for a user: the
/// command line prints it as is. [`Error::Invalid`] is the caller's to fix (a bad option,
/// file or folder); the other variants happened while running. [`Error::Invalid`] and
/// [`Error::Failed`] keep the error they came from, if any, as their
/// [`source`](std::error::Error::source).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Bad input: an invalid or inapplicable option, a malformed file, a folder that is not
    /// what the operation needs.
    #[error(transparent)]
    Invalid(Message),
    /// The operation ran and failed: an I/O error, an iteration of the algorithm that
    /// failed, an oracle that could not evaluate a policy, a figure that could not be drawn.
    #[error(transparent)]
    Failed(Message),
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
        Error::Invalid(Message::from(message.into()))
    }

    /// A failure while running (see [`Error::Failed`]).
    pub(crate) fn failed(message: impl Into<String>) -> Self {
        Error::Failed(Message::from(message.into()))
    }

    /// Bad input caused by `source`: the message is `"{context}: {source}"`, and `source`
    /// is kept as the error's [`source`](std::error::Error::source).
    ///
    /// ```
    /// use std::error::Error as _;
    /// let io = std::io::Error::new(std::io::ErrorKind::NotFound, "no such file");
    /// let e = sepg_runs::Error::invalid_from("cannot read log.csv", io);
    /// assert_eq!(e.to_string(), "cannot read log.csv: no such file");
    /// assert!(e.source().is_some_and(|s| s.is::<std::io::Error>()));
    /// ```
    pub fn invalid_from(context: impl std::fmt::Display, source: impl Into<Source>) -> Self {
        let source = source.into();
        Error::Invalid(Message {
            text: format!("{context}: {source}"),
            source: Some(source),
        })
    }

    /// A failure while running caused by `source`: the message is `"{context}: {source}"`,
    /// and `source` is kept as the error's [`source`](std::error::Error::source).
    pub fn failed_from(context: impl std::fmt::Display, source: impl Into<Source>) -> Self {
        let source = source.into();
        Error::Failed(Message {
            text: format!("{context}: {source}"),
            source: Some(source),
        })
    }

    /// This error with `source` as its [`source`](std::error::Error::source), the message
    /// unchanged: for a message that quotes its source other than as `"{context}: {source}"`.
    /// Only [`Error::Invalid`] and [`Error::Failed`] carry a source; the other variants are
    /// returned as they are.
    pub fn with_source(self, source: impl Into<Source>) -> Self {
        match self {
            Error::Invalid(m) => Error::Invalid(Message {
                source: Some(source.into()),
                ..m
            }),
            Error::Failed(m) => Error::Failed(Message {
                source: Some(source.into()),
                ..m
            }),
            other => other,
        }
    }

    /// Whether the error is bad input rather than a failure while running.
    pub fn is_invalid_input(&self) -> bool {
        matches!(self, Error::Invalid(_))
    }
}

/// Result of the operations of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use std::error::Error as _;
    use std::io;

    use super::*;
    use crate::sweep::{SweepFile, read_spec};

    /// The messages of `e` and of every error below it, outermost first.
    fn chain(e: &(dyn std::error::Error + 'static)) -> Vec<String> {
        let mut out = vec![e.to_string()];
        let mut next = e.source();
        while let Some(s) = next {
            out.push(s.to_string());
            next = s.source();
        }
        out
    }

    #[test]
    fn a_missing_file_keeps_its_io_error_as_the_source() {
        let dir = tempfile::tempdir().expect("tempdir");
        let missing = dir.path().join("sweep.toml");
        let e = read_spec(&missing).expect_err("no such file");
        let expected = io::ErrorKind::NotFound;
        let io = e
            .source()
            .and_then(|s| s.downcast_ref::<io::Error>())
            .expect("the io::Error is the source");
        assert_eq!(io.kind(), expected);
        assert!(e.is_invalid_input());
        // The message still quotes the io::Error, as the command line printed it before.
        assert_eq!(
            e.to_string(),
            format!("cannot read {}: {io}", missing.display())
        );
        let e = SweepFile::read(dir.path()).expect_err("no sweep.json");
        let io = e.source().and_then(|s| s.downcast_ref::<io::Error>());
        assert_eq!(io.map(io::Error::kind), Some(expected));
    }

    #[test]
    fn the_chain_walks_from_the_context_to_the_original_error() {
        let io = io::Error::new(io::ErrorKind::PermissionDenied, "denied");
        let inner = Error::invalid_from("cannot read log.csv", io);
        let outer = Error::failed_from("run seed-3", inner);
        assert!(!outer.is_invalid_input());
        assert_eq!(
            chain(&outer),
            [
                "run seed-3: cannot read log.csv: denied",
                "cannot read log.csv: denied",
                "denied",
            ]
        );
        let bottom = outer
            .source()
            .and_then(|s| s.source())
            .and_then(|s| s.downcast_ref::<io::Error>())
            .expect("the io::Error at the bottom");
        assert_eq!(bottom.kind(), io::ErrorKind::PermissionDenied);
    }

    #[test]
    fn a_message_without_a_source_ends_the_chain() {
        let e = Error::invalid("--alpha 2 must be in (0, 1)");
        assert_eq!(chain(&e), ["--alpha 2 must be in (0, 1)"]);
        let json = serde_json::from_str::<serde_json::Value>("{").expect_err("malformed");
        let text = format!("summary.json is malformed: {json}");
        let e = Error::failed(text.clone()).with_source(json);
        assert_eq!(e.to_string(), text);
        assert!(e.source().is_some_and(|s| s.is::<serde_json::Error>()));
        let stopped = Error::Interrupted {
            iteration: 1,
            total: 2,
            dir: PathBuf::from("r"),
        }
        .with_source(io::Error::other("ignored"));
        assert!(stopped.source().is_none());
    }
}
