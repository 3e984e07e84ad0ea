//! The human-readable report of an audit.

use std::fmt::Write as _;

use sepg_algo::core::statement::StatementKind;
use serde::Serialize;

use super::report::{AuditReport, Judgement};

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
    header(&mut s, report);
    check_table(&mut s, report);
    failure_table(&mut s, report);
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

/// The lines before the table: the run, the source of J, the tolerance, the statement and
/// the iterations audited.
fn header(s: &mut String, report: &AuditReport) {
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
}

/// The table of checks, one line per check.
fn check_table(s: &mut String, report: &AuditReport) {
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
}

/// The failing iterations of the judged checks (the first [`LISTED`] of them).
fn failure_table(s: &mut String, report: &AuditReport) {
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
}
