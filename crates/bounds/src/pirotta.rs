//! The adaptive step size of Pirotta et al. (Section 3.4): Theorem 3.10, Corollary 3.11 and the
//! high-probability Theorem 3.12, for a Gaussian policy with fixed σ and the full-gradient
//! update θ' = θ + α∇J.

use crate::constants::TaskConstants;
use crate::error::{
    BoundsError, finite, finite_vector, inf_norm, no_overflow, non_negative, same_length,
};
use crate::penalties::Penalties;

/// Outcome of the adaptive step-size rule of Corollary 3.11 / Theorem 3.12.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AdaptiveStep {
    /// The maximiser `alpha` of the lower bound and the improvement it guarantees.
    Step {
        /// α*, the step size (units: parameter per gradient unit).
        alpha: f64,
        /// The guaranteed improvement at α* (performance units).
        guarantee: f64,
    },
    /// The gradient is zero: every step leaves θ unchanged.
    ZeroGradient,
    /// Every corrected component max(|∇̂_i| − ε_i, 0) is zero: the estimate is within noise.
    BelowNoise,
}

/// ‖x‖₂² / ‖x‖₁², computed without overflow (x non-zero, finite).
fn l2_over_l1_squared(x: &[f64]) -> f64 {
    let m = inf_norm(x);
    let (s2, s1) = x.iter().fold((0.0, 0.0), |(s2, s1), v| {
        let u = v.abs() / m;
        (s2 + u * u, s1 + u)
    });
    s2 / (s1 * s1)
}

/// Squared norms (‖x‖₂², ‖x‖₁²) of a finite vector, checked for overflow.
fn squared_norms(x: &[f64]) -> Result<(f64, f64), BoundsError> {
    let l2 = x.iter().map(|v| v * v).sum::<f64>();
    let l1 = x.iter().map(|v| v.abs()).sum::<f64>();
    Ok((
        no_overflow("||grad||_2^2", l2)?,
        no_overflow("||grad||_1^2", l1 * l1)?,
    ))
}

/// Lower bound on J(θ + α∇J) − J(θ) of Theorem 3.10 (Corollary 5.1 of Pirotta et al. 2013).
///
/// # Formula
///
/// ```text
/// B(α) = α ‖∇J‖₂² − α² c(σ) ‖∇J‖₁²
/// ```
///
/// with `c` of [`crate::constants::c`]. Any finite α (negative steps are allowed); performance
/// units.
///
/// ```
/// use sepg_bounds::{constants::{TaskConstants, c}, pirotta::bound};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let grad = [3.0, -4.0];
/// let cc = c(&k, 0.5)?;
/// let expected = 0.01 * 25.0 - 1e-4 * cc * 49.0;
/// assert!((bound(&k, 0.5, &grad, 0.01)? - expected).abs() < 1e-12);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn bound(k: &TaskConstants, sigma: f64, grad: &[f64], alpha: f64) -> Result<f64, BoundsError> {
    finite_vector("grad", grad)?;
    finite("alpha", alpha)?;
    bound_at(&Penalties::new(k, sigma)?, grad, alpha)
}

/// [`bound`] for penalties evaluated once ([`Penalties`]), with c = `p.c()` of their
/// family; the same errors, without validating σ again.
pub fn bound_at(p: &Penalties, grad: &[f64], alpha: f64) -> Result<f64, BoundsError> {
    finite_vector("grad", grad)?;
    finite("alpha", alpha)?;
    let cc = p.c()?;
    let (l2, l1) = squared_norms(grad)?;
    no_overflow("Theorem 3.10 bound", alpha * l2 - alpha * alpha * cc * l1)
}

/// The step size of Corollary 3.11, maximising the bound of Theorem 3.10.
///
/// # Formula
///
/// ```text
/// α* = (1 − γ)³ √(2π) σ³ ‖∇J‖₂² / ((γ √(2π) σ + 2 (1 − γ) |A|) R M_φ² ‖∇J‖₁²)
///    = ‖∇J‖₂² / (2 c(σ) ‖∇J‖₁²),
/// guarantee = α* ‖∇J‖₂² / 2
/// ```
///
/// Returns [`AdaptiveStep::ZeroGradient`] for ∇J = 0.
///
/// ```
/// use sepg_bounds::{constants::{TaskConstants, c}, pirotta::{optimal_step, AdaptiveStep}};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let AdaptiveStep::Step { alpha, guarantee } = optimal_step(&k, 0.5, &[1.0, 1.0])? else {
///     panic!("non-zero gradient")
/// };
/// // ‖∇‖₂²/‖∇‖₁² = 1/2
/// assert!((alpha - 0.5 / (2.0 * c(&k, 0.5)?)).abs() < 1e-15);
/// assert!((guarantee - alpha).abs() < 1e-15);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn optimal_step(
    k: &TaskConstants,
    sigma: f64,
    grad: &[f64],
) -> Result<AdaptiveStep, BoundsError> {
    finite_vector("grad", grad)?;
    optimal_step_at(&Penalties::new(k, sigma)?, grad)
}

/// [`optimal_step`] for penalties evaluated once ([`Penalties`]), with c = `p.c()` of their
/// family; the same errors, without validating σ again.
pub fn optimal_step_at(p: &Penalties, grad: &[f64]) -> Result<AdaptiveStep, BoundsError> {
    finite_vector("grad", grad)?;
    let cc = p.c()?;
    if inf_norm(grad) == 0.0 {
        return Ok(AdaptiveStep::ZeroGradient);
    }
    let alpha = no_overflow("alpha*", l2_over_l1_squared(grad) / (2.0 * cc))?;
    let (l2, _) = squared_norms(grad)?;
    Ok(AdaptiveStep::Step {
        alpha,
        guarantee: no_overflow("guarantee", alpha * l2 / 2.0)?,
    })
}

/// Lower- and upper-corrected gradients of Theorem 3.12, (max(|∇̂_i| − ε_i, 0), |∇̂_i| + ε_i).
fn corrected(grad_hat: &[f64], eps: &[f64]) -> Result<(Vec<f64>, Vec<f64>), BoundsError> {
    finite_vector("grad_hat", grad_hat)?;
    finite_vector("eps", eps)?;
    same_length("grad_hat", grad_hat, "eps", eps)?;
    for &e in eps {
        non_negative("eps", e)?;
    }
    let lower = grad_hat
        .iter()
        .zip(eps)
        .map(|(g, e)| (g.abs() - e).max(0.0))
        .collect();
    let upper = grad_hat
        .iter()
        .zip(eps)
        .map(|(g, e)| g.abs() + e)
        .collect::<Vec<_>>();
    for &u in &upper {
        no_overflow("|grad_hat| + eps", u)?;
    }
    Ok((lower, upper))
}

/// The high-probability lower bound of Theorem 3.12, as printed in the thesis.
///
/// # Formula
///
/// ```text
/// ∇⁻_i = max(|∇̂_i| − ε_i, 0),  ∇⁺_i = |∇̂_i| + ε_i
/// B(α) = α ‖∇⁻ / 2‖₂² − α² c(σ) ‖∇⁺‖₁²
/// ```
///
/// The "/2" inside the first norm is kept as printed; it only makes the bound more conservative
/// than the α‖∇⁻‖₂² of the source. Holds on the event that every |∇_i − ∇̂_i| ≤ ε_i; when
/// each of these m events has probability at least 1 − δ, the union bound gives probability
/// at least 1 − mδ (the (1 − δ)^m of the thesis would need the m components to be
/// independent, and they are estimated from one batch; docs/ERRATA.md §26). `eps` holds one
/// width ε_i ≥ 0 per component.
///
/// ```
/// use sepg_bounds::{constants::{TaskConstants, c}, pirotta::hp_bound};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let cc = c(&k, 1.0)?;
/// // ∇⁻ = [1, 0], ∇⁺ = [3, 1]
/// let expected = 0.1 * 0.25 - 0.01 * cc * 16.0;
/// assert!((hp_bound(&k, 1.0, &[2.0, -0.5], &[1.0, 0.5], 0.1)? - expected).abs() < 1e-12);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn hp_bound(
    k: &TaskConstants,
    sigma: f64,
    grad_hat: &[f64],
    eps: &[f64],
    alpha: f64,
) -> Result<f64, BoundsError> {
    finite("alpha", alpha)?;
    corrected(grad_hat, eps)?;
    hp_bound_at(&Penalties::new(k, sigma)?, grad_hat, eps, alpha)
}

/// [`hp_bound`] for penalties evaluated once ([`Penalties`]), with c = `p.c()` of their
/// family; the same errors, without validating σ again.
pub fn hp_bound_at(
    p: &Penalties,
    grad_hat: &[f64],
    eps: &[f64],
    alpha: f64,
) -> Result<f64, BoundsError> {
    finite("alpha", alpha)?;
    let (lower, upper) = corrected(grad_hat, eps)?;
    let cc = p.c()?;
    let (l2_lower, _) = squared_norms(&lower)?;
    let (_, l1_upper) = squared_norms(&upper)?;
    no_overflow(
        "Theorem 3.12 bound",
        alpha * l2_lower / 4.0 - alpha * alpha * cc * l1_upper,
    )
}

/// The step size maximising the printed Theorem 3.12 bound (the vertex of [`hp_bound`]).
///
/// # Formula
///
/// ```text
/// α* = ‖∇⁻/2‖₂² / (2 c(σ) ‖∇⁺‖₁²),   guarantee = α* ‖∇⁻/2‖₂² / 2
/// ```
///
/// The thesis prints ‖∇⁻‖₁² in the denominator of α*; the maximiser of its own polynomial has
/// ‖∇⁺‖₁², which is used here. Returns [`AdaptiveStep::BelowNoise`] when ∇⁻ = 0 and
/// [`AdaptiveStep::ZeroGradient`] when ∇⁺ = 0.
///
/// ```
/// use sepg_bounds::{constants::{TaskConstants, c}, pirotta::{hp_optimal_step, AdaptiveStep}};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let AdaptiveStep::Step { alpha, .. } = hp_optimal_step(&k, 1.0, &[2.0], &[1.0])? else {
///     panic!("above noise")
/// };
/// assert!((alpha - 0.25 / (2.0 * c(&k, 1.0)? * 9.0)).abs() < 1e-15);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn hp_optimal_step(
    k: &TaskConstants,
    sigma: f64,
    grad_hat: &[f64],
    eps: &[f64],
) -> Result<AdaptiveStep, BoundsError> {
    corrected(grad_hat, eps)?;
    hp_optimal_step_at(&Penalties::new(k, sigma)?, grad_hat, eps)
}

/// [`hp_optimal_step`] for penalties evaluated once ([`Penalties`]), with c = `p.c()` of their
/// family; the same errors, without validating σ again.
pub fn hp_optimal_step_at(
    p: &Penalties,
    grad_hat: &[f64],
    eps: &[f64],
) -> Result<AdaptiveStep, BoundsError> {
    let (lower, upper) = corrected(grad_hat, eps)?;
    let cc = p.c()?;
    if inf_norm(&upper) == 0.0 {
        return Ok(AdaptiveStep::ZeroGradient);
    }
    if inf_norm(&lower) == 0.0 {
        return Ok(AdaptiveStep::BelowNoise);
    }
    let half: Vec<f64> = lower.iter().map(|v| v / 2.0).collect();
    let (l2_half, _) = squared_norms(&half)?;
    let (_, l1_upper) = squared_norms(&upper)?;
    let alpha = no_overflow("alpha*", l2_half / (2.0 * cc * l1_upper))?;
    Ok(AdaptiveStep::Step {
        alpha,
        guarantee: no_overflow("guarantee", alpha * l2_half / 2.0)?,
    })
}
