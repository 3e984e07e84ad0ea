//! The Python extension module `sepg._native`, re-exported by the Python package `sepg`.
//!
//! - [`bounds`]: every closed-form quantity of `sepg_bounds` (Chapters 3 and 4 of the thesis).
//! - [`envs`]: transitions of the built-in environments, for cross-checks against gymnasium.
//! - [`runs`]: run folders, sweeps (also mapped over Dask or Ray from Python), merges and
//!   audits of the built-in environments through `sepg_runs`.
//! - [`safe`]: the framework-agnostic safe-step API: gradient estimates, per-trajectory
//!   samples or confidence widths in, SEPG's safe steps, guarantees and flags out
//!   (Theorems 4.2–4.9).
//! - [`record`]: the per-iteration records with the columns of `log.csv`, and that file's
//!   rows written by the CLI's writer.
//! - [`train`]: SEPG and the comparison algorithms driven by trajectory batches collected in
//!   Python (any gymnasium environment), through `sepg_algo`'s collector API.
//!
//! Bad input never panics and never returns NaN: every error is raised as one of the
//! exception classes of `sepg.errors`, whose input errors are also `ValueError`s.

#![deny(missing_docs)]

use numpy::{PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyComplex, PyFloat, PyModule, PyString};
use sepg_bounds::constants::TaskConstants;
use sepg_bounds::penalties::{Family, Horizon, Rewards, Tight};

pub mod bounds;
pub mod envs;
pub mod pyjson;
pub mod record;
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
    // numpy converts complex numbers (dropping the imaginary part with a warning), strings
    // and booleans to float64 without an error: only real numbers are taken.
    let raw = np
        .call_method1("asarray", (obj,))
        .map_err(|e| invalid(format!("{name} must be an array of real numbers ({e})")))?;
    let dtype = raw.getattr("dtype")?;
    let kind: String = dtype.getattr("kind")?.extract()?;
    if !matches!(kind.as_str(), "i" | "u" | "f") {
        return Err(invalid(format!(
            "{name} must be an array of real numbers, got {} values",
            dtype.str()?
        )));
    }
    let arr = np
        .call_method1("ascontiguousarray", (raw, "float64"))
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

/// The real number passed as the argument `name`: a Python `int` or `float` or anything with
/// `__float__` (numpy scalars). Anything else (a string, a complex number, `None`) raises a
/// `TypeError` naming the argument; the domain is checked by the caller.
pub(crate) fn real(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<f64> {
    if obj.is_instance_of::<PyString>() || obj.is_instance_of::<PyComplex>() {
        return Err(PyTypeError::new_err(format!(
            "{name} must be a real number, got {} {obj}",
            obj.get_type().name()?
        )));
    }
    obj.extract::<f64>().map_err(|_| {
        let kind = obj
            .get_type()
            .name()
            .map_or_else(|_| "?".to_owned(), |n| n.to_string());
        PyTypeError::new_err(format!("{name} must be a real number, got {kind} {obj}"))
    })
}

/// The non-negative integer passed as the argument `name` (a Python `int` or numpy integer,
/// not a float): a `TypeError` for another type and an `InvalidInputError` for a negative or
/// too large value, both naming the argument.
pub(crate) fn natural<T: TryFrom<u64>>(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<T> {
    if obj.is_instance_of::<PyFloat>() || obj.is_instance_of::<PyString>() {
        return Err(PyTypeError::new_err(format!(
            "{name} must be an integer, got {} {obj}",
            obj.get_type().name()?
        )));
    }
    let n: i128 = obj
        .extract()
        .map_err(|_| PyTypeError::new_err(format!("{name} must be an integer, got {obj}")))?;
    u64::try_from(n)
        .ok()
        .and_then(|n| T::try_from(n).ok())
        .ok_or_else(|| {
            invalid(format!(
                "{name} = {n} must be a non-negative integer in range"
            ))
        })
}

/// A one-dimensional, non-empty, finite `f64` vector from an array-like.
pub(crate) fn vector(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<f64>> {
    let (values, _) = floats(obj, name, Some(1))?;
    if values.is_empty() {
        return Err(invalid(format!("{name} must not be empty")));
    }
    Ok(values)
}

/// The horizon `h`: a positive integer, or `inf` as a float or the string "inf".
pub(crate) fn horizon_arg(h: &Bound<'_, PyAny>) -> PyResult<Horizon> {
    if let Ok(n) = h.extract::<i64>() {
        match u64::try_from(n) {
            Ok(n) if n >= 1 => Ok(Horizon::Finite(n)),
            _ => Err(invalid(format!("horizon must be at least 1, got {n}"))),
        }
    } else if h.extract::<f64>().is_ok_and(|x| x == f64::INFINITY)
        || h.extract::<String>().is_ok_and(|s| s == "inf")
    {
        Ok(Horizon::Infinite)
    } else {
        Err(invalid(format!(
            "horizon must be a positive integer or inf, got {h}"
        )))
    }
}

/// The family of constants named by `constants` ("thesis" or "tight"), the tight family for
/// `horizon` (a positive integer, or `inf` as a float or the string "inf") and `rewards`
/// ("two-sided" or "non-positive").
fn family(
    constants: &str,
    horizon: Option<&Bound<'_, PyAny>>,
    rewards: Option<&str>,
) -> PyResult<Family> {
    match constants {
        "thesis" => {
            if horizon.is_some() || rewards.is_some() {
                return Err(invalid(
                    "horizon and rewards apply to constants=\"tight\" only",
                ));
            }
            Ok(Family::Thesis)
        }
        "tight" => {
            let h = horizon.ok_or_else(|| {
                invalid("constants=\"tight\" needs horizon (a positive integer or inf)")
            })?;
            let horizon = horizon_arg(h)?;
            let rewards = match rewards.unwrap_or("two-sided") {
                "two-sided" => Rewards::TwoSided,
                "non-positive" => Rewards::NonPositive,
                other => {
                    return Err(invalid(format!(
                        "rewards = {other:?} must be \"two-sided\" or \"non-positive\""
                    )));
                }
            };
            Ok(Family::Tight(Tight::new(horizon, rewards)))
        }
        other => Err(invalid(format!(
            "constants = {other:?} must be \"thesis\" or \"tight\""
        ))),
    }
}

/// The task constants of the bounds: discount γ ∈ [0, 1), reward bound R_max > 0
/// (|r| ≤ R_max), feature bound M_φ > 0 (|φ_i(s)| ≤ M_φ) and action-space volume |A| > 0
/// (Sec 3.4, Assumptions 4.1–4.2), with the family of the penalty coefficients c and d: the
/// thesis's (Theorems 3.14, 4.2, 4.3; the default) or the tight constants
/// c = ρ R M_φ² S_H / σ², d = 2ρ R S_H (docs/THEOREMS.md, "Tight constants"), which need the
/// horizon H and, to halve them, rewards stated non-positive.
#[pyclass(frozen, name = "TaskConstants", module = "sepg")]
#[derive(Debug, Clone, Copy)]
pub struct PyTaskConstants(pub(crate) TaskConstants);

#[pymethods]
impl PyTaskConstants {
    /// Validated constants; raises `InvalidInputError` (a `ValueError`) for γ ∉ [0, 1), a
    /// bound that is not finite and positive, an unknown family or reward sign, or a tight
    /// family without a horizon of at least 1 step.
    #[new]
    #[pyo3(signature = (gamma, r_max, m_phi, action_volume, *, constants = "thesis", horizon = None, rewards = None))]
    fn new(
        gamma: &Bound<'_, PyAny>,
        r_max: &Bound<'_, PyAny>,
        m_phi: &Bound<'_, PyAny>,
        action_volume: &Bound<'_, PyAny>,
        constants: &str,
        horizon: Option<&Bound<'_, PyAny>>,
        rewards: Option<&str>,
    ) -> PyResult<Self> {
        let (gamma, r_max) = (real(gamma, "gamma")?, real(r_max, "r_max")?);
        let (m_phi, action_volume) = (real(m_phi, "m_phi")?, real(action_volume, "action_volume")?);
        let family = family(constants, horizon, rewards)?;
        TaskConstants::new(gamma, r_max, m_phi, action_volume)
            .and_then(|k| k.with_family(family))
            .map(PyTaskConstants)
            .map_err(invalid)
    }

    /// The same constants with the family `constants` ("thesis" or "tight"; for "tight", the
    /// `horizon` and the `rewards` sign, "two-sided" unless stated), as the constructor takes
    /// them.
    #[pyo3(signature = (constants, *, horizon = None, rewards = None))]
    fn with_family(
        &self,
        constants: &str,
        horizon: Option<&Bound<'_, PyAny>>,
        rewards: Option<&str>,
    ) -> PyResult<Self> {
        let family = family(constants, horizon, rewards)?;
        self.0
            .with_family(family)
            .map(PyTaskConstants)
            .map_err(invalid)
    }

    /// The family of c and d: "thesis" or "tight".
    #[getter]
    fn family(&self) -> &'static str {
        match self.0.family() {
            Family::Tight(_) => "tight",
            _ => "thesis",
        }
    }

    /// The horizon H of the tight constants as a float (`inf` for H = ∞); `None` for the
    /// thesis's.
    #[getter]
    fn horizon(&self) -> Option<f64> {
        match self.0.family() {
            Family::Tight(t) => Some(match t.horizon() {
                Horizon::Finite(h) => h as f64,
                Horizon::Infinite => f64::INFINITY,
            }),
            _ => None,
        }
    }

    /// The reward sign of the tight constants ("two-sided" or "non-positive"); `None` for the
    /// thesis's.
    #[getter]
    fn rewards(&self) -> Option<&'static str> {
        match self.0.family() {
            Family::Tight(t) => Some(match t.rewards() {
                Rewards::TwoSided => "two-sided",
                Rewards::NonPositive => "non-positive",
            }),
            _ => None,
        }
    }

    /// S_H = Σ_{t<H} (t + 1) γᵗ of the tight constants; `None` for the thesis's.
    #[getter]
    fn horizon_weight(&self) -> Option<f64> {
        matches!(self.0.family(), Family::Tight(_)).then(|| self.0.horizon_weight())
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
    fn with_psi(&self, psi: &Bound<'_, PyAny>) -> PyResult<Self> {
        self.0
            .with_psi(real(psi, "psi")?)
            .map(PyTaskConstants)
            .map_err(invalid)
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
        let family = match (self.horizon(), self.rewards()) {
            (Some(h), Some(r)) if h.is_finite() => {
                format!(", constants='tight', horizon={h}, rewards='{r}'")
            }
            (Some(_), Some(r)) => format!(", constants='tight', horizon=inf, rewards='{r}'"),
            _ => String::new(),
        };
        format!(
            "TaskConstants(gamma={:?}, r_max={:?}, m_phi={:?}, action_volume={:?}{family}{psi})",
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
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<PyTaskConstants>()?;
    bounds::register(m)?;
    envs::register(m)?;
    record::register(m)?;
    runs::register(m)?;
    safe::register(m)?;
    train::register(m)?;
    Ok(())
}
