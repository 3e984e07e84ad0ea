//! Where J and its gradients come from: Monte Carlo estimates or exact oracles. The iteration
//! logic is written once against the crate-internal `GradientSource` trait.
use crate::core::check::Checker;
use crate::core::error::RunError;
use crate::core::seed::Block;

/// A gradient with its per-component confidence half-widths ε_i (Assumption 4.6); all
/// widths are 0 for exact gradients.
#[derive(Debug, Clone, PartialEq)]
pub struct Grad {
    /// The (estimated) gradient components.
    pub value: Vec<f64>,
    /// Half-widths ε_i, same length as `value`.
    pub eps: Vec<f64>,
}

impl Grad {
    /// An exact gradient (ε = 0).
    pub fn exact(value: Vec<f64>) -> Self {
        let eps = vec![0.0; value.len()];
        Grad { value, eps }
    }
}

/// Which gradients a block needs besides J.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Need {
    /// ∇_v J.
    pub grad_v: bool,
    /// ∇_w J.
    pub grad_wj: bool,
    /// ∇_w L (surrogate of Corollary 4.4), with the plug-in ingredients of other w-directions
    /// ([`BlockEstimate::parts`]).
    pub grad_wl: bool,
    /// A one-sided upper confidence width of Ĵ ([`BlockEstimate::j_width`]).
    pub j_width: bool,
}

/// Full-batch estimates from which the plug-in w-directions are assembled: ∇_v J and
/// ∂_σ ∇_v J (component `j · dim_v + k` for action j and mean parameter k).
#[derive(Debug, Clone, PartialEq)]
pub struct SurrogateParts {
    /// ∇_v J.
    pub grad_v: Vec<f64>,
    /// ∂_{σ_j} ∇_v J.
    pub mixed_sigma: Vec<f64>,
}

/// One evaluation of a policy by a block.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Query<'a> {
    /// Iteration the block belongs to (seeds the trajectories).
    pub iteration: u64,
    /// Which block (seeds the trajectories).
    pub block: Block,
    /// Mean parameters.
    pub v: &'a [f64],
    /// Log standard deviations, `None` for the deterministic policy (w = −∞).
    pub w: Option<&'a [f64]>,
    /// Number of trajectories of the block (ignored by exact sources).
    pub n: usize,
    /// Gradients requested.
    pub need: Need,
}

/// What one block yields: J and the gradients it was asked for.
#[derive(Debug, Clone, PartialEq)]
pub struct BlockEstimate {
    /// J(θ) (Ĵ, the mean discounted return, when sampled).
    pub j: f64,
    /// ∇_v J if requested.
    pub grad_v: Option<Grad>,
    /// ∇_w J if requested.
    pub grad_wj: Option<Grad>,
    /// ∇_w L if requested.
    pub grad_wl: Option<Grad>,
    /// With ∇_w L: the ingredients of its plug-in form and of the metagradient.
    pub parts: Option<SurrogateParts>,
    /// If requested: ε_J ≥ 0 with J ≤ Ĵ + ε_J at confidence 1 − δ (one-sided Student-t times
    /// the confidence factor; 0 for exact values and without confidence widths).
    pub j_width: f64,
    /// Trajectories used.
    pub trajectories: u64,
    /// Environment steps used.
    pub steps: u64,
}

/// A provider of J and its gradients.
pub(crate) trait GradientSource: Send {
    /// Evaluates the policy of `q`.
    fn estimate(&mut self, q: &Query<'_>) -> Result<BlockEstimate, RunError>;

    /// The check of the declared constants against the source's data (`None` for exact
    /// sources, which see no data).
    fn checker(&mut self) -> Option<&mut Checker> {
        None
    }
}
