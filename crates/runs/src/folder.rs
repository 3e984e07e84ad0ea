//! The run folder shared by runs, sweeps, audits and reproductions: its files, the columns
//! of `log.csv`, the checkpoint and the summary, and reading them back.
//!
//! # Folder layout and completeness rule
//! ```text
//! config.toml      resolved configuration (every option, the seed and the sepg version)
//! checkpoint.json  state after the last checkpointed iteration and the valid log length
//! log.partial.csv  rows of an unfinished run (valid up to the checkpoint's log_bytes)
//! log.csv          all rows; exists only once every iteration has been written
//! summary.json     final parameters and timings; written last: the run is complete iff it exists
//! ```
//! How a run writes these files, and resumes from them, is the subject of [`crate::run`].

use std::fs;
use std::io::Write;
use std::path::Path;

use sepg_algo::core::check::ConstantsCheck;
use sepg_algo::core::options::SepgOptions;
use sepg_algo::core::record::Record;
use sepg_algo::core::state::State;
use sepg_algo::core::statement::{SelfCheck, Statement};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::spec::{ConstantsName, Resolved, RewardsName, RunSpec, ScoresName, VERSION};
use sepg_bounds::BoundsError;
use sepg_bounds::constants::{self, TaskConstants};
use sepg_bounds::penalties::{Family, Horizon, Rewards};

/// Resolved configuration of a run.
pub const CONFIG_FILE: &str = "config.toml";
/// Checkpoint: state after the last checkpointed iteration.
pub const CHECKPOINT_FILE: &str = "checkpoint.json";
/// Log of an unfinished run.
pub const PARTIAL_LOG_FILE: &str = "log.partial.csv";
/// Log of a finished run.
pub const LOG_FILE: &str = "log.csv";
/// Summary of a finished run (its presence marks the run as complete).
pub const SUMMARY_FILE: &str = "summary.json";

/// Files a run writes; `--force` removes exactly these from an existing folder.
pub const RUN_FILES: [&str; 5] = [
    CONFIG_FILE,
    CHECKPOINT_FILE,
    PARTIAL_LOG_FILE,
    LOG_FILE,
    SUMMARY_FILE,
];

/// Writes `contents` to `path` atomically: the bytes go to a temporary file in the same
/// directory, which is then renamed over `path`, so a reader never sees a partial file.
/// On Unix the file is created with mode 0644 (less the umask), like an ordinary output file,
/// so run folders stay readable by collaborators on shared machines.
///
/// # Errors
/// [`Error::Failed`] when the folder cannot be written.
pub fn write_atomic(path: &Path, contents: &[u8]) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mut tmp = output_builder(0o644)
        .tempfile_in(dir)
        .map_err(|e| Error::failed_from(format!("cannot write in {}", dir.display()), e))?;
    tmp.write_all(contents)
        .and_then(|()| tmp.as_file().sync_all())
        .map_err(|e| Error::failed_from(format!("cannot write {}", path.display()), e))?;
    tmp.persist(path).map_err(|e| {
        Error::failed(format!("cannot write {}: {}", path.display(), e.error)).with_source(e.error)
    })?;
    Ok(())
}

/// A temporary-file builder whose file (or folder) is created with `mode` less the umask on
/// Unix (0644 for files, 0755 for folders), instead of tempfile's private 0600/0700: outputs
/// that are renamed into place keep the permissions of ordinary output files.
pub(crate) fn output_builder<'a, 'b>(mode: u32) -> tempfile::Builder<'a, 'b> {
    let mut builder = tempfile::Builder::new();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(mode));
    }
    #[cfg(not(unix))]
    let _ = mode;
    builder
}

/// Serialises `value` as pretty JSON followed by a newline.
///
/// # Errors
/// [`Error::Failed`] if serialisation fails.
pub fn to_json_line<T: serde::Serialize>(value: &T) -> Result<String> {
    let mut s = serde_json::to_string_pretty(value)
        .map_err(|e| Error::failed_from("cannot serialise output", e))?;
    s.push('\n');
    Ok(s)
}

fn indexed(name: &str, dim: usize) -> Vec<String> {
    if dim == 1 {
        vec![name.to_owned()]
    } else {
        (0..dim).map(|i| format!("{name}_{i}")).collect()
    }
}

/// The header of `log.csv` for `dim_v` mean parameters and `dim_w` standard deviations.
///
/// Columns: `iteration`, `v` (or `v_0, v_1, …`), `w`, `sigma`, `j_explore`, `j_after_v`,
/// `j_target`, `w_target`, `budget`, `required`, `required_w`, `alpha`, `beta`, `lambda_v`,
/// `lambda_w`, `guaranteed_v`, `guaranteed_w`, `infeasible`, `infeasible_v`, `infeasible_w`,
/// `below_noise_v`, `below_noise_w`, `trajectories`, `steps`, `certified_v`, `certified_w`
/// (1 when the step's bound was certified in interval arithmetic to meet its requirement, 0
/// when it was not — infeasible or within rounding of C_max —, empty when certification is
/// off or no step was taken; see `sepg_algo::core::record::Record::certified_v`).
pub fn log_header(dim_v: usize, dim_w: usize) -> String {
    let mut cols = Vec::new();
    for c in LOG_COLUMNS {
        cols.extend(match c {
            "v" => indexed(c, dim_v),
            "w" | "sigma" | "w_target" => indexed(c, dim_w),
            _ => vec![c.to_owned()],
        });
    }
    let mut s = cols.join(",");
    s.push('\n');
    s
}

/// The columns of `log.csv` in the file's order, the names of every face (the records of
/// the Python trainer are dicts with these keys): `v` has one column per mean parameter,
/// `w`, `sigma` and `w_target` one per standard deviation (`v_0, v_1, …`, or the name alone
/// for one component); see [`log_header`].
pub const LOG_COLUMNS: [&str; 26] = [
    "iteration",
    "v",
    "w",
    "sigma",
    "j_explore",
    "j_after_v",
    "j_target",
    "w_target",
    "budget",
    "required",
    "required_w",
    "alpha",
    "beta",
    "lambda_v",
    "lambda_w",
    "guaranteed_v",
    "guaranteed_w",
    "infeasible",
    "infeasible_v",
    "infeasible_w",
    "below_noise_v",
    "below_noise_w",
    "trajectories",
    "steps",
    "certified_v",
    "certified_w",
];

fn num(x: f64) -> String {
    format!("{x:?}")
}

fn opt(x: Option<f64>) -> String {
    x.map(num).unwrap_or_default()
}

/// One row of `log.csv` for `record` (shortest round-trip decimal; empty for "not
/// applicable"; `-inf` for the deterministic target's `w_target`; booleans as 0/1).
pub fn log_row(r: &Record) -> String {
    let mut cells = vec![r.iteration.to_string()];
    cells.extend(r.v.iter().copied().map(num));
    cells.extend(r.w.iter().copied().map(num));
    cells.extend(r.sigma.iter().copied().map(num));
    cells.extend([num(r.j_exploratory), opt(r.j_after_v), num(r.j_target)]);
    match &r.w_target {
        Some(w) => cells.extend(w.iter().copied().map(num)),
        None => cells.extend(r.w.iter().map(|_| num(f64::NEG_INFINITY))),
    }
    let b = |x: bool| if x { "1".to_owned() } else { "0".to_owned() };
    cells.extend([
        num(r.budget),
        opt(r.required_v),
        opt(r.required_w),
        num(r.alpha),
        num(r.beta),
        opt(r.lambda_v),
        opt(r.lambda_w),
        opt(r.guaranteed_v),
        opt(r.guaranteed_w),
        b(r.infeasible_v || r.infeasible_w),
        b(r.infeasible_v),
        b(r.infeasible_w),
        b(r.below_noise_v),
        b(r.below_noise_w),
        r.trajectories.to_string(),
        r.steps.to_string(),
        r.certified_v.map(b).unwrap_or_default(),
        r.certified_w.map(b).unwrap_or_default(),
    ]);
    let mut s = cells.join(",");
    s.push('\n');
    s
}

/// Counters over the whole run, carried in the checkpoint so that a resumed run reports the
/// same totals.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Tally {
    /// Iterations whose v- or w-requirement was infeasible (λ = 0 fallback).
    pub infeasible: u64,
    /// Iterations whose v-gradient was below its noise level.
    pub below_noise_v: u64,
    /// Iterations whose w-direction was below its noise level.
    pub below_noise_w: u64,
    /// J of the exploratory policy at the last iteration.
    pub last_j_explore: Option<f64>,
    /// J of the target policy at the last iteration.
    pub last_j_target: Option<f64>,
    /// The first iteration whose logged budget (the run's own bookkeeping: the certified
    /// budget or surplus, or the thesis's estimated budget) went below zero.
    #[serde(default)]
    pub self_check: SelfCheck,
}

impl Tally {
    /// Counts the iteration of `r`.
    pub(crate) fn add(&mut self, r: &Record) {
        self.infeasible += u64::from(r.infeasible_v || r.infeasible_w);
        self.below_noise_v += u64::from(r.below_noise_v);
        self.below_noise_w += u64::from(r.below_noise_w);
        self.last_j_explore = Some(r.j_exploratory);
        self.last_j_target = Some(r.j_target);
        self.self_check.observe(r.iteration, r.budget);
    }
}

/// The checkpoint file: the state after `state.iteration` iterations and the length of the
/// log that holds exactly the rows of those iterations.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Checkpoint {
    /// Bytes of the log (header included) written up to this checkpoint.
    pub log_bytes: u64,
    /// Wall time spent in iterations so far, in seconds.
    pub elapsed_s: f64,
    /// Counters so far.
    pub tally: Tally,
    /// The algorithm's state (resumable bit for bit).
    pub state: State,
}

/// Final parameters of a run.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FinalParams {
    /// Mean parameters v.
    pub v: Vec<f64>,
    /// Log standard deviations w.
    pub w: Vec<f64>,
    /// Standard deviations σ = e^w.
    pub sigma: Vec<f64>,
    /// Budget B.
    pub budget: f64,
}

/// `summary.json`: written last, its presence marks a complete run.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Summary {
    /// `"complete"`, or `"stopped"` for a run stopped because its data contradicted its
    /// declared constants (`constants_check` says where; `iterations` counts those done).
    pub status: String,
    /// Label of the run.
    pub name: String,
    /// Version of sepg that ran it.
    pub sepg_version: String,
    /// Iterations run.
    pub iterations: u64,
    /// Parameters after the last iteration.
    #[serde(rename = "final")]
    pub final_params: FinalParams,
    /// v* (LQG only).
    pub v_star: Option<Vec<f64>>,
    /// max_i |v_i − v*_i| after the last iteration (LQG only).
    pub abs_v_error: Option<f64>,
    /// J of the exploratory policy at the last iteration.
    pub last_j_explore: Option<f64>,
    /// J of the target policy at the last iteration.
    pub last_j_target: Option<f64>,
    /// Iterations with an infeasible requirement.
    pub infeasible_iterations: u64,
    /// Iterations without a v-update (gradient below noise).
    pub below_noise_v_iterations: u64,
    /// Iterations without a w-update (direction below noise).
    pub below_noise_w_iterations: u64,
    /// Trajectories used.
    pub trajectories: u64,
    /// Environment steps used.
    pub steps: u64,
    /// Wall time spent iterating, in seconds (summed over resumed segments).
    pub wall_time_s: f64,
    /// Iterations per second of wall time.
    pub iterations_per_s: f64,
    /// Environment steps per second of wall time.
    pub env_steps_per_s: f64,
    /// The SEPG options the run used (defaults for the comparison algorithms, which use only
    /// the constant overrides).
    #[serde(default)]
    pub options: SepgOptions,
    /// The task constants the bounds used, after the overrides.
    #[serde(default)]
    pub constants: UsedConstants,
    /// The action the policy scores were evaluated at (sampled gradients only; absent from
    /// older summaries, which always used the raw action).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scores: Option<ScoresName>,
    /// Whether the SEPG variants took certified safe steps (absent for the comparison
    /// algorithms, and from the summaries of older versions, which always did).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub certified_steps: Option<bool>,
    /// What the run promises about exact J (docs/THEOREMS.md, "Statements over a whole run");
    /// absent from the summaries of older versions, which promised per iteration only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub statement: Option<Statement>,
    /// The run's own certified bookkeeping: whether its budget or surplus went below zero
    /// (absent from the summaries of older versions).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub self_check: Option<SelfCheck>,
    /// The declared constants checked against the sampled data: counts per kind and the
    /// first offending value (absent with exact gradients and from older summaries).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub constants_check: Option<ConstantsCheck>,
}

/// The task constants γ, R, M_φ, |A|, ψ a run's bounds used (after the overrides), their
/// family, and the penalty coefficients c and d at σ⁰ (docs/THEOREMS.md, "Tight constants").
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct UsedConstants {
    /// Discount factor γ.
    pub gamma: f64,
    /// Maximal absolute reward R.
    pub r_max: f64,
    /// Maximal absolute feature M_φ.
    pub m_phi: f64,
    /// Action-space volume |A|.
    pub action_volume: f64,
    /// ψ of Lemma A.1 in d (Theorem 4.3): ψ = 0.52355702… unless overridden (absent from the
    /// summaries of older versions, which always used that value).
    #[serde(default = "sepg_bounds::constants::psi")]
    pub psi: f64,
    /// The family of c and d (absent from the summaries of older versions, which used the
    /// thesis's).
    #[serde(default = "ConstantsName::legacy")]
    pub family: ConstantsName,
    /// The horizon H of the tight constants (the run's horizon); absent for the thesis's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub horizon: Option<u64>,
    /// The reward sign of the tight constants; absent for the thesis's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rewards: Option<RewardsName>,
    /// S_H = Σ_{t<H} (t + 1) γᵗ of the tight constants; absent for the thesis's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub s_h: Option<f64>,
    /// c(σ⁰_j) for each component of σ⁰, `None` where not representable (empty in the
    /// summaries of older versions).
    #[serde(default)]
    pub c_sigma0: Vec<Option<f64>>,
    /// d(σ⁰_j) for each component of σ⁰, `None` where not representable (empty in the
    /// summaries of older versions).
    #[serde(default)]
    pub d_sigma0: Vec<Option<f64>>,
}

impl Default for UsedConstants {
    fn default() -> Self {
        UsedConstants {
            gamma: 0.0,
            r_max: 0.0,
            m_phi: 0.0,
            action_volume: 0.0,
            psi: sepg_bounds::constants::psi(),
            family: ConstantsName::legacy(),
            horizon: None,
            rewards: None,
            s_h: None,
            c_sigma0: Vec::new(),
            d_sigma0: Vec::new(),
        }
    }
}

impl UsedConstants {
    /// The constants of the resolved run `resolved`, with c and d at its σ⁰ (`None` where
    /// one is not representable, σ⁰ extremely small).
    pub fn of(resolved: &Resolved) -> Self {
        let k = resolved.checked.constants();
        let at = |f: fn(&TaskConstants, f64) -> std::result::Result<f64, BoundsError>| {
            resolved
                .checked
                .config()
                .sigma0
                .iter()
                .map(|&s| f(k, s).ok())
                .collect::<Vec<Option<f64>>>()
        };
        let (family, horizon, rewards, s_h) = match k.family() {
            Family::Tight(t) => (
                ConstantsName::Tight,
                match t.horizon() {
                    Horizon::Finite(h) => Some(h),
                    Horizon::Infinite => None,
                },
                Some(match t.rewards() {
                    Rewards::NonPositive => RewardsName::NonPositive,
                    Rewards::TwoSided => RewardsName::TwoSided,
                }),
                Some(k.horizon_weight()),
            ),
            _ => (ConstantsName::Thesis, None, None, None),
        };
        UsedConstants {
            gamma: k.gamma(),
            r_max: k.r_max(),
            m_phi: k.m_phi(),
            action_volume: k.action_volume(),
            psi: k.psi_used(),
            family,
            horizon,
            rewards,
            s_h,
            c_sigma0: at(constants::c),
            d_sigma0: at(constants::d),
        }
    }
}

/// [`Error::Failed`] for the I/O error `e` while doing `what` to `path`.
pub(crate) fn io_fail(what: &str, path: &Path, e: std::io::Error) -> Error {
    Error::failed_from(format!("cannot {what} {}", path.display()), e)
}

/// Checks, without creating anything, that the absent folder `dir` can be created: its
/// nearest existing ancestor is a folder in which a file can be written (probed with a
/// temporary file that is removed at once).
fn check_creatable(dir: &Path) -> Result<()> {
    let mut ancestor = dir.parent();
    while let Some(a) = ancestor {
        let a = if a.as_os_str().is_empty() {
            Path::new(".")
        } else {
            a
        };
        if a.exists() {
            if !a.is_dir() {
                return Err(Error::invalid(format!(
                    "cannot create {}: {} is not a folder",
                    dir.display(),
                    a.display()
                )));
            }
            return tempfile::tempfile_in(a).map(drop).map_err(|e| {
                Error::invalid(format!(
                    "cannot create {}: {} is not writable ({e})",
                    dir.display(),
                    a.display()
                ))
                .with_source(e)
            });
        }
        ancestor = a.parent();
    }
    Ok(())
}

/// Checks that `dir` is absent and can be created, or is an empty folder; with `force`,
/// removes the run files a previous run left there (and only those).
///
/// # Errors
/// [`Error::Invalid`] for a non-empty folder without `force`, a path that is not a folder, or
/// one that cannot be created or written (under a file, in a read-only folder).
pub fn check_out_dir(dir: &Path, force: bool, files: &[&str]) -> Result<()> {
    if !dir.exists() {
        return check_creatable(dir);
    }
    if !dir.is_dir() {
        return Err(Error::invalid(format!(
            "{} exists and is not a folder",
            dir.display()
        )));
    }
    let mut entries = fs::read_dir(dir)
        .map_err(|e| Error::invalid_from(format!("cannot read {}", dir.display()), e))?;
    if entries.next().is_some() && !force {
        return Err(Error::invalid(format!(
            "output folder {} is not empty (use --force to overwrite its run files)",
            dir.display()
        )));
    }
    tempfile::tempfile_in(dir).map(drop).map_err(|e| {
        Error::invalid(format!(
            "output folder {} is not writable ({e})",
            dir.display()
        ))
        .with_source(e)
    })?;
    for f in files {
        let p = dir.join(f);
        if p.is_dir() {
            fs::remove_dir_all(&p).map_err(|e| io_fail("remove", &p, e))?;
        } else if p.exists() {
            fs::remove_file(&p).map_err(|e| io_fail("remove", &p, e))?;
        }
    }
    Ok(())
}

/// Whether `dir` holds a complete run.
pub fn is_complete(dir: &Path) -> bool {
    dir.join(SUMMARY_FILE).is_file()
}

/// Reads and resolves the configuration of the run folder `dir`. A `config.toml` without
/// the `constants` key was written before the family could be chosen and resolves with the
/// thesis's constants, which it ran with.
///
/// # Errors
/// [`Error::Invalid`] for a missing or invalid configuration or one written by another sepg version.
pub fn load_resolved(dir: &Path) -> Result<Resolved> {
    let path = dir.join(CONFIG_FILE);
    if !path.is_file() {
        return Err(Error::invalid(format!(
            "{} is not a run folder (no {CONFIG_FILE})",
            dir.display()
        )));
    }
    let mut spec = RunSpec::from_file(&path)?;
    // A configuration written before the constants could be chosen ran with the thesis's.
    spec.constants.get_or_insert(ConstantsName::legacy());
    if let Some(v) = &spec.sepg_version
        && v != VERSION
    {
        return Err(Error::invalid(format!(
            "{} was written by sepg {v}; this is sepg {VERSION}, which may not reproduce it bit for bit",
            path.display()
        )));
    }
    spec.resolve()
}

/// Reads `summary.json` of a complete run.
///
/// # Errors
/// [`Error::Failed`] when the file cannot be read or parsed.
pub fn read_summary(dir: &Path) -> Result<Summary> {
    let p = dir.join(SUMMARY_FILE);
    let text = fs::read_to_string(&p).map_err(|e| io_fail("read", &p, e))?;
    serde_json::from_str(&text)
        .map_err(|e| Error::failed_from(format!("{} is invalid", p.display()), e))
}

/// A log read back from disk: column names and one row of numbers per logged iteration
/// (empty cells read as NaN).
#[derive(Debug, Clone, PartialEq)]
pub struct Log {
    /// Column names.
    pub columns: Vec<String>,
    /// Rows of values.
    pub rows: Vec<Vec<f64>>,
}

impl Log {
    /// Reads `log.csv` of a complete run, or the checkpointed prefix of `log.partial.csv`.
    ///
    /// # Errors
    /// [`Error::Invalid`] when no log can be read.
    pub fn read_run(dir: &Path) -> Result<Log> {
        let done = dir.join(LOG_FILE);
        let bytes = if done.is_file() {
            fs::read(&done)
                .map_err(|e| Error::invalid_from(format!("cannot read {}", done.display()), e))?
        } else {
            let partial = dir.join(PARTIAL_LOG_FILE);
            let mut b = fs::read(&partial)
                .map_err(|e| Error::invalid_from(format!("no log in {}", dir.display()), e))?;
            let ck: Option<Checkpoint> = fs::read_to_string(dir.join(CHECKPOINT_FILE))
                .ok()
                .and_then(|t| serde_json::from_str(&t).ok());
            if let Some(ck) = ck {
                b.truncate(
                    usize::try_from(ck.log_bytes)
                        .unwrap_or(usize::MAX)
                        .min(b.len()),
                );
            }
            b
        };
        let text = String::from_utf8_lossy(&bytes);
        let mut lines = text.lines();
        let columns: Vec<String> = lines
            .next()
            .ok_or_else(|| Error::invalid(format!("empty log in {}", dir.display())))?
            .split(',')
            .map(String::from)
            .collect();
        let rows = lines
            .filter(|l| l.split(',').count() == columns.len())
            .map(|l| {
                l.split(',')
                    .map(|c| c.parse::<f64>().unwrap_or(f64::NAN))
                    .collect()
            })
            .collect();
        Ok(Log { columns, rows })
    }

    /// The values of column `name` (or its first component `name_0`), if present.
    pub fn column(&self, name: &str) -> Option<Vec<f64>> {
        let idx = self
            .columns
            .iter()
            .position(|c| c == name)
            .or_else(|| self.columns.iter().position(|c| *c == format!("{name}_0")))?;
        Some(self.rows.iter().map(|r| r[idx]).collect())
    }
}

#[cfg(test)]
mod tests {
    use sepg_algo::core::executor::Solver;
    use sepg_algo::solver::PolicySolver;

    use super::*;

    #[test]
    fn header_and_rows_have_the_same_width() {
        let resolved = RunSpec {
            iterations: Some(2),
            batch: Some(12),
            ..RunSpec::default()
        }
        .resolve()
        .expect("valid");
        let mut solver = PolicySolver::new(&resolved.checked).expect("solver");
        let mut state = resolved.checked.initial_state();
        let r = solver.next_iter(&mut state).expect("iteration");
        let header = log_header(1, 1);
        assert_eq!(header.split(',').count(), log_row(&r).split(',').count());
        assert!(header.starts_with("iteration,v,w,sigma,j_explore,"));
    }
}
