//! Numerical verification harness for the sepg workspace.
//!
//! Every numbered statement of the thesis's Chapters 3–4 and Appendices A–B gets one or more
//! [`Check`]s. A check states its claim, its ground truth (exact finite-MDP evaluation, closed
//! forms, numeric integration, exact arithmetic, the exact J of the clipped LQG presets by
//! dynamic programming, Monte Carlo with exact binomial or z tests), how configurations are
//! drawn (proptest strategies, with edge cases), its tolerance and false-alarm rate, and the
//! outcome expected from measurement. [`run_checks`] runs a selection in parallel and returns a [`Report`] whose
//! Markdown and JSON forms are byte-identical for the same seed and version, whatever the
//! number of threads.
//!
//! ```
//! use sepg_verification::{registry, run_checks, RunConfig};
//! let report = run_checks(&registry(), &RunConfig { seed: 1, quick: true }, Some("thm-3.3"), |_| {});
//! assert_eq!(report.results.len(), 1);
//! assert!(report.all_as_expected());
//! assert!(report.to_markdown().contains("thm-3.3-performance-difference"));
//! ```

#![deny(missing_docs)]

pub mod bound_fns;
pub mod campaign;
mod check;
mod checks;
pub mod finite_mdp;
mod lqg;
mod report;
mod search;
pub mod stats;

pub use bound_fns::BoundFns;
pub use check::{
    Check, CheckContext, CheckFn, CheckMeta, CheckResult, ClaimKind, Evaluation, Expected, Figure,
    Outcome, RunConfig, Tolerance, derive_seed, fmt_f64,
};
pub use checks::registry;
pub use report::{Report, run_checks};
