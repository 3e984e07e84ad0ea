//! The per-iteration records of a [`Trainer`](crate::train::Trainer) as Python dicts with
//! the columns of the CLI's `log.csv`, and the rows of that file written from such dicts by
//! the same writer as `sepg run` (`sepg_runs::folder::log_row`).
//!
//! The names are those of `log.csv` (`j_explore`, `required`, `infeasible`, …, see
//! [`sepg_runs::folder::log_header`]); vectors (`v`, `w`, `sigma`, `w_target`) are lists, and
//! the deterministic target of ZV and SIM-ν has `w_target` −∞ in every component, as in the
//! file. Values that do not apply are `None` (an empty cell of the file).
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyModule};
use sepg_algo::core::record::Record;
use sepg_runs::folder;

use crate::invalid;

/// `record` as a dict with the columns of `log.csv`, in the file's order.
pub(crate) fn to_py<'py>(py: Python<'py>, r: &Record) -> PyResult<Bound<'py, PyDict>> {
    let [
        iteration,
        v,
        w,
        sigma,
        j_explore,
        j_after_v,
        j_target,
        w_target,
        budget,
        required,
        required_w,
        alpha,
        beta,
        lambda_v,
        lambda_w,
        guaranteed_v,
        guaranteed_w,
        infeasible,
        infeasible_v,
        infeasible_w,
        below_noise_v,
        below_noise_w,
        trajectories,
        steps,
        certified_v,
        certified_w,
    ] = folder::LOG_COLUMNS;
    let d = PyDict::new(py);
    d.set_item(iteration, r.iteration)?;
    d.set_item(v, r.v.clone())?;
    d.set_item(w, r.w.clone())?;
    d.set_item(sigma, r.sigma.clone())?;
    d.set_item(j_explore, r.j_exploratory)?;
    d.set_item(j_after_v, r.j_after_v)?;
    d.set_item(j_target, r.j_target)?;
    let target = r
        .w_target
        .clone()
        .unwrap_or_else(|| vec![f64::NEG_INFINITY; r.w.len()]);
    d.set_item(w_target, target)?;
    d.set_item(budget, r.budget)?;
    d.set_item(required, r.required_v)?;
    d.set_item(required_w, r.required_w)?;
    d.set_item(alpha, r.alpha)?;
    d.set_item(beta, r.beta)?;
    d.set_item(lambda_v, r.lambda_v)?;
    d.set_item(lambda_w, r.lambda_w)?;
    d.set_item(guaranteed_v, r.guaranteed_v)?;
    d.set_item(guaranteed_w, r.guaranteed_w)?;
    d.set_item(infeasible, r.infeasible_v || r.infeasible_w)?;
    d.set_item(infeasible_v, r.infeasible_v)?;
    d.set_item(infeasible_w, r.infeasible_w)?;
    d.set_item(below_noise_v, r.below_noise_v)?;
    d.set_item(below_noise_w, r.below_noise_w)?;
    d.set_item(trajectories, r.trajectories)?;
    d.set_item(steps, r.steps)?;
    d.set_item(certified_v, r.certified_v)?;
    d.set_item(certified_w, r.certified_w)?;
    Ok(d)
}

/// The item `key` of the record `d`, extracted as `T`; a missing key or a value of another
/// type raises `InvalidInputError` naming the key.
fn item<'py, T: for<'a> FromPyObject<'a, 'py>>(d: &Bound<'py, PyDict>, key: &str) -> PyResult<T> {
    let value = d
        .get_item(key)?
        .ok_or_else(|| invalid(format!("the record has no {key:?}")))?;
    value
        .extract::<T>()
        .map_err(|_| invalid(format!("the record's {key:?} has the wrong type: {value}")))
}

/// The record `d` (a dict as [`to_py`] returns it) back as a [`Record`]. A `w_target` that is
/// −∞ in every component is the deterministic target. The column `infeasible` is derived and
/// must equal `infeasible_v or infeasible_w`.
pub(crate) fn from_py(d: &Bound<'_, PyDict>) -> PyResult<Record> {
    let [
        iteration,
        v,
        w,
        sigma,
        j_explore,
        j_after_v,
        j_target,
        w_target,
        budget,
        required,
        required_w,
        alpha,
        beta,
        lambda_v,
        lambda_w,
        guaranteed_v,
        guaranteed_w,
        infeasible,
        infeasible_v,
        infeasible_w,
        below_noise_v,
        below_noise_w,
        trajectories,
        steps,
        certified_v,
        certified_w,
    ] = folder::LOG_COLUMNS;
    let w_target: Vec<f64> = item(d, w_target)?;
    let deterministic = !w_target.is_empty() && w_target.iter().all(|x| *x == f64::NEG_INFINITY);
    let r = Record {
        iteration: item(d, iteration)?,
        v: item(d, v)?,
        w: item(d, w)?,
        sigma: item(d, sigma)?,
        j_exploratory: item(d, j_explore)?,
        j_after_v: item(d, j_after_v)?,
        j_target: item(d, j_target)?,
        w_target: (!deterministic).then_some(w_target),
        budget: item(d, budget)?,
        required_v: item(d, required)?,
        required_w: item(d, required_w)?,
        alpha: item(d, alpha)?,
        beta: item(d, beta)?,
        lambda_v: item(d, lambda_v)?,
        lambda_w: item(d, lambda_w)?,
        guaranteed_v: item(d, guaranteed_v)?,
        guaranteed_w: item(d, guaranteed_w)?,
        infeasible_v: item(d, infeasible_v)?,
        infeasible_w: item(d, infeasible_w)?,
        below_noise_v: item(d, below_noise_v)?,
        below_noise_w: item(d, below_noise_w)?,
        trajectories: item(d, trajectories)?,
        steps: item(d, steps)?,
        certified_v: item(d, certified_v)?,
        certified_w: item(d, certified_w)?,
    };
    let infeasible: bool = item(d, infeasible)?;
    if infeasible != (r.infeasible_v || r.infeasible_w) {
        return Err(invalid(
            "the record's \"infeasible\" must equal infeasible_v or infeasible_w",
        ));
    }
    let p = r.w.len();
    if p == 0 || r.sigma.len() != p || r.w_target.as_ref().is_some_and(|t| t.len() != p) {
        return Err(invalid(format!(
            "the record's w, sigma and w_target must have the same non-zero length; got {}, {} and {}",
            p,
            r.sigma.len(),
            r.w_target.as_ref().map_or(p, Vec::len)
        )));
    }
    Ok(r)
}

/// The header line of `log.csv` (newline included) for `dim_v` mean parameters and `dim_w`
/// standard deviations, as `sepg run` writes it.
#[pyfunction]
fn log_header(dim_v: usize, dim_w: usize) -> PyResult<String> {
    if dim_v == 0 || dim_w == 0 {
        return Err(invalid(format!(
            "dim_v = {dim_v} and dim_w = {dim_w} must be at least 1"
        )));
    }
    Ok(folder::log_header(dim_v, dim_w))
}

/// The line of `log.csv` (newline included) for `record`, a dict with the columns of the
/// file (as the records of `Trainer.run`), written as `sepg run` writes it: shortest
/// round-trip decimals, empty cells for `None`, booleans as 0/1.
#[pyfunction]
fn log_row(record: &Bound<'_, PyDict>) -> PyResult<String> {
    Ok(folder::log_row(&from_py(record)?))
}

/// Adds the functions of this module to `m`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(log_header, m)?)?;
    m.add_function(wrap_pyfunction!(log_row, m)?)?;
    Ok(())
}
