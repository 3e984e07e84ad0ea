//! The certificate of an `f64` safe-step outcome: [`certify`] moves the largest safe step
//! toward the vertex until the enclosure of its bound meets the requirement, and the fast path
//! shared by the certified steps of [`crate::steps`] tries the a-priori error bound first.

use sepg_bounds::error::BoundsError;
use sepg_bounds::outcome::{SafeInterval, StepOutcome};

use crate::enclosure::EnclosedBound;
use crate::interval::{Interval, from_ordered_key, ordered_key};
use crate::rounding::RoundedBound;

/// Ulps walked one at a time around the predicted move before bisecting or doubling.
const LOCAL_STEPS: u64 = 4;

/// A step whose bound is certified to meet the requirement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CertifiedStep {
    /// The certified step x.
    pub step: f64,
    /// The enclosure of B(x); `bound.lo() ≥ required`.
    pub bound: Interval,
    /// How many ulps x was moved from the computed largest step toward the vertex.
    pub ulps_moved: u64,
    /// The safe interval computed in `f64` (λ, C_max and end points as computed): bit for bit
    /// the interval of the uncertified step function for the same inputs.
    pub interval: SafeInterval,
    /// Whether the certificate came from the a-priori rounding-error bound of the `f64`
    /// evaluation (the fast path) rather than from interval arithmetic (docs/THEOREMS.md,
    /// "Certified steps").
    pub by_error_bound: bool,
}

/// The outcome of a certified safe-step computation.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Certified {
    /// A step whose bound, evaluated in interval arithmetic, has a lower end ≥ C.
    Step(CertifiedStep),
    /// C > C_max: no step guarantees C. `step` is the vertex (the step of maximal guaranteed
    /// improvement) and `bound` the enclosure of its guarantee, below C.
    Infeasible {
        /// The vertex.
        step: f64,
        /// Enclosure of the bound at the vertex.
        bound: Interval,
    },
    /// C ≤ C_max as computed, but no `f64` step from the computed largest step to the vertex
    /// has an enclosure with lower end ≥ C (C is within rounding of C_max). `step` is the
    /// vertex and `bound` its enclosure.
    Uncertifiable {
        /// The vertex.
        step: f64,
        /// Enclosure of the bound at the vertex (it contains values below C).
        bound: Interval,
    },
    /// The update direction is zero (bound identically 0): no step to certify.
    ZeroGradient {
        /// Whether C ≤ 0.
        requirement_met: bool,
    },
    /// The estimate is within its confidence width (eq. (4.23) fails): no update.
    BelowNoise,
}

impl Certified {
    /// The step to take: the certified step, or the vertex when the requirement is infeasible
    /// or uncertifiable; `None` when no update should be made.
    ///
    /// ```
    /// use sepg_bounds::{constants::TaskConstants};
    /// use sepg_certified as certified;
    /// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
    /// let o = certified::v_safe_step(&k, 1.0, &[0.5], 0.0)?;
    /// assert!(o.chosen_step().unwrap() > 0.0);
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn chosen_step(&self) -> Option<f64> {
        match self {
            Self::Step(s) => Some(s.step),
            Self::Infeasible { step, .. } | Self::Uncertifiable { step, .. } => Some(*step),
            Self::ZeroGradient { .. } | Self::BelowNoise => None,
        }
    }

    /// The enclosure of the bound at [`Self::chosen_step`] (`None` when there is no step).
    pub fn bound(&self) -> Option<Interval> {
        match self {
            Self::Step(s) => Some(s.bound),
            Self::Infeasible { bound, .. } | Self::Uncertifiable { bound, .. } => Some(*bound),
            Self::ZeroGradient { .. } | Self::BelowNoise => None,
        }
    }

    /// Whether a step was certified to meet the requirement.
    pub fn is_certified(&self) -> bool {
        matches!(self, Self::Step(_))
    }
}

/// Certifies the `f64` outcome of a safe-step computation for the bound `bound` and the
/// requirement C = `required`.
///
/// A feasible outcome's largest step `hi` is kept when `bound.enclose(hi).lo() ≥ C`;
/// otherwise the step moves toward the vertex by doubling, then bisecting, the number of ulps
/// (the enclosure's lower end grows toward the vertex up to its own rounding), and the first
/// passing step is returned. An infeasible outcome returns the vertex with its enclosure.
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, v_update};
/// use sepg_certified::{self as certified, Certified, Quadratic};
/// let k = TaskConstants::new(0.99, 4.0, 2.0, 4.0)?;
/// let g = [0.7];
/// let outcome = v_update::safe_step(&k, 0.5, &g, 0.0)?;
/// let q = Quadratic::v_update(&k, 0.5, &g)?;
/// let Certified::Step(s) = certified::certify(&q, outcome, 0.0) else { panic!() };
/// assert!(s.bound.lo() >= 0.0 && s.step <= outcome.chosen_step().unwrap());
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn certify<B: EnclosedBound + ?Sized>(
    bound: &B,
    outcome: StepOutcome,
    required: f64,
) -> Certified {
    match outcome {
        StepOutcome::Feasible(s) => match certify_toward(bound, s.hi, s.vertex, required) {
            Ok((step, enclosure, ulps_moved)) => Certified::Step(CertifiedStep {
                step,
                bound: enclosure,
                ulps_moved,
                interval: s,
                by_error_bound: false,
            }),
            Err(enclosure) => Certified::Uncertifiable {
                step: s.vertex,
                bound: enclosure,
            },
        },
        StepOutcome::Infeasible { vertex, .. } => Certified::Infeasible {
            step: vertex,
            bound: bound.enclose(vertex),
        },
        StepOutcome::ZeroGradient { requirement_met } => {
            Certified::ZeroGradient { requirement_met }
        }
        StepOutcome::BelowNoise => Certified::BelowNoise,
    }
}

/// The first `f64` from `from` toward `toward` (both included) whose enclosure has lower end
/// ≥ `required`: (step, enclosure, ulps moved), or the enclosure at `toward` if none passes.
///
/// [`certify`] uses it from the largest safe step toward the vertex; use it directly to
/// certify another end point of a safe interval (e.g. the smallest step), moving toward the
/// vertex too. The search doubles the number of ulps until a step passes, then bisects.
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, outcome::StepOutcome, w_update};
/// use sepg_certified::{certify_toward, Quadratic};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let StepOutcome::Feasible(s) = w_update::safe_step_along_j(&k, 1.0, 0.3, -0.01)? else { panic!() };
/// let q = Quadratic::w_along_j(&k, 1.0, 0.3)?;
/// let (step, bound, _) = certify_toward(&q, s.lo, s.vertex, -0.01).unwrap();
/// assert!(bound.lo() >= -0.01 && step >= s.lo);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn certify_toward<B: EnclosedBound + ?Sized>(
    bound: &B,
    from: f64,
    toward: f64,
    required: f64,
) -> Result<(f64, Interval, u64), Interval> {
    let first = bound.enclose(from);
    if first.lo() >= required {
        return Ok((from, first, 0));
    }
    let start = ordered_key(from);
    let end = ordered_key(toward);
    let total = end.abs_diff(start);
    if total == 0 {
        return Err(first);
    }
    let at = |offset: u64| {
        let offset = offset as i64;
        from_ordered_key(if end < start {
            start - offset
        } else {
            start + offset
        })
    };
    let passes = |offset: u64| {
        let e = bound.enclose(at(offset));
        (e.lo() >= required, e)
    };
    // Bracket the first passing offset: `failed` fails, `good` passes. Start from the move
    // that the bound's slope predicts for the shortfall (usually within an ulp or two of the
    // answer), walking one ulp at a time near it; fall back to doubling.
    let guess = bound
        .slope(from)
        .map(|slope| (required - first.lo()) / (slope.abs() * (at(1) - from).abs()))
        .filter(|g| g.is_finite() && *g >= 1.0)
        .map_or(1, |g| (g.ceil() as u64).min(total));
    let (failed, good, good_enclosure) = match passes(guess) {
        (true, e) => {
            let (mut good, mut good_enclosure) = (guess, e);
            for _ in 0..LOCAL_STEPS {
                if good == 1 {
                    break;
                }
                match passes(good - 1) {
                    (true, e) => (good, good_enclosure) = (good - 1, e),
                    (false, _) => return Ok((at(good), good_enclosure, good)),
                }
            }
            (0, good, good_enclosure)
        }
        (false, e) => {
            let mut failed = guess;
            let mut last = e;
            let mut distance = 1_u64;
            loop {
                if failed == total {
                    return Err(last);
                }
                let offset = failed.saturating_add(distance).min(total);
                let (ok, e) = passes(offset);
                if ok {
                    break (failed, offset, e);
                }
                (failed, last) = (offset, e);
                if distance < LOCAL_STEPS {
                    distance += 1;
                } else {
                    distance = distance.saturating_mul(2);
                }
            }
        }
    };
    let (good, good_enclosure) = bisect(passes, failed, (good, good_enclosure));
    Ok((at(good), good_enclosure, good))
}

/// The first passing offset between `failed` (which fails) and `good` (which passes, with its
/// enclosure), by bisection: `passes(offset)` says whether the bound at `offset` meets the
/// requirement and gives its enclosure. Like the bracketing of [`certify_toward`] that
/// precedes it, it takes passing to be monotone in the offset.
fn bisect(
    passes: impl Fn(u64) -> (bool, Interval),
    mut failed: u64,
    (mut good, mut good_enclosure): (u64, Interval),
) -> (u64, Interval) {
    while good - failed > 1 {
        let mid = failed + (good - failed) / 2;
        match passes(mid) {
            (true, e) => (good, good_enclosure) = (mid, e),
            (false, _) => failed = mid,
        }
    }
    (good, good_enclosure)
}

/// Certifies `outcome` with the fast a-priori enclosure `fast` (module `rounding`) when it
/// applies and certifies a step, and otherwise with the interval enclosure `interval` (`None`:
/// below noise). The body shared by every certified step form.
#[inline(always)]
pub(crate) fn certify_fast_then_interval<S: EnclosedBound>(
    outcome: StepOutcome,
    required: f64,
    fast: impl FnOnce() -> Option<RoundedBound>,
    interval: impl FnOnce() -> Result<Option<S>, BoundsError>,
) -> Result<Certified, BoundsError> {
    match outcome {
        StepOutcome::ZeroGradient { requirement_met } => {
            return Ok(Certified::ZeroGradient { requirement_met });
        }
        StepOutcome::BelowNoise => return Ok(Certified::BelowNoise),
        StepOutcome::Infeasible { vertex, .. } => {
            if let Some(bound) = fast() {
                return Ok(Certified::Infeasible {
                    step: vertex,
                    bound: bound.enclose(vertex),
                });
            }
        }
        StepOutcome::Feasible(s) => {
            if let Some(step) = certify_feasible(Some(s), fast, required) {
                return Ok(Certified::Step(step));
            }
        }
    }
    certify_by_interval(outcome, required, interval)
}

/// [`certify_fast_then_interval`] for the outcome that `outcome` computes, kept out of line:
/// the fallback of the step functions whose common case [`certify_feasible`] handles.
#[cold]
#[inline(never)]
fn certify_out_of_line<S: EnclosedBound>(
    required: f64,
    outcome: impl FnOnce() -> Result<StepOutcome, BoundsError>,
    fast: impl FnOnce() -> Option<RoundedBound>,
    interval: impl FnOnce() -> Result<Option<S>, BoundsError>,
) -> Result<Certified, BoundsError> {
    certify_fast_then_interval(outcome()?, required, fast, interval)
}

/// The interval path of [`certify_fast_then_interval`], kept out of line: it is rarely taken,
/// and inlined it would crowd the registers of the fast path.
#[cold]
#[inline(never)]
fn certify_by_interval<S: EnclosedBound>(
    outcome: StepOutcome,
    required: f64,
    interval: impl FnOnce() -> Result<Option<S>, BoundsError>,
) -> Result<Certified, BoundsError> {
    Ok(match interval()? {
        Some(bound) => certify(&bound, outcome, required),
        None => Certified::BelowNoise,
    })
}

/// The common case of every certified step with an error-bound enclosure: a feasible safe
/// interval (`None` when the outcome is anything else) whose largest step, or that step
/// moved toward the vertex as [`certify_predicted`] predicts, the error-bound enclosure `fast`
/// certifies. `None` when any of these fails; the caller then computes the outcome again and
/// certifies it in full ([`certify_out_of_line`]).
///
/// Taking the interval as an `Option` of plain numbers, rather than a [`StepOutcome`], lets
/// the step functions compute it with the `feasible_*` companions of their solvers, which
/// return no error values; inlined, the interval then stays in registers and the certified
/// step is written once, which is most of what makes this path cheap.
#[inline(always)]
fn certify_feasible(
    interval: Option<SafeInterval>,
    fast: impl FnOnce() -> Option<RoundedBound>,
    required: f64,
) -> Option<CertifiedStep> {
    let s = interval?;
    let bound = fast()?;
    let (step, enclosure, ulps_moved) =
        certify_predicted(&bound, s.hi, s.vertex, s.c_max, required)?;
    Some(CertifiedStep {
        step,
        bound: enclosure,
        ulps_moved,
        interval: s,
        by_error_bound: true,
    })
}

/// The error-bound certificate of the largest safe step `hi` of a feasible outcome with the
/// given vertex and C_max: (step, enclosure, ulps moved). The step is `hi` when its enclosure
/// passes, else `hi` moved toward the vertex by the number of ulps that the bound's slope
/// predicts for the shortfall, enlarged by 1/8 and 2 ulps, when that passes (two evaluations
/// and no search). The error-bound enclosure is wider than the interval one, so the move is
/// longer than the interval path's (about twice as many ulps, ≲ 1e-14 relative). `None` when
/// neither passes: the caller then searches in interval arithmetic.
#[inline(always)]
fn certify_predicted(
    bound: &RoundedBound,
    hi: f64,
    vertex: f64,
    c_max: f64,
    required: f64,
) -> Option<(f64, Interval, u64)> {
    // The move predicted from the coefficients and `hi` alone (plus two ulps), evaluated
    // beside `hi` itself: `hi` is a root of p(x) = C, so its own enclosure almost never
    // reaches C, and the moved step is then ready without waiting for that evaluation.
    let key = ordered_key(hi);
    let ulp = hi - from_ordered_key(key.saturating_sub(1));
    let moved = hi - (bound.predicted_move(hi, c_max, required) + 2.0 * ulp);
    let first = bound.enclose(hi);
    if first.lo() >= required {
        return Some((hi, first, 0));
    }
    if moved >= vertex && moved < hi {
        let e = bound.enclose(moved);
        if e.lo() >= required {
            return Some((moved, e, key.abs_diff(ordered_key(moved))));
        }
    }
    certify_from_shortfall(*bound, hi, vertex, required, first.lo())
}

/// The last attempt of [`certify_predicted`]: `hi` moved toward `vertex` by the shortfall of
/// the lower end `first_lo` of its own enclosure over the bound's slope, enlarged by 1/8 and
/// 2 ulps (kept out of line: rarely taken).
#[cold]
#[inline(never)]
fn certify_from_shortfall(
    bound: RoundedBound,
    hi: f64,
    vertex: f64,
    required: f64,
    first_lo: f64,
) -> Option<(f64, Interval, u64)> {
    let (from, to) = (ordered_key(hi), ordered_key(vertex));
    let toward = |n: u64| {
        let n = n as i64;
        from_ordered_key(if to < from { from - n } else { from + n })
    };
    let ulp = (toward(1) - hi).abs();
    // the shortfall is positive, so `predicted` is ≥ 0, +∞ or NaN; 2⁵² bounds the cast
    let predicted = (required - first_lo) / (bound.slope(hi)?.abs() * ulp);
    if predicted.partial_cmp(&4_503_599_627_370_496.0) != Some(std::cmp::Ordering::Less) {
        return None;
    }
    // below 2⁵³ the conversion through i64 is exact and branch-free
    let n = (predicted * 1.125 + 2.0) as i64 as u64;
    if n > from.abs_diff(to) {
        return None;
    }
    let x = toward(n);
    let e = bound.enclose(x);
    (e.lo() >= required).then_some((x, e, n))
}

/// The body of the certified steps with an error-free companion: [`certify_feasible`] on the
/// companion's interval `feasible`, else, out of line, the full path on the outcome that
/// `outcome` computes ([`certify_out_of_line`]).
#[inline(always)]
pub(crate) fn certify_step<S: EnclosedBound>(
    feasible: Option<SafeInterval>,
    required: f64,
    outcome: impl FnOnce() -> Result<StepOutcome, BoundsError>,
    fast: impl FnOnce() -> Option<RoundedBound> + Copy,
    interval: impl FnOnce() -> Result<Option<S>, BoundsError>,
) -> Result<Certified, BoundsError> {
    if let Some(step) = certify_feasible(feasible, fast, required) {
        return Ok(Certified::Step(step));
    }
    certify_out_of_line(required, outcome, fast, interval)
}
