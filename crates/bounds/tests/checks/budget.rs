//! The budget of Theorem 4.1 (Definition 4.3) and the split of the requirement (eqs. (4.13)–(4.14)).

use approx::assert_abs_diff_eq;
use sepg_bounds::BoundsError;
use sepg_bounds::budget::{Budget, split_requirement};

#[test]
fn budget_telescopes_and_gives_theorem_4_1() {
    let mut b = Budget::new(1.0, -10.0, Some(-12.0)).unwrap();
    let steps = [(-9.5, -12.2), (-9.0, -11.0), (-9.8, -11.9), (-8.0, -10.5)];
    for (je, jt) in steps {
        b.record_exploratory(je).unwrap();
        b.record_target(jt).unwrap();
        assert_abs_diff_eq!(
            b.telescoped_change(),
            b.value() - b.initial(),
            epsilon = 1e-12
        );
        assert_abs_diff_eq!(b.average_performance(), (je + jt) / 2.0, epsilon = 1e-12);
        if b.is_type_two_safe() {
            assert!(b.average_performance() >= b.guaranteed_average() - 1e-12);
        }
    }
    assert_abs_diff_eq!(
        b.value(),
        1.0 + (-8.0 + 10.0) + (-10.5 + 12.0),
        epsilon = 1e-12
    );
    assert_eq!(b.baseline(), -11.0);
    assert_eq!(b.guaranteed_average(), -11.5);
    assert_eq!(b.required_improvement(), -b.value());
}

#[test]
fn budget_without_target_counts_each_difference_once() {
    let mut b = Budget::new(0.5, -3.0, None).unwrap();
    b.add_exploratory_difference(-0.4).unwrap();
    b.record_exploratory(-3.2).unwrap();
    assert_abs_diff_eq!(b.value(), 0.3, epsilon = 1e-15);
    assert_abs_diff_eq!(b.telescoped_change(), -0.2, epsilon = 1e-15);
    assert_eq!(b.guaranteed_average(), -3.5);
    assert!(b.is_type_two_safe() && b.average_performance() >= b.guaranteed_average());
    assert!(matches!(
        b.record_target(1.0),
        Err(BoundsError::NoTargetPolicy)
    ));
    assert!(matches!(
        Budget::new(f64::NAN, 0.0, None),
        Err(BoundsError::NonFinite { .. })
    ));
}

#[test]
fn requirement_split() {
    assert_eq!(split_requirement(4.0, 0.0).unwrap(), (4.0, 0.0));
    assert_eq!(split_requirement(4.0, 1.0).unwrap(), (0.0, 4.0));
    assert!(split_requirement(4.0, -0.1).is_err());
}
