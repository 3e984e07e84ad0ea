//! A rigorous lower bound for the w-update, with no neglected terms (SPEC §4).
//!
//! # Derivation
//!
//! Start from Lemma 3.1 of Pirotta et al. (eq. (A.9)) for θ = [v | w], θ' = [v | w + Δw]:
//!
//! ```text
//! J(θ') − J(θ) ≥ 1/(1−γ) ∫ d(s) ∫ (π' − π) Q da ds − γ/(2(1−γ)²) ‖π' − π‖∞² ‖Q‖∞
//! ```
//!
//! 1. Taylor with Lagrange remainder (A.4): π' − π = ∂_wπ Δw + ½ ∂²_wπ(w + εΔw) Δw², ε ∈ (0, 1).
//!    Lemma A.1 bounds |∂²_wπ| at w + εΔw by ψ/σ_{w+εΔw} ≤ ψ / min(σ, σe^{Δw}) — the
//!    thesis uses ψ/σ, the value at the *old* σ, which is smaller than the true supremum when
//!    Δw < 0. With |Q| ≤ R/(1−γ), ∫_A da = |A| and the policy gradient theorem, the first term
//!    is at least Δw ∇_w J − Δw² R ψ|A| / (2(1−γ)² min(σ, σe^{Δw})).
//! 2. Pinsker (A.6) holds for both KL directions because ‖π' − π‖₁ is symmetric; for Gaussians
//!    with equal means (A.7):
//!    2 KL(π'‖π) = e^{2Δw} − 1 − 2Δw,   2 KL(π‖π') = e^{−2Δw} − 1 + 2Δw.
//!    Taking the smaller, KL2(Δw) = e^{−2|Δw|} − 1 + 2|Δw| ≤ 2Δw² exactly (because
//!    e^{−y} ≤ 1 − y + y²/2 for y ≥ 0), so Lemma A.3 holds with no neglected term.
//!    With ‖Q‖∞ ≤ R/(1−γ) the penalty is γR/(1−γ)³ · KL2(Δw)/2.
//!
//! Hence, for every Δw, with a = Rψ|A|/(2(1−γ)²σ) and G = γR/(2(1−γ)³) (so d = a + 2G):
//!
//! ```text
//! f(Δw) = Δw ∇_w J − a Δw² max(1, e^{−Δw}) − G · KL2(Δw)
//! ```
//!
//! while the thesis form (4.15)/(A.11) is f_T(Δw) = Δw ∇_w J − d Δw². Consequences:
//! - Δw ≥ 0: f − f_T = G (2Δw² − KL2(Δw)) ∈ [0, (4/3) G Δw³], so the thesis form is itself a
//!   rigorous (slightly conservative) bound for increases of σ;
//! - Δw < 0: f − f_T = −a Δw² (e^{|Δw|} − 1) + G (2Δw² − KL2(Δw)), which is negative (the
//!   thesis form over-promises) as soon as a (e^{|Δw|} − 1) exceeds
//!   G (2 − KL2(Δw)/Δw²) ≈ (4/3) G |Δw|; for small |Δw| this happens iff a > (4/3) G, i.e.
//!   ψ|A|/σ > (4/3) γ/(1 − γ).
//!
//! f is strictly concave (each penalty is convex and C¹ at 0) with f(0) = 0, so the safe set
//! {Δw : f(Δw) ≥ C} is an interval, found here by bisection inside closed-form brackets.

use crate::constants::{TaskConstants, d, d_parts};
use crate::error::{BoundsError, finite, no_overflow};
use crate::outcome::{SafeInterval, StepOutcome};

/// Maximum number of bisection steps (enough to exhaust f64 precision from any finite bracket).
const MAX_BISECTIONS: usize = 2200;

/// KL2(Δw) = min(e^{2Δw} − 1 − 2Δw, e^{−2Δw} − 1 + 2Δw) = e^{−2|Δw|} − 1 + 2|Δw|: twice the
/// smaller of the two Kullback–Leibler divergences between N(μ, σ²) and N(μ, σ²e^{2Δw}).
///
/// # Formula
///
/// ```text
/// KL2(Δw) = e^{−2|Δw|} − 1 + 2|Δw|   (≤ 2Δw², equality only at 0)
/// ```
///
/// Computed by its Taylor series for small |Δw| so that it keeps full relative accuracy.
///
/// Errors: Δw not finite; [`BoundsError::Overflow`] when 2|Δw| overflows (|Δw| > f64::MAX / 2).
///
/// ```
/// use sepg_bounds::rigorous::kl2;
/// let x: f64 = 0.3;
/// let direct = ((2.0 * x).exp() - 1.0 - 2.0 * x).min((-2.0 * x).exp() - 1.0 + 2.0 * x);
/// assert!((kl2(x)? - direct).abs() < 1e-15);
/// assert!(kl2(x)? <= 2.0 * x * x);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn kl2(delta_w: f64) -> Result<f64, BoundsError> {
    finite("delta_w", delta_w)?;
    no_overflow("KL2", kl2_unchecked(delta_w))
}

/// e^{−y} − 1 + y for y = 2|Δw| ≥ 0: alternating Taylor series below 0.1 (no cancellation),
/// `exp_m1(−y) + y` above (relative error below 1e-14 there).
fn kl2_unchecked(delta_w: f64) -> f64 {
    let y = 2.0 * delta_w.abs();
    if y < 0.1 {
        // Σ_{n≥2} (−y)^n / n!; 16 terms leave a remainder below 0.1^16/16! ≈ 5e-30 relative
        let mut term = y * y / 2.0;
        let mut sum = term;
        for n in 3..18 {
            term *= -y / f64::from(n);
            sum += term;
        }
        sum
    } else {
        (-y).exp_m1() + y
    }
}

/// The validated coefficients of the rigorous bound.
#[derive(Debug, Clone, Copy)]
struct Rigorous {
    a: f64,
    g: f64,
    slope: f64,
}

impl Rigorous {
    fn new(k: &TaskConstants, sigma: f64, grad_w_j: f64) -> Result<Self, BoundsError> {
        let (a, g) = d_parts(k, sigma)?;
        Ok(Self {
            a,
            g,
            slope: finite("grad_w_j", grad_w_j)?,
        })
    }

    /// f(Δw); may be ±∞ or NaN for huge arguments, so callers compare with `>=`, which treats
    /// NaN as unsafe, and check every returned value for finiteness.
    fn value(&self, x: f64) -> f64 {
        let curvature = if x < 0.0 { (-x).exp() } else { 1.0 };
        x * self.slope - self.a * x * x * curvature - self.g * kl2_unchecked(x)
    }

    /// f'(Δw), strictly decreasing.
    fn derivative(&self, x: f64) -> f64 {
        let remainder = if x < 0.0 {
            self.a * (2.0 * x - x * x) * (-x).exp()
        } else {
            2.0 * self.a * x
        };
        let kl = 2.0 * x.signum() * (-(-2.0 * x.abs()).exp_m1());
        self.slope - remainder - self.g * kl
    }

    /// Δw maximising f: between 0 and ∇_wJ/(2a) (see module docs), by bisection on f'.
    fn maximiser(&self) -> Result<f64, BoundsError> {
        let far = no_overflow("rigorous maximiser bracket", self.slope / (2.0 * self.a))?;
        let (mut lo, mut hi) = if far >= 0.0 { (0.0, far) } else { (far, 0.0) };
        for _ in 0..MAX_BISECTIONS {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if self.derivative(mid) > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Ok(0.5 * (lo + hi))
    }

    /// Bisection for the boundary of {f ≥ C} between `safe` (f ≥ C) and `unsafe_` (f ≤ C, the
    /// closed-form bracket end, returned when f = C there);
    /// returns the last point known to be safe.
    fn boundary(&self, mut safe: f64, mut unsafe_: f64, required: f64) -> f64 {
        if self.value(unsafe_) >= required {
            // the bracket end is itself a root (e.g. Δw = 0 for C = 0)
            return unsafe_;
        }
        for _ in 0..MAX_BISECTIONS {
            let mid = 0.5 * (safe + unsafe_);
            if mid == safe || mid == unsafe_ {
                break;
            }
            if self.value(mid) >= required {
                safe = mid;
            } else {
                unsafe_ = mid;
            }
        }
        safe
    }

    /// The safe Δw interval for the requirement C.
    fn solve(&self, required: f64) -> Result<StepOutcome, BoundsError> {
        let vertex = self.maximiser()?;
        let c_max = no_overflow("rigorous C_max", self.value(vertex))?;
        if required > c_max {
            return Ok(StepOutcome::Infeasible { c_max, vertex });
        }
        // f(x) ≤ x·slope − a·x², so {f ≥ C} lies within the roots of a x² − slope x + C = 0.
        let disc = (self.slope * self.slope - 4.0 * self.a * required)
            .max(0.0)
            .sqrt();
        let far_hi = no_overflow("rigorous bracket", (self.slope + disc) / (2.0 * self.a))?;
        let far_lo = no_overflow("rigorous bracket", (self.slope - disc) / (2.0 * self.a))?;
        let hi = self.boundary(vertex, far_hi.max(vertex), required);
        let lo = self.boundary(vertex, far_lo.min(vertex), required);
        Ok(StepOutcome::Feasible(SafeInterval {
            c_max,
            vertex,
            lambda: None,
            lo,
            hi,
        }))
    }
}

/// The rigorous lower bound on J(v, w + Δw) − J(v, w) (module docs), Δw of either sign.
///
/// # Formula
///
/// ```text
/// f(Δw) = Δw ∇_w J − Δw² R/(1−γ)² · ψ|A| / (2 min(σ, σe^{Δw})) − γR/(1−γ)³ · KL2(Δw)/2
/// ```
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, rigorous};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// // for an increase of σ the rigorous bound is at least the thesis bound
/// let r = rigorous::bound(&k, 1.0, 0.5, 0.01)?;
/// assert!(r >= rigorous::thesis_bound(&k, 1.0, 0.5, 0.01)?);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn bound(
    k: &TaskConstants,
    sigma: f64,
    grad_w_j: f64,
    delta_w: f64,
) -> Result<f64, BoundsError> {
    finite("delta_w", delta_w)?;
    no_overflow(
        "rigorous bound",
        Rigorous::new(k, sigma, grad_w_j)?.value(delta_w),
    )
}

/// The thesis form of the same bound, (A.11): f_T(Δw) = Δw ∇_w J − d(σ) Δw².
///
/// # Formula
///
/// ```text
/// f_T(Δw) = Δw ∇_w J − d(σ) Δw²
/// ```
///
/// ```
/// use sepg_bounds::{constants::{TaskConstants, d}, rigorous::thesis_bound};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let expected = 0.05 - 0.01 * d(&k, 1.0)?;
/// assert!((thesis_bound(&k, 1.0, 0.5, 0.1)? - expected).abs() < 1e-12 * expected.abs());
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn thesis_bound(
    k: &TaskConstants,
    sigma: f64,
    grad_w_j: f64,
    delta_w: f64,
) -> Result<f64, BoundsError> {
    finite("grad_w_j", grad_w_j)?;
    finite("delta_w", delta_w)?;
    no_overflow(
        "thesis bound",
        delta_w * grad_w_j - d(k, sigma)? * delta_w * delta_w,
    )
}

/// The gap f_T(Δw) − f(Δw) between the thesis and the rigorous bounds; positive where the
/// thesis form over-promises.
///
/// # Formula
///
/// ```text
/// f_T − f = a Δw² (max(1, e^{−Δw}) − 1) − G (2Δw² − KL2(Δw)),
/// a = Rψ|A| / (2(1−γ)²σ),   G = γR / (2(1−γ)³)
/// ```
///
/// Computed from this closed form (no cancellation between the two bounds).
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, rigorous::gap};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// assert!(gap(&k, 1.0, 0.01)? <= 0.0); // increases of σ: thesis form is conservative
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn gap(k: &TaskConstants, sigma: f64, delta_w: f64) -> Result<f64, BoundsError> {
    finite("delta_w", delta_w)?;
    let (a, g) = d_parts(k, sigma)?;
    let x2 = delta_w * delta_w;
    let remainder = if delta_w < 0.0 {
        a * x2 * (-delta_w).exp_m1()
    } else {
        0.0
    };
    no_overflow(
        "rigorous gap",
        remainder - g * (2.0 * x2 - kl2_unchecked(delta_w)),
    )
}

/// The safe log-σ changes Δw for a required improvement C under the rigorous bound.
///
/// # Formula
///
/// ```text
/// { Δw : f(Δw) ≥ C } = [lo, hi],   vertex = argmax f,   C_max = f(vertex)
/// ```
///
/// Bisection inside the brackets given by the roots of a Δw² − ∇_wJ Δw + C = 0; the returned
/// end points satisfy f ≥ C. λ is `None` (the interval is not symmetric about the vertex).
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, outcome::StepOutcome, rigorous};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let StepOutcome::Feasible(s) = rigorous::safe_delta_w(&k, 1.0, 0.5, 0.0)? else { panic!() };
/// assert!(rigorous::bound(&k, 1.0, 0.5, s.hi)? >= 0.0);
/// assert!(rigorous::bound(&k, 1.0, 0.5, s.hi * 1.001)? < 0.0);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn safe_delta_w(
    k: &TaskConstants,
    sigma: f64,
    grad_w_j: f64,
    required: f64,
) -> Result<StepOutcome, BoundsError> {
    finite("required", required)?;
    Rigorous::new(k, sigma, grad_w_j)?.solve(required)
}

/// Maps a Δw outcome to steps β along a direction u (Δw = β u, u ≠ 0).
fn along(outcome: StepOutcome, u: f64) -> Result<StepOutcome, BoundsError> {
    Ok(match outcome {
        StepOutcome::Feasible(s) => {
            let (a, b) = (s.lo / u, s.hi / u);
            StepOutcome::Feasible(SafeInterval {
                vertex: no_overflow("rigorous step", s.vertex / u)?,
                lo: no_overflow("rigorous step", a.min(b))?,
                hi: no_overflow("rigorous step", a.max(b))?,
                ..s
            })
        }
        StepOutcome::Infeasible { c_max, vertex } => StepOutcome::Infeasible {
            c_max,
            vertex: no_overflow("rigorous step", vertex / u)?,
        },
        other => other,
    })
}

/// Rigorous safe steps β along ∇_w J (Δw = β ∇_w J), the rigorous counterpart of
/// [`crate::w_update::safe_step_along_j`].
///
/// # Formula
///
/// ```text
/// { β : f(β ∇_w J) ≥ C },   largest = hi
/// ```
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, rigorous, w_update};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let r = rigorous::safe_step_along_j(&k, 1.0, 0.5, 0.0)?.chosen_step().unwrap();
/// let t = w_update::safe_step_along_j(&k, 1.0, 0.5, 0.0)?.chosen_step().unwrap();
/// assert!(r >= t); // Δw > 0: the thesis step is rigorous, the exact one a bit larger
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn safe_step_along_j(
    k: &TaskConstants,
    sigma: f64,
    grad_w_j: f64,
    required: f64,
) -> Result<StepOutcome, BoundsError> {
    let outcome = safe_delta_w(k, sigma, grad_w_j, required)?;
    if grad_w_j == 0.0 {
        return Ok(StepOutcome::ZeroGradient {
            requirement_met: required <= 0.0,
        });
    }
    along(outcome, grad_w_j)
}

/// Rigorous safe steps β along ∇_w L (Δw = β ∇_w L), the rigorous counterpart of
/// [`crate::w_update::safe_step_along_l`]. `ZeroGradient` when ∇_w L = 0.
///
/// # Formula
///
/// ```text
/// { β : f(β ∇_w L) ≥ C },   largest = hi
/// ```
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, rigorous};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let o = rigorous::safe_step_along_l(&k, 1.0, 0.5, -3.0, -0.01)?;
/// assert!(o.chosen_step().unwrap() > 0.0); // a budget lets w follow ∇_w L against ∇_w J
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn safe_step_along_l(
    k: &TaskConstants,
    sigma: f64,
    grad_w_j: f64,
    grad_w_l: f64,
    required: f64,
) -> Result<StepOutcome, BoundsError> {
    finite("grad_w_l", grad_w_l)?;
    let outcome = safe_delta_w(k, sigma, grad_w_j, required)?;
    if grad_w_l == 0.0 {
        return Ok(StepOutcome::ZeroGradient {
            requirement_met: required <= 0.0,
        });
    }
    along(outcome, grad_w_l)
}
