//! The comparison algorithms of Chapter 5: G(PO)MDP with constant steps, with Adam, and the
//! adaptive step of Pirotta et al. (Corollary 3.11, Theorem 3.12). Each iteration runs a
//! single block of N trajectories at (vᵗ, wᵗ).
use crate::core::adam::AdamMoments;
use crate::core::config::Algorithm;
use crate::core::error::RunError;
use crate::core::record::Record;
use crate::core::seed::Block;
use crate::core::state::State;
use sepg_bounds::budget::Budget;
use sepg_bounds::constants::TaskConstants;

use crate::solver::source::{BlockEstimate, Grad, GradientSource, Need, Query};
use crate::solver::steps;

/// Runs iteration `state.iteration` of a comparison algorithm (`algorithm` must not be a
/// SEPG variant; those are handled by [`crate::solver::sepg`]).
pub(crate) fn iterate(
    source: &mut dyn GradientSource,
    k: &TaskConstants,
    algorithm: Algorithm,
    n: usize,
    state: &mut State,
) -> Result<Record, RunError> {
    let t = state.iteration;
    let e = batch(source, algorithm, n, state)?;
    let missing = || RunError::Estimator("the block returned no gradient".into());
    let gv = e.grad_v.as_ref().ok_or_else(missing)?;
    let mut v_new = state.v.clone();
    let mut w_new = state.w.clone();
    let mut adam = state.adam.clone();
    let (alpha, beta, guaranteed_v, below_noise_v) = step(
        algorithm,
        k,
        state,
        (gv, e.grad_wj.as_ref()),
        (&mut v_new, &mut w_new),
        &mut adam,
    )?;
    if v_new.iter().chain(w_new.iter()).any(|x| !x.is_finite()) {
        return Err(RunError::NonFinite {
            what: "policy parameters",
            iteration: t,
        });
    }
    let budget = logged_budget(state, e.j, t)?;
    let record = record(
        state,
        &e,
        budget,
        (alpha, beta),
        (guaranteed_v, below_noise_v),
    );
    state.iteration += 1;
    state.v = v_new;
    state.w = w_new;
    state.adam = adam;
    state.budget = budget;
    state.j0.get_or_insert(e.j);
    state.pending = Some(e.j);
    state.trajectories = record.trajectories;
    state.steps = record.steps;
    Ok(record)
}

/// The single batch of iteration `state.iteration` of `algorithm`: `n` trajectories at
/// (vᵗ, wᵗ) estimating J and ∇_v J, and ∇_w J unless the algorithm keeps σ fixed (a zero
/// w-step size).
fn batch(
    source: &mut dyn GradientSource,
    algorithm: Algorithm,
    n: usize,
    state: &State,
) -> Result<BlockEstimate, RunError> {
    let fixed_sigma = match algorithm {
        Algorithm::GpomdpConst { beta, .. } => beta == 0.0,
        Algorithm::GpomdpAdam { lr_w, .. } => lr_w == 0.0,
        _ => true,
    };
    source.estimate(&Query {
        iteration: state.iteration,
        block: Block::V,
        v: &state.v,
        w: Some(&state.w),
        n,
        need: Need {
            grad_v: true,
            grad_wj: !fixed_sigma,
            grad_wl: false,
            j_width: false,
        },
    })
}

/// The record of an iteration at the state before it, from its batch `e`, the logged
/// `budget`, the step sizes (α, β), and the adaptive step's guaranteed improvement and
/// whether it was below noise.
fn record(
    state: &State,
    e: &BlockEstimate,
    budget: f64,
    (alpha, beta): (f64, f64),
    (guaranteed_v, below_noise_v): (Option<f64>, bool),
) -> Record {
    Record {
        iteration: state.iteration,
        v: state.v.clone(),
        w: state.w.clone(),
        sigma: state.sigma(),
        j_exploratory: e.j,
        j_after_v: None,
        j_target: e.j,
        w_target: Some(state.w.clone()),
        budget,
        required_v: None,
        required_w: None,
        alpha,
        beta,
        lambda_v: None,
        lambda_w: None,
        guaranteed_v,
        guaranteed_w: None,
        infeasible_v: false,
        infeasible_w: false,
        below_noise_v,
        below_noise_w: false,
        trajectories: state.trajectories + e.trajectories,
        steps: state.steps + e.steps,
        certified_v: None,
        certified_w: None,
    }
}

/// The step of `algorithm` from the estimates `(∇̂_v J, ∇̂_w J)`, applied to `(v, w)`: returns
/// (α, β, the guaranteed improvement of the adaptive step, whether it was below noise).
fn step(
    algorithm: Algorithm,
    k: &TaskConstants,
    state: &State,
    (gv, gw): (&Grad, Option<&Grad>),
    (v_new, w_new): (&mut [f64], &mut [f64]),
    adam: &mut Option<(AdamMoments, AdamMoments)>,
) -> Result<(f64, f64, Option<f64>, bool), RunError> {
    Ok(match algorithm {
        Algorithm::GpomdpConst { alpha, beta } => {
            axpy(v_new, alpha, &gv.value);
            if let Some(gw) = gw {
                axpy(w_new, beta, &gw.value);
            }
            (alpha, beta, None, false)
        }
        Algorithm::GpomdpAdam {
            lr_v,
            lr_w,
            beta1,
            beta2,
            epsilon,
        } => {
            let (mv, mw) = adam.get_or_insert_with(|| {
                (
                    AdamMoments::zeros(state.v.len()),
                    AdamMoments::zeros(state.w.len()),
                )
            });
            let dv = mv.step(&gv.value, lr_v, beta1, beta2, epsilon);
            axpy(v_new, 1.0, &dv);
            if let Some(gw) = gw {
                let dw = mw.step(&gw.value, lr_w, beta1, beta2, epsilon);
                axpy(w_new, 1.0, &dw);
            }
            (lr_v, lr_w, None, false)
        }
        _ => {
            let sigma = state.w.iter().fold(f64::INFINITY, |m, &w| m.min(w.exp()));
            match steps::ada_step(k, sigma, gv)? {
                Some((alpha, guaranteed)) => {
                    axpy(v_new, alpha, &gv.value);
                    (alpha, 0.0, Some(guaranteed), false)
                }
                None => (0.0, 0.0, None, true),
            }
        }
    })
}

/// The budget B (Definition 4.3) of the comparison algorithms, logged and never used: B plus
/// the change of the estimated J since the last iteration.
fn logged_budget(state: &State, j: f64, t: u64) -> Result<f64, RunError> {
    Ok(match state.pending {
        Some(p) => Budget::new(state.budget, p, None)
            .and_then(|mut b| b.record_exploratory(j).map(|_| b.value()))
            .map_err(|_| RunError::NonFinite {
                what: "budget",
                iteration: t,
            })?,
        None => state.budget,
    })
}

fn axpy(x: &mut [f64], a: f64, y: &[f64]) {
    for (xi, yi) in x.iter_mut().zip(y) {
        *xi += a * yi;
    }
}
