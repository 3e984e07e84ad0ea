//! Exact evaluation of small finite MDPs (thesis Section 2.1, Definitions 2.1–2.10).
//!
//! Everything here is computed by dense linear algebra, without sampling: the value function
//! V^π, the action-value function Q^π, the advantage A^π, the normalised discounted future-state
//! distribution d^π_μ, the performance J_μ(π), the policy advantage 𝔸^{π'}_{π,μ}, and the policy
//! distances used by the safe-policy-iteration bounds of Chapter 3 (D_∞, ΔA, max-KL).
//!
//! Conventions (Definitions 2.2–2.9): values are *unnormalised* discounted sums of rewards,
//! while the future-state distribution is *normalised* to sum to one,
//!
//! ```text
//! V^π      = (I − γ P_π)^{-1} r_π
//! Q^π(s,a) = R(s,a) + γ Σ_{s'} P(s'|s,a) V^π(s')
//! d^π_μ    = (1 − γ) μᵀ (I − γ P_π)^{-1}
//! J_μ(π)   = μᵀ V^π = (1 − γ)^{-1} Σ_s d^π_μ(s) r_π(s)
//! ```

use nalgebra::{DMatrix, DVector};
use proptest::prelude::*;
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Largest admissible deviation of a probability vector's sum from one.
const SIMPLEX_TOLERANCE: f64 = 1e-9;

/// Errors raised when building or evaluating a finite MDP.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum MdpError {
    /// A dimension was zero or a vector had the wrong length.
    #[error("invalid dimensions: {0}")]
    Dimension(String),
    /// The discount factor was outside `[0, 1)` or not finite.
    #[error("discount factor {0} is outside [0, 1)")]
    Discount(f64),
    /// A probability vector had a negative or non-finite entry or did not sum to one.
    #[error("not a probability distribution: {0}")]
    NotADistribution(String),
    /// A reward was not finite.
    #[error("reward at (state {state}, action {action}) is not finite")]
    Reward {
        /// State index.
        state: usize,
        /// Action index.
        action: usize,
    },
    /// The policy does not match the MDP's state and action counts.
    #[error("policy has {policy_states}x{policy_actions} entries, MDP has {states}x{actions}")]
    Mismatch {
        /// States of the MDP.
        states: usize,
        /// Actions of the MDP.
        actions: usize,
        /// States of the policy.
        policy_states: usize,
        /// Actions of the policy.
        policy_actions: usize,
    },
    /// The linear system `I − γ P_π` could not be solved (cannot happen for γ < 1 up to
    /// rounding, kept as a typed outcome rather than a panic).
    #[error("the Bellman linear system is numerically singular")]
    Singular,
}

fn check_distribution(p: &[f64], what: &str) -> Result<(), MdpError> {
    if p.iter().any(|x| !x.is_finite() || *x < 0.0) {
        return Err(MdpError::NotADistribution(format!(
            "{what} has a negative or non-finite entry"
        )));
    }
    let sum: f64 = p.iter().sum();
    if (sum - 1.0).abs() > SIMPLEX_TOLERANCE {
        return Err(MdpError::NotADistribution(format!(
            "{what} sums to {sum:e}"
        )));
    }
    Ok(())
}

/// Normalises non-negative weights into a probability vector; an all-zero vector becomes the
/// point mass on index 0 (this keeps shrunk counterexamples simple).
fn normalise(weights: &[f64]) -> Vec<f64> {
    let sum: f64 = weights.iter().sum();
    if sum > 0.0 {
        weights.iter().map(|w| w / sum).collect()
    } else {
        let mut p = vec![0.0; weights.len()];
        p[0] = 1.0;
        p
    }
}

/// A finite, discounted, infinite-horizon MDP ⟨S, A, P, R, γ, μ⟩ (Definition 2.1).
///
/// States are `0..n_states`, actions `0..n_actions`; rewards are deterministic functions of
/// the state-action pair, as in Definition 2.1.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FiniteMdp {
    n_states: usize,
    n_actions: usize,
    /// `transitions[(s * n_actions + a) * n_states + s2] = P(s2 | s, a)`.
    transitions: Vec<f64>,
    /// `rewards[s * n_actions + a] = R(s, a)`.
    rewards: Vec<f64>,
    gamma: f64,
    initial: Vec<f64>,
}

impl FiniteMdp {
    /// Builds and validates a finite MDP (Definition 2.1).
    ///
    /// `transitions` is row-major `[s][a][s']` with each `P(·|s,a)` a probability vector,
    /// `rewards` is row-major `[s][a]`, `gamma ∈ [0, 1)`, `initial` is the distribution μ.
    ///
    /// # Errors
    /// [`MdpError`] on a wrong length, a discount outside `[0, 1)`, a non-finite reward or
    /// a vector that is not a probability distribution (tolerance 1e-9 on the sum).
    ///
    /// # Example
    /// ```
    /// use sepg_verification::finite_mdp::FiniteMdp;
    /// // One state, one action, reward 1, γ = 0.5: V = 1 / (1 − 0.5) = 2.
    /// let mdp = FiniteMdp::new(1, 1, vec![1.0], vec![1.0], 0.5, vec![1.0]).unwrap();
    /// assert_eq!(mdp.n_states(), 1);
    /// assert!(FiniteMdp::new(1, 1, vec![1.0], vec![1.0], 1.0, vec![1.0]).is_err());
    /// ```
    pub fn new(
        n_states: usize,
        n_actions: usize,
        transitions: Vec<f64>,
        rewards: Vec<f64>,
        gamma: f64,
        initial: Vec<f64>,
    ) -> Result<Self, MdpError> {
        if n_states == 0 || n_actions == 0 {
            return Err(MdpError::Dimension(
                "at least one state and one action are required".into(),
            ));
        }
        if transitions.len() != n_states * n_actions * n_states
            || rewards.len() != n_states * n_actions
            || initial.len() != n_states
        {
            return Err(MdpError::Dimension(format!(
                "expected {} transitions, {} rewards and {} initial probabilities",
                n_states * n_actions * n_states,
                n_states * n_actions,
                n_states
            )));
        }
        if !(0.0..1.0).contains(&gamma) {
            return Err(MdpError::Discount(gamma));
        }
        for (i, row) in transitions.chunks(n_states).enumerate() {
            check_distribution(
                row,
                &format!("P(·|s={}, a={})", i / n_actions, i % n_actions),
            )?;
        }
        if let Some(i) = rewards.iter().position(|r| !r.is_finite()) {
            return Err(MdpError::Reward {
                state: i / n_actions,
                action: i % n_actions,
            });
        }
        check_distribution(&initial, "μ")?;
        Ok(Self {
            n_states,
            n_actions,
            transitions,
            rewards,
            gamma,
            initial,
        })
    }

    /// Number of states |S|.
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::FiniteMdp;
    /// let mdp = FiniteMdp::new(1, 2, vec![1.0, 1.0], vec![0.0, 1.0], 0.0, vec![1.0]).unwrap();
    /// assert_eq!(mdp.n_states(), 1);
    /// ```
    pub fn n_states(&self) -> usize {
        self.n_states
    }

    /// Number of actions |A|.
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::FiniteMdp;
    /// let mdp = FiniteMdp::new(1, 2, vec![1.0, 1.0], vec![0.0, 1.0], 0.0, vec![1.0]).unwrap();
    /// assert_eq!(mdp.n_actions(), 2);
    /// ```
    pub fn n_actions(&self) -> usize {
        self.n_actions
    }

    /// Discount factor γ ∈ [0, 1).
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::FiniteMdp;
    /// let mdp = FiniteMdp::new(1, 1, vec![1.0], vec![0.0], 0.9, vec![1.0]).unwrap();
    /// assert_eq!(mdp.gamma(), 0.9);
    /// ```
    pub fn gamma(&self) -> f64 {
        self.gamma
    }

    /// Reward R(s, a).
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::FiniteMdp;
    /// let mdp = FiniteMdp::new(1, 2, vec![1.0, 1.0], vec![0.0, -3.0], 0.0, vec![1.0]).unwrap();
    /// assert_eq!(mdp.reward(0, 1), -3.0);
    /// ```
    pub fn reward(&self, s: usize, a: usize) -> f64 {
        self.rewards[s * self.n_actions + a]
    }

    /// Transition probability P(s2 | s, a).
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::FiniteMdp;
    /// let mdp = FiniteMdp::new(2, 1, vec![0.0, 1.0, 0.5, 0.5], vec![0.0, 0.0], 0.0, vec![1.0, 0.0]).unwrap();
    /// assert_eq!(mdp.transition(0, 0, 1), 1.0);
    /// ```
    pub fn transition(&self, s: usize, a: usize, s2: usize) -> f64 {
        self.transitions[(s * self.n_actions + a) * self.n_states + s2]
    }

    /// Initial-state distribution μ.
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::FiniteMdp;
    /// let mdp = FiniteMdp::new(1, 1, vec![1.0], vec![0.0], 0.0, vec![1.0]).unwrap();
    /// assert_eq!(mdp.initial(), &[1.0]);
    /// ```
    pub fn initial(&self) -> &[f64] {
        &self.initial
    }

    /// Maximum absolute reward `R = max_{s,a} |R(s, a)|` (the `r_max` of the specification).
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::FiniteMdp;
    /// let mdp = FiniteMdp::new(1, 2, vec![1.0, 1.0], vec![0.5, -2.0], 0.0, vec![1.0]).unwrap();
    /// assert_eq!(mdp.r_max(), 2.0);
    /// ```
    pub fn r_max(&self) -> f64 {
        self.rewards.iter().fold(0.0, |m, r| m.max(r.abs()))
    }

    fn check_policy(&self, pi: &TabularPolicy) -> Result<(), MdpError> {
        if pi.n_states != self.n_states || pi.n_actions != self.n_actions {
            return Err(MdpError::Mismatch {
                states: self.n_states,
                actions: self.n_actions,
                policy_states: pi.n_states,
                policy_actions: pi.n_actions,
            });
        }
        Ok(())
    }

    /// State-to-state kernel P_π(s, s') = Σ_a π(a|s) P(s'|s, a) as a dense matrix.
    fn kernel(&self, pi: &TabularPolicy) -> DMatrix<f64> {
        let n = self.n_states;
        DMatrix::from_fn(n, n, |s, s2| {
            (0..self.n_actions)
                .map(|a| pi.prob(s, a) * self.transition(s, a, s2))
                .sum()
        })
    }

    /// Exact policy evaluation (Definitions 2.5–2.9) by solving the Bellman linear systems.
    ///
    /// # Formula
    /// ```text
    /// V = (I − γ P_π)^{-1} r_π,  Q = R + γ P V,  d = (1 − γ) (I − γ P_π)^{-T} μ,  J = μᵀ V
    /// ```
    ///
    /// # Errors
    /// [`MdpError::Mismatch`] if the policy has other dimensions, [`MdpError::Singular`] if
    /// the LU factorisation fails.
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::{FiniteMdp, TabularPolicy};
    /// let mdp = FiniteMdp::new(1, 1, vec![1.0], vec![1.0], 0.5, vec![1.0]).unwrap();
    /// let eval = mdp.evaluate(&TabularPolicy::uniform(1, 1).unwrap()).unwrap();
    /// assert!((eval.j() - 2.0).abs() < 1e-12);
    /// ```
    pub fn evaluate(&self, pi: &TabularPolicy) -> Result<PolicyEvaluation, MdpError> {
        self.check_policy(pi)?;
        let n = self.n_states;
        let m = DMatrix::<f64>::identity(n, n) - self.kernel(pi) * self.gamma;
        let r_pi = DVector::from_fn(n, |s, _| {
            (0..self.n_actions)
                .map(|a| pi.prob(s, a) * self.reward(s, a))
                .sum()
        });
        let lu = m.clone().lu();
        let v = lu.solve(&r_pi).ok_or(MdpError::Singular)?;
        let mu = DVector::from_column_slice(&self.initial);
        let occupancy = m.transpose().lu().solve(&mu).ok_or(MdpError::Singular)?;
        let d: Vec<f64> = occupancy.iter().map(|x| (1.0 - self.gamma) * x).collect();
        let mut q = vec![0.0; n * self.n_actions];
        for s in 0..n {
            for a in 0..self.n_actions {
                let next: f64 = (0..n).map(|s2| self.transition(s, a, s2) * v[s2]).sum();
                q[s * self.n_actions + a] = self.reward(s, a) + self.gamma * next;
            }
        }
        let j = self.initial.iter().zip(v.iter()).map(|(m, v)| m * v).sum();
        Ok(PolicyEvaluation {
            n_actions: self.n_actions,
            v: v.iter().copied().collect(),
            q,
            d,
            j,
        })
    }

    /// Expected discounted sum of a per-state signal along trajectories of π started from μ,
    /// `E[Σ_t γ^t x(s_t)]`, computed by propagating the state distribution step by step
    /// (no linear solve), until `γ^t` falls below `1e-18`. Used as an independent ground truth
    /// for the trajectory form of Lemma 3.15.
    ///
    /// # Formula
    /// ```text
    /// Σ_{t ≥ 0} γ^t (μᵀ P_π^t) x
    /// ```
    ///
    /// # Errors
    /// [`MdpError::Mismatch`] for a policy or signal of the wrong size.
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::{FiniteMdp, TabularPolicy};
    /// let mdp = FiniteMdp::new(1, 1, vec![1.0], vec![1.0], 0.5, vec![1.0]).unwrap();
    /// let pi = TabularPolicy::uniform(1, 1).unwrap();
    /// let total = mdp.discounted_sum_along(&pi, &[1.0]).unwrap();
    /// assert!((total - 2.0).abs() < 1e-12);
    /// ```
    pub fn discounted_sum_along(&self, pi: &TabularPolicy, x: &[f64]) -> Result<f64, MdpError> {
        self.check_policy(pi)?;
        if x.len() != self.n_states {
            return Err(MdpError::Dimension(format!(
                "signal has {} entries, expected {}",
                x.len(),
                self.n_states
            )));
        }
        let kernel = self.kernel(pi);
        let mut dist = DVector::from_column_slice(&self.initial);
        let signal = DVector::from_column_slice(x);
        let mut total = 0.0;
        let mut discount = 1.0;
        while discount > 1e-18 {
            total += discount * dist.dot(&signal);
            dist = kernel.tr_mul(&dist);
            discount *= self.gamma;
        }
        Ok(total)
    }
}

/// A stationary stochastic policy over a finite MDP, `π(a|s)` (Definition 2.3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TabularPolicy {
    n_states: usize,
    n_actions: usize,
    /// `probs[s * n_actions + a] = π(a|s)`.
    probs: Vec<f64>,
}

impl TabularPolicy {
    /// Builds a policy from row-major probabilities `π(a|s)`.
    ///
    /// # Errors
    /// [`MdpError`] for a wrong length or a row that is not a probability vector.
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::TabularPolicy;
    /// let pi = TabularPolicy::new(1, 2, vec![0.25, 0.75]).unwrap();
    /// assert_eq!(pi.prob(0, 1), 0.75);
    /// assert!(TabularPolicy::new(1, 2, vec![0.5, 0.6]).is_err());
    /// ```
    pub fn new(n_states: usize, n_actions: usize, probs: Vec<f64>) -> Result<Self, MdpError> {
        if n_states == 0 || n_actions == 0 || probs.len() != n_states * n_actions {
            return Err(MdpError::Dimension(format!(
                "policy needs {n_states}x{n_actions} > 0 probabilities"
            )));
        }
        for (s, row) in probs.chunks(n_actions).enumerate() {
            check_distribution(row, &format!("π(·|s={s})"))?;
        }
        Ok(Self {
            n_states,
            n_actions,
            probs,
        })
    }

    /// The uniform policy π(a|s) = 1/|A|.
    ///
    /// # Errors
    /// [`MdpError::Dimension`] if a dimension is zero.
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::TabularPolicy;
    /// assert_eq!(TabularPolicy::uniform(2, 4).unwrap().prob(1, 3), 0.25);
    /// ```
    pub fn uniform(n_states: usize, n_actions: usize) -> Result<Self, MdpError> {
        if n_states == 0 || n_actions == 0 {
            return Err(MdpError::Dimension("empty policy".into()));
        }
        Ok(Self {
            n_states,
            n_actions,
            probs: vec![1.0 / n_actions as f64; n_states * n_actions],
        })
    }

    /// Builds a policy from per-state non-negative weights, normalising each row; an all-zero
    /// row becomes the point mass on action 0. Infallible by construction, used by strategies.
    fn from_weights(n_states: usize, n_actions: usize, weights: &[f64]) -> Self {
        let probs = weights.chunks(n_actions).flat_map(normalise).collect();
        Self {
            n_states,
            n_actions,
            probs,
        }
    }

    /// Probability π(a|s).
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::TabularPolicy;
    /// assert_eq!(TabularPolicy::uniform(1, 2).unwrap().prob(0, 0), 0.5);
    /// ```
    pub fn prob(&self, s: usize, a: usize) -> f64 {
        self.probs[s * self.n_actions + a]
    }

    /// Number of states.
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::TabularPolicy;
    /// assert_eq!(TabularPolicy::uniform(3, 2).unwrap().n_states(), 3);
    /// ```
    pub fn n_states(&self) -> usize {
        self.n_states
    }

    /// Number of actions.
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::TabularPolicy;
    /// assert_eq!(TabularPolicy::uniform(3, 2).unwrap().n_actions(), 2);
    /// ```
    pub fn n_actions(&self) -> usize {
        self.n_actions
    }

    /// Convex combination `(1 − α) π + α π̄` (eq. (3.1)).
    ///
    /// # Errors
    /// [`MdpError::Mismatch`] for policies of different shapes,
    /// [`MdpError::NotADistribution`] if `α ∉ [0, 1]`.
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::TabularPolicy;
    /// let a = TabularPolicy::new(1, 2, vec![1.0, 0.0]).unwrap();
    /// let b = TabularPolicy::new(1, 2, vec![0.0, 1.0]).unwrap();
    /// assert_eq!(a.mixture(&b, 0.25).unwrap().prob(0, 1), 0.25);
    /// ```
    pub fn mixture(&self, other: &TabularPolicy, alpha: f64) -> Result<Self, MdpError> {
        self.same_shape(other)?;
        if !(0.0..=1.0).contains(&alpha) {
            return Err(MdpError::NotADistribution(format!(
                "mixture weight {alpha} is outside [0, 1]"
            )));
        }
        let probs = self
            .probs
            .iter()
            .zip(&other.probs)
            .map(|(p, q)| (1.0 - alpha) * p + alpha * q)
            .collect();
        Ok(Self {
            n_states: self.n_states,
            n_actions: self.n_actions,
            probs,
        })
    }

    fn same_shape(&self, other: &TabularPolicy) -> Result<(), MdpError> {
        if self.n_states != other.n_states || self.n_actions != other.n_actions {
            return Err(MdpError::Mismatch {
                states: self.n_states,
                actions: self.n_actions,
                policy_states: other.n_states,
                policy_actions: other.n_actions,
            });
        }
        Ok(())
    }

    /// `D_∞^{π,π'} = max_s ‖π'(·|s) − π(·|s)‖₁` (eq. (3.9)); also the `‖π_θ' − π_θ‖_∞` of
    /// Theorem 3.8.
    ///
    /// # Errors
    /// [`MdpError::Mismatch`] for policies of different shapes.
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::TabularPolicy;
    /// let a = TabularPolicy::new(1, 2, vec![1.0, 0.0]).unwrap();
    /// let b = TabularPolicy::new(1, 2, vec![0.0, 1.0]).unwrap();
    /// assert_eq!(a.sup_l1_distance(&b).unwrap(), 2.0);
    /// ```
    pub fn sup_l1_distance(&self, other: &TabularPolicy) -> Result<f64, MdpError> {
        self.same_shape(other)?;
        Ok(self
            .probs
            .chunks(self.n_actions)
            .zip(other.probs.chunks(self.n_actions))
            .map(|(p, q)| p.iter().zip(q).map(|(x, y)| (x - y).abs()).sum::<f64>())
            .fold(0.0, f64::max))
    }

    /// `D_KL^max(π, π̃) = max_s KL(π(·|s) ‖ π̃(·|s))` (Theorem 3.16), in nats; `+∞` when π̃
    /// puts zero mass on an action that π plays.
    ///
    /// # Formula
    /// ```text
    /// max_s Σ_a π(a|s) ln(π(a|s) / π̃(a|s))     (0 ln 0 = 0)
    /// ```
    ///
    /// # Errors
    /// [`MdpError::Mismatch`] for policies of different shapes.
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::TabularPolicy;
    /// let a = TabularPolicy::new(1, 2, vec![0.5, 0.5]).unwrap();
    /// let b = TabularPolicy::new(1, 2, vec![1.0, 0.0]).unwrap();
    /// assert!((b.max_kl(&a).unwrap() - 2f64.ln()).abs() < 1e-15);
    /// assert_eq!(a.max_kl(&b).unwrap(), f64::INFINITY);
    /// ```
    pub fn max_kl(&self, other: &TabularPolicy) -> Result<f64, MdpError> {
        self.same_shape(other)?;
        let mut worst: f64 = 0.0;
        for (p, q) in self
            .probs
            .chunks(self.n_actions)
            .zip(other.probs.chunks(self.n_actions))
        {
            let mut kl = 0.0;
            for (&x, &y) in p.iter().zip(q) {
                if x > 0.0 {
                    if y <= 0.0 {
                        return Ok(f64::INFINITY);
                    }
                    kl += x * (x / y).ln();
                }
            }
            worst = worst.max(kl);
        }
        Ok(worst)
    }
}

/// Exact evaluation of one policy on one finite MDP (output of [`FiniteMdp::evaluate`]).
#[derive(Debug, Clone, PartialEq)]
pub struct PolicyEvaluation {
    n_actions: usize,
    v: Vec<f64>,
    q: Vec<f64>,
    d: Vec<f64>,
    j: f64,
}

impl PolicyEvaluation {
    /// Performance J_μ(π) = μᵀ V^π (Definition 2.4).
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::{FiniteMdp, TabularPolicy};
    /// let mdp = FiniteMdp::new(1, 1, vec![1.0], vec![-1.0], 0.0, vec![1.0]).unwrap();
    /// assert_eq!(mdp.evaluate(&TabularPolicy::uniform(1, 1).unwrap()).unwrap().j(), -1.0);
    /// ```
    pub fn j(&self) -> f64 {
        self.j
    }

    /// State values V^π(s) (Definition 2.7).
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::{FiniteMdp, TabularPolicy};
    /// let mdp = FiniteMdp::new(1, 1, vec![1.0], vec![1.0], 0.5, vec![1.0]).unwrap();
    /// let e = mdp.evaluate(&TabularPolicy::uniform(1, 1).unwrap()).unwrap();
    /// assert!((e.values()[0] - 2.0).abs() < 1e-12);
    /// ```
    pub fn values(&self) -> &[f64] {
        &self.v
    }

    /// Action value Q^π(s, a) (Definition 2.8).
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::{FiniteMdp, TabularPolicy};
    /// let mdp = FiniteMdp::new(1, 2, vec![1.0, 1.0], vec![0.0, 1.0], 0.0, vec![1.0]).unwrap();
    /// let e = mdp.evaluate(&TabularPolicy::uniform(1, 2).unwrap()).unwrap();
    /// assert_eq!(e.q(0, 1), 1.0);
    /// ```
    pub fn q(&self, s: usize, a: usize) -> f64 {
        self.q[s * self.n_actions + a]
    }

    /// Advantage A^π(s, a) = Q^π(s, a) − V^π(s) (Definition 2.9).
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::{FiniteMdp, TabularPolicy};
    /// let mdp = FiniteMdp::new(1, 2, vec![1.0, 1.0], vec![0.0, 1.0], 0.0, vec![1.0]).unwrap();
    /// let e = mdp.evaluate(&TabularPolicy::uniform(1, 2).unwrap()).unwrap();
    /// assert_eq!(e.advantage(0, 1), 0.5);
    /// ```
    pub fn advantage(&self, s: usize, a: usize) -> f64 {
        self.q(s, a) - self.v[s]
    }

    /// Normalised discounted future-state distribution d^π_μ (Definition 2.5); sums to one.
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::{FiniteMdp, TabularPolicy};
    /// let mdp = FiniteMdp::new(2, 1, vec![0.0, 1.0, 0.0, 1.0], vec![0.0, 0.0], 0.5, vec![1.0, 0.0]).unwrap();
    /// let d = mdp.evaluate(&TabularPolicy::uniform(2, 1).unwrap()).unwrap().state_distribution().to_vec();
    /// assert!((d[0] - 0.5).abs() < 1e-12 && (d[1] - 0.5).abs() < 1e-12);
    /// ```
    pub fn state_distribution(&self) -> &[f64] {
        &self.d
    }

    /// Largest action value `sup_{s,a} Q^π(s, a)`, without absolute value, as printed after
    /// eq. (3.12) and in Theorem 3.8.
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::{FiniteMdp, TabularPolicy};
    /// let mdp = FiniteMdp::new(1, 2, vec![1.0, 1.0], vec![-3.0, -1.0], 0.0, vec![1.0]).unwrap();
    /// let e = mdp.evaluate(&TabularPolicy::uniform(1, 2).unwrap()).unwrap();
    /// assert_eq!(e.q_sup(), -1.0);
    /// ```
    pub fn q_sup(&self) -> f64 {
        self.q.iter().copied().fold(f64::NEG_INFINITY, f64::max)
    }

    /// Supremum norm `‖Q^π‖_∞ = sup_{s,a} |Q^π(s, a)|`.
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::{FiniteMdp, TabularPolicy};
    /// let mdp = FiniteMdp::new(1, 2, vec![1.0, 1.0], vec![-3.0, -1.0], 0.0, vec![1.0]).unwrap();
    /// let e = mdp.evaluate(&TabularPolicy::uniform(1, 2).unwrap()).unwrap();
    /// assert_eq!(e.q_sup_abs(), 3.0);
    /// ```
    pub fn q_sup_abs(&self) -> f64 {
        self.q.iter().fold(0.0, |m, q| m.max(q.abs()))
    }

    /// `ε = max_{s,a} |A^π(s, a)|` (Theorem 3.16).
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::{FiniteMdp, TabularPolicy};
    /// let mdp = FiniteMdp::new(1, 2, vec![1.0, 1.0], vec![0.0, 1.0], 0.0, vec![1.0]).unwrap();
    /// let e = mdp.evaluate(&TabularPolicy::uniform(1, 2).unwrap()).unwrap();
    /// assert_eq!(e.max_abs_advantage(), 0.5);
    /// ```
    pub fn max_abs_advantage(&self) -> f64 {
        (0..self.v.len())
            .flat_map(|s| (0..self.n_actions).map(move |a| (s, a)))
            .fold(0.0, |m, (s, a)| m.max(self.advantage(s, a).abs()))
    }

    /// Per-state policy advantage `A^{π'}_π(s) = Σ_a π'(a|s) A^π(s, a)` (Definition 2.10).
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::{FiniteMdp, TabularPolicy};
    /// let mdp = FiniteMdp::new(1, 2, vec![1.0, 1.0], vec![0.0, 1.0], 0.0, vec![1.0]).unwrap();
    /// let e = mdp.evaluate(&TabularPolicy::uniform(1, 2).unwrap()).unwrap();
    /// let best = TabularPolicy::new(1, 2, vec![0.0, 1.0]).unwrap();
    /// assert_eq!(e.policy_advantage_by_state(&best), vec![0.5]);
    /// ```
    pub fn policy_advantage_by_state(&self, other: &TabularPolicy) -> Vec<f64> {
        (0..self.v.len())
            .map(|s| {
                (0..self.n_actions)
                    .map(|a| other.prob(s, a) * self.advantage(s, a))
                    .sum()
            })
            .collect()
    }

    /// Expected policy advantage `𝔸^{π'}_{π,μ} = Σ_s d^π_μ(s) A^{π'}_π(s)` (Definition 2.10,
    /// eq. (3.3)), weighted by this evaluation's own (normalised) d^π_μ.
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::{FiniteMdp, TabularPolicy};
    /// let mdp = FiniteMdp::new(1, 2, vec![1.0, 1.0], vec![0.0, 1.0], 0.0, vec![1.0]).unwrap();
    /// let e = mdp.evaluate(&TabularPolicy::uniform(1, 2).unwrap()).unwrap();
    /// let best = TabularPolicy::new(1, 2, vec![0.0, 1.0]).unwrap();
    /// assert_eq!(e.policy_advantage(&best), 0.5);
    /// ```
    pub fn policy_advantage(&self, other: &TabularPolicy) -> f64 {
        self.weighted_policy_advantage(&self.d, other)
    }

    /// `Σ_s weights(s) A^{π'}_π(s)`: the policy advantage under another state distribution
    /// (the `d^{π_b}_μ A^{π'}_π` term of eq. (3.10)).
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::{FiniteMdp, TabularPolicy};
    /// let mdp = FiniteMdp::new(1, 2, vec![1.0, 1.0], vec![0.0, 1.0], 0.0, vec![1.0]).unwrap();
    /// let e = mdp.evaluate(&TabularPolicy::uniform(1, 2).unwrap()).unwrap();
    /// let best = TabularPolicy::new(1, 2, vec![0.0, 1.0]).unwrap();
    /// assert_eq!(e.weighted_policy_advantage(&[2.0], &best), 1.0);
    /// ```
    pub fn weighted_policy_advantage(&self, weights: &[f64], other: &TabularPolicy) -> f64 {
        weights
            .iter()
            .zip(self.policy_advantage_by_state(other))
            .map(|(w, a)| w * a)
            .sum()
    }

    /// `ΔA^{π'}_π = sup_{s,s'} |A^{π'}_π(s) − A^{π'}_π(s')|` (eq. (3.11)).
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::{FiniteMdp, TabularPolicy};
    /// let mdp = FiniteMdp::new(1, 2, vec![1.0, 1.0], vec![0.0, 1.0], 0.0, vec![1.0]).unwrap();
    /// let e = mdp.evaluate(&TabularPolicy::uniform(1, 2).unwrap()).unwrap();
    /// assert_eq!(e.advantage_spread(&TabularPolicy::uniform(1, 2).unwrap()), 0.0);
    /// ```
    pub fn advantage_spread(&self, other: &TabularPolicy) -> f64 {
        let a = self.policy_advantage_by_state(other);
        let hi = a.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let lo = a.iter().copied().fold(f64::INFINITY, f64::min);
        hi - lo
    }

    /// Greedy policy `π̄(s) ∈ argmax_a Q^π(s, a)` (Definition 2.12), deterministic, ties broken
    /// towards the lowest action index.
    ///
    /// # Example
    /// ```
    /// # use sepg_verification::finite_mdp::{FiniteMdp, TabularPolicy};
    /// let mdp = FiniteMdp::new(1, 2, vec![1.0, 1.0], vec![0.0, 1.0], 0.0, vec![1.0]).unwrap();
    /// let e = mdp.evaluate(&TabularPolicy::uniform(1, 2).unwrap()).unwrap();
    /// assert_eq!(e.greedy().prob(0, 1), 1.0);
    /// ```
    pub fn greedy(&self) -> TabularPolicy {
        let n_states = self.v.len();
        let mut probs = vec![0.0; n_states * self.n_actions];
        for s in 0..n_states {
            let mut best = 0;
            for a in 1..self.n_actions {
                if self.q(s, a) > self.q(s, best) {
                    best = a;
                }
            }
            probs[s * self.n_actions + best] = 1.0;
        }
        TabularPolicy {
            n_states,
            n_actions: self.n_actions,
            probs,
        }
    }
}

/// Sign convention for the rewards drawn by [`scenario`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RewardRange {
    /// Rewards in `[−1, 1]`.
    Signed,
    /// Rewards in `[0, 1]` (the convention of Kakade & Langford and Pirotta et al.).
    NonNegative,
    /// Rewards in `[−1, 0]` (costs, as in the LQG of Chapter 5).
    NonPositive,
}

/// A random finite MDP together with random policies and a mixture weight: the configuration
/// space searched by the Chapter 3 checks.
#[derive(Debug, Clone)]
pub struct Scenario {
    /// The MDP.
    pub mdp: FiniteMdp,
    /// Independently drawn policies (dense, sparse or deterministic rows).
    pub policies: Vec<TabularPolicy>,
    /// A mixture weight in `[0, 1]` (edges 0 and 1 are drawn explicitly).
    pub alpha: f64,
}

fn row_strategy(len: usize) -> BoxedStrategy<Vec<f64>> {
    prop_oneof![
        2 => prop::collection::vec(0.0..=1.0f64, len),
        1 => prop::collection::vec(prop_oneof![2 => Just(0.0), 1 => 0.0..=1.0f64], len),
        2 => (0..len).prop_map(move |i| {
            let mut row = vec![0.0; len];
            row[i] = 1.0;
            row
        }),
    ]
    .boxed()
}

/// Proptest strategy for [`Scenario`]: `1..=max_states` states (with weight 2/3 at most 3, where
/// extreme cases are found most often), `1..=max_actions` actions,
/// transition rows that are dense, sparse or deterministic, rewards in the given range (with
/// its end points and 0 drawn explicitly),
/// γ ∈ {0, 0.5, 0.9, 0.99} or uniform in `[0, 0.99]`, a dense or point-mass μ, `n_policies`
/// policies, and α ∈ {0, 1} or uniform in `[0, 1]`. Everything shrinks towards one state,
/// one action, γ = 0, zero rewards and point masses.
///
/// # Example
/// ```
/// use proptest::strategy::{Strategy, ValueTree};
/// use proptest::test_runner::TestRunner;
/// use sepg_verification::finite_mdp::{scenario, RewardRange};
/// let mut runner = TestRunner::deterministic();
/// let s = scenario(4, 3, RewardRange::Signed, 2).new_tree(&mut runner).unwrap().current();
/// assert_eq!(s.policies.len(), 2);
/// assert!(s.mdp.n_states() <= 4);
/// ```
pub fn scenario(
    max_states: usize,
    max_actions: usize,
    rewards: RewardRange,
    n_policies: usize,
) -> impl Strategy<Value = Scenario> {
    let gamma = prop_oneof![
        2 => prop::sample::select(vec![0.0, 0.5, 0.9, 0.99]),
        1 => 0.0..=0.99f64,
    ];
    let alpha = prop_oneof![1 => Just(0.0), 1 => Just(1.0), 4 => 0.0..=1.0f64];
    let max_states = max_states.max(1);
    let states = prop_oneof![2 => 1..=max_states.min(3), 1 => 1..=max_states];
    (states, 1..=max_actions.max(1), gamma, alpha)
        .prop_flat_map(move |(ns, na, gamma, alpha)| {
            let (lo, hi) = match rewards {
                RewardRange::Signed => (-1.0, 1.0),
                RewardRange::NonNegative => (0.0, 1.0),
                RewardRange::NonPositive => (-1.0, 0.0),
            };
            let reward = prop_oneof![
                1 => Just(0.0),
                1 => Just(lo),
                1 => Just(hi),
                3 => lo..=hi,
            ];
            let policy = prop::collection::vec(row_strategy(na), ns);
            (
                prop::collection::vec(row_strategy(ns), ns * na),
                prop::collection::vec(reward, ns * na),
                row_strategy(ns),
                prop::collection::vec(policy, n_policies),
                Just((ns, na, gamma, alpha)),
            )
        })
        .prop_map(|(rows, rewards, mu, policies, (ns, na, gamma, alpha))| {
            let transitions = rows.iter().flat_map(|r| normalise(r)).collect();
            let mdp = FiniteMdp {
                n_states: ns,
                n_actions: na,
                transitions,
                rewards,
                gamma,
                initial: normalise(&mu),
            };
            let policies = policies
                .iter()
                .map(|rows| TabularPolicy::from_weights(ns, na, &rows.concat()))
                .collect();
            Scenario {
                mdp,
                policies,
                alpha,
            }
        })
}
