//! The surrogate objective L of Corollary 4.4 and its gradient with respect to w (Appendix B,
//! docs/CONVENTIONS.md §3).
//!
//! This crate follows Corollary 4.4, L = ‖∇_v J‖₂² / (4 m c(σ)). Appendix B writes
//! L = α*‖∇_v J‖₂² / (2m) with an α* that already carries a 1/m, i.e. an extra factor 1/m; the
//! two agree for m = 1.

use crate::constants::{TaskConstants, c, dc_dsigma};
use crate::error::{BoundsError, finite_vector, no_overflow, positive, same_length};

/// The surrogate objective L(v, w) of Corollary 4.4: a lower bound on the improvement of the
/// next v-update.
///
/// # Formula
///
/// ```text
/// L = ‖∇_v J‖₂² / (4 m c(σ)),   m = grad_v.len()
/// ```
///
/// `grad_v` is ∇_v J at (v, w) (m mean parameters); σ = e^w; performance units.
///
/// ```
/// use sepg_bounds::{constants::{TaskConstants, c}, surrogate::surrogate};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let l = surrogate(&k, 1.0, &[3.0, 4.0])?;
/// assert!((l - 25.0 / (8.0 * c(&k, 1.0)?)).abs() < 1e-14);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn surrogate(k: &TaskConstants, sigma: f64, grad_v: &[f64]) -> Result<f64, BoundsError> {
    finite_vector("grad_v", grad_v)?;
    let m = grad_v.len() as f64;
    let sq = no_overflow("||grad_v||_2^2", grad_v.iter().map(|g| g * g).sum::<f64>())?;
    no_overflow("L", sq / (4.0 * m * c(k, sigma)?))
}

/// The mixed derivative ∂_σ ∇_v J from h(θ) of Appendix B (eq. (B.2)).
///
/// # Formula
///
/// ```text
/// ∂_σ ∇_v J = h − (2/σ) ∇_v J
/// ```
///
/// `h` and `grad_v` have one entry per mean parameter.
///
/// ```
/// use sepg_bounds::surrogate::mixed_from_h;
/// assert_eq!(mixed_from_h(&[1.0, 0.0], &[0.5, 1.0], 2.0)?, vec![0.5, -1.0]);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn mixed_from_h(h: &[f64], grad_v: &[f64], sigma: f64) -> Result<Vec<f64>, BoundsError> {
    finite_vector("h", h)?;
    finite_vector("grad_v", grad_v)?;
    same_length("h", h, "grad_v", grad_v)?;
    positive("sigma", sigma)?;
    h.iter()
        .zip(grad_v)
        .map(|(h, g)| no_overflow("mixed derivative", h - 2.0 * g / sigma))
        .collect()
}

/// ∂_σ L, the derivative of the surrogate with respect to σ (Appendix B), with ∂c/∂σ analytic.
///
/// # Formula
///
/// ```text
/// ∂_σ L = ‖∇_v J‖₂² · ∂_σ(1/(4mc)) + (1/(4mc)) · 2 ⟨∇_v J, ∂_σ∇_v J⟩,
/// ∂_σ(1/(4mc)) = −(∂c/∂σ) / (4 m c²)
/// ```
///
/// `mixed` is ∂_σ ∇_v J (see [`mixed_from_h`]).
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, surrogate::{grad_sigma, surrogate}};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// // with ∇_v J independent of σ, ∂_σ L is the derivative of L through c alone
/// let h = 1e-6;
/// let fd = (surrogate(&k, 1.0 + h, &[0.3])? - surrogate(&k, 1.0 - h, &[0.3])?) / (2.0 * h);
/// assert!((grad_sigma(&k, 1.0, &[0.3], &[0.0])? - fd).abs() < 1e-7 * fd.abs());
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn grad_sigma(
    k: &TaskConstants,
    sigma: f64,
    grad_v: &[f64],
    mixed: &[f64],
) -> Result<f64, BoundsError> {
    finite_vector("grad_v", grad_v)?;
    finite_vector("mixed", mixed)?;
    same_length("grad_v", grad_v, "mixed", mixed)?;
    let m = grad_v.len() as f64;
    let cc = c(k, sigma)?;
    let dc = dc_dsigma(k, sigma)?;
    let sq = no_overflow("||grad_v||_2^2", grad_v.iter().map(|g| g * g).sum::<f64>())?;
    let inner = no_overflow(
        "<grad_v, mixed>",
        grad_v.iter().zip(mixed).map(|(g, x)| g * x).sum::<f64>(),
    )?;
    let inv = 1.0 / (4.0 * m * cc);
    let d_inv = no_overflow("d(1/(4mc))/dsigma", -dc / (4.0 * m * cc * cc))?;
    no_overflow("dL/dsigma", sq * d_inv + inv * 2.0 * inner)
}

/// ∇_w L = σ ∂_σ L, the surrogate gradient used by the w-update (4.18) (chain rule (B.1)).
///
/// # Formula
///
/// ```text
/// ∇_w L = σ · ∂_σ L
/// ```
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, surrogate::{grad_sigma, grad_w}};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let gs = grad_sigma(&k, 0.5, &[0.3], &[0.1])?;
/// assert_eq!(grad_w(&k, 0.5, &[0.3], &[0.1])?, 0.5 * gs);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn grad_w(
    k: &TaskConstants,
    sigma: f64,
    grad_v: &[f64],
    mixed: &[f64],
) -> Result<f64, BoundsError> {
    no_overflow("grad_w L", sigma * grad_sigma(k, sigma, grad_v, mixed)?)
}
