//! `sepg merge`: combines the shard folders of one sweep into a single sweep folder (see
//! [`sepg_runs::merge`]).

use std::path::PathBuf;

use clap::Args;

use crate::cli::CliError;

/// Arguments of `sepg merge`.
#[derive(Debug, Args)]
pub struct MergeArgs {
    /// The shard folders written by `sepg sweep --shard I/N`.
    #[arg(required = true, value_name = "DIR")]
    shards: Vec<PathBuf>,
    /// Output sweep folder (must be absent or empty unless --force).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Replace a previous merge in a non-empty folder.
    #[arg(long)]
    force: bool,
    /// No summary line.
    #[arg(long)]
    quiet: bool,
}

/// Runs `sepg merge`.
///
/// # Errors
/// Usage error (exit 2) for folders that are not complete shards of one sweep, a run whose
/// log `sepg audit` would refuse (cut, NaN, missing rows; the line names the log file and its
/// first bad line), or an output folder that is not empty or cannot be written; failure
/// (exit 1) for I/O errors while copying.
pub fn run(args: &MergeArgs) -> Result<(), CliError> {
    let merged = sepg_runs::merge::merge(&args.shards, &args.out, args.force)?;
    if !args.quiet {
        println!(
            "{}: {} runs from {} shards of sweep {}",
            args.out.display(),
            merged.runs.len(),
            args.shards.len(),
            merged.sweep_id
        );
    }
    Ok(())
}
