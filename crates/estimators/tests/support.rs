//! Shared helpers of the statistical tests: unclipped LQG set-ups with their exact oracle,
//! batches from the rollout engine, running moments and Bonferroni-corrected thresholds.

use sepg_bounds::constants::TaskConstants;
use sepg_estimators::normal_quantile;
use sepg_mdp::Batch;
use sepg_mdp::env::{Environment, LqgEnv};
use sepg_mdp::lqg_model::LqgModel;
use sepg_mdp::oracle::{ClosedFormOracle, ExactEval, ExactOracle, Horizon};
use sepg_mdp::policy::GaussianPolicy;
use sepg_mdp::rng::SeedKey;
use sepg_mdp::rollout::rollout_into;

/// An unclipped LQG, a policy and the exact values of `J` and its derivatives.
pub struct Setup {
    pub env: LqgEnv,
    pub policy: GaussianPolicy,
    pub exact: ExactEval,
    pub horizon: usize,
}

impl Setup {
    /// The model without clipping (the closed-form oracle's setting), the policy
    /// `N(Vs, diag(σ²))` with `v` action-major and `w = ln σ`.
    pub fn new(model: LqgModel, v: &[f64], sigma: &[f64], horizon: usize) -> Setup {
        let model = model.with_clipping(false);
        let w: Vec<f64> = sigma.iter().map(|s| s.ln()).collect();
        let features = v.len() / w.len();
        let policy = GaussianPolicy::new(v.to_vec(), w, features).expect("policy");
        let exact = ClosedFormOracle::new(&model)
            .expect("valid model")
            .evaluate_policy(&policy, Horizon::Finite(horizon))
            .expect("oracle");
        let env = LqgEnv::new(model)
            .expect("env")
            .with_horizon(horizon)
            .expect("horizon");
        Setup {
            env,
            policy,
            exact,
            horizon,
        }
    }

    /// The task constants of the model (for `c(σ)`).
    pub fn task(&self) -> TaskConstants {
        let k = self.env.constants();
        TaskConstants::new(k.gamma, k.r_max, k.m_phi, k.action_volume).expect("constants")
    }

    /// Batch `index` of `n` trajectories for `seed` (independent across `index`).
    pub fn batch_into(&self, n: usize, seed: u64, index: u64, batch: &mut Batch) {
        rollout_into(
            &self.env,
            &self.policy,
            n,
            self.horizon,
            SeedKey::new(seed, index, 0),
            batch,
        )
        .expect("rollout");
    }
}

/// Running mean and variance (Welford) of a scalar.
#[derive(Debug, Clone, Copy, Default)]
pub struct Moments {
    n: f64,
    mean: f64,
    m2: f64,
}

impl Moments {
    pub fn push(&mut self, x: f64) {
        self.n += 1.0;
        let d = x - self.mean;
        self.mean += d / self.n;
        self.m2 += d * (x - self.mean);
    }
    pub fn mean(&self) -> f64 {
        self.mean
    }
    pub fn var(&self) -> f64 {
        self.m2 / (self.n - 1.0)
    }
    /// Standard error of the mean.
    pub fn se(&self) -> f64 {
        (self.var() / self.n).sqrt()
    }
}

/// Two-sided normal critical value for a family-wise false-alarm rate `alpha` over
/// `comparisons` tests (Bonferroni).
pub fn bonferroni_z(alpha: f64, comparisons: usize) -> f64 {
    normal_quantile(1.0 - alpha / (2.0 * comparisons as f64)).expect("valid level")
}
