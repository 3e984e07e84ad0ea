//! The names of the options' values: one enum per option, with the names of configurations
//! and of the command line.

#[cfg(feature = "clap")]
use clap::ValueEnum;
use sepg_algo::core::check::OnContradiction;
use sepg_algo::core::config::Requirement;
use sepg_algo::core::options::RewardSign;
use sepg_mdp::rollout::ScoreAction;
use serde::{Deserialize, Serialize};

/// Environment presets accepted by `--env`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(ValueEnum))]
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(ValueEnum))]
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

impl AlgoName {
    /// The name of the algorithm in configurations and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            AlgoName::SepgMi => "sepg-mi",
            AlgoName::SepgLb1 => "sepg-lb1",
            AlgoName::SepgLb2 => "sepg-lb2",
            AlgoName::SepgLv => "sepg-lv",
            AlgoName::SepgZv => "sepg-zv",
            AlgoName::SepgSim => "sepg-sim",
            AlgoName::SepgNaiveW => "sepg-naive-w",
            AlgoName::GpomdpConst => "gpomdp-const",
            AlgoName::GpomdpAdam => "gpomdp-adam",
            AlgoName::Adastep => "adastep",
        }
    }

    /// Whether the algorithm splits its requirement with ν (LB-I and SIM-ν, Table 4.1, also
    /// as the requirement of `sepg-naive-w`).
    /// Whether the algorithm is a SEPG variant (the SEPG options apply).
    pub(super) fn is_sepg(self) -> bool {
        matches!(
            self,
            AlgoName::SepgMi
                | AlgoName::SepgLb1
                | AlgoName::SepgLb2
                | AlgoName::SepgLv
                | AlgoName::SepgZv
                | AlgoName::SepgSim
                | AlgoName::SepgNaiveW
        )
    }

    pub(super) fn uses_nu(self, requirement: Option<RequirementName>) -> bool {
        matches!(self, AlgoName::SepgLb1 | AlgoName::SepgSim)
            || (self == AlgoName::SepgNaiveW
                && matches!(
                    requirement,
                    Some(RequirementName::Lb1 | RequirementName::Sim)
                ))
    }
}

/// Safety requirements accepted by `--requirement` (the requirement of `sepg-naive-w`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(ValueEnum))]
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

impl RequirementName {
    /// The requirement of `sepg-algo`, with the split ν of LB-I and SIM-ν (default 0.5).
    pub(super) fn requirement(self, nu: Option<f64>) -> Requirement {
        let nu = nu.unwrap_or(0.5);
        match self {
            RequirementName::Mi => Requirement::Mi,
            RequirementName::Lb1 => Requirement::LbI { nu },
            RequirementName::Lb2 => Requirement::LbII,
            RequirementName::Lv => Requirement::Lv,
            RequirementName::Zv => Requirement::Zv,
            RequirementName::Sim => Requirement::Sim { nu },
        }
    }
}

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

/// The family of constants c and d of the bounds, accepted by `--constants`
/// (docs/THEOREMS.md, "Tight constants").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum ConstantsName {
    /// c of Theorems 3.14 / 4.2 and d of Theorem 4.3 (the thesis).
    Thesis,
    /// c = ρ R M_φ² S_H / σ² and d = 2ρ R S_H (Theorem T) for the run's horizon H.
    Tight,
}

impl ConstantsName {
    /// The family's name in configurations and reports.
    pub fn name(self) -> &'static str {
        match self {
            ConstantsName::Thesis => "thesis",
            ConstantsName::Tight => "tight",
        }
    }

    /// The family of a configuration written before the option existed: the thesis's.
    pub fn legacy() -> Self {
        ConstantsName::Thesis
    }
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
