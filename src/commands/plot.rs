//! `sepg plot`: performance, σ, v and budget panels of a run folder, or of every
//! (preset, variant, σ⁰) group of a sweep folder with 95% bands across seeds (see
//! [`sepg_runs::report::plot`]).

use std::path::PathBuf;

use clap::Args;

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
    let written = sepg_runs::report::plot(&args.dir, args.out.as_deref())?;
    if !args.quiet {
        for p in written {
            println!("{}", p.display());
        }
    }
    Ok(())
}
