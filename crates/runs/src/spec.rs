//! Run options and their resolution: [`RunSpec`] holds every option of a run (as a TOML
//! table and, with the `clap` feature, as command-line flags of the same names);
//! [`RunSpec::resolve`] fills in the defaults of the thesis's protocol (Sec 5.1), rejects
//! options that do not apply to the chosen algorithm, and validates the result into the
//! [`CheckedConfig`] that `sepg-algo` runs.

use std::fs;
use std::path::Path;

#[cfg(feature = "clap")]
use clap::{Args, ValueEnum};
use sepg_algo::core::check::OnContradiction;
use sepg_algo::core::config::reward_sign;
use sepg_algo::core::config::{Algorithm, CheckedConfig, GradientMode, Requirement, SepgConfig};
use sepg_algo::core::options::{
    Accounting, Confidence, ConstantOverrides, ConstantsFamily, Lb1Requirement, RewardSign,
    Schedule as WidthSchedule, SepgOptions, VDirection, WDirection, WStep,
};
use sepg_estimators::{Baseline, BaselineFit, GradientSpec, Kind};
use sepg_mdp::env::{AnyEnv, Environment, LqgEnv};
use sepg_mdp::mountain_car::MountainCar;
use sepg_mdp::oracle::ClosedFormOracle;
use sepg_mdp::policy::GaussianPolicy;
use sepg_mdp::rollout::ScoreAction;
use serde::{Deserialize, Deserializer, Serialize};

use crate::error::{Error, Result};

/// The version of sepg recorded in every configuration.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// Largest horizon H (steps per trajectory) a run, an estimate or an exact evaluation
/// accepts: the exact dynamic programme of a clipped preset takes about 60 µs per step, so
/// 10⁵ steps cost seconds per evaluation (docs/RELIABILITY.md, "Sizes").
pub const MAX_HORIZON: usize = 100_000;

/// Largest number of iterations of a run (docs/RELIABILITY.md, "Sizes").
pub const MAX_ITERATIONS: u64 = 1_000_000_000;

/// Largest memory, in bytes, one batch of trajectories may need (8 GiB): sizes beyond are
/// refused before anything is allocated (docs/RELIABILITY.md, "Sizes"). The limit does not
/// depend on the machine, so a configuration resolves the same everywhere.
pub const MAX_BATCH_BYTES: u64 = 8 << 30;

/// Bytes a batch of `n` trajectories of `horizon` steps takes, with `dim_v` mean and `dim_w`
/// log-standard-deviation parameters: per step the discounted reward and the cumulative
/// scores (`1 + dim_v + dim_w` numbers of 8 bytes), per trajectory its length (8 bytes);
/// `None` when the count overflows `u64`.
///
/// ```
/// // 100 trajectories of 20 steps, one parameter of each kind: 100 · (20 · 3 + 1) · 8.
/// assert_eq!(sepg_runs::spec::batch_bytes(100, 20, 1, 1), Some(48_800));
/// assert_eq!(sepg_runs::spec::batch_bytes(usize::MAX, 20, 1, 1), None);
/// ```
pub fn batch_bytes(n: usize, horizon: usize, dim_v: usize, dim_w: usize) -> Option<u64> {
    let per_step = 1u64.checked_add(dim_v as u64)?.checked_add(dim_w as u64)?;
    let per_trajectory = (horizon as u64).checked_mul(per_step)?.checked_add(1)?;
    (n as u64).checked_mul(per_trajectory)?.checked_mul(8)
}

/// Checks that a batch of `n` trajectories of `horizon` steps fits [`MAX_BATCH_BYTES`]
/// (see [`batch_bytes`]); `what` names the option for the message.
///
/// # Errors
/// [`Error::Invalid`] naming the size and the limit.
pub fn check_batch_memory(
    what: &str,
    n: usize,
    horizon: usize,
    dims: (usize, usize),
) -> Result<()> {
    match batch_bytes(n, horizon, dims.0, dims.1) {
        Some(b) if b <= MAX_BATCH_BYTES => Ok(()),
        b => Err(Error::invalid(format!(
            "{what} N = {n} trajectories of H = {horizon} steps need {} of memory, more than \
             the limit of {} GiB",
            b.map_or_else(
                || "more than 2^64 bytes".to_owned(),
                |b| format!("{} GiB", b.div_ceil(1 << 30))
            ),
            MAX_BATCH_BYTES >> 30
        ))),
    }
}

/// Checks `1 ≤ horizon ≤` [`MAX_HORIZON`].
///
/// # Errors
/// [`Error::Invalid`] naming the limit.
pub fn check_horizon(horizon: usize) -> Result<()> {
    if horizon == 0 {
        return Err(Error::invalid("horizon H must be at least 1"));
    }
    if horizon > MAX_HORIZON {
        return Err(Error::invalid(format!(
            "horizon H = {horizon} is above the limit of {MAX_HORIZON} steps"
        )));
    }
    Ok(())
}

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
    fn is_sepg(self) -> bool {
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

    fn uses_nu(self, requirement: Option<RequirementName>) -> bool {
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
    fn requirement(self, nu: Option<f64>) -> Requirement {
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
    fn expand(&self, dim: usize, what: &str) -> Result<Vec<f64>> {
        match self {
            Values::One(x) => Ok(vec![*x; dim]),
            Values::Many(v) if v.len() == 1 => Ok(vec![v[0]; dim]),
            Values::Many(v) if v.len() == dim => Ok(v.clone()),
            Values::Many(v) if dim == 1 => Err(Error::invalid(format!(
                "{what} has {} values, the environment needs 1",
                v.len()
            ))),
            Values::Many(v) => Err(Error::invalid(format!(
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

/// Parses the command-line form of [`Values`]: one number, or numbers separated by commas.
///
/// # Errors
/// A message naming the text when a part is not a number.
pub fn parse_values(s: &str) -> Result<Values, String> {
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
/// Absent options take the defaults of the thesis's protocol (Sec 5.1); a resolved configuration has every option
/// that applies to its algorithm set and no other.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(Args))]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct RunSpec {
    /// A label for the run (used in legends). Default: the algorithm's name.
    #[cfg_attr(feature = "clap", arg(long))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Environment [default: lqg].
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub env: Option<EnvName>,
    /// Mountain Car features: `state-bias` (default) or `rbf:KxV` (a K×V grid plus bias).
    #[cfg_attr(feature = "clap", arg(long))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub features: Option<String>,
    /// Algorithm [default: sepg-zv].
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub algo: Option<AlgoName>,
    /// Safety requirement of sepg-naive-w [default: zv].
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub requirement: Option<RequirementName>,
    /// Exact (oracle) or sampled gradients [default: sampled].
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gradients: Option<GradientsName>,
    /// Confidence δ ∈ (0, 1) of the sampled mode [default: 0.2].
    #[cfg_attr(feature = "clap", arg(long, allow_hyphen_values = true))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub delta: Option<f64>,
    /// Split ν ∈ [0, 1] of LB-I (share of C for w) and SIM (share of B for v) [default: 0.5].
    #[cfg_attr(feature = "clap", arg(long, allow_hyphen_values = true))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub nu: Option<f64>,
    /// Initial mean parameters v⁰: one value for all, or comma-separated [default: -0.1].
    #[cfg_attr(feature = "clap", arg(long, allow_hyphen_values = true, value_parser = parse_values))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub v0: Option<Values>,
    /// Initial standard deviations σ⁰ > 0: one value for all, or comma-separated [default: 1].
    #[cfg_attr(feature = "clap", arg(long, allow_hyphen_values = true, value_parser = parse_values))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sigma0: Option<Values>,
    /// Initial budget B⁰ ≥ 0 [default: 0; 1 for mountain-car].
    #[cfg_attr(feature = "clap", arg(long, allow_hyphen_values = true))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub budget0: Option<f64>,
    /// Step size α of v (gpomdp-const).
    #[cfg_attr(feature = "clap", arg(long, allow_hyphen_values = true))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alpha: Option<f64>,
    /// Step size β of w (gpomdp-const) [default: α].
    #[cfg_attr(feature = "clap", arg(long, allow_hyphen_values = true))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub beta: Option<f64>,
    /// Learning rate of v (gpomdp-adam).
    #[cfg_attr(feature = "clap", arg(long, allow_hyphen_values = true))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lr: Option<f64>,
    /// Learning rate of w (gpomdp-adam) [default: lr].
    #[cfg_attr(feature = "clap", arg(long = "lr-w", allow_hyphen_values = true))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lr_w: Option<f64>,
    /// Trajectories per iteration N [default: 100].
    #[cfg_attr(feature = "clap", arg(long, allow_negative_numbers = true))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub batch: Option<usize>,
    /// Horizon H [default: 20; 999 for mountain-car].
    #[cfg_attr(feature = "clap", arg(long, allow_negative_numbers = true))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub horizon: Option<usize>,
    /// Iterations [default: 10000].
    #[cfg_attr(feature = "clap", arg(long, allow_negative_numbers = true))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub iterations: Option<u64>,
    /// Seed [default: 0].
    #[cfg_attr(feature = "clap", arg(long, allow_hyphen_values = true, value_parser = parse_seed))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// Gradient estimator of the sampled mode [default: gpomdp].
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub estimator: Option<EstimatorName>,
    /// Baseline of the estimator [default: optimal].
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub baseline: Option<BaselineName>,
    /// How the baseline is fitted [default: leave-one-out].
    #[cfg_attr(feature = "clap", arg(long = "baseline-fit", value_enum))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub baseline_fit: Option<FitName>,
    /// Write every k-th iteration to the log (and always the last) [default: 1].
    #[cfg_attr(feature = "clap", arg(long = "log-every"))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub log_every: Option<u64>,
    /// Version of sepg that resolved the configuration (written by sepg; checked on resume).
    #[cfg_attr(feature = "clap", arg(skip))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sepg_version: Option<String>,
    /// Direction of the SEPG v-update: the greedy coordinate, or safe Adam (tight constants
    /// and certified accounting only) [default: greedy].
    #[cfg_attr(feature = "clap", arg(long = "v-direction", value_enum))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub v_direction: Option<VDirectionName>,
    /// Learning rate of safe Adam's proposed change, in units of v per step (> 0; needed by
    /// v-direction adam).
    #[cfg_attr(feature = "clap", arg(long = "adam-lr", allow_hyphen_values = true))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub adam_lr: Option<f64>,
    /// First-moment decay β₁ ∈ [0, 1) of safe Adam [default: 0.9].
    #[cfg_attr(feature = "clap", arg(long = "adam-beta1", allow_hyphen_values = true))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub adam_beta1: Option<f64>,
    /// Second-moment decay β₂ ∈ [0, 1) of safe Adam [default: 0.999].
    #[cfg_attr(feature = "clap", arg(long = "adam-beta2", allow_hyphen_values = true))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub adam_beta2: Option<f64>,
    /// Denominator offset ε > 0 of safe Adam, in units of ∇_v J [default: 1e-8].
    #[cfg_attr(feature = "clap", arg(long = "adam-eps", allow_hyphen_values = true))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub adam_eps: Option<f64>,
    /// Form of the SEPG w-update [default: exploring].
    #[cfg_attr(feature = "clap", arg(long = "w-step", value_enum))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub w_step: Option<WStepName>,
    /// Direction of the SEPG w-update [default: cross-fitted].
    #[cfg_attr(feature = "clap", arg(long = "w-direction", value_enum))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub w_direction: Option<WDirectionName>,
    /// Clipping threshold of the metagradient's last term [default: 100].
    #[cfg_attr(
        feature = "clap",
        arg(long = "metagradient-clip", allow_hyphen_values = true)
    )]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub metagradient_clip: Option<f64>,
    /// Confidence widths of sampled SEPG [default: sub-gaussian].
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub confidence: Option<ConfidenceName>,
    /// Multiplier of the Student-t quantile of the widths [default: 1].
    #[cfg_attr(
        feature = "clap",
        arg(long = "quantile-factor", allow_hyphen_values = true)
    )]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub quantile_factor: Option<f64>,
    /// LB-I's requirement per half-step [default: split].
    #[cfg_attr(feature = "clap", arg(long = "lb1-requirement", value_enum))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lb1_requirement: Option<Lb1Name>,
    /// Alternate v- and w-iterations with all N trajectories each (MI, LB-I) [default: false].
    #[cfg_attr(feature = "clap", arg(long))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alternating: Option<bool>,
    /// Trajectories of the reference batch of J(θ⁰), 0 for none [default: 1000].
    #[cfg_attr(feature = "clap", arg(long = "reference-batch"))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reference_batch: Option<usize>,
    /// Discount factor γ [default: the environment's, 0.99].
    #[cfg_attr(feature = "clap", arg(long, allow_hyphen_values = true))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gamma: Option<f64>,
    /// Maximal absolute reward R used by the bounds [default: the environment's].
    #[cfg_attr(feature = "clap", arg(long = "r-max", allow_hyphen_values = true))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub r_max: Option<f64>,
    /// Maximal absolute feature M_φ used by the bounds [default: the environment's].
    #[cfg_attr(feature = "clap", arg(long = "m-phi", allow_hyphen_values = true))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub m_phi: Option<f64>,
    /// Action-space volume |A| used by the bounds [default: the environment's].
    #[cfg_attr(
        feature = "clap",
        arg(long = "action-volume", allow_hyphen_values = true)
    )]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub action_volume: Option<f64>,
    /// ψ of Lemma A.1 used by the bound of Theorem 4.3 [default: Lemma A.1's
    /// ψ = 0.52355702…; the thesis-era code used 0.53]; the bounds hold for any value ≥ ψ
    /// (0.523557 is below it).
    #[cfg_attr(feature = "clap", arg(long, allow_hyphen_values = true))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub psi: Option<f64>,
    /// Policy scores of the sampled gradients at the raw or at the clipped action
    /// [default: raw].
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scores: Option<ScoresName>,
    /// Certified safe steps (SEPG variants): each step's bound, evaluated in outward-rounded
    /// interval arithmetic with the inputs taken as exact, meets its requirement; false takes
    /// the largest safe steps as computed in f64 [default: true].
    #[cfg_attr(feature = "clap", arg(long = "certified-steps"))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub certified_steps: Option<bool>,
    /// What SEPG's requirements are built on: certified guarantees (a statement about exact
    /// J) or the thesis's estimated J [default: certified].
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub accounting: Option<AccountingName>,
    /// How δ is spread over the confidence widths: over the whole run, or δ per width (the
    /// thesis) [default: run].
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub schedule: Option<ScheduleName>,
    /// Family of the constants c and d of every bound: the thesis's, or the tight constants
    /// of Theorem T for the run's horizon [default: tight; a config.toml without the key, written
    /// before it existed: thesis].
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub constants: Option<ConstantsName>,
    /// Sign of the rewards for the tight constants: non-positive halves c and d [default: the
    /// environment's: non-positive for the LQG presets, two-sided for mountain-car].
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rewards: Option<RewardsName>,
    /// What the run does when an observed reward or feature exceeds its declared bound
    /// (R_max, M_φ): stop with an error, or continue without a guarantee [default: stop].
    #[cfg_attr(feature = "clap", arg(long = "on-contradiction", value_enum))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub on_contradiction: Option<OnContradictionName>,
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
            estimator, baseline, baseline_fit, log_every, sepg_version, v_direction, adam_lr,
            adam_beta1, adam_beta2, adam_eps, w_step, w_direction, metagradient_clip, confidence, quantile_factor, lb1_requirement, alternating,
            reference_batch, gamma, r_max, m_phi, action_volume, psi, scores, certified_steps,
            accounting, schedule, constants, rewards, on_contradiction)
    }

    /// Reads a TOML file of options; unknown keys are rejected.
    ///
    /// # Errors
    /// [`Error::Invalid`] for a missing or unreadable file or an invalid key or value.
    pub fn from_file(path: &Path) -> Result<RunSpec> {
        let text = fs::read_to_string(path)
            .map_err(|e| Error::invalid(format!("cannot read {}: {e}", path.display())))?;
        toml::from_str(&text)
            .map_err(|e| Error::invalid(format!("{}: {}", path.display(), toml_message(&e))))
    }

    /// Resolves every default, validates the configuration (the checks of
    /// [`SepgConfig::check`] plus the options that do not apply to the algorithm) and builds
    /// the algorithm's configuration.
    ///
    /// # Errors
    /// [`Error::Invalid`] for any invalid or inapplicable option.
    pub fn resolve(&self) -> Result<Resolved> {
        let env_name = self.env.unwrap_or(EnvName::Lqg);
        let algo = self.algo.unwrap_or(AlgoName::SepgZv);
        let gradients = self.gradients.unwrap_or(GradientsName::Sampled);
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
        self.reject_inapplicable(algo, gradients)?;
        let method = self.method(algo)?;
        let sampling = self.sampling(gradients);
        let options = self.options(algo, gradients, reward_sign(&env));
        let dim_w = env.action_dim();
        let dim_v = dim_w * env.feature_dim();
        let start = self.start(env_name, dim_v, dim_w)?;
        let schedule = self.schedule(env.constants().horizon)?;
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
            .map_err(|e| Error::invalid(format!("invalid configuration: {e}")))?
            .with_certified_steps(certified_steps.unwrap_or(true));
        // The first iteration builds the policy θ⁰: refuse here what it would refuse there.
        let first = checked.initial_state();
        GaussianPolicy::new(first.v, first.w, feature_dim)
            .map_err(|e| Error::invalid(format!("invalid initial policy (v0, sigma0): {e}")))?;
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
            ..RunSpec::resolved_values(&method, &sampling, start, &schedule, options.as_ref())
        };
        Ok(Resolved {
            spec,
            checked,
            dims: (dim_v, dim_w),
        })
    }

    /// Rejects the options that do not apply to `algo` or to `gradients`.
    fn reject_inapplicable(&self, algo: AlgoName, gradients: GradientsName) -> Result<()> {
        let for_algo = format!("to algorithm {}", algo.name());
        reject(
            !algo.uses_nu(self.requirement) && self.nu.is_some(),
            "nu",
            &for_algo,
        )?;
        reject(
            algo != AlgoName::SepgNaiveW && self.requirement.is_some(),
            "requirement",
            &for_algo,
        )?;
        reject(
            algo != AlgoName::GpomdpConst && (self.alpha.is_some() || self.beta.is_some()),
            "alpha/beta",
            &for_algo,
        )?;
        reject(
            algo != AlgoName::GpomdpAdam && (self.lr.is_some() || self.lr_w.is_some()),
            "lr/lr-w",
            &for_algo,
        )?;
        let sepg = algo.is_sepg();
        reject(
            !sepg
                && (self.w_step.is_some()
                    || self.w_direction.is_some()
                    || self.metagradient_clip.is_some()
                    || self.lb1_requirement.is_some()
                    || self.alternating.is_some()
                    || self.reference_batch.is_some()
                    || self.confidence.is_some()
                    || self.quantile_factor.is_some()),
            "w-step/w-direction/metagradient-clip/lb1-requirement/alternating/\
             reference-batch/confidence/quantile-factor",
            &for_algo,
        )?;
        reject(
            !sepg
                && (self.v_direction.is_some()
                    || self.adam_lr.is_some()
                    || self.adam_beta1.is_some()
                    || self.adam_beta2.is_some()
                    || self.adam_eps.is_some()),
            "v-direction/adam-lr/adam-beta1/adam-beta2/adam-eps",
            &for_algo,
        )?;
        self.reject_v_direction()?;
        reject(
            !sepg && self.certified_steps.is_some(),
            "certified-steps",
            &for_algo,
        )?;
        reject(
            !sepg && (self.accounting.is_some() || self.schedule.is_some()),
            "accounting/schedule",
            &for_algo,
        )?;
        reject(
            self.rewards.is_some() && self.constants == Some(ConstantsName::Thesis),
            "rewards",
            "to the thesis's constants (only the tight constants use the reward sign)",
        )?;
        reject(
            self.alternating == Some(true) && self.accounting != Some(AccountingName::Estimated),
            "alternating",
            "without accounting estimated",
        )?;
        let naive = algo == AlgoName::SepgNaiveW;
        reject(
            naive && (self.w_step.is_some() || self.w_direction.is_some()),
            "w-step/w-direction",
            &for_algo,
        )?;
        reject(
            self.metagradient_clip.is_some()
                && self.w_direction != Some(WDirectionName::Metagradient),
            "metagradient-clip",
            "without w-direction metagradient",
        )?;
        reject(
            self.quantile_factor.is_some() && self.confidence != Some(ConfidenceName::StudentT),
            "quantile-factor",
            "without confidence student-t",
        )?;
        let lb1 =
            algo == AlgoName::SepgLb1 || (naive && self.requirement == Some(RequirementName::Lb1));
        reject(
            !lb1 && self.lb1_requirement.is_some(),
            "lb1-requirement",
            &for_algo,
        )?;
        let exact = gradients == GradientsName::Exact;
        reject(
            exact
                && (self.confidence.is_some()
                    || self.quantile_factor.is_some()
                    || self.reference_batch.is_some()),
            "confidence/quantile-factor/reference-batch",
            "to exact gradients",
        )?;
        reject(exact && self.delta.is_some(), "delta", "to exact gradients")?;
        reject(
            exact && self.scores.is_some(),
            "scores",
            "to exact gradients",
        )?;
        reject(
            exact
                && (self.estimator.is_some()
                    || self.baseline.is_some()
                    || self.baseline_fit.is_some()),
            "estimator/baseline/baseline-fit",
            "to exact gradients",
        )
    }

    /// Refuses safe Adam's parameters without `v-direction adam`, and safe Adam without its
    /// learning rate, with the thesis's constants (proven for the greedy coordinate only) or
    /// with the estimated accounting (docs/THEOREMS.md, "A step along any direction").
    fn reject_v_direction(&self) -> Result<()> {
        let adam = self.v_direction == Some(VDirectionName::Adam);
        reject(
            !adam
                && (self.adam_lr.is_some()
                    || self.adam_beta1.is_some()
                    || self.adam_beta2.is_some()
                    || self.adam_eps.is_some()),
            "adam-lr/adam-beta1/adam-beta2/adam-eps",
            "without v-direction adam",
        )?;
        if !adam {
            return Ok(());
        }
        if self.adam_lr.is_none() {
            return Err(Error::invalid("v-direction adam needs --adam-lr"));
        }
        reject(
            self.constants == Some(ConstantsName::Thesis),
            "v-direction adam",
            "with the thesis's constants (their c is proven for the greedy coordinate only; \
             use constants tight)",
        )?;
        reject(
            self.accounting == Some(AccountingName::Estimated),
            "v-direction adam",
            "with accounting estimated (safe Adam is certified at its realised change; use \
             accounting certified)",
        )
    }

    /// The algorithm of `algo` with its step options (the options were checked to apply).
    fn method(&self, algo: AlgoName) -> Result<Method> {
        let nu = algo
            .uses_nu(self.requirement)
            .then(|| self.nu.unwrap_or(0.5));
        let requirement =
            (algo == AlgoName::SepgNaiveW).then(|| self.requirement.unwrap_or(RequirementName::Zv));
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
                Algorithm::SepgNaiveW(requirement.unwrap_or(RequirementName::Zv).requirement(nu))
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

    /// The SEPG options with their defaults ([`SepgOptions`]); for the comparison algorithms
    /// only the constant overrides (the options were checked to apply).
    fn options(
        &self,
        algo: AlgoName,
        gradients: GradientsName,
        env_rewards: RewardSign,
    ) -> Option<SepgOptions> {
        let overrides = ConstantOverrides {
            gamma: self.gamma,
            r_max: self.r_max,
            m_phi: self.m_phi,
            action_volume: self.action_volume,
            psi: self.psi,
        };
        let constants = match self.constants.unwrap_or(ConstantsName::Tight) {
            ConstantsName::Thesis => ConstantsFamily::Thesis,
            ConstantsName::Tight => ConstantsFamily::Tight {
                rewards: self.rewards.map_or(env_rewards, RewardsName::sign),
            },
        };
        let defaults = SepgOptions::default();
        let on_contradiction = self
            .on_contradiction
            .map_or(defaults.on_contradiction, OnContradictionName::option);
        if !algo.is_sepg() {
            return Some(SepgOptions {
                overrides,
                constants,
                on_contradiction,
                ..defaults
            });
        }
        let sampled = gradients == GradientsName::Sampled;
        Some(SepgOptions {
            v_direction: match (self.v_direction, self.adam_lr) {
                (Some(VDirectionName::Adam), Some(lr)) => VDirection::Adam {
                    lr,
                    beta1: self.adam_beta1.unwrap_or(0.9),
                    beta2: self.adam_beta2.unwrap_or(0.999),
                    eps: self.adam_eps.unwrap_or(1e-8),
                },
                _ => defaults.v_direction,
            },
            w_step: match self.w_step {
                Some(WStepName::Theorem49) => WStep::Theorem49,
                Some(WStepName::Exploring) => WStep::Exploring,
                None => defaults.w_step,
            },
            w_direction: match self.w_direction {
                Some(WDirectionName::PlugIn) => WDirection::PlugIn,
                Some(WDirectionName::Metagradient) => WDirection::Metagradient {
                    clip: self.metagradient_clip.unwrap_or(100.0),
                },
                Some(WDirectionName::CrossFitted) | None => defaults.w_direction,
            },
            confidence: match self.confidence {
                Some(ConfidenceName::None) => Confidence::None,
                Some(ConfidenceName::StudentT) => Confidence::StudentT {
                    factor: self.quantile_factor.unwrap_or(1.0),
                },
                Some(ConfidenceName::SubGaussian) | None => defaults.confidence,
            },
            lb1_requirement: match self.lb1_requirement {
                Some(Lb1Name::Full) => Lb1Requirement::Full,
                Some(Lb1Name::Split) | None => defaults.lb1_requirement,
            },
            alternating: self.alternating.unwrap_or(false),
            reference_batch: if sampled {
                self.reference_batch.unwrap_or(defaults.reference_batch)
            } else {
                0
            },
            overrides,
            accounting: match self.accounting {
                Some(AccountingName::Estimated) => Accounting::Estimated,
                Some(AccountingName::Certified) | None => defaults.accounting,
            },
            schedule: match self.schedule {
                Some(ScheduleName::Iteration) => WidthSchedule::Iteration,
                Some(ScheduleName::Run) | None => defaults.schedule,
            },
            constants,
            on_contradiction,
        })
    }

    /// The confidence and estimator of the sampled mode (`None` for exact gradients).
    fn sampling(&self, gradients: GradientsName) -> Sampling {
        if gradients == GradientsName::Exact {
            return Sampling(None);
        }
        Sampling(Some((
            self.delta.unwrap_or(0.2),
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
            .unwrap_or(Values::One(-0.1))
            .expand(dim_v, "v0")?;
        let sigma0 = self
            .sigma0
            .clone()
            .unwrap_or(Values::One(1.0))
            .expand(dim_w, "sigma0")?;
        let budget0 = self.budget0.unwrap_or(if env == EnvName::MountainCar {
            1.0
        } else {
            0.0
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
        let batch = self.batch.unwrap_or(100);
        if batch < 2 {
            return Err(Error::invalid(format!(
                "batch N = {batch} must be at least 2"
            )));
        }
        let log_every = self.log_every.unwrap_or(1);
        let schedule = Schedule {
            batch,
            horizon: self.horizon.unwrap_or(default_horizon),
            iterations: self.iterations.unwrap_or(10_000),
            seed: self.seed.unwrap_or(0),
            log_every,
        };
        if log_every == 0 {
            return Err(Error::invalid("log-every must be at least 1"));
        }
        Ok(schedule)
    }

    /// The resolved options that come from the parts of [`RunSpec::resolve`] (every other
    /// option is `None`).
    fn resolved_values(
        method: &Method,
        sampling: &Sampling,
        start: Start,
        schedule: &Schedule,
        options: Option<&SepgOptions>,
    ) -> RunSpec {
        let one_or_many = |v: Vec<f64>| {
            if v.len() == 1 {
                Values::One(v[0])
            } else {
                Values::Many(v)
            }
        };
        let estimator = sampling.0.map(|(_, k, b, f)| (k, b, f));
        RunSpec {
            requirement: method.requirement,
            delta: sampling.0.map(|s| s.0),
            nu: method.nu,
            v0: Some(one_or_many(start.v0)),
            sigma0: Some(one_or_many(start.sigma0)),
            budget0: Some(start.budget0),
            alpha: method.alpha,
            beta: method.beta,
            lr: method.lr,
            lr_w: method.lr_w,
            batch: Some(schedule.batch),
            horizon: Some(schedule.horizon),
            iterations: Some(schedule.iterations),
            seed: Some(schedule.seed),
            estimator: estimator.map(|e| e.0),
            baseline: estimator.map(|e| e.1),
            baseline_fit: estimator.map(|e| e.2),
            log_every: Some(schedule.log_every),
            ..RunSpec::option_values(method, sampling, options)
        }
    }

    /// The resolved SEPG options and constant overrides: every SEPG option of a SEPG run (the
    /// sampled-only ones in the sampled mode), the overrides that were given.
    fn option_values(
        method: &Method,
        sampling: &Sampling,
        options: Option<&SepgOptions>,
    ) -> RunSpec {
        let Some(o) = options else {
            return RunSpec::default();
        };
        let (constants, rewards) = match o.constants {
            ConstantsFamily::Thesis => (ConstantsName::Thesis, None),
            ConstantsFamily::Tight { rewards } => {
                (ConstantsName::Tight, Some(RewardsName::of(rewards)))
            }
        };
        let overrides = RunSpec {
            gamma: o.overrides.gamma,
            r_max: o.overrides.r_max,
            m_phi: o.overrides.m_phi,
            action_volume: o.overrides.action_volume,
            psi: o.overrides.psi,
            constants: Some(constants),
            rewards,
            on_contradiction: (o.on_contradiction == OnContradiction::Continue)
                .then_some(OnContradictionName::Continue),
            ..RunSpec::default()
        };
        let (sepg, naive, lb1) = match method.algorithm {
            Algorithm::Sepg(r) => (true, false, matches!(r, Requirement::LbI { .. })),
            Algorithm::SepgNaiveW(r) => (true, true, matches!(r, Requirement::LbI { .. })),
            _ => (false, false, false),
        };
        if !sepg {
            return overrides;
        }
        let sampled = sampling.0.is_some();
        let (confidence, quantile_factor) = match o.confidence {
            Confidence::None => (ConfidenceName::None, None),
            Confidence::SubGaussian => (ConfidenceName::SubGaussian, None),
            Confidence::StudentT { factor } => (ConfidenceName::StudentT, Some(factor)),
        };
        let (w_direction, clip) = match o.w_direction {
            WDirection::CrossFitted => (WDirectionName::CrossFitted, None),
            WDirection::PlugIn => (WDirectionName::PlugIn, None),
            WDirection::Metagradient { clip } => (WDirectionName::Metagradient, Some(clip)),
        };
        let (v_direction, adam) = match o.v_direction {
            VDirection::Greedy => (VDirectionName::Greedy, None),
            VDirection::Adam {
                lr,
                beta1,
                beta2,
                eps,
            } => (VDirectionName::Adam, Some((lr, beta1, beta2, eps))),
        };
        RunSpec {
            v_direction: Some(v_direction),
            adam_lr: adam.map(|a| a.0),
            adam_beta1: adam.map(|a| a.1),
            adam_beta2: adam.map(|a| a.2),
            adam_eps: adam.map(|a| a.3),
            w_step: (!naive).then_some(match o.w_step {
                WStep::Exploring => WStepName::Exploring,
                WStep::Theorem49 => WStepName::Theorem49,
            }),
            w_direction: (!naive).then_some(w_direction),
            metagradient_clip: clip,
            confidence: sampled.then_some(confidence),
            quantile_factor: quantile_factor.filter(|_| sampled),
            lb1_requirement: lb1.then_some(match o.lb1_requirement {
                Lb1Requirement::Split => Lb1Name::Split,
                Lb1Requirement::Full => Lb1Name::Full,
            }),
            alternating: Some(o.alternating),
            reference_batch: sampled.then_some(o.reference_batch),
            accounting: Some(match o.accounting {
                Accounting::Certified => AccountingName::Certified,
                Accounting::Estimated => AccountingName::Estimated,
            }),
            schedule: sampled.then_some(match o.schedule {
                WidthSchedule::Run => ScheduleName::Run,
                WidthSchedule::Iteration => ScheduleName::Iteration,
            }),
            ..overrides
        }
    }
}

/// `Err` naming the option `what` and why it does not apply, when `set`.
fn reject(set: bool, what: &str, why: &str) -> Result<()> {
    if set {
        Err(Error::invalid(format!(
            "option {what} does not apply {why}"
        )))
    } else {
        Ok(())
    }
}

/// The algorithm of a run and the step options it uses.
struct Method {
    algorithm: Algorithm,
    requirement: Option<RequirementName>,
    nu: Option<f64>,
    alpha: Option<f64>,
    beta: Option<f64>,
    lr: Option<f64>,
    lr_w: Option<f64>,
}

/// δ, estimator, baseline and fit of the sampled mode; `None` for exact gradients.
struct Sampling(Option<(f64, EstimatorName, BaselineName, FitName)>);

impl Sampling {
    fn gradient(&self) -> GradientMode {
        match self.0 {
            Some((delta, ..)) => GradientMode::Sampled { delta },
            None => GradientMode::Exact,
        }
    }

    fn gradient_spec(&self) -> GradientSpec {
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
struct Start {
    v0: Vec<f64>,
    sigma0: Vec<f64>,
    budget0: f64,
}

/// Parses a seed: a non-negative integer below 2⁶⁴ (seeds index the random streams of
/// `sepg_mdp::rng`, which are keyed by unsigned 64-bit integers). The message says why a
/// negative or non-integer value is refused.
///
/// # Errors
/// A one-line message for anything else.
///
/// # Example
/// ```
/// use sepg_runs::spec::parse_seed;
/// assert_eq!(parse_seed("7"), Ok(7));
/// assert!(parse_seed("-1").unwrap_err().contains("non-negative"));
/// ```
pub fn parse_seed(s: &str) -> std::result::Result<u64, String> {
    s.trim().parse::<u64>().map_err(|_| {
        let why = if s.trim().parse::<i128>().is_ok_and(|x| x < 0) {
            "it is negative"
        } else if s.trim().parse::<i128>().is_ok() {
            "it is too large"
        } else {
            "it is not an integer"
        };
        format!("a seed is a non-negative integer in 0..=18446744073709551615 (u64), and {why}")
    })
}

/// Batch size, horizon, iterations, seed and log stride.
struct Schedule {
    batch: usize,
    horizon: usize,
    iterations: u64,
    seed: u64,
    log_every: u64,
}

/// The first line of a TOML error, without the source excerpt.
pub fn toml_message(e: &toml::de::Error) -> String {
    let msg = e.message().trim().to_owned();
    match e.span() {
        Some(span) => format!("{msg} (at byte {})", span.start),
        None => msg,
    }
}

fn build_env(name: EnvName, features: Option<&str>) -> Result<AnyEnv> {
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
                    .map_err(|e| Error::invalid(format!("features {f:?}: {e}")))?
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
    /// The resolved configuration as TOML text. The options are followed by comment lines
    /// that state the constants the bounds use: their family, and for the tight family its
    /// horizon, reward sign and S_H, then c and d at σ⁰ (comments, so that reading the file
    /// back sees the options only).
    ///
    /// # Errors
    /// [`Error::Failed`] if serialisation fails.
    pub fn toml(&self) -> Result<String> {
        let mut text = toml::to_string(&self.spec)
            .map_err(|e| Error::failed(format!("cannot serialise the configuration: {e}")))?;
        let used = crate::folder::UsedConstants::of(self);
        text.push_str(&format!(
            "# constants used by the bounds: {}",
            used.family.name()
        ));
        if let (Some(h), Some(r), Some(s_h)) = (used.horizon, used.rewards, used.s_h) {
            let sign = match r {
                RewardsName::TwoSided => "two-sided",
                RewardsName::NonPositive => "non-positive",
            };
            text.push_str(&format!(", horizon {h}, rewards {sign}, S_H = {s_h:?}"));
        }
        let list = |v: &[Option<f64>]| {
            let items: Vec<String> = v
                .iter()
                .map(|x| x.map_or_else(|| "not representable".to_owned(), |x| format!("{x:?}")))
                .collect();
            format!("[{}]", items.join(", "))
        };
        text.push_str(&format!(
            "\n# c(sigma0) = {}\n# d(sigma0) = {}\n",
            list(&used.c_sigma0),
            list(&used.d_sigma0)
        ));
        Ok(text)
    }

    /// v* of the LQG environments (the unclipped infinite-horizon optimum of the closed-form oracle), `None`
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

#[cfg(test)]
mod tests {
    use super::*;

    fn lqg1d(f: impl FnOnce(&mut RunSpec)) -> Result<Resolved> {
        let mut spec = RunSpec {
            env: Some(EnvName::Lqg1d),
            iterations: Some(1),
            ..RunSpec::default()
        };
        f(&mut spec);
        spec.resolve()
    }

    #[test]
    fn sizes_are_refused_at_resolution_exactly_above_their_limits() {
        // lqg1d, H = 20, one parameter of each kind: (20 · 3 + 1) · 8 = 488 bytes per
        // trajectory; 8 GiB = 8,589,934,592 bytes hold 17,602,324 of them
        // (8,589,934,112 bytes), one more needs 8,589,934,600.
        assert!(lqg1d(|s| s.batch = Some(17_602_324)).is_ok());
        let e = lqg1d(|s| s.batch = Some(17_602_325)).expect_err("too large");
        assert!(e.is_invalid_input(), "{e}");
        let e = lqg1d(|s| s.batch = Some(usize::MAX)).expect_err("overflow");
        assert!(e.to_string().contains("more than 2^64 bytes"), "{e}");
        assert!(lqg1d(|s| s.horizon = Some(MAX_HORIZON)).is_ok());
        let e = lqg1d(|s| s.horizon = Some(MAX_HORIZON + 1)).expect_err("horizon");
        assert!(e.is_invalid_input(), "{e}");
        let e = lqg1d(|s| s.iterations = Some(MAX_ITERATIONS + 1)).expect_err("iterations");
        assert!(e.is_invalid_input(), "{e}");
        // 2^30 returns of 8 bytes are exactly 8 GiB.
        assert!(lqg1d(|s| s.reference_batch = Some(1 << 30)).is_ok());
        assert!(lqg1d(|s| s.reference_batch = Some((1 << 30) + 1)).is_err());
    }

    #[test]
    fn an_initial_policy_the_policy_cannot_represent_is_refused_at_resolution() {
        // w = ln σ must satisfy |w| < 354: ln(1e153) = 352.3 passes, ln(1e154) = 354.6 not.
        assert!(lqg1d(|s| s.sigma0 = Some(Values::One(1e153))).is_ok());
        for sigma in [1e154, 1e300, 1e-154] {
            let e = lqg1d(|s| s.sigma0 = Some(Values::One(sigma))).expect_err("refused");
            assert!(
                e.is_invalid_input() && e.to_string().contains("sigma0"),
                "{e}"
            );
        }
    }

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

    /// Every SEPG option reaches the algorithm's configuration, is written back into the
    /// resolved specification, and survives a round trip through config.toml.
    #[test]
    fn sepg_options_resolve_and_round_trip() {
        let spec = RunSpec {
            env: Some(EnvName::Lqg1d),
            algo: Some(AlgoName::SepgLb1),
            w_step: Some(WStepName::Theorem49),
            w_direction: Some(WDirectionName::Metagradient),
            metagradient_clip: Some(50.0),
            confidence: Some(ConfidenceName::StudentT),
            quantile_factor: Some(2.0),
            lb1_requirement: Some(Lb1Name::Full),
            alternating: Some(true),
            accounting: Some(AccountingName::Estimated),
            reference_batch: Some(0),
            gamma: Some(0.9),
            r_max: Some(30.0),
            psi: Some(0.53),
            scores: Some(ScoresName::Clipped),
            ..RunSpec::default()
        };
        let once = spec.resolve().expect("valid");
        assert_eq!(once.checked.config().score_action, ScoreAction::Clipped);
        let o = once.checked.config().options;
        assert_eq!(o.w_step, WStep::Theorem49);
        assert_eq!(o.w_direction, WDirection::Metagradient { clip: 50.0 });
        assert_eq!(o.confidence, Confidence::StudentT { factor: 2.0 });
        assert_eq!(o.lb1_requirement, Lb1Requirement::Full);
        assert!(o.alternating);
        assert_eq!(o.accounting, Accounting::Estimated);
        assert_eq!(o.reference_batch, 0);
        assert_eq!(once.checked.constants().gamma(), 0.9);
        assert_eq!(once.checked.constants().r_max(), 30.0);
        assert_eq!(once.checked.constants().psi_override(), Some(0.53));
        assert_eq!(once.spec.m_phi, None);
        let text = once.toml().expect("toml");
        assert!(
            text.contains("w-step = \"theorem-4.9\"") && text.contains("quantile-factor = 2.0")
        );
        assert!(text.contains("psi = 0.53"), "{text}");
        assert!(text.contains("scores = \"clipped\""), "{text}");
        let again: RunSpec = toml::from_str(&text).expect("parse");
        let twice = again.resolve().expect("valid");
        assert_eq!(once.spec, twice.spec);
        assert_eq!(once.checked, twice.checked);
        // The defaults are written out too.
        let plain = RunSpec {
            algo: Some(AlgoName::SepgZv),
            ..RunSpec::default()
        }
        .resolve()
        .expect("valid");
        assert_eq!(plain.spec.w_step, Some(WStepName::Exploring));
        assert_eq!(plain.spec.confidence, Some(ConfidenceName::SubGaussian));
        assert_eq!(plain.spec.reference_batch, Some(1000));
        assert_eq!(plain.spec.lb1_requirement, None);
        assert_eq!(plain.checked.constants().psi_override(), None);
        assert_eq!(plain.spec.scores, Some(ScoresName::Raw));
        assert_eq!(plain.checked.config().score_action, ScoreAction::Raw);
    }

    #[test]
    fn sepg_options_that_do_not_apply_are_rejected() {
        let bad = [
            RunSpec {
                algo: Some(AlgoName::GpomdpAdam),
                lr: Some(1e-3),
                w_step: Some(WStepName::Exploring),
                ..RunSpec::default()
            },
            RunSpec {
                algo: Some(AlgoName::SepgZv),
                lb1_requirement: Some(Lb1Name::Full),
                ..RunSpec::default()
            },
            RunSpec {
                algo: Some(AlgoName::SepgZv),
                alternating: Some(true),
                ..RunSpec::default()
            },
            RunSpec {
                algo: Some(AlgoName::SepgZv),
                metagradient_clip: Some(1.0),
                ..RunSpec::default()
            },
            RunSpec {
                algo: Some(AlgoName::SepgZv),
                confidence: Some(ConfidenceName::None),
                quantile_factor: Some(2.0),
                ..RunSpec::default()
            },
            RunSpec {
                gradients: Some(GradientsName::Exact),
                reference_batch: Some(10),
                ..RunSpec::default()
            },
            RunSpec {
                gradients: Some(GradientsName::Exact),
                scores: Some(ScoresName::Clipped),
                ..RunSpec::default()
            },
            RunSpec {
                algo: Some(AlgoName::SepgNaiveW),
                w_direction: Some(WDirectionName::PlugIn),
                ..RunSpec::default()
            },
        ];
        for spec in bad {
            assert!(spec.resolve().is_err(), "{spec:?}");
        }
    }

    /// The constants family: tight by default with the preset's reward sign and the run's
    /// horizon, the thesis's on request; `rewards` only with the tight family, and
    /// non-positive refused on Mountain Car; every choice survives config.toml.
    #[test]
    fn the_constants_family_resolves_and_round_trips() {
        use sepg_bounds::penalties::{Family, Horizon, Rewards, Tight};
        let tight = |h, r| Family::Tight(Tight::new(Horizon::Finite(h), r));
        let cases = [
            (RunSpec::default(), tight(20, Rewards::NonPositive)),
            (
                RunSpec {
                    env: Some(EnvName::MountainCar),
                    horizon: Some(30),
                    ..RunSpec::default()
                },
                tight(30, Rewards::TwoSided),
            ),
            (
                RunSpec {
                    rewards: Some(RewardsName::TwoSided),
                    algo: Some(AlgoName::Adastep),
                    ..RunSpec::default()
                },
                tight(20, Rewards::TwoSided),
            ),
            (
                RunSpec {
                    constants: Some(ConstantsName::Thesis),
                    r_max: Some(3.0),
                    ..RunSpec::default()
                },
                Family::Thesis,
            ),
        ];
        for (spec, family) in cases {
            let once = spec.resolve().expect("valid");
            assert_eq!(once.checked.constants().family(), family, "{spec:?}");
            let again: RunSpec = toml::from_str(&once.toml().expect("toml")).expect("parse");
            let twice = again.resolve().expect("valid");
            assert_eq!(once.spec, twice.spec);
            assert_eq!(once.checked, twice.checked);
        }
        for bad in [
            RunSpec {
                constants: Some(ConstantsName::Thesis),
                rewards: Some(RewardsName::TwoSided),
                ..RunSpec::default()
            },
            RunSpec {
                env: Some(EnvName::MountainCar),
                rewards: Some(RewardsName::NonPositive),
                ..RunSpec::default()
            },
        ] {
            assert!(bad.resolve().is_err(), "{bad:?}");
        }
    }

    /// Safe Adam: the TOML keys build the algorithm's `VDirection::Adam` with the usual betas
    /// by default, survive config.toml, and are refused without `v_direction = "adam"`, without
    /// a learning rate, with the thesis's constants, with the estimated accounting and for the
    /// comparison algorithms.
    #[test]
    fn the_adam_v_direction_resolves_round_trips_and_is_refused_where_unproven() {
        let spec: RunSpec = toml::from_str(
            "algo = \"sepg-mi\"\nv-direction = \"adam\"\nadam-lr = 0.1\nadam-beta2 = 0.99\n",
        )
        .expect("parse");
        let once = spec.resolve().expect("valid");
        assert_eq!(
            once.checked.config().options.v_direction,
            VDirection::Adam {
                lr: 0.1,
                beta1: 0.9,
                beta2: 0.99,
                eps: 1e-8
            }
        );
        let again: RunSpec = toml::from_str(&once.toml().expect("toml")).expect("parse");
        let twice = again.resolve().expect("valid");
        assert_eq!(once.spec, twice.spec);
        assert_eq!(once.checked, twice.checked);
        let greedy = RunSpec::default().resolve().expect("valid");
        assert_eq!(greedy.spec.v_direction, Some(VDirectionName::Greedy));
        assert_eq!(
            greedy.checked.config().options.v_direction,
            VDirection::Greedy
        );
        let adam = |more: RunSpec| RunSpec {
            v_direction: Some(VDirectionName::Adam),
            adam_lr: Some(0.1),
            ..more
        };
        for bad in [
            RunSpec {
                adam_lr: Some(0.1),
                ..RunSpec::default()
            },
            RunSpec {
                v_direction: Some(VDirectionName::Greedy),
                adam_eps: Some(1e-6),
                ..RunSpec::default()
            },
            RunSpec {
                v_direction: Some(VDirectionName::Adam),
                ..RunSpec::default()
            },
            adam(RunSpec {
                constants: Some(ConstantsName::Thesis),
                ..RunSpec::default()
            }),
            adam(RunSpec {
                accounting: Some(AccountingName::Estimated),
                ..RunSpec::default()
            }),
            adam(RunSpec {
                algo: Some(AlgoName::Adastep),
                ..RunSpec::default()
            }),
            adam(RunSpec {
                adam_beta1: Some(1.0),
                ..RunSpec::default()
            }),
        ] {
            assert!(bad.resolve().is_err(), "{bad:?}");
        }
    }

    #[test]
    fn algorithm_names_are_the_configuration_names() {
        let all = [
            AlgoName::SepgMi,
            AlgoName::SepgLb1,
            AlgoName::SepgLb2,
            AlgoName::SepgLv,
            AlgoName::SepgZv,
            AlgoName::SepgSim,
            AlgoName::SepgNaiveW,
            AlgoName::GpomdpConst,
            AlgoName::GpomdpAdam,
            AlgoName::Adastep,
        ];
        for algo in all {
            let spec = RunSpec {
                algo: Some(algo),
                ..RunSpec::default()
            };
            let text = toml::to_string(&spec).expect("toml");
            assert_eq!(text.trim(), format!("algo = \"{}\"", algo.name()));
        }
    }
}
