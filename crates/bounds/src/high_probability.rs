//! High-probability variants of the update bounds, Theorems 4.7–4.9 (Section 4.5, docs/CONVENTIONS.md §4).
//!
//! The estimated gradients come with a confidence width ε (Assumption 4.6, ε = max_i ε_i):
//! with probability at least 1 − δ per component, |∇ − ∇̂| ≤ ε. The corrected norms are
//! ‖∇̂‖∞⁻ = ‖∇̂‖∞ − ε and ‖∇̂‖∞⁺ = ‖∇̂‖∞ + ε, valid when ‖∇̂‖∞ > ε (eq. (4.23)); otherwise the
//! outcome is [`StepOutcome::BelowNoise`].
//!
//! Every bound is a parabola in the signed step x along the *estimated* direction:
//!
//! ```text
//! thesis form:  B(x) = s·x·a⁻ − x²·b                        (eqs. (4.24), (4.27), Thm 4.9)
//! sign-aware:   B(x) = s·x·a⁻ − x²·b   if s·x ≥ 0
//!               B(x) = −|x|·a⁺ − x²·b   if s·x < 0
//! ```
//!
//! where s is the direction the estimates favour. The thesis form is a valid high-probability
//! bound only for s·x ≥ 0: on the other side the true linear term is only bounded below by
//! −|x|·a⁺. For C < 0 the printed intervals (4.26), (4.29), (4.30) reach that side, so the
//! sign-aware form is the one that keeps the guarantee there.

use crate::constants::TaskConstants;
use crate::error::{BoundsError, finite, finite_vector, inf_norm, no_overflow, non_negative};
use crate::outcome::{SafeInterval, StepOutcome};
use crate::parabola::{Parabola, feasible_sign_aware, solve_sign_aware};
use crate::penalties::Penalties;

/// Lower- and upper-corrected gradient norms of Section 4.5.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CorrectedNorm {
    /// ‖∇̂‖∞⁻ = ‖∇̂‖∞ − ε (> 0).
    pub lower: f64,
    /// ‖∇̂‖∞⁺ = ‖∇̂‖∞ + ε.
    pub upper: f64,
}

/// The corrected norms of an estimated gradient, or `None` when ‖∇̂‖∞ ≤ ε (eq. (4.23) fails).
///
/// # Formula
///
/// ```text
/// ‖∇̂‖∞⁻ = ‖∇̂‖∞ − ε,   ‖∇̂‖∞⁺ = ‖∇̂‖∞ + ε,   ε ≥ 0
/// ```
///
/// ```
/// use sepg_bounds::high_probability::corrected_norm;
/// let n = corrected_norm(&[0.5, -2.0], 0.5)?.unwrap();
/// assert_eq!((n.lower, n.upper), (1.5, 2.5));
/// assert!(corrected_norm(&[0.5], 0.5)?.is_none());
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
#[inline]
pub fn corrected_norm(grad_hat: &[f64], eps: f64) -> Result<Option<CorrectedNorm>, BoundsError> {
    finite_vector("grad_hat", grad_hat)?;
    non_negative("eps", eps)?;
    let n = inf_norm(grad_hat);
    if n <= eps {
        return Ok(None);
    }
    Ok(Some(CorrectedNorm {
        lower: n - eps,
        upper: no_overflow("||grad_hat|| + eps", n + eps)?,
    }))
}

/// Which form of the high-probability interval to compute.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HpForm {
    /// The intervals as printed, (4.26), (4.29), (4.30).
    Thesis,
    /// Valid on both sides of 0: opposite-direction steps use the linear term −|x|·a⁺.
    SignAware,
}

/// A high-probability bound B(x) on the improvement of a step x along the estimated direction.
///
/// Built by [`HighProbabilityBound::v_update`] (Theorem 4.7),
/// [`HighProbabilityBound::w_along_j`] (Theorem 4.8) or [`HighProbabilityBound::w_along_l`]
/// (Theorem 4.9); see the module documentation for the two forms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HighProbabilityBound {
    /// s = ±1, the sign of the steps the estimates favour.
    pub direction: f64,
    /// a⁻ > 0, the guaranteed linear coefficient for favoured steps.
    pub linear_lower: f64,
    /// a⁺ ≥ a⁻, the magnitude of the worst-case linear coefficient for opposite steps.
    pub linear_upper: f64,
    /// b > 0, the quadratic coefficient.
    pub quadratic: f64,
}

impl HighProbabilityBound {
    /// Theorem 4.7 (eq. (4.24)): the greedy-coordinate v-update with an estimated ∇_v J.
    ///
    /// # Formula
    ///
    /// ```text
    /// s = +1,  a⁻ = (‖∇̂_v J‖∞⁻)²,  a⁺ = (‖∇̂_v J‖∞⁺)²,  b = c(σ) (‖∇̂_v J‖∞⁺)²
    /// ```
    ///
    /// `None` when ‖∇̂_v J‖∞ ≤ ε.
    ///
    /// ```
    /// use sepg_bounds::{constants::{TaskConstants, c}, high_probability::HighProbabilityBound};
    /// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
    /// let b = HighProbabilityBound::v_update(&k, 1.0, &[0.3, -0.5], 0.1)?.unwrap();
    /// assert!((b.linear_lower - 0.16).abs() < 1e-15);
    /// assert!((b.quadratic - c(&k, 1.0)? * 0.36).abs() < 1e-14);
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn v_update(
        k: &TaskConstants,
        sigma: f64,
        grad_v_hat: &[f64],
        eps: f64,
    ) -> Result<Option<Self>, BoundsError> {
        Self::v_update_at(&Penalties::new(k, sigma)?, grad_v_hat, eps)
    }

    /// [`Self::v_update`] for penalties evaluated once ([`Penalties`]), with c = `p.c()`.
    #[inline]
    pub fn v_update_at(
        p: &Penalties,
        grad_v_hat: &[f64],
        eps: f64,
    ) -> Result<Option<Self>, BoundsError> {
        let cc = p.c()?;
        let Some(n) = corrected_norm(grad_v_hat, eps)? else {
            return Ok(None);
        };
        Self::squared(n, cc).map(Some)
    }

    /// Theorem 4.8 (eq. (4.27)): the w-update along an estimated ∇_w J.
    ///
    /// # Formula
    ///
    /// ```text
    /// s = +1,  a⁻ = (|∇̂_w J| − ε)²,  a⁺ = (|∇̂_w J| + ε)²,  b = d(σ) (|∇̂_w J| + ε)²
    /// ```
    ///
    /// ```
    /// use sepg_bounds::{constants::{TaskConstants, d}, high_probability::HighProbabilityBound};
    /// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
    /// let b = HighProbabilityBound::w_along_j(&k, 1.0, -0.5, 0.1)?.unwrap();
    /// assert!((b.vertex() - 0.16 / (2.0 * d(&k, 1.0)? * 0.36)).abs() < 1e-15);
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn w_along_j(
        k: &TaskConstants,
        sigma: f64,
        grad_w_j_hat: f64,
        eps: f64,
    ) -> Result<Option<Self>, BoundsError> {
        Self::w_along_j_at(&Penalties::new(k, sigma)?, grad_w_j_hat, eps)
    }

    /// [`Self::w_along_j`] for penalties evaluated once ([`Penalties`]), with d = `p.d()`.
    #[inline]
    pub fn w_along_j_at(
        p: &Penalties,
        grad_w_j_hat: f64,
        eps: f64,
    ) -> Result<Option<Self>, BoundsError> {
        let dd = p.d()?;
        let Some(n) = corrected_norm(&[grad_w_j_hat], eps)? else {
            return Ok(None);
        };
        Self::squared(n, dd).map(Some)
    }

    /// Theorem 4.9: the w-update along an estimated ∇_w L, step β of either sign.
    ///
    /// # Formula
    ///
    /// ```text
    /// s = sign(∇̂_w J · ∇̂_w L),  a⁻ = L⁻ J⁻,  a⁺ = L⁺ J⁺,  b = d(σ) (L⁺)²
    /// ```
    ///
    /// with J^± = |∇̂_w J| ± ε_J and L^± = |∇̂_w L| ± ε_L. `None` when either estimate is within
    /// its width.
    ///
    /// ```
    /// use sepg_bounds::{constants::TaskConstants, high_probability::HighProbabilityBound};
    /// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
    /// let b = HighProbabilityBound::w_along_l(&k, 1.0, 0.5, 0.1, -2.0, 0.5)?.unwrap();
    /// assert_eq!(b.direction, -1.0);
    /// assert!((b.linear_lower - 0.6).abs() < 1e-15 && (b.linear_upper - 1.5).abs() < 1e-15);
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn w_along_l(
        k: &TaskConstants,
        sigma: f64,
        grad_w_j_hat: f64,
        eps_j: f64,
        grad_w_l_hat: f64,
        eps_l: f64,
    ) -> Result<Option<Self>, BoundsError> {
        Self::w_along_l_at(
            &Penalties::new(k, sigma)?,
            grad_w_j_hat,
            eps_j,
            grad_w_l_hat,
            eps_l,
        )
    }

    /// [`Self::w_along_l`] for penalties evaluated once ([`Penalties`]), with d = `p.d()`.
    #[inline]
    pub fn w_along_l_at(
        p: &Penalties,
        grad_w_j_hat: f64,
        eps_j: f64,
        grad_w_l_hat: f64,
        eps_l: f64,
    ) -> Result<Option<Self>, BoundsError> {
        let dd = p.d()?;
        let nj = corrected_norm(&[grad_w_j_hat], eps_j)?;
        let nl = corrected_norm(&[grad_w_l_hat], eps_l)?;
        let (Some(nj), Some(nl)) = (nj, nl) else {
            return Ok(None);
        };
        let direction = if (grad_w_j_hat > 0.0) == (grad_w_l_hat > 0.0) {
            1.0
        } else {
            -1.0
        };
        Self {
            direction,
            linear_lower: no_overflow("L- J-", nl.lower * nj.lower)?,
            linear_upper: no_overflow("L+ J+", nl.upper * nj.upper)?,
            quadratic: no_overflow("d (L+)^2", dd * nl.upper * nl.upper)?,
        }
        .representable()
        .map(Some)
    }

    /// The bound with squared corrected norms (Theorems 4.7 and 4.8) and penalty `k`.
    #[inline]
    fn squared(n: CorrectedNorm, k: f64) -> Result<Self, BoundsError> {
        let up2 = no_overflow("(||grad||+)^2", n.upper * n.upper)?;
        Self {
            direction: 1.0,
            linear_lower: n.lower * n.lower,
            linear_upper: up2,
            quadratic: no_overflow("bound quadratic coefficient", k * up2)?,
        }
        .representable()
    }

    /// Checks that the vertex and C_max are finite: with tiny task constants or estimates the
    /// quadratic coefficient b can underflow to 0 (or a⁻/(2b) overflow) although the exact
    /// values are positive, which would make [`Self::vertex`] and [`Self::c_max`] NaN or ∞.
    #[inline]
    fn representable(self) -> Result<Self, BoundsError> {
        no_overflow("step-size vertex", self.vertex())?;
        no_overflow("C_max", self.c_max())?;
        Ok(self)
    }

    /// The thesis-form bound at the signed step x (valid for s·x ≥ 0).
    ///
    /// # Formula
    ///
    /// ```text
    /// B(x) = s·x·a⁻ − x²·b
    /// ```
    ///
    /// ```
    /// use sepg_bounds::high_probability::HighProbabilityBound;
    /// let b = HighProbabilityBound { direction: 1.0, linear_lower: 1.0, linear_upper: 4.0, quadratic: 2.0 };
    /// assert_eq!(b.value(0.5)?, 0.0);
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn value(&self, x: f64) -> Result<f64, BoundsError> {
        finite("step", x)?;
        no_overflow(
            "high-probability bound",
            self.direction * x * self.linear_lower - x * x * self.quadratic,
        )
    }

    /// The sign-aware bound at the signed step x, valid on both sides of 0.
    ///
    /// # Formula
    ///
    /// ```text
    /// B(x) = s·x·a⁻ − x²·b  if s·x ≥ 0,     −|x|·a⁺ − x²·b  otherwise
    /// ```
    ///
    /// ```
    /// use sepg_bounds::high_probability::HighProbabilityBound;
    /// let b = HighProbabilityBound { direction: 1.0, linear_lower: 1.0, linear_upper: 4.0, quadratic: 2.0 };
    /// assert_eq!(b.sign_aware_value(-0.5)?, -2.5);
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn sign_aware_value(&self, x: f64) -> Result<f64, BoundsError> {
        finite("step", x)?;
        let linear = if self.direction * x >= 0.0 {
            self.direction * x * self.linear_lower
        } else {
            -x.abs() * self.linear_upper
        };
        no_overflow("high-probability bound", linear - x * x * self.quadratic)
    }

    /// The step of maximal guaranteed improvement (the vertex of both forms).
    ///
    /// # Formula
    ///
    /// ```text
    /// x* = s·a⁻ / (2b)    e.g. α* = (‖∇̂‖∞⁻)² / (2c (‖∇̂‖∞⁺)²),
    ///                          β̃ = s L⁻J⁻ / (2d (L⁺)²)
    /// ```
    ///
    /// ```
    /// use sepg_bounds::high_probability::HighProbabilityBound;
    /// let b = HighProbabilityBound { direction: -1.0, linear_lower: 1.0, linear_upper: 4.0, quadratic: 2.0 };
    /// assert_eq!(b.vertex(), -0.25);
    /// ```
    #[inline]
    pub fn vertex(&self) -> f64 {
        self.direction * self.linear_lower / (2.0 * self.quadratic)
    }

    /// The largest guaranteed improvement.
    ///
    /// # Formula
    ///
    /// ```text
    /// C_max = (a⁻)² / (4b)   e.g. (‖∇̂‖∞⁻)⁴ / (4c (‖∇̂‖∞⁺)²),   (L⁻J⁻)² / (4d (L⁺)²)
    /// ```
    ///
    /// ```
    /// use sepg_bounds::high_probability::HighProbabilityBound;
    /// let b = HighProbabilityBound { direction: 1.0, linear_lower: 1.0, linear_upper: 4.0, quadratic: 2.0 };
    /// assert_eq!(b.c_max(), 0.125);
    /// ```
    #[inline]
    pub fn c_max(&self) -> f64 {
        self.linear_lower * (self.linear_lower / (2.0 * self.quadratic)) / 2.0
    }

    /// The safe steps for a required improvement C in the requested form.
    ///
    /// # Formula
    ///
    /// ```text
    /// Thesis:    |x − x*| ≤ λ|x*|,  λ = √(1 − C/C_max)           ((4.26), (4.29), (4.30))
    /// SignAware: favoured side as above; for C < 0 the opposite side reaches
    ///            |x| ≤ −2C / (a⁺ + √((a⁺)² − 4bC))
    /// ```
    ///
    /// ```
    /// use sepg_bounds::high_probability::{HighProbabilityBound, HpForm};
    /// use sepg_bounds::outcome::StepOutcome;
    /// let b = HighProbabilityBound { direction: 1.0, linear_lower: 1.0, linear_upper: 4.0, quadratic: 2.0 };
    /// let StepOutcome::Feasible(t) = b.safe_step(-1.0, HpForm::Thesis)? else { panic!() };
    /// let StepOutcome::Feasible(s) = b.safe_step(-1.0, HpForm::SignAware)? else { panic!() };
    /// assert_eq!(t.hi, s.hi);
    /// assert!(s.lo > t.lo); // fewer negative steps are safe
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    #[inline]
    pub fn safe_step(&self, required: f64, form: HpForm) -> Result<StepOutcome, BoundsError> {
        finite("required", required)?;
        match form {
            HpForm::Thesis => {
                Parabola::new(self.direction * self.linear_lower, self.quadratic).solve(required)
            }
            HpForm::SignAware => solve_sign_aware(
                self.direction,
                self.linear_lower,
                self.linear_upper,
                self.quadratic,
                required,
            ),
        }
    }

    /// The interval of [`Self::safe_step`] when it returns a feasible one, bit for bit, else
    /// `None` (see [`Parabola::feasible`]).
    #[inline(always)]
    pub fn feasible_step(&self, required: f64, form: HpForm) -> Option<SafeInterval> {
        match form {
            HpForm::Thesis => {
                Parabola::new(self.direction * self.linear_lower, self.quadratic).feasible(required)
            }
            HpForm::SignAware => feasible_sign_aware(
                self.direction,
                self.linear_lower,
                self.linear_upper,
                self.quadratic,
                required,
            ),
        }
    }
}

/// The safe steps of `bound` for the requirement C = `required` in the form `form`
/// ([`HighProbabilityBound::safe_step`]), or [`StepOutcome::BelowNoise`] when there is no
/// bound because the estimate is within its confidence width (eq. (4.23) fails).
#[inline]
pub(crate) fn safe_step_or_below_noise(
    bound: Option<HighProbabilityBound>,
    required: f64,
    form: HpForm,
) -> Result<StepOutcome, BoundsError> {
    match bound {
        Some(b) => b.safe_step(required, form),
        None => Ok(StepOutcome::BelowNoise),
    }
}

/// Safe steps of Theorem 4.7 (eq. (4.26)) for an estimated ∇_v J, or
/// [`StepOutcome::BelowNoise`].
///
/// # Formula
///
/// ```text
/// α* = (‖∇̂‖∞⁻)² / (2c (‖∇̂‖∞⁺)²),  C_max^v = (‖∇̂‖∞⁻)⁴ / (4c (‖∇̂‖∞⁺)²),
/// |α − α*| ≤ λ_v α*,  λ_v = √(1 − C/C_max^v)
/// ```
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, high_probability::{v_safe_step, HpForm}};
/// use sepg_bounds::outcome::StepOutcome;
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// assert_eq!(v_safe_step(&k, 1.0, &[0.05], 0.1, 0.0, HpForm::Thesis)?, StepOutcome::BelowNoise);
/// assert!(v_safe_step(&k, 1.0, &[0.5], 0.1, 0.0, HpForm::Thesis)?.is_feasible());
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn v_safe_step(
    k: &TaskConstants,
    sigma: f64,
    grad_v_hat: &[f64],
    eps: f64,
    required: f64,
    form: HpForm,
) -> Result<StepOutcome, BoundsError> {
    finite("required", required)?;
    safe_step_or_below_noise(
        HighProbabilityBound::v_update(k, sigma, grad_v_hat, eps)?,
        required,
        form,
    )
}

/// [`v_safe_step`] for penalties evaluated once ([`Penalties`]), with the
/// penalty of their family; the same errors, without validating σ again.
pub fn v_safe_step_at(
    p: &Penalties,
    grad_v_hat: &[f64],
    eps: f64,
    required: f64,
    form: HpForm,
) -> Result<StepOutcome, BoundsError> {
    finite("required", required)?;
    safe_step_or_below_noise(
        HighProbabilityBound::v_update_at(p, grad_v_hat, eps)?,
        required,
        form,
    )
}

/// Safe steps of Theorem 4.8 (eq. (4.29)) along an estimated ∇_w J, or
/// [`StepOutcome::BelowNoise`].
///
/// # Formula
///
/// ```text
/// β* = (J⁻)² / (2d (J⁺)²),  C_max^w = (J⁻)⁴ / (4d (J⁺)²),  |β − β*| ≤ λ_w β*
/// ```
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, high_probability::{w_safe_step_along_j, HpForm}};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// assert!(w_safe_step_along_j(&k, 1.0, 0.5, 0.1, 0.0, HpForm::SignAware)?.is_feasible());
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn w_safe_step_along_j(
    k: &TaskConstants,
    sigma: f64,
    grad_w_j_hat: f64,
    eps: f64,
    required: f64,
    form: HpForm,
) -> Result<StepOutcome, BoundsError> {
    finite("required", required)?;
    safe_step_or_below_noise(
        HighProbabilityBound::w_along_j(k, sigma, grad_w_j_hat, eps)?,
        required,
        form,
    )
}

/// [`w_safe_step_along_j`] for penalties evaluated once ([`Penalties`]), with the
/// penalty of their family; the same errors, without validating σ again.
pub fn w_safe_step_along_j_at(
    p: &Penalties,
    grad_w_j_hat: f64,
    eps: f64,
    required: f64,
    form: HpForm,
) -> Result<StepOutcome, BoundsError> {
    finite("required", required)?;
    safe_step_or_below_noise(
        HighProbabilityBound::w_along_j_at(p, grad_w_j_hat, eps)?,
        required,
        form,
    )
}

/// Safe steps of Theorem 4.9 (eq. (4.30)) along an estimated ∇_w L, or
/// [`StepOutcome::BelowNoise`].
///
/// # Formula
///
/// ```text
/// β̃ = sign(∇̂J ∇̂L) L⁻J⁻ / (2d (L⁺)²),  C_max^w = (L⁻J⁻)² / (4d (L⁺)²),
/// |β − β̃| ≤ λ_w |β̃|
/// ```
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, high_probability::{w_safe_step_along_l, HpForm}};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let o = w_safe_step_along_l(&k, 1.0, 0.5, 0.1, -2.0, 0.5, -0.01, HpForm::SignAware)?;
/// assert!(o.chosen_step().unwrap() > 0.0);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
#[allow(clippy::too_many_arguments)]
pub fn w_safe_step_along_l(
    k: &TaskConstants,
    sigma: f64,
    grad_w_j_hat: f64,
    eps_j: f64,
    grad_w_l_hat: f64,
    eps_l: f64,
    required: f64,
    form: HpForm,
) -> Result<StepOutcome, BoundsError> {
    finite("required", required)?;
    safe_step_or_below_noise(
        HighProbabilityBound::w_along_l(k, sigma, grad_w_j_hat, eps_j, grad_w_l_hat, eps_l)?,
        required,
        form,
    )
}

/// [`w_safe_step_along_l`] for penalties evaluated once ([`Penalties`]), with the
/// penalty of their family; the same errors, without validating σ again.
pub fn w_safe_step_along_l_at(
    p: &Penalties,
    grad_w_j_hat: f64,
    eps_j: f64,
    grad_w_l_hat: f64,
    eps_l: f64,
    required: f64,
    form: HpForm,
) -> Result<StepOutcome, BoundsError> {
    finite("required", required)?;
    safe_step_or_below_noise(
        HighProbabilityBound::w_along_l_at(p, grad_w_j_hat, eps_j, grad_w_l_hat, eps_l)?,
        required,
        form,
    )
}
