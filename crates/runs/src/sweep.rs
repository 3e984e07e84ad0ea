//! Sweeps: every (preset, variant, σ⁰, seed) combination of a sweep file, run in parallel
//! into one run folder each, optionally restricted to a shard `I/N` (the runs whose
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
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::audit::{DEFAULT_ALPHA, DEFAULT_TOLERANCE, audit, broken_runs_p_value, check_levels};
use crate::error::{Error, Result};
use crate::folder::{CONFIG_FILE, check_out_dir, is_complete, to_json_line, write_atomic};
use crate::run::{self, RunObserver, RunOptions, Silent};
use crate::spec::{EnvName, Resolved, RunSpec, Values, toml_message};

/// The sweep description file.
pub const SWEEP_FILE: &str = "sweep.json";
/// Folder of the run folders inside a sweep folder.
pub const RUNS_DIR: &str = "runs";
/// One row per run of a finished sweep folder: its settings, outcome and audit status.
pub const SUMMARY_CSV: &str = "summary.csv";

/// Seeds of a sweep: a count (seeds 0..count) or an explicit list.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Seeds {
    /// Seeds `0, 1, …, count − 1`.
    Count(u64),
    /// These seeds.
    List(Vec<u64>),
}

/// Largest number of runs of one sweep (presets × variants × σ⁰ × seeds): each run is
/// resolved and listed in `sweep.json` before any starts (docs/RELIABILITY.md, "Sizes").
pub const MAX_RUNS: u64 = 1_000_000;

impl Seeds {
    /// Number of seeds.
    fn count(&self) -> u64 {
        match self {
            Seeds::Count(n) => *n,
            Seeds::List(v) => v.len() as u64,
        }
    }

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
    /// [`Error::Invalid`] when the folder has no valid `sweep.json`.
    pub fn read(dir: &Path) -> Result<SweepFile> {
        let p = dir.join(SWEEP_FILE);
        let text = std::fs::read_to_string(&p).map_err(|e| {
            Error::invalid_from(format_args!("{} is not a sweep folder", dir.display()), e)
        })?;
        serde_json::from_str(&text)
            .map_err(|e| Error::invalid_from(format_args!("{} is invalid", p.display()), e))
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
/// [`Error::Invalid`] for an empty axis, more than [`MAX_RUNS`] runs, a duplicate or unsafe
/// variant name, a variant or base that sets a sweep axis (env, seed, sigma0), or any run whose
/// configuration is invalid.
pub fn expand(spec: &SweepSpec, shard: Shard) -> Result<(SweepFile, Vec<Resolved>)> {
    let runs = [
        spec.presets.len() as u64,
        spec.variant.len() as u64,
        spec.sigma0.len() as u64,
    ]
    .iter()
    .try_fold(spec.seeds.count(), |a, &b| a.checked_mul(b));
    if runs.is_none_or(|r| r > MAX_RUNS) {
        return Err(Error::invalid(format!(
            "the sweep has {} runs, more than the limit of {MAX_RUNS}",
            runs.map_or_else(|| "more than 2^64".to_owned(), |r| r.to_string())
        )));
    }
    let seeds = spec.seeds.list();
    if spec.presets.is_empty()
        || seeds.is_empty()
        || spec.sigma0.is_empty()
        || spec.variant.is_empty()
    {
        return Err(Error::invalid(
            "a sweep needs at least one preset, seed, sigma0 and variant",
        ));
    }
    let axis = |s: &RunSpec| s.env.is_some() || s.seed.is_some() || s.sigma0.is_some();
    if axis(&spec.base) || spec.variant.iter().any(axis) {
        return Err(Error::invalid(
            "env, seed and sigma0 are sweep axes (presets, seeds, sigma0), not run options",
        ));
    }
    let names = variant_names(&spec.variant)?;
    let mut runs = Vec::new();
    let mut resolved = Vec::new();
    let mut hash_input = String::new();
    for &preset in &spec.presets {
        for (variant, name) in spec.variant.iter().zip(&names) {
            for &sigma0 in &spec.sigma0 {
                for &seed in &seeds {
                    let r = resolve_run(&spec.base, variant, name, preset, sigma0, seed)?;
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

/// The name of each variant (its `name`, else its algorithm's), checked to be unique and
/// usable as a folder name.
fn variant_names(variants: &[RunSpec]) -> Result<Vec<String>> {
    let mut names: Vec<String> = Vec::new();
    for v in variants {
        let name = v
            .name
            .clone()
            .or_else(|| v.algo.map(|a| a.name().to_owned()))
            .ok_or_else(|| Error::invalid("every variant needs a name or an algo"))?;
        if !path_safe(&name) {
            return Err(Error::invalid(format!(
                "variant name {name:?} must use only letters, digits, '-', '_', '.'"
            )));
        }
        if names.contains(&name) {
            return Err(Error::invalid(format!(
                "variant name {name:?} appears twice"
            )));
        }
        names.push(name);
    }
    Ok(names)
}

/// The resolved run of `variant` (named `name`) over `base` at one point of the axes.
fn resolve_run(
    base: &RunSpec,
    variant: &RunSpec,
    name: &str,
    preset: EnvName,
    sigma0: f64,
    seed: u64,
) -> Result<Resolved> {
    let axes = RunSpec {
        name: Some(name.to_owned()),
        env: Some(preset),
        sigma0: Some(Values::One(sigma0)),
        seed: Some(seed),
        ..RunSpec::default()
    };
    base.overlay(variant).overlay(&axes).resolve().map_err(|e| {
        Error::invalid_from(
            format_args!("variant {name} on {} with sigma0 {sigma0:?}", preset.name()),
            e,
        )
    })
}

/// Parses `I/N` with `0 ≤ I < N`.
///
/// # Errors
/// [`Error::Invalid`] for anything else.
pub fn parse_shard(s: &str) -> Result<Shard> {
    let bad = || Error::invalid(format!("--shard {s:?}: expected I/N with 0 <= I < N"));
    let (i, n) = s.split_once('/').ok_or_else(bad)?;
    let index: usize = i.trim().parse().map_err(|_| bad())?;
    let count: usize = n.trim().parse().map_err(|_| bad())?;
    if count == 0 || index >= count {
        return Err(bad());
    }
    Ok(Shard { index, count })
}

/// The shard of this task of a Slurm job array: `I = (SLURM_ARRAY_TASK_ID −
/// SLURM_ARRAY_TASK_MIN) / SLURM_ARRAY_TASK_STEP` and `N = SLURM_ARRAY_TASK_COUNT`, so that an
/// array `--array=A-B` of any first index A (step 1, or a uniform step) numbers its tasks
/// 0, 1, …, N − 1. `SLURM_ARRAY_TASK_MIN` defaults to 0 and `SLURM_ARRAY_TASK_STEP` to 1
/// when absent. `var` looks a variable up (`std::env::var` on a cluster; a map in tests).
///
/// # Errors
/// [`Error::Invalid`] naming the variable when `SLURM_ARRAY_TASK_ID` or
/// `SLURM_ARRAY_TASK_COUNT` is absent, a variable is not a non-negative integer (the step
/// must be positive), or the task does not map to a shard `0 ≤ I < N` (an array with gaps,
/// such as `--array=1,5,9`).
pub fn slurm_shard(var: impl Fn(&str) -> Option<String>) -> Result<Shard> {
    let read = |name: &str, default: Option<usize>| -> Result<usize> {
        match (var(name), default) {
            (Some(text), _) => text.trim().parse::<usize>().map_err(|e| {
                Error::invalid(format!(
                    "--shard slurm: {name}={text:?} is not a non-negative integer"
                ))
                .with_source(e)
            }),
            (None, Some(d)) => Ok(d),
            (None, None) => Err(Error::invalid(format!(
                "--shard slurm: {name} is not set (run inside a Slurm job array: sbatch --array=0-N)"
            ))),
        }
    };
    let id = read("SLURM_ARRAY_TASK_ID", None)?;
    let count = read("SLURM_ARRAY_TASK_COUNT", None)?;
    let min = read("SLURM_ARRAY_TASK_MIN", Some(0))?;
    let step = read("SLURM_ARRAY_TASK_STEP", Some(1))?;
    if step == 0 {
        return Err(Error::invalid(
            "--shard slurm: SLURM_ARRAY_TASK_STEP=0 is not a positive integer",
        ));
    }
    let offset = id.checked_sub(min).filter(|o| o % step == 0);
    match offset.map(|o| o / step) {
        Some(index) if index < count => Ok(Shard { index, count }),
        _ => Err(Error::invalid(format!(
            "--shard slurm: task {id} of an array of {count} tasks from {min} by {step} is not \
             one of tasks 0..{count}; use a range without gaps, e.g. --array=0-{}",
            count.saturating_sub(1)
        ))),
    }
}

/// Reads a sweep file.
///
/// # Errors
/// [`Error::Invalid`] for a missing file or an invalid key or value.
pub fn read_spec(path: &Path) -> Result<SweepSpec> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| Error::invalid_from(format_args!("cannot read {}", path.display()), e))?;
    toml::from_str(&text).map_err(|e| {
        Error::invalid(format!("{}: {}", path.display(), toml_message(&e))).with_source(e)
    })
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

/// How a sweep is driven: checkpoint period of each run, stop flag and progress observer.
#[derive(Clone, Copy)]
pub struct SweepOptions<'a> {
    /// Iterations between checkpoints of each run (at least 1).
    pub checkpoint_every: u64,
    /// When raised, every run stops after its current iteration and checkpoints.
    pub stop: &'a AtomicBool,
    /// Receives the number of runs finished.
    pub observer: &'a dyn RunObserver,
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
    opts: SweepOptions<'_>,
) -> Result<SweepStats> {
    let todo: Vec<(&RunEntry, &Resolved)> = file
        .shard_runs()
        .map(|r| (r, &resolved[r.index]))
        .filter(|(r, _)| !is_complete(&dir.join(&r.dir)))
        .collect();
    let total: u64 = todo.iter().map(|(_, r)| r.iterations()).sum();
    opts.observer.begin(0, todo.len() as u64);
    let run_opts = RunOptions {
        checkpoint_every: opts.checkpoint_every,
        stop: opts.stop,
        observer: &Silent,
    };
    let finished = AtomicU64::new(0);
    let start = Instant::now();
    let results: Vec<Result<()>> = todo
        .par_iter()
        .map(|(entry, res)| {
            let out = run_entry(dir, entry, res, run_opts);
            opts.observer
                .advance(finished.fetch_add(1, Ordering::SeqCst) + 1);
            out
        })
        .collect();
    opts.observer.end();
    let interrupted = results
        .iter()
        .any(|r| matches!(r, Err(Error::Interrupted { .. })));
    // A failure is reported before an interruption: it is what the user must fix.
    if let Some(Err(e)) = results.into_iter().find(|r| {
        r.as_ref()
            .is_err_and(|e| !matches!(e, Error::Interrupted { .. }))
    }) {
        return Err(e);
    }
    if interrupted {
        let runs: Vec<&RunEntry> = file.shard_runs().collect();
        return Err(Error::SweepInterrupted {
            complete: runs
                .iter()
                .filter(|r| is_complete(&dir.join(&r.dir)))
                .count(),
            runs: runs.len(),
            dir: dir.to_path_buf(),
        });
    }
    write_summary_csv(dir, file, false)?;
    Ok(SweepStats {
        runs: todo.len(),
        iterations: total,
        wall_s: start.elapsed().as_secs_f64(),
    })
}

/// Creates the sweep folder `dir` with `sweep.json` and runs it.
///
/// # Errors
/// As [`execute`], and [`Error::Invalid`] for a non-empty folder without `force`.
pub fn start(
    dir: &Path,
    file: &SweepFile,
    resolved: &[Resolved],
    force: bool,
    opts: SweepOptions<'_>,
) -> Result<SweepStats> {
    prepare(dir, file, force)?;
    execute(dir, file, resolved, opts)
}

/// Creates the sweep folder `dir` with `file` as its `sweep.json` and runs nothing: the
/// first step of [`start`], and of a sweep whose runs are mapped over a cluster engine one
/// by one with [`run_one`] and closed by [`finish`].
///
/// # Errors
/// [`Error::Invalid`] for a non-empty folder without `force`; [`Error::Failed`] when the
/// folder or file cannot be written.
pub fn prepare(dir: &Path, file: &SweepFile, force: bool) -> Result<()> {
    check_out_dir(dir, force, &[SWEEP_FILE, RUNS_DIR, SUMMARY_CSV])?;
    std::fs::create_dir_all(dir)
        .map_err(|e| Error::failed_from(format_args!("cannot create {}", dir.display()), e))?;
    write_atomic(&dir.join(SWEEP_FILE), to_json_line(file)?.as_bytes())
}

/// Runs, resumes, or leaves as it is when complete, the run of `entry` in the sweep folder
/// `dir`: the unit of work of [`execute`] and [`run_one`].
fn run_entry(
    dir: &Path,
    entry: &RunEntry,
    resolved: &Resolved,
    opts: RunOptions<'_>,
) -> Result<()> {
    let run_dir = dir.join(&entry.dir);
    if is_complete(&run_dir) {
        Ok(())
    } else if run_dir.join(CONFIG_FILE).is_file() {
        run::resume(&run_dir, opts).map(|_| ())
    } else {
        run::start(&run_dir, resolved, opts).map(|_| ())
    }
}

/// Runs run `index` of the shard in the sweep folder `dir` (written by [`prepare`]), or
/// resumes it, or leaves it as it is when complete: one deterministic unit of a sweep, the
/// same bytes wherever it runs. Returns the run folder.
///
/// # Errors
/// [`Error::Invalid`] when `dir` is not a sweep folder of this version of sepg or `index` is
/// not a run of its shard; otherwise the run's error.
pub fn run_one(dir: &Path, index: usize, opts: RunOptions<'_>) -> Result<PathBuf> {
    let (file, resolved) = reopen(dir)?;
    let entry = file
        .shard_runs()
        .find(|r| r.index == index)
        .ok_or_else(|| {
            Error::invalid(format!(
                "run {index} is not in the shard of {}",
                dir.display()
            ))
        })?;
    run_entry(dir, entry, &resolved[index], opts)?;
    Ok(dir.join(&entry.dir))
}

/// Closes a sweep whose runs were run one by one with [`run_one`]: once every run of the
/// shard is complete, writes [`SUMMARY_CSV`] as [`execute`] does. Returns the sweep file.
///
/// # Errors
/// [`Error::Invalid`] when `dir` is not a sweep folder or a run of its shard is incomplete;
/// [`Error::Failed`] as [`write_summary_csv`].
pub fn finish(dir: &Path) -> Result<SweepFile> {
    let file = SweepFile::read(dir)?;
    if let Some(r) = file.shard_runs().find(|r| !is_complete(&dir.join(&r.dir))) {
        return Err(Error::invalid(format!(
            "run {} of {} is not complete",
            r.index,
            dir.display()
        )));
    }
    write_summary_csv(dir, &file, false)?;
    Ok(file)
}

/// `sweep.json` of `dir` re-expanded by this version of sepg, checked to describe the same
/// runs.
fn reopen(dir: &Path) -> Result<(SweepFile, Vec<Resolved>)> {
    let file = SweepFile::read(dir)?;
    let (expected, resolved) = expand(&file.spec, file.shard)?;
    if expected.sweep_id != file.sweep_id {
        return Err(Error::invalid(format!(
            "{} was written by another sepg version (sweep id differs)",
            dir.join(SWEEP_FILE).display()
        )));
    }
    Ok((file, resolved))
}

/// Resumes the sweep in `dir`: re-expands its `sweep.json` with this version of sepg, checks
/// that it describes the same runs, and runs the incomplete ones.
///
/// # Errors
/// [`Error::Invalid`] when `dir` is not a sweep folder or was written by a version of sepg
/// that resolves it differently; otherwise as [`execute`].
pub fn resume(dir: &Path, opts: SweepOptions<'_>) -> Result<(SweepFile, SweepStats)> {
    let (file, resolved) = reopen(dir)?;
    let stats = execute(dir, &file, &resolved, opts)?;
    Ok((file, stats))
}

/// The header of [`SUMMARY_CSV`].
pub const SUMMARY_CSV_HEADER: &str =
    "preset,variant,algorithm,sigma0,seed,v,sigma,j,abs_v_error,infeasible,audit";

/// Writes [`SUMMARY_CSV`] in the sweep folder `dir`: one row per run of its shard, in sweep
/// order, with the preset, variant, algorithm, σ⁰, seed, final v and σ (components joined by
/// `;`), the last logged J of the exploratory policy, max_i |v_i − v*_i| (LQG), the number of
/// infeasible iterations and, with `audit`, the verdict of `sepg audit` at its defaults
/// ([`audit_sweep`]; without `audit`: `not-audited`, since recomputing exact J costs several
/// times the run itself). The file is replaced atomically. Returns the audit column of each
/// run, in sweep order.
///
/// # Errors
/// [`Error::Failed`] when a finished run's summary cannot be read or the file cannot be
/// written.
pub fn write_summary_csv(dir: &Path, file: &SweepFile, audit: bool) -> Result<Vec<String>> {
    if audit {
        let audited = audit_sweep(dir, file, DEFAULT_TOLERANCE, DEFAULT_ALPHA)?;
        return Ok(audited.runs.into_iter().map(|r| r.verdict).collect());
    }
    let verdicts = vec!["not-audited".to_owned(); file.shard_runs().count()];
    summary_csv(dir, file, &verdicts)?;
    Ok(verdicts)
}

/// Writes [`SUMMARY_CSV`] with the audit column `verdicts` (one per run, in sweep order).
fn summary_csv(dir: &Path, file: &SweepFile, verdicts: &[String]) -> Result<()> {
    use crate::folder::{load_resolved, read_summary};
    let runs: Vec<&RunEntry> = file.shard_runs().collect();
    let rows: Vec<Result<String>> = runs
        .par_iter()
        .zip(verdicts)
        .map(|(r, verdict)| {
            let run_dir = dir.join(&r.dir);
            let summary = read_summary(&run_dir)?;
            let algorithm = load_resolved(&run_dir)?.spec.algo.map_or("", |a| a.name());
            let join = |xs: &[f64]| {
                xs.iter()
                    .map(|x| format!("{x:?}"))
                    .collect::<Vec<_>>()
                    .join(";")
            };
            let opt = |x: Option<f64>| x.map(|x| format!("{x:?}")).unwrap_or_default();
            Ok(format!(
                "{},{},{algorithm},{:?},{},{},{},{},{},{},{verdict}\n",
                r.preset.name(),
                r.variant,
                r.sigma0,
                r.seed,
                join(&summary.final_params.v),
                join(&summary.final_params.sigma),
                opt(summary.last_j_explore),
                opt(summary.abs_v_error),
                summary.infeasible_iterations,
            ))
        })
        .collect();
    let mut text = format!("{SUMMARY_CSV_HEADER}\n");
    for row in rows {
        text.push_str(&row?);
    }
    write_atomic(&dir.join(SUMMARY_CSV), text.as_bytes())
}

/// Group verdicts of `sepg audit SWEEP_DIR`: one row per (preset, variant, σ⁰).
pub const AUDIT_GROUPS_CSV: &str = "audit-groups.csv";

/// The header of [`AUDIT_GROUPS_CSV`].
pub const AUDIT_GROUPS_HEADER: &str =
    "preset,variant,sigma0,runs,failed,rate,p_value,level,verdict";

/// The audit of one run of a sweep.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunAudit {
    /// Run folder relative to the sweep folder.
    pub dir: String,
    /// The run's verdict ([`crate::audit::Verdict::name`]), or `malformed` (invalid folder) or
    /// `error` (the audit could not run).
    pub verdict: String,
    /// Whether the run failed what its statement states (counted in its group).
    pub failed: bool,
    /// The probability, under its statement, that the run is found failed
    /// ([`crate::audit::AuditReport::null_rate`]); `None` when nothing is tested.
    pub rate: Option<f64>,
}

/// The verdict on a group of runs that differ only in their seed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum GroupVerdict {
    /// Proven statements: the number of failed runs is consistent with their rate.
    Consistent,
    /// Proven statements: the exact binomial test rejects the number of failed runs at the
    /// Bonferroni level α / (number of tested groups).
    Rejected,
    /// Approximate statements: the count and its p-value are reported, not judged.
    Approximate,
    /// The runs state nothing about exact J.
    NoGuarantee,
    /// No exact oracle: not checked against exact J.
    NotChecked,
    /// A run is unfinished, malformed or could not be audited.
    Incomplete,
}

impl GroupVerdict {
    /// The name in [`AUDIT_GROUPS_CSV`] and the printed lines.
    pub fn name(self) -> &'static str {
        match self {
            GroupVerdict::Consistent => "consistent",
            GroupVerdict::Rejected => "rejected",
            GroupVerdict::Approximate => "approximate",
            GroupVerdict::NoGuarantee => "no-guarantee",
            GroupVerdict::NotChecked => "not-checked",
            GroupVerdict::Incomplete => "incomplete",
        }
    }
}

/// The test of one (preset, variant, σ⁰) group of a sweep.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GroupAudit {
    /// Environment.
    pub preset: String,
    /// Variant name.
    pub variant: String,
    /// Initial standard deviation.
    pub sigma0: f64,
    /// Runs (seeds) in the group.
    pub runs: u64,
    /// Runs that failed what their statement states.
    pub failed: u64,
    /// The probability with which each run may fail under its statement (0 for exact
    /// gradients, δ for scope `run`, α for scope `iteration`); `None` when untested.
    pub rate: Option<f64>,
    /// P(Binomial(runs, rate) ≥ failed).
    pub p_value: Option<f64>,
    /// The Bonferroni level the p-value is compared with: α / (number of tested groups).
    pub level: Option<f64>,
    /// The verdict.
    pub verdict: GroupVerdict,
}

/// The audit of a sweep: every run, and every group.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SweepAudit {
    /// The runs, in sweep order.
    pub runs: Vec<RunAudit>,
    /// The groups, in order of their first run.
    pub groups: Vec<GroupAudit>,
}

/// Audits every run of the sweep folder `dir` (in parallel) with relative tolerance
/// `tolerance` and level `alpha` ([`crate::audit::audit`]), writes their verdicts into the
/// audit column of [`SUMMARY_CSV`], and tests each (preset, variant, σ⁰) group: its runs are
/// independent (they differ only in their seed), each failing with probability at most
/// `rate` under its statement, so the number of failed runs is at most Binomial(n, rate); the
/// group is rejected when P(Binomial(n, rate) ≥ failed) < α / G, G the number of groups with
/// proven statements (Bonferroni). The group verdicts go to [`AUDIT_GROUPS_CSV`].
///
/// # Errors
/// [`Error::Invalid`] for a tolerance or level out of range; [`Error::Failed`] when a finished
/// run's summary cannot be read or a file cannot be written.
pub fn audit_sweep(dir: &Path, file: &SweepFile, tolerance: f64, alpha: f64) -> Result<SweepAudit> {
    check_levels(tolerance, alpha)?;
    let entries: Vec<&RunEntry> = file.shard_runs().collect();
    let runs: Vec<RunAudit> = entries
        .par_iter()
        .map(|r| audit_entry(dir, r, tolerance, alpha))
        .collect();
    let verdicts: Vec<String> = runs.iter().map(|r| r.verdict.clone()).collect();
    summary_csv(dir, file, &verdicts)?;
    let mut groups = Vec::new();
    for ((preset, variant, sigma0), idx) in audit_groups(&entries) {
        let of: Vec<&RunAudit> = idx.iter().map(|&i| &runs[i]).collect();
        groups.push(audit_group(preset, variant, f64::from_bits(sigma0), &of)?);
    }
    let tested = groups
        .iter()
        .filter(|g| g.verdict == GroupVerdict::Consistent)
        .count()
        .max(1);
    let level = alpha / tested as f64;
    for g in &mut groups {
        if let Some(p) = g.p_value {
            g.level = Some(level);
            if g.verdict == GroupVerdict::Consistent && p < level {
                g.verdict = GroupVerdict::Rejected;
            }
        }
    }
    write_atomic(
        &dir.join(AUDIT_GROUPS_CSV),
        audit_groups_csv(&groups).as_bytes(),
    )?;
    Ok(SweepAudit { runs, groups })
}

/// The audit of the run `r` of the sweep folder `dir`: its verdict, or `malformed` (bad
/// input) or `error` when it cannot be audited.
fn audit_entry(dir: &Path, r: &RunEntry, tolerance: f64, alpha: f64) -> RunAudit {
    match audit(&dir.join(&r.dir), tolerance, alpha) {
        Ok(a) => RunAudit {
            dir: r.dir.clone(),
            verdict: a.verdict.name().to_owned(),
            failed: a.statement_failed(),
            rate: a.null_rate(),
        },
        Err(e) => RunAudit {
            dir: r.dir.clone(),
            verdict: if e.is_invalid_input() {
                "malformed"
            } else {
                "error"
            }
            .to_owned(),
            failed: false,
            rate: None,
        },
    }
}

/// The key of a group of a sweep's audit: preset, variant and the bits of σ⁰.
type GroupKey<'e> = (EnvName, &'e str, u64);

/// The groups of `entries` in order of their first run, each with the indices of its runs.
fn audit_groups<'e>(entries: &[&'e RunEntry]) -> Vec<(GroupKey<'e>, Vec<usize>)> {
    let mut groups: Vec<(GroupKey<'_>, Vec<usize>)> = Vec::new();
    for (i, r) in entries.iter().enumerate() {
        let k = (r.preset, r.variant.as_str(), r.sigma0.to_bits());
        match groups.iter_mut().find(|(x, _)| *x == k) {
            Some((_, members)) => members.push(i),
            None => groups.push((k, vec![i])),
        }
    }
    groups
}

/// The audit of one group from the audits `of` its runs, before the Bonferroni level is set:
/// incomplete when a run is unfinished or could not be audited, else tested by the exact
/// binomial tail at the largest null rate of its runs when every run has one.
fn audit_group(
    preset: EnvName,
    variant: &str,
    sigma0: f64,
    of: &[&RunAudit],
) -> Result<GroupAudit> {
    let n = of.len() as u64;
    let failed = of.iter().filter(|r| r.failed).count() as u64;
    let has = |v: &str| of.iter().any(|r| r.verdict == v);
    let unfinished = ["incomplete", "malformed", "error"].iter().any(|v| has(v));
    let rate = of
        .iter()
        .map(|r| r.rate)
        .try_fold(0.0f64, |m, r| r.map(|r| m.max(r)));
    let (verdict, p_value) = match rate {
        _ if unfinished => (GroupVerdict::Incomplete, None),
        Some(rate) => {
            let p = broken_runs_p_value(failed, n, rate)?;
            let v = if has("approximate") {
                GroupVerdict::Approximate
            } else {
                GroupVerdict::Consistent
            };
            (v, Some(p))
        }
        None if has("not-checked") => (GroupVerdict::NotChecked, None),
        None => (GroupVerdict::NoGuarantee, None),
    };
    Ok(GroupAudit {
        preset: preset.name().to_owned(),
        variant: variant.to_owned(),
        sigma0,
        runs: n,
        failed,
        rate: rate.filter(|_| p_value.is_some()),
        p_value,
        level: None,
        verdict,
    })
}

/// The text of [`AUDIT_GROUPS_CSV`]: its header and one line per group.
fn audit_groups_csv(groups: &[GroupAudit]) -> String {
    let opt = |x: Option<f64>| x.map(|x| format!("{x:?}")).unwrap_or_default();
    let mut text = format!("{AUDIT_GROUPS_HEADER}\n");
    for g in groups {
        text.push_str(&format!(
            "{},{},{:?},{},{},{},{},{},{}\n",
            g.preset,
            g.variant,
            g.sigma0,
            g.runs,
            g.failed,
            opt(g.rate),
            opt(g.p_value),
            opt(g.level),
            g.verdict.name()
        ));
    }
    text
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use super::*;

    fn slurm(vars: &[(&str, &str)]) -> Result<Shard> {
        let map: HashMap<String, String> = vars
            .iter()
            .map(|(k, v)| ((*k).to_owned(), (*v).to_owned()))
            .collect();
        slurm_shard(|k| map.get(k).cloned())
    }

    #[test]
    fn slurm_arrays_number_their_tasks_from_zero() {
        let shard = |index, count| Shard { index, count };
        // --array=0-3, task 2.
        let vars = [
            ("SLURM_ARRAY_TASK_ID", "2"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ];
        assert_eq!(slurm(&vars).expect("valid"), shard(2, 4));
        // --array=1-4: ids 1..=4 are shards 0..=3.
        for id in 1..=4 {
            let id_text = id.to_string();
            let vars = [
                ("SLURM_ARRAY_TASK_ID", id_text.as_str()),
                ("SLURM_ARRAY_TASK_COUNT", "4"),
                ("SLURM_ARRAY_TASK_MIN", "1"),
            ];
            assert_eq!(slurm(&vars).expect("valid"), shard(id - 1, 4));
        }
        // --array=10-16:3: ids 10, 13, 16 are shards 0, 1, 2.
        let vars = [
            ("SLURM_ARRAY_TASK_ID", "16"),
            ("SLURM_ARRAY_TASK_COUNT", "3"),
            ("SLURM_ARRAY_TASK_MIN", "10"),
            ("SLURM_ARRAY_TASK_STEP", "3"),
        ];
        assert_eq!(slurm(&vars).expect("valid"), shard(2, 3));
    }

    #[test]
    fn slurm_variables_that_do_not_give_a_shard_are_named() {
        let message = |vars: &[(&str, &str)]| match slurm(vars) {
            Err(Error::Invalid(m)) => m.text().to_owned(),
            other => panic!("expected an invalid-input error, got {other:?}"),
        };
        let m = message(&[("SLURM_ARRAY_TASK_COUNT", "4")]);
        assert!(m.contains("SLURM_ARRAY_TASK_ID is not set"), "{m}");
        let m = message(&[("SLURM_ARRAY_TASK_ID", "0")]);
        assert!(m.contains("SLURM_ARRAY_TASK_COUNT is not set"), "{m}");
        let m = message(&[
            ("SLURM_ARRAY_TASK_ID", "x"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ]);
        assert!(m.contains("SLURM_ARRAY_TASK_ID=\"x\""), "{m}");
        let m = message(&[
            ("SLURM_ARRAY_TASK_ID", "-1"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ]);
        assert!(m.contains("not a non-negative integer"), "{m}");
        // Ids starting at 1 without SLURM_ARRAY_TASK_MIN: task 4 of 4 is out of range.
        let m = message(&[
            ("SLURM_ARRAY_TASK_ID", "4"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ]);
        assert!(m.contains("--array=0-3"), "{m}");
        // An id below the minimum, a step that is zero, an array with gaps, no tasks.
        for vars in [
            [("SLURM_ARRAY_TASK_ID", "0"), ("SLURM_ARRAY_TASK_MIN", "1")],
            [("SLURM_ARRAY_TASK_ID", "1"), ("SLURM_ARRAY_TASK_STEP", "0")],
            [("SLURM_ARRAY_TASK_ID", "5"), ("SLURM_ARRAY_TASK_MIN", "1")],
            [
                ("SLURM_ARRAY_TASK_ID", "0"),
                ("SLURM_ARRAY_TASK_COUNT", "0"),
            ],
        ] {
            let mut all = vec![("SLURM_ARRAY_TASK_COUNT", "3")];
            all.extend(vars);
            // Later entries override the count above.
            assert!(slurm(&all).is_err(), "{vars:?}");
        }
    }
}
