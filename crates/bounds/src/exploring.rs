//! The exploring w-update: the direction comes from ∇̂_w L, the guarantee only from the
//! confidence on ∇_w J (docs/THEOREMS.md, "The exploring w-update").
//!
//! Theorem 4.3 bounds the change of J for *any* change Δw of the log standard deviation:
//!
//! ```text
//! J(v, w + Δw) − J(v, w) ≥ Δw·∇_w J − d(σ)·Δw²          (eq. (4.15) with Δw = β∇_w J)
//! ```
//!
//! On the event |∇_w J − ∇̂_w J| ≤ ε_J of Assumption 4.6 (probability at least 1 − δ), the
//! linear term is at least Δw·∇̂_w J − |Δw|·ε_J for every Δw at once, so
//!
//! ```text
//! B(Δw) = Δw·∇̂_w J − |Δw|·ε_J − d(σ)·Δw²
//! ```
//!
//! is a high-probability lower bound that holds *uniformly* in Δw. A step chosen from the
//! data, in particular along the sign of an estimate ∇̂_w L from the same batch, inherits it:
//! ∇̂_w L only picks the direction and its confidence width ε_L plays no role in safety.
//! Theorem 4.9 instead multiplies corrected norms L⁻J⁻ and skips the update whenever
//! |∇̂_w L| ≤ ε_L, which blocks exploration without making the step any safer
//! (docs/ERRATA.md, "Theorem 4.9 is needlessly conservative").
//!
//! B is concave, so {Δw : B(Δw) ≥ C} is an interval; the exploring step is the end of that
//! interval furthest along ∇̂_w L, which is the thesis's β̄ = β̃ + λ_w|β̃| (eq. (4.20)) when
//! ε_J = 0. Steps are expressed as β with Δw = β·∇̂_w L, like [`crate::w_update`].
//!
//! The bound is the thesis form of Theorem 4.3, so it shares that theorem's neglected
//! third-order term for Δw < 0 (ERRATA §10); on the LQG presets at γ = 0.99 it is
//! conservative for σ ≥ 0.1.

use crate::constants::TaskConstants;
use crate::error::{BoundsError, finite, no_overflow, non_negative};
use crate::outcome::{SafeInterval, StepOutcome};
use crate::parabola::Parabola;
use crate::penalties::Penalties;

/// The lower bound B(Δw) of the exploring w-update for an estimate ∇̂_w J with half-width ε_J.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExploringBound {
    /// ∇̂_w J, the estimate of ∇_w J at (v^{t+1}, w^t).
    pub grad_w_j_hat: f64,
    /// ε_J ≥ 0, its confidence half-width (0 for an exact gradient).
    pub eps_j: f64,
    /// d(σ) of Theorem 4.3 at the current σ.
    pub d: f64,
}

impl ExploringBound {
    /// The bound for the task `k` at standard deviation `sigma`.
    ///
    /// # Errors
    /// Non-finite ∇̂_w J, ε_J < 0 or non-finite, and the errors of [`d`](crate::constants::d).
    ///
    /// ```
    /// use sepg_bounds::{constants::{TaskConstants, d}, exploring::ExploringBound};
    /// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
    /// let b = ExploringBound::new(&k, 0.5, -0.2, 0.3)?;
    /// assert_eq!(b.d, d(&k, 0.5)?);
    /// assert!(ExploringBound::new(&k, 0.5, f64::NAN, 0.3).is_err());
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    #[inline]
    pub fn new(
        k: &TaskConstants,
        sigma: f64,
        grad_w_j_hat: f64,
        eps_j: f64,
    ) -> Result<Self, BoundsError> {
        Ok(ExploringBound {
            grad_w_j_hat: finite("grad_w_j_hat", grad_w_j_hat)?,
            eps_j: non_negative("eps_j", eps_j)?,
            d: Penalties::new(k, sigma)?.d()?,
        })
    }

    /// [`ExploringBound::new`] for penalties evaluated once ([`Penalties`]), with
    /// d = `p.d()` of their family; the same errors, without validating σ again.
    #[inline]
    pub fn at(p: &Penalties, grad_w_j_hat: f64, eps_j: f64) -> Result<Self, BoundsError> {
        Ok(ExploringBound {
            grad_w_j_hat: finite("grad_w_j_hat", grad_w_j_hat)?,
            eps_j: non_negative("eps_j", eps_j)?,
            d: p.d()?,
        })
    }

    /// B(Δw), the guaranteed change of J for the change Δw of w (with probability ≥ 1 − δ
    /// when ε_J is a (1 − δ) confidence half-width).
    ///
    /// # Formula
    ///
    /// ```text
    /// B(Δw) = Δw·∇̂_w J − |Δw|·ε_J − d·Δw²
    /// ```
    ///
    /// ```
    /// use sepg_bounds::exploring::ExploringBound;
    /// let b = ExploringBound { grad_w_j_hat: 1.0, eps_j: 0.5, d: 2.0 };
    /// assert_eq!(b.value(0.5)?, 0.5 - 0.25 - 0.5);
    /// assert_eq!(b.value(-0.5)?, -0.5 - 0.25 - 0.5);
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn value(&self, delta_w: f64) -> Result<f64, BoundsError> {
        finite("delta_w", delta_w)?;
        no_overflow(
            "exploring bound",
            delta_w * self.grad_w_j_hat - delta_w.abs() * self.eps_j - self.d * delta_w * delta_w,
        )
    }

    /// The step Δw of maximal guaranteed improvement and that improvement.
    ///
    /// # Formula
    ///
    /// ```text
    /// a = |∇̂_w J| − ε_J;   a > 0: Δw* = sign(∇̂_w J)·a/(2d),  C_max = a²/(4d);
    ///                      a ≤ 0: Δw* = 0,                   C_max = 0
    /// ```
    ///
    /// ```
    /// use sepg_bounds::exploring::ExploringBound;
    /// let b = ExploringBound { grad_w_j_hat: -1.0, eps_j: 0.5, d: 2.0 };
    /// assert_eq!(b.vertex()?, (-0.125, 0.03125));
    /// let noisy = ExploringBound { grad_w_j_hat: -1.0, eps_j: 1.5, d: 2.0 };
    /// assert_eq!(noisy.vertex()?, (0.0, 0.0));
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    #[inline]
    pub fn vertex(&self) -> Result<(f64, f64), BoundsError> {
        let a = self.grad_w_j_hat.abs() - self.eps_j;
        if a <= 0.0 {
            return Ok((0.0, 0.0));
        }
        let t = no_overflow("step-size vertex", a / (2.0 * self.d))?;
        Ok((
            self.grad_w_j_hat.signum() * t,
            no_overflow("C_max", a * t / 2.0)?,
        ))
    }

    /// The interval of changes Δw with B(Δw) ≥ C, or [`StepOutcome::Infeasible`] (with the
    /// Δw of maximal guaranteed improvement) when C exceeds C_max.
    ///
    /// # Formula
    ///
    /// ```text
    /// {Δw ≥ 0 : Δw(∇̂_w J − ε_J) − dΔw² ≥ C} ∪ {Δw ≤ 0 : Δw(∇̂_w J + ε_J) − dΔw² ≥ C}
    /// ```
    ///
    /// Each part is solved by the crate's stable quadratic solver; B is concave, so the union
    /// is one interval [lo, hi]. `vertex` and `c_max` are those of [`Self::vertex`]; `lambda`
    /// is `None` (the interval is not of the form |Δw − Δw*| ≤ λ|Δw*| when ε_J > 0).
    ///
    /// ```
    /// use sepg_bounds::{exploring::ExploringBound, outcome::StepOutcome};
    /// // |∇̂_w J| ≤ ε_J: no improvement is guaranteed, but a worsening of 0.1 allows steps
    /// // of either sign.
    /// let b = ExploringBound { grad_w_j_hat: 0.2, eps_j: 0.5, d: 2.0 };
    /// let StepOutcome::Feasible(s) = b.safe_interval(-0.1)? else { panic!() };
    /// assert!(s.lo < 0.0 && s.hi > 0.0);
    /// assert!((b.value(s.hi)? + 0.1).abs() < 1e-15 && (b.value(s.lo)? + 0.1).abs() < 1e-15);
    /// assert!(matches!(b.safe_interval(0.1)?, StepOutcome::Infeasible { .. }));
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    #[inline]
    pub fn safe_interval(&self, required: f64) -> Result<StepOutcome, BoundsError> {
        finite("required", required)?;
        let (vertex, c_max) = self.vertex()?;
        let positive = Parabola::new(self.grad_w_j_hat - self.eps_j, self.d).solve(required)?;
        let negative = Parabola::new(self.grad_w_j_hat + self.eps_j, self.d).solve(required)?;
        let side = |o: StepOutcome, keep: fn(f64, f64) -> Option<(f64, f64)>| match o {
            StepOutcome::Feasible(s) => keep(s.lo, s.hi),
            _ => None,
        };
        let pos = side(positive, |lo, hi| (hi >= 0.0).then_some((lo.max(0.0), hi)));
        let neg = side(negative, |lo, hi| (lo <= 0.0).then_some((lo, hi.min(0.0))));
        let (lo, hi) = match (neg, pos) {
            (Some((lo, _)), Some((_, hi))) => (lo, hi),
            (Some(iv), None) | (None, Some(iv)) => iv,
            (None, None) => return Ok(StepOutcome::Infeasible { c_max, vertex }),
        };
        Ok(StepOutcome::Feasible(SafeInterval {
            c_max,
            vertex: vertex.clamp(lo, hi),
            lambda: None,
            lo,
            hi,
        }))
    }
}

/// The exploring w-update along an estimated ∇_w L: the safe steps β (Δw = β·∇̂_w L) for a
/// required improvement C, whose guarantee rests only on the confidence of ∇̂_w J.
///
/// # Formula
///
/// ```text
/// [lo, hi] = {Δw : Δw·∇̂_w J − |Δw|·ε_J − d(σ)·Δw² ≥ C}     (see ExploringBound)
/// β-interval = [lo, hi] / ∇̂_w L  (ends swapped when ∇̂_w L < 0)
/// chosen step β̄ = its upper end, the safe step furthest along ∇̂_w L
/// ```
///
/// With ε_J = 0 this is the interval of Theorem 4.5 (eq. (4.19)). Outcomes:
/// [`StepOutcome::ZeroGradient`] when ∇̂_w L = 0 (no direction), [`StepOutcome::Infeasible`]
/// with the β of maximal guaranteed improvement when C > C_max, otherwise
/// [`StepOutcome::Feasible`]. There is no below-noise outcome: neither |∇̂_w L| ≤ ε_L nor
/// |∇̂_w J| ≤ ε_J blocks a step that the budget allows.
///
/// # Errors
/// Non-finite inputs, ε_J < 0, the errors of [`d`](crate::constants::d), and
/// [`BoundsError::Overflow`] when β
/// is not representable (|∇̂_w L| below about 1e-300).
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, exploring::w_exploring_step};
/// use sepg_bounds::high_probability::{w_safe_step_along_l, HpForm};
/// use sepg_bounds::outcome::StepOutcome;
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// // ∇̂_w L = 0.4 is within its width 0.5: Theorem 4.9 makes no update ...
/// let thesis = w_safe_step_along_l(&k, 1.0, -0.3, 0.1, 0.4, 0.5, -0.01, HpForm::SignAware)?;
/// assert_eq!(thesis, StepOutcome::BelowNoise);
/// // ... while the exploring step raises σ within the allowed worsening of 0.01.
/// let beta = w_exploring_step(&k, 1.0, -0.3, 0.1, 0.4, -0.01)?.chosen_step().unwrap();
/// assert!(beta > 0.0);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn w_exploring_step(
    k: &TaskConstants,
    sigma: f64,
    grad_w_j_hat: f64,
    eps_j: f64,
    grad_w_l_hat: f64,
    required: f64,
) -> Result<StepOutcome, BoundsError> {
    let bound = ExploringBound::new(k, sigma, grad_w_j_hat, eps_j)?;
    bound.step_along(grad_w_l_hat, required)
}

/// [`w_exploring_step`] for penalties evaluated once ([`Penalties`]), with d = `p.d()` of
/// their family; the same errors, without validating σ again.
pub fn w_exploring_step_at(
    p: &Penalties,
    grad_w_j_hat: f64,
    eps_j: f64,
    grad_w_l_hat: f64,
    required: f64,
) -> Result<StepOutcome, BoundsError> {
    ExploringBound::at(p, grad_w_j_hat, eps_j)?.step_along(grad_w_l_hat, required)
}

impl ExploringBound {
    /// The exploring step along ∇̂_w L for this bound: [`w_exploring_step`] without
    /// evaluating d(σ) again.
    ///
    /// Errors: non-finite ∇̂_w L or `required`, and [`BoundsError::Overflow`] when β is not
    /// representable.
    ///
    /// ```
    /// use sepg_bounds::{constants::TaskConstants, exploring::{ExploringBound, w_exploring_step}};
    /// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
    /// let b = ExploringBound::new(&k, 1.0, -0.3, 0.1)?;
    /// assert_eq!(b.step_along(0.4, -0.01)?, w_exploring_step(&k, 1.0, -0.3, 0.1, 0.4, -0.01)?);
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    #[inline]
    pub fn step_along(&self, grad_w_l_hat: f64, required: f64) -> Result<StepOutcome, BoundsError> {
        finite("grad_w_l_hat", grad_w_l_hat)?;
        finite("required", required)?;
        if grad_w_l_hat == 0.0 {
            return Ok(StepOutcome::ZeroGradient {
                requirement_met: required <= 0.0,
            });
        }
        let to_beta = |dw: f64| no_overflow("step size beta", dw / grad_w_l_hat);
        Ok(match self.safe_interval(required)? {
            StepOutcome::Feasible(s) => {
                let (a, b) = (to_beta(s.lo)?, to_beta(s.hi)?);
                StepOutcome::Feasible(SafeInterval {
                    c_max: s.c_max,
                    vertex: to_beta(s.vertex)?,
                    lambda: None,
                    lo: a.min(b),
                    hi: a.max(b),
                })
            }
            StepOutcome::Infeasible { c_max, vertex } => StepOutcome::Infeasible {
                c_max,
                vertex: to_beta(vertex)?,
            },
            other => other,
        })
    }
}
