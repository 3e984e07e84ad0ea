//! `sepg audit DIR`: re-checks the log of a run folder against the run's safety requirement,
//! check by check (the checks and how they are judged are described in
//! [`sepg_runs::audit`]).
//!
//! Exit status: 0 when the guarantees hold, 1 when one is violated, 2 for malformed or
//! incomplete input.

use std::path::PathBuf;

use clap::Args;
use sepg_runs::audit::{DEFAULT_ALPHA, Status, audit, render};

use crate::cli::CliError;

/// Arguments of `sepg audit`.
#[derive(Debug, Args)]
#[command(after_help = "\
Checks against exact J (where an oracle exists) are judged; the algorithm's own estimated
bookkeeping (the recorded budget) is reported as a note. With exact gradients a single failure
is a violation. With sampled gradients each step's guarantee holds with probability 1 - delta,
so a check is violated only when a one-sided exact binomial test rejects the allowed failure
rate (delta per step, 1 - (1 - delta)^2 per iteration) at level --alpha (Bonferroni across
checks).

Exit status:
  0  every exact and high-probability check holds on a complete run
  1  a check is violated (the report is printed first)
  2  malformed or incomplete input: not a run folder, NaN or non-numeric cells, missing rows,
     missing summary.json, an unfinished run")]
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
    /// Family-wise significance level of the binomial tests of a sampled run.
    #[arg(long, default_value_t = DEFAULT_ALPHA)]
    alpha: f64,
}

/// Runs `sepg audit`.
///
/// # Errors
/// Usage error (exit 2) for bad input or an unfinished run (the report is printed first);
/// failure (exit 1) when a check is violated (the report is printed first) or J cannot be
/// recomputed.
pub fn run(args: &AuditArgs) -> Result<(), CliError> {
    let report = audit(&args.dir, args.tolerance, args.alpha)?;
    if args.json {
        let text = serde_json::to_string_pretty(&report)
            .map_err(|e| CliError::failure(format!("cannot serialise the report: {e}")))?;
        println!("{text}");
    } else {
        print!("{}", render(&report));
    }
    match report.status {
        Status::Violated => {
            let broken = report.broken_iterations();
            Err(CliError::failure(format!(
                "{} iteration(s) of {} broke the safety requirement (first: {})",
                broken.len(),
                args.dir.display(),
                broken.first().copied().unwrap_or_default()
            )))
        }
        Status::Incomplete => Err(CliError::usage(format!(
            "{} is incomplete ({} of {} iterations): resume it with sepg run --resume {}",
            args.dir.display(),
            report.iterations_done,
            report.iterations_total,
            args.dir.display()
        ))),
        _ => Ok(()),
    }
}
