//! The compact trajectory batch that rollouts produce and estimators consume.
//!
//! A [`Batch`] holds, for `n` trajectories of at most `horizon` steps, exactly what the
//! likelihood-ratio estimators of the thesis need (Sec 2.3.1, Appendix B):
//!
//! - the per-step *discounted* rewards `γ^t r_t`,
//! - the per-step *cumulative* scores `Σ_{k≤t} ∇_v log π(a_k|s_k)` and
//!   `Σ_{k≤t} ∇_w log π(a_k|s_k)`, computed with the raw (unclipped) sampled action.
//!
//! With these, REINFORCE (eq. 2.1) uses the last cumulative score times the summed discounted
//! rewards, G(PO)MDP uses `Σ_t cum_score_t · γ^t r_t`, and the estimator of `h(θ)` (eq. B.3)
//! uses `Σ_t γ^t r_t · (cum σ-score_t)(cum v-score_t)` where the σ-score is the w-score
//! divided by σ.
//!
//! # Layout
//! Row-major, trajectory first:
//! - `disc_rewards[i * horizon + t]`
//! - `cum_score_v[(i * horizon + t) * dim_v + k]`
//! - `cum_score_w[(i * horizon + t) * dim_w + j]`
//!
//! A trajectory that terminates early (Mountain Car) after `len_i < horizon` steps is padded:
//! rewards are `0` and cumulative scores keep their last value for `t ≥ len_i`, so every
//! estimator formula can run over the full rectangle without special cases.
//!
//! The mean parameter vector is flattened action-major: for `l` action dimensions and `p`
//! features, `v[j * p + i]` multiplies feature `i` in the mean of action `j`, so
//! `dim_v = l · p` and `dim_w = l`.

/// A batch of `n` trajectories of at most `horizon` steps in estimator-ready form.
#[derive(Debug, Clone, PartialEq)]
pub struct Batch {
    /// Number of trajectories `N`.
    pub n: usize,
    /// Maximum number of steps `H` per trajectory (the padded row length).
    pub horizon: usize,
    /// Number of mean parameters `m = l · p`.
    pub dim_v: usize,
    /// Number of log-standard-deviation parameters `l` (one per action dimension).
    pub dim_w: usize,
    /// Discount factor `γ` used for `disc_rewards`.
    pub gamma: f64,
    /// Standard deviations `σ_j = e^{w_j}` of the policy that generated the batch (length `dim_w`).
    pub sigma: Vec<f64>,
    /// Discounted rewards `γ^t r_t`, length `n · horizon`.
    pub disc_rewards: Vec<f64>,
    /// Cumulative v-scores, length `n · horizon · dim_v`.
    pub cum_score_v: Vec<f64>,
    /// Cumulative w-scores, length `n · horizon · dim_w`.
    pub cum_score_w: Vec<f64>,
    /// Number of steps actually taken by each trajectory (`≤ horizon`), length `n`.
    pub lengths: Vec<usize>,
}

impl Batch {
    /// An all-zero batch of the given shape (every trajectory of full length), ready to be
    /// filled in place by a rollout engine or a test.
    pub fn zeros(n: usize, horizon: usize, dim_v: usize, dim_w: usize, gamma: f64) -> Self {
        Batch {
            n,
            horizon,
            dim_v,
            dim_w,
            gamma,
            sigma: vec![1.0; dim_w],
            disc_rewards: vec![0.0; n * horizon],
            cum_score_v: vec![0.0; n * horizon * dim_v],
            cum_score_w: vec![0.0; n * horizon * dim_w],
            lengths: vec![horizon; n],
        }
    }

    /// Discounted rewards `γ^t r_t` of trajectory `i` (length `horizon`).
    #[inline]
    pub fn rewards(&self, i: usize) -> &[f64] {
        &self.disc_rewards[i * self.horizon..(i + 1) * self.horizon]
    }

    /// Cumulative v-score of trajectory `i` at step `t` (length `dim_v`).
    #[inline]
    pub fn score_v(&self, i: usize, t: usize) -> &[f64] {
        let o = (i * self.horizon + t) * self.dim_v;
        &self.cum_score_v[o..o + self.dim_v]
    }

    /// Cumulative w-score of trajectory `i` at step `t` (length `dim_w`).
    #[inline]
    pub fn score_w(&self, i: usize, t: usize) -> &[f64] {
        let o = (i * self.horizon + t) * self.dim_w;
        &self.cum_score_w[o..o + self.dim_w]
    }

    /// Discounted return `Σ_t γ^t r_t` of trajectory `i`.
    #[inline]
    pub fn discounted_return(&self, i: usize) -> f64 {
        self.rewards(i).iter().sum()
    }

    /// Total number of environment steps in the batch (`Σ_i len_i`).
    #[inline]
    pub fn steps(&self) -> usize {
        self.lengths.iter().sum()
    }
}
