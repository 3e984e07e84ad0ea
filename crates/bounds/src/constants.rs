//! Task constants and the penalty coefficients `c` (Theorems 3.14 / 4.2) and `d` (Theorem 4.3).

use crate::error::{BoundsError, finite, no_overflow, positive};
use crate::penalties::{Family, Horizon, Rewards, Tight};

/// √(2π).
const SQRT_2PI: f64 = 2.506_628_274_631_000_7;

/// The constants of a task that enter every closed-form bound, validated once.
///
/// Build it with [`TaskConstants::new`]; only validated constants can reach the bounds
/// (Section 4.3.1 and docs/CONVENTIONS.md §1).
///
/// - `gamma`: discount factor γ ∈ [0, 1);
/// - `r_max`: R, the largest absolute reward, R > 0;
/// - `m_phi`: M_φ, the bound on every feature, |φ_i(s)| ≤ M_φ (eq. (3.14)), M_φ > 0;
/// - `action_volume`: |A|, the volume of the action space, |A| > 0;
/// - the [`Family`] of the penalty coefficients c and d (the thesis's unless
///   [`TaskConstants::with_family`] chose another).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TaskConstants {
    gamma: f64,
    r_max: f64,
    m_phi: f64,
    action_volume: f64,
    psi: Option<f64>,
    family: Family,
    /// S_H of the tight family (docs/THEOREMS.md "Tight constants"), computed once; 0 for
    /// the thesis family, which does not use it.
    s_h: f64,
}

impl TaskConstants {
    /// Validates the task constants.
    ///
    /// Errors: any input non-finite, γ ∉ [0, 1), or R, M_φ, |A| not strictly positive.
    ///
    /// ```
    /// use sepg_bounds::constants::TaskConstants;
    /// let k = TaskConstants::new(0.99, 4.0, 2.0, 4.0)?;
    /// assert_eq!(k.gamma(), 0.99);
    /// assert!(TaskConstants::new(1.0, 4.0, 2.0, 4.0).is_err());
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn new(
        gamma: f64,
        r_max: f64,
        m_phi: f64,
        action_volume: f64,
    ) -> Result<Self, BoundsError> {
        discount(gamma)?;
        let (r_max, m_phi, action_volume) = (
            positive("r_max", r_max)?,
            positive("m_phi", m_phi)?,
            positive("action_volume", action_volume)?,
        );
        Ok(Self {
            gamma,
            r_max,
            m_phi,
            action_volume,
            psi: None,
            family: Family::Thesis,
            s_h: 0.0,
        })
    }

    /// The same constants with the penalty coefficients c and d of `family`: every bound that
    /// takes these constants then uses that family's c, d and ∂c/∂σ.
    ///
    /// For [`Family::Tight`] the horizon's S_H = Σ_{t<H} (t + 1) γᵗ ([`s_h`]) is computed
    /// here, once.
    ///
    /// Errors: a finite horizon of 0 steps.
    ///
    /// ```
    /// use sepg_bounds::constants::{TaskConstants, c, d};
    /// use sepg_bounds::penalties::{Family, Horizon, Rewards, Tight};
    /// let k = TaskConstants::new(0.99, 28.8, 4.0, 8.0)?;
    /// let tight = Tight::new(Horizon::Finite(20), Rewards::NonPositive);
    /// let t = k.with_family(Family::Tight(tight))?;
    /// assert_eq!(t.family(), Family::Tight(tight));
    /// assert!(c(&t, 1.0)? * 5000.0 < c(&k, 1.0)?);
    /// assert!(d(&t, 1.0)? * 5000.0 < d(&k, 1.0)?);
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn with_family(self, family: Family) -> Result<Self, BoundsError> {
        let s_h = match family {
            Family::Thesis => 0.0,
            Family::Tight(t) => s_h(self.gamma, t.horizon())?,
        };
        Ok(Self {
            family,
            s_h,
            ..self
        })
    }

    /// The family of the penalty coefficients ([`TaskConstants::with_family`]).
    pub fn family(&self) -> Family {
        self.family
    }

    /// S_H of the tight family as computed once by [`TaskConstants::with_family`]
    /// ([`s_h`]); 0 for the thesis family, which does not use it.
    pub fn horizon_weight(&self) -> f64 {
        self.s_h
    }

    /// The same constants with ψ of Lemma A.1 replaced by `psi` in d (Theorem 4.3) and every
    /// bound built on it (the thesis-era public code used ψ = 0.53). The bounds stay valid for
    /// any `psi` ≥ [`psi()`]; a smaller value voids them. Only the thesis family uses ψ.
    ///
    /// Errors: `psi` not finite and strictly positive.
    ///
    /// ```
    /// use sepg_bounds::constants::{TaskConstants, d, psi};
    /// let k = TaskConstants::new(0.0, 1.0, 1.0, 2.0)?;
    /// assert_eq!(d(&k.with_psi(0.53)?, 1.0)?, 0.53);
    /// assert_eq!(k.psi_override(), None);
    /// assert!(k.with_psi(f64::NAN).is_err());
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn with_psi(self, psi: f64) -> Result<Self, BoundsError> {
        Ok(Self {
            psi: Some(positive("psi", psi)?),
            ..self
        })
    }

    /// The ψ that replaces Lemma A.1's value, if any ([`TaskConstants::with_psi`]).
    pub fn psi_override(&self) -> Option<f64> {
        self.psi
    }

    /// The ψ that d (Theorem 4.3) uses: the override, or Lemma A.1's [`psi()`].
    ///
    /// ```
    /// use sepg_bounds::constants::{TaskConstants, psi};
    /// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
    /// assert_eq!(k.psi_used(), psi());
    /// assert_eq!(k.with_psi(0.53)?.psi_used(), 0.53);
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn psi_used(&self) -> f64 {
        self.psi.unwrap_or_else(psi)
    }

    /// The discount factor γ ∈ [0, 1).
    ///
    /// ```
    /// # use sepg_bounds::constants::TaskConstants;
    /// assert_eq!(TaskConstants::new(0.9, 1.0, 1.0, 2.0)?.gamma(), 0.9);
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn gamma(&self) -> f64 {
        self.gamma
    }

    /// R, the largest absolute reward (> 0).
    ///
    /// ```
    /// # use sepg_bounds::constants::TaskConstants;
    /// assert_eq!(TaskConstants::new(0.9, 1.5, 1.0, 2.0)?.r_max(), 1.5);
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn r_max(&self) -> f64 {
        self.r_max
    }

    /// M_φ, the uniform bound on the features (> 0), eq. (3.14).
    ///
    /// ```
    /// # use sepg_bounds::constants::TaskConstants;
    /// assert_eq!(TaskConstants::new(0.9, 1.0, 3.0, 2.0)?.m_phi(), 3.0);
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn m_phi(&self) -> f64 {
        self.m_phi
    }

    /// |A|, the volume of the action space (> 0).
    ///
    /// ```
    /// # use sepg_bounds::constants::TaskConstants;
    /// assert_eq!(TaskConstants::new(0.9, 1.0, 1.0, 8.0)?.action_volume(), 8.0);
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn action_volume(&self) -> f64 {
        self.action_volume
    }
}

/// ψ of Lemma A.1: the largest value of |∂²π/∂w²| · σ over actions.
///
/// # Formula
///
/// ```text
/// ψ = max_{χ ≥ 0} |(χ² − 4χ + 1) e^{−χ/2}| / √(2π)
///   = 4 (√7 − 2) e^{√7/2 − 2} / √(2π)  ≈ 0.523 557
/// ```
///
/// The maximum of |f(χ)| = |(χ² − 4χ + 1)e^{−χ/2}| on χ ≥ 0 is attained at the stationary point
/// χ₂ = 4 − √7, where f(χ₂) = −4(√7 − 2)e^{√7/2 − 2} ≈ −1.31236 (the other stationary point
/// χ₁ = 4 + √7 gives f(χ₁) = 4(√7 + 2)e^{−√7/2 − 2} ≈ 0.66990, and f(0) = 1).
/// Dimensionless.
///
/// ```
/// let psi = sepg_bounds::constants::psi();
/// assert!((psi - 0.523_557_020_321_374).abs() < 1e-15);
/// ```
pub fn psi() -> f64 {
    let s7 = 7.0_f64.sqrt();
    4.0 * (s7 - 2.0) * (s7 / 2.0 - 2.0).exp() / SQRT_2PI
}

/// The penalty coefficient `c` of the mean-parameter bound (Theorem 3.14 / Theorem 4.2).
///
/// # Formula
///
/// ```text
/// c(σ) = R M_φ² / ((1 − γ)² σ²) · ( |A| / (√(2π) σ) + γ / (2 (1 − γ)) )   thesis family
/// c(σ) = ρ R M_φ² S_H / σ²                                                tight family
/// ```
///
/// where, for the tight family (docs/THEOREMS.md "Tight constants"), S_H is [`s_h`] and
/// ρ = 1 for rewards of either sign, ρ = 1/2 for non-positive rewards.
///
/// Domain: σ > 0 (standard deviation of the Gaussian policy, action units). Units of
/// R / (action)², so that c‖Δv‖² is a performance. Strictly decreasing in σ.
///
/// Errors: σ not finite and positive; overflow (σ extremely small).
///
/// ```
/// use sepg_bounds::constants::{TaskConstants, c};
/// let k = TaskConstants::new(0.5, 1.0, 1.0, 1.0)?;
/// // R M²/((1-γ)²σ²) = 4, bracket = 1/√(2π) + 0.5
/// let expected = 4.0 * (1.0 / (2.0 * std::f64::consts::PI).sqrt() + 0.5);
/// assert!((c(&k, 1.0)? - expected).abs() < 1e-14);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
#[inline]
pub fn c(k: &TaskConstants, sigma: f64) -> Result<f64, BoundsError> {
    positive("sigma", sigma)?;
    no_overflow("c", c_value(k, sigma))
}

/// c(σ) of [`c`] for a validated σ, unchecked for overflow.
#[inline]
pub(crate) fn c_value(k: &TaskConstants, sigma: f64) -> f64 {
    if let Family::Tight(t) = k.family {
        return t.rewards().factor() * k.r_max * k.m_phi * k.m_phi * k.s_h / (sigma * sigma);
    }
    let g = k.gamma;
    let one_minus = 1.0 - g;
    let front = k.r_max * k.m_phi * k.m_phi / (one_minus * one_minus);
    let bracket_over_sigma2 = k.action_volume / (SQRT_2PI * sigma * sigma * sigma)
        + g / (2.0 * one_minus * sigma * sigma);
    front * bracket_over_sigma2
}

/// The analytic derivative ∂c/∂σ of [`c`] (used by the surrogate gradient of Appendix B).
///
/// # Formula
///
/// ```text
/// ∂c/∂σ = R M_φ² / (1 − γ)² · ( −3 |A| / (√(2π) σ⁴) − γ / ((1 − γ) σ³) )   thesis family
/// ∂c/∂σ = −2 c(σ) / σ                                                    tight family
/// ```
///
/// Domain: σ > 0. Always strictly negative.
///
/// ```
/// use sepg_bounds::constants::{TaskConstants, c, dc_dsigma};
/// let k = TaskConstants::new(0.9, 2.0, 1.5, 3.0)?;
/// let h = 1e-6;
/// let fd = (c(&k, 0.7 + h)? - c(&k, 0.7 - h)?) / (2.0 * h);
/// assert!((dc_dsigma(&k, 0.7)? - fd).abs() < 1e-6 * fd.abs());
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn dc_dsigma(k: &TaskConstants, sigma: f64) -> Result<f64, BoundsError> {
    positive("sigma", sigma)?;
    if let Family::Tight(_) = k.family {
        // c = K/σ² ⇒ ∂c/∂σ = −2K/σ³ = −2c/σ
        return no_overflow("dc/dsigma", -2.0 * (c_value(k, sigma) / sigma));
    }
    let g = k.gamma;
    let one_minus = 1.0 - g;
    let front = k.r_max * k.m_phi * k.m_phi / (one_minus * one_minus);
    let s3 = sigma * sigma * sigma;
    let bracket = -3.0 * k.action_volume / (SQRT_2PI * s3 * sigma) - g / (one_minus * s3);
    no_overflow("dc/dsigma", front * bracket)
}

/// ψ of the task: Lemma A.1's value unless [`TaskConstants::with_psi`] replaced it.
fn psi_of(k: &TaskConstants) -> f64 {
    k.psi_used()
}

/// The penalty coefficient `d` of the variance-parameter bound (Theorem 4.3, eq. (4.15)).
///
/// # Formula
///
/// ```text
/// d(σ) = R / (1 − γ)² · ( ψ |A| / (2σ) + γ / (1 − γ) ),   ψ = psi() unless overridden
/// d    = 2 ρ R S_H                                         tight family, every σ
/// ```
///
/// (ρ and S_H as in [`c`].)
///
/// Domain: σ > 0 is the standard deviation *before* the w-update (σ = e^w). Units of R per
/// (log-σ)², so that dΔw² is a performance. Strictly decreasing in σ.
///
/// ```
/// use sepg_bounds::constants::{TaskConstants, d, psi};
/// let k = TaskConstants::new(0.0, 1.0, 1.0, 2.0)?;
/// assert!((d(&k, 1.0)? - psi()).abs() < 1e-15);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
#[inline]
pub fn d(k: &TaskConstants, sigma: f64) -> Result<f64, BoundsError> {
    positive("sigma", sigma)?;
    no_overflow("d", d_value(k, sigma))
}

/// d(σ) of [`d`] for a validated σ, unchecked for overflow.
#[inline]
pub(crate) fn d_value(k: &TaskConstants, sigma: f64) -> f64 {
    if let Family::Tight(t) = k.family {
        return t.rewards().factor() * 2.0 * k.r_max * k.s_h;
    }
    let one_minus = 1.0 - k.gamma;
    let front = k.r_max / (one_minus * one_minus);
    let bracket = psi_of(k) * k.action_volume / (2.0 * sigma) + k.gamma / one_minus;
    front * bracket
}

/// The two coefficients of the rigorous w-bound (module [`crate::rigorous`]):
/// `(a, g)` with a = R ψ |A| / (2 (1 − γ)² σ) and g = γ R / (2 (1 − γ)³), so that
/// d(σ) = a + 2g. Thesis family only: the tight family's d needs no rigorous form.
pub(crate) fn d_parts(k: &TaskConstants, sigma: f64) -> Result<(f64, f64), BoundsError> {
    positive("sigma", sigma)?;
    let one_minus = 1.0 - k.gamma;
    let a = k.r_max * psi_of(k) * k.action_volume / (2.0 * one_minus * one_minus * sigma);
    let g = k.gamma * k.r_max / (2.0 * one_minus * one_minus * one_minus);
    Ok((no_overflow("d", a)?, no_overflow("d", g)?))
}

/// S_H = Σ_{t<H} (t + 1) γᵗ, the horizon's weight in the tight constants (docs/THEOREMS.md
/// "Tight constants"): the discounted sum of the number of score terms each reward is
/// multiplied by.
///
/// # Formula
///
/// ```text
/// S_H = Σ_{t=0}^{H−1} (t + 1) γᵗ = (1 − (H + 1) γ^H + H γ^{H+1}) / (1 − γ)²,   S_∞ = 1 / (1 − γ)²
/// ```
///
/// Evaluated by Horner's rule for H ≤ 2²⁰ (positive terms, two roundings each: relative error
/// at most 2Hu/(1 − 2Hu), u = 2⁻⁵³), and beyond by the closed form with `exp_m1` and `ln_1p`,
/// clamped to [1, S_∞]. Dimensionless,
/// in [1, 1/(1 − γ)²]; S_H = H(H + 1)/2 when γ = 1 is excluded by γ < 1.
///
/// Errors: γ not in [0, 1); a finite horizon of 0 steps.
///
/// ```
/// use sepg_bounds::constants::s_h;
/// use sepg_bounds::penalties::Horizon;
/// assert_eq!(s_h(0.5, Horizon::Finite(1))?, 1.0);
/// assert_eq!(s_h(0.5, Horizon::Finite(2))?, 2.0); // 1 + 2·0.5
/// assert_eq!(s_h(0.5, Horizon::Infinite)?, 4.0);
/// let closed = (1.0 - 21.0 * 0.99f64.powi(20) + 20.0 * 0.99f64.powi(21)) / (0.01f64 * 0.01);
/// assert!((s_h(0.99, Horizon::Finite(20))? - closed).abs() < 1e-11 * closed);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn s_h(gamma: f64, horizon: Horizon) -> Result<f64, BoundsError> {
    discount(gamma)?;
    let one_minus = 1.0 - gamma;
    let infinite = 1.0 / (one_minus * one_minus);
    let h = match horizon {
        Horizon::Infinite => return Ok(infinite),
        Horizon::Finite(0) => {
            return Err(BoundsError::OutOfDomain {
                name: "horizon",
                value: 0.0,
                domain: "{1, 2, ...} or infinite",
            });
        }
        Horizon::Finite(h) => h,
    };
    if h <= HORNER_LIMIT {
        // Σ_{t<H} (t + 1) γᵗ = 1 + γ(2 + γ(3 + … + γ·H))
        let mut acc = h as f64;
        for t in (0..h - 1).rev() {
            acc = (t + 1) as f64 + gamma * acc;
        }
        return Ok(acc);
    }
    // 1 − (H + 1)γ^H + Hγ^{H+1} = 1 − γ^H (1 + H(1 − γ)) = −expm1(H ln γ + ln(1 + H(1 − γ)))
    let hf = h as f64;
    let exponent = hf * gamma.ln() + (hf * one_minus).ln_1p();
    let value = -exponent.exp_m1() / (one_minus * one_minus);
    Ok(value.clamp(1.0, infinite))
}

/// Validates a discount factor: finite and in [0, 1).
fn discount(gamma: f64) -> Result<f64, BoundsError> {
    finite("gamma", gamma)?;
    if !(0.0..1.0).contains(&gamma) {
        return Err(BoundsError::OutOfDomain {
            name: "gamma",
            value: gamma,
            domain: "[0, 1)",
        });
    }
    Ok(gamma)
}

/// The largest horizon [`s_h`] sums term by term.
const HORNER_LIMIT: u64 = 1 << 20;

impl Rewards {
    /// ρ of the tight constants: 1 for rewards of either sign, 1/2 for non-positive rewards.
    pub(crate) fn factor(self) -> f64 {
        match self {
            Rewards::TwoSided => 1.0,
            Rewards::NonPositive => 0.5,
        }
    }
}

impl Tight {
    /// The tight family for a horizon and a reward sign.
    pub const fn new(horizon: Horizon, rewards: Rewards) -> Self {
        Self { horizon, rewards }
    }

    /// The horizon H the constants hold for.
    pub fn horizon(self) -> Horizon {
        self.horizon
    }

    /// What is known of the rewards' sign.
    pub fn rewards(self) -> Rewards {
        self.rewards
    }
}
