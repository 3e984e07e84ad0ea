//! Audit: re-checks the log of a run folder against exactly what the run promises about the
//! exact performance J — the statement recorded in its `summary.json` (docs/THEOREMS.md,
//! "Statements over a whole run") — and gives the run one verdict.
//!
//! # Checks
//! For iteration t (row t of `log.csv`): θᵗ = (vᵗ, wᵗ), θᵗ⁺¹ from the next row (or the final
//! parameters), θᵗ⁺½ = (vᵗ⁺¹, wᵗ) the point after the v-step, θ_Tᵗ = (vᵗ, w_targetᵗ) the
//! target (w = −∞: the deterministic policy), B⁰ the initial budget.
//!
//! ```text
//! guarantee-v    J(θᵗ⁺½) − J(θᵗ) ≥ guaranteed_v                  every SEPG variant
//! guarantee-w    J(θᵗ⁺¹) − J(θᵗ⁺½) ≥ guaranteed_w                 (SIM-ν: J(vᵗ, wᵗ⁺¹) − J(θᵗ))
//! mi             J(θᵗ⁺½) ≥ J(θᵗ) and J(θᵗ⁺¹) ≥ J(θᵗ⁺½)             MI
//! lb-i           J(θᵗ⁺½) ≥ J(θ⁰) and J(θᵗ⁺¹) ≥ J(θ⁰)               LB-I (Table 4.1)
//! budget-exact   J(θᵗ⁺½) ≥ J(θ⁰) − B⁰ and J(θᵗ⁺¹) ≥ J(θ⁰) − B⁰     LB-II, LV, ZV
//! budget-target  J(θ_Tᵗ) ≥ J(θ⁰) − B⁰                             LV (ZV: reported only)
//! budget         recorded Bᵗ ≥ 0                                   type II: the run's bookkeeping
//! ```
//! A guarantee check is evaluated at every iteration whose next parameters the log holds
//! (the denominator of its failure rate is the number of iterations, not of steps taken: the
//! theorems bound P(the step is taken and fails) per iteration); it can fail only at an
//! iteration whose step was taken (α ≠ 0, β ≠ 0). ZV's deterministic target carries no
//! guarantee, so its `budget-target` and every run's recorded `budget` are reported, never
//! judged.
//!
//! # Exact J and the tolerance
//! J is recomputed for every logged point with [`ClippedDpOracle`] at [`audit_dp_config`]
//! (the clipped `lqg`, `lqg1d` presets) or [`ClosedFormOracle`] (unclipped models), in
//! parallel over the points: each value is a pure function of its point, so the report does
//! not depend on the number of threads. A check compares two exact values (a difference of J
//! with a guarantee, or J with a floor); it fails when its shortfall `required − actual`
//! exceeds `tolerance · max(1, |J|)`, |J| the largest magnitude among the values compared.
//! The default [`DEFAULT_TOLERANCE`] = 1e-12 is about 50 times the largest error of the
//! audit's DP on differences of J measured against a much finer DP (2.1e-14 · |J|; the test
//! `the_tolerance_exceeds_the_oracles_error_on_differences` repeats the measurement), and
//! |J| ≤ 200 on the presets, so a genuine failure of 1e-9 near convergence is seen. The DP's
//! default resolution (10 nodes per element) is not accurate enough for that: its errors on
//! differences reach 2.5e-9.
//!
//! # How failures are judged
//! By the run's statement ([`Statement`]):
//! - kind `none`: nothing is promised; every check is reported ([`Test::Reported`]).
//! - scope `run`, or exact gradients (δ = null, a certainty): one failure of a covered check
//!   breaks the promise ([`Test::OneFailure`]).
//! - scope `iteration`: the statement's δ bounds, given the past, the probability that any
//!   of the iteration's K scalar confidence statements fails (its own union bound, each
//!   statement at δ/K; K as the run counts them). A check resting on k of them (the l·p
//!   components of ∇̂_v J for `guarantee-v`, the l of ∇̂_w J for `guarantee-w`, both for
//!   `mi`) fails with probability at most k·δ/K; its failure count over n iterations is then
//!   stochastically below Binomial(n, k·δ/K), tested exactly ([`Test::Binomial`]:
//!   P(X ≥ failed) < α/m rejects, m the number of tested checks, Bonferroni). The floors
//!   `lb-i`, `budget-exact` and `budget-target` rest on every event up to their iteration
//!   (their failures persist), so no per-iteration null exists for them; the union bound
//!   gives P(first failure at or before t) ≤ (t + 1)·k·δ/K, and that is the test
//!   ([`Test::FirstFailure`]).
//!
//! A rejected check is [`Judgement::Broken`] under a proven statement and
//! [`Judgement::Exceeded`] under an approximate one.
//!
//! # Verdict
//! [`Verdict::Broken`] when a check is broken (even if the run is unfinished); else
//! [`Verdict::Incomplete`] for an unfinished run; else [`Verdict::NotChecked`] without an
//! exact oracle (Mountain Car); else by the statement's kind: `proven` → [`Verdict::Holds`],
//! `approximate` → [`Verdict::Approximate`] (never "holds"), `none` →
//! [`Verdict::NoGuarantee`]. A summary written before statements were recorded is read as
//! scope `iteration`, kind `approximate` (kind `none` for runs that promise nothing); an
//! unfinished run is judged by the statement its configuration gives. The run's own
//! bookkeeping ([`SelfCheck`]) is reported beside the verdict, not in it.
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
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

use rayon::prelude::*;
use sepg_algo::core::config::{Algorithm, GradientMode, Requirement};
use sepg_algo::core::statement::{Covers, Scope, SelfCheck, Statement, StatementKind};
use sepg_estimators::binomial::upper_tail;
use sepg_mdp::env::AnyEnv;
use sepg_mdp::oracle::{
    ClippedDpOracle, ClosedFormOracle, DpConfig, ExactOracle, Exploration, Horizon, Needs,
};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::folder::{SUMMARY_FILE, Summary, load_resolved};
use crate::logcheck::{Row, bad, log_bytes, parse_log};
use crate::run::{RunObserver, Silent};
use crate::spec::{AlgoName, RunSpec};

/// Family-wise significance level of the tests of a run (and of the groups of a sweep),
/// unless the caller asks for another one.
pub const DEFAULT_ALPHA: f64 = 0.01;

/// Relative tolerance of the checks: a shortfall up to `DEFAULT_TOLERANCE · max(1, |J|)` is
/// attributed to the oracle's error (see the module documentation for its measurement).
pub const DEFAULT_TOLERANCE: f64 = 1e-12;

/// Chebyshev nodes per element of the dynamic programme the audit evaluates J with.
pub const AUDIT_NODES_PER_ELEMENT: usize = 14;

/// The resolution of [`ClippedDpOracle`] used by the audit: [`DpConfig::default`] with
/// [`AUDIT_NODES_PER_ELEMENT`] nodes per element. Measured against a DP with 24 nodes, 2.5
/// times narrower elements and 16 quadrature points on 240 random pairs of both presets
/// (v ∈ [−1.5, 0.2], σ ∈ [0.02, 2], steps from 1e-9 to 1, H = 20), its error on J is at most
/// 1.8e-12 and on differences of J at most 2.7e-12 (2.1e-14 · |J|), at 1.5 times the cost of
/// the default resolution (whose errors on differences reach 2.5e-9).
///
/// ```
/// assert_eq!(sepg_runs::audit::audit_dp_config().nodes_per_element, 14);
/// ```
pub fn audit_dp_config() -> DpConfig {
    DpConfig {
        nodes_per_element: AUDIT_NODES_PER_ELEMENT,
        ..DpConfig::default()
    }
}

/// The verdict on a run: what its audit establishes about the statement it recorded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum Verdict {
    /// A proven (or certain) statement, and no check rejected against exact J.
    Holds,
    /// A proven (or certain) statement broken against exact J: under scope `run` (or exact
    /// gradients) one exact violation; under scope `iteration` a failure count its test
    /// rejects.
    Broken,
    /// An approximate statement: its failures are reported, it never "holds".
    Approximate,
    /// The run makes no statement about exact J (its checks are reported as information).
    NoGuarantee,
    /// No exact oracle for the environment (Mountain Car): not checked against exact J.
    NotChecked,
    /// An unfinished run without a broken check.
    Incomplete,
}

impl Verdict {
    /// The name used in reports and in a sweep's `summary.csv` (`holds`, `broken`,
    /// `approximate`, `no-guarantee`, `not-checked`, `incomplete`).
    ///
    /// ```
    /// assert_eq!(sepg_runs::audit::Verdict::NoGuarantee.name(), "no-guarantee");
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Holds => "holds",
            Verdict::Broken => "broken",
            Verdict::Approximate => "approximate",
            Verdict::NoGuarantee => "no-guarantee",
            Verdict::NotChecked => "not-checked",
            Verdict::Incomplete => "incomplete",
        }
    }
}

/// How the failures of a check are tested (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum Test {
    /// Scope `run` or a certainty: one failure rejects.
    OneFailure,
    /// Scope `iteration`, a per-step check: P(Binomial(n, rate) ≥ failed) < α/m rejects.
    Binomial,
    /// Scope `iteration`, a floor: P(first failure ≤ t) ≤ min(1, (t + 1)·rate) < α/m rejects.
    FirstFailure,
    /// Not promised (no statement, not covered, or the run's own bookkeeping): reported only.
    Reported,
}

impl Test {
    fn label(self) -> &'static str {
        match self {
            Test::OneFailure => "one-failure",
            Test::Binomial => "binomial",
            Test::FirstFailure => "first-fail",
            Test::Reported => "reported",
        }
    }
}

/// The judgement on one check.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum Judgement {
    /// Not rejected by its test.
    Holds,
    /// Rejected, and promised by a proven statement: the run broke its promise.
    Broken,
    /// Rejected, under an approximate statement: reported, not a broken promise.
    Exceeded,
    /// Reported only ([`Test::Reported`]).
    Note,
}

impl Judgement {
    fn label(self) -> &'static str {
        match self {
            Judgement::Holds => "holds",
            Judgement::Broken => "BROKEN",
            Judgement::Exceeded => "exceeded",
            Judgement::Note => "note",
        }
    }
}

/// The summary of one check over the whole log.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CheckSummary {
    /// Name of the check (`guarantee-v`, `guarantee-w`, `mi`, `lb-i`, `budget-exact`,
    /// `budget-target`, `budget`).
    pub check: &'static str,
    /// How its failures are tested.
    pub test: Test,
    /// Iterations at which it was evaluated: the denominator of its failure rate.
    pub checked: u64,
    /// Guarantee checks: iterations whose step was taken (the others cannot fail).
    pub steps: Option<u64>,
    /// Iterations at which it failed.
    pub failed: u64,
    /// The first failing iteration.
    pub first_failure: Option<u64>,
    /// The longest run of consecutive failing iterations.
    pub longest_run: u64,
    /// Largest `required − actual` over the checked iterations (negative: the smallest margin
    /// by which it held; 0 when no iteration could fail, e.g. no step taken).
    pub worst_shortfall: f64,
    /// Iteration of the worst shortfall.
    pub worst_iteration: u64,
    /// Scope `iteration`: the per-iteration failure probability the statement allows this
    /// check (k·δ/K, see the module documentation).
    pub allowed_rate: Option<f64>,
    /// Scope `iteration`: the p-value of its test.
    pub p_value: Option<f64>,
    /// The judgement.
    pub judgement: Judgement,
}

/// One iteration at which a check failed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Violation {
    /// Iteration t whose update (or target) broke the check.
    pub iteration: u64,
    /// Which check.
    pub check: &'static str,
    /// The value the requirement asks for (a guaranteed improvement, J(θᵗ), J(θ⁰) or
    /// J(θ⁰) − B⁰).
    pub required: f64,
    /// The value the run achieved (exact J, or a difference of exact J).
    pub actual: f64,
    /// How far below the requirement: `required − actual` (> the tolerance).
    pub shortfall: f64,
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
    /// Where J comes from: `exact (…)`, or `none (no exact oracle for …)`.
    pub source: String,
    /// Relative tolerance of the checks.
    pub tolerance: f64,
    /// Family-wise level of the tests.
    pub alpha: f64,
    /// Iterations the run has completed (all of them unless interrupted).
    pub iterations_done: u64,
    /// Iterations of the whole run.
    pub iterations_total: u64,
    /// Rows of the log audited.
    pub rows: usize,
    /// Rows whose checks were skipped because θᵗ⁺¹ is not logged (`log-every` > 1).
    pub skipped: usize,
    /// The statement the run is judged by.
    pub statement: Statement,
    /// Whether the statement was read from `summary.json` (false: an older summary, or an
    /// unfinished run, whose statement is derived as the module documentation says).
    pub statement_recorded: bool,
    /// The run's own certified bookkeeping, when its summary records it.
    pub self_check: Option<SelfCheck>,
    /// What the self-check tracks: `surplus` (type I) or `budget` (type II).
    pub self_check_quantity: &'static str,
    /// One summary per check, in a fixed order, passing checks included.
    pub checks: Vec<CheckSummary>,
    /// Every failing iteration of every check.
    pub failures: Vec<Violation>,
    /// The verdict.
    pub verdict: Verdict,
    /// Why, in one line.
    pub reason: String,
}

impl AuditReport {
    /// The summary of check `name`, if it was evaluated.
    pub fn check(&self, name: &str) -> Option<&CheckSummary> {
        self.checks.iter().find(|c| c.check == name)
    }

    /// Whether a check the statement covers was rejected by its test (judged
    /// [`Judgement::Broken`] or [`Judgement::Exceeded`]): the run failed what it states,
    /// firmly or approximately.
    pub fn statement_failed(&self) -> bool {
        self.checks
            .iter()
            .any(|c| matches!(c.judgement, Judgement::Broken | Judgement::Exceeded))
    }

    /// The failures of the checks judged [`Judgement::Broken`] or [`Judgement::Exceeded`],
    /// in order of iteration.
    pub fn judged_failures(&self) -> Vec<&Violation> {
        self.failures
            .iter()
            .filter(|f| {
                self.check(f.check)
                    .is_some_and(|c| matches!(c.judgement, Judgement::Broken | Judgement::Exceeded))
            })
            .collect()
    }

    /// The probability, under the run's statement, that an audit at level `alpha` finds it
    /// failed ([`AuditReport::statement_failed`]): 0 for a certainty (exact gradients), δ
    /// for scope `run`, `alpha` for scope `iteration` (the family-wise level of its tests);
    /// `None` when nothing is tested (no statement, no oracle, an unfinished run). The
    /// number of failed runs among independent seeds is then at most Binomial(n, rate).
    pub fn null_rate(&self) -> Option<f64> {
        let tested = matches!(
            self.verdict,
            Verdict::Holds | Verdict::Broken | Verdict::Approximate
        ) && self.checks.iter().any(|c| c.test != Test::Reported);
        if !tested {
            return None;
        }
        Some(match (self.statement.delta, self.statement.scope) {
            (None, _) => 0.0,
            (Some(d), Scope::Run) => d,
            (Some(_), Scope::Iteration) => self.alpha,
        })
    }
}

/// P(X ≥ `failed`) for X ~ Binomial(`runs`, `rate`): the p-value of `failed` broken runs among
/// `runs` independent runs each broken with probability at most `rate` (exact one-sided
/// binomial test; `rate` = 0 gives 1 for no failure and 0 otherwise).
///
/// # Errors
/// [`Error::Invalid`] for `runs` = 0, `failed > runs` or `rate ∉ [0, 1]`.
///
/// ```
/// use sepg_runs::audit::broken_runs_p_value;
/// // 1 broken run of 2 at rate 0.5: P(X ≥ 1) = 0.75.
/// assert!((broken_runs_p_value(1, 2, 0.5)? - 0.75).abs() < 1e-15);
/// # Ok::<(), sepg_runs::Error>(())
/// ```
pub fn broken_runs_p_value(failed: u64, runs: u64, rate: f64) -> Result<f64> {
    upper_tail(failed, runs, rate).map_err(|e| Error::invalid(format!("binomial test: {e}")))
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

/// Exact J of the run's environment.
struct ExactJ {
    oracle: Box<dyn ExactOracle + Send + Sync>,
    horizon: Horizon,
    dim_v: usize,
}

impl ExactJ {
    /// J at the point `v ++ w`; `w` all −∞ is the deterministic policy.
    fn j(&self, point: &[f64]) -> Result<f64> {
        let (v, w) = point.split_at(self.dim_v.min(point.len()));
        let exploration = if w.iter().all(|x| *x == f64::NEG_INFINITY) {
            Exploration::Deterministic
        } else {
            Exploration::Gaussian { w: w.to_vec() }
        };
        let j = self
            .oracle
            .evaluate_with(v, &exploration, self.horizon, Needs::VALUE)
            .map_err(|e| Error::failed(format!("exact J at v = {v:?}, w = {w:?}: {e}")))?
            .j;
        if !j.is_finite() {
            return Err(Error::failed(format!(
                "exact J at v = {v:?}, w = {w:?} is not finite"
            )));
        }
        Ok(j)
    }
}

/// The key of the point (v, w): the bits of `v ++ w`.
fn key(v: &[f64], w: &[f64]) -> Vec<u64> {
    v.iter().chain(w).map(|x| x.to_bits()).collect()
}

/// Exact J at every point of `points` (keys of [`key`]), evaluated in parallel; the first
/// error in key order is returned, so the outcome does not depend on the number of threads.
/// Progress goes to `observer` in units of the audited iterations: `begin(0, iterations)`,
/// then `advance` with the share of the distinct points evaluated so far (at most every
/// [`PROGRESS_EVERY`] points), then `end`.
fn evaluate_all(
    exact: &ExactJ,
    points: Vec<Vec<u64>>,
    iterations: u64,
    observer: &dyn RunObserver,
) -> Result<HashMap<Vec<u64>, f64>> {
    let mut points = points;
    points.sort_unstable();
    points.dedup();
    let total = points.len() as u64;
    observer.begin(0, iterations);
    let done = AtomicU64::new(0);
    let values: Vec<Result<f64>> = points
        .par_iter()
        .map(|k| {
            let point: Vec<f64> = k.iter().map(|b| f64::from_bits(*b)).collect();
            let value = exact.j(&point);
            let n = done.fetch_add(1, Ordering::Relaxed) + 1;
            if n.is_multiple_of(PROGRESS_EVERY) || n == total {
                observer.advance(iterations * n / total.max(1));
            }
            value
        })
        .collect();
    observer.end();
    let mut out = HashMap::with_capacity(points.len());
    for (k, value) in points.into_iter().zip(values) {
        out.insert(k, value?);
    }
    Ok(out)
}

/// Points evaluated between two progress reports of [`evaluate_all`].
const PROGRESS_EVERY: u64 = 64;

/// Where J comes from for the environment of the run, and its label.
fn source(env: &AnyEnv, horizon: usize, dim_v: usize) -> Result<(Option<ExactJ>, String)> {
    let AnyEnv::Lqg(env) = env else {
        return Ok((
            None,
            "none (no exact oracle for this environment)".to_owned(),
        ));
    };
    let model = env.model();
    let (oracle, name): (Box<dyn ExactOracle + Send + Sync>, String) = if model.clipping {
        let o = ClippedDpOracle::with_config(model, audit_dp_config())
            .map_err(|e| Error::failed(e.to_string()))?;
        (
            Box::new(o),
            format!("ClippedDpOracle, {AUDIT_NODES_PER_ELEMENT} nodes per element"),
        )
    } else {
        let o = ClosedFormOracle::new(model).map_err(|e| Error::failed(e.to_string()))?;
        (Box::new(o), "ClosedFormOracle".to_owned())
    };
    let exact = ExactJ {
        oracle,
        horizon: Horizon::Finite(horizon),
        dim_v,
    };
    Ok((Some(exact), format!("exact ({name}, H = {horizon})")))
}

/// The statement a run is judged by, and whether it was recorded (see the module
/// documentation): the summary's, else — for an older summary — the configuration's with
/// scope `iteration` and kind `approximate`, else (an unfinished run) the configuration's.
fn judged_statement(
    summary: Option<&Summary>,
    derived: Statement,
    per_iteration: usize,
) -> (Statement, bool) {
    match summary {
        Some(Summary {
            statement: Some(s), ..
        }) => (s.clone(), true),
        Some(_) if derived.covers != Covers::None => (
            Statement {
                kind: StatementKind::Approximate,
                scope: Scope::Iteration,
                // those runs set every width at δ: an iteration's K statements fail together
                // with probability at most K·δ
                delta: derived
                    .delta
                    .map(|d| (d * per_iteration.max(1) as f64).min(1.0)),
                reasons: vec!["written before statements were recorded".to_owned()],
                ..derived
            },
            false,
        ),
        _ => (derived, false),
    }
}

/// How one check is judged.
#[derive(Debug, Clone, Copy)]
struct Plan {
    name: &'static str,
    test: Test,
    rate: Option<f64>,
}

/// Order in which checks are reported.
const CHECK_ORDER: [&str; 7] = [
    "guarantee-v",
    "guarantee-w",
    "mi",
    "lb-i",
    "budget-exact",
    "budget-target",
    "budget",
];

/// The checks of `requirement` (none for the comparison algorithms) and how `statement`
/// judges them, for `dims` = (l·p, l) parameters and `per_iteration` = K, the number of
/// scalar confidence statements one iteration rests on (the union a per-iteration δ covers).
fn plans(
    requirement: Option<Requirement>,
    statement: &Statement,
    dims: (usize, usize),
    per_iteration: usize,
) -> Vec<Plan> {
    let Some(r) = requirement else {
        return Vec::new();
    };
    let applies = |name: &str| match name {
        "guarantee-v" | "guarantee-w" => true,
        "mi" => r == Requirement::Mi,
        "lb-i" => matches!(r, Requirement::LbI { .. }),
        "budget-exact" => matches!(r, Requirement::LbII | Requirement::Lv | Requirement::Zv),
        "budget-target" => matches!(r, Requirement::Lv | Requirement::Zv),
        _ => r.is_type_two(),
    };
    let stated = statement.kind != StatementKind::None;
    let one_failure = statement.delta.is_none() || statement.scope == Scope::Run;
    let (dv, dw) = dims;
    CHECK_ORDER
        .into_iter()
        .filter(|n| applies(n))
        .map(|name| {
            let promised = stated
                && match name {
                    "budget" => false,
                    "budget-target" => statement.covers == Covers::ExploratoryAndTarget,
                    _ => statement.covers != Covers::None,
                };
            let events = match name {
                "guarantee-v" => dv,
                "guarantee-w" => dw,
                "budget-target" => dv + 2 * dw,
                _ => dv + dw,
            };
            let test = if !promised {
                Test::Reported
            } else if one_failure {
                Test::OneFailure
            } else if matches!(name, "guarantee-v" | "guarantee-w" | "mi") {
                Test::Binomial
            } else {
                Test::FirstFailure
            };
            // A per-iteration δ bounds the union of the iteration's K statements, each at
            // δ/K; a check resting on `events` of them fails with probability at most
            // events·δ/K (δ = 1 promises nothing).
            let rate = matches!(test, Test::Binomial | Test::FirstFailure).then(|| match statement
                .delta
            {
                Some(d) if d < 1.0 => (events as f64 * d / per_iteration.max(1) as f64).min(1.0),
                _ => 1.0,
            });
            Plan { name, test, rate }
        })
        .collect()
}

/// Counts of one check while walking the log.
#[derive(Debug, Clone, Copy, Default)]
struct Tally {
    checked: u64,
    steps: u64,
    failed: u64,
    first: Option<u64>,
    last_failed: Option<u64>,
    streak: u64,
    longest: u64,
    /// Largest shortfall and its iteration.
    worst: Option<(f64, u64)>,
}

/// max(1, |x| for x in xs): the scale of the tolerance of a comparison of these values.
fn scale(xs: &[f64]) -> f64 {
    xs.iter().fold(1.0f64, |m, x| m.max(x.abs()))
}

/// The failures and counts of every check while walking the log.
struct Auditor {
    tolerance: f64,
    tallies: BTreeMap<&'static str, Tally>,
    failures: Vec<Violation>,
}

impl Auditor {
    /// Counts one evaluation of check `name` at iteration `t` over the comparisons
    /// `(required, actual, scale)` (none: the iteration cannot fail, e.g. no step taken);
    /// the iteration fails when a shortfall `required − actual` exceeds `tolerance · scale`,
    /// and the largest such shortfall is recorded.
    fn check(&mut self, t: u64, name: &'static str, comparisons: &[(f64, f64, f64)]) {
        let tally = self.tallies.entry(name).or_default();
        tally.checked += 1;
        let mut failure: Option<Violation> = None;
        for &(required, actual, scale) in comparisons {
            let shortfall = required - actual;
            if tally.worst.is_none_or(|(w, _)| shortfall > w) {
                tally.worst = Some((shortfall, t));
            }
            if shortfall > self.tolerance * scale
                && failure.as_ref().is_none_or(|f| shortfall > f.shortfall)
            {
                failure = Some(Violation {
                    iteration: t,
                    check: name,
                    required,
                    actual,
                    shortfall,
                });
            }
        }
        if let Some(f) = failure {
            tally.failed += 1;
            tally.first.get_or_insert(t);
            tally.streak = match tally.last_failed {
                Some(prev) if prev + 1 == t => tally.streak + 1,
                _ => 1,
            };
            tally.longest = tally.longest.max(tally.streak);
            tally.last_failed = Some(t);
            self.failures.push(f);
        }
    }

    /// Counts a step taken by check `name`.
    fn step(&mut self, name: &'static str) {
        self.tallies.entry(name).or_default().steps += 1;
    }
}

/// One row of the log with the parameters after its update (`None`: not in the log).
struct Step<'r> {
    row: &'r Row,
    next: Option<(Vec<f64>, Vec<f64>)>,
}

/// What the walk needs to know about the run.
struct Walk {
    requirement: Option<Requirement>,
    budget0: f64,
}

impl Walk {
    fn sim(&self) -> bool {
        matches!(self.requirement, Some(Requirement::Sim { .. }))
    }

    /// The points whose exact J the checks of `step` use.
    fn points(&self, step: &Step<'_>, plans: &[Plan], out: &mut Vec<Vec<u64>>) {
        let row = step.row;
        out.push(key(&row.v, &row.w));
        if plans.iter().any(|p| p.name == "budget-target") {
            out.push(key(&row.v, &row.w_target));
        }
        if let Some((v, w)) = &step.next {
            out.push(key(v, &row.w));
            out.push(key(v, w));
            if self.sim() {
                out.push(key(&row.v, w));
            }
        }
    }

    /// Every check of one step, with exact J from `js` and J(θ⁰) = `j0`.
    fn step(
        &self,
        a: &mut Auditor,
        plans: &[Plan],
        step: &Step<'_>,
        js: &HashMap<Vec<u64>, f64>,
        j0: f64,
    ) -> Result<bool> {
        let row = step.row;
        let t = row.iteration;
        let j = |v: &[f64], w: &[f64]| {
            js.get(&key(v, w))
                .copied()
                .ok_or_else(|| Error::failed(format!("exact J at v = {v:?}, w = {w:?} missing")))
        };
        let has = |name: &str| plans.iter().any(|p| p.name == name);
        let floor = j0 - self.budget0;
        if has("budget-target") {
            let jt = j(&row.v, &row.w_target)?;
            a.check(
                t,
                "budget-target",
                &[(floor, jt, scale(&[j0, jt, self.budget0]))],
            );
        }
        if has("budget") {
            a.check(t, "budget", &[(0.0, row.budget, 1.0)]);
        }
        let Some((v_next, w_next)) = &step.next else {
            return Ok(false);
        };
        if plans
            .iter()
            .all(|p| matches!(p.name, "budget" | "budget-target"))
        {
            return Ok(true);
        }
        let j_t = j(&row.v, &row.w)?;
        let j_mid = j(v_next, &row.w)?;
        let j_next = j(v_next, w_next)?;
        if has("guarantee-v") {
            let taken = row.alpha != 0.0;
            if taken {
                a.step("guarantee-v");
            }
            let comps: Vec<(f64, f64, f64)> = row
                .guaranteed_v
                .filter(|_| taken)
                .map(|g| (g, j_mid - j_t, scale(&[j_mid, j_t])))
                .into_iter()
                .collect();
            a.check(t, "guarantee-v", &comps);
        }
        if has("guarantee-w") {
            let taken = row.beta != 0.0;
            if taken {
                a.step("guarantee-w");
            }
            let (from, to) = if self.sim() {
                (j_t, j(&row.v, w_next)?)
            } else {
                (j_mid, j_next)
            };
            let comps: Vec<(f64, f64, f64)> = row
                .guaranteed_w
                .filter(|_| taken)
                .map(|g| (g, to - from, scale(&[to, from])))
                .into_iter()
                .collect();
            a.check(t, "guarantee-w", &comps);
        }
        if has("mi") {
            let s = scale(&[j_t, j_mid, j_next]);
            a.check(t, "mi", &[(j_t, j_mid, s), (j_mid, j_next, s)]);
        }
        for (name, required) in [("lb-i", j0), ("budget-exact", floor)] {
            if has(name) {
                let s = scale(&[j0, j_mid, j_next, self.budget0]);
                a.check(t, name, &[(required, j_mid, s), (required, j_next, s)]);
            }
        }
        Ok(true)
    }
}

/// The summaries of the checks of `plans` that were evaluated, judged at family-wise level
/// `alpha` (Bonferroni over the tested checks) under a statement of kind `kind`.
fn judge(
    plans: &[Plan],
    tallies: &BTreeMap<&'static str, Tally>,
    kind: StatementKind,
    alpha: f64,
) -> Result<Vec<CheckSummary>> {
    let tested = plans
        .iter()
        .filter(|p| matches!(p.test, Test::Binomial | Test::FirstFailure))
        .count()
        .max(1);
    let level = alpha / tested as f64;
    let mut out = Vec::new();
    for plan in plans {
        let Some(t) = tallies.get(plan.name) else {
            continue;
        };
        let rate = plan.rate.unwrap_or(0.0);
        let (p_value, rejected) = match plan.test {
            Test::OneFailure => (None, t.failed > 0),
            Test::Reported => (None, false),
            Test::Binomial => {
                let p = if t.checked == 0 {
                    1.0
                } else {
                    upper_tail(t.failed, t.checked, rate).map_err(|e| {
                        Error::failed(format!("binomial test of {}: {e}", plan.name))
                    })?
                };
                (Some(p), p < level)
            }
            Test::FirstFailure => {
                let p = t
                    .first
                    .map_or(1.0, |first| ((first as f64 + 1.0) * rate).min(1.0));
                (Some(p), p < level)
            }
        };
        let judgement = match (plan.test, rejected, kind) {
            (Test::Reported, _, _) => Judgement::Note,
            (_, false, _) => Judgement::Holds,
            (_, true, StatementKind::Proven) => Judgement::Broken,
            (_, true, _) => Judgement::Exceeded,
        };
        let guarantee = plan.name.starts_with("guarantee-");
        out.push(CheckSummary {
            check: plan.name,
            test: plan.test,
            checked: t.checked,
            steps: guarantee.then_some(t.steps),
            failed: t.failed,
            first_failure: t.first,
            longest_run: t.longest,
            worst_shortfall: t.worst.map_or(0.0, |w| w.0),
            worst_iteration: t.worst.map_or(0, |w| w.1),
            allowed_rate: plan.rate,
            p_value,
            judgement,
        });
    }
    Ok(out)
}

/// Runs the audit of `dir` (no printing): checks against exact J with relative tolerance
/// `tolerance` ([`DEFAULT_TOLERANCE`] is the command line's default), tests at family-wise
/// level `alpha` ([`DEFAULT_ALPHA`]).
///
/// # Errors
/// [`Error::Invalid`] for a folder that is not a readable run, a malformed or incomplete log
/// (see the module documentation) or a tolerance or level out of range; [`Error::Failed`]
/// when the oracle cannot evaluate a logged policy.
pub fn audit(dir: &Path, tolerance: f64, alpha: f64) -> Result<AuditReport> {
    audit_observed(dir, tolerance, alpha, &Silent)
}

/// [`audit`], reporting its progress to `observer` (the exact-J evaluations, in audited
/// iterations; they run in parallel on the rayon pool, and the report is the same bit for bit
/// whatever the number of threads).
///
/// # Errors
/// As [`audit`].
pub fn audit_observed(
    dir: &Path,
    tolerance: f64,
    alpha: f64,
    observer: &dyn RunObserver,
) -> Result<AuditReport> {
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
    let (exact, source_name) = source(&config.env, config.horizon, resolved.dims.0)?;
    let requirement = match config.algorithm {
        Algorithm::Sepg(r) | Algorithm::SepgNaiveW(r) => Some(r),
        _ => None,
    };
    let gradients = match config.gradient {
        GradientMode::Exact => "exact".to_owned(),
        GradientMode::Sampled { delta } => format!("sampled (δ = {delta})"),
    };
    let per_iteration = sepg_algo::solver::statements_per_iteration(
        config.algorithm,
        &config.options,
        resolved.dims,
    );
    let (statement, statement_recorded) = judged_statement(
        progress.summary.as_ref(),
        resolved.checked.statement(),
        per_iteration,
    );
    let statement = statement.checked_against(&progress.constants_check);
    if let Some(d) = statement.delta
        && !(d > 0.0 && d < 1.0)
    {
        return Err(bad(
            dir,
            format!("{SUMMARY_FILE}: the statement's delta {d} is not in (0, 1)"),
        ));
    }
    let self_check = progress.summary.as_ref().and_then(|s| s.self_check);
    let mut plans = plans(requirement, &statement, resolved.dims, per_iteration);
    if exact.is_none() {
        // Without exact J only the run's own bookkeeping can be read from the log.
        plans.retain(|p| p.name == "budget");
    }
    let steps: Vec<Step<'_>> = rows
        .iter()
        .enumerate()
        .map(|(k, row)| {
            let t = row.iteration;
            let next = match rows.get(k + 1) {
                Some(n) if n.iteration == t + 1 => Some((n.v.clone(), n.w.clone())),
                Some(_) => None,
                None => (t + 1 == progress.done)
                    .then(|| (progress.last.v.clone(), progress.last.w.clone())),
            };
            Step { row, next }
        })
        .collect();
    let walk = Walk {
        requirement,
        budget0: config.initial_budget,
    };
    let mut points = Vec::new();
    if exact.is_some() {
        for step in &steps {
            walk.points(step, &plans, &mut points);
        }
    }
    let js = match &exact {
        Some(e) => evaluate_all(e, points, rows.len() as u64, observer)?,
        None => HashMap::new(),
    };
    let mut auditor = Auditor {
        tolerance,
        tallies: BTreeMap::new(),
        failures: Vec::new(),
    };
    let j0 = rows
        .first()
        .and_then(|r| js.get(&key(&r.v, &r.w)).copied())
        .unwrap_or(0.0);
    let mut skipped = 0;
    for step in &steps {
        if !walk.step(&mut auditor, &plans, step, &js, j0)? {
            skipped += 1;
        }
    }
    auditor.failures.sort_by_key(|f| f.iteration);
    let checks = judge(&plans, &auditor.tallies, statement.kind, alpha)?;
    let (mut verdict, mut reason) = verdict(
        &checks,
        &auditor.failures,
        &statement,
        (progress.done, progress.complete),
        exact.is_some(),
    );
    if let Some(why) = progress.constants_check.reason() {
        // data that refute the constants void every bound: never "holds"
        (verdict, reason) = (
            Verdict::NoGuarantee,
            format!("the run states nothing about exact J: {why}"),
        );
    }
    let type_one = requirement.is_some_and(|r| !r.is_type_two());
    Ok(AuditReport {
        dir: dir.display().to_string(),
        algorithm: algorithm_name(&resolved.spec),
        gradients,
        source: source_name,
        tolerance,
        alpha,
        iterations_done: progress.done,
        iterations_total: total,
        rows: rows.len(),
        skipped,
        statement,
        statement_recorded,
        self_check,
        self_check_quantity: if type_one { "surplus" } else { "budget" },
        checks,
        failures: auditor.failures,
        verdict,
        reason,
    })
}

/// The verdict and its reason (see the module documentation), from the judged checks, the
/// statement, the iterations done and whether the run finished, and whether J is exact.
fn verdict(
    checks: &[CheckSummary],
    failures: &[Violation],
    statement: &Statement,
    (done, complete): (u64, bool),
    exact: bool,
) -> (Verdict, String) {
    let first_broken = checks
        .iter()
        .filter(|c| c.judgement == Judgement::Broken)
        .min_by_key(|c| c.first_failure.unwrap_or(u64::MAX));
    if let Some(c) = first_broken {
        let first = failures.iter().find(|f| f.check == c.check);
        let why = match (c.test, first) {
            (Test::OneFailure, Some(f)) => format!(
                "{} failed against exact J at iteration {} (shortfall {:.3e}); one exact \
                 violation breaks {}",
                c.check,
                f.iteration,
                f.shortfall,
                if statement.delta.is_none() {
                    "a certain statement"
                } else {
                    "a run-level statement"
                }
            ),
            _ => format!(
                "{} failed at {} of {} iterations (first {}), p = {:.3e}: more than the \
                 statement's per-iteration probability allows",
                c.check,
                c.failed,
                c.checked,
                c.first_failure.unwrap_or_default(),
                c.p_value.unwrap_or(0.0)
            ),
        };
        return (Verdict::Broken, format!("the run broke its promise: {why}"));
    }
    if !complete {
        return (
            Verdict::Incomplete,
            format!("no broken check in the {done} iterations done, but the run has not finished"),
        );
    }
    if !exact {
        return (
            Verdict::NotChecked,
            "no exact oracle for this environment: not checked against exact J".to_owned(),
        );
    }
    let reasons = if statement.reasons.is_empty() {
        String::new()
    } else {
        format!(" ({})", statement.reasons.join("; "))
    };
    match statement.kind {
        StatementKind::Proven => (
            Verdict::Holds,
            "every check the proven statement covers held against exact J".to_owned(),
        ),
        StatementKind::Approximate => {
            let exceeded = checks
                .iter()
                .filter(|c| c.judgement == Judgement::Exceeded)
                .count();
            (
                Verdict::Approximate,
                format!(
                    "the statement is approximate{reasons}: {exceeded} check(s) exceeded what it \
                     states; an approximate statement is never called \"holds\""
                ),
            )
        }
        StatementKind::None => (
            Verdict::NoGuarantee,
            format!("the run states nothing about exact J{reasons}"),
        ),
    }
}

/// The serialised name of a statement field (`proven`, `run`, `exploratory`, …).
fn kebab<T: Serialize>(x: &T) -> String {
    serde_json::to_value(x)
        .ok()
        .and_then(|v| v.as_str().map(str::to_owned))
        .unwrap_or_default()
}

fn fmt(x: f64) -> String {
    format!("{x:.6e}")
}

/// Rows of failures the table lists; `--json` carries all of them.
const LISTED: usize = 20;

/// The line of the run's own bookkeeping, when it says the run broke its requirement.
fn self_check_line(report: &AuditReport) -> Option<String> {
    let s = report.self_check.filter(|s| s.broken)?;
    Some(format!(
        "self-check: the run's own bookkeeping says its {} went to {} at iteration {}",
        report.self_check_quantity,
        s.value
            .map_or_else(|| "below zero".to_owned(), |v| format!("{v:.1e}")),
        s.first_iteration
            .map_or_else(|| "?".to_owned(), |t| t.to_string())
    ))
}

/// The human-readable report: the header and statement, one line per check (passing checks
/// included), the failing iterations of the judged checks, notes, the run's own
/// bookkeeping, and the verdict.
pub fn render(report: &AuditReport) -> String {
    let mut s = String::new();
    let st = &report.statement;
    let _ = writeln!(s, "audit of {}", report.dir);
    let _ = writeln!(s, "algorithm: {}", report.algorithm);
    let _ = writeln!(s, "gradients: {}", report.gradients);
    let _ = writeln!(s, "J from:    {}", report.source);
    let _ = writeln!(
        s,
        "tolerance: {:e} · max(1, |J|), alpha {}",
        report.tolerance, report.alpha
    );
    let _ = writeln!(
        s,
        "statement: {}, scope {}, δ = {}, covers {} ({})",
        kebab(&st.kind),
        kebab(&st.scope),
        st.delta.map_or_else(
            || match st.kind {
                StatementKind::None => "-".to_owned(),
                _ => "none (certain)".to_owned(),
            },
            |d| d.to_string()
        ),
        kebab(&st.covers),
        if report.statement_recorded {
            "recorded"
        } else {
            "derived"
        }
    );
    let _ = writeln!(s, "promise:   {}", st.requirement);
    if !st.reasons.is_empty() {
        let _ = writeln!(s, "reasons:   {}", st.reasons.join("; "));
    }
    let _ = writeln!(
        s,
        "{} of {} iterations done, {} rows, {} skipped (next parameters not logged)",
        report.iterations_done, report.iterations_total, report.rows, report.skipped
    );
    let _ = writeln!(
        s,
        "{:<13} {:<11} {:>8} {:>6} {:>7} {:>6} {:>7} {:>14} {:>7} {:>9} {:>10}  judgement",
        "check",
        "test",
        "checked",
        "steps",
        "failed",
        "first",
        "longest",
        "worst shortf.",
        "at",
        "allowed",
        "p-value"
    );
    let dash = |x: Option<String>| x.unwrap_or_else(|| "-".to_owned());
    for c in &report.checks {
        let _ = writeln!(
            s,
            "{:<13} {:<11} {:>8} {:>6} {:>7} {:>6} {:>7} {:>14} {:>7} {:>9} {:>10}  {}",
            c.check,
            c.test.label(),
            c.checked,
            dash(c.steps.map(|x| x.to_string())),
            c.failed,
            dash(c.first_failure.map(|x| x.to_string())),
            c.longest_run,
            fmt(c.worst_shortfall),
            c.worst_iteration,
            dash(c.allowed_rate.map(|x| format!("{x:.3e}"))),
            dash(c.p_value.map(|x| format!("{x:.3e}"))),
            c.judgement.label()
        );
    }
    let judged = report.judged_failures();
    if !judged.is_empty() {
        let _ = writeln!(
            s,
            "{:>10}  {:<13} {:>14} {:>14} {:>14}",
            "iteration", "check", "required", "actual", "shortfall"
        );
        for v in judged.iter().take(LISTED) {
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
        if judged.len() > LISTED {
            let _ = writeln!(
                s,
                "... {} more failing iterations (--json lists all)",
                judged.len() - LISTED
            );
        }
    }
    for c in report
        .checks
        .iter()
        .filter(|c| c.judgement == Judgement::Note && c.failed > 0)
    {
        let _ = writeln!(
            s,
            "note: {} failed at {} of {} iterations (first {}); it is not promised by the \
             statement, so it is reported only",
            c.check,
            c.failed,
            c.checked,
            c.first_failure.unwrap_or_default()
        );
    }
    if let Some(line) = self_check_line(report) {
        let _ = writeln!(s, "{line}");
    }
    let _ = writeln!(s, "{}: {}", report.verdict.name(), report.reason);
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

    fn exact(model: &LqgModel) -> ExactJ {
        ExactJ {
            oracle: Box::new(
                ClippedDpOracle::with_config(model, audit_dp_config()).expect("a DP exists"),
            ),
            horizon: Horizon::Finite(H),
            dim_v: 1,
        }
    }

    /// Exact J of N(v s, e^{2w}) on the clipped `lqg` preset, from the oracle called
    /// directly (not through the audit's walk).
    fn j(v: f64, w: f64) -> f64 {
        ClippedDpOracle::with_config(&LqgModel::thesis(), audit_dp_config())
            .expect("a DP exists")
            .evaluate(
                &[v],
                &Exploration::Gaussian { w: vec![w] },
                Horizon::Finite(H),
            )
            .expect("exact J")
            .j
    }

    /// A logged row at θ = (v, w) (target: the deterministic policy).
    fn row(t: u64, v: f64, w: f64, guaranteed_w: Option<f64>) -> Row {
        Row {
            iteration: t,
            v: vec![v],
            w: vec![w],
            w_target: vec![f64::NEG_INFINITY],
            budget: 0.0,
            alpha: 1.0,
            beta: 1.0,
            guaranteed_v: None,
            guaranteed_w,
        }
    }

    fn statement(
        kind: StatementKind,
        scope: Scope,
        delta: Option<f64>,
        covers: Covers,
    ) -> Statement {
        Statement {
            kind,
            scope,
            delta,
            covers,
            requirement: String::new(),
            reasons: Vec::new(),
        }
    }

    /// Walks the rows `path[k] → path[k + 1]` (w-steps to `w_next[k]`) of requirement `r`
    /// with B⁰ = `budget0` through the audit and returns its tallies and failures.
    fn walk(
        r: Requirement,
        budget0: f64,
        rows: &[Row],
        next: &[(f64, f64)],
    ) -> (BTreeMap<&'static str, Tally>, Vec<Violation>) {
        let s = statement(StatementKind::Proven, Scope::Run, None, Covers::Exploratory);
        let plans = plans(Some(r), &s, (1, 1), 2);
        let walk = Walk {
            requirement: Some(r),
            budget0,
        };
        let steps: Vec<Step<'_>> = rows
            .iter()
            .zip(next)
            .map(|(row, &(v, w))| Step {
                row,
                next: Some((vec![v], vec![w])),
            })
            .collect();
        let mut points = Vec::new();
        for s in &steps {
            walk.points(s, &plans, &mut points);
        }
        let js = evaluate_all(&exact(&LqgModel::thesis()), points, 1, &Silent).expect("exact J");
        let j0 = js[&key(&rows[0].v, &rows[0].w)];
        let mut a = Auditor {
            tolerance: DEFAULT_TOLERANCE,
            tallies: BTreeMap::new(),
            failures: Vec::new(),
        };
        for s in &steps {
            walk.step(&mut a, &plans, s, &js, j0).expect("walk");
        }
        (a.tallies, a.failures)
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
        // which LB-I allows; a θ³ = V_LOW + 0.1 below J(θ⁰) breaks it.
        let below = V_LOW + 0.1;
        assert!(j(below, w()) < j(V_LOW, w()));
        let path = [V_LOW, V_HIGH, V_MID, below];
        let rows: Vec<Row> = (0..3)
            .map(|t| row(t, path[t as usize], w(), None))
            .collect();
        let next: Vec<(f64, f64)> = path[1..].iter().map(|v| (*v, w())).collect();
        let (tallies, failures) = walk(Requirement::LbI { nu: 0.5 }, 0.0, &rows, &next);
        let t = tallies["lb-i"];
        assert_eq!((t.checked, t.failed), (3, 1));
        assert_eq!(t.worst.expect("worst").0, j(V_LOW, w()) - j(below, w()));
        let its: Vec<u64> = failures.iter().map(|f| f.iteration).collect();
        assert_eq!(its, [2]);
    }

    #[test]
    fn budget_exact_telescopes_from_the_first_j() {
        // LB-II, B⁰ = 0: the floor is J(θ⁰) at both points of every iteration, however J
        // moved in between. θ⁰ = V_LOW, θ¹ = V_HIGH, θ² = V_MID: it holds although J falls at
        // row 1.
        let rows = [row(0, V_LOW, w(), None), row(1, V_HIGH, w(), None)];
        let (tallies, _) = walk(
            Requirement::LbII,
            0.0,
            &rows,
            &[(V_HIGH, w()), (V_MID, w())],
        );
        let t = tallies["budget-exact"];
        assert_eq!((t.checked, t.failed), (2, 0));
        let j0 = j(V_LOW, w());
        let smallest = (j(V_HIGH, w()) - j0).min(j(V_MID, w()) - j0);
        assert_eq!(t.worst.expect("worst").0, -smallest);
        // B⁰ = 0 and a first v-step that loses: broken from row 0 on; a budget B⁰ larger
        // than the loss covers it.
        let rows = [row(0, V_MID, w(), None)];
        let loss = j(V_MID, w()) - j(V_LOW, w());
        let (tallies, _) = walk(Requirement::LbII, 0.0, &rows, &[(V_LOW, w())]);
        assert_eq!(tallies["budget-exact"].failed, 1);
        let (tallies, _) = walk(Requirement::LbII, loss * 1.01, &rows, &[(V_LOW, w())]);
        assert_eq!(tallies["budget-exact"].failed, 0);
    }

    #[test]
    fn the_floors_are_checked_after_the_v_step_too() {
        // θ⁰ = (V_MID, w); the v-step goes to V_LOW (J falls), the w-step to the σ of the
        // grid that raises J(V_LOW, ·) most. With B⁰ putting the floor J(θ⁰) − B⁰ above
        // J(θ⁰⁺½) and below J(θ¹), the point after the v-step breaks LB-II although θ¹ does
        // not.
        let w_back = (0..40)
            .map(|i| w() - 3.0 + 0.1 * f64::from(i))
            .max_by(|a, b| j(V_LOW, *a).total_cmp(&j(V_LOW, *b)))
            .expect("a grid");
        let (j0, j_mid, j_next) = (j(V_MID, w()), j(V_LOW, w()), j(V_LOW, w_back));
        assert!(j_mid + 1e-3 < j0.min(j_next), "{j_mid} {j_next} {j0}");
        let floor = 0.5 * (j_mid + j0.min(j_next));
        let budget0 = j0 - floor;
        let rows = [row(0, V_MID, w(), None)];
        let (tallies, failures) = walk(Requirement::LbII, budget0, &rows, &[(V_LOW, w_back)]);
        assert_eq!(tallies["budget-exact"].failed, 1);
        assert_eq!(failures[0].actual, j_mid);
        assert_eq!(failures[0].required, j0 - budget0);
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
            let rows = [row(0, V_LOW, w(), Some(g))];
            let (tallies, _) = walk(Requirement::LbI { nu: 0.5 }, 0.0, &rows, &[(V_HIGH, w1)]);
            let t = tallies["guarantee-w"];
            assert_eq!((t.checked, t.failed), (1, failed), "guarantee {g}");
            assert_eq!(t.worst.expect("worst").0, g - gain_w);
        }
    }

    #[test]
    fn a_guarantee_is_counted_at_every_iteration_but_fails_only_when_its_step_was_taken() {
        // Two iterations claim a v-improvement of 100 they do not deliver; only the first
        // took its step (α ≠ 0).
        let mut rows = [row(0, V_LOW, w(), None), row(1, V_MID, w(), None)];
        rows[0].guaranteed_v = Some(100.0);
        rows[1].guaranteed_v = Some(100.0);
        rows[1].alpha = 0.0;
        let (tallies, _) = walk(Requirement::Mi, 0.0, &rows, &[(V_MID, w()), (V_MID, w())]);
        let t = tallies["guarantee-v"];
        assert_eq!((t.checked, t.steps, t.failed), (2, 1, 1));
    }

    /// P(X ≥ k) for X ~ Binomial(n, p) summed term by term in f64 (each term from exact
    /// binomial coefficients and powers; relative error below n·1e-15 for n ≤ 1000).
    fn tail_by_sum(k: u64, n: u64, p: f64) -> f64 {
        let ln_choose =
            |n: u64, i: u64| -> f64 { (1..=i).map(|j| ((n - i + j) as f64 / j as f64).ln()).sum() };
        (k..=n)
            .map(|i| (ln_choose(n, i) + i as f64 * p.ln() + (n - i) as f64 * (1.0 - p).ln()).exp())
            .sum()
    }

    fn tally(checked: u64, steps: u64, failed: u64, first: Option<u64>) -> Tally {
        Tally {
            checked,
            steps,
            failed,
            first,
            worst: Some((1.0, first.unwrap_or(0))),
            ..Tally::default()
        }
    }

    #[test]
    fn a_per_step_check_of_scope_iteration_divides_by_iterations_not_steps() {
        // δ = 0.2 per width, two widths (v and w) per iteration: the statement's δ is 0.4.
        // 20 failures among 40 steps taken in 300 iterations: the per-step rate 0.5 would be
        // rejected (P(Bin(40, 0.2) ≥ 20) < 1e-4), the per-iteration rate 0.067 is what δ
        // allows.
        let s = statement(
            StatementKind::Proven,
            Scope::Iteration,
            Some(0.4),
            Covers::Exploratory,
        );
        let plans = plans(Some(Requirement::Mi), &s, (1, 1), 2);
        let tests: Vec<(&str, Test, Option<f64>)> =
            plans.iter().map(|p| (p.name, p.test, p.rate)).collect();
        assert_eq!(
            tests,
            [
                ("guarantee-v", Test::Binomial, Some(0.2)),
                ("guarantee-w", Test::Binomial, Some(0.2)),
                ("mi", Test::Binomial, Some(0.4)),
            ]
        );
        assert!(tail_by_sum(20, 40, 0.2) < 1e-4);
        let judged = |failed: u64, kind| {
            let mut tallies = BTreeMap::new();
            tallies.insert("guarantee-v", tally(300, 40, failed, Some(3)));
            judge(&plans, &tallies, kind, 0.01).expect("judged")[0].clone()
        };
        let c = judged(20, StatementKind::Proven);
        let p = c.p_value.expect("p");
        assert!((p - tail_by_sum(20, 300, 0.2)).abs() <= 1e-12 * p, "{p}");
        assert_eq!(c.judgement, Judgement::Holds);
        assert_eq!((c.checked, c.steps), (300, Some(40)));
        // 90 failing iterations of 300: P(Bin(300, 0.2) ≥ 90) is below 0.01/3 (three
        // tested checks, Bonferroni).
        let c = judged(90, StatementKind::Proven);
        let p = c.p_value.expect("p");
        assert!((p - tail_by_sum(90, 300, 0.2)).abs() <= 1e-12 * p, "{p}");
        assert!(p < 0.01 / 3.0);
        assert_eq!(c.judgement, Judgement::Broken);
        // The same under an approximate statement is reported, not broken.
        assert_eq!(
            judged(90, StatementKind::Approximate).judgement,
            Judgement::Exceeded
        );
        // The boundary: the smallest count the test rejects is the first k whose tail is
        // below α/3 by the term-by-term sum.
        let k_min = (0..=300)
            .find(|&k| tail_by_sum(k, 300, 0.2) < 0.01 / 3.0)
            .expect("k");
        assert_eq!(
            judged(k_min, StatementKind::Proven).judgement,
            Judgement::Broken
        );
        assert_eq!(
            judged(k_min - 1, StatementKind::Proven).judgement,
            Judgement::Holds
        );
    }

    #[test]
    fn a_floor_of_scope_iteration_is_tested_by_its_first_failure() {
        let s = statement(
            StatementKind::Proven,
            Scope::Iteration,
            Some(2e-4),
            Covers::Exploratory,
        );
        let plans = plans(Some(Requirement::LbII), &s, (1, 1), 2);
        let floor = plans
            .iter()
            .find(|p| p.name == "budget-exact")
            .expect("plan");
        assert_eq!((floor.test, floor.rate), (Test::FirstFailure, Some(2e-4)));
        // Widths at δ = 1e-4, two per iteration: P(first failure ≤ t) ≤ (t + 1)·2δ: a failure from iteration 9 on (p = 2e-3) is
        // below 0.01/3; one from iteration 49 (p = 1e-2) is not, however long it lasts.
        for (first, judgement) in [(9, Judgement::Broken), (49, Judgement::Holds)] {
            let mut tallies = BTreeMap::new();
            tallies.insert("budget-exact", tally(300, 0, 300 - first, Some(first)));
            let c = judge(&plans, &tallies, StatementKind::Proven, 0.01).expect("judged");
            assert_eq!(c[0].judgement, judgement, "{first}");
            let expected = (first as f64 + 1.0) * 2e-4;
            assert!((c[0].p_value.expect("p") - expected).abs() < 1e-15);
        }
    }

    #[test]
    fn each_statement_promises_exactly_its_checks() {
        let names = |r, s: &Statement| -> Vec<(&str, Test)> {
            plans(Some(r), s, (1, 1), 2)
                .iter()
                .map(|p| (p.name, p.test))
                .collect()
        };
        let run = statement(
            StatementKind::Proven,
            Scope::Run,
            Some(0.2),
            Covers::Exploratory,
        );
        // ZV: its deterministic target and the recorded budget are reported only.
        assert_eq!(
            names(Requirement::Zv, &run),
            [
                ("guarantee-v", Test::OneFailure),
                ("guarantee-w", Test::OneFailure),
                ("budget-exact", Test::OneFailure),
                ("budget-target", Test::Reported),
                ("budget", Test::Reported),
            ]
        );
        // LV covers its target.
        let lv = Statement {
            covers: Covers::ExploratoryAndTarget,
            ..run.clone()
        };
        assert!(names(Requirement::Lv, &lv).contains(&("budget-target", Test::OneFailure)));
        // Exact gradients (δ = null) are a certainty: one failure, whatever the scope.
        let certain = statement(
            StatementKind::Proven,
            Scope::Iteration,
            None,
            Covers::Exploratory,
        );
        assert!(
            names(Requirement::Mi, &certain)
                .iter()
                .all(|(_, t)| *t == Test::OneFailure)
        );
        // Kind none promises nothing; the comparison algorithms have no checks.
        let none = statement(
            StatementKind::None,
            Scope::Run,
            Some(0.2),
            Covers::Exploratory,
        );
        assert!(
            names(Requirement::LbI { nu: 0.5 }, &none)
                .iter()
                .all(|(_, t)| *t == Test::Reported)
        );
        assert!(plans(None, &run, (1, 1), 2).is_empty());
    }

    #[test]
    fn older_summaries_are_read_as_approximate_per_iteration_statements() {
        let derived = statement(
            StatementKind::None,
            Scope::Run,
            Some(0.2),
            Covers::Exploratory,
        );
        let summary: Summary = serde_json::from_value(serde_json::json!({
            "status": "complete", "name": "r", "sepg_version": "0", "iterations": 1,
            "final": {"v": [0.0], "w": [0.0], "sigma": [1.0], "budget": 0.0},
            "v_star": null, "abs_v_error": null, "last_j_explore": null, "last_j_target": null,
            "infeasible_iterations": 0, "below_noise_v_iterations": 0,
            "below_noise_w_iterations": 0, "trajectories": 0, "steps": 0, "wall_time_s": 0.0,
            "iterations_per_s": 0.0, "env_steps_per_s": 0.0
        }))
        .expect("an older summary");
        // δ = 0.2 per width, two widths per iteration: 0.4 per iteration.
        let (s, recorded) = judged_statement(Some(&summary), derived.clone(), 2);
        assert!(!recorded);
        assert_eq!(
            (s.kind, s.scope, s.delta),
            (StatementKind::Approximate, Scope::Iteration, Some(0.4))
        );
        assert_eq!(s.reasons, ["written before statements were recorded"]);
        // A run that promises nothing (SIM-ν, the comparison algorithms) still promises
        // nothing.
        let nothing = Statement {
            covers: Covers::None,
            ..derived
        };
        let (s, _) = judged_statement(Some(&summary), nothing, 2);
        assert_eq!(s.kind, StatementKind::None);
    }

    #[test]
    fn the_verdict_follows_the_statement_and_a_broken_check_comes_first() {
        let check = |judgement| CheckSummary {
            check: "mi",
            test: Test::OneFailure,
            checked: 1,
            steps: None,
            failed: u64::from(judgement != Judgement::Holds),
            first_failure: None,
            longest_run: 0,
            worst_shortfall: 0.0,
            worst_iteration: 0,
            allowed_rate: None,
            p_value: None,
            judgement,
        };
        let st = |kind| statement(kind, Scope::Run, Some(0.2), Covers::Exploratory);
        let v =
            |j, kind, complete, exact| verdict(&[check(j)], &[], &st(kind), (3, complete), exact).0;
        use StatementKind::{Approximate, None as NoKind, Proven};
        assert_eq!(v(Judgement::Holds, Proven, true, true), Verdict::Holds);
        assert_eq!(v(Judgement::Broken, Proven, false, true), Verdict::Broken);
        assert_eq!(
            v(Judgement::Holds, Proven, false, true),
            Verdict::Incomplete
        );
        assert_eq!(
            v(Judgement::Holds, Proven, true, false),
            Verdict::NotChecked
        );
        assert_eq!(
            v(Judgement::Holds, Approximate, true, true),
            Verdict::Approximate
        );
        assert_eq!(
            v(Judgement::Exceeded, Approximate, true, true),
            Verdict::Approximate
        );
        assert_eq!(v(Judgement::Note, NoKind, true, true), Verdict::NoGuarantee);
    }

    #[test]
    fn exact_j_does_not_depend_on_the_number_of_threads() {
        let points: Vec<Vec<u64>> = (0..24)
            .map(|i| key(&[-1.2 + 0.05 * f64::from(i)], &[w() + 0.01 * f64::from(i)]))
            .collect();
        let e = exact(&LqgModel::lqg1d());
        let many = evaluate_all(&e, points.clone(), 24, &Silent).expect("J");
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .expect("pool");
        let one = pool
            .install(|| evaluate_all(&e, points, 24, &Silent))
            .expect("J");
        assert_eq!(many, one);
    }

    /// The audit's DP against a much finer one (24 nodes, 2.5 times narrower elements, 16
    /// quadrature points) on differences J(θ + h) − J(θ): near the optima of both presets
    /// (the starts of the review), at small σ, and where the default resolution errs most
    /// (closed loops near expansion, v > 0). The error must stay 10 times below the
    /// tolerance, and the tolerance must let a failure of 1e-9 be seen.
    #[test]
    fn the_tolerance_exceeds_the_oracles_error_on_differences() {
        let reference = DpConfig {
            nodes_per_element: 24,
            elements_per_scale: 2.5,
            min_elements: 32,
            max_elements: 16_000,
            quad_points: 16,
        };
        let cases: [(&str, f64, f64, f64, f64); 12] = [
            ("lqg", -1.122_111_597_656_494_6, 2.0, 1e-5, 0.0),
            ("lqg", -0.615, 0.5, 1e-7, 0.0),
            ("lqg", -0.6, 0.05, 0.0, 1e-4),
            ("lqg", 0.1858, 0.3491, 0.0, 0.31),
            ("lqg", 0.0373, 0.0223, 4e-3, 0.0),
            ("lqg", 0.0474, 0.3889, 0.0, 6e-3),
            ("lqg1d", -0.608_896_117_584_795_6, 1.0, 1e-6, 0.0),
            ("lqg1d", -0.1, 1.0, 0.0, 1e-3),
            ("lqg1d", 0.1286, 0.4935, 0.0, -5.5e-4),
            ("lqg1d", -0.0189, 1.3377, 0.42, 0.0),
            ("lqg1d", 0.1502, 0.8124, -2.9e-2, 0.0),
            ("lqg1d", 0.0797, 0.0298, 0.0, 1.6e-2),
        ];
        let mut largest_tolerance: f64 = 0.0;
        for (preset, v, sigma, dv, dw) in cases {
            let model = if preset == "lqg" {
                LqgModel::thesis()
            } else {
                LqgModel::lqg1d()
            };
            let audit_oracle = exact(&model);
            let fine = ExactJ {
                oracle: Box::new(ClippedDpOracle::with_config(&model, reference).expect("DP")),
                horizon: Horizon::Finite(H),
                dim_v: 1,
            };
            let (a, b) = ([v, sigma.ln()], [v + dv, sigma.ln() + dw]);
            let d_audit = audit_oracle.j(&b).expect("J") - audit_oracle.j(&a).expect("J");
            let (ja, jb) = (fine.j(&a).expect("J"), fine.j(&b).expect("J"));
            let tolerance = DEFAULT_TOLERANCE * scale(&[ja, jb]);
            largest_tolerance = largest_tolerance.max(tolerance);
            let error = (d_audit - (jb - ja)).abs();
            assert!(
                error <= tolerance / 10.0,
                "{preset} v = {v} σ = {sigma} ({dv}, {dw}): error {error:e}, tol. {tolerance:e}"
            );
        }
        assert!(largest_tolerance < 1e-9 / 2.0, "{largest_tolerance:e}");
    }
}
