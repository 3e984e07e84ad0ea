//! Multiple-precision interval arithmetic on dyadic rationals m·2^e (m a big integer).
//!
//! Addition, subtraction and multiplication of dyadics are exact; a result is rounded
//! outward to [`PRECISION`] bits only when its mantissa is longer. Division, square roots and
//! the exponential round outward at the same precision. Every `f64` is a dyadic, so a
//! polynomial in `f64` inputs is evaluated exactly unless its mantissas exceed the precision;
//! irrational constants (π, √7, e^x) are enclosed by convergent series with rigorous
//! remainder bounds. The result of every evaluation is an interval that contains the exact
//! real value.

use std::cmp::Ordering;
use std::sync::OnceLock;

use num_bigint::BigInt;
use num_integer::Integer;
use num_traits::{Signed, ToPrimitive, Zero};

/// Bits kept by rounded results (enclosure width ≈ 2⁻²⁵⁰ relative).
pub(crate) const PRECISION: u64 = 256;

/// The dyadic rational m·2^e.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Dyadic {
    m: BigInt,
    e: i64,
}

impl Dyadic {
    /// The exact value of a finite `f64`.
    pub(crate) fn from_f64(x: f64) -> Self {
        assert!(x.is_finite(), "only finite f64 are dyadics");
        let bits = x.to_bits();
        let exponent = ((bits >> 52) & 0x7ff) as i64;
        let fraction = bits & ((1 << 52) - 1);
        let (m, e) = if exponent == 0 {
            (fraction, -1074)
        } else {
            (fraction | (1 << 52), exponent - 1075)
        };
        let m = BigInt::from(m);
        Self {
            m: if bits >> 63 == 1 { -m } else { m },
            e,
        }
    }

    fn int(i: i64) -> Self {
        Self {
            m: BigInt::from(i),
            e: 0,
        }
    }

    fn zero() -> Self {
        Self::int(0)
    }

    fn is_negative(&self) -> bool {
        self.m.is_negative()
    }

    fn neg(&self) -> Self {
        Self {
            m: -&self.m,
            e: self.e,
        }
    }

    /// The exact product a·b of two finite `f64`.
    pub(crate) fn product(a: f64, b: f64) -> Self {
        Self::from_f64(a).mul(&Self::from_f64(b))
    }

    pub(crate) fn abs(&self) -> Self {
        Self {
            m: self.m.abs(),
            e: self.e,
        }
    }

    fn add(&self, o: &Self) -> Self {
        if self.m.is_zero() {
            return o.clone();
        }
        if o.m.is_zero() {
            return self.clone();
        }
        let e = self.e.min(o.e);
        let a = &self.m << (self.e - e) as u64;
        let b = &o.m << (o.e - e) as u64;
        Self { m: a + b, e }
    }

    fn sub(&self, o: &Self) -> Self {
        self.add(&o.neg())
    }

    fn mul(&self, o: &Self) -> Self {
        Self {
            m: &self.m * &o.m,
            e: self.e + o.e,
        }
    }

    /// Multiplication by 2^k (exact).
    fn ldexp(&self, k: i64) -> Self {
        Self {
            m: self.m.clone(),
            e: self.e + k,
        }
    }

    fn cmp(&self, o: &Self) -> Ordering {
        match self.sub(o).m.sign() {
            num_bigint::Sign::Minus => Ordering::Less,
            num_bigint::Sign::NoSign => Ordering::Equal,
            num_bigint::Sign::Plus => Ordering::Greater,
        }
    }

    /// Rounds to at most `PRECISION` bits of mantissa, down (toward −∞) or up.
    fn round(self, up: bool) -> Self {
        let bits = self.m.bits();
        if bits <= PRECISION {
            return self;
        }
        let shift = bits - PRECISION;
        let mut m = &self.m >> shift;
        if up && (&m << shift) != self.m {
            m += 1;
        }
        Self {
            m,
            e: self.e + shift as i64,
        }
    }

    /// self / o rounded down or up (o ≠ 0).
    fn div(&self, o: &Self, up: bool) -> Self {
        let (num, den) = if o.m.is_negative() {
            (-&self.m, -&o.m)
        } else {
            (self.m.clone(), o.m.clone())
        };
        let k = (PRECISION + 2 + den.bits()) as i64 - num.bits() as i64;
        let k = k.max(0) as u64;
        let scaled = num << k;
        let (q, r) = scaled.div_mod_floor(&den);
        let q = if up && !r.is_zero() { q + 1 } else { q };
        Self {
            m: q,
            e: self.e - o.e - k as i64,
        }
        .round(up)
    }

    /// √self rounded down or up (self ≥ 0).
    fn sqrt(&self, up: bool) -> Self {
        let mut k = (2 * PRECISION + 2) as i64 - self.m.bits() as i64;
        k = k.max(0);
        if (self.e - k).rem_euclid(2) != 0 {
            k += 1;
        }
        let scaled = &self.m << k as u64;
        let s = scaled.sqrt();
        let s = if up && &s * &s != scaled { s + 1 } else { s };
        Self {
            m: s,
            e: (self.e - k) / 2,
        }
        .round(up)
    }

    /// The nearest `f64` (for reports; no rigour needed).
    pub(crate) fn to_f64(&self) -> f64 {
        let bits = self.m.bits() as i64;
        let shift = (bits - 60).max(0);
        let top = (&self.m >> shift as u64).to_f64().unwrap_or(0.0);
        let e = self.e + shift;
        // split the scaling so that intermediate powers of two stay in range
        let half = (e / 2) as i32;
        top * 2f64.powi(half) * 2f64.powi(e as i32 - half)
    }
}

/// A closed interval [lo, hi] of reals with dyadic end points.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Mp {
    pub(crate) lo: Dyadic,
    pub(crate) hi: Dyadic,
}

fn min(a: Dyadic, b: Dyadic) -> Dyadic {
    if a.cmp(&b) == Ordering::Greater { b } else { a }
}

fn max(a: Dyadic, b: Dyadic) -> Dyadic {
    if a.cmp(&b) == Ordering::Less { b } else { a }
}

impl Mp {
    /// The exact point x.
    pub(crate) fn f(x: f64) -> Self {
        let d = Dyadic::from_f64(x);
        Self {
            lo: d.clone(),
            hi: d,
        }
    }

    /// The exact point d.
    pub(crate) fn point(d: Dyadic) -> Self {
        Self {
            lo: d.clone(),
            hi: d,
        }
    }

    /// The exact integer i.
    pub(crate) fn int(i: i64) -> Self {
        Self {
            lo: Dyadic::int(i),
            hi: Dyadic::int(i),
        }
    }

    fn rounded(lo: Dyadic, hi: Dyadic) -> Self {
        Self {
            lo: lo.round(false),
            hi: hi.round(true),
        }
    }

    pub(crate) fn add(&self, o: &Self) -> Self {
        Self::rounded(self.lo.add(&o.lo), self.hi.add(&o.hi))
    }

    pub(crate) fn sub(&self, o: &Self) -> Self {
        Self::rounded(self.lo.sub(&o.hi), self.hi.sub(&o.lo))
    }

    pub(crate) fn neg(&self) -> Self {
        Self {
            lo: self.hi.neg(),
            hi: self.lo.neg(),
        }
    }

    pub(crate) fn mul(&self, o: &Self) -> Self {
        let p = [
            self.lo.mul(&o.lo),
            self.lo.mul(&o.hi),
            self.hi.mul(&o.lo),
            self.hi.mul(&o.hi),
        ];
        let lo = p.iter().cloned().reduce(min).unwrap_or_else(Dyadic::zero);
        let hi = p.into_iter().reduce(max).unwrap_or_else(Dyadic::zero);
        Self::rounded(lo, hi)
    }

    /// x² (non-negative).
    pub(crate) fn sqr(&self) -> Self {
        let (a, b) = (self.lo.abs(), self.hi.abs());
        let large = max(a.clone(), b.clone());
        let small = if self.lo.is_negative() && !self.hi.is_negative() {
            Dyadic::zero()
        } else {
            min(a, b)
        };
        Self::rounded(small.mul(&small), large.mul(&large))
    }

    /// self / o; `None` when o contains 0.
    pub(crate) fn div(&self, o: &Self) -> Option<Self> {
        if o.lo.cmp(&Dyadic::zero()) != Ordering::Greater
            && o.hi.cmp(&Dyadic::zero()) != Ordering::Less
        {
            return None;
        }
        let pairs = [
            (&self.lo, &o.lo),
            (&self.lo, &o.hi),
            (&self.hi, &o.lo),
            (&self.hi, &o.hi),
        ];
        let lo = pairs
            .iter()
            .map(|(a, b)| a.div(b, false))
            .reduce(min)
            .unwrap_or_else(Dyadic::zero);
        let hi = pairs
            .iter()
            .map(|(a, b)| a.div(b, true))
            .reduce(max)
            .unwrap_or_else(Dyadic::zero);
        Some(Self { lo, hi })
    }

    /// Multiplication by 2^k (exact).
    pub(crate) fn ldexp(&self, k: i64) -> Self {
        Self {
            lo: self.lo.ldexp(k),
            hi: self.hi.ldexp(k),
        }
    }

    /// √x of a non-negative interval.
    pub(crate) fn sqrt(&self) -> Self {
        let lo = max(self.lo.clone(), Dyadic::zero());
        Self {
            lo: lo.sqrt(false),
            hi: self.hi.sqrt(true),
        }
    }

    /// The larger of two intervals, end point by end point.
    pub(crate) fn max(&self, o: &Self) -> Self {
        Self {
            lo: max(self.lo.clone(), o.lo.clone()),
            hi: max(self.hi.clone(), o.hi.clone()),
        }
    }

    /// The interval [−t, t] for t ≥ 0.
    fn symmetric(t: &Dyadic) -> Self {
        Self {
            lo: t.abs().neg(),
            hi: t.abs(),
        }
    }

    /// e^x (exp is increasing: end points separately); `None` when |x| ≥ 2^40.
    pub(crate) fn exp(&self) -> Option<Self> {
        let limit = Dyadic::int(1).ldexp(40);
        let fits = |d: &Dyadic| d.abs().cmp(&limit) == Ordering::Less;
        (fits(&self.lo) && fits(&self.hi)).then(|| Self {
            lo: exp_point(&self.lo).lo,
            hi: exp_point(&self.hi).hi,
        })
    }

    /// Whether every point of the interval is ≥ c.
    pub(crate) fn certainly_ge(&self, c: &Self) -> bool {
        self.lo.cmp(&c.hi) != Ordering::Less
    }

    /// Whether every point of the interval is < c.
    pub(crate) fn certainly_lt(&self, c: &Self) -> bool {
        self.hi.cmp(&c.lo) == Ordering::Less
    }

    /// Whether self ⊆ [lo, hi].
    pub(crate) fn inside(&self, lo: f64, hi: f64) -> bool {
        (lo == f64::NEG_INFINITY || Dyadic::from_f64(lo).cmp(&self.lo) != Ordering::Greater)
            && (hi == f64::INFINITY || self.hi.cmp(&Dyadic::from_f64(hi)) != Ordering::Greater)
    }

    /// The midpoint as an `f64` (for reports).
    pub(crate) fn approx(&self) -> f64 {
        0.5 * (self.lo.to_f64() + self.hi.to_f64())
    }
}

/// e^x at a dyadic point with |x| < 2^40 (larger arguments would overflow the exponent):
/// e^x = (e^{x/2^k})^{2^k} with |x/2^k| ≤ 2⁻⁸, the Taylor series of the
/// reduced argument summed to 30 terms and its remainder bounded by 2|r|^31/31!.
fn exp_point(x: &Dyadic) -> Mp {
    if x.m.is_zero() {
        return Mp::int(1);
    }
    // |x| < 2^(bits + e); reduce so that |r| ≤ 2^-8
    let magnitude = x.m.bits() as i64 + x.e;
    let k = (magnitude + 8).max(0);
    let r = Mp {
        lo: x.ldexp(-k),
        hi: x.ldexp(-k),
    };
    let mut term = Mp::int(1);
    let mut sum = Mp::int(1);
    for n in 1..=30 {
        term = term.mul(&r).div(&Mp::int(n)).unwrap_or_else(|| Mp::int(0));
        sum = sum.add(&term);
    }
    let tail = term.mul(&r).div(&Mp::int(31)).unwrap_or_else(|| Mp::int(0));
    let bound = max(tail.lo.abs(), tail.hi.abs()).ldexp(1);
    let mut value = sum.add(&Mp::symmetric(&bound));
    for _ in 0..k {
        value = value.sqr();
    }
    value
}

/// KL2(t) = e^{−2t} − 1 + 2t at an exact t ≥ 0: for 2t ≤ 1/2 the alternating series
/// Σ_{n≥2} (−2t)^n/n! to n = 50 with its first omitted term as remainder, else from [`exp_point`].
pub(crate) fn kl2(t: &Dyadic) -> Mp {
    let y = Mp {
        lo: t.ldexp(1),
        hi: t.ldexp(1),
    };
    if y.hi.cmp(&Dyadic::int(1).ldexp(-1)) != Ordering::Greater {
        let mut term = y.sqr().ldexp(-1);
        let mut sum = term.clone();
        for n in 3..=50 {
            term = term
                .mul(&y)
                .neg()
                .div(&Mp::int(n))
                .unwrap_or_else(|| Mp::int(0));
            sum = sum.add(&term);
        }
        let tail = term.mul(&y).div(&Mp::int(51)).unwrap_or_else(|| Mp::int(0));
        let bound = max(tail.lo.abs(), tail.hi.abs());
        sum.add(&Mp::symmetric(&bound))
    } else if y.hi.cmp(&Dyadic::int(1024)) == Ordering::Less {
        exp_point(&y.lo.neg()).sub(&Mp::int(1)).add(&y)
    } else {
        // 0 < e^{−y} < e^{−1024} < 2^{−1000}
        let tiny = Mp {
            lo: Dyadic::zero(),
            hi: Dyadic::int(1).ldexp(-1000),
        };
        tiny.sub(&Mp::int(1)).add(&y)
    }
}

/// arctan(1/q) for an integer q ≥ 5: alternating series to 200 terms with its first omitted
/// term as remainder.
fn atan_inv(q: i64) -> Mp {
    let x = Mp::int(1).div(&Mp::int(q)).unwrap_or_else(|| Mp::int(0));
    let x2 = x.sqr();
    let mut power = x.clone();
    let mut sum = x.clone();
    for n in 1..200 {
        power = power.mul(&x2);
        let term = power.div(&Mp::int(2 * n + 1)).unwrap_or_else(|| Mp::int(0));
        sum = if n % 2 == 1 {
            sum.sub(&term)
        } else {
            sum.add(&term)
        };
    }
    let tail = power
        .mul(&x2)
        .div(&Mp::int(401))
        .unwrap_or_else(|| Mp::int(0));
    sum.add(&Mp::symmetric(&max(tail.lo.abs(), tail.hi.abs())))
}

/// π by Machin's formula π = 16 arctan(1/5) − 4 arctan(1/239).
pub(crate) fn pi() -> &'static Mp {
    static PI: OnceLock<Mp> = OnceLock::new();
    PI.get_or_init(|| atan_inv(5).ldexp(4).sub(&atan_inv(239).ldexp(2)))
}

/// √(2π).
pub(crate) fn sqrt_2pi() -> &'static Mp {
    static S: OnceLock<Mp> = OnceLock::new();
    S.get_or_init(|| pi().ldexp(1).sqrt())
}

/// ψ = 4(√7 − 2) e^{√7/2 − 2} / √(2π) (Lemma A.1).
pub(crate) fn psi() -> &'static Mp {
    static P: OnceLock<Mp> = OnceLock::new();
    P.get_or_init(|| {
        let s7 = Mp::int(7).sqrt();
        let e = s7
            .ldexp(-1)
            .sub(&Mp::int(2))
            .exp()
            .unwrap_or_else(|| Mp::int(0));
        s7.sub(&Mp::int(2))
            .ldexp(2)
            .mul(&e)
            .div(sqrt_2pi())
            .unwrap_or_else(|| Mp::int(0))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constants_are_enclosed_tightly() {
        let p = pi();
        assert!(p.inside(
            std::f64::consts::PI.next_down(),
            std::f64::consts::PI.next_up()
        ));
        let width = p.hi.sub(&p.lo);
        assert!(width.cmp(&Dyadic::int(1).ldexp(-240)) == Ordering::Less);
        let e = Mp::int(1).exp().expect("small argument");
        assert!(e.inside(
            std::f64::consts::E.next_down(),
            std::f64::consts::E.next_up()
        ));
        // exp(−x)·exp(x) encloses 1 for a large argument
        let big = Mp::f(37.25);
        let one = big
            .exp()
            .expect("small")
            .mul(&big.neg().exp().expect("small"));
        assert!(one.sub(&Mp::int(1)).inside(-1e-60, 1e-60));
        let s = Mp::int(2).sqrt();
        assert!(s.sqr().sub(&Mp::int(2)).inside(-1e-70, 1e-70));
    }

    #[test]
    fn kl2_series_and_exp_branches_agree_at_the_switch() {
        let t = Dyadic::from_f64(0.25);
        let series = kl2(&t);
        let direct = exp_point(&Dyadic::from_f64(-0.5))
            .sub(&Mp::int(1))
            .add(&Mp::f(0.5));
        assert!(series.sub(&direct).inside(-1e-70, 1e-70));
        // KL2(t) = 2t² − (4/3)t³ + O(t⁴), so (KL2(t)/(2t²) − 1)/t = −2/3 + O(t)
        let t = 2f64.powi(-66);
        let slope = kl2(&Dyadic::from_f64(t))
            .div(&Mp::f(t).sqr().ldexp(1))
            .expect("t ≠ 0")
            .sub(&Mp::int(1))
            .div(&Mp::f(t))
            .expect("t ≠ 0");
        assert!(slope.inside(-2.0 / 3.0 - 1e-15, -2.0 / 3.0 + 1e-15));
    }

    #[test]
    fn subnormals_and_signs_round_trip() {
        for x in [5e-324, -5e-324, -1.5, f64::MAX, -f64::MIN_POSITIVE] {
            assert_eq!(Dyadic::from_f64(x).to_f64(), x);
        }
    }
}
