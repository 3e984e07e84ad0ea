//! The greedy-coordinate step of Theorem 3.14 against every other diagonal step.

use super::common::{c_ref, close, presets};
use sepg_bounds::papini;

/// Theorem 3.14: the greedy step attains ‖∇‖∞²/(4c) and no diagonal step on a grid does better.
#[test]
fn theorem_3_14_greedy_step_is_best_diagonal_step() {
    let k = presets()[2];
    let g = [0.4, -0.9, 0.9, 0.1];
    let sigma = 0.5;
    let cc = c_ref(&k, sigma);
    let s = papini::greedy_step(&k, sigma, &g).unwrap();
    assert_eq!(s.index, 1);
    let value = papini::bound(&k, sigma, &g, &s.steps).unwrap();
    assert!(close(value, 0.81 / (4.0 * cc), 1e-12, 0.0));
    assert!(close(s.guarantee, value, 1e-12, 0.0));
    let scale = 1.0 / (2.0 * cc);
    let grid = [-0.5, 0.0, 0.25, 0.5, 0.75, 1.0, 1.5];
    for a in grid {
        for b in grid {
            for c3 in grid {
                let steps = [a * scale, b * scale, c3 * scale, 0.3 * scale];
                let lin: f64 = g.iter().zip(&steps).map(|(g, a)| a * g * g).sum();
                let pen: f64 = g
                    .iter()
                    .zip(&steps)
                    .map(|(g, a)| (a * g).abs())
                    .sum::<f64>();
                assert!(lin - cc * pen * pen <= value * (1.0 + 1e-12));
            }
        }
    }
}
