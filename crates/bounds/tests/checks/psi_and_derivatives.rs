//! ψ against a numeric maximisation, c and d against the printed formulas, and every analytic
//! derivative against central finite differences.

use super::common::{c_ref, close, d_ref, golden_max, presets, psi_numeric};
use approx::assert_abs_diff_eq;
use sepg_bounds::constants::{c, d, dc_dsigma, psi};
use sepg_bounds::surrogate::{grad_sigma, grad_w, mixed_from_h, surrogate};

#[test]
fn psi_matches_numeric_maximisation() {
    let numeric = psi_numeric();
    assert!(close(psi(), numeric, 1e-12, 0.0), "{} vs {numeric}", psi());
}

/// Lemma A.1 lists two stationary values of f(χ) = (χ² − 4χ + 1)e^{−χ/2}; both printed
/// exponents are right: f(4 − √7) = −4(√7 − 2)e^{√7/2 − 2} is the global minimum and
/// f(4 + √7) = 4(√7 + 2)e^{−√7/2 − 2} the interior local maximum.
#[test]
fn lemma_a1_stationary_values_as_printed() {
    let f = |x: f64| (x * x - 4.0 * x + 1.0) * (-x / 2.0).exp();
    let s7 = 7.0_f64.sqrt();
    let x_min = golden_max(|x| -f(x), 0.0, 4.0);
    let x_max = golden_max(f, 4.0, 20.0);
    assert_abs_diff_eq!(x_min, 4.0 - s7, epsilon = 1e-7);
    assert_abs_diff_eq!(x_max, 4.0 + s7, epsilon = 1e-7);
    assert!(close(
        f(x_min),
        -4.0 * (s7 - 2.0) * (s7 / 2.0 - 2.0).exp(),
        1e-13,
        0.0
    ));
    assert!(close(
        f(x_max),
        4.0 * (s7 + 2.0) * (-s7 / 2.0 - 2.0).exp(),
        1e-13,
        0.0
    ));
    assert_abs_diff_eq!(f(x_min), -1.312_362_830_519_112_6, epsilon = 1e-14);
    assert_abs_diff_eq!(f(x_max), 0.669_899_090_567_421_5, epsilon = 1e-14);
}

#[test]
fn c_and_d_match_printed_formulas() {
    let psi_n = psi_numeric();
    for k in presets() {
        for sigma in [0.05, 0.1, 0.5, 1.0, 3.0] {
            assert!(close(c(&k, sigma).unwrap(), c_ref(&k, sigma), 1e-13, 0.0));
            assert!(close(
                d(&k, sigma).unwrap(),
                d_ref(&k, sigma, psi_n),
                1e-12,
                0.0
            ));
        }
    }
}

#[test]
fn dc_dsigma_matches_central_differences() {
    for k in presets() {
        for sigma in [0.05, 0.2, 1.0, 4.0] {
            let h = 1e-5 * sigma;
            let fd = (c_ref(&k, sigma + h) - c_ref(&k, sigma - h)) / (2.0 * h);
            let analytic = dc_dsigma(&k, sigma).unwrap();
            // central difference truncation error O(h²) ~ 1e-10 relative
            assert!(close(analytic, fd, 1e-7, 0.0), "{analytic} vs {fd}");
        }
    }
}

/// ∇_w L against finite differences of L(σ) = ‖∇_v J(σ)‖² / (4 m c(σ)) where ∇_v J(σ) is the
/// smooth test function (sin σ, σ², e^{−σ}) and ∂_σ∇_v J its exact derivative.
#[test]
fn surrogate_gradient_matches_finite_differences() {
    let grad_at = |s: f64| vec![s.sin(), s * s, (-s).exp()];
    let mixed_at = |s: f64| vec![s.cos(), 2.0 * s, -(-s).exp()];
    for k in presets() {
        for sigma in [0.1, 0.7, 2.0] {
            let l = |s: f64| surrogate(&k, s, &grad_at(s)).unwrap();
            let h = 1e-5 * sigma;
            let fd_sigma = (l(sigma + h) - l(sigma - h)) / (2.0 * h);
            let analytic = grad_sigma(&k, sigma, &grad_at(sigma), &mixed_at(sigma)).unwrap();
            assert!(
                close(analytic, fd_sigma, 1e-7, 0.0),
                "{analytic} vs {fd_sigma}"
            );
            // the same in w = ln σ
            let w = sigma.ln();
            let hw = 1e-5;
            let fd_w = (l((w + hw).exp()) - l((w - hw).exp())) / (2.0 * hw);
            let gw = grad_w(&k, sigma, &grad_at(sigma), &mixed_at(sigma)).unwrap();
            assert!(close(gw, fd_w, 1e-7, 0.0), "{gw} vs {fd_w}");
        }
    }
}

/// Surrogate value against Corollary 4.4 written out, and against the Appendix B form, which
/// carries an extra 1/m.
#[test]
fn surrogate_follows_corollary_4_4() {
    let k = presets()[0];
    let g = [0.3, -1.2, 0.5];
    let sigma = 0.4;
    let m = g.len() as f64;
    let sq: f64 = g.iter().map(|x| x * x).sum();
    let cor_4_4 = sq / (4.0 * m * c_ref(&k, sigma));
    assert!(close(
        surrogate(&k, sigma, &g).unwrap(),
        cor_4_4,
        1e-14,
        0.0
    ));
    // Appendix B: L = α*‖∇‖²/(2m) with α* = c₁σ³/(m(c₂σ + c₃))
    let (gm, r, mp, a) = (k.gamma(), k.r_max(), k.m_phi(), k.action_volume());
    let c1 = (1.0 - gm).powi(3) * (2.0 * std::f64::consts::PI).sqrt();
    let c2 = gm * (2.0 * std::f64::consts::PI).sqrt() * r * mp * mp;
    let c3 = 2.0 * (1.0 - gm) * a * r * mp * mp;
    let alpha_b = c1 * sigma.powi(3) / (m * (c2 * sigma + c3));
    let appendix_b = alpha_b * sq / (2.0 * m);
    assert!(close(appendix_b * m, cor_4_4, 1e-13, 0.0));
}

#[test]
fn mixed_from_h_is_h_minus_two_over_sigma_grad() {
    let out = mixed_from_h(&[1.0, -2.0], &[0.25, 0.5], 0.5).unwrap();
    assert_eq!(out, vec![0.0, -4.0]);
}
