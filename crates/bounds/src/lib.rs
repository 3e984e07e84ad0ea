//! Closed-form safety quantities of Safely-Exploring Policy Gradient (SEPG).
//!
//! Every function is pure, works in `f64`, validates its input and returns a
//! [`BoundsError`] instead of panicking or producing NaN. Requirements that no step can meet
//! are an ordinary outcome ([`outcome::StepOutcome::Infeasible`]), not an error.
//!
//! | module | thesis |
//! |---|---|
//! | [`constants`] | ψ (Lemma A.1), c (Thms 3.14, 4.2), d (Thm 4.3), ∂c/∂σ |
//! | [`pirotta`] | Theorem 3.10, Corollary 3.11, Theorem 3.12 |
//! | [`papini`] | Theorem 3.14 |
//! | [`batch_size`] | Corollary 3.13 |
//! | [`v_update`] | Theorem 4.2, eqs. (4.8)–(4.10) |
//! | [`w_update`] | Theorems 4.3 and 4.5, eqs. (4.15)–(4.19) |
//! | [`surrogate`] | Corollary 4.4, Appendix B |
//! | [`high_probability`] | Theorems 4.7–4.9, eqs. (4.23)–(4.30) |
//! | [`greedy`] | Section 4.3.4 (multi-dimensional greedy-coordinate updates) |
//! | [`rigorous`] | Theorem 4.3 without neglected terms (Lemmas A.1–A.3) |
//! | [`budget`] | Definition 4.3, Theorem 4.1, eqs. (4.13)–(4.14) |
//! | [`interval`] | outward-rounded interval arithmetic |
//! | [`certified`] | certified safe steps: the bounds above evaluated in interval arithmetic |
//! | [`exploring`] | the exploring w-update: Theorem 4.3 with the confidence on ∇_w J only |
//!
//! ```
//! use sepg_bounds::{constants::TaskConstants, outcome::StepOutcome, v_update};
//! let k = TaskConstants::new(0.99, 4.0, 2.0, 4.0)?;
//! let outcome = v_update::safe_step(&k, 1.0, &[0.8, -0.2], 0.0)?;
//! let StepOutcome::Feasible(steps) = outcome else { panic!("monotonic improvement is feasible") };
//! assert!(v_update::bound(&k, 1.0, &[0.8, -0.2], steps.largest())? >= -1e-12);
//! # Ok::<(), sepg_bounds::BoundsError>(())
//! ```

pub mod batch_size;
pub mod budget;
pub mod certified;
pub mod constants;
pub mod error;
pub mod exploring;
pub mod greedy;
pub mod high_probability;
pub mod interval;
pub mod outcome;
pub mod papini;
pub mod pirotta;
pub mod rigorous;
mod rounding;
pub mod surrogate;
pub mod v_update;
pub mod w_update;

pub use error::BoundsError;
