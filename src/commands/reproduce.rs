//! `sepg reproduce`: the experiments of thesis Chapter 5 with the protocol of Sec 5.1, run as
//! sweeps (parallel, resumable) and summarised as Table 5.1 (markdown and CSV, side by side
//! with the published values) and Figures 5.1–5.4 (PNG and SVG, bands across seeds: 95%
//! t-intervals by default); see [`sepg_runs::reproduce`] and [`sepg_runs::report`].

use std::path::PathBuf;

use clap::Args;
use sepg_runs::figure_flags::FigureFlags;
use sepg_runs::report::{self, Outputs};
use sepg_runs::reproduce::{
    self, Experiment, LqgPreset, Mode, OptionFlags, ReproduceOptions, Setting,
};
use sepg_runs::sweep::SweepOptions;

use crate::cli::CliError;
use crate::commands::sweep::stats_line;
use crate::progress::{self, Bar, STOP};

/// Arguments of `sepg reproduce`.
#[derive(Debug, Args)]
pub struct ReproduceArgs {
    /// The experiment.
    #[arg(value_enum)]
    what: Experiment,
    /// Only this LQG preset (default: both).
    #[arg(long, value_enum)]
    preset: Option<LqgPreset>,
    /// Number of seeds (0..K).
    #[arg(long, default_value_t = 10, allow_negative_numbers = true)]
    seeds: u64,
    /// Iterations per run [default: 10000; 1000 for fig-5.4].
    #[arg(long, allow_negative_numbers = true)]
    iterations: Option<u64>,
    /// Confidence δ of the sampled gradients.
    #[arg(long, default_value_t = sepg_algo::DEFAULT_DELTA, allow_negative_numbers = true)]
    delta: f64,
    /// σ⁰ of the LQG figures (fig-5.1 to fig-5.3).
    #[arg(
        long = "fig-sigma0",
        default_value_t = 1.0,
        allow_negative_numbers = true
    )]
    fig_sigma0: f64,
    /// Named choice of the algorithm options: sepg's guaranteed defaults, the thesis-era
    /// choices that reproduce the published SEPG cells, the thesis-era code taken literally,
    /// or the defaults without confidence widths (docs/REPRODUCTION.md lists each).
    #[arg(long, value_enum, default_value_t = Setting::Default)]
    setting: Setting,
    /// Options overriding the setting's.
    #[command(flatten)]
    flags: OptionFlags,
    /// Options of the figures.
    #[command(flatten)]
    figures: FigureFlags,
    /// Output folder [default: sepg-<experiment>].
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Write into a non-empty folder, replacing a previous reproduction there.
    #[arg(long)]
    force: bool,
    /// Continue an interrupted reproduction in --out (same options).
    #[arg(long)]
    resume: bool,
    /// No progress bar; print only the table or the written files.
    #[arg(long)]
    quiet: bool,
}

/// Runs `sepg reproduce`.
///
/// # Errors
/// Usage error (exit 2) for bad options or a non-empty output folder; failure (exit 1) for
/// failed runs or I/O errors.
pub fn run(args: &ReproduceArgs) -> Result<(), CliError> {
    // Checked before any run starts, so that a bad style costs nothing.
    let figure_opts = args.figures.options(args.what)?;
    let opts = ReproduceOptions {
        what: args.what,
        preset: args.preset,
        seeds: args.seeds,
        iterations: args.iterations,
        delta: args.delta,
        fig_sigma0: args.fig_sigma0,
        setting: args.setting,
        flags: args.flags,
    };
    let dir = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("sepg-{}", args.what.name())));
    let mode = if args.resume {
        Mode::Resume
    } else {
        Mode::Start { force: args.force }
    };
    let bar = Bar::runs(!args.quiet);
    let sweep_opts = SweepOptions {
        checkpoint_every: 2000,
        stop: &STOP,
        observer: &bar,
    };
    progress::install_interrupt_handler();
    let (file, stats) =
        reproduce::run(&opts, &dir, mode, sweep_opts).map_err(|e| match e {
            sepg_runs::Error::SweepInterrupted { complete, runs, .. } => CliError::failure(format!(
                "interrupted with {complete} of {runs} runs complete; resume with: sepg reproduce {} --resume --out {} (and the same options)",
                args.what.name(),
                dir.display()
            )),
            e => e.into(),
        })?;
    if !args.quiet {
        eprintln!("{}", stats_line(&dir, &file, &stats));
    }
    match report::write_outputs(&opts, &dir, &file, &figure_opts)? {
        Outputs::Table { markdown, warnings } => {
            for w in &warnings {
                eprintln!("warning: {w}");
            }
            print!("{markdown}");
        }
        Outputs::Figures { paths, warnings } => {
            for w in &warnings {
                eprintln!("warning: {w}");
            }
            if !args.quiet {
                for p in paths {
                    println!("{}", p.display());
                }
            }
        }
        _ => {}
    }
    Ok(())
}
