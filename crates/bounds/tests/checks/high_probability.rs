//! High-probability variants: reduction to the exact theorems at ε = 0, the below-noise
//! outcome (4.23), and the sign of the Theorem 4.9 step.

use super::common::presets;
use approx::{assert_relative_eq, relative_eq};
use sepg_bounds::high_probability::{
    HighProbabilityBound, HpForm, corrected_norm, v_safe_step, w_safe_step_along_j,
    w_safe_step_along_l,
};
use sepg_bounds::outcome::StepOutcome;
use sepg_bounds::{v_update, w_update};

fn same(a: StepOutcome, b: StepOutcome) {
    match (a, b) {
        (StepOutcome::Feasible(x), StepOutcome::Feasible(y)) => {
            for (p, q) in [
                (x.lo, y.lo),
                (x.hi, y.hi),
                (x.vertex, y.vertex),
                (x.c_max, y.c_max),
            ] {
                assert!(
                    relative_eq!(p, q, epsilon = 0.0, max_relative = 1e-13),
                    "{p} vs {q}"
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
            assert_relative_eq!(a, b, epsilon = 0.0, max_relative = 1e-13);
            assert_relative_eq!(v, w, epsilon = 0.0, max_relative = 1e-13);
        }
        (a, b) => panic!("{a:?} vs {b:?}"),
    }
}

#[test]
fn zero_width_reduces_to_exact_theorems() {
    for k in presets() {
        for required in [0.5, 0.0, -0.5, 1e9] {
            let g = [0.3, -0.8];
            for form in [HpForm::Thesis, HpForm::SignAware] {
                same(
                    v_safe_step(&k, 0.7, &g, 0.0, required, form).unwrap(),
                    v_update::safe_step(&k, 0.7, &g, required).unwrap(),
                );
                same(
                    w_safe_step_along_j(&k, 0.7, -0.8, 0.0, required, form).unwrap(),
                    w_update::safe_step_along_j(&k, 0.7, -0.8, required).unwrap(),
                );
                same(
                    w_safe_step_along_l(&k, 0.7, -0.8, 0.0, 2.0, 0.0, required, form).unwrap(),
                    w_update::safe_step_along_l(&k, 0.7, -0.8, 2.0, required).unwrap(),
                );
            }
        }
    }
}

#[test]
fn below_noise_is_its_own_outcome() {
    let k = presets()[0];
    assert_eq!(corrected_norm(&[0.1, -0.2], 0.2).unwrap(), None);
    for form in [HpForm::Thesis, HpForm::SignAware] {
        assert_eq!(
            v_safe_step(&k, 1.0, &[0.1, -0.2], 0.2, 0.0, form).unwrap(),
            StepOutcome::BelowNoise
        );
        assert_eq!(
            w_safe_step_along_j(&k, 1.0, 0.0, 0.0, -1.0, form).unwrap(),
            StepOutcome::BelowNoise
        );
        assert_eq!(
            w_safe_step_along_l(&k, 1.0, 0.5, 0.1, 0.05, 0.1, 0.0, form).unwrap(),
            StepOutcome::BelowNoise
        );
    }
    assert_eq!(StepOutcome::BelowNoise.chosen_step(), None);
}

/// Figure 4.1: with ∇̂_w J ∇̂_w L < 0 the largest step is negative for a required improvement
/// and positive (following ∇̂_w L) for a bounded worsening.
#[test]
fn theorem_4_9_step_sign_follows_figure_4_1() {
    let k = presets()[0];
    let b = HighProbabilityBound::w_along_l(&k, 0.5, 0.9, 0.2, -3.0, 0.5)
        .unwrap()
        .unwrap();
    for form in [HpForm::Thesis, HpForm::SignAware] {
        let up = b
            .safe_step(0.5 * b.c_max(), form)
            .unwrap()
            .chosen_step()
            .unwrap();
        let down = b
            .safe_step(-0.5 * b.c_max(), form)
            .unwrap()
            .chosen_step()
            .unwrap();
        assert!(up < 0.0 && down > 0.0, "{up} {down}");
        // the chosen step is really guaranteed by the valid (sign-aware) bound only for SignAware
        if form == HpForm::SignAware {
            assert!(b.sign_aware_value(down).unwrap() >= -0.5 * b.c_max() * (1.0 + 1e-12));
        } else {
            assert!(b.sign_aware_value(down).unwrap() < -0.5 * b.c_max());
        }
    }
    let StepOutcome::Infeasible { c_max, vertex } =
        b.safe_step(2.0 * b.c_max(), HpForm::SignAware).unwrap()
    else {
        panic!("C > C_max")
    };
    assert_eq!((c_max, vertex), (b.c_max(), b.vertex()));
}
