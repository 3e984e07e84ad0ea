//! The per-iteration log line.
use serde::{Deserialize, Serialize};

/// What one iteration did, for logging and analysis (the CLI writes `log.csv` from it).
///
/// Parameters are those the iteration *started from* (θᵗ, at which `j_exploratory` was
/// measured); the parameters after the last iteration are in the
/// [`State`](crate::core::state::State). Values that do not apply to an algorithm are
/// `None` (for example λ and guaranteed improvements of the constant-step baseline).
/// In the sampled mode every `j_*` is the Monte Carlo estimate Ĵ (mean discounted return of
/// the block's trajectories); in the exact mode it is the oracle value.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Record {
    /// Iteration counter t (0-based).
    pub iteration: u64,
    /// Mean parameters vᵗ (flattened action-major, as in `sepg_mdp::Batch`).
    pub v: Vec<f64>,
    /// Log standard deviations wᵗ (one per action dimension).
    pub w: Vec<f64>,
    /// Standard deviations σᵗ = e^{wᵗ}.
    pub sigma: Vec<f64>,
    /// J(vᵗ, wᵗ) of the exploratory policy.
    pub j_exploratory: f64,
    /// J(vᵗ⁺¹, wᵗ) after the v-update (`None` if no w-block ran).
    pub j_after_v: Option<f64>,
    /// J(θ_Tᵗ) of the target policy (equal to `j_exploratory` when the target is the
    /// exploratory policy: MI, LB-I, LB-II and the comparison algorithms).
    pub j_target: f64,
    /// log-standard deviation of the target policy (`None` for the deterministic target of
    /// ZV and SIM-ν; equal to `w` when the target is the exploratory policy).
    pub w_target: Option<Vec<f64>>,
    /// Budget B after the iteration's (delayed) budget updates (Definition 4.3, Sec 4.4.4);
    /// for type-I requirements and the comparison algorithms it is tracked the same way,
    /// for information only.
    pub budget: f64,
    /// Required improvement C of the v-update ((1 − ν)Cᵗ for type-I, −B for type-II, −νB
    /// for SIM-ν).
    pub required_v: Option<f64>,
    /// Required improvement of the w-update (νCᵗ for type-I, −B for type-II, −(1 − ν)B for
    /// SIM-ν).
    pub required_w: Option<f64>,
    /// Step size α used for the v-update (0 if the block did not update).
    pub alpha: f64,
    /// Step size β used for the w-update (0 if the block did not update).
    pub beta: f64,
    /// λ_v of eq. (4.10)/(4.26) (0 for the λ = 0 fallback of an infeasible requirement).
    pub lambda_v: Option<f64>,
    /// λ_w of eq. (4.17)/(4.19)/(4.30).
    pub lambda_w: Option<f64>,
    /// Lower bound on J(vᵗ⁺¹, wᵗ) − J(vᵗ, wᵗ) guaranteed by the chosen α (Theorem 4.2/4.7).
    pub guaranteed_v: Option<f64>,
    /// Lower bound on J(vᵗ⁺¹, wᵗ⁺¹) − J(vᵗ⁺¹, wᵗ) guaranteed by the chosen β
    /// (Theorem 4.3/4.5/4.8/4.9).
    pub guaranteed_w: Option<f64>,
    /// The v requirement exceeded C_max^v: the λ = 0 step was taken instead.
    pub infeasible_v: bool,
    /// The w requirement exceeded C_max^w: the λ = 0 step was taken instead.
    pub infeasible_w: bool,
    /// ‖∇̂_v J‖∞ ≤ ε (eq. 4.23): v was not updated.
    pub below_noise_v: bool,
    /// The w-update direction was at or below its noise level (eq. 4.23): w was not updated.
    pub below_noise_w: bool,
    /// Trajectories used since the start of the run, this iteration included.
    pub trajectories: u64,
    /// Environment steps used since the start of the run, this iteration included. Blocks
    /// that estimate gradients count the true trajectory lengths; a returns-only evaluation
    /// (the target block of LV, ZV and SIM-ν) counts `n · min(H, time limit)` because
    /// `sepg_mdp::rollout::rollout_returns_into` does not report lengths, which over-counts
    /// the trajectories that terminate early (Mountain Car).
    pub steps: u64,
    /// Whether the v-step's bound was certified in interval arithmetic to meet its
    /// requirement (`sepg_certified`): `Some(true)` certified, `Some(false)` the
    /// requirement was infeasible or within rounding of C_max (no `f64` step certifies it;
    /// `infeasible_v` is then set and the vertex taken), `None` when certification is off, no
    /// step was taken, or the algorithm has no safe step.
    #[serde(default)]
    pub certified_v: Option<bool>,
    /// The same for the w-step.
    #[serde(default)]
    pub certified_w: Option<bool>,
}
