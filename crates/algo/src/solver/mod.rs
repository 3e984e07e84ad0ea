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
//! assert_eq!(log.records[2].trajectories, 90);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
pub(crate) mod baseline;
pub(crate) mod exact;
pub(crate) mod sampled;
pub(crate) mod sepg;
pub(crate) mod source;
pub(crate) mod steps;

use sepg_bounds::constants::TaskConstants;
use sepg_mdp::env::AnyEnv;
use sepg_mdp::oracle::{ClippedDpOracle, ClosedFormOracle, ExactOracle, Horizon};

use crate::core::config::{Algorithm, CheckedConfig, GradientMode};
use crate::core::error::{ConfigError, RunError};
use crate::core::executor::Solver;
use crate::core::record::Record;
use crate::core::state::State;
use crate::solver::exact::ExactSource;
use crate::solver::sampled::SampledSource;
use crate::solver::source::GradientSource;

/// Every algorithm of the crate as a [`Solver`], built from a [`CheckedConfig`].
pub struct PolicySolver {
    algorithm: Algorithm,
    n: usize,
    dims: (usize, usize),
    constants: TaskConstants,
    source: Box<dyn GradientSource>,
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
    /// [`ConfigError::ExactUnsupported`] when the exact oracle cannot be built for the model.
    ///
    /// # Examples
    /// See the [module documentation](self).
    pub fn new(config: &CheckedConfig) -> Result<Self, ConfigError> {
        let cfg = config.config();
        let constants = *config.constants();
        let source: Box<dyn GradientSource> = match cfg.gradient {
            GradientMode::Sampled { delta } => Box::new(SampledSource::new(
                cfg.env.clone(),
                cfg.horizon,
                cfg.seed,
                delta,
                cfg.estimator,
                constants,
            )),
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
        Ok(PolicySolver {
            algorithm: cfg.algorithm,
            n: cfg.n_trajectories,
            dims: (cfg.v0.len(), cfg.sigma0.len()),
            constants,
            source,
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
        match self.algorithm {
            Algorithm::Sepg(req) => sepg::iterate(
                &mut *self.source,
                &self.constants,
                req,
                false,
                self.n,
                state,
            ),
            Algorithm::SepgNaiveW(req) => {
                sepg::iterate(&mut *self.source, &self.constants, req, true, self.n, state)
            }
            other => baseline::iterate(&mut *self.source, &self.constants, other, self.n, state),
        }
    }
}
