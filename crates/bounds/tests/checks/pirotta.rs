//! The adaptive steps of Corollary 3.11 and Theorem 3.12 against a direct golden-section
//! maximisation of their bounds, evaluated from the printed definitions (reference c of `common`).

use super::common::{SIGMAS, c_ref, close, l1sq, l2sq, numeric_vertex, presets};
use sepg_bounds::pirotta::{AdaptiveStep, hp_optimal_step, optimal_step};

#[test]
fn corollary_3_11_step_maximises_theorem_3_10() {
    let grads: [&[f64]; 3] = [&[0.3, -0.1], &[1.0, 1.0, -1.0], &[5.0]];
    for k in presets() {
        for sigma in SIGMAS {
            for g in grads {
                let cc = c_ref(&k, sigma);
                let poly = |a: f64| a * l2sq(g) - a * a * cc * l1sq(g);
                let best = numeric_vertex(poly, l2sq(g), cc * l1sq(g));
                let AdaptiveStep::Step { alpha, guarantee } = optimal_step(&k, sigma, g).unwrap()
                else {
                    panic!("non-zero gradient")
                };
                assert!(close(alpha, best, 1e-6, 0.0), "{alpha} vs {best}");
                assert!(close(guarantee, poly(best), 1e-12, 0.0));
                // Cor 3.11's closed form written out
                let (gm, r, m, av) = (k.gamma(), k.r_max(), k.m_phi(), k.action_volume());
                let s2pi = (2.0 * std::f64::consts::PI).sqrt();
                let printed = (1.0 - gm).powi(3) * s2pi * sigma.powi(3) * l2sq(g)
                    / ((gm * s2pi * sigma + 2.0 * (1.0 - gm) * av) * r * m * m * l1sq(g));
                assert!(close(alpha, printed, 1e-13, 0.0));
            }
        }
    }
}

/// Theorem 3.12: the implemented step is the vertex of the printed polynomial; the printed α*
/// (‖∇⁻‖₁² in the denominator) is not, and guarantees less.
#[test]
fn theorem_3_12_step_is_vertex_and_printed_step_is_not() {
    let k = presets()[0];
    let g = [0.8_f64, -0.3, 0.05];
    let eps = [0.1_f64, 0.1, 0.1];
    let lower: Vec<f64> = g
        .iter()
        .zip(&eps)
        .map(|(g, e)| (g.abs() - e).max(0.0))
        .collect();
    let upper: Vec<f64> = g.iter().zip(&eps).map(|(g, e)| g.abs() + e).collect();
    for sigma in SIGMAS {
        let cc = c_ref(&k, sigma);
        let half: Vec<f64> = lower.iter().map(|x| x / 2.0).collect();
        let poly = |a: f64| a * l2sq(&half) - a * a * cc * l1sq(&upper);
        let best = numeric_vertex(poly, l2sq(&half), cc * l1sq(&upper));
        let AdaptiveStep::Step { alpha, guarantee } = hp_optimal_step(&k, sigma, &g, &eps).unwrap()
        else {
            panic!("above noise")
        };
        assert!(close(alpha, best, 1e-6, 0.0));
        assert!(close(guarantee, poly(best), 1e-12, 0.0));
        let printed = l2sq(&half) / (2.0 * cc * l1sq(&lower));
        assert!(printed > 1.5 * alpha, "printed α* is far from the vertex");
        assert!(poly(printed) < guarantee);
    }
}
