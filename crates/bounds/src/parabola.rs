//! The concave parabola through the origin that every step-size bound of Chapter 4 is, and its
//! solver.
//!
//! As a function of the step x, each guaranteed-improvement bound of Theorems 4.2, 4.3, 4.5 and
//! 4.7–4.9 is p(x) = a·x − b·x² (b ≥ 0) on each side of x = 0. For a required improvement C the
//! safe steps are {x : p(x) ≥ C}; [`Parabola::solve`] solves that inequality once, robustly, and
//! [`Parabola::feasible`] returns the same interval, bit for bit, without error values (for
//! callers that keep it in registers, such as the certified steps of the `sepg-certified`
//! crate). The theorem modules build their parabolas (e.g. [`crate::v_update::parabola`]).

use crate::error::{BoundsError, no_overflow};
use crate::outcome::{SafeInterval, StepOutcome};

/// The parabola B(x) = a·x − b·x² of a step-size bound, with a = `linear` and b = `quadratic`
/// (b ≥ 0 for a bound; performance units per step unit and per squared step unit).
///
/// ```
/// use sepg_bounds::{parabola::Parabola, outcome::StepOutcome};
/// let p = Parabola::new(1.0, 2.0);
/// assert_eq!(p.vertex_and_c_max()?, (0.25, 0.125));
/// let StepOutcome::Feasible(s) = p.solve(0.0)? else { panic!("C = 0 is feasible") };
/// assert_eq!((s.lo, s.hi), (0.0, 0.5));
/// assert_eq!(p.feasible(0.0), Some(s));
/// assert!(matches!(p.solve(0.2)?, StepOutcome::Infeasible { .. }));
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Parabola {
    /// a, the linear coefficient.
    pub linear: f64,
    /// b, the quadratic coefficient.
    pub quadratic: f64,
}

impl Parabola {
    /// The parabola a·x − b·x² with a = `linear`, b = `quadratic` (not validated: [`Self::solve`]
    /// checks the coefficients).
    #[inline(always)]
    pub const fn new(linear: f64, quadratic: f64) -> Self {
        Self { linear, quadratic }
    }

    /// The vertex a/(2b) and the maximum C_max = a²/(4b) (b > 0), computed in one place so
    /// that a C_max reported by one function is accepted by another.
    ///
    /// Errors: [`BoundsError::Overflow`] when either is not finite.
    #[inline]
    pub fn vertex_and_c_max(&self) -> Result<(f64, f64), BoundsError> {
        vertex_and_c_max(self.linear, self.quadratic)
    }

    /// C_max = a²/(4b), and 0 when a = b = 0 (zero gradient).
    ///
    /// Errors: [`BoundsError::Overflow`] when b ≤ 0 with a ≠ 0 (an underflowed b) or C_max
    /// is not finite.
    ///
    /// ```
    /// use sepg_bounds::parabola::Parabola;
    /// assert_eq!(Parabola::new(1.0, 2.0).c_max()?, 0.125);
    /// assert_eq!(Parabola::new(0.0, 0.0).c_max()?, 0.0);
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    #[inline]
    pub fn c_max(&self) -> Result<f64, BoundsError> {
        quadratic_c_max(self.linear, self.quadratic)
    }

    /// The safe steps {x : a·x − b·x² ≥ C} for the requirement C = `required` (finite).
    ///
    /// Uses the numerically stable pair of roots (the small root from the product of the
    /// roots, C/b) so that both end points are accurate even when |C| ≪ C_max. A requirement
    /// above C_max by at most 8 ulps (rounding, e.g. C_max computed by another formula) is
    /// treated as C = C_max. Outcomes: [`StepOutcome::ZeroGradient`] when a = b = 0,
    /// [`StepOutcome::Infeasible`] when C > C_max, else [`StepOutcome::Feasible`].
    ///
    /// Errors: [`BoundsError::Overflow`] when a coefficient, the vertex, C_max or an end point
    /// is not finite, or b ≤ 0 with a ≠ 0.
    #[inline]
    pub fn solve(&self, required: f64) -> Result<StepOutcome, BoundsError> {
        solve_quadratic(self.linear, self.quadratic, required)
    }

    /// The interval of `Ok(StepOutcome::Feasible(_))` when [`Self::solve`] returns one, bit
    /// for bit, and `None` for every other outcome (zero gradient, C > C_max, an error). It
    /// returns no error values, so that a caller that inlines it keeps the interval in
    /// registers.
    #[inline(always)]
    pub fn feasible(&self, required: f64) -> Option<SafeInterval> {
        feasible_interval(self.linear, self.quadratic, required)
    }
}

/// Vertex a/(2b) and maximum a²/(4b) of a·x − b·x² (b > 0), the single place where every
/// module computes them, so that a C_max reported by one function is accepted by another.
fn vertex_and_c_max(a: f64, b: f64) -> Result<(f64, f64), BoundsError> {
    let (vertex, c_max) = vertex_and_c_max_unchecked(a, b);
    no_overflow("step-size vertex", vertex)?;
    Ok((vertex, no_overflow("C_max", c_max)?))
}

/// [`vertex_and_c_max`] without the overflow checks.
#[inline(always)]
fn vertex_and_c_max_unchecked(a: f64, b: f64) -> (f64, f64) {
    let vertex = a / (2.0 * b);
    (vertex, a * vertex / 2.0)
}

/// C_max = a²/(4b) of a·x − b·x², 0 when a = b = 0 (zero gradient).
fn quadratic_c_max(a: f64, b: f64) -> Result<f64, BoundsError> {
    if a == 0.0 && b == 0.0 {
        return Ok(0.0);
    }
    if b <= 0.0 {
        return Err(BoundsError::Overflow { quantity: "C_max" });
    }
    Ok(vertex_and_c_max(a, b)?.1)
}

/// Relative slack within which C > C_max is attributed to rounding and treated as C = C_max.
const ROUNDING_SLACK: f64 = 8.0 * f64::EPSILON;

/// Whether C exceeds C_max by more than the rounding slack: the requirement is infeasible.
#[inline(always)]
fn beyond_c_max(required: f64, c_max: f64) -> bool {
    required > c_max + ROUNDING_SLACK * c_max.abs()
}

/// Solves a·x − b·x² ≥ C for x (b ≥ 0, all inputs finite).
///
/// Uses the numerically stable pair of roots (the small root from the product of the roots,
/// C/b) so that both end points are accurate even when |C| ≪ C_max. A requirement above
/// C_max by at most 8 ulps (rounding, e.g. C_max computed by another formula) is treated as
/// C = C_max.
#[inline]
fn solve_quadratic(a: f64, b: f64, required: f64) -> Result<StepOutcome, BoundsError> {
    no_overflow("bound coefficient", a)?;
    no_overflow("bound coefficient", b)?;
    if a == 0.0 && b == 0.0 {
        return Ok(StepOutcome::ZeroGradient {
            requirement_met: required <= 0.0,
        });
    }
    if b <= 0.0 {
        // Linear term without curvature: only reachable through underflow of b.
        return Err(BoundsError::Overflow {
            quantity: "step-size vertex",
        });
    }
    let (vertex, c_max) = vertex_and_c_max(a, b)?;
    if beyond_c_max(required, c_max) {
        return Ok(StepOutcome::Infeasible { c_max, vertex });
    }
    let (half, s) = interval_parts(a, b, vertex, c_max, required);
    no_overflow("safe-step interval", half)?;
    Ok(StepOutcome::Feasible(SafeInterval {
        lambda: s.lambda.map(|l| no_overflow("lambda", l)).transpose()?,
        lo: no_overflow("safe-step interval", s.lo)?,
        hi: no_overflow("safe-step interval", s.hi)?,
        ..s
    }))
}

/// The safe interval of a·x − b·x² ≥ C (b > 0) for its vertex and C_max, with C ≤ C_max(1 +
/// 8ε) clamped to C_max: the half-width √((C_max − C)/b) and the interval, unchecked (the
/// callers check that the values are finite). The arithmetic shared by [`solve_quadratic`]
/// and [`feasible_interval`].
#[inline(always)]
fn interval_parts(a: f64, b: f64, vertex: f64, c_max: f64, required: f64) -> (f64, SafeInterval) {
    let required = required.min(c_max);
    let half = ((c_max - required) / b).sqrt();
    let (lo, hi) = if a > 0.0 {
        let hi = vertex + half;
        (required / (b * hi), hi)
    } else if a < 0.0 {
        let lo = vertex - half;
        (lo, required / (b * lo))
    } else {
        (-half, half)
    };
    // lo ≤ vertex ≤ hi exactly; the quotient C/(b·x) can land an ulp past the vertex when
    // C = C_max, and many ulps when C_max is subnormal.
    let (lo, hi) = (lo.min(vertex), hi.max(vertex));
    let lambda = (c_max > 0.0).then(|| (1.0 - required / c_max).max(0.0).sqrt());
    (
        half,
        SafeInterval {
            c_max,
            vertex,
            lambda,
            lo,
            hi,
        },
    )
}

/// The interval of `Ok(StepOutcome::Feasible(_))` when [`solve_quadratic`] returns one, bit
/// for bit, and `None` for every other outcome (zero gradient, C > C_max, an error). It
/// returns no error values, so that a caller that inlines it keeps the interval in
/// registers: the certified steps' fast path, which falls back to [`solve_quadratic`] on
/// `None`.
#[inline(always)]
fn feasible_interval(a: f64, b: f64, required: f64) -> Option<SafeInterval> {
    // b > 0 finite and a finite; a = b = 0 (zero gradient) fails b > 0
    if !(a.is_finite() && b > 0.0 && b <= f64::MAX && required.is_finite()) {
        return None;
    }
    let (vertex, c_max) = vertex_and_c_max_unchecked(a, b);
    if !(vertex.is_finite() && c_max.is_finite()) || beyond_c_max(required, c_max) {
        return None;
    }
    let (half, s) = interval_parts(a, b, vertex, c_max, required);
    let finite = half.is_finite()
        && s.lo.is_finite()
        && s.hi.is_finite()
        && s.lambda.is_none_or(f64::is_finite);
    finite.then_some(s)
}

/// Solves the sign-aware high-probability inequality.
///
/// Steps x = s·t (t ≥ 0) in the favoured direction s = ±1 are guaranteed
/// p₊(t) = t·a_plus − t²·b; steps x = −s·t in the opposite direction only
/// p₋(t) = −t·a_minus − t²·b (a_plus ≥ 0, a_minus ≥ 0, b > 0).
pub(crate) fn solve_sign_aware(
    sign: f64,
    a_plus: f64,
    a_minus: f64,
    b: f64,
    required: f64,
) -> Result<StepOutcome, BoundsError> {
    let favoured = match solve_quadratic(a_plus, b, required)? {
        StepOutcome::Feasible(s) => s,
        other => return Ok(flip(other, sign)),
    };
    let (t_opposite, s) = sign_aware_parts(sign, favoured, a_minus, b, required);
    no_overflow("safe-step interval", t_opposite)?;
    Ok(StepOutcome::Feasible(s))
}

/// The sign-aware interval from the favoured side's interval, and the opposite side's
/// largest step t (unchecked: 0 when C ≥ 0). The arithmetic shared by [`solve_sign_aware`]
/// and [`feasible_sign_aware`].
#[inline(always)]
fn sign_aware_parts(
    sign: f64,
    favoured: SafeInterval,
    a_minus: f64,
    b: f64,
    required: f64,
) -> (f64, SafeInterval) {
    let (t_lo, t_hi) = (favoured.lo.max(0.0), favoured.hi);
    let t_opposite = if required < 0.0 {
        // root of b t² + a_minus t + C = 0 on t ≥ 0, written without cancellation
        -2.0 * required / (a_minus + (a_minus * a_minus - 4.0 * b * required).sqrt())
    } else {
        0.0
    };
    let (lo_t, hi_t) = if required < 0.0 {
        (-t_opposite, t_hi)
    } else {
        (t_lo, t_hi)
    };
    let (lo, hi) = if sign >= 0.0 {
        (lo_t, hi_t)
    } else {
        (-hi_t, -lo_t)
    };
    (
        t_opposite,
        SafeInterval {
            c_max: favoured.c_max,
            vertex: sign * favoured.vertex,
            lambda: favoured.lambda,
            lo,
            hi,
        },
    )
}

/// [`feasible_interval`] for [`solve_sign_aware`]: its interval when it returns one, bit for
/// bit, else `None`.
#[inline(always)]
pub(crate) fn feasible_sign_aware(
    sign: f64,
    a_plus: f64,
    a_minus: f64,
    b: f64,
    required: f64,
) -> Option<SafeInterval> {
    let favoured = feasible_interval(a_plus, b, required)?;
    let (t_opposite, s) = sign_aware_parts(sign, favoured, a_minus, b, required);
    t_opposite.is_finite().then_some(s)
}

/// Expresses a non-feasible outcome of the favoured direction in signed steps.
fn flip(outcome: StepOutcome, sign: f64) -> StepOutcome {
    match outcome {
        StepOutcome::Infeasible { c_max, vertex } => StepOutcome::Infeasible {
            c_max,
            vertex: sign * vertex,
        },
        other => other,
    }
}
