//! The set-up of a new run, shared by `sepg run` and `sepg.run`: the options of a TOML file
//! overlaid by the caller's, resolved by this version, and the output folder checked, ready
//! to [`start`](crate::run::start).

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::folder::{RUN_FILES, Summary, check_out_dir};
use crate::run::{self, RunOptions};
use crate::spec::{Resolved, RunSpec};

/// A new run whose options are resolved and whose folder is ready to be written.
#[derive(Debug, Clone)]
pub struct NewRun {
    /// The run folder: absent, empty, or (with `force`) holding a previous run's files.
    pub dir: PathBuf,
    /// The resolved options.
    pub resolved: Resolved,
}

impl NewRun {
    /// Runs the new run to completion (see [`run::start`]).
    ///
    /// # Errors
    /// As [`run::start`].
    pub fn start(&self, opts: RunOptions<'_>) -> Result<Summary> {
        run::start(&self.dir, &self.resolved, opts)
    }
}

/// Sets up a new run: the options of the TOML file `config` (keys are the option names; none
/// without a file) overlaid by `options`, re-resolved by this version (a configuration copied
/// from an earlier run loses its `sepg_version`), and the folder `out` checked to be absent or
/// empty (unless `force`, which allows replacing a previous run's files).
///
/// # Errors
/// [`Error::Invalid`] for an unreadable or malformed file, an invalid or inapplicable option,
/// no `out`, or a folder that is not empty or cannot be read.
pub fn set_up(
    config: Option<&Path>,
    options: &RunSpec,
    out: Option<&Path>,
    force: bool,
) -> Result<NewRun> {
    let file = match config {
        Some(path) => RunSpec::from_file(path)?,
        None => RunSpec::default(),
    };
    let merged = RunSpec {
        sepg_version: None,
        ..file.overlay(options)
    };
    let resolved = merged.resolve()?;
    let dir = out.ok_or_else(|| Error::invalid("--out DIR is required"))?;
    check_out_dir(dir, force, &RUN_FILES)?;
    Ok(NewRun {
        dir: dir.to_path_buf(),
        resolved,
    })
}
