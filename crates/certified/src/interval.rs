//! Closed intervals of reals with outward-rounded `f64` end points.
//!
//! Every operation computes its end points in round-to-nearest `f64` and then moves the lower
//! end one ulp down and the upper end one ulp up (`f64::next_down` / `f64::next_up`). IEEE 754
//! addition, subtraction, multiplication, division and square root are correctly rounded, so
//! the exact real result of each end-point operation lies within half an ulp of the computed
//! one, hence within the widened interval: an [`Interval`] computed from intervals that
//! enclose some reals encloses the exact real result. Overflow is sound too: a lower end that
//! rounds to +∞ is widened to `f64::MAX`, an upper end that rounds to +∞ stays +∞.
//!
//! The exponential ([`Interval::exp`], [`Interval::exp_m1`]) is the one exception to the
//! correctly-rounded rule: it uses the platform's `exp` / `exp_m1` (glibc on Linux, error below
//! one ulp) and widens by two ulps on each side. The exact-arithmetic campaign of
//! `tests/exact` checks every result that uses it against an independent multiple-precision
//! evaluation.
//!
//! End points are never NaN: an operation whose end point would be NaN (∞ − ∞, 0 · ∞) returns
//! the widest end point (−∞ for a lower end, +∞ for an upper end).

use std::ops::{Add, Div, Mul, Neg, Sub};

/// A closed interval [lo, hi] of reals (lo ≤ hi, neither NaN; either may be infinite).
///
/// Constructed exactly from an `f64` by [`Interval::point`] or from two bounds by
/// [`Interval::new`]; arithmetic with `+ − × ÷`, [`Interval::sqr`], [`Interval::sqrt`],
/// [`Interval::exp`] rounds outward (module docs), so results enclose the exact reals.
///
/// ```
/// use sepg_certified::Interval;
/// let third = Interval::point(1.0) / Interval::point(3.0);
/// assert!(third.lo() < third.hi());
/// assert!(third.lo() <= 1.0 / 3.0 && 1.0 / 3.0 <= third.hi());
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interval {
    lo: f64,
    hi: f64,
}

/// Lower end point, widened one ulp down; NaN (from ∞ − ∞ or 0 · ∞) becomes −∞.
#[inline]
fn down(x: f64) -> f64 {
    if x.is_nan() {
        f64::NEG_INFINITY
    } else {
        x.next_down()
    }
}

/// Upper end point, widened one ulp up; NaN becomes +∞.
#[inline]
fn up(x: f64) -> f64 {
    if x.is_nan() {
        f64::INFINITY
    } else {
        x.next_up()
    }
}

impl Interval {
    /// The whole real line (−∞, +∞), the enclosure of an unknown value.
    pub const ENTIRE: Interval = Interval {
        lo: f64::NEG_INFINITY,
        hi: f64::INFINITY,
    };

    /// The degenerate interval [x, x] (exact). NaN gives [`Interval::ENTIRE`].
    ///
    /// ```
    /// use sepg_certified::Interval;
    /// assert_eq!(Interval::point(0.1).lo(), 0.1);
    /// assert_eq!(Interval::point(f64::NAN), Interval::ENTIRE);
    /// ```
    #[inline]
    pub fn point(x: f64) -> Self {
        if x.is_nan() {
            Self::ENTIRE
        } else {
            Self { lo: x, hi: x }
        }
    }

    /// [lo, hi], or `None` when lo > hi or either is NaN.
    ///
    /// ```
    /// use sepg_certified::Interval;
    /// assert!(Interval::new(1.0, 2.0).is_some());
    /// assert!(Interval::new(2.0, 1.0).is_none());
    /// ```
    pub fn new(lo: f64, hi: f64) -> Option<Self> {
        (lo <= hi).then_some(Self { lo, hi })
    }

    /// [lo, hi] for end points known to be ordered and not NaN (constants of the crate, and
    /// end points whose rounding the caller has bounded).
    #[inline]
    pub(crate) const fn from_sorted(lo: f64, hi: f64) -> Self {
        Self { lo, hi }
    }

    /// The lower end point.
    #[inline]
    pub fn lo(&self) -> f64 {
        self.lo
    }

    /// The upper end point.
    #[inline]
    pub fn hi(&self) -> f64 {
        self.hi
    }

    /// Whether x ∈ [lo, hi].
    ///
    /// ```
    /// use sepg_certified::Interval;
    /// assert!(Interval::new(1.0, 2.0).unwrap().contains(1.5));
    /// ```
    pub fn contains(&self, x: f64) -> bool {
        self.lo <= x && x <= self.hi
    }

    /// Whether both end points are finite.
    pub fn is_finite(&self) -> bool {
        self.lo.is_finite() && self.hi.is_finite()
    }

    /// hi − lo rounded up (an upper bound on the width).
    ///
    /// ```
    /// use sepg_certified::Interval;
    /// assert!(Interval::new(1.0, 2.0).unwrap().width() >= 1.0);
    /// ```
    pub fn width(&self) -> f64 {
        up(self.hi - self.lo)
    }

    /// Widened end points of an operation whose exact result lies in [lo, hi] up to rounding.
    #[inline]
    fn rounded(lo: f64, hi: f64) -> Self {
        Self {
            lo: down(lo),
            hi: up(hi),
        }
    }

    /// The enclosure of x² (non-negative, tighter than x · x when 0 ∈ x).
    ///
    /// ```
    /// use sepg_certified::Interval;
    /// let s = Interval::new(-1.0, 2.0).unwrap().sqr();
    /// assert_eq!(s.lo(), 0.0);
    /// assert!(s.hi() >= 4.0);
    /// ```
    #[inline]
    pub fn sqr(self) -> Self {
        let (a, b) = (self.lo.abs(), self.hi.abs());
        let (small, large) = if a <= b { (a, b) } else { (b, a) };
        if large == 0.0 {
            Self::point(0.0)
        } else if self.lo <= 0.0 && self.hi >= 0.0 {
            Self {
                lo: 0.0,
                hi: up(large * large),
            }
        } else {
            Self {
                lo: down(small * small).max(0.0),
                hi: up(large * large),
            }
        }
    }

    /// The enclosure of √x over the non-negative part of x (lower end ≥ 0).
    ///
    /// ```
    /// use sepg_certified::Interval;
    /// let r = Interval::point(2.0).sqrt();
    /// assert!(r.lo() * r.lo() <= 2.0 && r.hi() * r.hi() >= 2.0);
    /// ```
    pub fn sqrt(self) -> Self {
        let lo = self.lo.max(0.0);
        let hi = self.hi.max(0.0);
        Self {
            lo: down(lo.sqrt()).max(0.0),
            hi: up(hi.sqrt()),
        }
    }

    /// The enclosure of e^x, assuming the platform `exp` errs by less than one ulp (module
    /// docs); widened by two ulps on each side.
    ///
    /// ```
    /// use sepg_certified::Interval;
    /// let e = Interval::point(1.0).exp();
    /// assert!(e.contains(std::f64::consts::E));
    /// ```
    pub fn exp(self) -> Self {
        Self {
            lo: down(down(self.lo.exp())).max(0.0),
            hi: up(up(self.hi.exp())),
        }
    }

    /// The enclosure of e^x − 1, assuming the platform `exp_m1` errs by less than one ulp;
    /// widened by two ulps on each side.
    ///
    /// ```
    /// use sepg_certified::Interval;
    /// assert!(Interval::point(1e-20).exp_m1().contains(1e-20));
    /// ```
    pub fn exp_m1(self) -> Self {
        Self {
            lo: down(down(self.lo.exp_m1())).max(-1.0),
            hi: up(up(self.hi.exp_m1())),
        }
    }

    /// The enclosure of max(self, other), element-wise on the end points (exact).
    ///
    /// ```
    /// use sepg_certified::Interval;
    /// let m = Interval::point(1.0).max(Interval::new(0.0, 2.0).unwrap());
    /// assert_eq!((m.lo(), m.hi()), (1.0, 2.0));
    /// ```
    pub fn max(self, other: Self) -> Self {
        Self {
            lo: self.lo.max(other.lo),
            hi: self.hi.max(other.hi),
        }
    }

    /// The enclosure of self · x for an exact `f64` x (two products instead of four).
    ///
    /// ```
    /// use sepg_certified::Interval;
    /// let p = Interval::new(1.0, 2.0).unwrap().scale(-3.0);
    /// assert!(p.contains(-3.0) && p.contains(-6.0));
    /// ```
    #[inline]
    pub fn scale(self, x: f64) -> Self {
        if x == 0.0 {
            // an enclosed real times exactly zero is exactly zero
            return Self::point(0.0);
        }
        if x > 0.0 {
            Self::rounded(self.lo * x, self.hi * x)
        } else {
            Self::rounded(self.hi * x, self.lo * x)
        }
    }

    /// The enclosure of |x| (exact end points).
    ///
    /// ```
    /// use sepg_certified::Interval;
    /// let a = Interval::new(-3.0, 2.0).unwrap().abs();
    /// assert_eq!((a.lo(), a.hi()), (0.0, 3.0));
    /// assert_eq!(Interval::new(-3.0, -2.0).unwrap().abs(), Interval::new(2.0, 3.0).unwrap());
    /// ```
    pub fn abs(self) -> Self {
        if self.lo >= 0.0 {
            self
        } else if self.hi <= 0.0 {
            -self
        } else {
            Self {
                lo: 0.0,
                hi: self.hi.max(-self.lo),
            }
        }
    }

    /// The interval [x − e, x + e] widened one ulp on each side, for a computed x and an error
    /// bound e ≥ 0 with |exact − x| ≤ e (the roundings of x − e and x + e are covered by the
    /// widening).
    #[inline]
    pub(crate) fn around(x: f64, e: f64) -> Self {
        Self::rounded(x - e, x + e)
    }

    /// The convex hull of two intervals.
    ///
    /// ```
    /// use sepg_certified::Interval;
    /// let h = Interval::point(1.0).hull(Interval::point(3.0));
    /// assert!(h.contains(2.0));
    /// ```
    pub fn hull(self, other: Self) -> Self {
        Self {
            lo: self.lo.min(other.lo),
            hi: self.hi.max(other.hi),
        }
    }
}

impl From<f64> for Interval {
    fn from(x: f64) -> Self {
        Self::point(x)
    }
}

impl Neg for Interval {
    type Output = Interval;
    #[inline]
    fn neg(self) -> Interval {
        Interval {
            lo: -self.hi,
            hi: -self.lo,
        }
    }
}

impl Add for Interval {
    type Output = Interval;
    #[inline]
    fn add(self, rhs: Interval) -> Interval {
        Interval::rounded(self.lo + rhs.lo, self.hi + rhs.hi)
    }
}

impl Sub for Interval {
    type Output = Interval;
    #[inline]
    fn sub(self, rhs: Interval) -> Interval {
        Interval::rounded(self.lo - rhs.hi, self.hi - rhs.lo)
    }
}

impl Mul for Interval {
    type Output = Interval;
    #[inline]
    fn mul(self, rhs: Interval) -> Interval {
        if self.lo >= 0.0 && rhs.lo >= 0.0 {
            // both non-negative: the common case of every penalty coefficient
            return Interval::rounded(self.lo * rhs.lo, self.hi * rhs.hi);
        }
        let p = [
            self.lo * rhs.lo,
            self.lo * rhs.hi,
            self.hi * rhs.lo,
            self.hi * rhs.hi,
        ];
        if p.iter().any(|x| x.is_nan()) {
            // 0 · ∞: an unbounded factor
            return Interval::ENTIRE;
        }
        let lo = p.iter().fold(f64::INFINITY, |m, &x| m.min(x));
        let hi = p.iter().fold(f64::NEG_INFINITY, |m, &x| m.max(x));
        Interval::rounded(lo, hi)
    }
}

impl Div for Interval {
    type Output = Interval;
    #[inline]
    fn div(self, rhs: Interval) -> Interval {
        if rhs.lo <= 0.0 && rhs.hi >= 0.0 {
            return Interval::ENTIRE;
        }
        if self.lo >= 0.0 && rhs.lo > 0.0 {
            return Interval::rounded(self.lo / rhs.hi, self.hi / rhs.lo);
        }
        let q = [
            self.lo / rhs.lo,
            self.lo / rhs.hi,
            self.hi / rhs.lo,
            self.hi / rhs.hi,
        ];
        if q.iter().any(|x| x.is_nan()) {
            return Interval::ENTIRE;
        }
        let lo = q.iter().fold(f64::INFINITY, |m, &x| m.min(x));
        let hi = q.iter().fold(f64::NEG_INFINITY, |m, &x| m.max(x));
        Interval::rounded(lo, hi)
    }
}

/// The position of a finite or infinite `f64` in the total order of floating-point numbers,
/// as an integer: consecutive floats have consecutive keys (−0.0 and +0.0 are neighbours).
///
/// Non-negative floats keep their bit pattern; a negative one, −m − 1 for the magnitude bits
/// m, which flipping the 63 low bits of the pattern gives without a branch.
#[inline]
pub(crate) fn ordered_key(x: f64) -> i64 {
    let bits = x.to_bits() as i64;
    bits ^ ((bits >> 63) & i64::MAX)
}

/// The inverse of [`ordered_key`] (the same flip: it is an involution).
#[inline]
pub(crate) fn from_ordered_key(key: i64) -> f64 {
    f64::from_bits((key ^ ((key >> 63) & i64::MAX)) as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ordered_keys_are_consecutive_across_zero() {
        for x in [
            -1.0,
            -f64::MIN_POSITIVE,
            -5e-324,
            -0.0,
            0.0,
            5e-324,
            1.0,
            f64::MAX,
        ] {
            let k = ordered_key(x);
            assert_eq!(from_ordered_key(k).to_bits(), x.to_bits());
            let next = from_ordered_key(k + 1);
            if x.to_bits() == (-0.0f64).to_bits() {
                assert_eq!(next.to_bits(), 0.0f64.to_bits());
            } else {
                assert_eq!(next.to_bits(), x.next_up().to_bits());
            }
        }
        assert_eq!(ordered_key(0.0) - ordered_key(-0.0), 1);
    }
}
