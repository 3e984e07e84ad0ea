//! Exact J and derivatives of a 1-D LQG preset, as `sepg exact` and Python's `sepg.runs.exact`
//! compute them: the closed form of the unclipped model (any horizon) or dynamic programming
//! on the clipped model (finite horizon), with the arguments checked once, here.

use nalgebra::DVector;
use sepg_mdp::LqgModel;
use sepg_mdp::oracle::{
    ClippedDpOracle, ClosedFormOracle, ExactEval, ExactOracle, Exploration, Horizon, OracleError,
};

use crate::error::{Error, Result};

/// What to evaluate: the policy a ~ N(v s, σ²) on the preset `env` (`lqg`, thesis Sec 5.1,
/// or `lqg1d`) with transition noise η.
#[derive(Debug, Clone, PartialEq)]
pub struct ExactSpec {
    /// `lqg` or `lqg1d`.
    pub env: String,
    /// Mean parameter v (finite).
    pub v: f64,
    /// Standard deviation σ ≥ 0 (0: the deterministic policy a = v s).
    pub sigma: f64,
    /// Horizon; `None` is the infinite discounted sum for the closed form and 20 steps for
    /// the clipped model.
    pub horizon: Option<Horizon>,
    /// Standard deviation η ≥ 0 of the transition noise.
    pub eta: f64,
    /// Evaluate the clipped model by dynamic programming instead of the unclipped closed form.
    pub clipped: bool,
}

/// The horizon used when a spec gives none: 20 steps for the clipped model, else infinite.
pub const DEFAULT_CLIPPED_HORIZON: usize = 20;

/// The oracle's error: numerical failures are [`Error::Failed`], the rest bad input.
fn oracle_error(e: OracleError) -> Error {
    match e {
        OracleError::NotConverged { .. }
        | OracleError::Overflow
        | OracleError::ResolutionExceeded { .. } => Error::failed(e.to_string()),
        _ => Error::invalid(e.to_string()),
    }
}

/// The model of an LQG preset name.
fn model(env: &str) -> Result<LqgModel> {
    match env {
        "lqg" => Ok(LqgModel::thesis()),
        "lqg1d" => Ok(LqgModel::lqg1d()),
        other => Err(Error::invalid(format!(
            "exact values exist for the presets lqg and lqg1d, not {other:?}"
        ))),
    }
}

/// Checks `spec` and returns its model, exploration and horizon.
fn check(spec: &ExactSpec) -> Result<(LqgModel, Exploration, Horizon)> {
    if !spec.v.is_finite() {
        return Err(Error::invalid(format!("v must be finite, got {}", spec.v)));
    }
    for (name, x) in [("sigma", spec.sigma), ("eta", spec.eta)] {
        if !(x.is_finite() && x >= 0.0) {
            return Err(Error::invalid(format!(
                "{name} must be finite and >= 0, got {x}"
            )));
        }
    }
    let model = model(&spec.env)?
        .with_noise(DVector::from_element(1, spec.eta))
        .map_err(|e| Error::invalid(e.to_string()))?;
    let exploration = if spec.sigma == 0.0 {
        Exploration::Deterministic
    } else {
        Exploration::Gaussian {
            w: vec![spec.sigma.ln()],
        }
    };
    let horizon = match (spec.horizon, spec.clipped) {
        (Some(Horizon::Finite(0)), _) => {
            return Err(Error::invalid("the horizon must be at least 1"));
        }
        (Some(Horizon::Infinite), true) => {
            return Err(Error::invalid("the clipped model needs a finite --horizon"));
        }
        (Some(Horizon::Finite(h)), _) => {
            crate::spec::check_horizon(h)?;
            Horizon::Finite(h)
        }
        (Some(h), _) => h,
        (None, true) => Horizon::Finite(DEFAULT_CLIPPED_HORIZON),
        (None, false) => Horizon::Infinite,
    };
    Ok((model, exploration, horizon))
}

/// J(v, σ), ∇_v J and, for σ > 0, ∇_w J and ∂²J/∂w∂v (and the Hessian when the oracle
/// computes it) of `spec`, with the horizon used.
///
/// # Errors
/// [`Error::Invalid`] for an unknown preset, v not finite, σ or η negative or not finite, a
/// zero horizon, a finite one above [`crate::spec::MAX_HORIZON`] (both oracles cost time
/// linear in H), or an infinite horizon on the clipped model; [`Error::Failed`] when the
/// oracle does not converge or overflows.
///
/// ```
/// use sepg_runs::exact::{ExactSpec, exact};
/// let spec = ExactSpec { env: "lqg1d".into(), v: -0.5, sigma: 0.0, horizon: None, eta: 0.0, clipped: false };
/// let (eval, _) = exact(&spec)?;
/// assert!(eval.j < 0.0);
/// assert!(exact(&ExactSpec { sigma: -1.0, ..spec }).is_err());
/// # Ok::<(), sepg_runs::Error>(())
/// ```
pub fn exact(spec: &ExactSpec) -> Result<(ExactEval, Horizon)> {
    let (model, exploration, horizon) = check(spec)?;
    let eval = if spec.clipped {
        ClippedDpOracle::new(&model)
            .map_err(oracle_error)?
            .evaluate(&[spec.v], &exploration, horizon)
    } else {
        ClosedFormOracle::new(&model)
            .map_err(oracle_error)?
            .evaluate(&[spec.v], &exploration, horizon)
    }
    .map_err(oracle_error)?;
    Ok((eval, horizon))
}
