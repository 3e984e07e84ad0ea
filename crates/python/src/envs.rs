//! The built-in environments from Python: exact J and derivatives of the LQG presets and
//! Monte Carlo estimates with 95% Student-t intervals, through `sepg_runs::exact` and
//! `sepg_runs::estimate` as `sepg exact` and `sepg estimate` (the same checks of the
//! arguments, the same numbers), and Mountain Car transitions for cross-checks against
//! gymnasium.
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyModule;
use sepg_mdp::Environment;
use sepg_mdp::MountainCar;
use sepg_mdp::features::FeatureMap;
use sepg_mdp::rng::rng_from_seed;

use pyo3::types::PyDict;
use sepg_mdp::oracle::Horizon;
use sepg_runs::estimate::{EstimateSpec, Interval};
use sepg_runs::exact::ExactSpec;

use crate::{failed, floats, invalid, vector};

/// [`invalid`] for an error of bad input, [`failed`] otherwise.
fn run_error(e: sepg_runs::Error) -> PyErr {
    if e.is_invalid_input() {
        invalid(e)
    } else {
        failed(e)
    }
}

/// Exact J(v, σ) and its derivatives for the LQG preset `env` (`"lqg"`, thesis Sec 5.1, or
/// `"lqg1d"`) with the policy a ~ N(v s, σ²) (σ = 0: deterministic): the closed form of the
/// unclipped model (any horizon; `horizon=None` is the infinite discounted sum), or dynamic
/// programming on the clipped model (`clipped=True`, finite horizon, default 20), with
/// transition noise η; `sepg_runs::exact`, as `sepg exact`. Returns a dict with `j`,
/// `grad_v`, and for σ > 0 `grad_w`, `grad_sigma`, `mixed_wv` (∂²J/∂w∂v), plus `hessian`
/// when the oracle computes it.
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
    let spec = ExactSpec {
        env: env.to_string(),
        v,
        sigma,
        horizon: horizon.map(Horizon::Finite),
        eta,
        clipped,
    };
    let (eval, _) = py
        .detach(|| sepg_runs::exact::exact(&spec))
        .map_err(run_error)?;
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

/// Means `(k,)` and 95% intervals `(k, 2)` of an estimate.
type Means<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray2<f64>>);

/// The means and 95% intervals of an estimate, as `(means (k,), intervals (k, 2))`.
fn arrays<'py>(py: Python<'py>, i: &Interval) -> PyResult<Means<'py>> {
    let (mean, ci): (Vec<f64>, Vec<Vec<f64>>) = match i {
        Interval::Scalar { mean, ci95 } => (vec![*mean], vec![ci95.to_vec()]),
        Interval::Vector { mean, ci95 } => {
            (mean.clone(), ci95.iter().map(|c| c.to_vec()).collect())
        }
    };
    Ok((
        PyArray1::from_vec(py, mean),
        PyArray2::from_vec2(py, &ci).map_err(failed)?,
    ))
}

/// Monte Carlo estimates of J, ∇_v J and ∇_w J from `n` ≥ 2 trajectories of `horizon` steps
/// of the built-in environment `env` (`lqg`, `lqg1d`, `lqg-nd`, `mountain-car`) under
/// N(v φ(s), σ²) (σ = 0: deterministic, J only), with 95% Student-t intervals (Sec 4.5):
/// `sepg_runs::estimate`, as `sepg estimate`, the same numbers. A dict with `j` (a pair
/// `(mean, [lo, hi])`), `grad_v`, `grad_w` (pairs `(means, intervals (k, 2))`, `None` for
/// σ = 0), `steps` and `steps_per_sec`.
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
    let spec = EstimateSpec {
        env: env.to_string(),
        v: vector(v, "v")?,
        sigma,
        horizon,
        n,
        seed,
    };
    let r = py
        .detach(|| sepg_runs::estimate::estimate(&spec))
        .map_err(run_error)?;
    let out = PyDict::new(py);
    let Interval::Scalar { mean, ci95 } = r.j else {
        return Err(failed("the estimate of J is not a scalar"));
    };
    out.set_item("j", (mean, ci95.to_vec()))?;
    for (name, i) in [("grad_v", &r.grad_v), ("grad_w", &r.grad_w)] {
        match i {
            Some(i) => out.set_item(name, arrays(py, i)?)?,
            None => out.set_item(name, py.None())?,
        }
    }
    out.set_item("steps", r.steps)?;
    out.set_item("steps_per_sec", r.steps_per_sec)?;
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
