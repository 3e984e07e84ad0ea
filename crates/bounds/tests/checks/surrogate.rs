//! The surrogate L of Corollary 4.4 and its gradient (Appendix B) against the printed formulas
//! and central finite differences.

use super::common::{c_ref, close, presets};
use sepg_bounds::surrogate::{grad_sigma, grad_w, mixed_from_h, surrogate};

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
