//! Certified safe steps of Safely-Exploring Policy Gradient: steps whose guarantee survives
//! floating-point rounding.
//!
//! The safe steps of `sepg-bounds` are computed in `f64`. Their largest step lies exactly
//! on the boundary {B(x) = C} of the safe set, so rounding puts it outside the true safe set
//! about half of the time: B(x) < C in real arithmetic by a few ulps, although the `f64`
//! computation says B(x) ≥ C. This crate evaluates each bound B at the returned step in
//! interval arithmetic ([`Interval`]), with the inputs taken as exact reals and every
//! irrational constant (ψ, √(2π), e^x) enclosed, and returns a step only when the lower end
//! of the enclosure is at least C. When the computed step fails that test it is moved toward
//! the vertex (the step of maximal guaranteed improvement) by the fewest ulps that pass; when
//! no `f64` step between the computed one and the vertex passes, the outcome is
//! [`Certified::Uncertifiable`]. docs/THEOREMS.md ("Certified steps") states what the
//! certificate means and what it assumes.
//!
//! Each bound form is an [`EnclosedBound`]; [`certify()`] turns the `f64`
//! [`StepOutcome`](sepg_bounds::StepOutcome) of any form into a [`Certified`] outcome, so a new
//! step form is certified by implementing the trait for its bound.
//!
//! The step functions below first try a cheaper certificate: the bound evaluated in plain
//! `f64` with an a-priori bound on its rounding error (standard model of floating-point
//! arithmetic, γ_k = k·u/(1 − k·u); the analysis is in docs/THEOREMS.md, "Certified steps"),
//! and fall back to interval arithmetic when that analysis does not apply or does not certify
//! a step ([`CertifiedStep::by_error_bound`] says which). The rigorous forms and
//! [`adaptive_step`] use interval arithmetic only. On the fast path the `f64` safe interval
//! comes from the error-free companions of the solvers ([`Parabola::feasible`] and
//! [`HighProbabilityBound::feasible_step`]), which return it bit for bit or nothing, so that it
//! stays in registers; every other outcome takes the full path.
//!
//! [`Parabola::feasible`]: sepg_bounds::Parabola::feasible
//! [`HighProbabilityBound::feasible_step`]: sepg_bounds::high_probability::HighProbabilityBound::feasible_step
//!
//! The crate depends on `sepg-bounds` and never the reverse: the plain `f64` formulas know
//! nothing of this layer. Whether the a-priori analysis applies to a task (its constants lie
//! in the range where no intermediate result of c(σ) or d(σ) underflows or overflows) is
//! decided here: once, by a [`CertifiedTask`] built from the
//! [`TaskConstants`](sepg_bounds::TaskConstants), or at each call when a step function is
//! given the task constants themselves.
//!
//! | module | contents |
//! |---|---|
//! | [`interval`] | outward-rounded interval arithmetic ([`Interval`]) |
//! | [`enclosure`] | enclosures of √(2π), ψ, c(σ), d(σ) and of every bound form ([`EnclosedBound`]) |
//! | [`certificate`] | the certificate of an `f64` outcome ([`certify()`], [`Certified`]) |
//! | [`steps`] | the certified step of each bound form (table below) |
//! | [`task`] | [`CertifiedTask`]: the task constants with their rounding range decided once |
//!
//! | function | bound | thesis |
//! |---|---|---|
//! | [`v_safe_step`] | α‖∇_vJ‖∞² − α²c‖∇_vJ‖∞² | Theorem 4.2 |
//! | [`w_safe_step_along_j`] | β(∇_wJ)² − β²d(∇_wJ)² | Theorem 4.3 |
//! | [`w_safe_step_along_l`] | β∇_wL∇_wJ − β²d(∇_wL)² | Theorem 4.5 |
//! | [`hp_v_safe_step`], [`hp_w_safe_step_along_j`], [`hp_w_safe_step_along_l`] | high-probability forms | Theorems 4.7–4.9 |
//! | [`rigorous_safe_step_along_j`], [`rigorous_safe_step_along_l`] | rigorous w-bound | [`sepg_bounds::rigorous`] |
//! | [`direction_safe_step`] | t(u·ĝ) − tΣ\|u_i\|ε_i − c(σ)κ_φt²‖u‖₂² (any direction u) | docs/THEOREMS.md, Theorem T |
//! | [`exploring_safe_step`] | Δw·∇̂_wJ − \|Δw\|·ε_J − d(σ)Δw² | docs/THEOREMS.md, Theorem E |
//! | [`adaptive_step`] | α‖∇J‖₂² − α²c(σ)‖∇J‖₁² (guarantee only) | Theorem 3.10, Corollary 3.11 |

//!
//! ```
//! use sepg_bounds::{TaskConstants, v_update};
//! let k = TaskConstants::new(0.99, 4.0, 2.0, 4.0)?;
//! let o = sepg_certified::v_safe_step(&k, 1.0, &[0.8], 0.0)?;
//! // the certified step is the f64 largest safe step, moved toward the vertex if need be
//! let f64_step = v_update::safe_step(&k, 1.0, &[0.8], 0.0)?.chosen_step().unwrap();
//! assert!(o.is_certified() && o.chosen_step().unwrap() <= f64_step);
//! assert!(o.bound().unwrap().lo() >= 0.0);
//! # Ok::<(), sepg_bounds::BoundsError>(())
//! ```

#![deny(missing_docs)]

pub mod certificate;
pub mod enclosure;
pub mod interval;
mod rounding;
pub mod steps;
pub mod task;

pub use certificate::{Certified, CertifiedStep, certify, certify_toward};
pub use enclosure::{
    EnclosedBound, ExploringEnclosure, HpEnclosure, Quadratic, RigorousEnclosure, c, d, psi,
    sqrt_2pi,
};
pub use interval::Interval;
pub use steps::{
    adaptive_step, direction_safe_step, exploring_safe_step, hp_v_safe_step,
    hp_w_safe_step_along_j, hp_w_safe_step_along_l, rigorous_safe_step_along_j,
    rigorous_safe_step_along_l, v_safe_step, w_safe_step_along_j, w_safe_step_along_l,
};
pub use task::{AsCertifiedTask, CertifiedTask};
