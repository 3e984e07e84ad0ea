//! The rigorous w-bound against its definition, its root-finder against the definition, and
//! its relation to the thesis form.

use super::common::{close, d_ref, golden_max, presets, psi_numeric};
use super::intervals::check_interval;
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

/// The rigorous bound written from its definition: remainder at min(σ, σe^{Δw}), Pinsker with
/// the smaller of the two Gaussian KL divergences.
fn f_ref(k: &TaskConstants, sigma: f64, grad: f64, x: f64, psi: f64) -> (f64, f64) {
    let (g, r, av) = (k.gamma(), k.r_max(), k.action_volume());
    let sigma_min = sigma.min(sigma * x.exp());
    let remainder = x * x * r / (1.0 - g).powi(2) * psi * av / (2.0 * sigma_min);
    let kl_forward = exp_minus_linear(2.0 * x);
    let kl_backward = exp_minus_linear(-2.0 * x);
    let pinsker = g * r / (1.0 - g).powi(3) * kl_forward.min(kl_backward) / 2.0;
    let value = x * grad - remainder - pinsker;
    (value, (x * grad).abs().max(remainder).max(pinsker))
}

#[test]
fn bound_matches_definition() {
    let psi = psi_numeric();
    for k in presets() {
        for sigma in [0.1, 1.0] {
            for x in [-0.5, -0.05, -1e-3, 1e-3, 0.05, 0.5] {
                let (v, scale) = f_ref(&k, sigma, 0.7, x, psi);
                let got = rigorous::bound(&k, sigma, 0.7, x).unwrap();
                assert!((got - v).abs() <= 1e-12 * scale, "{got} vs {v} at {x}");
                let thesis = rigorous::thesis_bound(&k, sigma, 0.7, x).unwrap();
                let gap = rigorous::gap(&k, sigma, x).unwrap();
                assert!((thesis - got - gap).abs() <= 1e-12 * scale);
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
        for sigma in [0.1, 1.0] {
            for grad in [0.8, -0.8] {
                let f = |x: f64| f_ref(&k, sigma, grad, x, psi).0;
                let (a, _) = parts(&k, sigma, psi);
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
