//! Confidence widths of `Ĵ`, `∇̂_v J` and `∇̂_w J` that hold at every number of trajectories
//! `N`, proven from the task's stated constants only (docs/THEOREMS.md, "Proven confidence
//! widths"). The Student-t widths of Sec 4.5 rely on the central limit theorem and
//! under-cover at small `N`; these do not.
//!
//! # Conditions
//! - rewards `|r_t| ≤ R` surely (or `r_t ∈ [−R, 0]` when declared non-positive); Mountain
//!   Car's penalty on the raw action is not bounded, so the widths do not apply to it as is;
//! - features `|φ_i(s)| ≤ M_φ` for every component and state;
//! - the Gaussian policy `a = μ(s) + σ ξ`, `ξ ~ N(0, 1)` i.i.d. across steps and action
//!   dimensions, with the scores of the raw sampled action: `∇_{v_{j,i}} log π = ξ_j φ_i(s)/σ_j`,
//!   `∇_{w_j} log π = ξ_j² − 1`;
//! - discount `γ ∈ [0, 1)`, horizon `H`; trajectories may terminate early (padded as in
//!   [`sepg_mdp::Batch`]: reward 0 and frozen cumulative scores after the end);
//! - the centre is G(PO)MDP with the constant baseline `b` of [`ProvenWidths::baseline`]
//!   ([`ProvenWidths::gradient_spec`]), fixed before sampling, so that the `N`
//!   per-trajectory samples are i.i.d.
//!
//! Then, for one component, `P(|∇̂ − ∇J| ≥ ε) ≤ δ` with the widths of [`ProvenWidths`].
//!
//! # Formula
//! ```text
//! R' = R (two-sided, b = 0)  or  R/2 (non-positive, b = −R/2);   a_t = γ^t R';   L = ln(2/δ)/N
//! v-component (ψ2):  K_v = √(8/3) (M_φ/σ) Σ_{t<H} a_t √(t+1)     ≥ ‖g‖_ψ2
//!                    ε_v = 2 K_v √(κ L)  if L ≤ κ,   K_v (κ + L)  otherwise,   κ = 2 ln 2
//! w-component (ψ1):  k_n = ‖χ²_n − n‖_ψ1 (computed, rounded up)
//!                    K_w = Σ_{t<H} a_t k_{t+1}                    ≥ ‖g‖_ψ1
//!                    ε_w = K_w √(8 L)  if L ≤ 1/2,   K_w (1 + 2L)  otherwise
//! J (Hoeffding):     ε_J = c Σ_{t<H} γ^t · √(L/2),   c = 2R (two-sided) or R
//! ```
//! `g` is one per-trajectory sample of the component; the norms bound `g` itself, not its
//! centred version: the moment generating function of `g − E g` is bounded through an
//! independent copy of `g` ([`psi2_width`], [`psi1_width`]).
//! Every width is multiplied by `1 + 4(H + 16)u` (`u` the unit roundoff) to cover the
//! rounding of its evaluation.

use std::f64::consts::LN_2;

use statrs::function::gamma::{checked_gamma_lr, checked_gamma_ur};

use crate::error::EstimatorError;
use crate::gradient::{Baseline, BaselineFit, GradientSpec, Kind};

/// Number of degrees of freedom up to which [`chi2_psi1_norm`] is computed directly; beyond,
/// it is bounded by the triangle inequality over blocks of this size.
pub const DIRECT_DOF: usize = 4096;

/// The value of `E e^{|Z|/K}` that the computed `K` must not exceed: 2 minus a margin that
/// covers the rounding of the incomplete gamma functions (relative error ~1e-14).
const PSI1_TARGET: f64 = 2.0 - 1e-9;

/// The largest horizon accepted by [`ProvenWidths::new`] (its cost is linear in `H`).
pub const MAX_HORIZON: usize = 100_000_000;

/// Relative width of the bracket at which the bisection of [`chi2_psi1_norm`] stops.
const BISECTION_TOL: f64 = 1e-11;

/// The constants of a task, validated once, from which the proven confidence widths of its
/// gradient and value estimates are computed (see the [module documentation](self)).
///
/// # Examples
/// ```
/// use sepg_estimators::proven::ProvenWidths;
/// // lqg1d: R = 28.8, rewards non-positive, M_φ = 4, γ = 0.99, H = 20.
/// let p = ProvenWidths::new(28.8, true, 4.0, 0.99, 20)?;
/// assert_eq!(p.baseline(), -14.4);
/// let (ev, ew, ej) = (p.v_width(0.5, 50, 1e-5)?, p.w_width(50, 1e-5)?, p.j_width(50, 1e-5)?);
/// assert!(ev > 0.0 && ew > 0.0 && ej > 0.0);
/// // Halving σ doubles the v-width; the w-width does not depend on σ.
/// assert!((p.v_width(0.25, 50, 1e-5)? / ev - 2.0).abs() < 1e-12);
/// # Ok::<(), sepg_estimators::EstimatorError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct ProvenWidths {
    /// `R`.
    r_max: f64,
    /// Rewards declared in `[−R, 0]`.
    non_positive: bool,
    /// `M_φ`.
    m_phi: f64,
    /// `γ`.
    gamma: f64,
    /// `H`.
    horizon: usize,
    /// `b`: 0, or `−R/2` for non-positive rewards.
    baseline: f64,
    /// `R'`, the bound on `|r_t − b|`.
    deviation: f64,
    /// `Σ_t a_t √(t+1)`.
    v_sum: f64,
    /// `K_w = Σ_t a_t k_{t+1}`.
    w_norm: f64,
    /// `c Σ_t γ^t`, the length of an interval holding every discounted return.
    j_range: f64,
    /// `1 + 4(H + 16)u`.
    rounding: f64,
}

impl ProvenWidths {
    /// Validates the task constants and precomputes the σ-independent parts of the widths
    /// (`O(min(H, 4096))` incomplete-gamma bisections for the ψ1 norms, once).
    ///
    /// `r_max` is `R` (reward units), `rewards_non_positive` declares `r_t ∈ [−R, 0]`,
    /// `m_phi` is `M_φ` (feature units), `gamma ∈ [0, 1)`, `horizon = H` steps with
    /// `1 ≤ H ≤` [`MAX_HORIZON`].
    ///
    /// # Errors
    /// [`EstimatorError::InvalidTaskConstant`] for `R` or `M_φ` not finite and positive,
    /// `γ ∉ [0, 1)` or `H` outside `[1, MAX_HORIZON]`; [`EstimatorError::NonFinite`] if a sum overflows.
    ///
    /// # Examples
    /// ```
    /// use sepg_estimators::proven::ProvenWidths;
    /// assert!(ProvenWidths::new(4.0, false, 2.0, 0.9, 20).is_ok());
    /// assert!(ProvenWidths::new(4.0, false, 2.0, 1.0, 20).is_err());
    /// assert!(ProvenWidths::new(f64::NAN, false, 2.0, 0.9, 20).is_err());
    /// ```
    pub fn new(
        r_max: f64,
        rewards_non_positive: bool,
        m_phi: f64,
        gamma: f64,
        horizon: usize,
    ) -> Result<Self, EstimatorError> {
        let positive = |what, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(value)
            } else {
                Err(EstimatorError::InvalidTaskConstant { what, value })
            }
        };
        positive("R", r_max)?;
        positive("M_phi", m_phi)?;
        if !(0.0..1.0).contains(&gamma) {
            return Err(EstimatorError::InvalidTaskConstant {
                what: "gamma",
                value: gamma,
            });
        }
        if horizon == 0 || horizon > MAX_HORIZON {
            return Err(EstimatorError::InvalidTaskConstant {
                what: "horizon",
                value: horizon as f64,
            });
        }
        let (baseline, deviation, j_scale) = if rewards_non_positive {
            (-0.5 * r_max, 0.5 * r_max, r_max)
        } else {
            (0.0, r_max, 2.0 * r_max)
        };
        // The steps whose discount γ^t is not zero (γ = 0 or underflow end the sums).
        let mut steps = 0;
        let mut discount = 1.0f64;
        while steps < horizon && discount > 0.0 {
            steps += 1;
            discount *= gamma;
        }
        let psi1 = Chi2Psi1::new(steps.min(DIRECT_DOF))?;
        let (mut v_sum, mut w_norm, mut discounts) = (0.0, 0.0, 0.0);
        let mut discount = 1.0f64;
        for dof in 1..=steps {
            let a = discount * deviation;
            v_sum += a * (dof as f64).sqrt();
            w_norm += a * psi1.norm(dof);
            discounts += discount;
            discount *= gamma;
        }
        let j_range = j_scale * discounts;
        if ![v_sum, w_norm, j_range].iter().all(|x| x.is_finite()) {
            return Err(EstimatorError::NonFinite {
                what: "proven width constants (overflow)",
            });
        }
        Ok(ProvenWidths {
            r_max,
            non_positive: rewards_non_positive,
            m_phi,
            gamma,
            horizon,
            baseline,
            deviation,
            v_sum,
            w_norm,
            j_range,
            rounding: 1.0 + 4.0 * (horizon as f64 + 16.0) * f64::EPSILON,
        })
    }

    /// `R` (reward units).
    pub fn r_max(&self) -> f64 {
        self.r_max
    }

    /// Whether the rewards are declared in `[−R, 0]`.
    pub fn rewards_non_positive(&self) -> bool {
        self.non_positive
    }

    /// `M_φ` (feature units).
    pub fn m_phi(&self) -> f64 {
        self.m_phi
    }

    /// `γ`.
    pub fn gamma(&self) -> f64 {
        self.gamma
    }

    /// `H` (steps).
    pub fn horizon(&self) -> usize {
        self.horizon
    }

    /// The constant baseline `b` (reward units) of the centre: 0 for two-sided rewards,
    /// `−R/2` for rewards declared non-positive (then `|r_t − b| ≤ R/2`).
    pub fn baseline(&self) -> f64 {
        self.baseline
    }

    /// `R' ≥ |r_t − b|` (reward units): `R`, or `R/2` for non-positive rewards.
    pub fn reward_deviation(&self) -> f64 {
        self.deviation
    }

    /// The estimator whose per-component estimates the widths cover: G(PO)MDP with
    /// `Baseline::Constant(b)` (the fit is irrelevant for a constant baseline).
    ///
    /// # Examples
    /// ```
    /// use sepg_estimators::{Baseline, Kind, proven::ProvenWidths};
    /// let spec = ProvenWidths::new(4.0, true, 2.0, 0.9, 20)?.gradient_spec();
    /// assert_eq!((spec.kind, spec.baseline), (Kind::Gpomdp, Baseline::Constant(-2.0)));
    /// # Ok::<(), sepg_estimators::EstimatorError>(())
    /// ```
    pub fn gradient_spec(&self) -> GradientSpec {
        GradientSpec {
            kind: Kind::Gpomdp,
            baseline: Baseline::Constant(self.baseline),
            fit: BaselineFit::PlugIn,
        }
    }

    /// `K_v`, a bound on the Orlicz ψ2 norm of one per-trajectory sample `g` of a v-component
    /// of action `j` with standard deviation `σ = σ_j > 0` (return units per parameter unit).
    ///
    /// # Formula
    /// ```text
    /// K_v = √(8/3) (M_φ/σ) Σ_{t<H} γ^t R' √(t+1)
    /// ```
    ///
    /// # Errors
    /// [`EstimatorError::InvalidSigma`] unless `σ` is finite and positive;
    /// [`EstimatorError::NonFinite`] on overflow.
    pub fn v_psi2_norm(&self, sigma: f64) -> Result<f64, EstimatorError> {
        let scale = self.v_scale(sigma)?;
        finite((8.0f64 / 3.0).sqrt() * scale, "v-component psi2 norm")
    }

    /// The proven half-width `ε_v` of a v-component estimate (mean of `n ≥ 1` samples) of an
    /// action with standard deviation `σ > 0`, two-sided at level `δ ∈ (0, 1)`:
    /// `P(|∇̂_v J − ∇_v J| ≥ ε_v) ≤ δ` (return units per parameter unit).
    ///
    /// # Formula
    /// ```text
    /// L = ln(2/δ)/n,   κ = 2 ln 2
    /// ε_v = 2 K_v √(κ L)  if L ≤ κ,   K_v (κ + L)  otherwise
    /// ```
    ///
    /// # Errors
    /// As [`ProvenWidths::v_psi2_norm`], and as [`psi2_width`].
    pub fn v_width(&self, sigma: f64, n: usize, delta: f64) -> Result<f64, EstimatorError> {
        let width = psi2_width(self.v_psi2_norm(sigma)?, n, delta)?;
        finite(width * self.rounding, "v-component proven width")
    }

    /// `K_w`, a bound on the Orlicz ψ1 norm of one per-trajectory sample `g` of a
    /// w-component (return units; it does not depend on `σ`).
    ///
    /// # Formula
    /// ```text
    /// K_w = Σ_{t<H} γ^t R' ‖χ²_{t+1} − (t+1)‖_ψ1
    /// ```
    pub fn w_psi1_norm(&self) -> f64 {
        self.w_norm
    }

    /// The proven half-width `ε_w` of a w-component estimate (mean of `n ≥ 1` samples),
    /// two-sided at level `δ ∈ (0, 1)`: `P(|∇̂_w J − ∇_w J| ≥ ε_w) ≤ δ` (return units; it
    /// does not depend on `σ`).
    ///
    /// # Formula
    /// ```text
    /// L = ln(2/δ)/n
    /// ε_w = K_w √(8 L)  if L ≤ 1/2,   K_w (1 + 2L)  otherwise
    /// ```
    ///
    /// # Errors
    /// As [`psi1_width`].
    pub fn w_width(&self, n: usize, delta: f64) -> Result<f64, EstimatorError> {
        let width = psi1_width(self.w_norm, n, delta)?;
        finite(width * self.rounding, "w-component proven width")
    }

    /// The length `c Σ_{t<H} γ^t` of an interval that holds every discounted return
    /// (`c = 2R`, or `R` for non-positive rewards; return units).
    pub fn j_range(&self) -> f64 {
        self.j_range
    }

    /// The proven half-width of `Ĵ` (Hoeffding, mean of `n ≥ 1` returns), two-sided at
    /// level `δ ∈ (0, 1)`: `P(|Ĵ − J| ≥ ε_J) ≤ δ` (return units).
    ///
    /// # Formula
    /// ```text
    /// ε_J = (c Σ_{t<H} γ^t) √(ln(2/δ) / (2n))
    /// ```
    ///
    /// # Errors
    /// [`EstimatorError::TooFewTrajectories`] for `n = 0`, [`EstimatorError::InvalidDelta`]
    /// unless `0 < δ < 1`, [`EstimatorError::NonFinite`] on overflow.
    pub fn j_width(&self, n: usize, delta: f64) -> Result<f64, EstimatorError> {
        let log_term = log_two_over(n, delta)?;
        let width = self.j_range * (log_term / (2.0 * n as f64)).sqrt();
        finite(width * self.rounding, "J proven width")
    }

    /// `(M_φ/σ) Σ_t a_t √(t+1)`.
    fn v_scale(&self, sigma: f64) -> Result<f64, EstimatorError> {
        if !(sigma.is_finite() && sigma > 0.0) {
            return Err(EstimatorError::InvalidSigma {
                index: 0,
                value: sigma,
            });
        }
        finite(self.m_phi / sigma * self.v_sum, "v-component norm")
    }
}

/// The two-sided half-width for the mean of `n ≥ 1` i.i.d. samples `g_i` with Orlicz ψ2 norm
/// at most `norm` (`E e^{(g/K)²} ≤ 2`; `g` need not be centred), at level `δ ∈ (0, 1)`:
/// `P(|ḡ − E g| ≥ ε) ≤ δ`. Units of `norm`.
///
/// # Formula
/// ```text
/// E e^{λ(g − Eg)} ≤ E e^{λ(g − g′)} ≤ E e^{λ²(g − g′)²/2} ≤ (E e^{λ²g²})² ≤ e^{κ λ² K²}
///     for |λ| ≤ 1/K,   κ = 2 ln 2   (g′ an independent copy; docs/THEOREMS.md)
/// L = ln(2/δ)/n
/// ε = 2 K √(κ L)      if L ≤ κ    (Chernoff at λ = ε/(2κK²) ≤ 1/K)
/// ε = K (κ + L)       if L > κ    (λ = 1/K)
/// ```
///
/// # Errors
/// [`EstimatorError::InvalidRange`] unless `norm` is finite and non-negative;
/// [`EstimatorError::TooFewTrajectories`] for `n = 0`; [`EstimatorError::InvalidDelta`]
/// unless `0 < δ < 1`; [`EstimatorError::NonFinite`] on overflow.
///
/// # Examples
/// ```
/// use sepg_estimators::proven::psi2_width;
/// // K = 1, n = 4, δ = 2/e: L = 1/4 ≤ κ, ε = 2 √(2 ln 2 / 4) = √(2 ln 2).
/// let eps = psi2_width(1.0, 4, 2.0 / std::f64::consts::E)?;
/// assert!((eps - (2.0 * std::f64::consts::LN_2).sqrt()).abs() < 1e-15);
/// # Ok::<(), sepg_estimators::EstimatorError>(())
/// ```
pub fn psi2_width(norm: f64, n: usize, delta: f64) -> Result<f64, EstimatorError> {
    check_norm(norm)?;
    let l = log_two_over(n, delta)? / n as f64;
    let kappa = 2.0 * LN_2;
    let width = if l <= kappa {
        2.0 * norm * (kappa * l).sqrt()
    } else {
        norm * (kappa + l)
    };
    finite(width, "psi2 width")
}

/// The two-sided half-width for the mean of `n ≥ 1` i.i.d. samples `g_i` with Orlicz ψ1 norm
/// at most `norm` (`E e^{|g|/K} ≤ 2`; `g` need not be centred), at level `δ ∈ (0, 1)`:
/// `P(|ḡ − E g| ≥ ε) ≤ δ`. Units of `norm`.
///
/// # Formula
/// ```text
/// E e^{λ(g − Eg)} ≤ E cosh(λ(g − g′)) ≤ 1 + 4λ²K² (E cosh(g/K) − 1) ≤ 1 + 2λ²K² ≤ e^{2λ²K²}
///     for |λ| ≤ 1/(2K)   (g′ an independent copy; docs/THEOREMS.md)
/// L = ln(2/δ)/n
/// ε = K √(8 L)        if L ≤ 1/2   (Chernoff at λ = ε/(4K²) ≤ 1/(2K))
/// ε = K (1 + 2L)      if L > 1/2   (λ = 1/(2K))
/// ```
///
/// # Errors
/// As [`psi2_width`].
///
/// # Examples
/// ```
/// use sepg_estimators::proven::psi1_width;
/// // K = 1, n = 1, δ = 2/e³: L = 3 > 1/2, ε = 1 + 6.
/// assert!((psi1_width(1.0, 1, 2.0 * (-3.0f64).exp())? - 7.0).abs() < 1e-14);
/// # Ok::<(), sepg_estimators::EstimatorError>(())
/// ```
pub fn psi1_width(norm: f64, n: usize, delta: f64) -> Result<f64, EstimatorError> {
    check_norm(norm)?;
    let l = log_two_over(n, delta)? / n as f64;
    let width = if l <= 0.5 {
        norm * (8.0 * l).sqrt()
    } else {
        norm * (1.0 + 2.0 * l)
    };
    finite(width, "psi1 width")
}

/// The Orlicz ψ1 norm of `Z = χ²_n − n` (a sum of `n` independent `ξ² − 1`), rounded up: the
/// smallest `K` with `E e^{|Z|/K} ≤ 2`, up to a relative `1e-11` and a margin of `1e-9` on
/// the 2. Directly computed for `n ≤ 4096`; for larger `n = q·4096 + r` bounded by the
/// triangle inequality `q k_4096 + k_r`. Dimensionless, `n ≥ 1`.
///
/// # Formula
/// ```text
/// E e^{|Z|/K} = e^{−n s}(1 − 2s)^{−n/2} Q(n/2, n(1 − 2s)/2) + e^{n s}(1 + 2s)^{−n/2} P(n/2, n(1 + 2s)/2),
/// s = 1/K < 1/2,  P, Q the regularised incomplete gamma functions;  bisection in K.
/// ```
///
/// # Errors
/// [`EstimatorError::TooFewTrajectories`] for `n = 0` (no degrees of freedom).
///
/// # Examples
/// ```
/// use sepg_estimators::proven::chi2_psi1_norm;
/// let k1 = chi2_psi1_norm(1)?;
/// assert!(k1 > 2.0 && k1 < 3.0);
/// # Ok::<(), sepg_estimators::EstimatorError>(())
/// ```
pub fn chi2_psi1_norm(n: usize) -> Result<f64, EstimatorError> {
    if n == 0 {
        return Err(EstimatorError::TooFewTrajectories { n: 0, min: 1 });
    }
    Ok(Chi2Psi1::new(n.min(DIRECT_DOF))?.norm(n))
}

/// The ψ1 norms `k_1, …, k_m` of `χ²_n − n`.
struct Chi2Psi1 {
    norms: Vec<f64>,
}

impl Chi2Psi1 {
    /// Computes `k_1..k_m` by bisection, each in `[k_{n−1}, k_{n−1} + k_1]` (the norm grows
    /// with `n` by Jensen's inequality and by at most `k_1` by the triangle inequality).
    fn new(m: usize) -> Result<Self, EstimatorError> {
        let mut norms = Vec::with_capacity(m);
        let mut hi = 4.0;
        while abs_mgf(1.0, hi)? > PSI1_TARGET {
            hi *= 2.0;
        }
        let k1 = bisect(1.0, 2.0, hi)?;
        norms.push(k1);
        for n in 2..=m {
            let prev = norms[n - 2];
            norms.push(bisect(n as f64, prev, prev + k1)?);
        }
        Ok(Chi2Psi1 { norms })
    }

    /// `k_n`, by blocks of `m` beyond the table.
    fn norm(&self, n: usize) -> f64 {
        let m = self.norms.len();
        if n <= m {
            return self.norms[n - 1];
        }
        let (q, r) = (n / m, n % m);
        let rest = if r == 0 { 0.0 } else { self.norms[r - 1] };
        q as f64 * self.norms[m - 1] + rest
    }
}

/// The smallest `K` in `[lo, hi]` (up to [`BISECTION_TOL`], rounded up) with
/// `E e^{|χ²_n − n|/K} ≤ PSI1_TARGET`; `hi` must satisfy it.
fn bisect(n: f64, mut lo: f64, mut hi: f64) -> Result<f64, EstimatorError> {
    while hi - lo > BISECTION_TOL * hi {
        let mid = 0.5 * (lo + hi);
        if abs_mgf(n, mid)? > PSI1_TARGET {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(hi)
}

/// `E e^{|χ²_n − n|/K}` for `K > 2` (`+∞` or any value above 2 near `K = 2`).
fn abs_mgf(n: f64, k: f64) -> Result<f64, EstimatorError> {
    if k <= 2.0 {
        return Ok(f64::INFINITY);
    }
    let s = 1.0 / k;
    let a = 0.5 * n;
    let gamma_err = |_| EstimatorError::NonFinite {
        what: "incomplete gamma function (psi1 norm)",
    };
    let upper = checked_gamma_ur(a, a * (1.0 - 2.0 * s)).map_err(gamma_err)?;
    let lower = checked_gamma_lr(a, a * (1.0 + 2.0 * s)).map_err(gamma_err)?;
    let up = (-n * s - a * (-2.0 * s).ln_1p()).exp() * upper;
    let down = (n * s - a * (2.0 * s).ln_1p()).exp() * lower;
    let value = up + down;
    if value.is_nan() {
        return Err(EstimatorError::NonFinite {
            what: "psi1 norm of the chi-squared sum",
        });
    }
    Ok(value)
}

/// `ln(2/δ)` after checking `n ≥ 1` and `δ ∈ (0, 1)`.
fn log_two_over(n: usize, delta: f64) -> Result<f64, EstimatorError> {
    if n == 0 {
        return Err(EstimatorError::TooFewTrajectories { n: 0, min: 1 });
    }
    if !(delta > 0.0 && delta < 1.0) {
        return Err(EstimatorError::InvalidDelta { delta });
    }
    Ok(LN_2 - delta.ln())
}

fn check_norm(norm: f64) -> Result<(), EstimatorError> {
    if norm.is_finite() && norm >= 0.0 {
        Ok(())
    } else {
        Err(EstimatorError::InvalidRange { range: norm })
    }
}

fn finite(x: f64, what: &'static str) -> Result<f64, EstimatorError> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(EstimatorError::NonFinite { what })
    }
}
