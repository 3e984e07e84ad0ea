//! The registry of checks: every statement of the thesis covered so far, in a fixed order.

mod algorithm;
mod appendix_a;
mod certified;
mod chapter3;
mod chapter4;
mod exploring;
mod lqg_exact;
pub(crate) mod sampled;

use crate::check::Check;

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
    let mut checks = chapter3::checks();
    checks.extend(appendix_a::checks());
    checks.extend(chapter4::checks());
    checks.extend(lqg_exact::checks());
    checks.extend(sampled::checks());
    checks.extend(algorithm::checks());
    checks.extend(certified::checks());
    checks.extend(exploring::checks());
    checks
}
