//! Running a selection of checks and rendering the deterministic report.

use std::fmt::Write as _;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::check::{Check, CheckResult, ClaimKind, Expected, Outcome, RunConfig, fmt_f64};

/// Result of a verification run: configuration and one [`CheckResult`] per check, in registry
/// order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// Version of the harness that produced the report.
    pub version: String,
    /// Master seed.
    pub seed: u64,
    /// Quick mode.
    pub quick: bool,
    /// Substring filter on check ids, if any.
    pub filter: Option<String>,
    /// Results, in the order of the checks passed to [`run_checks`].
    pub results: Vec<CheckResult>,
}

/// Runs every check whose id contains `filter` (all when `None`) in parallel on the current
/// rayon pool; `progress` is called once per finished check (in completion order). The report
/// keeps the order of `checks`, and each check draws from its own stream derived from
/// `(config.seed, id)`, so the report does not depend on the number of threads nor on which
/// other checks run.
///
/// # Example
/// ```
/// use std::sync::atomic::{AtomicUsize, Ordering};
/// use sepg_verification::{registry, run_checks, RunConfig};
/// let done = AtomicUsize::new(0);
/// let report = run_checks(&registry(), &RunConfig { seed: 0, quick: true }, Some("thm-4.1"), |_| {
///     done.fetch_add(1, Ordering::Relaxed);
/// });
/// assert_eq!(report.results.len(), done.load(Ordering::Relaxed));
/// ```
pub fn run_checks(
    checks: &[Check],
    config: &RunConfig,
    filter: Option<&str>,
    progress: impl Fn(&CheckResult) + Sync,
) -> Report {
    let selected: Vec<&Check> = checks
        .iter()
        .filter(|c| filter.is_none_or(|f| c.meta.id.contains(f)))
        .collect();
    let results = selected
        .par_iter()
        .map(|c| {
            let r = c.run(config);
            progress(&r);
            r
        })
        .collect();
    Report {
        version: env!("CARGO_PKG_VERSION").to_string(),
        seed: config.seed,
        quick: config.quick,
        filter: filter.map(str::to_string),
        results,
    }
}

fn expected_label(e: Expected) -> &'static str {
    match e {
        Expected::Holds => "holds",
        Expected::Violated => "violated",
        Expected::Inconclusive => "inconclusive",
    }
}

fn kind_label(k: ClaimKind) -> &'static str {
    match k {
        ClaimKind::Equality => "equality",
        ClaimKind::LowerBound => "lower bound (truth ≥ claimed)",
        ClaimKind::UpperBound => "upper bound (truth ≤ claimed)",
    }
}

/// One-line figure summarising an outcome for the summary table (the tolerance is printed in
/// the check's section).
fn outcome_figure(o: &Outcome) -> String {
    match o {
        Outcome::Holds { max_error } => format!("max error {}", fmt_f64(*max_error)),
        Outcome::HoldsWithMargin {
            margin,
            relative_margin,
        } => format!(
            "within tolerance; tightest slack {} (relative {})",
            fmt_f64(*margin),
            fmt_f64(*relative_margin)
        ),
        Outcome::Violated { amount, .. } => format!("violated by {}", fmt_f64(*amount)),
        Outcome::Inconclusive { reason } => reason.clone(),
    }
}

fn cell(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

impl Report {
    /// Whether every check produced its expected outcome (the CLI's exit status).
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::*;
    /// let r = run_checks(&registry(), &RunConfig { seed: 0, quick: true }, Some("lemma-a.1-psi"), |_| {});
    /// assert!(r.all_as_expected());
    /// ```
    pub fn all_as_expected(&self) -> bool {
        self.results.iter().all(|r| r.as_expected)
    }

    /// The checks whose outcome differs from the expected one.
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::*;
    /// let r = run_checks(&registry(), &RunConfig { seed: 0, quick: true }, Some("lemma-a.1-psi"), |_| {});
    /// assert!(r.unexpected().is_empty());
    /// ```
    pub fn unexpected(&self) -> Vec<&CheckResult> {
        self.results.iter().filter(|r| !r.as_expected).collect()
    }

    /// Deterministic Markdown rendering: header, summary table, then one section per check
    /// with its claim, ground truth, sampling, cases, tolerance, false-alarm rate, expected and
    /// actual outcome, margin or counterexample, and figures. No timestamps or timings; floats
    /// use `{:.6e}`.
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::*;
    /// let cfg = RunConfig { seed: 5, quick: true };
    /// let a = run_checks(&registry(), &cfg, Some("thm-4.1"), |_| {}).to_markdown();
    /// let b = run_checks(&registry(), &cfg, Some("thm-4.1"), |_| {}).to_markdown();
    /// assert_eq!(a, b);
    /// ```
    pub fn to_markdown(&self) -> String {
        let mut md = String::new();
        let unexpected = self.unexpected();
        let _ = writeln!(md, "# sepg verification report\n");
        let _ = writeln!(md, "- harness version: {}", self.version);
        let _ = writeln!(md, "- seed: {}", self.seed);
        let _ = writeln!(md, "- mode: {}", if self.quick { "quick" } else { "full" });
        let _ = writeln!(
            md,
            "- filter: {}",
            self.filter
                .as_deref()
                .map_or("none".to_string(), |f| format!("`{f}`"))
        );
        let _ = writeln!(
            md,
            "- checks: {}, as expected: {}, differing from expected: {}",
            self.results.len(),
            self.results.len() - unexpected.len(),
            unexpected.len()
        );
        if !unexpected.is_empty() {
            let ids: Vec<String> = unexpected
                .iter()
                .map(|r| format!("`{}`", r.meta.id))
                .collect();
            let _ = writeln!(md, "- differing: {}", ids.join(", "));
        }
        let _ = writeln!(md, "\n## Summary\n");
        let _ = writeln!(
            md,
            "| check | statement | expected | outcome | as expected | cases | figure |"
        );
        let _ = writeln!(md, "|---|---|---|---|---|---|---|");
        for r in &self.results {
            let _ = writeln!(
                md,
                "| `{}` | {} | {} | {} | {} | {} | {} |",
                r.meta.id,
                cell(&r.meta.statement),
                expected_label(r.meta.expected),
                r.outcome.label(),
                if r.as_expected { "yes" } else { "**NO**" },
                r.cases,
                cell(&outcome_figure(&r.outcome))
            );
        }
        let _ = writeln!(md, "\n## Checks");
        for r in &self.results {
            self.write_check(&mut md, r);
        }
        md
    }

    fn write_check(&self, md: &mut String, r: &CheckResult) {
        let m = &r.meta;
        let _ = writeln!(md, "\n### `{}`: {}\n", m.id, m.statement);
        let _ = writeln!(md, "- location: {}", m.location);
        let _ = writeln!(md, "- claim ({}): {}", kind_label(m.kind), m.claim);
        let _ = writeln!(md, "- ground truth: {}", m.ground_truth);
        let _ = writeln!(md, "- configurations: {}", m.sampling);
        let requested = if self.quick {
            m.cases_quick
        } else {
            m.cases_full
        };
        let _ = writeln!(
            md,
            "- cases: {} evaluated ({} requested)",
            r.cases, requested
        );
        let _ = writeln!(
            md,
            "- tolerance: {} + {} · max(|truth|, |claimed|)",
            fmt_f64(m.tolerance.abs),
            fmt_f64(m.tolerance.rel)
        );
        let _ = writeln!(md, "- false-alarm rate: {}", m.false_alarm_rate);
        let _ = writeln!(md, "- expected outcome: {}", expected_label(m.expected));
        if !m.basis.is_empty() {
            let _ = writeln!(md, "- expected outcome from: {}", m.basis);
        }
        let _ = writeln!(
            md,
            "- outcome: {}{}",
            r.outcome.describe(&m.tolerance),
            if r.as_expected {
                ""
            } else {
                " — DIFFERS FROM EXPECTED"
            }
        );
        if let Outcome::Violated { counterexample, .. } = &r.outcome {
            let _ = writeln!(
                md,
                "- smallest counterexample found:\n\n```text\n{counterexample}\n```\n"
            );
        }
        for f in &r.figures {
            let _ = writeln!(md, "- {}: {}", f.name, f.value);
        }
        if !m.notes.is_empty() {
            let _ = writeln!(md, "- notes: {}", m.notes);
        }
    }

    /// JSON rendering (serde), deterministic like the Markdown form.
    ///
    /// # Errors
    /// Propagates a `serde_json` serialisation error (not expected for this type).
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::*;
    /// let r = run_checks(&registry(), &RunConfig { seed: 0, quick: true }, Some("lemma-a.1-psi"), |_| {});
    /// let json = r.to_json().unwrap();
    /// let back: Report = serde_json::from_str(&json).unwrap();
    /// assert_eq!(back.results.len(), 1);
    /// ```
    pub fn to_json(&self) -> Result<String, serde_json::Error> {
        serde_json::to_string_pretty(self)
    }
}
