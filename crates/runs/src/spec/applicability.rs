//! The options that do not apply to a run's algorithm or gradients.

use super::names::{
    AccountingName, AlgoName, BatchRuleName, ConfidenceName, ConstantsName, GradientsName,
    RequirementName, VDirectionName, WDirectionName,
};
use super::run_spec::RunSpec;
use crate::error::{Error, Result};

impl RunSpec {
    /// Rejects the options that do not apply to `algo` or to `gradients`, in this order: the
    /// options of other algorithms, the options that need another option, the options of
    /// the sampled mode with exact gradients (the first refused option is reported).
    pub(super) fn reject_inapplicable(
        &self,
        algo: AlgoName,
        gradients: GradientsName,
    ) -> Result<()> {
        self.reject_for_algorithm(algo)?;
        self.reject_combinations(algo)?;
        if gradients == GradientsName::Exact {
            self.reject_for_exact()?;
        }
        Ok(())
    }

    /// Rejects the options of other algorithms than `algo`.
    fn reject_for_algorithm(&self, algo: AlgoName) -> Result<()> {
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
            !sepg
                && (self.batch_rule.is_some()
                    || self.batch_min.is_some()
                    || self.batch_max.is_some()),
            "batch-rule/batch-min/batch-max",
            &for_algo,
        )?;
        self.reject_batch_rule()?;
        reject(
            !sepg && self.certified_steps.is_some(),
            "certified-steps",
            &for_algo,
        )?;
        reject(
            !sepg && (self.accounting.is_some() || self.schedule.is_some()),
            "accounting/schedule",
            &for_algo,
        )
    }

    /// Rejects the options that need another option or value, for `algo`.
    fn reject_combinations(&self, algo: AlgoName) -> Result<()> {
        let for_algo = format!("to algorithm {}", algo.name());
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
        )
    }

    /// Rejects the options of the sampled mode (with exact gradients).
    fn reject_for_exact(&self) -> Result<()> {
        reject(
            self.confidence.is_some()
                || self.quantile_factor.is_some()
                || self.reference_batch.is_some(),
            "confidence/quantile-factor/reference-batch",
            "to exact gradients",
        )?;
        reject(self.delta.is_some(), "delta", "to exact gradients")?;
        reject(
            self.batch_rule.is_some() || self.batch_min.is_some() || self.batch_max.is_some(),
            "batch-rule/batch-min/batch-max",
            "to exact gradients",
        )?;
        reject(self.scores.is_some(), "scores", "to exact gradients")?;
        reject(
            self.estimator.is_some() || self.baseline.is_some() || self.baseline_fit.is_some(),
            "estimator/baseline/baseline-fit",
            "to exact gradients",
        )
    }

    /// Refuses the adaptive batch rule's bounds without `batch-rule adaptive`, the rule without
    /// both bounds, and the rule with the estimated accounting (its choice of n keeps the
    /// run's union bound only for certified steps: docs/THEOREMS.md, "An adaptive batch
    /// size"). The bounds' domains are checked by the algorithm's validation.
    fn reject_batch_rule(&self) -> Result<()> {
        let adaptive = self.batch_rule == Some(BatchRuleName::Adaptive);
        reject(
            !adaptive && (self.batch_min.is_some() || self.batch_max.is_some()),
            "batch-min/batch-max",
            "without batch-rule adaptive",
        )?;
        if adaptive && (self.batch_min.is_none() || self.batch_max.is_none()) {
            return Err(Error::invalid(
                "batch-rule adaptive needs --batch-min and --batch-max (trajectories per block)",
            ));
        }
        reject(
            adaptive && self.accounting == Some(AccountingName::Estimated),
            "batch-rule adaptive",
            "with accounting estimated (use accounting certified)",
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
}

/// `Err` naming the option `what` and why it does not apply, when `set`.
pub(super) fn reject(set: bool, what: &str, why: &str) -> Result<()> {
    if set {
        Err(Error::invalid(format!(
            "option {what} does not apply {why}"
        )))
    } else {
        Ok(())
    }
}
