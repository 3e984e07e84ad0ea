//! Chebyshev batch sizes of Corollary 3.13 (Theorems 5.4 and 5.6 of Pirotta et al. 2013).
//!
//! The number N of H-step trajectories that guarantees |∇̂J − ∇J| ≤ ε with probability at
//! least 1 − δ for a Gaussian policy with standard deviation σ.

use crate::constants::TaskConstants;
use crate::error::{BoundsError, positive, unit_open};

/// Validates the common inputs and returns R² M_φ² / (δ ε² σ²).
fn front(
    k: &TaskConstants,
    sigma: f64,
    delta: f64,
    eps: f64,
    horizon: u32,
) -> Result<f64, BoundsError> {
    positive("sigma", sigma)?;
    unit_open("delta", delta)?;
    positive("eps", eps)?;
    if horizon == 0 {
        return Err(BoundsError::ZeroHorizon);
    }
    let rm = k.r_max() * k.m_phi() / (eps * sigma);
    Ok(rm * rm / delta)
}

/// Rounds a positive count up to an integer, reporting values beyond `u64` as overflow.
fn ceil_count(n: f64) -> Result<u64, BoundsError> {
    // 2^64 as f64; every finite f64 below it converts exactly after ceil.
    const LIMIT: f64 = 18_446_744_073_709_551_616.0;
    let n = n.ceil();
    if n.is_finite() && n < LIMIT {
        Ok(n.max(1.0) as u64)
    } else {
        Err(BoundsError::Overflow {
            quantity: "batch size",
        })
    }
}

/// Chebyshev batch size for REINFORCE (Corollary 3.13, corrected from Theorem 5.4 of the
/// source; the thesis prints H(γ^H)²/(…(1 − δ)²)).
///
/// # Formula
///
/// ```text
/// N = ⌈ R² M_φ² H (1 − γ^H)² / (δ ε² σ² (1 − γ)²) ⌉ = ⌈ R² M_φ² H (Σ_{t<H} γ^t)² / (δ ε² σ²) ⌉
/// ```
///
/// Domain: σ > 0, δ ∈ (0, 1), ε > 0, H ≥ 1. Errors on overflow beyond `u64`.
///
/// ```
/// use sepg_bounds::{batch_size::reinforce, constants::TaskConstants};
/// let k = TaskConstants::new(0.5, 1.0, 1.0, 1.0)?;
/// // H = 2: Σγ^t = 1.5, N = 2 · 2.25 / (0.5 · 1 · 1) = 9
/// assert_eq!(reinforce(&k, 1.0, 0.5, 1.0, 2)?, 9);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn reinforce(
    k: &TaskConstants,
    sigma: f64,
    delta: f64,
    eps: f64,
    horizon: u32,
) -> Result<u64, BoundsError> {
    let f = front(k, sigma, delta, eps, horizon)?;
    let mut geometric = 0.0;
    let mut power = 1.0;
    for _ in 0..horizon {
        geometric += power;
        power *= k.gamma();
    }
    ceil_count(f * f64::from(horizon) * geometric * geometric)
}

/// Chebyshev batch size for G(PO)MDP / PGT (Corollary 3.13, Theorem 5.6 of the source).
///
/// # Formula
///
/// ```text
/// N = ⌈ R² M_φ² / (δ ε² σ² (1 − γ)²) · [ (1 − γ^{2H})/(1 − γ²) + H γ^{2H} − 2γ^H (1 − γ^H)/(1 − γ) ] ⌉
///   = ⌈ R² M_φ² / (δ ε² σ²) · Σ_{t<H} ( γ^t (1 − γ^{H−t}) / (1 − γ) )² ⌉
/// ```
///
/// The bracket equals Σ_{t<H} (γ^t − γ^H)²; it is evaluated in the second, cancellation-free
/// form (the geometric sums are accumulated directly).
///
/// ```
/// use sepg_bounds::{batch_size::gpomdp, constants::TaskConstants};
/// let k = TaskConstants::new(0.5, 1.0, 1.0, 1.0)?;
/// // H = 2: terms (1 + 0.5)² and (0.5)², sum 2.5; N = 2.5 / 0.5 = 5
/// assert_eq!(gpomdp(&k, 1.0, 0.5, 1.0, 2)?, 5);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn gpomdp(
    k: &TaskConstants,
    sigma: f64,
    delta: f64,
    eps: f64,
    horizon: u32,
) -> Result<u64, BoundsError> {
    let f = front(k, sigma, delta, eps, horizon)?;
    let g = k.gamma();
    // For t = H−1 down to 0: partial = Σ_{j < H−t} γ^j, term_t = γ^t · partial.
    let mut partial = 0.0;
    let mut total = 0.0;
    for t in (0..horizon).rev() {
        partial = 1.0 + g * partial;
        let term = g.powi(t.min(i32::MAX as u32) as i32) * partial;
        total += term * term;
    }
    ceil_count(f * total)
}
