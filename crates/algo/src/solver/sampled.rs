//! Monte Carlo J and gradients: deterministic rollouts (`sepg_mdp::rollout`) and the
//! estimators of `sepg_estimators` with Student-t confidence widths (Sec 4.5).
use sepg_bounds::constants::{TaskConstants, c as penalty_c, dc_dsigma};
use sepg_estimators::{Estimate, Estimator, GradientSpec, Param, SurrogateEstimate, Width};
use sepg_mdp::Batch;
use sepg_mdp::env::{AnyEnv, Environment};
use sepg_mdp::policy::GaussianPolicy;
use sepg_mdp::rollout::{rollout_into, rollout_returns_into};

use crate::core::error::RunError;
use crate::solver::source::{Estimate as BlockEstimate, Grad, GradientSource, Query};

fn ee(e: sepg_estimators::EstimatorError) -> RunError {
    RunError::Estimator(e.to_string())
}

fn me(e: impl std::fmt::Display) -> RunError {
    RunError::Mdp(e.to_string())
}

/// A [`GradientSource`] that rolls out trajectories and estimates from them. Buffers are
/// reused across iterations.
pub(crate) struct SampledSource {
    env: AnyEnv,
    horizon: usize,
    seed: u64,
    delta: f64,
    spec: GradientSpec,
    constants: TaskConstants,
    estimator: Estimator,
    batch: Batch,
    value: Estimate,
    grad: Estimate,
    surrogate: SurrogateEstimate,
    returns: Vec<f64>,
}

impl SampledSource {
    pub(crate) fn new(
        env: AnyEnv,
        horizon: usize,
        seed: u64,
        delta: f64,
        spec: GradientSpec,
        constants: TaskConstants,
    ) -> Self {
        SampledSource {
            env,
            horizon,
            seed,
            delta,
            spec,
            constants,
            estimator: Estimator::new(),
            batch: Batch::zeros(0, 0, 0, 0, 0.0),
            value: Estimate::new(),
            grad: Estimate::new(),
            surrogate: SurrogateEstimate::new(),
            returns: Vec::new(),
        }
    }

    /// The mean and the per-component Student-t widths of an estimate.
    fn grad_of(e: &Estimate, delta: f64) -> Result<Grad, RunError> {
        let mut eps = vec![0.0; e.dim()];
        e.widths_into(Width::StudentT, delta, &mut eps)
            .map_err(ee)?;
        Ok(Grad {
            value: e.mean().to_vec(),
            eps,
        })
    }

    /// ∇̂_w L for every action dimension, with L defined with c at σ_min = min_j σ_j
    /// (the c of the v-update): ∂c/∂σ_j is c′(σ_min) for the (lowest) minimising j, else 0.
    fn surrogate_grad(&mut self, sigmas: &[f64]) -> Result<Grad, RunError> {
        let (jmin, smin) =
            sigmas
                .iter()
                .copied()
                .enumerate()
                .fold(
                    (0, f64::INFINITY),
                    |b, (j, s)| if s < b.1 { (j, s) } else { b },
                );
        let be = |e: sepg_bounds::BoundsError| RunError::Bounds(e.to_string());
        let c = penalty_c(&self.constants, smin).map_err(be)?;
        let dc_min = dc_dsigma(&self.constants, smin).map_err(be)?;
        let dc: Vec<f64> = (0..sigmas.len())
            .map(|j| if j == jmin { dc_min } else { 0.0 })
            .collect();
        self.estimator
            .surrogate_gradient(&self.batch, self.spec, c, &dc, &mut self.surrogate)
            .map_err(ee)?;
        Self::grad_of(self.surrogate.grad_w_l(), self.delta)
    }
}

impl GradientSource for SampledSource {
    fn estimate(&mut self, q: &Query<'_>) -> Result<BlockEstimate, RunError> {
        let key = q.block.key(self.seed, q.iteration);
        let features = self.env.feature_dim();
        let actions = self.env.action_dim();
        let any_grad = q.need.grad_v || q.need.grad_wj || q.need.grad_wl;
        let policy = match q.w {
            Some(w) => GaussianPolicy::new(q.v.to_vec(), w.to_vec(), features),
            None => GaussianPolicy::deterministic(q.v.to_vec(), actions, features),
        }
        .map_err(me)?;
        if !any_grad {
            rollout_returns_into(
                &self.env,
                &policy,
                q.n,
                self.horizon,
                key,
                &mut self.returns,
            )
            .map_err(me)?;
            let j = self.returns.iter().sum::<f64>() / q.n as f64;
            let limit = self
                .env
                .time_limit()
                .map_or(self.horizon, |l| l.min(self.horizon));
            return Ok(BlockEstimate {
                j,
                grad_v: None,
                grad_wj: None,
                grad_wl: None,
                trajectories: q.n as u64,
                steps: (q.n * limit) as u64,
            });
        }
        rollout_into(&self.env, &policy, q.n, self.horizon, key, &mut self.batch).map_err(me)?;
        self.estimator
            .value(&self.batch, &mut self.value)
            .map_err(ee)?;
        let j = self.value.mean()[0];
        let mut grad = |param| -> Result<Grad, RunError> {
            self.estimator
                .gradient(&self.batch, param, self.spec, &mut self.grad)
                .map_err(ee)?;
            Self::grad_of(&self.grad, self.delta)
        };
        let grad_v = q.need.grad_v.then(|| grad(Param::V)).transpose()?;
        let grad_wj = q.need.grad_wj.then(|| grad(Param::W)).transpose()?;
        let grad_wl = if q.need.grad_wl {
            let sigmas: Vec<f64> = self.batch.sigma.clone();
            Some(self.surrogate_grad(&sigmas)?)
        } else {
            None
        };
        Ok(BlockEstimate {
            j,
            grad_v,
            grad_wj,
            grad_wl,
            trajectories: q.n as u64,
            steps: self.batch.steps() as u64,
        })
    }
}
