//! Every quantity of `sepg_bounds` and the certified steps of `sepg_certified`, one Python
//! function per Rust function, named `<module>_<function>` after the Rust path
//! (`v_update::safe_step` → `v_update_safe_step`, `sepg_certified::v_safe_step` →
//! `certified_v_safe_step`),
//! and its classes: `StepOutcome`, `HighProbabilityBound`, `Budget`, `ExploringBound`, and
//! the interval arithmetic of the certified steps (`Interval`, `Enclosure`, `Certified`).
//! Vectors are any one-dimensional array-like of floats; steps and improvements are in the
//! units of the parameters and of J. The functions are defined by one table
//! (`bound_fns!`) that converts the arguments and errors the same way for every one.
use pyo3::prelude::*;
use pyo3::types::PyModule;
use sepg_bounds::budget::{self, Budget};
use sepg_bounds::exploring::{self, ExploringBound};
use sepg_bounds::high_probability::{self as hp, HighProbabilityBound, HpForm};
use sepg_bounds::outcome::StepOutcome;
use sepg_bounds::pirotta::AdaptiveStep;
use sepg_bounds::{
    BoundsError, batch_size, constants, greedy, papini, pirotta, rigorous, surrogate, v_update,
    w_update,
};
use sepg_certified::Interval;
use sepg_certified::{
    self as certified, Certified, EnclosedBound, ExploringEnclosure, HpEnclosure, Quadratic,
    RigorousEnclosure,
};

use sepg_runs::bounds_report::{BoundsQuery, StepVerdict, report};
use sepg_runs::spec::{ConstantsName, RewardsName};

use crate::pyjson::serialize_to_py;
use crate::{PyTaskConstants, horizon_arg, invalid, vector};

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

    /// Whether `x` lies in the safe interval `[lo, hi]` (`False` unless feasible).
    fn contains(&self, x: f64) -> bool {
        match self.0 {
            StepOutcome::Feasible(s) => s.contains(x),
            _ => false,
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

fn outcome(o: Result<StepOutcome, BoundsError>) -> PyResult<PyStepOutcome> {
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

impl From<StepOutcome> for PyStepOutcome {
    fn from(o: StepOutcome) -> Self {
        PyStepOutcome(o)
    }
}

/// The Python type of an argument of [`bound_fns!`], by kind: `k` validated task
/// constants, `f64` a real, `u32` a count, `vec` a one-dimensional array-like of finite reals, `pair` a
/// `(value, width)` tuple, `form` the name of a high-probability form.
macro_rules! param {
    (k) => { PyRef<'_, PyTaskConstants> };
    (f64) => { f64 };
    (u32) => { u32 };
    (vec) => { &Bound<'_, PyAny> };
    (pair) => { (f64, f64) };
    (form) => { &str };
}

/// The Rust argument of [`bound_fns!`] for the Python argument `$x` of kind `$kind` (see
/// [`param!`]); a bad vector or form name raises `InvalidInputError` naming the argument.
macro_rules! convert {
    (k, $x:ident) => {
        &$x.0
    };
    (f64, $x:ident) => {
        $x
    };
    (u32, $x:ident) => {
        $x
    };
    (vec, $x:ident) => {
        &vector($x, stringify!($x))?
    };
    (pair, $x:ident) => {
        $x
    };
    (form, $x:ident) => {
        form($x)?
    };
}

/// `Into::into`, or the given conversion of a Rust result into its Python value.
macro_rules! or_into {
    () => {
        Into::into
    };
    ($wrap:expr) => {
        $wrap
    };
}

/// One Python function per line of the table: `fn name(arg: kind, ...) -> PyType = rust::path`
/// (optionally `, conversion`) defines `name`, which converts each argument by its kind
/// ([`param!`], [`convert!`]), calls the Rust function, raises its error as
/// `InvalidInputError` (a `ValueError`) and converts its value with `Into` or the given
/// conversion. Attributes and doc comments go to the Python function (`#[pyo3(signature)]`
/// for defaults). Also defines `add_functions`, which registers every function of the table.
macro_rules! bound_fns {
    ($($(#[$attr:meta])* fn $name:ident($($arg:ident: $kind:ident),*) -> $out:ty = $path:path $(, $wrap:expr)?;)*) => {
        $(
            #[pyfunction]
            $(#[$attr])*
            fn $name($($arg: param!($kind)),*) -> PyResult<$out> {
                $path($(convert!($kind, $arg)),*)
                    .map_err(invalid)
                    .map(or_into!($($wrap)?))
            }
        )*

        /// Adds the functions of the table of [`bound_fns!`] to `m`.
        fn add_functions(m: &Bound<'_, PyModule>) -> PyResult<()> {
            $(m.add_function(wrap_pyfunction!($name, m)?)?;)*
            Ok(())
        }
    };
}

/// `(alpha, guarantee, kind)` of an adaptive step, kind `"step"`, `"zero_gradient"` or
/// `"below_noise"`.
fn adaptive(step: AdaptiveStep) -> (Option<f64>, Option<f64>, &'static str) {
    match step {
        AdaptiveStep::Step { alpha, guarantee } => (Some(alpha), Some(guarantee), "step"),
        AdaptiveStep::ZeroGradient => (None, None, "zero_gradient"),
        AdaptiveStep::BelowNoise => (None, None, "below_noise"),
    }
}

/// `(index, outcome)` of a greedy-coordinate step.
fn greedy_step(s: greedy::CoordinateStep) -> (usize, PyStepOutcome) {
    (s.index, PyStepOutcome(s.outcome))
}

bound_fns! {
    /// c(σ) of Theorems 3.14 and 4.2: the penalty coefficient of the v-update bound.
    fn constants_c(k: k, sigma: f64) -> f64 = constants::c;
    /// ∂c/∂σ, the derivative of c(σ) (Corollary 4.4, Appendix B).
    fn constants_dc_dsigma(k: k, sigma: f64) -> f64 = constants::dc_dsigma;
    /// d(σ) of Theorem 4.3 (eq. 4.15): the penalty coefficient of the w-update bound.
    fn constants_d(k: k, sigma: f64) -> f64 = constants::d;

    /// The lower bound of Theorem 3.10 on J(θ + α∇J) − J(θ) with fixed σ.
    fn pirotta_bound(k: k, sigma: f64, grad: vec, alpha: f64) -> f64 = pirotta::bound;
    /// The adaptive step α* of Corollary 3.11 and its guaranteed improvement, as
    /// `(alpha, guarantee, kind)` with kind `"step"` or `"zero_gradient"`.
    fn pirotta_optimal_step(k: k, sigma: f64, grad: vec) -> (Option<f64>, Option<f64>, &'static str)
        = pirotta::optimal_step, adaptive;
    /// The high-probability lower bound of Theorem 3.12 for an estimate `grad_hat` with
    /// component widths `eps`.
    fn pirotta_hp_bound(k: k, sigma: f64, grad_hat: vec, eps: vec, alpha: f64) -> f64 = pirotta::hp_bound;
    /// The step maximising the bound of Theorem 3.12, as `(alpha, guarantee, kind)` with kind
    /// `"step"`, `"zero_gradient"` or `"below_noise"`.
    fn pirotta_hp_optimal_step(k: k, sigma: f64, grad_hat: vec, eps: vec) -> (Option<f64>, Option<f64>, &'static str)
        = pirotta::hp_optimal_step, adaptive;

    /// The bound of Theorem 3.14 for per-coordinate steps `steps` (the diagonal of Λ).
    fn papini_bound(k: k, sigma: f64, grad: vec, steps: vec) -> f64 = papini::bound;
    /// The greedy-coordinate maximiser of the Theorem 3.14 bound, as
    /// `(index, alpha, steps, guarantee)` (eq. 4.9).
    fn papini_greedy_step(k: k, sigma: f64, grad: vec) -> (usize, f64, Vec<f64>, f64)
        = papini::greedy_step, |s| (s.index, s.alpha, s.steps, s.guarantee);

    /// The REINFORCE batch size of Corollary 3.13 for an ε-accurate gradient with probability
    /// 1 − δ over `horizon` steps.
    fn batch_size_reinforce(k: k, sigma: f64, delta: f64, eps: f64, horizon: u32) -> u64 = batch_size::reinforce;
    /// The G(PO)MDP batch size of Corollary 3.13.
    fn batch_size_gpomdp(k: k, sigma: f64, delta: f64, eps: f64, horizon: u32) -> u64 = batch_size::gpomdp;

    /// α* of Theorem 4.2 (eq. 4.8): the step of maximal guaranteed improvement of the v-update.
    fn v_update_alpha_star(k: k, sigma: f64) -> f64 = v_update::alpha_star;
    /// C_max of the v-update (Theorem 4.2, eq. 4.9).
    fn v_update_c_max(k: k, sigma: f64, grad_v: vec) -> f64 = v_update::c_max;
    /// The guaranteed improvement of the greedy-coordinate v-step α (Theorem 4.2).
    fn v_update_bound(k: k, sigma: f64, grad_v: vec, alpha: f64) -> f64 = v_update::bound;
    /// The safe v-steps for a required improvement C (Theorem 4.2, eq. 4.10).
    fn v_update_safe_step(k: k, sigma: f64, grad_v: vec, required: f64) -> PyStepOutcome = v_update::safe_step;

    /// β* = 1/(2d) of Theorem 4.3: the step of maximal guaranteed improvement along ∇_w J.
    fn w_update_beta_star(k: k, sigma: f64) -> f64 = w_update::beta_star;
    /// C_max of the w-update along ∇_w J (Theorem 4.3, eq. 4.16).
    fn w_update_c_max(k: k, sigma: f64, grad_w_j: f64) -> f64 = w_update::c_max;
    /// The guaranteed improvement of the w-step β along ∇_w J (Theorem 4.3).
    fn w_update_bound_along_j(k: k, sigma: f64, grad_w_j: f64, beta: f64) -> f64 = w_update::bound_along_j;
    /// The safe w-steps along ∇_w J for a required improvement C (eq. 4.17).
    fn w_update_safe_step_along_j(k: k, sigma: f64, grad_w_j: f64, required: f64) -> PyStepOutcome
        = w_update::safe_step_along_j;
    /// The guaranteed improvement of the w-step β along ∇_w L (Theorem 4.5).
    fn w_update_bound_along_l(k: k, sigma: f64, grad_w_j: f64, grad_w_l: f64, beta: f64) -> f64
        = w_update::bound_along_l;
    /// β̃ of Theorem 4.5: the step along ∇_w L of maximal guaranteed improvement.
    fn w_update_beta_tilde(k: k, sigma: f64, grad_w_j: f64, grad_w_l: f64) -> f64 = w_update::beta_tilde;
    /// The safe w-steps along ∇_w L for a required improvement C (eq. 4.19).
    fn w_update_safe_step_along_l(k: k, sigma: f64, grad_w_j: f64, grad_w_l: f64, required: f64) -> PyStepOutcome
        = w_update::safe_step_along_l;

    /// The surrogate L(σ) = ‖∇_v J‖₂² / (4 m c(σ)) of Corollary 4.4.
    fn surrogate_surrogate(k: k, sigma: f64, grad_v: vec) -> f64 = surrogate::surrogate;
    /// ∂_σ ∇_v J from h(θ) (Appendix B, eq. B.2): the mixed derivatives the surrogate gradient needs.
    fn surrogate_mixed_from_h(h: vec, grad_v: vec, sigma: f64) -> Vec<f64> = surrogate::mixed_from_h;
    /// ∂L/∂σ (Corollary 4.4, eq. B.1) from ∇_v J and the mixed derivatives ∂_σ∇_v J.
    fn surrogate_grad_sigma(k: k, sigma: f64, grad_v: vec, mixed: vec) -> f64 = surrogate::grad_sigma;
    /// ∇_w L = σ ∂L/∂σ (Corollary 4.4).
    fn surrogate_grad_w(k: k, sigma: f64, grad_v: vec, mixed: vec) -> f64 = surrogate::grad_w;

    /// The corrected norms (‖∇̂‖∞ − ε, ‖∇̂‖∞ + ε) of Sec 4.5, `None` when ‖∇̂‖∞ ≤ ε (eq. 4.23).
    fn high_probability_corrected_norm(grad_hat: vec, eps: f64) -> Option<(f64, f64)>
        = hp::corrected_norm, |n: Option<hp::CorrectedNorm>| n.map(|n| (n.lower, n.upper));
    /// The safe v-steps for an estimated gradient with width ε (Theorem 4.7, eq. 4.26).
    #[pyo3(signature = (k, sigma, grad_v_hat, eps, required, form = "sign_aware"))]
    fn high_probability_v_safe_step(k: k, sigma: f64, grad_v_hat: vec, eps: f64, required: f64, form: form)
        -> PyStepOutcome = hp::v_safe_step;
    /// The safe w-steps along an estimated ∇_w J (Theorem 4.8, eq. 4.29).
    #[pyo3(signature = (k, sigma, grad_w_j_hat, eps, required, form = "sign_aware"))]
    fn high_probability_w_safe_step_along_j(k: k, sigma: f64, grad_w_j_hat: f64, eps: f64, required: f64, form: form)
        -> PyStepOutcome = hp::w_safe_step_along_j;
    /// The safe w-steps along an estimated ∇_w L (Theorem 4.9, eq. 4.30).
    #[pyo3(signature = (k, sigma, grad_w_j_hat, eps_j, grad_w_l_hat, eps_l, required, form = "sign_aware"))]
    #[allow(clippy::too_many_arguments)]
    fn high_probability_w_safe_step_along_l(
        k: k, sigma: f64, grad_w_j_hat: f64, eps_j: f64, grad_w_l_hat: f64, eps_l: f64, required: f64, form: form
    ) -> PyStepOutcome = hp::w_safe_step_along_l;

    /// The lowest index of max_i |x_i| (the greedy coordinate of Sec 4.3.4).
    fn greedy_argmax_abs(values: vec) -> usize = greedy::argmax_abs;
    /// The greedy-coordinate update: `params` with only coordinate argmax |grad_i| moved by
    /// `step · grad_k` (eq. 4.11).
    fn greedy_coordinate_update(params: vec, grad: vec, step: f64) -> Vec<f64> = greedy::coordinate_update;
    /// The greedy-coordinate v-update (Theorem 4.2 with eq. 4.11), as `(index, outcome)`.
    fn greedy_v_step(k: k, sigma: f64, grad_v: vec, required: f64) -> (usize, PyStepOutcome)
        = greedy::v_step, greedy_step;
    /// The greedy-coordinate w-update along ∇_w L (Theorem 4.5), as `(index, outcome)`.
    fn greedy_w_step(k: k, sigmas: vec, grad_w_j: vec, grad_w_l: vec, required: f64) -> (usize, PyStepOutcome)
        = greedy::w_step, greedy_step;

    /// KL2(Δw) = e^{−2|Δw|} − 1 + 2|Δw|, the smaller doubled KL divergence of two Gaussians
    /// with equal means (eq. A.7).
    fn rigorous_kl2(delta_w: f64) -> f64 = rigorous::kl2;
    /// c_ℝ(σ): c(σ) of Theorem 4.2 made sound for a Gaussian on the real line (clipped
    /// actions), the box term |A|/(√(2π)σ) replaced by its maximum with K_MU; equal to c(σ)
    /// for σ ≤ |A|e^{1/2}/4.
    fn rigorous_c(k: k, sigma: f64) -> f64 = rigorous::c;
    /// The v-update bound of Theorem 4.2 with c_ℝ(σ): α‖∇_vJ‖∞² − α²c_ℝ(σ)‖∇_vJ‖∞².
    fn rigorous_v_bound(k: k, sigma: f64, grad_v: vec, alpha: f64) -> f64 = rigorous::v_bound;
    /// The safe v-steps of Theorem 4.2 (eqs. 4.9–4.10) with c_ℝ(σ).
    fn rigorous_v_safe_step(k: k, sigma: f64, grad_v: vec, required: f64) -> PyStepOutcome = rigorous::v_safe_step;
    /// The rigorous lower bound of the w-update with no neglected terms (Lemmas A.1–A.3, with
    /// the real-line curvature K_W).
    fn rigorous_bound(k: k, sigma: f64, grad_w_j: f64, delta_w: f64) -> f64 = rigorous::bound;
    /// The bound of Theorem 4.3 as printed, at the change Δw.
    fn rigorous_thesis_bound(k: k, sigma: f64, grad_w_j: f64, delta_w: f64) -> f64 = rigorous::thesis_bound;
    /// The gap between the printed bound of Theorem 4.3 and the rigorous bound at Δw.
    fn rigorous_gap(k: k, sigma: f64, delta_w: f64) -> f64 = rigorous::gap;
    /// The changes Δw that the rigorous bound guarantees for a required improvement C.
    fn rigorous_safe_delta_w(k: k, sigma: f64, grad_w_j: f64, required: f64) -> PyStepOutcome = rigorous::safe_delta_w;
    /// The rigorous safe steps β along ∇_w J for a required improvement C.
    fn rigorous_safe_step_along_j(k: k, sigma: f64, grad_w_j: f64, required: f64) -> PyStepOutcome
        = rigorous::safe_step_along_j;
    /// The rigorous safe steps β along ∇_w L for a required improvement C.
    fn rigorous_safe_step_along_l(k: k, sigma: f64, grad_w_j: f64, grad_w_l: f64, required: f64) -> PyStepOutcome
        = rigorous::safe_step_along_l;

    /// The exploring w-update (the bound of Theorem 4.3 on the confidence event of ∇_w J,
    /// Assumption 4.6): the safe steps β along ∇̂_w L (Δw = β∇̂_w L) of
    /// B(Δw) = Δw∇̂_w J − |Δw|ε_J − d(σ)Δw² ≥ C; with ε_J = 0 the interval of eq. 4.19.
    fn exploring_w_exploring_step(k: k, sigma: f64, grad_w_j_hat: f64, eps_j: f64, grad_w_l_hat: f64, required: f64)
        -> PyStepOutcome = exploring::w_exploring_step;

    /// c(σ) of Theorem 4.2 enclosed in an interval (ψ, √(2π) and every operation rounded
    /// outward).
    fn certified_c(k: k, sigma: f64) -> PyInterval = certified::c;
    /// d(σ) of Theorem 4.3 (eq. 4.15) enclosed in an interval.
    fn certified_d(k: k, sigma: f64) -> PyInterval = certified::d;
    /// The certified safe v-step of Theorem 4.2 (eq. 4.10): its bound, evaluated in interval
    /// arithmetic, is at least C.
    fn certified_v_safe_step(k: k, sigma: f64, grad_v: vec, required: f64) -> PyCertified = certified::v_safe_step;
    /// The certified safe step along ∇_w J of Theorem 4.3 (eq. 4.17).
    fn certified_w_safe_step_along_j(k: k, sigma: f64, grad_w_j: f64, required: f64) -> PyCertified
        = certified::w_safe_step_along_j;
    /// The certified safe step along ∇_w L of Theorem 4.5 (eq. 4.19).
    fn certified_w_safe_step_along_l(k: k, sigma: f64, grad_w_j: f64, grad_w_l: f64, required: f64) -> PyCertified
        = certified::w_safe_step_along_l;
    /// The certified high-probability v-step of Theorem 4.7 (eq. 4.26).
    #[pyo3(signature = (k, sigma, grad_v_hat, eps, required, form = "sign_aware"))]
    fn certified_hp_v_safe_step(k: k, sigma: f64, grad_v_hat: vec, eps: f64, required: f64, form: form)
        -> PyCertified = certified::hp_v_safe_step;
    /// The certified high-probability step along ∇̂_w J of Theorem 4.8 (eq. 4.29).
    #[pyo3(signature = (k, sigma, grad_w_j_hat, eps, required, form = "sign_aware"))]
    fn certified_hp_w_safe_step_along_j(k: k, sigma: f64, grad_w_j_hat: f64, eps: f64, required: f64, form: form)
        -> PyCertified = certified::hp_w_safe_step_along_j;
    /// The certified high-probability step along ∇̂_w L of Theorem 4.9 (eq. 4.30); the
    /// estimates are `(value, width)` pairs.
    #[pyo3(signature = (k, sigma, grad_w_j_hat, grad_w_l_hat, required, form = "sign_aware"))]
    fn certified_hp_w_safe_step_along_l(k: k, sigma: f64, grad_w_j_hat: pair, grad_w_l_hat: pair, required: f64, form: form)
        -> PyCertified = certified::hp_w_safe_step_along_l;
    /// The certified rigorous step along ∇_w J (`rigorous_safe_step_along_j`).
    fn certified_rigorous_safe_step_along_j(k: k, sigma: f64, grad_w_j: f64, required: f64) -> PyCertified
        = certified::rigorous_safe_step_along_j;
    /// The certified rigorous step along ∇_w L (`rigorous_safe_step_along_l`).
    fn certified_rigorous_safe_step_along_l(k: k, sigma: f64, grad_w_j: f64, grad_w_l: f64, required: f64) -> PyCertified
        = certified::rigorous_safe_step_along_l;
    /// The certified exploring w-step along ∇̂_w L (`exploring_w_exploring_step`).
    fn certified_exploring_safe_step(k: k, sigma: f64, grad_w_j_hat: f64, eps_j: f64, grad_w_l_hat: f64, required: f64)
        -> PyCertified = certified::exploring_safe_step;
    /// The adaptive step of Corollary 3.11 (`pirotta_optimal_step`) with the Theorem 3.10
    /// bound at that step enclosed in interval arithmetic: `bound.lo` is a guarantee in exact
    /// arithmetic (there is no requirement; the guarantee is what the step attains).
    fn certified_adaptive_step(k: k, sigma: f64, grad: vec) -> PyCertified = certified::adaptive_step;

    /// The split (C_v, C_w) = ((1 − ν)C, νC) of a required improvement (eqs. 4.13, 4.14).
    fn budget_split_requirement(required: f64, nu: f64) -> (f64, f64) = budget::split_requirement;
}

/// ψ = max_{χ ≥ 0} |(χ² − 4χ + 1) e^{−χ/2}| / √(2π) ≈ 0.5235570203, the constant of Lemma A.1
/// bounding the second derivative of a Gaussian density in its log standard deviation.
#[pyfunction]
fn constants_psi() -> f64 {
    constants::psi()
}

/// K_W = ∫ |z⁴ − 4z² + 1| φ(z) dz ≈ 1.832126: the integral over the real line of
/// |∂²π/∂w²| for a Gaussian density π with σ = e^w (scale-free), the curvature of the
/// rigorous w-bound for large σ (Lemma A.1 on ℝ instead of the action box).
#[pyfunction]
fn rigorous_k_w() -> f64 {
    rigorous::k_w()
}

/// K_MU = ∫ |z² − 1| φ(z) dz = 4φ(1) ≈ 0.967883: σ² times the integral over the real line
/// of |∂²π/∂μ²| for a Gaussian density π (scale-free), the term of c_ℝ(σ).
#[pyfunction]
fn rigorous_k_mu() -> f64 {
    rigorous::k_mu()
}

/// An enclosure of √(2π): the two neighbouring floats around it.
#[pyfunction]
fn certified_sqrt_2pi() -> PyInterval {
    PyInterval(certified::sqrt_2pi())
}

/// An enclosure of ψ of Lemma A.1.
#[pyfunction]
fn certified_psi() -> PyInterval {
    PyInterval(certified::psi())
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

/// A closed interval [lo, hi] of reals that encloses an exact value: the arithmetic of the
/// certified steps, every operation rounded outward (`+ − × ÷` with intervals or floats,
/// `sqr`, `sqrt`, `exp`, `exp_m1`, `scale`, `max`, `hull`).
#[pyclass(frozen, name = "Interval", module = "sepg")]
#[derive(Debug, Clone, Copy)]
pub struct PyInterval(pub(crate) Interval);

impl From<Interval> for PyInterval {
    fn from(i: Interval) -> Self {
        PyInterval(i)
    }
}

/// A float that is not NaN, as an exact degenerate interval.
fn exact(x: f64, name: &str) -> PyResult<Interval> {
    if x.is_nan() {
        Err(invalid(format!("{name} must not be NaN")))
    } else {
        Ok(Interval::point(x))
    }
}

/// The other operand of an interval operation: an `Interval` or a real number.
fn operand(other: &Bound<'_, PyAny>) -> PyResult<Interval> {
    if let Ok(i) = other.cast::<PyInterval>() {
        return Ok(i.get().0);
    }
    let x: f64 = other
        .extract()
        .map_err(|_| invalid("the operand must be an Interval or a real number"))?;
    exact(x, "the operand")
}

#[pymethods]
impl PyInterval {
    /// [lo, hi]; raises `InvalidInputError` when lo > hi or either is NaN.
    #[new]
    fn new(lo: f64, hi: f64) -> PyResult<Self> {
        Interval::new(lo, hi)
            .map(PyInterval)
            .ok_or_else(|| invalid(format!("[{lo}, {hi}] is not an interval (lo > hi or NaN)")))
    }

    /// The degenerate interval [x, x] (exact).
    #[staticmethod]
    fn point(x: f64) -> PyResult<Self> {
        exact(x, "x").map(PyInterval)
    }

    /// The whole real line (−∞, +∞), the enclosure of an unknown value.
    #[classattr]
    #[allow(non_snake_case)]
    fn ENTIRE() -> Self {
        PyInterval(Interval::ENTIRE)
    }

    /// The lower end point.
    #[getter]
    fn lo(&self) -> f64 {
        self.0.lo()
    }

    /// The upper end point.
    #[getter]
    fn hi(&self) -> f64 {
        self.0.hi()
    }

    /// hi − lo, rounded up.
    #[getter]
    fn width(&self) -> f64 {
        self.0.width()
    }

    /// Whether lo ≤ x ≤ hi.
    fn contains(&self, x: f64) -> bool {
        self.0.contains(x)
    }

    /// Whether both end points are finite.
    fn is_finite(&self) -> bool {
        self.0.is_finite()
    }

    /// The enclosure of x² (non-negative).
    fn sqr(&self) -> Self {
        PyInterval(self.0.sqr())
    }

    /// The enclosure of √x over the non-negative part of x.
    fn sqrt(&self) -> Self {
        PyInterval(self.0.sqrt())
    }

    /// The enclosure of e^x.
    fn exp(&self) -> Self {
        PyInterval(self.0.exp())
    }

    /// The enclosure of e^x − 1.
    fn exp_m1(&self) -> Self {
        PyInterval(self.0.exp_m1())
    }

    /// The enclosure of self · x for an exact float x.
    fn scale(&self, x: f64) -> PyResult<Self> {
        exact(x, "x")?;
        Ok(PyInterval(self.0.scale(x)))
    }

    /// The enclosure of |x| (exact end points).
    fn abs(&self) -> Self {
        PyInterval(self.0.abs())
    }

    fn __abs__(&self) -> Self {
        self.abs()
    }

    /// The enclosure of max(self, other).
    fn max(&self, other: &Bound<'_, PyAny>) -> PyResult<Self> {
        Ok(PyInterval(self.0.max(operand(other)?)))
    }

    /// The convex hull of self and other.
    fn hull(&self, other: &Bound<'_, PyAny>) -> PyResult<Self> {
        Ok(PyInterval(self.0.hull(operand(other)?)))
    }

    fn __add__(&self, other: &Bound<'_, PyAny>) -> PyResult<Self> {
        Ok(PyInterval(self.0 + operand(other)?))
    }

    fn __radd__(&self, other: &Bound<'_, PyAny>) -> PyResult<Self> {
        Ok(PyInterval(operand(other)? + self.0))
    }

    fn __sub__(&self, other: &Bound<'_, PyAny>) -> PyResult<Self> {
        Ok(PyInterval(self.0 - operand(other)?))
    }

    fn __rsub__(&self, other: &Bound<'_, PyAny>) -> PyResult<Self> {
        Ok(PyInterval(operand(other)? - self.0))
    }

    fn __mul__(&self, other: &Bound<'_, PyAny>) -> PyResult<Self> {
        Ok(PyInterval(self.0 * operand(other)?))
    }

    fn __rmul__(&self, other: &Bound<'_, PyAny>) -> PyResult<Self> {
        Ok(PyInterval(operand(other)? * self.0))
    }

    /// Division; a divisor that contains 0 gives the whole real line.
    fn __truediv__(&self, other: &Bound<'_, PyAny>) -> PyResult<Self> {
        Ok(PyInterval(self.0 / operand(other)?))
    }

    fn __rtruediv__(&self, other: &Bound<'_, PyAny>) -> PyResult<Self> {
        Ok(PyInterval(operand(other)? / self.0))
    }

    fn __neg__(&self) -> Self {
        PyInterval(-self.0)
    }

    fn __eq__(&self, other: &Self) -> bool {
        self.0 == other.0
    }

    fn __repr__(&self) -> String {
        format!("Interval({:?}, {:?})", self.0.lo(), self.0.hi())
    }
}

/// The outcome of a certified safe-step computation (docs/THEOREMS.md, "Certified steps"):
/// `kind` is `"certified"` (the bound at `chosen_step`, evaluated in interval arithmetic, is at
/// least C), `"infeasible"` (C > C_max; the vertex), `"uncertifiable"` (C ≤ C_max as
/// computed, but no float step between the computed largest step and the vertex has an
/// enclosure at least C: C is within rounding of C_max; the vertex), `"zero_gradient"` or
/// `"below_noise"` (no update).
#[pyclass(frozen, name = "Certified", module = "sepg")]
#[derive(Debug, Clone, Copy)]
pub struct PyCertified(pub(crate) Certified);

impl From<Certified> for PyCertified {
    fn from(c: Certified) -> Self {
        PyCertified(c)
    }
}

#[pymethods]
impl PyCertified {
    /// `"certified"`, `"infeasible"`, `"uncertifiable"`, `"zero_gradient"` or `"below_noise"`:
    /// a certified step has the label of `sepg bounds --certified` and of `bounds_report`.
    #[getter]
    fn kind(&self) -> &'static str {
        match self.0 {
            Certified::Step(_) => StepVerdict::Certified.label(),
            Certified::Infeasible { .. } => "infeasible",
            Certified::Uncertifiable { .. } => "uncertifiable",
            Certified::ZeroGradient { .. } => "zero_gradient",
            _ => "below_noise",
        }
    }

    /// The step to take: the certified step, or the vertex when the requirement is
    /// infeasible or uncertifiable; `None` when no update should be made.
    #[getter]
    fn chosen_step(&self) -> Option<f64> {
        self.0.chosen_step()
    }

    /// The enclosure of the bound at `chosen_step` (`None` without a step).
    #[getter]
    fn bound(&self) -> Option<PyInterval> {
        self.0.bound().map(PyInterval)
    }

    /// Whether a step was certified to meet the requirement.
    #[getter]
    fn is_certified(&self) -> bool {
        self.0.is_certified()
    }

    /// How many ulps the certified step was moved from the computed largest step toward
    /// the vertex (`kind == "certified"` only).
    #[getter]
    fn ulps_moved(&self) -> Option<u64> {
        match self.0 {
            Certified::Step(s) => Some(s.ulps_moved),
            _ => None,
        }
    }

    /// Whether the certificate came from the a-priori rounding-error bound of the float
    /// evaluation rather than from interval arithmetic (`kind == "certified"` only).
    #[getter]
    fn by_error_bound(&self) -> Option<bool> {
        match self.0 {
            Certified::Step(s) => Some(s.by_error_bound),
            _ => None,
        }
    }

    /// The safe interval as computed in floats, as a feasible `StepOutcome`
    /// (`kind == "certified"` only).
    #[getter]
    fn interval(&self) -> Option<PyStepOutcome> {
        match self.0 {
            Certified::Step(s) => Some(PyStepOutcome(StepOutcome::Feasible(s.interval))),
            _ => None,
        }
    }

    /// Whether C ≤ 0 (`kind == "zero_gradient"` only: the zero step meets it).
    #[getter]
    fn requirement_met(&self) -> Option<bool> {
        match self.0 {
            Certified::ZeroGradient { requirement_met } => Some(requirement_met),
            _ => None,
        }
    }

    fn __repr__(&self) -> String {
        let step = self
            .chosen_step()
            .map_or("None".into(), |x| format!("{x:?}"));
        let bound = self.0.bound().map_or("None".into(), |b| {
            format!("Interval({:?}, {:?})", b.lo(), b.hi())
        });
        format!(
            "Certified(kind='{}', chosen_step={step}, bound={bound})",
            self.kind()
        )
    }
}

/// The bound forms that can be certified.
#[derive(Debug, Clone, Copy)]
enum Form {
    Quadratic(Quadratic),
    Hp(HpEnclosure),
    Rigorous(RigorousEnclosure),
    Exploring(ExploringEnclosure),
}

impl Form {
    fn bound(&self) -> &dyn EnclosedBound {
        match self {
            Form::Quadratic(b) => b,
            Form::Hp(b) => b,
            Form::Rigorous(b) => b,
            Form::Exploring(b) => b,
        }
    }
}

/// A safety bound B(x) of a step x whose value is enclosed in interval arithmetic (the
/// inputs taken as exact reals): the parabolas of Theorems 4.2, 4.3 and 4.5
/// (`quadratic_*`), the high-probability bounds of Theorems 4.7–4.9 (`hp_*`), the rigorous
/// w-bound (`rigorous`) and the exploring w-bound (`exploring`). `certify` turns the float
/// outcome of the same bound into a certified one.
#[pyclass(frozen, name = "Enclosure", module = "sepg")]
#[derive(Debug, Clone, Copy)]
pub struct PyEnclosure(Form);

/// `Some(Enclosure)` of a high-probability form, `None` below noise.
fn hp_enclosure(e: Result<Option<HpEnclosure>, BoundsError>) -> PyResult<Option<PyEnclosure>> {
    Ok(e.map_err(invalid)?.map(|e| PyEnclosure(Form::Hp(e))))
}

#[pymethods]
impl PyEnclosure {
    /// Theorem 4.2: B(α) = α‖∇_vJ‖∞² − α²c(σ)‖∇_vJ‖∞².
    #[staticmethod]
    fn quadratic_v_update(k: K<'_>, sigma: f64, grad_v: &Bound<'_, PyAny>) -> PyResult<Self> {
        let q = Quadratic::v_update(&k.0, sigma, &vector(grad_v, "grad_v")?).map_err(invalid)?;
        Ok(PyEnclosure(Form::Quadratic(q)))
    }

    /// Theorem 4.3: B(β) = β(∇_wJ)² − β²d(σ)(∇_wJ)².
    #[staticmethod]
    fn quadratic_w_along_j(k: K<'_>, sigma: f64, grad_w_j: f64) -> PyResult<Self> {
        let q = Quadratic::w_along_j(&k.0, sigma, grad_w_j).map_err(invalid)?;
        Ok(PyEnclosure(Form::Quadratic(q)))
    }

    /// Theorem 4.5: B(β) = β∇_wL∇_wJ − β²d(σ)(∇_wL)².
    #[staticmethod]
    fn quadratic_w_along_l(k: K<'_>, sigma: f64, grad_w_j: f64, grad_w_l: f64) -> PyResult<Self> {
        let q = Quadratic::w_along_l(&k.0, sigma, grad_w_j, grad_w_l).map_err(invalid)?;
        Ok(PyEnclosure(Form::Quadratic(q)))
    }

    /// Theorem 4.7 in form `form`; `None` when ‖∇̂_vJ‖∞ ≤ ε.
    #[staticmethod]
    #[pyo3(signature = (k, sigma, grad_v_hat, eps, form = "sign_aware"))]
    fn hp_v_update(
        k: K<'_>,
        sigma: f64,
        grad_v_hat: &Bound<'_, PyAny>,
        eps: f64,
        form: &str,
    ) -> PyResult<Option<Self>> {
        let g = vector(grad_v_hat, "grad_v_hat")?;
        hp_enclosure(HpEnclosure::v_update(
            &k.0,
            sigma,
            &g,
            eps,
            self::form(form)?,
        ))
    }

    /// Theorem 4.8 in form `form`; `None` when |∇̂_wJ| ≤ ε.
    #[staticmethod]
    #[pyo3(signature = (k, sigma, grad_w_j_hat, eps, form = "sign_aware"))]
    fn hp_w_along_j(
        k: K<'_>,
        sigma: f64,
        grad_w_j_hat: f64,
        eps: f64,
        form: &str,
    ) -> PyResult<Option<Self>> {
        hp_enclosure(HpEnclosure::w_along_j(
            &k.0,
            sigma,
            grad_w_j_hat,
            eps,
            self::form(form)?,
        ))
    }

    /// Theorem 4.9 in form `form`, the estimates as `(value, width)` pairs; `None` when
    /// either is within its width.
    #[staticmethod]
    #[pyo3(signature = (k, sigma, grad_w_j_hat, grad_w_l_hat, form = "sign_aware"))]
    fn hp_w_along_l(
        k: K<'_>,
        sigma: f64,
        grad_w_j_hat: (f64, f64),
        grad_w_l_hat: (f64, f64),
        form: &str,
    ) -> PyResult<Option<Self>> {
        let form = self::form(form)?;
        hp_enclosure(HpEnclosure::w_along_l(
            &k.0,
            sigma,
            grad_w_j_hat,
            grad_w_l_hat,
            form,
        ))
    }

    /// The rigorous w-bound of a step β along `direction` (Δw = β·direction: ∇_wJ or ∇_wL).
    #[staticmethod]
    fn rigorous(k: K<'_>, sigma: f64, grad_w_j: f64, direction: f64) -> PyResult<Self> {
        let r = RigorousEnclosure::new(&k.0, sigma, grad_w_j, direction).map_err(invalid)?;
        Ok(PyEnclosure(Form::Rigorous(r)))
    }

    /// The exploring w-bound B(β) = Δw∇̂_wJ − |Δw|ε_J − d(σ)Δw², Δw = β∇̂_wL.
    #[staticmethod]
    fn exploring(
        k: K<'_>,
        sigma: f64,
        grad_w_j_hat: f64,
        eps_j: f64,
        grad_w_l_hat: f64,
    ) -> PyResult<Self> {
        let e = ExploringEnclosure::new(&k.0, sigma, grad_w_j_hat, eps_j, grad_w_l_hat)
            .map_err(invalid)?;
        Ok(PyEnclosure(Form::Exploring(e)))
    }

    /// An interval that contains the exact B(x), x a finite step.
    fn enclose(&self, x: f64) -> PyResult<PyInterval> {
        if !x.is_finite() {
            return Err(invalid(format!("x must be finite, got {x}")));
        }
        Ok(PyInterval(self.0.bound().enclose(x)))
    }

    /// Certifies the float `outcome` of this bound's safe-step computation for the
    /// requirement C = `required`: the largest step is kept when its enclosure is at least
    /// C, else moved toward the vertex by the fewest ulps that pass.
    fn certify(&self, outcome: &PyStepOutcome, required: f64) -> PyResult<PyCertified> {
        if !required.is_finite() {
            return Err(invalid(format!("required must be finite, got {required}")));
        }
        Ok(PyCertified(certified::certify(
            self.0.bound(),
            outcome.0,
            required,
        )))
    }

    /// The first float from `start` toward `toward` (both included) whose enclosure is at
    /// least `required`, as `(step, bound, ulps_moved)`, or `(None, bound at toward, None)`
    /// when none passes.
    fn certify_toward(
        &self,
        start: f64,
        toward: f64,
        required: f64,
    ) -> PyResult<(Option<f64>, PyInterval, Option<u64>)> {
        for (name, x) in [("start", start), ("toward", toward), ("required", required)] {
            if !x.is_finite() {
                return Err(invalid(format!("{name} must be finite, got {x}")));
            }
        }
        Ok(
            match certified::certify_toward(self.0.bound(), start, toward, required) {
                Ok((step, bound, ulps)) => (Some(step), PyInterval(bound), Some(ulps)),
                Err(bound) => (None, PyInterval(bound), None),
            },
        )
    }

    fn __repr__(&self) -> String {
        format!("Enclosure({:?})", self.0)
    }
}

/// The concave parabola B(x) = a·x − b·x² (b ≥ 0) of Theorems 4.2, 4.3 and 4.5 with its
/// coefficients a (`linear`) and b (`quadratic`) enclosed in intervals, and the enclosures
/// of the quantities of the safe steps: C_max = a²/(4b), the vertex a/(2b), λ = √(1 − C/C_max)
/// (eqs. (4.10), (4.17), (4.19)) and the end points of {x : B(x) ≥ C}.
#[pyclass(frozen, name = "Quadratic", module = "sepg")]
#[derive(Debug, Clone, Copy)]
pub struct PyQuadratic(Quadratic);

#[pymethods]
impl PyQuadratic {
    /// The parabola with coefficients a = `linear` and b = `quadratic` (intervals, or floats
    /// taken as exact); raises `InvalidInputError` when b can be negative (`quadratic.lo < 0`).
    #[new]
    fn new(linear: &Bound<'_, PyAny>, quadratic: &Bound<'_, PyAny>) -> PyResult<Self> {
        let (linear, quadratic) = (operand(linear)?, operand(quadratic)?);
        if quadratic.lo() < 0.0 {
            return Err(invalid(format!(
                "the quadratic coefficient b = [{}, {}] must be non-negative",
                quadratic.lo(),
                quadratic.hi()
            )));
        }
        Ok(PyQuadratic(Quadratic { linear, quadratic }))
    }

    /// Theorem 4.2: a = ‖∇_vJ‖∞², b = c(σ)‖∇_vJ‖∞².
    #[staticmethod]
    fn v_update(k: K<'_>, sigma: f64, grad_v: &Bound<'_, PyAny>) -> PyResult<Self> {
        let g = vector(grad_v, "grad_v")?;
        Quadratic::v_update(&k.0, sigma, &g)
            .map(PyQuadratic)
            .map_err(invalid)
    }

    /// Theorem 4.3: a = (∇_wJ)², b = d(σ)(∇_wJ)².
    #[staticmethod]
    fn w_along_j(k: K<'_>, sigma: f64, grad_w_j: f64) -> PyResult<Self> {
        Quadratic::w_along_j(&k.0, sigma, grad_w_j)
            .map(PyQuadratic)
            .map_err(invalid)
    }

    /// Theorem 4.5: a = ∇_wL ∇_wJ, b = d(σ)(∇_wL)².
    #[staticmethod]
    fn w_along_l(k: K<'_>, sigma: f64, grad_w_j: f64, grad_w_l: f64) -> PyResult<Self> {
        Quadratic::w_along_l(&k.0, sigma, grad_w_j, grad_w_l)
            .map(PyQuadratic)
            .map_err(invalid)
    }

    /// The enclosure of the linear coefficient a.
    #[getter]
    fn linear(&self) -> PyInterval {
        PyInterval(self.0.linear)
    }

    /// The enclosure of the quadratic coefficient b ≥ 0.
    #[getter]
    fn quadratic(&self) -> PyInterval {
        PyInterval(self.0.quadratic)
    }

    /// An enclosure of C_max = a²/(4b), the value at the vertex.
    fn c_max(&self) -> PyInterval {
        PyInterval(self.0.c_max())
    }

    /// An enclosure of the vertex a/(2b).
    fn vertex(&self) -> PyInterval {
        PyInterval(self.0.vertex())
    }

    /// An enclosure of λ = √(1 − C/C_max) for C = `required` ≤ C_max (eqs. (4.10), (4.17),
    /// (4.19)); `lambda` is a keyword of Python, hence the underscore.
    #[pyo3(name = "lambda_")]
    fn lambda(&self, required: f64) -> PyResult<PyInterval> {
        Ok(PyInterval(self.0.lambda(finite_required(required)?)))
    }

    /// Enclosures `(lo, hi)` of the end points of {x : a x − b x² ≥ C} for C = `required`, or
    /// `None` when the enclosure cannot exclude C > C_max.
    fn end_points(&self, required: f64) -> PyResult<Option<(PyInterval, PyInterval)>> {
        Ok(self
            .0
            .end_points(finite_required(required)?)
            .map(|(lo, hi)| (PyInterval(lo), PyInterval(hi))))
    }

    /// An interval that contains the exact B(x), x a finite step.
    fn enclose(&self, x: f64) -> PyResult<PyInterval> {
        if !x.is_finite() {
            return Err(invalid(format!("x must be finite, got {x}")));
        }
        Ok(PyInterval(self.0.enclose(x)))
    }

    /// The same bound as an `Enclosure`, to certify a step with.
    fn enclosure(&self) -> PyEnclosure {
        PyEnclosure(Form::Quadratic(self.0))
    }

    fn __eq__(&self, other: &Self) -> bool {
        self.0 == other.0
    }

    fn __repr__(&self) -> String {
        format!(
            "Quadratic(linear=Interval({:?}, {:?}), quadratic=Interval({:?}, {:?}))",
            self.0.linear.lo(),
            self.0.linear.hi(),
            self.0.quadratic.lo(),
            self.0.quadratic.hi()
        )
    }
}

/// `required` when finite, else `InvalidInputError`.
fn finite_required(required: f64) -> PyResult<f64> {
    if required.is_finite() {
        Ok(required)
    } else {
        Err(invalid(format!("required must be finite, got {required}")))
    }
}

/// The lower bound of the exploring w-update (Theorem 4.3 on the confidence event of ∇_w J,
/// Assumption 4.6): B(Δw) = Δw∇̂_wJ − |Δw|ε_J − d(σ)Δw², uniform in Δw.
#[pyclass(frozen, name = "ExploringBound", module = "sepg")]
#[derive(Debug, Clone, Copy)]
pub struct PyExploringBound(ExploringBound);

#[pymethods]
impl PyExploringBound {
    /// The bound for the task `k` at standard deviation `sigma`, the estimate ∇̂_wJ and its
    /// half-width ε_J ≥ 0.
    #[new]
    fn new(k: K<'_>, sigma: f64, grad_w_j_hat: f64, eps_j: f64) -> PyResult<Self> {
        ExploringBound::new(&k.0, sigma, grad_w_j_hat, eps_j)
            .map(PyExploringBound)
            .map_err(invalid)
    }

    /// ∇̂_wJ.
    #[getter]
    fn grad_w_j_hat(&self) -> f64 {
        self.0.grad_w_j_hat
    }

    /// ε_J.
    #[getter]
    fn eps_j(&self) -> f64 {
        self.0.eps_j
    }

    /// d(σ) of Theorem 4.3.
    #[getter]
    fn d(&self) -> f64 {
        self.0.d
    }

    /// B(Δw), the guaranteed change of J for the change Δw of w.
    fn value(&self, delta_w: f64) -> PyResult<f64> {
        self.0.value(delta_w).map_err(invalid)
    }

    /// `(Δw*, C_max)`: the change of maximal guaranteed improvement and that improvement.
    fn vertex(&self) -> PyResult<(f64, f64)> {
        self.0.vertex().map_err(invalid)
    }

    /// The changes Δw with B(Δw) ≥ C (`"feasible"`), or `"infeasible"` with Δw*.
    fn safe_interval(&self, required: f64) -> PyResult<PyStepOutcome> {
        outcome(self.0.safe_interval(required))
    }

    fn __repr__(&self) -> String {
        format!("{:?}", self.0)
    }
}

/// A name of the command line's vocabulary (`constants`, `rewards`), raising
/// `InvalidInputError` naming the argument and its choices otherwise.
fn name_arg<T: serde::de::DeserializeOwned>(value: &str, arg: &str, choices: &str) -> PyResult<T> {
    serde_json::from_value(serde_json::Value::String(value.to_owned()))
        .map_err(|_| invalid(format!("{arg} = {value:?} must be {choices}")))
}

/// The report of `sepg bounds` as a dict, the object `sepg bounds --json` prints, built by the
/// same library function: every closed-form quantity that the task constants (γ, R, M_φ,
/// |A|), σ and the gradients determine (Theorems 3.11, 3.13, 3.14, 4.2, 4.3, 4.5, Lemma A.1,
/// Corollary 4.4). The keywords are the command's flags: `grad_v` an array-like, `horizon` a
/// positive integer or inf, `constants` "thesis" or "tight", `rewards` "two-sided" or
/// "non-positive"; with `certified`, the key `certified` holds the outward-rounded enclosures
/// and the certified largest steps, each with its `outcome` ("certified", "uncertifiable",
/// "infeasible" or "no-step"). Quantities that the inputs do not determine are absent.
#[pyfunction]
#[pyo3(signature = (gamma, r_max, m_phi, action_volume, sigma, *, dim_v = None, grad_v = None,
    grad_w = None, grad_w_l = None, required = 0.0, nu = None, delta = None, eps = None,
    horizon = None, constants = "thesis", rewards = None, certified = false))]
#[allow(clippy::too_many_arguments)]
fn bounds_report<'py>(
    py: Python<'py>,
    gamma: f64,
    r_max: f64,
    m_phi: f64,
    action_volume: f64,
    sigma: f64,
    dim_v: Option<usize>,
    grad_v: Option<&Bound<'py, PyAny>>,
    grad_w: Option<f64>,
    grad_w_l: Option<f64>,
    required: f64,
    nu: Option<f64>,
    delta: Option<f64>,
    eps: Option<f64>,
    horizon: Option<&Bound<'py, PyAny>>,
    constants: &str,
    rewards: Option<&str>,
    certified: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let query = BoundsQuery {
        dim_v,
        grad_v: grad_v.map(|g| vector(g, "grad_v")).transpose()?,
        grad_w,
        grad_w_l,
        required,
        nu,
        delta,
        eps,
        horizon: horizon.map(horizon_arg).transpose()?,
        constants: name_arg::<ConstantsName>(constants, "constants", "\"thesis\" or \"tight\"")?,
        rewards: rewards
            .map(|r| name_arg::<RewardsName>(r, "rewards", "\"two-sided\" or \"non-positive\""))
            .transpose()?,
        ..BoundsQuery::new(gamma, r_max, m_phi, action_volume, sigma)
    };
    serialize_to_py(py, &report(&query, certified).map_err(invalid)?)
}

/// Adds the functions and classes of this module to `m`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyStepOutcome>()?;
    m.add_class::<PyHighProbabilityBound>()?;
    m.add_class::<PyBudget>()?;
    m.add_class::<PyInterval>()?;
    m.add_class::<PyCertified>()?;
    m.add_class::<PyEnclosure>()?;
    m.add_class::<PyQuadratic>()?;
    m.add_class::<PyExploringBound>()?;
    m.add_function(wrap_pyfunction!(constants_psi, m)?)?;
    m.add_function(wrap_pyfunction!(rigorous_k_w, m)?)?;
    m.add_function(wrap_pyfunction!(rigorous_k_mu, m)?)?;
    m.add_function(wrap_pyfunction!(certified_sqrt_2pi, m)?)?;
    m.add_function(wrap_pyfunction!(certified_psi, m)?)?;
    m.add_function(wrap_pyfunction!(bounds_report, m)?)?;
    add_functions(m)
}
