//! Every optimal step against a direct golden-section maximisation of its lower-bound
//! polynomial, evaluated from the printed definition (reference c and d of `common`).
//!
//! Golden-section search locates a maximiser to ~√ε relative precision (the function is flat
//! there), so steps are compared at 1e-6 relative and maximal values at 1e-12.

use super::common::{c_ref, close, d_ref, golden_max, presets, psi_numeric};
use sepg_bounds::high_probability::HighProbabilityBound;
use sepg_bounds::outcome::StepOutcome;
use sepg_bounds::pirotta::{AdaptiveStep, hp_optimal_step, optimal_step};
use sepg_bounds::{papini, v_update, w_update};

const SIGMAS: [f64; 3] = [0.1, 0.5, 2.0];

fn l1sq(x: &[f64]) -> f64 {
    x.iter().map(|v| v.abs()).sum::<f64>().powi(2)
}
fn l2sq(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum()
}

/// Maximises a·x − b·x² (b > 0) numerically over the bracket between its roots.
fn numeric_vertex(poly: impl Fn(f64) -> f64, a: f64, b: f64) -> f64 {
    let root = a / b;
    golden_max(poly, root.min(0.0) - 1e-300, root.max(0.0) + 1e-300)
}

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

#[test]
fn theorem_4_2_and_4_3_and_4_5_vertices() {
    let psi_n = psi_numeric();
    for k in presets() {
        for sigma in SIGMAS {
            let cc = c_ref(&k, sigma);
            let dd = d_ref(&k, sigma, psi_n);
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
