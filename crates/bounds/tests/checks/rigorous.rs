//! The rigorous w-bound against its definition, its root-finder against the definition, and
//! its relation to the thesis form.

use super::common::check_interval;
use super::common::{
    c_ref, close, d_ref, golden_max, k_mu_numeric, k_w_numeric, presets, psi_numeric,
};
use approx::{abs_diff_eq, assert_abs_diff_eq};
use sepg_bounds::constants::TaskConstants;
use sepg_bounds::outcome::StepOutcome;
use sepg_bounds::{rigorous, w_update};

/// (a, G): a = Rψ|A|/(2(1−γ)²σ), G = γR/(2(1−γ)³).
fn parts(k: &TaskConstants, sigma: f64, psi: f64) -> (f64, f64) {
    let (g, r) = (k.gamma(), k.r_max());
    (
        r * psi * k.action_volume() / (2.0 * (1.0 - g).powi(2) * sigma),
        g * r / (2.0 * (1.0 - g).powi(3)),
    )
}

/// The reference table written by `scripts/gen_gaussian_constants.py` (mpmath, 60 digits).
const GAUSSIAN_CONSTANTS: &str = include_str!("../data/gaussian_constants.csv");

fn table(name: &str) -> f64 {
    GAUSSIAN_CONSTANTS
        .lines()
        .skip(1)
        .find_map(|l| {
            let (n, v) = l.split_once(',')?;
            (n == name).then(|| v.parse().unwrap())
        })
        .unwrap_or_else(|| panic!("{name} missing from the table"))
}

/// e^y − 1 − y: Taylor series for small |y| (no cancellation), direct otherwise.
fn exp_minus_linear(y: f64) -> f64 {
    if y.abs() < 0.1 {
        let mut term = y;
        let mut sum = 0.0;
        for n in 2..20 {
            term *= y / f64::from(n);
            sum += term;
        }
        sum
    } else {
        y.exp() - 1.0 - y
    }
}

/// The rigorous bound written from its definition: remainder at min(σ, σe^{Δw}) with the larger
/// of the box term ψ|A|/σ_min and the real-line integral K_W, Pinsker with the smaller of the
/// two Gaussian KL divergences.
fn f_ref(k: &TaskConstants, sigma: f64, grad: f64, x: f64, psi: f64) -> (f64, f64) {
    let (g, r, av) = (k.gamma(), k.r_max(), k.action_volume());
    let sigma_min = sigma.min(sigma * x.exp());
    let curvature = (psi * av / sigma_min).max(k_w_numeric());
    let remainder = x * x * r / (1.0 - g).powi(2) * curvature / 2.0;
    let kl_forward = exp_minus_linear(2.0 * x);
    let kl_backward = exp_minus_linear(-2.0 * x);
    let pinsker = g * r / (1.0 - g).powi(3) * kl_forward.min(kl_backward) / 2.0;
    let value = x * grad - remainder - pinsker;
    (value, (x * grad).abs().max(remainder).max(pinsker))
}

#[test]
fn gaussian_constants_match_the_high_precision_table() {
    let cases = [
        ("k_w", rigorous::k_w(), k_w_numeric()),
        ("k_mu", rigorous::k_mu(), k_mu_numeric()),
    ];
    for (name, got, quadrature) in cases {
        let reference = table(name);
        assert!(
            close(got, reference, 1e-15, 0.0),
            "{name}: {got} vs {reference}"
        );
        assert!(
            close(quadrature, reference, 1e-9, 0.0),
            "{name}: quadrature {quadrature}"
        );
    }
    assert!(close(
        sepg_bounds::constants::psi(),
        table("psi"),
        1e-15,
        0.0
    ));
    // the σ above which each real-line term exceeds the thesis's box term
    for volume in [4.0, 8.0] {
        let k = TaskConstants::new(0.99, 4.0, 2.0, volume).unwrap();
        let sw = table(&format!("sigma_threshold_w_volume_{volume}"));
        let sc = table(&format!("sigma_threshold_c_volume_{volume}"));
        assert!(close(
            sw,
            sepg_bounds::constants::psi() * volume / rigorous::k_w(),
            1e-14,
            0.0
        ));
        // below the c threshold the sound c is the thesis's, above it strictly larger
        let below = rigorous::c(&k, 0.99 * sc).unwrap();
        assert_eq!(below, sepg_bounds::constants::c(&k, 0.99 * sc).unwrap());
        assert!(close(below, c_ref(&k, 0.99 * sc), 1e-13, 0.0));
        let above = rigorous::c(&k, 1.01 * sc).unwrap();
        assert!(above > 1.0001 * c_ref(&k, 1.01 * sc));
        let expected = c_real_line(&k, 1.01 * sc);
        assert!(close(above, expected, 1e-13, 0.0), "{above} vs {expected}");
        // below the w threshold the rigorous curvature is the box term, above it K_W (γ = 0
        // removes the Pinsker slack, so the sign of the gap shows which term is active)
        let psi = psi_numeric();
        let k0 = TaskConstants::new(0.0, 4.0, 2.0, volume).unwrap();
        for (s, active_box) in [(0.99 * sw, true), (1.01 * sw, false)] {
            let (v, scale) = f_ref(&k0, s, 0.3, 1e-3, psi);
            let got = rigorous::bound(&k0, s, 0.3, 1e-3).unwrap();
            assert_abs_diff_eq!(got, v, epsilon = 1e-12 * scale);
            let gap = rigorous::gap(&k0, s, 1e-3).unwrap();
            assert_eq!(gap > 0.0, !active_box, "σ = {s}: gap {gap}");
        }
    }
}

/// c with the box term |A|/(√(2π)σ) replaced by the real-line K_MU (numeric).
fn c_real_line(k: &TaskConstants, sigma: f64) -> f64 {
    let (g, r, m) = (k.gamma(), k.r_max(), k.m_phi());
    r * m * m / ((1.0 - g).powi(2) * sigma.powi(2)) * (k_mu_numeric() + g / (2.0 * (1.0 - g)))
}

#[test]
fn bound_matches_definition() {
    let psi = psi_numeric();
    for k in presets() {
        for sigma in [0.1, 1.0, 3.0] {
            for x in [-0.5, -0.05, -1e-3, 1e-3, 0.05, 0.5] {
                let (v, scale) = f_ref(&k, sigma, 0.7, x, psi);
                let got = rigorous::bound(&k, sigma, 0.7, x).unwrap();
                assert!(
                    abs_diff_eq!(got, v, epsilon = 1e-12 * scale),
                    "{got} vs {v} at {x}"
                );
                let thesis = rigorous::thesis_bound(&k, sigma, 0.7, x).unwrap();
                let gap = rigorous::gap(&k, sigma, x).unwrap();
                assert_abs_diff_eq!(thesis - got, gap, epsilon = 1e-12 * scale);
            }
        }
    }
}

#[test]
fn kl2_is_at_most_two_dw_squared() {
    for x in [-3.0, -0.5, -1e-4, 0.0, 1e-8, 1e-4, 0.5, 3.0] {
        let v = rigorous::kl2(x).unwrap();
        assert!(v <= 2.0 * x * x);
        assert!(v >= 2.0 * x * x - 4.0 / 3.0 * x.abs().powi(3));
    }
}

#[test]
fn rigorous_vertex_and_intervals() {
    let psi = psi_numeric();
    for k in presets() {
        for sigma in [0.1, 1.0, 3.0] {
            for grad in [0.8, -0.8] {
                let f = |x: f64| f_ref(&k, sigma, grad, x, psi).0;
                let (box_a, _) = parts(&k, sigma, psi);
                let line_a = k.r_max() * k_w_numeric() / (2.0 * (1.0 - k.gamma()).powi(2));
                let a = box_a.max(line_a);
                let far = grad / a;
                let best = golden_max(f, far.min(0.0), far.max(0.0));
                let StepOutcome::Infeasible { c_max, vertex } =
                    rigorous::safe_delta_w(&k, sigma, grad, 1e12).unwrap()
                else {
                    panic!("1e12 is infeasible")
                };
                assert!(close(vertex, best, 1e-6, 0.0), "{vertex} vs {best}");
                assert!(close(c_max, f(best), 1e-9, 0.0));
                for frac in [1.0, 0.5, 0.0, -0.5, -5.0] {
                    let required = frac * c_max;
                    let StepOutcome::Feasible(s) =
                        rigorous::safe_delta_w(&k, sigma, grad, required).unwrap()
                    else {
                        panic!("C ≤ C_max is feasible")
                    };
                    let bound = |x: f64| f_ref(&k, sigma, grad, x, psi);
                    check_interval(&bound, &s, required);
                    // in β along ∇_w J and along an arbitrary ∇_w L
                    let StepOutcome::Feasible(b) =
                        rigorous::safe_step_along_j(&k, sigma, grad, required).unwrap()
                    else {
                        panic!()
                    };
                    assert!(close(
                        b.hi * grad,
                        if grad > 0.0 { s.hi } else { s.lo },
                        1e-15,
                        0.0
                    ));
                    let StepOutcome::Feasible(l) =
                        rigorous::safe_step_along_l(&k, sigma, grad, -2.0, required).unwrap()
                    else {
                        panic!()
                    };
                    assert!(close(l.lo * -2.0, s.hi, 1e-15, 0.0));
                    assert!(close(l.hi * -2.0, s.lo, 1e-15, 0.0));
                }
            }
        }
    }
}

/// With ψ|A|/σ > (4/3)γ/(1 − γ) the thesis form over-promises for decreases of σ: its largest
/// safe step for C = 0 has a negative rigorous bound.
#[test]
fn thesis_form_can_be_violated_when_sigma_shrinks() {
    let k = TaskConstants::new(0.5, 1.0, 1.0, 4.0).unwrap();
    let (sigma, grad) = (0.1, -0.5);
    let psi = psi_numeric();
    let (a, g) = parts(&k, sigma, psi);
    assert!(a > 4.0 / 3.0 * g);
    let beta = w_update::safe_step_along_j(&k, sigma, grad, 0.0)
        .unwrap()
        .chosen_step()
        .unwrap();
    let dw = beta * grad;
    assert!(dw < 0.0);
    assert!(close(dw, grad / d_ref(&k, sigma, psi), 1e-12, 0.0));
    assert!(rigorous::thesis_bound(&k, sigma, grad, dw).unwrap().abs() < 1e-15);
    assert!(
        f_ref(&k, sigma, grad, dw, psi).0 < 0.0,
        "the thesis step loses performance"
    );
    assert!(rigorous::gap(&k, sigma, dw).unwrap() > 0.0);
    // and the rigorous step is smaller
    let r = rigorous::safe_step_along_j(&k, sigma, grad, 0.0)
        .unwrap()
        .chosen_step()
        .unwrap();
    assert!(r < beta);
}

/// For the `lqg` preset (γ = 0.99) the Pinsker slack dominates: the thesis form is
/// conservative for small decreases of σ too.
#[test]
fn thesis_form_is_conservative_for_lqg_small_steps() {
    let k = presets()[0];
    for sigma in [0.1, 0.5, 1.0] {
        for dw in [-1e-2, -1e-3, 1e-3, 1e-2] {
            assert!(rigorous::gap(&k, sigma, dw).unwrap() < 0.0);
        }
    }
}
