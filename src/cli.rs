//! Command-line definitions, error type and dispatch.
//!
//! Every failure is reported as one line on standard error, and nothing is printed on
//! standard output. Bad input exits with status 2; a run that could not complete or a
//! verification whose outcome changed exits with status 1.

use std::fmt;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use crate::commands;

/// Exit status for bad input (unknown flag, malformed value, out-of-domain parameter).
pub const EXIT_USAGE: u8 = 2;
/// Exit status for a command that ran but failed (I/O error, changed verification outcome).
pub const EXIT_FAILURE: u8 = 1;

/// A command failure: the one-line message and the exit status it maps to.
#[derive(Debug)]
pub struct CliError {
    code: u8,
    message: String,
}

impl CliError {
    /// Bad input: exit status 2.
    pub fn usage(message: impl Into<String>) -> Self {
        CliError {
            code: EXIT_USAGE,
            message: message.into(),
        }
    }

    /// A failure while running: exit status 1.
    pub fn failure(message: impl Into<String>) -> Self {
        CliError {
            code: EXIT_FAILURE,
            message: message.into(),
        }
    }
}

impl From<sepg_runs::Error> for CliError {
    /// Bad input exits with status 2, every other error of a run with status 1.
    fn from(e: sepg_runs::Error) -> Self {
        if e.is_invalid_input() {
            CliError::usage(e.to_string())
        } else {
            CliError::failure(e.to_string())
        }
    }
}

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // Keep the report on a single line whatever the underlying error printed.
        let one_line = self
            .message
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ");
        f.write_str(&one_line)
    }
}

/// Safely-Exploring Policy Gradient: closed-form safety bounds, exact LQG oracles, estimators,
/// SEPG and a verification harness.
#[derive(Debug, Parser)]
#[command(name = "sepg", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Every closed-form safety quantity the given task constants and gradients determine.
    Bounds(commands::bounds::BoundsArgs),
    /// Check every statement of the thesis numerically and report the outcomes.
    Verify(commands::verify::VerifyArgs),
    /// Exact J and gradients of an LQG preset (closed form, or dynamic programming if clipped).
    Exact(commands::exact::ExactArgs),
    /// A Mountain Car trajectory from a given state under given actions.
    Replay(commands::replay::ReplayArgs),
    /// Monte Carlo J, grad_v J and grad_w J with 95% confidence intervals.
    Estimate(commands::estimate::EstimateArgs),
    /// Run SEPG or a comparison algorithm into a run folder (log, summary, checkpoint).
    Run(Box<commands::run::RunArgs>),
    /// Run every (preset, variant, σ⁰, seed) of a sweep file in parallel, or one shard of it.
    Sweep(commands::sweep::SweepArgs),
    /// Combine the shard folders of one sweep into a single sweep folder.
    Merge(commands::merge::MergeArgs),
    /// Reproduce Table 5.1 or Figures 5.1–5.4 of the thesis (the protocol of Sec 5.1).
    Reproduce(commands::reproduce::ReproduceArgs),
    /// Plot performance, σ, v and budget of a run or sweep folder.
    Plot(commands::plot::PlotArgs),
    /// Re-check a run's log against its safety requirement (exact J where an oracle exists).
    Audit(commands::audit::AuditArgs),
}

/// One line for a command-line parsing error that keeps the parser's detail: the missing
/// flags, the rejected value with the valid values, or the reason a value was refused.
fn parse_error_line(e: &clap::Error) -> String {
    use clap::error::{ContextKind, ContextValue, ErrorKind};
    let strings = |kind: ContextKind| -> Vec<String> {
        match e.get(kind) {
            Some(ContextValue::String(s)) => vec![s.clone()],
            Some(ContextValue::Strings(v)) => v.clone(),
            _ => Vec::new(),
        }
    };
    let invalid = strings(ContextKind::InvalidArg).join(", ");
    match e.kind() {
        ErrorKind::MissingRequiredArgument if !invalid.is_empty() => {
            format!("missing required arguments: {invalid}")
        }
        ErrorKind::InvalidValue if !invalid.is_empty() => {
            let value = strings(ContextKind::InvalidValue).join(", ");
            let mut line = if value.is_empty() {
                format!("{invalid} needs a value")
            } else {
                format!("invalid value '{value}' for {invalid}")
            };
            let valid = strings(ContextKind::ValidValue);
            if !valid.is_empty() {
                line.push_str(&format!("; valid values: {}", valid.join(", ")));
            }
            line
        }
        _ => {
            // Every other kind: the rendered message without the usage and help footer, its
            // lines (the error, then any tip) joined into one.
            let text = e.render().to_string();
            let parts: Vec<&str> = text
                .lines()
                .map(str::trim)
                .filter(|l| {
                    !l.is_empty()
                        && !l.starts_with("Usage:")
                        && !l.starts_with("For more information")
                })
                .map(|l| l.trim_start_matches("error: "))
                .collect();
            if parts.is_empty() {
                "invalid arguments".to_owned()
            } else {
                parts.join("; ")
            }
        }
    }
}

/// Parses the command line, runs the command and maps failures to exit statuses.
pub fn run() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind;
            return match e.kind() {
                ErrorKind::DisplayHelp
                | ErrorKind::DisplayVersion
                | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
                    let _ = e.print();
                    if e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
                        ExitCode::from(EXIT_USAGE)
                    } else {
                        ExitCode::SUCCESS
                    }
                }
                _ => {
                    eprintln!("sepg: error: {}", parse_error_line(&e));
                    ExitCode::from(EXIT_USAGE)
                }
            };
        }
    };
    let result = match cli.command {
        Command::Bounds(args) => commands::bounds::run(&args),
        Command::Verify(args) => commands::verify::run(&args),
        Command::Exact(args) => commands::exact::run(&args),
        Command::Replay(args) => commands::replay::run(&args),
        Command::Estimate(args) => commands::estimate::run(&args),
        Command::Run(args) => commands::run::run(&args),
        Command::Sweep(args) => commands::sweep::run(&args),
        Command::Merge(args) => commands::merge::run(&args),
        Command::Reproduce(args) => commands::reproduce::run(&args),
        Command::Plot(args) => commands::plot::run(&args),
        Command::Audit(args) => commands::audit::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("sepg: error: {e}");
            ExitCode::from(e.code)
        }
    }
}
