//! The closed forms under test, as printed in the thesis, gathered in [`BoundFns`] so that a test
//! can replace one by a deliberately broken version and watch the harness catch it.
//!
//! All quantities use the thesis's conventions: unnormalised values J, V, Q, A and the
//! normalised future-state distribution d (Definition 2.5).

use sepg_bounds::BoundsError;
use sepg_bounds::constants::TaskConstants;
use sepg_bounds::outcome::StepOutcome;

/// Function pointers to every closed form checked by the harness; [`BoundFns::default`] holds
/// the printed formulas.
#[derive(Debug, Clone, Copy)]
pub struct BoundFns {
    /// Kakade's CPI lower bound, eq. (3.2): see [`cpi_bound`].
    pub cpi_bound: fn(f64, f64, f64, f64) -> f64,
    /// CPI step size α*, eq. (3.5): see [`cpi_alpha_star`].
    pub cpi_alpha_star: fn(f64, f64, f64) -> f64,
    /// CPI guaranteed improvement, eq. (3.6): see [`cpi_guarantee`].
    pub cpi_guarantee: fn(f64, f64) -> f64,
    /// Bound on ‖d^{π'} − d^π‖₁, eq. (3.8): see [`state_distribution_bound`].
    pub state_distribution_bound: fn(f64, f64) -> f64,
    /// Pirotta's advantage-based bound, eq. (3.10): see [`pirotta_advantage_bound`].
    pub pirotta_advantage_bound: fn(f64, f64, f64, f64) -> f64,
    /// Pirotta's Q-based bound, eq. (3.12) and Theorem 3.8: see [`pirotta_q_bound`].
    pub pirotta_q_bound: fn(f64, f64, f64, f64) -> f64,
    /// USPI step size, Theorem 3.7: see [`uspi_alpha_star`].
    pub uspi_alpha_star: fn(f64, f64, f64, f64) -> f64,
    /// USPI guaranteed improvement for α* ≤ 1, Theorem 3.7: see [`uspi_guarantee`].
    pub uspi_guarantee: fn(f64, f64, f64, f64) -> f64,
    /// TRPO penalty coefficient C, Theorem 3.16: see [`trpo_penalty`].
    pub trpo_penalty: fn(f64, f64) -> f64,
    /// The constant ψ of Lemma A.1 (default: `sepg_bounds::constants::psi`).
    pub psi: fn() -> f64,
    /// Lemma A.3's bound on ‖π_{w'} − π_w‖²: see [`l1_squared_bound`].
    pub l1_squared_bound: fn(f64) -> f64,
    /// Theorem 4.2, eq. (4.8): lower bound of the greedy-coordinate v-update for a step α
    /// (default `sepg_bounds::v_update::bound`).
    pub v_update_bound: fn(&TaskConstants, f64, &[f64], f64) -> Result<f64, BoundsError>,
    /// Theorem 4.2, eqs. (4.9)–(4.10): safe step sizes for a required improvement C
    /// (default `sepg_bounds::v_update::safe_step`).
    pub v_safe_step: fn(&TaskConstants, f64, &[f64], f64) -> Result<StepOutcome, BoundsError>,
    /// The penalty c(σ) of the task constants' family, for the tight constants of
    /// docs/THEOREMS.md "Tight constants" c = ρ R M_φ² S_H / σ² (default
    /// `sepg_bounds::constants::c`).
    pub tight_c: fn(&TaskConstants, f64) -> Result<f64, BoundsError>,
    /// The penalty d(σ) of the task constants' family, for the tight constants d = 2ρ R S_H
    /// (default `sepg_bounds::constants::d`).
    pub tight_d: fn(&TaskConstants, f64) -> Result<f64, BoundsError>,
}

impl Default for BoundFns {
    /// The formulas as printed in the thesis (ψ and the Chapter 4 bounds from `sepg-bounds`).
    fn default() -> Self {
        Self {
            cpi_bound,
            cpi_alpha_star,
            cpi_guarantee,
            state_distribution_bound,
            pirotta_advantage_bound,
            pirotta_q_bound,
            uspi_alpha_star,
            uspi_guarantee,
            trpo_penalty,
            psi: sepg_bounds::constants::psi,
            l1_squared_bound,
            v_update_bound: sepg_bounds::v_update::bound,
            v_safe_step: sepg_bounds::v_update::safe_step,
            tight_c: sepg_bounds::constants::c,
            tight_d: sepg_bounds::constants::d,
        }
    }
}

/// Kakade & Langford's conservative-policy-iteration bound, Theorem 3.1, eq. (3.2): lower bound
/// on `J(π') − J(π)` for `π' = (1 − α)π + απ̄`.
///
/// # Formula
/// ```text
/// α / (1 − γ) · ( 𝔸 − 2αγε / (1 − γ(1 − α)) )
/// ```
/// with 𝔸 the policy advantage (eq. 3.3) and ε = max_s |E_{a∼π̄} A_π(s, a)| (eq. 3.4).
///
/// # Example
/// ```
/// use sepg_verification::bound_fns::cpi_bound;
/// assert_eq!(cpi_bound(0.0, 1.0, 1.0, 0.5), 0.0);
/// // α = 1, γ = 1/2: 2 · (1 − 2 · 0.5 · 0.25 / 1) = 1.5.
/// assert!((cpi_bound(1.0, 1.0, 0.25, 0.5) - 1.5).abs() < 1e-15);
/// ```
pub fn cpi_bound(alpha: f64, policy_advantage: f64, epsilon: f64, gamma: f64) -> f64 {
    alpha / (1.0 - gamma)
        * (policy_advantage - 2.0 * alpha * gamma * epsilon / (1.0 - gamma * (1.0 - alpha)))
}

/// CPI step size of Theorem 3.2, eq. (3.5), with R the maximum reward.
///
/// # Formula
/// ```text
/// α* = (1 − γ) 𝔸 / (4R)
/// ```
///
/// # Example
/// ```
/// use sepg_verification::bound_fns::cpi_alpha_star;
/// assert_eq!(cpi_alpha_star(2.0, 1.0, 0.5), 0.25);
/// ```
pub fn cpi_alpha_star(policy_advantage: f64, r: f64, gamma: f64) -> f64 {
    (1.0 - gamma) * policy_advantage / (4.0 * r)
}

/// CPI guaranteed improvement of Theorem 3.2, eq. (3.6).
///
/// # Formula
/// ```text
/// 𝔸² / (8R)
/// ```
///
/// # Example
/// ```
/// use sepg_verification::bound_fns::cpi_guarantee;
/// assert_eq!(cpi_guarantee(2.0, 1.0), 0.5);
/// ```
pub fn cpi_guarantee(policy_advantage: f64, r: f64) -> f64 {
    policy_advantage * policy_advantage / (8.0 * r)
}

/// Theorem 3.4, eq. (3.8): upper bound on `‖d^{π'}_μ − d^π_μ‖₁`.
///
/// # Formula
/// ```text
/// γ / (1 − γ)² · D_∞^{π,π'}
/// ```
///
/// # Example
/// ```
/// use sepg_verification::bound_fns::state_distribution_bound;
/// assert_eq!(state_distribution_bound(1.0, 0.5), 2.0);
/// ```
pub fn state_distribution_bound(d_inf: f64, gamma: f64) -> f64 {
    gamma / ((1.0 - gamma) * (1.0 - gamma)) * d_inf
}

/// Theorem 3.5, eq. (3.10): lower bound on `J(π') − J(π)` using a baseline policy π_b.
///
/// # Formula
/// ```text
/// d^{π_b}_μ A^{π'}_π / (1 − γ) − γ / (1 − γ)² · D_∞^{π_b,π'} · ΔA^{π'}_π / 2
/// ```
///
/// # Example
/// ```
/// use sepg_verification::bound_fns::pirotta_advantage_bound;
/// assert_eq!(pirotta_advantage_bound(1.0, 0.0, 5.0, 0.5), 2.0);
/// ```
pub fn pirotta_advantage_bound(
    weighted_advantage: f64,
    d_inf: f64,
    advantage_spread: f64,
    gamma: f64,
) -> f64 {
    weighted_advantage / (1.0 - gamma)
        - gamma / ((1.0 - gamma) * (1.0 - gamma)) * d_inf * advantage_spread / 2.0
}

/// Theorem 3.6, eq. (3.12) (and Theorem 3.8 on finite MDPs): lower bound on `J(π') − J(π)`
/// using the sup-norm of Q.
///
/// # Formula
/// ```text
/// 𝔸^{π'}_{π,μ} / (1 − γ) − γ / (1 − γ)² · (D_∞^{π,π'})² · ‖Q^π‖_∞ / 2
/// ```
///
/// # Example
/// ```
/// use sepg_verification::bound_fns::pirotta_q_bound;
/// assert_eq!(pirotta_q_bound(1.0, 1.0, 1.0, 0.5), 1.0);
/// ```
pub fn pirotta_q_bound(policy_advantage: f64, d_inf: f64, q_norm: f64, gamma: f64) -> f64 {
    policy_advantage / (1.0 - gamma)
        - gamma / ((1.0 - gamma) * (1.0 - gamma)) * d_inf * d_inf * q_norm / 2.0
}

/// USPI step size of Theorem 3.7 (with D_∞ and ΔA taken between π and the greedy π̄).
///
/// # Formula
/// ```text
/// α* = (1 − γ) 𝔸^{π̄}_{π,μ} / (γ D_∞^{π,π̄} ΔA^{π̄}_π)
/// ```
///
/// # Example
/// ```
/// use sepg_verification::bound_fns::uspi_alpha_star;
/// assert_eq!(uspi_alpha_star(1.0, 1.0, 1.0, 0.5), 1.0);
/// ```
pub fn uspi_alpha_star(
    policy_advantage: f64,
    d_inf: f64,
    advantage_spread: f64,
    gamma: f64,
) -> f64 {
    (1.0 - gamma) * policy_advantage / (gamma * d_inf * advantage_spread)
}

/// USPI guaranteed improvement of Theorem 3.7 when α* ≤ 1.
///
/// # Formula
/// ```text
/// 𝔸² / (2γ D_∞^{π,π̄} ΔA^{π̄}_π)
/// ```
///
/// # Example
/// ```
/// use sepg_verification::bound_fns::uspi_guarantee;
/// assert_eq!(uspi_guarantee(1.0, 1.0, 1.0, 0.5), 1.0);
/// ```
pub fn uspi_guarantee(policy_advantage: f64, d_inf: f64, advantage_spread: f64, gamma: f64) -> f64 {
    policy_advantage * policy_advantage / (2.0 * gamma * d_inf * advantage_spread)
}

/// TRPO penalty coefficient of Theorem 3.16, with ε = max_{s,a} |A_π(s, a)|.
///
/// # Formula
/// ```text
/// C = 4εγ / (1 − γ)²
/// ```
///
/// # Example
/// ```
/// use sepg_verification::bound_fns::trpo_penalty;
/// assert_eq!(trpo_penalty(1.0, 0.5), 8.0);
/// ```
pub fn trpo_penalty(epsilon: f64, gamma: f64) -> f64 {
    4.0 * epsilon * gamma / ((1.0 - gamma) * (1.0 - gamma))
}

/// Lemma A.3: bound on the squared distance between Gaussian policies whose log-standard
/// deviations differ by Δw (o(Δw³) terms neglected in the thesis).
///
/// # Formula
/// ```text
/// ‖π_{v,w+Δw} − π_{v,w}‖²_∞ ≤ 2Δw²
/// ```
///
/// # Example
/// ```
/// use sepg_verification::bound_fns::l1_squared_bound;
/// assert_eq!(l1_squared_bound(0.5), 0.5);
/// ```
pub fn l1_squared_bound(delta_w: f64) -> f64 {
    2.0 * delta_w * delta_w
}
