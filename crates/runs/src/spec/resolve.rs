//! [`RunSpec::resolve`]: the defaults, the algorithm, the sampled mode, the start and the
//! schedule of a run, and its environment.

use sepg_algo::core::config::{Algorithm, GradientMode, SepgConfig, reward_sign};
use sepg_algo::core::defaults::{
    DEFAULT_ALGO, DEFAULT_BUDGET0, DEFAULT_DELTA, DEFAULT_ITERATIONS, DEFAULT_N_TRAJECTORIES,
    DEFAULT_NU, DEFAULT_REQUIREMENT, DEFAULT_SEED, DEFAULT_SIGMA0, DEFAULT_V0,
};
use sepg_estimators::{Baseline, BaselineFit, GradientSpec, Kind};
use sepg_mdp::env::{AnyEnv, Environment, LqgEnv};
use sepg_mdp::mountain_car::MountainCar;
use sepg_mdp::policy::GaussianPolicy;
use sepg_mdp::rollout::ScoreAction;

use super::applicability::reject;
use super::limits::{MAX_BATCH_BYTES, MAX_ITERATIONS, VERSION, check_batch_memory, check_horizon};
use super::names::{
    AlgoName, BaselineName, EnvName, EstimatorName, FitName, GradientsName, RequirementName,
    ScoresName,
};
use super::resolved::Resolved;
use super::run_spec::RunSpec;
use super::values::Values;
use crate::error::{Error, Result};

impl RunSpec {
    /// Resolves every default, validates the configuration (the checks of
    /// [`SepgConfig::check`] plus the options that do not apply to the algorithm) and builds
    /// the algorithm's configuration.
    ///
    /// # Errors
    /// [`Error::Invalid`] for any invalid or inapplicable option.
    pub fn resolve(&self) -> Result<Resolved> {
        let env_name = self.env.unwrap_or(EnvName::Lqg);
        let algo = self.algo.unwrap_or(DEFAULT_ALGO);
        let gradients = self.gradients.unwrap_or(GradientsName::Sampled);
        let env = build_env(env_name, self.features.as_deref())?;
        let features = self.features_of(env_name)?;
        self.reject_inapplicable(algo, gradients)?;
        let method = self.method(algo)?;
        let sampling = self.sampling(gradients);
        let options = self.options(algo, gradients, reward_sign(&env));
        let dim_w = env.action_dim();
        let dim_v = dim_w * env.feature_dim();
        let start = self.start(env_name, dim_v, dim_w)?;
        let schedule = self.schedule(env.constants().horizon)?;
        self.check_sizes(&schedule, (dim_v, dim_w))?;
        let feature_dim = env.feature_dim();
        let config = SepgConfig {
            env,
            algorithm: method.algorithm,
            gradient: sampling.gradient(),
            estimator: sampling.gradient_spec(),
            v0: start.v0.clone(),
            sigma0: start.sigma0.clone(),
            n_trajectories: schedule.batch,
            horizon: schedule.horizon,
            iterations: schedule.iterations,
            seed: schedule.seed,
            initial_budget: start.budget0,
            options: options.unwrap_or_default(),
            score_action: self
                .scores
                .map_or(ScoreAction::Raw, ScoresName::score_action),
        };
        let certified_steps = algo.is_sepg().then(|| self.certified_steps.unwrap_or(true));
        let checked = config
            .check()
            .map_err(|e| Error::invalid_from("invalid configuration", e))?
            .with_certified_steps(certified_steps.unwrap_or(true));
        // The first iteration builds the policy θ⁰: refuse here what it would refuse there.
        let first = checked.initial_state();
        GaussianPolicy::new(first.v, first.w, feature_dim)
            .map_err(|e| Error::invalid_from("invalid initial policy (v0, sigma0)", e))?;
        let spec = RunSpec {
            name: Some(self.name.clone().unwrap_or_else(|| algo.name().to_owned())),
            env: Some(env_name),
            features,
            algo: Some(algo),
            gradients: Some(gradients),
            sepg_version: Some(
                self.sepg_version
                    .clone()
                    .unwrap_or_else(|| VERSION.to_owned()),
            ),
            scores: (gradients == GradientsName::Sampled)
                .then_some(self.scores.unwrap_or(ScoresName::Raw)),
            certified_steps,
            batch_rule: self.batch_rule,
            batch_min: self.batch_min,
            batch_max: self.batch_max,
            ..RunSpec::resolved_values(&method, &sampling, start, &schedule, options.as_ref())
        };
        Ok(Resolved {
            spec,
            checked,
            dims: (dim_v, dim_w),
        })
    }

    /// The feature map of Mountain Car (default `state-bias`); `None` for the LQG presets,
    /// which refuse the option.
    fn features_of(&self, env_name: EnvName) -> Result<Option<String>> {
        match env_name {
            EnvName::MountainCar => Ok(Some(
                self.features.clone().unwrap_or_else(|| "state-bias".into()),
            )),
            _ => {
                reject(self.features.is_some(), "features", "to LQG environments")?;
                Ok(None)
            }
        }
    }

    /// Checks the horizon, the iterations, the batch's and the reference batch's memory
    /// against their limits, for `dims` = (mean, standard-deviation) parameters.
    fn check_sizes(&self, schedule: &Schedule, (dim_v, dim_w): (usize, usize)) -> Result<()> {
        check_horizon(schedule.horizon)?;
        if schedule.iterations > MAX_ITERATIONS {
            return Err(Error::invalid(format!(
                "iterations = {} is above the limit of {MAX_ITERATIONS}",
                schedule.iterations
            )));
        }
        check_batch_memory("batch", schedule.batch, schedule.horizon, (dim_v, dim_w))?;
        // The reference batch keeps one return (8 bytes) per trajectory.
        let reference = self.reference_batch.unwrap_or(0) as u64;
        if reference.checked_mul(8).is_none_or(|b| b > MAX_BATCH_BYTES) {
            return Err(Error::invalid(format!(
                "reference-batch N = {reference} returns need more than the limit of {} GiB",
                MAX_BATCH_BYTES >> 30
            )));
        }
        Ok(())
    }

    /// The algorithm of `algo` with its step options (the options were checked to apply).
    fn method(&self, algo: AlgoName) -> Result<Method> {
        let nu = algo
            .uses_nu(self.requirement)
            .then(|| self.nu.unwrap_or(DEFAULT_NU));
        let requirement =
            (algo == AlgoName::SepgNaiveW).then(|| self.requirement.unwrap_or(DEFAULT_REQUIREMENT));
        let need = |v: Option<f64>, flag: &str| {
            v.ok_or_else(|| Error::invalid(format!("algorithm {} needs --{flag}", algo.name())))
        };
        let mut method = Method {
            algorithm: Algorithm::AdaStep,
            requirement,
            nu,
            alpha: None,
            beta: None,
            lr: None,
            lr_w: None,
        };
        let sepg = |r: RequirementName| Algorithm::Sepg(r.requirement(nu));
        method.algorithm = match algo {
            AlgoName::SepgMi => sepg(RequirementName::Mi),
            AlgoName::SepgLb1 => sepg(RequirementName::Lb1),
            AlgoName::SepgLb2 => sepg(RequirementName::Lb2),
            AlgoName::SepgLv => sepg(RequirementName::Lv),
            AlgoName::SepgZv => sepg(RequirementName::Zv),
            AlgoName::SepgSim => sepg(RequirementName::Sim),
            AlgoName::SepgNaiveW => {
                Algorithm::SepgNaiveW(requirement.unwrap_or(DEFAULT_REQUIREMENT).requirement(nu))
            }
            AlgoName::GpomdpConst => {
                let alpha = need(self.alpha, "alpha")?;
                let beta = self.beta.unwrap_or(alpha);
                (method.alpha, method.beta) = (Some(alpha), Some(beta));
                Algorithm::GpomdpConst { alpha, beta }
            }
            AlgoName::GpomdpAdam => {
                let lr = need(self.lr, "lr")?;
                let lr_w = self.lr_w.unwrap_or(lr);
                (method.lr, method.lr_w) = (Some(lr), Some(lr_w));
                Algorithm::adam(lr, lr_w)
            }
            AlgoName::Adastep => Algorithm::AdaStep,
        };
        Ok(method)
    }

    /// The confidence and estimator of the sampled mode (`None` for exact gradients).
    fn sampling(&self, gradients: GradientsName) -> Sampling {
        if gradients == GradientsName::Exact {
            return Sampling(None);
        }
        Sampling(Some((
            self.delta.unwrap_or(DEFAULT_DELTA),
            self.estimator.unwrap_or(EstimatorName::Gpomdp),
            self.baseline.unwrap_or(BaselineName::Optimal),
            self.baseline_fit.unwrap_or(FitName::LeaveOneOut),
        )))
    }

    /// The initial parameters and budget for an environment with `dim_v` mean parameters and
    /// `dim_w` standard deviations.
    fn start(&self, env: EnvName, dim_v: usize, dim_w: usize) -> Result<Start> {
        let v0 = self
            .v0
            .clone()
            .unwrap_or(Values::One(DEFAULT_V0))
            .expand(dim_v, "v0")?;
        let sigma0 = self
            .sigma0
            .clone()
            .unwrap_or(Values::One(DEFAULT_SIGMA0))
            .expand(dim_w, "sigma0")?;
        // Mountain Car starts with a budget of 1 (Fig 5.4), the LQG presets with none.
        let budget0 = self.budget0.unwrap_or(if env == EnvName::MountainCar {
            1.0
        } else {
            DEFAULT_BUDGET0
        });
        Ok(Start {
            v0,
            sigma0,
            budget0,
        })
    }

    /// Batch size, horizon (default: the environment's `default_horizon`), iterations, seed
    /// and log stride.
    fn schedule(&self, default_horizon: usize) -> Result<Schedule> {
        let batch = self.batch.unwrap_or(DEFAULT_N_TRAJECTORIES);
        if batch < 2 {
            return Err(Error::invalid(format!(
                "batch N = {batch} must be at least 2"
            )));
        }
        let log_every = self.log_every.unwrap_or(1);
        let schedule = Schedule {
            batch,
            horizon: self.horizon.unwrap_or(default_horizon),
            iterations: self.iterations.unwrap_or(DEFAULT_ITERATIONS),
            seed: self.seed.unwrap_or(DEFAULT_SEED),
            log_every,
        };
        if log_every == 0 {
            return Err(Error::invalid("log-every must be at least 1"));
        }
        Ok(schedule)
    }
}

/// The algorithm of a run and the step options it uses.
pub(super) struct Method {
    pub(super) algorithm: Algorithm,
    pub(super) requirement: Option<RequirementName>,
    pub(super) nu: Option<f64>,
    pub(super) alpha: Option<f64>,
    pub(super) beta: Option<f64>,
    pub(super) lr: Option<f64>,
    pub(super) lr_w: Option<f64>,
}

/// δ, estimator, baseline and fit of the sampled mode; `None` for exact gradients.
pub(super) struct Sampling(pub(super) Option<(f64, EstimatorName, BaselineName, FitName)>);

impl Sampling {
    pub(super) fn gradient(&self) -> GradientMode {
        match self.0 {
            Some((delta, ..)) => GradientMode::Sampled { delta },
            None => GradientMode::Exact,
        }
    }

    pub(super) fn gradient_spec(&self) -> GradientSpec {
        self.0
            .map_or_else(GradientSpec::default, |(_, k, b, f)| GradientSpec {
                kind: match k {
                    EstimatorName::Gpomdp => Kind::Gpomdp,
                    EstimatorName::Reinforce => Kind::Reinforce,
                    EstimatorName::Pgt => Kind::Pgt,
                },
                baseline: match b {
                    BaselineName::None => Baseline::None,
                    BaselineName::Mean => Baseline::Mean,
                    BaselineName::Optimal => Baseline::Optimal,
                },
                fit: match f {
                    FitName::LeaveOneOut => BaselineFit::LeaveOneOut,
                    FitName::PlugIn => BaselineFit::PlugIn,
                },
            })
    }
}

/// Initial parameters v⁰, σ⁰ and budget B⁰.
pub(super) struct Start {
    pub(super) v0: Vec<f64>,
    pub(super) sigma0: Vec<f64>,
    pub(super) budget0: f64,
}

/// Batch size, horizon, iterations, seed and log stride.
pub(super) struct Schedule {
    pub(super) batch: usize,
    pub(super) horizon: usize,
    pub(super) iterations: u64,
    pub(super) seed: u64,
    pub(super) log_every: u64,
}

pub(super) fn build_env(name: EnvName, features: Option<&str>) -> Result<AnyEnv> {
    Ok(match name {
        EnvName::Lqg => AnyEnv::Lqg(Box::new(LqgEnv::thesis())),
        EnvName::Lqg1d => AnyEnv::Lqg(Box::new(LqgEnv::lqg1d())),
        EnvName::MountainCar => AnyEnv::MountainCar(match features.unwrap_or("state-bias") {
            "state-bias" => MountainCar::state_bias(),
            f => {
                let bad =
                    || Error::invalid(format!("features {f:?}: expected state-bias or rbf:KxV"));
                let grid = f.strip_prefix("rbf:").ok_or_else(bad)?;
                let (k, v) = grid.split_once('x').ok_or_else(bad)?;
                let k: usize = k.parse().map_err(|_| bad())?;
                let v: usize = v.parse().map_err(|_| bad())?;
                MountainCar::rbf([k, v], true)
                    .map_err(|e| Error::invalid_from(format!("features {f:?}"), e))?
            }
        }),
    })
}
