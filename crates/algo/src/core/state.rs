//! The mutable, serialisable state of a run: everything needed to resume it bit for bit.
use serde::{Deserialize, Serialize};

use crate::core::adam::AdamMoments;
use crate::core::check::ConstantsCheck;

/// State of a run between iterations; serialised, it is the checkpoint.
///
/// Resuming a run from a `State` with the same checked configuration yields exactly the
/// records the uninterrupted run would have produced, because every batch seed is derived
/// from `(seed, iteration, block)` (see [`Block::key`](crate::core::seed::Block::key)).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct State {
    /// Index of the next iteration to run.
    pub iteration: u64,
    /// Current mean parameters vᵗ.
    pub v: Vec<f64>,
    /// Current log standard deviations wᵗ.
    pub w: Vec<f64>,
    /// Current budget B (Definition 4.3), starting at B⁰.
    pub budget: f64,
    /// J(θ⁰), measured by the first iteration (the LB-I baseline of Table 4.1).
    pub j0: Option<f64>,
    /// A J value whose successor is still to be measured: the delayed budget update
    /// B ← B + J(next) − `pending` is applied right after the next J of the exploratory
    /// policy is estimated (Sec 4.4.4).
    pub pending: Option<f64>,
    /// J(θ_Tᵗ⁻¹) of the previous target evaluation (for the target budget update, line 12).
    pub target_prev: Option<f64>,
    /// Adam moments of v and w (only for the Adam baseline).
    pub adam: Option<(AdamMoments, AdamMoments)>,
    /// Trajectories used so far.
    pub trajectories: u64,
    /// Environment steps used so far.
    pub steps: u64,
    /// Step size α of the latest v-update (the metagradient w-direction uses it).
    #[serde(default)]
    pub last_alpha: Option<f64>,
    /// Adam moments of v for SEPG's Adam v-direction (`VDirection::Adam`), from the first
    /// v-update on.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub adam_v: Option<AdamMoments>,
    /// The declared constants checked against the data seen so far (omitted while nothing
    /// was checked, e.g. with exact gradients).
    #[serde(default, skip_serializing_if = "ConstantsCheck::is_empty")]
    pub constants_check: ConstantsCheck,
    /// Trajectories per block of the next iteration, chosen by the adaptive batch rule
    /// ([`BatchRule::Adaptive`](crate::core::options::BatchRule)) from the data of the
    /// iterations so far; `None` before the first iteration and under the fixed rule.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub next_batch: Option<usize>,
}

impl State {
    /// The state before the first iteration: θ⁰ = (v⁰, w⁰), B = B⁰, nothing measured yet.
    ///
    /// # Examples
    /// ```
    /// use sepg_algo::core::state::State;
    /// let s = State::new(vec![-0.1], vec![0.0], 1.0);
    /// assert_eq!(s.iteration, 0);
    /// assert_eq!(s.budget, 1.0);
    /// assert!(s.j0.is_none());
    /// ```
    pub fn new(v0: Vec<f64>, w0: Vec<f64>, budget0: f64) -> Self {
        State {
            iteration: 0,
            v: v0,
            w: w0,
            budget: budget0,
            j0: None,
            pending: None,
            target_prev: None,
            adam: None,
            trajectories: 0,
            steps: 0,
            last_alpha: None,
            adam_v: None,
            constants_check: ConstantsCheck::default(),
            next_batch: None,
        }
    }

    /// Standard deviations σ = e^w of the exploratory policy.
    ///
    /// # Examples
    /// ```
    /// use sepg_algo::core::state::State;
    /// let s = State::new(vec![0.0], vec![0.0], 0.0);
    /// assert_eq!(s.sigma(), vec![1.0]);
    /// ```
    pub fn sigma(&self) -> Vec<f64> {
        self.w.iter().map(|w| w.exp()).collect()
    }
}
