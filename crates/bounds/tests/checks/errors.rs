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
