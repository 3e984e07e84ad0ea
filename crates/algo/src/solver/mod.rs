//! The algorithms: SEPG (Algorithm 4.3) for every safety requirement, SEPG with the naive
//! variance update, and the comparison algorithms of Chapter 5, behind one [`PolicySolver`].
//!
//! # Example
//! ```
//! use sepg_algo::core::config::{Algorithm, GradientMode, Requirement, SepgConfig};
//! use sepg_algo::core::executor::{Collect, Executor};
//! use sepg_algo::solver::PolicySolver;
//! use sepg_mdp::env::Preset;
//! let mut cfg = SepgConfig::new(Preset::Lqg1d.build(), Algorithm::Sepg(Requirement::Zv));
//! cfg.n_trajectories = 30;
//! let checked = cfg.check()?;
//! let mut log = Collect::default();
//! let mut exec = Executor::new(PolicySolver::new(&checked)?, checked.initial_state())
//!     .observe(&mut log);
//! exec.run(3)?;
//! drop(exec);
//! assert_eq!(log.records.len(), 3);
//! // 3 iterations of N = 30: the certified accounting estimates no J(θ⁰)
//! assert_eq!(log.records[2].trajectories, 90);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
pub(crate) mod baseline;
pub mod batch;
pub(crate) mod exact;
pub mod realise;
pub mod sampled;
pub(crate) mod sepg;
pub mod source;
pub mod steps;

use sepg_bounds::constants::TaskConstants;
use sepg_estimators::GradientSpec;
use sepg_estimators::proven::ProvenWidths;
use sepg_mdp::env::{AnyEnv, Environment};
use sepg_mdp::oracle::{ClippedDpOracle, ClosedFormOracle, ExactOracle, Horizon};

use crate::core::check::Limits;
use crate::core::config::{
    Algorithm, CheckedConfig, GradientMode, Requirement, check_sampled, check_v_direction,
};
use crate::core::error::{ConfigError, RunError};
use crate::core::executor::Solver;
use crate::core::options::{BatchRule, Confidence, Schedule, SepgOptions, WStep};
use crate::core::record::Record;
use crate::core::state::State;
use crate::solver::exact::ExactSource;
use crate::solver::sampled::{BatchCollector, BlockEstimator, CollectedSource, SampledSource};
use crate::solver::source::GradientSource;

/// Every algorithm of the crate as a [`Solver`], built from a [`CheckedConfig`].
pub struct PolicySolver {
    algorithm: Algorithm,
    n: usize,
    dims: (usize, usize),
    constants: TaskConstants,
    options: SepgOptions,
    source: Box<dyn GradientSource>,
    certified: bool,
    batch: BatchRule,
}

impl std::fmt::Debug for PolicySolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PolicySolver")
            .field("algorithm", &self.algorithm)
            .field("n", &self.n)
            .finish_non_exhaustive()
    }
}

impl PolicySolver {
    /// The solver of `config`: sampled gradients from rollouts, or exact ones from the
    /// clipped-LQG dynamic programme (scalar clipped LQG) or the closed form (unclipped LQG).
    ///
    /// # Errors
    /// [`ConfigError::ExactUnsupported`] when the exact oracle cannot be built for the model;
    /// [`ConfigError::UnsupportedOption`] for the Adam v-direction with the thesis's constants
    /// (see [`CheckedConfig::with_family`]).
    ///
    /// # Examples
    /// See the [module documentation](self).
    pub fn new(config: &CheckedConfig) -> Result<Self, ConfigError> {
        let cfg = config.config();
        let constants = *config.constants();
        let source: Box<dyn GradientSource> = match cfg.gradient {
            GradientMode::Sampled { delta } => {
                let level = width_delta(config, delta);
                let mut source = SampledSource::new(
                    cfg.env.clone(),
                    cfg.horizon,
                    cfg.seed,
                    level,
                    cfg.options.confidence.factor(),
                    cfg.estimator,
                    constants,
                )
                .with_score_action(cfg.score_action);
                let sepg = matches!(cfg.algorithm, Algorithm::Sepg(_) | Algorithm::SepgNaiveW(_));
                if sepg && cfg.options.confidence == Confidence::SubGaussian {
                    source = source.with_proven_widths(proven_widths(config)?, level);
                }
                Box::new(source)
            }
            GradientMode::Exact => {
                let unsupported = |e: sepg_mdp::oracle::OracleError| {
                    ConfigError::ExactUnsupported { env: e.to_string() }
                };
                let AnyEnv::Lqg(env) = &cfg.env else {
                    return Err(ConfigError::ExactUnsupported {
                        env: "mountain-car".into(),
                    });
                };
                let model = env.model();
                let oracle: Box<dyn ExactOracle + Send> = if model.clipping {
                    Box::new(ClippedDpOracle::new(model).map_err(unsupported)?)
                } else {
                    Box::new(ClosedFormOracle::new(model).map_err(unsupported)?)
                };
                Box::new(ExactSource::new(
                    oracle,
                    Horizon::Finite(cfg.horizon),
                    constants,
                ))
            }
        };
        check_v_direction(&cfg.options, &constants)?;
        let mut options = cfg.options;
        if cfg.gradient == GradientMode::Exact {
            // Exact J(θ⁰) needs no reference batch.
            options.reference_batch = 0;
        }
        Ok(PolicySolver {
            algorithm: cfg.algorithm,
            n: cfg.n_trajectories,
            dims: (cfg.v0.len(), cfg.sigma0.len()),
            constants,
            options,
            source,
            certified: config.certified(),
            batch: BatchRule::Fixed,
        })
    }
}

/// The number K of scalar confidence statements one iteration of `algorithm` rests on, with
/// `dims` = (mean parameters l·p, action dimensions l): every component of ∇̂_v J (the v-step
/// uses ‖·‖∞), every component of ∇̂_w J (the w-coordinate is chosen from the data), l more
/// for LV's target, and l more for ∇̂_w L when Theorem 4.9's step reads its width.
/// Comparison algorithms: one gradient of all l·p + l components.
pub fn statements_per_iteration(
    algorithm: Algorithm,
    options: &SepgOptions,
    dims: (usize, usize),
) -> usize {
    let (m, l) = dims;
    match algorithm {
        Algorithm::Sepg(r) | Algorithm::SepgNaiveW(r) => {
            let naive = matches!(algorithm, Algorithm::SepgNaiveW(_));
            let target = usize::from(r == Requirement::Lv);
            let direction = usize::from(!naive && options.w_step == WStep::Theorem49);
            m + l * (1 + target + direction)
        }
        _ => m + l,
    }
}

/// The level of each confidence width of a sampled run: δ (schedule `Iteration`) or
/// δ/(T·K) (schedule `Run`, T iterations of K statements each,
/// [`statements_per_iteration`]), so that by the union bound the probability that any
/// width of the run fails is at most δ.
///
/// # Formula
/// ```text
/// Run:        δ_width = δ / (T · K)
/// Iteration:  δ_width = δ
/// ```
pub fn width_delta(config: &CheckedConfig, delta: f64) -> f64 {
    let cfg = config.config();
    match cfg.options.schedule {
        Schedule::Iteration => delta,
        Schedule::Run => {
            let k = statements_per_iteration(
                cfg.algorithm,
                &cfg.options,
                (cfg.v0.len(), cfg.sigma0.len()),
            );
            delta / (cfg.iterations as f64 * k as f64)
        }
    }
}

/// The proven widths of a checked configuration (`Confidence::SubGaussian`): R, M_φ and γ of
/// its constants, its horizon (capped by the environment's time limit) and its rewards' sign
/// (the LQG rewards −(sᵀQs + aᵀRa) are non-positive; Mountain Car's are not).
///
/// # Errors
/// [`ConfigError::Environment`] when the estimators reject the constants.
pub fn proven_widths(config: &CheckedConfig) -> Result<ProvenWidths, ConfigError> {
    let cfg = config.config();
    let k = config.constants();
    let non_positive = matches!(cfg.env, AnyEnv::Lqg(_));
    let horizon = cfg
        .env
        .time_limit()
        .map_or(cfg.horizon, |l| l.min(cfg.horizon));
    ProvenWidths::new(k.r_max(), non_positive, k.m_phi(), k.gamma(), horizon)
        .map_err(|e| ConfigError::Environment(e.to_string()))
}

/// The settings of a run whose trajectories are collected outside the crate by a
/// [`BatchCollector`] (any environment, any language): what [`CheckedConfig`] takes from the
/// environment is given here directly.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CollectedConfig {
    /// The algorithm.
    pub algorithm: Algorithm,
    /// The task constants R, M_φ, |A|, γ of the environment (validated).
    pub constants: TaskConstants,
    /// Confidence parameter δ ∈ (0, 1) of the widths (Sec 4.5).
    pub delta: f64,
    /// Estimator of ∇_v J and ∇_w J.
    pub estimator: GradientSpec,
    /// Trajectories per iteration N, split evenly among the blocks.
    pub n_trajectories: usize,
    /// Seed of the run: the seed keys of the requests derive from (seed, iteration, block).
    pub seed: u64,
    /// Number of action dimensions l.
    pub actions: usize,
    /// Number of features p (the mean has `l · p` parameters).
    pub features: usize,
}

impl PolicySolver {
    /// Turns certified steps (`sepg_certified`, on by default) on or off for this
    /// solver, e.g. one built by [`PolicySolver::with_collector`]; see
    /// [`CheckedConfig::with_certified_steps`].
    pub fn with_certified_steps(mut self, on: bool) -> Self {
        self.certified = on;
        self
    }

    /// Sets how many trajectories each block of a SEPG iteration draws (the default is
    /// [`BatchRule::Fixed`]: N split evenly among the blocks). With
    /// [`BatchRule::Adaptive`] every block after the first iteration draws the size chosen
    /// by [`batch::next_batch`] from the previous iteration's v-block, kept in
    /// [`State::next_batch`] so that a resumed run continues bit for bit (docs/THEOREMS.md "An
    /// adaptive batch size"). The comparison algorithms ignore the rule.
    ///
    /// # Errors
    /// As [`BatchRule::validate`] with the solver's accounting.
    ///
    /// # Examples
    /// ```
    /// use sepg_algo::core::config::{Algorithm, Requirement, SepgConfig};
    /// use sepg_algo::core::options::BatchRule;
    /// use sepg_algo::solver::PolicySolver;
    /// use sepg_mdp::env::Preset;
    /// let checked = SepgConfig::new(Preset::Lqg1d.build(), Algorithm::Sepg(Requirement::Mi)).check()?;
    /// let rule = BatchRule::Adaptive { n_min: 50, n_max: 250_000 };
    /// assert!(PolicySolver::new(&checked)?.with_batch_rule(rule).is_ok());
    /// let bad = BatchRule::Adaptive { n_min: 50, n_max: 49 };
    /// assert!(PolicySolver::new(&checked)?.with_batch_rule(bad).is_err());
    /// # Ok::<(), sepg_algo::core::error::ConfigError>(())
    /// ```
    pub fn with_batch_rule(mut self, rule: BatchRule) -> Result<Self, ConfigError> {
        rule.validate(self.options.accounting)?;
        self.batch = rule;
        Ok(self)
    }

    /// Replaces the SEPG options of this solver, e.g. one built by
    /// [`PolicySolver::with_collector`], which starts from [`SepgOptions::default`] with
    /// [`Schedule::Iteration`] (a collector that reproduces the thesis's pseudocode sets
    /// `reference_batch` to 0).
    ///
    /// # Errors
    /// As [`SepgOptions::validate`]; [`ConfigError::UnsupportedOption`] for a schedule other
    /// than the solver's (its widths are built for it), or for the estimated accounting when
    /// the solver has an adaptive batch rule.
    pub fn with_options(mut self, options: SepgOptions) -> Result<Self, ConfigError> {
        options.validate()?;
        self.batch.validate(options.accounting)?;
        check_v_direction(&options, &self.constants)?;
        if options.schedule != self.options.schedule
            || options.confidence != self.options.confidence
        {
            // the widths were built for the solver's schedule
            return Err(ConfigError::UnsupportedOption {
                option: "schedule/confidence",
                reason: "the schedule and widths are fixed when the solver is built (a \
                         collector solver: schedule iteration, Student-t widths)",
            });
        }
        self.options = options;
        Ok(self)
    }

    /// The solver of `config` with every batch collected by `collector` and estimated by
    /// [`BlockEstimator`]: the same iteration code as [`PolicySolver::new`] in the sampled
    /// mode, so a collector that reproduces the built-in rollouts reproduces their records.
    /// SEPG runs with the default [`SepgOptions`] (including the reference batch of J(θ⁰),
    /// requested from the collector as [`Block::Reference`](crate::core::seed::Block)).
    ///
    /// # Errors
    /// A [`ConfigError`] for bad hyper-parameters, δ ∉ (0, 1), N too small for the blocks, or
    /// zero dimensions.
    pub fn with_collector(
        config: &CollectedConfig,
        collector: Box<dyn BatchCollector>,
    ) -> Result<Self, ConfigError> {
        config.algorithm.validate()?;
        check_sampled(config.algorithm, config.n_trajectories, config.delta)?;
        for (what, got) in [("actions", config.actions), ("features", config.features)] {
            if got == 0 {
                return Err(ConfigError::DimensionMismatch {
                    what,
                    expected: 1,
                    got,
                });
            }
        }
        let dims = (config.actions * config.features, config.actions);
        let estimator = BlockEstimator::new(config.delta, config.estimator, config.constants);
        Ok(PolicySolver {
            algorithm: config.algorithm,
            n: config.n_trajectories,
            dims,
            constants: config.constants,
            // No iteration count is known here, so δ cannot be spread over a run: every width
            // is at level δ (per-iteration statements); no horizon or reward sign is known
            // either, so the widths are Student-t.
            options: SepgOptions {
                schedule: Schedule::Iteration,
                confidence: Confidence::StudentT { factor: 1.0 },
                ..SepgOptions::default()
            },
            source: Box::new(CollectedSource::new(
                collector,
                config.seed,
                dims,
                estimator,
            )),
            certified: true,
            batch: BatchRule::Fixed,
        })
    }
}

impl Solver for PolicySolver {
    fn init(&mut self, state: &mut State) -> Result<(), RunError> {
        if state.v.len() != self.dims.0 || state.w.len() != self.dims.1 {
            return Err(RunError::Checkpoint(format!(
                "state has {} mean and {} variance parameters, the configuration {} and {}",
                state.v.len(),
                state.w.len(),
                self.dims.0,
                self.dims.1
            )));
        }
        Ok(())
    }

    fn next_iter(&mut self, state: &mut State) -> Result<Record, RunError> {
        self.init(state)?;
        let limits = Limits::of(&self.constants, &self.options);
        if let Some(c) = self.source.checker() {
            c.arm(limits, self.options.on_contradiction);
        }
        let result = self.iterate(state);
        if let Some(c) = self.source.checker() {
            let seen = c.take();
            if result.is_ok() {
                state.constants_check.merge(&seen);
            }
        }
        result
    }
}

impl PolicySolver {
    /// One iteration of the algorithm (the state is updated only when it succeeds).
    fn iterate(&mut self, state: &mut State) -> Result<Record, RunError> {
        match self.algorithm {
            Algorithm::Sepg(req) | Algorithm::SepgNaiveW(req) => {
                let setup = sepg::Setup {
                    k: &self.constants,
                    req,
                    naive_w: matches!(self.algorithm, Algorithm::SepgNaiveW(_)),
                    n: self.n,
                    opts: &self.options,
                    certify: self.certified,
                    features: self.dims.0 / self.dims.1.max(1),
                    batch: self.batch,
                };
                sepg::iterate(&mut *self.source, &setup, state)
            }
            other => baseline::iterate(&mut *self.source, &self.constants, other, self.n, state),
        }
    }
}
