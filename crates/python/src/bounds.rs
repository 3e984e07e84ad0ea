//! Every closed-form quantity of `sepg_bounds`, one Python function per Rust function, named
//! `<module>_<function>` after the Rust path (`v_update::safe_step` → `v_update_safe_step`).
//! Vectors are any one-dimensional array-like of floats; steps and improvements are in the
//! units of the parameters and of J.
use pyo3::prelude::*;
use pyo3::types::PyModule;
use sepg_bounds::budget::{self, Budget};
use sepg_bounds::high_probability::{self as hp, HighProbabilityBound, HpForm};
use sepg_bounds::outcome::StepOutcome;
use sepg_bounds::pirotta::AdaptiveStep;
use sepg_bounds::{
    batch_size, constants, greedy, papini, pirotta, rigorous, surrogate, v_update, w_update,
};

use crate::{PyTaskConstants, invalid, vector};

type K<'a> = PyRef<'a, PyTaskConstants>;

/// The outcome of a safe-step computation for a required improvement C (Theorems 4.2–4.9):
/// `kind` is `"feasible"` (every step in `[lo, hi]` guarantees at least C), `"infeasible"`
/// (C > C_max; `vertex` attains C_max), `"zero_gradient"` (the direction is 0) or
/// `"below_noise"` (the estimate is within its confidence width, eq. 4.23).
#[pyclass(frozen, name = "StepOutcome", module = "sepg")]
#[derive(Debug, Clone, Copy)]
pub struct PyStepOutcome(pub(crate) StepOutcome);

#[pymethods]
impl PyStepOutcome {
    /// `"feasible"`, `"infeasible"`, `"zero_gradient"` or `"below_noise"`.
    #[getter]
    fn kind(&self) -> &'static str {
        match self.0 {
            StepOutcome::Feasible(_) => "feasible",
            StepOutcome::Infeasible { .. } => "infeasible",
            StepOutcome::ZeroGradient { .. } => "zero_gradient",
            StepOutcome::BelowNoise => "below_noise",
        }
    }

    /// The step to take: the largest safe step when feasible, the vertex when infeasible,
    /// `None` when no update should be made.
    #[getter]
    fn chosen_step(&self) -> Option<f64> {
        self.0.chosen_step()
    }

    /// C_max, the largest guaranteed improvement (`None` below noise).
    #[getter]
    fn c_max(&self) -> Option<f64> {
        self.0.c_max()
    }

    /// Whether the requirement can be guaranteed.
    #[getter]
    fn is_feasible(&self) -> bool {
        self.0.is_feasible()
    }

    /// The step of maximal guaranteed improvement (feasible or infeasible outcomes).
    #[getter]
    fn vertex(&self) -> Option<f64> {
        match self.0 {
            StepOutcome::Feasible(s) => Some(s.vertex),
            StepOutcome::Infeasible { vertex, .. } => Some(vertex),
            _ => None,
        }
    }

    /// λ = √(1 − C/C_max) of eqs. (4.10), (4.17), (4.19) (feasible outcomes, when defined).
    #[getter]
    fn lam(&self) -> Option<f64> {
        match self.0 {
            StepOutcome::Feasible(s) => s.lambda,
            _ => None,
        }
    }

    /// Smallest safe step (feasible outcomes).
    #[getter]
    fn lo(&self) -> Option<f64> {
        match self.0 {
            StepOutcome::Feasible(s) => Some(s.lo),
            _ => None,
        }
    }

    /// Largest safe step (feasible outcomes).
    #[getter]
    fn hi(&self) -> Option<f64> {
        match self.0 {
            StepOutcome::Feasible(s) => Some(s.hi),
            _ => None,
        }
    }

    fn __repr__(&self) -> String {
        let opt = |x: Option<f64>| x.map_or("None".to_string(), |v| format!("{v:?}"));
        format!(
            "StepOutcome(kind='{}', chosen_step={}, c_max={}, lo={}, hi={}, lam={})",
            self.kind(),
            opt(self.chosen_step()),
            opt(self.c_max()),
            opt(self.lo()),
            opt(self.hi()),
            opt(self.lam())
        )
    }
}

fn outcome(o: Result<StepOutcome, sepg_bounds::BoundsError>) -> PyResult<PyStepOutcome> {
    o.map(PyStepOutcome).map_err(invalid)
}

fn form(name: &str) -> PyResult<HpForm> {
    match name {
        "sign_aware" => Ok(HpForm::SignAware),
        "thesis" => Ok(HpForm::Thesis),
        other => Err(invalid(format!(
            "form must be \"sign_aware\" or \"thesis\", got {other:?}"
        ))),
    }
}

/// ψ = max_{χ ≥ 0} |(χ² − 4χ + 1) e^{−χ/2}| / √(2π) ≈ 0.523557, the constant of Lemma A.1
/// bounding the second derivative of a Gaussian density in its log standard deviation.
#[pyfunction]
fn constants_psi() -> f64 {
    constants::psi()
}

/// c(σ) of Theorems 3.14 and 4.2: the penalty coefficient of the v-update bound.
#[pyfunction]
fn constants_c(k: K<'_>, sigma: f64) -> PyResult<f64> {
    constants::c(&k.0, sigma).map_err(invalid)
}

/// ∂c/∂σ, the derivative of c(σ) (Corollary 4.4, Appendix B).
#[pyfunction]
fn constants_dc_dsigma(k: K<'_>, sigma: f64) -> PyResult<f64> {
    constants::dc_dsigma(&k.0, sigma).map_err(invalid)
}

/// d(σ) of Theorem 4.3 (eq. 4.15): the penalty coefficient of the w-update bound.
#[pyfunction]
fn constants_d(k: K<'_>, sigma: f64) -> PyResult<f64> {
    constants::d(&k.0, sigma).map_err(invalid)
}

/// The lower bound of Theorem 3.10 on J(θ + α∇J) − J(θ) with fixed σ.
#[pyfunction]
fn pirotta_bound(k: K<'_>, sigma: f64, grad: &Bound<'_, PyAny>, alpha: f64) -> PyResult<f64> {
    pirotta::bound(&k.0, sigma, &vector(grad, "grad")?, alpha).map_err(invalid)
}

fn adaptive(step: AdaptiveStep) -> (Option<f64>, Option<f64>, &'static str) {
    match step {
        AdaptiveStep::Step { alpha, guarantee } => (Some(alpha), Some(guarantee), "step"),
        AdaptiveStep::ZeroGradient => (None, None, "zero_gradient"),
        AdaptiveStep::BelowNoise => (None, None, "below_noise"),
    }
}

/// The adaptive step α* of Corollary 3.11 and its guaranteed improvement, as
/// `(alpha, guarantee, kind)` with kind `"step"` or `"zero_gradient"`.
#[pyfunction]
fn pirotta_optimal_step(
    k: K<'_>,
    sigma: f64,
    grad: &Bound<'_, PyAny>,
) -> PyResult<(Option<f64>, Option<f64>, &'static str)> {
    pirotta::optimal_step(&k.0, sigma, &vector(grad, "grad")?)
        .map(adaptive)
        .map_err(invalid)
}

/// The high-probability lower bound of Theorem 3.12 for an estimate `grad_hat` with
/// component widths `eps`.
#[pyfunction]
fn pirotta_hp_bound(
    k: K<'_>,
    sigma: f64,
    grad_hat: &Bound<'_, PyAny>,
    eps: &Bound<'_, PyAny>,
    alpha: f64,
) -> PyResult<f64> {
    pirotta::hp_bound(
        &k.0,
        sigma,
        &vector(grad_hat, "grad_hat")?,
        &vector(eps, "eps")?,
        alpha,
    )
    .map_err(invalid)
}

/// The step maximising the bound of Theorem 3.12, as `(alpha, guarantee, kind)` with kind
/// `"step"`, `"zero_gradient"` or `"below_noise"`.
#[pyfunction]
fn pirotta_hp_optimal_step(
    k: K<'_>,
    sigma: f64,
    grad_hat: &Bound<'_, PyAny>,
    eps: &Bound<'_, PyAny>,
) -> PyResult<(Option<f64>, Option<f64>, &'static str)> {
    pirotta::hp_optimal_step(
        &k.0,
        sigma,
        &vector(grad_hat, "grad_hat")?,
        &vector(eps, "eps")?,
    )
    .map(adaptive)
    .map_err(invalid)
}

/// The bound of Theorem 3.14 for per-coordinate steps `steps` (the diagonal of Λ).
#[pyfunction]
fn papini_bound(
    k: K<'_>,
    sigma: f64,
    grad: &Bound<'_, PyAny>,
    steps: &Bound<'_, PyAny>,
) -> PyResult<f64> {
    papini::bound(
        &k.0,
        sigma,
        &vector(grad, "grad")?,
        &vector(steps, "steps")?,
    )
    .map_err(invalid)
}

/// The greedy-coordinate maximiser of the Theorem 3.14 bound, as
/// `(index, alpha, steps, guarantee)` (eq. 4.9).
#[pyfunction]
fn papini_greedy_step(
    k: K<'_>,
    sigma: f64,
    grad: &Bound<'_, PyAny>,
) -> PyResult<(usize, f64, Vec<f64>, f64)> {
    let s = papini::greedy_step(&k.0, sigma, &vector(grad, "grad")?).map_err(invalid)?;
    Ok((s.index, s.alpha, s.steps, s.guarantee))
}

/// The REINFORCE batch size of Corollary 3.13 for an ε-accurate gradient with probability
/// 1 − δ over `horizon` steps.
#[pyfunction]
fn batch_size_reinforce(k: K<'_>, sigma: f64, delta: f64, eps: f64, horizon: u32) -> PyResult<u64> {
    batch_size::reinforce(&k.0, sigma, delta, eps, horizon).map_err(invalid)
}

/// The G(PO)MDP batch size of Corollary 3.13.
#[pyfunction]
fn batch_size_gpomdp(k: K<'_>, sigma: f64, delta: f64, eps: f64, horizon: u32) -> PyResult<u64> {
    batch_size::gpomdp(&k.0, sigma, delta, eps, horizon).map_err(invalid)
}

/// α* of Theorem 4.2 (eq. 4.8): the step of maximal guaranteed improvement of the v-update.
#[pyfunction]
fn v_update_alpha_star(k: K<'_>, sigma: f64) -> PyResult<f64> {
    v_update::alpha_star(&k.0, sigma).map_err(invalid)
}

/// C_max of the v-update (Theorem 4.2, eq. 4.9).
#[pyfunction]
fn v_update_c_max(k: K<'_>, sigma: f64, grad_v: &Bound<'_, PyAny>) -> PyResult<f64> {
    v_update::c_max(&k.0, sigma, &vector(grad_v, "grad_v")?).map_err(invalid)
}

/// The guaranteed improvement of the greedy-coordinate v-step α (Theorem 4.2).
#[pyfunction]
fn v_update_bound(k: K<'_>, sigma: f64, grad_v: &Bound<'_, PyAny>, alpha: f64) -> PyResult<f64> {
    v_update::bound(&k.0, sigma, &vector(grad_v, "grad_v")?, alpha).map_err(invalid)
}

/// The safe v-steps for a required improvement C (Theorem 4.2, eq. 4.10).
#[pyfunction]
fn v_update_safe_step(
    k: K<'_>,
    sigma: f64,
    grad_v: &Bound<'_, PyAny>,
    required: f64,
) -> PyResult<PyStepOutcome> {
    outcome(v_update::safe_step(
        &k.0,
        sigma,
        &vector(grad_v, "grad_v")?,
        required,
    ))
}

/// β* = 1/(2d) of Theorem 4.3: the step of maximal guaranteed improvement along ∇_w J.
#[pyfunction]
fn w_update_beta_star(k: K<'_>, sigma: f64) -> PyResult<f64> {
    w_update::beta_star(&k.0, sigma).map_err(invalid)
}

/// C_max of the w-update along ∇_w J (Theorem 4.3, eq. 4.16).
#[pyfunction]
fn w_update_c_max(k: K<'_>, sigma: f64, grad_w_j: f64) -> PyResult<f64> {
    w_update::c_max(&k.0, sigma, grad_w_j).map_err(invalid)
}

/// The guaranteed improvement of the w-step β along ∇_w J (Theorem 4.3).
#[pyfunction]
fn w_update_bound_along_j(k: K<'_>, sigma: f64, grad_w_j: f64, beta: f64) -> PyResult<f64> {
    w_update::bound_along_j(&k.0, sigma, grad_w_j, beta).map_err(invalid)
}

/// The safe w-steps along ∇_w J for a required improvement C (eq. 4.17).
#[pyfunction]
fn w_update_safe_step_along_j(
    k: K<'_>,
    sigma: f64,
    grad_w_j: f64,
    required: f64,
) -> PyResult<PyStepOutcome> {
    outcome(w_update::safe_step_along_j(&k.0, sigma, grad_w_j, required))
}

/// The guaranteed improvement of the w-step β along ∇_w L (Theorem 4.5).
#[pyfunction]
fn w_update_bound_along_l(
    k: K<'_>,
    sigma: f64,
    grad_w_j: f64,
    grad_w_l: f64,
    beta: f64,
) -> PyResult<f64> {
    w_update::bound_along_l(&k.0, sigma, grad_w_j, grad_w_l, beta).map_err(invalid)
}

/// β̃ of Theorem 4.5: the step along ∇_w L of maximal guaranteed improvement.
#[pyfunction]
fn w_update_beta_tilde(k: K<'_>, sigma: f64, grad_w_j: f64, grad_w_l: f64) -> PyResult<f64> {
    w_update::beta_tilde(&k.0, sigma, grad_w_j, grad_w_l).map_err(invalid)
}

/// The safe w-steps along ∇_w L for a required improvement C (eq. 4.19).
#[pyfunction]
fn w_update_safe_step_along_l(
    k: K<'_>,
    sigma: f64,
    grad_w_j: f64,
    grad_w_l: f64,
    required: f64,
) -> PyResult<PyStepOutcome> {
    outcome(w_update::safe_step_along_l(
        &k.0, sigma, grad_w_j, grad_w_l, required,
    ))
}

/// The surrogate L(σ) = ‖∇_v J‖₂² / (4 m c(σ)) of Corollary 4.4.
#[pyfunction]
fn surrogate_surrogate(k: K<'_>, sigma: f64, grad_v: &Bound<'_, PyAny>) -> PyResult<f64> {
    surrogate::surrogate(&k.0, sigma, &vector(grad_v, "grad_v")?).map_err(invalid)
}

/// ∂_σ ∇_v J from h(θ) (Appendix B, eq. B.2): the mixed derivatives the surrogate gradient needs.
#[pyfunction]
fn surrogate_mixed_from_h(
    h: &Bound<'_, PyAny>,
    grad_v: &Bound<'_, PyAny>,
    sigma: f64,
) -> PyResult<Vec<f64>> {
    surrogate::mixed_from_h(&vector(h, "h")?, &vector(grad_v, "grad_v")?, sigma).map_err(invalid)
}

/// ∂L/∂σ (Corollary 4.4, eq. B.1) from ∇_v J and the mixed derivatives ∂_σ∇_v J.
#[pyfunction]
fn surrogate_grad_sigma(
    k: K<'_>,
    sigma: f64,
    grad_v: &Bound<'_, PyAny>,
    mixed: &Bound<'_, PyAny>,
) -> PyResult<f64> {
    surrogate::grad_sigma(
        &k.0,
        sigma,
        &vector(grad_v, "grad_v")?,
        &vector(mixed, "mixed")?,
    )
    .map_err(invalid)
}

/// ∇_w L = σ ∂L/∂σ (Corollary 4.4).
#[pyfunction]
fn surrogate_grad_w(
    k: K<'_>,
    sigma: f64,
    grad_v: &Bound<'_, PyAny>,
    mixed: &Bound<'_, PyAny>,
) -> PyResult<f64> {
    surrogate::grad_w(
        &k.0,
        sigma,
        &vector(grad_v, "grad_v")?,
        &vector(mixed, "mixed")?,
    )
    .map_err(invalid)
}

/// The corrected norms (‖∇̂‖∞ − ε, ‖∇̂‖∞ + ε) of Sec 4.5, `None` when ‖∇̂‖∞ ≤ ε (eq. 4.23).
#[pyfunction]
fn high_probability_corrected_norm(
    grad_hat: &Bound<'_, PyAny>,
    eps: f64,
) -> PyResult<Option<(f64, f64)>> {
    Ok(hp::corrected_norm(&vector(grad_hat, "grad_hat")?, eps)
        .map_err(invalid)?
        .map(|n| (n.lower, n.upper)))
}

/// A high-probability bound B(x) = a x − b x² on the improvement of a step x along an
/// estimated direction: Theorem 4.7 (`v_update`), 4.8 (`w_along_j`) or 4.9 (`w_along_l`).
#[pyclass(frozen, name = "HighProbabilityBound", module = "sepg")]
#[derive(Debug, Clone, Copy)]
pub struct PyHighProbabilityBound(HighProbabilityBound);

#[pymethods]
impl PyHighProbabilityBound {
    /// Theorem 4.7 (eq. 4.24); `None` when ‖∇̂_v J‖∞ ≤ ε.
    #[staticmethod]
    fn v_update(
        k: K<'_>,
        sigma: f64,
        grad_v_hat: &Bound<'_, PyAny>,
        eps: f64,
    ) -> PyResult<Option<Self>> {
        Ok(
            HighProbabilityBound::v_update(&k.0, sigma, &vector(grad_v_hat, "grad_v_hat")?, eps)
                .map_err(invalid)?
                .map(Self),
        )
    }

    /// Theorem 4.8 (eq. 4.27); `None` when |∇̂_w J| ≤ ε.
    #[staticmethod]
    fn w_along_j(k: K<'_>, sigma: f64, grad_w_j_hat: f64, eps: f64) -> PyResult<Option<Self>> {
        Ok(
            HighProbabilityBound::w_along_j(&k.0, sigma, grad_w_j_hat, eps)
                .map_err(invalid)?
                .map(Self),
        )
    }

    /// Theorem 4.9; `None` when the estimates are within their widths.
    #[staticmethod]
    fn w_along_l(
        k: K<'_>,
        sigma: f64,
        grad_w_j_hat: f64,
        eps_j: f64,
        grad_w_l_hat: f64,
        eps_l: f64,
    ) -> PyResult<Option<Self>> {
        Ok(
            HighProbabilityBound::w_along_l(&k.0, sigma, grad_w_j_hat, eps_j, grad_w_l_hat, eps_l)
                .map_err(invalid)?
                .map(Self),
        )
    }

    /// s = ±1, the sign of the steps the estimates favour.
    #[getter]
    fn direction(&self) -> f64 {
        self.0.direction
    }

    /// a⁻, the guaranteed linear coefficient for favoured steps.
    #[getter]
    fn linear_lower(&self) -> f64 {
        self.0.linear_lower
    }

    /// a⁺, the worst-case linear coefficient for opposite steps.
    #[getter]
    fn linear_upper(&self) -> f64 {
        self.0.linear_upper
    }

    /// b, the quadratic coefficient.
    #[getter]
    fn quadratic(&self) -> f64 {
        self.0.quadratic
    }

    /// The bound as printed in the thesis at step x.
    fn value(&self, x: f64) -> PyResult<f64> {
        self.0.value(x).map_err(invalid)
    }

    /// The sign-aware bound at step x (valid on both sides of 0).
    fn sign_aware_value(&self, x: f64) -> PyResult<f64> {
        self.0.sign_aware_value(x).map_err(invalid)
    }

    /// The step of maximal guaranteed improvement.
    fn vertex(&self) -> f64 {
        self.0.vertex()
    }

    /// The maximal guaranteed improvement.
    fn c_max(&self) -> f64 {
        self.0.c_max()
    }

    /// The safe steps for a required improvement C, in form `"sign_aware"` or `"thesis"`
    /// (eqs. 4.26, 4.29, 4.30).
    #[pyo3(signature = (required, form = "sign_aware"))]
    fn safe_step(&self, required: f64, form: &str) -> PyResult<PyStepOutcome> {
        outcome(self.0.safe_step(required, self::form(form)?))
    }

    fn __repr__(&self) -> String {
        format!("{:?}", self.0)
    }
}

/// The safe v-steps for an estimated gradient with width ε (Theorem 4.7, eq. 4.26).
#[pyfunction]
#[pyo3(signature = (k, sigma, grad_v_hat, eps, required, form = "sign_aware"))]
fn high_probability_v_safe_step(
    k: K<'_>,
    sigma: f64,
    grad_v_hat: &Bound<'_, PyAny>,
    eps: f64,
    required: f64,
    form: &str,
) -> PyResult<PyStepOutcome> {
    outcome(hp::v_safe_step(
        &k.0,
        sigma,
        &vector(grad_v_hat, "grad_v_hat")?,
        eps,
        required,
        self::form(form)?,
    ))
}

/// The safe w-steps along an estimated ∇_w J (Theorem 4.8, eq. 4.29).
#[pyfunction]
#[pyo3(signature = (k, sigma, grad_w_j_hat, eps, required, form = "sign_aware"))]
fn high_probability_w_safe_step_along_j(
    k: K<'_>,
    sigma: f64,
    grad_w_j_hat: f64,
    eps: f64,
    required: f64,
    form: &str,
) -> PyResult<PyStepOutcome> {
    outcome(hp::w_safe_step_along_j(
        &k.0,
        sigma,
        grad_w_j_hat,
        eps,
        required,
        self::form(form)?,
    ))
}

/// The safe w-steps along an estimated ∇_w L (Theorem 4.9, eq. 4.30).
#[pyfunction]
#[pyo3(signature = (k, sigma, grad_w_j_hat, eps_j, grad_w_l_hat, eps_l, required, form = "sign_aware"))]
#[allow(clippy::too_many_arguments)]
fn high_probability_w_safe_step_along_l(
    k: K<'_>,
    sigma: f64,
    grad_w_j_hat: f64,
    eps_j: f64,
    grad_w_l_hat: f64,
    eps_l: f64,
    required: f64,
    form: &str,
) -> PyResult<PyStepOutcome> {
    outcome(hp::w_safe_step_along_l(
        &k.0,
        sigma,
        grad_w_j_hat,
        eps_j,
        grad_w_l_hat,
        eps_l,
        required,
        self::form(form)?,
    ))
}

/// The lowest index of max_i |x_i| (the greedy coordinate of Sec 4.3.4).
#[pyfunction]
fn greedy_argmax_abs(values: &Bound<'_, PyAny>) -> PyResult<usize> {
    greedy::argmax_abs(&vector(values, "values")?).map_err(invalid)
}

/// The greedy-coordinate update: `params` with only coordinate argmax |grad_i| moved by
/// `step · grad_k` (eq. 4.11).
#[pyfunction]
fn greedy_coordinate_update(
    params: &Bound<'_, PyAny>,
    grad: &Bound<'_, PyAny>,
    step: f64,
) -> PyResult<Vec<f64>> {
    greedy::coordinate_update(&vector(params, "params")?, &vector(grad, "grad")?, step)
        .map_err(invalid)
}

/// The greedy-coordinate v-update (Theorem 4.2 with eq. 4.11), as `(index, outcome)`.
#[pyfunction]
fn greedy_v_step(
    k: K<'_>,
    sigma: f64,
    grad_v: &Bound<'_, PyAny>,
    required: f64,
) -> PyResult<(usize, PyStepOutcome)> {
    let s = greedy::v_step(&k.0, sigma, &vector(grad_v, "grad_v")?, required).map_err(invalid)?;
    Ok((s.index, PyStepOutcome(s.outcome)))
}

/// The greedy-coordinate w-update along ∇_w L (Theorem 4.5), as `(index, outcome)`.
#[pyfunction]
fn greedy_w_step(
    k: K<'_>,
    sigmas: &Bound<'_, PyAny>,
    grad_w_j: &Bound<'_, PyAny>,
    grad_w_l: &Bound<'_, PyAny>,
    required: f64,
) -> PyResult<(usize, PyStepOutcome)> {
    let s = greedy::w_step(
        &k.0,
        &vector(sigmas, "sigmas")?,
        &vector(grad_w_j, "grad_w_j")?,
        &vector(grad_w_l, "grad_w_l")?,
        required,
    )
    .map_err(invalid)?;
    Ok((s.index, PyStepOutcome(s.outcome)))
}

/// KL2(Δw) = e^{−2|Δw|} − 1 + 2|Δw|, the smaller doubled KL divergence of two Gaussians
/// with equal means (eq. A.7).
#[pyfunction]
fn rigorous_kl2(delta_w: f64) -> PyResult<f64> {
    rigorous::kl2(delta_w).map_err(invalid)
}

/// The rigorous lower bound of the w-update with no neglected terms (Lemmas A.1–A.3).
#[pyfunction]
fn rigorous_bound(k: K<'_>, sigma: f64, grad_w_j: f64, delta_w: f64) -> PyResult<f64> {
    rigorous::bound(&k.0, sigma, grad_w_j, delta_w).map_err(invalid)
}

/// The bound of Theorem 4.3 as printed, at the change Δw.
#[pyfunction]
fn rigorous_thesis_bound(k: K<'_>, sigma: f64, grad_w_j: f64, delta_w: f64) -> PyResult<f64> {
    rigorous::thesis_bound(&k.0, sigma, grad_w_j, delta_w).map_err(invalid)
}

/// The gap between the printed bound of Theorem 4.3 and the rigorous bound at Δw.
#[pyfunction]
fn rigorous_gap(k: K<'_>, sigma: f64, delta_w: f64) -> PyResult<f64> {
    rigorous::gap(&k.0, sigma, delta_w).map_err(invalid)
}

/// The changes Δw that the rigorous bound guarantees for a required improvement C.
#[pyfunction]
fn rigorous_safe_delta_w(
    k: K<'_>,
    sigma: f64,
    grad_w_j: f64,
    required: f64,
) -> PyResult<PyStepOutcome> {
    outcome(rigorous::safe_delta_w(&k.0, sigma, grad_w_j, required))
}

/// The rigorous safe steps β along ∇_w J for a required improvement C.
#[pyfunction]
fn rigorous_safe_step_along_j(
    k: K<'_>,
    sigma: f64,
    grad_w_j: f64,
    required: f64,
) -> PyResult<PyStepOutcome> {
    outcome(rigorous::safe_step_along_j(&k.0, sigma, grad_w_j, required))
}

/// The rigorous safe steps β along ∇_w L for a required improvement C.
#[pyfunction]
fn rigorous_safe_step_along_l(
    k: K<'_>,
    sigma: f64,
    grad_w_j: f64,
    grad_w_l: f64,
    required: f64,
) -> PyResult<PyStepOutcome> {
    outcome(rigorous::safe_step_along_l(
        &k.0, sigma, grad_w_j, grad_w_l, required,
    ))
}

/// The split (C_v, C_w) = ((1 − ν)C, νC) of a required improvement (eqs. 4.13, 4.14).
#[pyfunction]
fn budget_split_requirement(required: f64, nu: f64) -> PyResult<(f64, f64)> {
    budget::split_requirement(required, nu).map_err(invalid)
}

/// The budget B of Definition 4.3, tracked from measured performance differences
/// (Theorem 4.1): B^t = B⁰ + Σ ΔJ_E + Σ ΔJ_T.
#[pyclass(name = "Budget", module = "sepg")]
#[derive(Debug, Clone)]
pub struct PyBudget(Budget);

#[pymethods]
impl PyBudget {
    /// A budget B⁰ = `initial` with starting performances J_E⁰ and, optionally, J_T⁰ of the
    /// target policy (Algorithm 4.3, lines 2–3).
    #[new]
    #[pyo3(signature = (initial, j_exploratory, j_target = None))]
    fn new(initial: f64, j_exploratory: f64, j_target: Option<f64>) -> PyResult<Self> {
        Budget::new(initial, j_exploratory, j_target)
            .map(Self)
            .map_err(invalid)
    }

    /// Adds a measured difference ΔJ_E of the exploratory policy.
    fn add_exploratory_difference(&mut self, delta: f64) -> PyResult<()> {
        self.0.add_exploratory_difference(delta).map_err(invalid)
    }

    /// Adds a measured difference ΔJ_T of the target policy.
    fn add_target_difference(&mut self, delta: f64) -> PyResult<()> {
        self.0.add_target_difference(delta).map_err(invalid)
    }

    /// Records a new J_E and returns the difference added to the budget.
    fn record_exploratory(&mut self, j: f64) -> PyResult<f64> {
        self.0.record_exploratory(j).map_err(invalid)
    }

    /// Records a new J_T and returns the difference added to the budget.
    fn record_target(&mut self, j: f64) -> PyResult<f64> {
        self.0.record_target(j).map_err(invalid)
    }

    /// The current budget B.
    #[getter]
    fn value(&self) -> f64 {
        self.0.value()
    }

    /// B⁰.
    #[getter]
    fn initial(&self) -> f64 {
        self.0.initial()
    }

    /// The required improvement C = −B of the next type-II update.
    #[getter]
    fn required_improvement(&self) -> f64 {
        self.0.required_improvement()
    }

    /// The baseline performance of the type-II guarantee.
    #[getter]
    fn baseline(&self) -> f64 {
        self.0.baseline()
    }

    /// The average performance of the tracked policies.
    #[getter]
    fn average_performance(&self) -> f64 {
        self.0.average_performance()
    }

    /// The telescoped change J_E^t − J_E⁰ (+ J_T^t − J_T⁰) of the proof of Theorem 4.1.
    #[getter]
    fn telescoped_change(&self) -> f64 {
        self.0.telescoped_change()
    }

    /// The average performance Theorem 4.1 guarantees.
    #[getter]
    fn guaranteed_average(&self) -> f64 {
        self.0.guaranteed_average()
    }

    /// Whether B ≥ 0 (type-II safety holds).
    #[getter]
    fn is_type_two_safe(&self) -> bool {
        self.0.is_type_two_safe()
    }

    fn __repr__(&self) -> String {
        format!(
            "Budget(value={:?}, initial={:?})",
            self.0.value(),
            self.0.initial()
        )
    }
}

/// Adds the functions and classes of this module to `m`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyStepOutcome>()?;
    m.add_class::<PyHighProbabilityBound>()?;
    m.add_class::<PyBudget>()?;
    macro_rules! add {
        ($($f:ident),* $(,)?) => {
            $(m.add_function(wrap_pyfunction!($f, m)?)?;)*
        };
    }
    add!(
        constants_psi,
        constants_c,
        constants_dc_dsigma,
        constants_d,
        pirotta_bound,
        pirotta_optimal_step,
        pirotta_hp_bound,
        pirotta_hp_optimal_step,
        papini_bound,
        papini_greedy_step,
        batch_size_reinforce,
        batch_size_gpomdp,
        v_update_alpha_star,
        v_update_c_max,
        v_update_bound,
        v_update_safe_step,
        w_update_beta_star,
        w_update_c_max,
        w_update_bound_along_j,
        w_update_safe_step_along_j,
        w_update_bound_along_l,
        w_update_beta_tilde,
        w_update_safe_step_along_l,
        surrogate_surrogate,
        surrogate_mixed_from_h,
        surrogate_grad_sigma,
        surrogate_grad_w,
        high_probability_corrected_norm,
        high_probability_v_safe_step,
        high_probability_w_safe_step_along_j,
        high_probability_w_safe_step_along_l,
        greedy_argmax_abs,
        greedy_coordinate_update,
        greedy_v_step,
        greedy_w_step,
        rigorous_kl2,
        rigorous_bound,
        rigorous_thesis_bound,
        rigorous_gap,
        rigorous_safe_delta_w,
        rigorous_safe_step_along_j,
        rigorous_safe_step_along_l,
        budget_split_requirement,
    );
    Ok(())
}
