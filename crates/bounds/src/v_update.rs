//! The mean-parameter update with fixed σ, Theorem 4.2 (eqs. (4.8)–(4.10)).
//!
//! The update is the greedy-coordinate step (4.11) of size α on the coordinate with the largest
//! |∇_{v_k} J|; every function takes the whole gradient ∇_v J and uses its ∞-norm.

use crate::constants::TaskConstants;
use crate::error::{BoundsError, finite, finite_vector, inf_norm, no_overflow};
use crate::outcome::StepOutcome;
use crate::parabola::Parabola;
use crate::penalties::Penalties;

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
    alpha_star_at(&Penalties::new(k, sigma)?)
}

/// [`alpha_star`] for penalties evaluated once ([`Penalties`]), with c = `p.c()` of their
/// family; the same errors, without validating σ again.
pub fn alpha_star_at(p: &Penalties) -> Result<f64, BoundsError> {
    no_overflow("alpha*", 0.5 / p.c()?)
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
    no_overflow("||grad_v||^2", n * n)?;
    c_max_at(&Penalties::new(k, sigma)?, grad_v)
}

/// [`c_max`] for penalties evaluated once ([`Penalties`]), with c = `p.c()` of their
/// family; the same errors, without validating σ again.
pub fn c_max_at(p: &Penalties, grad_v: &[f64]) -> Result<f64, BoundsError> {
    finite_vector("grad_v", grad_v)?;
    let n = inf_norm(grad_v);
    let n2 = no_overflow("||grad_v||^2", n * n)?;
    Parabola::new(n2, p.c()? * n2).c_max()
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
    bound_at(&Penalties::new(k, sigma)?, grad_v, alpha)
}

/// [`bound`] for penalties evaluated once ([`Penalties`]), with c = `p.c()` of their
/// family; the same errors, without validating σ again.
pub fn bound_at(p: &Penalties, grad_v: &[f64], alpha: f64) -> Result<f64, BoundsError> {
    finite_vector("grad_v", grad_v)?;
    finite("alpha", alpha)?;
    bound_with_c(p.c()?, grad_v, alpha, "Theorem 4.2 bound")
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
    parabola(Penalties::new(k, sigma)?.c()?, inf_norm(grad_v))?.solve(required)
}

/// [`safe_step`] for penalties evaluated once ([`Penalties`]): the safe steps of eq. (4.10)
/// with c = `p.c()`.
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, penalties::Penalties, v_update};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let p = Penalties::new(&k, 1.0)?;
/// assert_eq!(v_update::safe_step_at(&p, &[0.5], 0.0)?, v_update::safe_step(&k, 1.0, &[0.5], 0.0)?);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn safe_step_at(
    p: &Penalties,
    grad_v: &[f64],
    required: f64,
) -> Result<StepOutcome, BoundsError> {
    finite_vector("grad_v", grad_v)?;
    finite("required", required)?;
    parabola(p.c()?, inf_norm(grad_v))?.solve(required)
}

/// The parabola of Theorem 4.2 for the penalty coefficient `c` (the thesis's c, or the sound
/// c of [`crate::rigorous::c`]) and the norm `norm` = ‖∇_v J‖∞ of a validated gradient.
///
/// # Formula
///
/// ```text
/// B(α) = a·α − b·α²,   a = ‖∇_v J‖∞²,   b = c·‖∇_v J‖∞²
/// ```
///
/// Errors: [`BoundsError::Overflow`] when ‖∇_v J‖∞² is not finite.
///
/// ```
/// use sepg_bounds::v_update::parabola;
/// let p = parabola(3.0, 0.5)?;
/// assert_eq!((p.linear, p.quadratic), (0.25, 0.75));
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
#[inline(always)]
pub fn parabola(c: f64, norm: f64) -> Result<Parabola, BoundsError> {
    let n2 = no_overflow("||grad_v||^2", norm * norm)?;
    Ok(Parabola::new(n2, c * n2))
}
