//! `sepg audit DIR`: re-checks the log of a run folder against the run's safety requirement
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
//! Exit status: 0 when no iteration broke the requirement, 1 when some did, 2 for bad input.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};

use clap::Args;
use sepg_algo::core::config::{Algorithm, Requirement};
use sepg_mdp::env::AnyEnv;
use sepg_mdp::oracle::{ClippedDpOracle, ClosedFormOracle, ExactOracle, Exploration, Horizon};
use serde::Serialize;

use crate::cli::CliError;
use crate::commands::runfmt::{
    self, CHECKPOINT_FILE, Checkpoint, LOG_FILE, PARTIAL_LOG_FILE, SUMMARY_FILE, Summary,
};

/// Arguments of `sepg audit`.
#[derive(Debug, Args)]
pub struct AuditArgs {
    /// Run folder written by `sepg run` (complete, or interrupted: its checkpointed rows).
    #[arg(value_name = "DIR")]
    dir: PathBuf,
    /// Print the report as JSON on standard output instead of the table.
    #[arg(long)]
    json: bool,
    /// Relative slack: a shortfall below tolerance · max(1, |J|) is attributed to rounding.
    #[arg(long, default_value_t = 1e-9)]
    tolerance: f64,
}

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

fn bad(dir: &Path, what: impl std::fmt::Display) -> CliError {
    CliError::usage(format!("{}: {what}", dir.display()))
}

/// The bytes of the log: `log.csv`, or the checkpointed prefix of `log.partial.csv`.
fn log_bytes(dir: &Path) -> Result<Vec<u8>, CliError> {
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

fn read_checkpoint(dir: &Path) -> Result<Option<Checkpoint>, CliError> {
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
fn final_params(dir: &Path) -> Result<Option<Params>, CliError> {
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

/// Parses the log strictly: the header of this run's dimensions, rows of the same width,
/// numbers (or empty cells where a value does not apply), increasing iterations.
fn parse_log(dir: &Path, bytes: &[u8], dims: (usize, usize)) -> Result<Vec<Row>, CliError> {
    let text = std::str::from_utf8(bytes).map_err(|_| bad(dir, "the log is not UTF-8"))?;
    let mut lines = text.split_terminator('\n');
    let header = runfmt::log_header(dims.0, dims.1);
    if lines.next() != Some(header.trim_end()) {
        return Err(bad(
            dir,
            "the log header does not match the run's configuration",
        ));
    }
    let columns: Vec<&str> = header.trim_end().split(',').collect();
    let col = |name: &str| columns.iter().position(|c| *c == name);
    let cols = |name: &str, dim: usize| -> Vec<usize> {
        if dim == 1 {
            col(name).into_iter().collect()
        } else {
            (0..dim)
                .filter_map(|i| col(&format!("{name}_{i}")))
                .collect()
        }
    };
    let (iv, iw, iwt) = (
        cols("v", dims.0),
        cols("w", dims.1),
        cols("w_target", dims.1),
    );
    let named = |name: &str| col(name).ok_or_else(|| bad(dir, format!("no column {name}")));
    let [ije, ija, ijt, ib, ia, ibt, igv, igw] = [
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
    let (ije, ija, ijt, ib, ia, ibt, igv, igw) = (ije?, ija?, ijt?, ib?, ia?, ibt?, igv?, igw?);
    let mut rows: Vec<Row> = Vec::new();
    for (n, line) in lines.enumerate() {
        let line_no = n + 2;
        let cells: Vec<&str> = line.split(',').collect();
        if cells.len() != columns.len() {
            return Err(bad(
                dir,
                format!(
                    "log line {line_no} has {} cells, the header {}",
                    cells.len(),
                    columns.len()
                ),
            ));
        }
        let cell = |i: usize| -> Result<Option<f64>, CliError> {
            let c = cells[i];
            if c.is_empty() {
                return Ok(None);
            }
            c.parse::<f64>().map(Some).map_err(|_| {
                bad(
                    dir,
                    format!(
                        "log line {line_no}, column {}: {c:?} is not a number",
                        columns[i]
                    ),
                )
            })
        };
        let req = |i: usize| -> Result<f64, CliError> {
            cell(i)?.ok_or_else(|| {
                bad(
                    dir,
                    format!("log line {line_no}, column {} is empty", columns[i]),
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
        if rows.last().is_some_and(|r| r.iteration >= iteration) {
            return Err(bad(
                dir,
                format!("log line {line_no}: iterations are not increasing"),
            ));
        }
        let many = |idx: &[usize]| idx.iter().map(|&i| req(i)).collect::<Result<Vec<_>, _>>();
        rows.push(Row {
            iteration,
            v: many(&iv)?,
            w: many(&iw)?,
            j_explore: req(ije)?,
            j_after_v: cell(ija)?,
            j_target: req(ijt)?,
            w_target: many(&iwt)?,
            budget: req(ib)?,
            alpha: req(ia)?,
            beta: req(ibt)?,
            guaranteed_v: cell(igv)?,
            guaranteed_w: cell(igw)?,
        });
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
    fn j(&mut self, v: &[f64], w: &[f64]) -> Result<f64, CliError> {
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
            .map_err(|e| CliError::failure(format!("exact J at v = {v:?}, w = {w:?}: {e}")))?
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
/// Usage error for a folder that is not a readable run or holds a malformed log; failure
/// when the oracle cannot evaluate a logged policy.
pub fn audit(dir: &Path, tolerance: f64) -> Result<AuditReport, CliError> {
    if !(tolerance.is_finite() && tolerance >= 0.0) {
        return Err(CliError::usage(format!(
            "--tolerance {tolerance} must be finite and >= 0"
        )));
    }
    if !dir.is_dir() {
        return Err(CliError::usage(format!(
            "{} is not a folder",
            dir.display()
        )));
    }
    let resolved = runfmt::load_resolved(dir)?;
    let config = resolved.checked.config();
    let rows = parse_log(dir, &log_bytes(dir)?, resolved.dims)?;
    let last = final_params(dir)?;
    let (mut source, source_name) = match &config.env {
        AnyEnv::Lqg(env) => {
            let model = env.model();
            let (oracle, name): (Box<dyn ExactOracle>, _) = if model.clipping {
                let o =
                    ClippedDpOracle::new(model).map_err(|e| CliError::failure(e.to_string()))?;
                (Box::new(o), "ClippedDpOracle")
            } else {
                let o =
                    ClosedFormOracle::new(model).map_err(|e| CliError::failure(e.to_string()))?;
                (Box::new(o), "ClosedFormOracle")
            };
            let horizon = Horizon::Finite(config.horizon);
            let cache = HashMap::new();
            let label = format!("exact ({name}, H = {})", config.horizon);
            (
                Source::Exact(ExactJ {
                    oracle,
                    horizon,
                    cache,
                }),
                label,
            )
        }
        AnyEnv::MountainCar(_) => (Source::Logged, "log (no exact oracle)".to_owned()),
    };
    let requirement = match config.algorithm {
        Algorithm::Sepg(r) | Algorithm::SepgNaiveW(r) => Some(r),
        _ => None,
    };
    let mut report = AuditReport {
        dir: dir.display().to_string(),
        algorithm: format!("{:?}", config.algorithm),
        source: source_name,
        iterations: rows.len(),
        checks: 0,
        skipped: 0,
        violations: Vec::new(),
    };
    let tol = |j: f64| tolerance * j.abs().max(1.0);
    let exact = matches!(source, Source::Exact(_));
    let mut j_of = |v: &[f64], w: &[f64], logged: Option<f64>| -> Result<Option<f64>, CliError> {
        match &mut source {
            Source::Exact(e) => e.j(v, w).map(Some),
            Source::Logged => Ok(logged),
        }
    };
    let budget0 = config.initial_budget;
    let sim = matches!(requirement, Some(Requirement::Sim { .. }));
    let has_target = matches!(
        requirement,
        Some(Requirement::Lv | Requirement::Zv | Requirement::Sim { .. })
    );
    let mut j_first: Option<(f64, f64)> = None;
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
        let j_t = j_of(&row.v, &row.w, Some(row.j_explore))?.unwrap_or(row.j_explore);
        let j_target = if has_target {
            j_of(&row.v, &row.w_target, Some(row.j_target))?.unwrap_or(row.j_target)
        } else {
            j_t
        };
        let (j0, jt0) = *j_first.get_or_insert((j_t, j_target));
        let check = |report: &mut AuditReport, name: &'static str, required: f64, actual: f64| {
            report.checks += 1;
            let shortfall = required - actual;
            if shortfall > tol(j_t) {
                report.violations.push(Violation {
                    iteration: t,
                    check: name,
                    required,
                    actual,
                    shortfall,
                });
            }
        };
        let Some((v_next, w_next, j_next_logged)) = next else {
            report.skipped += 1;
            if requirement.is_some_and(|r| r.is_type_two()) {
                check(&mut report, "budget", 0.0, row.budget);
            }
            continue;
        };
        let j_mid = j_of(&v_next, &row.w, row.j_after_v)?;
        let j_next = j_of(&v_next, &w_next, j_next_logged)?;
        if let (Some(g), Some(j_mid)) = (row.guaranteed_v, j_mid)
            && row.alpha != 0.0
        {
            check(&mut report, "guarantee-v", g, j_mid - j_t);
        }
        if let Some(g) = row.guaranteed_w.filter(|_| row.beta != 0.0) {
            let actual = if sim {
                j_of(&row.v, &w_next, None)?.map(|j| j - j_t)
            } else {
                j_mid.zip(j_next).map(|(m, n)| n - m)
            };
            if let Some(actual) = actual {
                check(&mut report, "guarantee-w", g, actual);
            }
        }
        match requirement {
            Some(Requirement::Mi) => {
                if let Some(j_next) = j_next {
                    check(&mut report, "mi", j_t, j_next);
                }
            }
            Some(Requirement::LbI { .. }) => {
                if let Some(j_next) = j_next {
                    check(&mut report, "lb-i", j0, j_next);
                }
            }
            Some(_) => {
                check(&mut report, "budget", 0.0, row.budget);
                if exact {
                    let explore = if sim { Some(j_t) } else { j_mid };
                    if let Some(explore) = explore {
                        let target = if has_target { j_target - jt0 } else { 0.0 };
                        check(
                            &mut report,
                            "budget-exact",
                            0.0,
                            budget0 + explore - j0 + target,
                        );
                    }
                }
            }
            None => {}
        }
    }
    Ok(report)
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

/// Runs `sepg audit`.
///
/// # Errors
/// Usage error (exit 2) for bad input; failure (exit 1) when some iteration broke the
/// requirement (the report is printed first) or J cannot be recomputed.
pub fn run(args: &AuditArgs) -> Result<(), CliError> {
    let report = audit(&args.dir, args.tolerance)?;
    if args.json {
        let text = serde_json::to_string_pretty(&report)
            .map_err(|e| CliError::failure(format!("cannot serialise the report: {e}")))?;
        println!("{text}");
    } else {
        print!("{}", render(&report));
    }
    let broken = report.broken_iterations();
    if broken.is_empty() {
        Ok(())
    } else {
        Err(CliError::failure(format!(
            "{} iteration(s) of {} broke the safety requirement (first: {})",
            broken.len(),
            args.dir.display(),
            broken[0]
        )))
    }
}
