//! Outward rounding of `sepg_certified::Interval`: the exact result of each operation
//! on two `f64` points lies in the computed interval. The exact result is known through
//! error-free transformations: a + b = s + e (TwoSum), a·b = p + e with e = fma(a, b, −p), and
//! a/b = q + r/b with r = fma(−q, b, a) exact; so the exact value is above the rounded one iff
//! the error term is positive.
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use sepg_certified::Interval;

/// Whether `i` contains the exact real `rounded + (error term with the sign of err)`.
fn encloses(i: Interval, rounded: f64, err: f64) -> bool {
    if err > 0.0 {
        i.lo() <= rounded && i.hi() > rounded
    } else if err < 0.0 {
        i.lo() < rounded && i.hi() >= rounded
    } else {
        i.contains(rounded)
    }
}

fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

fn finite() -> impl Strategy<Value = f64> {
    prop_oneof![
        -1e3..1e3_f64,
        any::<f64>().prop_filter("finite", |x| x.is_finite() && x.abs() < 1e300),
        (1u64..(1 << 52)).prop_map(f64::from_bits),
    ]
}

proptest! {
    #![proptest_config(Config {
        cases: 4000,
        rng_seed: RngSeed::Fixed(16),
        failure_persistence: None,
        ..Config::default()
    })]

    #[test]
    fn arithmetic_encloses_the_exact_result(a in finite(), b in finite()) {
        let (x, y) = (Interval::point(a), Interval::point(b));
        let (s, e) = two_sum(a, b);
        prop_assert!(encloses(x + y, s, e));
        let (d, e) = two_sum(a, -b);
        prop_assert!(encloses(x - y, d, e));
        let p = a * b;
        prop_assert!(encloses(x * y, p, a.mul_add(b, -p)));
        prop_assert!(encloses(y.scale(a), p, a.mul_add(b, -p)));
        if b != 0.0 && (a / b).is_normal() {
            let q = a / b;
            // a − q·b exactly; the exact quotient is q + r/b
            let r = (-q).mul_add(b, a);
            prop_assert!(encloses(x / y, q, r * b.signum()));
        }
        if a > 0.0 {
            let r = a.sqrt();
            // a − r² exactly: the exact root is above r iff it is positive
            prop_assert!(encloses(x.sqrt(), r, (-r).mul_add(r, a)));
        }
    }

    #[test]
    fn products_of_intervals_enclose_every_product_of_members(
        a in -1e3..1e3_f64, b in -1e3..1e3_f64, c in -1e3..1e3_f64, d in -1e3..1e3_f64,
        t in 0.0..1.0_f64, u in 0.0..1.0_f64,
    ) {
        let x = Interval::new(a.min(b), a.max(b)).expect("ordered");
        let y = Interval::new(c.min(d), c.max(d)).expect("ordered");
        let (p, q) = (x.lo() + t * (x.hi() - x.lo()), y.lo() + u * (y.hi() - y.lo()));
        prop_assume!(x.contains(p) && y.contains(q));
        let prod = p * q;
        prop_assert!(encloses(x * y, prod, p.mul_add(q, -prod)));
        prop_assert!((x.sqr()).contains(p * p) && x.sqr().lo() >= 0.0);
    }
}

#[test]
fn overflow_and_zero_are_sound() {
    let big = Interval::point(f64::MAX);
    let s = big + big;
    assert_eq!(s.lo(), f64::MAX);
    assert_eq!(s.hi(), f64::INFINITY);
    assert_eq!(Interval::point(3.0).scale(0.0), Interval::point(0.0));
    assert_eq!(
        Interval::point(1.0) / Interval::new(-1.0, 1.0).expect("ordered"),
        Interval::ENTIRE
    );
    let tiny = Interval::point(5e-324) * Interval::point(0.5);
    assert!(tiny.lo() <= 0.0 && tiny.hi() >= 5e-324);
}
