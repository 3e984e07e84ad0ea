//! Interval end points make the bound exactly C, steps inside guarantee C, steps just outside
//! do not — for every interval (4.10), (4.17), (4.19), (4.26), (4.29), (4.30) and the
//! sign-aware variants. Bounds are evaluated from the printed definitions.
//!
//! "Exactly" means |B(x) − C| ≤ 1e-10 · max(|C|, |a·x|, |b·x²|): the bound is a difference of
//! its two terms, so no evaluation can be more accurate than the size of those terms.

use super::common::{c_ref, d_ref, presets, psi_numeric};
use approx::{assert_abs_diff_eq, assert_relative_eq, relative_eq};
use sepg_bounds::high_probability::{HighProbabilityBound, HpForm};
use sepg_bounds::outcome::{SafeInterval, StepOutcome};
use sepg_bounds::{v_update, w_update};

/// A bound given as a function returning (value, scale of its terms).
pub fn check_interval(bound: &dyn Fn(f64) -> (f64, f64), s: &SafeInterval, required: f64) {
    for x in [s.lo, s.hi] {
        let (v, scale) = bound(x);
        assert!(
            relative_eq!(v, required, epsilon = 1e-10 * scale, max_relative = 1e-10),
            "B({x}) = {v}, C = {required}"
        );
    }
    let span = s.hi.abs().max(s.lo.abs());
    for i in 1..20 {
        let x = s.lo + (s.hi - s.lo) * f64::from(i) / 20.0;
        let (v, scale) = bound(x);
        assert!(
            v >= required - 1e-12 * scale,
            "inside: B({x}) = {v} < C = {required}"
        );
    }
    let offset = 1e-4 * (s.hi - s.lo) + 1e-6 * span;
    for x in [s.lo - offset, s.hi + offset] {
        assert!(bound(x).0 < required, "outside: B({x}) ≥ C = {required}");
    }
    let slack = 1e-12 * span;
    assert!(s.lo - slack <= s.vertex && s.vertex <= s.hi + slack);
}

fn feasible(o: StepOutcome) -> SafeInterval {
    match o {
        StepOutcome::Feasible(s) => s,
        other => panic!("expected a feasible outcome, got {other:?}"),
    }
}

/// Quadratic a x − b x² with its term scale.
fn quad(a: f64, b: f64) -> impl Fn(f64) -> (f64, f64) {
    move |x| (a * x - b * x * x, (a * x).abs().max(b * x * x))
}

/// Required improvements as fractions of C_max: required improvements, C = 0 and bounded
/// worsenings down to −10 C_max, plus tiny fractions where naive formulas cancel.
const FRACTIONS: [f64; 9] = [1.0, 0.999_999, 0.75, 1e-6, 0.0, -1e-6, -0.3, -2.0, -10.0];

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
