//! `sepg plot`: performance, σ, v and budget panels of a run folder, or of every
//! (preset, variant, σ⁰) group of a sweep folder with bands across seeds (see
//! [`sepg_runs::report::plot`]).

use std::path::PathBuf;

use clap::Args;
use sepg_runs::figure::{BandKind, Style};
use sepg_runs::report::{FigureOptions, XAxis};

use crate::cli::CliError;

/// Arguments of `sepg plot`.
#[derive(Debug, Args)]
pub struct PlotArgs {
    /// A run folder (from `sepg run`) or a sweep folder (from `sepg sweep` or `reproduce`).
    #[arg(value_name = "DIR")]
    dir: PathBuf,
    /// Output file, .png or .svg [default: DIR/plot.png and DIR/plot.svg].
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Band around each sweep group's mean: 95% interval, one standard error, or none
    /// (warned about below 3 seeds). σ is banded on log σ, the budget by a percentile
    /// bootstrap, so that no band leaves its quantity's domain.
    #[arg(long, value_enum, default_value_t = BandKind::Ci95)]
    band: BandKind,
    /// Abscissa: iteration, trajectories or environment steps (trajectories × horizon).
    #[arg(long = "x-axis", value_enum, default_value_t = XAxis::Iteration)]
    x_axis: XAxis,
    /// Size of the tick labels in points; other text scales with it (4 to 72).
    #[arg(
        long = "font-size",
        default_value_t = 12.0,
        allow_negative_numbers = true
    )]
    font_size: f64,
    /// Resolution in dots per inch: the PNG has dpi/100 times the default pixels in each
    /// direction (50 to 1200).
    #[arg(long, default_value_t = 100, allow_negative_numbers = true)]
    dpi: u32,
    /// Print nothing.
    #[arg(long)]
    quiet: bool,
}

/// Runs `sepg plot`.
///
/// # Errors
/// Usage error (exit 2) for a folder that is neither a run nor a sweep, a truncated, NaN or
/// otherwise malformed log (naming the file and its first bad line), an output file that is
/// not .png or .svg, or a font size or resolution out of range; failure (exit 1) when
/// drawing or writing fails. An unfinished run is plotted, marked "incomplete: k of n
/// iterations" in the title, with a warning.
pub fn run(args: &PlotArgs) -> Result<(), CliError> {
    let opts = FigureOptions {
        band: args.band,
        style: Style {
            font_size: args.font_size,
            dpi: args.dpi,
        },
        x_axis: Some(args.x_axis),
    };
    let plotted = sepg_runs::report::plot(&args.dir, args.out.as_deref(), &opts)?;
    for w in &plotted.warnings {
        eprintln!("warning: {w}");
    }
    if !args.quiet {
        for p in plotted.paths {
            println!("{}", p.display());
        }
    }
    Ok(())
}
