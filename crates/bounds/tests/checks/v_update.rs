//! Theorem 4.2: the interval (4.10) against the bound evaluated from its printed definition
//! (end points exactly C, steps inside guarantee C, steps just outside do not), and α*, C_max
//! against a golden-section maximisation.

use super::common::{
    FRACTIONS, SIGMAS, c_ref, check_interval, close, feasible, numeric_vertex, presets, quad,
};
use approx::{assert_abs_diff_eq, assert_relative_eq};
use sepg_bounds::v_update;

#[test]
fn v_update_interval_4_10() {
    for k in presets() {
        for sigma in [0.1, 1.0] {
            let g = [0.25, -0.8, 0.1];
            let cc = c_ref(&k, sigma);
            let bound = quad(0.64, cc * 0.64);
            let c_max = v_update::c_max(&k, sigma, &g).unwrap();
            for f in FRACTIONS {
                let s = feasible(v_update::safe_step(&k, sigma, &g, f * c_max).unwrap());
                check_interval(&bound, &s, f * c_max);
                let lambda = s.lambda.unwrap();
                assert_abs_diff_eq!(lambda, (1.0 - f).sqrt(), epsilon = 1e-12);
                let a = v_update::alpha_star(&k, sigma).unwrap();
                assert_relative_eq!(
                    s.largest(),
                    (1.0 + lambda) * a,
                    epsilon = 0.0,
                    max_relative = 1e-12
                );
            }
        }
    }
}

#[test]
fn theorem_4_2_vertex() {
    for k in presets() {
        for sigma in SIGMAS {
            let cc = c_ref(&k, sigma);
            // Theorem 4.2
            let g = [0.2, -0.6];
            let n2 = 0.36;
            let poly = |a: f64| a * n2 - a * a * cc * n2;
            let best = numeric_vertex(poly, n2, cc * n2);
            assert!(close(
                v_update::alpha_star(&k, sigma).unwrap(),
                best,
                1e-6,
                0.0
            ));
            assert!(close(
                v_update::c_max(&k, sigma, &g).unwrap(),
                poly(best),
                1e-12,
                0.0
            ));
        }
    }
}
