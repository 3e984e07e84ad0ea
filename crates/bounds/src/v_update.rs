//! The mean-parameter update with fixed σ, Theorem 4.2 (eqs. (4.8)–(4.10)).
//!
//! The update is the greedy-coordinate step (4.11) of size α on the coordinate with the largest
//! |∇_{v_k} J|; every function takes the whole gradient ∇_v J and uses its ∞-norm.

use crate::constants::{TaskConstants, c};
use crate::error::{BoundsError, finite, finite_vector, inf_norm, no_overflow};
use crate::outcome::{
    SafeInterval, StepOutcome, feasible_interval, quadratic_c_max, solve_quadratic,
};

/// The step size of maximal guaranteed improvement, α* = 1/(2c) (Theorem 4.2).
///
/// # Formula
///
/// ```text
/// α* = 1 / (2 c(σ))
/// ```
///
/// ```
/// use sepg_bounds::{constants::{TaskConstants, c}, v_update::alpha_star};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// assert_eq!(alpha_star(&k, 0.5)?, 0.5 / c(&k, 0.5)?);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn alpha_star(k: &TaskConstants, sigma: f64) -> Result<f64, BoundsError> {
    no_overflow("alpha*", 0.5 / c(k, sigma)?)
}

/// The largest guaranteed improvement of the v-update, eq. (4.9).
///
/// # Formula
///
/// ```text
/// C_max^v = ‖∇_v J‖∞² / (4 c(σ))
/// ```
///
/// ```
/// use sepg_bounds::{constants::{TaskConstants, c}, v_update::c_max};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let expected = 4.0 / (4.0 * c(&k, 1.0)?);
/// assert!((c_max(&k, 1.0, &[1.0, -2.0])? - expected).abs() < 1e-15);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn c_max(k: &TaskConstants, sigma: f64, grad_v: &[f64]) -> Result<f64, BoundsError> {
    finite_vector("grad_v", grad_v)?;
    let n = inf_norm(grad_v);
    let n2 = no_overflow("||grad_v||^2", n * n)?;
    quadratic_c_max(n2, c(k, sigma)? * n2)
}

/// The lower bound (4.8) on J(v', w) − J(v, w) for a greedy-coordinate step of size α.
///
/// # Formula
///
/// ```text
/// B(α) = α ‖∇_v J‖∞² − α² c(σ) ‖∇_v J‖∞²
/// ```
///
/// Any finite α (negative steps included); performance units.
///
/// ```
/// use sepg_bounds::v_update::{alpha_star, bound, c_max};
/// use sepg_bounds::constants::TaskConstants;
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let g = [0.3, -0.7];
/// let top = bound(&k, 1.0, &g, alpha_star(&k, 1.0)?)?;
/// assert!((top - c_max(&k, 1.0, &g)?).abs() < 1e-15);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn bound(
    k: &TaskConstants,
    sigma: f64,
    grad_v: &[f64],
    alpha: f64,
) -> Result<f64, BoundsError> {
    finite_vector("grad_v", grad_v)?;
    finite("alpha", alpha)?;
    bound_with_c(c(k, sigma)?, grad_v, alpha, "Theorem 4.2 bound")
}

/// α‖∇_vJ‖∞² − α²·cc·‖∇_vJ‖∞² for a validated gradient and step and a penalty coefficient cc
/// (the thesis's c or the sound c of [`crate::rigorous::c`]).
pub(crate) fn bound_with_c(
    cc: f64,
    grad_v: &[f64],
    alpha: f64,
    quantity: &'static str,
) -> Result<f64, BoundsError> {
    let n = inf_norm(grad_v);
    let n2 = no_overflow("||grad_v||^2", n * n)?;
    no_overflow(quantity, alpha * n2 - alpha * alpha * cc * n2)
}

/// The safe step sizes of Theorem 4.2 for a required improvement C (eq. (4.10)).
///
/// # Formula
///
/// ```text
/// C ≤ C_max^v:  λ_v = √(1 − C / C_max^v),   α ∈ [α*(1 − λ_v), α*(1 + λ_v)],
///               largest ᾱ = (1 + λ_v) α*
/// C > C_max^v:  infeasible, best step α* (λ = 0)
/// ∇_v J = 0:    zero gradient (C_max = 0)
/// ```
///
/// `required` is the improvement this update must guarantee (e.g. (1 − ν)C, eq. (4.13)); any
/// finite real (C < 0 is a bounded worsening, Definition 4.2).
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, outcome::StepOutcome, v_update};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let g = [0.5];
/// let cmax = v_update::c_max(&k, 1.0, &g)?;
/// let StepOutcome::Feasible(s) = v_update::safe_step(&k, 1.0, &g, 0.75 * cmax)? else {
///     panic!("feasible")
/// };
/// let a = v_update::alpha_star(&k, 1.0)?;
/// assert!((s.lambda.unwrap() - 0.5).abs() < 1e-12);
/// assert!((s.largest() - 1.5 * a).abs() < 1e-12 * a);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn safe_step(
    k: &TaskConstants,
    sigma: f64,
    grad_v: &[f64],
    required: f64,
) -> Result<StepOutcome, BoundsError> {
    finite_vector("grad_v", grad_v)?;
    finite("required", required)?;
    safe_step_with_c(c(k, sigma)?, grad_v, required)
}

/// The safe steps of eq. (4.10) for a validated gradient and requirement and a penalty
/// coefficient cc: {α : α‖∇_vJ‖∞² − α²·cc·‖∇_vJ‖∞² ≥ C}.
pub(crate) fn safe_step_with_c(
    cc: f64,
    grad_v: &[f64],
    required: f64,
) -> Result<StepOutcome, BoundsError> {
    safe_step_with_norm(cc, inf_norm(grad_v), required)
}

/// [`safe_step_with_c`] for the norm n = ‖∇_vJ‖∞ of a validated gradient.
#[inline]
pub(crate) fn safe_step_with_norm(
    cc: f64,
    n: f64,
    required: f64,
) -> Result<StepOutcome, BoundsError> {
    let n2 = no_overflow("||grad_v||^2", n * n)?;
    solve_quadratic(n2, cc * n2, required)
}

/// The interval of [`safe_step_with_norm`] when it returns a feasible one, else `None`
/// ([`feasible_interval`]).
#[inline(always)]
pub(crate) fn feasible_with_norm(cc: f64, n: f64, required: f64) -> Option<SafeInterval> {
    let n2 = n * n;
    feasible_interval(n2, cc * n2, required)
}
