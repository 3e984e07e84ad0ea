//! Monte Carlo J and gradients: deterministic rollouts (`sepg_mdp::rollout`) and the
//! estimators of `sepg_estimators` with Student-t confidence widths (Sec 4.5).
use sepg_bounds::constants::{TaskConstants, c as penalty_c, dc_dsigma};
use sepg_estimators::proven::ProvenWidths;
use sepg_estimators::{
    Estimate, Estimator, GradientSpec, Param, SurrogateEstimate, student_t_quantile,
};
use sepg_mdp::Batch;
use sepg_mdp::env::{AnyEnv, Environment};
use sepg_mdp::policy::GaussianPolicy;
use sepg_mdp::rng::SeedKey;
use sepg_mdp::rollout::{ScoreAction, rollout_into_with, rollout_returns_into};

use crate::core::check::{At, Checker, RawSteps};
use crate::core::error::RunError;
use crate::core::seed::Block;
use crate::solver::source::{BlockEstimate, Grad, GradientSource, Need, Query, SurrogateParts};

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
    batch: Batch,
    returns: Vec<f64>,
    estimator: BlockEstimator,
    score_action: ScoreAction,
    checker: Checker,
}

/// The estimates of one block from its batch of trajectories: Ĵ, the requested gradients
/// (G(PO)MDP or the estimator of the configuration, Appendix B) and their Student-t
/// half-widths ε_i at level δ (Sec 4.5, eq. 4.22). Every sampled block of every algorithm
/// goes through [`BlockEstimator::estimate`], whether the batch comes from the built-in
/// rollout engine or from a [`BatchCollector`]. Buffers are reused across calls.
pub struct BlockEstimator {
    spec: GradientSpec,
    proven: Option<Proven>,
    constants: TaskConstants,
    estimator: Estimator,
    value: Estimate,
    grad: Estimate,
    surrogate: SurrogateEstimate,
    dc: Vec<f64>,
    widths: StudentT,
}

impl std::fmt::Debug for BlockEstimator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BlockEstimator")
            .field("spec", &self.spec)
            .field("delta", &self.widths.delta)
            .finish_non_exhaustive()
    }
}

/// The Student-t width factors `factor · t(1 − δ/2, n − 1)/√n` of the sample sizes seen so
/// far (`factor` = 0 turns every width off, the confidence option `none`).
///
/// One iteration estimates from blocks of different sizes (34 and 33 trajectories for
/// N = 100 split in three), so the factor of each size is kept instead of recomputing the
/// quantile (a Newton iteration) on every change of size.
#[derive(Debug, Clone, Default)]
struct StudentT {
    delta: f64,
    factor: f64,
    scales: Vec<(usize, f64)>,
}

impl StudentT {
    /// The factor of `n` samples, computed once per `n` with the formula of
    /// `sepg_estimators::width` (so the widths are the same bits).
    ///
    /// # Formula
    /// ```text
    /// scale(n) = factor · t(1 − δ/2, n − 1) / √n,    ε_i = scale(n) · √Var_i
    /// ```
    fn scale(&mut self, n: usize) -> Result<f64, RunError> {
        if self.factor == 0.0 {
            return Ok(0.0);
        }
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
        let s = self.factor * t / nf.sqrt();
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

    /// The one-sided upper confidence width of a mean of `n` samples with sample variance
    /// `var`: J ≤ Ĵ + width with probability about 1 − δ.
    ///
    /// # Formula
    /// ```text
    /// width = factor · t(1 − δ, n − 1) · √(var / n)
    /// ```
    fn one_sided(&self, n: usize, var: f64) -> Result<f64, RunError> {
        if self.factor == 0.0 {
            return Ok(0.0);
        }
        if n < 2 {
            return Err(RunError::Estimator(format!(
                "a confidence width needs at least 2 trajectories, got {n}"
            )));
        }
        let nf = n as f64;
        let t = student_t_quantile(1.0 - self.delta, nf - 1.0)
            .map_err(|e| RunError::Estimator(e.to_string()))?;
        Ok(self.factor * t * (var / nf).sqrt())
    }
}

/// Proven widths (`Confidence::SubGaussian`): the gradients a guarantee rests on are
/// estimated by G(PO)MDP with the constant baseline of `widths`, and each component's width is
/// the proven one at level `delta` (`sepg_estimators::proven`).
#[derive(Debug, Clone)]
struct Proven {
    widths: ProvenWidths,
    delta: f64,
}

impl Proven {
    /// The mean of `e` (an estimate of ∇_v J or ∇_w J from `n` trajectories) and the proven
    /// half-widths of its components; `sigma` are the batch's σ_j (a mean component
    /// `j · p + i` uses σ_j).
    fn grad(&self, e: &Estimate, param: Param, sigma: &[f64]) -> Result<Grad, RunError> {
        let (n, m) = (e.n(), e.dim());
        let eps: Result<Vec<f64>, _> = match param {
            Param::V => {
                let p = (m / sigma.len().max(1)).max(1);
                (0..m)
                    .map(|i| {
                        let s = sigma.get(i / p).copied().unwrap_or(f64::NAN);
                        self.widths.v_width(s, n, self.delta)
                    })
                    .collect()
            }
            Param::W => (0..m).map(|_| self.widths.w_width(n, self.delta)).collect(),
        };
        Ok(Grad {
            value: e.mean().to_vec(),
            eps: eps.map_err(ee)?,
        })
    }
}

/// Unbiased sample variance of `x` (n ≥ 2).
fn sample_variance(x: &[f64]) -> f64 {
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n;
    x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1.0)
}

impl SampledSource {
    pub(crate) fn new(
        env: AnyEnv,
        horizon: usize,
        seed: u64,
        delta: f64,
        confidence_factor: f64,
        spec: GradientSpec,
        constants: TaskConstants,
    ) -> Self {
        SampledSource {
            env,
            horizon,
            seed,
            batch: Batch::zeros(0, 0, 0, 0, 0.0),
            returns: Vec::new(),
            estimator: BlockEstimator::new(delta, spec, constants)
                .with_confidence_factor(confidence_factor),
            score_action: ScoreAction::Raw,
            checker: Checker::default(),
        }
    }

    /// The same source with proven widths (see [`BlockEstimator::with_proven_widths`]).
    pub(crate) fn with_proven_widths(mut self, widths: ProvenWidths, delta: f64) -> Self {
        self.estimator = self.estimator.with_proven_widths(widths, delta);
        self
    }

    /// The same source with the scores of its rollouts evaluated at the action chosen by
    /// `score` (raw by default).
    pub(crate) fn with_score_action(mut self, score: ScoreAction) -> Self {
        self.score_action = score;
        self
    }
}

impl BlockEstimator {
    /// An estimator with confidence parameter `delta` ∈ (0, 1) for the widths, gradient
    /// estimator `spec` and the task constants that define c(σ) in ∇_w L (Corollary 4.4).
    pub fn new(delta: f64, spec: GradientSpec, constants: TaskConstants) -> Self {
        BlockEstimator {
            spec,
            proven: None,
            constants,
            estimator: Estimator::new(),
            value: Estimate::new(),
            grad: Estimate::new(),
            surrogate: SurrogateEstimate::new(),
            dc: Vec::new(),
            widths: StudentT {
                delta,
                factor: 1.0,
                scales: Vec::new(),
            },
        }
    }

    /// The same estimator with the gradients a guarantee rests on (∇_v J, ∇_w J) estimated by
    /// G(PO)MDP with the constant baseline of `widths` and given their proven widths at level
    /// `delta` (the confidence option `SubGaussian`); the direction ∇̂_w L and J keep their
    /// estimator and Student-t widths.
    pub fn with_proven_widths(mut self, widths: ProvenWidths, delta: f64) -> Self {
        self.proven = Some(Proven { widths, delta });
        self
    }

    /// The same estimator with every width multiplied by `factor` ≥ 0 (the confidence
    /// option: 1 is the Student-t width of Section 4.5, 0 turns the widths off).
    pub fn with_confidence_factor(mut self, factor: f64) -> Self {
        self.widths.factor = factor;
        self.widths.scales.clear();
        self
    }

    /// Ĵ and the gradients `need` asks for, from `batch`.
    ///
    /// # Formula
    /// ```text
    /// Ĵ = mean_i Σ_t γ^t r_t,   ε_i = t(1 − δ/2, N − 1) · √(Var_i / N)
    /// ```
    ///
    /// # Errors
    /// [`RunError::Estimator`] when the batch is too small (fewer than 2 trajectories for a
    /// gradient, 4 for ∇_w L) or has the wrong dimensions; [`RunError::Bounds`] when c(σ)
    /// cannot be evaluated.
    pub fn estimate(&mut self, batch: &Batch, need: Need) -> Result<BlockEstimate, RunError> {
        if !(need.grad_v || need.grad_wj || need.grad_wl) {
            let returns: Vec<f64> = (0..batch.n).map(|i| batch.discounted_return(i)).collect();
            let j = returns.iter().sum::<f64>() / batch.n as f64;
            let j_width = if need.j_width {
                self.widths.one_sided(batch.n, sample_variance(&returns))?
            } else {
                0.0
            };
            return Ok(BlockEstimate {
                j,
                grad_v: None,
                grad_wj: None,
                grad_wl: None,
                parts: None,
                j_width,
                trajectories: batch.n as u64,
                steps: batch.steps() as u64,
            });
        }
        self.estimator.value(batch, &mut self.value).map_err(ee)?;
        let j = self.value.mean()[0];
        let mut grad = |param| -> Result<Grad, RunError> {
            let spec = match &self.proven {
                Some(p) => p.widths.gradient_spec(),
                None => self.spec,
            };
            self.estimator
                .gradient(batch, param, spec, &mut self.grad)
                .map_err(ee)?;
            match &self.proven {
                Some(p) => p.grad(&self.grad, param, &batch.sigma),
                None => self.widths.grad(&self.grad),
            }
        };
        let grad_v = need.grad_v.then(|| grad(Param::V)).transpose()?;
        let grad_wj = need.grad_wj.then(|| grad(Param::W)).transpose()?;
        let grad_wl = need
            .grad_wl
            .then(|| self.surrogate_grad(batch))
            .transpose()?;
        let parts = need.grad_wl.then(|| SurrogateParts {
            grad_v: self.surrogate.grad_v().mean().to_vec(),
            mixed_sigma: self.surrogate.mixed().mean().to_vec(),
        });
        let j_width = if need.j_width {
            self.widths.one_sided(batch.n, self.value.variance()[0])?
        } else {
            0.0
        };
        Ok(BlockEstimate {
            j,
            grad_v,
            grad_wj,
            grad_wl,
            parts,
            j_width,
            trajectories: batch.n as u64,
            steps: batch.steps() as u64,
        })
    }

    /// ∇̂_w L for every action dimension of `batch`, with L defined with c at
    /// σ_min = min_j σ_j (the c of the v-update): ∂c/∂σ_j is c′(σ_min) for the (lowest)
    /// minimising j, else 0.
    fn surrogate_grad(&mut self, batch: &Batch) -> Result<Grad, RunError> {
        let sigmas = &batch.sigma;
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
            .surrogate_gradient(batch, self.spec, c, &self.dc, &mut self.surrogate)
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
            let j_width = if q.need.j_width {
                self.estimator
                    .widths
                    .one_sided(q.n, sample_variance(&self.returns))?
            } else {
                0.0
            };
            let limit = self
                .env
                .time_limit()
                .map_or(self.horizon, |l| l.min(self.horizon));
            return Ok(BlockEstimate {
                j,
                grad_v: None,
                grad_wj: None,
                grad_wl: None,
                parts: None,
                j_width,
                trajectories: q.n as u64,
                steps: (q.n * limit) as u64,
            });
        }
        let (n, h, score) = (q.n, self.horizon, self.score_action);
        rollout_into_with(&self.env, &policy, n, h, key, score, &mut self.batch).map_err(me)?;
        let at = At {
            iteration: q.iteration,
            block: q.block,
        };
        let offence = self.checker.scan_batch(&self.batch, at);
        self.checker.verdict(offence)?;
        self.estimator.estimate(&self.batch, q.need)
    }

    fn checker(&mut self) -> Option<&mut Checker> {
        Some(&mut self.checker)
    }
}

/// What a [`BatchCollector`] must collect for one block of an iteration (Algorithm 4.3).
#[derive(Debug, Clone, PartialEq)]
pub struct BatchRequest<'a> {
    /// Iteration the block belongs to.
    pub iteration: u64,
    /// Which block.
    pub block: Block,
    /// The seed key of the block; trajectory `i` should draw from streams derived from
    /// `key.trajectory_seed(i, ..)` so that a run is reproducible.
    pub key: SeedKey,
    /// Mean parameters v (action-major, `v[j · p + i]`).
    pub v: &'a [f64],
    /// Log standard deviations w, `None` for the deterministic policy (w = −∞).
    pub w: Option<&'a [f64]>,
    /// Number of trajectories to collect.
    pub n: usize,
    /// Whether the scores are needed; when `false`, only the rewards and lengths are used
    /// (a batch without scores, see [`Batch::from_steps`], suffices).
    pub scores: bool,
}

/// A provider of trajectory batches collected outside the crate (another language, another
/// simulator): the policy N(v φ(s), diag σ²) of the request is run `n` times and the batch
/// returned with raw rewards discounted and scores accumulated ([`Batch::from_steps`]).
pub trait BatchCollector: Send {
    /// Collects the batch of `request`.
    ///
    /// # Errors
    /// Any [`RunError`]; it ends the iteration and leaves the state unchanged.
    fn collect(&mut self, request: &BatchRequest<'_>) -> Result<Batch, RunError>;

    /// The batch of `request` with the raw rewards and features it was built from, checked
    /// against the declared constants ([`crate::core::check`]). The default collects with
    /// [`BatchCollector::collect`] and gives no raw data: only the discounted rewards of the
    /// batches with scores are then checked.
    ///
    /// # Errors
    /// As [`BatchCollector::collect`].
    fn collect_raw(
        &mut self,
        request: &BatchRequest<'_>,
    ) -> Result<(Batch, Option<RawSteps>), RunError> {
        Ok((self.collect(request)?, None))
    }
}

/// A [`GradientSource`] fed by a [`BatchCollector`], estimating with [`BlockEstimator`].
pub(crate) struct CollectedSource {
    collector: Box<dyn BatchCollector>,
    seed: u64,
    dims: (usize, usize),
    estimator: BlockEstimator,
    checker: Checker,
}

impl CollectedSource {
    pub(crate) fn new(
        collector: Box<dyn BatchCollector>,
        seed: u64,
        dims: (usize, usize),
        estimator: BlockEstimator,
    ) -> Self {
        CollectedSource {
            collector,
            seed,
            dims,
            estimator,
            checker: Checker::default(),
        }
    }
}

impl GradientSource for CollectedSource {
    fn estimate(&mut self, q: &Query<'_>) -> Result<BlockEstimate, RunError> {
        let scores = q.need.grad_v || q.need.grad_wj || q.need.grad_wl;
        let (batch, raw) = self.collector.collect_raw(&BatchRequest {
            iteration: q.iteration,
            block: q.block,
            key: q.block.key(self.seed, q.iteration),
            v: q.v,
            w: q.w,
            n: q.n,
            scores,
        })?;
        let dims = (batch.dim_v, batch.dim_w);
        if batch.n != q.n || (scores && dims != self.dims) {
            return Err(RunError::Mdp(format!(
                "the collected batch has {} trajectories and dimensions {dims:?}, the request {} and {:?}",
                batch.n, q.n, self.dims
            )));
        }
        if let (true, Some(w)) = (scores, q.w) {
            let expected = w.iter().map(|w| w.exp());
            if !batch.sigma.iter().copied().eq(expected) {
                return Err(RunError::Mdp(
                    "the collected batch was generated with other standard deviations than the request's"
                        .into(),
                ));
            }
        }
        let at = At {
            iteration: q.iteration,
            block: q.block,
        };
        // Without the raw data only a scored batch's per-step rewards are checked, as for the
        // built-in engine: a batch that only estimates J may hold one return per trajectory.
        let offence = match &raw {
            Some(raw) => self.checker.scan_steps(raw, &batch, at),
            None if scores => self.checker.scan_batch(&batch, at),
            None => None,
        };
        self.checker.verdict(offence)?;
        self.estimator.estimate(&batch, q.need)
    }

    fn checker(&mut self) -> Option<&mut Checker> {
        Some(&mut self.checker)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sepg_estimators::Width;
    use sepg_mdp::rollout::rollout;

    /// The memoised factors give the widths of `Estimate::widths_into` bit for bit, for
    /// alternating sample sizes (the pattern of one SEPG iteration).
    #[test]
    fn cached_widths_equal_the_estimator_widths() {
        let env = sepg_mdp::env::Preset::Lqg1d.build();
        let policy = GaussianPolicy::new(vec![-0.3], vec![0.2], 1).expect("policy");
        let mut widths = StudentT {
            delta: 0.2,
            factor: 1.0,
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

    /// Replays the built-in rollouts as an outside collector would: scored blocks through
    /// `rollout`, J-only blocks as one discounted return per trajectory.
    struct Replay {
        env: AnyEnv,
        horizon: usize,
        /// Added to the iteration of every key (0 replays the built-in streams).
        shift: u64,
    }

    impl BatchCollector for Replay {
        fn collect(&mut self, r: &BatchRequest<'_>) -> Result<Batch, RunError> {
            let key = SeedKey::new(r.key.seed, r.key.iteration + self.shift, r.key.block);
            let (p, l) = (self.env.feature_dim(), self.env.action_dim());
            let policy = match r.w {
                Some(w) => GaussianPolicy::new(r.v.to_vec(), w.to_vec(), p),
                None => GaussianPolicy::deterministic(r.v.to_vec(), l, p),
            }
            .map_err(me)?;
            if r.scores {
                return rollout(&self.env, &policy, r.n, self.horizon, key).map_err(me);
            }
            let g = sepg_mdp::rollout::rollout_returns(&self.env, &policy, r.n, self.horizon, key)
                .map_err(me)?;
            let mut rewards = vec![0.0; r.n * self.horizon];
            for (i, gi) in g.iter().enumerate() {
                rewards[i * self.horizon] = *gi;
            }
            let lengths = vec![self.horizon; r.n];
            Batch::from_steps(self.horizon, 1.0, &[], &rewards, &[], &[], &lengths).map_err(me)
        }
    }

    /// Batches handed in through the collector API give the records of the built-in sampled
    /// path bit for bit, for every algorithm family (the block logic is shared, not copied);
    /// a collector drawing other streams (shift 1) gives different records.
    #[test]
    fn collected_batches_reproduce_the_sampled_records() {
        use crate::core::config::{Algorithm, Requirement, SepgConfig};
        use crate::core::executor::{Collect, Executor};
        use crate::solver::{CollectedConfig, PolicySolver};
        let algorithms = [
            Algorithm::Sepg(Requirement::Mi),
            Algorithm::Sepg(Requirement::LbI { nu: 0.5 }),
            Algorithm::Sepg(Requirement::Lv),
            Algorithm::Sepg(Requirement::Zv),
            Algorithm::Sepg(Requirement::Sim { nu: 0.5 }),
            Algorithm::SepgNaiveW(Requirement::Zv),
            Algorithm::AdaStep,
            Algorithm::adam(0.01, 0.01),
        ];
        let records = |solver: PolicySolver, state| {
            let mut log = Collect::default();
            let mut exec = Executor::new(solver, state).observe(&mut log);
            exec.run(4).expect("run");
            drop(exec);
            log.records
        };
        for algorithm in algorithms {
            let mut cfg = SepgConfig::new(sepg_mdp::env::Preset::Lqg1d.build(), algorithm);
            // a collector run knows no iteration count: its widths are Student-t at level δ
            cfg.options.schedule = crate::core::options::Schedule::Iteration;
            cfg.options.confidence = crate::core::options::Confidence::StudentT { factor: 1.0 };
            cfg.n_trajectories = 60;
            cfg.seed = 9;
            let checked = cfg.clone().check().expect("config");
            let built_in = records(
                PolicySolver::new(&checked).expect("solver"),
                checked.initial_state(),
            );
            let collected = |shift| {
                let external = CollectedConfig {
                    algorithm,
                    constants: *checked.constants(),
                    delta: crate::core::defaults::DEFAULT_DELTA,
                    estimator: cfg.estimator,
                    n_trajectories: cfg.n_trajectories,
                    seed: cfg.seed,
                    actions: 1,
                    features: 1,
                };
                let replay = Replay {
                    env: cfg.env.clone(),
                    horizon: cfg.horizon,
                    shift,
                };
                let solver = PolicySolver::with_collector(&external, Box::new(replay))
                    .expect("collected solver");
                records(solver, checked.initial_state())
            };
            assert_eq!(collected(0), built_in, "{algorithm:?}");
            assert_ne!(collected(1), built_in, "{algorithm:?}");
        }
    }
}
