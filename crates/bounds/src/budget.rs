//! The safety budget of type-II safety (Definition 4.3, Theorem 4.1) and the split of a
//! required improvement between the v- and w-updates (eqs. (4.13), (4.14)).

use crate::error::{BoundsError, finite, no_overflow, unit_closed};

/// Splits a required improvement C between the v-update and the w-update.
///
/// # Formula
///
/// ```text
/// (C_v, C_w) = ((1 − ν) C, ν C),   ν ∈ [0, 1]      (eqs. (4.13), (4.14))
/// ```
///
/// ```
/// use sepg_bounds::budget::split_requirement;
/// assert_eq!(split_requirement(-2.0, 0.25)?, (-1.5, -0.5));
/// assert!(split_requirement(1.0, 1.5).is_err());
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn split_requirement(required: f64, nu: f64) -> Result<(f64, f64), BoundsError> {
    finite("required", required)?;
    unit_closed("nu", nu)?;
    Ok(((1.0 - nu) * required, nu * required))
}

/// The budget B of Definition 4.3, tracked from measured performance differences.
///
/// B^t = B⁰ + Σ ΔJ_E + Σ ΔJ_T, which telescopes to B^t − B⁰ = J_E^t − J_E⁰ + J_T^t − J_T⁰
/// (proof of Theorem 4.1). The budget may track only the exploratory policy (θ_T ≡ θ_E, as in
/// SEPG-II / LB-II, Algorithm 4.2), in which case each difference is counted once and the
/// baseline is J_E⁰.
#[derive(Debug, Clone, PartialEq)]
pub struct Budget {
    initial: f64,
    value: f64,
    exploratory_start: f64,
    exploratory: f64,
    target: Option<(f64, f64)>,
}

impl Budget {
    /// A budget starting at B⁰ = `initial` with starting performances J_E⁰ and (optionally)
    /// J_T⁰ of the target policy (Algorithm 4.3, lines 2–3).
    ///
    /// Errors: an input not finite; [`BoundsError::Overflow`] if the baseline or another
    /// reported quantity overflows (performances near ±f64::MAX).
    ///
    /// ```
    /// use sepg_bounds::budget::Budget;
    /// let b = Budget::new(1.0, -10.0, Some(-8.0))?;
    /// assert_eq!((b.value(), b.baseline()), (1.0, -9.0));
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn new(
        initial: f64,
        j_exploratory: f64,
        j_target: Option<f64>,
    ) -> Result<Self, BoundsError> {
        finite("initial budget", initial)?;
        finite("J_E", j_exploratory)?;
        let target = match j_target {
            Some(t) => Some((finite("J_T", t)?, t)),
            None => None,
        };
        Self {
            initial,
            value: initial,
            exploratory_start: j_exploratory,
            exploratory: j_exploratory,
            target,
        }
        .checked()
    }

    /// `self` if every quantity the budget reports is finite: finite performances near
    /// ±f64::MAX can still overflow in the sums behind [`Self::baseline`],
    /// [`Self::average_performance`], [`Self::telescoped_change`] and
    /// [`Self::guaranteed_average`]. Every constructor and update goes through it, so a
    /// budget never holds a state whose reported values are not finite.
    fn checked(self) -> Result<Self, BoundsError> {
        let reported = [
            self.baseline(),
            self.average_performance(),
            self.telescoped_change(),
            self.guaranteed_average(),
        ];
        if reported.iter().all(|x| x.is_finite()) {
            Ok(self)
        } else {
            Err(BoundsError::Overflow {
                quantity: "budget baseline, average or change",
            })
        }
    }

    /// Adds a measured difference ΔJ_E = J(θ_E') − J(θ_E) (v- or w-budget update,
    /// Algorithm 4.3 lines 9 and 18).
    ///
    /// # Formula
    ///
    /// ```text
    /// B ← B + ΔJ_E,   J_E ← J_E + ΔJ_E
    /// ```
    ///
    /// Errors: ΔJ_E not finite; [`BoundsError::Overflow`] (budget unchanged) if the budget or
    /// a reported quantity would overflow.
    ///
    /// ```
    /// use sepg_bounds::budget::Budget;
    /// let mut b = Budget::new(0.0, -10.0, None)?;
    /// b.add_exploratory_difference(0.5)?;
    /// assert_eq!(b.value(), 0.5);
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn add_exploratory_difference(&mut self, delta: f64) -> Result<(), BoundsError> {
        finite("delta J_E", delta)?;
        let value = no_overflow("budget", self.value + delta)?;
        let exploratory = no_overflow("J_E", self.exploratory + delta)?;
        *self = Self {
            value,
            exploratory,
            ..self.clone()
        }
        .checked()?;
        Ok(())
    }

    /// Adds a measured difference ΔJ_T of the target policy (Algorithm 4.3 line 12).
    ///
    /// # Formula
    ///
    /// ```text
    /// B ← B + ΔJ_T,   J_T ← J_T + ΔJ_T
    /// ```
    ///
    /// Errors: [`BoundsError::NoTargetPolicy`] if the budget tracks no target;
    /// [`BoundsError::Overflow`] (budget unchanged) if a reported quantity would overflow.
    ///
    /// ```
    /// use sepg_bounds::budget::Budget;
    /// let mut b = Budget::new(0.0, -10.0, Some(-8.0))?;
    /// b.add_target_difference(-0.25)?;
    /// assert_eq!(b.value(), -0.25);
    /// assert!(Budget::new(0.0, -10.0, None)?.add_target_difference(1.0).is_err());
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn add_target_difference(&mut self, delta: f64) -> Result<(), BoundsError> {
        finite("delta J_T", delta)?;
        let (start, current) = self.target.ok_or(BoundsError::NoTargetPolicy)?;
        let value = no_overflow("budget", self.value + delta)?;
        let target = no_overflow("J_T", current + delta)?;
        *self = Self {
            value,
            target: Some((start, target)),
            ..self.clone()
        }
        .checked()?;
        Ok(())
    }

    /// Records a new measurement J_E of the exploratory policy and returns the difference
    /// added to the budget.
    ///
    /// # Formula
    ///
    /// ```text
    /// ΔJ_E = J_E(new) − J_E(last);  B ← B + ΔJ_E
    /// ```
    ///
    /// ```
    /// use sepg_bounds::budget::Budget;
    /// let mut b = Budget::new(0.0, -10.0, None)?;
    /// assert_eq!(b.record_exploratory(-9.0)?, 1.0);
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn record_exploratory(&mut self, j: f64) -> Result<f64, BoundsError> {
        finite("J_E", j)?;
        let delta = no_overflow("delta J_E", j - self.exploratory)?;
        let mut next = self.clone();
        next.add_exploratory_difference(delta)?;
        next.exploratory = j;
        *self = next.checked()?;
        Ok(delta)
    }

    /// Records a new measurement J_T of the target policy and returns the difference added.
    ///
    /// # Formula
    ///
    /// ```text
    /// ΔJ_T = J_T(new) − J_T(last);  B ← B + ΔJ_T
    /// ```
    ///
    /// ```
    /// use sepg_bounds::budget::Budget;
    /// let mut b = Budget::new(0.0, -10.0, Some(-8.0))?;
    /// assert_eq!(b.record_target(-8.5)?, -0.5);
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn record_target(&mut self, j: f64) -> Result<f64, BoundsError> {
        finite("J_T", j)?;
        let (start, current) = self.target.ok_or(BoundsError::NoTargetPolicy)?;
        let delta = no_overflow("delta J_T", j - current)?;
        let mut next = self.clone();
        next.add_target_difference(delta)?;
        next.target = Some((start, j));
        *self = next.checked()?;
        Ok(delta)
    }

    /// The current budget B^t.
    ///
    /// ```
    /// use sepg_bounds::budget::Budget;
    /// assert_eq!(Budget::new(2.0, 0.0, None)?.value(), 2.0);
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn value(&self) -> f64 {
        self.value
    }

    /// The initial budget B⁰.
    ///
    /// ```
    /// use sepg_bounds::budget::Budget;
    /// assert_eq!(Budget::new(2.0, 0.0, None)?.initial(), 2.0);
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn initial(&self) -> f64 {
        self.initial
    }

    /// The required improvement of the next update, C = −B (Table 4.1).
    ///
    /// ```
    /// use sepg_bounds::budget::Budget;
    /// assert_eq!(Budget::new(2.0, 0.0, None)?.required_improvement(), -2.0);
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn required_improvement(&self) -> f64 {
        -self.value
    }

    /// The number of tracked policies k (2 with a target, 1 without).
    fn policies(&self) -> f64 {
        if self.target.is_some() { 2.0 } else { 1.0 }
    }

    /// The constant baseline J_B of Theorem 4.1.
    ///
    /// # Formula
    ///
    /// ```text
    /// J_B = (J_E⁰ + J_T⁰) / 2     (J_B = J_E⁰ without a target policy)
    /// ```
    ///
    /// ```
    /// use sepg_bounds::budget::Budget;
    /// assert_eq!(Budget::new(0.0, -4.0, Some(-2.0))?.baseline(), -3.0);
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn baseline(&self) -> f64 {
        let start = self.exploratory_start + self.target.map_or(0.0, |(s, _)| s);
        start / self.policies()
    }

    /// The current average performance (J_E^t + J_T^t)/2 (J_E^t without a target policy),
    /// from the recorded measurements.
    ///
    /// ```
    /// use sepg_bounds::budget::Budget;
    /// let mut b = Budget::new(0.0, -4.0, Some(-2.0))?;
    /// b.record_exploratory(-3.0)?;
    /// assert_eq!(b.average_performance(), -2.5);
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn average_performance(&self) -> f64 {
        let now = self.exploratory + self.target.map_or(0.0, |(_, t)| t);
        now / self.policies()
    }

    /// The telescoped change J_E^t − J_E⁰ + J_T^t − J_T⁰, equal to B^t − B⁰ up to rounding
    /// (proof of Theorem 4.1).
    ///
    /// ```
    /// use sepg_bounds::budget::Budget;
    /// let mut b = Budget::new(1.0, -4.0, Some(-2.0))?;
    /// b.record_exploratory(-3.0)?;
    /// b.record_target(-2.5)?;
    /// assert_eq!(b.telescoped_change(), b.value() - b.initial());
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn telescoped_change(&self) -> f64 {
        let target = self.target.map_or(0.0, |(s, t)| t - s);
        self.exploratory - self.exploratory_start + target
    }

    /// The performance level guaranteed by Theorem 4.1 while B^t ≥ 0.
    ///
    /// # Formula
    ///
    /// ```text
    /// B^t ≥ 0  ⇒  (J_E^t + J_T^t)/2 ≥ J_B − B⁰/2      (J_E^t ≥ J_E⁰ − B⁰ without target)
    /// ```
    ///
    /// ```
    /// use sepg_bounds::budget::Budget;
    /// assert_eq!(Budget::new(1.0, -4.0, Some(-2.0))?.guaranteed_average(), -3.5);
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn guaranteed_average(&self) -> f64 {
        self.baseline() - self.initial / self.policies()
    }

    /// Whether B^t ≥ 0, the condition of Theorem 4.1 for type-II safety.
    ///
    /// ```
    /// use sepg_bounds::budget::Budget;
    /// let mut b = Budget::new(0.0, -4.0, None)?;
    /// b.record_exploratory(-4.5)?;
    /// assert!(!b.is_type_two_safe());
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn is_type_two_safe(&self) -> bool {
        self.value >= 0.0
    }
}
