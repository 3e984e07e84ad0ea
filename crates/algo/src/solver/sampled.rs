//! Monte Carlo J and gradients: deterministic rollouts (`sepg_mdp::rollout`) and the
//! estimators of `sepg_estimators` with Student-t confidence widths (Sec 4.5).
use sepg_bounds::constants::{TaskConstants, c as penalty_c, dc_dsigma};
use sepg_estimators::{
    Estimate, Estimator, GradientSpec, Param, SurrogateEstimate, student_t_quantile,
};
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
    spec: GradientSpec,
    constants: TaskConstants,
    estimator: Estimator,
    batch: Batch,
    value: Estimate,
    grad: Estimate,
    surrogate: SurrogateEstimate,
    returns: Vec<f64>,
    dc: Vec<f64>,
    widths: StudentT,
}

/// The Student-t width factors `t(1 − δ/2, n − 1)/√n` of the sample sizes seen so far.
///
/// One iteration estimates from blocks of different sizes (34 and 33 trajectories for
/// N = 100 split in three), so the factor of each size is kept instead of recomputing the
/// quantile (a Newton iteration) on every change of size.
#[derive(Debug, Clone, Default)]
struct StudentT {
    delta: f64,
    scales: Vec<(usize, f64)>,
}

impl StudentT {
    /// The factor of `n` samples, computed once per `n` with the formula of
    /// `sepg_estimators::width` (so the widths are the same bits).
    ///
    /// # Formula
    /// ```text
    /// scale(n) = t(1 − δ/2, n − 1) / √n,    ε_i = scale(n) · √Var_i
    /// ```
    fn scale(&mut self, n: usize) -> Result<f64, RunError> {
        if let Some(&(_, s)) = self.scales.iter().find(|(m, _)| *m == n) {
            return Ok(s);
        }
        if n < 2 {
            return Err(RunError::Estimator(format!(
                "a confidence width needs at least 2 trajectories, got {n}"
            )));
        }
        let nf = n as f64;
        let t = student_t_quantile(1.0 - 0.5 * self.delta, nf - 1.0)
            .map_err(|e| RunError::Estimator(e.to_string()))?;
        let s = t / nf.sqrt();
        self.scales.push((n, s));
        Ok(s)
    }

    /// The mean of `e` and its per-component half-widths ε_i (Sec 4.5, eq. 4.22).
    fn grad(&mut self, e: &Estimate) -> Result<Grad, RunError> {
        let scale = self.scale(e.n())?;
        Ok(Grad {
            value: e.mean().to_vec(),
            eps: e.variance().iter().map(|v| scale * v.sqrt()).collect(),
        })
    }
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
            spec,
            constants,
            estimator: Estimator::new(),
            batch: Batch::zeros(0, 0, 0, 0, 0.0),
            value: Estimate::new(),
            grad: Estimate::new(),
            surrogate: SurrogateEstimate::new(),
            returns: Vec::new(),
            dc: Vec::new(),
            widths: StudentT {
                delta,
                scales: Vec::new(),
            },
        }
    }

    /// ∇̂_w L for every action dimension of the current batch, with L defined with c at
    /// σ_min = min_j σ_j (the c of the v-update): ∂c/∂σ_j is c′(σ_min) for the (lowest)
    /// minimising j, else 0.
    fn surrogate_grad(&mut self) -> Result<Grad, RunError> {
        let sigmas = &self.batch.sigma;
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
        self.dc.clear();
        self.dc
            .extend((0..sigmas.len()).map(|j| if j == jmin { dc_min } else { 0.0 }));
        self.estimator
            .surrogate_gradient(&self.batch, self.spec, c, &self.dc, &mut self.surrogate)
            .map_err(ee)?;
        self.widths.grad(self.surrogate.grad_w_l())
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
            self.widths.grad(&self.grad)
        };
        let grad_v = q.need.grad_v.then(|| grad(Param::V)).transpose()?;
        let grad_wj = q.need.grad_wj.then(|| grad(Param::W)).transpose()?;
        let grad_wl = q.need.grad_wl.then(|| self.surrogate_grad()).transpose()?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use sepg_estimators::Width;
    use sepg_mdp::rng::SeedKey;
    use sepg_mdp::rollout::rollout;

    /// The memoised factors give the widths of `Estimate::widths_into` bit for bit, for
    /// alternating sample sizes (the pattern of one SEPG iteration).
    #[test]
    fn cached_widths_equal_the_estimator_widths() {
        let env = sepg_mdp::env::Preset::Lqg1d.build();
        let policy = GaussianPolicy::new(vec![-0.3], vec![0.2], 1).expect("policy");
        let mut widths = StudentT {
            delta: 0.2,
            scales: Vec::new(),
        };
        let mut estimator = Estimator::new();
        let mut e = Estimate::new();
        for (i, n) in [34, 33, 33, 34, 2, 1000].into_iter().enumerate() {
            let batch =
                rollout(&env, &policy, n, 20, SeedKey::new(1, i as u64, 0)).expect("rollout");
            estimator
                .gradient(&batch, Param::V, GradientSpec::default(), &mut e)
                .expect("gradient");
            let mut expected = vec![0.0; e.dim()];
            e.widths_into(Width::StudentT, 0.2, &mut expected)
                .expect("widths");
            let got = widths.grad(&e).expect("grad");
            assert_eq!(got.value, e.mean());
            assert_eq!(
                got.eps.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                expected.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
            );
        }
        assert_eq!(widths.scales.len(), 4);
        assert!(widths.scale(1).is_err());
    }
}
