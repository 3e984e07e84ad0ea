//! The variance-parameter update w ← w + β·(direction), Theorems 4.3 and 4.5
//! (eqs. (4.15)–(4.19)), in the thesis form that neglects O(Δw³) terms. The rigorous
//! counterpart is in [`crate::rigorous`].
//!
//! σ = e^w is the standard deviation *before* the update; `grad_w_j` is ∇_w J and `grad_w_l`
//! is ∇_w L (the surrogate gradient of [`crate::surrogate`]), both at (v^{t+1}, w^t).

use crate::constants::TaskConstants;
use crate::error::{BoundsError, finite, no_overflow};
use crate::outcome::StepOutcome;
use crate::parabola::Parabola;
use crate::penalties::Penalties;

/// β* = 1/(2d), the step of maximal guaranteed improvement along ∇_w J (Theorem 4.3).
///
/// # Formula
///
/// ```text
/// β* = 1 / (2 d(σ))
/// ```
///
/// ```
/// use sepg_bounds::{constants::{TaskConstants, d}, w_update::beta_star};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// assert_eq!(beta_star(&k, 0.5)?, 0.5 / d(&k, 0.5)?);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn beta_star(k: &TaskConstants, sigma: f64) -> Result<f64, BoundsError> {
    beta_star_at(&Penalties::new(k, sigma)?)
}

/// [`beta_star`] for penalties evaluated once ([`Penalties`]), with d = `p.d()` of their
/// family; the same errors, without validating σ again.
pub fn beta_star_at(p: &Penalties) -> Result<f64, BoundsError> {
    no_overflow("beta*", 0.5 / p.d()?)
}

/// The largest guaranteed improvement of the w-update, eq. (4.16) (also that of Theorem 4.5).
///
/// # Formula
///
/// ```text
/// C_max^w = (∇_w J)² / (4 d(σ))
/// ```
///
/// ```
/// use sepg_bounds::{constants::{TaskConstants, d}, w_update::c_max};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// assert!((c_max(&k, 1.0, -2.0)? - 1.0 / d(&k, 1.0)?).abs() < 1e-15);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn c_max(k: &TaskConstants, sigma: f64, grad_w_j: f64) -> Result<f64, BoundsError> {
    finite("grad_w_j", grad_w_j)?;
    no_overflow("(grad_w_j)^2", grad_w_j * grad_w_j)?;
    c_max_at(&Penalties::new(k, sigma)?, grad_w_j)
}

/// [`c_max`] for penalties evaluated once ([`Penalties`]), with d = `p.d()` of their
/// family; the same errors, without validating σ again.
pub fn c_max_at(p: &Penalties, grad_w_j: f64) -> Result<f64, BoundsError> {
    finite("grad_w_j", grad_w_j)?;
    let g2 = no_overflow("(grad_w_j)^2", grad_w_j * grad_w_j)?;
    Parabola::new(g2, p.d()? * g2).c_max()
}

/// The lower bound (4.15) for the step Δw = β ∇_w J.
///
/// # Formula
///
/// ```text
/// B(β) = β (∇_w J)² − β² d(σ) (∇_w J)²
/// ```
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, w_update::{beta_star, bound_along_j, c_max}};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let top = bound_along_j(&k, 1.0, 0.3, beta_star(&k, 1.0)?)?;
/// assert!((top - c_max(&k, 1.0, 0.3)?).abs() < 1e-15);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn bound_along_j(
    k: &TaskConstants,
    sigma: f64,
    grad_w_j: f64,
    beta: f64,
) -> Result<f64, BoundsError> {
    finite("grad_w_j", grad_w_j)?;
    finite("beta", beta)?;
    no_overflow("(grad_w_j)^2", grad_w_j * grad_w_j)?;
    bound_along_j_at(&Penalties::new(k, sigma)?, grad_w_j, beta)
}

/// [`bound_along_j`] for penalties evaluated once ([`Penalties`]), with d = `p.d()` of their
/// family; the same errors, without validating σ again.
pub fn bound_along_j_at(p: &Penalties, grad_w_j: f64, beta: f64) -> Result<f64, BoundsError> {
    finite("grad_w_j", grad_w_j)?;
    finite("beta", beta)?;
    let g2 = no_overflow("(grad_w_j)^2", grad_w_j * grad_w_j)?;
    no_overflow("Theorem 4.3 bound", beta * g2 - beta * beta * p.d()? * g2)
}

/// The safe steps along ∇_w J for a required improvement νC (Theorem 4.3, eq. (4.17)).
///
/// # Formula
///
/// ```text
/// νC ≤ C_max^w:  λ_w = √(1 − νC / C_max^w),  β ∈ [β*(1 − λ_w), β*(1 + λ_w)]
/// νC > C_max^w:  infeasible, best step β*
/// ```
///
/// `required` is the improvement this update must guarantee (νC of (4.14)).
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, w_update};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let o = w_update::safe_step_along_j(&k, 1.0, 0.3, 0.0)?;
/// let b = w_update::beta_star(&k, 1.0)?;
/// assert!((o.chosen_step().unwrap() - 2.0 * b).abs() < 1e-12 * b);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn safe_step_along_j(
    k: &TaskConstants,
    sigma: f64,
    grad_w_j: f64,
    required: f64,
) -> Result<StepOutcome, BoundsError> {
    finite("grad_w_j", grad_w_j)?;
    finite("required", required)?;
    parabola_along_j(Penalties::new(k, sigma)?.d()?, grad_w_j)?.solve(required)
}

/// [`safe_step_along_j`] for penalties evaluated once ([`Penalties`]), with d = `p.d()`.
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, penalties::Penalties, w_update};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let p = Penalties::new(&k, 1.0)?;
/// let expected = w_update::safe_step_along_j(&k, 1.0, 0.3, 0.0)?;
/// assert_eq!(w_update::safe_step_along_j_at(&p, 0.3, 0.0)?, expected);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn safe_step_along_j_at(
    p: &Penalties,
    grad_w_j: f64,
    required: f64,
) -> Result<StepOutcome, BoundsError> {
    finite("grad_w_j", grad_w_j)?;
    finite("required", required)?;
    parabola_along_j(p.d()?, grad_w_j)?.solve(required)
}

/// The parabola of Theorem 4.3 (eq. (4.15)) for the penalty `d` and a finite ∇_w J.
///
/// # Formula
///
/// ```text
/// B(β) = a·β − b·β²,   a = (∇_w J)²,   b = d·(∇_w J)²
/// ```
///
/// Errors: [`BoundsError::Overflow`] when (∇_w J)² is not finite.
///
/// ```
/// let p = sepg_bounds::w_update::parabola_along_j(2.0, 0.5)?;
/// assert_eq!((p.linear, p.quadratic), (0.25, 0.5));
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
#[inline(always)]
pub fn parabola_along_j(d: f64, grad_w_j: f64) -> Result<Parabola, BoundsError> {
    let g2 = no_overflow("(grad_w_j)^2", grad_w_j * grad_w_j)?;
    Ok(Parabola::new(g2, d * g2))
}

/// The lower bound of Theorem 4.5 for the step Δw = β ∇_w L (β of either sign).
///
/// # Formula
///
/// ```text
/// B(β) = β ∇_w L ∇_w J − β² d(σ) (∇_w L)²
/// ```
///
/// ```
/// use sepg_bounds::{constants::{TaskConstants, d}, w_update::bound_along_l};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let value = bound_along_l(&k, 1.0, 0.3, -2.0, -0.1)?;
/// let expected = 0.06 - 0.04 * d(&k, 1.0)?;
/// assert!((value - expected).abs() < 1e-12 * expected.abs());
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn bound_along_l(
    k: &TaskConstants,
    sigma: f64,
    grad_w_j: f64,
    grad_w_l: f64,
    beta: f64,
) -> Result<f64, BoundsError> {
    finite("grad_w_j", grad_w_j)?;
    finite("grad_w_l", grad_w_l)?;
    finite("beta", beta)?;
    no_overflow("grad_w_l * grad_w_j", grad_w_l * grad_w_j)?;
    no_overflow("(grad_w_l)^2", grad_w_l * grad_w_l)?;
    bound_along_l_at(&Penalties::new(k, sigma)?, grad_w_j, grad_w_l, beta)
}

/// [`bound_along_l`] for penalties evaluated once ([`Penalties`]), with d = `p.d()` of their
/// family; the same errors, without validating σ again.
pub fn bound_along_l_at(
    p: &Penalties,
    grad_w_j: f64,
    grad_w_l: f64,
    beta: f64,
) -> Result<f64, BoundsError> {
    finite("grad_w_j", grad_w_j)?;
    finite("grad_w_l", grad_w_l)?;
    finite("beta", beta)?;
    let lj = no_overflow("grad_w_l * grad_w_j", grad_w_l * grad_w_j)?;
    let l2 = no_overflow("(grad_w_l)^2", grad_w_l * grad_w_l)?;
    no_overflow("Theorem 4.5 bound", beta * lj - beta * beta * p.d()? * l2)
}

/// β̃ = ∇_w J / (2 d ∇_w L), the step along ∇_w L of maximal guaranteed improvement
/// (Theorem 4.5); negative when the two gradients disagree in sign.
///
/// # Formula
///
/// ```text
/// β̃ = ∇_w J / (2 d(σ) ∇_w L)
/// ```
///
/// Errors: ∇_w L = 0 (no direction to step along).
///
/// ```
/// use sepg_bounds::{constants::{TaskConstants, d}, w_update::beta_tilde};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// assert!((beta_tilde(&k, 1.0, 0.3, -2.0)? + 0.075 / d(&k, 1.0)?).abs() < 1e-15);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn beta_tilde(
    k: &TaskConstants,
    sigma: f64,
    grad_w_j: f64,
    grad_w_l: f64,
) -> Result<f64, BoundsError> {
    finite("grad_w_j", grad_w_j)?;
    finite("grad_w_l", grad_w_l)?;
    if grad_w_l == 0.0 {
        return Err(BoundsError::OutOfDomain {
            name: "grad_w_l",
            value: grad_w_l,
            domain: "non-zero reals",
        });
    }
    beta_tilde_at(&Penalties::new(k, sigma)?, grad_w_j, grad_w_l)
}

/// [`beta_tilde`] for penalties evaluated once ([`Penalties`]), with d = `p.d()` of their
/// family; the same errors, without validating σ again.
pub fn beta_tilde_at(p: &Penalties, grad_w_j: f64, grad_w_l: f64) -> Result<f64, BoundsError> {
    finite("grad_w_j", grad_w_j)?;
    finite("grad_w_l", grad_w_l)?;
    if grad_w_l == 0.0 {
        return Err(BoundsError::OutOfDomain {
            name: "grad_w_l",
            value: grad_w_l,
            domain: "non-zero reals",
        });
    }
    no_overflow("beta~", grad_w_j / (2.0 * p.d()? * grad_w_l))
}

/// The safe steps along ∇_w L for a required improvement νC (Theorem 4.5, eq. (4.19)).
///
/// # Formula
///
/// ```text
/// νC ≤ C_max^w:  |β − β̃| ≤ λ_w |β̃|,  λ_w = √(1 − νC / C_max^w),
///                largest β̄ = β̃ + λ_w |β̃|  (eq. (4.20))
/// ```
///
/// With ∇_w L = 0 the outcome is [`StepOutcome::ZeroGradient`]. With ∇_w J = 0 ≠ ∇_w L,
/// C_max = 0 and, for νC ≤ 0, the safe steps are |β| ≤ √(−νC / (d (∇_w L)²)) (λ undefined).
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, outcome::StepOutcome, w_update};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// // gradients of opposite sign and a budget to spend: the largest step follows ∇_w L
/// let StepOutcome::Feasible(s) = w_update::safe_step_along_l(&k, 1.0, 0.3, -2.0, -0.1)? else {
///     panic!("feasible")
/// };
/// assert!(s.vertex < 0.0 && s.largest() > 0.0);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn safe_step_along_l(
    k: &TaskConstants,
    sigma: f64,
    grad_w_j: f64,
    grad_w_l: f64,
    required: f64,
) -> Result<StepOutcome, BoundsError> {
    finite("grad_w_j", grad_w_j)?;
    finite("grad_w_l", grad_w_l)?;
    finite("required", required)?;
    let d = Penalties::new(k, sigma)?.d()?;
    parabola_along_l(d, grad_w_j, grad_w_l)?.solve(required)
}

/// [`safe_step_along_l`] for penalties evaluated once ([`Penalties`]), with d = `p.d()`.
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, penalties::Penalties, w_update};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let p = Penalties::new(&k, 1.0)?;
/// let expected = w_update::safe_step_along_l(&k, 1.0, 0.3, -2.0, -0.1)?;
/// assert_eq!(w_update::safe_step_along_l_at(&p, 0.3, -2.0, -0.1)?, expected);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn safe_step_along_l_at(
    p: &Penalties,
    grad_w_j: f64,
    grad_w_l: f64,
    required: f64,
) -> Result<StepOutcome, BoundsError> {
    finite("grad_w_j", grad_w_j)?;
    finite("grad_w_l", grad_w_l)?;
    finite("required", required)?;
    parabola_along_l(p.d()?, grad_w_j, grad_w_l)?.solve(required)
}

/// The parabola of Theorem 4.5 for the penalty `d` and finite ∇_w J, ∇_w L.
///
/// # Formula
///
/// ```text
/// B(β) = a·β − b·β²,   a = ∇_w L·∇_w J,   b = d·(∇_w L)²
/// ```
///
/// Errors: [`BoundsError::Overflow`] when ∇_w L·∇_w J or (∇_w L)² is not finite.
///
/// ```
/// let p = sepg_bounds::w_update::parabola_along_l(2.0, 0.5, -2.0)?;
/// assert_eq!((p.linear, p.quadratic), (-1.0, 8.0));
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
#[inline(always)]
pub fn parabola_along_l(d: f64, grad_w_j: f64, grad_w_l: f64) -> Result<Parabola, BoundsError> {
    let lj = no_overflow("grad_w_l * grad_w_j", grad_w_l * grad_w_j)?;
    let l2 = no_overflow("(grad_w_l)^2", grad_w_l * grad_w_l)?;
    Ok(Parabola::new(lj, d * l2))
}
