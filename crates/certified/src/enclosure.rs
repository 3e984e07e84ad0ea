//! Enclosures: intervals that contain the exact real value of the constants √(2π), ψ, c(σ),
//! d(σ) and of each bound form of `sepg-bounds` at an exact step ([`EnclosedBound`]).

use sepg_bounds::constants::TaskConstants;
use sepg_bounds::direction::{Direction, FeatureNorm};
use sepg_bounds::error::{BoundsError, finite, finite_vector, inf_norm, non_negative, positive};
use sepg_bounds::high_probability::HpForm;
use sepg_bounds::penalties::{Family, Horizon, Rewards, Tight};
use sepg_bounds::rigorous;

use crate::interval::Interval;

/// √(2π) ∈ [2.5066282746310002, 2.5066282746310007] (the two `f64` around it).
const SQRT_2PI_LO: f64 = 2.506_628_274_631_000_2;
const SQRT_2PI_HI: f64 = 2.506_628_274_631_000_7;
/// ψ ∈ [0.5235570203213736, 0.5235570203213737] (Lemma A.1).
const PSI_LO: f64 = 0.523_557_020_321_373_6;
const PSI_HI: f64 = 0.523_557_020_321_373_7;

/// An enclosure of √(2π): the two neighbouring `f64` around it.
///
/// ```
/// let s = sepg_certified::sqrt_2pi();
/// assert!(s.contains((2.0 * std::f64::consts::PI).sqrt()));
/// assert!(s.width() < 1e-15);
/// ```
pub fn sqrt_2pi() -> Interval {
    Interval::from_sorted(SQRT_2PI_LO, SQRT_2PI_HI)
}

/// An enclosure of ψ = 4(√7 − 2)e^{√7/2 − 2}/√(2π) of Lemma A.1 (see
/// [`sepg_bounds::constants::psi`]): the two neighbouring `f64` around it.
///
/// ```
/// let p = sepg_certified::psi();
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

/// S_H of the tight constants ([`sepg_bounds::constants::s_h`]), enclosed.
///
/// For H ≤ 2²⁰ the `f64` value kept by the task constants is Horner's sum of H positive terms
/// with two roundings each, so Ŝ = S_H (1 + θ) with |θ| ≤ γ_{2H} = 2Hu/(1 − 2Hu), and
/// |S_H − Ŝ| ≤ 4Hu·Ŝ (2Hu ≤ 2⁻³²). Beyond, or for H = ∞, [1, 1/(1 − γ)²] (S_H increases
/// to S_∞ = 1/(1 − γ)²; equality for H = ∞).
fn s_h(k: &TaskConstants, tight: Tight) -> Interval {
    let om = one_minus_gamma(k);
    let infinite = Interval::point(1.0) / om.sqr();
    match tight.horizon() {
        Horizon::Infinite => infinite,
        Horizon::Finite(h) if h <= 1 << 20 => {
            let value = k.horizon_weight();
            Interval::around(value, value * (4.0 * h as f64 * f64::EPSILON / 2.0))
        }
        Horizon::Finite(_) => Interval::point(1.0).hull(infinite),
    }
}

/// ρ of the tight constants: 1, or 1/2 for non-positive rewards (exact in `f64`).
fn rho(tight: Tight) -> f64 {
    match tight.rewards() {
        Rewards::NonPositive => 0.5,
        Rewards::TwoSided => 1.0,
    }
}

/// An enclosure of c(σ) of Theorems 3.14 / 4.2 (see [`sepg_bounds::constants::c`]), or of
/// the tight family's c(σ) = ρ R M_φ² S_H / σ².
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
/// use sepg_bounds::{constants::{self, TaskConstants}};
/// use sepg_certified as certified;
/// let k = TaskConstants::new(0.99, 4.0, 2.0, 4.0)?;
/// assert!(certified::c(&k, 0.3)?.contains(constants::c(&k, 0.3)?));
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn c(k: &TaskConstants, sigma: f64) -> Result<Interval, BoundsError> {
    positive("sigma", sigma)?;
    if let Family::Tight(t) = k.family() {
        let s = Interval::point(sigma);
        return Ok(
            (Interval::point(k.r_max()) * Interval::point(k.m_phi()).sqr() * s_h(k, t) / s.sqr())
                .scale(rho(t)),
        );
    }
    let om = one_minus_gamma(k);
    let s = Interval::point(sigma);
    let front =
        Interval::point(k.r_max()) * Interval::point(k.m_phi()).sqr() / (om.sqr() * s.sqr());
    let bracket = Interval::point(k.action_volume()) / (sqrt_2pi() * s)
        + Interval::point(k.gamma()) / (om + om);
    Ok(front * bracket)
}

/// An enclosure of d(σ) of Theorem 4.3 (see [`sepg_bounds::constants::d`]), or of the tight
/// family's d = 2ρ R S_H.
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
/// use sepg_bounds::{constants::{self, TaskConstants}};
/// use sepg_certified as certified;
/// let k = TaskConstants::new(0.99, 4.0, 2.0, 4.0)?;
/// assert!(certified::d(&k, 0.3)?.contains(constants::d(&k, 0.3)?));
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn d(k: &TaskConstants, sigma: f64) -> Result<Interval, BoundsError> {
    positive("sigma", sigma)?;
    if let Family::Tight(t) = k.family() {
        return Ok((Interval::point(k.r_max()) * s_h(k, t)).scale(2.0 * rho(t)));
    }
    let om = one_minus_gamma(k);
    let front = Interval::point(k.r_max()) / om.sqr();
    let bracket = psi_of(k) * Interval::point(k.action_volume())
        / Interval::point(sigma).scale(2.0)
        + Interval::point(k.gamma()) / om;
    Ok(front * bracket)
}

/// κ_φ of a step along `d` (`sepg_bounds::direction`), enclosed: 1 for a coordinate
/// direction, p, or (M₂/M_φ)² in interval arithmetic.
///
/// Errors: [`BoundsError::UnprovenDirection`] for a non-coordinate direction with the thesis
/// family (the error of `Direction::feature_factor`).
///
/// ```
/// use sepg_bounds::constants::TaskConstants;
/// use sepg_bounds::direction::{Direction, FeatureNorm};
/// use sepg_bounds::penalties::{Family, Horizon, Rewards, Tight};
/// let k = TaskConstants::new(0.9, 1.0, 3.0, 2.0)?
///     .with_family(Family::Tight(Tight::new(Horizon::Infinite, Rewards::TwoSided)))?;
/// let d = Direction { direction: &[1.0, 1.0], grad_hat: &[0.0, 0.0], eps: &[0.0, 0.0], features: FeatureNorm::Stated(0.3) };
/// assert!(sepg_certified::enclosure::feature_factor(&k, &d)?.contains(0.01));
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn feature_factor(k: &TaskConstants, d: &Direction) -> Result<Interval, BoundsError> {
    // validates the family and the coordinate case; the value is recomputed enclosed
    let value = d.feature_factor(k)?;
    Ok(match d.features {
        FeatureNorm::Stated(m2) if !d.is_coordinate() => {
            (Interval::point(m2) / Interval::point(k.m_phi())).sqr()
        }
        // 1 or p: integers, exact in f64 below 2⁵³
        _ => Interval::point(value),
    })
}

/// A bound B(x) on the guaranteed improvement of a step x that can be enclosed in interval
/// arithmetic, with x taken as an exact real.
///
/// Implement it for a new step form and pass the form's `f64`
/// [`StepOutcome`](sepg_bounds::StepOutcome) to
/// [`certify`](crate::certify).
pub trait EnclosedBound {
    /// An interval that contains the exact value B(x).
    fn enclose(&self, x: f64) -> Interval;

    /// An approximation of B'(x), used only to guess how far a failing step must move
    /// (any value, or `None`, keeps [`certify`](crate::certify) correct; a good one makes it
    /// faster).
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
    /// use sepg_bounds::{constants::TaskConstants, v_update};
    /// use sepg_certified::{EnclosedBound, Quadratic};
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
    /// use sepg_bounds::{constants::TaskConstants, w_update};
    /// use sepg_certified::{EnclosedBound, Quadratic};
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
    /// use sepg_bounds::{constants::TaskConstants, w_update};
    /// use sepg_certified::{EnclosedBound, Quadratic};
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

    /// A step t ≥ 0 along a proposed direction u (`sepg_bounds::direction`):
    /// a = u·ĝ − Σ|u_i|ε_i, b = c(σ)·κ_φ·‖u‖₂², with c of the family of `k` and κ_φ of
    /// [`feature_factor`]. Valid for t ≥ 0 only (the ε term is t·Σ|u_i|ε_i there).
    ///
    /// Errors: those of [`Direction::validate`], [`c`] and [`feature_factor`].
    ///
    /// ```
    /// use sepg_bounds::constants::TaskConstants;
    /// use sepg_bounds::direction::{Direction, DirectionBound, FeatureNorm};
    /// use sepg_certified::{EnclosedBound, Quadratic};
    /// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
    /// let d = Direction { direction: &[0.5], grad_hat: &[0.3], eps: &[0.1], features: FeatureNorm::FromMax { features: 1 } };
    /// let q = Quadratic::direction(&k, 1.0, &d)?;
    /// assert!(q.enclose(0.2).contains(DirectionBound::new(&k, 1.0, &d)?.bound(0.2)?));
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn direction(k: &TaskConstants, sigma: f64, d: &Direction) -> Result<Self, BoundsError> {
        d.validate()?;
        let kappa = feature_factor(k, d)?;
        let zero = Interval::point(0.0);
        let (mut linear, mut norm2) = (zero, zero);
        for ((&u, &g), &e) in d.direction.iter().zip(d.grad_hat).zip(d.eps) {
            let u = Interval::point(u);
            linear = linear + u.scale(g) - u.abs().scale(e);
            norm2 = norm2 + u.sqr();
        }
        Ok(Self {
            linear,
            quadratic: c(k, sigma)? * kappa * norm2,
        })
    }

    /// An enclosure of C_max = a²/(4b), the value at the vertex.
    ///
    /// ```
    /// use sepg_certified::Quadratic;
    /// use sepg_bounds::{constants::TaskConstants, v_update};
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
    /// use sepg_certified::Quadratic;
    /// use sepg_bounds::{constants::TaskConstants, v_update};
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
    /// use sepg_certified::Quadratic;
    /// use sepg_bounds::{constants::TaskConstants, outcome::StepOutcome, v_update};
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
/// form of [`HpForm`] (see [`sepg_bounds::high_probability`]).
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

/// The rigorous w-bound of [`sepg_bounds::rigorous`] for Δw = β·u, enclosed.
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
    /// use sepg_bounds::{constants::TaskConstants, rigorous};
    /// use sepg_certified::{EnclosedBound, RigorousEnclosure};
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
        if let Family::Tight(_) = k.family() {
            // the tight d holds for every Δw: f(Δw) = Δw ∇_wJ − d Δw² (a = 0, a_ℝ = d, G = 0)
            return Ok(Self {
                a: Interval::point(0.0),
                a_line: d(k, sigma)?,
                g: Interval::point(0.0),
                slope: finite("grad_w_j", grad_w_j)?,
                direction: finite("direction", direction)?,
            });
        }
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

/// The bound of the exploring w-update (`sepg_bounds::exploring`) as a function of the step size β
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
