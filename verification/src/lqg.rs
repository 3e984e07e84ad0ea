//! Ground truth on the clipped scalar LQG presets: the dynamic-programming oracle of
//! `sepg-mdp`, the task constants the bounds use, and rollouts for the sampled checks.
//!
//! The bounds of Chapters 3–4 are stated for the infinite-horizon discounted J. The checks use
//! the finite-horizon J_H = E[Σ_{t<H} γ^t r_t] (H = 20, the horizon of the experiments): it is
//! the infinite-horizon J of the time-augmented MDP (state (s, t), zero reward and an absorbing
//! state after H) which has the same reward bound R, the same features and action space and the
//! same stationary Gaussian policy, so every bound applies to J_H verbatim.

use sepg_bounds::constants::TaskConstants;
use sepg_mdp::Batch;
use sepg_mdp::env::LqgEnv;
use sepg_mdp::lqg_model::LqgModel;
use sepg_mdp::oracle::{
    ClippedDpOracle, ClosedFormOracle, ExactEval, ExactOracle, Exploration, Horizon,
};
use sepg_mdp::policy::GaussianPolicy;
use sepg_mdp::rng::SeedKey;
use sepg_mdp::rollout::rollout;

/// Horizon of every finite-horizon J in the harness (the experiments' H).
pub(crate) const HORIZON: usize = 20;

/// Which clipped LQG preset (docs/CONVENTIONS.md §1).
pub(crate) use sepg_mdp::env::LqgPreset as Preset;

/// A clipped LQG preset at a discount factor γ, with its exact oracle and bound constants.
pub(crate) struct Task {
    pub(crate) model: LqgModel,
    pub(crate) oracle: Box<dyn ExactOracle>,
    pub(crate) k: TaskConstants,
}

impl Task {
    /// The clipped preset with discount γ (DP oracle); `None` if the model, oracle or
    /// constants reject it.
    pub(crate) fn new(preset: Preset, gamma: f64) -> Option<Self> {
        Self::build(preset, gamma, true)
    }

    /// The unclipped twin of the preset (closed-form oracle); its reward is unbounded, so only
    /// estimator checks use it.
    pub(crate) fn unclipped(preset: Preset, gamma: f64) -> Option<Self> {
        Self::build(preset, gamma, false)
    }

    fn build(preset: Preset, gamma: f64, clipping: bool) -> Option<Self> {
        let base = preset.model();
        let model = base.with_gamma(gamma).ok()?.with_clipping(clipping);
        let oracle: Box<dyn ExactOracle> = if clipping {
            Box::new(ClippedDpOracle::new(&model).ok()?)
        } else {
            Box::new(ClosedFormOracle::new(&model).ok()?)
        };
        let k =
            TaskConstants::new(gamma, model.r_max(), model.m_phi(), model.action_volume()).ok()?;
        Some(Self { model, oracle, k })
    }

    /// Exact J_H and derivatives of the Gaussian policy N(v s, e^{2w}).
    pub(crate) fn eval(&self, v: f64, w: f64) -> Option<ExactEval> {
        self.oracle
            .evaluate(
                &[v],
                &Exploration::Gaussian { w: vec![w] },
                Horizon::Finite(HORIZON),
            )
            .ok()
    }

    /// Exact J_H only.
    pub(crate) fn j(&self, v: f64, w: f64) -> Option<f64> {
        self.eval(v, w).map(|e| e.j)
    }

    /// Exact J_H of the policy N(v s, e^{2w}), or of the deterministic policy a = v s when
    /// `w` is `None`.
    pub(crate) fn j_of(&self, v: f64, w: Option<f64>) -> Option<f64> {
        match w {
            Some(w) => self.j(v, w),
            None => self
                .oracle
                .evaluate(&[v], &Exploration::Deterministic, Horizon::Finite(HORIZON))
                .ok()
                .map(|e| e.j),
        }
    }

    /// The environment for rollouts (same model, horizon H).
    pub(crate) fn env(&self) -> Option<LqgEnv> {
        LqgEnv::new(self.model.clone())
            .ok()?
            .with_horizon(HORIZON)
            .ok()
    }
}

/// A policy on a preset, with its exact values, rollouts and estimators.
pub(crate) struct Setting {
    pub(crate) task: Task,
    env: LqgEnv,
    policy: GaussianPolicy,
    pub(crate) v: f64,
    pub(crate) w: f64,
    pub(crate) sigma: f64,
    pub(crate) exact: ExactEval,
}

impl Setting {
    pub(crate) fn new(
        preset: Preset,
        gamma: f64,
        sigma: f64,
        v: f64,
        clipped: bool,
    ) -> Option<Self> {
        let task = if clipped {
            Task::new(preset, gamma)?
        } else {
            Task::unclipped(preset, gamma)?
        };
        let env = task.env()?;
        let w = sigma.ln();
        let exact = task.eval(v, w)?;
        Some(Self {
            policy: GaussianPolicy::scalar(v, w).ok()?,
            task,
            env,
            v,
            w,
            sigma,
            exact,
        })
    }

    pub(crate) fn batch(&self, n: usize, seed: u64, index: u64) -> Option<Batch> {
        rollout(
            &self.env,
            &self.policy,
            n,
            HORIZON,
            SeedKey::new(seed, index, 0),
        )
        .ok()
    }

    pub(crate) fn k(&self) -> &TaskConstants {
        &self.task.k
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use sepg_bounds::constants::c;

    #[test]
    fn presets_publish_the_constants_of_their_boxes_in_order() {
        // From the boxes and rewards (docs/CONVENTIONS.md §1): lqg has S = A = [−2, 2] and
        // reward −0.5(s² + a²), so R = 0.5(4 + 4) = 4, M_φ = 2, |A| = 4; lqg1d has
        // S = A = [−4, 4] and −0.9(s² + a²), so R = 0.9(16 + 16) = 28.8, M_φ = 4, |A| = 8.
        for (preset, r, m, a) in [
            (Preset::Lqg, 4.0, 2.0, 4.0),
            (Preset::Lqg1d, 28.8, 4.0, 8.0),
        ] {
            let task = Task::new(preset, 0.9).expect("preset builds");
            let k = &task.k;
            assert_eq!(k.gamma(), 0.9);
            assert_relative_eq!(k.r_max(), r, max_relative = 1e-15);
            assert_eq!((k.m_phi(), k.action_volume()), (m, a), "{preset:?}");
            // c(σ) of Theorem 4.2 from its printed formula with these constants.
            let sigma: f64 = 0.7;
            let printed = r * m * m / (0.1 * 0.1)
                * (a / ((2.0 * std::f64::consts::PI).sqrt() * sigma.powi(3))
                    + 0.9 / (2.0 * 0.1 * sigma * sigma));
            assert_relative_eq!(c(k, sigma).unwrap(), printed, max_relative = 1e-12);
        }
    }
}
