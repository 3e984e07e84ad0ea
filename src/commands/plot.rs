//! `sepg plot`: performance, σ, v and budget panels of a run folder, or of every
//! (preset, variant, σ⁰) group of a sweep folder with bands across seeds (see
//! [`sepg_runs::report::plot`]).

use std::path::PathBuf;

use clap::Args;
use sepg_runs::figure::BandKind;

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
    /// Band around each sweep group's mean: 95% t-interval, one standard error, or none
    /// (warned about below 3 seeds).
    #[arg(long, value_enum, default_value_t = BandKind::Ci95)]
    band: BandKind,
    /// Print nothing.
    #[arg(long)]
    quiet: bool,
}

/// Runs `sepg plot`.
///
/// # Errors
/// Usage error (exit 2) for a folder that is neither a run nor a sweep, or an output file
/// that is not .png or .svg; failure (exit 1) when drawing or writing fails.
pub fn run(args: &PlotArgs) -> Result<(), CliError> {
    let plotted = sepg_runs::report::plot(&args.dir, args.out.as_deref(), args.band)?;
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
