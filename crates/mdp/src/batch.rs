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

/// Errors of [`Batch::from_steps`]: arrays that cannot describe a batch of trajectories.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum BatchError {
    /// `n = 0` trajectories or `horizon = 0`.
    #[error("a batch needs n ≥ 1 trajectories and horizon ≥ 1 (got n = {n}, horizon = {horizon})")]
    Empty {
        /// Number of trajectories (length of `lengths`).
        n: usize,
        /// Horizon.
        horizon: usize,
    },
    /// An array does not have the length its shape requires.
    #[error("{what} has length {got}, expected {expected}")]
    Length {
        /// Which array.
        what: &'static str,
        /// Length implied by `n`, `horizon` and the dimensions.
        expected: usize,
        /// Length given.
        got: usize,
    },
    /// A trajectory length is 0 or exceeds the horizon.
    #[error("trajectory {index} has length {len}, outside 1..={horizon}")]
    TrajectoryLength {
        /// Trajectory index.
        index: usize,
        /// Its length.
        len: usize,
        /// The horizon.
        horizon: usize,
    },
    /// γ is not in [0, 1].
    #[error("discount factor gamma = {gamma} is not in [0, 1]")]
    Gamma {
        /// The value given.
        gamma: f64,
    },
    /// A standard deviation is not finite and positive.
    #[error("standard deviation sigma[{index}] = {value} is not finite and positive")]
    Sigma {
        /// Action dimension.
        index: usize,
        /// The value given.
        value: f64,
    },
    /// A reward or score of a taken step, or a cumulative sum of them, is not finite.
    #[error("{what} of trajectory {index} is not finite")]
    NonFinite {
        /// `"reward"`, `"v-score"` or `"w-score"`.
        what: &'static str,
        /// Trajectory index.
        index: usize,
    },
}

impl Batch {
    /// A batch from per-step data collected by any rollout loop (for example a Python
    /// environment): the raw rewards `r_t` and the per-step scores `∇_v log π(a_t|s_t)`,
    /// `∇_w log π(a_t|s_t)` of `n = lengths.len()` trajectories, each stored over `horizon`
    /// steps (values at `t ≥ len_i` are ignored). The rewards are discounted and the scores
    /// accumulated as the rollout engine does (Sec 2.3.1), with the padding of the module
    /// documentation.
    ///
    /// Shapes (row-major, trajectory first): `rewards` is `n · horizon`, `score_v` is
    /// `n · horizon · dim_v`, `score_w` is `n · horizon · dim_w` with `dim_w = sigma.len()`;
    /// `dim_v` is read off the length of `score_v`. A batch that only estimates `J` (no
    /// gradients) passes empty `sigma`, `score_v` and `score_w`.
    ///
    /// # Formula
    /// ```text
    /// disc_rewards[i, t] = γ^t r_t                      (0 for t ≥ len_i)
    /// cum_score[i, t]    = Σ_{k ≤ min(t, len_i − 1)} score_k
    /// ```
    ///
    /// # Errors
    /// A [`BatchError`] for an empty batch, inconsistent lengths, a trajectory length outside
    /// `1..=horizon`, γ ∉ [0, 1], σ not finite and positive, or a non-finite reward, score or
    /// cumulative sum within the taken steps.
    ///
    /// # Examples
    /// ```
    /// use sepg_mdp::Batch;
    /// // Two trajectories, horizon 2, one mean and one variance parameter; the second stops
    /// // after one step.
    /// let b = Batch::from_steps(2, 0.5, &[1.0], &[1.0, 2.0, 3.0, 9.0],
    ///     &[0.1, 0.2, 0.3, 9.0], &[1.0, -1.0, 0.5, 9.0], &[2, 1]).unwrap();
    /// assert_eq!(b.disc_rewards, vec![1.0, 1.0, 3.0, 0.0]);
    /// assert_eq!(b.cum_score_v, vec![0.1, 0.1 + 0.2, 0.3, 0.3]);
    /// assert_eq!(b.cum_score_w, vec![1.0, 0.0, 0.5, 0.5]);
    /// assert_eq!(b.steps(), 3);
    /// ```
    pub fn from_steps(
        horizon: usize,
        gamma: f64,
        sigma: &[f64],
        rewards: &[f64],
        score_v: &[f64],
        score_w: &[f64],
        lengths: &[usize],
    ) -> Result<Batch, BatchError> {
        let n = lengths.len();
        if n == 0 || horizon == 0 {
            return Err(BatchError::Empty { n, horizon });
        }
        if !(0.0..=1.0).contains(&gamma) {
            return Err(BatchError::Gamma { gamma });
        }
        if let Some((index, &value)) = sigma
            .iter()
            .enumerate()
            .find(|(_, s)| !(s.is_finite() && **s > 0.0))
        {
            return Err(BatchError::Sigma { index, value });
        }
        let cells = n.saturating_mul(horizon);
        let dim_v = score_v.len() / cells;
        let dim_w = sigma.len();
        for (what, expected, got) in [
            ("rewards", cells, rewards.len()),
            ("score_v", cells.saturating_mul(dim_v), score_v.len()),
            ("score_w", cells.saturating_mul(dim_w), score_w.len()),
        ] {
            if expected != got {
                return Err(BatchError::Length {
                    what,
                    expected,
                    got,
                });
            }
        }
        let mut batch = Batch::zeros(n, horizon, dim_v, dim_w, gamma);
        batch.sigma.copy_from_slice(sigma);
        for (index, &len) in lengths.iter().enumerate() {
            if len == 0 || len > horizon {
                return Err(BatchError::TrajectoryLength {
                    index,
                    len,
                    horizon,
                });
            }
            batch.lengths[index] = len;
            let row = index * horizon;
            let mut disc = 1.0;
            for t in 0..len {
                batch.disc_rewards[row + t] = disc * rewards[row + t];
                disc *= gamma;
            }
            accumulate(&mut batch.cum_score_v, score_v, row, len, horizon, dim_v);
            accumulate(&mut batch.cum_score_w, score_w, row, len, horizon, dim_w);
            let finite = |xs: &[f64], d: usize| {
                xs[row * d..(row + horizon) * d]
                    .iter()
                    .all(|x| x.is_finite())
            };
            for (what, ok) in [
                ("reward", finite(&batch.disc_rewards, 1)),
                ("v-score", finite(&batch.cum_score_v, dim_v)),
                ("w-score", finite(&batch.cum_score_w, dim_w)),
            ] {
                if !ok {
                    return Err(BatchError::NonFinite { what, index });
                }
            }
        }
        Ok(batch)
    }
}

/// Running sums of the `dim`-vectors `steps[row + t]` for `t < len` into `cum`, the last sum
/// repeated for `len ≤ t < horizon`.
fn accumulate(cum: &mut [f64], steps: &[f64], row: usize, len: usize, horizon: usize, dim: usize) {
    if dim == 0 {
        return;
    }
    let mut acc = vec![0.0; dim];
    for t in 0..horizon {
        if t < len {
            let o = (row + t) * dim;
            for (a, s) in acc.iter_mut().zip(&steps[o..o + dim]) {
                *a += s;
            }
        }
        let o = (row + t) * dim;
        cum[o..o + dim].copy_from_slice(&acc);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Values after a trajectory's end are ignored (even NaN), γ^t is applied from t = 0,
    /// and the cumulative scores are running sums padded with their last value.
    #[test]
    fn from_steps_discounts_accumulates_and_pads() {
        let nan = f64::NAN;
        let b = Batch::from_steps(
            3,
            0.5,
            &[2.0],
            &[4.0, 4.0, 4.0, 1.0, nan, nan],
            &[1.0, 2.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, nan, nan, nan, nan],
            &[1.0, 1.0, 1.0, -1.0, nan, nan],
            &[3, 1],
        )
        .expect("batch");
        assert_eq!(
            (b.n, b.dim_v, b.dim_w, b.sigma.clone()),
            (2, 2, 1, vec![2.0])
        );
        assert_eq!(b.disc_rewards, vec![4.0, 2.0, 1.0, 1.0, 0.0, 0.0]);
        assert_eq!(
            b.cum_score_v,
            vec![1.0, 2.0, 2.0, 4.0, 5.0, 8.0, 5.0, 6.0, 5.0, 6.0, 5.0, 6.0]
        );
        assert_eq!(b.cum_score_w, vec![1.0, 2.0, 3.0, -1.0, -1.0, -1.0]);
        assert_eq!(b.lengths, vec![3, 1]);
    }

    #[test]
    fn from_steps_rejects_bad_input_with_typed_errors() {
        let ok = |r: &[f64], sv: &[f64], sigma: &[f64], gamma, lengths: &[usize]| {
            Batch::from_steps(
                2,
                gamma,
                sigma,
                r,
                sv,
                &[0.0; 2][..sigma.len() * 2],
                lengths,
            )
        };
        assert!(ok(&[1.0, 1.0], &[0.0, 0.0], &[1.0], 0.9, &[2]).is_ok());
        assert!(matches!(
            ok(&[], &[], &[], 0.9, &[]),
            Err(BatchError::Empty { n: 0, .. })
        ));
        assert!(matches!(
            ok(&[1.0], &[], &[], 0.9, &[2]),
            Err(BatchError::Length {
                what: "rewards",
                ..
            })
        ));
        assert!(matches!(
            ok(&[1.0, 1.0], &[0.0, 0.0, 0.0], &[1.0], 0.9, &[2]),
            Err(BatchError::Length {
                what: "score_v",
                ..
            })
        ));
        assert!(matches!(
            ok(&[1.0, 1.0], &[], &[], 0.9, &[3]),
            Err(BatchError::TrajectoryLength { len: 3, .. })
        ));
        assert!(matches!(
            ok(&[1.0, 1.0], &[], &[], 0.9, &[0]),
            Err(BatchError::TrajectoryLength { len: 0, .. })
        ));
        assert!(matches!(
            ok(&[1.0, 1.0], &[], &[], f64::NAN, &[2]),
            Err(BatchError::Gamma { .. })
        ));
        assert!(matches!(
            ok(&[1.0, 1.0], &[0.0, 0.0], &[0.0], 0.9, &[2]),
            Err(BatchError::Sigma { index: 0, .. })
        ));
        assert!(matches!(
            ok(&[1.0, f64::INFINITY], &[], &[], 0.9, &[2]),
            Err(BatchError::NonFinite {
                what: "reward",
                index: 0
            })
        ));
        assert!(matches!(
            ok(&[1.0, 1.0], &[f64::MAX, f64::MAX], &[1.0], 0.9, &[2]),
            Err(BatchError::NonFinite {
                what: "v-score",
                index: 0
            })
        ));
    }
}
