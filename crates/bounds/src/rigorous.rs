//! Rigorous lower bounds for the w-update and the v-update, with no neglected terms and no
//! assumption on where the Gaussian density lives (docs/CONVENTIONS.md §4).
//!
//! # Derivation
//!
//! Start from Lemma 3.1 of Pirotta et al. (eq. (A.9)) for θ = [v | w], θ' = [v | w + Δw]:
//!
//! ```text
//! J(θ') − J(θ) ≥ 1/(1−γ) ∫ d(s) ∫ (π' − π) Q da ds − γ/(2(1−γ)²) ‖π' − π‖∞² ‖Q‖∞
//! ```
//!
//! 1. Taylor with the integral remainder: π' − π = ∂_wπ Δw + ∫₀^Δw (Δw − t) ∂²_wπ(w + t) dt.
//!    The thesis (Lemma A.2, after Pirotta et al.) bounds ∫ |∂²_wπ| da by |A| ψ/σ: the
//!    supremum of Lemma A.1 times the volume of the action box. That assumes the density lives
//!    on the box. On the clipped presets the Gaussian is sampled on ℝ and clipped afterwards
//!    (Q(s, a) = Q(s, clip(a)) is defined and bounded on ℝ), so the integral runs over ℝ, where
//!    ∫_ℝ |∂²_wπ| da = K_W ≈ 1.832 for every σ ([`k_w`]). Any constant that is at least K_W is
//!    sound; this module uses the larger of the two,
//!    ρ_w(σ_min) = max(ψ|A|/σ_min, K_W), σ_min = min(σ, σe^{Δw}),
//!    which equals the thesis's term (at the smaller σ, see ERRATA §8) for
//!    σ_min ≤ ψ|A|/K_W (1.143 for |A| = 4, 2.286 for |A| = 8) and K_W above. With |Q| ≤ R/(1−γ)
//!    and the policy gradient theorem the first term is at least
//!    Δw ∇_w J − Δw² R ρ_w / (2(1−γ)²).
//! 2. Pinsker (A.6) holds for both KL directions because ‖π' − π‖₁ is symmetric; for Gaussians
//!    with equal means (A.7):
//!    2 KL(π'‖π) = e^{2Δw} − 1 − 2Δw,   2 KL(π‖π') = e^{−2Δw} − 1 + 2Δw.
//!    Taking the smaller, KL2(Δw) = e^{−2|Δw|} − 1 + 2|Δw| ≤ 2Δw² exactly (because
//!    e^{−y} ≤ 1 − y + y²/2 for y ≥ 0), so Lemma A.3 holds with no neglected term. Clipping
//!    can only shrink the total variation, and no |A| enters.
//!    With ‖Q‖∞ ≤ R/(1−γ) the penalty is γR/(1−γ)³ · KL2(Δw)/2.
//!
//! Hence, for every Δw, with a = Rψ|A|/(2(1−γ)²σ), a_ℝ = R K_W/(2(1−γ)²) and
//! G = γR/(2(1−γ)³) (so the thesis's d = a + 2G):
//!
//! ```text
//! f(Δw) = Δw ∇_w J − Δw² max(a · max(1, e^{−Δw}), a_ℝ) − G · KL2(Δw)
//! ```
//!
//! while the thesis form (4.15)/(A.11) is f_T(Δw) = Δw ∇_w J − d Δw². Consequences:
//! - σ ≤ ψ|A|/K_W and Δw ≥ 0: f − f_T = G (2Δw² − KL2(Δw)) ∈ [0, (4/3) G Δw³], so the thesis
//!   form is itself a rigorous (slightly conservative) bound for increases of σ;
//! - Δw < 0: the thesis form over-promises as soon as a (e^{|Δw|} − 1) exceeds
//!   G (2 − KL2(Δw)/Δw²) ≈ (4/3) G |Δw|; for small |Δw| this happens iff a > (4/3) G, i.e.
//!   ψ|A|/σ > (4/3) γ/(1 − γ);
//! - σ > ψ|A|/K_W: the thesis's d is below the provable curvature for small steps of either
//!   sign (unproven, not necessarily wrong: the true J usually has far more slack).
//!
//! The v-update (Theorem 4.2) has the same gap. Its c carries ∫ |∂²π/∂μ²| da ≤ |A|/(√(2π)σ³)
//! (box) where on ℝ the integral is K_MU/σ², K_MU = 4φ(1) ≈ 0.968 ([`k_mu`]); [`c`] uses the
//! larger, which differs from the thesis's c for σ > |A|e^{1/2}/4 (1.649 for |A| = 4).
//!
//! f is strictly concave (each penalty is convex and C¹ away from the switch between the two
//! curvature terms, where it is still convex) with f(0) = 0, so the safe set {Δw : f(Δw) ≥ C}
//! is an interval, found here by bisection inside closed-form brackets.

use crate::constants::{TaskConstants, d, d_parts};
use crate::error::{BoundsError, finite, finite_vector, no_overflow, positive};
use crate::outcome::{SafeInterval, StepOutcome};
use crate::penalties::Family;

/// √(2π).
const SQRT_2PI: f64 = 2.506_628_274_631_000_7;

/// K_W = ∫_ℝ |∂²π/∂w²| da for a Gaussian density π = φ((a − μ)/σ)/σ, σ = e^w: scale-free.
///
/// # Formula
///
/// ```text
/// ∂²π/∂w² = (z⁴ − 4z² + 1) φ(z)/σ,   z = (a − μ)/σ
/// K_W = ∫ |z⁴ − 4z² + 1| φ(z) dz = 4 (G(z₁) − G(z₂)),   G(z) = (z − z³) φ(z),
/// z₁ = √(2 − √3),  z₂ = √(2 + √3)          ≈ 1.832 126
/// ```
///
/// G(z) = (z − z³)φ(z) is an antiderivative of (z⁴ − 4z² + 1)φ(z): since φ′(z) = −zφ(z),
/// G′(z) = (1 − 3z²)φ(z) − z(z − z³)φ(z) = (z⁴ − 4z² + 1)φ(z). The polynomial is positive on
/// [0, z₁), negative on (z₁, z₂) and positive beyond z₂, so with G(0) = G(∞) = 0 the half
/// line gives (G(z₁) − G(0)) − (G(z₂) − G(z₁)) + (G(∞) − G(z₂)) = 2(G(z₁) − G(z₂)), and the
/// even integrand doubles it. Dimensionless; the value is checked against
/// `scripts/gen_gaussian_constants.py` (mpmath, 60 digits).
///
/// ```
/// let k = sepg_bounds::rigorous::k_w();
/// assert!((k - 1.832_126_049_403_788).abs() < 1e-14);
/// ```
pub fn k_w() -> f64 {
    let s3 = 3.0_f64.sqrt();
    let g = |z: f64| (z - z * z * z) * (-0.5 * z * z).exp() / SQRT_2PI;
    4.0 * (g((2.0 - s3).sqrt()) - g((2.0 + s3).sqrt()))
}

/// K_MU = σ² ∫_ℝ |∂²π/∂μ²| da for a Gaussian density π = φ((a − μ)/σ)/σ: scale-free.
///
/// # Formula
///
/// ```text
/// ∂²π/∂μ² = (z² − 1) φ(z)/σ³,   K_MU = ∫ |z² − 1| φ(z) dz = 4 φ(1) = 4 e^{−1/2}/√(2π) ≈ 0.967 883
/// ```
///
/// (−zφ(z) is an antiderivative of (z² − 1)φ(z).) Dimensionless; checked against
/// `scripts/gen_gaussian_constants.py`.
///
/// ```
/// let k = sepg_bounds::rigorous::k_mu();
/// assert!((k - 0.967_882_898_076_573_4).abs() < 1e-15);
/// ```
pub fn k_mu() -> f64 {
    4.0 * (-0.5_f64).exp() / SQRT_2PI
}

/// The mean-parameter penalty coefficient c of Theorem 4.2 made sound for a Gaussian on ℝ
/// (clipped actions): the box term |A|/(√(2π)σ) of [`crate::constants::c`] is replaced by the
/// larger of itself and K_MU ([`k_mu`]); see the module docs.
///
/// # Formula
///
/// ```text
/// c_ℝ(σ) = R M_φ² / ((1 − γ)² σ²) · ( max(|A| / (√(2π) σ), K_MU) + γ / (2 (1 − γ)) )
/// ```
///
/// Equal to the thesis's c for σ ≤ |A| e^{1/2} / 4 (1.649 for |A| = 4), larger above. For the
/// tight family ([`crate::penalties::Family::Tight`]), whose c holds on ℝ, it is that c.
/// Domain σ > 0; units as c.
///
/// Errors: σ not finite and positive; overflow.
///
/// ```
/// use sepg_bounds::{constants::{self, TaskConstants}, rigorous};
/// let k = TaskConstants::new(0.99, 4.0, 2.0, 4.0)?;
/// assert_eq!(rigorous::c(&k, 1.0)?, constants::c(&k, 1.0)?);
/// assert!(rigorous::c(&k, 3.0)? > constants::c(&k, 3.0)?);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn c(k: &TaskConstants, sigma: f64) -> Result<f64, BoundsError> {
    positive("sigma", sigma)?;
    if let Family::Tight(_) = k.family() {
        // the tight family's c is proven on ℝ (docs/THEOREMS.md "Tight constants")
        return crate::constants::c(k, sigma);
    }
    if k.action_volume() / (SQRT_2PI * sigma) >= k_mu() {
        // the box term is the larger: the thesis's c, bit for bit
        return crate::constants::c(k, sigma);
    }
    let g = k.gamma();
    let one_minus = 1.0 - g;
    let front = k.r_max() * k.m_phi() * k.m_phi() / (one_minus * one_minus * sigma * sigma);
    no_overflow("rigorous c", front * (k_mu() + g / (2.0 * one_minus)))
}

/// The v-update lower bound of Theorem 4.2 with the sound [`c`]:
/// J(v + αe_k∇_{v_k}J, w) − J(v, w) ≥ α‖∇_vJ‖∞² − α² c_ℝ(σ) ‖∇_vJ‖∞² (greedy coordinate k).
///
/// # Formula
///
/// ```text
/// α ‖∇_v J‖∞² − α² c_ℝ(σ) ‖∇_v J‖∞²
/// ```
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, rigorous, v_update};
/// let k = TaskConstants::new(0.99, 4.0, 2.0, 4.0)?;
/// assert!(rigorous::v_bound(&k, 3.0, &[0.5], 1e-4)? < v_update::bound(&k, 3.0, &[0.5], 1e-4)?);
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn v_bound(
    k: &TaskConstants,
    sigma: f64,
    grad_v: &[f64],
    alpha: f64,
) -> Result<f64, BoundsError> {
    finite_vector("grad_v", grad_v)?;
    finite("alpha", alpha)?;
    crate::v_update::bound_with_c(c(k, sigma)?, grad_v, alpha, "rigorous v bound")
}

/// The safe v-steps of Theorem 4.2 (eqs. (4.9)–(4.10)) with the sound [`c`]: vertex
/// α* = 1/(2c_ℝ), C_max = ‖∇_vJ‖∞²/(4c_ℝ), interval (1 ± λ_v)α*.
///
/// # Formula
///
/// ```text
/// { α : α ‖∇‖∞² − α² c_ℝ ‖∇‖∞² ≥ C }
/// ```
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, rigorous, v_update};
/// let k = TaskConstants::new(0.99, 4.0, 2.0, 4.0)?;
/// let r = rigorous::v_safe_step(&k, 3.0, &[0.5], 0.0)?.chosen_step().unwrap();
/// let t = v_update::safe_step(&k, 3.0, &[0.5], 0.0)?.chosen_step().unwrap();
/// assert!(r < t); // above σ = 1.649 the sound c is larger
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn v_safe_step(
    k: &TaskConstants,
    sigma: f64,
    grad_v: &[f64],
    required: f64,
) -> Result<StepOutcome, BoundsError> {
    finite_vector("grad_v", grad_v)?;
    finite("required", required)?;
    crate::v_update::parabola(c(k, sigma)?, crate::error::inf_norm(grad_v))?.solve(required)
}

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

/// a_ℝ = R K_W / (2(1−γ)²), the real-line curvature coefficient of the module docs.
fn a_line(k: &TaskConstants) -> Result<f64, BoundsError> {
    let one_minus = 1.0 - k.gamma();
    no_overflow(
        "rigorous curvature",
        k.r_max() * k_w() / (2.0 * one_minus * one_minus),
    )
}

/// (a, a_ℝ, G) of the module docs. The tight family's d holds for every Δw and every σ
/// (docs/THEOREMS.md "Tight constants"), so its rigorous bound is Δw ∇_w J − d Δw²:
/// a = 0, a_ℝ = d, G = 0.
fn parts(k: &TaskConstants, sigma: f64) -> Result<(f64, f64, f64), BoundsError> {
    if let Family::Tight(_) = k.family() {
        return Ok((0.0, d(k, sigma)?, 0.0));
    }
    let (a, g) = d_parts(k, sigma)?;
    Ok((a, a_line(k)?, g))
}

/// The validated coefficients of the rigorous bound.
#[derive(Debug, Clone, Copy)]
struct Rigorous {
    /// Box term a = Rψ|A|/(2(1−γ)²σ).
    a: f64,
    /// Real-line term a_ℝ = R K_W/(2(1−γ)²).
    a_line: f64,
    g: f64,
    slope: f64,
}

impl Rigorous {
    fn new(k: &TaskConstants, sigma: f64, grad_w_j: f64) -> Result<Self, BoundsError> {
        let (a, a_line, g) = parts(k, sigma)?;
        Ok(Self {
            a,
            a_line,
            g,
            slope: finite("grad_w_j", grad_w_j)?,
        })
    }

    /// The smallest curvature coefficient over all Δw: f(x) ≤ x·slope − a_min·x².
    fn a_min(&self) -> f64 {
        self.a.max(self.a_line)
    }

    /// Whether the box term is the larger at Δw = x.
    fn box_term_active(&self, x: f64) -> bool {
        let curvature = if x < 0.0 { (-x).exp() } else { 1.0 };
        self.a * curvature >= self.a_line
    }

    /// f(Δw); may be ±∞ or NaN for huge arguments, so callers compare with `>=`, which treats
    /// NaN as unsafe, and check every returned value for finiteness.
    fn value(&self, x: f64) -> f64 {
        let curvature = if x < 0.0 { (-x).exp() } else { 1.0 };
        let coefficient = (self.a * curvature).max(self.a_line);
        x * self.slope - coefficient * x * x - self.g * kl2_unchecked(x)
    }

    /// f'(Δw) (a subgradient where the curvature term switches), decreasing.
    fn derivative(&self, x: f64) -> f64 {
        let remainder = if !self.box_term_active(x) {
            2.0 * self.a_line * x
        } else if x < 0.0 {
            self.a * (2.0 * x - x * x) * (-x).exp()
        } else {
            2.0 * self.a * x
        };
        let kl = 2.0 * x.signum() * (-(-2.0 * x.abs()).exp_m1());
        self.slope - remainder - self.g * kl
    }

    /// Δw maximising f: between 0 and ∇_wJ/(2a_min) (see module docs), by bisection on f'.
    fn maximiser(&self) -> Result<f64, BoundsError> {
        let far = no_overflow(
            "rigorous maximiser bracket",
            self.slope / (2.0 * self.a_min()),
        )?;
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
        // f(x) ≤ x·slope − a_min·x², so {f ≥ C} lies within the roots of
        // a_min x² − slope x + C = 0.
        let a = self.a_min();
        let disc = (self.slope * self.slope - 4.0 * a * required)
            .max(0.0)
            .sqrt();
        let far_hi = no_overflow("rigorous bracket", (self.slope + disc) / (2.0 * a))?;
        let far_lo = no_overflow("rigorous bracket", (self.slope - disc) / (2.0 * a))?;
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
/// f(Δw) = Δw ∇_w J − Δw² R/(2(1−γ)²) · max(ψ|A| / min(σ, σe^{Δw}), K_W) − γR/(1−γ)³ · KL2(Δw)/2
/// ```
///
/// Sound for a Gaussian policy on ℝ with clipped actions, for every σ (module docs).
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, rigorous};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// // for an increase of a small σ the rigorous bound is at least the thesis bound
/// let r = rigorous::bound(&k, 0.5, 0.5, 0.01)?;
/// assert!(r >= rigorous::thesis_bound(&k, 0.5, 0.5, 0.01)?);
/// // for a large σ the real-line curvature K_W takes over and the thesis form over-promises
/// assert!(rigorous::bound(&k, 2.0, 0.5, 0.01)? < rigorous::thesis_bound(&k, 2.0, 0.5, 0.01)?);
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
/// f_T − f = Δw² (max(a · max(1, e^{−Δw}), a_ℝ) − a) − G (2Δw² − KL2(Δw)),
/// a = Rψ|A| / (2(1−γ)²σ),   a_ℝ = R K_W / (2(1−γ)²),   G = γR / (2(1−γ)³)
/// ```
///
/// Computed from this closed form (no cancellation between the two bounds).
///
/// ```
/// use sepg_bounds::{constants::TaskConstants, rigorous::gap};
/// let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0)?;
/// assert!(gap(&k, 0.5, 0.01)? <= 0.0); // increases of a small σ: thesis form is conservative
/// assert!(gap(&k, 2.0, 0.01)? > 0.0); // σ > ψ|A|/K_W: it is not
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
pub fn gap(k: &TaskConstants, sigma: f64, delta_w: f64) -> Result<f64, BoundsError> {
    finite("delta_w", delta_w)?;
    if let Family::Tight(_) = k.family() {
        // the thesis form with the tight d is itself rigorous: the two bounds coincide
        positive("sigma", sigma)?;
        return Ok(0.0);
    }
    let (a, g) = d_parts(k, sigma)?;
    let a_line = a_line(k)?;
    let x2 = delta_w * delta_w;
    let box_excess = if delta_w < 0.0 {
        a * (-delta_w).exp_m1()
    } else {
        0.0
    };
    // max(a·curvature, a_ℝ) − a, without cancellation when the box term is the larger
    let remainder = x2 * box_excess.max(a_line - a);
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
/// let r = rigorous::safe_step_along_j(&k, 0.5, 0.5, 0.0)?.chosen_step().unwrap();
/// let t = w_update::safe_step_along_j(&k, 0.5, 0.5, 0.0)?.chosen_step().unwrap();
/// assert!(r >= t); // Δw > 0, σ ≤ ψ|A|/K_W: the thesis step is rigorous, the exact one larger
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
