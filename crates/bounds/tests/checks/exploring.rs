//! The exploring w-update: reduction to Theorem 4.5 at ε_J = 0, the end points of its safe
//! interval against the bound written out here, dominance over Theorem 4.9, and bad input.

use super::common::presets;
use approx::{assert_relative_eq, relative_eq};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use sepg_bounds::constants::{TaskConstants, d};
use sepg_bounds::exploring::{ExploringBound, w_exploring_step};
use sepg_bounds::high_probability::{HpForm, w_safe_step_along_l};
use sepg_bounds::outcome::StepOutcome;
use sepg_bounds::w_update;

/// B(Δw) = Δw ĝ − |Δw| ε − d Δw², written out independently of the crate.
fn bound_ref(k: &TaskConstants, sigma: f64, g: f64, eps: f64, dw: f64) -> f64 {
    dw * g - dw.abs() * eps - d(k, sigma).unwrap() * dw * dw
}

#[test]
fn zero_width_is_theorem_4_5() {
    for k in presets() {
        for sigma in [0.1, 0.7, 2.0] {
            for (g, l) in [(-0.8, 2.0), (0.8, 2.0), (0.3, -0.01), (0.0, 1.5)] {
                let c_max = w_update::c_max(&k, sigma, g).unwrap();
                for required in [0.5 * c_max, 0.0, -0.5, -1e-6, 2.0 * c_max + 1e-300] {
                    let ours = w_exploring_step(&k, sigma, g, 0.0, l, required).unwrap();
                    let thesis = w_update::safe_step_along_l(&k, sigma, g, l, required).unwrap();
                    match (ours, thesis) {
                        (StepOutcome::Feasible(a), StepOutcome::Feasible(b)) => {
                            for (p, q) in [(a.lo, b.lo), (a.hi, b.hi), (a.c_max, b.c_max)] {
                                assert!(
                                    relative_eq!(
                                        p,
                                        q,
                                        epsilon = f64::MIN_POSITIVE,
                                        max_relative = 1e-12
                                    ),
                                    "{k:?} {g} {l} {required}: {p} vs {q}"
                                );
                            }
                        }
                        (
                            StepOutcome::Infeasible {
                                c_max: a,
                                vertex: v,
                            },
                            StepOutcome::Infeasible {
                                c_max: b,
                                vertex: w,
                            },
                        ) => {
                            assert_relative_eq!(
                                a,
                                b,
                                epsilon = f64::MIN_POSITIVE,
                                max_relative = 1e-12
                            );
                            assert_relative_eq!(
                                v,
                                w,
                                epsilon = f64::MIN_POSITIVE,
                                max_relative = 1e-12
                            );
                        }
                        (a, b) => panic!("{a:?} vs {b:?} at g = {g}, l = {l}, C = {required}"),
                    }
                }
            }
        }
    }
}

/// Every end point of the safe Δw-interval meets C with equality (unless it is 0, where B = 0
/// ≥ C), 19 interior points meet C, and points 1e-6 beyond either end do not.
#[test]
fn interval_end_points_meet_the_requirement() {
    let mut checked = 0;
    for k in presets() {
        for sigma in [0.2, 1.0] {
            for (g, eps) in [(0.5, 0.1), (0.5, 0.7), (-0.5, 0.1), (0.0, 0.3), (-2.0, 2.0)] {
                let b = ExploringBound::new(&k, sigma, g, eps).unwrap();
                let (_, c_max) = b.vertex().unwrap();
                for frac in [0.9, 0.3, 0.0] {
                    for required in [frac * c_max, -1e-3, -10.0] {
                        let StepOutcome::Feasible(s) = b.safe_interval(required).unwrap() else {
                            panic!("C = {required} ≤ C_max = {c_max} must be feasible");
                        };
                        let f = |x: f64| bound_ref(&k, sigma, g, eps, x);
                        for (end, out) in [(s.lo, -1.0), (s.hi, 1.0)] {
                            if end != 0.0 {
                                assert!(
                                    relative_eq!(
                                        f(end),
                                        required,
                                        epsilon = 1e-9 * c_max,
                                        max_relative = 1e-9
                                    ),
                                    "B({end}) = {} ≠ C = {required}",
                                    f(end)
                                );
                                assert!(f(end + out * 1e-6 * end.abs()) < required, "beyond {end}");
                            }
                        }
                        for i in 1..20 {
                            let x = s.lo + (s.hi - s.lo) * i as f64 / 20.0;
                            assert!(f(x) >= required - 1e-12 * required.abs().max(c_max));
                        }
                        checked += 1;
                    }
                }
            }
        }
    }
    assert_eq!(checked, 4 * 2 * 5 * 3 * 3);
}

#[test]
fn infeasible_takes_the_step_of_maximal_guaranteed_improvement() {
    let k = presets()[1];
    let b = ExploringBound::new(&k, 0.5, -0.4, 0.1).unwrap();
    let (vertex, c_max) = b.vertex().unwrap();
    assert!(
        vertex < 0.0
            && relative_eq!(
                c_max,
                0.09 / (4.0 * d(&k, 0.5).unwrap()),
                max_relative = 1e-14
            )
    );
    assert_eq!(
        b.safe_interval(2.0 * c_max).unwrap(),
        StepOutcome::Infeasible { c_max, vertex }
    );
    // Within the noise no improvement is guaranteed: any C > 0 is infeasible, the step is 0.
    let noisy = ExploringBound::new(&k, 0.5, -0.4, 0.5).unwrap();
    assert_eq!(
        noisy.safe_interval(1e-12).unwrap(),
        StepOutcome::Infeasible {
            c_max: 0.0,
            vertex: 0.0
        }
    );
    // In β units (Δw = β ∇̂_w L) the infeasible vertex keeps its Δw.
    let StepOutcome::Infeasible { vertex: beta, .. } =
        w_exploring_step(&k, 0.5, -0.4, 0.1, -4.0, 2.0 * c_max).unwrap()
    else {
        panic!()
    };
    assert_relative_eq!(beta * -4.0, vertex, max_relative = 1e-15);
}

#[test]
fn below_noise_surrogate_still_explores() {
    // The situation of most w-blocks of a sampled run: |∇̂_w L| ≤ ε_L, budget available.
    for k in presets() {
        let required = -1e-4;
        let thesis =
            w_safe_step_along_l(&k, 1.0, -0.3, 0.1, 0.4, 0.5, required, HpForm::SignAware).unwrap();
        assert_eq!(thesis, StepOutcome::BelowNoise);
        let beta = w_exploring_step(&k, 1.0, -0.3, 0.1, 0.4, required)
            .unwrap()
            .chosen_step()
            .unwrap();
        let dw = beta * 0.4;
        assert!(dw > 0.0, "σ rises along ∇̂_w L");
        assert!(bound_ref(&k, 1.0, -0.3, 0.1, dw) >= required * (1.0 + 1e-12));
    }
}

#[test]
fn zero_direction_and_bad_input() {
    let k = presets()[0];
    assert_eq!(
        w_exploring_step(&k, 1.0, 0.3, 0.1, 0.0, -1.0).unwrap(),
        StepOutcome::ZeroGradient {
            requirement_met: true
        }
    );
    for (g, eps, l, c) in [
        (f64::NAN, 0.1, 1.0, 0.0),
        (0.3, -0.1, 1.0, 0.0),
        (0.3, f64::INFINITY, 1.0, 0.0),
        (0.3, 0.1, f64::NAN, 0.0),
        (0.3, 0.1, 1.0, f64::NEG_INFINITY),
    ] {
        assert!(w_exploring_step(&k, 1.0, g, eps, l, c).is_err());
    }
    assert!(w_exploring_step(&k, 0.0, 0.3, 0.1, 1.0, 0.0).is_err());
    assert!(w_exploring_step(&k, 1.0, 0.3, 0.1, 1e-320, -1.0).is_err());
}

proptest! {
    #![proptest_config(Config {
        cases: 2000,
        rng_seed: RngSeed::Fixed(11),
        failure_persistence: None,
        ..Config::default()
    })]

    /// Theorem 4.9's bound is pointwise below the exploring bound, so wherever Theorem 4.9
    /// allows a step the exploring interval contains it and reaches at least as far along
    /// ∇̂_w L; the chosen step meets C; feasibility ⇔ C ≤ C_max.
    #[test]
    fn dominates_theorem_4_9(
        k_index in 0usize..4, sigma in 0.05..3.0_f64, g in -50.0..50.0_f64,
        eps_j in 0.0..30.0_f64, l in prop_oneof![-50.0..-1e-3_f64, 1e-3..50.0_f64],
        eps_l in 0.0..30.0_f64, frac in -3.0..1.2_f64,
    ) {
        let k = presets()[k_index];
        let bound = ExploringBound::new(&k, sigma, g, eps_j).unwrap();
        let (_, c_max) = bound.vertex().unwrap();
        let scale = d(&k, sigma).unwrap().recip() * (g.abs() + eps_j).powi(2);
        let required = if frac < 0.0 { frac * scale } else { frac * c_max };
        let ours = w_exploring_step(&k, sigma, g, eps_j, l, required).unwrap();
        prop_assert_eq!(ours.is_feasible(), required <= c_max * (1.0 + 1e-15));
        if let StepOutcome::Feasible(s) = ours {
            let beta = ours.chosen_step().unwrap();
            prop_assert!(beta == s.hi);
            let tol = 1e-9 * required.abs().max(c_max).max(1e-300);
            prop_assert!(bound_ref(&k, sigma, g, eps_j, beta * l) >= required - tol);
            if let StepOutcome::Feasible(t) =
                w_safe_step_along_l(&k, sigma, g, eps_j, l, eps_l, required, HpForm::SignAware)
                    .unwrap()
            {
                let slack = 1e-9 * s.hi.abs().max(s.lo.abs());
                prop_assert!(s.lo <= t.lo + slack && t.hi <= s.hi + slack, "{:?} vs {:?}", s, t);
            }
        }
    }
}
