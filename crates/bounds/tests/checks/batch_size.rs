//! Chebyshev batch sizes (Corollary 3.13): the counts against the source and printed formulas,
//! and their errors.

use super::common::presets;
use approx::{abs_diff_eq, assert_abs_diff_eq};
use sepg_bounds::BoundsError;
use sepg_bounds::batch_size::{gpomdp, reinforce};
use sepg_bounds::constants::TaskConstants;

/// The integer count is the ceiling of the real bound: n − 1 < N_real ≤ n (up to rounding).
fn is_ceiling(n: u64, real: f64) -> bool {
    let n = n as f64;
    n >= real * (1.0 - 1e-12) && n - 1.0 < real * (1.0 + 1e-12)
}

#[test]
fn reinforce_matches_source_formula() {
    for k in presets() {
        for (sigma, delta, eps, h) in [
            (0.5, 0.05, 0.1, 20_u32),
            (1.0, 0.2, 1.0, 1),
            (0.1, 0.5, 2.0, 300),
        ] {
            let (g, r, m) = (k.gamma(), k.r_max(), k.m_phi());
            let real = r * r * m * m * f64::from(h) * (1.0 - g.powi(h as i32)).powi(2)
                / (delta * eps * eps * sigma * sigma * (1.0 - g).powi(2));
            let n = reinforce(&k, sigma, delta, eps, h).unwrap();
            assert!(is_ceiling(n, real), "{n} vs {real}");
        }
    }
}

#[test]
fn gpomdp_matches_printed_formula() {
    for k in presets() {
        for (sigma, delta, eps, h) in [
            (0.5, 0.05, 0.1, 20_u32),
            (1.0, 0.2, 1.0, 1),
            (0.1, 0.5, 2.0, 300),
        ] {
            let (g, r, m) = (k.gamma(), k.r_max(), k.m_phi());
            let gh = g.powi(h as i32);
            let hf = f64::from(h);
            let bracket =
                (1.0 - gh * gh) / (1.0 - g * g) + hf * gh * gh - 2.0 * gh * (1.0 - gh) / (1.0 - g);
            let real =
                r * r * m * m / (delta * eps * eps * sigma * sigma * (1.0 - g).powi(2)) * bracket;
            let n = gpomdp(&k, sigma, delta, eps, h).unwrap();
            // the printed bracket cancels for γ → 1: compare at 1e-9
            assert!(
                abs_diff_eq!(n as f64, real, epsilon = 1.0 + 1e-9 * real),
                "{n} vs {real}"
            );
        }
    }
}

/// As γ → 1 the G(PO)MDP bracket / (1 − γ)² tends to Σ_{k=1}^{H} k² = H(H+1)(2H+1)/6; the
/// printed form loses all digits there, the implemented one does not.
#[test]
fn gpomdp_is_stable_near_gamma_one() {
    let k = TaskConstants::new(1.0 - 1e-12, 1.0, 1.0, 1.0).unwrap();
    let h = 50_u32;
    let limit = f64::from(h * (h + 1) * (2 * h + 1)) / 6.0;
    let n = gpomdp(&k, 1.0, 0.5, 1.0, h).unwrap();
    assert_abs_diff_eq!(n as f64, 2.0 * limit, epsilon = 1.0 + 1e-6 * limit);
}

/// The printed REINFORCE count R²M²H(γ^H)²/(δε²σ²(1−δ)²) vanishes as H grows; the source's
/// R²M²H(1−γ^H)²/(δε²σ²(1−γ)²) grows linearly.
#[test]
fn printed_reinforce_count_vanishes_with_horizon() {
    let k = presets()[0];
    let printed = |h: i32| {
        let (g, r, m, d, e, s) = (k.gamma(), k.r_max(), k.m_phi(), 0.05_f64, 0.1, 0.5);
        r * r * m * m * f64::from(h) * g.powi(h).powi(2) / (d * e * e * s * s * (1.0 - d).powi(2))
    };
    assert!(printed(10_000) < 1e-80 * printed(10));
    let n10 = reinforce(&k, 0.5, 0.05, 0.1, 10).unwrap();
    let n10k = reinforce(&k, 0.5, 0.05, 0.1, 10_000).unwrap();
    assert!(n10k > 100 * n10);
}

#[test]
fn batch_size_overflow_and_domain_errors() {
    let k = presets()[1];
    assert!(matches!(
        reinforce(&k, 1e-3, 1e-3, 1e-9, 1000),
        Err(BoundsError::Overflow { .. })
    ));
    assert!(matches!(
        gpomdp(&k, 1.0, 0.1, 0.1, 0),
        Err(BoundsError::ZeroHorizon)
    ));
    assert!(matches!(
        gpomdp(&k, 1.0, 1.0, 0.1, 5),
        Err(BoundsError::OutOfDomain { .. })
    ));
    assert!(matches!(
        reinforce(&k, 1.0, 0.1, 0.0, 5),
        Err(BoundsError::OutOfDomain { .. })
    ));
}
