//! The run folder shared by `sepg run`, `sepg sweep` and `sepg reproduce`: the configuration
//! file format ([`RunSpec`]), the columns of `log.csv`, checkpoints, and the engine that runs
//! an algorithm of `sepg-algo` into a folder and resumes it bit for bit.
//!
//! # Folder layout and completeness rule
//! ```text
//! config.toml      resolved configuration (every option, the seed and the sepg version)
//! checkpoint.json  state after the last checkpointed iteration and the valid log length
//! log.partial.csv  rows of an unfinished run (valid up to the checkpoint's log_bytes)
//! log.csv          all rows; exists only once every iteration has been written
//! summary.json     final parameters and timings; written last: the run is complete iff it exists
//! ```
//! Rows are appended in chunks of `checkpoint_every` iterations; after each chunk the log is
//! flushed to disk and the checkpoint is replaced atomically. A run killed at any point
//! therefore leaves a checkpoint whose state matches the first `log_bytes` bytes of
//! `log.partial.csv`, and resuming truncates the log there and continues. Because every batch
//! of trajectories is seeded by (seed, iteration, block), the resumed run produces the same
//! rows, bit for bit, as an uninterrupted one.

use std::fs::{self, OpenOptions};
use std::io::{IsTerminal, Write};
use std::path::Path;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use sepg_algo::core::config::{Algorithm, CheckedConfig, GradientMode, Requirement, SepgConfig};
use sepg_algo::core::executor::Solver;
use sepg_algo::core::record::Record;
use sepg_algo::core::state::State;
use sepg_algo::solver::PolicySolver;
use sepg_estimators::{Baseline, BaselineFit, GradientSpec, Kind};
use sepg_mdp::env::{AnyEnv, Environment, LqgEnv};
use sepg_mdp::mountain_car::MountainCar;
use sepg_mdp::oracle::ClosedFormOracle;
use serde::{Deserialize, Deserializer, Serialize};

use crate::cli::CliError;
use crate::output::{to_json_line, write_atomic};

/// Resolved configuration of a run.
pub const CONFIG_FILE: &str = "config.toml";
/// Checkpoint: state after the last checkpointed iteration.
pub const CHECKPOINT_FILE: &str = "checkpoint.json";
/// Log of an unfinished run.
pub const PARTIAL_LOG_FILE: &str = "log.partial.csv";
/// Log of a finished run.
pub const LOG_FILE: &str = "log.csv";
/// Summary of a finished run (its presence marks the run as complete).
pub const SUMMARY_FILE: &str = "summary.json";
/// The version of sepg recorded in every configuration.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// Files a run writes; `--force` removes exactly these from an existing folder.
pub const RUN_FILES: [&str; 5] = [
    CONFIG_FILE,
    CHECKPOINT_FILE,
    PARTIAL_LOG_FILE,
    LOG_FILE,
    SUMMARY_FILE,
];

/// Environment presets accepted by `--env`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum EnvName {
    /// Thesis Sec 5.1 as written (S, A = [−2, 2], r = −0.5(s² + a²)).
    Lqg,
    /// The 1-D LQG behind the thesis's numbers (S, A = [−4, 4], r = −0.9(s² + a²)).
    Lqg1d,
    /// Gymnasium's MountainCarContinuous-v0.
    MountainCar,
}

impl EnvName {
    /// The registry name.
    pub fn name(self) -> &'static str {
        match self {
            EnvName::Lqg => "lqg",
            EnvName::Lqg1d => "lqg1d",
            EnvName::MountainCar => "mountain-car",
        }
    }
}

/// Algorithms accepted by `--algo`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum AlgoName {
    /// SEPG, monotonic improvement.
    SepgMi,
    /// SEPG, lower-bounded I (split ν).
    SepgLb1,
    /// SEPG, lower-bounded II (budget).
    SepgLb2,
    /// SEPG, low-variance target.
    SepgLv,
    /// SEPG, zero-variance (deterministic) target.
    SepgZv,
    /// SEPG with simultaneous updates from one batch (budget split ν).
    SepgSim,
    /// SEPG with the naive variance update along ∇_w J (eq. 4.12).
    SepgNaiveW,
    /// G(PO)MDP with constant steps α, β.
    GpomdpConst,
    /// G(PO)MDP with Adam.
    GpomdpAdam,
    /// The adaptive step of Pirotta et al. with fixed σ.
    Adastep,
}

/// Safety requirements accepted by `--requirement` (the requirement of `sepg-naive-w`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum RequirementName {
    /// Monotonic improvement.
    Mi,
    /// Lower-bounded I.
    Lb1,
    /// Lower-bounded II.
    Lb2,
    /// Low variance.
    Lv,
    /// Zero variance.
    Zv,
    /// Simultaneous updates.
    Sim,
}

/// Gradient modes accepted by `--gradients`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum GradientsName {
    /// Oracle J and gradients (LQG only).
    Exact,
    /// Monte Carlo estimates with confidence level δ.
    Sampled,
}

/// Estimators accepted by `--estimator`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum EstimatorName {
    /// G(PO)MDP.
    Gpomdp,
    /// REINFORCE.
    Reinforce,
    /// PGT (reward-to-go order).
    Pgt,
}

/// Baselines accepted by `--baseline`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum BaselineName {
    /// No baseline.
    None,
    /// Mean baseline.
    Mean,
    /// Variance-optimal baseline.
    Optimal,
}

/// Baseline fits accepted by `--baseline-fit`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum FitName {
    /// Each trajectory's baseline is fitted on the others (unbiased).
    LeaveOneOut,
    /// One baseline from the whole batch.
    PlugIn,
}

/// One value broadcast to every component, or one value per component.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Values {
    /// The same value for every component.
    One(f64),
    /// One value per component.
    Many(Vec<f64>),
}

impl Values {
    fn expand(&self, dim: usize, what: &str) -> Result<Vec<f64>, CliError> {
        match self {
            Values::One(x) => Ok(vec![*x; dim]),
            Values::Many(v) if v.len() == 1 => Ok(vec![v[0]; dim]),
            Values::Many(v) if v.len() == dim => Ok(v.clone()),
            Values::Many(v) => Err(CliError::usage(format!(
                "{what} has {} values, the environment needs 1 or {dim}",
                v.len()
            ))),
        }
    }
}

impl<'de> Deserialize<'de> for Values {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            One(f64),
            Many(Vec<f64>),
        }
        match Raw::deserialize(d) {
            Ok(Raw::One(x)) => Ok(Values::One(x)),
            Ok(Raw::Many(v)) => Ok(Values::Many(v)),
            Err(_) => Err(serde::de::Error::custom(
                "expected a number or an array of numbers",
            )),
        }
    }
}

fn parse_values(s: &str) -> Result<Values, String> {
    let v: Result<Vec<f64>, _> = s.split(',').map(|x| x.trim().parse::<f64>()).collect();
    match v {
        Ok(v) if v.len() == 1 => Ok(Values::One(v[0])),
        Ok(v) => Ok(Values::Many(v)),
        Err(e) => Err(format!(
            "{s:?} is not a comma-separated list of numbers: {e}"
        )),
    }
}

/// Every option of a run, as flags of `sepg run` and as keys of a TOML file (the same names).
/// Absent options take the defaults of SPEC §6; a resolved configuration has every option
/// that applies to its algorithm set and no other.
#[derive(Debug, Clone, Default, PartialEq, Args, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct RunSpec {
    /// A label for the run (used in legends). Default: the algorithm's name.
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Environment [default: lqg].
    #[arg(long, value_enum)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub env: Option<EnvName>,
    /// Mountain Car features: `state-bias` (default) or `rbf:KxV` (a K×V grid plus bias).
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub features: Option<String>,
    /// Algorithm [default: sepg-zv].
    #[arg(long, value_enum)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub algo: Option<AlgoName>,
    /// Safety requirement of sepg-naive-w [default: zv].
    #[arg(long, value_enum)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub requirement: Option<RequirementName>,
    /// Exact (oracle) or sampled gradients [default: sampled].
    #[arg(long, value_enum)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gradients: Option<GradientsName>,
    /// Confidence δ ∈ (0, 1) of the sampled mode [default: 0.2].
    #[arg(long, allow_hyphen_values = true)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub delta: Option<f64>,
    /// Split ν ∈ [0, 1] of LB-I (share of C for w) and SIM (share of B for v) [default: 0.5].
    #[arg(long, allow_hyphen_values = true)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub nu: Option<f64>,
    /// Initial mean parameters v⁰: one value for all, or comma-separated [default: -0.1].
    #[arg(long, allow_hyphen_values = true, value_parser = parse_values)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub v0: Option<Values>,
    /// Initial standard deviations σ⁰ > 0: one value for all, or comma-separated [default: 1].
    #[arg(long, allow_hyphen_values = true, value_parser = parse_values)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sigma0: Option<Values>,
    /// Initial budget B⁰ ≥ 0 [default: 0; 1 for mountain-car].
    #[arg(long, allow_hyphen_values = true)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub budget0: Option<f64>,
    /// Step size α of v (gpomdp-const).
    #[arg(long, allow_hyphen_values = true)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alpha: Option<f64>,
    /// Step size β of w (gpomdp-const) [default: α].
    #[arg(long, allow_hyphen_values = true)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub beta: Option<f64>,
    /// Learning rate of v (gpomdp-adam).
    #[arg(long, allow_hyphen_values = true)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lr: Option<f64>,
    /// Learning rate of w (gpomdp-adam) [default: lr].
    #[arg(long = "lr-w", allow_hyphen_values = true)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lr_w: Option<f64>,
    /// Trajectories per iteration N [default: 100].
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub batch: Option<usize>,
    /// Horizon H [default: 20; 999 for mountain-car].
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub horizon: Option<usize>,
    /// Iterations [default: 10000].
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub iterations: Option<u64>,
    /// Seed [default: 0].
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// Gradient estimator of the sampled mode [default: gpomdp].
    #[arg(long, value_enum)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub estimator: Option<EstimatorName>,
    /// Baseline of the estimator [default: optimal].
    #[arg(long, value_enum)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub baseline: Option<BaselineName>,
    /// How the baseline is fitted [default: leave-one-out].
    #[arg(long = "baseline-fit", value_enum)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub baseline_fit: Option<FitName>,
    /// Write every k-th iteration to the log (and always the last) [default: 1].
    #[arg(long = "log-every")]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub log_every: Option<u64>,
    /// Version of sepg that resolved the configuration (written by sepg; checked on resume).
    #[arg(skip)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sepg_version: Option<String>,
}

macro_rules! overlay_fields {
    ($base:ident, $top:ident; $($f:ident),*) => {
        RunSpec { $($f: $top.$f.clone().or_else(|| $base.$f.clone()),)* }
    };
}

impl RunSpec {
    /// This specification with every option set in `top` replacing the same option here.
    pub fn overlay(&self, top: &RunSpec) -> RunSpec {
        let base = self;
        overlay_fields!(base, top; name, env, features, algo, requirement, gradients, delta, nu,
            v0, sigma0, budget0, alpha, beta, lr, lr_w, batch, horizon, iterations, seed,
            estimator, baseline, baseline_fit, log_every, sepg_version)
    }

    /// Reads a TOML file of options; unknown keys are rejected.
    ///
    /// # Errors
    /// Usage error for a missing or unreadable file or an invalid key or value.
    pub fn from_file(path: &Path) -> Result<RunSpec, CliError> {
        let text = fs::read_to_string(path)
            .map_err(|e| CliError::usage(format!("cannot read {}: {e}", path.display())))?;
        toml::from_str(&text)
            .map_err(|e| CliError::usage(format!("{}: {}", path.display(), toml_message(&e))))
    }

    /// Resolves every default, validates the configuration (the checks of
    /// [`SepgConfig::check`] plus the options that do not apply to the algorithm) and builds
    /// the algorithm's configuration.
    ///
    /// # Errors
    /// Usage error for any invalid or inapplicable option.
    pub fn resolve(&self) -> Result<Resolved, CliError> {
        let env_name = self.env.unwrap_or(EnvName::Lqg);
        let algo = self.algo.unwrap_or(AlgoName::SepgZv);
        let gradients = self.gradients.unwrap_or(GradientsName::Sampled);
        let reject = |set: bool, what: &str, why: &str| {
            if set {
                Err(CliError::usage(format!(
                    "option {what} does not apply {why}"
                )))
            } else {
                Ok(())
            }
        };
        let algo_str = algo
            .to_possible_value()
            .map(|v| v.get_name().to_owned())
            .unwrap_or_default();
        let for_algo = format!("to algorithm {algo_str}");
        let env = build_env(env_name, self.features.as_deref())?;
        let features = match env_name {
            EnvName::MountainCar => {
                Some(self.features.clone().unwrap_or_else(|| "state-bias".into()))
            }
            _ => {
                reject(self.features.is_some(), "features", "to LQG environments")?;
                None
            }
        };
        let uses_nu = matches!(algo, AlgoName::SepgLb1 | AlgoName::SepgSim)
            || (algo == AlgoName::SepgNaiveW
                && matches!(
                    self.requirement,
                    Some(RequirementName::Lb1 | RequirementName::Sim)
                ));
        reject(!uses_nu && self.nu.is_some(), "nu", &for_algo)?;
        reject(
            algo != AlgoName::SepgNaiveW && self.requirement.is_some(),
            "requirement",
            &for_algo,
        )?;
        let is_const = algo == AlgoName::GpomdpConst;
        let is_adam = algo == AlgoName::GpomdpAdam;
        reject(
            !is_const && (self.alpha.is_some() || self.beta.is_some()),
            "alpha/beta",
            &for_algo,
        )?;
        reject(
            !is_adam && (self.lr.is_some() || self.lr_w.is_some()),
            "lr/lr-w",
            &for_algo,
        )?;
        let exact = gradients == GradientsName::Exact;
        reject(exact && self.delta.is_some(), "delta", "to exact gradients")?;
        reject(
            exact
                && (self.estimator.is_some()
                    || self.baseline.is_some()
                    || self.baseline_fit.is_some()),
            "estimator/baseline/baseline-fit",
            "to exact gradients",
        )?;
        let nu = uses_nu.then(|| self.nu.unwrap_or(0.5));
        let requirement =
            (algo == AlgoName::SepgNaiveW).then(|| self.requirement.unwrap_or(RequirementName::Zv));
        let req_of = |r: RequirementName| match r {
            RequirementName::Mi => Requirement::Mi,
            RequirementName::Lb1 => Requirement::LbI {
                nu: nu.unwrap_or(0.5),
            },
            RequirementName::Lb2 => Requirement::LbII,
            RequirementName::Lv => Requirement::Lv,
            RequirementName::Zv => Requirement::Zv,
            RequirementName::Sim => Requirement::Sim {
                nu: nu.unwrap_or(0.5),
            },
        };
        let need = |v: Option<f64>, flag: &str| {
            v.ok_or_else(|| CliError::usage(format!("algorithm {algo_str} needs --{flag}")))
        };
        let (alpha, beta, lr, lr_w) = match algo {
            AlgoName::GpomdpConst => {
                let a = need(self.alpha, "alpha")?;
                (Some(a), Some(self.beta.unwrap_or(a)), None, None)
            }
            AlgoName::GpomdpAdam => {
                let l = need(self.lr, "lr")?;
                (None, None, Some(l), Some(self.lr_w.unwrap_or(l)))
            }
            _ => (None, None, None, None),
        };
        let algorithm = match algo {
            AlgoName::SepgMi => Algorithm::Sepg(Requirement::Mi),
            AlgoName::SepgLb1 => Algorithm::Sepg(req_of(RequirementName::Lb1)),
            AlgoName::SepgLb2 => Algorithm::Sepg(Requirement::LbII),
            AlgoName::SepgLv => Algorithm::Sepg(Requirement::Lv),
            AlgoName::SepgZv => Algorithm::Sepg(Requirement::Zv),
            AlgoName::SepgSim => Algorithm::Sepg(req_of(RequirementName::Sim)),
            AlgoName::SepgNaiveW => {
                Algorithm::SepgNaiveW(req_of(requirement.unwrap_or(RequirementName::Zv)))
            }
            AlgoName::GpomdpConst => Algorithm::GpomdpConst {
                alpha: alpha.unwrap_or(0.0),
                beta: beta.unwrap_or(0.0),
            },
            AlgoName::GpomdpAdam => Algorithm::adam(lr.unwrap_or(0.0), lr_w.unwrap_or(0.0)),
            AlgoName::Adastep => Algorithm::AdaStep,
        };
        let delta = (!exact).then(|| self.delta.unwrap_or(0.2));
        let gradient = match delta {
            Some(delta) => GradientMode::Sampled { delta },
            None => GradientMode::Exact,
        };
        let estimator = (!exact).then(|| {
            (
                self.estimator.unwrap_or(EstimatorName::Gpomdp),
                self.baseline.unwrap_or(BaselineName::Optimal),
                self.baseline_fit.unwrap_or(FitName::LeaveOneOut),
            )
        });
        let spec_est = estimator.map_or_else(GradientSpec::default, |(k, b, f)| GradientSpec {
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
        });
        let dim_w = env.action_dim();
        let dim_v = dim_w * env.feature_dim();
        let v0 = self
            .v0
            .clone()
            .unwrap_or(Values::One(-0.1))
            .expand(dim_v, "v0")?;
        let sigma0 = self
            .sigma0
            .clone()
            .unwrap_or(Values::One(1.0))
            .expand(dim_w, "sigma0")?;
        let budget0 = self.budget0.unwrap_or(if env_name == EnvName::MountainCar {
            1.0
        } else {
            0.0
        });
        let batch = self.batch.unwrap_or(100);
        if batch < 2 {
            return Err(CliError::usage(format!(
                "batch N = {batch} must be at least 2"
            )));
        }
        let horizon = self.horizon.unwrap_or(env.constants().horizon);
        let iterations = self.iterations.unwrap_or(10_000);
        let seed = self.seed.unwrap_or(0);
        let log_every = self.log_every.unwrap_or(1);
        if log_every == 0 {
            return Err(CliError::usage("log-every must be at least 1"));
        }
        let config = SepgConfig {
            env,
            algorithm,
            gradient,
            estimator: spec_est,
            v0: v0.clone(),
            sigma0: sigma0.clone(),
            n_trajectories: batch,
            horizon,
            iterations,
            seed,
            initial_budget: budget0,
        };
        let checked = config
            .check()
            .map_err(|e| CliError::usage(format!("invalid configuration: {e}")))?;
        let one_or_many = |v: Vec<f64>| {
            if v.len() == 1 {
                Values::One(v[0])
            } else {
                Values::Many(v)
            }
        };
        let spec = RunSpec {
            name: Some(self.name.clone().unwrap_or_else(|| algo_str.clone())),
            env: Some(env_name),
            features,
            algo: Some(algo),
            requirement,
            gradients: Some(gradients),
            delta,
            nu,
            v0: Some(one_or_many(v0)),
            sigma0: Some(one_or_many(sigma0)),
            budget0: Some(budget0),
            alpha,
            beta,
            lr,
            lr_w,
            batch: Some(batch),
            horizon: Some(horizon),
            iterations: Some(iterations),
            seed: Some(seed),
            estimator: estimator.map(|e| e.0),
            baseline: estimator.map(|e| e.1),
            baseline_fit: estimator.map(|e| e.2),
            log_every: Some(log_every),
            sepg_version: Some(
                self.sepg_version
                    .clone()
                    .unwrap_or_else(|| VERSION.to_owned()),
            ),
        };
        Ok(Resolved {
            spec,
            checked,
            dims: (dim_v, dim_w),
        })
    }
}

/// The first line of a TOML error, without the source excerpt.
pub fn toml_message(e: &toml::de::Error) -> String {
    let msg = e.message().trim().to_owned();
    match e.span() {
        Some(span) => format!("{msg} (at byte {})", span.start),
        None => msg,
    }
}

fn build_env(name: EnvName, features: Option<&str>) -> Result<AnyEnv, CliError> {
    Ok(match name {
        EnvName::Lqg => AnyEnv::Lqg(Box::new(LqgEnv::thesis())),
        EnvName::Lqg1d => AnyEnv::Lqg(Box::new(LqgEnv::lqg1d())),
        EnvName::MountainCar => AnyEnv::MountainCar(match features.unwrap_or("state-bias") {
            "state-bias" => MountainCar::state_bias(),
            f => {
                let bad =
                    || CliError::usage(format!("features {f:?}: expected state-bias or rbf:KxV"));
                let grid = f.strip_prefix("rbf:").ok_or_else(bad)?;
                let (k, v) = grid.split_once('x').ok_or_else(bad)?;
                let k: usize = k.parse().map_err(|_| bad())?;
                let v: usize = v.parse().map_err(|_| bad())?;
                MountainCar::rbf([k, v], true)
                    .map_err(|e| CliError::usage(format!("features {f:?}: {e}")))?
            }
        }),
    })
}

/// A fully resolved and validated run configuration.
#[derive(Debug, Clone)]
pub struct Resolved {
    /// Every option that applies, with its value (what `config.toml` holds).
    pub spec: RunSpec,
    /// The validated configuration of the algorithm.
    pub checked: CheckedConfig,
    /// Number of mean parameters and of standard deviations.
    pub dims: (usize, usize),
}

impl Resolved {
    /// The resolved configuration as TOML text.
    ///
    /// # Errors
    /// Failure if serialisation fails.
    pub fn toml(&self) -> Result<String, CliError> {
        toml::to_string(&self.spec)
            .map_err(|e| CliError::failure(format!("cannot serialise the configuration: {e}")))
    }

    /// v* of the LQG environments (the unclipped infinite-horizon optimum, SPEC §1), `None`
    /// for other environments.
    pub fn v_star(&self) -> Option<Vec<f64>> {
        match &self.checked.config().env {
            AnyEnv::Lqg(e) => ClosedFormOracle::new(e.model())
                .ok()?
                .optimal_gain()
                .ok()
                .map(|g| g.v),
            AnyEnv::MountainCar(_) => None,
        }
    }

    /// Number of iterations of the run.
    pub fn iterations(&self) -> u64 {
        self.checked.config().iterations
    }

    /// Row stride of the log.
    pub fn log_every(&self) -> u64 {
        self.spec.log_every.unwrap_or(1)
    }
}

fn indexed(name: &str, dim: usize) -> Vec<String> {
    if dim == 1 {
        vec![name.to_owned()]
    } else {
        (0..dim).map(|i| format!("{name}_{i}")).collect()
    }
}

/// The header of `log.csv` for `dim_v` mean parameters and `dim_w` standard deviations.
///
/// Columns: `iteration`, `v` (or `v_0, v_1, …`), `w`, `sigma`, `j_explore`, `j_after_v`,
/// `j_target`, `w_target`, `budget`, `required`, `required_w`, `alpha`, `beta`, `lambda_v`,
/// `lambda_w`, `guaranteed_v`, `guaranteed_w`, `infeasible`, `infeasible_v`, `infeasible_w`,
/// `below_noise_v`, `below_noise_w`, `trajectories`, `steps`.
pub fn log_header(dim_v: usize, dim_w: usize) -> String {
    let mut cols = vec!["iteration".to_owned()];
    cols.extend(indexed("v", dim_v));
    cols.extend(indexed("w", dim_w));
    cols.extend(indexed("sigma", dim_w));
    cols.extend(["j_explore", "j_after_v", "j_target"].map(String::from));
    cols.extend(indexed("w_target", dim_w));
    cols.extend(
        [
            "budget",
            "required",
            "required_w",
            "alpha",
            "beta",
            "lambda_v",
            "lambda_w",
            "guaranteed_v",
            "guaranteed_w",
            "infeasible",
            "infeasible_v",
            "infeasible_w",
            "below_noise_v",
            "below_noise_w",
            "trajectories",
            "steps",
        ]
        .map(String::from),
    );
    let mut s = cols.join(",");
    s.push('\n');
    s
}

fn num(x: f64) -> String {
    format!("{x:?}")
}

fn opt(x: Option<f64>) -> String {
    x.map(num).unwrap_or_default()
}

/// One row of `log.csv` for `record` (shortest round-trip decimal; empty for "not
/// applicable"; `-inf` for the deterministic target's `w_target`; booleans as 0/1).
pub fn log_row(r: &Record) -> String {
    let mut cells = vec![r.iteration.to_string()];
    cells.extend(r.v.iter().copied().map(num));
    cells.extend(r.w.iter().copied().map(num));
    cells.extend(r.sigma.iter().copied().map(num));
    cells.extend([num(r.j_exploratory), opt(r.j_after_v), num(r.j_target)]);
    match &r.w_target {
        Some(w) => cells.extend(w.iter().copied().map(num)),
        None => cells.extend(r.w.iter().map(|_| num(f64::NEG_INFINITY))),
    }
    let b = |x: bool| if x { "1".to_owned() } else { "0".to_owned() };
    cells.extend([
        num(r.budget),
        opt(r.required_v),
        opt(r.required_w),
        num(r.alpha),
        num(r.beta),
        opt(r.lambda_v),
        opt(r.lambda_w),
        opt(r.guaranteed_v),
        opt(r.guaranteed_w),
        b(r.infeasible_v || r.infeasible_w),
        b(r.infeasible_v),
        b(r.infeasible_w),
        b(r.below_noise_v),
        b(r.below_noise_w),
        r.trajectories.to_string(),
        r.steps.to_string(),
    ]);
    let mut s = cells.join(",");
    s.push('\n');
    s
}

/// Counters over the whole run, carried in the checkpoint so that a resumed run reports the
/// same totals.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Tally {
    /// Iterations whose v- or w-requirement was infeasible (λ = 0 fallback).
    pub infeasible: u64,
    /// Iterations whose v-gradient was below its noise level.
    pub below_noise_v: u64,
    /// Iterations whose w-direction was below its noise level.
    pub below_noise_w: u64,
    /// J of the exploratory policy at the last iteration.
    pub last_j_explore: Option<f64>,
    /// J of the target policy at the last iteration.
    pub last_j_target: Option<f64>,
}

impl Tally {
    fn add(&mut self, r: &Record) {
        self.infeasible += u64::from(r.infeasible_v || r.infeasible_w);
        self.below_noise_v += u64::from(r.below_noise_v);
        self.below_noise_w += u64::from(r.below_noise_w);
        self.last_j_explore = Some(r.j_exploratory);
        self.last_j_target = Some(r.j_target);
    }
}

/// The checkpoint file: the state after `state.iteration` iterations and the length of the
/// log that holds exactly the rows of those iterations.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Checkpoint {
    /// Bytes of the log (header included) written up to this checkpoint.
    pub log_bytes: u64,
    /// Wall time spent in iterations so far, in seconds.
    pub elapsed_s: f64,
    /// Counters so far.
    pub tally: Tally,
    /// The algorithm's state (resumable bit for bit).
    pub state: State,
}

/// Final parameters of a run.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FinalParams {
    /// Mean parameters v.
    pub v: Vec<f64>,
    /// Log standard deviations w.
    pub w: Vec<f64>,
    /// Standard deviations σ = e^w.
    pub sigma: Vec<f64>,
    /// Budget B.
    pub budget: f64,
}

/// `summary.json`: written last, its presence marks a complete run.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Summary {
    /// Always `"complete"`.
    pub status: String,
    /// Label of the run.
    pub name: String,
    /// Version of sepg that ran it.
    pub sepg_version: String,
    /// Iterations run.
    pub iterations: u64,
    /// Parameters after the last iteration.
    #[serde(rename = "final")]
    pub final_params: FinalParams,
    /// v* (LQG only).
    pub v_star: Option<Vec<f64>>,
    /// max_i |v_i − v*_i| after the last iteration (LQG only).
    pub abs_v_error: Option<f64>,
    /// J of the exploratory policy at the last iteration.
    pub last_j_explore: Option<f64>,
    /// J of the target policy at the last iteration.
    pub last_j_target: Option<f64>,
    /// Iterations with an infeasible requirement.
    pub infeasible_iterations: u64,
    /// Iterations without a v-update (gradient below noise).
    pub below_noise_v_iterations: u64,
    /// Iterations without a w-update (direction below noise).
    pub below_noise_w_iterations: u64,
    /// Trajectories used.
    pub trajectories: u64,
    /// Environment steps used.
    pub steps: u64,
    /// Wall time spent iterating, in seconds (summed over resumed segments).
    pub wall_time_s: f64,
    /// Iterations per second of wall time.
    pub iterations_per_s: f64,
    /// Environment steps per second of wall time.
    pub env_steps_per_s: f64,
}

/// Set by SIGINT: every running loop stops after its current iteration and checkpoints.
static STOP: AtomicBool = AtomicBool::new(false);

/// Installs the SIGINT handler (once per process).
pub fn install_interrupt_handler() {
    static ONCE: OnceLock<()> = OnceLock::new();
    ONCE.get_or_init(|| {
        // Without a handler (e.g. one is already installed) Ctrl-C keeps its default
        // action; the checkpoints still leave the folder consistent.
        let _ = ctrlc::set_handler(|| STOP.store(true, Ordering::SeqCst));
    });
}

/// Whether an interrupt was requested.
pub fn interrupted() -> bool {
    STOP.load(Ordering::SeqCst)
}

/// How the engine runs: checkpoint period and progress display.
#[derive(Debug, Clone, Copy)]
pub struct RunOptions {
    /// Iterations between checkpoints.
    pub checkpoint_every: u64,
    /// Show a progress bar on standard error (only if it is a terminal).
    pub progress: bool,
}

fn io_fail(what: &str, path: &Path, e: std::io::Error) -> CliError {
    CliError::failure(format!("cannot {what} {}: {e}", path.display()))
}

/// Checks that `dir` is absent or empty; with `force`, removes the run files a previous run
/// left there (and only those).
///
/// # Errors
/// Usage error for a non-empty folder without `force`, or a path that is not a folder.
pub fn check_out_dir(dir: &Path, force: bool, files: &[&str]) -> Result<(), CliError> {
    if !dir.exists() {
        return Ok(());
    }
    if !dir.is_dir() {
        return Err(CliError::usage(format!(
            "{} exists and is not a folder",
            dir.display()
        )));
    }
    let mut entries = fs::read_dir(dir)
        .map_err(|e| CliError::usage(format!("cannot read {}: {e}", dir.display())))?;
    if entries.next().is_some() && !force {
        return Err(CliError::usage(format!(
            "output folder {} is not empty (use --force to overwrite its run files)",
            dir.display()
        )));
    }
    for f in files {
        let p = dir.join(f);
        if p.is_dir() {
            fs::remove_dir_all(&p).map_err(|e| io_fail("remove", &p, e))?;
        } else if p.exists() {
            fs::remove_file(&p).map_err(|e| io_fail("remove", &p, e))?;
        }
    }
    Ok(())
}

/// Whether `dir` holds a complete run.
pub fn is_complete(dir: &Path) -> bool {
    dir.join(SUMMARY_FILE).is_file()
}

/// Reads and resolves the configuration of the run folder `dir`.
///
/// # Errors
/// Usage error for a missing or invalid configuration or one written by another sepg version.
pub fn load_resolved(dir: &Path) -> Result<Resolved, CliError> {
    let path = dir.join(CONFIG_FILE);
    if !path.is_file() {
        return Err(CliError::usage(format!(
            "{} is not a run folder (no {CONFIG_FILE})",
            dir.display()
        )));
    }
    let spec = RunSpec::from_file(&path)?;
    if let Some(v) = &spec.sepg_version
        && v != VERSION
    {
        return Err(CliError::usage(format!(
            "{} was written by sepg {v}; this is sepg {VERSION}, which may not reproduce it bit for bit",
            path.display()
        )));
    }
    spec.resolve()
}

/// Starts a new run of `resolved` in `dir` (created if needed; the caller has checked it is
/// empty) and runs it to completion.
///
/// # Errors
/// Failure for I/O errors, a failing iteration, or an interrupt (after checkpointing).
pub fn start(dir: &Path, resolved: &Resolved, opts: RunOptions) -> Result<Summary, CliError> {
    fs::create_dir_all(dir).map_err(|e| io_fail("create", dir, e))?;
    let header = log_header(resolved.dims.0, resolved.dims.1);
    write_atomic(&dir.join(PARTIAL_LOG_FILE), header.as_bytes())?;
    let ck = Checkpoint {
        log_bytes: header.len() as u64,
        elapsed_s: 0.0,
        tally: Tally::default(),
        state: resolved.checked.initial_state(),
    };
    write_atomic(&dir.join(CHECKPOINT_FILE), to_json_line(&ck)?.as_bytes())?;
    // The configuration goes last: a folder with a config.toml always has a checkpoint.
    write_atomic(&dir.join(CONFIG_FILE), resolved.toml()?.as_bytes())?;
    drive(dir, resolved, ck, opts)
}

/// Resumes the run in `dir` from its checkpoint and runs it to completion; a complete run is
/// returned as is.
///
/// # Errors
/// Usage error when `dir` is not a resumable run folder; otherwise as [`start`].
pub fn resume(dir: &Path, opts: RunOptions) -> Result<Summary, CliError> {
    let resolved = load_resolved(dir)?;
    if is_complete(dir) {
        return read_summary(dir);
    }
    let ck_path = dir.join(CHECKPOINT_FILE);
    let text = fs::read_to_string(&ck_path)
        .map_err(|e| CliError::usage(format!("cannot read {}: {e}", ck_path.display())))?;
    let ck: Checkpoint = serde_json::from_str(&text).map_err(|e| {
        CliError::usage(format!(
            "{} is not a valid checkpoint: {e}",
            ck_path.display()
        ))
    })?;
    let partial = dir.join(PARTIAL_LOG_FILE);
    let finished = dir.join(LOG_FILE);
    if !partial.exists() && finished.is_file() && ck.state.iteration == resolved.iterations() {
        // Killed between the final rename and the summary: only the summary is missing.
        return finish(dir, &resolved, &ck);
    }
    let file = OpenOptions::new()
        .write(true)
        .open(&partial)
        .map_err(|e| CliError::usage(format!("cannot open {}: {e}", partial.display())))?;
    let len = file
        .metadata()
        .map_err(|e| io_fail("read", &partial, e))?
        .len();
    if len < ck.log_bytes {
        return Err(CliError::usage(format!(
            "{} is shorter ({len} bytes) than its checkpoint says ({} bytes)",
            partial.display(),
            ck.log_bytes
        )));
    }
    file.set_len(ck.log_bytes)
        .map_err(|e| io_fail("truncate", &partial, e))?;
    file.sync_all().map_err(|e| io_fail("sync", &partial, e))?;
    drive(dir, &resolved, ck, opts)
}

fn read_summary(dir: &Path) -> Result<Summary, CliError> {
    let p = dir.join(SUMMARY_FILE);
    let text = fs::read_to_string(&p).map_err(|e| io_fail("read", &p, e))?;
    serde_json::from_str(&text)
        .map_err(|e| CliError::failure(format!("{} is invalid: {e}", p.display())))
}

fn progress_bar(total: u64, done: u64, show: bool) -> ProgressBar {
    if !(show && std::io::stderr().is_terminal()) {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new(total);
    if let Ok(style) = ProgressStyle::with_template("{bar:40} {pos}/{len} it  {per_sec}  eta {eta}")
    {
        pb.set_style(style);
    }
    pb.set_position(done);
    pb
}

fn drive(
    dir: &Path,
    resolved: &Resolved,
    mut ck: Checkpoint,
    opts: RunOptions,
) -> Result<Summary, CliError> {
    let total = resolved.iterations();
    let every = resolved.log_every();
    let partial = dir.join(PARTIAL_LOG_FILE);
    let mut log = OpenOptions::new()
        .append(true)
        .open(&partial)
        .map_err(|e| io_fail("open", &partial, e))?;
    let mut solver = PolicySolver::new(&resolved.checked)
        .map_err(|e| CliError::usage(format!("invalid configuration: {e}")))?;
    let mut state = ck.state.clone();
    if state.iteration == 0 {
        solver
            .init(&mut state)
            .map_err(|e| CliError::failure(e.to_string()))?;
    }
    let pb = progress_bar(total, state.iteration, opts.progress);
    let mut chunk = String::new();
    let mut tally = ck.tally.clone();
    let mut segment = Instant::now();
    let period = opts.checkpoint_every.max(1);
    while state.iteration < total {
        let record = match solver.next_iter(&mut state) {
            Ok(r) => r,
            Err(e) => {
                pb.finish_and_clear();
                return Err(CliError::failure(format!("{}: {e}", dir.display())));
            }
        };
        tally.add(&record);
        if record.iteration.is_multiple_of(every) || state.iteration == total {
            chunk.push_str(&log_row(&record));
        }
        pb.set_position(state.iteration);
        let stop = interrupted();
        if state.iteration.is_multiple_of(period) || state.iteration == total || stop {
            log.write_all(chunk.as_bytes())
                .and_then(|()| log.sync_data())
                .map_err(|e| io_fail("write", &partial, e))?;
            ck = Checkpoint {
                log_bytes: ck.log_bytes + chunk.len() as u64,
                elapsed_s: ck.elapsed_s + segment.elapsed().as_secs_f64(),
                tally: tally.clone(),
                state: state.clone(),
            };
            segment = Instant::now();
            chunk.clear();
            write_atomic(&dir.join(CHECKPOINT_FILE), to_json_line(&ck)?.as_bytes())?;
            if stop && state.iteration < total {
                pb.finish_and_clear();
                return Err(CliError::failure(format!(
                    "interrupted after iteration {} of {total}; resume with: sepg run --resume {}",
                    state.iteration,
                    dir.display()
                )));
            }
        }
    }
    pb.finish_and_clear();
    drop(log);
    fs::rename(&partial, dir.join(LOG_FILE)).map_err(|e| io_fail("rename", &partial, e))?;
    finish(dir, resolved, &ck)
}

fn finish(dir: &Path, resolved: &Resolved, ck: &Checkpoint) -> Result<Summary, CliError> {
    let s = &ck.state;
    let v_star = resolved.v_star();
    let abs_v_error = v_star.as_ref().map(|vs| {
        s.v.iter()
            .zip(vs)
            .fold(0.0_f64, |m, (v, vs)| m.max((v - vs).abs()))
    });
    let wall = ck.elapsed_s;
    let rate = |x: f64| if wall > 0.0 { x / wall } else { 0.0 };
    let summary = Summary {
        status: "complete".into(),
        name: resolved.spec.name.clone().unwrap_or_default(),
        sepg_version: VERSION.into(),
        iterations: s.iteration,
        final_params: FinalParams {
            v: s.v.clone(),
            w: s.w.clone(),
            sigma: s.sigma(),
            budget: s.budget,
        },
        v_star,
        abs_v_error,
        last_j_explore: ck.tally.last_j_explore,
        last_j_target: ck.tally.last_j_target,
        infeasible_iterations: ck.tally.infeasible,
        below_noise_v_iterations: ck.tally.below_noise_v,
        below_noise_w_iterations: ck.tally.below_noise_w,
        trajectories: s.trajectories,
        steps: s.steps,
        wall_time_s: wall,
        iterations_per_s: rate(s.iteration as f64),
        env_steps_per_s: rate(s.steps as f64),
    };
    write_atomic(&dir.join(SUMMARY_FILE), to_json_line(&summary)?.as_bytes())?;
    Ok(summary)
}

/// A log read back from disk: column names and one row of numbers per logged iteration
/// (empty cells read as NaN).
#[derive(Debug, Clone, PartialEq)]
pub struct Log {
    /// Column names.
    pub columns: Vec<String>,
    /// Rows of values.
    pub rows: Vec<Vec<f64>>,
}

impl Log {
    /// Reads `log.csv` of a complete run, or the checkpointed prefix of `log.partial.csv`.
    ///
    /// # Errors
    /// Usage error when no log can be read.
    pub fn read_run(dir: &Path) -> Result<Log, CliError> {
        let done = dir.join(LOG_FILE);
        let bytes = if done.is_file() {
            fs::read(&done)
                .map_err(|e| CliError::usage(format!("cannot read {}: {e}", done.display())))?
        } else {
            let partial = dir.join(PARTIAL_LOG_FILE);
            let mut b = fs::read(&partial)
                .map_err(|e| CliError::usage(format!("no log in {}: {e}", dir.display())))?;
            let ck: Option<Checkpoint> = fs::read_to_string(dir.join(CHECKPOINT_FILE))
                .ok()
                .and_then(|t| serde_json::from_str(&t).ok());
            if let Some(ck) = ck {
                b.truncate(
                    usize::try_from(ck.log_bytes)
                        .unwrap_or(usize::MAX)
                        .min(b.len()),
                );
            }
            b
        };
        let text = String::from_utf8_lossy(&bytes);
        let mut lines = text.lines();
        let columns: Vec<String> = lines
            .next()
            .ok_or_else(|| CliError::usage(format!("empty log in {}", dir.display())))?
            .split(',')
            .map(String::from)
            .collect();
        let rows = lines
            .filter(|l| l.split(',').count() == columns.len())
            .map(|l| {
                l.split(',')
                    .map(|c| c.parse::<f64>().unwrap_or(f64::NAN))
                    .collect()
            })
            .collect();
        Ok(Log { columns, rows })
    }

    /// The values of column `name` (or its first component `name_0`), if present.
    pub fn column(&self, name: &str) -> Option<Vec<f64>> {
        let idx = self
            .columns
            .iter()
            .position(|c| c == name)
            .or_else(|| self.columns.iter().position(|c| *c == format!("{name}_0")))?;
        Some(self.rows.iter().map(|r| r[idx]).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolving_a_resolved_configuration_changes_nothing() {
        let spec = RunSpec {
            env: Some(EnvName::Lqg1d),
            algo: Some(AlgoName::GpomdpAdam),
            lr: Some(1e-5),
            sigma0: Some(Values::One(0.1)),
            ..RunSpec::default()
        };
        let once = spec.resolve().expect("valid");
        let text = once.toml().expect("toml");
        let again: RunSpec = toml::from_str(&text).expect("parse");
        let twice = again.resolve().expect("valid");
        assert_eq!(once.spec, twice.spec);
        assert_eq!(once.checked, twice.checked);
        assert_eq!(twice.spec.lr_w, Some(1e-5));
    }

    #[test]
    fn inapplicable_options_are_rejected() {
        let spec = RunSpec {
            algo: Some(AlgoName::SepgZv),
            alpha: Some(0.1),
            ..RunSpec::default()
        };
        assert!(spec.resolve().is_err());
        let spec = RunSpec {
            gradients: Some(GradientsName::Exact),
            delta: Some(0.1),
            ..RunSpec::default()
        };
        assert!(spec.resolve().is_err());
        let spec = RunSpec {
            algo: Some(AlgoName::GpomdpConst),
            ..RunSpec::default()
        };
        assert!(spec.resolve().is_err());
    }

    #[test]
    fn header_and_rows_have_the_same_width() {
        let resolved = RunSpec {
            iterations: Some(2),
            batch: Some(12),
            ..RunSpec::default()
        }
        .resolve()
        .expect("valid");
        let mut solver = PolicySolver::new(&resolved.checked).expect("solver");
        let mut state = resolved.checked.initial_state();
        let r = solver.next_iter(&mut state).expect("iteration");
        let header = log_header(1, 1);
        assert_eq!(header.split(',').count(), log_row(&r).split(',').count());
        assert!(header.starts_with("iteration,v,w,sigma,j_explore,"));
    }
}
