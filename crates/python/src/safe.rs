//! The framework-agnostic safe-step API: a training loop written with any framework passes
//! its own gradient estimates (with confidence widths, or the per-trajectory samples they
//! come from, or the raw per-step rewards and scores of its trajectories) and gets back
//! SEPG's greedy-coordinate safe steps, the improvement each guarantees and its flags — the
//! same code the Rust algorithms run (`sepg_algo::solver::steps`).
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyModule;
use sepg_algo::core::options::WStep;
use sepg_algo::solver::sampled::BlockEstimator;
use sepg_algo::solver::source::{Grad, Need};
use sepg_algo::solver::steps::{self, Plan};
use sepg_bounds::direction::{Direction, FeatureNorm};
use sepg_estimators::{GradientSpec, Width, width};
use sepg_mdp::Batch;

use crate::{PyTaskConstants, floats, invalid, vector};

/// One greedy-coordinate update chosen by SEPG's step rule: coordinate `index` moves by
/// `delta = size · direction_index`. `guaranteed` is the improvement of J the step
/// guarantees (with probability 1 − δ per width when estimated, Theorems 4.7–4.9);
/// `infeasible` says the requirement exceeded C_max and the step of maximal guaranteed
/// improvement was taken instead (λ = 0); `below_noise` says no update is made (a zero
/// direction, or ‖∇̂‖∞ ≤ ε, eq. 4.23).
#[pyclass(frozen, name = "SafeStep", module = "sepg")]
#[derive(Debug, Clone, Copy)]
pub struct PySafeStep(pub(crate) Plan);

#[pymethods]
impl PySafeStep {
    /// The coordinate that moves (`None` below noise).
    #[getter]
    fn index(&self) -> Option<usize> {
        match self.0 {
            Plan::Update(s) => Some(s.index),
            Plan::BelowNoise => None,
        }
    }

    /// The step size (α or β; 0 below noise).
    #[getter]
    fn size(&self) -> f64 {
        match self.0 {
            Plan::Update(s) => s.size,
            Plan::BelowNoise => 0.0,
        }
    }

    /// The change of the moving coordinate (0 below noise).
    #[getter]
    fn delta(&self) -> f64 {
        match self.0 {
            Plan::Update(s) => s.delta,
            Plan::BelowNoise => 0.0,
        }
    }

    /// λ of the safe interval (eqs. 4.10, 4.17, 4.19); 0 when infeasible, `None` when
    /// undefined.
    #[getter]
    fn lam(&self) -> Option<f64> {
        match self.0 {
            Plan::Update(s) => s.lambda,
            Plan::BelowNoise => None,
        }
    }

    /// The improvement of J the step guarantees (`None` below noise).
    #[getter]
    fn guaranteed(&self) -> Option<f64> {
        match self.0 {
            Plan::Update(s) => Some(s.guaranteed),
            Plan::BelowNoise => None,
        }
    }

    /// The requirement was infeasible: the step of maximal guaranteed improvement was taken.
    #[getter]
    fn infeasible(&self) -> bool {
        matches!(self.0, Plan::Update(s) if s.infeasible)
    }

    /// No update: zero or sub-noise direction.
    #[getter]
    fn below_noise(&self) -> bool {
        matches!(self.0, Plan::BelowNoise)
    }

    /// `params` after the step (a new array; `params` itself is not modified).
    fn apply<'py>(
        &self,
        py: Python<'py>,
        params: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let mut x = vector(params, "params")?;
        if let Plan::Update(s) = self.0 {
            let len = x.len();
            let slot = x.get_mut(s.index).ok_or_else(|| {
                invalid(format!(
                    "params has {len} entries, the step moves entry {}",
                    s.index
                ))
            })?;
            *slot += s.delta;
            if !slot.is_finite() {
                return Err(invalid("the updated parameter overflows"));
            }
        }
        Ok(PyArray1::from_vec(py, x))
    }

    fn __repr__(&self) -> String {
        match self.0 {
            Plan::Update(s) => format!(
                "SafeStep(index={}, size={:?}, delta={:?}, lam={}, guaranteed={:?}, infeasible={})",
                s.index,
                s.size,
                s.delta,
                s.lambda.map_or("None".into(), |l| format!("{l:?}")),
                s.guaranteed,
                if s.infeasible { "True" } else { "False" }
            ),
            Plan::BelowNoise => "SafeStep(below_noise=True)".into(),
        }
    }
}

fn run_err(e: sepg_algo::core::error::RunError) -> PyErr {
    invalid(e)
}

/// A [`Grad`] from a gradient and optional widths (a scalar for every component, or one per
/// component; `None` for an exact gradient).
fn grad(value: &Bound<'_, PyAny>, eps: Option<&Bound<'_, PyAny>>, name: &str) -> PyResult<Grad> {
    let value = vector(value, name)?;
    let eps = match eps {
        None => vec![0.0; value.len()],
        Some(e) => {
            let (e, shape) = floats(e, &format!("widths of {name}"), None)?;
            match (shape.len(), e.len()) {
                (0 | 1, 1) => vec![e[0]; value.len()],
                (1, n) if n == value.len() => e,
                _ => {
                    return Err(invalid(format!(
                        "the widths of {name} must be a scalar or have length {}, got shape {shape:?}",
                        value.len()
                    )));
                }
            }
        }
    };
    if let Some(e) = eps.iter().find(|e| **e < 0.0) {
        return Err(invalid(format!(
            "the widths of {name} must be non-negative, got {e}"
        )));
    }
    Ok(Grad { value, eps })
}

/// The greedy-coordinate v-update with the largest safe step for the required improvement
/// `required` (C): Theorem 4.2, eq. (4.10) for an exact gradient (`eps=None`), and its
/// high-probability version, Theorem 4.7, eq. (4.26), with ε = max_i ε_i otherwise.
/// `sigma` is the smallest standard deviation of the policy.
#[pyfunction]
/// With `certify=True` the step is chosen with the certified (interval-arithmetic) bounds.
#[pyo3(signature = (constants, sigma, grad_v, eps = None, required = 0.0, certify = false))]
fn v_step(
    constants: PyRef<'_, PyTaskConstants>,
    sigma: f64,
    grad_v: &Bound<'_, PyAny>,
    eps: Option<&Bound<'_, PyAny>>,
    required: f64,
    certify: bool,
) -> PyResult<PySafeStep> {
    let g = grad(grad_v, eps, "grad_v")?;
    steps::v_step(&constants.0, sigma, &g, required, certify)
        .map(PySafeStep)
        .map_err(run_err)
}

/// The greedy-coordinate w-update with the largest safe step for the required improvement
/// `required` (C). With `grad_w_l` (∇_w L of Corollary 4.4) it moves along ∇_w L
/// (Theorem 4.5, eq. 4.19; Theorem 4.9, eq. 4.30 when estimated); without it, along ∇_w J
/// (the naive update, Theorem 4.3, eq. 4.17; Theorem 4.8, eq. 4.29). `sigmas` are the
/// standard deviations σ_j = e^{w_j}; the widths are per component or a scalar.
#[pyfunction]
/// With `certify=True` the step is chosen with the certified (interval-arithmetic) bounds.
/// Estimated gradients along ∇_w L use the exploring w-update (the confidence of ∇̂_w J only)
/// unless `theorem_4_9=True` asks for Theorem 4.9's form (eq. 4.30).
#[pyo3(signature = (constants, sigmas, grad_w_j, grad_w_l = None, eps_j = None, eps_l = None, required = 0.0, certify = false, theorem_4_9 = false))]
#[allow(clippy::too_many_arguments)]
fn w_step(
    constants: PyRef<'_, PyTaskConstants>,
    sigmas: &Bound<'_, PyAny>,
    grad_w_j: &Bound<'_, PyAny>,
    grad_w_l: Option<&Bound<'_, PyAny>>,
    eps_j: Option<&Bound<'_, PyAny>>,
    eps_l: Option<&Bound<'_, PyAny>>,
    required: f64,
    certify: bool,
    theorem_4_9: bool,
) -> PyResult<PySafeStep> {
    let form = if theorem_4_9 {
        WStep::Theorem49
    } else {
        WStep::Exploring
    };
    let sigmas = vector(sigmas, "sigmas")?;
    let gj = grad(grad_w_j, eps_j, "grad_w_j")?;
    if gj.value.len() != sigmas.len() {
        return Err(invalid(format!(
            "grad_w_j has length {}, sigmas {}",
            gj.value.len(),
            sigmas.len()
        )));
    }
    let plan = match grad_w_l {
        Some(l) => {
            let gl = grad(l, eps_l, "grad_w_l")?;
            if gl.value.len() != sigmas.len() {
                return Err(invalid(format!(
                    "grad_w_l has length {}, sigmas {}",
                    gl.value.len(),
                    sigmas.len()
                )));
            }
            steps::w_step_surrogate(&constants.0, &sigmas, &gl, &gj, required, certify, form)
        }
        None if eps_l.is_some() => return Err(invalid("eps_l was given without grad_w_l")),
        None => steps::w_step_naive(&constants.0, &sigmas, &gj, required, certify),
    };
    plan.map(PySafeStep).map_err(run_err)
}

/// The adaptive step of Pirotta et al. with fixed σ (Corollary 3.11; Theorem 3.12 with
/// widths), as `(alpha, guaranteed)`, or `None` for a zero or sub-noise gradient.
#[pyfunction]
#[pyo3(signature = (constants, sigma, grad, eps = None))]
fn ada_step(
    constants: PyRef<'_, PyTaskConstants>,
    sigma: f64,
    grad: &Bound<'_, PyAny>,
    eps: Option<&Bound<'_, PyAny>>,
) -> PyResult<Option<(f64, f64)>> {
    let g = self::grad(grad, eps, "grad")?;
    steps::ada_step(&constants.0, sigma, &g).map_err(run_err)
}

/// A mean and its confidence half-widths.
type MeanAndWidths<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>);

/// The mean of per-trajectory samples (shape `(N, d)`, one row per trajectory) and their
/// Student-t half-widths ε_i = t(1 − δ/2, N − 1)·√(Var_i / N) (Sec 4.5, eq. 4.22), as two
/// arrays of length d. Needs N ≥ 2.
#[pyfunction]
#[pyo3(signature = (samples, delta = sepg_algo::DEFAULT_DELTA))]
fn confidence_widths<'py>(
    py: Python<'py>,
    samples: &Bound<'py, PyAny>,
    delta: f64,
) -> PyResult<MeanAndWidths<'py>> {
    let (x, shape) = floats(samples, "samples", Some(2))?;
    let (n, d) = (shape[0], shape[1]);
    if d == 0 {
        return Err(invalid("samples must have at least one column"));
    }
    if n < 2 {
        return Err(invalid(format!(
            "a confidence width needs at least 2 samples (rows), got {n}"
        )));
    }
    let mut mean = vec![0.0; d];
    for row in x.chunks_exact(d) {
        for (m, v) in mean.iter_mut().zip(row) {
            *m += v;
        }
    }
    mean.iter_mut().for_each(|m| *m /= n as f64);
    let mut var = vec![0.0; d];
    for row in x.chunks_exact(d) {
        for ((s, v), m) in var.iter_mut().zip(row).zip(&mean) {
            *s += (v - m) * (v - m);
        }
    }
    let eps = var
        .iter()
        .map(|s| width(Width::StudentT, s / (n as f64 - 1.0), n, delta))
        .collect::<Result<Vec<_>, _>>()
        .map_err(invalid)?;
    if mean.iter().chain(&eps).any(|v| !v.is_finite()) {
        return Err(invalid("the samples overflow"));
    }
    Ok((PyArray1::from_vec(py, mean), PyArray1::from_vec(py, eps)))
}

/// A batch from per-step arrays: `rewards` `(N, H)`, `score_v` `(N, H, m)`, `score_w`
/// `(N, H, l)`, `lengths` `(N,)`; empty scores for a J-only batch.
fn batch_from_arrays(
    gamma: f64,
    sigma: &[f64],
    rewards: &Bound<'_, PyAny>,
    score_v: Option<&Bound<'_, PyAny>>,
    score_w: Option<&Bound<'_, PyAny>>,
    lengths: &Bound<'_, PyAny>,
) -> PyResult<Batch> {
    let (r, rshape) = floats(rewards, "rewards", Some(2))?;
    let lengths = lengths_of(lengths, rshape[0])?;
    let scores = |a: Option<&Bound<'_, PyAny>>, name: &str| -> PyResult<Vec<f64>> {
        match a {
            None => Ok(Vec::new()),
            Some(a) => {
                let (x, shape) = floats(a, name, Some(3))?;
                if shape[..2] != rshape[..] {
                    return Err(invalid(format!(
                        "{name} has shape {shape:?}, its first two dimensions must be those of rewards {rshape:?}"
                    )));
                }
                Ok(x)
            }
        }
    };
    let sv = scores(score_v, "score_v")?;
    let sw = scores(score_w, "score_w")?;
    Batch::from_steps(rshape[1], gamma, sigma, &r, &sv, &sw, &lengths).map_err(invalid)
}

/// Trajectory lengths: `n` non-negative integers.
pub(crate) fn lengths_of(obj: &Bound<'_, PyAny>, n: usize) -> PyResult<Vec<usize>> {
    let (l, shape) = floats(obj, "lengths", Some(1))?;
    if shape[0] != n {
        return Err(invalid(format!(
            "lengths has {} entries, rewards {n} rows",
            shape[0]
        )));
    }
    l.iter()
        .map(|&x| {
            if x >= 0.0 && x.fract() == 0.0 && x <= usize::MAX as f64 {
                Ok(x as usize)
            } else {
                Err(invalid(format!(
                    "lengths must be non-negative integers, got {x}"
                )))
            }
        })
        .collect()
}

/// The estimates of one block of SEPG from the per-step data of its N trajectories:
/// Ĵ (mean discounted return), ∇̂_v J, ∇̂_w J (G(PO)MDP with the leave-one-out
/// variance-optimal baseline) and ∇̂_w L (Corollary 4.4, estimator of Appendix B), each with
/// Student-t widths at level δ (Sec 4.5). `rewards` are the raw rewards r_t, `score_v` and
/// `score_w` the per-step scores ∇ log π(a_t|s_t) (not accumulated), `lengths` the steps each
/// trajectory took (values past a trajectory's end are ignored), `sigma` the standard
/// deviations that generated the actions. Returns a dict with `j`, `grad_v`, `eps_v`,
/// `grad_w_j`, `eps_w_j`, `grad_w_l`, `eps_w_l`, `trajectories` and `steps`.
#[pyfunction]
#[pyo3(signature = (constants, sigma, rewards, score_v, score_w, lengths, delta = sepg_algo::DEFAULT_DELTA, grad_w_l = true))]
#[allow(clippy::too_many_arguments)]
fn estimate_block<'py>(
    py: Python<'py>,
    constants: PyRef<'_, PyTaskConstants>,
    sigma: &Bound<'py, PyAny>,
    rewards: &Bound<'py, PyAny>,
    score_v: &Bound<'py, PyAny>,
    score_w: &Bound<'py, PyAny>,
    lengths: &Bound<'py, PyAny>,
    delta: f64,
    grad_w_l: bool,
) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
    let sigma = vector(sigma, "sigma")?;
    if !(delta > 0.0 && delta < 1.0) {
        return Err(invalid(format!("delta = {delta} is not in (0, 1)")));
    }
    let k = constants.0;
    let batch = batch_from_arrays(
        k.gamma(),
        &sigma,
        rewards,
        Some(score_v),
        Some(score_w),
        lengths,
    )?;
    let need = Need {
        grad_v: true,
        grad_wj: true,
        grad_wl: grad_w_l,
        j_width: false,
    };
    let e = BlockEstimator::new(delta, GradientSpec::default(), k)
        .estimate(&batch, need)
        .map_err(run_err)?;
    let out = pyo3::types::PyDict::new(py);
    out.set_item("j", e.j)?;
    for (name, eps_name, g) in [
        ("grad_v", "eps_v", e.grad_v),
        ("grad_w_j", "eps_w_j", e.grad_wj),
        ("grad_w_l", "eps_w_l", e.grad_wl),
    ] {
        match g {
            Some(g) => {
                out.set_item(name, PyArray1::from_vec(py, g.value))?;
                out.set_item(eps_name, PyArray1::from_vec(py, g.eps))?;
            }
            None => {
                out.set_item(name, py.None())?;
                out.set_item(eps_name, py.None())?;
            }
        }
    }
    out.set_item("trajectories", e.trajectories)?;
    out.set_item("steps", e.steps)?;
    Ok(out)
}

/// The largest certified step t ∈ [0, `max_step`] along a proposed change `direction` = u of
/// the mean parameters (Adam's, a natural gradient's, a user optimiser's), for the required
/// improvement `required` = C, against the estimate `grad` = ĝ of ∇_vJ with half-widths `eps`
/// (a scalar or one per component; 0 for an exact gradient) (docs/THEOREMS.md, "A step along
/// any direction"):
///
/// B(t) = t·(u·ĝ) − t·Σ|u_i|ε_i − c(σ)·κ_φ·t²·‖u‖₂² ≥ C,
///
/// with κ_φ = 1 for a coordinate direction, else p = `features` (the features of one action;
/// default the length of u, which bounds it) or (M₂/M_φ)² for a stated bound `feature_norm`
/// = M₂ ≥ ‖φ(s)‖₂. The step is certified in outward-rounded interval arithmetic
/// (`sepg_certified::direction_safe_step` over `sepg_bounds::direction::DirectionBound`).
/// `sigma` is the smallest standard deviation of the policy. Returns `(t, guaranteed,
/// certified)`: `guaranteed` is the lower end of the enclosure of B(t) (performance units);
/// when `certified` is false no step meets C, and t is the step of largest guarantee within
/// the cap (its guarantee below C). The thesis's constants are proven for coordinate
/// directions only: another direction raises `InvalidInputError`.
#[pyfunction]
#[pyo3(signature = (constants, sigma, direction, grad, eps, required, max_step = 1.0, features = None, feature_norm = None))]
#[allow(clippy::too_many_arguments)]
fn direction_safe_step(
    constants: PyRef<'_, PyTaskConstants>,
    sigma: f64,
    direction: &Bound<'_, PyAny>,
    grad: &Bound<'_, PyAny>,
    eps: &Bound<'_, PyAny>,
    required: f64,
    max_step: f64,
    features: Option<usize>,
    feature_norm: Option<f64>,
) -> PyResult<(f64, f64, bool)> {
    let u = vector(direction, "direction")?;
    let g = self::grad(grad, Some(eps), "grad")?;
    let features = match (features, feature_norm) {
        (Some(_), Some(_)) => {
            return Err(invalid(
                "give at most one of features (p) and feature_norm (M2)",
            ));
        }
        (_, Some(m2)) => FeatureNorm::Stated(m2),
        (Some(p), None) => FeatureNorm::FromMax { features: p },
        (None, None) => FeatureNorm::FromMax { features: u.len() },
    };
    let d = Direction {
        direction: &u,
        grad_hat: &g.value,
        eps: &g.eps,
        features,
    };
    let outcome = sepg_certified::direction_safe_step(&constants.0, sigma, &d, required, max_step)
        .map_err(invalid)?;
    match (outcome.chosen_step(), outcome.bound()) {
        (Some(t), Some(b)) => Ok((t, b.lo(), outcome.is_certified())),
        _ => Err(invalid("no step along the direction")),
    }
}

/// Adds the functions and classes of this module to `m`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PySafeStep>()?;
    m.add_function(wrap_pyfunction!(v_step, m)?)?;
    m.add_function(wrap_pyfunction!(w_step, m)?)?;
    m.add_function(wrap_pyfunction!(ada_step, m)?)?;
    m.add_function(wrap_pyfunction!(direction_safe_step, m)?)?;
    m.add_function(wrap_pyfunction!(confidence_widths, m)?)?;
    m.add_function(wrap_pyfunction!(estimate_block, m)?)?;
    Ok(())
}
