//! Step selection of every update block, delegating each closed form to `sepg_bounds`.
//!
//! Exact gradients use Theorems 4.2, 4.3 and 4.5 directly; estimated gradients use their
//! high-probability versions (Theorems 4.7–4.9) in the sign-aware form, which keeps the
//! guarantee for steps against the estimated direction (`HpForm::SignAware`, docs/THEOREMS.md).
//! With certification on (the default), every step comes from `sepg_certified`: its
//! bound, evaluated in interval arithmetic, meets the requirement.
use sepg_bounds::constants::{TaskConstants, c};
use sepg_bounds::exploring::{ExploringBound, w_exploring_step};
use sepg_bounds::greedy::argmax_abs;
use sepg_bounds::high_probability::{self as hp, HighProbabilityBound, HpForm};
use sepg_bounds::outcome::StepOutcome;
use sepg_bounds::{BoundsError, pirotta, surrogate, v_update, w_update};
use sepg_certified::{self as certified, Certified};

use crate::core::error::RunError;
use crate::core::options::{WDirection, WStep};
use crate::solver::source::{Grad, SurrogateParts};

const FORM: HpForm = HpForm::SignAware;

fn be(e: BoundsError) -> RunError {
    RunError::Bounds(e.to_string())
}

/// Whether a gradient is exact (every ε_i = 0).
fn is_exact(g: &Grad) -> bool {
    g.eps.iter().all(|&e| e == 0.0)
}

/// ε = max_i ε_i (Sec 4.5).
fn eps_max(g: &Grad) -> f64 {
    g.eps.iter().fold(0.0, |m: f64, &e| m.max(e))
}

/// A chosen greedy-coordinate step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    /// Coordinate that moves.
    pub index: usize,
    /// Step size (α or β).
    pub size: f64,
    /// Increment added to the coordinate (size × direction component).
    pub delta: f64,
    /// λ of the safe interval (0 for the λ = 0 fallback; `None` when undefined).
    pub lambda: Option<f64>,
    /// The guaranteed improvement of the chosen step.
    pub guaranteed: f64,
    /// The requirement was infeasible: the step of maximal guaranteed improvement was taken.
    pub infeasible: bool,
    /// Whether the step's bound was certified in interval arithmetic to meet the requirement
    /// (`None` when certification is off).
    pub certified: Option<bool>,
}

/// What an update block does.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Plan {
    /// Zero or sub-noise direction (eq. 4.23): no update.
    BelowNoise,
    /// Update one coordinate.
    Update(Step),
}

/// Turns a [`StepOutcome`] into a plan for coordinate `index` of direction `dir`, with
/// `bound` evaluating the guaranteed improvement of a step size.
fn plan_from(
    outcome: StepOutcome,
    index: usize,
    dir: f64,
    bound: impl Fn(f64) -> Result<f64, BoundsError>,
) -> Result<Plan, RunError> {
    let (size, lambda, infeasible) = match outcome {
        StepOutcome::Feasible(s) => (s.largest(), s.lambda, false),
        StepOutcome::Infeasible { vertex, .. } => (vertex, Some(0.0), true),
        StepOutcome::ZeroGradient { .. } | StepOutcome::BelowNoise => return Ok(Plan::BelowNoise),
    };
    Ok(Plan::Update(Step {
        index,
        size,
        delta: size * dir,
        lambda,
        guaranteed: bound(size).map_err(be)?,
        infeasible,
        certified: None,
    }))
}

/// Turns a [`Certified`] outcome into a plan for coordinate `index` of direction `dir`; the
/// guaranteed improvement is the lower end of the bound's enclosure. A requirement that no
/// `f64` step can certify is handled like an infeasible one (vertex, flagged).
fn plan_certified(outcome: Certified, index: usize, dir: f64) -> Plan {
    let (size, lambda, bound, infeasible, certified) = match outcome {
        Certified::Step(s) => (s.step, s.interval.lambda, s.bound, false, true),
        Certified::Infeasible { step, bound } | Certified::Uncertifiable { step, bound } => {
            (step, Some(0.0), bound, true, false)
        }
        _ => return Plan::BelowNoise,
    };
    Plan::Update(Step {
        index,
        size,
        delta: size * dir,
        lambda,
        guaranteed: bound.lo(),
        infeasible,
        certified: Some(certified),
    })
}

/// The greedy-coordinate v-update with the largest safe ᾱ for `required` (Theorem 4.2,
/// eq. 4.10; Theorem 4.7, eq. 4.26 when estimated).
pub fn v_step(
    k: &TaskConstants,
    sigma: f64,
    g: &Grad,
    required: f64,
    certify: bool,
) -> Result<Plan, RunError> {
    let index = argmax_abs(&g.value).map_err(be)?;
    let dir = g.value[index];
    if certify {
        let outcome = if is_exact(g) {
            certified::v_safe_step(k, sigma, &g.value, required)
        } else {
            certified::hp_v_safe_step(k, sigma, &g.value, eps_max(g), required, FORM)
        };
        return Ok(plan_certified(outcome.map_err(be)?, index, dir));
    }
    if is_exact(g) {
        let outcome = v_update::safe_step(k, sigma, &g.value, required).map_err(be)?;
        plan_from(outcome, index, dir, |a| {
            v_update::bound(k, sigma, &g.value, a)
        })
    } else {
        let eps = eps_max(g);
        let Some(b) = HighProbabilityBound::v_update(k, sigma, &g.value, eps).map_err(be)? else {
            return Ok(Plan::BelowNoise);
        };
        let outcome = hp::v_safe_step(k, sigma, &g.value, eps, required, FORM).map_err(be)?;
        plan_from(outcome, index, dir, |a| b.sign_aware_value(a))
    }
}

/// The greedy-coordinate w-update along ∇_w L with the largest safe β̄ (Theorem 4.5,
/// eq. 4.19, for exact gradients), coordinate h = argmax |∇_{w_j} L| with d at σ_h. Estimated
/// gradients use the exploring w-update (`sepg_bounds::exploring`, the confidence of ∇̂_w J
/// only) or Theorem 4.9 (eq. 4.30), as `form` says.
pub fn w_step_surrogate(
    k: &TaskConstants,
    sigmas: &[f64],
    gl: &Grad,
    gj: &Grad,
    required: f64,
    certify: bool,
    form: WStep,
) -> Result<Plan, RunError> {
    let h = argmax_abs(&gl.value).map_err(be)?;
    let (s, l, j) = (sigmas[h], gl.value[h], gj.value[h]);
    let exact = is_exact(gl) && is_exact(gj);
    if form == WStep::Exploring && !exact && certify {
        let outcome = certified::exploring_safe_step(k, s, j, gj.eps[h], l, required);
        return Ok(plan_certified(outcome.map_err(be)?, h, l));
    }
    if form == WStep::Exploring && !exact {
        let ej = gj.eps[h];
        let bound = ExploringBound::new(k, s, j, ej).map_err(be)?;
        let outcome = w_exploring_step(k, s, j, ej, l, required).map_err(be)?;
        return plan_from(outcome, h, l, |b| bound.value(b * l));
    }
    if certify {
        if exact && l == 0.0 {
            return Ok(Plan::BelowNoise);
        }
        let (ej, el) = (gj.eps[h], gl.eps[h]);
        let outcome = if exact {
            certified::w_safe_step_along_l(k, s, j, l, required)
        } else {
            certified::hp_w_safe_step_along_l(k, s, (j, ej), (l, el), required, FORM)
        };
        return Ok(plan_certified(outcome.map_err(be)?, h, l));
    }
    if exact {
        if l == 0.0 {
            return Ok(Plan::BelowNoise);
        }
        let outcome = w_update::safe_step_along_l(k, s, j, l, required).map_err(be)?;
        plan_from(outcome, h, l, |b| w_update::bound_along_l(k, s, j, l, b))
    } else {
        let (ej, el) = (gj.eps[h], gl.eps[h]);
        let Some(b) = HighProbabilityBound::w_along_l(k, s, j, ej, l, el).map_err(be)? else {
            return Ok(Plan::BelowNoise);
        };
        let outcome = hp::w_safe_step_along_l(k, s, j, ej, l, el, required, FORM).map_err(be)?;
        plan_from(outcome, h, l, |x| b.sign_aware_value(x))
    }
}

/// The direction of the w-update (`WDirection`): the cross-fitted ∇̂_w L itself, the
/// plug-in ∇̂_w L assembled from full-batch means, or the thesis-era metagradient with the
/// step size `alpha` of the latest v-update (scalar action).
///
/// # Formula
/// ```text
/// plug-in:      ∇_{w_j} L from ∇̂_v J and ∂̂_{w_j}∇_v J = σ_j ∂̂_{σ_j}∇_v J   (surrogate_grad_w)
/// metagradient: ∇̂_w J + 2α‖∇̂_v J‖² + clip(2σα⟨∇̂_v J, ∂̂_σ∇_v J⟩, −clip, clip)
/// ```
///
/// The plug-in direction keeps the widths of the cross-fitted estimate; the metagradient has
/// width 0 (its scale is that of J, not of L). Only the exploring step and Theorem 4.9 read
/// these widths, and the exploring step ignores them.
pub fn w_direction(
    k: &TaskConstants,
    sigmas: &[f64],
    direction: WDirection,
    cross_fitted: &Grad,
    parts: Option<&SurrogateParts>,
    gj: &Grad,
    alpha: f64,
) -> Result<Grad, RunError> {
    let parts = || {
        parts.ok_or_else(|| RunError::Estimator("the w-block returned no surrogate parts".into()))
    };
    match direction {
        WDirection::CrossFitted => Ok(cross_fitted.clone()),
        WDirection::PlugIn => {
            let p = parts()?;
            let m = p.grad_v.len();
            let mixed_wv: Vec<f64> = p
                .mixed_sigma
                .iter()
                .enumerate()
                .map(|(i, x)| x * sigmas[i / m.max(1)])
                .collect();
            Ok(Grad {
                value: surrogate_grad_w(k, &p.grad_v, &mixed_wv, sigmas)?,
                eps: cross_fitted.eps.clone(),
            })
        }
        WDirection::Metagradient { clip } => {
            let p = parts()?;
            let norm2: f64 = p.grad_v.iter().map(|g| g * g).sum();
            let inner: f64 = p
                .grad_v
                .iter()
                .zip(&p.mixed_sigma)
                .map(|(g, x)| g * x)
                .sum();
            let value = gj.value[0]
                + 2.0 * alpha * norm2
                + (2.0 * sigmas[0] * alpha * inner).clamp(-clip, clip);
            if !value.is_finite() {
                return Err(RunError::Estimator("the metagradient is not finite".into()));
            }
            Ok(Grad::exact(vec![value]))
        }
    }
}

/// The naive greedy-coordinate w-update along ∇_w J, eq. (4.12), with the largest safe
/// β̄ = (1 + λ_w)β* (Theorem 4.3, eq. 4.17; Theorem 4.8, eq. 4.29 when estimated).
pub fn w_step_naive(
    k: &TaskConstants,
    sigmas: &[f64],
    gj: &Grad,
    required: f64,
    certify: bool,
) -> Result<Plan, RunError> {
    let h = argmax_abs(&gj.value).map_err(be)?;
    let (s, j) = (sigmas[h], gj.value[h]);
    if certify {
        let outcome = if is_exact(gj) {
            certified::w_safe_step_along_j(k, s, j, required)
        } else {
            certified::hp_w_safe_step_along_j(k, s, j, gj.eps[h], required, FORM)
        };
        return Ok(plan_certified(outcome.map_err(be)?, h, j));
    }
    if is_exact(gj) {
        let outcome = w_update::safe_step_along_j(k, s, j, required).map_err(be)?;
        plan_from(outcome, h, j, |b| w_update::bound_along_j(k, s, j, b))
    } else {
        let e = gj.eps[h];
        let Some(b) = HighProbabilityBound::w_along_j(k, s, j, e).map_err(be)? else {
            return Ok(Plan::BelowNoise);
        };
        let outcome = hp::w_safe_step_along_j(k, s, j, e, required, FORM).map_err(be)?;
        plan_from(outcome, h, j, |x| b.sign_aware_value(x))
    }
}

/// The LV target (Sec 4.4.3): the lowest w_h reachable along ∇_w J within the safe steps of
/// (4.17) (or (4.29)) for `required` = −B, h = argmax |∇_{w_j} J|. Returns the coordinate
/// and the (non-positive) change of w_h, or `None` when no reduction is guaranteed.
///
/// # Formula
/// ```text
/// Δw_h = min(0, min_{β ∈ [lo, hi]} β ∇_{w_h} J) = min(0, lo·∇_{w_h} J, hi·∇_{w_h} J)
/// ```
pub fn lv_target(
    k: &TaskConstants,
    sigmas: &[f64],
    gj: &Grad,
    required: f64,
    certify: bool,
) -> Result<Option<(usize, f64)>, RunError> {
    let h = argmax_abs(&gj.value).map_err(be)?;
    let (s, j) = (sigmas[h], gj.value[h]);
    let outcome = if is_exact(gj) {
        w_update::safe_step_along_j(k, s, j, required)
    } else {
        hp::w_safe_step_along_j(k, s, j, gj.eps[h], required, FORM)
    }
    .map_err(be)?;
    let StepOutcome::Feasible(iv) = outcome else {
        return Ok(None);
    };
    let end = if iv.lo * j <= iv.hi * j { iv.lo } else { iv.hi };
    let end = if certify {
        // move the chosen end toward the vertex until its bound is certified
        let certified = if is_exact(gj) {
            let q = certified::Quadratic::w_along_j(k, s, j).map_err(be)?;
            certified::certify_toward(&q, end, iv.vertex, required)
        } else {
            let Some(b) =
                certified::HpEnclosure::w_along_j(k, s, j, gj.eps[h], FORM).map_err(be)?
            else {
                return Ok(None);
            };
            certified::certify_toward(&b, end, iv.vertex, required)
        };
        match certified {
            Ok((step, _, _)) => step,
            Err(_) => return Ok(None),
        }
    } else {
        end
    };
    let dw = end * j;
    Ok((dw < 0.0).then_some((h, dw)))
}

/// ∇_w L of Corollary 4.4 for each action dimension j, from ∇_v J and the mixed derivatives
/// ∂²J/∂w_j∂v (layout `mixed_wv[j * m + k]`), with L = ‖∇_v J‖₂²/(4 m c(σ_min)) defined with
/// the c of the v-update (σ_min = min_j σ_j, lowest index on ties).
///
/// # Formula
/// ```text
/// j = argmin σ:  ∇_{w_j} L = σ_j ∂_σ L(σ_j)       (sepg_bounds::surrogate::grad_w, eq. B.1)
/// otherwise:     ∇_{w_j} L = 2⟨∇_v J, ∂_{w_j}∇_v J⟩ / (4 m c(σ_min))   (c does not move)
/// ```
pub fn surrogate_grad_w(
    k: &TaskConstants,
    grad_v: &[f64],
    mixed_wv: &[f64],
    sigmas: &[f64],
) -> Result<Vec<f64>, RunError> {
    let m = grad_v.len();
    let (jmin, smin) = sigmas
        .iter()
        .copied()
        .enumerate()
        .fold(
            (0, f64::INFINITY),
            |b, (j, s)| if s < b.1 { (j, s) } else { b },
        );
    let cc = c(k, smin).map_err(be)?;
    sigmas
        .iter()
        .enumerate()
        .map(|(j, &s)| {
            let row = mixed_wv
                .get(j * m..(j + 1) * m)
                .ok_or_else(|| RunError::Mdp("mixed derivative has the wrong length".into()))?;
            if j == jmin {
                // ∂_σ ∇_v J = (∂_w ∇_v J)/σ.
                let mixed_sigma: Vec<f64> = row.iter().map(|x| x / s).collect();
                surrogate::grad_w(k, s, grad_v, &mixed_sigma).map_err(be)
            } else {
                let inner: f64 = grad_v.iter().zip(row).map(|(g, x)| g * x).sum();
                Ok(2.0 * inner / (4.0 * m as f64 * cc))
            }
        })
        .collect()
}

/// The adaptive step of Pirotta et al. with fixed σ: α* of Corollary 3.11 (exact) or
/// Theorem 3.12 (estimated), and its guaranteed improvement; `None` for a zero or sub-noise
/// gradient.
pub fn ada_step(k: &TaskConstants, sigma: f64, g: &Grad) -> Result<Option<(f64, f64)>, RunError> {
    let step = if is_exact(g) {
        pirotta::optimal_step(k, sigma, &g.value)
    } else {
        pirotta::hp_optimal_step(k, sigma, &g.value, &g.eps)
    }
    .map_err(be)?;
    Ok(match step {
        pirotta::AdaptiveStep::Step { alpha, guarantee } => Some((alpha, guarantee)),
        _ => None,
    })
}
