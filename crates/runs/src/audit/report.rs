//! The audit's report: the verdict, the tests, the judgements and the summaries of checks.

use sepg_algo::core::statement::{Scope, SelfCheck, Statement};
use sepg_estimators::binomial::upper_tail;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

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
    pub(super) fn label(self) -> &'static str {
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
    pub(super) fn label(self) -> &'static str {
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
    upper_tail(failed, runs, rate).map_err(|e| Error::invalid_from("binomial test", e))
}
