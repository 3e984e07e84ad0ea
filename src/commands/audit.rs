//! `sepg audit DIR`: re-checks the log of a run folder against the run's safety requirement
//! and reports every iteration that broke it, and by how much (the checks are listed in
//! [`sepg_runs::audit`]).
//!
//! Exit status: 0 when no iteration broke the requirement, 1 when some did, 2 for bad input.

use std::path::PathBuf;

use clap::Args;
use sepg_runs::audit::{audit, render};

use crate::cli::CliError;

/// Arguments of `sepg audit`.
#[derive(Debug, Args)]
pub struct AuditArgs {
    /// Run folder written by `sepg run` (complete, or interrupted: its checkpointed rows).
    #[arg(value_name = "DIR")]
    dir: PathBuf,
    /// Print the report as JSON on standard output instead of the table.
    #[arg(long)]
    json: bool,
    /// Relative slack: a shortfall below tolerance · max(1, |J|) is attributed to rounding.
    #[arg(long, default_value_t = 1e-9)]
    tolerance: f64,
}

/// Runs `sepg audit`.
///
/// # Errors
/// Usage error (exit 2) for bad input; failure (exit 1) when some iteration broke the
/// requirement (the report is printed first) or J cannot be recomputed.
pub fn run(args: &AuditArgs) -> Result<(), CliError> {
    let report = audit(&args.dir, args.tolerance)?;
    if args.json {
        let text = serde_json::to_string_pretty(&report)
            .map_err(|e| CliError::failure(format!("cannot serialise the report: {e}")))?;
        println!("{text}");
    } else {
        print!("{}", render(&report));
    }
    let broken = report.broken_iterations();
    if broken.is_empty() {
        Ok(())
    } else {
        Err(CliError::failure(format!(
            "{} iteration(s) of {} broke the safety requirement (first: {})",
            broken.len(),
            args.dir.display(),
            broken[0]
        )))
    }
}
