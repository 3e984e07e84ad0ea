//! Judging: the statement a run is judged by, the checks it promises and how their failure
//! counts are tested, and the verdict.

use std::collections::BTreeMap;

use sepg_algo::core::config::Requirement;
use sepg_algo::core::statement::{Covers, Scope, Statement, StatementKind};
use sepg_estimators::binomial::upper_tail;

use super::report::{CheckSummary, Judgement, Test, Verdict, Violation};
use super::walk::Tally;
use crate::error::{Error, Result};
use crate::folder::Summary;

/// The statement a run is judged by, and whether it was recorded (see the module
/// documentation): the summary's, else — for an older summary — the configuration's with
/// scope `iteration` and kind `approximate`, else (an unfinished run) the configuration's.
pub(super) fn judged_statement(
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
pub(super) struct Plan {
    pub(super) name: &'static str,
    pub(super) test: Test,
    pub(super) rate: Option<f64>,
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
pub(super) fn plans(
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

/// The summaries of the checks of `plans` that were evaluated, judged at family-wise level
/// `alpha` (Bonferroni over the tested checks) under a statement of kind `kind`.
pub(super) fn judge(
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
                        Error::failed_from(format_args!("binomial test of {}", plan.name), e)
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

/// The verdict and its reason (see the module documentation), from the judged checks, the
/// statement, the iterations done and whether the run finished, and whether J is exact.
pub(super) fn verdict(
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
