//! The SEPG options of a run: built from the names with their defaults, and written back as
//! names into the resolved specification.

use sepg_algo::core::check::OnContradiction;
use sepg_algo::core::config::{Algorithm, Requirement};
use sepg_algo::core::defaults::{
    DEFAULT_ADAM_BETA1, DEFAULT_ADAM_BETA2, DEFAULT_ADAM_EPS, DEFAULT_METAGRADIENT_CLIP,
    DEFAULT_QUANTILE_FACTOR, RUN_CONSTANTS,
};
use sepg_algo::core::options::{
    Accounting, Confidence, ConstantOverrides, ConstantsFamily, Lb1Requirement, RewardSign,
    Schedule as WidthSchedule, SepgOptions, VDirection, WDirection, WStep,
};

use super::names::{
    AccountingName, AlgoName, ConfidenceName, ConstantsName, GradientsName, Lb1Name,
    OnContradictionName, RewardsName, ScheduleName, VDirectionName, WDirectionName, WStepName,
};
use super::resolve::{Method, Sampling, Schedule, Start};
use super::run_spec::RunSpec;
use super::values::Values;

impl RunSpec {
    /// The SEPG options with their defaults ([`SepgOptions`]); for the comparison algorithms
    /// only the constant overrides (the options were checked to apply).
    pub(super) fn options(
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
        let constants = self
            .constants
            .unwrap_or(RUN_CONSTANTS)
            .family(self.rewards.map_or(env_rewards, RewardsName::sign));
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
        Some(self.sepg_options(
            gradients == GradientsName::Sampled,
            SepgOptions {
                overrides,
                constants,
                on_contradiction,
                ..defaults
            },
        ))
    }

    /// The options of a SEPG run: each option given, else its value in `defaults` (which
    /// carries the constant overrides, the family and the reaction to a contradiction);
    /// `sampled` for sampled gradients (exact gradients take no reference batch).
    fn sepg_options(&self, sampled: bool, defaults: SepgOptions) -> SepgOptions {
        SepgOptions {
            v_direction: match (self.v_direction, self.adam_lr) {
                (Some(VDirectionName::Adam), Some(lr)) => VDirection::Adam {
                    lr,
                    beta1: self.adam_beta1.unwrap_or(DEFAULT_ADAM_BETA1),
                    beta2: self.adam_beta2.unwrap_or(DEFAULT_ADAM_BETA2),
                    eps: self.adam_eps.unwrap_or(DEFAULT_ADAM_EPS),
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
                    clip: self.metagradient_clip.unwrap_or(DEFAULT_METAGRADIENT_CLIP),
                },
                Some(WDirectionName::CrossFitted) | None => defaults.w_direction,
            },
            confidence: match self.confidence {
                Some(ConfidenceName::None) => Confidence::None,
                Some(ConfidenceName::StudentT) => Confidence::StudentT {
                    factor: self.quantile_factor.unwrap_or(DEFAULT_QUANTILE_FACTOR),
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
            accounting: match self.accounting {
                Some(AccountingName::Estimated) => Accounting::Estimated,
                Some(AccountingName::Certified) | None => defaults.accounting,
            },
            schedule: match self.schedule {
                Some(ScheduleName::Iteration) => WidthSchedule::Iteration,
                Some(ScheduleName::Run) | None => defaults.schedule,
            },
            ..defaults
        }
    }

    /// The resolved options that come from the parts of [`RunSpec::resolve`] (every other
    /// option is `None`).
    pub(super) fn resolved_values(
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
        RunSpec::sepg_option_values(o, naive, lb1, sampling.0.is_some(), overrides)
    }

    /// The resolved SEPG options of a SEPG run written as names over `overrides`: without
    /// the w-update's form and direction for `naive` (sepg-naive-w), LB-I's requirement for
    /// `lb1` only, the widths, reference batch and schedule for `sampled` gradients only.
    fn sepg_option_values(
        o: &SepgOptions,
        naive: bool,
        lb1: bool,
        sampled: bool,
        overrides: RunSpec,
    ) -> RunSpec {
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
