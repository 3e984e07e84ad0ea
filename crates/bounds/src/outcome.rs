//! Outcomes of a safe-step computation, and the solver shared by every quadratic bound.
//!
//! Every guaranteed-improvement bound of Chapter 4 is, as a function of the step x, a concave
//! parabola through the origin, p(x) = a·x − b·x² (b ≥ 0). For a required improvement C the
//! safe steps are {x : p(x) ≥ C}; this module solves that inequality once, robustly.

use crate::error::{BoundsError, no_overflow};

/// The safe steps for a required improvement C that some step can meet.
///
/// All steps x with `lo ≤ x ≤ hi` guarantee an improvement of at least C. The thesis's largest
/// step (ᾱ = (1 + λ)α*, β̄ = β̃ + λ|β̃|, eq. (4.20)) is `hi`, see [`SafeInterval::largest`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SafeInterval {
    /// C_max: the largest guaranteed improvement (the bound at its maximiser).
    pub c_max: f64,
    /// The step of maximal guaranteed improvement (α*, β*, β̃ or their high-probability
    /// and rigorous versions).
    pub vertex: f64,
    /// λ = √(1 − C/C_max) (eqs. (4.10), (4.17), (4.19)): the half-width of the interval
    /// relative to |vertex|. `None` when C_max = 0 (zero linear term, vertex at 0), where λ is
    /// undefined, or when the interval is not of the form |x − vertex| ≤ λ|vertex| (rigorous
    /// bound). λ ∈ [0, 1] iff C ≥ 0; for C < 0, λ > 1 and the interval contains steps of
    /// the sign opposite to the vertex.
    pub lambda: Option<f64>,
    /// Smallest safe step.
    pub lo: f64,
    /// Largest safe step.
    pub hi: f64,
}

impl SafeInterval {
    /// The largest safe step (ᾱ = (1 + λ_v)α* or β̄ = β̃ + λ_w|β̃|, eq. (4.20)), i.e. `hi`.
    ///
    /// ```
    /// use sepg_bounds::outcome::SafeInterval;
    /// let s = SafeInterval { c_max: 1.0, vertex: 1.0, lambda: Some(0.5), lo: 0.5, hi: 1.5 };
    /// assert_eq!(s.largest(), 1.5);
    /// ```
    pub fn largest(&self) -> f64 {
        self.hi
    }

    /// Whether `x` lies in the safe interval.
    ///
    /// ```
    /// use sepg_bounds::outcome::SafeInterval;
    /// let s = SafeInterval { c_max: 1.0, vertex: 1.0, lambda: Some(0.5), lo: 0.5, hi: 1.5 };
    /// assert!(s.contains(1.2) && !s.contains(1.6));
    /// ```
    pub fn contains(&self, x: f64) -> bool {
        self.lo <= x && x <= self.hi
    }
}

/// Result of asking for the steps that guarantee an improvement of at least C.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StepOutcome {
    /// C ≤ C_max: the interval of safe steps.
    Feasible(SafeInterval),
    /// C > C_max: no step guarantees C ("no real solution", proofs of Thms 4.2 and 4.3).
    /// `vertex` is the step of maximal guaranteed improvement (λ = 0), which guarantees
    /// `c_max` (docs/CONVENTIONS.md §5: take it and flag the iteration).
    Infeasible {
        /// The largest guaranteed improvement.
        c_max: f64,
        /// The step attaining it.
        vertex: f64,
    },
    /// The update direction is zero, so every step leaves the parameters unchanged and the
    /// bound is identically 0: C_max = 0, and the requirement is met iff C ≤ 0.
    ZeroGradient {
        /// Whether C ≤ 0.
        requirement_met: bool,
    },
    /// A high-probability gradient estimate is within its confidence width, ‖∇̂‖∞ ≤ ε
    /// (eq. (4.23) fails): no reliable update can be made (Section 4.5).
    BelowNoise,
}

impl StepOutcome {
    /// The step an algorithm should take: the largest safe step when feasible, the vertex
    /// (maximal guaranteed improvement) when infeasible, `None` when no update should be made.
    ///
    /// ```
    /// use sepg_bounds::outcome::StepOutcome;
    /// let o = StepOutcome::Infeasible { c_max: 0.25, vertex: 0.5 };
    /// assert_eq!(o.chosen_step(), Some(0.5));
    /// assert_eq!(StepOutcome::BelowNoise.chosen_step(), None);
    /// ```
    pub fn chosen_step(&self) -> Option<f64> {
        match self {
            Self::Feasible(s) => Some(s.hi),
            Self::Infeasible { vertex, .. } => Some(*vertex),
            Self::ZeroGradient { .. } | Self::BelowNoise => None,
        }
    }

    /// The largest guaranteed improvement C_max, `None` for [`StepOutcome::BelowNoise`].
    ///
    /// ```
    /// use sepg_bounds::outcome::StepOutcome;
    /// assert_eq!(StepOutcome::ZeroGradient { requirement_met: true }.c_max(), Some(0.0));
    /// ```
    pub fn c_max(&self) -> Option<f64> {
        match self {
            Self::Feasible(s) => Some(s.c_max),
            Self::Infeasible { c_max, .. } => Some(*c_max),
            Self::ZeroGradient { .. } => Some(0.0),
            Self::BelowNoise => None,
        }
    }

    /// Whether the requirement C can be guaranteed.
    ///
    /// ```
    /// use sepg_bounds::outcome::StepOutcome;
    /// assert!(!StepOutcome::Infeasible { c_max: 0.25, vertex: 0.5 }.is_feasible());
    /// ```
    pub fn is_feasible(&self) -> bool {
        match self {
            Self::Feasible(_) => true,
            Self::ZeroGradient { requirement_met } => *requirement_met,
            Self::Infeasible { .. } | Self::BelowNoise => false,
        }
    }
}

/// Vertex a/(2b) and maximum a²/(4b) of a·x − b·x² (b > 0), the single place where every
/// module computes them, so that a C_max reported by one function is accepted by another.
pub(crate) fn vertex_and_c_max(a: f64, b: f64) -> Result<(f64, f64), BoundsError> {
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
pub(crate) fn quadratic_c_max(a: f64, b: f64) -> Result<f64, BoundsError> {
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
pub(crate) fn solve_quadratic(a: f64, b: f64, required: f64) -> Result<StepOutcome, BoundsError> {
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
pub(crate) fn feasible_interval(a: f64, b: f64, required: f64) -> Option<SafeInterval> {
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
