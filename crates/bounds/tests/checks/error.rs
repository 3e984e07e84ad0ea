//! Invalid input gives typed errors, never a panic or NaN.

use sepg_bounds::BoundsError;
use sepg_bounds::constants::{TaskConstants, c, d, dc_dsigma};
use sepg_bounds::high_probability::{HpForm, v_safe_step};
use sepg_bounds::{greedy, papini, pirotta, rigorous, surrogate, v_update, w_update};

fn domain(r: Result<impl std::fmt::Debug, BoundsError>) {
    assert!(matches!(r, Err(BoundsError::OutOfDomain { .. })), "{r:?}");
}
fn non_finite(r: Result<impl std::fmt::Debug, BoundsError>) {
    assert!(matches!(r, Err(BoundsError::NonFinite { .. })), "{r:?}");
}

#[test]
fn task_constants_are_validated() {
    domain(TaskConstants::new(1.0, 1.0, 1.0, 1.0));
    domain(TaskConstants::new(-0.1, 1.0, 1.0, 1.0));
    domain(TaskConstants::new(0.5, 0.0, 1.0, 1.0));
    domain(TaskConstants::new(0.5, 1.0, -1.0, 1.0));
    domain(TaskConstants::new(0.5, 1.0, 1.0, 0.0));
    non_finite(TaskConstants::new(f64::NAN, 1.0, 1.0, 1.0));
    non_finite(TaskConstants::new(0.5, f64::INFINITY, 1.0, 1.0));
}

#[test]
fn sigma_and_vectors_are_validated() {
    let k = TaskConstants::new(0.9, 1.0, 1.0, 1.0).unwrap();
    domain(c(&k, 0.0));
    domain(d(&k, -1.0));
    non_finite(dc_dsigma(&k, f64::NAN));
    assert!(matches!(
        v_update::safe_step(&k, 1.0, &[], 0.0),
        Err(BoundsError::EmptyVector { .. })
    ));
    non_finite(v_update::safe_step(&k, 1.0, &[1.0, f64::NAN], 0.0));
    non_finite(v_update::safe_step(&k, 1.0, &[1.0], f64::NEG_INFINITY));
    assert!(matches!(
        papini::bound(&k, 1.0, &[1.0, 2.0], &[0.1]),
        Err(BoundsError::LengthMismatch { .. })
    ));
    assert!(matches!(
        surrogate::mixed_from_h(&[1.0], &[1.0, 2.0], 1.0),
        Err(BoundsError::LengthMismatch { .. })
    ));
    domain(pirotta::hp_optimal_step(&k, 1.0, &[1.0], &[-0.1]));
    domain(v_safe_step(&k, 1.0, &[1.0], -0.1, 0.0, HpForm::Thesis));
    domain(w_update::beta_tilde(&k, 1.0, 0.5, 0.0));
    non_finite(rigorous::bound(&k, 1.0, 0.5, f64::INFINITY));
    assert!(matches!(
        greedy::w_step(&k, &[1.0, 1.0], &[0.1, 0.2], &[0.3], 0.0),
        Err(BoundsError::LengthMismatch { .. })
    ));
}

#[test]
fn overflow_is_a_typed_error() {
    let k = TaskConstants::new(0.999_999, 1e100, 1e100, 1e100).unwrap();
    assert!(matches!(c(&k, 1e-100), Err(BoundsError::Overflow { .. })));
    let k = TaskConstants::new(0.5, 1.0, 1.0, 1.0).unwrap();
    assert!(matches!(
        v_update::bound(&k, 1.0, &[1e200], 1.0),
        Err(BoundsError::Overflow { .. })
    ));
}

/// Regression (robustness property): with |∇̂_w J| = 1e-170 the squared corrected norms
/// underflow to 0, so the bound had a⁻ = b = 0 and `vertex()` = 0/0 = NaN. The constructors
/// now return a typed error whenever the vertex or C_max is not representable.
#[test]
fn high_probability_bounds_never_hold_an_unrepresentable_vertex() {
    use sepg_bounds::high_probability::HighProbabilityBound;
    let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0).unwrap();
    let tiny = [
        HighProbabilityBound::w_along_j(&k, 1e154, -1e-170, 5.5e-221),
        HighProbabilityBound::v_update(&k, 1.0, &[1e-170], 0.0),
        HighProbabilityBound::w_along_l(&k, 1.0, 1e-170, 0.0, 1e-170, 0.0),
    ];
    for r in tiny {
        match r {
            Ok(Some(b)) => panic!("unrepresentable bound returned: {b:?}"),
            Ok(None) => panic!("an estimate above its width is not below noise"),
            Err(e) => assert!(matches!(e, BoundsError::Overflow { .. }), "{e:?}"),
        }
    }
    // Representable small gradients still give finite bounds.
    let b = HighProbabilityBound::w_along_j(&k, 1.0, -1e-100, 0.0)
        .unwrap()
        .unwrap();
    assert!(b.vertex().is_finite() && b.vertex() > 0.0 && b.c_max().is_finite());
}

/// Regression (fuzzing): `kl2(f64::MAX)` returned `Ok(inf)` because 2|Δw| overflows.
#[test]
fn kl2_of_a_huge_step_is_an_overflow_error() {
    assert!(matches!(
        rigorous::kl2(f64::MAX),
        Err(BoundsError::Overflow { .. })
    ));
    assert!(matches!(
        rigorous::kl2(-f64::MAX),
        Err(BoundsError::Overflow { .. })
    ));
    let big = rigorous::kl2(1e300).unwrap();
    assert_eq!(big, 2e300 - 1.0);
}

/// Regression (fuzzing): finite performances near ±f64::MAX made the budget's reported
/// baseline, average or telescoped change ±∞. Construction and updates that would do so are
/// now overflow errors that leave the budget unchanged.
#[test]
fn budget_never_reports_an_overflowed_quantity() {
    use sepg_bounds::budget::Budget;
    let max = f64::MAX;
    assert!(matches!(
        Budget::new(max, -max, Some(-max)),
        Err(BoundsError::Overflow { .. })
    ));
    assert!(matches!(
        Budget::new(-max, max, None),
        Err(BoundsError::Overflow { .. })
    ));
    let mut b = Budget::new(0.0, max, None).unwrap();
    let before = b.clone();
    assert!(matches!(
        b.record_exploratory(-max),
        Err(BoundsError::Overflow { .. })
    ));
    assert_eq!(b, before);
    let mut t = Budget::new(0.0, max, Some(0.0)).unwrap();
    let before = t.clone();
    assert!(matches!(
        t.add_target_difference(max),
        Err(BoundsError::Overflow { .. })
    ));
    assert_eq!(t, before);
    for x in [
        t.baseline(),
        t.average_performance(),
        t.telescoped_change(),
        t.guaranteed_average(),
    ] {
        assert!(x.is_finite());
    }
}

/// Regression (fuzzing): with a subnormal C_max (5e-324) and C = C_max, the small root
/// C/(b·hi) lost its precision and the safe interval came out with lo > hi.
#[test]
fn safe_intervals_are_ordered_even_for_a_subnormal_c_max() {
    use sepg_bounds::outcome::StepOutcome;
    let k = TaskConstants::new(2.220446049250313e-16, 0.5, 1e-154, 0.9999999999999999).unwrap();
    let sigma = 2.220446049250313e-16;
    let out = w_update::safe_step_along_j(&k, sigma, 1e-154, 5e-324).unwrap();
    let StepOutcome::Feasible(s) = out else {
        panic!("C = C_max is feasible: {out:?}")
    };
    assert!(s.lo <= s.vertex && s.vertex <= s.hi, "{s:?}");
}

/// σ is validated where the formulas first need c or d, after the inputs checked before it,
/// as before the evaluated `Penalties` existed: an invalid σ together with an invalid gradient
/// reports whichever the function checked first.
#[test]
fn sigma_is_validated_in_its_original_place() {
    use sepg_bounds::exploring::ExploringBound;
    use sepg_bounds::high_probability::HighProbabilityBound;
    let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0).expect("valid");
    let is_sigma = |e: BoundsError| matches!(e, BoundsError::OutOfDomain { name: "sigma", .. });
    let is_grad = |e: BoundsError| matches!(e, BoundsError::NonFinite { name, .. } | BoundsError::EmptyVector { name } if name != "sigma");
    let nan = f64::NAN;
    // the gradient first
    for e in [
        v_update::safe_step(&k, -1.0, &[nan], 0.0).unwrap_err(),
        v_update::c_max(&k, -1.0, &[]).unwrap_err(),
        v_update::bound(&k, -1.0, &[nan], 0.1).unwrap_err(),
        w_update::safe_step_along_j(&k, -1.0, nan, 0.0).unwrap_err(),
        w_update::safe_step_along_l(&k, -1.0, 0.3, nan, 0.0).unwrap_err(),
        w_update::bound_along_l(&k, -1.0, nan, 1.0, 0.1).unwrap_err(),
        w_update::beta_tilde(&k, -1.0, nan, 1.0).unwrap_err(),
        pirotta::bound(&k, -1.0, &[], 0.1).unwrap_err(),
        pirotta::hp_bound(&k, -1.0, &[nan], &[0.1], 0.1).unwrap_err(),
        papini::greedy_step(&k, -1.0, &[]).unwrap_err(),
        ExploringBound::new(&k, -1.0, nan, 0.1).unwrap_err(),
        v_safe_step(&k, -1.0, &[0.5], 0.1, nan, HpForm::Thesis).unwrap_err(),
    ] {
        assert!(is_grad(e), "{e:?}");
    }
    // σ first
    for e in [
        v_safe_step(&k, -1.0, &[nan], 0.1, 0.0, HpForm::Thesis).unwrap_err(),
        HighProbabilityBound::v_update(&k, -1.0, &[nan], 0.1).unwrap_err(),
        HighProbabilityBound::w_along_l(&k, -1.0, nan, 0.1, 1.0, 0.1).unwrap_err(),
        v_update::alpha_star(&k, -1.0).unwrap_err(),
    ] {
        assert!(is_sigma(e), "{e:?}");
    }
}
