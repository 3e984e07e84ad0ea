//! Certified safe steps: steps whose guarantee survives floating-point rounding.
//!
//! The safe steps of the other modules are computed in `f64`. Their largest step lies exactly
//! on the boundary {B(x) = C} of the safe set, so rounding puts it outside the true safe set
//! about half of the time: B(x) < C in real arithmetic by a few ulps, although the `f64`
//! computation says B(x) ≥ C. This module evaluates each bound B at the returned step in
//! interval arithmetic ([`Interval`]), with the inputs taken as exact reals and every
//! irrational constant (ψ, √(2π), e^x) enclosed, and returns a step only when the lower end
//! of the enclosure is at least C. When the computed step fails that test it is moved toward
//! the vertex (the step of maximal guaranteed improvement) by the fewest ulps that pass; when
//! no `f64` step between the computed one and the vertex passes, the outcome is
//! [`Certified::Uncertifiable`]. docs/THEOREMS.md ("Certified steps") states what the
//! certificate means and what it assumes.
//!
//! Each bound form is an [`EnclosedBound`]; [`certify`] turns the `f64` [`StepOutcome`] of
//! any form into a [`Certified`] outcome, so a new step form is certified by implementing the
//! trait for its bound.
//!
//! The step functions below first try a cheaper certificate: the bound evaluated in plain
//! `f64` with an a-priori bound on its rounding error (standard model of floating-point
//! arithmetic, γ_k = k·u/(1 − k·u); the analysis is in docs/THEOREMS.md, "Certified steps"),
//! and fall back to interval arithmetic when that analysis does not apply or does not certify
//! a step ([`CertifiedStep::by_error_bound`] says which). The rigorous forms and
//! [`adaptive_step`] use interval arithmetic only. On the fast path the `f64` safe interval
//! comes from error-free companions of the solvers (`outcome::feasible_interval` and its
//! callers), which return it bit for bit or nothing, so that it stays in registers; every other
//! outcome takes the full path.
//!
//! | function | bound | thesis |
//! |---|---|---|
//! | [`v_safe_step`] | α‖∇_vJ‖∞² − α²c‖∇_vJ‖∞² | Theorem 4.2 |
//! | [`w_safe_step_along_j`] | β(∇_wJ)² − β²d(∇_wJ)² | Theorem 4.3 |
//! | [`w_safe_step_along_l`] | β∇_wL∇_wJ − β²d(∇_wL)² | Theorem 4.5 |
//! | [`hp_v_safe_step`], [`hp_w_safe_step_along_j`], [`hp_w_safe_step_along_l`] | high-probability forms | Theorems 4.7–4.9 |
//! | [`rigorous_safe_step_along_j`], [`rigorous_safe_step_along_l`] | rigorous w-bound | [`crate::rigorous`] |
//! | [`exploring_safe_step`] | Δw·∇̂_wJ − \|Δw\|·ε_J − d(σ)Δw² | docs/THEOREMS.md, Theorem E |
//! | [`adaptive_step`] | α‖∇J‖₂² − α²c(σ)‖∇J‖₁² (guarantee only) | Theorem 3.10, Corollary 3.11 |

use crate::constants::{self, TaskConstants};
use crate::error::{BoundsError, finite, finite_vector, inf_norm, non_negative, positive};
use crate::exploring::ExploringBound;
use crate::high_probability::{self as hp, HpForm};
use crate::interval::{Interval, from_ordered_key, ordered_key};
use crate::outcome::{SafeInterval, StepOutcome};
use crate::rounding::{self, Rounded, RoundedBound};
use crate::{pirotta, rigorous, v_update, w_update};

/// Ulps walked one at a time around the predicted move before bisecting or doubling.
const LOCAL_STEPS: u64 = 4;

/// √(2π) ∈ [2.5066282746310002, 2.5066282746310007] (the two `f64` around it).
const SQRT_2PI_LO: f64 = 2.506_628_274_631_000_2;
const SQRT_2PI_HI: f64 = 2.506_628_274_631_000_7;
/// ψ ∈ [0.5235570203213736, 0.5235570203213737] (Lemma A.1).
const PSI_LO: f64 = 0.523_557_020_321_373_6;
const PSI_HI: f64 = 0.523_557_020_321_373_7;

/// An enclosure of √(2π): the two neighbouring `f64` around it.
///
/// ```
/// let s = sepg_bounds::certified::sqrt_2pi();
/// assert!(s.contains((2.0 * std::f64::consts::PI).sqrt()));
/// assert!(s.width() < 1e-15);
/// ```
pub fn sqrt_2pi() -> Interval {
    Interval::from_sorted(SQRT_2PI_LO, SQRT_2PI_HI)
}

/// An enclosure of ψ = 4(√7 − 2)e^{√7/2 − 2}/√(2π) of Lemma A.1 (see
/// [`crate::constants::psi`]): the two neighbouring `f64` around it.
///
/// ```
/// let p = sepg_bounds::certified::psi();
/// assert!(p.lo() < p.hi() && p.width() < 1e-15);
/// assert!((p.lo() - sepg_bounds::constants::psi()).abs() < 1e-15);
/// ```
pub fn psi() -> Interval {
    Interval::from_sorted(PSI_LO, PSI_HI)
}

/// ψ of the task, enclosed: [`psi`], or the override of `TaskConstants::with_psi` exactly.
fn psi_of(k: &TaskConstants) -> Interval {
    k.psi_override().map_or_else(psi, Interval::point)
}

/// 1 − γ, enclosed.
fn one_minus_gamma(k: &TaskConstants) -> Interval {
    Interval::point(1.0) - Interval::point(k.gamma())
}

/// An enclosure of c(σ) of Theorems 3.14 / 4.2 (see [`crate::constants::c`]).
///
/// # Formula
///
/// ```text
/// c(σ) = R M_φ² / ((1 − γ)² σ²) · ( |A| / (√(2π) σ) + γ / (2 (1 − γ)) )
/// ```
///
/// Errors: σ not finite and positive.
///
/// ```
/// use sepg_bounds::{certified, constants::{self, TaskConstants}};
/// let k = TaskConstants::new(0.99, 4.0, 2.0, 4.0)?;
/// assert!(certified::c(&k, 0.3)?.contains(constants::c(&k, 0.3)?));
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn c(k: &TaskConstants, sigma: f64) -> Result<Interval, BoundsError> {
    positive("sigma", sigma)?;
    let om = one_minus_gamma(k);
    let s = Interval::point(sigma);
    let front =
        Interval::point(k.r_max()) * Interval::point(k.m_phi()).sqr() / (om.sqr() * s.sqr());
    let bracket = Interval::point(k.action_volume()) / (sqrt_2pi() * s)
        + Interval::point(k.gamma()) / (om + om);
    Ok(front * bracket)
}

/// An enclosure of d(σ) of Theorem 4.3 (see [`crate::constants::d`]).
///
/// # Formula
///
/// ```text
/// d(σ) = R / (1 − γ)² · ( ψ |A| / (2σ) + γ / (1 − γ) )
/// ```
///
/// Errors: σ not finite and positive.
///
/// ```
/// use sepg_bounds::{certified, constants::{self, TaskConstants}};
/// let k = TaskConstants::new(0.99, 4.0, 2.0, 4.0)?;
/// assert!(certified::d(&k, 0.3)?.contains(constants::d(&k, 0.3)?));
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn d(k: &TaskConstants, sigma: f64) -> Result<Interval, BoundsError> {
    positive("sigma", sigma)?;
    let om = one_minus_gamma(k);
    let front = Interval::point(k.r_max()) / om.sqr();
    let bracket = psi_of(k) * Interval::point(k.action_volume())
        / Interval::point(sigma).scale(2.0)
        + Interval::point(k.gamma()) / om;
    Ok(front * bracket)
}

/// A bound B(x) on the guaranteed improvement of a step x that can be enclosed in interval
/// arithmetic, with x taken as an exact real.
///
/// Implement it for a new step form and pass the form's `f64` [`StepOutcome`] to
/// [`certify`].
pub trait EnclosedBound {
    /// An interval that contains the exact value B(x).
    fn enclose(&self, x: f64) -> Interval;

    /// An approximation of B'(x), used only to guess how far a failing step must move
    /// (any value, or `None`, keeps [`certify`] correct; a good one makes it faster).
    fn slope(&self, _x: f64) -> Option<f64> {
        None
    }
}

/// The concave parabola B(x) = a·x − b·x² (b ≥ 0) shared by Theorems 4.2, 4.3, 4.5, 4.7–4.9,
/// with enclosed coefficients.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quadratic {
    /// Enclosure of the linear coefficient a.
    pub linear: Interval,
    /// Enclosure of the quadratic coefficient b ≥ 0.
    pub quadratic: Interval,
}

impl Quadratic {
    /// Theorem 4.2: a = ‖∇_vJ‖∞², b = c(σ)‖∇_vJ‖∞².
    ///
    /// ```
    /// use sepg_bounds::{certified::{EnclosedBound, Quadratic}, constants::TaskConstants, v_update};
    /// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
    /// let q = Quadratic::v_update(&k, 1.0, &[0.3, -0.7])?;
    /// assert!(q.enclose(0.01).contains(v_update::bound(&k, 1.0, &[0.3, -0.7], 0.01)?));
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn v_update(k: &TaskConstants, sigma: f64, grad_v: &[f64]) -> Result<Self, BoundsError> {
        finite_vector("grad_v", grad_v)?;
        let n2 = Interval::point(inf_norm(grad_v)).sqr();
        Ok(Self {
            linear: n2,
            quadratic: c(k, sigma)? * n2,
        })
    }

    /// Theorem 4.3: a = (∇_wJ)², b = d(σ)(∇_wJ)².
    ///
    /// ```
    /// use sepg_bounds::{certified::{EnclosedBound, Quadratic}, constants::TaskConstants, w_update};
    /// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
    /// let q = Quadratic::w_along_j(&k, 1.0, 0.3)?;
    /// assert!(q.enclose(0.2).contains(w_update::bound_along_j(&k, 1.0, 0.3, 0.2)?));
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn w_along_j(k: &TaskConstants, sigma: f64, grad_w_j: f64) -> Result<Self, BoundsError> {
        let g2 = Interval::point(finite("grad_w_j", grad_w_j)?).sqr();
        Ok(Self {
            linear: g2,
            quadratic: d(k, sigma)? * g2,
        })
    }

    /// Theorem 4.5: a = ∇_wL ∇_wJ, b = d(σ)(∇_wL)².
    ///
    /// ```
    /// use sepg_bounds::{certified::{EnclosedBound, Quadratic}, constants::TaskConstants, w_update};
    /// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
    /// let q = Quadratic::w_along_l(&k, 1.0, 0.3, -2.0)?;
    /// assert!(q.enclose(-0.1).contains(w_update::bound_along_l(&k, 1.0, 0.3, -2.0, -0.1)?));
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn w_along_l(
        k: &TaskConstants,
        sigma: f64,
        grad_w_j: f64,
        grad_w_l: f64,
    ) -> Result<Self, BoundsError> {
        let j = Interval::point(finite("grad_w_j", grad_w_j)?);
        let l = Interval::point(finite("grad_w_l", grad_w_l)?);
        Ok(Self {
            linear: l * j,
            quadratic: d(k, sigma)? * l.sqr(),
        })
    }

    /// An enclosure of C_max = a²/(4b), the value at the vertex.
    ///
    /// ```
    /// use sepg_bounds::{certified::Quadratic, constants::TaskConstants, v_update};
    /// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
    /// let q = Quadratic::v_update(&k, 1.0, &[0.5])?;
    /// assert!(q.c_max().contains(v_update::c_max(&k, 1.0, &[0.5])?));
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn c_max(&self) -> Interval {
        self.linear.sqr() / self.quadratic.scale(4.0)
    }

    /// An enclosure of the vertex a/(2b).
    pub fn vertex(&self) -> Interval {
        self.linear / self.quadratic.scale(2.0)
    }

    /// An enclosure of λ = √(1 − C/C_max) (eqs. (4.10), (4.17), (4.19)), for C ≤ C_max.
    ///
    /// ```
    /// use sepg_bounds::{certified::Quadratic, constants::TaskConstants, v_update};
    /// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
    /// let q = Quadratic::v_update(&k, 1.0, &[0.5])?;
    /// let cmax = v_update::c_max(&k, 1.0, &[0.5])?;
    /// assert!(q.lambda(0.75 * cmax).contains(0.5));
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn lambda(&self, required: f64) -> Interval {
        (Interval::point(1.0) - Interval::point(required) / self.c_max()).sqrt()
    }

    /// Enclosures of the two real end points of {x : a x − b x² ≥ C}, or `None` when the
    /// enclosure cannot exclude C > C_max (no real end points).
    ///
    /// # Formula
    ///
    /// ```text
    /// s = √(a² − 4bC);  a > 0: hi = (a + s)/(2b), lo = 2C/(a + s);
    ///                   a < 0: lo = (a − s)/(2b), hi = 2C/(a − s)
    /// ```
    ///
    /// ```
    /// use sepg_bounds::{certified::Quadratic, constants::TaskConstants, outcome::StepOutcome, v_update};
    /// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
    /// let q = Quadratic::v_update(&k, 1.0, &[0.5])?;
    /// let StepOutcome::Feasible(s) = v_update::safe_step(&k, 1.0, &[0.5], 0.0)? else { panic!() };
    /// let (lo, hi) = q.end_points(0.0).unwrap();
    /// assert!(lo.contains(s.lo) && hi.contains(s.hi));
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn end_points(&self, required: f64) -> Option<(Interval, Interval)> {
        let cc = Interval::point(required);
        let disc = self.linear.sqr() - self.quadratic.scale(4.0) * cc;
        if disc.hi() < 0.0 {
            return None;
        }
        let s = disc.sqrt();
        let two_b = self.quadratic.scale(2.0);
        let two_c = cc.scale(2.0);
        if self.linear.lo() > 0.0 {
            let sum = self.linear + s;
            Some((two_c / sum, sum / two_b))
        } else if self.linear.hi() < 0.0 {
            let diff = self.linear - s;
            Some((diff / two_b, two_c / diff))
        } else {
            Some(((self.linear - s) / two_b, (self.linear + s) / two_b))
        }
    }
}

impl EnclosedBound for Quadratic {
    #[inline]
    fn enclose(&self, x: f64) -> Interval {
        (self.linear - self.quadratic.scale(x)).scale(x)
    }

    fn slope(&self, x: f64) -> Option<f64> {
        Some(self.linear.lo() - 2.0 * self.quadratic.lo() * x)
    }
}

/// The high-probability bounds of Theorems 4.7–4.9 with enclosed coefficients, in either
/// form of [`HpForm`] (see [`crate::high_probability`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HpEnclosure {
    /// s = ±1, the direction the estimates favour.
    pub direction: f64,
    /// Enclosure of a⁻.
    pub linear_lower: Interval,
    /// Enclosure of a⁺.
    pub linear_upper: Interval,
    /// Enclosure of b.
    pub quadratic: Interval,
    /// Which form is evaluated.
    pub form: HpForm,
}

/// Enclosures of (‖∇̂‖ − ε)² and (‖∇̂‖ + ε)² (Section 4.5); `None` when ‖∇̂‖ ≤ ε.
fn corrected_squares(n: f64, eps: f64) -> Option<(Interval, Interval)> {
    (n > eps).then(|| {
        let (n, e) = (Interval::point(n), Interval::point(eps));
        let lower = n - e;
        // n > ε exactly, so the corrected norm is positive even if rounding says otherwise
        let lower = Interval::new(lower.lo().max(0.0), lower.hi()).unwrap_or(lower);
        (lower.sqr(), (n + e).sqr())
    })
}

impl HpEnclosure {
    /// Theorem 4.7: s = +1, a⁻ = (‖∇̂_vJ‖∞ − ε)², a⁺ = (‖∇̂_vJ‖∞ + ε)², b = c(σ)a⁺; `None`
    /// when ‖∇̂_vJ‖∞ ≤ ε.
    pub fn v_update(
        k: &TaskConstants,
        sigma: f64,
        grad_v_hat: &[f64],
        eps: f64,
        form: HpForm,
    ) -> Result<Option<Self>, BoundsError> {
        finite_vector("grad_hat", grad_v_hat)?;
        let cc = c(k, sigma)?;
        Ok(
            corrected_squares(inf_norm(grad_v_hat), eps).map(|(lower, upper)| Self {
                direction: 1.0,
                linear_lower: lower,
                linear_upper: upper,
                quadratic: cc * upper,
                form,
            }),
        )
    }

    /// Theorem 4.8: s = +1, a⁻ = (|∇̂_wJ| − ε)², a⁺ = (|∇̂_wJ| + ε)², b = d(σ)a⁺.
    pub fn w_along_j(
        k: &TaskConstants,
        sigma: f64,
        grad_w_j_hat: f64,
        eps: f64,
        form: HpForm,
    ) -> Result<Option<Self>, BoundsError> {
        finite("grad_hat", grad_w_j_hat)?;
        let dd = d(k, sigma)?;
        Ok(
            corrected_squares(grad_w_j_hat.abs(), eps).map(|(lower, upper)| Self {
                direction: 1.0,
                linear_lower: lower,
                linear_upper: upper,
                quadratic: dd * upper,
                form,
            }),
        )
    }

    /// Theorem 4.9: s = sign(∇̂_wJ ∇̂_wL), a⁻ = L⁻J⁻, a⁺ = L⁺J⁺, b = d(σ)(L⁺)².
    pub fn w_along_l(
        k: &TaskConstants,
        sigma: f64,
        (grad_w_j_hat, eps_j): (f64, f64),
        (grad_w_l_hat, eps_l): (f64, f64),
        form: HpForm,
    ) -> Result<Option<Self>, BoundsError> {
        finite("grad_hat", grad_w_j_hat)?;
        finite("grad_hat", grad_w_l_hat)?;
        let dd = d(k, sigma)?;
        let (nj, nl) = (grad_w_j_hat.abs(), grad_w_l_hat.abs());
        if nj <= eps_j || nl <= eps_l {
            return Ok(None);
        }
        let positive_part = |x: Interval| Interval::new(x.lo().max(0.0), x.hi()).unwrap_or(x);
        let j_lo = positive_part(Interval::point(nj) - Interval::point(eps_j));
        let l_lo = positive_part(Interval::point(nl) - Interval::point(eps_l));
        let j_hi = Interval::point(nj) + Interval::point(eps_j);
        let l_hi = Interval::point(nl) + Interval::point(eps_l);
        let direction = if (grad_w_j_hat > 0.0) == (grad_w_l_hat > 0.0) {
            1.0
        } else {
            -1.0
        };
        Ok(Some(Self {
            direction,
            linear_lower: l_lo * j_lo,
            linear_upper: l_hi * j_hi,
            quadratic: dd * l_hi.sqr(),
            form,
        }))
    }

    /// The parabola that the bound equals on the side of x.
    fn side(&self, x: f64) -> Quadratic {
        let favoured = self.direction * x >= 0.0;
        let a = if favoured || self.form == HpForm::Thesis {
            self.linear_lower
        } else {
            self.linear_upper
        };
        Quadratic {
            linear: if self.direction > 0.0 { a } else { -a },
            quadratic: self.quadratic,
        }
    }
}

impl EnclosedBound for HpEnclosure {
    #[inline]
    fn enclose(&self, x: f64) -> Interval {
        self.side(x).enclose(x)
    }

    fn slope(&self, x: f64) -> Option<f64> {
        self.side(x).slope(x)
    }
}

/// The rigorous w-bound of [`crate::rigorous`] for Δw = β·u, enclosed.
///
/// ```text
/// f(Δw) = Δw ∇_w J − a Δw² max(1, e^{−Δw}) − G · KL2(Δw),
/// a = Rψ|A| / (2(1−γ)²σ),   G = γR / (2(1−γ)³)
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigorousEnclosure {
    a: Interval,
    a_line: Interval,
    g: Interval,
    slope: f64,
    direction: f64,
}

impl RigorousEnclosure {
    /// The rigorous bound of a step β along the direction u (Δw = β·u): u = ∇_wJ for
    /// [`rigorous::safe_step_along_j`], u = ∇_wL for [`rigorous::safe_step_along_l`].
    ///
    /// ```
    /// use sepg_bounds::{certified::{EnclosedBound, RigorousEnclosure}, constants::TaskConstants, rigorous};
    /// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
    /// let r = RigorousEnclosure::new(&k, 1.0, 0.5, 0.5)?;
    /// assert!(r.enclose(-0.2).contains(rigorous::bound(&k, 1.0, 0.5, -0.1)?));
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn new(
        k: &TaskConstants,
        sigma: f64,
        grad_w_j: f64,
        direction: f64,
    ) -> Result<Self, BoundsError> {
        positive("sigma", sigma)?;
        let om = one_minus_gamma(k);
        let r = Interval::point(k.r_max());
        let a = r * psi_of(k) * Interval::point(k.action_volume())
            / (om.sqr() * Interval::point(sigma).scale(2.0));
        let g = Interval::point(k.gamma()) * r / (om.sqr() * om).scale(2.0);
        // K_W of `rigorous::k_w` is computed to within a few ulps (tested against a 60-digit
        // table to 1e-15); 1e-13 relative encloses it with a wide margin.
        let kw = rigorous::k_w();
        let k_w = Interval::new(kw * (1.0 - 1e-13), kw * (1.0 + 1e-13)).unwrap_or(Interval::ENTIRE);
        let a_line = r * k_w / om.sqr().scale(2.0);
        Ok(Self {
            a,
            a_line,
            g,
            slope: finite("grad_w_j", grad_w_j)?,
            direction: finite("direction", direction)?,
        })
    }
}

/// Encloses KL2(t) = e^{−2t} − 1 + 2t at an exact t ≥ 0 (see [`rigorous::kl2`]).
fn kl2_at(t: f64) -> Interval {
    if t == 0.0 {
        return Interval::point(0.0);
    }
    let y = Interval::point(t).scale(2.0);
    if y.hi() < 0.1 {
        // Σ_{n≥2} (−y)^n / n!: alternating with decreasing terms, so the tail after n = 17 lies
        // between 0 and the first omitted term y^18/18!
        let mut term = y.sqr() / Interval::point(2.0);
        let mut sum = term;
        for n in 3..18 {
            term = -(term * y) / Interval::point(f64::from(n));
            sum = sum + term;
        }
        let next = (term * y / Interval::point(18.0)).hi().abs();
        sum + Interval::new(0.0, next).unwrap_or(Interval::ENTIRE)
    } else {
        (-y).exp_m1() + y
    }
}

impl EnclosedBound for RigorousEnclosure {
    fn enclose(&self, beta: f64) -> Interval {
        if beta == 0.0 {
            // f(0) = 0 exactly
            return Interval::point(0.0);
        }
        let dw = Interval::point(beta).scale(self.direction);
        let curvature = Interval::point(1.0).max((-dw).exp());
        let m = dw.abs();
        let kl =
            Interval::new(kl2_at(m.lo()).lo(), kl2_at(m.hi()).hi()).unwrap_or(Interval::ENTIRE);
        let coefficient = (self.a * curvature).max(self.a_line);
        dw.scale(self.slope) - coefficient * dw.sqr() - self.g * kl
    }
}

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
    /// use sepg_bounds::{certified, constants::TaskConstants};
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
/// use sepg_bounds::{certified::{self, Certified, Quadratic}, constants::TaskConstants, v_update};
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
/// use sepg_bounds::{certified::{certify_toward, Quadratic}, constants::TaskConstants, outcome::StepOutcome, w_update};
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
    let (mut failed, mut good, mut good_enclosure) = match passes(guess) {
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
    while good - failed > 1 {
        let mid = failed + (good - failed) / 2;
        match passes(mid) {
            (true, e) => (good, good_enclosure) = (mid, e),
            (false, _) => failed = mid,
        }
    }
    Ok((at(good), good_enclosure, good))
}

/// Certifies `outcome` with the fast a-priori enclosure `fast` (module `rounding`) when it
/// applies and certifies a step, and otherwise with the interval enclosure `interval` (`None`:
/// below noise). The body shared by every certified step form.
#[inline(always)]
fn certify_fast_then_interval<S: EnclosedBound>(
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

/// The common tail of the certified high-probability steps: [`certify_feasible`] on the
/// feasible interval of `bound`, else the full path on its outcome
/// ([`hp::safe_step_or_below_noise`]).
#[inline(always)]
fn certify_high_probability<S: EnclosedBound>(
    bound: Option<hp::HighProbabilityBound>,
    required: f64,
    form: HpForm,
    fast: impl FnOnce() -> Option<RoundedBound> + Copy,
    interval: impl FnOnce() -> Result<Option<S>, BoundsError>,
) -> Result<Certified, BoundsError> {
    certify_step(
        bound.and_then(|b| b.feasible_step(required, form)),
        required,
        move || hp::safe_step_or_below_noise(bound, required, form),
        fast,
        interval,
    )
}

/// The body of the certified steps with an error-free companion: [`certify_feasible`] on the
/// companion's interval `feasible`, else, out of line, the full path on the outcome that
/// `outcome` computes ([`certify_out_of_line`]).
#[inline(always)]
fn certify_step<S: EnclosedBound>(
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

/// The parabola a·x − b·x² with a = g², b = k·g² (Theorems 4.2, 4.3) in rounded `f64`.
fn squared_parabola(g: f64, k: Option<Rounded>) -> Option<RoundedBound> {
    let g = Rounded::exact(g);
    let a = g.mul(g)?;
    Some(RoundedBound::parabola(a, k?.mul(a)?))
}

/// The high-probability bound with s = +1, a^∓ = (n ∓ ε)², b = k·a⁺ (Theorems 4.7, 4.8) in
/// rounded `f64`; only called when n > ε.
fn corrected_parabola(n: f64, eps: f64, k: Option<Rounded>, form: HpForm) -> Option<RoundedBound> {
    let (lower, upper) = (Rounded::difference(n, eps), Rounded::sum(n, eps));
    let upper2 = upper.mul(upper)?;
    Some(RoundedBound::high_probability(
        1.0,
        lower.mul(lower)?,
        upper2,
        k?.mul(upper2)?,
        form,
    ))
}

/// Certified safe v-step of Theorem 4.2 (eq. (4.10)) for the requirement C.
///
/// # Formula
///
/// ```text
/// B(α) = α ‖∇_v J‖∞² − α² c(σ) ‖∇_v J‖∞²,   certified: enclosure of B(α) ≥ C
/// ```
///
/// ```
/// use sepg_bounds::{certified::{self, Certified}, constants::TaskConstants, v_update};
/// let k = TaskConstants::new(0.99, 4.0, 2.0, 4.0)?;
/// let cmax = v_update::c_max(&k, 1.0, &[0.8])?;
/// assert!(certified::v_safe_step(&k, 1.0, &[0.8], 0.5 * cmax)?.is_certified());
/// // C = C_max exactly cannot be certified in floating point
/// let o = certified::v_safe_step(&k, 1.0, &[0.8], cmax)?;
/// assert!(matches!(o, Certified::Uncertifiable { .. }));
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn v_safe_step(
    k: &TaskConstants,
    sigma: f64,
    grad_v: &[f64],
    required: f64,
) -> Result<Certified, BoundsError> {
    finite_vector("grad_v", grad_v)?;
    finite("required", required)?;
    let cc = constants::c(k, sigma)?;
    let n = inf_norm(grad_v);
    let fast = move || squared_parabola(n, rounding::c(k, sigma, cc));
    let interval = v_update::feasible_with_norm(cc, n, required);
    certify_step(
        interval,
        required,
        move || v_update::safe_step_with_norm(cc, n, required),
        fast,
        move || Quadratic::v_update(k, sigma, grad_v).map(Some),
    )
}

/// Certified safe steps along ∇_w J, Theorem 4.3 (eq. (4.17)).
///
/// ```
/// use sepg_bounds::{certified, constants::TaskConstants};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// assert!(certified::w_safe_step_along_j(&k, 1.0, 0.3, 0.0)?.is_certified());
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn w_safe_step_along_j(
    k: &TaskConstants,
    sigma: f64,
    grad_w_j: f64,
    required: f64,
) -> Result<Certified, BoundsError> {
    finite("grad_w_j", grad_w_j)?;
    finite("required", required)?;
    let dd = constants::d(k, sigma)?;
    let fast = move || squared_parabola(grad_w_j, rounding::d(k, sigma, dd));
    let interval = w_update::feasible_along_j_with_d(dd, grad_w_j, required);
    certify_step(
        interval,
        required,
        move || w_update::safe_step_along_j_with_d(dd, grad_w_j, required),
        fast,
        move || Quadratic::w_along_j(k, sigma, grad_w_j).map(Some),
    )
}

/// Certified safe steps along ∇_w L, Theorem 4.5 (eq. (4.19)).
///
/// ```
/// use sepg_bounds::{certified, constants::TaskConstants};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let o = certified::w_safe_step_along_l(&k, 1.0, 0.3, -2.0, -0.1)?;
/// assert!(o.is_certified() && o.bound().unwrap().lo() >= -0.1);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn w_safe_step_along_l(
    k: &TaskConstants,
    sigma: f64,
    grad_w_j: f64,
    grad_w_l: f64,
    required: f64,
) -> Result<Certified, BoundsError> {
    finite("grad_w_j", grad_w_j)?;
    finite("grad_w_l", grad_w_l)?;
    finite("required", required)?;
    let dd = constants::d(k, sigma)?;
    let fast = move || {
        let (j, l) = (Rounded::exact(grad_w_j), Rounded::exact(grad_w_l));
        let b = rounding::d(k, sigma, dd)?.mul(l.mul(l)?)?;
        Some(RoundedBound::parabola(l.mul(j)?, b))
    };
    let interval = w_update::feasible_along_l_with_d(dd, grad_w_j, grad_w_l, required);
    certify_step(
        interval,
        required,
        move || w_update::safe_step_along_l_with_d(dd, grad_w_j, grad_w_l, required),
        fast,
        move || Quadratic::w_along_l(k, sigma, grad_w_j, grad_w_l).map(Some),
    )
}

/// Certified high-probability v-step, Theorem 4.7 (eq. (4.26)), in the form `form`.
///
/// ```
/// use sepg_bounds::{certified, constants::TaskConstants, high_probability::HpForm};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// assert!(certified::hp_v_safe_step(&k, 1.0, &[0.5], 0.1, 0.0, HpForm::SignAware)?.is_certified());
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn hp_v_safe_step(
    k: &TaskConstants,
    sigma: f64,
    grad_v_hat: &[f64],
    eps: f64,
    required: f64,
    form: HpForm,
) -> Result<Certified, BoundsError> {
    finite("required", required)?;
    let cc = constants::c(k, sigma)?;
    let bound = hp::HighProbabilityBound::v_update_with_c(cc, grad_v_hat, eps)?;
    let fast =
        move || corrected_parabola(inf_norm(grad_v_hat), eps, rounding::c(k, sigma, cc), form);
    certify_high_probability(bound, required, form, fast, move || {
        HpEnclosure::v_update(k, sigma, grad_v_hat, eps, form)
    })
}

/// Certified high-probability step along ∇̂_w J, Theorem 4.8 (eq. (4.29)).
///
/// ```
/// use sepg_bounds::{certified, constants::TaskConstants, high_probability::HpForm};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let o = certified::hp_w_safe_step_along_j(&k, 1.0, 0.5, 0.1, -0.01, HpForm::SignAware)?;
/// assert!(o.is_certified());
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn hp_w_safe_step_along_j(
    k: &TaskConstants,
    sigma: f64,
    grad_w_j_hat: f64,
    eps: f64,
    required: f64,
    form: HpForm,
) -> Result<Certified, BoundsError> {
    finite("required", required)?;
    let dd = constants::d(k, sigma)?;
    let bound = hp::HighProbabilityBound::w_along_j_with_d(dd, grad_w_j_hat, eps)?;
    let fast = move || corrected_parabola(grad_w_j_hat.abs(), eps, rounding::d(k, sigma, dd), form);
    certify_high_probability(bound, required, form, fast, move || {
        HpEnclosure::w_along_j(k, sigma, grad_w_j_hat, eps, form)
    })
}

/// Certified high-probability step along ∇̂_w L, Theorem 4.9 (eq. (4.30)); the estimates
/// come as (value, width) pairs.
///
/// ```
/// use sepg_bounds::{certified, constants::TaskConstants, high_probability::HpForm};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let o = certified::hp_w_safe_step_along_l(&k, 1.0, (0.5, 0.1), (-2.0, 0.5), -0.01, HpForm::SignAware)?;
/// assert!(o.chosen_step().unwrap() > 0.0);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn hp_w_safe_step_along_l(
    k: &TaskConstants,
    sigma: f64,
    grad_w_j_hat: (f64, f64),
    grad_w_l_hat: (f64, f64),
    required: f64,
    form: HpForm,
) -> Result<Certified, BoundsError> {
    let (j, ej) = grad_w_j_hat;
    let (l, el) = grad_w_l_hat;
    finite("required", required)?;
    let dd = constants::d(k, sigma)?;
    let bound = hp::HighProbabilityBound::w_along_l_with_d(dd, j, ej, l, el)?;
    let fast = move || {
        let (nj, nl) = (j.abs(), l.abs());
        let (l_hi, j_hi) = (Rounded::sum(nl, el), Rounded::sum(nj, ej));
        let lower = Rounded::difference(nl, el).mul(Rounded::difference(nj, ej))?;
        let b = rounding::d(k, sigma, dd)?.mul(l_hi.mul(l_hi)?)?;
        let direction = if (j > 0.0) == (l > 0.0) { 1.0 } else { -1.0 };
        Some(RoundedBound::high_probability(
            direction,
            lower,
            l_hi.mul(j_hi)?,
            b,
            form,
        ))
    };
    certify_high_probability(bound, required, form, fast, move || {
        HpEnclosure::w_along_l(k, sigma, grad_w_j_hat, grad_w_l_hat, form)
    })
}

/// Certified rigorous steps along ∇_w J ([`rigorous::safe_step_along_j`]); interval
/// arithmetic only (the bound involves e^x).
///
/// ```
/// use sepg_bounds::{certified, constants::TaskConstants};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// assert!(certified::rigorous_safe_step_along_j(&k, 1.0, 0.5, 0.0)?.is_certified());
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn rigorous_safe_step_along_j(
    k: &TaskConstants,
    sigma: f64,
    grad_w_j: f64,
    required: f64,
) -> Result<Certified, BoundsError> {
    let outcome = rigorous::safe_step_along_j(k, sigma, grad_w_j, required)?;
    certify_fast_then_interval(
        outcome,
        required,
        || None,
        || RigorousEnclosure::new(k, sigma, grad_w_j, grad_w_j).map(Some),
    )
}

/// Certified rigorous steps along ∇_w L ([`rigorous::safe_step_along_l`]); interval
/// arithmetic only.
///
/// ```
/// use sepg_bounds::{certified, constants::TaskConstants};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let o = certified::rigorous_safe_step_along_l(&k, 1.0, 0.5, -3.0, -0.01)?;
/// assert!(o.chosen_step().unwrap() > 0.0);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn rigorous_safe_step_along_l(
    k: &TaskConstants,
    sigma: f64,
    grad_w_j: f64,
    grad_w_l: f64,
    required: f64,
) -> Result<Certified, BoundsError> {
    let outcome = rigorous::safe_step_along_l(k, sigma, grad_w_j, grad_w_l, required)?;
    certify_fast_then_interval(
        outcome,
        required,
        || None,
        || RigorousEnclosure::new(k, sigma, grad_w_j, grad_w_l).map(Some),
    )
}

/// The bound of the exploring w-update (`crate::exploring`) as a function of the step size β
/// along ∇̂_w L (Δw = β·∇̂_w L), with an enclosed d(σ).
///
/// # Formula
///
/// ```text
/// B(β) = Δw·∇̂_w J − |Δw|·ε_J − d(σ)·Δw²,   Δw = β·∇̂_w L
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExploringEnclosure {
    /// ∇̂_w J.
    pub grad_w_j_hat: f64,
    /// ε_J ≥ 0.
    pub eps_j: f64,
    /// ∇̂_w L, the direction.
    pub grad_w_l_hat: f64,
    /// Enclosure of d(σ).
    pub d: Interval,
}

impl ExploringEnclosure {
    /// The enclosure for the task `k` at standard deviation `sigma`.
    ///
    /// # Errors
    /// Non-finite estimates, ε_J < 0, and the errors of [`d`].
    pub fn new(
        k: &TaskConstants,
        sigma: f64,
        grad_w_j_hat: f64,
        eps_j: f64,
        grad_w_l_hat: f64,
    ) -> Result<Self, BoundsError> {
        let eps_j = non_negative("eps_j", eps_j)?;
        Ok(ExploringEnclosure {
            grad_w_j_hat: finite("grad_w_j_hat", grad_w_j_hat)?,
            eps_j,
            grad_w_l_hat: finite("grad_w_l_hat", grad_w_l_hat)?,
            d: d(k, sigma)?,
        })
    }
}

impl EnclosedBound for ExploringEnclosure {
    fn enclose(&self, x: f64) -> Interval {
        let dw = Interval::point(x).scale(self.grad_w_l_hat);
        dw.scale(self.grad_w_j_hat) - dw.abs().scale(self.eps_j) - self.d * dw.sqr()
    }

    fn slope(&self, x: f64) -> Option<f64> {
        let l = self.grad_w_l_hat;
        let dw = x * l;
        Some(l * (self.grad_w_j_hat - dw.signum() * self.eps_j - 2.0 * self.d.lo() * dw))
    }
}

/// Certified exploring w-step along ∇̂_w L (`crate::exploring::w_exploring_step`) for the
/// requirement C: the returned β's enclosed bound has lower end ≥ C.
///
/// ```
/// use sepg_bounds::{certified, constants::TaskConstants};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let o = certified::exploring_safe_step(&k, 1.0, -0.3, 0.1, 0.4, -0.01)?;
/// assert!(o.is_certified() && o.bound().unwrap().lo() >= -0.01);
/// assert!(o.chosen_step().unwrap() > 0.0);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn exploring_safe_step(
    k: &TaskConstants,
    sigma: f64,
    grad_w_j_hat: f64,
    eps_j: f64,
    grad_w_l_hat: f64,
    required: f64,
) -> Result<Certified, BoundsError> {
    let bound = ExploringBound::new(k, sigma, grad_w_j_hat, eps_j)?;
    let outcome = bound.step_along(grad_w_l_hat, required)?;
    let fast = move || {
        // in β (Δw = β·l): a = l·(j − sign(l)·ε) for β ≥ 0, l·(j + sign(l)·ε) for β < 0,
        // b = d·l²
        let l = Rounded::exact(grad_w_l_hat);
        let (toward, against) = (
            Rounded::difference(grad_w_j_hat, eps_j),
            Rounded::sum(grad_w_j_hat, eps_j),
        );
        let (pos, neg) = if grad_w_l_hat > 0.0 {
            (toward, against)
        } else {
            (against, toward)
        };
        let b = rounding::d(k, sigma, bound.d)?.mul(l.mul(l)?)?;
        Some(RoundedBound::two_sided(l.mul(pos)?, l.mul(neg)?, b))
    };
    certify_fast_then_interval(outcome, required, fast, move || {
        ExploringEnclosure::new(k, sigma, grad_w_j_hat, eps_j, grad_w_l_hat).map(Some)
    })
}

/// The adaptive step of Pirotta et al. with fixed σ (Corollary 3.11, the step of the
/// AdaStep comparison algorithm) with a certified guarantee: the step is α* of
/// [`pirotta::optimal_step`], and `bound` encloses the Theorem 3.10 bound at that `f64` α*,
/// so `bound.lo()` is a guarantee that holds in exact arithmetic (the `f64` guarantee α*‖∇‖₂²/2
/// can exceed it by rounding).
///
/// # Formula
///
/// ```text
/// B(α) = α ‖∇J‖₂² − α² c(σ) ‖∇J‖₁²,   α* = ‖∇J‖₂² / (2 c(σ) ‖∇J‖₁²)
/// ```
///
/// Outcomes: [`Certified::Step`] with `ulps_moved` 0 and the degenerate `interval` [α*, α*]
/// whose `c_max` is the `f64` guarantee; [`Certified::ZeroGradient`] for ∇J = 0. There is no
/// requirement to certify: the guarantee is whatever the step attains.
///
/// ```
/// use sepg_bounds::{certified, constants::TaskConstants, pirotta};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// let o = certified::adaptive_step(&k, 1.0, &[0.3, -0.5])?;
/// let b = o.bound().unwrap();
/// assert!(b.lo() <= pirotta::bound(&k, 1.0, &[0.3, -0.5], o.chosen_step().unwrap())?);
/// assert!(b.lo() > 0.0 && b.width() < 1e-15);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn adaptive_step(
    k: &TaskConstants,
    sigma: f64,
    grad: &[f64],
) -> Result<Certified, BoundsError> {
    let (alpha, guarantee) = match pirotta::optimal_step(k, sigma, grad)? {
        pirotta::AdaptiveStep::Step { alpha, guarantee } => (alpha, guarantee),
        pirotta::AdaptiveStep::ZeroGradient => {
            return Ok(Certified::ZeroGradient {
                requirement_met: true,
            });
        }
        _ => return Ok(Certified::BelowNoise),
    };
    let (l2, l1) = grad.iter().fold(
        (Interval::point(0.0), Interval::point(0.0)),
        |(l2, l1), &g| (l2 + Interval::point(g).sqr(), l1 + Interval::point(g.abs())),
    );
    let bound = Quadratic {
        linear: l2,
        quadratic: c(k, sigma)? * l1.sqr(),
    }
    .enclose(alpha);
    Ok(Certified::Step(CertifiedStep {
        step: alpha,
        bound,
        ulps_moved: 0,
        interval: SafeInterval {
            c_max: guarantee,
            vertex: alpha,
            lambda: Some(0.0),
            lo: alpha,
            hi: alpha,
        },
        by_error_bound: false,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_error_bound_certifies_ordinary_steps_and_intervals_the_rest() {
        let k = TaskConstants::new(0.99, 28.8, 4.0, 8.0).expect("lqg1d constants");
        let Ok(Certified::Step(s)) = v_safe_step(&k, 0.5, &[-3.7], 0.0) else {
            panic!("certified")
        };
        assert!(s.by_error_bound && s.bound.lo() >= 0.0 && s.ulps_moved > 0);
        // σ below 2⁻¹⁰⁰: the rounding analysis of c does not apply
        let Ok(Certified::Step(s)) = v_safe_step(&k, 1e-31, &[1e-60], 0.0) else {
            panic!("certified")
        };
        assert!(!s.by_error_bound && s.bound.lo() >= 0.0);
        // the same step form certified both ways meets C both ways
        let cmax = v_update::c_max(&k, 0.5, &[-3.7]).expect("finite");
        for required in [0.5 * cmax, -cmax] {
            let fast = v_safe_step(&k, 0.5, &[-3.7], required).expect("valid");
            let outcome = v_update::safe_step(&k, 0.5, &[-3.7], required).expect("valid");
            let q = Quadratic::v_update(&k, 0.5, &[-3.7]).expect("valid");
            let slow = certify(&q, outcome, required);
            let (Certified::Step(f), Certified::Step(s)) = (fast, slow) else {
                panic!("both certified")
            };
            assert!(f.by_error_bound && !s.by_error_bound);
            assert!(f.bound.lo() >= required && s.bound.lo() >= required);
            // the predicted move is at most 1/8 longer than the fewest ulps, plus 2
            // the error bound is wider (about (k+7)u per term, k ≤ 18) than the interval
            // enclosure, so its step moves further in, but by a negligible amount
            assert!((f.step - s.step).abs() <= 1e-13 * s.step.abs());
        }
    }
}
