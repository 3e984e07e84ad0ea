//! [`Resolved`], a run configuration with every default filled in and validated.

use sepg_algo::core::config::CheckedConfig;
use sepg_algo::core::error::ConfigError;
use sepg_algo::core::options::BatchRule;
use sepg_algo::solver::PolicySolver;
use sepg_mdp::env::AnyEnv;
use sepg_mdp::oracle::ClosedFormOracle;

use super::names::{BatchRuleName, RewardsName};
use super::run_spec::RunSpec;
use crate::error::{Error, Result};

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
    /// The batch rule of a sampled SEPG run: [`BatchRule::Adaptive`] with the spec's bounds
    /// under `batch-rule adaptive`, else [`BatchRule::Fixed`].
    pub fn batch_rule(&self) -> BatchRule {
        match (
            self.spec.batch_rule,
            self.spec.batch_min,
            self.spec.batch_max,
        ) {
            (Some(BatchRuleName::Adaptive), Some(n_min), Some(n_max)) => {
                BatchRule::Adaptive { n_min, n_max }
            }
            _ => BatchRule::Fixed,
        }
    }

    /// The algorithm of this configuration, ready to iterate: [`PolicySolver::new`] with the
    /// batch rule of [`Resolved::batch_rule`].
    ///
    /// # Errors
    /// [`Error::Invalid`] if the algorithm refuses the configuration or the batch rule.
    pub fn solver(&self) -> Result<PolicySolver> {
        let invalid = |e: ConfigError| Error::invalid_from("invalid configuration", e);
        let solver = PolicySolver::new(&self.checked).map_err(invalid)?;
        match self.batch_rule() {
            BatchRule::Fixed => Ok(solver),
            rule => solver.with_batch_rule(rule).map_err(invalid),
        }
    }

    /// The resolved configuration as TOML text. The options are followed by comment lines
    /// that state the constants the bounds use: their family, and for the tight family its
    /// horizon, reward sign and S_H, then c and d at σ⁰ (comments, so that reading the file
    /// back sees the options only).
    ///
    /// # Errors
    /// [`Error::Failed`] if serialisation fails.
    pub fn toml(&self) -> Result<String> {
        let mut text = toml::to_string(&self.spec)
            .map_err(|e| Error::failed_from("cannot serialise the configuration", e))?;
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
