//! `sepg reproduce`: the experiments of thesis Chapter 5 with the protocol of Sec 5.1, run as
//! sweeps (parallel, resumable) and summarised as Table 5.1 (markdown and CSV, side by side
//! with the published values) and Figures 5.1–5.4 (PNG and SVG, bands across seeds: 95%
//! t-intervals by default); see [`sepg_runs::reproduce`] and [`sepg_runs::report`].

use std::path::PathBuf;

use clap::Args;
use sepg_runs::figure::{BandKind, Style};
use sepg_runs::report::{self, FigureOptions, Outputs, XAxis};
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
    #[arg(long, default_value_t = 0.2, allow_negative_numbers = true)]
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
    /// Band around each curve of the figures: 95% interval, one standard error, or none
    /// (warned about below 3 seeds) [default: ci95]. σ is banded on log σ, the budget by a
    /// percentile bootstrap, so that no band leaves its quantity's domain.
    #[arg(long, value_enum)]
    band: Option<BandKind>,
    /// Abscissa of the figures: iteration, trajectories or environment steps (trajectories ×
    /// horizon) [default: trajectories for fig-5.3, iteration otherwise].
    #[arg(long = "x-axis", value_enum)]
    x_axis: Option<XAxis>,
    /// Size of the figures' tick labels in points; other text scales with it (4 to 72).
    #[arg(long = "font-size", allow_negative_numbers = true)]
    font_size: Option<f64>,
    /// Resolution of the figures in dots per inch (50 to 1200) [default: 100].
    #[arg(long, allow_negative_numbers = true)]
    dpi: Option<u32>,
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
    if args.what == Experiment::Table51
        && let Some(flag) = [
            (args.band.is_some(), "--band"),
            (args.x_axis.is_some(), "--x-axis"),
            (args.font_size.is_some(), "--font-size"),
            (args.dpi.is_some(), "--dpi"),
        ]
        .iter()
        .find_map(|&(given, flag)| given.then_some(flag))
    {
        return Err(CliError::usage(format!(
            "{flag} applies to the figures; table-5.1 has none"
        )));
    }
    let defaults = Style::default();
    let figure_opts = FigureOptions {
        band: args.band.unwrap_or_default(),
        style: Style {
            font_size: args.font_size.unwrap_or(defaults.font_size),
            dpi: args.dpi.unwrap_or(defaults.dpi),
        },
        x_axis: args.x_axis,
    };
    // Checked before any run starts, so that a bad style costs nothing.
    figure_opts.style.validate()?;
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
