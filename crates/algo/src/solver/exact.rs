//! Exact J and gradients from an oracle of `sepg_mdp::oracle` (the setting of Sec 4.3).
use sepg_bounds::constants::TaskConstants;
use sepg_mdp::oracle::{ExactOracle, Exploration, Horizon, Needs};

use crate::core::error::RunError;
use crate::solver::source::{BlockEstimate, Grad, GradientSource, Query, SurrogateParts};
use crate::solver::steps;

/// A [`GradientSource`] backed by an exact oracle: no trajectories, ε = 0.
pub(crate) struct ExactSource {
    oracle: Box<dyn ExactOracle + Send>,
    horizon: Horizon,
    constants: TaskConstants,
}

impl ExactSource {
    pub(crate) fn new(
        oracle: Box<dyn ExactOracle + Send>,
        horizon: Horizon,
        constants: TaskConstants,
    ) -> Self {
        ExactSource {
            oracle,
            horizon,
            constants,
        }
    }
}

impl GradientSource for ExactSource {
    fn estimate(&mut self, q: &Query<'_>) -> Result<BlockEstimate, RunError> {
        let exploration = match q.w {
            Some(w) => Exploration::Gaussian { w: w.to_vec() },
            None => Exploration::Deterministic,
        };
        // Only what the block uses: the Hessian is never needed, and the target block needs J.
        let needs = Needs {
            grad_v: q.need.grad_v,
            grad_w: q.need.grad_wj || q.need.grad_wl,
            mixed: q.need.grad_wl,
            hessian: false,
        };
        let e = self
            .oracle
            .evaluate_with(q.v, &exploration, self.horizon, needs)
            .map_err(|err| RunError::Mdp(err.to_string()))?;
        let grad_wl = if q.need.grad_wl {
            Some(Grad::exact(steps::surrogate_grad_w(
                &self.constants,
                &e.grad_v,
                &e.mixed_wv,
                &e.sigma,
            )?))
        } else {
            None
        };
        let parts = q.need.grad_wl.then(|| SurrogateParts {
            grad_v: e.grad_v.clone(),
            mixed_sigma: e.mixed_sigma_v(),
        });
        Ok(BlockEstimate {
            j: e.j,
            grad_v: q.need.grad_v.then(|| Grad::exact(e.grad_v.clone())),
            grad_wj: q.need.grad_wj.then(|| Grad::exact(e.grad_w.clone())),
            grad_wl,
            parts,
            j_width: 0.0,
            trajectories: 0,
            steps: 0,
        })
    }
}
