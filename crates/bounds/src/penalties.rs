//! The penalty coefficients c(σ) and d(σ) of one family of constants, evaluated at one σ.
//!
//! Every step-size bound of Chapter 4 is a parabola whose curvature is c(σ) (the v-update,
//! Theorems 3.14 and 4.2) or d(σ) (the w-update, Theorem 4.3) times a squared gradient. A
//! [`Penalties`] validates σ once and computes each coefficient at most once, so that the
//! functions taking it (the `_at` functions: [`crate::v_update::safe_step_at`],
//! [`crate::w_update::safe_step_along_j_at`],
//! [`crate::high_probability::HighProbabilityBound::v_update_at`], ...) neither re-validate σ
//! nor recompute c or d.
//!
//! The [`Family`] says which formulas give c and d: the thesis's (Theorems 3.14, 4.2, 4.3) or
//! the tight constants (docs/THEOREMS.md "Tight constants"). The family is part of the
//! [`TaskConstants`] ([`TaskConstants::with_family`]), so every bound that takes the
//! constants, with or without a [`Penalties`], follows it.

use std::cell::Cell;

use crate::constants::{TaskConstants, c_value, d_value};
use crate::error::{BoundsError, no_overflow, positive};

/// The family of constants that gives the penalty coefficients c(σ) and d(σ).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[non_exhaustive]
pub enum Family {
    /// c of Theorems 3.14 / 4.2 ([`crate::constants::c`]) and d of Theorem 4.3
    /// ([`crate::constants::d`]), with ψ of Lemma A.1 unless
    /// [`TaskConstants::with_psi`] replaced it.
    #[default]
    Thesis,
    /// The tight constants c = ρ R M_φ² S_H / σ² and d = 2ρ R S_H of docs/THEOREMS.md
    /// "Tight constants" (Theorem T), from the likelihood-ratio form of the Hessian of J:
    /// valid on ℝ (no action volume enters), for every σ and, for d, for every change of σ.
    Tight(Tight),
}

/// What the tight constants need to know of the task beyond R, M_φ and γ.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Tight {
    pub(crate) horizon: Horizon,
    pub(crate) rewards: Rewards,
}

/// The horizon H of J_H = E Σ_{t<H} γᵗ r_t.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Horizon {
    /// H steps (H ≥ 1); an episode that terminates earlier has reward 0 afterwards.
    Finite(u64),
    /// H = ∞ (γ < 1).
    Infinite,
}

/// What is known of the sign of every reward r_t (|r_t| ≤ R always).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Rewards {
    /// Rewards of either sign: the two-sided constants (ρ = 1). Always sound.
    TwoSided,
    /// −R ≤ r_t ≤ 0 for every t: the curvature of log π is then of the favourable sign and
    /// the constants halve (ρ = 1/2). A task with rewards in [lo, hi], a fixed horizon and no
    /// termination can be shifted by −hi to qualify, with R = hi − lo.
    NonPositive,
}

/// The penalty coefficients of a task at one standard deviation σ, for one [`Family`]:
/// σ is validated once, and c(σ), d(σ) are each computed on first use and kept.
///
/// ```
/// use sepg_bounds::constants::{self, TaskConstants};
/// use sepg_bounds::penalties::{Family, Penalties};
/// let k = TaskConstants::new(0.99, 4.0, 2.0, 4.0)?;
/// let p = Penalties::new(&k, 0.5)?;
/// assert_eq!(p.family(), Family::Thesis);
/// assert_eq!(p.c()?, constants::c(&k, 0.5)?);
/// assert_eq!(p.d()?, constants::d(&k, 0.5)?);
/// assert!(Penalties::new(&k, 0.0).is_err());
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Penalties {
    task: TaskConstants,
    sigma: f64,
    c: Cell<Option<f64>>,
    d: Cell<Option<f64>>,
}

impl Penalties {
    /// The coefficients of the family of `k` ([`TaskConstants::family`]) at standard
    /// deviation `sigma` (action units).
    ///
    /// Errors: σ not finite and strictly positive (the error of [`crate::constants::c`]).
    #[inline]
    pub fn new(k: &TaskConstants, sigma: f64) -> Result<Self, BoundsError> {
        Ok(Self {
            task: *k,
            sigma: positive("sigma", sigma)?,
            c: Cell::new(None),
            d: Cell::new(None),
        })
    }

    /// The task constants.
    pub fn task(&self) -> &TaskConstants {
        &self.task
    }

    /// The family of the coefficients, that of the task constants.
    pub fn family(&self) -> Family {
        self.task.family()
    }

    /// σ > 0, the standard deviation the coefficients are evaluated at.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// c(σ), the penalty of the mean-parameter bounds (units of R per (action)²).
    ///
    /// Errors: [`BoundsError::Overflow`] when c(σ) is not representable (σ extremely small).
    #[inline]
    pub fn c(&self) -> Result<f64, BoundsError> {
        let value = match self.c.get() {
            Some(value) => value,
            None => {
                let value = c_value(&self.task, self.sigma);
                self.c.set(Some(value));
                value
            }
        };
        no_overflow("c", value)
    }

    /// d(σ), the penalty of the variance-parameter bounds (units of R per (log-σ)²).
    ///
    /// Errors: [`BoundsError::Overflow`] when d(σ) is not representable.
    #[inline]
    pub fn d(&self) -> Result<f64, BoundsError> {
        let value = match self.d.get() {
            Some(value) => value,
            None => {
                let value = d_value(&self.task, self.sigma);
                self.d.set(Some(value));
                value
            }
        };
        no_overflow("d", value)
    }
}
