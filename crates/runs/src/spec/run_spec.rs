//! [`RunSpec`], every option of a run, read from TOML and overlaid.

use std::fs;
use std::path::Path;

#[cfg(feature = "clap")]
use clap::Args;
use serde::{Deserialize, Serialize};

use super::names::{
    AccountingName, AlgoName, BaselineName, BatchRuleName, ConfidenceName, ConstantsName, EnvName,
    EstimatorName, FitName, GradientsName, Lb1Name, OnContradictionName, RequirementName,
    RewardsName, ScheduleName, ScoresName, VDirectionName, WDirectionName, WStepName,
};
use super::values::Values;
#[cfg(feature = "clap")]
use super::values::{parse_seed, parse_values};
use crate::error::{Error, Result};

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
    /// How many trajectories each block of a sampled SEPG iteration draws: N split evenly, or
    /// the adaptive batch size (certified accounting only; needs batch-min and batch-max)
    /// [default: fixed].
    #[cfg_attr(feature = "clap", arg(long = "batch-rule", value_enum))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub batch_rule: Option<BatchRuleName>,
    /// Smallest block size of the adaptive batch rule, in trajectories (≥ 2).
    #[cfg_attr(
        feature = "clap",
        arg(long = "batch-min", allow_negative_numbers = true)
    )]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub batch_min: Option<usize>,
    /// Largest block size of the adaptive batch rule, in trajectories (≥ batch-min).
    #[cfg_attr(
        feature = "clap",
        arg(long = "batch-max", allow_negative_numbers = true)
    )]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub batch_max: Option<usize>,
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
            accounting, schedule, constants, rewards, on_contradiction, batch_rule, batch_min,
            batch_max)
    }

    /// Reads a TOML file of options; unknown keys are rejected.
    ///
    /// # Errors
    /// [`Error::Invalid`] for a missing or unreadable file or an invalid key or value.
    pub fn from_file(path: &Path) -> Result<RunSpec> {
        let text = fs::read_to_string(path)
            .map_err(|e| Error::invalid_from(format!("cannot read {}", path.display()), e))?;
        toml::from_str(&text)
            .map_err(|e| Error::invalid(format!("{}: {}", path.display(), toml_message(&e))))
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
