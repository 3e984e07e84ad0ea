//! Exact oracles for the expected discounted return `J(v, w)` of a linear Gaussian policy on
//! an LQG problem, and for its derivatives.
//!
//! The "exact gradient" mode of SEPG (docs/CONVENTIONS.md §5, the setting of thesis Sec 4.3) needs `J`,
//! `∇_v J`, `∇_w J` and the mixed derivative `∇_w ∇_v J` that enters `∇_w L` (Corollary 4.4,
//! Appendix B) without estimation error. Two oracles implement the common [`ExactOracle`]
//! trait:
//!
//! - [`ClosedFormOracle`] ([`closed_form`]): the *unclipped* LQG of any dimension, finite or
//!   infinite horizon, by the discounted Lyapunov recursion differentiated in forward mode
//!   (exact up to rounding), including the full Hessian in `(v, w)` and the optimal gain of the
//!   discounted Riccati equation;
//! - [`ClippedDpOracle`] ([`clipped_dp`]): the *clipped* scalar LQG (presets `lqg`, `lqg1d`),
//!   finite horizon, by backward dynamic programming on the value function with exact
//!   treatment of the clipping point masses.
//!
//! # Conventions
//! The policy is `a ~ N(V s, diag(σ²))`, `σ_j = e^{w_j}` (eq. 4.21, features `φ(s) = s`), with
//! `v` the matrix `V` (l×n) flattened action-major: `v[j * n + i]` multiplies state component
//! `i` in the mean of action `j` (the layout of [`crate::batch`]). `J` is the expected
//! discounted return `E[Σ_{t<H} γ^t r_t]` (or the infinite sum), `s_0` uniform on the init box.
//!
//! # Formula
//! ```text
//! J(v, w) = E_{s_0 ~ U[init]} E_π [ Σ_{t<H} γ^t r(s_t, a_t) ],   a_t ~ N(V s_t, diag(e^{2w}))
//! ```

pub mod clipped_dp;
pub mod closed_form;
mod jet;
mod quadrature;

pub use clipped_dp::{ClippedDpOracle, DpConfig};
pub use closed_form::{ClosedFormOracle, OptimalGain};

use nalgebra::DMatrix;

pub use crate::policy::Exploration;
use crate::policy::GaussianPolicy;

/// The horizon of the discounted sum defining `J`.
///
/// # Formula
/// ```text
/// Finite(H):  J = E[Σ_{t=0}^{H−1} γ^t r_t]       Infinite:  J = E[Σ_{t≥0} γ^t r_t]
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Horizon {
    /// `H ≥ 1` steps.
    Finite(usize),
    /// The infinite discounted sum (`γ < 1`).
    Infinite,
}

/// The result of an exact evaluation: `J` and its derivatives with respect to the policy
/// parameters `θ = [v | w]` (eq. 4.21).
///
/// # Layout
/// - `grad_v[k] = ∂J/∂v_k` (length `m = l·n`, action-major as in [`crate::batch`]);
/// - `grad_w[j] = ∂J/∂w_j` (length `l`; empty for the deterministic policy);
/// - `mixed_wv[j * m + k] = ∂²J/∂w_j ∂v_k` (length `l·m`; empty for the deterministic
///   policy);
/// - `hessian`: the `(m + l) × (m + l)` matrix of second derivatives in the order
///   `(v_0, …, v_{m−1}, w_0, …, w_{l−1})` (only `v` for the deterministic policy), or `None`
///   when the oracle does not provide it;
/// - `sigma[j] = e^{w_j}` (empty for the deterministic policy).
///
/// # Formula
/// ```text
/// grad_v = ∇_v J,   grad_w = ∇_w J,   mixed_wv = ∇_w ∇_v J,   ∂/∂σ = e^{−w} ∂/∂w
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct ExactEval {
    /// The expected discounted return `J(v, w)`.
    pub j: f64,
    /// `∇_v J` (length `m`).
    pub grad_v: Vec<f64>,
    /// `∇_w J` (length `l`, empty when deterministic).
    pub grad_w: Vec<f64>,
    /// `∂²J/∂w_j∂v_k` at index `j * m + k` (empty when deterministic).
    pub mixed_wv: Vec<f64>,
    /// The Hessian of `J` in `(v, w)`, when the oracle computes it.
    pub hessian: Option<DMatrix<f64>>,
    /// The standard deviations `σ_j = e^{w_j}` (empty when deterministic).
    pub sigma: Vec<f64>,
}

impl ExactEval {
    /// `∇_σ J`, the gradient with respect to the standard deviations (Appendix B, eq. B.1
    /// read backwards).
    ///
    /// # Formula
    /// ```text
    /// ∂J/∂σ_j = (∂J/∂w_j) / σ_j
    /// ```
    ///
    /// ```
    /// use sepg_mdp::lqg_model::LqgModel;
    /// use sepg_mdp::oracle::{ClosedFormOracle, ExactOracle, Exploration, Horizon};
    /// let oracle = ClosedFormOracle::new(&LqgModel::thesis().with_clipping(false)).unwrap();
    /// let e = oracle
    ///     .evaluate(&[-0.5], &Exploration::Gaussian { w: vec![0.0] }, Horizon::Finite(20))
    ///     .unwrap();
    /// assert_eq!(e.grad_sigma()[0], e.grad_w[0] / 1.0);
    /// ```
    pub fn grad_sigma(&self) -> Vec<f64> {
        self.grad_w
            .iter()
            .zip(&self.sigma)
            .map(|(g, s)| g / s)
            .collect()
    }

    /// `∂_σ ∇_v J`, the mixed derivative with respect to the standard deviations, as used by
    /// `∇_σ L` in Appendix B (`∂_σ ∇_v J = h(θ) − (2/σ) ∇_v J`). Same layout as
    /// [`mixed_wv`](Self::mixed_wv).
    ///
    /// # Formula
    /// ```text
    /// ∂²J/∂σ_j∂v_k = (∂²J/∂w_j∂v_k) / σ_j
    /// ```
    ///
    /// ```
    /// use sepg_mdp::lqg_model::LqgModel;
    /// use sepg_mdp::oracle::{ClosedFormOracle, ExactOracle, Exploration, Horizon};
    /// let oracle = ClosedFormOracle::new(&LqgModel::thesis().with_clipping(false)).unwrap();
    /// let e = oracle
    ///     .evaluate(&[-0.5], &Exploration::Gaussian { w: vec![(0.5f64).ln()] }, Horizon::Finite(20))
    ///     .unwrap();
    /// assert!((e.mixed_sigma_v()[0] - e.mixed_wv[0] / 0.5).abs() < 1e-12);
    /// ```
    pub fn mixed_sigma_v(&self) -> Vec<f64> {
        let m = self.grad_v.len();
        self.mixed_wv
            .iter()
            .enumerate()
            .map(|(idx, x)| x / self.sigma[idx / m.max(1)])
            .collect()
    }
}

/// Errors of the exact oracles.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum OracleError {
    /// The computation was cancelled ([`crate::cancel::request`]) before it completed.
    #[error("cancelled")]
    Cancelled,
    /// The model failed its own validation.
    #[error("invalid model: {0}")]
    Model(#[from] crate::lqg_model::ModelError),
    /// The oracle does not cover this model or request (e.g. the scalar DP on a 2-D model).
    #[error("unsupported: {0}")]
    Unsupported(&'static str),
    /// A parameter vector has the wrong length.
    #[error("{what} has length {found}, expected {expected}")]
    DimensionMismatch {
        /// `"v"` or `"w"`.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Actual length.
        found: usize,
    },
    /// A parameter is NaN or ±∞.
    #[error("{what} contains a non-finite value")]
    NonFinite {
        /// `"v"` or `"w"`.
        what: &'static str,
    },
    /// `σ = e^w` is not usable: `σ²` underflows to zero (use [`Exploration::Deterministic`]
    /// instead) or overflows.
    #[error("sigma = exp(w) underflows or overflows in component {index} (w = {w})")]
    SigmaOutOfRange {
        /// Action component.
        index: usize,
        /// The offending log standard deviation.
        w: f64,
    },
    /// A [`DpConfig`] field is out of range.
    #[error("invalid configuration: {0}")]
    InvalidConfig(&'static str),
    /// `H = 0` was requested.
    #[error("the horizon must be at least 1")]
    ZeroHorizon,
    /// The closed loop is not stable in the discounted sense (`√γ ρ(A + BV) ≥ 1`): the infinite
    /// discounted sum diverges to `J = −∞`.
    #[error("unstable closed loop: sqrt(gamma) * spectral radius = {scaled_radius} >= 1")]
    Unstable {
        /// `√γ · ρ(A + BV)`.
        scaled_radius: f64,
    },
    /// An iterative solver did not converge in its iteration budget.
    #[error("{what} did not converge in {iterations} iterations")]
    NotConverged {
        /// Which solver.
        what: &'static str,
        /// Iterations performed.
        iterations: usize,
    },
    /// The result overflowed (e.g. a very long finite horizon with an unstable closed loop).
    #[error("the result is not finite (overflow)")]
    Overflow,
    /// The value function has features too narrow for the configured maximal resolution
    /// (very small `σ`); raise [`DpConfig::max_elements`] or use the deterministic policy.
    #[error("the dynamic programme needs {needed} elements, more than the maximum {max}")]
    ResolutionExceeded {
        /// Elements needed for the requested accuracy.
        needed: usize,
        /// The configured maximum.
        max: usize,
    },
}

/// Which derivatives an evaluation must return ([`ExactOracle::evaluate_with`]); `J` is
/// always computed.
///
/// One SEPG iteration in exact mode (docs/CONVENTIONS.md §5, thesis Sec 4.3) needs `∇_v J` for the mean step
/// (Theorem 4.3), and `∇_w J` with `∇_w ∇_v J` for the exploration step (the surrogate
/// gradient `∇_w L` of Corollary 4.4 / Appendix B), but never the Hessian; the target policy
/// of LV / ZV needs `J` only.
///
/// # Formula
/// ```text
/// grad_v: ∇_v J    grad_w: ∇_w J    mixed: ∇_w ∇_v J    hessian: ∇²_{(v,w)} J
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Needs {
    /// `∇_v J`.
    pub grad_v: bool,
    /// `∇_w J`.
    pub grad_w: bool,
    /// `∇_w ∇_v J`.
    pub mixed: bool,
    /// The Hessian in `(v, w)`.
    pub hessian: bool,
}

impl Needs {
    /// `J` only.
    ///
    /// ```
    /// assert!(!sepg_mdp::oracle::Needs::VALUE.grad_v);
    /// ```
    pub const VALUE: Needs = Needs {
        grad_v: false,
        grad_w: false,
        mixed: false,
        hessian: false,
    };

    /// `J`, `∇_v J`, `∇_w J` and `∇_w ∇_v J`: everything an SEPG iteration uses.
    ///
    /// ```
    /// let n = sepg_mdp::oracle::Needs::SEPG;
    /// assert!(n.grad_v && n.grad_w && n.mixed && !n.hessian);
    /// ```
    pub const SEPG: Needs = Needs {
        grad_v: true,
        grad_w: true,
        mixed: true,
        hessian: false,
    };

    /// Everything, as [`ExactOracle::evaluate`] returns.
    ///
    /// ```
    /// assert!(sepg_mdp::oracle::Needs::ALL.hessian);
    /// ```
    pub const ALL: Needs = Needs {
        grad_v: true,
        grad_w: true,
        mixed: true,
        hessian: true,
    };
}

/// An oracle computing `J` and its derivatives exactly (docs/CONVENTIONS.md §5 "exact" gradient mode, the
/// setting of thesis Sec 4.3 where `∇_v J` and `∇_w J` are known).
///
/// # Formula
/// ```text
/// (v, w) ↦ (J, ∇_v J, ∇_w J, ∇_w∇_v J, [∇²J])
/// ```
pub trait ExactOracle {
    /// Number of mean parameters `m = l·n`.
    ///
    /// ```
    /// use sepg_mdp::lqg_model::LqgModel;
    /// use sepg_mdp::oracle::{ClosedFormOracle, ExactOracle};
    /// assert_eq!(ClosedFormOracle::new(&LqgModel::thesis()).unwrap().dim_v(), 1);
    /// ```
    fn dim_v(&self) -> usize;

    /// Number of log standard deviations `l`.
    ///
    /// ```
    /// use sepg_mdp::lqg_model::LqgModel;
    /// use sepg_mdp::oracle::{ClippedDpOracle, ExactOracle};
    /// assert_eq!(ClippedDpOracle::new(&LqgModel::thesis()).unwrap().dim_w(), 1);
    /// ```
    fn dim_w(&self) -> usize;

    /// `J(v, w)` and its derivatives (see [`ExactEval`] for the layout).
    ///
    /// # Errors
    /// Wrong lengths, non-finite parameters, `σ` out of range, `H = 0`, an unsupported horizon
    /// or a diverging / unresolvable problem give an [`OracleError`]; never a NaN.
    ///
    /// ```
    /// use sepg_mdp::lqg_model::LqgModel;
    /// use sepg_mdp::oracle::{ClippedDpOracle, ExactOracle, Exploration, Horizon};
    /// let o = ClippedDpOracle::new(&LqgModel::lqg1d()).unwrap();
    /// let e = o.evaluate(&[-0.6], &Exploration::Deterministic, Horizon::Finite(20)).unwrap();
    /// assert!(e.j < 0.0 && e.grad_w.is_empty());
    /// ```
    fn evaluate(
        &self,
        v: &[f64],
        exploration: &Exploration,
        horizon: Horizon,
    ) -> Result<ExactEval, OracleError>;

    /// `J` and at least the derivatives `needs` asks for (an oracle may return more; the
    /// default computes everything with [`evaluate`](Self::evaluate)). Fields of quantities
    /// neither requested nor computed are empty (`hessian: None`).
    ///
    /// # Errors
    /// As [`evaluate`](Self::evaluate).
    ///
    /// ```
    /// use sepg_mdp::lqg_model::LqgModel;
    /// use sepg_mdp::oracle::{ClosedFormOracle, ExactOracle, Exploration, Horizon, Needs};
    /// let o = ClosedFormOracle::new(&LqgModel::thesis()).unwrap();
    /// let ex = Exploration::Gaussian { w: vec![0.0] };
    /// let e = o.evaluate_with(&[-0.5], &ex, Horizon::Finite(20), Needs::SEPG).unwrap();
    /// assert_eq!(e, o.evaluate(&[-0.5], &ex, Horizon::Finite(20)).unwrap());
    /// ```
    fn evaluate_with(
        &self,
        v: &[f64],
        exploration: &Exploration,
        horizon: Horizon,
        _needs: Needs,
    ) -> Result<ExactEval, OracleError> {
        self.evaluate(v, exploration, horizon)
    }

    /// [`evaluate`](Self::evaluate) at the parameters of a linear policy with features
    /// `φ(s) = s` (its feature dimension must be the state dimension).
    ///
    /// # Errors
    /// As [`evaluate`](Self::evaluate).
    ///
    /// ```
    /// use sepg_mdp::lqg_model::LqgModel;
    /// use sepg_mdp::oracle::{ClosedFormOracle, ExactOracle, Horizon};
    /// use sepg_mdp::policy::GaussianPolicy;
    /// let o = ClosedFormOracle::new(&LqgModel::thesis()).unwrap();
    /// let pi = GaussianPolicy::scalar(-0.5, 0.0).unwrap();
    /// let e = o.evaluate_policy(&pi, Horizon::Finite(10)).unwrap();
    /// assert_eq!(e, o.evaluate(pi.v(), pi.exploration(), Horizon::Finite(10)).unwrap());
    /// ```
    fn evaluate_policy(
        &self,
        policy: &GaussianPolicy,
        horizon: Horizon,
    ) -> Result<ExactEval, OracleError> {
        self.evaluate(policy.v(), policy.exploration(), horizon)
    }
}

/// Validated policy parameters: `v` of length `m`, and `σ` (empty when deterministic).
pub(crate) struct CheckedParams {
    /// Standard deviations `e^{w_j}`, empty for the deterministic policy.
    pub sigma: Vec<f64>,
}

/// Checks lengths, finiteness and `σ² > 0` of the policy parameters.
pub(crate) fn check_params(
    v: &[f64],
    exploration: &Exploration,
    dim_v: usize,
    dim_w: usize,
) -> Result<CheckedParams, OracleError> {
    if v.len() != dim_v {
        return Err(OracleError::DimensionMismatch {
            what: "v",
            expected: dim_v,
            found: v.len(),
        });
    }
    if v.iter().any(|x| !x.is_finite()) {
        return Err(OracleError::NonFinite { what: "v" });
    }
    let sigma = match exploration {
        Exploration::Deterministic => Vec::new(),
        Exploration::Gaussian { w } => {
            if w.len() != dim_w {
                return Err(OracleError::DimensionMismatch {
                    what: "w",
                    expected: dim_w,
                    found: w.len(),
                });
            }
            if w.iter().any(|x| !x.is_finite()) {
                return Err(OracleError::NonFinite { what: "w" });
            }
            let sigma: Vec<f64> = w.iter().map(|x| x.exp()).collect();
            for (index, (&s, &wj)) in sigma.iter().zip(w).enumerate() {
                if !(s * s > 0.0 && (s * s).is_finite()) {
                    return Err(OracleError::SigmaOutOfRange { index, w: wj });
                }
            }
            sigma
        }
    };
    Ok(CheckedParams { sigma })
}
