//! `sepg verify`: runs the registry of numerical checks of the thesis's statements
//! (`sepg-verification`) and reports whether every outcome is the one recorded as expected.

use std::io::IsTerminal;
use std::path::PathBuf;

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use sepg_verification::{CheckResult, Report, RunConfig, registry, run_checks};

use crate::cli::CliError;
use crate::output::write_atomic;

/// Arguments of `sepg verify`.
#[derive(Debug, Args)]
pub struct VerifyArgs {
    /// Fewer cases per check (the CI subset: about 55 s of CPU time in release).
    #[arg(long)]
    quick: bool,
    /// Run only the checks whose identifier contains this text (e.g. `thm-3.3`).
    #[arg(long = "check", value_name = "ID")]
    check: Option<String>,
    /// Print the report as JSON on standard output instead of the summary table.
    #[arg(long)]
    json: bool,
    /// Also write the markdown report to this file (atomically).
    #[arg(long, value_name = "FILE.md")]
    out: Option<PathBuf>,
    /// Master seed; each check derives its own stream from it and its identifier.
    #[arg(long, default_value_t = 0, allow_hyphen_values = true, value_parser = sepg_runs::spec::parse_seed)]
    seed: u64,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

fn outcome_text(r: &CheckResult) -> String {
    r.outcome.describe(&r.meta.tolerance)
}

fn summary(report: &Report) -> String {
    let width = report
        .results
        .iter()
        .map(|r| r.meta.id.len())
        .max()
        .unwrap_or(2)
        .max(2);
    let mut out = String::new();
    for r in &report.results {
        let mark = if r.as_expected { "ok" } else { "CHANGED" };
        out.push_str(&format!(
            "{:<7} {:<width$}  {}\n",
            mark,
            r.meta.id,
            outcome_text(r)
        ));
    }
    let changed = report.results.iter().filter(|r| !r.as_expected).count();
    out.push_str(&format!(
        "{} checks, {} as expected, {} changed\n",
        report.results.len(),
        report.results.len() - changed,
        changed
    ));
    out
}

/// Runs `sepg verify`.
pub fn run(args: &VerifyArgs) -> Result<(), CliError> {
    let checks = registry();
    let filter = args.check.as_deref();
    let selected = checks
        .iter()
        .filter(|c| filter.is_none_or(|f| c.meta.id.contains(f)))
        .count();
    if selected == 0 {
        return Err(CliError::usage(format!(
            "no check matches '{}' (see `sepg verify --json` for the identifiers)",
            filter.unwrap_or_default()
        )));
    }
    let bar = if !args.quiet && std::io::stderr().is_terminal() {
        let bar = ProgressBar::new(selected as u64);
        if let Ok(style) = ProgressStyle::with_template("{bar:40} {pos}/{len} {msg}") {
            bar.set_style(style);
        }
        bar
    } else {
        ProgressBar::hidden()
    };
    let config = RunConfig {
        seed: args.seed,
        quick: args.quick,
    };
    let report = run_checks(&checks, &config, filter, |r| {
        bar.set_message(r.meta.id.clone());
        bar.inc(1);
    });
    bar.finish_and_clear();

    if let Some(path) = &args.out {
        write_atomic(path, report.to_markdown().as_bytes())?;
    }
    if args.json {
        let mut json = report
            .to_json()
            .map_err(|e| CliError::failure(format!("cannot serialise the report: {e}")))?;
        json.push('\n');
        print!("{json}");
    } else {
        print!("{}", summary(&report));
    }
    let changed: Vec<&str> = report
        .unexpected()
        .iter()
        .map(|r| r.meta.id.as_str())
        .collect();
    if changed.is_empty() {
        Ok(())
    } else {
        Err(CliError::failure(format!(
            "{} check(s) changed outcome: {}",
            changed.len(),
            changed.join(", ")
        )))
    }
}
