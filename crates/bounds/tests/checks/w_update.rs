//! Theorems 4.3 and 4.5: the intervals (4.17), (4.19) against the bounds evaluated from their
//! printed definitions, and β*, β̃, C_max against a golden-section maximisation.

use super::common::{
    FRACTIONS, SIGMAS, check_interval, close, d_ref, feasible, numeric_vertex, presets,
    psi_numeric, quad,
};
use approx::assert_relative_eq;
use sepg_bounds::outcome::StepOutcome;
use sepg_bounds::{v_update, w_update};

#[test]
fn w_update_intervals_4_17_and_4_19() {
    let psi_n = psi_numeric();
    for k in presets() {
        for sigma in [0.1, 1.0] {
            let dd = d_ref(&k, sigma, psi_n);
            let gj = 0.6;
            let c_max = w_update::c_max(&k, sigma, gj).unwrap();
            for f in FRACTIONS {
                let s = feasible(w_update::safe_step_along_j(&k, sigma, gj, f * c_max).unwrap());
                check_interval(&quad(gj * gj, dd * gj * gj), &s, f * c_max);
                for gl in [-4.0, 0.3] {
                    let o = w_update::safe_step_along_l(&k, sigma, gj, gl, f * c_max).unwrap();
                    let s = feasible(o);
                    check_interval(&quad(gl * gj, dd * gl * gl), &s, f * c_max);
                    let tilde = w_update::beta_tilde(&k, sigma, gj, gl).unwrap();
                    let lambda = s.lambda.unwrap();
                    let bar = tilde + lambda * tilde.abs();
                    assert_relative_eq!(
                        s.largest(),
                        bar,
                        epsilon = 1e-12 * tilde.abs(),
                        max_relative = 1e-12
                    );
                }
            }
        }
    }
}

/// ∇_w J = 0 but ∇_w L ≠ 0: C_max = 0, and a bounded worsening allows |β| ≤ √(−C/(d L²)).
#[test]
fn zero_j_gradient_with_budget() {
    let k = presets()[0];
    let dd = d_ref(&k, 1.0, psi_numeric());
    let s = feasible(w_update::safe_step_along_l(&k, 1.0, 0.0, 2.0, -0.5).unwrap());
    assert_eq!(s.lambda, None);
    let half = (0.5 / (dd * 4.0)).sqrt();
    assert_relative_eq!(s.hi, half, epsilon = 0.0, max_relative = 1e-14);
    assert_relative_eq!(s.lo, -half, epsilon = 0.0, max_relative = 1e-14);
    assert!(matches!(
        w_update::safe_step_along_l(&k, 1.0, 0.0, 2.0, 0.1).unwrap(),
        StepOutcome::Infeasible { c_max, vertex } if c_max == 0.0 && vertex == 0.0
    ));
    assert_eq!(
        w_update::safe_step_along_l(&k, 1.0, 0.3, 0.0, 0.1).unwrap(),
        StepOutcome::ZeroGradient {
            requirement_met: false
        }
    );
    assert_eq!(
        v_update::safe_step(&k, 1.0, &[0.0, 0.0], -1.0).unwrap(),
        StepOutcome::ZeroGradient {
            requirement_met: true
        }
    );
}

#[test]
fn theorem_4_3_and_4_5_vertices() {
    let psi_n = psi_numeric();
    for k in presets() {
        for sigma in SIGMAS {
            let dd = d_ref(&k, sigma, psi_n);
            // Theorem 4.3
            let gw = -0.7;
            let poly = |b: f64| b * gw * gw - b * b * dd * gw * gw;
            let best = numeric_vertex(poly, gw * gw, dd * gw * gw);
            assert!(close(
                w_update::beta_star(&k, sigma).unwrap(),
                best,
                1e-6,
                0.0
            ));
            assert!(close(
                w_update::c_max(&k, sigma, gw).unwrap(),
                poly(best),
                1e-11,
                0.0
            ));
            // Theorem 4.5, both sign combinations
            for gl in [2.5, -2.5] {
                let poly = |b: f64| b * gl * gw - b * b * dd * gl * gl;
                let best = numeric_vertex(poly, gl * gw, dd * gl * gl);
                let tilde = w_update::beta_tilde(&k, sigma, gw, gl).unwrap();
                assert!(close(tilde, best, 1e-6, 0.0));
                let StepOutcome::Infeasible { c_max, vertex } =
                    w_update::safe_step_along_l(&k, sigma, gw, gl, 1e9).unwrap()
                else {
                    panic!("C = 1e9 is infeasible")
                };
                assert!(close(vertex, tilde, 1e-14, 0.0));
                assert!(close(c_max, poly(best), 1e-11, 0.0));
                assert!(close(
                    c_max,
                    w_update::c_max(&k, sigma, gw).unwrap(),
                    1e-12,
                    0.0
                ));
            }
        }
    }
}
