//! `sepg sweep`: every (preset, variant, σ⁰, seed) combination of a sweep file, run in
//! parallel into one run folder each, optionally restricted to a shard `I/N` (the runs whose
//! index mod N is I) so that a cluster job array can split the work (`--shard slurm` reads
//! I and N from a Slurm job array, see docs/CLUSTER.md). The sweep file format
//! is documented in [`sepg_runs::sweep`].

use std::path::{Path, PathBuf};

use clap::Args;
use sepg_runs::spec::ConstantsName;
use sepg_runs::sweep::{self, Shard, SweepFile, SweepOptions, SweepStats};

use crate::cli::CliError;
use crate::progress::{self, Bar, STOP};

/// Arguments of `sepg sweep`.
#[derive(Debug, Args)]
pub struct SweepArgs {
    /// The sweep file (TOML).
    #[arg(long, value_name = "FILE.toml")]
    config: Option<PathBuf>,
    /// Output sweep folder (must be absent or empty unless --force).
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Run only shard I of N: the runs whose index mod N equals I. `slurm` takes I and N from
    /// the Slurm job array of this task (SLURM_ARRAY_TASK_ID minus SLURM_ARRAY_TASK_MIN, and
    /// SLURM_ARRAY_TASK_COUNT).
    #[arg(long, value_name = "I/N|slurm")]
    shard: Option<String>,
    /// Write into a non-empty folder, replacing a previous sweep's files there.
    #[arg(long)]
    force: bool,
    /// Family of the constants c and d of every run, replacing the sweep file's `constants`
    /// keys [default: the file's, else tight].
    #[arg(long, value_enum)]
    constants: Option<ConstantsName>,
    /// No progress bar and no summary line.
    #[arg(long)]
    quiet: bool,
    /// Continue the interrupted sweep in DIR (complete runs are kept, others resumed).
    #[arg(long, value_name = "DIR")]
    resume: Option<PathBuf>,
    /// Iterations between checkpoints of each run.
    #[arg(
        long = "checkpoint-every",
        value_name = "K",
        default_value_t = 2000,
        allow_negative_numbers = true
    )]
    checkpoint_every: u64,
}

/// The one-line report of a finished sweep.
pub fn stats_line(dir: &Path, file: &SweepFile, s: &SweepStats) -> String {
    let shard = if file.shard.count > 1 {
        format!(" (shard {}/{})", file.shard.index, file.shard.count)
    } else {
        String::new()
    };
    if s.runs == 0 {
        return format!(
            "{}{shard}: no run left to run ({} complete)",
            dir.display(),
            file.shard_runs().count()
        );
    }
    let rate = if s.wall_s > 0.0 {
        s.iterations as f64 / s.wall_s
    } else {
        0.0
    };
    format!(
        "{}{shard}: {} run{}, {} iterations in {:.1} s ({:.0} it/s)",
        dir.display(),
        s.runs,
        if s.runs == 1 { "" } else { "s" },
        s.iterations,
        s.wall_s,
        rate
    )
}

/// Runs `sepg sweep`.
///
/// # Errors
/// Usage error (exit 2) for a bad sweep file, shard or folder; failure (exit 1) otherwise.
pub fn run(args: &SweepArgs) -> Result<(), CliError> {
    if args.checkpoint_every == 0 {
        return Err(CliError::usage("--checkpoint-every must be at least 1"));
    }
    let bar = Bar::runs(!args.quiet);
    let opts = SweepOptions {
        checkpoint_every: args.checkpoint_every,
        stop: &STOP,
        observer: &bar,
    };
    let (dir, file, stats) = if let Some(dir) = &args.resume {
        if args.config.is_some()
            || args.out.is_some()
            || args.shard.is_some()
            || args.force
            || args.constants.is_some()
        {
            return Err(CliError::usage(
                "--resume takes no other options than --quiet and --checkpoint-every",
            ));
        }
        progress::install_interrupt_handler();
        let (file, stats) = sweep::resume(dir, opts)?;
        (dir.clone(), file, stats)
    } else {
        let path = args
            .config
            .as_ref()
            .ok_or_else(|| CliError::usage("--config FILE.toml is required"))?;
        let mut spec = sweep::read_spec(path)?;
        if let Some(c) = args.constants {
            for run in std::iter::once(&mut spec.base).chain(spec.variant.iter_mut()) {
                run.constants = Some(c);
            }
        }
        let shard = match &args.shard {
            Some(s) if s == "slurm" => sweep::slurm_shard(|k| std::env::var(k).ok())?,
            Some(s) => sweep::parse_shard(s)?,
            None => Shard { index: 0, count: 1 },
        };
        let (file, resolved) = sweep::expand(&spec, shard)?;
        let dir = args
            .out
            .clone()
            .ok_or_else(|| CliError::usage("--out DIR is required"))?;
        progress::install_interrupt_handler();
        let stats = sweep::start(&dir, &file, &resolved, args.force, opts)?;
        (dir, file, stats)
    };
    if !args.quiet {
        println!("{}", stats_line(&dir, &file, &stats));
    }
    Ok(())
}
