//! `sepg audit DIR`: re-checks the log of a run folder against exactly what the run promises
//! about exact J, and gives one verdict (the checks, the tests and the verdicts are described
//! in [`sepg_runs::audit`]); on a sweep folder, tests the number of failed runs of each
//! (preset, variant, σ⁰) group ([`sepg_runs::sweep::audit_sweep`]).
//!
//! Exit status: 1 for a broken run (or a rejected sweep group), 2 for malformed or unfinished
//! input, 0 otherwise (holds, approximate, no-guarantee, not-checked).

use std::path::PathBuf;

use clap::Args;
use sepg_runs::audit::{DEFAULT_ALPHA, DEFAULT_TOLERANCE, Verdict, audit_observed, render};
use sepg_runs::sweep::{
    AUDIT_GROUPS_CSV, GroupVerdict, SUMMARY_CSV, SWEEP_FILE, SweepFile, audit_sweep,
};

use crate::cli::CliError;
use crate::progress::Bar;

/// Arguments of `sepg audit`.
#[derive(Debug, Args)]
#[command(after_help = "\
Judges the run by the statement recorded in its summary.json (kind proven, approximate or
none; scope run or iteration; delta). Scope run, or exact gradients: one exact violation of a
covered requirement or logged guarantee breaks the promise. Scope iteration: each per-step
check's failures over the iterations are tested against K*delta with an exact binomial test
(K the scalar confidence events of the step), each floor by its first failure, at level
--alpha (Bonferroni across checks). Verdicts: holds, broken, approximate (never holds),
no-guarantee, not-checked (no exact oracle, e.g. Mountain Car), incomplete. A sweep folder:
every run is audited into summary.csv, and each (preset, variant, sigma0) group's number of
failed runs is tested with an exact binomial test against its statements' rate, Bonferroni
across groups (audit-groups.csv).

Exit status:
  0  holds, approximate, no-guarantee or not-checked (nothing broken)
  1  broken: a run broke its promise, or a sweep group is rejected (the report is printed first)
  2  malformed or incomplete input: not a run folder, NaN or non-numeric cells, missing rows,
     missing summary.json, an unfinished run")]
pub struct AuditArgs {
    /// Run folder written by `sepg run` (complete, or interrupted: its checkpointed rows), or a
    /// sweep folder.
    #[arg(value_name = "DIR")]
    dir: PathBuf,
    /// Print the report as JSON on standard output instead of the table.
    #[arg(long)]
    json: bool,
    /// Relative tolerance: a shortfall up to tolerance · max(1, |J|) of the compared values is
    /// attributed to the oracle's error (the default is about 50 times its measured error on
    /// differences of J).
    #[arg(long, default_value_t = DEFAULT_TOLERANCE)]
    tolerance: f64,
    /// Family-wise significance level of the tests of a run, and of the groups of a sweep.
    #[arg(long, default_value_t = DEFAULT_ALPHA)]
    alpha: f64,
}

/// Runs `sepg audit`.
///
/// # Errors
/// Usage error (exit 2) for bad input or an unfinished run (the report is printed first);
/// failure (exit 1) for a broken run (the report is printed first) or when J cannot be
/// recomputed.
pub fn run(args: &AuditArgs) -> Result<(), CliError> {
    if args.dir.join(SWEEP_FILE).is_file() {
        return sweep(args);
    }
    // The exact-J evaluations, in parallel over the audited iterations, with a progress bar
    // when standard error is a terminal.
    let bar = Bar::iterations(true);
    let report = audit_observed(&args.dir, args.tolerance, args.alpha, &bar)?;
    if args.json {
        let text = serde_json::to_string_pretty(&report)
            .map_err(|e| CliError::failure(format!("cannot serialise the report: {e}")))?;
        println!("{text}");
    } else {
        print!("{}", render(&report));
    }
    match report.verdict {
        Verdict::Broken => Err(CliError::failure(format!(
            "{}: {}",
            args.dir.display(),
            report.reason
        ))),
        Verdict::Incomplete => Err(CliError::usage(format!(
            "{} is incomplete ({} of {} iterations): resume it with sepg run --resume {}",
            args.dir.display(),
            report.iterations_done,
            report.iterations_total,
            args.dir.display()
        ))),
        _ => Ok(()),
    }
}

/// `sepg audit SWEEP_DIR`: audits every run of a sweep folder into its `summary.csv`, tests
/// each group into `audit-groups.csv` and prints one line per group; exit 1 if a group is
/// rejected, 2 if a run is malformed, unfinished or could not be audited.
fn sweep(args: &AuditArgs) -> Result<(), CliError> {
    let file = SweepFile::read(&args.dir)?;
    let audited = audit_sweep(&args.dir, &file, args.tolerance, args.alpha)?;
    if args.json {
        let text = serde_json::to_string_pretty(&audited)
            .map_err(|e| CliError::failure(format!("cannot serialise the report: {e}")))?;
        println!("{text}");
    } else {
        let opt = |x: Option<f64>| x.map_or_else(|| "-".to_owned(), |x| format!("{x:.3e}"));
        println!(
            "{:<8} {:<16} {:>8} {:>5} {:>7} {:>10} {:>10} {:>10}  verdict",
            "preset", "variant", "sigma0", "runs", "failed", "rate", "p-value", "level"
        );
        for g in &audited.groups {
            println!(
                "{:<8} {:<16} {:>8} {:>5} {:>7} {:>10} {:>10} {:>10}  {}",
                g.preset,
                g.variant,
                g.sigma0,
                g.runs,
                g.failed,
                opt(g.rate),
                opt(g.p_value),
                opt(g.level),
                g.verdict.name()
            );
        }
        let count = |v: &str| audited.runs.iter().filter(|r| r.verdict == v).count();
        println!(
            "{}: {} runs audited into {SUMMARY_CSV} ({} holds, {} broken, {} approximate, {} \
             no-guarantee, {} not-checked, {} incomplete, {} malformed, {} could not be \
             audited); groups in {AUDIT_GROUPS_CSV}",
            args.dir.display(),
            audited.runs.len(),
            count("holds"),
            count("broken"),
            count("approximate"),
            count("no-guarantee"),
            count("not-checked"),
            count("incomplete"),
            count("malformed"),
            count("error")
        );
    }
    let rejected = audited
        .groups
        .iter()
        .filter(|g| g.verdict == GroupVerdict::Rejected)
        .count();
    if rejected > 0 {
        return Err(CliError::failure(format!(
            "{rejected} group(s) of {} have more broken runs than their statements allow (see \
             {AUDIT_GROUPS_CSV})",
            args.dir.display()
        )));
    }
    let unfinished = audited
        .runs
        .iter()
        .filter(|r| ["incomplete", "malformed", "error"].contains(&r.verdict.as_str()))
        .count();
    if unfinished > 0 {
        return Err(CliError::usage(format!(
            "{unfinished} run(s) of {} could not be audited to the end (see {SUMMARY_CSV})",
            args.dir.display()
        )));
    }
    Ok(())
}
