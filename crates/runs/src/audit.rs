//! Audit: re-checks the log of a run folder against the run's safety requirement
//! and reports every iteration that broke it, and by how much.
//!
//! For iteration t (row t of `log.csv`, parameters θᵗ = (vᵗ, wᵗ), the update producing
//! θᵗ⁺¹ from the next row or the checkpoint) the audit checks:
//!
//! ```text
//! guarantee-v   J(vᵗ⁺¹, wᵗ) − J(vᵗ, wᵗ)       ≥ guaranteed_v    (Theorems 4.2 / 4.7)
//! guarantee-w   J(vᵗ⁺¹, wᵗ⁺¹) − J(vᵗ⁺¹, wᵗ)   ≥ guaranteed_w    (Theorems 4.3 / 4.5 / 4.8 / 4.9)
//!               SIM-ν: J(vᵗ, wᵗ⁺¹) − J(vᵗ, wᵗ) ≥ guaranteed_w   (both steps taken at θᵗ)
//! mi            J(θᵗ⁺¹) ≥ J(θᵗ)                                  (MI, Table 4.1)
//! lb-i          J(θᵗ⁺¹) ≥ J(θ⁰)                                  (LB-I, Table 4.1)
//! budget        recorded Bᵗ ≥ 0                                   (type II, Theorem 4.1)
//! budget-exact  B⁰ + ΔJ_E + ΔJ_T ≥ 0 recomputed from exact J       (type II, Definition 4.3)
//! ```
//!
//! J is recomputed exactly for the logged parameters when the environment has an oracle
//! (`ClippedDpOracle` for the clipped LQG presets, `ClosedFormOracle` for unclipped ones), so
//! runs with sampled gradients are audited against the truth; otherwise the logged values are
//! used. A shortfall counts as a violation when it exceeds `tolerance · max(1, |Jᵗ|)`.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::fs;
use std::path::Path;

use sepg_algo::core::config::{Algorithm, Requirement};
use sepg_mdp::env::AnyEnv;
use sepg_mdp::oracle::{ClippedDpOracle, ClosedFormOracle, ExactOracle, Exploration, Horizon};
use serde::Serialize;

use crate::error::{Error, Result};
use crate::folder::{
    CHECKPOINT_FILE, Checkpoint, LOG_FILE, PARTIAL_LOG_FILE, SUMMARY_FILE, Summary, load_resolved,
    log_header,
};

/// One iteration that broke a check.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Violation {
    /// Iteration t whose update broke the check.
    pub iteration: u64,
    /// Which check (`guarantee-v`, `guarantee-w`, `mi`, `lb-i`, `budget`, `budget-exact`).
    pub check: &'static str,
    /// The value the requirement asks for (a guaranteed improvement, J(θᵗ), J(θ⁰) or 0).
    pub required: f64,
    /// The value the run achieved.
    pub actual: f64,
    /// How far below the requirement: `required − actual` (> 0).
    pub shortfall: f64,
}

/// The audit of one run folder.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AuditReport {
    /// The run folder.
    pub dir: String,
    /// Algorithm and requirement, as in the configuration.
    pub algorithm: String,
    /// Where J comes from: `exact (…)` or `log`.
    pub source: String,
    /// Rows of the log audited.
    pub iterations: usize,
    /// Individual checks evaluated.
    pub checks: usize,
    /// Checks skipped because θᵗ⁺¹ is not in the log (log-every > 1 or no checkpoint).
    pub skipped: usize,
    /// Every check that failed, by iteration.
    pub violations: Vec<Violation>,
}

impl AuditReport {
    /// Distinct iterations with at least one violation, in order.
    pub fn broken_iterations(&self) -> Vec<u64> {
        let mut its: Vec<u64> = self.violations.iter().map(|v| v.iteration).collect();
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

/// The bytes of the log: `log.csv`, or the checkpointed prefix of `log.partial.csv`.
fn log_bytes(dir: &Path) -> Result<Vec<u8>> {
    let done = dir.join(LOG_FILE);
    if done.is_file() {
        return fs::read(&done).map_err(|e| bad(dir, format!("cannot read {LOG_FILE}: {e}")));
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
    Ok(bytes)
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

/// Parameters θᵗ = (vᵗ, wᵗ) reached after `iteration` iterations.
struct Params {
    iteration: u64,
    v: Vec<f64>,
    w: Vec<f64>,
}

/// The parameters after the last checkpointed (or final) iteration.
fn final_params(dir: &Path) -> Result<Option<Params>> {
    if let Some(ck) = read_checkpoint(dir)? {
        let s = ck.state;
        return Ok(Some(Params {
            iteration: s.iteration,
            v: s.v,
            w: s.w,
        }));
    }
    let path = dir.join(SUMMARY_FILE);
    if !path.is_file() {
        return Ok(None);
    }
    let text = fs::read_to_string(&path)
        .map_err(|e| bad(dir, format!("cannot read {SUMMARY_FILE}: {e}")))?;
    let s: Summary = serde_json::from_str(&text)
        .map_err(|e| bad(dir, format!("{SUMMARY_FILE} is malformed: {e}")))?;
    let (v, w) = (s.final_params.v, s.final_params.w);
    Ok(Some(Params {
        iteration: s.iterations,
        v,
        w,
    }))
}

/// Positions of the columns the audit reads, in a header of this run's dimensions.
struct Columns<'h> {
    names: Vec<&'h str>,
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
            names,
        })
    }

    /// Parses line `line_no` of the log (1 is the header), whose iteration must follow
    /// `previous`.
    fn row(&self, dir: &Path, line_no: usize, line: &str, previous: Option<u64>) -> Result<Row> {
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
        let cell = |i: usize| -> Result<Option<f64>> {
            let c = cells[i];
            if c.is_empty() {
                return Ok(None);
            }
            c.parse::<f64>().map(Some).map_err(|_| {
                bad(
                    dir,
                    format!(
                        "log line {line_no}, column {}: {c:?} is not a number",
                        self.names[i]
                    ),
                )
            })
        };
        let req = |i: usize| -> Result<f64> {
            cell(i)?.ok_or_else(|| {
                bad(
                    dir,
                    format!("log line {line_no}, column {} is empty", self.names[i]),
                )
            })
        };
        let iteration: u64 = cells[0].parse().map_err(|_| {
            bad(
                dir,
                format!(
                    "log line {line_no}: iteration {:?} is not an integer",
                    cells[0]
                ),
            )
        })?;
        if previous.is_some_and(|p| p >= iteration) {
            return Err(bad(
                dir,
                format!("log line {line_no}: iterations are not increasing"),
            ));
        }
        let many = |idx: &[usize]| idx.iter().map(|&i| req(i)).collect::<Result<Vec<_>>>();
        let [ije, ija, ijt, ib, ia, ibt, igv, igw] = self.scalars;
        Ok(Row {
            iteration,
            v: many(&self.v)?,
            w: many(&self.w)?,
            j_explore: req(ije)?,
            j_after_v: cell(ija)?,
            j_target: req(ijt)?,
            w_target: many(&self.w_target)?,
            budget: req(ib)?,
            alpha: req(ia)?,
            beta: req(ibt)?,
            guaranteed_v: cell(igv)?,
            guaranteed_w: cell(igw)?,
        })
    }
}

/// Parses the log strictly: the header of this run's dimensions, rows of the same width,
/// numbers (or empty cells where a value does not apply), increasing iterations.
fn parse_log(dir: &Path, bytes: &[u8], dims: (usize, usize)) -> Result<Vec<Row>> {
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
    let mut rows: Vec<Row> = Vec::new();
    for (n, line) in lines.enumerate() {
        let line_no = n + 2;
        let row = columns.row(dir, line_no, line, rows.last().map(|r| r.iteration))?;
        rows.push(row);
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
        self.cache.insert(key, j);
        Ok(j)
    }
}

/// J values of the audit: exact when an oracle exists, else the logged estimates.
enum Source {
    Exact(ExactJ),
    Logged,
}

/// Runs the audit of `dir` (no printing).
///
/// # Errors
/// [`Error::Invalid`] for a folder that is not a readable run or holds a malformed log;
/// [`Error::Failed`] when the oracle cannot evaluate a logged policy.
pub fn audit(dir: &Path, tolerance: f64) -> Result<AuditReport> {
    if !(tolerance.is_finite() && tolerance >= 0.0) {
        return Err(Error::invalid(format!(
            "--tolerance {tolerance} must be finite and >= 0"
        )));
    }
    if !dir.is_dir() {
        return Err(Error::invalid(format!("{} is not a folder", dir.display())));
    }
    let resolved = load_resolved(dir)?;
    let config = resolved.checked.config();
    let rows = parse_log(dir, &log_bytes(dir)?, resolved.dims)?;
    let last = final_params(dir)?;
    let (source, source_name) = source(config)?;
    let requirement = match config.algorithm {
        Algorithm::Sepg(r) | Algorithm::SepgNaiveW(r) => Some(r),
        _ => None,
    };
    let mut auditor = Auditor {
        exact: matches!(source, Source::Exact(_)),
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
        report: AuditReport {
            dir: dir.display().to_string(),
            algorithm: format!("{:?}", config.algorithm),
            source: source_name,
            iterations: rows.len(),
            checks: 0,
            skipped: 0,
            violations: Vec::new(),
        },
    };
    for (k, row) in rows.iter().enumerate() {
        let t = row.iteration;
        let next = match rows.get(k + 1) {
            Some(n) if n.iteration == t + 1 => Some((n.v.clone(), n.w.clone(), Some(n.j_explore))),
            Some(_) => None,
            None => last
                .as_ref()
                .filter(|p| p.iteration == t + 1)
                .map(|p| (p.v.clone(), p.w.clone(), None)),
        };
        auditor.row(row, next)?;
    }
    Ok(auditor.report)
}

/// Where J comes from for the environment of `config`, and its label.
fn source(config: &sepg_algo::core::config::SepgConfig) -> Result<(Source, String)> {
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
    exact: bool,
    requirement: Option<Requirement>,
    sim: bool,
    has_target: bool,
    budget0: f64,
    tolerance: f64,
    /// J of the exploratory and of the target policy at the first row.
    first: Option<(f64, f64)>,
    report: AuditReport,
}

impl Auditor {
    /// J at (v, w): exact when an oracle exists, else `logged`.
    fn j_of(&mut self, v: &[f64], w: &[f64], logged: Option<f64>) -> Result<Option<f64>> {
        match &mut self.source {
            Source::Exact(e) => e.j(v, w).map(Some),
            Source::Logged => Ok(logged),
        }
    }

    /// Counts one check of iteration `t`, and records it when `actual` falls short of
    /// `required` by more than the tolerance relative to `j_t`.
    fn check(&mut self, t: u64, j_t: f64, name: &'static str, required: f64, actual: f64) {
        self.report.checks += 1;
        let shortfall = required - actual;
        if shortfall > self.tolerance * j_t.abs().max(1.0) {
            self.report.violations.push(Violation {
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
        let Some((v_next, w_next, j_next_logged)) = next else {
            self.report.skipped += 1;
            if self.requirement.is_some_and(|r| r.is_type_two()) {
                self.check(t, j_t, "budget", 0.0, row.budget);
            }
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
                self.check(t, j_t, "budget", 0.0, row.budget);
                let explore = if self.sim { Some(j_t) } else { j_mid };
                if let Some(explore) = explore.filter(|_| self.exact) {
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

/// The human-readable report.
pub fn render(report: &AuditReport) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "audit of {}", report.dir);
    let _ = writeln!(s, "algorithm: {}", report.algorithm);
    let _ = writeln!(s, "J from:    {}", report.source);
    let _ = writeln!(
        s,
        "{} iterations, {} checks, {} skipped (next parameters not logged)",
        report.iterations, report.checks, report.skipped
    );
    if report.violations.is_empty() {
        let _ = writeln!(s, "no iteration broke the safety requirement");
        return s;
    }
    let _ = writeln!(
        s,
        "{:>10}  {:<13} {:>14} {:>14} {:>14}",
        "iteration", "check", "required", "actual", "shortfall"
    );
    for v in &report.violations {
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
    let broken = report.broken_iterations();
    let _ = writeln!(
        s,
        "{} iteration(s) broke the safety requirement",
        broken.len()
    );
    s
}
