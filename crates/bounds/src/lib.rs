//! Closed-form safety quantities of Safely-Exploring Policy Gradient (SEPG).
//!
//! Every function is pure, works in `f64`, validates its input and returns a
//! [`BoundsError`] instead of panicking or producing NaN. Requirements that no step can meet
//! are an ordinary outcome ([`outcome::StepOutcome::Infeasible`]), not an error.
//!
//! This crate knows nothing of rounding errors: its formulas are the thesis's, evaluated in
//! `f64`. The `sepg-certified` crate builds on it the steps whose guarantee survives rounding
//! (interval arithmetic and a-priori error bounds); the dependency goes one way only.
//!
//! The vocabulary, re-exported here: [`TaskConstants`] (validated once), [`Penalties`] (c and
//! d of a [`Family`] at one σ, validated once), [`Parabola`] (the bound a·x − b·x² that every
//! step rule solves), and the outcomes [`StepOutcome`] and [`SafeInterval`].
//!
//! | module | thesis |
//! |---|---|
//! | [`constants`] | ψ (Lemma A.1), c (Thms 3.14, 4.2), d (Thm 4.3), ∂c/∂σ |
//! | [`penalties`] | c and d of one family of constants at one σ, evaluated once |
//! | [`parabola`] | the parabola a·x − b·x² of Theorems 4.2–4.9 and its safe interval |
//! | [`outcome`] | the outcome of a safe-step computation |
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
//! | [`exploring`] | the exploring w-update: Theorem 4.3 with the confidence on ∇_w J only |
//! | [`direction`] | a safe step along any proposed direction of v (Theorem T, docs/THEOREMS.md) |
//!
//! ```
//! use sepg_bounds::{constants::TaskConstants, outcome::StepOutcome, v_update};
//! let k = TaskConstants::new(0.99, 4.0, 2.0, 4.0)?;
//! let outcome = v_update::safe_step(&k, 1.0, &[0.8, -0.2], 0.0)?;
//! let StepOutcome::Feasible(steps) = outcome else { panic!("monotonic improvement is feasible") };
//! assert!(v_update::bound(&k, 1.0, &[0.8, -0.2], steps.largest())? >= -1e-12);
//! # Ok::<(), sepg_bounds::BoundsError>(())
//! ```

#![deny(missing_docs)]

pub mod batch_size;
pub mod budget;
pub mod constants;
pub mod direction;
pub mod error;
pub mod exploring;
pub mod greedy;
pub mod high_probability;
pub mod outcome;
pub mod papini;
pub mod parabola;
pub mod penalties;
pub mod pirotta;
pub mod rigorous;
pub mod surrogate;
pub mod v_update;
pub mod w_update;

pub use constants::TaskConstants;
pub use error::BoundsError;
pub use outcome::{SafeInterval, StepOutcome};
pub use parabola::Parabola;
pub use penalties::{Family, Penalties};
