//! `sepg run`: one run of SEPG or a comparison algorithm into a run folder (`config.toml`,
//! `log.csv`, `summary.json`, `checkpoint.json`), resumable bit for bit with `--resume`.

use std::path::{Path, PathBuf};

use clap::Args;
use sepg_runs::folder::{self, Summary};
use sepg_runs::run::{self, RunOptions};
use sepg_runs::setup;
use sepg_runs::spec::RunSpec;

use crate::cli::CliError;
use crate::progress::{self, Bar, STOP};

/// Arguments of `sepg run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// Read options from a TOML file (keys are the flag names); flags override it.
    #[arg(long, value_name = "FILE.toml")]
    config: Option<PathBuf>,
    #[command(flatten)]
    spec: RunSpec,
    /// Output run folder (must be absent or empty unless --force).
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Write into a non-empty folder, replacing the run files a previous run left there.
    #[arg(long)]
    force: bool,
    /// No progress bar and no summary line.
    #[arg(long)]
    quiet: bool,
    /// Continue the interrupted run in DIR from its checkpoint (no other options).
    #[arg(long, value_name = "DIR")]
    resume: Option<PathBuf>,
    /// Iterations between checkpoints (rows are appended to the log at each checkpoint).
    #[arg(
        long = "checkpoint-every",
        value_name = "K",
        default_value_t = 500,
        allow_negative_numbers = true
    )]
    checkpoint_every: u64,
}

/// The one-line report of a finished run.
pub fn summary_line(dir: &Path, s: &Summary) -> String {
    let mut line = format!(
        "{}: {} iterations in {:.2} s ({:.0} it/s, {:.3e} env steps/s)",
        dir.display(),
        s.iterations,
        s.wall_time_s,
        s.iterations_per_s,
        s.env_steps_per_s
    );
    if let Some(e) = s.abs_v_error {
        line.push_str(&format!(", |v - v*| = {e:.4}"));
    }
    line
}

/// Runs `sepg run`.
///
/// # Errors
/// Usage error (exit 2) for bad options, files or folders; failure (exit 1) for I/O errors,
/// a failing iteration or an interrupt.
pub fn run(args: &RunArgs) -> Result<(), CliError> {
    if args.checkpoint_every == 0 {
        return Err(CliError::usage("--checkpoint-every must be at least 1"));
    }
    let bar = Bar::iterations(!args.quiet);
    let opts = RunOptions {
        checkpoint_every: args.checkpoint_every,
        stop: &STOP,
        observer: &bar,
    };
    progress::install_interrupt_handler();
    let (dir, summary) = if let Some(dir) = &args.resume {
        if args.config.is_some()
            || args.out.is_some()
            || args.force
            || args.spec != RunSpec::default()
        {
            return Err(CliError::usage(
                "--resume takes no other options than --quiet and --checkpoint-every",
            ));
        }
        if folder::is_complete(dir) {
            let s = folder::read_summary(dir)?;
            // a run stopped by contradicted constants: run::resume says why it cannot go on
            if s.status != "stopped" {
                if !args.quiet {
                    println!(
                        "{}: already complete ({} iterations); nothing to resume",
                        dir.display(),
                        s.iterations
                    );
                }
                return Ok(());
            }
        }
        (dir.clone(), run::resume(dir, opts)?)
    } else {
        let new = setup::set_up(
            args.config.as_deref(),
            &args.spec,
            args.out.as_deref(),
            args.force,
        )?;
        (new.dir.clone(), new.start(opts)?)
    };
    if !args.quiet {
        println!("{}", summary_line(&dir, &summary));
    }
    if let Some(line) = self_check_line(&summary) {
        eprintln!("{line}");
    }
    Ok(())
}

/// The warning a run prints, even with `--quiet`, when its own bookkeeping says it broke its
/// requirement (its budget or surplus went below zero); `None` otherwise.
pub fn self_check_line(s: &Summary) -> Option<String> {
    let c = s.self_check.filter(|c| c.broken)?;
    Some(format!(
        "warning: the run's own budget went to {:.3e} at iteration {}: it broke its requirement \
         (summary.json: self_check)",
        c.value.unwrap_or(f64::NAN),
        c.first_iteration.unwrap_or(0)
    ))
}
