//! SEPG and the comparison algorithms on trajectories collected in Python: a [`Trainer`]
//! owns a `sepg_algo` solver whose every batch comes from a Python callable (the collector),
//! so the estimation, the safe steps and the budget bookkeeping are those of the Rust
//! algorithms, bit for bit. The gymnasium driver of `sepg.gym` is such a collector.
use std::sync::{Arc, Mutex};

use numpy::PyArray2;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyModule, PyTuple};
use sepg_algo::core::check::RawSteps;
use sepg_algo::core::config::Algorithm;
use sepg_algo::core::defaults::{
    DEFAULT_ADAM_BETA1, DEFAULT_ADAM_BETA2, DEFAULT_ADAM_EPS, DEFAULT_ALGO, DEFAULT_BUDGET0,
    DEFAULT_DELTA, DEFAULT_N_TRAJECTORIES, DEFAULT_NU, DEFAULT_QUANTILE_FACTOR,
    DEFAULT_REQUIREMENT, DEFAULT_SEED, DEFAULT_SIGMA0, DEFAULT_V0, RUN_CONSTANTS,
};
use sepg_algo::core::error::RunError;
use sepg_algo::core::executor::{Collect, Executor};
use sepg_algo::core::names::{AlgoName, RequirementName};
use sepg_algo::core::options::{Accounting, Confidence, Schedule, SepgOptions, VDirection};
use sepg_algo::core::seed::Block;
use sepg_algo::core::state::State;
use sepg_algo::solver::sampled::{BatchCollector, BatchRequest};
use sepg_algo::solver::{CollectedConfig, PolicySolver};
use sepg_estimators::GradientSpec;
use sepg_mdp::rng::Stream;
use sepg_mdp::{Batch, GaussianPolicy};
use sepg_runs::spec::{AccountingName, OnContradictionName, VDirectionName};

use crate::record;
use crate::safe::lengths_of;
use crate::{PyTaskConstants, failed, floats, invalid, natural, real};

/// The algorithm named as on the command line (a name of [`AlgoName`]): `sepg-mi`,
/// `sepg-lb1`, `sepg-lb2`, `sepg-lv`, `sepg-zv`, `sepg-sim`, `sepg-naive-w` (with
/// `requirement`, a name of [`RequirementName`]), `gpomdp-const` (with `alpha`, `beta`),
/// `gpomdp-adam` (with `lr`, `lr_w`) or `adastep`; ν is the split of LB-I and SIM.
pub(crate) fn algorithm(
    name: &str,
    nu: f64,
    requirement: &str,
    alpha: Option<f64>,
    beta: Option<f64>,
    lr: Option<f64>,
    lr_w: Option<f64>,
) -> PyResult<Algorithm> {
    let algo: AlgoName = name.parse().map_err(invalid)?;
    let need = |v: Option<f64>, what: &str| {
        v.ok_or_else(|| invalid(format!("algorithm {name} needs {what}")))
    };
    if let Some(r) = algo.sepg_requirement() {
        return Ok(Algorithm::Sepg(r.requirement(Some(nu))));
    }
    Ok(match algo {
        AlgoName::SepgNaiveW => {
            let r: RequirementName = requirement.parse().map_err(invalid)?;
            Algorithm::SepgNaiveW(r.requirement(Some(nu)))
        }
        AlgoName::GpomdpConst => {
            let a = need(alpha, "alpha")?;
            Algorithm::GpomdpConst {
                alpha: a,
                beta: beta.unwrap_or(a),
            }
        }
        AlgoName::GpomdpAdam => {
            let l = need(lr, "lr")?;
            Algorithm::adam(l, lr_w.unwrap_or(l))
        }
        // adastep (the SEPG variants named by their requirement returned above)
        _ => Algorithm::AdaStep,
    })
}

/// SEPG's v-direction named `name` (greedy or adam, [`VDirectionName`]; `None` for the
/// default of [`SepgOptions`]) with Adam's parameters, which are refused without adam; adam
/// needs `lr`, and its betas and ε default to [`DEFAULT_ADAM_BETA1`], [`DEFAULT_ADAM_BETA2`]
/// and [`DEFAULT_ADAM_EPS`] (their domains are checked with the configuration).
fn v_direction(
    name: Option<VDirectionName>,
    lr: Option<f64>,
    beta1: Option<f64>,
    beta2: Option<f64>,
    eps: Option<f64>,
) -> PyResult<VDirection> {
    match name {
        None | Some(VDirectionName::Greedy) => {
            if lr.is_some() || beta1.is_some() || beta2.is_some() || eps.is_some() {
                return Err(invalid(
                    "adam_lr, adam_beta1, adam_beta2 and adam_eps apply only with v_direction=\"adam\"",
                ));
            }
            Ok(match name {
                None => SepgOptions::default().v_direction,
                _ => VDirection::Greedy,
            })
        }
        Some(VDirectionName::Adam) => {
            let lr = lr.ok_or_else(|| invalid("v_direction=\"adam\" needs adam_lr"))?;
            Ok(VDirection::Adam {
                lr,
                beta1: beta1.unwrap_or(DEFAULT_ADAM_BETA1),
                beta2: beta2.unwrap_or(DEFAULT_ADAM_BETA2),
                eps: eps.unwrap_or(DEFAULT_ADAM_EPS),
            })
        }
    }
}

/// The value named `name` of the option `option`, parsed by the names of configurations and
/// of the command line (`sepg_runs::spec`), so Python accepts exactly the same names.
fn value_name<T: serde::de::DeserializeOwned>(option: &str, name: &str) -> PyResult<T> {
    use serde::de::IntoDeserializer;
    T::deserialize(name.into_deserializer())
        .map_err(|e: serde::de::value::Error| invalid(format!("{option} = {name:?}: {e}")))
}

/// What the collector is asked for: `n` trajectories of the policy
/// a ~ N(V φ(s), diag σ²) (deterministic a = V φ(s) when `w` is `None`), trajectory `i`
/// seeded with `env_seeds[i]` (for `env.reset(seed=...)`) and `policy_seeds[i]` (for the
/// action noise). `scores` says whether the actions and features are needed (else only
/// the rewards and lengths are used).
#[pyclass(frozen, name = "BatchRequest", module = "sepg")]
#[derive(Debug, Clone)]
pub struct PyBatchRequest {
    /// Iteration of the algorithm.
    #[pyo3(get)]
    iteration: u64,
    /// `"v"`, `"target"` or `"w"` (the blocks of Algorithm 4.3).
    #[pyo3(get)]
    block: &'static str,
    /// Number of trajectories.
    #[pyo3(get)]
    n: usize,
    /// Whether actions and features are needed.
    #[pyo3(get)]
    scores: bool,
    /// Per-trajectory environment seeds.
    #[pyo3(get)]
    env_seeds: Vec<u64>,
    /// Per-trajectory policy seeds.
    #[pyo3(get)]
    policy_seeds: Vec<u64>,
    v: Vec<f64>,
    w: Option<Vec<f64>>,
    actions: usize,
}

#[pymethods]
impl PyBatchRequest {
    /// The mean matrix V, shape `(actions, features)`: μ(s) = V φ(s).
    #[getter]
    fn mean<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let p = self.v.len() / self.actions;
        let rows: Vec<Vec<f64>> = self.v.chunks_exact(p).map(<[f64]>::to_vec).collect();
        PyArray2::from_vec2(py, &rows).map_err(failed)
    }

    /// The standard deviations σ = e^w, `None` for the deterministic policy.
    #[getter]
    fn sigma(&self) -> Option<Vec<f64>> {
        self.w.as_ref().map(|w| w.iter().map(|x| x.exp()).collect())
    }

    fn __repr__(&self) -> String {
        format!(
            "BatchRequest(iteration={}, block={:?}, n={}, scores={})",
            self.iteration, self.block, self.n, self.scores
        )
    }
}

/// The collector side of a [`Trainer`]: calls the Python callable and turns its arrays into
/// a [`Batch`]. A Python exception is kept to be re-raised as it is.
struct PyCollector {
    callable: Py<PyAny>,
    gamma: f64,
    features: usize,
    error: Arc<Mutex<Option<PyErr>>>,
}

impl PyCollector {
    /// The request handed to the Python collector for the batch `r`.
    fn request(&self, r: &BatchRequest<'_>) -> PyBatchRequest {
        let seeds = |stream| (0..r.n as u64).map(move |i| r.key.trajectory_seed(i, stream));
        PyBatchRequest {
            iteration: r.iteration,
            block: match r.block {
                Block::V => "v",
                Block::Target => "target",
                Block::W => "w",
                Block::Reference => "reference",
                Block::ReferenceTarget => "reference-target",
            },
            n: r.n,
            scores: r.scores,
            env_seeds: seeds(Stream::Environment).collect(),
            policy_seeds: seeds(Stream::Policy).collect(),
            v: r.v.to_vec(),
            w: r.w.map(<[f64]>::to_vec),
            actions: r.v.len() / self.features,
        }
    }

    fn collect_py(
        &self,
        py: Python<'_>,
        r: &BatchRequest<'_>,
    ) -> PyResult<(Batch, Option<RawSteps>)> {
        let out = self.callable.bind(py).call1((self.request(r),))?;
        let parts: (
            Bound<'_, PyAny>,
            Bound<'_, PyAny>,
            Bound<'_, PyAny>,
            Bound<'_, PyAny>,
        ) = out.extract().map_err(|_| {
            invalid("the collector must return (rewards, actions, features, lengths)")
        })?;
        let (rewards, actions, features, lengths) = parts;
        // features are read before the rewards they produced, so that a feature map that
        // returns NaN is reported as such and not through the rewards of the NaN actions
        let scored = match (r.w, r.scores) {
            (Some(w), true) => Some((
                w,
                floats(&features, "features", Some(3))?,
                floats(&actions, "actions", Some(3))?,
            )),
            _ => None,
        };
        let (rw, rshape) = floats(&rewards, "rewards", Some(2))?;
        if rshape[0] != r.n {
            return Err(invalid(format!(
                "rewards must have {} rows (one per trajectory), got shape {rshape:?}",
                r.n
            )));
        }
        let (n, h) = (rshape[0], rshape[1]);
        let lens = lengths_of(&lengths, n)?;
        let Some((w, (phi, fshape), (a, ashape))) = scored else {
            let batch =
                Batch::from_steps(h, self.gamma, &[], &rw, &[], &[], &lens).map_err(invalid)?;
            let raw = RawSteps {
                rewards: rw,
                ..RawSteps::default()
            };
            return Ok((batch, Some(raw)));
        };
        self.scored_batch(r, w, (rw, h, lens), (phi, fshape), (a, ashape))
    }

    /// The batch of `r` with its policy scores, from the rewards `(values, H, lengths)`, the
    /// features and the actions the collector returned (flat values and shapes).
    fn scored_batch(
        &self,
        r: &BatchRequest<'_>,
        w: &[f64],
        (rw, h, lens): (Vec<f64>, usize, Vec<usize>),
        (phi, fshape): (Vec<f64>, Vec<usize>),
        (a, ashape): (Vec<f64>, Vec<usize>),
    ) -> PyResult<(Batch, Option<RawSteps>)> {
        let n = r.n;
        let policy =
            GaussianPolicy::new(r.v.to_vec(), w.to_vec(), self.features).map_err(invalid)?;
        let (l, p) = (policy.action_dim(), self.features);
        if ashape != [n, h, l] || fshape != [n, h, p] {
            return Err(invalid(format!(
                "actions must have shape ({n}, {h}, {l}) and features ({n}, {h}, {p}); got {ashape:?} and {fshape:?}"
            )));
        }
        let (mut sv, mut sw) = (vec![0.0; n * h * l * p], vec![0.0; n * h * l]);
        for (i, &len) in lens.iter().enumerate() {
            for t in 0..len.min(h) {
                let c = i * h + t;
                let (phi, a) = (&phi[c * p..(c + 1) * p], &a[c * l..(c + 1) * l]);
                policy
                    .score_v(phi, a, &mut sv[c * l * p..(c + 1) * l * p])
                    .map_err(invalid)?;
                policy
                    .score_w(phi, a, &mut sw[c * l..(c + 1) * l])
                    .map_err(invalid)?;
            }
        }
        let sigma: Vec<f64> = w.iter().map(|x| x.exp()).collect();
        let batch =
            Batch::from_steps(h, self.gamma, &sigma, &rw, &sv, &sw, &lens).map_err(invalid)?;
        let raw = RawSteps {
            rewards: rw,
            features: phi,
            p,
        };
        Ok((batch, Some(raw)))
    }
}

impl BatchCollector for PyCollector {
    fn collect(&mut self, request: &BatchRequest<'_>) -> Result<Batch, RunError> {
        self.collect_raw(request).map(|(batch, _)| batch)
    }

    fn collect_raw(
        &mut self,
        request: &BatchRequest<'_>,
    ) -> Result<(Batch, Option<RawSteps>), RunError> {
        Python::attach(|py| {
            self.collect_py(py, request).map_err(|e| {
                let message = e.to_string();
                if let Ok(mut slot) = self.error.lock() {
                    *slot = Some(e);
                }
                RunError::Mdp(format!("the collector failed: {message}"))
            })
        })
    }
}

/// The keyword arguments of [`Trainer`]'s constructor, named when an unknown one is passed.
const TRAINER_KEYWORDS: &str = "n_trajectories, seed, delta, v0, sigma0, initial_budget, nu, requirement, alpha, beta, lr, lr_w, reference_batch, accounting, v_direction, adam_lr, adam_beta1, adam_beta2, adam_eps, on_contradiction";

/// SEPG (Algorithm 4.3, every requirement of Table 4.1) or a comparison algorithm of
/// Chapter 5 on trajectories collected by a Python callable. `collector(request)` receives a
/// [`PyBatchRequest`] and returns `(rewards (N, H), actions (N, H, l), features (N, H, p),
/// lengths (N,))` with the raw sampled actions; the scores, estimates, widths, safe steps and
/// budget are computed in Rust. Records are returned as dicts with the columns of `log.csv`.
#[pyclass(unsendable, name = "Trainer", module = "sepg")]
pub struct Trainer {
    parts: Option<(PolicySolver, State)>,
    error: Arc<Mutex<Option<PyErr>>>,
}

#[pymethods]
impl Trainer {
    /// A trainer for `algorithm` (named as on the command line) with validated `constants`,
    /// `actions` action dimensions and `features` features; v⁰ (default −0.1 everywhere,
    /// action-major `v[j·p + i]`), σ⁰ (default 1), N trajectories per iteration, seed, δ,
    /// initial budget B⁰ ≥ 0, `accounting` ("certified", the default: requirements built on
    /// the certified guarantees of the applied steps; "estimated": the thesis's bookkeeping
    /// with estimated J), and N₀, the trajectories of the reference batch that estimates
    /// J(θ⁰) before the first iteration of SEPG under the estimated bookkeeping (default 1000;
    /// 0 takes J(θ⁰) from the first v-block as the thesis's pseudocode does; 1 is an error).
    /// `v_direction` is SEPG's v-update: "greedy" (the default, Theorem 4.2's coordinate) or
    /// "adam" ("safe Adam": Adam with learning rate `adam_lr` > 0 in units of v, β₁ =
    /// `adam_beta1` (0.9), β₂ = `adam_beta2` (0.999), ε = `adam_eps` (1e-8) proposes the
    /// change, and the largest certified step along it at most 1 is taken; docs/THEOREMS.md,
    /// "A step along any direction"), which needs the tight constants and the certified
    /// accounting. Every reward and feature the collector returns is checked against the
    /// declared R_max and M_φ (docs/RELIABILITY.md): `on_contradiction` = "stop" (the default)
    /// raises at the first value beyond its bound, "continue" goes on and records the
    /// contradiction in the state's `constants_check` (no guarantee).
    #[new]
    #[pyo3(signature = (algorithm, constants, actions, features, collector, *, n_trajectories = None, seed = None, delta = None, v0 = None, sigma0 = None, initial_budget = None, nu = None, requirement = DEFAULT_REQUIREMENT.name(), alpha = None, beta = None, lr = None, lr_w = None, reference_batch = None, accounting = None, v_direction = None, adam_lr = None, adam_beta1 = None, adam_beta2 = None, adam_eps = None, on_contradiction = None, **unknown))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        algorithm: &str,
        constants: PyRef<'_, PyTaskConstants>,
        actions: usize,
        features: usize,
        collector: Py<PyAny>,
        n_trajectories: Option<&Bound<'_, PyAny>>,
        seed: Option<&Bound<'_, PyAny>>,
        delta: Option<&Bound<'_, PyAny>>,
        v0: Option<&Bound<'_, PyAny>>,
        sigma0: Option<&Bound<'_, PyAny>>,
        initial_budget: Option<&Bound<'_, PyAny>>,
        nu: Option<&Bound<'_, PyAny>>,
        requirement: &str,
        alpha: Option<f64>,
        beta: Option<f64>,
        lr: Option<f64>,
        lr_w: Option<f64>,
        reference_batch: Option<usize>,
        accounting: Option<&str>,
        v_direction: Option<&str>,
        adam_lr: Option<f64>,
        adam_beta1: Option<f64>,
        adam_beta2: Option<f64>,
        adam_eps: Option<f64>,
        on_contradiction: Option<&str>,
        unknown: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        if let Some(key) = unknown.and_then(|d| d.keys().iter().next()) {
            return Err(PyTypeError::new_err(format!(
                "Trainer() got an unexpected keyword argument {key}; its keyword arguments are {TRAINER_KEYWORDS}"
            )));
        }
        // numbers are read here rather than by pyo3, so that a wrong type names the argument
        let n_trajectories: usize =
            n_trajectories.map_or(Ok(DEFAULT_N_TRAJECTORIES), |n| natural(n, "n_trajectories"))?;
        let seed: u64 = seed.map_or(Ok(DEFAULT_SEED), |s| natural(s, "seed"))?;
        let delta = delta.map_or(Ok(DEFAULT_DELTA), |d| real(d, "delta"))?;
        let nu = nu.map_or(Ok(DEFAULT_NU), |x| real(x, "nu"))?;
        let initial_budget =
            initial_budget.map_or(Ok(DEFAULT_BUDGET0), |b| real(b, "initial_budget"))?;
        let algorithm = self::algorithm(algorithm, nu, requirement, alpha, beta, lr, lr_w)?;
        let state = initial_state(actions, features, v0, sigma0, initial_budget)?;
        let config = CollectedConfig {
            algorithm,
            constants: constants.0,
            delta,
            estimator: GradientSpec::default(),
            n_trajectories,
            seed,
            actions,
            features,
        };
        let error = Arc::new(Mutex::new(None));
        let collector = PyCollector {
            callable: collector,
            gamma: constants.0.gamma(),
            features,
            error: Arc::clone(&error),
        };
        let options = trainer_options(
            reference_batch,
            accounting,
            v_direction,
            (adam_lr, adam_beta1, adam_beta2, adam_eps),
            on_contradiction,
        )?;
        let solver = PolicySolver::with_collector(&config, Box::new(collector))
            .and_then(|s| s.with_options(options))
            .map_err(invalid)?;
        Ok(Trainer {
            parts: Some((solver, state)),
            error,
        })
    }

    /// Runs `iterations` more iterations and returns their records: one dict per iteration
    /// with the columns of `log.csv` (`crate::record`). On error the state stays after the
    /// last completed iteration; an exception of the collector is re-raised as it is.
    fn run<'py>(&mut self, py: Python<'py>, iterations: u64) -> PyResult<Vec<Bound<'py, PyDict>>> {
        let (solver, state) = self
            .parts
            .take()
            .ok_or_else(|| failed("the trainer is unusable after an internal error"))?;
        let mut log = Collect::default();
        let mut exec = Executor::new(solver, state).observe(&mut log);
        let result = exec.run(iterations);
        self.parts = Some(exec.into_parts());
        if let Err(e) = result {
            let stored = self.error.lock().ok().and_then(|mut s| s.take());
            return Err(stored.unwrap_or_else(|| failed(e)));
        }
        log.records.iter().map(|r| record::to_py(py, r)).collect()
    }

    /// Replaces the state by `state`, JSON text as `state()` returns it (the checkpoint of a
    /// saved model). Raises `InvalidInputError` for text that is not such a state, or a state
    /// whose v and w do not have the trainer's dimensions; the trainer is unchanged then.
    fn set_state(&mut self, state: &str) -> PyResult<()> {
        let new: State = serde_json::from_str(state).map_err(|e| invalid(format!("state: {e}")))?;
        let (solver, old) = self
            .parts
            .take()
            .ok_or_else(|| failed("the trainer is unusable after an internal error"))?;
        if new.v.len() != old.v.len() || new.w.len() != old.w.len() {
            let message = format!(
                "state: v and w must have {} and {} entries, got {} and {}",
                old.v.len(),
                old.w.len(),
                new.v.len(),
                new.w.len()
            );
            self.parts = Some((solver, old));
            return Err(invalid(message));
        }
        self.parts = Some((solver, new));
        Ok(())
    }

    /// The state after the last completed iteration (the checkpoint), as JSON text.
    fn state(&self) -> PyResult<String> {
        let (_, state) = self
            .parts
            .as_ref()
            .ok_or_else(|| failed("the trainer is unusable after an internal error"))?;
        serde_json::to_string(state).map_err(failed)
    }
}

/// The initial state of a [`Trainer`]: v⁰ (default [`DEFAULT_V0`] everywhere, `actions ×
/// features` entries), σ⁰ (default [`DEFAULT_SIGMA0`], `actions` entries, positive with a
/// finite logarithm) and the budget B⁰ (finite, non-negative).
fn initial_state(
    actions: usize,
    features: usize,
    v0: Option<&Bound<'_, PyAny>>,
    sigma0: Option<&Bound<'_, PyAny>>,
    initial_budget: f64,
) -> PyResult<State> {
    let dim_v = actions
        .checked_mul(features)
        .ok_or_else(|| invalid("actions × features overflows"))?;
    let v0 = match v0 {
        Some(v) => floats(v, "v0", None)?.0,
        None => vec![DEFAULT_V0; dim_v],
    };
    let sigma0 = match sigma0 {
        Some(s) => floats(s, "sigma0", None)?.0,
        None => vec![DEFAULT_SIGMA0; actions],
    };
    if v0.len() != dim_v || sigma0.len() != actions {
        return Err(invalid(format!(
            "v0 must have {dim_v} entries (actions × features) and sigma0 {actions}; got {} and {}",
            v0.len(),
            sigma0.len()
        )));
    }
    if let Some(s) = sigma0.iter().find(|s| !(**s > 0.0 && s.ln().is_finite())) {
        return Err(invalid(format!(
            "sigma0 must be positive and finite, got {s}"
        )));
    }
    if !(initial_budget.is_finite() && initial_budget >= 0.0) {
        return Err(invalid(format!(
            "initial_budget = {initial_budget} must be finite and non-negative"
        )));
    }
    Ok(State::new(
        v0,
        sigma0.iter().map(|s| s.ln()).collect(),
        initial_budget,
    ))
}

/// The SEPG options of a [`Trainer`]: Student-t widths at level δ each, the reference batch,
/// the accounting, the v-direction with Adam's (lr, β₁, β₂, ε) and the reaction to a
/// contradiction, each named as in [`Trainer`]'s constructor.
fn trainer_options(
    reference_batch: Option<usize>,
    accounting: Option<&str>,
    v_direction: Option<&str>,
    adam: (Option<f64>, Option<f64>, Option<f64>, Option<f64>),
    on_contradiction: Option<&str>,
) -> PyResult<SepgOptions> {
    // the trainer knows no iteration count, so δ is not spread over a run: every width is
    // at level δ, Student-t (docs/THEOREMS.md, "Statements over a whole run")
    let mut options = SepgOptions {
        schedule: Schedule::Iteration,
        confidence: Confidence::StudentT {
            factor: DEFAULT_QUANTILE_FACTOR,
        },
        ..SepgOptions::default()
    };
    if let Some(n0) = reference_batch {
        options.reference_batch = n0;
    }
    if let Some(name) = accounting {
        options.accounting = match value_name("accounting", name)? {
            AccountingName::Certified => Accounting::Certified,
            AccountingName::Estimated => Accounting::Estimated,
        };
    }
    let (adam_lr, adam_beta1, adam_beta2, adam_eps) = adam;
    let v_direction = v_direction
        .map(|name| value_name("v_direction", name))
        .transpose()?;
    options.v_direction =
        self::v_direction(v_direction, adam_lr, adam_beta1, adam_beta2, adam_eps)?;
    if let Some(name) = on_contradiction {
        options.on_contradiction =
            value_name::<OnContradictionName>("on_contradiction", name)?.option();
    }
    Ok(options)
}

/// The required improvements `(C_v, C_w)` of SEPG's v- and w-updates for the requirement
/// named `requirement` (Table 4.1; [`Requirement::required_improvements`]), the budget B,
/// the split ν and, for LB-I, the drop J(θ⁰) − J(θᵗ); read by `sepg.required_improvement`,
/// which checks the arguments' types first.
///
/// [`Requirement::required_improvements`]: sepg_algo::Requirement::required_improvements
#[pyfunction]
fn _required_improvement(
    requirement: &str,
    budget: f64,
    nu: f64,
    j_drop: f64,
) -> PyResult<(f64, f64)> {
    let r: RequirementName = requirement.parse().map_err(invalid)?;
    r.requirement(Some(nu))
        .required_improvements(budget, j_drop)
        .map_err(invalid)
}

/// Adds the classes of this module to `m`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyBatchRequest>()?;
    m.add_class::<Trainer>()?;
    m.add_function(wrap_pyfunction!(_required_improvement, m)?)?;
    // the names and defaults the Python package reads (one table, in sepg_algo)
    m.add("_ALGORITHMS", PyTuple::new(m.py(), AlgoName::names())?)?;
    m.add(
        "_REQUIREMENTS",
        PyTuple::new(m.py(), RequirementName::names())?,
    )?;
    m.add("_DEFAULT_ALGORITHM", DEFAULT_ALGO.name())?;
    m.add("_DEFAULT_REQUIREMENT", DEFAULT_REQUIREMENT.name())?;
    m.add("_DEFAULT_CONSTANTS", RUN_CONSTANTS.name())?;
    m.add("_DEFAULT_DELTA", DEFAULT_DELTA)?;
    m.add("_DEFAULT_NU", DEFAULT_NU)?;
    m.add("_DEFAULT_N_TRAJECTORIES", DEFAULT_N_TRAJECTORIES)?;
    m.add("_DEFAULT_SEED", DEFAULT_SEED)?;
    m.add("_DEFAULT_BUDGET0", DEFAULT_BUDGET0)?;
    Ok(())
}
