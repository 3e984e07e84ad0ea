//! The registry of checks: every statement of the thesis covered so far, in a fixed order.
//!
//! The checks are grouped by how their ground truth is obtained, one file per method; which
//! check covers which statement is the table of docs/THEOREMS.md (statement → function →
//! check), and `sepg verify --check ID` runs one.
//!
//! | file | ground truth |
//! |---|---|
//! | `finite_mdps` | exact policy evaluation of random finite MDPs (linear solves) |
//! | `quadrature` | closed forms and numerical integration over the Gaussian family |
//! | `budget_algebra` | exact dyadic arithmetic on synthetic learning histories |
//! | `lqg_exact` | the exact J and gradients of the clipped LQG presets (DP oracle), exact gradients |
//! | `curvature` | the exact Hessian of the clipped presets and closed-form adversarial tasks |
//! | `sampled` | Monte Carlo batches against exact values: binomial and z tests |
//! | `exploring` | Monte Carlo batches of the exploring w-step against exact J |
//! | `algorithm` | whole SEPG runs (exact and sampled gradients) judged with the DP oracle |
//! | `run_statement` | SEPG runs over many seeds, point by point against exact J (Theorem R) |
//! | `certified` | certified steps against 256-bit exact arithmetic (the campaign) |
//!
//! The statistical tests are in [`crate::stats`], the LQG tasks and sampled settings in
//! `crate::lqg`.

mod algorithm;
mod budget_algebra;
mod certified;
mod curvature;
mod exploring;
mod finite_mdps;
mod lqg_exact;
mod quadrature;
mod run_statement;
pub(crate) mod sampled;

use crate::check::{Check, Expected};

/// Every check, in a deterministic order: Chapter 3, Appendix A, Chapter 4.
///
/// # Example
/// ```
/// let checks = sepg_verification::registry();
/// assert!(checks.iter().any(|c| c.meta.id == "thm-3.1-cpi-bound"));
/// let mut ids: Vec<_> = checks.iter().map(|c| c.meta.id.clone()).collect();
/// ids.sort();
/// ids.dedup();
/// assert_eq!(ids.len(), checks.len());
/// ```
pub fn registry() -> Vec<Check> {
    let mut checks = finite_mdps::checks();
    checks.extend(quadrature::checks());
    checks.extend(budget_algebra::checks());
    checks.extend(lqg_exact::checks());
    checks.extend(sampled::checks());
    checks.extend(algorithm::checks());
    checks.extend(certified::checks());
    checks.extend(exploring::checks());
    checks.extend(curvature::checks());
    checks.extend(run_statement::checks());
    for c in &mut checks {
        if c.meta.basis.is_empty() {
            c.meta.basis = default_basis(c.meta.expected).into();
        }
    }
    checks
}

/// Where the expected outcome of a check comes from when the check does not say more: a
/// proven statement (holds) or a closed-form counterexample recorded in docs/ERRATA.md
/// (violated).
fn default_basis(expected: Expected) -> &'static str {
    match expected {
        Expected::Holds => {
            "theory: the statement is proven (in the thesis or its source, for the reading given \
             in the claim); the check compares it with exact or independently computed values, \
             so a violation would be a counterexample"
        }
        Expected::Violated => {
            "theory: a closed-form counterexample to the printed statement, derived by hand and \
             recorded in docs/ERRATA.md (see the notes); the check finds one numerically"
        }
        Expected::Inconclusive => "theory: the statement cannot be decided by this check",
    }
}
