//! Counterexample search: drives a proptest [`TestRunner`] with a fixed-seed ChaCha RNG over a
//! configuration strategy, compares the two sides of a claim on every case, and turns the
//! result (including proptest's shrunk counterexample) into an [`Evaluation`].

use std::cell::RefCell;
use std::fmt::Debug;

use proptest::strategy::Strategy;
use proptest::test_runner::{Config, RngAlgorithm, TestCaseError, TestError, TestRng, TestRunner};

use crate::check::{
    CheckContext, ClaimKind, Evaluation, Figure, Outcome, Tolerance, fmt_f64, splitmix64,
};
use crate::stats::clopper_pearson_upper;

/// Maximal number of configurations evaluated while shrinking a counterexample: beyond it every
/// candidate is treated as passing, so shrinking ends quickly and deterministically with the
/// smallest failing configuration found so far.
const SHRINK_EVALUATIONS: u32 = 1024;

/// proptest's own shrinking cap, far above what [`SHRINK_EVALUATIONS`] lets shrinking reach (so
/// that proptest never prints its "Aborting shrinking" notice).
const MAX_SHRINK_ITERS: u32 = 1 << 24;

/// One comparison between the ground truth and the claimed value of a statement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Comparison {
    /// Exact (or reference) value.
    pub truth: f64,
    /// Value claimed by the statement (the bound, or the right-hand side of an equality).
    pub claimed: f64,
}

impl Comparison {
    pub(crate) fn new(truth: f64, claimed: f64) -> Self {
        Self { truth, claimed }
    }

    /// By how much the claim fails (positive = failure beyond zero tolerance).
    fn shortfall(&self, kind: ClaimKind) -> f64 {
        match kind {
            ClaimKind::Equality => (self.truth - self.claimed).abs(),
            ClaimKind::LowerBound => self.claimed - self.truth,
            ClaimKind::UpperBound => self.truth - self.claimed,
        }
    }

    pub(crate) fn fails(&self, kind: ClaimKind, tol: Tolerance) -> bool {
        let s = self.shortfall(kind);
        s.is_nan() || s > tol.allowed(self.truth, self.claimed)
    }
}

#[derive(Debug, Default)]
struct Stats {
    cases: u64,
    skipped: u64,
    comparisons: u64,
    failed: bool,
    min_slack: Option<f64>,
    min_rel: Option<f64>,
    max_err: f64,
}

impl Stats {
    /// Records a passing comparison. Comparisons where both sides are within the absolute
    /// tolerance of zero (e.g. α = 0, π' = π) are trivially tight and left out of the margins.
    fn record(&mut self, kind: ClaimKind, tol: Tolerance, c: &Comparison) {
        self.comparisons += 1;
        let scale = c.truth.abs().max(c.claimed.abs());
        if scale <= tol.abs {
            return;
        }
        let slack = match kind {
            ClaimKind::UpperBound => c.claimed - c.truth,
            ClaimKind::Equality | ClaimKind::LowerBound => c.truth - c.claimed,
        };
        if slack.is_finite() {
            self.min_slack = Some(self.min_slack.map_or(slack, |m| m.min(slack)));
            let rel = slack / scale;
            self.min_rel = Some(self.min_rel.map_or(rel, |m| m.min(rel)));
            self.max_err = self.max_err.max(slack.abs());
        }
    }
}

/// 32 seed bytes for ChaCha from a 64-bit seed.
fn seed_bytes(seed: u64) -> [u8; 32] {
    let mut out = [0u8; 32];
    for (i, chunk) in out.chunks_mut(8).enumerate() {
        chunk.copy_from_slice(&splitmix64(seed.wrapping_add(i as u64)).to_le_bytes());
    }
    out
}

fn runner(ctx: &CheckContext<'_>) -> TestRunner {
    let config = Config {
        cases: ctx.cases,
        max_shrink_iters: MAX_SHRINK_ITERS,
        max_shrink_time: 0,
        max_local_rejects: 65_536,
        max_global_rejects: 1024,
        failure_persistence: None,
        source_file: None,
        fork: false,
        timeout: 0,
        verbose: 0,
        rng_algorithm: RngAlgorithm::ChaCha,
        ..Config::default()
    };
    TestRunner::new_with_rng(
        config,
        TestRng::from_seed(RngAlgorithm::ChaCha, &seed_bytes(ctx.seed)),
    )
}

/// Standard figures shared by every search.
fn common_figures(stats: &Stats, random: bool) -> Vec<Figure> {
    let mut figures = vec![
        Figure {
            name: "cases evaluated".into(),
            value: stats.cases.to_string(),
        },
        Figure {
            name: "degenerate cases skipped".into(),
            value: stats.skipped.to_string(),
        },
        Figure {
            name: "comparisons".into(),
            value: stats.comparisons.to_string(),
        },
    ];
    let informative = stats.cases - stats.skipped;
    if random
        && !stats.failed
        && informative > 0
        && let Ok(p) = clopper_pearson_upper(0, informative, 0.95)
    {
        figures.push(Figure {
            name: "95% upper bound on the per-case violation probability (Clopper-Pearson)".into(),
            value: fmt_f64(p),
        });
    }
    figures
}

/// Runs a proptest search: `eval` maps a configuration to the comparisons it implies (an empty
/// vector marks a degenerate configuration, counted as skipped). A failing comparison makes
/// proptest shrink the configuration; the smallest one is reported as the counterexample.
pub(crate) fn search<S>(
    ctx: &CheckContext<'_>,
    strategy: S,
    eval: impl Fn(&S::Value) -> Vec<Comparison>,
) -> Evaluation
where
    S: Strategy,
    S::Value: Debug,
{
    let stats = RefCell::new(Stats::default());
    let shrink_evaluations = std::cell::Cell::new(0u32);
    let kind = ctx.kind;
    let tol = ctx.tolerance;
    let mut runner = runner(ctx);
    let result = runner.run(&strategy, |value| {
        if stats.borrow().failed {
            if shrink_evaluations.get() >= SHRINK_EVALUATIONS {
                return Ok(());
            }
            shrink_evaluations.set(shrink_evaluations.get() + 1);
        }
        let comparisons = eval(&value);
        let mut st = stats.borrow_mut();
        let worst = comparisons
            .iter()
            .filter(|c| c.fails(kind, tol))
            .map(|c| (c.shortfall(kind), *c))
            .fold(None, |acc: Option<(f64, Comparison)>, x| match acc {
                Some(a) if x.0 <= a.0 => Some(a),
                _ => Some(x),
            });
        if !st.failed {
            st.cases += 1;
            if comparisons.is_empty() {
                st.skipped += 1;
            }
            if worst.is_none() {
                comparisons.iter().for_each(|c| st.record(kind, tol, c));
            }
        }
        match worst {
            None => Ok(()),
            Some((amount, c)) => {
                st.failed = true;
                Err(TestCaseError::fail(format!(
                    "truth = {}, claimed = {}, shortfall = {}",
                    fmt_f64(c.truth),
                    fmt_f64(c.claimed),
                    fmt_f64(amount)
                )))
            }
        }
    });
    let stats = stats.into_inner();
    let figures = common_figures(&stats, true);
    let outcome = match result {
        Ok(()) => holds_outcome(kind, &stats),
        Err(TestError::Fail(reason, value)) => {
            let amount = eval(&value)
                .iter()
                .filter(|c| c.fails(kind, tol))
                .map(|c| c.shortfall(kind))
                .fold(0.0, f64::max);
            Outcome::Violated {
                counterexample: format!("{value:?} => {reason}"),
                amount,
            }
        }
        Err(TestError::Abort(reason)) => Outcome::Inconclusive {
            reason: format!("search aborted: {reason}"),
        },
    };
    Evaluation {
        outcome,
        cases: stats.cases,
        figures,
    }
}

fn holds_outcome(kind: ClaimKind, stats: &Stats) -> Outcome {
    if stats.comparisons == 0 {
        return Outcome::Inconclusive {
            reason: "every drawn configuration was degenerate".into(),
        };
    }
    match kind {
        ClaimKind::Equality => Outcome::Holds {
            max_error: stats.max_err,
        },
        ClaimKind::LowerBound | ClaimKind::UpperBound => Outcome::HoldsWithMargin {
            margin: stats.min_slack.unwrap_or(f64::INFINITY),
            relative_margin: stats.min_rel.unwrap_or(f64::INFINITY),
        },
    }
}

/// Evaluates a fixed list of labelled comparisons (deterministic grids, constants).
pub(crate) fn fixed(ctx: &CheckContext<'_>, comparisons: &[(String, Comparison)]) -> Evaluation {
    let mut stats = Stats::default();
    let mut failure: Option<(f64, &str, Comparison)> = None;
    for (label, c) in comparisons {
        stats.cases += 1;
        if c.fails(ctx.kind, ctx.tolerance) {
            let s = c.shortfall(ctx.kind);
            if failure.is_none_or(|(worst, _, _)| s > worst) {
                failure = Some((s, label, *c));
            }
        } else {
            stats.record(ctx.kind, ctx.tolerance, c);
        }
    }
    let outcome = match failure {
        Some((amount, label, c)) => {
            stats.failed = true;
            Outcome::Violated {
                counterexample: format!(
                    "{label} => truth = {}, claimed = {}",
                    fmt_f64(c.truth),
                    fmt_f64(c.claimed)
                ),
                amount,
            }
        }
        None => holds_outcome(ctx.kind, &stats),
    };
    Evaluation {
        outcome,
        cases: stats.cases,
        figures: common_figures(&stats, false),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_small_shortfall_beyond_the_relative_tolerance_fails() {
        // Tolerance of the DP checks: 1e-13 + 1e-4·max(|truth|, |claimed|). A lower bound
        // 2e-4 (relative) above a truth of 1e-3 falls short by 2e-7 > 1.0002e-7: it fails; one
        // 5e-5 above falls short by 5e-8 < 1.00005e-7: it passes, and so does any claim below.
        let tol = Tolerance {
            abs: 1e-13,
            rel: 1e-4,
        };
        let lower = ClaimKind::LowerBound;
        assert!(Comparison::new(1e-3, 1e-3 * (1.0 + 2e-4)).fails(lower, tol));
        assert!(!Comparison::new(1e-3, 1e-3 * (1.0 + 5e-5)).fails(lower, tol));
        assert!(!Comparison::new(1e-3, 0.5e-3).fails(lower, tol));
        assert!(Comparison::new(-1e-3, -1e-3 * (1.0 - 2e-4)).fails(lower, tol));
        assert!(Comparison::new(1e-3, f64::NAN).fails(lower, tol));
        assert!(Comparison::new(2e-3, 1e-3).fails(ClaimKind::UpperBound, tol));
        assert!(Comparison::new(1e-3, 1e-3 * (1.0 + 2e-4)).fails(ClaimKind::Equality, tol));
    }
}
