//! A safe step along any proposed direction of the mean parameters (docs/THEOREMS.md, "Tight
//! constants", Theorem T, and "A step along any direction").
//!
//! Theorem T bounds J(v + Δ, w) − J(v, w) below by Δ·∇_vJ − c‖Δ‖₂² for every change Δ of the
//! mean parameters at once, with c the tight c(σ) when ‖φ(s)‖₂ ≤ M_φ. On the confidence event
//! |∂J/∂v_i − ĝ_i| ≤ ε_i (every i), Δ·∇_vJ ≥ Δ·ĝ − Σ|Δ_i|ε_i, so for a proposed direction u
//! (Adam's change, a natural gradient, a user's own) and a step t ≥ 0 along it, Δ = t·u:
//!
//! ```text
//! B(t) = t·(u·ĝ) − t·Σ|u_i|ε_i − c₂·t²·‖u‖₂²,   c₂ = c(σ)·κ_φ
//! κ_φ = 1                     u has one non-zero entry (Theorem 4.2's coordinate case)
//! κ_φ = p                     otherwise, ‖φ‖₂ ≤ √p·M_φ from |φ_i| ≤ M_φ (p features per action)
//! κ_φ = (M₂ / M_φ)²           otherwise, with a stated bound ‖φ(s)‖₂ ≤ M₂
//! ```
//!
//! [`DirectionBound::safe_step`] returns the largest t ≥ 0 (at most a cap) with B(t) ≥ C for a
//! requirement C (C < 0 is a bounded worsening). The thesis's c (Theorems 3.14, 4.2) is proven
//! for the greedy coordinate only, so with [`Family::Thesis`] a direction with several non-zero
//! entries is refused ([`BoundsError::UnprovenDirection`]).
//!
//! ```
//! use sepg_bounds::constants::TaskConstants;
//! use sepg_bounds::direction::{Direction, DirectionBound, FeatureNorm};
//! use sepg_bounds::penalties::{Family, Horizon, Rewards, Tight};
//! let k = TaskConstants::new(0.99, 28.8, 4.0, 8.0)?
//!     .with_family(Family::Tight(Tight::new(Horizon::Finite(20), Rewards::NonPositive)))?;
//! let d = Direction {
//!     direction: &[0.01, -0.02],
//!     grad_hat: &[30.0, -10.0],
//!     eps: &[0.0, 0.0],
//!     features: FeatureNorm::FromMax { features: 2 },
//! };
//! let b = DirectionBound::new(&k, 1.0, &d)?;
//! let s = b.safe_step(0.0, f64::INFINITY)?;
//! assert!(s.step > 0.0 && s.guaranteed >= -1e-15);
//! # Ok::<(), sepg_bounds::BoundsError>(())
//! ```

use crate::constants::TaskConstants;
use crate::error::{BoundsError, finite, no_overflow, positive, same_length};
use crate::outcome::{SafeInterval, StepOutcome};
use crate::parabola::Parabola;
use crate::penalties::{Family, Penalties};

/// What bounds ‖φ(s)‖₂, the 2-norm of the features of one action, at every reachable state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FeatureNorm {
    /// No statement beyond |φ_i(s)| ≤ M_φ (eq. (3.14)): ‖φ(s)‖₂ ≤ √p·M_φ with p = `features`
    /// features per action (p ≥ 1), so κ_φ = p.
    FromMax {
        /// p, the number of features of one action.
        features: usize,
    },
    /// A stated bound M₂ > 0 with ‖φ(s)‖₂ ≤ M₂ at every reachable state (feature units), so
    /// κ_φ = (M₂/M_φ)². It is worth stating only when M₂ < √p·M_φ.
    Stated(f64),
}

/// A proposed direction with the gradient estimate the step is certified against.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Direction<'a> {
    /// u, the proposed change of the mean parameters per unit step (units of v; non-zero,
    /// finite, action-major like v).
    pub direction: &'a [f64],
    /// ĝ, the estimate of ∇_vJ (performance per unit of v), the length of `direction`.
    pub grad_hat: &'a [f64],
    /// ε_i ≥ 0, the confidence half-width of each component of ĝ (0: exact gradient).
    pub eps: &'a [f64],
    /// What bounds the 2-norm of the features.
    pub features: FeatureNorm,
}

impl Direction<'_> {
    /// Checks the inputs: non-empty vectors of one length, finite entries, ε_i ≥ 0, u ≠ 0,
    /// p ≥ 1 or M₂ finite and positive.
    ///
    /// Errors: [`BoundsError::EmptyVector`], [`BoundsError::LengthMismatch`],
    /// [`BoundsError::NonFinite`], [`BoundsError::OutOfDomain`].
    pub fn validate(&self) -> Result<(), BoundsError> {
        crate::error::finite_vector("direction", self.direction)?;
        same_length("direction", self.direction, "grad_hat", self.grad_hat)?;
        same_length("direction", self.direction, "eps", self.eps)?;
        crate::error::finite_vector("grad_hat", self.grad_hat)?;
        for &e in self.eps {
            crate::error::non_negative("eps", e)?;
        }
        if self.direction.iter().all(|&x| x == 0.0) {
            return Err(BoundsError::OutOfDomain {
                name: "direction",
                value: 0.0,
                domain: "non-zero vectors",
            });
        }
        match self.features {
            FeatureNorm::FromMax { features: 0 } => Err(BoundsError::OutOfDomain {
                name: "features",
                value: 0.0,
                domain: "at least 1",
            }),
            FeatureNorm::FromMax { .. } => Ok(()),
            FeatureNorm::Stated(m2) => positive("feature 2-norm bound", m2).map(|_| ()),
        }
    }

    /// Whether u has exactly one non-zero entry (a coordinate direction, Theorem 4.2's case).
    ///
    /// ```
    /// use sepg_bounds::direction::{Direction, FeatureNorm};
    /// let f = FeatureNorm::FromMax { features: 2 };
    /// let d = Direction { direction: &[0.0, -3.0], grad_hat: &[1.0, 1.0], eps: &[0.0, 0.0], features: f };
    /// assert!(d.is_coordinate());
    /// ```
    pub fn is_coordinate(&self) -> bool {
        self.direction.iter().filter(|&&x| x != 0.0).count() == 1
    }

    /// κ_φ of the module documentation for the task constants `k` (M_φ): 1 for a coordinate
    /// direction, else p or (M₂/M_φ)² (dimensionless).
    ///
    /// Errors: [`BoundsError::UnprovenDirection`] for a non-coordinate direction with the
    /// thesis family; [`BoundsError::Overflow`] when (M₂/M_φ)² is not finite.
    pub fn feature_factor(&self, k: &TaskConstants) -> Result<f64, BoundsError> {
        if self.is_coordinate() {
            return Ok(1.0);
        }
        if k.family() == Family::Thesis {
            return Err(BoundsError::UnprovenDirection);
        }
        match self.features {
            FeatureNorm::FromMax { features } => Ok(features as f64),
            FeatureNorm::Stated(m2) => {
                let r = m2 / k.m_phi();
                no_overflow("(M2/M_phi)^2", r * r)
            }
        }
    }
}

/// The bound B(t) = a·t − b·t² of a step t ≥ 0 along a validated [`Direction`], with
/// a = u·ĝ − Σ|u_i|ε_i and b = c₂‖u‖₂² (module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DirectionBound {
    /// B(t) = a·t − b·t² (performance units; t dimensionless).
    pub parabola: Parabola,
    /// c₂ = c(σ)·κ_φ (performance per squared unit of v).
    pub penalty: f64,
}

/// The largest safe step along a direction, and what it guarantees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DirectionStep {
    /// The safe steps t ≥ 0 with B(t) ≥ C ([`StepOutcome::Feasible`], its `lo` clipped to 0;
    /// the cap is not applied to it), or why there is none ([`StepOutcome::Infeasible`] with
    /// the best t ≥ 0 and its bound; a direction of non-positive a has c_max 0 at t = 0).
    pub outcome: StepOutcome,
    /// The chosen t: the largest safe t, at most the cap; when infeasible, the t ≥ 0 of
    /// maximal guarantee, at most the cap.
    pub step: f64,
    /// B(step), computed in `f64` (performance units).
    pub guaranteed: f64,
}

impl DirectionBound {
    /// The bound for the task constants `k` at standard deviation `sigma` > 0 (the smallest
    /// σ of the policy): c(σ) of the family of `k`.
    ///
    /// Errors: those of [`Penalties::new`] and [`DirectionBound::at`].
    pub fn new(k: &TaskConstants, sigma: f64, d: &Direction) -> Result<Self, BoundsError> {
        Self::at(&Penalties::new(k, sigma)?, d)
    }

    /// [`DirectionBound::new`] for penalties evaluated once.
    ///
    /// Errors: an invalid direction ([`Direction::validate`]), a non-coordinate direction
    /// with the thesis family ([`BoundsError::UnprovenDirection`]), and
    /// [`BoundsError::Overflow`] when a, ‖u‖₂² or b is not finite.
    pub fn at(p: &Penalties, d: &Direction) -> Result<Self, BoundsError> {
        d.validate()?;
        let kappa = d.feature_factor(p.task())?;
        let mut linear = 0.0;
        let mut norm2 = 0.0;
        for ((&u, &g), &e) in d.direction.iter().zip(d.grad_hat).zip(d.eps) {
            linear += u * g - u.abs() * e;
            norm2 += u * u;
        }
        no_overflow("u.g - sum |u_i| eps_i", linear)?;
        no_overflow("||u||^2", norm2)?;
        let penalty = no_overflow("c2", p.c()? * kappa)?;
        Ok(Self {
            parabola: Parabola::new(linear, no_overflow("c2 ||u||^2", penalty * norm2)?),
            penalty,
        })
    }

    /// B(t) = a·t − b·t² at the step `t` (finite; performance units).
    ///
    /// Errors: t not finite; [`BoundsError::Overflow`].
    pub fn bound(&self, t: f64) -> Result<f64, BoundsError> {
        finite("t", t)?;
        no_overflow("direction bound", self.value(t))
    }

    fn value(&self, t: f64) -> f64 {
        self.parabola.linear * t - self.parabola.quadratic * t * t
    }

    /// The largest t ∈ [0, `max_step`] with B(t) ≥ C = `required` (finite), and B there.
    ///
    /// # Formula
    ///
    /// ```text
    /// t* = (a + √(a² − 4bC)) / (2b)   when C ≤ a²/(4b) (a > 0) or C ≤ 0
    /// step = min(t*, max_step)
    /// ```
    ///
    /// With C > 0 and no safe t ≤ `max_step` (a ≤ 0, C > a²/(4b), or the cap below the
    /// smallest safe t) the outcome is [`StepOutcome::Infeasible`] and the step the t of
    /// maximal guarantee within [0, `max_step`]. `max_step` > 0, +∞ allowed.
    ///
    /// Errors: C not finite, `max_step` NaN or not positive, [`BoundsError::Overflow`].
    ///
    /// ```
    /// use sepg_bounds::direction::{Direction, DirectionBound, FeatureNorm};
    /// use sepg_bounds::TaskConstants;
    /// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
    /// let d = Direction { direction: &[2.0], grad_hat: &[0.5], eps: &[0.0], features: FeatureNorm::FromMax { features: 1 } };
    /// let b = DirectionBound::new(&k, 1.0, &d)?;
    /// // a = 1, b = 4c: t* = 1/(4c) for C = 0
    /// let t = b.safe_step(0.0, f64::INFINITY)?.step;
    /// assert!((t - 1.0 / b.parabola.quadratic).abs() < 1e-15 * t);
    /// assert_eq!(b.safe_step(0.0, 0.5 * t)?.step, 0.5 * t);
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn safe_step(&self, required: f64, max_step: f64) -> Result<DirectionStep, BoundsError> {
        finite("required", required)?;
        if max_step.is_nan() || max_step <= 0.0 {
            return Err(BoundsError::OutOfDomain {
                name: "max_step",
                value: max_step,
                domain: "(0, +inf]",
            });
        }
        let infeasible = |c_max: f64, vertex: f64| -> Result<DirectionStep, BoundsError> {
            let step = vertex.clamp(0.0, max_step);
            Ok(DirectionStep {
                outcome: StepOutcome::Infeasible { c_max, vertex },
                step,
                guaranteed: self.bound(step)?,
            })
        };
        let outcome = self.parabola.solve(required)?;
        match outcome {
            StepOutcome::Feasible(s) if s.hi >= 0.0 => {
                let lo = s.lo.max(0.0);
                if lo > max_step {
                    return infeasible(s.c_max, s.vertex);
                }
                // + 0.0 turns a −0 end point into +0
                let step = s.hi.min(max_step) + 0.0;
                Ok(DirectionStep {
                    outcome: StepOutcome::Feasible(SafeInterval { lo, ..s }),
                    step,
                    guaranteed: self.bound(step)?,
                })
            }
            StepOutcome::Infeasible { c_max, vertex } if vertex > 0.0 => infeasible(c_max, vertex),
            // a ≤ 0 with C > 0: B(t) ≤ 0 < C for every t ≥ 0, at best 0 at t = 0
            _ => infeasible(0.0, 0.0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_non_positive_linear_term_with_a_positive_requirement_is_infeasible_at_zero() {
        let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0).expect("constants");
        let d = Direction {
            direction: &[-1.0],
            grad_hat: &[0.5],
            eps: &[0.0],
            features: FeatureNorm::FromMax { features: 1 },
        };
        let b = DirectionBound::new(&k, 1.0, &d).expect("bound");
        let s = b.safe_step(1e-3, 1.0).expect("step");
        assert_eq!(
            s.outcome,
            StepOutcome::Infeasible {
                c_max: 0.0,
                vertex: 0.0
            }
        );
        assert_eq!((s.step, s.guaranteed), (0.0, 0.0));
        // C = 0 against the gradient: only t = 0 is safe
        let s = b.safe_step(0.0, 1.0).expect("step");
        assert_eq!(s.step, 0.0);
        assert!(matches!(s.outcome, StepOutcome::Feasible(_)));
    }
}
