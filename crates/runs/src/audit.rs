//! Audit: re-checks the log of a run folder against the run's safety requirement, check by
//! check, and says whether the guarantees the run claims held.
//!
//! For iteration t (row t of `log.csv`, parameters θᵗ = (vᵗ, wᵗ), the update producing
//! θᵗ⁺¹ from the next row or the final parameters) the audit evaluates:
//!
//! ```text
//! guarantee-v   J(vᵗ⁺¹, wᵗ) − J(vᵗ, wᵗ)       ≥ guaranteed_v    (Theorems 4.2 / 4.7)
//! guarantee-w   J(vᵗ⁺¹, wᵗ⁺¹) − J(vᵗ⁺¹, wᵗ)   ≥ guaranteed_w    (Theorems 4.3 / 4.5 / 4.8 / 4.9)
//!               SIM-ν: J(vᵗ, wᵗ⁺¹) − J(vᵗ, wᵗ) ≥ guaranteed_w   (both steps taken at θᵗ)
//! mi            J(θᵗ⁺¹) ≥ J(θᵗ)                                  (MI, Table 4.1)
//! lb-i          J(θᵗ⁺¹) ≥ J(θ⁰)                                  (LB-I, Table 4.1)
//! budget-exact  B⁰ + ΔJ_E + ΔJ_T ≥ 0 recomputed from exact J       (type II, Definition 4.3)
//! budget        recorded Bᵗ ≥ 0                                   (type II, Theorem 4.1)
//! ```
//!
//! # What counts as a violation
//! J is recomputed exactly for the logged parameters when the environment has an oracle
//! (`ClippedDpOracle` for the clipped LQG presets, `ClosedFormOracle` for unclipped ones). A
//! check fails at an iteration when its shortfall `required − actual` exceeds
//! `tolerance · max(1, |Jᵗ|)` (rounding). How the failures of a check are judged depends on
//! what the run claims ([`Kind`]):
//!
//! - [`Kind::Exact`]: exact gradients and exact J. The guarantees are deterministic; a single
//!   failure is a violation.
//! - [`Kind::HighProbability`]: sampled gradients, exact J. Theorems 4.7–4.9 promise each
//!   step's guaranteed improvement with probability at least 1 − δ, given the past, so the
//!   number of failing iterations is at most Binomial(n, p) with p = δ for one step and
//!   p = 1 − (1 − δ)² for a check that relies on both steps of an iteration (`mi`, `lb-i`,
//!   `budget-exact`). The check is violated only when the exact one-sided binomial test
//!   rejects p at level α / (number of such checks) (Bonferroni): P(X ≥ failed) < α/K.
//! - [`Kind::Bookkeeping`]: a check of the algorithm's own bookkeeping (the recorded budget,
//!   computed from estimated J in a sampled run), or any check when no oracle exists. Its failures are notes:
//!   they cannot establish that the exact requirement broke.
//!
//! Every check is listed in the report with its count of checked and failed iterations and
//! its worst shortfall (negative when it always held: the smallest margin), passing checks
//! included.
//!
//! # Malformed input
//! The log must be complete and well-formed: the header of the run's dimensions, every cell a
//! finite number (or empty where a value does not apply, `-inf` for a deterministic target),
//! counters as non-negative integers, one row for each iteration the configuration's
//! `log-every` logs, and — for a finished log — a `summary.json` matching it. Anything else is
//! [`Error::Invalid`]. An interrupted run (checkpointed `log.partial.csv`) is audited up to its
//! checkpoint and reported as incomplete.

use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use std::fs;
use std::path::Path;

use sepg_algo::core::config::{Algorithm, GradientMode, Requirement, SepgConfig};
use sepg_estimators::binomial::upper_tail;
use sepg_mdp::env::AnyEnv;
use sepg_mdp::oracle::{ClippedDpOracle, ClosedFormOracle, ExactOracle, Exploration, Horizon};
use serde::Serialize;

use crate::error::{Error, Result};
use crate::folder::{
    CHECKPOINT_FILE, Checkpoint, LOG_FILE, PARTIAL_LOG_FILE, SUMMARY_FILE, Summary, load_resolved,
    log_header,
};
use crate::spec::{AlgoName, RunSpec};

/// Family-wise significance level of the binomial tests of a sampled run, unless the caller
/// asks for another one.
pub const DEFAULT_ALPHA: f64 = 0.01;

/// How the failures of a check are judged (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum Kind {
    /// Deterministic guarantee against exact J: any failure is a violation.
    Exact,
    /// Per-iteration guarantee with probability 1 − δ against exact J: binomial test.
    HighProbability,
    /// The algorithm's own bookkeeping (from estimated J in a sampled run), or any check
    /// without exact J: failures are notes.
    Bookkeeping,
}

impl Kind {
    fn label(self) -> &'static str {
        match self {
            Kind::Exact => "exact",
            Kind::HighProbability => "high-prob",
            Kind::Bookkeeping => "bookkeeping",
        }
    }
}

/// The verdict on one check.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum Verdict {
    /// No failure (exact), or a failure count the allowed rate explains (high probability).
    Holds,
    /// A failure of a deterministic guarantee, or a failure count the binomial test rejects.
    Violated,
    /// Failures of an estimated check: reported, not judged.
    Note,
}

impl Verdict {
    fn label(self) -> &'static str {
        match self {
            Verdict::Holds => "holds",
            Verdict::Violated => "VIOLATED",
            Verdict::Note => "note",
        }
    }
}

/// The summary of one check over the whole log.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CheckSummary {
    /// Name of the check (`guarantee-v`, `guarantee-w`, `mi`, `lb-i`, `budget-exact`, `budget`).
    pub check: &'static str,
    /// How its failures are judged.
    pub kind: Kind,
    /// Iterations at which it was evaluated.
    pub checked: u64,
    /// Iterations at which it failed.
    pub failed: u64,
    /// Largest `required − actual` over the checked iterations (negative: the smallest margin
    /// by which it held).
    pub worst_shortfall: f64,
    /// Iteration of the worst shortfall.
    pub worst_iteration: u64,
    /// High probability only: the per-iteration failure probability the guarantee allows.
    pub allowed_rate: Option<f64>,
    /// High probability only: P(X ≥ failed) for X ~ Binomial(checked, allowed_rate).
    pub p_value: Option<f64>,
    /// The verdict.
    pub verdict: Verdict,
}

/// One iteration at which a check failed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Violation {
    /// Iteration t whose update broke the check.
    pub iteration: u64,
    /// Which check.
    pub check: &'static str,
    /// The value the requirement asks for (a guaranteed improvement, J(θᵗ), J(θ⁰) or 0).
    pub required: f64,
    /// The value the run achieved.
    pub actual: f64,
    /// How far below the requirement: `required − actual` (> 0).
    pub shortfall: f64,
}

/// The overall outcome of an audit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum Status {
    /// Every exact and high-probability check holds on a complete run.
    Holds,
    /// At least one check is violated.
    Violated,
    /// No check is violated, but the run is unfinished: its guarantees cannot be certified.
    Incomplete,
}

/// The audit of one run folder.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AuditReport {
    /// The run folder.
    pub dir: String,
    /// Algorithm and requirement, as in the configuration.
    pub algorithm: String,
    /// `exact`, or `sampled (δ = …)`.
    pub gradients: String,
    /// Where J comes from: `exact (…)` or `log (no exact oracle)`.
    pub source: String,
    /// Family-wise level of the binomial tests (sampled runs).
    pub alpha: f64,
    /// Iterations the run has completed (all of them unless interrupted).
    pub iterations_done: u64,
    /// Iterations of the whole run.
    pub iterations_total: u64,
    /// Rows of the log audited.
    pub rows: usize,
    /// Rows whose checks were skipped because θᵗ⁺¹ is not logged (`log-every` > 1).
    pub skipped: usize,
    /// One summary per check, in a fixed order, passing checks included.
    pub checks: Vec<CheckSummary>,
    /// Every failing iteration of every check (see each check's kind and verdict).
    pub failures: Vec<Violation>,
    /// The outcome.
    pub status: Status,
}

impl AuditReport {
    /// The summary of check `name`, if it was evaluated.
    pub fn check(&self, name: &str) -> Option<&CheckSummary> {
        self.checks.iter().find(|c| c.check == name)
    }

    /// The failures of the checks whose verdict is [`Verdict::Violated`], by iteration.
    pub fn violations(&self) -> Vec<&Violation> {
        self.failures
            .iter()
            .filter(|f| {
                self.check(f.check)
                    .is_some_and(|c| c.verdict == Verdict::Violated)
            })
            .collect()
    }

    /// Distinct iterations with a failure of a violated check, in order.
    pub fn broken_iterations(&self) -> Vec<u64> {
        let mut its: Vec<u64> = self.violations().iter().map(|v| v.iteration).collect();
        its.dedup();
        its
    }
}

/// One parsed row of `log.csv`.
#[derive(Debug, Clone)]
struct Row {
    iteration: u64,
    v: Vec<f64>,
    w: Vec<f64>,
    j_explore: f64,
    j_after_v: Option<f64>,
    j_target: f64,
    w_target: Vec<f64>,
    budget: f64,
    alpha: f64,
    beta: f64,
    guaranteed_v: Option<f64>,
    guaranteed_w: Option<f64>,
}

fn bad(dir: &Path, what: impl std::fmt::Display) -> Error {
    Error::invalid(format!("{}: {what}", dir.display()))
}

/// Columns holding counters (non-negative integers).
const INTEGER_COLUMNS: [&str; 8] = [
    "iteration",
    "infeasible",
    "infeasible_v",
    "infeasible_w",
    "below_noise_v",
    "below_noise_w",
    "trajectories",
    "steps",
];

/// Columns that are empty when they do not apply to the algorithm or the iteration.
const OPTIONAL_COLUMNS: [&str; 9] = [
    "certified_v",
    "certified_w",
    "j_after_v",
    "required",
    "required_w",
    "lambda_v",
    "lambda_w",
    "guaranteed_v",
    "guaranteed_w",
];

/// How the cells of a column are validated.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Cell {
    /// A non-negative integer.
    Integer,
    /// A finite number, or empty.
    Optional,
    /// A finite number, or `-inf` (the deterministic target's log standard deviation).
    WTarget,
    /// A finite number.
    Number,
}

fn cell_kind(name: &str) -> Cell {
    if INTEGER_COLUMNS.contains(&name) {
        Cell::Integer
    } else if OPTIONAL_COLUMNS.contains(&name) {
        Cell::Optional
    } else if name == "w_target" || name.starts_with("w_target_") {
        Cell::WTarget
    } else {
        Cell::Number
    }
}

/// The configuration, the completed iterations and the parameters after the last one.
struct Progress {
    /// Iterations completed (= the configured total for a finished run).
    done: u64,
    /// Whether the run finished (`log.csv` and a matching `summary.json`).
    complete: bool,
    /// θ after `done` iterations.
    last: Params,
}

/// Parameters θᵗ = (vᵗ, wᵗ).
struct Params {
    v: Vec<f64>,
    w: Vec<f64>,
}

fn read_checkpoint(dir: &Path) -> Result<Option<Checkpoint>> {
    let path = dir.join(CHECKPOINT_FILE);
    if !path.is_file() {
        return Ok(None);
    }
    let text = fs::read_to_string(&path)
        .map_err(|e| bad(dir, format!("cannot read {CHECKPOINT_FILE}: {e}")))?;
    serde_json::from_str(&text)
        .map(Some)
        .map_err(|e| bad(dir, format!("{CHECKPOINT_FILE} is malformed: {e}")))
}

/// The bytes of the log and the run's progress: `log.csv` with its `summary.json`, or the
/// checkpointed prefix of `log.partial.csv`.
fn log_bytes(dir: &Path, total: u64, dims: (usize, usize)) -> Result<(Vec<u8>, Progress)> {
    let finite = |xs: &[f64]| xs.iter().all(|x| x.is_finite());
    let done = dir.join(LOG_FILE);
    if done.is_file() {
        let bytes =
            fs::read(&done).map_err(|e| bad(dir, format!("cannot read {LOG_FILE}: {e}")))?;
        let path = dir.join(SUMMARY_FILE);
        if !path.is_file() {
            return Err(bad(
                dir,
                format!(
                    "{LOG_FILE} without {SUMMARY_FILE}: the run did not finish writing its folder \
                     (sepg run --resume {} completes it)",
                    dir.display()
                ),
            ));
        }
        let text = fs::read_to_string(&path)
            .map_err(|e| bad(dir, format!("cannot read {SUMMARY_FILE}: {e}")))?;
        let s: Summary = serde_json::from_str(&text)
            .map_err(|e| bad(dir, format!("{SUMMARY_FILE} is malformed: {e}")))?;
        if s.iterations != total {
            return Err(bad(
                dir,
                format!(
                    "{SUMMARY_FILE} reports {} iterations, the configuration {total}",
                    s.iterations
                ),
            ));
        }
        let (v, w) = (s.final_params.v, s.final_params.w);
        if v.len() != dims.0 || w.len() != dims.1 || !finite(&v) || !finite(&w) {
            return Err(bad(
                dir,
                format!("{SUMMARY_FILE}: the final parameters do not fit the run"),
            ));
        }
        let progress = Progress {
            done: total,
            complete: true,
            last: Params { v, w },
        };
        return Ok((bytes, progress));
    }
    let mut bytes = fs::read(dir.join(PARTIAL_LOG_FILE)).map_err(|e| {
        bad(
            dir,
            format!("no {LOG_FILE} and no readable {PARTIAL_LOG_FILE}: {e}"),
        )
    })?;
    let ck = read_checkpoint(dir)?.ok_or_else(|| {
        bad(
            dir,
            format!("{PARTIAL_LOG_FILE} without a valid {CHECKPOINT_FILE}"),
        )
    })?;
    let valid = usize::try_from(ck.log_bytes).unwrap_or(usize::MAX);
    if valid > bytes.len() {
        return Err(bad(
            dir,
            format!("{PARTIAL_LOG_FILE} is shorter than its checkpoint says"),
        ));
    }
    bytes.truncate(valid);
    let s = ck.state;
    if s.iteration > total
        || s.v.len() != dims.0
        || s.w.len() != dims.1
        || !finite(&s.v)
        || !finite(&s.w)
    {
        return Err(bad(
            dir,
            format!("{CHECKPOINT_FILE} does not fit the run's configuration"),
        ));
    }
    let progress = Progress {
        done: s.iteration,
        complete: false,
        last: Params { v: s.v, w: s.w },
    };
    Ok((bytes, progress))
}

/// Positions of the columns the audit reads, in a header of this run's dimensions.
struct Columns<'h> {
    names: Vec<&'h str>,
    kinds: Vec<Cell>,
    v: Vec<usize>,
    w: Vec<usize>,
    w_target: Vec<usize>,
    /// j_explore, j_after_v, j_target, budget, alpha, beta, guaranteed_v, guaranteed_w.
    scalars: [usize; 8],
}

impl<'h> Columns<'h> {
    fn new(dir: &Path, header: &'h str, dims: (usize, usize)) -> Result<Columns<'h>> {
        let names: Vec<&str> = header.split(',').collect();
        let col = |name: &str| names.iter().position(|c| *c == name);
        let cols = |name: &str, dim: usize| -> Vec<usize> {
            if dim == 1 {
                col(name).into_iter().collect()
            } else {
                (0..dim)
                    .filter_map(|i| col(&format!("{name}_{i}")))
                    .collect()
            }
        };
        let named = |name: &str| col(name).ok_or_else(|| bad(dir, format!("no column {name}")));
        let scalars = [
            "j_explore",
            "j_after_v",
            "j_target",
            "budget",
            "alpha",
            "beta",
            "guaranteed_v",
            "guaranteed_w",
        ]
        .map(named);
        let [a, b, c, d, e, f, g, h] = scalars;
        Ok(Columns {
            v: cols("v", dims.0),
            w: cols("w", dims.1),
            w_target: cols("w_target", dims.1),
            scalars: [a?, b?, c?, d?, e?, f?, g?, h?],
            kinds: names.iter().map(|n| cell_kind(n)).collect(),
            names,
        })
    }

    /// Parses line `line_no` of the log (1 is the header): every cell is validated by the
    /// kind of its column.
    fn row(&self, dir: &Path, line_no: usize, line: &str) -> Result<Row> {
        let cells: Vec<&str> = line.split(',').collect();
        if cells.len() != self.names.len() {
            return Err(bad(
                dir,
                format!(
                    "log line {line_no} has {} cells, the header {}",
                    cells.len(),
                    self.names.len()
                ),
            ));
        }
        let mut values = Vec::with_capacity(cells.len());
        for ((c, name), kind) in cells.iter().zip(&self.names).zip(&self.kinds) {
            let at = || format!("log line {line_no}, column {name}");
            let value = match kind {
                Cell::Integer => Some(c.parse::<u64>().map_err(|_| {
                    bad(
                        dir,
                        format!("{}: {c:?} is not a non-negative integer", at()),
                    )
                })? as f64),
                _ if c.is_empty() => {
                    if *kind != Cell::Optional {
                        return Err(bad(dir, format!("{} is empty", at())));
                    }
                    None
                }
                _ => {
                    let x = c
                        .parse::<f64>()
                        .map_err(|_| bad(dir, format!("{}: {c:?} is not a number", at())))?;
                    let allowed =
                        x.is_finite() || (*kind == Cell::WTarget && x == f64::NEG_INFINITY);
                    if !allowed {
                        return Err(bad(dir, format!("{}: {c} is not a finite number", at())));
                    }
                    Some(x)
                }
            };
            values.push(value);
        }
        let iteration: u64 = cells[0].parse().unwrap_or_default();
        let req = |i: usize| values[i].unwrap_or_default();
        let many = |idx: &[usize]| idx.iter().map(|&i| req(i)).collect::<Vec<_>>();
        let [ije, ija, ijt, ib, ia, ibt, igv, igw] = self.scalars;
        Ok(Row {
            iteration,
            v: many(&self.v),
            w: many(&self.w),
            j_explore: req(ije),
            j_after_v: values[ija],
            j_target: req(ijt),
            w_target: many(&self.w_target),
            budget: req(ib),
            alpha: req(ia),
            beta: req(ibt),
            guaranteed_v: values[igv],
            guaranteed_w: values[igw],
        })
    }
}

/// Whether the run logs the row of iteration `t` (`log-every` k: every k-th and the last).
fn logged(t: u64, every: u64, total: u64) -> bool {
    t.is_multiple_of(every) || t + 1 == total
}

/// Parses the log strictly: the header of this run's dimensions, rows of the same width and
/// validated cells, and exactly the rows of the first `done` iterations that `log-every`
/// logs, in order.
fn parse_log(
    dir: &Path,
    bytes: &[u8],
    dims: (usize, usize),
    (done, every, total): (u64, u64, u64),
) -> Result<Vec<Row>> {
    let text = std::str::from_utf8(bytes).map_err(|_| bad(dir, "the log is not UTF-8"))?;
    let mut lines = text.split_terminator('\n');
    let header = log_header(dims.0, dims.1);
    if lines.next() != Some(header.trim_end()) {
        return Err(bad(
            dir,
            "the log header does not match the run's configuration",
        ));
    }
    let columns = Columns::new(dir, header.trim_end(), dims)?;
    let mut expected = (0..done).filter(|&t| logged(t, every, total));
    let mut rows: Vec<Row> = Vec::new();
    for (n, line) in lines.enumerate() {
        let line_no = n + 2;
        let row = columns.row(dir, line_no, line)?;
        match expected.next() {
            Some(t) if t == row.iteration => rows.push(row),
            Some(t) => {
                return Err(bad(
                    dir,
                    format!(
                        "log line {line_no} is iteration {}, expected {t}: rows are missing or out of order",
                        row.iteration
                    ),
                ));
            }
            None => {
                return Err(bad(
                    dir,
                    format!(
                        "log line {line_no} (iteration {}) is beyond the {done} iterations the run completed",
                        row.iteration
                    ),
                ));
            }
        }
    }
    if let Some(t) = expected.next() {
        return Err(bad(
            dir,
            format!("the log ends before the row of iteration {t} (rows are missing)"),
        ));
    }
    Ok(rows)
}

/// Exact J of the run's environment, memoised on the parameters' bits.
struct ExactJ {
    oracle: Box<dyn ExactOracle>,
    horizon: Horizon,
    cache: HashMap<Vec<u64>, f64>,
}

impl ExactJ {
    /// `w` all −∞ is the deterministic policy.
    fn j(&mut self, v: &[f64], w: &[f64]) -> Result<f64> {
        let key: Vec<u64> = v.iter().chain(w).map(|x| x.to_bits()).collect();
        if let Some(j) = self.cache.get(&key) {
            return Ok(*j);
        }
        let exploration = if w.iter().all(|x| *x == f64::NEG_INFINITY) {
            Exploration::Deterministic
        } else {
            Exploration::Gaussian { w: w.to_vec() }
        };
        let j = self
            .oracle
            .evaluate(v, &exploration, self.horizon)
            .map_err(|e| Error::failed(format!("exact J at v = {v:?}, w = {w:?}: {e}")))?
            .j;
        if !j.is_finite() {
            return Err(Error::failed(format!(
                "exact J at v = {v:?}, w = {w:?} is not finite"
            )));
        }
        self.cache.insert(key, j);
        Ok(j)
    }
}

/// The algorithm of `spec` under its configuration name (`sepg-zv`), with the requirement of
/// `sepg-naive-w` (`sepg-naive-w, requirement zv`).
fn algorithm_name(spec: &RunSpec) -> String {
    let algo = spec.algo.map_or("unknown", AlgoName::name);
    let requirement = spec
        .requirement
        .and_then(|r| serde_json::to_value(r).ok())
        .and_then(|v| v.as_str().map(str::to_owned));
    match requirement {
        Some(r) => format!("{algo}, requirement {r}"),
        None => algo.to_owned(),
    }
}

/// J values of the audit: exact when an oracle exists, else the logged estimates.
enum Source {
    Exact(ExactJ),
    Logged,
}

/// Runs the audit of `dir` (no printing) with the family-wise level `alpha` for the binomial
/// tests of a sampled run ([`DEFAULT_ALPHA`] is the command line's default).
///
/// # Errors
/// [`Error::Invalid`] for a folder that is not a readable run, a malformed or incomplete log
/// (see the module documentation) or a tolerance or level out of range; [`Error::Failed`]
/// when the oracle cannot evaluate a logged policy.
pub fn audit(dir: &Path, tolerance: f64, alpha: f64) -> Result<AuditReport> {
    if !(tolerance.is_finite() && tolerance >= 0.0) {
        return Err(Error::invalid(format!(
            "--tolerance {tolerance} must be finite and >= 0"
        )));
    }
    if !(alpha > 0.0 && alpha < 1.0) {
        return Err(Error::invalid(format!("--alpha {alpha} must be in (0, 1)")));
    }
    if !dir.is_dir() {
        return Err(Error::invalid(format!("{} is not a folder", dir.display())));
    }
    let resolved = load_resolved(dir)?;
    let config = resolved.checked.config();
    let total = resolved.iterations();
    let (bytes, progress) = log_bytes(dir, total, resolved.dims)?;
    let rows = parse_log(
        dir,
        &bytes,
        resolved.dims,
        (progress.done, resolved.log_every(), total),
    )?;
    let (source, source_name) = source(config)?;
    let requirement = match config.algorithm {
        Algorithm::Sepg(r) | Algorithm::SepgNaiveW(r) => Some(r),
        _ => None,
    };
    let exact = matches!(source, Source::Exact(_));
    let (gradients, delta) = match config.gradient {
        GradientMode::Exact => ("exact".to_owned(), None),
        GradientMode::Sampled { delta } => (format!("sampled (δ = {delta})"), Some(delta)),
    };
    let mut auditor = Auditor {
        source,
        requirement,
        sim: matches!(requirement, Some(Requirement::Sim { .. })),
        has_target: matches!(
            requirement,
            Some(Requirement::Lv | Requirement::Zv | Requirement::Sim { .. })
        ),
        budget0: config.initial_budget,
        tolerance,
        first: None,
        tallies: BTreeMap::new(),
        failures: Vec::new(),
        skipped: 0,
    };
    for (k, row) in rows.iter().enumerate() {
        let t = row.iteration;
        let next = match rows.get(k + 1) {
            Some(n) if n.iteration == t + 1 => Some((n.v.clone(), n.w.clone(), Some(n.j_explore))),
            Some(_) => None,
            None => (t + 1 == progress.done)
                .then(|| (progress.last.v.clone(), progress.last.w.clone(), None)),
        };
        auditor.row(row, next)?;
    }
    let checks = judge(&auditor.tallies, exact, delta, alpha)?;
    let violated = checks.iter().any(|c| c.verdict == Verdict::Violated);
    let status = if violated {
        Status::Violated
    } else if progress.complete {
        Status::Holds
    } else {
        Status::Incomplete
    };
    Ok(AuditReport {
        dir: dir.display().to_string(),
        algorithm: algorithm_name(&resolved.spec),
        gradients,
        source: source_name,
        alpha,
        iterations_done: progress.done,
        iterations_total: total,
        rows: rows.len(),
        skipped: auditor.skipped,
        checks,
        failures: auditor.failures,
        status,
    })
}

/// Order in which checks are reported.
const CHECK_ORDER: [&str; 6] = [
    "guarantee-v",
    "guarantee-w",
    "mi",
    "lb-i",
    "budget-exact",
    "budget",
];

/// The kind, allowed rate, p-value and verdict of every evaluated check.
fn judge(
    tallies: &BTreeMap<&'static str, Tally>,
    exact: bool,
    delta: Option<f64>,
    alpha: f64,
) -> Result<Vec<CheckSummary>> {
    let kind_of = |name: &str| match (name, exact, delta) {
        ("budget", _, _) | (_, false, _) => Kind::Bookkeeping,
        (_, true, None) => Kind::Exact,
        (_, true, Some(_)) => Kind::HighProbability,
    };
    let tested = tallies
        .keys()
        .filter(|n| kind_of(n) == Kind::HighProbability)
        .count()
        .max(1);
    let mut out = Vec::new();
    for name in CHECK_ORDER {
        let Some(t) = tallies.get(name) else {
            continue;
        };
        let kind = kind_of(name);
        let (allowed_rate, p_value, verdict) = match kind {
            Kind::Exact => {
                let v = if t.failed == 0 {
                    Verdict::Holds
                } else {
                    Verdict::Violated
                };
                (None, None, v)
            }
            Kind::Bookkeeping => (None, None, Verdict::Note),
            Kind::HighProbability => {
                let d = delta.unwrap_or(1.0);
                let allowed = if name.starts_with("guarantee-") {
                    d
                } else {
                    1.0 - (1.0 - d) * (1.0 - d)
                };
                let p = upper_tail(t.failed, t.checked, allowed)
                    .map_err(|e| Error::failed(format!("binomial test of {name}: {e}")))?;
                let v = if p < alpha / tested as f64 {
                    Verdict::Violated
                } else {
                    Verdict::Holds
                };
                (Some(allowed), Some(p), v)
            }
        };
        out.push(CheckSummary {
            check: name,
            kind,
            checked: t.checked,
            failed: t.failed,
            worst_shortfall: t.worst.0,
            worst_iteration: t.worst.1,
            allowed_rate,
            p_value,
            verdict,
        });
    }
    Ok(out)
}

/// Counts of one check while walking the log.
#[derive(Debug, Clone, Copy)]
struct Tally {
    checked: u64,
    failed: u64,
    /// Largest shortfall and its iteration.
    worst: (f64, u64),
}

/// Where J comes from for the environment of `config`, and its label.
fn source(config: &SepgConfig) -> Result<(Source, String)> {
    let AnyEnv::Lqg(env) = &config.env else {
        return Ok((Source::Logged, "log (no exact oracle)".to_owned()));
    };
    let model = env.model();
    let (oracle, name): (Box<dyn ExactOracle>, _) = if model.clipping {
        let o = ClippedDpOracle::new(model).map_err(|e| Error::failed(e.to_string()))?;
        (Box::new(o), "ClippedDpOracle")
    } else {
        let o = ClosedFormOracle::new(model).map_err(|e| Error::failed(e.to_string()))?;
        (Box::new(o), "ClosedFormOracle")
    };
    let label = format!("exact ({name}, H = {})", config.horizon);
    let exact = ExactJ {
        oracle,
        horizon: Horizon::Finite(config.horizon),
        cache: HashMap::new(),
    };
    Ok((Source::Exact(exact), label))
}

/// The next parameters θᵗ⁺¹ = (v, w) of a row, with their logged J if the log has it.
type Next = (Vec<f64>, Vec<f64>, Option<f64>);

/// The state of an audit as it walks through the rows of the log.
struct Auditor {
    source: Source,
    requirement: Option<Requirement>,
    sim: bool,
    has_target: bool,
    budget0: f64,
    tolerance: f64,
    /// J of the exploratory and of the target policy at the first row.
    first: Option<(f64, f64)>,
    tallies: BTreeMap<&'static str, Tally>,
    failures: Vec<Violation>,
    skipped: usize,
}

impl Auditor {
    /// J at (v, w): exact when an oracle exists, else `logged`.
    fn j_of(&mut self, v: &[f64], w: &[f64], logged: Option<f64>) -> Result<Option<f64>> {
        match &mut self.source {
            Source::Exact(e) => e.j(v, w).map(Some),
            Source::Logged => Ok(logged),
        }
    }

    /// Counts one evaluation of check `name` at iteration `t`, and records a failure when
    /// `actual` falls short of `required` by more than the tolerance relative to `j_t`.
    fn check(&mut self, t: u64, j_t: f64, name: &'static str, required: f64, actual: f64) {
        let shortfall = required - actual;
        let tally = self.tallies.entry(name).or_insert(Tally {
            checked: 0,
            failed: 0,
            worst: (f64::NEG_INFINITY, t),
        });
        tally.checked += 1;
        if shortfall > tally.worst.0 {
            tally.worst = (shortfall, t);
        }
        if shortfall > self.tolerance * j_t.abs().max(1.0) {
            tally.failed += 1;
            self.failures.push(Violation {
                iteration: t,
                check: name,
                required,
                actual,
                shortfall,
            });
        }
    }

    /// Every check of one row, whose update leads to `next` (`None`: not in the log).
    fn row(&mut self, row: &Row, next: Option<Next>) -> Result<()> {
        let t = row.iteration;
        let exact = matches!(self.source, Source::Exact(_));
        let j_t = self
            .j_of(&row.v, &row.w, Some(row.j_explore))?
            .unwrap_or(row.j_explore);
        let j_target = if self.has_target {
            self.j_of(&row.v, &row.w_target, Some(row.j_target))?
                .unwrap_or(row.j_target)
        } else {
            j_t
        };
        let (j0, jt0) = *self.first.get_or_insert((j_t, j_target));
        let type_two = self.requirement.is_some_and(|r| r.is_type_two());
        if type_two {
            self.check(t, j_t, "budget", 0.0, row.budget);
        }
        let Some((v_next, w_next, j_next_logged)) = next else {
            self.skipped += 1;
            return Ok(());
        };
        let j_mid = self.j_of(&v_next, &row.w, row.j_after_v)?;
        let j_next = self.j_of(&v_next, &w_next, j_next_logged)?;
        if let (Some(g), Some(j_mid)) = (row.guaranteed_v, j_mid)
            && row.alpha != 0.0
        {
            self.check(t, j_t, "guarantee-v", g, j_mid - j_t);
        }
        if let Some(g) = row.guaranteed_w.filter(|_| row.beta != 0.0) {
            let actual = if self.sim {
                self.j_of(&row.v, &w_next, None)?.map(|j| j - j_t)
            } else {
                j_mid.zip(j_next).map(|(m, n)| n - m)
            };
            if let Some(actual) = actual {
                self.check(t, j_t, "guarantee-w", g, actual);
            }
        }
        match self.requirement {
            Some(Requirement::Mi) => {
                if let Some(j_next) = j_next {
                    self.check(t, j_t, "mi", j_t, j_next);
                }
            }
            Some(Requirement::LbI { .. }) => {
                if let Some(j_next) = j_next {
                    self.check(t, j_t, "lb-i", j0, j_next);
                }
            }
            Some(_) => {
                let explore = if self.sim { Some(j_t) } else { j_mid };
                if let Some(explore) = explore.filter(|_| exact) {
                    let target = if self.has_target { j_target - jt0 } else { 0.0 };
                    let recomputed = self.budget0 + explore - j0 + target;
                    self.check(t, j_t, "budget-exact", 0.0, recomputed);
                }
            }
            None => {}
        }
        Ok(())
    }
}

fn fmt(x: f64) -> String {
    format!("{x:.6e}")
}

/// Rows of failures the table lists per violated check; `--json` carries all of them.
const LISTED: usize = 20;

/// The human-readable report: the header, one line per check (passing checks included), the
/// failing iterations of each violated check, and the outcome.
pub fn render(report: &AuditReport) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "audit of {}", report.dir);
    let _ = writeln!(s, "algorithm: {}", report.algorithm);
    let _ = writeln!(s, "gradients: {}", report.gradients);
    let _ = writeln!(s, "J from:    {}", report.source);
    let _ = writeln!(
        s,
        "{} of {} iterations done, {} rows, {} skipped (next parameters not logged)",
        report.iterations_done, report.iterations_total, report.rows, report.skipped
    );
    let _ = writeln!(
        s,
        "{:<13} {:<11} {:>8} {:>8} {:>14} {:>10} {:>9} {:>10}  verdict",
        "check", "kind", "checked", "failed", "worst shortf.", "at", "allowed", "p-value"
    );
    for c in &report.checks {
        let opt = |x: Option<f64>| x.map_or_else(|| "-".to_owned(), |x| format!("{x:.3e}"));
        let _ = writeln!(
            s,
            "{:<13} {:<11} {:>8} {:>8} {:>14} {:>10} {:>9} {:>10}  {}",
            c.check,
            c.kind.label(),
            c.checked,
            c.failed,
            fmt(c.worst_shortfall),
            c.worst_iteration,
            opt(c.allowed_rate),
            opt(c.p_value),
            c.verdict.label()
        );
    }
    let violations = report.violations();
    if !violations.is_empty() {
        let _ = writeln!(
            s,
            "{:>10}  {:<13} {:>14} {:>14} {:>14}",
            "iteration", "check", "required", "actual", "shortfall"
        );
        for v in violations.iter().take(LISTED) {
            let _ = writeln!(
                s,
                "{:>10}  {:<13} {:>14} {:>14} {:>14}",
                v.iteration,
                v.check,
                fmt(v.required),
                fmt(v.actual),
                fmt(v.shortfall)
            );
        }
        if violations.len() > LISTED {
            let _ = writeln!(
                s,
                "... {} more failing iterations (--json lists all)",
                violations.len() - LISTED
            );
        }
    }
    let notes: Vec<&CheckSummary> = report
        .checks
        .iter()
        .filter(|c| c.verdict == Verdict::Note && c.failed > 0)
        .collect();
    for c in notes {
        let _ = writeln!(
            s,
            "note: {} failed at {} of {} iterations; it is the algorithm's own bookkeeping, not \
             exact J, so it does not show that the exact requirement broke",
            c.check, c.failed, c.checked
        );
    }
    let _ = match report.status {
        Status::Holds => writeln!(s, "holds: every exact and high-probability check held"),
        Status::Violated => writeln!(
            s,
            "VIOLATED: {} iteration(s) broke the safety requirement",
            report.broken_iterations().len()
        ),
        Status::Incomplete => writeln!(
            s,
            "incomplete: no violation in the {} iterations done, but the run has not finished",
            report.iterations_done
        ),
    };
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use sepg_mdp::lqg_model::LqgModel;

    const H: usize = 20;
    /// w = ln 0.5 throughout.
    fn w() -> f64 {
        0.5f64.ln()
    }

    fn oracle() -> Box<dyn ExactOracle> {
        Box::new(ClippedDpOracle::new(&LqgModel::thesis()).expect("the lqg preset has a DP"))
    }

    /// Exact J of N(v s, e^{2w}) on the clipped `lqg` preset, evaluated here without the
    /// auditor's cache.
    fn j(v: f64, w: f64) -> f64 {
        oracle()
            .evaluate(
                &[v],
                &Exploration::Gaussian { w: vec![w] },
                Horizon::Finite(H),
            )
            .expect("exact J")
            .j
    }

    fn auditor(requirement: Requirement, budget0: f64) -> Auditor {
        Auditor {
            source: Source::Exact(ExactJ {
                oracle: oracle(),
                horizon: Horizon::Finite(H),
                cache: HashMap::new(),
            }),
            requirement: Some(requirement),
            sim: matches!(requirement, Requirement::Sim { .. }),
            has_target: matches!(
                requirement,
                Requirement::Lv | Requirement::Zv | Requirement::Sim { .. }
            ),
            budget0,
            tolerance: 1e-9,
            first: None,
            tallies: BTreeMap::new(),
            failures: Vec::new(),
            skipped: 0,
        }
    }

    /// A logged row at θ = (v, w) whose logged J's are deliberately wrong (−1e6): with an
    /// oracle, the audit must use exact J only.
    fn row(t: u64, v: f64, w: f64, guaranteed_w: Option<f64>) -> Row {
        Row {
            iteration: t,
            v: vec![v],
            w: vec![w],
            j_explore: -1e6,
            j_after_v: Some(-1e6),
            j_target: -1e6,
            w_target: vec![f64::NEG_INFINITY],
            budget: 0.0,
            alpha: 1.0,
            beta: 1.0,
            guaranteed_v: None,
            guaranteed_w,
        }
    }

    fn next(v: f64, w: f64) -> Option<Next> {
        Some((vec![v], vec![w], Some(-1e6)))
    }

    fn tally(a: &Auditor, name: &str) -> (u64, u64, f64) {
        let t = &a.tallies[name];
        (t.checked, t.failed, t.worst.0)
    }

    /// Mean parameters with J(v_low) < J(v_mid) < J(v_high) at w = ln 0.5 (checked below).
    const V_LOW: f64 = -0.05;
    const V_MID: f64 = -0.2;
    const V_HIGH: f64 = -0.5;

    #[test]
    fn ordering_of_the_test_parameters() {
        let (lo, mid, hi) = (j(V_LOW, w()), j(V_MID, w()), j(V_HIGH, w()));
        assert!(lo < mid && mid < hi, "{lo} {mid} {hi}");
    }

    #[test]
    fn lb_i_compares_with_the_first_j_not_the_previous_one() {
        // θ⁰ = V_LOW, θ¹ = V_HIGH, θ² = V_MID: J falls from θ¹ to θ² but stays above J(θ⁰),
        // which LB-I allows; a θ³ = V_LOW − 0.1 below J(θ⁰) breaks it.
        let below = V_LOW + 0.1;
        assert!(j(below, w()) < j(V_LOW, w()));
        let mut a = auditor(Requirement::LbI { nu: 0.5 }, 0.0);
        let path = [V_LOW, V_HIGH, V_MID, below];
        for (t, pair) in path.windows(2).enumerate() {
            a.row(&row(t as u64, pair[0], w(), None), next(pair[1], w()))
                .unwrap();
        }
        let (checked, failed, worst) = tally(&a, "lb-i");
        assert_eq!((checked, failed), (3, 1));
        assert_eq!(worst, j(V_LOW, w()) - j(below, w()));
        assert_eq!(
            a.failures.iter().map(|f| f.iteration).collect::<Vec<_>>(),
            [2]
        );
    }

    #[test]
    fn budget_exact_telescopes_from_the_first_j() {
        // LB-II, B⁰ = 0: the exploratory policy after the v-step of row t is (vᵗ⁺¹, wᵗ), so the
        // recomputed budget of row t is J(vᵗ⁺¹, w) − J(θ⁰) (Definition 4.3 telescoped). With
        // θ⁰ = V_LOW, θ¹ = V_HIGH, θ² = V_MID it stays positive although J falls at row 1.
        let mut a = auditor(Requirement::LbII, 0.0);
        a.row(&row(0, V_LOW, w(), None), next(V_HIGH, w())).unwrap();
        a.row(&row(1, V_HIGH, w(), None), next(V_MID, w())).unwrap();
        let (checked, failed, worst) = tally(&a, "budget-exact");
        assert_eq!((checked, failed), (2, 0));
        let j0 = j(V_LOW, w());
        let smallest = (0.0 + j(V_HIGH, w()) - j0).min(0.0 + j(V_MID, w()) - j0);
        assert_eq!(worst, -smallest);
        // B⁰ = 0 and a first v-step that loses: the budget is negative from row 0 on.
        let mut a = auditor(Requirement::LbII, 0.0);
        a.row(&row(0, V_MID, w(), None), next(V_LOW, w())).unwrap();
        assert_eq!(tally(&a, "budget-exact").1, 1);
    }

    #[test]
    fn guarantee_w_measures_the_w_step_from_after_the_v_step() {
        // Row 0 goes from (V_LOW, w) to (V_HIGH, w + 0.1): the w-step's own gain is
        // J(V_HIGH, w + 0.1) − J(V_HIGH, w), much smaller than the gain from J(θ⁰).
        let w1 = w() + 0.1;
        let gain_w = j(V_HIGH, w1) - j(V_HIGH, w());
        let gain_total = j(V_HIGH, w1) - j(V_LOW, w());
        assert!(gain_total > gain_w + 1e-3, "{gain_total} {gain_w}");
        // A guarantee just above the w-step's gain fails; one just below holds.
        for (g, failed) in [(gain_w + 1e-4, 1), (gain_w - 1e-4, 0)] {
            let mut a = auditor(Requirement::LbI { nu: 0.5 }, 0.0);
            a.row(&row(0, V_LOW, w(), Some(g)), next(V_HIGH, w1))
                .unwrap();
            let (checked, f, worst) = tally(&a, "guarantee-w");
            assert_eq!((checked, f), (1, failed), "guarantee {g}");
            assert_eq!(worst, g - (j(V_HIGH, w1) - j(V_HIGH, w())));
        }
    }
}
