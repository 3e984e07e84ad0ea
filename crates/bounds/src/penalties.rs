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
//! The [`Family`] says which formulas give c and d. Only the thesis family exists today;
//! another family adds a variant here and its formulas in [`Penalties::c`] and
//! [`Penalties::d`], and every bound built on a [`Penalties`] follows.

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
}

/// The penalty coefficients of a task at one standard deviation σ, for one [`Family`]:
/// σ is validated once, and c(σ), d(σ) are each computed on first use and kept.
///
/// ```
/// use sepg_bounds::constants::{self, TaskConstants};
/// use sepg_bounds::penalties::{Family, Penalties};
/// let k = TaskConstants::new(0.99, 4.0, 2.0, 4.0)?;
/// let p = Penalties::new(&k, Family::Thesis, 0.5)?;
/// assert_eq!(p.c()?, constants::c(&k, 0.5)?);
/// assert_eq!(p.d()?, constants::d(&k, 0.5)?);
/// assert!(Penalties::new(&k, Family::Thesis, 0.0).is_err());
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Penalties {
    task: TaskConstants,
    family: Family,
    sigma: f64,
    c: Cell<Option<f64>>,
    d: Cell<Option<f64>>,
}

impl Penalties {
    /// The coefficients of `family` for the task `k` at standard deviation `sigma` (action
    /// units).
    ///
    /// Errors: σ not finite and strictly positive (the error of [`crate::constants::c`]).
    #[inline]
    pub fn new(k: &TaskConstants, family: Family, sigma: f64) -> Result<Self, BoundsError> {
        Ok(Self {
            task: *k,
            family,
            sigma: positive("sigma", sigma)?,
            c: Cell::new(None),
            d: Cell::new(None),
        })
    }

    /// [`Penalties::new`] for the thesis family.
    ///
    /// ```
    /// use sepg_bounds::{constants::TaskConstants, penalties::{Family, Penalties}};
    /// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
    /// assert_eq!(Penalties::thesis(&k, 1.0)?.family(), Family::Thesis);
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    #[inline]
    pub fn thesis(k: &TaskConstants, sigma: f64) -> Result<Self, BoundsError> {
        Self::new(k, Family::Thesis, sigma)
    }

    /// The task constants.
    pub fn task(&self) -> &TaskConstants {
        &self.task
    }

    /// The family of the coefficients.
    pub fn family(&self) -> Family {
        self.family
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
                let value = match self.family {
                    Family::Thesis => c_value(&self.task, self.sigma),
                };
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
                let value = match self.family {
                    Family::Thesis => d_value(&self.task, self.sigma),
                };
                self.d.set(Some(value));
                value
            }
        };
        no_overflow("d", value)
    }
}
