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

/// The certified step along a direction: never beyond the `f64` step nor the cap, its
/// enclosure meets C, the enclosure contains the `f64` bound at that step, and it is within
/// 1e-12 (relative) of the `f64` step, over a fixed grid of directions, widths and
/// requirements with the tight constants.
#[test]
fn direction_steps_are_certified_and_close_to_the_f64_step() {
    use sepg_bounds::direction::{Direction, DirectionBound, FeatureNorm};
    use sepg_bounds::penalties::{Family, Horizon, Rewards, Tight};
    let k = TaskConstants::new(0.99, 28.8, 4.0, 8.0)
        .and_then(|k| {
            k.with_family(Family::Tight(Tight::new(
                Horizon::Finite(20),
                Rewards::NonPositive,
            )))
        })
        .expect("constants");
    let mut n = 0;
    for (i, u) in [[1e-2, -3e-3], [0.0, 0.7], [-1e-4, -1e-4]]
        .iter()
        .enumerate()
    {
        for g in [[35.0, -4.0], [-0.3, 0.2], [1e-3, 12.0]] {
            for e in [0.0, 0.1, 3.0] {
                for sigma in [0.1, 0.5, 1.0] {
                    let d = Direction {
                        direction: u,
                        grad_hat: &g,
                        eps: &[e, e],
                        features: FeatureNorm::FromMax { features: 2 + i },
                    };
                    let b = DirectionBound::new(&k, sigma, &d).expect("bound");
                    // C_max over t ≥ 0: 0 when the direction does not ascend the bound
                    let c_max = if b.parabola.linear > 0.0 {
                        b.parabola.c_max().expect("c_max")
                    } else {
                        0.0
                    };
                    for (required, cap) in [
                        (0.0, 1.0),
                        (0.0, f64::INFINITY),
                        (-1e-3, 1.0),
                        (0.5 * c_max, f64::INFINITY),
                    ] {
                        let f = b.safe_step(required, cap).expect("f64 step");
                        let o = sepg_certified::direction_safe_step(&k, sigma, &d, required, cap)
                            .expect("certified");
                        let Certified::Step(s) = o else {
                            panic!("{u:?} {g:?} {e} {sigma} {required}: {o:?}")
                        };
                        assert!(s.step <= f.step && s.step <= cap && s.step >= 0.0);
                        assert!(s.bound.lo() >= required);
                        assert!(s.bound.contains(b.bound(s.step).expect("bound")));
                        assert!(
                            f.step - s.step <= 1e-12 * f.step,
                            "{} vs {}",
                            s.step,
                            f.step
                        );
                        n += 1;
                    }
                }
            }
        }
    }
    assert_eq!(n, 324);
}
