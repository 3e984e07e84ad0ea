//! `sepg audit DIR`: re-checks the log of a run folder against the run's safety requirement,
//! check by check (the checks and how they are judged are described in
//! [`sepg_runs::audit`]).
//!
//! Exit status: 0 when the guarantees hold, 1 when one is violated, 2 for malformed or
//! incomplete input.

use std::path::PathBuf;

use clap::Args;
use sepg_runs::audit::{DEFAULT_ALPHA, Status, audit, render};
use sepg_runs::sweep::{SUMMARY_CSV, SWEEP_FILE, SweepFile, write_summary_csv};

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
    /// Run folder written by `sepg run` (complete, or interrupted: its checkpointed rows), or a
    /// sweep folder: every run is audited at the default tolerance and level, and the audit
    /// column of its summary.csv filled in.
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
    if args.dir.join(SWEEP_FILE).is_file() {
        return sweep_audit(args);
    }
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

/// `sepg audit SWEEP_DIR`: audits every run of a sweep folder into its `summary.csv` and
/// prints one line per status; exit 1 if a run is violated, 2 if one is malformed or
/// incomplete.
fn sweep_audit(args: &AuditArgs) -> Result<(), CliError> {
    let file = SweepFile::read(&args.dir)?;
    let statuses = write_summary_csv(&args.dir, &file, true)?;
    let count = |s: &str| statuses.iter().filter(|x| x.as_str() == s).count();
    if args.json {
        let runs: Vec<serde_json::Value> = file
            .shard_runs()
            .zip(&statuses)
            .map(|(r, s)| serde_json::json!({ "dir": r.dir, "status": s }))
            .collect();
        println!(
            "{}",
            serde_json::json!({ "dir": args.dir.display().to_string(), "runs": runs })
        );
    } else {
        println!(
            "{}: {} runs audited into {SUMMARY_CSV}: {} hold, {} violated, {} incomplete, {} malformed, {} could not be audited",
            args.dir.display(),
            statuses.len(),
            count("holds"),
            count("violated"),
            count("incomplete"),
            count("malformed"),
            count("error")
        );
    }
    if count("violated") > 0 {
        return Err(CliError::failure(format!(
            "{} run(s) of {} broke the safety requirement (see {SUMMARY_CSV})",
            count("violated"),
            args.dir.display()
        )));
    }
    if count("holds") < statuses.len() {
        return Err(CliError::usage(format!(
            "{} run(s) of {} could not be certified (see {SUMMARY_CSV})",
            statuses.len() - count("holds"),
            args.dir.display()
        )));
    }
    Ok(())
}
