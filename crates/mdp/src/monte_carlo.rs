//! Monte Carlo oracle for the performance `J(θ)` (eq. 2.1's expected discounted return,
//! truncated at the horizon), for performance differences `J(θ′) − J(θ)` with common random
//! numbers, and for the policy gradients `∇_v J`, `∇_w J` (G(PO)MDP, Sec 2.3.1), all streamed.
//!
//! # Streaming
//! No trajectory is stored. Trajectories are generated in work items of [`BLOCK`] consecutive
//! indices; each work item reduces its per-trajectory samples to [`Moments`] (count,
//! compensated sum, centred sum of squares), and the work items are merged in index order
//! (Chan et al.'s pairwise update, Neumaier-compensated sums). Work items run in parallel in
//! rounds of a fixed number, so memory is `O(threads × BLOCK)` whatever `n`, and the result is
//! bit-identical for any number of threads: which thread computes a work item never changes
//! what it computes or the order of the merge.
//!
//! Differences are estimated from paired samples: trajectory `i` of both policies uses the same
//! streams `key.rngs(i)`, so both see the same initial state and transition noise and their
//! Gaussian perturbations `z` come from the same policy stream. The paired differences
//! `d_i = G_i(θ′) − G_i(θ)` are i.i.d., and their variance is usually far smaller than the sum
//! of the two variances.
//!
//! Confidence intervals rely on the central limit theorem: the estimate is treated as normal
//! with the sample standard error, `mean ± z_{(1+level)/2} · s/√n`. This is asymptotic; for
//! the bounded returns of the presets and `n` in the hundreds or more it is accurate, and the
//! tests of this crate check it against closed forms.
//!
//! # Formula
//! ```text
//! Ĵ = (1/n) Σ_i G_i,   s² = Σ_i (G_i − Ĵ)² / (n − 1),   SE = s/√n
//! CI = [Ĵ − z SE, Ĵ + z SE],   z = Φ⁻¹((1 + level)/2)
//! ```

use statrs::distribution::{ContinuousCDF, Normal};

use rayon::prelude::*;

use crate::env::Environment;
use crate::policy::GaussianPolicy;
use crate::rng::SeedKey;
use crate::rollout::{RolloutError, ScoreAction, Scratch};
use crate::stream::{StepBaseline, Streamer};

/// Number of consecutive trajectories in one streamed work item.
///
/// Public because it fixes the order of the streamed sums, hence their last bits: a caller
/// comparing streamed estimates with sums of its own (the crate's tests cross block
/// boundaries this way) needs it.
pub const BLOCK: usize = 1024;

/// Number of work items run in parallel before their results are merged.
const ROUND: usize = 64;

/// Default size of the pilot batch that fits the baseline of [`stream_gradients`].
///
/// Public because `stream_gradients` takes the pilot size as an argument and its callers
/// (`sepg estimate`, the benchmarks) use this default.
pub const DEFAULT_PILOT: usize = 4096;

/// Errors of the Monte Carlo oracle.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum McError {
    /// The rollout failed.
    #[error("rollout failed: {0}")]
    Rollout(#[from] RolloutError),
    /// Fewer than two samples: no variance estimate.
    #[error("a Monte Carlo estimate needs at least 2 samples (got {0})")]
    TooFewSamples(usize),
    /// The confidence level is outside `(0, 1)`.
    #[error("confidence level {0} is outside (0, 1)")]
    InvalidLevel(f64),
    /// A sample is NaN or infinite.
    #[error("a sample is not finite")]
    NonFinite,
    /// The two policies do not have the same dimensions.
    #[error("the two policies have different feature or action dimensions")]
    PolicyShape,
}

/// A Monte Carlo estimate with its standard error and a normal (CLT) confidence interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct McEstimate {
    /// Sample mean.
    pub mean: f64,
    /// Standard error `s/√n` (sample standard deviation with `n − 1`).
    pub std_error: f64,
    /// Lower end of the confidence interval.
    pub ci_low: f64,
    /// Upper end of the confidence interval.
    pub ci_high: f64,
    /// Confidence level of the interval.
    pub level: f64,
    /// Number of samples.
    pub n: usize,
}

impl McEstimate {
    /// Half-width `z · SE` of the confidence interval.
    ///
    /// ```
    /// let e = sepg_mdp::monte_carlo::summarize(&[1.0, 2.0, 3.0], 0.95).unwrap();
    /// assert!((e.half_width() - (e.ci_high - e.mean)).abs() < 1e-15);
    /// ```
    pub fn half_width(&self) -> f64 {
        0.5 * (self.ci_high - self.ci_low)
    }

    /// Whether `x` lies in the confidence interval.
    ///
    /// ```
    /// let e = sepg_mdp::monte_carlo::summarize(&[1.0, 2.0, 3.0], 0.95).unwrap();
    /// assert!(e.contains(2.0));
    /// ```
    pub fn contains(&self, x: f64) -> bool {
        self.ci_low <= x && x <= self.ci_high
    }
}

/// Mean, standard error and normal confidence interval at `level ∈ (0, 1)` of i.i.d. samples
/// (`n ≥ 2`, all finite). The variance uses a two-pass sum.
///
/// # Formula
/// ```text
/// mean ± Φ⁻¹((1 + level)/2) · √(Σ (x_i − mean)² / (n − 1)) / √n
/// ```
///
/// ```
/// let e = sepg_mdp::monte_carlo::summarize(&[1.0, 2.0, 3.0, 4.0], 0.95).unwrap();
/// assert_eq!(e.mean, 2.5);
/// assert!((e.std_error - (5.0f64 / 3.0 / 4.0).sqrt()).abs() < 1e-15);
/// ```
pub fn summarize(samples: &[f64], level: f64) -> Result<McEstimate, McError> {
    if samples.len() < 2 {
        return Err(McError::TooFewSamples(samples.len()));
    }
    if !(level > 0.0 && level < 1.0) {
        return Err(McError::InvalidLevel(level));
    }
    if !samples.iter().all(|x| x.is_finite()) {
        return Err(McError::NonFinite);
    }
    Moments::from_samples(samples).estimate(level)
}

/// Streamed sample moments of i.i.d. samples: the count, the sum (Neumaier-compensated) and
/// the centred sum of squares `M₂ = Σ (x_i − x̄)²`. Blocks are reduced with a two-pass sum and
/// merged with the pairwise update of Chan, Golub and LeVeque, which is exact in exact
/// arithmetic and numerically stable.
///
/// # Formula
/// ```text
/// merge(a, b):  n = n_a + n_b,   δ = x̄_b − x̄_a,   M₂ = M₂a + M₂b + δ² n_a n_b / n
/// ```
///
/// ```
/// use sepg_mdp::monte_carlo::Moments;
/// let mut m = Moments::from_samples(&[1.0, 2.0]);
/// m.merge(&Moments::from_samples(&[3.0, 4.0]));
/// assert_eq!((m.count(), m.mean(), m.variance()), (4, 2.5, 5.0 / 3.0));
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Moments {
    n: u64,
    sum: f64,
    comp: f64,
    m2: f64,
}

impl Moments {
    /// The moments of a block of samples (two-pass: compensated sum, then centred squares).
    ///
    /// ```
    /// let m = sepg_mdp::monte_carlo::Moments::from_samples(&[1.0, 2.0, 3.0]);
    /// assert_eq!((m.mean(), m.variance()), (2.0, 1.0));
    /// ```
    pub fn from_samples(samples: &[f64]) -> Self {
        let mut m = Moments {
            n: samples.len() as u64,
            ..Moments::default()
        };
        for &x in samples {
            m.add_to_sum(x);
        }
        let mean = m.mean();
        m.m2 = samples.iter().map(|x| (x - mean) * (x - mean)).sum();
        m
    }

    /// Neumaier's compensated addition of `x` to the sum.
    #[inline]
    fn add_to_sum(&mut self, x: f64) {
        let t = self.sum + x;
        self.comp += if self.sum.abs() >= x.abs() {
            (self.sum - t) + x
        } else {
            (x - t) + self.sum
        };
        self.sum = t;
    }

    /// Merges the moments of another, disjoint set of samples into these.
    ///
    /// ```
    /// use sepg_mdp::monte_carlo::Moments;
    /// let mut a = Moments::default();
    /// a.merge(&Moments::from_samples(&[5.0, 7.0]));
    /// assert_eq!(a, Moments::from_samples(&[5.0, 7.0]));
    /// ```
    pub fn merge(&mut self, other: &Moments) {
        if other.n == 0 {
            return;
        }
        if self.n == 0 {
            *self = *other;
            return;
        }
        let (na, nb) = (self.n as f64, other.n as f64);
        let delta = other.mean() - self.mean();
        self.m2 += other.m2 + delta * delta * (na * nb / (na + nb));
        self.add_to_sum(other.sum);
        self.comp += other.comp;
        self.n += other.n;
    }

    /// Number of samples `n`.
    pub fn count(&self) -> u64 {
        self.n
    }

    /// Sample mean `x̄` (NaN for no samples).
    pub fn mean(&self) -> f64 {
        (self.sum + self.comp) / self.n as f64
    }

    /// Unbiased sample variance `M₂ / (n − 1)` (NaN for fewer than 2 samples).
    pub fn variance(&self) -> f64 {
        if self.n < 2 {
            return f64::NAN;
        }
        self.m2 / (self.n - 1) as f64
    }

    /// Standard error of the mean `√(variance / n)`.
    pub fn std_error(&self) -> f64 {
        (self.variance() / self.n as f64).sqrt()
    }

    /// The normal (CLT) confidence interval at `level ∈ (0, 1)`.
    ///
    /// # Formula
    /// ```text
    /// x̄ ± Φ⁻¹((1 + level)/2) · √(M₂ / (n − 1)) / √n
    /// ```
    ///
    /// ```
    /// let m = sepg_mdp::monte_carlo::Moments::from_samples(&[1.0, 2.0, 3.0, 4.0]);
    /// let e = m.estimate(0.95).unwrap();
    /// assert_eq!(e.mean, 2.5);
    /// assert!((e.std_error - (5.0f64 / 3.0 / 4.0).sqrt()).abs() < 1e-15);
    /// ```
    pub fn estimate(&self, level: f64) -> Result<McEstimate, McError> {
        let n = usize::try_from(self.n).map_err(|_| McError::TooFewSamples(usize::MAX))?;
        if n < 2 {
            return Err(McError::TooFewSamples(n));
        }
        if !(level > 0.0 && level < 1.0) {
            return Err(McError::InvalidLevel(level));
        }
        let (mean, std_error) = (self.mean(), self.std_error());
        // The upper quantile from the tail probability (1 − level)/2, exact in f64 even for a
        // level within an ulp of 1, where 0.5 + 0.5·level would round to 1 and give z = ∞.
        let z = -Normal::standard().inverse_cdf(0.5 * (1.0 - level));
        let (ci_low, ci_high) = (mean - z * std_error, mean + z * std_error);
        if ![mean, std_error, z, ci_low, ci_high]
            .iter()
            .all(|x| x.is_finite())
        {
            return Err(McError::NonFinite);
        }
        Ok(McEstimate {
            mean,
            std_error,
            ci_low,
            ci_high,
            level,
            n,
        })
    }
}

/// Per-worker buffers of [`stream`].
struct Work {
    sc: Scratch,
    tmp: Vec<f64>,
}

/// Streams `n` trajectories through `block` in work items of [`BLOCK`] indices and merges the
/// per-component moments of their samples in index order. `block(first, count, out, work)`
/// writes `comps` components of `count` samples component-major into `out` and returns the
/// number of environment steps; returns the merged moments and the total number of steps.
fn stream<E, F>(
    streamer: &Streamer<'_, E>,
    n: usize,
    comps: usize,
    block: F,
) -> Result<(Vec<Moments>, u64), McError>
where
    E: Environment + ?Sized,
    F: Fn(u64, usize, &mut [f64], &mut Work) -> u64 + Sync,
{
    let mut total = vec![Moments::default(); comps];
    let mut steps = 0u64;
    let items = n.div_ceil(BLOCK);
    let mut round = Vec::with_capacity(ROUND);
    for start in (0..items).step_by(ROUND) {
        if crate::cancel::requested() {
            return Err(McError::Rollout(RolloutError::Cancelled));
        }
        (start..items.min(start + ROUND))
            .into_par_iter()
            .map_init(
                || {
                    let work = Work {
                        sc: streamer.scratch(),
                        tmp: Vec::new(),
                    };
                    (Vec::new(), work)
                },
                |(buf, work), item| {
                    let first = item * BLOCK;
                    let count = BLOCK.min(n - first);
                    buf.resize(comps * count, 0.0);
                    let steps = block(first as u64, count, buf, work);
                    if !buf.iter().all(|x| x.is_finite()) {
                        return Err(McError::Rollout(RolloutError::NonFinite));
                    }
                    let m: Vec<Moments> =
                        buf.chunks_exact(count).map(Moments::from_samples).collect();
                    Ok((m, steps))
                },
            )
            .collect_into_vec(&mut round);
        for item in round.drain(..) {
            let (m, s) = item?;
            for (t, b) in total.iter_mut().zip(&m) {
                t.merge(b);
            }
            steps += s;
        }
    }
    Ok((total, steps))
}

/// Streamed moments of the discounted returns `G_i` of `n` trajectories, and the number of
/// environment steps taken. Memory does not grow with `n`; the result does not depend on the
/// number of threads.
///
/// # Formula
/// ```text
/// G_i = Σ_{t < len_i} γ^t r_{i,t},   i = 0 .. n − 1 (trajectory i uses key.rngs(i))
/// ```
///
/// ```
/// use sepg_mdp::{env::LqgEnv, monte_carlo::stream_returns, policy::GaussianPolicy, rng::SeedKey};
/// let pi = GaussianPolicy::scalar(-0.6, -1.0).unwrap();
/// let (m, steps) = stream_returns(&LqgEnv::thesis(), &pi, 3000, 20, SeedKey::default()).unwrap();
/// assert_eq!((m.count(), steps), (3000, 60_000));
/// ```
pub fn stream_returns<E: Environment + ?Sized>(
    env: &E,
    policy: &GaussianPolicy,
    n: usize,
    horizon: usize,
    key: SeedKey,
) -> Result<(Moments, u64), McError> {
    if n == 0 {
        return Err(McError::TooFewSamples(0));
    }
    let s = Streamer::new(env, policy, horizon, key, ScoreAction::Raw)?;
    let (m, steps) = stream(&s, n, 1, |first, _, out, w| {
        s.returns(first, out, &mut w.sc)
    })?;
    Ok((m[0], steps))
}

/// Streamed Monte Carlo estimates of `J`, `∇_v J` and `∇_w J` (G(PO)MDP, Sec 2.3.1) from `n`
/// trajectories: the [`Moments`] of every per-trajectory sample, from which the mean, the
/// standard error and a confidence interval of each component follow.
#[derive(Debug, Clone, PartialEq)]
pub struct GradientMoments {
    /// Moments of the discounted returns `G_i` (estimate of `J`).
    pub j: Moments,
    /// Moments of `g^v_{i,k}`, one per v-component (estimates of `∂J/∂v_k`).
    pub grad_v: Vec<Moments>,
    /// Moments of `g^w_{i,j}`, one per w-component (estimates of `∂J/∂w_j`).
    pub grad_w: Vec<Moments>,
    /// Environment steps of the `n` trajectories (the pilot batch excluded).
    pub steps: u64,
    /// Number of pilot trajectories the baseline was fitted on.
    pub pilot: usize,
}

/// The key of the pilot batch of [`stream_gradients`] for `key`: the same seed and block, with
/// the iteration counter complemented (`!iteration`), so its trajectories are independent of
/// every trajectory of the estimate.
///
/// ```
/// use sepg_mdp::{monte_carlo::pilot_key, rng::SeedKey};
/// assert_eq!(pilot_key(SeedKey::new(3, 0, 2)), SeedKey::new(3, u64::MAX, 2));
/// ```
pub fn pilot_key(key: SeedKey) -> SeedKey {
    SeedKey::new(key.seed, !key.iteration, key.block)
}

/// Streamed G(PO)MDP estimates of `J`, `∇_v J` and `∇_w J` from `n` trajectories of the
/// stochastic `policy`, with the variance-optimal per-step baseline fitted on an independent
/// pilot batch of `pilot` trajectories (key [`pilot_key`]; `pilot = 0` gives no baseline).
///
/// The baseline is independent of the `n` trajectories, so each per-trajectory sample is an
/// exactly unbiased estimate of the gradient and the samples are i.i.d.: their mean, standard
/// error and interval are those of i.i.d. samples. Trajectories that end early are padded as
/// in a [`crate::Batch`] (reward 0, scores frozen). Memory does not grow with `n`; the result
/// does not depend on the number of threads.
///
/// # Formula
/// ```text
/// g^v_{i,k} = Σ_{t<H} S^v_{i,t,k} (γ^t r_{i,t} − b^v_{t,k}),   S^v_{i,t} = Σ_{s≤t} ∇_v log π(a_s|s_s)
/// b^v_{t,k} = Σ_pilot (S^v_{t,k})² γ^t r_t / Σ_pilot (S^v_{t,k})²   (0 if the denominator is 0)
/// ```
/// and the same for `w`.
///
/// ```
/// use sepg_mdp::{env::LqgEnv, monte_carlo::stream_gradients, policy::GaussianPolicy, rng::SeedKey};
/// let pi = GaussianPolicy::scalar(-0.3, 0.5f64.ln()).unwrap();
/// let g = stream_gradients(&LqgEnv::lqg1d(), &pi, 5000, 20, SeedKey::new(1, 0, 0), 1000).unwrap();
/// assert_eq!((g.j.count(), g.grad_v.len(), g.grad_w.len(), g.steps), (5000, 1, 1, 100_000));
/// ```
pub fn stream_gradients<E: Environment + ?Sized>(
    env: &E,
    policy: &GaussianPolicy,
    n: usize,
    horizon: usize,
    key: SeedKey,
    pilot: usize,
) -> Result<GradientMoments, McError> {
    stream_gradients_with(env, policy, n, horizon, key, pilot, ScoreAction::Raw)
}

/// [`stream_gradients`] with the scores (of the pilot batch and of the `n` trajectories)
/// evaluated at the action chosen by `score` ([`ScoreAction::Raw`] is exactly
/// [`stream_gradients`]; with [`ScoreAction::Clipped`] the gradient estimates are biased where
/// the action box clips).
///
/// # Formula
/// ```text
/// as stream_gradients, with S^v, S^w the cumulative scores of the action chosen by score
/// ```
///
/// ```
/// use sepg_mdp::{env::LqgEnv, policy::GaussianPolicy, rng::SeedKey};
/// use sepg_mdp::{monte_carlo::stream_gradients_with, rollout::ScoreAction};
/// let pi = GaussianPolicy::scalar(-0.3, 0.5f64.ln()).unwrap();
/// let (env, key) = (LqgEnv::lqg1d(), SeedKey::new(1, 0, 0));
/// let g = stream_gradients_with(&env, &pi, 500, 20, key, 100, ScoreAction::Clipped).unwrap();
/// assert_eq!(g.j.count(), 500);
/// ```
pub fn stream_gradients_with<E: Environment + ?Sized>(
    env: &E,
    policy: &GaussianPolicy,
    n: usize,
    horizon: usize,
    key: SeedKey,
    pilot: usize,
    score: ScoreAction,
) -> Result<GradientMoments, McError> {
    if n == 0 {
        return Err(McError::TooFewSamples(0));
    }
    if policy.is_deterministic() {
        return Err(McError::Rollout(RolloutError::DeterministicPolicy));
    }
    let s = Streamer::new(env, policy, horizon, key, score)?;
    let baseline =
        fit_baseline(env, policy, horizon, key, pilot, score)?.unwrap_or_else(|| s.zero_baseline());
    let (dv, dw) = (s.dim_v(), s.dim_w());
    let (m, steps) = stream(&s, n, 1 + dv + dw, |first, count, out, w| {
        s.gpomdp(first, count, &baseline, out, &mut w.sc)
    })?;
    Ok(GradientMoments {
        j: m[0],
        grad_v: m[1..1 + dv].to_vec(),
        grad_w: m[1 + dv..].to_vec(),
        steps,
        pilot,
    })
}

/// The variance-optimal per-step baseline fitted on `pilot` trajectories of key
/// [`pilot_key`] (`None` for `pilot = 0`), summed serially in trajectory order.
fn fit_baseline<E: Environment + ?Sized>(
    env: &E,
    policy: &GaussianPolicy,
    horizon: usize,
    key: SeedKey,
    pilot: usize,
    score: ScoreAction,
) -> Result<Option<StepBaseline>, McError> {
    if pilot == 0 {
        return Ok(None);
    }
    let s = Streamer::new(env, policy, horizon, pilot_key(key), score)?;
    let mut sums = s.baseline_sums();
    let mut sc = s.scratch();
    s.fit(0, pilot, &mut sums, &mut sc);
    sums.baseline()
        .map(Some)
        .ok_or(McError::Rollout(RolloutError::NonFinite))
}

/// Monte Carlo estimate of `J(θ)` from `n ≥ 2` trajectories of `horizon` steps.
///
/// # Formula
/// ```text
/// Ĵ(θ) = (1/n) Σ_i Σ_t γ^t r_{i,t}
/// ```
///
/// ```
/// use sepg_mdp::{env::LqgEnv, monte_carlo::estimate_j, policy::GaussianPolicy, rng::SeedKey};
/// let pi = GaussianPolicy::scalar(-0.6, -1.0).unwrap();
/// let e = estimate_j(&LqgEnv::thesis(), &pi, 1000, 20, SeedKey::default(), 0.95).unwrap();
/// assert!(e.ci_low < e.mean && e.mean < e.ci_high);
/// ```
pub fn estimate_j<E: Environment + ?Sized>(
    env: &E,
    policy: &GaussianPolicy,
    n: usize,
    horizon: usize,
    key: SeedKey,
    level: f64,
) -> Result<McEstimate, McError> {
    check_args(n, level)?;
    stream_returns(env, policy, n, horizon, key)?
        .0
        .estimate(level)
}

/// Monte Carlo estimate of `J(v, −∞)`, the deterministic policy acting the mean of `policy`
/// (Sec 4.3.1).
///
/// # Formula
/// ```text
/// Ĵ(v, −∞) = (1/n) Σ_i Σ_t γ^t r(s_{i,t}, μ(s_{i,t}))
/// ```
///
/// ```
/// use sepg_mdp::{env::LqgEnv, monte_carlo::estimate_j_deterministic, policy::GaussianPolicy, rng::SeedKey};
/// let pi = GaussianPolicy::scalar(-0.6, 0.0).unwrap();
/// let e = estimate_j_deterministic(&LqgEnv::thesis(), &pi, 1000, 20, SeedKey::default(), 0.95).unwrap();
/// assert!(e.mean < 0.0);
/// ```
pub fn estimate_j_deterministic<E: Environment + ?Sized>(
    env: &E,
    policy: &GaussianPolicy,
    n: usize,
    horizon: usize,
    key: SeedKey,
    level: f64,
) -> Result<McEstimate, McError> {
    estimate_j(env, &policy.to_deterministic(), n, horizon, key, level)
}

/// Monte Carlo estimate of `J(θ′) − J(θ)` (`candidate` minus `base`) from paired trajectories
/// with common random numbers (same key, same trajectory index).
///
/// # Formula
/// ```text
/// d_i = G_i(θ′) − G_i(θ),   Δ̂ = (1/n) Σ_i d_i,   CI from the d_i
/// ```
///
/// ```
/// use sepg_mdp::{env::LqgEnv, monte_carlo::estimate_j_difference, policy::GaussianPolicy, rng::SeedKey};
/// let base = GaussianPolicy::scalar(-0.1, -1.0).unwrap();
/// let better = GaussianPolicy::scalar(-0.5, -1.0).unwrap();
/// let d = estimate_j_difference(&LqgEnv::thesis(), &base, &better, 500, 20, SeedKey::default(), 0.99).unwrap();
/// assert!(d.ci_low > 0.0);
/// ```
pub fn estimate_j_difference<E: Environment + ?Sized>(
    env: &E,
    base: &GaussianPolicy,
    candidate: &GaussianPolicy,
    n: usize,
    horizon: usize,
    key: SeedKey,
    level: f64,
) -> Result<McEstimate, McError> {
    check_args(n, level)?;
    if base.feature_dim() != candidate.feature_dim() || base.action_dim() != candidate.action_dim()
    {
        return Err(McError::PolicyShape);
    }
    let sb = Streamer::new(env, base, horizon, key, ScoreAction::Raw)?;
    let sc = Streamer::new(env, candidate, horizon, key, ScoreAction::Raw)?;
    let (m, _) = stream(&sb, n, 1, |first, count, d, w| {
        w.tmp.resize(count, 0.0);
        let steps = sb.returns(first, &mut w.tmp, &mut w.sc) + sc.returns(first, d, &mut w.sc);
        for (di, g) in d.iter_mut().zip(&w.tmp) {
            *di -= g;
        }
        steps
    })?;
    m[0].estimate(level)
}

fn check_args(n: usize, level: f64) -> Result<(), McError> {
    if n < 2 {
        return Err(McError::TooFewSamples(n));
    }
    if !(level > 0.0 && level < 1.0) {
        return Err(McError::InvalidLevel(level));
    }
    Ok(())
}
