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

/// With the tight constants (docs/THEOREMS.md "Tight constants") the a-priori analysis, which
/// counts the roundings of the thesis's formulas, does not apply: every step is certified in
/// interval arithmetic, the enclosures of c and d contain the `f64` values and the exact
/// S_H, and the certified bound is the tight parabola's.
#[test]
fn tight_constants_are_certified_by_enclosure() {
    use sepg_bounds::penalties::{Family, Horizon, Rewards, Tight};
    let base = TaskConstants::new(0.99, 28.8, 4.0, 8.0).expect("valid");
    for (horizon, rewards) in [
        (Horizon::Finite(20), Rewards::NonPositive),
        (Horizon::Finite(1), Rewards::TwoSided),
        (Horizon::Finite(3_000_000), Rewards::TwoSided),
        (Horizon::Infinite, Rewards::NonPositive),
    ] {
        let k = base
            .with_family(Family::Tight(Tight::new(horizon, rewards)))
            .expect("valid");
        let task = CertifiedTask::new(&k);
        assert!(!task.in_rounding_range());
        let rho = if rewards == Rewards::NonPositive {
            0.5
        } else {
            1.0
        };
        // S_H from an independent term-by-term sum (H = 20, 1), or S_∞
        let s = match horizon {
            Horizon::Finite(h) if h < 100 => (0..h)
                .map(|t| (t + 1) as f64 * 0.99f64.powi(t as i32))
                .sum(),
            _ => 1e4,
        };
        for sigma in [0.05, 0.3, 1.0, 4.0] {
            let c = sepg_certified::c(&k, sigma).expect("valid");
            let d = sepg_certified::d(&k, sigma).expect("valid");
            assert!(c.contains(sepg_bounds::constants::c(&k, sigma).expect("finite")));
            assert!(d.contains(sepg_bounds::constants::d(&k, sigma).expect("finite")));
            let c_exact = rho * 28.8 * 16.0 * s / (sigma * sigma);
            assert!(c.lo() <= c_exact * (1.0 + 1e-12) && c.hi() >= c_exact * (1.0 - 1e-12));
            for required in [0.0, -1e-3] {
                let grad = [-3.7 * c.hi().sqrt()];
                match v_safe_step(&task, sigma, &grad, required).expect("valid") {
                    Certified::Step(st) => {
                        assert!(!st.by_error_bound && st.bound.lo() >= required);
                        // the bound of the tight parabola at the step: x‖∇‖² − c x²‖∇‖²
                        let g2 = grad[0] * grad[0];
                        let plain = st.step * g2 - c.hi() * st.step * st.step * g2;
                        assert!(plain >= required - 1e-12 * g2.abs());
                    }
                    other => panic!("expected a certified step, got {other:?}"),
                }
                match w_safe_step_along_j(&task, sigma, 0.8, required).expect("valid") {
                    Certified::Step(st) => assert!(st.bound.lo() >= required),
                    other => panic!("expected a certified w-step, got {other:?}"),
                }
            }
        }
    }
}
