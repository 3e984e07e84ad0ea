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
//! J is recomputed for every logged point with
//! [`ClippedDpOracle`](sepg_mdp::oracle::ClippedDpOracle) at [`audit_dp_config`]
//! (the clipped `lqg`, `lqg1d` presets) or
//! [`ClosedFormOracle`](sepg_mdp::oracle::ClosedFormOracle) (unclipped models), in
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
//! bookkeeping ([`SelfCheck`](sepg_algo::core::statement::SelfCheck)) is reported beside the verdict, not in it.
//!
//! # Malformed input
//! The log must be complete and well-formed: the header of the run's dimensions, every cell a
//! finite number (or empty where a value does not apply, `-inf` for a deterministic target),
//! counters as non-negative integers, one row for each iteration the configuration's
//! `log-every` logs, and — for a finished log — a `summary.json` matching it. Anything else is
//! [`Error::Invalid`]. An interrupted run (checkpointed `log.partial.csv`) is audited up to its
//! checkpoint and reported as incomplete.

mod exact;
mod judge;
mod render;
mod report;
#[cfg(test)]
mod tests;
mod walk;

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use sepg_algo::core::config::{Algorithm, GradientMode};
use sepg_algo::core::statement::Statement;
use sepg_mdp::oracle::DpConfig;

use crate::error::{Error, Result};
use crate::folder::{SUMMARY_FILE, load_resolved};
use crate::logcheck::{Progress, Row, bad, log_bytes, parse_log};
use crate::run::{RunObserver, Silent};
use crate::spec::{AlgoName, Resolved, RunSpec};

use exact::{ExactJ, evaluate_all, key, source};
use judge::{Plan, judge, judged_statement, plans, verdict};
pub use render::render;
pub use report::{
    AuditReport, CheckSummary, Judgement, Test, Verdict, Violation, broken_runs_p_value,
};
use walk::{Auditor, Step, Walk};

/// Family-wise significance level of the tests of a run (and of the groups of a sweep),
/// unless the caller asks for another one.
pub const DEFAULT_ALPHA: f64 = 0.01;

/// Relative tolerance of the checks: a shortfall up to `DEFAULT_TOLERANCE · max(1, |J|)` is
/// attributed to the oracle's error (see the module documentation for its measurement).
pub const DEFAULT_TOLERANCE: f64 = 1e-12;

/// Chebyshev nodes per element of the dynamic programme the audit evaluates J with.
pub const AUDIT_NODES_PER_ELEMENT: usize = 14;

/// The resolution of [`ClippedDpOracle`](sepg_mdp::oracle::ClippedDpOracle) used by the audit: [`DpConfig::default`] with
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
    check_arguments(dir, tolerance, alpha)?;
    let input = Input::read(dir)?;
    let config = input.resolved.checked.config();
    let (exact, source_name) = source(&config.env, config.horizon, input.resolved.dims.0)?;
    let requirement = match config.algorithm {
        Algorithm::Sepg(r) | Algorithm::SepgNaiveW(r) => Some(r),
        _ => None,
    };
    let gradients = match config.gradient {
        GradientMode::Exact => "exact".to_owned(),
        GradientMode::Sampled { delta } => format!("sampled (δ = {delta})"),
    };
    let (statement, statement_recorded, per_iteration) = input.statement(dir)?;
    let mut plans = plans(requirement, &statement, input.resolved.dims, per_iteration);
    if exact.is_none() {
        // Without exact J only the run's own bookkeeping can be read from the log.
        plans.retain(|p| p.name == "budget");
    }
    let walk = Walk {
        requirement,
        budget0: config.initial_budget,
    };
    let steps = input.steps();
    let js = exact_values(exact.as_ref(), &walk, &steps, &plans, observer)?;
    let (auditor, skipped) = walk_log(&walk, &plans, &steps, &js, tolerance)?;
    let checks = judge(&plans, &auditor.tallies, statement.kind, alpha)?;
    let (mut verdict, mut reason) = verdict(
        &checks,
        &auditor.failures,
        &statement,
        (input.progress.done, input.progress.complete),
        exact.is_some(),
    );
    if let Some(why) = input.progress.constants_check.reason() {
        // data that refute the constants void every bound: never "holds"
        (verdict, reason) = (
            Verdict::NoGuarantee,
            format!("the run states nothing about exact J: {why}"),
        );
    }
    let type_one = requirement.is_some_and(|r| !r.is_type_two());
    Ok(AuditReport {
        dir: dir.display().to_string(),
        algorithm: algorithm_name(&input.resolved.spec),
        gradients,
        source: source_name,
        tolerance,
        alpha,
        iterations_done: input.progress.done,
        iterations_total: input.resolved.iterations(),
        rows: input.rows.len(),
        skipped,
        statement,
        statement_recorded,
        self_check: input.progress.summary.as_ref().and_then(|s| s.self_check),
        self_check_quantity: if type_one { "surplus" } else { "budget" },
        checks,
        failures: auditor.failures,
        verdict,
        reason,
    })
}

/// Rejects a relative tolerance that is not finite and ≥ 0 and a level outside (0, 1).
pub(crate) fn check_levels(tolerance: f64, alpha: f64) -> Result<()> {
    if !(tolerance.is_finite() && tolerance >= 0.0) {
        return Err(Error::invalid(format!(
            "--tolerance {tolerance} must be finite and >= 0"
        )));
    }
    if !(alpha > 0.0 && alpha < 1.0) {
        return Err(Error::invalid(format!("--alpha {alpha} must be in (0, 1)")));
    }
    Ok(())
}

/// Rejects a tolerance or level out of range ([`check_levels`]) and a `dir` that is not a
/// folder.
fn check_arguments(dir: &Path, tolerance: f64, alpha: f64) -> Result<()> {
    check_levels(tolerance, alpha)?;
    if !dir.is_dir() {
        return Err(Error::invalid(format!("{} is not a folder", dir.display())));
    }
    Ok(())
}

/// What the audit reads from a run folder: its resolved configuration, the rows of its log
/// and its progress.
struct Input {
    resolved: Resolved,
    rows: Vec<Row>,
    progress: Progress,
}

impl Input {
    /// Reads the configuration, the log and the progress of the run folder `dir`.
    fn read(dir: &Path) -> Result<Self> {
        let resolved = load_resolved(dir)?;
        let total = resolved.iterations();
        let (bytes, progress) = log_bytes(dir, total, resolved.dims)?;
        let rows = parse_log(
            dir,
            &bytes,
            resolved.dims,
            (progress.done, resolved.log_every(), total),
        )?;
        Ok(Input {
            resolved,
            rows,
            progress,
        })
    }

    /// The statement the run is judged by (checked against the run's constants), whether it
    /// was recorded, and K, the scalar confidence statements of one iteration.
    fn statement(&self, dir: &Path) -> Result<(Statement, bool, usize)> {
        let config = self.resolved.checked.config();
        let per_iteration = sepg_algo::solver::statements_per_iteration(
            config.algorithm,
            &config.options,
            self.resolved.dims,
        );
        let (statement, recorded) = judged_statement(
            self.progress.summary.as_ref(),
            self.resolved.checked.statement(),
            per_iteration,
        );
        let statement = statement.checked_against(&self.progress.constants_check);
        if let Some(d) = statement.delta
            && !(d > 0.0 && d < 1.0)
        {
            return Err(bad(
                dir,
                format!("{SUMMARY_FILE}: the statement's delta {d} is not in (0, 1)"),
            ));
        }
        Ok((statement, recorded, per_iteration))
    }

    /// Each row with the parameters after its update: the next row's when it logs the next
    /// iteration, the final parameters after the last iteration done, else none.
    fn steps(&self) -> Vec<Step<'_>> {
        let rows = &self.rows;
        rows.iter()
            .enumerate()
            .map(|(k, row)| {
                let t = row.iteration;
                let next = match rows.get(k + 1) {
                    Some(n) if n.iteration == t + 1 => Some((n.v.clone(), n.w.clone())),
                    Some(_) => None,
                    None => (t + 1 == self.progress.done)
                        .then(|| (self.progress.last.v.clone(), self.progress.last.w.clone())),
                };
                Step { row, next }
            })
            .collect()
    }
}

/// Exact J at every point the checks of `steps` use (none without an oracle); progress in
/// units of the audited rows.
fn exact_values(
    exact: Option<&ExactJ>,
    walk: &Walk,
    steps: &[Step<'_>],
    plans: &[Plan],
    observer: &dyn RunObserver,
) -> Result<HashMap<Vec<u64>, f64>> {
    let Some(exact) = exact else {
        return Ok(HashMap::new());
    };
    let mut points = Vec::new();
    for step in steps {
        walk.points(step, plans, &mut points);
    }
    evaluate_all(exact, points, steps.len() as u64, observer)
}

/// Every check of every step against the exact values `js` (J(θ⁰) from the first row), the
/// failures in order of iteration, and the number of rows skipped for want of their next
/// parameters.
fn walk_log(
    walk: &Walk,
    plans: &[Plan],
    steps: &[Step<'_>],
    js: &HashMap<Vec<u64>, f64>,
    tolerance: f64,
) -> Result<(Auditor, usize)> {
    let mut auditor = Auditor {
        tolerance,
        tallies: BTreeMap::new(),
        failures: Vec::new(),
    };
    let j0 = steps
        .first()
        .and_then(|s| js.get(&key(&s.row.v, &s.row.w)).copied())
        .unwrap_or(0.0);
    let mut skipped = 0;
    for step in steps {
        if !walk.step(&mut auditor, plans, step, js, j0)? {
            skipped += 1;
        }
    }
    auditor.failures.sort_by_key(|f| f.iteration);
    Ok((auditor, skipped))
}
