//! The names of the options' values: one enum per option, with the names of configurations
//! and of the command line.

#[cfg(feature = "clap")]
use clap::ValueEnum;
use sepg_algo::core::check::OnContradiction;
use sepg_algo::core::options::RewardSign;
use sepg_mdp::rollout::ScoreAction;
use serde::{Deserialize, Serialize};

pub use sepg_algo::core::names::{AlgoName, ConstantsName, RequirementName};
/// Environment presets accepted by `--env` (the registry of `sepg-mdp`).
pub use sepg_mdp::env::Preset as EnvName;

/// Gradient modes accepted by `--gradients`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum GradientsName {
    /// Oracle J and gradients (LQG only).
    Exact,
    /// Monte Carlo estimates with confidence level δ.
    Sampled,
}

/// Estimators accepted by `--estimator`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(ValueEnum))]
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(ValueEnum))]
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum FitName {
    /// Each trajectory's baseline is fitted on the others (unbiased).
    LeaveOneOut,
    /// One baseline from the whole batch.
    PlugIn,
}

/// The w-update form accepted by `--w-step`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum WStepName {
    /// As far along the direction as Theorem 4.3 with the confidence on ∇_w J allows.
    Exploring,
    /// Theorem 4.9 (corrected norms; no update when the direction is within its width).
    #[cfg_attr(feature = "clap", value(name = "theorem-4.9"))]
    #[serde(rename = "theorem-4.9")]
    Theorem49,
}

/// The w-direction accepted by `--w-direction`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum WDirectionName {
    /// ∇̂_w L cross-fitted on two halves of the batch (unbiased).
    CrossFitted,
    /// ∇̂_w L from full-batch plug-in products (biased upwards).
    PlugIn,
    /// The thesis-era code's w-derivative of J + α‖∇_v J‖² (scalar actions).
    Metagradient,
}

/// The v-direction accepted by `--v-direction`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum VDirectionName {
    /// The greedy coordinate of Theorem 4.2 / eq. (4.11) with its largest safe step.
    Greedy,
    /// "Safe Adam": Adam proposes the change u, the applied change is t·u with t ≤ 1 the
    /// largest certified step along u (docs/THEOREMS.md, "A step along any direction"); tight
    /// constants and certified accounting only.
    Adam,
}

/// The confidence widths accepted by `--confidence`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum ConfidenceName {
    /// Widths proven at every batch size from R, M_φ, σ, γ and H (sub-Gaussian for ∇_v J,
    /// sub-exponential for ∇_w J), around G(PO)MDP with a constant baseline.
    SubGaussian,
    /// Student-t widths times `quantile-factor` (Sec 4.5): approximate.
    StudentT,
    /// No widths: estimates used as exact (the thesis-era code's δ = 1).
    None,
}

/// The action the policy scores of the sampled gradients are evaluated at, accepted by
/// `--scores`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum ScoresName {
    /// The sampled action a = μ(s) + σz: the exact scores ∇ log π(a|s), unbiased estimators.
    Raw,
    /// The action the environment applies, clip(a) (the thesis-era code's choice): the
    /// estimators are biased wherever the action box clips.
    Clipped,
}

impl ScoresName {
    /// The rollout engine's choice for this name.
    pub fn score_action(self) -> ScoreAction {
        match self {
            ScoresName::Raw => ScoreAction::Raw,
            ScoresName::Clipped => ScoreAction::Clipped,
        }
    }
}

/// What SEPG's requirements are built on, accepted by `--accounting`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum AccountingName {
    /// Sums of the certified guarantees of the applied steps: every requirement holds
    /// against exact J on the confidence events.
    Certified,
    /// The thesis's bookkeeping with estimated J (Sec 4.4.4): no statement about exact J.
    Estimated,
}

/// How many trajectories each block of a sampled SEPG iteration draws, accepted by
/// `--batch-rule` (docs/THEOREMS.md, "An adaptive batch size").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum BatchRuleName {
    /// N trajectories per iteration, split evenly among its blocks (Algorithm 4.3).
    Fixed,
    /// After the first iteration, each block draws the n that maximises the guaranteed
    /// improvement per trajectory of the v-step, n = 4b̂²/ĝ² from the previous iteration's
    /// v-block, clamped to [`batch-min`, `batch-max`] (certified accounting only).
    Adaptive,
}

/// How δ is spread over a run's confidence statements, accepted by `--schedule`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum ScheduleName {
    /// δ/(T·K) per width: the whole run holds with probability ≥ 1 − δ.
    Run,
    /// δ per width (the thesis): a statement per iteration at most.
    Iteration,
}

/// What a run does when its data contradict its declared constants, accepted by
/// `--on-contradiction` (docs/RELIABILITY.md, "Declared constants checked against the data").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum OnContradictionName {
    /// Stop at the first reward or feature beyond its declared bound (exit 1).
    Stop,
    /// Go on, marked "constants contradicted: no guarantee".
    Continue,
}

impl OnContradictionName {
    /// The algorithm's option for this name.
    pub fn option(self) -> OnContradiction {
        match self {
            OnContradictionName::Stop => OnContradiction::Stop,
            OnContradictionName::Continue => OnContradiction::Continue,
        }
    }
}

/// What is known of the sign of the rewards, accepted by `--rewards` (tight constants only).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum RewardsName {
    /// Rewards of either sign (ρ = 1): always sound.
    TwoSided,
    /// Every reward in [−R, 0] (ρ = 1/2): the LQG presets.
    NonPositive,
}

impl RewardsName {
    /// The algorithm's reward sign for this name.
    pub fn sign(self) -> RewardSign {
        match self {
            RewardsName::TwoSided => RewardSign::TwoSided,
            RewardsName::NonPositive => RewardSign::NonPositive,
        }
    }

    /// The name of the algorithm's reward sign.
    pub fn of(sign: RewardSign) -> Self {
        match sign {
            RewardSign::TwoSided => RewardsName::TwoSided,
            RewardSign::NonPositive => RewardsName::NonPositive,
        }
    }
}

/// LB-I's requirement per half-step, accepted by `--lb1-requirement`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum Lb1Name {
    /// (1 − ν)C for the v-update, νC for the w-update (eqs. 4.13, 4.14).
    Split,
    /// The whole requirement, measured at the start of each half-step.
    Full,
}
