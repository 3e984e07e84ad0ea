//! Options of SEPG beyond the thesis's pseudocode: the default, exploring and guaranteed
//! choices, and the choices of the thesis-era public code (potion, `algorithms/safe.py`,
//! January 2019) that reproduce the published numbers without their guarantee.
//!
//! | option | default | thesis-era code |
//! |---|---|---|
//! | [`SepgOptions::w_step`] | [`WStep::Exploring`] | (δ = 1 makes both forms Theorem 4.5) |
//! | [`SepgOptions::w_direction`] | [`WDirection::CrossFitted`] | [`WDirection::Metagradient`] |
//! | [`SepgOptions::confidence`] | [`Confidence::SubGaussian`] (proven) | [`Confidence::None`] (δ = 1), or Student-t with factor 2 |
//! | [`SepgOptions::lb1_requirement`] | [`Lb1Requirement::Split`] | [`Lb1Requirement::Full`] |
//! | [`SepgOptions::alternating`] | `false` | `true` |
//! | [`SepgOptions::reference_batch`] | 1000 | 0 |
//! | [`SepgOptions::overrides`] | none | γ = 0.9 in its script, ψ = 0.53 in d |
//! | [`SepgOptions::accounting`] | [`Accounting::Certified`] | [`Accounting::Estimated`] |
//! | [`SepgOptions::schedule`] | [`Schedule::Run`] | [`Schedule::Iteration`] |
//! | [`SepgOptions::v_direction`] | [`VDirection::Greedy`] | [`VDirection::Greedy`] |
//! | [`SepgOptions::constants`] | [`ConstantsFamily::Thesis`] (`sepg run`: tight) | [`ConstantsFamily::Thesis`] |
//!
//! Serialised (the `options` of a run's `summary.json`), every choice is named in kebab-case as
//! in `config.toml` (`"cross-fitted"`, `{"student-t": {"factor": 2.0}}`, `"theorem-4.9"`); the
//! PascalCase names that older summaries wrote (`"CrossFitted"`, `{"StudentT": …}`) are read
//! as well.

use crate::core::check::OnContradiction;
use crate::core::defaults::{
    DEFAULT_ADAM_BETA1, DEFAULT_ADAM_BETA2, DEFAULT_ADAM_EPS, DEFAULT_QUANTILE_FACTOR,
    DEFAULT_REFERENCE_BATCH, LIBRARY_CONSTANTS,
};
use sepg_bounds::penalties::{Family, Horizon, Rewards, Tight};
use serde::{Deserialize, Serialize};

use crate::core::error::ConfigError;

/// How the w-update turns its estimates into a safe step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum WStep {
    /// The exploring w-update (docs/THEOREMS.md, `sepg_bounds::exploring`): the step goes
    /// as far along the chosen direction as the bound of Theorem 4.3 with the confidence on
    /// ∇_w J alone allows. The width of the direction's estimate plays no role.
    #[default]
    #[serde(alias = "Exploring")]
    Exploring,
    /// Theorem 4.9 in the sign-aware form: corrected norms L⁻J⁻, no update when the direction
    /// is within its confidence width (eq. 4.23).
    #[serde(rename = "theorem-4.9", alias = "Theorem49")]
    Theorem49,
}

/// The direction of the w-update.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum WDirection {
    /// ∇̂_w L, cross-fitted on two halves of the batch (unbiased, `sepg_estimators`).
    #[default]
    #[serde(alias = "CrossFitted")]
    CrossFitted,
    /// ∇̂_w L from full-batch plug-in products ‖∇̂_v J‖² and ⟨∇̂_v J, ∂̂_σ∇_v J⟩, biased
    /// upwards by the variance of ∇̂_v J.
    #[serde(alias = "PlugIn")]
    PlugIn,
    /// The thesis-era code's direction: the w-derivative of J + α‖∇_v J‖² with α the step
    /// size of the latest v-update (scalar actions only):
    /// `∇̂_w J + 2α‖∇̂_v J‖² + clip(2σα⟨∇̂_v J, ∂̂_σ∇_v J⟩, ±clip)`.
    #[serde(alias = "Metagradient")]
    Metagradient {
        /// The clipping threshold of the last term (100 in the thesis-era code).
        clip: f64,
    },
}

/// The confidence widths ε of the sampled mode (Section 4.5).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Confidence {
    /// Widths proven at every batch size from the task's constants R, M_φ, σ, γ and H
    /// (`sepg_estimators::proven`, docs/THEOREMS.md "Proven confidence widths"): the
    /// gradients a guarantee rests on are estimated by G(PO)MDP with a constant baseline, and
    /// ε_i is the sub-Gaussian (∇_v J) or sub-exponential (∇_w J) width of that estimator. The
    /// direction ∇̂_w L, which carries no guarantee, keeps Student-t widths.
    #[default]
    #[serde(alias = "SubGaussian")]
    SubGaussian,
    /// ε = 0: the estimates are used as if exact (the thesis-era code's default δ = 1).
    #[serde(alias = "None")]
    None,
    /// ε_i = factor · t(1 − δ/2, N − 1) · √(Var_i/N); the thesis-era code used factor 2.
    #[serde(alias = "StudentT")]
    StudentT {
        /// Multiplier of the Student-t quantile (> 0).
        factor: f64,
    },
}

impl Confidence {
    /// The multiplier of every confidence width: 0 for [`Confidence::None`].
    ///
    /// # Examples
    /// ```
    /// use sepg_algo::core::options::Confidence;
    /// assert_eq!(Confidence::None.factor(), 0.0);
    /// assert_eq!(Confidence::StudentT { factor: 2.0 }.factor(), 2.0);
    /// ```
    pub fn factor(self) -> f64 {
        match self {
            Confidence::None => 0.0,
            Confidence::StudentT { factor } => factor,
            Confidence::SubGaussian => 1.0,
        }
    }
}

/// How LB-I's requirement C = J(θ⁰) − J is shared between the two half-steps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Lb1Requirement {
    /// (1 − ν)Cᵗ for the v-update and νCᵗ for the w-update, Cᵗ = J(θ⁰) − J(θᵗ)
    /// (eqs. 4.13, 4.14).
    #[default]
    #[serde(alias = "Split")]
    Split,
    /// Each half-step gets the whole requirement measured at its own start:
    /// J(θ⁰) − J(vᵗ, wᵗ) for the v-update, J(θ⁰) − J(vᵗ⁺¹, wᵗ) for the w-update.
    #[serde(alias = "Full")]
    Full,
}

/// What the safety requirements are built on (docs/THEOREMS.md, "Statements over a whole
/// run").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Accounting {
    /// Certified quantities only: LB-I's surplus and the type-II budget are sums of the
    /// guaranteed improvements of the steps actually applied (each the certified lower end
    /// of its bound), rounded down; on the confidence events they are lower bounds of
    /// J(θᵗ) − J(θ⁰), so every requirement holds against exact J. No estimate of J enters.
    #[default]
    #[serde(alias = "Certified")]
    Certified,
    /// The thesis's bookkeeping (Sec 4.4.4): LB-I's J(θ⁰) − Ĵᵗ and the budget's measured
    /// differences of estimated J (with the reference batch's upper bound Û⁰). Kept for
    /// reproduction; it carries no statement about exact J.
    #[serde(alias = "Estimated")]
    Estimated,
}

impl Accounting {
    /// The bookkeeping of summaries written before the option existed.
    fn legacy() -> Self {
        Accounting::Estimated
    }
}

/// How many trajectories each block of a sampled SEPG iteration draws, set on a solver with
/// [`PolicySolver::with_batch_rule`](crate::solver::PolicySolver::with_batch_rule).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BatchRule {
    /// N trajectories per iteration, split evenly among its blocks (Algorithm 4.3).
    #[default]
    Fixed,
    /// The adaptive batch size (docs/THEOREMS.md "An adaptive batch size"): the first
    /// iteration splits N as [`BatchRule::Fixed`] does; every later block draws the n that
    /// maximises the guaranteed improvement per trajectory of the greedy v-step, computed from
    /// the previous iteration's v-block ([`crate::solver::batch::next_batch`]) and clamped to
    /// `[n_min, n_max]` (trajectories per block).
    Adaptive {
        /// Smallest block size (≥ 2, for the Student-t widths).
        n_min: usize,
        /// Largest block size (≥ `n_min`).
        n_max: usize,
    },
}

impl BatchRule {
    /// Whether the rule is [`BatchRule::Fixed`].
    ///
    /// # Examples
    /// ```
    /// use sepg_algo::core::options::BatchRule;
    /// assert!(BatchRule::default().is_fixed());
    /// ```
    pub fn is_fixed(&self) -> bool {
        *self == BatchRule::Fixed
    }

    /// Checks the rule for a solver with the given `accounting`.
    ///
    /// # Errors
    /// [`ConfigError::InvalidHyperParameter`] for an adaptive rule with `n_min < 2` or
    /// `n_max < n_min`; [`ConfigError::UnsupportedOption`] for an adaptive rule with the
    /// estimated accounting (only the certified iteration reads the rule).
    ///
    /// # Examples
    /// ```
    /// use sepg_algo::core::options::{Accounting, BatchRule};
    /// let rule = BatchRule::Adaptive { n_min: 50, n_max: 250_000 };
    /// assert!(rule.validate(Accounting::Certified).is_ok());
    /// assert!(rule.validate(Accounting::Estimated).is_err());
    /// ```
    pub fn validate(&self, accounting: Accounting) -> Result<(), ConfigError> {
        let BatchRule::Adaptive { n_min, n_max } = *self else {
            return Ok(());
        };
        let bad = |name, value: usize, domain| ConfigError::InvalidHyperParameter {
            name,
            value: value as f64,
            domain,
        };
        if n_min < 2 {
            return Err(bad("adaptive batch n_min", n_min, "[2, n_max]"));
        }
        if n_max < n_min {
            return Err(bad("adaptive batch n_max", n_max, "[n_min, inf)"));
        }
        if accounting == Accounting::Estimated {
            return Err(ConfigError::UnsupportedOption {
                option: "batch",
                reason: "the adaptive batch size needs the certified accounting",
            });
        }
        Ok(())
    }
}

/// The direction of the v-update.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum VDirection {
    /// The greedy coordinate of Theorem 4.2 / eq. (4.11): the coordinate of the largest
    /// |∇̂_{v_k}J|, with the largest safe step along it.
    #[default]
    #[serde(alias = "Greedy")]
    Greedy,
    /// "Safe Adam": Adam (Kingma and Ba 2015) proposes the change u from its moments of the
    /// v-gradient estimates, and the applied change is t·u with t = min(1, the largest t whose
    /// bound along u meets the v-block's requirement) (`sepg_bounds::direction`,
    /// docs/THEOREMS.md "A step along any direction"): never longer than Adam's own change.
    /// Proven with the tight constants only (Theorem T); the certified accounting only.
    #[serde(alias = "Adam")]
    Adam {
        /// Learning rate (> 0, units of v per step).
        lr: f64,
        /// First-moment decay β₁ ∈ [0, 1).
        beta1: f64,
        /// Second-moment decay β₂ ∈ [0, 1).
        beta2: f64,
        /// Denominator offset ε > 0 (units of ∇_vJ).
        eps: f64,
    },
}

impl VDirection {
    /// Adam with the usual defaults β₁ = 0.9, β₂ = 0.999, ε = 1e-8 and learning rate `lr`.
    ///
    /// # Examples
    /// ```
    /// use sepg_algo::core::options::VDirection;
    /// assert!(matches!(VDirection::adam(1e-2), VDirection::Adam { beta2, .. } if beta2 == 0.999));
    /// ```
    pub fn adam(lr: f64) -> Self {
        VDirection::Adam {
            lr,
            beta1: DEFAULT_ADAM_BETA1,
            beta2: DEFAULT_ADAM_BETA2,
            eps: DEFAULT_ADAM_EPS,
        }
    }

    /// Whether this is the default greedy coordinate (not written to summaries, so that
    /// they read as before the option existed).
    pub fn is_greedy(&self) -> bool {
        *self == VDirection::Greedy
    }
}

/// How the confidence δ is spread over the confidence statements of a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Schedule {
    /// Over the whole run: iteration t of T gets δ/T, split evenly over its K scalar
    /// confidence statements (every component of every estimated gradient a guarantee rests
    /// on), so that by the union bound P(any statement of the run fails) ≤ δ.
    #[default]
    #[serde(alias = "Run")]
    Run,
    /// Every width at level δ (the thesis): each iteration's requirement holds with
    /// probability about 1 − δ, not the whole run's.
    #[serde(alias = "Iteration")]
    Iteration,
}

impl Schedule {
    /// The schedule of summaries written before the option existed.
    fn legacy() -> Self {
        Schedule::Iteration
    }
}

/// What is known of the sign of every reward r_t of a task (|r_t| ≤ R always).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RewardSign {
    /// Rewards of either sign: the two-sided tight constants (ρ = 1). Always sound.
    #[serde(alias = "TwoSided")]
    TwoSided,
    /// −R ≤ r_t ≤ 0 for every t (the LQG presets, whose reward −(sᵀQs + aᵀRa) has Q and R
    /// positive semi-definite): the tight constants halve (ρ = 1/2).
    #[serde(alias = "NonPositive")]
    NonPositive,
}

impl RewardSign {
    /// The reward sign of `sepg-bounds`' tight family.
    pub fn rewards(self) -> Rewards {
        match self {
            RewardSign::TwoSided => Rewards::TwoSided,
            RewardSign::NonPositive => Rewards::NonPositive,
        }
    }
}

/// The family of constants that gives the penalty coefficients c(σ) and d(σ) of every bound
/// of a run (docs/THEOREMS.md, "Tight constants").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ConstantsFamily {
    /// c of Theorems 3.14 / 4.2 and d of Theorem 4.3 (the thesis).
    #[default]
    #[serde(alias = "Thesis")]
    Thesis,
    /// The tight constants c = ρ R M_φ² S_H / σ² and d = 2ρ R S_H of Theorem T, with S_H for
    /// the run's horizon H ([`crate::core::config::SepgConfig::horizon`]).
    #[serde(alias = "Tight")]
    Tight {
        /// What is known of the rewards' sign (ρ = 1 two-sided, 1/2 non-positive).
        rewards: RewardSign,
    },
}

impl ConstantsFamily {
    /// The family of summaries written before the option existed: the thesis's.
    fn legacy() -> Self {
        ConstantsFamily::Thesis
    }

    /// The family of `sepg-bounds` for a run of `horizon` steps.
    ///
    /// # Examples
    /// ```
    /// use sepg_algo::core::options::{ConstantsFamily, RewardSign};
    /// use sepg_bounds::penalties::{Family, Horizon, Rewards, Tight};
    /// let f = ConstantsFamily::Tight { rewards: RewardSign::NonPositive };
    /// let expected = Family::Tight(Tight::new(Horizon::Finite(20), Rewards::NonPositive));
    /// assert_eq!(f.family(20), expected);
    /// assert_eq!(ConstantsFamily::Thesis.family(20), Family::Thesis);
    /// ```
    pub fn family(self, horizon: usize) -> Family {
        match self {
            ConstantsFamily::Thesis => Family::Thesis,
            ConstantsFamily::Tight { rewards } => Family::Tight(Tight::new(
                Horizon::Finite(horizon as u64),
                rewards.rewards(),
            )),
        }
    }
}

/// Overrides of the task constants R, M_φ, |A|, γ and ψ that the bounds use.
///
/// `gamma` also changes the environment's discount, so J itself changes; the others only
/// change the bounds (they must stay valid bounds for the guarantees to hold).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ConstantOverrides {
    /// Discount factor γ ∈ [0, 1).
    pub gamma: Option<f64>,
    /// Maximal absolute reward R.
    pub r_max: Option<f64>,
    /// Maximal absolute feature M_φ.
    pub m_phi: Option<f64>,
    /// Action-space volume |A|.
    pub action_volume: Option<f64>,
    /// ψ of Lemma A.1 in d (Theorem 4.3); the thesis-era code used 0.53. The bounds hold for
    /// any value ≥ ψ = 0.52355702032137… (`sepg_bounds::constants::psi`); a smaller value,
    /// 0.523557 included, voids them.
    pub psi: Option<f64>,
}

/// SEPG options (see the module documentation for the defaults and the thesis-era values).
///
/// # Examples
/// ```
/// use sepg_algo::core::options::{SepgOptions, WStep};
/// let o = SepgOptions::default();
/// assert_eq!(o.w_step, WStep::Exploring);
/// assert_eq!(o.reference_batch, 1000);
/// assert!(o.validate().is_ok());
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SepgOptions {
    /// The form of the w-update.
    pub w_step: WStep,
    /// The direction of the w-update.
    pub w_direction: WDirection,
    /// The confidence widths of the sampled mode.
    pub confidence: Confidence,
    /// LB-I's requirement per half-step.
    pub lb1_requirement: Lb1Requirement,
    /// Alternate v-iterations and w-iterations, each with all N trajectories (MI and LB-I
    /// only), instead of a v-block and a w-block in every iteration.
    pub alternating: bool,
    /// N₀ trajectories of a reference batch that estimates J(θ⁰) (and the first target's J)
    /// before the first iteration of LB-I and the type-II requirements, used through its
    /// upper confidence bound Ĵ⁰ + ε₀ (one-sided, level δ); 0 takes J(θ⁰) from the first
    /// v-block with no confidence bound (the thesis's pseudocode). Sampled mode only.
    pub reference_batch: usize,
    /// Overrides of γ, R, M_φ, |A|.
    pub overrides: ConstantOverrides,
    /// What the requirements are built on.
    #[serde(default = "Accounting::legacy")]
    pub accounting: Accounting,
    /// How δ is spread over the run's confidence statements.
    #[serde(default = "Schedule::legacy")]
    pub schedule: Schedule,
    /// The direction of the v-update.
    #[serde(default, skip_serializing_if = "VDirection::is_greedy")]
    pub v_direction: VDirection,
    /// The family of the penalty coefficients c and d, applied by
    /// [`crate::core::config::SepgConfig::check`] (a solver built from a collector takes the
    /// family of the task constants it is given). Absent from summaries written before the
    /// option existed, which used the thesis's.
    #[serde(default = "ConstantsFamily::legacy")]
    pub constants: ConstantsFamily,
    /// What the run does when an observed reward or feature contradicts the declared
    /// constants ([`crate::core::check`]): stop (the default) or continue without a guarantee.
    #[serde(default, skip_serializing_if = "OnContradiction::is_stop")]
    pub on_contradiction: OnContradiction,
}

impl Default for SepgOptions {
    fn default() -> Self {
        SepgOptions {
            w_step: WStep::Exploring,
            w_direction: WDirection::CrossFitted,
            confidence: Confidence::default(),
            lb1_requirement: Lb1Requirement::Split,
            alternating: false,
            reference_batch: DEFAULT_REFERENCE_BATCH,
            overrides: ConstantOverrides::default(),
            accounting: Accounting::Certified,
            schedule: Schedule::Run,
            v_direction: VDirection::Greedy,
            // The reward sign is read by the tight family only: two-sided is always sound.
            constants: LIBRARY_CONSTANTS.family(RewardSign::TwoSided),
            on_contradiction: OnContradiction::Stop,
        }
    }
}

impl SepgOptions {
    /// The defaults with the thesis's bookkeeping: requirements built on estimated J
    /// ([`Accounting::Estimated`]), Student-t widths (Sec 4.5) and every width at level δ
    /// ([`Schedule::Iteration`]).
    ///
    /// # Examples
    /// ```
    /// use sepg_algo::core::options::{Accounting, Schedule, SepgOptions};
    /// let o = SepgOptions::estimated();
    /// assert_eq!((o.accounting, o.schedule), (Accounting::Estimated, Schedule::Iteration));
    /// ```
    pub fn estimated() -> Self {
        SepgOptions {
            accounting: Accounting::Estimated,
            schedule: Schedule::Iteration,
            confidence: Confidence::StudentT {
                factor: DEFAULT_QUANTILE_FACTOR,
            },
            ..SepgOptions::default()
        }
    }

    /// Checks the domains of the options that carry numbers.
    ///
    /// # Errors
    /// [`ConfigError::InvalidHyperParameter`] for a quantile factor that is not finite and
    /// positive, a clipping threshold that is not finite and positive, a reference batch
    /// of 1 trajectory (a width needs 2), or Adam's hyper-parameters out of their domains;
    /// [`ConfigError::UnsupportedOption`] for alternating iterations or the Adam v-direction
    /// with the certified, resp. estimated, accounting.
    ///
    /// # Examples
    /// ```
    /// use sepg_algo::core::options::{Confidence, SepgOptions};
    /// let bad = SepgOptions { confidence: Confidence::StudentT { factor: 0.0 }, ..Default::default() };
    /// assert!(bad.validate().is_err());
    /// ```
    pub fn validate(&self) -> Result<(), ConfigError> {
        let bad = |name, value: f64, domain| ConfigError::InvalidHyperParameter {
            name,
            value,
            domain,
        };
        if let Confidence::StudentT { factor } = self.confidence
            && !(factor.is_finite() && factor > 0.0)
        {
            return Err(bad("confidence factor", factor, "(0, inf)"));
        }
        if let WDirection::Metagradient { clip } = self.w_direction
            && !(clip.is_finite() && clip > 0.0)
        {
            return Err(bad("metagradient clip", clip, "(0, inf)"));
        }
        if self.alternating && self.accounting == Accounting::Certified {
            return Err(ConfigError::UnsupportedOption {
                option: "alternating",
                reason: "alternating v/w iterations need the estimated accounting",
            });
        }
        if self.reference_batch == 1 {
            return Err(bad("reference batch", 1.0, "0 or at least 2"));
        }
        if let VDirection::Adam {
            lr,
            beta1,
            beta2,
            eps,
        } = self.v_direction
        {
            let unit = |x: f64| (0.0..1.0).contains(&x);
            for (name, value, ok, domain) in [
                ("adam lr", lr, lr > 0.0, "(0, inf)"),
                ("adam beta1", beta1, unit(beta1), "[0, 1)"),
                ("adam beta2", beta2, unit(beta2), "[0, 1)"),
                ("adam eps", eps, eps > 0.0, "(0, inf)"),
            ] {
                if !(ok && value.is_finite()) {
                    return Err(bad(name, value, domain));
                }
            }
            if self.accounting == Accounting::Estimated {
                return Err(ConfigError::UnsupportedOption {
                    option: "v_direction",
                    reason: "the Adam v-direction is certified at its realised change: it needs \
                             the certified accounting",
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Options with a choice of every serialised enum off its default.
    fn varied() -> SepgOptions {
        SepgOptions {
            w_step: WStep::Theorem49,
            w_direction: WDirection::Metagradient { clip: 100.0 },
            confidence: Confidence::StudentT { factor: 2.0 },
            lb1_requirement: Lb1Requirement::Full,
            accounting: Accounting::Certified,
            schedule: Schedule::Iteration,
            v_direction: VDirection::adam(0.01),
            constants: ConstantsFamily::Tight {
                rewards: RewardSign::NonPositive,
            },
            ..SepgOptions::default()
        }
    }

    #[test]
    fn options_serialise_in_the_kebab_case_of_config_toml() {
        let json = serde_json::to_value(varied()).expect("serialise");
        let expected = serde_json::json!({
            "w_step": "theorem-4.9",
            "w_direction": {"metagradient": {"clip": 100.0}},
            "confidence": {"student-t": {"factor": 2.0}},
            "lb1_requirement": "full",
            "accounting": "certified",
            "schedule": "iteration",
            "v_direction": {"adam": {"lr": 0.01, "beta1": 0.9, "beta2": 0.999, "eps": 1e-8}},
            "constants": {"tight": {"rewards": "non-positive"}},
        });
        for (key, value) in expected.as_object().expect("object") {
            assert_eq!(&json[key], value, "{key}");
        }
        let plain = serde_json::to_value(SepgOptions::default()).expect("serialise");
        assert_eq!(plain["w_direction"], "cross-fitted");
        assert_eq!(plain["confidence"], "sub-gaussian");
        assert_eq!(plain["w_step"], "exploring");
    }

    #[test]
    fn options_of_older_summaries_in_pascal_case_are_read() {
        let old = serde_json::json!({
            "w_step": "Theorem49",
            "w_direction": {"Metagradient": {"clip": 100.0}},
            "confidence": {"StudentT": {"factor": 2.0}},
            "lb1_requirement": "Full",
            "alternating": false,
            "reference_batch": 1000,
            "overrides": {"gamma": null, "r_max": null, "m_phi": null, "action_volume": null,
                          "psi": null},
            "accounting": "Certified",
            "schedule": "Iteration",
            "v_direction": {"Adam": {"lr": 0.01, "beta1": 0.9, "beta2": 0.999, "eps": 1e-8}},
            "constants": {"Tight": {"rewards": "NonPositive"}},
        });
        let read: SepgOptions = serde_json::from_value(old).expect("old names");
        assert_eq!(read, varied());
        for (text, expected) in [
            ("\"CrossFitted\"", WDirection::CrossFitted),
            ("\"PlugIn\"", WDirection::PlugIn),
        ] {
            assert_eq!(
                serde_json::from_str::<WDirection>(text).expect("old"),
                expected
            );
        }
        for (text, expected) in [
            ("\"SubGaussian\"", Confidence::SubGaussian),
            ("\"None\"", Confidence::None),
            ("\"none\"", Confidence::None),
        ] {
            assert_eq!(
                serde_json::from_str::<Confidence>(text).expect("old"),
                expected
            );
        }
        assert_eq!(
            serde_json::from_str::<ConstantsFamily>("\"Thesis\"").expect("old"),
            ConstantsFamily::Thesis
        );
        assert_eq!(
            serde_json::from_str::<RewardSign>("\"TwoSided\"").expect("old"),
            RewardSign::TwoSided
        );
        assert_eq!(
            serde_json::from_str::<Accounting>("\"Estimated\"").expect("old"),
            Accounting::Estimated
        );
        assert_eq!(
            serde_json::from_str::<Schedule>("\"Run\"").expect("old"),
            Schedule::Run
        );
        assert_eq!(
            serde_json::from_str::<WStep>("\"Exploring\"").expect("old"),
            WStep::Exploring
        );
        assert_eq!(
            serde_json::from_str::<Lb1Requirement>("\"Split\"").expect("old"),
            Lb1Requirement::Split
        );
        assert_eq!(
            serde_json::from_str::<VDirection>("\"Greedy\"").expect("old"),
            VDirection::Greedy
        );
    }
}
