//! The certified steps take the a-priori error bound exactly when the task constants and σ lie
//! in the range of its analysis (R, M_φ, |A|, σ ∈ [2⁻¹⁰⁰, 2¹⁰⁰], γ = 0 or γ ≥ 2⁻¹⁰⁰), and
//! interval arithmetic otherwise; both certify the step.

use sepg_bounds::TaskConstants;
use sepg_certified::{Certified, CertifiedStep, CertifiedTask, v_safe_step, w_safe_step_along_j};

/// The certified v-step (Theorem 4.2) of the `lqg1d` inputs of the bench, with one constant
/// replaced; the range decided once by a `CertifiedTask` gives the same outcome as the range
/// decided at the call, and agrees with the path taken.
fn v_step(gamma: f64, r: f64, m: f64, a: f64) -> CertifiedStep {
    let k = TaskConstants::new(gamma, r, m, a).expect("valid constants");
    // scale the gradient so that ‖∇‖²·c stays of order one whatever the constants
    let c = sepg_bounds::constants::c(&k, 0.5).expect("finite");
    let grad = [-3.7 * c.sqrt()];
    let task = CertifiedTask::new(&k);
    let once = v_safe_step(&task, 0.5, &grad, 0.0).expect("valid");
    assert_eq!(once, v_safe_step(&k, 0.5, &grad, 0.0).expect("valid"));
    match once {
        Certified::Step(s) => {
            assert!(s.bound.lo() >= 0.0);
            assert_eq!(s.by_error_bound, task.in_rounding_range());
            s
        }
        other => panic!("expected a certified step, got {other:?}"),
    }
}

#[test]
fn the_error_bound_applies_inside_the_range_only() {
    let (g, r, m, a) = (0.99, 28.8, 4.0, 8.0);
    let lo = 2f64.powi(-100);
    let hi = 2f64.powi(100);
    assert!(v_step(g, r, m, a).by_error_bound);
    for (what, inside, outside) in [
        ("R", (g, hi, m, a), (g, hi * 1.01, m, a)),
        ("R", (g, lo, m, a), (g, lo * 0.99, m, a)),
        ("M_phi", (g, r, hi.sqrt(), a), (g, r, lo * 0.99, a)),
        ("|A|", (g, r, m, lo), (g, r, m, hi * 1.01)),
        ("gamma", (lo, r, m, a), (lo * 0.99, r, m, a)),
        ("gamma", (0.0, r, m, a), (lo * 0.5, r, m, a)),
    ] {
        assert!(
            v_step(inside.0, inside.1, inside.2, inside.3).by_error_bound,
            "{what} inside"
        );
        assert!(
            !v_step(outside.0, outside.1, outside.2, outside.3).by_error_bound,
            "{what} outside"
        );
    }
}

#[test]
fn sigma_outside_the_range_takes_the_interval_path() {
    let k = TaskConstants::new(0.99, 28.8, 4.0, 8.0).expect("valid");
    let step = |sigma: f64| match w_safe_step_along_j(&k, sigma, 0.3, 0.0).expect("valid") {
        Certified::Step(s) => s,
        other => panic!("expected a certified step, got {other:?}"),
    };
    assert!(step(0.5).by_error_bound);
    assert!(step(2f64.powi(-100)).by_error_bound);
    assert!(!step(2f64.powi(-100) * 0.99).by_error_bound);
}
