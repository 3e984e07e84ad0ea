//! Run configuration: unchecked [`SepgConfig`] → validated [`CheckedConfig`] (linfa's
//! `ParamGuard` pattern). Only a checked configuration can build a solver.
use crate::core::defaults::{
    DEFAULT_ADAM_BETA1, DEFAULT_ADAM_BETA2, DEFAULT_ADAM_EPS, DEFAULT_BUDGET0, DEFAULT_DELTA,
    DEFAULT_ITERATIONS, DEFAULT_N_TRAJECTORIES, DEFAULT_SEED, DEFAULT_SIGMA0, DEFAULT_V0,
};
use sepg_bounds::budget::split_requirement;
use sepg_bounds::constants::TaskConstants;
use sepg_estimators::GradientSpec;
use sepg_mdp::env::{AnyEnv, Environment};
use sepg_mdp::rollout::ScoreAction;
use serde::{Deserialize, Serialize};

use crate::core::error::ConfigError;
use crate::core::options::{ConstantsFamily, RewardSign, SepgOptions, VDirection, WDirection};
use crate::core::state::State;
use crate::core::statement::Statement;

/// Safety requirement of SEPG (Table 4.1, docs/CONVENTIONS.md §5).
///
/// Type-I requirements constrain every update, J(θᵗ⁺¹) − J(θᵗ) ≥ Cᵗ (eq. 4.2), with Cᵗ split
/// between the v-update ((1 − ν)Cᵗ, eq. 4.13) and the w-update (νCᵗ, eq. 4.14). Type-II
/// requirements use the budget B (Definition 4.3) with C = −B for each update and differ by
/// their target policy.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Requirement {
    /// Monotonic improvement: Cᵗ = 0.
    Mi,
    /// Lower-bounded I: Cᵗ = J(θ⁰) − J(θᵗ), split by `nu` ∈ [0, 1] (eqs. 4.13, 4.14).
    LbI {
        /// Share ν of Cᵗ given to the w-update.
        nu: f64,
    },
    /// Lower-bounded II: budget, target = exploratory policy.
    LbII,
    /// Low variance: budget, target = (vᵗ, w_LV) with w_LV the lowest w allowed by (4.17)
    /// for a worsening of at most B from the exploratory policy (Sec 4.4.3).
    Lv,
    /// Zero variance: budget, target = deterministic policy (vᵗ, −∞).
    Zv,
    /// SIM-ν (Sec 4.4.4, 5.1.3): v- and w-update computed from one batch at (vᵗ, wᵗ), the
    /// budget split νB (v-update) / (1 − ν)B (w-update); target = deterministic policy as
    /// in ZV (the merged block plus the target block use 2/3 of ZV's blocks).
    Sim {
        /// Share ν of the budget given to the v-update.
        nu: f64,
    },
}

impl Requirement {
    /// The required improvements `(C_v, C_w)` of the v- and w-updates under the estimated
    /// bookkeeping (Table 4.1, Sec 4.4.4), for the budget B = `budget` and, for LB-I, the
    /// drop `j_drop` = J(θ⁰) − J(θᵗ) (units of J): MI (0, 0); LB-I ((1 − ν)C, νC) with
    /// C = `j_drop` (eqs. 4.13, 4.14); LB-II, LV and ZV (−B, −B) (Definition 4.3); SIM-ν
    /// (−νB, −(1 − ν)B). Between the two updates SEPG updates B: the w-update's value is this
    /// function's at the new budget.
    ///
    /// # Errors
    /// [`BoundsError`](sepg_bounds::BoundsError) for a non-finite `j_drop` (LB-I) or
    /// `budget` (SIM-ν), or ν ∉ [0, 1] (LB-I, SIM-ν).
    ///
    /// # Examples
    /// ```
    /// use sepg_algo::core::config::Requirement;
    /// assert_eq!(Requirement::Sim { nu: 0.25 }.required_improvements(4.0, 0.0), Ok((-1.0, -3.0)));
    /// assert_eq!(Requirement::LbI { nu: 0.25 }.required_improvements(4.0, 2.0), Ok((1.5, 0.5)));
    /// ```
    pub fn required_improvements(
        self,
        budget: f64,
        j_drop: f64,
    ) -> Result<(f64, f64), sepg_bounds::BoundsError> {
        match self {
            Requirement::Mi => split_requirement(0.0, 0.0),
            Requirement::LbI { nu } => split_requirement(j_drop, nu),
            Requirement::Sim { nu } => {
                let (v, w) = split_requirement(-budget, nu)?;
                Ok((w, v))
            }
            Requirement::LbII | Requirement::Lv | Requirement::Zv => Ok((-budget, -budget)),
        }
    }

    /// Whether the requirement uses the budget B (type II, including SIM-ν).
    ///
    /// # Examples
    /// ```
    /// use sepg_algo::core::config::Requirement;
    /// assert!(Requirement::Zv.is_type_two());
    /// assert!(!Requirement::LbI { nu: 0.5 }.is_type_two());
    /// ```
    pub fn is_type_two(self) -> bool {
        matches!(
            self,
            Requirement::LbII | Requirement::Lv | Requirement::Zv | Requirement::Sim { .. }
        )
    }

    /// Number of blocks one SEPG iteration runs, among which N is split evenly
    /// (Sec 4.4.4): v and w (MI, LB-I, LB-II), v, target and w (LV, ZV), merged v/w and
    /// target (SIM-ν).
    ///
    /// # Examples
    /// ```
    /// use sepg_algo::core::config::Requirement;
    /// assert_eq!(Requirement::Mi.blocks(), 2);
    /// assert_eq!(Requirement::Zv.blocks(), 3);
    /// assert_eq!(Requirement::Sim { nu: 0.5 }.blocks(), 2);
    /// ```
    pub fn blocks(self) -> usize {
        match self {
            Requirement::Mi | Requirement::LbI { .. } | Requirement::LbII => 2,
            Requirement::Lv | Requirement::Zv => 3,
            Requirement::Sim { .. } => 2,
        }
    }
}

/// The optimisation algorithm (docs/CONVENTIONS.md §5, comparison algorithms of Chapter 5).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Algorithm {
    /// SEPG, update (4.20): greedy-coordinate v-update with the largest safe ᾱ, w-update
    /// along ∇_w L with the largest safe β̄ (Theorems 4.2/4.5, high-probability 4.7/4.9).
    Sepg(Requirement),
    /// SEPG with the naive w-update along ∇_w J, eq. (4.12), β̄ = (1 + λ_w)β*
    /// (Theorem 4.3/4.8).
    SepgNaiveW(Requirement),
    /// G(PO)MDP with constant steps: v ← v + α ∇̂_v J, w ← w + β ∇̂_w J.
    GpomdpConst {
        /// Step size α > 0 of the mean parameters.
        alpha: f64,
        /// Step size β ≥ 0 of the log standard deviations (0 keeps σ fixed).
        beta: f64,
    },
    /// G(PO)MDP with Adam (Kingma and Ba 2015) on v and w separately.
    GpomdpAdam {
        /// Learning rate of v (> 0).
        lr_v: f64,
        /// Learning rate of w (≥ 0; 0 keeps σ fixed).
        lr_w: f64,
        /// First-moment decay β₁ ∈ [0, 1).
        beta1: f64,
        /// Second-moment decay β₂ ∈ [0, 1).
        beta2: f64,
        /// Denominator offset ε > 0.
        epsilon: f64,
    },
    /// Adaptive step of Pirotta et al. with fixed σ: θ ← θ + α* ∇̂_θ J with α* of
    /// Corollary 3.11 (exact) or Theorem 3.12 (sampled).
    AdaStep,
}

impl Algorithm {
    /// Adam with the usual defaults β₁ = 0.9, β₂ = 0.999, ε = 1e-8.
    ///
    /// # Examples
    /// ```
    /// use sepg_algo::core::config::Algorithm;
    /// let a = Algorithm::adam(1e-4, 1e-4);
    /// assert!(matches!(a, Algorithm::GpomdpAdam { beta1, .. } if beta1 == 0.9));
    /// ```
    pub fn adam(lr_v: f64, lr_w: f64) -> Self {
        Algorithm::GpomdpAdam {
            lr_v,
            lr_w,
            beta1: DEFAULT_ADAM_BETA1,
            beta2: DEFAULT_ADAM_BETA2,
            epsilon: DEFAULT_ADAM_EPS,
        }
    }

    /// Number of trajectory blocks one iteration runs.
    ///
    /// # Examples
    /// ```
    /// use sepg_algo::core::config::{Algorithm, Requirement};
    /// assert_eq!(Algorithm::AdaStep.blocks(), 1);
    /// assert_eq!(Algorithm::Sepg(Requirement::Lv).blocks(), 3);
    /// ```
    pub fn blocks(self) -> usize {
        match self {
            Algorithm::Sepg(r) | Algorithm::SepgNaiveW(r) => r.blocks(),
            _ => 1,
        }
    }

    pub(crate) fn validate(self) -> Result<(), ConfigError> {
        let hp = |name, value: f64, ok: bool, domain| {
            if ok && value.is_finite() {
                Ok(())
            } else {
                Err(ConfigError::InvalidHyperParameter {
                    name,
                    value,
                    domain,
                })
            }
        };
        match self {
            Algorithm::Sepg(r) | Algorithm::SepgNaiveW(r) => match r {
                Requirement::LbI { nu } | Requirement::Sim { nu } => {
                    if (0.0..=1.0).contains(&nu) {
                        Ok(())
                    } else {
                        Err(ConfigError::NuOutOfRange { nu })
                    }
                }
                _ => Ok(()),
            },
            Algorithm::GpomdpConst { alpha, beta } => {
                hp("alpha", alpha, alpha > 0.0, "(0, inf)")?;
                hp("beta", beta, beta >= 0.0, "[0, inf)")
            }
            Algorithm::GpomdpAdam {
                lr_v,
                lr_w,
                beta1,
                beta2,
                epsilon,
            } => {
                hp("lr_v", lr_v, lr_v > 0.0, "(0, inf)")?;
                hp("lr_w", lr_w, lr_w >= 0.0, "[0, inf)")?;
                hp("beta1", beta1, (0.0..1.0).contains(&beta1), "[0, 1)")?;
                hp("beta2", beta2, (0.0..1.0).contains(&beta2), "[0, 1)")?;
                hp("epsilon", epsilon, epsilon > 0.0, "(0, inf)")
            }
            Algorithm::AdaStep => Ok(()),
        }
    }
}

/// How J and its gradients are obtained.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum GradientMode {
    /// Monte Carlo estimates (G(PO)MDP, estimator of Appendix B) with t-based confidence
    /// widths at level `delta` (Sec 4.5) and the high-probability bounds of Theorems 4.7–4.9.
    Sampled {
        /// Confidence parameter δ ∈ (0, 1) of each width ε_i = t(1 − δ/2, N − 1)·√(Var_i/N).
        delta: f64,
    },
    /// Exact oracle values (the setting of Sec 4.3): Theorems 4.2, 4.3 and 4.5 directly,
    /// no ε corrections.
    Exact,
}

/// Unchecked configuration of a run. Validate it with [`SepgConfig::check`].
///
/// # Examples
/// ```
/// use sepg_algo::core::config::{Algorithm, GradientMode, Requirement, SepgConfig};
/// use sepg_mdp::env::Preset;
/// let cfg = SepgConfig::new(Preset::Lqg1d.build(), Algorithm::Sepg(Requirement::Zv));
/// assert_eq!(cfg.n_trajectories, 100);
/// assert!(cfg.clone().check().is_ok());
/// let bad = SepgConfig { sigma0: vec![0.0], ..cfg };
/// assert!(bad.check().is_err());
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct SepgConfig {
    /// The environment (its constants R, M_φ, |A|, γ enter every bound).
    pub env: AnyEnv,
    /// The algorithm.
    pub algorithm: Algorithm,
    /// Sampled or exact J and gradients.
    pub gradient: GradientMode,
    /// Estimator of ∇_v J and ∇_w J in the sampled mode (G(PO)MDP with the leave-one-out
    /// variance-optimal baseline by default).
    pub estimator: GradientSpec,
    /// Initial mean parameters v⁰ (length `action_dim · feature_dim`, action-major).
    pub v0: Vec<f64>,
    /// Initial standard deviations σ⁰ > 0 (length `action_dim`); w⁰ = ln σ⁰.
    pub sigma0: Vec<f64>,
    /// Trajectories per iteration N, split evenly among the blocks that run (Sec 4.4.4).
    pub n_trajectories: usize,
    /// Horizon H of every trajectory (and of the exact oracle's finite-horizon J).
    pub horizon: usize,
    /// Number of iterations a full run performs.
    pub iterations: u64,
    /// Seed of the run; trajectory streams derive from (seed, iteration, block, index).
    pub seed: u64,
    /// Initial budget B⁰ ≥ 0 (Algorithm 4.3; docs/CONVENTIONS.md §5 default 0).
    pub initial_budget: f64,
    /// Options of SEPG: the form and direction of the w-update, confidence widths, LB-I's
    /// requirement, alternating iterations, the reference batch of J(θ⁰), constant overrides
    /// (ignored by the comparison algorithms except the overrides).
    pub options: SepgOptions,
    /// The action at which the sampled mode's rollouts evaluate the policy scores: the raw
    /// Gaussian action (exact scores, unbiased estimators; the default) or the action clipped
    /// to the action box (the thesis-era code). Ignored by exact gradients.
    pub score_action: ScoreAction,
}

impl SepgConfig {
    /// The reproduction defaults of docs/CONVENTIONS.md §6 for `env` and `algorithm`: v⁰ = −0.1 on every
    /// mean parameter, σ⁰ = 1, N = 100, H = 20, 10,000 iterations, seed 0, B⁰ = 0, sampled
    /// gradients with δ = 0.2.
    pub fn new(env: AnyEnv, algorithm: Algorithm) -> Self {
        let dim_v = env.action_dim() * env.feature_dim();
        let dim_w = env.action_dim();
        SepgConfig {
            env,
            algorithm,
            gradient: GradientMode::Sampled {
                delta: DEFAULT_DELTA,
            },
            estimator: GradientSpec::default(),
            v0: vec![DEFAULT_V0; dim_v],
            sigma0: vec![DEFAULT_SIGMA0; dim_w],
            n_trajectories: DEFAULT_N_TRAJECTORIES,
            horizon: sepg_mdp::env::LQG_HORIZON,
            iterations: DEFAULT_ITERATIONS,
            seed: DEFAULT_SEED,
            initial_budget: DEFAULT_BUDGET0,
            options: SepgOptions::default(),
            score_action: ScoreAction::Raw,
        }
    }

    /// Validates the configuration (linfa's `ParamGuard::check`).
    ///
    /// # Errors
    /// A [`ConfigError`] for ν ∉ [0, 1], σ⁰ ≤ 0 or non-finite, non-finite v⁰, wrong vector
    /// lengths, δ ∉ (0, 1), zero iterations, H = 0, B⁰ < 0 or non-finite, N too small to give
    /// every block at least 2 trajectories (4 for a block that estimates ∇_w L, whose
    /// estimator is cross-fitted on two halves), bad hyper-parameters, exact mode without an
    /// exact oracle, options that do not apply (alternating iterations outside MI and LB-I,
    /// the metagradient direction with several action dimensions), or environment constants
    /// (after the overrides) the bounds reject.
    pub fn check(mut self) -> Result<CheckedConfig, ConfigError> {
        self.algorithm.validate()?;
        self.options.validate()?;
        self.check_options()?;
        self = self.override_gamma()?;
        if self.options.constants
            == (ConstantsFamily::Tight {
                rewards: RewardSign::NonPositive,
            })
            && reward_sign(&self.env) != RewardSign::NonPositive
        {
            return Err(ConfigError::UnsupportedOption {
                option: "rewards",
                reason: "the environment has positive rewards (Mountain Car's goal reward)",
            });
        }
        self.check_start()?;
        self.check_gradient_mode()?;
        let constants = self.task_constants()?;
        check_v_direction(&self.options, &constants)?;
        Ok(CheckedConfig {
            inner: self,
            constants,
            certified: true,
        })
    }

    /// Options that apply only to some algorithms or environments.
    fn check_options(&self) -> Result<(), ConfigError> {
        let requirement = match self.algorithm {
            Algorithm::Sepg(r) | Algorithm::SepgNaiveW(r) => Some(r),
            _ => None,
        };
        if self.options.alternating
            && !matches!(requirement, Some(Requirement::Mi | Requirement::LbI { .. }))
        {
            return Err(ConfigError::UnsupportedOption {
                option: "alternating",
                reason: "alternating v/w iterations exist for SEPG-MI and SEPG-LB-I only",
            });
        }
        if matches!(self.options.w_direction, WDirection::Metagradient { .. })
            && self.env.action_dim() != 1
        {
            return Err(ConfigError::UnsupportedOption {
                option: "w_direction",
                reason: "the metagradient direction needs a scalar action",
            });
        }
        Ok(())
    }

    /// The configuration with its environment replaced by one with the overridden discount
    /// factor, if any.
    fn override_gamma(mut self) -> Result<Self, ConfigError> {
        if let Some(gamma) = self.options.overrides.gamma {
            self.env = match self.env {
                AnyEnv::Lqg(e) => {
                    let model = e
                        .model()
                        .clone()
                        .with_gamma(gamma)
                        .map_err(|e| ConfigError::Environment(e.to_string()))?;
                    let horizon = e.constants().horizon;
                    AnyEnv::Lqg(Box::new(
                        sepg_mdp::env::LqgEnv::new(model)
                            .and_then(|env| env.with_horizon(horizon))
                            .map_err(|e| ConfigError::Environment(e.to_string()))?,
                    ))
                }
                AnyEnv::MountainCar(m) => AnyEnv::MountainCar(
                    m.with_gamma(gamma)
                        .map_err(|e| ConfigError::Environment(e.to_string()))?,
                ),
            };
        }
        Ok(self)
    }

    /// The run's length and its start: iterations, horizon, B⁰, the dimensions and values of
    /// v⁰ and σ⁰.
    fn check_start(&self) -> Result<(), ConfigError> {
        if self.iterations == 0 {
            return Err(ConfigError::ZeroIterations);
        }
        if self.horizon == 0 {
            return Err(ConfigError::ZeroHorizon);
        }
        if !(self.initial_budget.is_finite() && self.initial_budget >= 0.0) {
            return Err(ConfigError::InvalidBudget {
                value: self.initial_budget,
            });
        }
        let dim_w = self.env.action_dim();
        let dim_v = dim_w * self.env.feature_dim();
        for (what, expected, got) in [
            ("v0", dim_v, self.v0.len()),
            ("sigma0", dim_w, self.sigma0.len()),
        ] {
            if expected != got {
                return Err(ConfigError::DimensionMismatch {
                    what,
                    expected,
                    got,
                });
            }
        }
        if let Some((index, &value)) = self.v0.iter().enumerate().find(|(_, x)| !x.is_finite()) {
            return Err(ConfigError::InvalidMean { index, value });
        }
        for (index, &value) in self.sigma0.iter().enumerate() {
            let w = value.ln();
            if !(value.is_finite() && value > 0.0 && w.is_finite()) {
                return Err(ConfigError::InvalidSigma { index, value });
            }
        }
        Ok(())
    }

    /// The batch size and δ of the sampled mode, or an exact oracle for the exact mode.
    fn check_gradient_mode(&self) -> Result<(), ConfigError> {
        match self.gradient {
            GradientMode::Sampled { delta } => {
                check_sampled(self.algorithm, self.n_trajectories, delta)?;
            }
            GradientMode::Exact => {
                let unsupported = match &self.env {
                    AnyEnv::Lqg(e) if e.model().clipping && !e.model().is_scalar() => {
                        Some("clipped multi-dimensional LQG")
                    }
                    AnyEnv::Lqg(_) => None,
                    _ => Some("mountain-car"),
                };
                if let Some(env) = unsupported {
                    return Err(ConfigError::ExactUnsupported { env: env.into() });
                }
            }
        }
        Ok(())
    }

    /// The task constants of the bounds: the environment's, after the overrides, in the
    /// chosen family.
    fn task_constants(&self) -> Result<TaskConstants, ConfigError> {
        let k = self.env.constants();
        let o = self.options.overrides;
        let constants = TaskConstants::new(
            k.gamma,
            o.r_max.unwrap_or(k.r_max),
            o.m_phi.unwrap_or(k.m_phi),
            o.action_volume.unwrap_or(k.action_volume),
        )
        .and_then(|c| match o.psi {
            Some(psi) => c.with_psi(psi),
            None => Ok(c),
        })
        .and_then(|c| c.with_family(self.options.constants.family(self.horizon)))
        .map_err(|e| ConfigError::Environment(e.to_string()))?;
        Ok(constants)
    }
}

/// What is known of the sign of the rewards of `env`, for the tight constants
/// (docs/THEOREMS.md, "Tight constants"): the LQG environments' reward −(sᵀQs + aᵀRa), with Q
/// and R positive semi-definite (checked when the model is built), is never positive; Mountain
/// Car pays +100 at the goal, so its rewards have both signs.
///
/// # Examples
/// ```
/// use sepg_algo::core::config::reward_sign;
/// use sepg_algo::core::options::RewardSign;
/// use sepg_mdp::env::Preset;
/// assert_eq!(reward_sign(&Preset::Lqg1d.build()), RewardSign::NonPositive);
/// assert_eq!(reward_sign(&Preset::MountainCar.build()), RewardSign::TwoSided);
/// ```
pub fn reward_sign(env: &AnyEnv) -> RewardSign {
    match env {
        AnyEnv::Lqg(_) => RewardSign::NonPositive,
        AnyEnv::MountainCar(_) => RewardSign::TwoSided,
    }
}

/// A validated [`SepgConfig`]; only this type can build a solver.
#[derive(Debug, Clone, PartialEq)]
pub struct CheckedConfig {
    inner: SepgConfig,
    constants: TaskConstants,
    certified: bool,
}

impl CheckedConfig {
    /// The validated configuration.
    pub fn config(&self) -> &SepgConfig {
        &self.inner
    }

    /// The validated task constants R, M_φ, |A|, γ of the environment (docs/CONVENTIONS.md §1),
    /// after the overrides, with the family of [`SepgOptions::constants`] (the tight family for
    /// the run's horizon H).
    pub fn constants(&self) -> &TaskConstants {
        &self.constants
    }

    /// Whether SEPG takes certified steps (`sepg_certified`, the default): every
    /// v- and w-step, and the LV target, is a step whose bound, evaluated in outward-rounded
    /// interval arithmetic with the inputs taken as exact, meets its requirement.
    pub fn certified(&self) -> bool {
        self.certified
    }

    /// Turns certified steps on (the default) or off. Off, SEPG takes the largest safe steps
    /// as computed in `f64`, whose bound can fall short of the requirement by rounding.
    ///
    /// # Examples
    /// ```
    /// use sepg_algo::core::config::{Algorithm, Requirement, SepgConfig};
    /// use sepg_mdp::env::Preset;
    /// let c = SepgConfig::new(Preset::Lqg.build(), Algorithm::Sepg(Requirement::Mi)).check()?;
    /// assert!(c.certified());
    /// assert!(!c.with_certified_steps(false).certified());
    /// # Ok::<(), sepg_algo::core::error::ConfigError>(())
    /// ```
    pub fn with_certified_steps(mut self, on: bool) -> Self {
        self.certified = on;
        self
    }

    /// The same configuration with the penalty coefficients c and d of `family`
    /// (`sepg_bounds::penalties::Family`; the thesis's unless set): every bound and
    /// certified step of the run follows it.
    ///
    /// # Errors
    /// [`ConfigError::Environment`] when the family is rejected (a horizon of 0 steps);
    /// [`ConfigError::UnsupportedOption`] for the Adam v-direction with the thesis's constants
    /// ([`check_v_direction`]).
    ///
    /// # Examples
    /// ```
    /// use sepg_algo::core::config::{Algorithm, Requirement, SepgConfig};
    /// use sepg_algo::core::options::{ConstantsFamily, RewardSign, VDirection};
    /// use sepg_bounds::penalties::{Family, Horizon, Rewards, Tight};
    /// use sepg_mdp::env::Preset;
    /// let mut cfg = SepgConfig::new(Preset::Lqg1d.build(), Algorithm::Sepg(Requirement::Mi));
    /// cfg.options.v_direction = VDirection::adam(1e-2);
    /// cfg.options.constants = ConstantsFamily::Tight { rewards: RewardSign::NonPositive };
    /// let checked = cfg.check()?;
    /// let tight = Family::Tight(Tight::new(Horizon::Finite(20), Rewards::NonPositive));
    /// assert!(checked.clone().with_family(tight).is_ok());
    /// assert!(checked.with_family(Family::Thesis).is_err());
    /// # Ok::<(), sepg_algo::core::error::ConfigError>(())
    /// ```
    pub fn with_family(mut self, family: sepg_bounds::Family) -> Result<Self, ConfigError> {
        self.constants = self
            .constants
            .with_family(family)
            .map_err(|e| ConfigError::Environment(e.to_string()))?;
        check_v_direction(&self.inner.options, &self.constants)?;
        Ok(self)
    }

    /// What a run of this configuration promises about exact J, and how firmly
    /// (docs/THEOREMS.md, "Statements over a whole run").
    ///
    /// # Examples
    /// ```
    /// use sepg_algo::core::config::{Algorithm, SepgConfig};
    /// use sepg_algo::core::statement::StatementKind;
    /// use sepg_mdp::env::Preset;
    /// let adam = SepgConfig::new(Preset::Lqg.build(), Algorithm::adam(1e-3, 0.0)).check()?;
    /// assert_eq!(adam.statement().kind, StatementKind::None);
    /// # Ok::<(), sepg_algo::core::error::ConfigError>(())
    /// ```
    pub fn statement(&self) -> Statement {
        crate::core::statement::classify(self)
    }

    /// The state before the first iteration: (v⁰, ln σ⁰), B = B⁰.
    ///
    /// # Examples
    /// ```
    /// use sepg_algo::core::config::{Algorithm, Requirement, SepgConfig};
    /// use sepg_mdp::env::Preset;
    /// let c = SepgConfig::new(Preset::Lqg.build(), Algorithm::Sepg(Requirement::Mi)).check()?;
    /// let s = c.initial_state();
    /// assert_eq!((s.v.clone(), s.w.clone()), (vec![-0.1], vec![0.0]));
    /// # Ok::<(), sepg_algo::core::error::ConfigError>(())
    /// ```
    pub fn initial_state(&self) -> State {
        State::new(
            self.inner.v0.clone(),
            self.inner.sigma0.iter().map(|s| s.ln()).collect(),
            self.inner.initial_budget,
        )
    }
}

/// Checks that the v-direction of `options` is proven with the family of `constants`: the
/// Adam v-direction steps along non-coordinate directions, for which only the tight constants
/// are proven (docs/THEOREMS.md, "A step along any direction"; the thesis's c is proven for the
/// greedy coordinate only).
///
/// # Errors
/// [`ConfigError::UnsupportedOption`] for the Adam v-direction with the thesis's constants.
pub fn check_v_direction(
    options: &SepgOptions,
    constants: &TaskConstants,
) -> Result<(), ConfigError> {
    if matches!(options.v_direction, VDirection::Adam { .. })
        && constants.family() == sepg_bounds::Family::Thesis
    {
        return Err(ConfigError::UnsupportedOption {
            option: "v_direction",
            reason: "the Adam v-direction needs the tight constants (Theorem T): the thesis's \
                     c is proven for the greedy coordinate only",
        });
    }
    Ok(())
}

/// Checks the sampled-mode settings: δ ∈ (0, 1) and N large enough to give every block at
/// least 2 trajectories (4 for a block that estimates ∇_w L, cross-fitted on two halves).
pub(crate) fn check_sampled(
    algorithm: Algorithm,
    n_trajectories: usize,
    delta: f64,
) -> Result<(), ConfigError> {
    if !(delta > 0.0 && delta < 1.0) {
        return Err(ConfigError::InvalidDelta { delta });
    }
    let blocks = algorithm.blocks();
    let min = match algorithm {
        Algorithm::Sepg(_) => 4,
        _ => 2,
    };
    if n_trajectories / blocks < min {
        return Err(ConfigError::TooFewTrajectories {
            n: n_trajectories,
            blocks,
            per_block: min,
        });
    }
    Ok(())
}
