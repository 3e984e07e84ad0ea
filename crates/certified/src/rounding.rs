//! A-priori rounding-error bounds: the fast path of [`crate::certificate`].
//!
//! Interval arithmetic rounds every end point outward, which costs about ten times a plain
//! `f64` operation. The bounds of Theorems 4.2–4.9 and of the exploring w-update are, on each
//! side of x = 0, parabolas p(x) = a·x − b·x² whose coefficients a, b are short products of
//! the inputs with c(σ) or d(σ). This module evaluates them in plain `f64` and bounds the
//! rounding error with the standard model of floating-point arithmetic (docs/THEOREMS.md,
//! "Certified steps", gives the same argument in prose).
//!
//! # Error analysis
//!
//! Let u = 2⁻⁵³. For `f64` operands x, y and ∘ ∈ {+, −, ×, ÷}, round-to-nearest gives
//! fl(x ∘ y) = (x ∘ y)(1 + δ), |δ| ≤ u, provided the result neither overflows nor underflows
//! (for + and − an underflowing result is exact, so the model always holds). A product of k
//! factors (1 + δᵢ)^{±1} equals 1 + θ with |θ| ≤ γ_k = k·u/(1 − k·u) (the classical lemma on
//! accumulated rounding errors). A value "with k roundings" ([`Rounded`]) is an `f64` v̂ with
//! v̂ = v(1 + θ), |θ| ≤ γ_k, for the exact real v it stands for; the product of values with j
//! and k roundings has j + k + 1, the sum of two non-negative ones max(j, k) + 1.
//!
//! - **c(σ)** as computed by [`sepg_bounds::constants::c`] has 14 roundings: 1 − γ (1), the front
//!   factor R·M·M/((1−γ)(1−γ)) (6, counting 1 − γ twice), |A|/(√(2π)·σ·σ·σ) (6, of which 2
//!   for the `f64` √(2π), which is within 1.6u of √(2π)), γ/(2(1−γ)σσ) (4), their sum (+1),
//!   the final product (+1): 6 + 7 + 1.
//! - **d(σ)** as computed by [`sepg_bounds::constants::d`] has 12: R/((1−γ)(1−γ)) (4),
//!   ψ·|A|/(2σ) (6, of which 4 for the `f64` ψ: it is computed with `exp`, and checked once to
//!   lie within one ulp of the two-`f64` enclosure [`crate::enclosure::psi`], hence within
//!   2·2⁻⁵³ ≤ 3.9u·ψ of ψ), γ/(1−γ) (2), the sum (+1), the product (+1): 4 + 7 + 1.
//!
//!   Both counts need every intermediate result to be a normal number: that holds when R,
//!   M_φ, |A| and σ lie in [2⁻¹⁰⁰, 2¹⁰⁰] and γ = 0 or γ ≥ 2⁻¹⁰⁰ (every intermediate then lies
//!   within 2^±810), which [`apriori_box`] checks (the part on R, M_φ, |A|, γ once, when the
//!   [`CertifiedTask`](crate::CertifiedTask) is built, or at each call: [`task_in_box`]); outside
//!   it the interval path is used.
//! - Further products are checked one at a time: a product whose result is normal obeys the
//!   model ([`Rounded::mul`] returns `None` otherwise).
//! - **The parabola at an exact x** ([`RoundedBound::enclose`]). With â = a(1 + θ_a),
//!   b̂ = b(1 + θ_b), |θ| ≤ γ_k, compute t₁ = fl(x·â), t₂ = fl(fl(x·x)·b̂), r = fl(t₁ − t₂).
//!   When fl(x·x) is normal, t₁ = x·a(1 + θ_{k+1}) + η₁ and t₂ = x²b(1 + θ_{k+2}) + η₂ with
//!   |ηᵢ| ≤ 2⁻¹⁰⁷⁵ (underflow of the products), so |x·a − t₁| ≤ (k+2)u|t₁| + 2η,
//!   |x²b − t₂| ≤ (k+3)u|t₂| + 2η (using γ_j/(1 − γ_j) ≤ (j+1)u), and |r − (t₁ − t₂)| ≤
//!   u(|t₁| + |t₂|). Hence |p(x) − r| ≤ (k+4)u(|t₁| + |t₂|) + 4·2⁻¹⁰⁷⁵. The computed bound
//!   e = fl(fl(fl(|t₁| + |t₂|)·(k+7)u) + 2⁻¹⁰⁷⁰) is at least (1 − u)³ times its exact value,
//!   and the end points fl(r ∓ e) err by at most u(|r| + e) ≤ u(1 + u)(|t₁| + |t₂|) + u·e (or
//!   not at all when they underflow). Since (1 − u)⁴(k+7) ≥ k + 5 + u and
//!   (1 − u)²·31 ≥ 4, [fl(r − e), fl(r + e)] encloses p(x): the three extra units of u absorb
//!   the roundings of e and of its end points, the added 2⁻¹⁰⁷⁰ the underflow terms.
//!
//! A [`RoundedBound`] has one b and a linear coefficient for each side of 0; k is the largest
//! count of the three. Two comparisons select the case above: fl(x·x) ≥ 2⁻¹⁰²² (a
//! non-negative square is normal unless below that or infinite) and e ≤ `f64::MAX` (an infinite
//! fl(x·x), t₁ or t₂ makes e infinite or NaN, which fails the comparison, and a finite e bounds
//! |r| ≤ fl(|t₁| + |t₂|)). When they fail (x = 0, fl(x·x) not normal, an overflow), the same
//! parabola is evaluated in interval arithmetic with its coefficients widened by (k+4)u
//! ([`RoundedBound::widened`]).
//! The exact-arithmetic campaign (`verification/src/campaign`) checks every enclosure of both
//! paths against a 256-bit evaluation from independent formulas.

use std::sync::OnceLock;

use sepg_bounds::constants::{self, TaskConstants};
use sepg_bounds::high_probability::HpForm;

use crate::enclosure::{EnclosedBound, Quadratic};
use crate::interval::Interval;

/// u = 2⁻⁵³, the unit roundoff of `f64`.
const U: f64 = f64::EPSILON / 2.0;
/// Roundings of [`constants::c`] (module docs).
const C_ROUNDINGS: u32 = 14;
/// Roundings of [`constants::d`] (module docs).
const D_ROUNDINGS: u32 = 12;
/// 2⁻¹⁰⁷⁰: covers the underflow terms of [`RoundedBound::enclose`] (module docs).
const UNDERFLOW_SLACK: f64 = 16.0 * f64::from_bits(1);
/// The range [2⁻¹⁰⁰, 2¹⁰⁰] in which the task constants and σ keep c and d normal.
const BOX_LO: f64 = 7.888_609_052_210_118e-31;
const BOX_HI: f64 = 1.267_650_600_228_229_4e30;

/// Whether the constants are of the thesis family, R, M_φ, |A| ∈ [2⁻¹⁰⁰, 2¹⁰⁰], γ = 0 or
/// γ ≥ 2⁻¹⁰⁰, and the platform's ψ lies within
/// one ulp of its enclosure (the last condition only matters for d, holds wherever `exp` is
/// accurate to an ulp, and is decided once per process): the range of the task constants that
/// [`CertifiedTask`](crate::CertifiedTask) decides once.
#[inline]
pub(crate) fn task_in_box(k: &TaskConstants) -> bool {
    let inside = |x: f64| (BOX_LO..=BOX_HI).contains(&x);
    let gamma = k.gamma();
    // the a-priori counts are those of the thesis's formulas; the tight family is enclosed
    matches!(k.family(), sepg_bounds::Family::Thesis)
        && inside(k.r_max())
        && inside(k.m_phi())
        && inside(k.action_volume())
        && (gamma == 0.0 || gamma >= BOX_LO)
        && psi_is_enclosed()
}

/// Whether the roundings counted for c(σ) and d(σ) hold: R, M_φ, |A|, σ ∈ [2⁻¹⁰⁰, 2¹⁰⁰] and
/// γ = 0 or γ ≥ 2⁻¹⁰⁰, so that no intermediate result underflows or overflows, and the
/// platform's ψ is enclosed (`in_range`: [`task_in_box`] of the task constants, decided once
/// by a [`CertifiedTask`](crate::CertifiedTask) or at the call).
#[inline]
fn apriori_box(in_range: bool, sigma: f64) -> bool {
    in_range && (BOX_LO..=BOX_HI).contains(&sigma)
}

/// Whether the platform's `f64` ψ ([`constants::psi`], which calls `exp`) lies within one ulp
/// of the enclosure of [`crate::enclosure::psi`] (checked once).
fn psi_is_enclosed() -> bool {
    static ENCLOSED: OnceLock<bool> = OnceLock::new();
    *ENCLOSED.get_or_init(|| {
        let p = crate::enclosure::psi();
        (p.lo().next_down()..=p.hi().next_up()).contains(&constants::psi())
    })
}

/// An `f64` v̂ standing for an exact real v with v̂ = v(1 + θ), |θ| ≤ γ_k, k = `roundings`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Rounded {
    value: f64,
    roundings: u32,
}

impl Rounded {
    /// An exact `f64`.
    pub(crate) fn exact(value: f64) -> Self {
        Self {
            value,
            roundings: 0,
        }
    }

    /// fl(x − y) for exact x, y: one rounding (subtraction obeys the model even on underflow).
    pub(crate) fn difference(x: f64, y: f64) -> Self {
        Self {
            value: x - y,
            roundings: 1,
        }
    }

    /// fl(x + y) for exact x, y: one rounding.
    pub(crate) fn sum(x: f64, y: f64) -> Self {
        Self {
            value: x + y,
            roundings: 1,
        }
    }

    /// The product, or `None` when it underflows or overflows (the model would not hold). A
    /// zero factor gives the exact zero.
    pub(crate) fn mul(self, o: Self) -> Option<Self> {
        let value = self.value * o.value;
        if (f64::MIN_POSITIVE..=f64::MAX).contains(&value.abs()) {
            Some(Self {
                value,
                roundings: self.roundings + o.roundings + 1,
            })
        } else if self.value == 0.0 || o.value == 0.0 {
            Some(Self::exact(0.0))
        } else {
            None
        }
    }

    /// The exact negation.
    pub(crate) fn neg(self) -> Self {
        Self {
            value: -self.value,
            ..self
        }
    }
}

/// c(σ) with its 14 roundings, from `value` = [`constants::c`]`(k, sigma)`; `None` outside
/// [`apriori_box`].
#[inline]
pub(crate) fn c(in_range: bool, sigma: f64, value: f64) -> Option<Rounded> {
    apriori_box(in_range, sigma).then_some(Rounded {
        value,
        roundings: C_ROUNDINGS,
    })
}

/// d(σ) with its 12 roundings, from `value` = [`constants::d`]`(k, sigma)`; `None` outside
/// [`apriori_box`] (which includes the check that the platform's ψ is within one ulp of its
/// enclosure).
#[inline]
pub(crate) fn d(in_range: bool, sigma: f64, value: f64) -> Option<Rounded> {
    apriori_box(in_range, sigma).then_some(Rounded {
        value,
        roundings: D_ROUNDINGS,
    })
}

/// A bound that is the parabola p(x) = a₊·x − b·x² for x ≥ 0 and a₋·x − b·x² for x < 0 (one
/// quadratic coefficient, both through the origin), with `f64` coefficients of at most k
/// roundings, enclosed with a-priori error bounds (module docs): the fast [`EnclosedBound`] of
/// the certified steps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct RoundedBound {
    /// a₊, the linear coefficient for x ≥ 0.
    positive: f64,
    /// a₋, the linear coefficient for x < 0.
    negative: f64,
    /// b.
    b: f64,
    /// (k + 7)·u for the largest k of the three coefficients: the relative error factor of
    /// [`Self::enclose`].
    margin: f64,
}

impl RoundedBound {
    /// Separate linear coefficients for x ≥ 0 and x < 0 (the exploring w-update).
    pub(crate) fn two_sided(positive: Rounded, negative: Rounded, b: Rounded) -> Self {
        let k = positive.roundings.max(negative.roundings).max(b.roundings);
        Self {
            positive: positive.value,
            negative: negative.value,
            b: b.value,
            margin: f64::from(k + 7) * U,
        }
    }

    /// One parabola on both sides (Theorems 4.2, 4.3, 4.5).
    pub(crate) fn parabola(a: Rounded, b: Rounded) -> Self {
        Self::two_sided(a, a, b)
    }

    /// The high-probability bounds of Theorems 4.7–4.9: direction s = ±1, corrected linear
    /// coefficients a⁻ ≤ a⁺ and b; the favoured side (s·x ≥ 0) uses s·a⁻, the other side s·a⁺
    /// in the sign-aware form and s·a⁻ in the thesis form.
    pub(crate) fn high_probability(
        direction: f64,
        lower: Rounded,
        upper: Rounded,
        b: Rounded,
        form: HpForm,
    ) -> Self {
        let other = if form == HpForm::Thesis { lower } else { upper };
        if direction > 0.0 {
            Self::two_sided(lower, other, b)
        } else {
            Self::two_sided(other.neg(), lower.neg(), b)
        }
    }

    /// The linear coefficient on the side of x.
    #[inline(always)]
    fn linear(&self, x: f64) -> f64 {
        if x >= 0.0 {
            self.positive
        } else {
            self.negative
        }
    }

    /// The parabola of the side of x with interval coefficients that contain the exact a and
    /// b: each coefficient v̂ of k roundings is within |v̂|·γ_k/(1 − γ_k) ≤ (k+1)u|v̂| of v,
    /// and the widening by (k+4)u = margin − 3u, rounded outward, covers that and its own
    /// rounding.
    pub(crate) fn widened(&self, x: f64) -> Quadratic {
        let widening = self.margin - 3.0 * U;
        let widen = |v: f64| Interval::around(v, v.abs() * widening);
        Quadratic {
            linear: widen(self.linear(x)),
            quadratic: widen(self.b),
        }
    }

    /// The predicted distance from a root x of p(x) = C toward the vertex at which the
    /// enclosure's lower end reaches C: the error bound's factor plus 4u (for the rounding of
    /// the root itself) times the size of the terms |a·x| + b·x², enlarged by 1/8, over the
    /// slope at the root, |p′(x)| = 2√(b·(C_max − C)). The slope comes from the coefficients
    /// alone, so the processor computes it beside the step rather than after it. Only a
    /// prediction: the caller evaluates the enclosure at the moved step. +∞ or NaN when
    /// C ≥ C_max.
    #[inline(always)]
    pub(crate) fn predicted_move(&self, x: f64, c_max: f64, required: f64) -> f64 {
        let per_size = (self.margin + 4.0 * U) * 0.5625 / (self.b * (c_max - required)).sqrt();
        ((x * self.linear(x)).abs() + x * x * self.b) * per_size
    }

    /// The rare cases of [`Self::enclose`]: p(0) = 0, and the widened interval evaluation.
    #[cold]
    #[inline(never)]
    fn enclose_widened(&self, x: f64) -> Interval {
        if x == 0.0 {
            Interval::point(0.0)
        } else {
            self.widened(x).enclose(x)
        }
    }
}

impl EnclosedBound for RoundedBound {
    /// An enclosure of p(x) at the exact x (module docs).
    #[inline(always)]
    fn enclose(&self, x: f64) -> Interval {
        let xx = x * x;
        let t1 = x * self.linear(x);
        let t2 = xx * self.b;
        let r = t1 - t2;
        let e = (t1.abs() + t2.abs()) * self.margin + UNDERFLOW_SLACK;
        // two comparisons decide the common case: xx ≥ 0 is normal unless below
        // MIN_POSITIVE or infinite, and an infinite xx, t₁ or t₂ makes e infinite or NaN
        // (NaN fails the comparison); a finite e bounds |r| ≤ fl(|t₁| + |t₂|)
        if xx >= f64::MIN_POSITIVE && e <= f64::MAX {
            Interval::from_sorted(r - e, r + e)
        } else {
            self.enclose_widened(x)
        }
    }

    #[inline(always)]
    fn slope(&self, x: f64) -> Option<f64> {
        Some(self.linear(x) - 2.0 * self.b * x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_constants_are_powers_of_two() {
        assert_eq!(BOX_LO, 2f64.powi(-100));
        assert_eq!(BOX_HI, 2f64.powi(100));
        assert_eq!(UNDERFLOW_SLACK, 2f64.powi(-1070));
    }

    #[test]
    fn psi_of_this_platform_is_enclosed() {
        assert!(psi_is_enclosed());
    }

    #[test]
    fn underflowing_products_are_refused() {
        let tiny = Rounded::exact(1e-200);
        assert!(tiny.mul(tiny).is_none());
        assert!(Rounded::exact(1e200).mul(Rounded::exact(1e200)).is_none());
        assert_eq!(tiny.mul(Rounded::exact(0.0)), Some(Rounded::exact(0.0)));
        let p = Rounded::exact(3.0)
            .mul(Rounded::exact(0.1))
            .expect("normal");
        assert_eq!(p.roundings, 1);
    }

    #[test]
    fn subnormal_steps_fall_back_to_the_widened_interval() {
        let p = RoundedBound::parabola(Rounded::exact(1.0), Rounded::exact(1.0));
        // x² underflows: the interval evaluation of the widened coefficients is used
        let x = 1e-170;
        assert_eq!(p.enclose(x), p.widened(x).enclose(x));
        assert!(p.enclose(x).contains(x));
        // a normal step uses the error bound, whose width is about 2(k+7)u|x|
        let e = p.enclose(0.5);
        assert!(e.contains(0.25) && e.width() < 1e-14);
    }
}
