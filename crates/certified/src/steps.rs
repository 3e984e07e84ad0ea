//! The certified step of each bound form: the `f64` step of `sepg-bounds`, certified by the
//! a-priori error bound when it applies and by interval arithmetic otherwise (crate docs).

use sepg_bounds::TaskConstants;
use sepg_bounds::error::{BoundsError, finite, finite_vector, inf_norm};
use sepg_bounds::exploring::ExploringBound;
use sepg_bounds::high_probability::{self as hp, HpForm};
use sepg_bounds::outcome::{SafeInterval, StepOutcome};
use sepg_bounds::penalties::Penalties;
use sepg_bounds::{pirotta, rigorous, v_update, w_update};

use sepg_bounds::direction::{Direction, DirectionBound};

use crate::certificate::{
    Certified, CertifiedStep, certify_fast_then_interval, certify_step, certify_toward,
};
use crate::enclosure::{
    EnclosedBound, ExploringEnclosure, HpEnclosure, Quadratic, RigorousEnclosure, c,
};
use crate::interval::Interval;
use crate::rounding::{self, Rounded, RoundedBound};
use crate::task::AsCertifiedTask;

/// The common tail of the certified high-probability steps: the fast path on the
/// feasible interval of `bound`, else the full path on its outcome
/// ([`hp::HighProbabilityBound::safe_step`], or below noise when there is no bound).
#[inline(always)]
fn certify_high_probability<S: EnclosedBound>(
    bound: Option<hp::HighProbabilityBound>,
    required: f64,
    form: HpForm,
    fast: impl FnOnce() -> Option<RoundedBound> + Copy,
    interval: impl FnOnce() -> Result<Option<S>, BoundsError>,
) -> Result<Certified, BoundsError> {
    certify_step(
        bound.and_then(|b| b.feasible_step(required, form)),
        required,
        move || match bound {
            Some(b) => b.safe_step(required, form),
            None => Ok(StepOutcome::BelowNoise),
        },
        fast,
        interval,
    )
}

/// The parabola a·x − b·x² with a = g², b = k·g² (Theorems 4.2, 4.3) in rounded `f64`.
#[inline(always)]
fn squared_parabola(g: f64, k: Option<Rounded>) -> Option<RoundedBound> {
    let g = Rounded::exact(g);
    let a = g.mul(g)?;
    Some(RoundedBound::parabola(a, k?.mul(a)?))
}

/// The high-probability bound with s = +1, a^∓ = (n ∓ ε)², b = k·a⁺ (Theorems 4.7, 4.8) in
/// rounded `f64`; only called when n > ε.
#[inline(always)]
fn corrected_parabola(n: f64, eps: f64, k: Option<Rounded>, form: HpForm) -> Option<RoundedBound> {
    let (lower, upper) = (Rounded::difference(n, eps), Rounded::sum(n, eps));
    let upper2 = upper.mul(upper)?;
    Some(RoundedBound::high_probability(
        1.0,
        lower.mul(lower)?,
        upper2,
        k?.mul(upper2)?,
        form,
    ))
}

/// Certified safe v-step of Theorem 4.2 (eq. (4.10)) for the requirement C.
///
/// # Formula
///
/// ```text
/// B(α) = α ‖∇_v J‖∞² − α² c(σ) ‖∇_v J‖∞²,   certified: enclosure of B(α) ≥ C
/// ```
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, v_update};
/// use sepg_certified::{self as certified, Certified};
/// let k = TaskConstants::new(0.99, 4.0, 2.0, 4.0)?;
/// let cmax = v_update::c_max(&k, 1.0, &[0.8])?;
/// assert!(certified::v_safe_step(&k, 1.0, &[0.8], 0.5 * cmax)?.is_certified());
/// // C = C_max exactly cannot be certified in floating point
/// let o = certified::v_safe_step(&k, 1.0, &[0.8], cmax)?;
/// assert!(matches!(o, Certified::Uncertifiable { .. }));
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn v_safe_step(
    task: impl AsCertifiedTask,
    sigma: f64,
    grad_v: &[f64],
    required: f64,
) -> Result<Certified, BoundsError> {
    v_safe_step_in(
        task.constants(),
        task.in_rounding_range(),
        sigma,
        grad_v,
        required,
    )
}

/// [`v_safe_step`] for the task constants `k` whose rounding range is `in_range`, compiled
/// once in this crate (the generic function above only chooses how the range is decided).
fn v_safe_step_in(
    k: &TaskConstants,
    in_range: bool,
    sigma: f64,
    grad_v: &[f64],
    required: f64,
) -> Result<Certified, BoundsError> {
    finite_vector("grad_v", grad_v)?;
    finite("required", required)?;
    let cc = Penalties::new(k, sigma)?.c()?;
    let n = inf_norm(grad_v);
    let fast = move || squared_parabola(n, rounding::c(in_range, sigma, cc));
    let parabola = v_update::parabola(cc, n);
    certify_step(
        parabola.ok().and_then(|p| p.feasible(required)),
        required,
        move || parabola?.solve(required),
        fast,
        move || Quadratic::v_update(k, sigma, grad_v).map(Some),
    )
}

/// Certified safe steps along ∇_w J, Theorem 4.3 (eq. (4.17)).
///
/// ```
/// use sepg_bounds::{constants::TaskConstants};
/// use sepg_certified as certified;
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// assert!(certified::w_safe_step_along_j(&k, 1.0, 0.3, 0.0)?.is_certified());
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn w_safe_step_along_j(
    task: impl AsCertifiedTask,
    sigma: f64,
    grad_w_j: f64,
    required: f64,
) -> Result<Certified, BoundsError> {
    w_safe_step_along_j_in(
        task.constants(),
        task.in_rounding_range(),
        sigma,
        grad_w_j,
        required,
    )
}

/// [`w_safe_step_along_j`] for the task constants `k` whose rounding range is `in_range`, compiled
/// once in this crate (the generic function above only chooses how the range is decided).
fn w_safe_step_along_j_in(
    k: &TaskConstants,
    in_range: bool,
    sigma: f64,
    grad_w_j: f64,
    required: f64,
) -> Result<Certified, BoundsError> {
    finite("grad_w_j", grad_w_j)?;
    finite("required", required)?;
    let dd = Penalties::new(k, sigma)?.d()?;
    let fast = move || squared_parabola(grad_w_j, rounding::d(in_range, sigma, dd));
    let parabola = w_update::parabola_along_j(dd, grad_w_j);
    certify_step(
        parabola.ok().and_then(|p| p.feasible(required)),
        required,
        move || parabola?.solve(required),
        fast,
        move || Quadratic::w_along_j(k, sigma, grad_w_j).map(Some),
    )
}

/// Certified safe steps along ∇_w L, Theorem 4.5 (eq. (4.19)).
///
/// ```
/// use sepg_bounds::{constants::TaskConstants};
/// use sepg_certified as certified;
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let o = certified::w_safe_step_along_l(&k, 1.0, 0.3, -2.0, -0.1)?;
/// assert!(o.is_certified() && o.bound().unwrap().lo() >= -0.1);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn w_safe_step_along_l(
    task: impl AsCertifiedTask,
    sigma: f64,
    grad_w_j: f64,
    grad_w_l: f64,
    required: f64,
) -> Result<Certified, BoundsError> {
    w_safe_step_along_l_in(
        task.constants(),
        task.in_rounding_range(),
        sigma,
        grad_w_j,
        grad_w_l,
        required,
    )
}

/// [`w_safe_step_along_l`] for the task constants `k` whose rounding range is `in_range`, compiled
/// once in this crate (the generic function above only chooses how the range is decided).
fn w_safe_step_along_l_in(
    k: &TaskConstants,
    in_range: bool,
    sigma: f64,
    grad_w_j: f64,
    grad_w_l: f64,
    required: f64,
) -> Result<Certified, BoundsError> {
    finite("grad_w_j", grad_w_j)?;
    finite("grad_w_l", grad_w_l)?;
    finite("required", required)?;
    let dd = Penalties::new(k, sigma)?.d()?;
    let fast = move || {
        let (j, l) = (Rounded::exact(grad_w_j), Rounded::exact(grad_w_l));
        let b = rounding::d(in_range, sigma, dd)?.mul(l.mul(l)?)?;
        Some(RoundedBound::parabola(l.mul(j)?, b))
    };
    let parabola = w_update::parabola_along_l(dd, grad_w_j, grad_w_l);
    certify_step(
        parabola.ok().and_then(|p| p.feasible(required)),
        required,
        move || parabola?.solve(required),
        fast,
        move || Quadratic::w_along_l(k, sigma, grad_w_j, grad_w_l).map(Some),
    )
}

/// Certified high-probability v-step, Theorem 4.7 (eq. (4.26)), in the form `form`.
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, high_probability::HpForm};
/// use sepg_certified as certified;
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// assert!(certified::hp_v_safe_step(&k, 1.0, &[0.5], 0.1, 0.0, HpForm::SignAware)?.is_certified());
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn hp_v_safe_step(
    task: impl AsCertifiedTask,
    sigma: f64,
    grad_v_hat: &[f64],
    eps: f64,
    required: f64,
    form: HpForm,
) -> Result<Certified, BoundsError> {
    hp_v_safe_step_in(
        task.constants(),
        task.in_rounding_range(),
        sigma,
        grad_v_hat,
        eps,
        required,
        form,
    )
}

/// [`hp_v_safe_step`] for the task constants `k` whose rounding range is `in_range`, compiled
/// once in this crate (the generic function above only chooses how the range is decided).
fn hp_v_safe_step_in(
    k: &TaskConstants,
    in_range: bool,
    sigma: f64,
    grad_v_hat: &[f64],
    eps: f64,
    required: f64,
    form: HpForm,
) -> Result<Certified, BoundsError> {
    finite("required", required)?;
    let penalties = Penalties::new(k, sigma)?;
    let cc = penalties.c()?;
    let bound = hp::HighProbabilityBound::v_update_at(&penalties, grad_v_hat, eps)?;
    let fast = move || {
        corrected_parabola(
            inf_norm(grad_v_hat),
            eps,
            rounding::c(in_range, sigma, cc),
            form,
        )
    };
    certify_high_probability(bound, required, form, fast, move || {
        HpEnclosure::v_update(k, sigma, grad_v_hat, eps, form)
    })
}

/// Certified high-probability step along ∇̂_w J, Theorem 4.8 (eq. (4.29)).
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, high_probability::HpForm};
/// use sepg_certified as certified;
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let o = certified::hp_w_safe_step_along_j(&k, 1.0, 0.5, 0.1, -0.01, HpForm::SignAware)?;
/// assert!(o.is_certified());
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn hp_w_safe_step_along_j(
    task: impl AsCertifiedTask,
    sigma: f64,
    grad_w_j_hat: f64,
    eps: f64,
    required: f64,
    form: HpForm,
) -> Result<Certified, BoundsError> {
    hp_w_safe_step_along_j_in(
        task.constants(),
        task.in_rounding_range(),
        sigma,
        grad_w_j_hat,
        eps,
        required,
        form,
    )
}

/// [`hp_w_safe_step_along_j`] for the task constants `k` whose rounding range is `in_range`, compiled
/// once in this crate (the generic function above only chooses how the range is decided).
fn hp_w_safe_step_along_j_in(
    k: &TaskConstants,
    in_range: bool,
    sigma: f64,
    grad_w_j_hat: f64,
    eps: f64,
    required: f64,
    form: HpForm,
) -> Result<Certified, BoundsError> {
    finite("required", required)?;
    let penalties = Penalties::new(k, sigma)?;
    let dd = penalties.d()?;
    let bound = hp::HighProbabilityBound::w_along_j_at(&penalties, grad_w_j_hat, eps)?;
    let fast = move || {
        corrected_parabola(
            grad_w_j_hat.abs(),
            eps,
            rounding::d(in_range, sigma, dd),
            form,
        )
    };
    certify_high_probability(bound, required, form, fast, move || {
        HpEnclosure::w_along_j(k, sigma, grad_w_j_hat, eps, form)
    })
}

/// Certified high-probability step along ∇̂_w L, Theorem 4.9 (eq. (4.30)); the estimates
/// come as (value, width) pairs.
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, high_probability::HpForm};
/// use sepg_certified as certified;
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let o = certified::hp_w_safe_step_along_l(&k, 1.0, (0.5, 0.1), (-2.0, 0.5), -0.01, HpForm::SignAware)?;
/// assert!(o.chosen_step().unwrap() > 0.0);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn hp_w_safe_step_along_l(
    task: impl AsCertifiedTask,
    sigma: f64,
    grad_w_j_hat: (f64, f64),
    grad_w_l_hat: (f64, f64),
    required: f64,
    form: HpForm,
) -> Result<Certified, BoundsError> {
    hp_w_safe_step_along_l_in(
        task.constants(),
        task.in_rounding_range(),
        sigma,
        grad_w_j_hat,
        grad_w_l_hat,
        required,
        form,
    )
}

/// [`hp_w_safe_step_along_l`] for the task constants `k` whose rounding range is `in_range`, compiled
/// once in this crate (the generic function above only chooses how the range is decided).
fn hp_w_safe_step_along_l_in(
    k: &TaskConstants,
    in_range: bool,
    sigma: f64,
    grad_w_j_hat: (f64, f64),
    grad_w_l_hat: (f64, f64),
    required: f64,
    form: HpForm,
) -> Result<Certified, BoundsError> {
    let (j, ej) = grad_w_j_hat;
    let (l, el) = grad_w_l_hat;
    finite("required", required)?;
    let penalties = Penalties::new(k, sigma)?;
    let dd = penalties.d()?;
    let bound = hp::HighProbabilityBound::w_along_l_at(&penalties, j, ej, l, el)?;
    let fast = move || {
        let (nj, nl) = (j.abs(), l.abs());
        let (l_hi, j_hi) = (Rounded::sum(nl, el), Rounded::sum(nj, ej));
        let lower = Rounded::difference(nl, el).mul(Rounded::difference(nj, ej))?;
        let b = rounding::d(in_range, sigma, dd)?.mul(l_hi.mul(l_hi)?)?;
        let direction = if (j > 0.0) == (l > 0.0) { 1.0 } else { -1.0 };
        Some(RoundedBound::high_probability(
            direction,
            lower,
            l_hi.mul(j_hi)?,
            b,
            form,
        ))
    };
    certify_high_probability(bound, required, form, fast, move || {
        HpEnclosure::w_along_l(k, sigma, grad_w_j_hat, grad_w_l_hat, form)
    })
}

/// Certified rigorous steps along ∇_w J ([`rigorous::safe_step_along_j`]); interval
/// arithmetic only (the bound involves e^x).
///
/// ```
/// use sepg_bounds::{constants::TaskConstants};
/// use sepg_certified as certified;
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// assert!(certified::rigorous_safe_step_along_j(&k, 1.0, 0.5, 0.0)?.is_certified());
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn rigorous_safe_step_along_j(
    task: impl AsCertifiedTask,
    sigma: f64,
    grad_w_j: f64,
    required: f64,
) -> Result<Certified, BoundsError> {
    rigorous_safe_step_along_j_in(
        task.constants(),
        task.in_rounding_range(),
        sigma,
        grad_w_j,
        required,
    )
}

/// [`rigorous_safe_step_along_j`] for the task constants `k` whose rounding range is `in_range`, compiled
/// once in this crate (the generic function above only chooses how the range is decided).
fn rigorous_safe_step_along_j_in(
    k: &TaskConstants,
    _in_range: bool,
    sigma: f64,
    grad_w_j: f64,
    required: f64,
) -> Result<Certified, BoundsError> {
    let outcome = rigorous::safe_step_along_j(k, sigma, grad_w_j, required)?;
    certify_fast_then_interval(
        outcome,
        required,
        || None,
        || RigorousEnclosure::new(k, sigma, grad_w_j, grad_w_j).map(Some),
    )
}

/// Certified rigorous steps along ∇_w L ([`rigorous::safe_step_along_l`]); interval
/// arithmetic only.
///
/// ```
/// use sepg_bounds::{constants::TaskConstants};
/// use sepg_certified as certified;
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let o = certified::rigorous_safe_step_along_l(&k, 1.0, 0.5, -3.0, -0.01)?;
/// assert!(o.chosen_step().unwrap() > 0.0);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn rigorous_safe_step_along_l(
    task: impl AsCertifiedTask,
    sigma: f64,
    grad_w_j: f64,
    grad_w_l: f64,
    required: f64,
) -> Result<Certified, BoundsError> {
    rigorous_safe_step_along_l_in(
        task.constants(),
        task.in_rounding_range(),
        sigma,
        grad_w_j,
        grad_w_l,
        required,
    )
}

/// [`rigorous_safe_step_along_l`] for the task constants `k` whose rounding range is `in_range`, compiled
/// once in this crate (the generic function above only chooses how the range is decided).
fn rigorous_safe_step_along_l_in(
    k: &TaskConstants,
    _in_range: bool,
    sigma: f64,
    grad_w_j: f64,
    grad_w_l: f64,
    required: f64,
) -> Result<Certified, BoundsError> {
    let outcome = rigorous::safe_step_along_l(k, sigma, grad_w_j, grad_w_l, required)?;
    certify_fast_then_interval(
        outcome,
        required,
        || None,
        || RigorousEnclosure::new(k, sigma, grad_w_j, grad_w_l).map(Some),
    )
}

/// Certified exploring w-step along ∇̂_w L (`sepg_bounds::exploring::w_exploring_step`) for the
/// requirement C: the returned β's enclosed bound has lower end ≥ C.
///
/// ```
/// use sepg_bounds::{constants::TaskConstants};
/// use sepg_certified as certified;
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let o = certified::exploring_safe_step(&k, 1.0, -0.3, 0.1, 0.4, -0.01)?;
/// assert!(o.is_certified() && o.bound().unwrap().lo() >= -0.01);
/// assert!(o.chosen_step().unwrap() > 0.0);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn exploring_safe_step(
    task: impl AsCertifiedTask,
    sigma: f64,
    grad_w_j_hat: f64,
    eps_j: f64,
    grad_w_l_hat: f64,
    required: f64,
) -> Result<Certified, BoundsError> {
    exploring_safe_step_in(
        task.constants(),
        task.in_rounding_range(),
        sigma,
        grad_w_j_hat,
        eps_j,
        grad_w_l_hat,
        required,
    )
}

/// [`exploring_safe_step`] for the task constants `k` whose rounding range is `in_range`, compiled
/// once in this crate (the generic function above only chooses how the range is decided).
fn exploring_safe_step_in(
    k: &TaskConstants,
    in_range: bool,
    sigma: f64,
    grad_w_j_hat: f64,
    eps_j: f64,
    grad_w_l_hat: f64,
    required: f64,
) -> Result<Certified, BoundsError> {
    let bound = ExploringBound::new(k, sigma, grad_w_j_hat, eps_j)?;
    let outcome = bound.step_along(grad_w_l_hat, required)?;
    let fast = move || {
        // in β (Δw = β·l): a = l·(j − sign(l)·ε) for β ≥ 0, l·(j + sign(l)·ε) for β < 0,
        // b = d·l²
        let l = Rounded::exact(grad_w_l_hat);
        let (toward, against) = (
            Rounded::difference(grad_w_j_hat, eps_j),
            Rounded::sum(grad_w_j_hat, eps_j),
        );
        let (pos, neg) = if grad_w_l_hat > 0.0 {
            (toward, against)
        } else {
            (against, toward)
        };
        let b = rounding::d(in_range, sigma, bound.d)?.mul(l.mul(l)?)?;
        Some(RoundedBound::two_sided(l.mul(pos)?, l.mul(neg)?, b))
    };
    certify_fast_then_interval(outcome, required, fast, move || {
        ExploringEnclosure::new(k, sigma, grad_w_j_hat, eps_j, grad_w_l_hat).map(Some)
    })
}

/// Certified largest step t ∈ [0, `max_step`] along a proposed direction u
/// (`sepg_bounds::direction::DirectionBound::safe_step`) for the requirement C: the returned
/// t's enclosed bound has lower end ≥ C. Interval arithmetic only.
///
/// # Formula
///
/// ```text
/// B(t) = t·(u·ĝ) − t·Σ|u_i|ε_i − c(σ)·κ_φ·t²·‖u‖₂²,   certified: enclosure of B(t) ≥ C
/// ```
///
/// The `f64` step is moved toward 0 (toward the vertex when C > 0) by the fewest ulps whose
/// enclosure passes; with C ≤ 0, t = 0 (bound exactly 0) always passes. Outcomes:
/// [`Certified::Step`] (its `interval` the `f64` safe interval, `lo` clipped to 0),
/// [`Certified::Infeasible`] (the best t within the cap, its bound below C) and
/// [`Certified::Uncertifiable`].
///
/// Errors: those of [`DirectionBound::new`] and [`DirectionBound::safe_step`].
///
/// ```
/// use sepg_bounds::constants::TaskConstants;
/// use sepg_bounds::direction::{Direction, FeatureNorm};
/// use sepg_bounds::penalties::{Family, Horizon, Rewards, Tight};
/// let k = TaskConstants::new(0.99, 28.8, 4.0, 8.0)?
///     .with_family(Family::Tight(Tight::new(Horizon::Finite(20), Rewards::NonPositive)))?;
/// let d = Direction {
///     direction: &[1e-2, -1e-2],
///     grad_hat: &[40.0, -10.0],
///     eps: &[5.0, 5.0],
///     features: FeatureNorm::FromMax { features: 2 },
/// };
/// let o = sepg_certified::direction_safe_step(&k, 1.0, &d, 0.0, 1.0)?;
/// let t = o.chosen_step().unwrap();
/// assert!(o.is_certified() && t > 0.0 && t <= 1.0 && o.bound().unwrap().lo() >= 0.0);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn direction_safe_step(
    task: impl AsCertifiedTask,
    sigma: f64,
    d: &Direction,
    required: f64,
    max_step: f64,
) -> Result<Certified, BoundsError> {
    let k = task.constants();
    let step = DirectionBound::new(k, sigma, d)?.safe_step(required, max_step)?;
    let q = Quadratic::direction(k, sigma, d)?;
    let StepOutcome::Feasible(interval) = step.outcome else {
        return Ok(Certified::Infeasible {
            step: step.step,
            bound: q.enclose(step.step),
        });
    };
    let toward = if required <= 0.0 {
        0.0
    } else {
        interval.vertex.clamp(0.0, step.step)
    };
    Ok(match certify_toward(&q, step.step, toward, required) {
        Ok((t, bound, ulps_moved)) => Certified::Step(CertifiedStep {
            step: t,
            bound,
            ulps_moved,
            interval,
            by_error_bound: false,
        }),
        Err(bound) => Certified::Uncertifiable {
            step: toward,
            bound,
        },
    })
}

/// The adaptive step of Pirotta et al. with fixed σ (Corollary 3.11, the step of the
/// AdaStep comparison algorithm) with a certified guarantee: the step is α* of
/// [`pirotta::optimal_step`], and `bound` encloses the Theorem 3.10 bound at that `f64` α*,
/// so `bound.lo()` is a guarantee that holds in exact arithmetic (the `f64` guarantee α*‖∇‖₂²/2
/// can exceed it by rounding).
///
/// # Formula
///
/// ```text
/// B(α) = α ‖∇J‖₂² − α² c(σ) ‖∇J‖₁²,   α* = ‖∇J‖₂² / (2 c(σ) ‖∇J‖₁²)
/// ```
///
/// Outcomes: [`Certified::Step`] with `ulps_moved` 0 and the degenerate `interval` [α*, α*]
/// whose `c_max` is the `f64` guarantee; [`Certified::ZeroGradient`] for ∇J = 0. There is no
/// requirement to certify: the guarantee is whatever the step attains.
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, pirotta};
/// use sepg_certified as certified;
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let o = certified::adaptive_step(&k, 1.0, &[0.3, -0.5])?;
/// let b = o.bound().unwrap();
/// assert!(b.lo() <= pirotta::bound(&k, 1.0, &[0.3, -0.5], o.chosen_step().unwrap())?);
/// assert!(b.lo() > 0.0 && b.width() < 1e-15);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn adaptive_step(
    task: impl AsCertifiedTask,
    sigma: f64,
    grad: &[f64],
) -> Result<Certified, BoundsError> {
    adaptive_step_in(task.constants(), task.in_rounding_range(), sigma, grad)
}

/// [`adaptive_step`] for the task constants `k` whose rounding range is `in_range`, compiled
/// once in this crate (the generic function above only chooses how the range is decided).
fn adaptive_step_in(
    k: &TaskConstants,
    _in_range: bool,
    sigma: f64,
    grad: &[f64],
) -> Result<Certified, BoundsError> {
    let (alpha, guarantee) = match pirotta::optimal_step(k, sigma, grad)? {
        pirotta::AdaptiveStep::Step { alpha, guarantee } => (alpha, guarantee),
        pirotta::AdaptiveStep::ZeroGradient => {
            return Ok(Certified::ZeroGradient {
                requirement_met: true,
            });
        }
        _ => return Ok(Certified::BelowNoise),
    };
    let (l2, l1) = grad.iter().fold(
        (Interval::point(0.0), Interval::point(0.0)),
        |(l2, l1), &g| (l2 + Interval::point(g).sqr(), l1 + Interval::point(g.abs())),
    );
    let bound = Quadratic {
        linear: l2,
        quadratic: c(k, sigma)? * l1.sqr(),
    }
    .enclose(alpha);
    Ok(Certified::Step(CertifiedStep {
        step: alpha,
        bound,
        ulps_moved: 0,
        interval: SafeInterval {
            c_max: guarantee,
            vertex: alpha,
            lambda: Some(0.0),
            lo: alpha,
            hi: alpha,
        },
        by_error_bound: false,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::certificate::certify;

    #[test]
    fn the_error_bound_certifies_ordinary_steps_and_intervals_the_rest() {
        let k = TaskConstants::new(0.99, 28.8, 4.0, 8.0).expect("lqg1d constants");
        let Ok(Certified::Step(s)) = v_safe_step(&k, 0.5, &[-3.7], 0.0) else {
            panic!("certified")
        };
        assert!(s.by_error_bound && s.bound.lo() >= 0.0 && s.ulps_moved > 0);
        // σ below 2⁻¹⁰⁰: the rounding analysis of c does not apply
        let Ok(Certified::Step(s)) = v_safe_step(&k, 1e-31, &[1e-60], 0.0) else {
            panic!("certified")
        };
        assert!(!s.by_error_bound && s.bound.lo() >= 0.0);
        // the same step form certified both ways meets C both ways
        let cmax = v_update::c_max(&k, 0.5, &[-3.7]).expect("finite");
        for required in [0.5 * cmax, -cmax] {
            let fast = v_safe_step(&k, 0.5, &[-3.7], required).expect("valid");
            let outcome = v_update::safe_step(&k, 0.5, &[-3.7], required).expect("valid");
            let q = Quadratic::v_update(&k, 0.5, &[-3.7]).expect("valid");
            let slow = certify(&q, outcome, required);
            let (Certified::Step(f), Certified::Step(s)) = (fast, slow) else {
                panic!("both certified")
            };
            assert!(f.by_error_bound && !s.by_error_bound);
            assert!(f.bound.lo() >= required && s.bound.lo() >= required);
            // the predicted move is at most 1/8 longer than the fewest ulps, plus 2
            // the error bound is wider (about (k+7)u per term, k ≤ 18) than the interval
            // enclosure, so its step moves further in, but by a negligible amount
            assert!((f.step - s.step).abs() <= 1e-13 * s.step.abs());
        }
    }
}
