//! The check abstraction: metadata, expected outcome, run configuration and results.

use serde::{Deserialize, Serialize};

use crate::bound_fns::BoundFns;

/// How a verification run is configured.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct RunConfig {
    /// Master seed; each check derives its own random stream from `(seed, check id)`.
    pub seed: u64,
    /// Quick mode: fewer cases per check (continuous integration).
    pub quick: bool,
}

impl Default for RunConfig {
    /// Seed 0, full mode.
    fn default() -> Self {
        Self {
            seed: 0,
            quick: false,
        }
    }
}

/// Whether the claim of a check is an equality or a lower bound.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum ClaimKind {
    /// `truth = claimed` up to the tolerance.
    Equality,
    /// `truth ≥ claimed bound` up to the tolerance.
    LowerBound,
    /// `truth ≤ claimed bound` up to the tolerance.
    UpperBound,
}

/// Numerical tolerance of a comparison: a case fails when the discrepancy exceeds
/// `abs + rel · max(|truth|, |claimed|)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Tolerance {
    /// Absolute part.
    pub abs: f64,
    /// Relative part.
    pub rel: f64,
}

impl Tolerance {
    /// Allowed discrepancy for a pair of values.
    ///
    /// # Formula
    /// ```text
    /// abs + rel · max(|truth|, |claimed|)
    /// ```
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::Tolerance;
    /// let t = Tolerance { abs: 1e-12, rel: 1e-9 };
    /// assert_eq!(t.allowed(2.0, -4.0), 1e-12 + 4e-9);
    /// ```
    pub fn allowed(&self, truth: f64, claimed: f64) -> f64 {
        self.abs + self.rel * truth.abs().max(claimed.abs())
    }
}

/// The outcome a check is expected to produce, recorded in the registry from measurement.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Expected {
    /// The statement holds on every case tried ([`Outcome::Holds`] or
    /// [`Outcome::HoldsWithMargin`]).
    Holds,
    /// The statement, as printed, is violated ([`Outcome::Violated`]).
    Violated,
    /// The check cannot decide ([`Outcome::Inconclusive`]).
    Inconclusive,
}

/// What a check found.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Outcome {
    /// An equality held on every case; `max_error` is the largest discrepancy found.
    Holds {
        /// Largest `|truth − claimed|` over all cases.
        max_error: f64,
    },
    /// An inequality held on every case.
    HoldsWithMargin {
        /// Tightest slack: `min over cases of (truth − bound)` for a lower bound,
        /// `min over cases of (bound − truth)` for an upper bound.
        margin: f64,
        /// Tightest relative slack: the slack divided by `max(|truth|, |bound|)`, minimised
        /// over cases. Both margins leave out trivial comparisons where both sides are within
        /// the absolute tolerance of zero.
        relative_margin: f64,
    },
    /// A case violates the statement beyond the tolerance; the counterexample is the smallest
    /// one found by shrinking.
    Violated {
        /// Debug rendering of the shrunk failing configuration and of the two sides.
        counterexample: String,
        /// By how much the statement fails on the shrunk counterexample
        /// (`bound − truth` for lower bounds, `truth − bound` for upper bounds,
        /// `|truth − claimed|` for equalities).
        amount: f64,
    },
    /// The check could not decide (e.g. every case was degenerate).
    Inconclusive {
        /// Why.
        reason: String,
    },
}

impl Outcome {
    /// Whether this outcome matches an expected outcome.
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::{Expected, Outcome};
    /// let o = Outcome::HoldsWithMargin { margin: 0.1, relative_margin: 0.5 };
    /// assert!(o.matches(Expected::Holds));
    /// assert!(!o.matches(Expected::Violated));
    /// ```
    pub fn matches(&self, expected: Expected) -> bool {
        matches!(
            (self, expected),
            (Outcome::Holds { .. }, Expected::Holds)
                | (Outcome::HoldsWithMargin { .. }, Expected::Holds)
                | (Outcome::Violated { .. }, Expected::Violated)
                | (Outcome::Inconclusive { .. }, Expected::Inconclusive)
        )
    }

    /// One-line description with the tolerance used: "holds within tolerance T …" for a hold
    /// (the tightest slack may be negative but inside T), "violated by …" otherwise.
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::{Outcome, Tolerance};
    /// let t = Tolerance { abs: 1e-10, rel: 1e-9 };
    /// let o = Outcome::HoldsWithMargin { margin: -1.1e-16, relative_margin: -1e-14 };
    /// let text = o.describe(&t);
    /// assert!(text.starts_with("holds within tolerance 1.000000e-10 + 1.000000e-9"));
    /// assert!(!text.contains("holds with margin"));
    /// ```
    pub fn describe(&self, tolerance: &Tolerance) -> String {
        let tol = format!(
            "{} + {}·max(|truth|, |claimed|)",
            fmt_f64(tolerance.abs),
            fmt_f64(tolerance.rel)
        );
        match self {
            Outcome::Holds { max_error } => {
                format!(
                    "holds within tolerance {tol} (max error {})",
                    fmt_f64(*max_error)
                )
            }
            Outcome::HoldsWithMargin {
                margin,
                relative_margin,
            } => format!(
                "holds within tolerance {tol} (tightest slack {}, relative {})",
                fmt_f64(*margin),
                fmt_f64(*relative_margin)
            ),
            Outcome::Violated { amount, .. } => {
                format!("violated by {} (tolerance {tol})", fmt_f64(*amount))
            }
            Outcome::Inconclusive { reason } => format!("inconclusive: {reason}"),
        }
    }

    /// Short label: `holds`, `violated` or `inconclusive`.
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::Outcome;
    /// assert_eq!(Outcome::Holds { max_error: 0.0 }.label(), "holds");
    /// ```
    pub fn label(&self) -> &'static str {
        match self {
            Outcome::Holds { .. } | Outcome::HoldsWithMargin { .. } => "holds",
            Outcome::Violated { .. } => "violated",
            Outcome::Inconclusive { .. } => "inconclusive",
        }
    }
}

/// A named figure reported next to the outcome (already formatted, so the report is
/// byte-stable).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Figure {
    /// What the figure is.
    pub name: String,
    /// Its value, formatted with [`fmt_f64`] or as an integer.
    pub value: String,
}

/// Formats a float for reports: `{:.6e}`, stable across platforms and runs.
///
/// # Example
/// ```
/// assert_eq!(sepg_verification::fmt_f64(0.5), "5.000000e-1");
/// ```
pub fn fmt_f64(x: f64) -> String {
    format!("{x:.6e}")
}

/// Static description of a check: what it verifies, against what, how.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CheckMeta {
    /// Stable identifier, e.g. `thm-3.1-cpi-bound`.
    pub id: String,
    /// The statement checked (name and number in the thesis).
    pub statement: String,
    /// Where it is printed (section, equation).
    pub location: String,
    /// The claim, in words, with the exact form tested.
    pub claim: String,
    /// Ground truth used.
    pub ground_truth: String,
    /// How configurations are drawn.
    pub sampling: String,
    /// Whether the claim is an equality or a lower bound.
    pub kind: ClaimKind,
    /// Cases in full mode.
    pub cases_full: u32,
    /// Cases in quick mode.
    pub cases_quick: u32,
    /// Numerical tolerance.
    pub tolerance: Tolerance,
    /// Probability that a true statement is reported violated, in words.
    pub false_alarm_rate: String,
    /// Outcome recorded from measurement.
    pub expected: Expected,
    /// Explanation of the expected outcome (and the erratum for a violation).
    pub notes: String,
    /// Where the expected outcome comes from: `theory: …` (a proof, or a closed-form
    /// counterexample) or `independent computation: …` (a computation that does not use the
    /// code under test, e.g. a long exact run or a published table), never the check's own
    /// measurement alone.
    #[serde(default)]
    pub basis: String,
}

/// What a check's body returns: the outcome, the number of cases evaluated and extra figures.
#[derive(Debug, Clone, PartialEq)]
pub struct Evaluation {
    /// The outcome.
    pub outcome: Outcome,
    /// Cases evaluated (not counting shrinking steps).
    pub cases: u64,
    /// Check-specific figures.
    pub figures: Vec<Figure>,
}

/// Everything a check body needs: its case budget, its own seed and the bound functions.
#[derive(Debug, Clone, Copy)]
pub struct CheckContext<'a> {
    /// Seed derived from `(RunConfig::seed, check id)`.
    pub seed: u64,
    /// Number of random cases to draw.
    pub cases: u32,
    /// Quick mode.
    pub quick: bool,
    /// Tolerance of the check.
    pub tolerance: Tolerance,
    /// Claim kind of the check.
    pub kind: ClaimKind,
    /// The closed forms under test.
    pub bounds: &'a BoundFns,
}

/// Body of a check.
pub type CheckFn = fn(&CheckContext<'_>) -> Evaluation;

/// One verification check: metadata, the bound functions it tests, and its body.
#[derive(Debug, Clone)]
pub struct Check {
    /// Metadata.
    pub meta: CheckMeta,
    /// Closed forms under test; replace one to inject a fault.
    pub bounds: BoundFns,
    body: CheckFn,
}

/// Result of running one check.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CheckResult {
    /// Metadata of the check.
    pub meta: CheckMeta,
    /// Cases evaluated.
    pub cases: u64,
    /// What was found.
    pub outcome: Outcome,
    /// Whether the outcome matches `meta.expected`.
    pub as_expected: bool,
    /// Check-specific figures.
    pub figures: Vec<Figure>,
}

/// Derives a 64-bit seed from a master seed and a check identifier (SplitMix64 finaliser over
/// FNV-1a of the identifier), so that each check's stream is independent of scheduling and of
/// which other checks run.
///
/// # Example
/// ```
/// use sepg_verification::derive_seed;
/// assert_eq!(derive_seed(7, "a"), derive_seed(7, "a"));
/// assert_ne!(derive_seed(7, "a"), derive_seed(7, "b"));
/// ```
pub fn derive_seed(seed: u64, id: &str) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in id.bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    splitmix64(seed ^ h)
}

/// SplitMix64 output function (Steele, Lea & Flood 2014).
pub(crate) fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

impl Check {
    /// Builds a check from its metadata and body, with the default bound functions.
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::*;
    /// fn body(_: &CheckContext<'_>) -> Evaluation {
    ///     Evaluation { outcome: Outcome::Holds { max_error: 0.0 }, cases: 1, figures: vec![] }
    /// }
    /// let meta = registry()[0].meta.clone();
    /// let result = Check::new(meta, body).run(&RunConfig::default());
    /// assert_eq!(result.cases, 1);
    /// assert_eq!(result.outcome.label(), "holds");
    /// ```
    pub fn new(meta: CheckMeta, body: CheckFn) -> Self {
        Self {
            meta,
            bounds: BoundFns::default(),
            body,
        }
    }

    /// Replaces the bound functions (fault injection: pass a deliberately broken bound and
    /// the check must report [`Outcome::Violated`]).
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::*;
    /// let broken = BoundFns { psi: || 0.5 * sepg_bounds::constants::psi(), ..BoundFns::default() };
    /// let check = registry().into_iter().find(|c| c.meta.id == "lemma-a.1-second-derivative-bound").unwrap();
    /// let result = check.with_bounds(broken).run(&RunConfig { seed: 1, quick: true });
    /// assert_eq!(result.outcome.label(), "violated");
    /// ```
    pub fn with_bounds(mut self, bounds: BoundFns) -> Self {
        self.bounds = bounds;
        self
    }

    /// Runs the check with its own random stream derived from `(config.seed, id)`.
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::*;
    /// let check = registry().into_iter().find(|c| c.meta.id == "thm-3.3-performance-difference").unwrap();
    /// let r = check.run(&RunConfig { seed: 3, quick: true });
    /// assert!(r.as_expected);
    /// ```
    pub fn run(&self, config: &RunConfig) -> CheckResult {
        let cases = if config.quick {
            self.meta.cases_quick
        } else {
            self.meta.cases_full
        };
        let ctx = CheckContext {
            seed: derive_seed(config.seed, &self.meta.id),
            cases,
            quick: config.quick,
            tolerance: self.meta.tolerance,
            kind: self.meta.kind,
            bounds: &self.bounds,
        };
        let eval = (self.body)(&ctx);
        CheckResult {
            as_expected: eval.outcome.matches(self.meta.expected),
            meta: self.meta.clone(),
            cases: eval.cases,
            outcome: eval.outcome,
            figures: eval.figures,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn relative_tolerance_scales_with_the_larger_magnitude_also_below_one() {
        // abs + rel·max(|truth|, |claimed|), written out by hand. Magnitudes below 1 must not
        // be floored at 1: the DP checks compare improvements of order 1e-6..1e-3.
        let t = Tolerance {
            abs: 1e-13,
            rel: 1e-4,
        };
        assert_relative_eq!(t.allowed(1e-3, -2e-3), 1e-13 + 2e-7, max_relative = 1e-12);
        assert_relative_eq!(t.allowed(0.0, 0.0), 1e-13, max_relative = 1e-12);
        assert_relative_eq!(t.allowed(-50.0, 3.0), 1e-13 + 5e-3, max_relative = 1e-12);
    }
}
