//! The built-in environments from Python: exact J and derivatives of the LQG presets (the
//! oracles of `sepg_mdp`, as `sepg exact`), Monte Carlo estimates with 95% Student-t
//! intervals (as `sepg estimate`), and Mountain Car transitions for cross-checks against
//! gymnasium.
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyModule;
use sepg_mdp::Environment;
use sepg_mdp::MountainCar;
use sepg_mdp::features::FeatureMap;
use sepg_mdp::rng::rng_from_seed;

use nalgebra::DVector;
use numpy::PyArray1 as Arr;
use pyo3::types::PyDict;
use sepg_estimators::{Estimate, Estimator, GradientSpec, Param, Width};
use sepg_mdp::env::Preset;
use sepg_mdp::oracle::{
    ClippedDpOracle, ClosedFormOracle, ExactOracle, Exploration, Horizon, OracleError,
};
use sepg_mdp::rng::SeedKey;
use sepg_mdp::rollout::rollout;
use sepg_mdp::{GaussianPolicy, LqgModel};

use crate::{failed, floats, invalid, vector};

/// Input problems are [`invalid`]; numerical failures of the oracle are [`failed`].
fn oracle_error(e: OracleError) -> PyErr {
    match e {
        OracleError::NotConverged { .. }
        | OracleError::Overflow
        | OracleError::ResolutionExceeded { .. } => failed(e),
        _ => invalid(e),
    }
}

/// Exact J(v, σ) and its derivatives for the LQG preset `env` (`"lqg"`, thesis Sec 5.1, or
/// `"lqg1d"`) with the policy a ~ N(v s, σ²) (σ = 0: deterministic): the closed form of the
/// unclipped model (any horizon; `horizon=None` is the infinite discounted sum), or dynamic
/// programming on the clipped model (`clipped=True`, finite horizon, default 20), with
/// transition noise η. Returns a dict with `j`, `grad_v`, and for σ > 0 `grad_w`,
/// `grad_sigma`, `mixed_wv` (∂²J/∂w∂v), plus `hessian` when the oracle computes it.
#[pyfunction]
#[pyo3(signature = (env, v, sigma, horizon = None, eta = 0.0, clipped = false))]
fn exact<'py>(
    py: Python<'py>,
    env: &str,
    v: f64,
    sigma: f64,
    horizon: Option<usize>,
    eta: f64,
    clipped: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let model = match env {
        "lqg" => LqgModel::thesis(),
        "lqg1d" => LqgModel::lqg1d(),
        other => {
            return Err(invalid(format!(
                "exact values exist for the presets lqg and lqg1d, not {other:?}"
            )));
        }
    };
    for (name, x) in [("sigma", sigma), ("eta", eta)] {
        if !(x.is_finite() && x >= 0.0) {
            return Err(invalid(format!("{name} must be finite and >= 0, got {x}")));
        }
    }
    if !v.is_finite() {
        return Err(invalid(format!("v must be finite, got {v}")));
    }
    let model = model
        .with_noise(DVector::from_element(1, eta))
        .map_err(invalid)?;
    let exploration = if sigma == 0.0 {
        Exploration::Deterministic
    } else {
        Exploration::Gaussian {
            w: vec![sigma.ln()],
        }
    };
    let horizon = match (horizon, clipped) {
        (Some(0), _) => return Err(invalid("horizon must be at least 1")),
        (Some(h), _) => Horizon::Finite(h),
        (None, true) => Horizon::Finite(20),
        (None, false) => Horizon::Infinite,
    };
    let eval = if clipped {
        ClippedDpOracle::new(&model)
            .map_err(oracle_error)?
            .evaluate(&[v], &exploration, horizon)
    } else {
        ClosedFormOracle::new(&model)
            .map_err(oracle_error)?
            .evaluate(&[v], &exploration, horizon)
    }
    .map_err(oracle_error)?;
    let out = PyDict::new(py);
    out.set_item("j", eval.j)?;
    out.set_item("grad_v", eval.grad_v[0])?;
    if sigma > 0.0 {
        out.set_item("grad_w", eval.grad_w.first().copied())?;
        out.set_item("grad_sigma", eval.grad_sigma().first().copied())?;
        out.set_item("mixed_wv", eval.mixed_wv.first().copied())?;
    }
    if let Some(h) = &eval.hessian {
        let rows: Vec<Vec<f64>> = (0..h.nrows())
            .map(|i| (0..h.ncols()).map(|j| h[(i, j)]).collect())
            .collect();
        out.set_item("hessian", PyArray2::from_vec2(py, &rows).map_err(failed)?)?;
    }
    Ok(out)
}

/// The mean and the 95% Student-t interval `[lo, hi]` of each component of an estimate.
fn interval(e: &Estimate) -> PyResult<(Vec<f64>, Vec<Vec<f64>>)> {
    let mut half = vec![0.0; e.dim()];
    e.widths_into(Width::StudentT, 0.05, &mut half)
        .map_err(failed)?;
    let ci = e
        .mean()
        .iter()
        .zip(&half)
        .map(|(m, h)| vec![m - h, m + h])
        .collect();
    Ok((e.mean().to_vec(), ci))
}

/// Monte Carlo estimates of J, ∇_v J and ∇_w J (G(PO)MDP with the leave-one-out optimal
/// baseline) from `n` ≥ 2 trajectories of `horizon` steps of the built-in environment `env`
/// (`lqg`, `lqg1d`, `lqg-nd`, `mountain-car`) under N(v φ(s), σ²), with 95% Student-t
/// intervals (Sec 4.5), as `sepg estimate`: a dict with `j`, `grad_v`, `grad_w` (each a pair
/// `(mean, ci95)`), `steps`.
#[pyfunction]
#[pyo3(signature = (env, v, sigma, horizon, n, seed = 0))]
fn estimate<'py>(
    py: Python<'py>,
    env: &str,
    v: &Bound<'py, PyAny>,
    sigma: f64,
    horizon: usize,
    n: usize,
    seed: u64,
) -> PyResult<Bound<'py, PyDict>> {
    let env = Preset::from_name(env).map_err(invalid)?.build();
    let v = vector(v, "v")?;
    if n < 2 || horizon == 0 {
        return Err(invalid(format!(
            "n must be at least 2 and horizon at least 1, got n = {n}, horizon = {horizon}"
        )));
    }
    if !(sigma.is_finite() && sigma > 0.0) {
        return Err(invalid(format!(
            "sigma must be finite and > 0, got {sigma}"
        )));
    }
    let policy = GaussianPolicy::new(v, vec![sigma.ln(); env.action_dim()], env.feature_dim())
        .map_err(invalid)?;
    let batch = py
        .detach(|| rollout(&env, &policy, n, horizon, SeedKey::new(seed, 0, 0)))
        .map_err(invalid)?;
    let mut estimator = Estimator::new();
    let mut est = Estimate::new();
    let out = PyDict::new(py);
    estimator.value(&batch, &mut est).map_err(failed)?;
    let (m, ci) = interval(&est)?;
    out.set_item("j", (m[0], ci[0].clone()))?;
    for (name, param) in [("grad_v", Param::V), ("grad_w", Param::W)] {
        estimator
            .gradient(&batch, param, GradientSpec::default(), &mut est)
            .map_err(failed)?;
        let (m, ci) = interval(&est)?;
        let ci = PyArray2::from_vec2(py, &ci).map_err(failed)?;
        out.set_item(name, (Arr::from_vec(py, m), ci))?;
    }
    out.set_item("steps", batch.steps())?;
    Ok(out)
}

/// States `(T + 1, 2)`, rewards `(T,)` and whether the episode terminated.
type Trajectory<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray1<f64>>, bool);

/// The trajectory of the built-in `mountain-car` (gymnasium's `MountainCarContinuous-v0`
/// dynamics in f64) from `state` = (position, velocity) under the raw `actions` (one per
/// step), stopping at termination: `(states, rewards, terminated)` with `states` of shape
/// `(T + 1, 2)` and `rewards` of length T.
#[pyfunction]
fn mountain_car_trajectory<'py>(
    py: Python<'py>,
    state: &Bound<'py, PyAny>,
    actions: &Bound<'py, PyAny>,
) -> PyResult<Trajectory<'py>> {
    let s0 = vector(state, "state")?;
    if s0.len() != 2 {
        return Err(invalid(format!(
            "state must be (position, velocity), got {} values",
            s0.len()
        )));
    }
    let (actions, _) = floats(actions, "actions", Some(1))?;
    let env = MountainCar::new(FeatureMap::Identity { dim: 2 }).map_err(failed)?;
    let mut rng = rng_from_seed(0);
    let (mut states, mut rewards) = (vec![s0.clone()], Vec::new());
    let mut terminated = false;
    let (mut s, mut next) = (s0, vec![0.0; 2]);
    for a in actions {
        let (r, done) = env.step(&s, &[a], &mut rng, &mut next);
        rewards.push(r);
        states.push(next.clone());
        std::mem::swap(&mut s, &mut next);
        if done {
            terminated = true;
            break;
        }
    }
    let states = PyArray2::from_vec2(py, &states).map_err(failed)?;
    Ok((states, PyArray1::from_vec(py, rewards), terminated))
}

/// Adds the functions of this module to `m`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(mountain_car_trajectory, m)?)?;
    m.add_function(wrap_pyfunction!(exact, m)?)?;
    m.add_function(wrap_pyfunction!(estimate, m)?)?;
    Ok(())
}
