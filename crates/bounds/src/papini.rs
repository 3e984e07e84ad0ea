//! The non-scalar step size of Papini et al. (Theorem 3.14): the bound for a diagonal step
//! matrix Λ and its maximiser, the greedy-coordinate step.

use crate::constants::TaskConstants;
use crate::error::{BoundsError, finite_vector, inf_norm, no_overflow, same_length};
use crate::greedy::argmax_abs;
use crate::penalties::Penalties;

/// Lower bound on J(θ + Λ∇J) − J(θ) for a diagonal step Λ = diag(α₁, …, α_m) (Theorem 3.14).
///
/// # Formula
///
/// ```text
/// B(Λ) = ∇Jᵀ Λ ∇J − c(σ) ‖Λ ∇J‖₁²  =  Σ_i α_i ∇_i² − c(σ) (Σ_i |α_i ∇_i|)²
/// ```
///
/// `steps` holds the diagonal (α₁, …, α_m), same length as `grad`; performance units.
///
/// ```
/// use sepg_bounds::{constants::{TaskConstants, c}, papini::bound};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let cc = c(&k, 1.0)?;
/// let value = bound(&k, 1.0, &[2.0, 1.0], &[0.1, 0.0])?;
/// assert!((value - (0.4 - cc * 0.04)).abs() < 1e-14);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn bound(
    k: &TaskConstants,
    sigma: f64,
    grad: &[f64],
    steps: &[f64],
) -> Result<f64, BoundsError> {
    finite_vector("grad", grad)?;
    finite_vector("steps", steps)?;
    same_length("grad", grad, "steps", steps)?;
    bound_at(&Penalties::new(k, sigma)?, grad, steps)
}

/// [`bound`] for penalties evaluated once ([`Penalties`]), with c = `p.c()` of their
/// family; the same errors, without validating σ again.
pub fn bound_at(p: &Penalties, grad: &[f64], steps: &[f64]) -> Result<f64, BoundsError> {
    finite_vector("grad", grad)?;
    finite_vector("steps", steps)?;
    same_length("grad", grad, "steps", steps)?;
    let cc = p.c()?;
    let linear: f64 = grad.iter().zip(steps).map(|(g, a)| a * g * g).sum();
    let l1: f64 = grad.iter().zip(steps).map(|(g, a)| (a * g).abs()).sum();
    no_overflow("Theorem 3.14 bound", linear - cc * l1 * l1)
}

/// The maximiser of the Theorem 3.14 bound: the greedy-coordinate step.
#[derive(Debug, Clone, PartialEq)]
pub struct GreedyStep {
    /// k, the lowest index of argmax_i |∇_i|.
    pub index: usize,
    /// α_k = 1 / (2c).
    pub alpha: f64,
    /// The diagonal of Λ*: `alpha` at `index`, 0 elsewhere.
    pub steps: Vec<f64>,
    /// The improvement it guarantees, ‖∇J‖∞² / (4c) (eq. (4.9)).
    pub guarantee: f64,
}

/// The step of Theorem 3.14 maximising [`bound`]: only the coordinate with the largest
/// |∇_i J| moves (ties: lowest index).
///
/// # Formula
///
/// ```text
/// α_k = 1/(2c) if k = min argmax_i |∇_i J|, else 0;   guarantee = ‖∇J‖∞² / (4c)
/// ```
///
/// ```
/// use sepg_bounds::{constants::{TaskConstants, c}, papini::greedy_step};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let s = greedy_step(&k, 1.0, &[1.0, -3.0, 3.0])?;
/// assert_eq!(s.index, 1);
/// assert_eq!(s.steps, vec![0.0, 1.0 / (2.0 * c(&k, 1.0)?), 0.0]);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn greedy_step(k: &TaskConstants, sigma: f64, grad: &[f64]) -> Result<GreedyStep, BoundsError> {
    argmax_abs(grad)?;
    greedy_step_at(&Penalties::new(k, sigma)?, grad)
}

/// [`greedy_step`] for penalties evaluated once ([`Penalties`]), with c = `p.c()` of their
/// family; the same errors, without validating σ again.
pub fn greedy_step_at(p: &Penalties, grad: &[f64]) -> Result<GreedyStep, BoundsError> {
    let index = argmax_abs(grad)?;
    let cc = p.c()?;
    let alpha = no_overflow("alpha*", 1.0 / (2.0 * cc))?;
    let mut steps = vec![0.0; grad.len()];
    steps[index] = alpha;
    let n = inf_norm(grad);
    Ok(GreedyStep {
        index,
        alpha,
        steps,
        guarantee: no_overflow("C_max", n * n / (4.0 * cc))?,
    })
}
