//! High-probability variants: reduction to the exact theorems at ε = 0, the below-noise
//! outcome (4.23), and the sign of the Theorem 4.9 step.

use super::common::{
    FRACTIONS, SIGMAS, c_ref, check_interval, close, d_ref, feasible, numeric_vertex, presets,
    psi_numeric,
};
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

/// The thesis-form high-probability intervals against the printed polynomials, and the
/// sign-aware intervals against the piecewise bound that stays valid on both sides of 0.
#[test]
fn high_probability_intervals() {
    let psi_n = psi_numeric();
    for k in presets() {
        for sigma in [0.1, 1.0] {
            let cc = c_ref(&k, sigma);
            let dd = d_ref(&k, sigma, psi_n);
            let bounds = [
                (
                    HighProbabilityBound::v_update(&k, sigma, &[0.5, -0.9], 0.2)
                        .unwrap()
                        .unwrap(),
                    (1.0, 0.49, 1.21, cc * 1.21),
                ),
                (
                    HighProbabilityBound::w_along_j(&k, sigma, -0.9, 0.2)
                        .unwrap()
                        .unwrap(),
                    (1.0, 0.49, 1.21, dd * 1.21),
                ),
                (
                    HighProbabilityBound::w_along_l(&k, sigma, 0.9, 0.2, -3.0, 0.5)
                        .unwrap()
                        .unwrap(),
                    (-1.0, 2.5 * 0.7, 3.5 * 1.1, dd * 3.5 * 3.5),
                ),
            ];
            for (b, (s, a_lo, a_up, q)) in bounds {
                let thesis =
                    move |x: f64| (s * x * a_lo - q * x * x, (a_lo * x).abs().max(q * x * x));
                let aware = move |x: f64| {
                    let lin = if s * x >= 0.0 {
                        s * x * a_lo
                    } else {
                        -x.abs() * a_up
                    };
                    (lin - q * x * x, lin.abs().max(q * x * x))
                };
                for f in FRACTIONS {
                    let required = f * b.c_max();
                    let t = feasible(b.safe_step(required, HpForm::Thesis).unwrap());
                    check_interval(&thesis, &t, required);
                    let a = feasible(b.safe_step(required, HpForm::SignAware).unwrap());
                    check_interval(&aware, &a, required);
                    // same favoured end, never wider than the thesis interval
                    if s > 0.0 {
                        assert_relative_eq!(a.hi, t.hi, epsilon = 0.0, max_relative = 1e-14);
                        assert!(a.lo >= t.lo);
                    } else {
                        assert_relative_eq!(a.lo, t.lo, epsilon = 0.0, max_relative = 1e-14);
                        assert!(a.hi <= t.hi);
                    }
                    // for C < 0 the thesis interval reaches steps whose valid bound is < C
                    if f <= -0.3 {
                        let far = if s > 0.0 { t.lo } else { t.hi };
                        assert!(aware(far).0 < required, "printed interval not guaranteed");
                    }
                }
            }
        }
    }
}

/// Theorems 4.7–4.9: the step is the vertex of the stated polynomial and C_max its value;
/// the printed α* = 1/(2c) of Thm 4.7 and the printed C_max of Thm 4.9 (d² for d) are not.
#[test]
fn high_probability_vertices_and_errata() {
    let psi_n = psi_numeric();
    for k in presets() {
        for sigma in SIGMAS {
            let cc = c_ref(&k, sigma);
            let dd = d_ref(&k, sigma, psi_n);
            // Theorem 4.7
            let (g, eps) = ([0.5, -0.9], 0.2);
            let (lo, up) = (0.7_f64, 1.1_f64);
            let poly = |a: f64| a * lo * lo - a * a * cc * up * up;
            let best = numeric_vertex(poly, lo * lo, cc * up * up);
            let b = HighProbabilityBound::v_update(&k, sigma, &g, eps)
                .unwrap()
                .unwrap();
            assert!(close(b.vertex(), best, 1e-6, 0.0));
            assert!(close(b.c_max(), poly(best), 1e-11, 0.0));
            assert!(close(
                b.c_max(),
                lo.powi(4) / (4.0 * cc * up * up),
                1e-12,
                0.0
            ));
            let printed_alpha = 1.0 / (2.0 * cc);
            assert!(
                poly(printed_alpha) < 0.5 * b.c_max(),
                "1/(2c) is not the maximiser"
            );
            // Theorem 4.8
            let b = HighProbabilityBound::w_along_j(&k, sigma, -0.9, eps)
                .unwrap()
                .unwrap();
            let poly = |x: f64| x * lo * lo - x * x * dd * up * up;
            let best = numeric_vertex(poly, lo * lo, dd * up * up);
            assert!(close(b.vertex(), best, 1e-6, 0.0));
            assert!(close(b.c_max(), poly(best), 1e-11, 0.0));
            // Theorem 4.9, ∇̂J and ∇̂L of opposite signs: β̃ < 0
            let (j, ej, l, el) = (0.9_f64, 0.2_f64, -3.0_f64, 0.5_f64);
            let (jm, lm, lp) = (j - ej, l.abs() - el, l.abs() + el);
            let b = HighProbabilityBound::w_along_l(&k, sigma, j, ej, l, el)
                .unwrap()
                .unwrap();
            let poly = |x: f64| -x * lm * jm - x * x * dd * lp * lp;
            let best = numeric_vertex(poly, -lm * jm, dd * lp * lp);
            assert!(b.vertex() < 0.0);
            assert!(close(b.vertex(), best, 1e-6, 0.0));
            assert!(close(b.c_max(), poly(best), 1e-11, 0.0));
            let printed_c_max = (lm * jm / (2.0 * dd * lp)).powi(2);
            assert!(close(printed_c_max * dd, b.c_max(), 1e-12, 0.0));
            assert!(
                !close(printed_c_max, poly(best), 1e-3, 0.0),
                "printed C_max has d²"
            );
        }
    }
}
