//! `sepg sweep`: every (preset, variant, σ⁰, seed) combination of a sweep file, run in
//! parallel into one run folder each, optionally restricted to a shard `I/N` (the runs whose
//! index mod N is I) so that a cluster job array can split the work.
//!
//! # Sweep file
//! ```toml
//! presets = ["lqg", "lqg1d"]
//! seeds = 10                 # seeds 0..9, or an explicit list [1, 5, 9]
//! sigma0 = [0.1, 0.5, 1.0]
//! [base]                     # options shared by every run (the keys of `sepg run`)
//! iterations = 2000
//! [[variant]]
//! name = "zv"
//! algo = "sepg-zv"
//! [[variant]]
//! name = "adam-1e-4"
//! algo = "gpomdp-adam"
//! lr = 1e-4
//! ```
//! Runs are numbered preset-major, then variant, σ⁰ and seed; run `i` lives in
//! `runs/<preset>/<variant>/sigma-<σ⁰>/seed-<seed>`. `sweep.json` records the sweep, its
//! identifier (a hash of every resolved run configuration), the run list and the shard.

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::cli::CliError;
use crate::commands::runfmt::{self, EnvName, Resolved, RunOptions, RunSpec, Values};
use crate::output::{to_json_line, write_atomic};

/// The sweep description file.
pub const SWEEP_FILE: &str = "sweep.json";
/// Folder of the run folders inside a sweep folder.
pub const RUNS_DIR: &str = "runs";

/// Arguments of `sepg sweep`.
#[derive(Debug, Args)]
pub struct SweepArgs {
    /// The sweep file (TOML).
    #[arg(long, value_name = "FILE.toml")]
    config: Option<PathBuf>,
    /// Output sweep folder (must be absent or empty unless --force).
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Run only shard I of N: the runs whose index mod N equals I.
    #[arg(long, value_name = "I/N")]
    shard: Option<String>,
    /// Write into a non-empty folder, replacing a previous sweep's files there.
    #[arg(long)]
    force: bool,
    /// No progress bar and no summary line.
    #[arg(long)]
    quiet: bool,
    /// Continue the interrupted sweep in DIR (complete runs are kept, others resumed).
    #[arg(long, value_name = "DIR")]
    resume: Option<PathBuf>,
    /// Iterations between checkpoints of each run.
    #[arg(long = "checkpoint-every", value_name = "K", default_value_t = 2000)]
    checkpoint_every: u64,
}

/// Seeds of a sweep: a count (seeds 0..count) or an explicit list.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Seeds {
    /// Seeds `0, 1, …, count − 1`.
    Count(u64),
    /// These seeds.
    List(Vec<u64>),
}

impl Seeds {
    fn list(&self) -> Vec<u64> {
        match self {
            Seeds::Count(n) => (0..*n).collect(),
            Seeds::List(v) => v.clone(),
        }
    }
}

/// A sweep: the product presets × variants × σ⁰ × seeds over a base configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct SweepSpec {
    /// Environments.
    pub presets: Vec<EnvName>,
    /// Seeds.
    pub seeds: Seeds,
    /// Initial standard deviations σ⁰ (one value each, for every action dimension).
    pub sigma0: Vec<f64>,
    /// Options shared by every run.
    #[serde(default)]
    pub base: RunSpec,
    /// The variants (each a set of run options with a unique `name`).
    pub variant: Vec<RunSpec>,
}

/// One run of a sweep.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunEntry {
    /// Index in the sweep (preset-major, then variant, σ⁰, seed).
    pub index: usize,
    /// Environment.
    pub preset: EnvName,
    /// Variant name.
    pub variant: String,
    /// Initial standard deviation.
    pub sigma0: f64,
    /// Seed.
    pub seed: u64,
    /// Run folder relative to the sweep folder.
    pub dir: String,
}

/// Which runs of the sweep a folder holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// Shard index I.
    pub index: usize,
    /// Number of shards N (1: the whole sweep).
    pub count: usize,
}

/// `sweep.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepFile {
    /// Hash of every resolved run configuration (FNV-1a, hex): equal iff the sweeps are.
    pub sweep_id: String,
    /// The sweep.
    pub spec: SweepSpec,
    /// Every run of the sweep (all shards).
    pub runs: Vec<RunEntry>,
    /// The runs this folder holds.
    pub shard: Shard,
    /// Number of shard folders merged into this one (0 if it was run directly).
    pub merged_from: usize,
}

impl SweepFile {
    /// The runs of the shard.
    pub fn shard_runs(&self) -> impl Iterator<Item = &RunEntry> {
        self.runs
            .iter()
            .filter(|r| r.index % self.shard.count == self.shard.index)
    }

    /// Reads `sweep.json` of a sweep folder.
    ///
    /// # Errors
    /// Usage error when the folder has no valid `sweep.json`.
    pub fn read(dir: &Path) -> Result<SweepFile, CliError> {
        let p = dir.join(SWEEP_FILE);
        let text = std::fs::read_to_string(&p).map_err(|e| {
            CliError::usage(format!("{} is not a sweep folder: {e}", dir.display()))
        })?;
        serde_json::from_str(&text)
            .map_err(|e| CliError::usage(format!("{} is invalid: {e}", p.display())))
    }
}

fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325_u64, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

fn path_safe(name: &str) -> bool {
    !name.is_empty()
        && name != "."
        && name != ".."
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'))
}

/// Expands a sweep into its resolved runs and `sweep.json` contents (for shard `shard`).
///
/// # Errors
/// Usage error for an empty axis, a duplicate or unsafe variant name, a variant or base that
/// sets a sweep axis (env, seed, sigma0), or any run whose configuration is invalid.
pub fn expand(spec: &SweepSpec, shard: Shard) -> Result<(SweepFile, Vec<Resolved>), CliError> {
    let seeds = spec.seeds.list();
    if spec.presets.is_empty()
        || seeds.is_empty()
        || spec.sigma0.is_empty()
        || spec.variant.is_empty()
    {
        return Err(CliError::usage(
            "a sweep needs at least one preset, seed, sigma0 and variant",
        ));
    }
    let axis = |s: &RunSpec| s.env.is_some() || s.seed.is_some() || s.sigma0.is_some();
    if axis(&spec.base) || spec.variant.iter().any(axis) {
        return Err(CliError::usage(
            "env, seed and sigma0 are sweep axes (presets, seeds, sigma0), not run options",
        ));
    }
    let mut names = Vec::new();
    for v in &spec.variant {
        let name = v
            .name
            .clone()
            .or_else(|| {
                v.algo
                    .and_then(|a| clap::ValueEnum::to_possible_value(&a))
                    .map(|p| p.get_name().to_owned())
            })
            .ok_or_else(|| CliError::usage("every variant needs a name or an algo"))?;
        if !path_safe(&name) {
            return Err(CliError::usage(format!(
                "variant name {name:?} must use only letters, digits, '-', '_', '.'"
            )));
        }
        if names.contains(&name) {
            return Err(CliError::usage(format!(
                "variant name {name:?} appears twice"
            )));
        }
        names.push(name);
    }
    let mut runs = Vec::new();
    let mut resolved = Vec::new();
    let mut hash_input = String::new();
    for &preset in &spec.presets {
        for (variant, name) in spec.variant.iter().zip(&names) {
            for &sigma0 in &spec.sigma0 {
                for &seed in &seeds {
                    let axes = RunSpec {
                        name: Some(name.clone()),
                        env: Some(preset),
                        sigma0: Some(Values::One(sigma0)),
                        seed: Some(seed),
                        ..RunSpec::default()
                    };
                    let r = spec
                        .base
                        .overlay(variant)
                        .overlay(&axes)
                        .resolve()
                        .map_err(|e| {
                            CliError::usage(format!(
                                "variant {name} on {} with sigma0 {sigma0}: {e}",
                                preset.name()
                            ))
                        })?;
                    hash_input.push_str(&r.toml()?);
                    runs.push(RunEntry {
                        index: runs.len(),
                        preset,
                        variant: name.clone(),
                        sigma0,
                        seed,
                        dir: format!(
                            "{RUNS_DIR}/{}/{name}/sigma-{sigma0:?}/seed-{seed}",
                            preset.name()
                        ),
                    });
                    resolved.push(r);
                }
            }
        }
    }
    let file = SweepFile {
        sweep_id: format!("{:016x}", fnv1a(hash_input.as_bytes())),
        spec: spec.clone(),
        runs,
        shard,
        merged_from: 0,
    };
    Ok((file, resolved))
}

/// Parses `I/N` with `0 ≤ I < N`.
///
/// # Errors
/// Usage error for anything else.
pub fn parse_shard(s: &str) -> Result<Shard, CliError> {
    let bad = || CliError::usage(format!("--shard {s:?}: expected I/N with 0 <= I < N"));
    let (i, n) = s.split_once('/').ok_or_else(bad)?;
    let index: usize = i.trim().parse().map_err(|_| bad())?;
    let count: usize = n.trim().parse().map_err(|_| bad())?;
    if count == 0 || index >= count {
        return Err(bad());
    }
    Ok(Shard { index, count })
}

/// Reads a sweep file.
///
/// # Errors
/// Usage error for a missing file or an invalid key or value.
pub fn read_spec(path: &Path) -> Result<SweepSpec, CliError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| CliError::usage(format!("cannot read {}: {e}", path.display())))?;
    toml::from_str(&text)
        .map_err(|e| CliError::usage(format!("{}: {}", path.display(), runfmt::toml_message(&e))))
}

/// Throughput of a finished sweep.
#[derive(Debug, Clone, Copy)]
pub struct SweepStats {
    /// Runs executed (or resumed) by this call.
    pub runs: usize,
    /// Iterations executed by this call.
    pub iterations: u64,
    /// Wall time in seconds.
    pub wall_s: f64,
}

/// Runs every incomplete run of the shard in `dir` (which holds `file` as `sweep.json`), in
/// parallel over runs.
///
/// # Errors
/// The first run's failure (after every other run has stopped at a checkpoint).
pub fn execute(
    dir: &Path,
    file: &SweepFile,
    resolved: &[Resolved],
    checkpoint_every: u64,
    progress: bool,
) -> Result<SweepStats, CliError> {
    runfmt::install_interrupt_handler();
    let todo: Vec<(&RunEntry, &Resolved)> = file
        .shard_runs()
        .map(|r| (r, &resolved[r.index]))
        .filter(|(r, _)| !runfmt::is_complete(&dir.join(&r.dir)))
        .collect();
    let total: u64 = todo.iter().map(|(_, r)| r.iterations()).sum();
    let pb = if progress && std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        let pb = ProgressBar::new(todo.len() as u64);
        if let Ok(style) = ProgressStyle::with_template("{bar:40} {pos}/{len} runs  eta {eta}") {
            pb.set_style(style);
        }
        pb
    } else {
        ProgressBar::hidden()
    };
    let opts = RunOptions {
        checkpoint_every,
        progress: false,
    };
    let start = Instant::now();
    let results: Vec<Result<(), CliError>> = todo
        .par_iter()
        .map(|(entry, res)| {
            let run_dir = dir.join(&entry.dir);
            let out = if run_dir.join(runfmt::CONFIG_FILE).is_file() {
                runfmt::resume(&run_dir, opts)
            } else {
                runfmt::start(&run_dir, res, opts)
            };
            pb.inc(1);
            out.map(|_| ())
        })
        .collect();
    pb.finish_and_clear();
    if let Some(Err(e)) = results.into_iter().find(Result::is_err) {
        return Err(e);
    }
    Ok(SweepStats {
        runs: todo.len(),
        iterations: total,
        wall_s: start.elapsed().as_secs_f64(),
    })
}

/// Creates the sweep folder `dir` with `sweep.json` and runs it.
///
/// # Errors
/// As [`execute`], and usage error for a non-empty folder without `force`.
pub fn start(
    dir: &Path,
    file: &SweepFile,
    resolved: &[Resolved],
    force: bool,
    checkpoint_every: u64,
    progress: bool,
) -> Result<SweepStats, CliError> {
    runfmt::check_out_dir(dir, force, &[SWEEP_FILE, RUNS_DIR])?;
    std::fs::create_dir_all(dir)
        .map_err(|e| CliError::failure(format!("cannot create {}: {e}", dir.display())))?;
    write_atomic(&dir.join(SWEEP_FILE), to_json_line(file)?.as_bytes())?;
    execute(dir, file, resolved, checkpoint_every, progress)
}

/// The one-line report of a finished sweep.
pub fn stats_line(dir: &Path, file: &SweepFile, s: &SweepStats) -> String {
    let shard = if file.shard.count > 1 {
        format!(" (shard {}/{})", file.shard.index, file.shard.count)
    } else {
        String::new()
    };
    let rate = if s.wall_s > 0.0 {
        s.iterations as f64 / s.wall_s
    } else {
        0.0
    };
    format!(
        "{}{shard}: {} runs, {} iterations in {:.1} s ({:.0} it/s)",
        dir.display(),
        s.runs,
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
    let (dir, file, stats) = if let Some(dir) = &args.resume {
        if args.config.is_some() || args.out.is_some() || args.shard.is_some() || args.force {
            return Err(CliError::usage(
                "--resume takes no other options than --quiet and --checkpoint-every",
            ));
        }
        let file = SweepFile::read(dir)?;
        let (expected, resolved) = expand(&file.spec, file.shard)?;
        if expected.sweep_id != file.sweep_id {
            return Err(CliError::usage(format!(
                "{} was written by another sepg version (sweep id differs)",
                dir.join(SWEEP_FILE).display()
            )));
        }
        let stats = execute(dir, &file, &resolved, args.checkpoint_every, !args.quiet)?;
        (dir.clone(), file, stats)
    } else {
        let path = args
            .config
            .as_ref()
            .ok_or_else(|| CliError::usage("--config FILE.toml is required"))?;
        let spec = read_spec(path)?;
        let shard = match &args.shard {
            Some(s) => parse_shard(s)?,
            None => Shard { index: 0, count: 1 },
        };
        let (file, resolved) = expand(&spec, shard)?;
        let dir = args
            .out
            .clone()
            .ok_or_else(|| CliError::usage("--out DIR is required"))?;
        let stats = start(
            &dir,
            &file,
            &resolved,
            args.force,
            args.checkpoint_every,
            !args.quiet,
        )?;
        (dir, file, stats)
    };
    if !args.quiet {
        println!("{}", stats_line(&dir, &file, &stats));
    }
    Ok(())
}
