//! ψ against a numeric maximisation, c and d against the printed formulas, and ∂c/∂σ against
//! central finite differences.

use super::common::{c_ref, close, d_ref, golden_max, presets, psi_numeric};
use approx::assert_abs_diff_eq;
use sepg_bounds::constants::{c, d, dc_dsigma, psi};

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
