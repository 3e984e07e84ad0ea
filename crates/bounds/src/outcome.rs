//! Outcomes of a safe-step computation: the interval of safe steps, or why there is none.
//!
//! The solver that produces them is [`crate::parabola::Parabola`].

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
