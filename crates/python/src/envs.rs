//! The transitions of the built-in environments, so that Python can cross-check them
//! against gymnasium's implementations.
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyModule;
use sepg_mdp::Environment;
use sepg_mdp::MountainCar;
use sepg_mdp::features::FeatureMap;
use sepg_mdp::rng::rng_from_seed;

use crate::{failed, floats, invalid, vector};

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
    Ok(())
}
