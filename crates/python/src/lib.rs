//! The Python extension module `sepg._native`, re-exported by the Python package `sepg`.
//!
//! - [`bounds`]: every closed-form quantity of `sepg_bounds` (Chapters 3 and 4 of the thesis).
//! - [`envs`]: transitions of the built-in environments, for cross-checks against gymnasium.
//! - [`runs`]: run folders, sweeps (also mapped over Dask or Ray from Python), merges and
//!   audits of the built-in environments through `sepg_runs`.
//! - [`safe`]: the framework-agnostic safe-step API: gradient estimates, per-trajectory
//!   samples or confidence widths in, SEPG's safe steps, guarantees and flags out
//!   (Theorems 4.2–4.9).
//! - [`train`]: SEPG and the comparison algorithms driven by trajectory batches collected in
//!   Python (any gymnasium environment), through `sepg_algo`'s collector API.
//!
//! Bad input never panics and never returns NaN: every error is raised as one of the
//! exception classes of `sepg.errors`, whose input errors are also `ValueError`s.
use numpy::{PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyModule;
use sepg_bounds::constants::TaskConstants;

pub mod bounds;
pub mod envs;
pub mod pyjson;
pub mod runs;
pub mod safe;
pub mod train;

pyo3::import_exception!(sepg.errors, InvalidInputError);
pyo3::import_exception!(sepg.errors, RunFailedError);

/// An [`InvalidInputError`] (a `ValueError`) with `message`.
pub(crate) fn invalid(message: impl std::fmt::Display) -> PyErr {
    InvalidInputError::new_err(message.to_string())
}

/// A [`RunFailedError`] with `message`.
pub(crate) fn failed(message: impl std::fmt::Display) -> PyErr {
    RunFailedError::new_err(message.to_string())
}

/// An array of `f64` read from any array-like `obj` (numpy array, list, scalar), with its
/// shape, checked to have `ndim` dimensions (any when `None`) and finite entries.
pub(crate) fn floats(
    obj: &Bound<'_, PyAny>,
    name: &str,
    ndim: Option<usize>,
) -> PyResult<(Vec<f64>, Vec<usize>)> {
    let py = obj.py();
    let np = py.import("numpy")?;
    let arr = np
        .call_method1("ascontiguousarray", (obj, "float64"))
        .map_err(|e| invalid(format!("{name} must be an array of real numbers ({e})")))?;
    let arr = arr
        .cast::<PyArrayDyn<f64>>()
        .map_err(|_| invalid(format!("{name} must be an array of real numbers")))?;
    let shape = arr.shape().to_vec();
    if let Some(d) = ndim
        && shape.len() != d
    {
        return Err(invalid(format!(
            "{name} must have {d} dimension(s), got shape {shape:?}"
        )));
    }
    let values = arr.to_vec().map_err(|e| invalid(format!("{name}: {e}")))?;
    if let Some(i) = values.iter().position(|x| !x.is_finite()) {
        return Err(invalid(format!(
            "{name} must be finite, entry {i} is {}",
            values[i]
        )));
    }
    Ok((values, shape))
}

/// A one-dimensional, non-empty, finite `f64` vector from an array-like.
pub(crate) fn vector(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<f64>> {
    let (values, _) = floats(obj, name, Some(1))?;
    if values.is_empty() {
        return Err(invalid(format!("{name} must not be empty")));
    }
    Ok(values)
}

/// The task constants of the thesis's bounds: discount γ ∈ [0, 1), reward bound R_max > 0
/// (|r| ≤ R_max), feature bound M_φ > 0 (|φ_i(s)| ≤ M_φ) and action-space volume |A| > 0
/// (Sec 3.4, Assumptions 4.1–4.2).
#[pyclass(frozen, name = "TaskConstants", module = "sepg")]
#[derive(Debug, Clone, Copy)]
pub struct PyTaskConstants(pub(crate) TaskConstants);

#[pymethods]
impl PyTaskConstants {
    /// Validated constants; raises `InvalidInputError` (a `ValueError`) for γ ∉ [0, 1) or a
    /// bound that is not finite and positive.
    #[new]
    #[pyo3(signature = (gamma, r_max, m_phi, action_volume))]
    fn new(gamma: f64, r_max: f64, m_phi: f64, action_volume: f64) -> PyResult<Self> {
        TaskConstants::new(gamma, r_max, m_phi, action_volume)
            .map(PyTaskConstants)
            .map_err(invalid)
    }

    /// Discount factor γ.
    #[getter]
    fn gamma(&self) -> f64 {
        self.0.gamma()
    }

    /// Reward bound R_max.
    #[getter]
    fn r_max(&self) -> f64 {
        self.0.r_max()
    }

    /// Feature bound M_φ.
    #[getter]
    fn m_phi(&self) -> f64 {
        self.0.m_phi()
    }

    /// Action-space volume |A|.
    #[getter]
    fn action_volume(&self) -> f64 {
        self.0.action_volume()
    }

    /// The same constants with ψ replaced by `psi` in d(σ) (Theorem 4.3): the guarantees hold
    /// for any ψ ≥ Lemma A.1's value (`sepg.bounds.constants_psi()`), a smaller one voids
    /// them. Raises `InvalidInputError` unless `psi` is finite and positive.
    fn with_psi(&self, psi: f64) -> PyResult<Self> {
        self.0.with_psi(psi).map(PyTaskConstants).map_err(invalid)
    }

    /// The ψ that replaces Lemma A.1's value (`with_psi`), or `None`.
    #[getter]
    fn psi_override(&self) -> Option<f64> {
        self.0.psi_override()
    }

    /// The ψ that d(σ) (Theorem 4.3) uses: the override, or Lemma A.1's value.
    #[getter]
    fn psi_used(&self) -> f64 {
        self.0.psi_used()
    }

    fn __repr__(&self) -> String {
        let psi = self
            .0
            .psi_override()
            .map_or(String::new(), |p| format!(", psi={p:?}"));
        format!(
            "TaskConstants(gamma={:?}, r_max={:?}, m_phi={:?}, action_volume={:?}{psi})",
            self.0.gamma(),
            self.0.r_max(),
            self.0.m_phi(),
            self.0.action_volume()
        )
    }

    fn __eq__(&self, other: &Self) -> bool {
        self.0 == other.0
    }
}

/// The extension module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyTaskConstants>()?;
    bounds::register(m)?;
    envs::register(m)?;
    runs::register(m)?;
    safe::register(m)?;
    train::register(m)?;
    Ok(())
}
