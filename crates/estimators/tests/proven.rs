//! The constants of the proven widths (`sepg_estimators::proven`, docs/THEOREMS.md "Proven
//! confidence widths") against independent quadratures, the Chernoff inversions against a
//! numerical minimisation over λ, and the input validation.
//!
//! Every reference value here is computed by Simpson's rule on the density (Gaussian or χ²)
//! or by a direct minimisation, never by the closed forms of the module.

use sepg_estimators::EstimatorError;
use sepg_estimators::proven::{ProvenWidths, chi2_psi1_norm, psi1_width, psi2_width};
use sepg_testkit::simpson;
use statrs::function::gamma::ln_gamma;

/// `E exp(X²/K²)` for `X ~ N(0, s²)` by quadrature (`+∞` when the integral diverges).
fn gaussian_psi2_moment(s: f64, k: f64) -> f64 {
    let rate = 0.5 / (s * s) - 1.0 / (k * k);
    if rate <= 0.0 {
        return f64::INFINITY;
    }
    // The integrand is below e^{-60} beyond |x| = √(60/rate).
    let l = (60.0 / rate).sqrt();
    let norm = 1.0 / (s * (2.0 * std::f64::consts::PI).sqrt());
    simpson(|x| norm * (-rate * x * x).exp(), -l, l, 40_000)
}

/// `E exp(|Q − n|/K)` for `Q ~ χ²_n` by quadrature in `u = √Q` (density `2u f(u²)`, smooth
/// at 0), split at the kink `u = √n`.
fn chi2_abs_moment(n: usize, k: f64) -> f64 {
    if k <= 2.0 {
        return f64::INFINITY;
    }
    let nf = n as f64;
    let log_norm = std::f64::consts::LN_2 - 0.5 * nf * std::f64::consts::LN_2 - ln_gamma(0.5 * nf);
    let f = |u: f64| {
        if u == 0.0 {
            return if n == 1 {
                (log_norm + nf / k).exp()
            } else {
                0.0
            };
        }
        let q = u * u;
        (log_norm + (nf - 1.0) * u.ln() - 0.5 * q + (q - nf).abs() / k).exp()
    };
    // Past the peak; beyond u_max the (decreasing) integrand is below e^{-60}.
    let root = nf.sqrt();
    let mut u_max = root + 10.0;
    while f(u_max) > (-60.0f64).exp() {
        u_max *= 1.1;
    }
    simpson(f, 0.0, root, 40_000) + simpson(f, root, u_max, 80_000)
}

/// The smallest `K` with `moment(K) ≤ 2`, by bisection (`moment` decreasing in `K`).
fn solve_norm(moment: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> f64 {
    assert!(moment(hi) <= 2.0 && moment(lo) > 2.0, "bracket");
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if moment(mid) > 2.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

/// The discounts and reward deviations of a test task: `a_t = γ^t R'`.
fn weights(r_dev: f64, gamma: f64, horizon: usize) -> Vec<f64> {
    (0..horizon).map(|t| r_dev * gamma.powi(t as i32)).collect()
}

#[test]
fn psi2_constant_is_exact_for_the_gaussian() {
    // H = 1, R = M_φ = σ = 1: K_v is the ψ2 constant of one step, X = ξ φ/σ ~ N(0, 1) when
    // φ = M_φ (the worst case of the martingale), and E exp(X²/K²) = 2 exactly there.
    let p = ProvenWidths::new(1.0, false, 1.0, 0.5, 1).unwrap();
    let k = p.v_psi2_norm(1.0).unwrap();
    let moment = gaussian_psi2_moment(1.0, k);
    eprintln!("K = {k}, E exp(X²/K²) = {moment}");
    assert!((moment - 2.0).abs() < 1e-9, "E exp(X²/K²) = {moment}");

    // Several steps: K_v = Σ_t a_t K_t with K_t the ψ2 norm of N(0, (t+1) M²/σ²), each
    // found by bisection on the quadrature.
    let (r, m, sigma, gamma, h) = (3.0, 2.0, 0.5, 0.7, 6);
    let p = ProvenWidths::new(r, false, m, gamma, h).unwrap();
    let expected: f64 = weights(r, gamma, h)
        .iter()
        .enumerate()
        .map(|(t, a)| {
            let s = ((t + 1) as f64).sqrt() * m / sigma;
            a * solve_norm(|k| gaussian_psi2_moment(s, k), s, 10.0 * s)
        })
        .sum();
    let got = p.v_psi2_norm(sigma).unwrap();
    eprintln!("K_v = {got}, by quadrature {expected}");
    assert!((got / expected - 1.0).abs() < 1e-8);
    // Non-positive rewards: R' = R/2.
    let half = ProvenWidths::new(r, true, m, gamma, h).unwrap();
    assert!((half.v_psi2_norm(sigma).unwrap() / expected - 0.5).abs() < 1e-8);
}

#[test]
fn psi1_constant_is_valid_and_tight() {
    for n in [1usize, 2, 3, 5, 10, 20, 60, 300] {
        let k = chi2_psi1_norm(n).unwrap();
        let moment = chi2_abs_moment(n, k);
        let exact = solve_norm(|k| chi2_abs_moment(n, k), 2.0 + 1e-9, 3.0 * k);
        eprintln!(
            "n = {n}: K = {k:.10}, E e^(|Z|/K) = {moment:.12}, exact K = {exact:.10}, ratio {:.3e}",
            k / exact - 1.0
        );
        // Valid: the moment at K is at most 2 (the module keeps a margin of 1e-9).
        assert!(moment <= 2.0, "n = {n}: E e^(|Z|/K) = {moment}");
        // Tight: within 1e-6 of the exact norm (far inside the 1% asked of it).
        assert!(
            k >= exact * (1.0 - 1e-9) && k <= exact * (1.0 + 1e-6),
            "n = {n}"
        );
    }
    // Beyond the directly computed range the triangle inequality over blocks is valid.
    let n = 5000;
    let k = chi2_psi1_norm(n).unwrap();
    let moment = chi2_abs_moment(n, k);
    eprintln!("n = {n}: K = {k}, E e^(|Z|/K) = {moment}");
    assert!(moment <= 2.0);

    // K_w = Σ_t a_t k_{t+1}, with each k from the quadrature.
    let (r, gamma, h) = (2.0, 0.8, 5);
    let p = ProvenWidths::new(r, false, 1.0, gamma, h).unwrap();
    let expected: f64 = weights(r, gamma, h)
        .iter()
        .enumerate()
        .map(|(t, a)| a * solve_norm(|k| chi2_abs_moment(t + 1, k), 2.0 + 1e-9, 20.0))
        .sum();
    let got = p.w_psi1_norm();
    eprintln!("K_w = {got}, by quadrature {expected}");
    assert!((got / expected - 1.0).abs() < 1e-6);
}

/// `min_{0 < λ ≤ λ_max} exp(n(κ λ² K² − λ ε))` by a grid and golden-section search on the
/// exponent (convex in λ).
fn chernoff_bound(kappa: f64, norm: f64, n: usize, eps: f64, lambda_max: f64) -> f64 {
    let exponent = |l: f64| n as f64 * (kappa * l * l * norm * norm - l * eps);
    let grid = 10_000;
    let best = (1..=grid)
        .map(|i| lambda_max * i as f64 / grid as f64)
        .min_by(|a, b| exponent(*a).total_cmp(&exponent(*b)))
        .unwrap();
    let step = lambda_max / grid as f64;
    let (mut lo, mut hi) = ((best - step).max(0.0), (best + step).min(lambda_max));
    let phi = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..200 {
        let (a, b) = (hi - phi * (hi - lo), lo + phi * (hi - lo));
        if exponent(a) < exponent(b) {
            hi = b;
        } else {
            lo = a;
        }
    }
    exponent(0.5 * (lo + hi)).exp()
}

#[test]
fn widths_invert_the_chernoff_bound() {
    // Sub-Gaussian lemma: E e^{λ(g−Eg)} ≤ e^{2 ln 2 λ²K²} for |λ| ≤ 1/K; sub-exponential
    // lemma: E e^{λ(g−Eg)} ≤ e^{2λ²K²} for |λ| ≤ 1/(2K). The width is the ε at which the
    // one-sided Chernoff bound of the mean of n samples, minimised over the allowed λ,
    // equals δ/2. The cases cover both regimes of each width.
    for (norm, n, delta) in [
        (1.0, 50, 1e-5),
        (3.5, 10, 0.05),
        (0.2, 1000, 0.2),
        (2.0, 1, 0.3),
        (1.0, 3, 1e-5),
        (1.0, 1, 1e-9),
    ] {
        let e2 = psi2_width(norm, n, delta).unwrap();
        let b2 = chernoff_bound(2.0 * std::f64::consts::LN_2, norm, n, e2, 1.0 / norm);
        let e1 = psi1_width(norm, n, delta).unwrap();
        let b1 = chernoff_bound(2.0, norm, n, e1, 0.5 / norm);
        eprintln!(
            "K {norm} n {n} δ {delta}: ψ2 ε {e2:.6} bound {b2:.6e}; ψ1 ε {e1:.6} bound {b1:.6e}"
        );
        for b in [b2, b1] {
            assert!(b <= 0.5 * delta * (1.0 + 1e-9), "bound {b} above δ/2");
            assert!(
                b >= 0.5 * delta * (1.0 - 1e-6),
                "bound {b} far below δ/2 (not tight)"
            );
        }
    }
}

/// `max over the grid of ln E e^{λ(g − Eg)} / (κ λ² K²)` for `0 < |λ| ≤ λ_max`.
fn worst_ratio(log_mgf: impl Fn(f64) -> f64, kappa: f64, norm: f64, lambda_max: f64) -> f64 {
    (-2000..=2000)
        .filter(|i| *i != 0)
        .map(|i| {
            let l = lambda_max * i as f64 / 2000.0;
            log_mgf(l) / (kappa * l * l * norm * norm)
        })
        .fold(f64::NEG_INFINITY, f64::max)
}

#[test]
fn sub_exponential_lemma_holds_on_examples() {
    // E e^{λ(g − Eg)} ≤ e^{2λ²K²} for |λ| ≤ 1/(2K), K = ‖g‖_ψ1, on laws with exact moment
    // generating functions: Z = χ²_n − n (centred, K = k_n), Q = χ²_n (not centred,
    // E e^{Q/K} = (1 − 2/K)^{−n/2} = 2 gives K = 2/(1 − 2^{−2/n})), and Bernoulli(p)
    // (K = 1/ln(1 + 1/p)).
    let chi2 = |n: f64| move |l: f64| -l * n - 0.5 * n * (-2.0 * l).ln_1p();
    for n in [1usize, 2, 5, 20, 100] {
        let nf = n as f64;
        let k = chi2_psi1_norm(n).unwrap();
        let centred = worst_ratio(chi2(nf), 2.0, k, 0.5 / k);
        let kq = 2.0 / (1.0 - 2f64.powf(-2.0 / nf));
        let raw = worst_ratio(chi2(nf), 2.0, kq, 0.5 / kq);
        eprintln!("χ²_{n}: worst ratio {centred:.4} (centred), {raw:.4} (not centred)");
        assert!(centred <= 1.0 && raw <= 1.0, "n = {n}");
    }
    for p in [0.5f64, 0.1, 0.01, 1e-3, 1e-5] {
        let k = 1.0 / (1.0 / p).ln_1p();
        let bern = |l: f64| (p * (l * (1.0 - p)).exp() + (1.0 - p) * (-l * p).exp()).ln();
        let r = worst_ratio(bern, 2.0, k, 0.5 / k);
        eprintln!("Bernoulli({p}): K = {k:.5}, worst ratio {r:.4}");
        assert!(r <= 1.0, "p = {p}");
    }
}

#[test]
fn sub_gaussian_lemma_holds_on_examples() {
    // E e^{λ(g − Eg)} ≤ e^{2 ln 2 λ²K²} for |λ| ≤ 1/K, K = ‖g‖_ψ2, on Bernoulli(p)
    // (K = 1/√ln(1 + 1/p), mean p: skewed and not centred) and on two-point laws ±1 with
    // P(+1) = p (K = 1/√ln 2 whatever p, mean 2p − 1).
    let kappa = 2.0 * std::f64::consts::LN_2;
    for p in [0.5f64, 0.1, 0.01, 1e-3, 1e-5] {
        let k = 1.0 / (1.0 / p).ln_1p().sqrt();
        let bern = |l: f64| (p * (l * (1.0 - p)).exp() + (1.0 - p) * (-l * p).exp()).ln();
        let r = worst_ratio(bern, kappa, k, 1.0 / k);
        let ks = 1.0 / std::f64::consts::LN_2.sqrt();
        let m = 2.0 * p - 1.0;
        let sign = |l: f64| (p * (l * (1.0 - m)).exp() + (1.0 - p) * (-l * (1.0 + m)).exp()).ln();
        let rs = worst_ratio(sign, kappa, ks, 1.0 / ks);
        eprintln!("p = {p}: Bernoulli K = {k:.5} worst ratio {r:.4}; ±1 worst ratio {rs:.4}");
        assert!(r <= 1.0 && rs <= 1.0, "p = {p}");
    }
}

#[test]
fn widths_scale_as_stated() {
    // lqg1d constants. The v-width is proportional to 1/σ and to R' (so halved by declaring
    // the rewards non-positive); all widths shrink as 1/√N in the sub-Gaussian regime.
    let p = ProvenWidths::new(28.8, true, 4.0, 0.99, 20).unwrap();
    let two = ProvenWidths::new(28.8, false, 4.0, 0.99, 20).unwrap();
    let (n, d) = (50, 1e-5);
    let ev = p.v_width(0.5, n, d).unwrap();
    assert!((p.v_width(1.0, n, d).unwrap() / ev - 0.5).abs() < 1e-12);
    assert!((two.v_width(0.5, n, d).unwrap() / ev - 2.0).abs() < 1e-12);
    assert!((two.w_width(n, d).unwrap() / p.w_width(n, d).unwrap() - 2.0).abs() < 1e-12);
    assert!((two.j_width(n, d).unwrap() / p.j_width(n, d).unwrap() - 2.0).abs() < 1e-12);
    assert!((p.v_width(0.5, 4 * n, d).unwrap() / ev - 0.5).abs() < 1e-12);
    assert_eq!((p.baseline(), two.baseline()), (-14.4, 0.0));
    // J: Hoeffding with the range R Σ_{t<20} 0.99^t.
    let range: f64 = (0..20).map(|t| 28.8 * 0.99f64.powi(t)).sum();
    assert!((p.j_range() / range - 1.0).abs() < 1e-14);
}

#[test]
fn invalid_inputs_are_typed_errors() {
    use EstimatorError as E;
    let bad = [
        ProvenWidths::new(0.0, false, 1.0, 0.9, 20),
        ProvenWidths::new(f64::INFINITY, false, 1.0, 0.9, 20),
        ProvenWidths::new(1.0, false, f64::NAN, 0.9, 20),
        ProvenWidths::new(1.0, false, -1.0, 0.9, 20),
        ProvenWidths::new(1.0, false, 1.0, 1.0, 20),
        ProvenWidths::new(1.0, false, 1.0, -0.1, 20),
        ProvenWidths::new(1.0, false, 1.0, f64::NAN, 20),
        ProvenWidths::new(1.0, false, 1.0, 0.9, 0),
        ProvenWidths::new(1.0, false, 1.0, 0.9, usize::MAX),
    ];
    for b in bad {
        assert!(matches!(b, Err(E::InvalidTaskConstant { .. })), "{b:?}");
    }
    // Overflow of the sums.
    assert!(matches!(
        ProvenWidths::new(f64::MAX, false, 1.0, 0.999, 1000),
        Err(E::NonFinite { .. })
    ));
    let p = ProvenWidths::new(1.0, false, 1.0, 0.9, 20).unwrap();
    assert!(matches!(
        p.v_width(0.0, 10, 0.1),
        Err(E::InvalidSigma { .. })
    ));
    assert!(matches!(
        p.v_width(f64::NAN, 10, 0.1),
        Err(E::InvalidSigma { .. })
    ));
    assert!(matches!(
        p.v_width(1e-310, 10, 0.1),
        Err(E::NonFinite { .. })
    ));
    assert!(matches!(
        p.v_width(1.0, 0, 0.1),
        Err(E::TooFewTrajectories { .. })
    ));
    assert!(matches!(p.w_width(10, 1.0), Err(E::InvalidDelta { .. })));
    assert!(matches!(p.j_width(10, 0.0), Err(E::InvalidDelta { .. })));
    assert!(matches!(
        p.j_width(10, f64::NAN),
        Err(E::InvalidDelta { .. })
    ));
    assert!(matches!(
        psi2_width(-1.0, 10, 0.1),
        Err(E::InvalidRange { .. })
    ));
    assert!(matches!(
        psi1_width(f64::INFINITY, 10, 0.1),
        Err(E::InvalidRange { .. })
    ));
    assert!(matches!(
        psi1_width(f64::MAX, 1, 1e-300),
        Err(E::NonFinite { .. })
    ));
    assert!(matches!(
        chi2_psi1_norm(0),
        Err(E::TooFewTrajectories { .. })
    ));
    // One trajectory is enough: the widths hold at every N ≥ 1.
    assert!(p.v_width(1.0, 1, 0.1).unwrap() > 0.0);
    assert!(p.w_width(1, 0.1).unwrap() > 0.0);
    // γ = 0: only the first step counts.
    let g0 = ProvenWidths::new(1.0, false, 1.0, 0.0, 50).unwrap();
    assert!((g0.v_psi2_norm(1.0).unwrap() - (8.0f64 / 3.0).sqrt()).abs() < 1e-15);
}
