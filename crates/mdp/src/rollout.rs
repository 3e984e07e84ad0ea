//! The deterministic parallel rollout engine: trajectories into a [`Batch`] (discounted rewards
//! and cumulative raw-action scores, Sec 2.3.1), or discounted returns only.
//!
//! Trajectory `i` of a batch draws only from its own streams `key.rngs(i)`
//! ([`crate::rng::SeedKey`]), and every output value is written by exactly one trajectory, with
//! no floating-point reduction across threads. The result is therefore bit-identical for any
//! number of rayon threads. Work is split in fixed chunks of 64 trajectories.
//!
//! For a one-dimensional LQG ([`Environment::as_scalar_lqg`]) a fused scalar kernel runs
//! instead of the generic one; both perform the same floating-point operations in the same
//! order, so the kernel choice never changes a result.
//!
//! # Formula
//! ```text
//! disc_rewards[i, t] = γ^t r_t                              (0 for t ≥ len_i)
//! cum_score_v[i, t]  = Σ_{k ≤ min(t, len_i − 1)} (a_k − μ(s_k)) φ(s_k) / σ²
//! cum_score_w[i, t]  = Σ_{k ≤ min(t, len_i − 1)} ((a_k − μ(s_k))/σ)² − 1
//! G_i                = Σ_t γ^t r_t
//! ```
//! where `a_k − μ(s_k) = σ z_k` is the raw (unclipped) Gaussian perturbation. With
//! [`ScoreAction::Clipped`] the scores take the action after clipping to the action box
//! instead, `a_k − μ(s_k) = clip(a_k) − μ(s_k)` ([`Environment::clip_action`]).

use rayon::prelude::*;

use crate::batch::Batch;
use crate::env::{Environment, ScalarLqg};
use crate::features::FeatureMap;
use crate::policy::GaussianPolicy;
use crate::rng::{SeedKey, TrajectoryRngs, rngs_from_prefix, standard_normal, uniform};
use crate::stream::Streamer;

/// Number of trajectories in one parallel work item.
pub(crate) const CHUNK: usize = 64;

/// Which action the policy scores `∇_v log π(a|s)`, `∇_w log π(a|s)` of a scored rollout are
/// evaluated at (Sec 2.3.1; the policy scores of Sec 4.3.4).
///
/// The environment always applies the clipped action; only the scores differ. `Raw` scores
/// the sampled Gaussian action, which makes them the exact scores of the policy and the
/// gradient estimators unbiased. `Clipped` scores `a_c = clip(a)` (the choice of the
/// thesis-era code): the estimators are then biased wherever the action box clips, and the
/// scores coincide with `Raw` (up to rounding) where it does not. `Raw` is the default.
///
/// # Formula
/// ```text
/// Raw:      ∇_v log π = (a − μ(s)) φ(s) / σ²,     ∇_w log π = ((a − μ(s))/σ)² − 1
/// Clipped:  ∇_v log π = (a_c − μ(s)) φ(s) / σ²,   ∇_w log π = ((a_c − μ(s))/σ)² − 1
/// ```
///
/// ```
/// use sepg_mdp::rollout::ScoreAction;
/// assert_eq!(ScoreAction::default(), ScoreAction::Raw);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum ScoreAction {
    /// Scores of the raw sampled action `a = μ(s) + σ z` (exact policy scores).
    #[default]
    Raw,
    /// Scores of the clipped action `clip(a)` that the environment applies.
    Clipped,
}

/// Errors of the rollout engine.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum RolloutError {
    /// `n = 0` or `horizon = 0`.
    #[error("a batch needs n ≥ 1 trajectories and horizon ≥ 1 (got n = {n}, horizon = {horizon})")]
    Empty {
        /// Number of trajectories requested.
        n: usize,
        /// Horizon requested.
        horizon: usize,
    },
    /// The policy's feature or action dimension does not match the environment's.
    #[error("policy {what} dimension {found} does not match the environment's {expected}")]
    DimensionMismatch {
        /// `"feature"` or `"action"`.
        what: &'static str,
        /// Environment's dimension.
        expected: usize,
        /// Policy's dimension.
        found: usize,
    },
    /// Scores were requested for the deterministic policy (they do not exist).
    #[error("score rollouts need a stochastic policy (w > −∞)")]
    DeterministicPolicy,
    /// `n · horizon · dim_v` overflows `usize`.
    #[error("the batch size overflows the address space")]
    TooLarge,
    /// A reward, score or return overflowed to ±∞ or NaN (diverging dynamics or huge policy
    /// parameters on an unclipped environment).
    #[error("a reward, score or return is not finite (diverging dynamics or overflow)")]
    NonFinite,
    /// The computation was cancelled ([`crate::cancel::request`]) before it completed.
    #[error("cancelled")]
    Cancelled,
}

/// Rolls out `n` trajectories of at most `horizon` steps with the stochastic `policy` and
/// returns them as an estimator-ready [`Batch`] (Sec 2.3.1; layout and padding in
/// [`crate::batch`]). Trajectory `i` uses the streams `key.rngs(i)`.
///
/// # Formula
/// ```text
/// s_0 ~ reset,  a_t = μ(s_t) + σ z_t,  (r_t, s_{t+1}) = step(s_t, a_t)
/// ```
///
/// ```
/// use sepg_mdp::{env::LqgEnv, policy::GaussianPolicy, rng::SeedKey, rollout::rollout};
/// let env = LqgEnv::lqg1d();
/// let pi = GaussianPolicy::scalar(-0.1, 0.0).unwrap();
/// let b = rollout(&env, &pi, 100, 20, SeedKey::new(1, 0, 0)).unwrap();
/// assert_eq!((b.n, b.horizon, b.steps()), (100, 20, 2000));
/// ```
pub fn rollout<E: Environment + ?Sized>(
    env: &E,
    policy: &GaussianPolicy,
    n: usize,
    horizon: usize,
    key: SeedKey,
) -> Result<Batch, RolloutError> {
    let mut batch = Batch::zeros(0, 0, 0, 0, 0.0);
    rollout_into(env, policy, n, horizon, key, &mut batch)?;
    Ok(batch)
}

/// [`rollout`] into an existing [`Batch`], reusing its buffers (they are resized to the new
/// shape, so they are not reallocated when the shape does not grow).
///
/// # Formula
/// ```text
/// same as rollout
/// ```
///
/// ```
/// use sepg_mdp::{env::LqgEnv, policy::GaussianPolicy, rng::SeedKey, rollout::{rollout, rollout_into}, Batch};
/// let env = LqgEnv::lqg1d();
/// let pi = GaussianPolicy::scalar(-0.1, 0.0).unwrap();
/// let mut b = Batch::zeros(0, 0, 0, 0, 0.0);
/// rollout_into(&env, &pi, 10, 5, SeedKey::new(1, 0, 0), &mut b).unwrap();
/// assert_eq!(b, rollout(&env, &pi, 10, 5, SeedKey::new(1, 0, 0)).unwrap());
/// ```
pub fn rollout_into<E: Environment + ?Sized>(
    env: &E,
    policy: &GaussianPolicy,
    n: usize,
    horizon: usize,
    key: SeedKey,
    batch: &mut Batch,
) -> Result<(), RolloutError> {
    rollout_into_with(env, policy, n, horizon, key, ScoreAction::Raw, batch)
}

/// [`rollout_into`] with the scores evaluated at the action chosen by `score`
/// ([`ScoreAction::Raw`] is exactly [`rollout_into`]). The trajectories (states, actions,
/// rewards) do not depend on `score`.
///
/// # Formula
/// ```text
/// cum_score_v[i, t] = Σ_{k ≤ t} (â_k − μ(s_k)) φ(s_k) / σ²,   cum_score_w[i, t] = Σ_{k ≤ t} ((â_k − μ(s_k))/σ)² − 1
/// â_k = a_k (Raw) or clip(a_k) (Clipped)
/// ```
///
/// ```
/// use sepg_mdp::{env::LqgEnv, policy::GaussianPolicy, rng::SeedKey, Batch};
/// use sepg_mdp::rollout::{ScoreAction, rollout, rollout_into_with};
/// let (env, key) = (LqgEnv::lqg1d(), SeedKey::new(1, 0, 0));
/// let pi = GaussianPolicy::scalar(-0.1, 1.0).unwrap();
/// let mut b = Batch::zeros(0, 0, 0, 0, 0.0);
/// rollout_into_with(&env, &pi, 10, 5, key, ScoreAction::Clipped, &mut b).unwrap();
/// let raw = rollout(&env, &pi, 10, 5, key).unwrap();
/// assert_eq!(b.disc_rewards, raw.disc_rewards);
/// assert_ne!(b.cum_score_w, raw.cum_score_w);
/// ```
pub fn rollout_into_with<E: Environment + ?Sized>(
    env: &E,
    policy: &GaussianPolicy,
    n: usize,
    horizon: usize,
    key: SeedKey,
    score: ScoreAction,
    batch: &mut Batch,
) -> Result<(), RolloutError> {
    check(env, policy, n, horizon)?;
    let (sigma, inv_sigma) = policy.sigma_raw();
    if policy.is_deterministic() {
        return Err(RolloutError::DeterministicPolicy);
    }
    let dim_v = policy.dim_v();
    let dim_w = policy.dim_w();
    let cells = n.checked_mul(horizon).ok_or(RolloutError::TooLarge)?;
    let cells_v = cells.checked_mul(dim_v).ok_or(RolloutError::TooLarge)?;
    let cells_w = cells.checked_mul(dim_w).ok_or(RolloutError::TooLarge)?;
    let gamma = env.gamma();
    batch.n = n;
    batch.horizon = horizon;
    batch.dim_v = dim_v;
    batch.dim_w = dim_w;
    batch.gamma = gamma;
    batch.sigma.clear();
    batch.sigma.extend_from_slice(sigma);
    batch.disc_rewards.resize(cells, 0.0);
    batch.cum_score_v.resize(cells_v, 0.0);
    batch.cum_score_w.resize(cells_w, 0.0);
    batch.lengths.resize(n, 0);
    let limit = env.time_limit().map_or(horizon, |tl| tl.min(horizon));

    let finite = if let Some(p) = env.as_scalar_lqg().and_then(|e| e.scalar()) {
        let pol = ScalarPolicy {
            v: policy.v()[0],
            sigma: sigma[0],
            inv_sigma: inv_sigma[0],
            score,
        };
        fill_batch_scalar(batch, key, p, pol, limit)
    } else {
        let dims = (env.state_dim(), env.action_dim(), env.feature_dim());
        let fused = FusedPolicy::of(env, policy, score);
        fill_batch(batch, key, dims, |rngs, rewards, score_v, score_w, sc| {
            let mut rows = TrajRows {
                rewards,
                score_v,
                score_w,
            };
            let (len, g) = kernel(env, policy, fused, score, gamma, limit, rngs, &mut rows, sc);
            (len, finite_trajectory(g, &sc.cum_v, &sc.cum_w))
        })
    };
    if crate::cancel::requested() {
        Err(RolloutError::Cancelled)
    } else if finite {
        Ok(())
    } else {
        Err(RolloutError::NonFinite)
    }
}

/// The discounted returns `G_i = Σ_t γ^t r_t` of `n` trajectories, without scores (the fast
/// path for estimating `J`). Works with stochastic and deterministic policies; with the same
/// key and a stochastic policy, `G_i` equals `rollout(..).discounted_return(i)` bit for bit.
///
/// # Formula
/// ```text
/// G_i = Σ_{t < len_i} γ^t r_t
/// ```
///
/// ```
/// use sepg_mdp::{env::LqgEnv, policy::GaussianPolicy, rng::SeedKey, rollout::{rollout, rollout_returns}};
/// let env = LqgEnv::thesis();
/// let pi = GaussianPolicy::scalar(-0.4, -1.0).unwrap();
/// let key = SeedKey::new(5, 0, 0);
/// let g = rollout_returns(&env, &pi, 8, 20, key).unwrap();
/// assert_eq!(g[3], rollout(&env, &pi, 8, 20, key).unwrap().discounted_return(3));
/// ```
pub fn rollout_returns<E: Environment + ?Sized>(
    env: &E,
    policy: &GaussianPolicy,
    n: usize,
    horizon: usize,
    key: SeedKey,
) -> Result<Vec<f64>, RolloutError> {
    let mut out = Vec::new();
    rollout_returns_into(env, policy, n, horizon, key, &mut out)?;
    Ok(out)
}

/// [`rollout_returns`] into an existing vector (resized to `n`).
///
/// # Formula
/// ```text
/// G_i = Σ_{t < len_i} γ^t r_t
/// ```
///
/// ```
/// use sepg_mdp::{env::LqgEnv, policy::GaussianPolicy, rng::SeedKey, rollout::rollout_returns_into};
/// let mut g = Vec::new();
/// let pi = GaussianPolicy::deterministic(vec![-0.5], 1, 1).unwrap();
/// rollout_returns_into(&LqgEnv::thesis(), &pi, 4, 10, SeedKey::default(), &mut g).unwrap();
/// assert!(g.iter().all(|x| *x <= 0.0));
/// ```
pub fn rollout_returns_into<E: Environment + ?Sized>(
    env: &E,
    policy: &GaussianPolicy,
    n: usize,
    horizon: usize,
    key: SeedKey,
    out: &mut Vec<f64>,
) -> Result<(), RolloutError> {
    check(env, policy, n, horizon)?;
    out.resize(n, 0.0);
    let s = Streamer::new(env, policy, horizon, key, ScoreAction::Raw)?;
    let body = |c: usize, chunk: &mut [f64]| {
        if crate::cancel::requested() {
            return;
        }
        let mut scratch = s.scratch();
        s.returns((c * CHUNK) as u64, chunk, &mut scratch);
    };
    if n <= CHUNK {
        body(0, out);
    } else {
        out.par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(c, chunk)| body(c, chunk));
    }
    if crate::cancel::requested() {
        return Err(RolloutError::Cancelled);
    }
    if out.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(RolloutError::NonFinite)
    }
}

/// The Monte Carlo estimate `Ĵ = (1/n) Σ_i G_i` of the expected discounted return (eq. 2.1's
/// `J(θ)` truncated at `horizon`), summed in trajectory order.
///
/// # Formula
/// ```text
/// Ĵ = (1/n) Σ_i Σ_t γ^t r_{i,t}
/// ```
///
/// ```
/// use sepg_mdp::{env::LqgEnv, policy::GaussianPolicy, rng::SeedKey, rollout::mean_return};
/// let pi = GaussianPolicy::scalar(-0.6, -2.0).unwrap();
/// let j = mean_return(&LqgEnv::thesis(), &pi, 1000, 20, SeedKey::default()).unwrap();
/// assert!(j < 0.0 && j > -4.0 * 20.0);
/// ```
pub fn mean_return<E: Environment + ?Sized>(
    env: &E,
    policy: &GaussianPolicy,
    n: usize,
    horizon: usize,
    key: SeedKey,
) -> Result<f64, RolloutError> {
    let g = rollout_returns(env, policy, n, horizon, key)?;
    let mean = g.iter().sum::<f64>() / n as f64;
    if mean.is_finite() {
        Ok(mean)
    } else {
        Err(RolloutError::NonFinite)
    }
}

/// The Monte Carlo estimate of `J(v, −∞)`, the performance of the deterministic policy that
/// acts the mean `μ(s)` of `policy` (Sec 4.3.1: `θ = [v | −∞]`).
///
/// # Formula
/// ```text
/// Ĵ(v, −∞) = (1/n) Σ_i Σ_t γ^t r(s_{i,t}, μ(s_{i,t}))
/// ```
///
/// ```
/// use sepg_mdp::{env::LqgEnv, policy::GaussianPolicy, rng::SeedKey, rollout::evaluate_mean_policy};
/// let pi = GaussianPolicy::scalar(-0.6, 0.0).unwrap();
/// let j = evaluate_mean_policy(&LqgEnv::thesis(), &pi, 1000, 20, SeedKey::default()).unwrap();
/// assert!(j < 0.0);
/// ```
pub fn evaluate_mean_policy<E: Environment + ?Sized>(
    env: &E,
    policy: &GaussianPolicy,
    n: usize,
    horizon: usize,
    key: SeedKey,
) -> Result<f64, RolloutError> {
    mean_return(env, &policy.to_deterministic(), n, horizon, key)
}

pub(crate) fn check<E: Environment + ?Sized>(
    env: &E,
    policy: &GaussianPolicy,
    n: usize,
    horizon: usize,
) -> Result<(), RolloutError> {
    if n == 0 || horizon == 0 {
        return Err(RolloutError::Empty { n, horizon });
    }
    for (what, expected, found) in [
        ("feature", env.feature_dim(), policy.feature_dim()),
        ("action", env.action_dim(), policy.action_dim()),
    ] {
        if expected != found {
            return Err(RolloutError::DimensionMismatch {
                what,
                expected,
                found,
            });
        }
    }
    Ok(())
}

/// Per-chunk work buffers of the generic kernel. After a trajectory, `cum_v` and `cum_w` hold
/// its final cumulative scores.
pub(crate) struct Scratch {
    state: Vec<f64>,
    next: Vec<f64>,
    phi: Vec<f64>,
    action: Vec<f64>,
    pub(crate) cum_v: Vec<f64>,
    pub(crate) cum_w: Vec<f64>,
}

impl Scratch {
    /// Buffers for `(state, action, feature)` dimensions `(n, l, p)`.
    pub(crate) fn new((n, l, p): (usize, usize, usize)) -> Self {
        Scratch {
            state: vec![0.0; n],
            next: vec![0.0; n],
            phi: vec![0.0; p],
            action: vec![0.0; l],
            cum_v: vec![0.0; l * p],
            cum_w: vec![0.0; l],
        }
    }
}

/// What the generic kernel does with each step of a trajectory: `record(t, γ^t r_t, S^v_t,
/// S^w_t)` with the cumulative scores after step `t` (only meaningful when `SCORES`).
pub(crate) trait TrajSink {
    /// Whether the kernel must accumulate the scores.
    const SCORES: bool;
    /// Step `t` of the trajectory.
    fn record(&mut self, t: usize, dr: f64, cum_v: &[f64], cum_w: &[f64]);
}

/// Discards the steps (returns-only rollouts).
pub(crate) struct NoSteps;

impl TrajSink for NoSteps {
    const SCORES: bool = false;
    #[inline(always)]
    fn record(&mut self, _: usize, _: f64, _: &[f64], _: &[f64]) {}
}

impl<const K: usize> LaneSink<K> for NoSteps {
    const SCORES: bool = false;
    #[inline(always)]
    fn record(&mut self, _: usize, _: usize, _: f64, _: f64, _: f64) {}
}

/// Writes the steps into one trajectory's [`Batch`] rows.
struct TrajRows<'a> {
    rewards: &'a mut [f64],
    score_v: &'a mut [f64],
    score_w: &'a mut [f64],
}

impl TrajSink for TrajRows<'_> {
    const SCORES: bool = true;
    #[inline(always)]
    fn record(&mut self, t: usize, dr: f64, cum_v: &[f64], cum_w: &[f64]) {
        let (dv, l) = (cum_v.len(), cum_w.len());
        self.rewards[t] = dr;
        self.score_v[t * dv..(t + 1) * dv].copy_from_slice(cum_v);
        self.score_w[t * l..(t + 1) * l].copy_from_slice(cum_w);
    }
}

/// What the fused scalar kernel does with step `t` of lane `k`: `record(k, t, γ^t r_t, S^v_t,
/// S^w_t)` (scores only meaningful when `SCORES`).
pub(crate) trait LaneSink<const K: usize> {
    /// Whether the kernel must accumulate the scores.
    const SCORES: bool;
    /// Step `t` of lane `k`.
    fn record(&mut self, k: usize, t: usize, dr: f64, cv: f64, cw: f64);
}

/// Writes the steps into the [`Batch`] rows of `K` consecutive trajectories (rows of length
/// `h` back to back).
struct LaneRows<'a> {
    rw: &'a mut [f64],
    sv: &'a mut [f64],
    sw: &'a mut [f64],
    h: usize,
}

impl<const K: usize> LaneSink<K> for LaneRows<'_> {
    const SCORES: bool = true;
    #[inline(always)]
    fn record(&mut self, k: usize, t: usize, dr: f64, cv: f64, cw: f64) {
        let i = k * self.h + t;
        self.rw[i] = dr;
        self.sv[i] = cv;
        self.sw[i] = cw;
    }
}

/// Runs `kernel` for every trajectory of `batch` in parallel chunks (on the calling thread when
/// there is a single chunk) and pads each trajectory after its length (rewards 0, cumulative
/// scores frozen). `kernel` returns the length and whether the trajectory is finite; returns
/// whether every trajectory is.
fn fill_batch<F>(batch: &mut Batch, key: SeedKey, dims: (usize, usize, usize), kernel: F) -> bool
where
    F: Fn(&mut TrajectoryRngs, &mut [f64], &mut [f64], &mut [f64], &mut Scratch) -> (usize, bool)
        + Sync,
{
    let (h, dv, dw) = (batch.horizon, batch.dim_v, batch.dim_w);
    let prefix = key.prefix();
    let body = |c: usize, rw: &mut [f64], sv: &mut [f64], sw: &mut [f64], lens: &mut [usize]| {
        let mut scratch = Scratch::new(dims);
        let trajectories = rw
            .chunks_exact_mut(h)
            .zip(sv.chunks_exact_mut(h * dv))
            .zip(sw.chunks_exact_mut(h * dw))
            .zip(lens.iter_mut());
        let mut finite = true;
        for (k, (((r, v), w), len)) in trajectories.enumerate() {
            let mut rngs = rngs_from_prefix(prefix, (c * CHUNK + k) as u64);
            let (l, ok) = kernel(&mut rngs, r, v, w, &mut scratch);
            pad(r, v, dv, l);
            pad_scores(w, dw, l);
            *len = l;
            finite &= ok;
        }
        finite
    };
    for_each_chunk(batch, body)
}

/// Runs `body(c, rewards, scores_v, scores_w, lengths)` on the rows of every chunk `c` of
/// [`CHUNK`] trajectories of `batch`, in parallel (on the calling thread when there is a single
/// chunk); returns whether every call returned `true`.
fn for_each_chunk<F>(batch: &mut Batch, body: F) -> bool
where
    F: Fn(usize, &mut [f64], &mut [f64], &mut [f64], &mut [usize]) -> bool + Sync,
{
    let (h, dv, dw) = (batch.horizon, batch.dim_v, batch.dim_w);
    // A cancelled chunk is skipped (its rows are discarded with the batch).
    let body = |c: usize, rw: &mut [f64], sv: &mut [f64], sw: &mut [f64], lens: &mut [usize]| {
        crate::cancel::requested() || body(c, rw, sv, sw, lens)
    };
    let b = batch;
    if b.n <= CHUNK {
        return body(
            0,
            &mut b.disc_rewards,
            &mut b.cum_score_v,
            &mut b.cum_score_w,
            &mut b.lengths,
        );
    }
    b.disc_rewards
        .par_chunks_mut(CHUNK * h)
        .zip(b.cum_score_v.par_chunks_mut(CHUNK * h * dv))
        .zip(b.cum_score_w.par_chunks_mut(CHUNK * h * dw))
        .zip(b.lengths.par_chunks_mut(CHUNK))
        .enumerate()
        .map(|(c, (((rw, sv), sw), lens))| body(c, rw, sv, sw, lens))
        .reduce(|| true, |a, b| a & b)
}

/// Whether a trajectory with return `g` and final cumulative scores `cum_v`, `cum_w` has only
/// finite rewards and scores: a running sum that meets ±∞ or NaN never becomes finite again,
/// so checking the sums checks every term.
#[inline]
fn finite_trajectory(g: f64, cum_v: &[f64], cum_w: &[f64]) -> bool {
    g.is_finite() && cum_v.iter().chain(cum_w).all(|x| x.is_finite())
}

/// Zero rewards from `len` on, freeze the v-scores at their last value.
fn pad(rewards: &mut [f64], scores: &mut [f64], dim: usize, len: usize) {
    rewards[len..].fill(0.0);
    pad_scores(scores, dim, len);
}

fn pad_scores(scores: &mut [f64], dim: usize, len: usize) {
    let (done, rest) = scores.split_at_mut(len * dim);
    if rest.is_empty() {
        return;
    }
    match done.len().checked_sub(dim) {
        Some(last) => {
            let last = &done[last..];
            for row in rest.chunks_exact_mut(dim) {
                row.copy_from_slice(last);
            }
        }
        None => rest.fill(0.0),
    }
}

/// Trajectories advanced in lockstep by the fused scalar kernel. Each trajectory is a serial
/// chain of dependent floating-point operations; interleaving independent trajectories lets
/// the CPU overlap their latencies. The arithmetic of each trajectory is unchanged.
pub(crate) const LANES: usize = 4;

/// Mean gain and noise scale of a one-feature, one-action policy, and the action its scores
/// are evaluated at.
#[derive(Clone, Copy)]
pub(crate) struct ScalarPolicy {
    pub(crate) v: f64,
    pub(crate) sigma: f64,
    pub(crate) inv_sigma: f64,
    pub(crate) score: ScoreAction,
}

/// [`fill_batch`] for the scalar LQG, running the fused kernel on groups of [`LANES`]
/// trajectories.
fn fill_batch_scalar(
    batch: &mut Batch,
    key: SeedKey,
    p: &ScalarLqg,
    pol: ScalarPolicy,
    limit: usize,
) -> bool {
    let h = batch.horizon;
    let prefix = key.prefix();
    let body = |c: usize, rw: &mut [f64], sv: &mut [f64], sw: &mut [f64], lens: &mut [usize]| {
        let groups = rw
            .chunks_mut(LANES * h)
            .zip(sv.chunks_mut(LANES * h))
            .zip(sw.chunks_mut(LANES * h))
            .zip(lens.chunks_mut(LANES));
        let mut finite = true;
        for (g, (((r, v), w), ls)) in groups.enumerate() {
            let first = (c * CHUNK + g * LANES) as u64;
            if ls.len() == LANES {
                finite &= scalar_group::<LANES>(p, pol, limit, prefix, first, r, v, w, h);
            } else {
                for k in 0..ls.len() {
                    let span = k * h..(k + 1) * h;
                    let (rk, vk, wk) = (&mut r[span.clone()], &mut v[span.clone()], &mut w[span]);
                    finite &=
                        scalar_group::<1>(p, pol, limit, prefix, first + k as u64, rk, vk, wk, h);
                }
            }
            for (k, len) in ls.iter_mut().enumerate() {
                let span = k * h..(k + 1) * h;
                pad(&mut r[span.clone()], &mut v[span.clone()], 1, limit);
                pad_scores(&mut w[span], 1, limit);
                *len = limit;
            }
        }
        finite
    };
    for_each_chunk(batch, body)
}

/// Runs the scored scalar kernel on `K` consecutive trajectories whose rows are consecutive in
/// `r`, `v`, `w` (each of length `K · h`); returns whether they are all finite
/// ([`finite_trajectory`]).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn scalar_group<const K: usize>(
    p: &ScalarLqg,
    pol: ScalarPolicy,
    limit: usize,
    prefix: u64,
    first: u64,
    r: &mut [f64],
    v: &mut [f64],
    w: &mut [f64],
    h: usize,
) -> bool {
    let mut rngs: [TrajectoryRngs; K] =
        std::array::from_fn(|k| rngs_from_prefix(prefix, first + k as u64));
    let limit = limit.min(h);
    let mut rows = LaneRows {
        rw: &mut r[..K * h],
        sv: &mut v[..K * h],
        sw: &mut w[..K * h],
        h,
    };
    let g = scalar_kernel::<K, _, true>(p, pol, limit, &mut rngs, &mut rows);
    let last = limit - 1;
    (0..K).all(|k| finite_trajectory(g[k], &v[k * h + last..][..1], &w[k * h + last..][..1]))
}

/// The fused kernel of the scalar LQG (docs/CONVENTIONS.md §1 step order) on `K` trajectories in lockstep,
/// for `limit` steps; every step goes to `sink`. `STOCH = false` is the deterministic policy
/// (no draws from the policy stream). Returns the discounted returns.
#[inline(always)]
pub(crate) fn scalar_kernel<const K: usize, S: LaneSink<K>, const STOCH: bool>(
    p: &ScalarLqg,
    pol: ScalarPolicy,
    limit: usize,
    rngs: &mut [TrajectoryRngs; K],
    sink: &mut S,
) -> [f64; K] {
    let clipped_scores = S::SCORES && STOCH && pol.score == ScoreAction::Clipped;
    if p.noise_std > 0.0 {
        scalar_kernel_noise::<K, S, STOCH, true>(p, pol, limit, rngs, sink, clipped_scores)
    } else {
        scalar_kernel_noise::<K, S, STOCH, false>(p, pol, limit, rngs, sink, clipped_scores)
    }
}

/// [`scalar_kernel`] with the transition noise (`NOISY`) decided at compile time.
#[inline(always)]
fn scalar_kernel_noise<const K: usize, S: LaneSink<K>, const STOCH: bool, const NOISY: bool>(
    p: &ScalarLqg,
    pol: ScalarPolicy,
    limit: usize,
    rngs: &mut [TrajectoryRngs; K],
    sink: &mut S,
    clipped_scores: bool,
) -> [f64; K] {
    let (r, l) = (rngs, limit);
    match (p.clipping, clipped_scores) {
        (true, false) => scalar_kernel_impl::<K, S, STOCH, true, false, NOISY>(p, pol, l, r, sink),
        (false, false) => {
            scalar_kernel_impl::<K, S, STOCH, false, false, NOISY>(p, pol, l, r, sink)
        }
        (true, true) => scalar_kernel_impl::<K, S, STOCH, true, true, NOISY>(p, pol, l, r, sink),
        (false, true) => scalar_kernel_impl::<K, S, STOCH, false, true, NOISY>(p, pol, l, r, sink),
    }
}

/// [`scalar_kernel`] with the clipping, the scored action (`CSCORE`: the clipped one) and
/// the transition noise decided at compile time. Each step first draws the lanes' variates (policy stream, then
/// environment stream, in the same per-stream order as the generic kernel), then runs the
/// short branch-free arithmetic over the lanes.
#[inline(always)]
fn scalar_kernel_impl<
    const K: usize,
    S: LaneSink<K>,
    const STOCH: bool,
    const CLIP: bool,
    const CSCORE: bool,
    const NOISY: bool,
>(
    p: &ScalarLqg,
    pol: ScalarPolicy,
    limit: usize,
    rngs: &mut [TrajectoryRngs; K],
    sink: &mut S,
) -> [f64; K] {
    let p = *p;
    let ScalarPolicy {
        v,
        sigma,
        inv_sigma,
        ..
    } = pol;
    let noisy = NOISY;
    let mut s: [f64; K] =
        std::array::from_fn(|k| uniform(&mut rngs[k].env, p.init_low, p.init_high));
    let (mut cv, mut cw, mut ret) = ([0.0; K], [0.0; K], [0.0; K]);
    let mut disc = 1.0;
    let (mut z, mut eta) = ([0.0; K], [0.0; K]);
    for t in 0..limit {
        if STOCH {
            for (zk, rng) in z.iter_mut().zip(rngs.iter_mut()) {
                *zk = standard_normal(&mut rng.policy);
            }
        }
        if noisy {
            for (ek, rng) in eta.iter_mut().zip(rngs.iter_mut()) {
                *ek = p.noise_std * standard_normal(&mut rng.env);
            }
        }
        for k in 0..K {
            let sk = s[k];
            let mu = v * sk;
            let a = if STOCH {
                let zk = z[k];
                if S::SCORES && !CSCORE {
                    cv[k] += zk * inv_sigma * sk;
                    cw[k] += zk * zk - 1.0;
                }
                mu + sigma * zk
            } else {
                mu
            };
            let ac = if CLIP {
                clip(a, p.action_low, p.action_high)
            } else {
                a
            };
            if CSCORE {
                let zc = (ac - mu) * inv_sigma;
                cv[k] += zc * inv_sigma * sk;
                cw[k] += zc * zc - 1.0;
            }
            let r = -(sk * (p.q * sk) + ac * (p.r * ac));
            let dr = disc * r;
            sink.record(k, t, dr, cv[k], cw[k]);
            ret[k] += dr;
            let mut x = p.a * sk + p.b * ac;
            if noisy {
                x += eta[k];
            }
            s[k] = if CLIP {
                clip(x, p.state_low, p.state_high)
            } else {
                x
            };
        }
        disc *= p.gamma;
    }
    ret
}

/// `x` clipped to `[lo, hi]` for `lo ≤ hi`: exactly [`f64::clamp`] (NaN stays NaN, the
/// bounds themselves are returned at the ends), without its check of `lo ≤ hi`, which the
/// environment's validation has already made; this compiles to a branch-free max and min.
#[inline(always)]
fn clip(x: f64, lo: f64, hi: f64) -> f64 {
    let x = if x < lo { lo } else { x };
    if x > hi { hi } else { x }
}

/// The policy of a rollout that runs a fused kernel instead of the generic one: Mountain Car
/// with state + bias features (`φ = [pos, vel, 1]`, one action).
#[derive(Clone, Copy)]
pub(crate) struct FusedPolicy {
    v: [f64; 3],
    sigma: f64,
    inv_sigma: f64,
    stochastic: bool,
    clipped_scores: bool,
}

impl FusedPolicy {
    /// The fused Mountain Car policy, if `env` and `policy` have that shape, scoring the action
    /// chosen by `score`.
    pub(crate) fn of<E: Environment + ?Sized>(
        env: &E,
        policy: &GaussianPolicy,
        score: ScoreAction,
    ) -> Option<Self> {
        let mc = env.as_mountain_car()?;
        let state_bias = matches!(mc.feature_map(), FeatureMap::StateBias { dim: 2 });
        let v: [f64; 3] = policy.v().try_into().ok()?;
        if !state_bias || policy.action_dim() != 1 {
            return None;
        }
        let (sigma, inv_sigma) = policy.sigma_raw();
        let stochastic = !policy.is_deterministic();
        Some(FusedPolicy {
            v,
            sigma: if stochastic { sigma[0] } else { 0.0 },
            inv_sigma: if stochastic { inv_sigma[0] } else { 0.0 },
            stochastic,
            clipped_scores: score == ScoreAction::Clipped,
        })
    }
}

/// One trajectory with the fused kernel when there is one (`fused`, built with the same
/// `score`), else the generic kernel; both compute the same bits. Returns `(len, G)`;
/// afterwards `sc.cum_v`, `sc.cum_w` hold the final cumulative scores.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn kernel<E: Environment + ?Sized, S: TrajSink>(
    env: &E,
    policy: &GaussianPolicy,
    fused: Option<FusedPolicy>,
    score: ScoreAction,
    gamma: f64,
    limit: usize,
    rngs: &mut TrajectoryRngs,
    sink: &mut S,
    sc: &mut Scratch,
) -> (usize, f64) {
    match fused {
        Some(p) => mountain_car_kernel(p, gamma, limit, rngs, sink, sc),
        None => generic_kernel(env, policy, score, gamma, limit, rngs, sink, sc),
    }
}

/// The generic kernel specialised to Mountain Car with state + bias features: the same
/// floating-point operations in the same order (features, mean summed from the first feature,
/// scores, [`crate::mountain_car`]'s transition), with the state and scores in registers.
fn mountain_car_kernel<S: TrajSink>(
    p: FusedPolicy,
    gamma: f64,
    limit: usize,
    rngs: &mut TrajectoryRngs,
    sink: &mut S,
    sc: &mut Scratch,
) -> (usize, f64) {
    let mut state = [0.0; 2];
    crate::mountain_car::reset(&mut rngs.env, &mut state);
    let [mut pos, mut vel] = state;
    let (mut cv, mut cw) = ([0.0; 3], [0.0; 1]);
    let (mut disc, mut ret) = (1.0, 0.0);
    let mut len = limit;
    for t in 0..limit {
        let phi = [pos, vel, 1.0];
        let mu = p.v[0] * phi[0] + p.v[1] * phi[1] + p.v[2] * phi[2];
        let a = if p.stochastic {
            let z = standard_normal(&mut rngs.policy);
            let a = mu + p.sigma * z;
            if S::SCORES {
                let z = if p.clipped_scores {
                    (a.clamp(-1.0, 1.0) - mu) * p.inv_sigma
                } else {
                    z
                };
                let c = z * p.inv_sigma;
                for (cvk, f) in cv.iter_mut().zip(phi) {
                    *cvk += c * f;
                }
                cw[0] += z * z - 1.0;
            }
            a
        } else {
            mu
        };
        let (next_pos, next_vel, r, done) = crate::mountain_car::transition(pos, vel, a);
        let dr = disc * r;
        sink.record(t, dr, &cv, &cw);
        ret += dr;
        disc *= gamma;
        (pos, vel) = (next_pos, next_vel);
        if done {
            len = t + 1;
            break;
        }
    }
    sc.cum_v.copy_from_slice(&cv);
    sc.cum_w.copy_from_slice(&cw);
    (len, ret)
}

/// The generic kernel over any [`Environment`], scoring the action chosen by `score`. Returns
/// `(len, G)`; stops after a terminal step.
#[allow(clippy::too_many_arguments)]
pub(crate) fn generic_kernel<E: Environment + ?Sized, S: TrajSink>(
    env: &E,
    policy: &GaussianPolicy,
    score: ScoreAction,
    gamma: f64,
    limit: usize,
    rngs: &mut TrajectoryRngs,
    sink: &mut S,
    sc: &mut Scratch,
) -> (usize, f64) {
    let (sigma, inv_sigma) = policy.sigma_raw();
    let stochastic = !policy.is_deterministic();
    let clipped_scores = score == ScoreAction::Clipped;
    let p = policy.feature_dim();
    let l = policy.action_dim();
    env.reset(&mut rngs.env, &mut sc.state);
    sc.cum_v.fill(0.0);
    sc.cum_w.fill(0.0);
    let (mut disc, mut ret) = (1.0, 0.0);
    for t in 0..limit {
        env.features(&sc.state, &mut sc.phi);
        for j in 0..l {
            let mu = policy.mean_j(&sc.phi, j);
            sc.action[j] = if stochastic {
                let z = standard_normal(&mut rngs.policy);
                let a = mu + sigma[j] * z;
                if S::SCORES {
                    let z = if clipped_scores {
                        (env.clip_action(j, a) - mu) * inv_sigma[j]
                    } else {
                        z
                    };
                    let c = z * inv_sigma[j];
                    for (cv, f) in sc.cum_v[j * p..(j + 1) * p].iter_mut().zip(&sc.phi) {
                        *cv += c * f;
                    }
                    sc.cum_w[j] += z * z - 1.0;
                }
                a
            } else {
                mu
            };
        }
        let (r, done) = env.step(&sc.state, &sc.action, &mut rngs.env, &mut sc.next);
        let dr = disc * r;
        sink.record(t, dr, &sc.cum_v, &sc.cum_w);
        ret += dr;
        disc *= gamma;
        std::mem::swap(&mut sc.state, &mut sc.next);
        if done {
            return (t + 1, ret);
        }
    }
    (limit, ret)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::env::LqgEnv;
    use crate::lqg_model::LqgModel;
    use nalgebra::DVector;

    /// The fused Mountain Car kernel and the generic kernel agree bit for bit: scored batches
    /// (with terminations and padding, scores on raw and on clipped actions) and returns of
    /// stochastic and deterministic policies.
    #[test]
    fn mountain_car_kernel_matches_generic_kernel() {
        let env = crate::mountain_car::MountainCar::state_bias();
        let key = SeedKey::new(8, 1, 2);
        let (n, h) = (70, 300);
        // Energy pumping (μ = 100·vel) terminates within the horizon; the other does not.
        for (pi, terminates) in [
            (
                GaussianPolicy::new(vec![0.0, 100.0, 0.0], vec![-3.0], 3).unwrap(),
                true,
            ),
            (
                GaussianPolicy::new(vec![0.3, -2.0, 0.1], vec![-0.5], 3).unwrap(),
                false,
            ),
        ] {
            for score in [ScoreAction::Raw, ScoreAction::Clipped] {
                assert!(FusedPolicy::of(&env, &pi, score).is_some());
                let mut fast = Batch::zeros(0, 0, 0, 0, 0.0);
                rollout_into_with(&env, &pi, n, h, key, score, &mut fast).unwrap();
                assert_eq!(fast.steps() < n * h, terminates);
                let mut slow = fast.clone();
                fill_batch(
                    &mut slow,
                    key,
                    (2, 1, 3),
                    |rngs, rewards, score_v, score_w, sc| {
                        let mut rows = TrajRows {
                            rewards,
                            score_v,
                            score_w,
                        };
                        let k = generic_kernel(&env, &pi, score, 0.99, h, rngs, &mut rows, sc);
                        (k.0, true)
                    },
                );
                assert_eq!(fast, slow);
            }
            for p in [pi.clone(), pi.to_deterministic()] {
                let fast = rollout_returns(&env, &p, n, h, key).unwrap();
                let mut sc = Scratch::new((2, 1, 3));
                for (i, g) in fast.iter().enumerate() {
                    let mut rngs = key.rngs(i as u64);
                    let raw = ScoreAction::Raw;
                    let slow =
                        generic_kernel(&env, &p, raw, 0.99, h, &mut rngs, &mut NoSteps, &mut sc);
                    assert_eq!(g.to_bits(), slow.1.to_bits());
                }
            }
        }
    }

    /// The fused scalar kernel and the generic kernel agree bit for bit on every scalar LQG
    /// variant (clipping on/off, noise on/off), with scores on raw and on clipped actions.
    #[test]
    fn scalar_kernel_matches_generic_kernel() {
        let base = LqgModel::lqg1d();
        let models = [
            base.clone(),
            base.clone().with_clipping(false),
            base.clone()
                .with_noise(DVector::from_element(1, 0.3))
                .unwrap(),
            base.with_noise(DVector::from_element(1, 0.3))
                .unwrap()
                .with_clipping(false),
        ];
        let pi = GaussianPolicy::scalar(-0.3, 0.4).unwrap();
        let key = SeedKey::new(11, 2, 1);
        let (n, h) = (70, 15);
        for model in models {
            let env = LqgEnv::new(model).unwrap();
            let gamma = env.gamma();
            for score in [ScoreAction::Raw, ScoreAction::Clipped] {
                let mut fast = Batch::zeros(0, 0, 0, 0, 0.0);
                rollout_into_with(&env, &pi, n, h, key, score, &mut fast).unwrap();
                let mut slow = fast.clone();
                fill_batch(
                    &mut slow,
                    key,
                    (1, 1, 1),
                    |rngs, rewards, score_v, score_w, sc| {
                        let mut rows = TrajRows {
                            rewards,
                            score_v,
                            score_w,
                        };
                        let k = generic_kernel(&env, &pi, score, gamma, h, rngs, &mut rows, sc);
                        (k.0, true)
                    },
                );
                assert_eq!(fast, slow);
            }
            let fast_g = rollout_returns(&env, &pi, n, h, key).unwrap();
            let det = pi.to_deterministic();
            let fast_det = rollout_returns(&env, &det, n, h, key).unwrap();
            for i in 0..n {
                let mut sc = Scratch::new((1, 1, 1));
                let mut rngs = key.rngs(i as u64);
                let raw = ScoreAction::Raw;
                let g =
                    generic_kernel(&env, &pi, raw, gamma, h, &mut rngs, &mut NoSteps, &mut sc).1;
                assert_eq!(g.to_bits(), fast_g[i].to_bits());
                let mut rngs = key.rngs(i as u64);
                let g =
                    generic_kernel(&env, &det, raw, gamma, h, &mut rngs, &mut NoSteps, &mut sc).1;
                assert_eq!(g.to_bits(), fast_det[i].to_bits());
            }
        }
    }
}
