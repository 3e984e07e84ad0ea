//! Greedy-coordinate updates for multi-dimensional parameters (Section 4.3.4, docs/CONVENTIONS.md §4).
//!
//! Only the coordinate with the largest absolute partial derivative moves (ties: lowest
//! index): v_k ← v_k + ᾱ ∇_{v_k} J for the mean, and w_h ← w_h + β̄ ∇_{w_h} L for the
//! log-standard deviations, with d evaluated at σ_h.

use crate::constants::TaskConstants;
use crate::error::{BoundsError, finite, finite_vector, no_overflow, same_length};
use crate::outcome::StepOutcome;
use crate::{v_update, w_update};

/// The lowest index of argmax_i |x_i| (the coordinate chosen by (4.11), ties broken by the
/// lowest index as in Theorem 3.14).
///
/// Errors: empty or non-finite vector.
///
/// ```
/// use sepg_bounds::greedy::argmax_abs;
/// assert_eq!(argmax_abs(&[0.5, -2.0, 2.0])?, 1);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn argmax_abs(values: &[f64]) -> Result<usize, BoundsError> {
    finite_vector("gradient", values)?;
    let mut best = 0;
    for (i, v) in values.iter().enumerate() {
        if v.abs() > values[best].abs() {
            best = i;
        }
    }
    Ok(best)
}

/// Applies a greedy-coordinate step: returns `params` with params_k ← params_k + step · grad_k
/// for k = [`argmax_abs`]`(grad)`, all other entries unchanged (Section 4.3.4, with the
/// "v_k +" that the printed multi-dimensional update omits).
///
/// # Formula
///
/// ```text
/// θ'_k = θ_k + step · ∇_k  if k = min argmax_i |∇_i|,   θ'_i = θ_i otherwise
/// ```
///
/// ```
/// use sepg_bounds::greedy::coordinate_update;
/// let v = coordinate_update(&[1.0, 1.0], &[0.5, -2.0], 0.25)?;
/// assert_eq!(v, vec![1.0, 0.5]);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn coordinate_update(params: &[f64], grad: &[f64], step: f64) -> Result<Vec<f64>, BoundsError> {
    finite_vector("params", params)?;
    same_length("params", params, "grad", grad)?;
    finite("step", step)?;
    let k = argmax_abs(grad)?;
    let mut out = params.to_vec();
    out[k] = no_overflow("updated parameter", params[k] + step * grad[k])?;
    Ok(out)
}

/// A safe step for one chosen coordinate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoordinateStep {
    /// The coordinate that moves.
    pub index: usize,
    /// The safe steps for that coordinate.
    pub outcome: StepOutcome,
}

/// Greedy-coordinate v-update (Theorem 4.2 with (4.11)): the coordinate k and its safe steps
/// for a required improvement `required` (already split, e.g. (1 − ν)C of (4.13)).
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, greedy::v_step};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let s = v_step(&k, 1.0, &[0.1, -0.3], 0.0)?;
/// assert_eq!(s.index, 1);
/// assert!(s.outcome.is_feasible());
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn v_step(
    k: &TaskConstants,
    sigma: f64,
    grad_v: &[f64],
    required: f64,
) -> Result<CoordinateStep, BoundsError> {
    Ok(CoordinateStep {
        index: argmax_abs(grad_v)?,
        outcome: v_update::safe_step(k, sigma, grad_v, required)?,
    })
}

/// Greedy-coordinate w-update along the surrogate gradient (Theorem 4.5 per coordinate,
/// Section 4.3.4): h = min argmax_j |∇_{w_j} L|, and the safe steps of Theorem 4.5 for
/// coordinate h with d evaluated at σ_h.
///
/// `sigmas`, `grad_w_j`, `grad_w_l` have one entry per action dimension. The action volume
/// |A| of `k` is used as in the one-dimensional theorem.
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, greedy::w_step};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let s = w_step(&k, &[1.0, 0.5], &[0.2, 0.1], &[0.01, 0.3], -0.1)?;
/// assert_eq!(s.index, 1);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn w_step(
    k: &TaskConstants,
    sigmas: &[f64],
    grad_w_j: &[f64],
    grad_w_l: &[f64],
    required: f64,
) -> Result<CoordinateStep, BoundsError> {
    finite_vector("sigmas", sigmas)?;
    finite_vector("grad_w_j", grad_w_j)?;
    same_length("sigmas", sigmas, "grad_w_j", grad_w_j)?;
    same_length("sigmas", sigmas, "grad_w_l", grad_w_l)?;
    let h = argmax_abs(grad_w_l)?;
    Ok(CoordinateStep {
        index: h,
        outcome: w_update::safe_step_along_l(k, sigmas[h], grad_w_j[h], grad_w_l[h], required)?,
    })
}
