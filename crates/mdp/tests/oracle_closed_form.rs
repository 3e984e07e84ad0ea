//! Tests of the closed-form unclipped LQG oracle against independent references: the scalar
//! Lyapunov formula, a forward second-moment recursion written here from scratch, fourth-order
//! central finite differences of `J`, and the published optimum of the presets.

use approx::{abs_diff_eq, assert_abs_diff_eq, assert_relative_eq, relative_eq};
use nalgebra::{DMatrix, DVector};
use proptest::prelude::*;
use proptest::test_runner::{FileFailurePersistence, RngSeed};
use sepg_mdp::lqg_model::{BoxBounds, LqgModel};
use sepg_mdp::oracle::{
    ClosedFormOracle, ExactEval, ExactOracle, Exploration, Horizon, OracleError,
};

fn gaussian(w: &[f64]) -> Exploration {
    Exploration::Gaussian { w: w.to_vec() }
}

/// Fourth-order central difference `f'(x)` with step `h` (error `O(h⁴)`).
fn fd4(h: f64, mut f: impl FnMut(f64) -> f64) -> f64 {
    (8.0 * (f(h) - f(-h)) - (f(2.0 * h) - f(-2.0 * h))) / (12.0 * h)
}

/// `|analytic − FD|` minus the FD error estimate `|FD(h) − FD(h/2)|` (steps 2e-3 and 1e-3):
/// positive only when the analytic value disagrees beyond the differencing error.
fn fd_excess(analytic: f64, mut f: impl FnMut(f64) -> f64) -> f64 {
    let coarse = fd4(2e-3, &mut f);
    let fine = fd4(1e-3, &mut f);
    (analytic - fine).abs() - 2.0 * (coarse - fine).abs()
}

/// `v* = (1 − √(1 + 4γ²)) / (2γ)` of the scalar presets.
fn v_star(gamma: f64) -> f64 {
    (1.0 - (1.0 + 4.0 * gamma * gamma).sqrt()) / (2.0 * gamma)
}

/// A random unclipped model described by a flat list of numbers in `[-1, 1]`.
struct RandomCase {
    model: LqgModel,
    v: Vec<f64>,
    w: Vec<f64>,
}

fn random_case(n: usize, l: usize, xs: &[f64], gamma: f64) -> RandomCase {
    let mut it = xs.iter().copied().cycle();
    let mut take = |k: usize| -> Vec<f64> { (0..k).map(|_| it.next().unwrap_or(0.0)).collect() };
    let a = DMatrix::from_vec(n, n, take(n * n)) * 0.8;
    let b = DMatrix::from_vec(n, l, take(n * l));
    let lq = DMatrix::from_vec(n, n, take(n * n));
    let q = &lq * lq.transpose() + DMatrix::identity(n, n) * 0.1;
    let lr = DMatrix::from_vec(l, l, take(l * l));
    let r = &lr * lr.transpose() + DMatrix::identity(l, l) * 0.1;
    let noise = DVector::from_vec(take(n).iter().map(|x| 0.5 * x.abs()).collect());
    let lo = DVector::from_vec(take(n).iter().map(|x| 2.0 * x).collect());
    let width = DVector::from_vec(take(n).iter().map(|x| 0.5 + 1.5 * x.abs()).collect());
    let hi = &lo + width;
    let v = take(l * n).iter().map(|x| 0.4 * x).collect();
    let w = take(l).iter().map(|x| 0.8 * x - 0.3).collect();
    let model = LqgModel::new(
        a,
        b,
        q,
        r,
        BoxBounds::cube(n, -10.0, 10.0),
        BoxBounds::cube(l, -10.0, 10.0),
        BoxBounds::new(lo, hi),
    )
    .and_then(|m| m.with_noise(noise))
    .and_then(|m| m.with_gamma(gamma))
    .expect("valid random model")
    .with_clipping(false);
    RandomCase { model, v, w }
}

/// `J` by the forward second-moment recursion `X_{t+1} = K X_t Kᵀ + B Σ_a Bᵀ + Σ_η`,
/// `J = −Σ_t γ^t [tr((Q + VᵀRV) X_t) + tr(R Σ_a)]`, with `X_0 = Cov(s_0) + E[s_0]E[s_0]ᵀ`
/// computed component by component.
fn forward_moments_j(model: &LqgModel, v: &[f64], sigma: &[f64], h: usize) -> f64 {
    let (n, l) = (model.state_dim(), model.action_dim());
    let vm = DMatrix::from_fn(l, n, |j, i| v[j * n + i]);
    let k = &model.a + &model.b * &vm;
    let m = &model.q + vm.transpose() * &model.r * &vm;
    let sa = DMatrix::from_fn(l, l, |i, j| {
        if i == j && !sigma.is_empty() {
            sigma[i] * sigma[i]
        } else {
            0.0
        }
    });
    let noise = DMatrix::from_fn(n, n, |i, j| {
        if i == j {
            model.noise_std[i].powi(2)
        } else {
            0.0
        }
    });
    let wmat = &model.b * &sa * model.b.transpose() + noise;
    let mut x = DMatrix::from_fn(n, n, |i, j| {
        let (li, hi) = (model.init_low[i], model.init_high[i]);
        let (lj, hj) = (model.init_low[j], model.init_high[j]);
        let mi = 0.5 * (li + hi);
        let mj = 0.5 * (lj + hj);
        if i == j {
            (hi - li).powi(2) / 12.0 + mi * mi
        } else {
            mi * mj
        }
    });
    let tr_rs = (&model.r * &sa).trace();
    let mut j = 0.0;
    let mut disc = 1.0;
    for _ in 0..h {
        j -= disc * ((&m * &x).trace() + tr_rs);
        x = &k * &x * k.transpose() + &wmat;
        disc *= model.gamma;
    }
    j
}

fn scale_of(e: &ExactEval) -> f64 {
    e.j.abs().max(1.0)
}

/// `J` and derivatives of the unclipped scalar presets at 50 digits by
/// `scripts/gen_lqg_reference.py` (closed-form sums evaluated in mpmath).
const LQG_SCALAR: &str = include_str!("data/lqg_scalar.csv");

#[test]
fn scalar_presets_match_the_high_precision_table() {
    let mut rows = 0;
    for line in LQG_SCALAR.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let model = match f[0] {
            "lqg" => LqgModel::thesis(),
            _ => LqgModel::lqg1d(),
        };
        let num = |i: usize| f[i].parse::<f64>().unwrap();
        let v = num(1);
        let ex = if f[2] == "-inf" {
            Exploration::Deterministic
        } else {
            gaussian(&[num(2)])
        };
        let h = match f[3] {
            "inf" => Horizon::Infinite,
            x => Horizon::Finite(x.parse().unwrap()),
        };
        let e = ClosedFormOracle::new(&model)
            .unwrap()
            .evaluate(&[v], &ex, h)
            .unwrap();
        let (j, djv, djw, dwv) = (num(4), num(5), num(6), num(7));
        // The derivatives share J's tolerance: 1e-13 in units of max(|J|, 1).
        let tol = 1e-13 * j.abs().max(1.0);
        assert!(
            relative_eq!(e.j, j, epsilon = 1e-13, max_relative = 1e-13),
            "{line}: J = {}",
            e.j
        );
        assert!(
            abs_diff_eq!(e.grad_v[0], djv, epsilon = tol),
            "{line}: dJ/dv = {}",
            e.grad_v[0]
        );
        if let Exploration::Gaussian { .. } = ex {
            assert!(
                abs_diff_eq!(e.grad_w[0], djw, epsilon = tol),
                "{line}: dJ/dw = {}",
                e.grad_w[0]
            );
            assert!(
                abs_diff_eq!(e.mixed_wv[0], dwv, epsilon = tol),
                "{line}: d2J = {}",
                e.mixed_wv[0]
            );
        }
        rows += 1;
    }
    assert_eq!(rows, 58);
}

#[test]
fn preset_optimum_matches_the_published_values() {
    for (model, j_ref) in [
        (LqgModel::thesis(), -1.076834),
        (LqgModel::lqg1d(), -7.753206),
    ] {
        let o = ClosedFormOracle::new(&model).unwrap();
        let opt = o.optimal_gain().unwrap();
        assert_abs_diff_eq!(opt.v[0], -0.615251245663011, epsilon = 1e-14);
        assert_abs_diff_eq!(opt.v[0], v_star(0.99), epsilon = 1e-14);
        // Published to 6 decimals.
        assert_abs_diff_eq!(opt.j_deterministic, j_ref, epsilon = 5e-7);
        // Scalar Lyapunov formula P = q(1 + v²)/(1 − γ(1 + v)²), J = −P E[s0²].
        let q = model.q[(0, 0)];
        let s2 = model.init_high[0].powi(2) / 3.0;
        let v = opt.v[0];
        let p = q * (1.0 + v * v) / (1.0 - 0.99 * (1.0 + v).powi(2));
        assert_relative_eq!(opt.j_deterministic, -p * s2, max_relative = 1e-13);
        assert_relative_eq!(opt.p[(0, 0)], p, max_relative = 1e-13);
    }
    for gamma in [0.1, 0.5, 0.9, 0.999] {
        let m = LqgModel::thesis().with_gamma(gamma).unwrap();
        let opt = ClosedFormOracle::new(&m).unwrap().optimal_gain().unwrap();
        assert!(
            abs_diff_eq!(opt.v[0], v_star(gamma), epsilon = 1e-13),
            "γ = {gamma}"
        );
    }
}

#[test]
fn optimal_gain_is_a_stationary_maximum_in_two_dimensions() {
    let xs = [
        0.3, -0.2, 0.5, 0.9, 0.7, -0.4, 0.2, 0.1, -0.3, 0.6, 0.4, 0.0, -0.5, 0.8, 0.2, -0.7, 0.1,
    ];
    let case = random_case(2, 2, &xs, 0.95);
    let o = ClosedFormOracle::new(&case.model).unwrap();
    let opt = o.optimal_gain().unwrap();
    let w = [-0.5, 0.2];
    let e = o
        .evaluate(&opt.v, &gaussian(&w), Horizon::Infinite)
        .unwrap();
    let g = e.grad_v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(g < 1e-10 * scale_of(&e), "gradient at V* = {:?}", e.grad_v);
    let hv = e
        .hessian
        .as_ref()
        .unwrap()
        .view((0, 0), (4, 4))
        .clone_owned();
    let eig = hv.symmetric_eigenvalues();
    assert!(eig.iter().all(|x| *x < 0.0), "Hessian eigenvalues {eig}");
    for d in [
        [0.01, 0.0, 0.0, 0.0],
        [0.0, -0.02, 0.01, 0.0],
        [0.0, 0.0, 0.0, 0.05],
    ] {
        let vp: Vec<f64> = opt.v.iter().zip(d).map(|(a, b)| a + b).collect();
        let ep = o.evaluate(&vp, &gaussian(&w), Horizon::Infinite).unwrap();
        assert!(ep.j < e.j);
    }
}

#[test]
fn scalar_infinite_horizon_matches_the_lyapunov_formula() {
    for (v, w, eta) in [
        (-0.1, 0.0, 0.0),
        (-0.6, -1.0, 0.3),
        (-1.5, 0.5, 0.1),
        (0.004, -2.0, 1.0),
    ] {
        let m = LqgModel::lqg1d()
            .with_noise(DVector::from_element(1, eta))
            .unwrap()
            .with_clipping(false);
        let o = ClosedFormOracle::new(&m).unwrap();
        let e = o
            .evaluate(&[v], &gaussian(&[w]), Horizon::Infinite)
            .unwrap();
        let (g, q, s) = (0.99, 0.9, f64::exp(w));
        let p = q * (1.0 + v * v) / (1.0 - g * (1.0 + v).powi(2));
        let j = -p * (16.0 / 3.0 + g * (s * s + eta * eta) / (1.0 - g)) - q * s * s / (1.0 - g);
        assert_relative_eq!(e.j, j, max_relative = 1e-12);
    }
}

#[test]
fn finite_horizon_converges_to_the_infinite_one() {
    let o = ClosedFormOracle::new(&LqgModel::thesis()).unwrap();
    let ex = gaussian(&[-0.7]);
    let inf = o.evaluate(&[-0.4], &ex, Horizon::Infinite).unwrap();
    // γ^6000 ≈ 6e-27: the tail is far below rounding.
    let fin = o.evaluate(&[-0.4], &ex, Horizon::Finite(6000)).unwrap();
    assert_relative_eq!(inf.j, fin.j, max_relative = 1e-11);
    for (a, b) in inf.grad_v.iter().zip(&fin.grad_v) {
        assert_relative_eq!(a, b, epsilon = 1e-10, max_relative = 1e-10);
    }
    let (ha, hb) = (inf.hessian.unwrap(), fin.hessian.unwrap());
    assert!((ha - hb).amax() < 1e-9);
}

#[test]
fn deterministic_policy_is_the_zero_variance_limit() {
    let o = ClosedFormOracle::new(&LqgModel::lqg1d()).unwrap();
    for h in [Horizon::Finite(20), Horizon::Infinite] {
        let det = o.evaluate(&[-0.3], &Exploration::Deterministic, h).unwrap();
        let tiny = o.evaluate(&[-0.3], &gaussian(&[-25.0]), h).unwrap();
        assert_relative_eq!(det.j, tiny.j, max_relative = 1e-12);
        assert_relative_eq!(det.grad_v[0], tiny.grad_v[0], max_relative = 1e-12);
        assert_abs_diff_eq!(tiny.grad_w[0], 0.0, epsilon = 1e-18);
        assert!(det.grad_w.is_empty() && det.mixed_wv.is_empty() && det.sigma.is_empty());
        assert_eq!(det.hessian.as_ref().unwrap().shape(), (1, 1));
    }
}

#[test]
fn mixed_layout_and_sigma_conversions() {
    let xs = [0.2, -0.4, 0.6, 0.1, -0.9, 0.3, 0.5, -0.2, 0.7];
    let case = random_case(3, 2, &xs, 0.9);
    let o = ClosedFormOracle::new(&case.model).unwrap();
    let e = o
        .evaluate(&case.v, &gaussian(&case.w), Horizon::Finite(15))
        .unwrap();
    let h = e.hessian.as_ref().unwrap();
    let m = 6;
    assert_eq!(h.shape(), (8, 8));
    for j in 0..2 {
        for k in 0..m {
            assert_eq!(e.mixed_wv[j * m + k], h[(m + j, k)]);
            assert_eq!(e.mixed_wv[j * m + k], h[(k, m + j)]);
            let s = f64::exp(case.w[j]);
            assert_abs_diff_eq!(
                e.mixed_sigma_v()[j * m + k],
                e.mixed_wv[j * m + k] / s,
                epsilon = 1e-15
            );
        }
        assert_abs_diff_eq!(e.grad_sigma()[j] * e.sigma[j], e.grad_w[j], epsilon = 1e-13);
    }
}

#[test]
fn unstable_closed_loop_is_a_typed_error() {
    let o = ClosedFormOracle::new(&LqgModel::thesis()).unwrap();
    for v in [0.5, -2.5, 1.0 / 0.99f64.sqrt() - 1.0 + 1e-12] {
        match o.evaluate(&[v], &Exploration::Deterministic, Horizon::Infinite) {
            Err(OracleError::Unstable { scaled_radius }) => assert!(scaled_radius >= 1.0),
            other => panic!("v = {v}: {other:?}"),
        }
    }
    // Just inside the boundary the sum is finite, large and converged.
    let v = 1.0 / 0.99f64.sqrt() - 1.0 - 1e-6;
    let e = o
        .evaluate(&[v], &Exploration::Deterministic, Horizon::Infinite)
        .unwrap();
    let p = 0.5 * (1.0 + v * v) / (1.0 - 0.99 * (1.0 + v).powi(2));
    // 1e-7 in units of P, i.e. 7.5e-8 in units of |J| = 4P/3.
    assert_relative_eq!(e.j, -p * 4.0 / 3.0, max_relative = 7.5e-8);
    // Finite horizon of an unstable loop is finite; an overflowing one is a typed error.
    assert!(
        o.evaluate(&[2.0], &Exploration::Deterministic, Horizon::Finite(50))
            .unwrap()
            .j
            .is_finite()
    );
    assert_eq!(
        o.evaluate(&[1e3], &Exploration::Deterministic, Horizon::Finite(400)),
        Err(OracleError::Overflow)
    );
}

#[test]
fn invalid_inputs_are_typed_errors() {
    let o = ClosedFormOracle::new(&LqgModel::thesis()).unwrap();
    let h = Horizon::Finite(5);
    assert!(matches!(
        o.evaluate(&[0.1, 0.2], &Exploration::Deterministic, h),
        Err(OracleError::DimensionMismatch { what: "v", .. })
    ));
    assert!(matches!(
        o.evaluate(&[0.1], &gaussian(&[0.0, 0.0]), h),
        Err(OracleError::DimensionMismatch { what: "w", .. })
    ));
    assert!(matches!(
        o.evaluate(&[f64::NAN], &Exploration::Deterministic, h),
        Err(OracleError::NonFinite { what: "v" })
    ));
    assert!(matches!(
        o.evaluate(&[0.1], &gaussian(&[f64::INFINITY]), h),
        Err(OracleError::NonFinite { what: "w" })
    ));
    for w in [-400.0, 400.0] {
        assert!(matches!(
            o.evaluate(&[0.1], &gaussian(&[w]), h),
            Err(OracleError::SigmaOutOfRange { index: 0, .. })
        ));
    }
    assert_eq!(
        o.evaluate(&[0.1], &Exploration::Deterministic, Horizon::Finite(0)),
        Err(OracleError::ZeroHorizon)
    );
    let mut bad = LqgModel::thesis();
    bad.gamma = 1.0;
    assert!(matches!(
        ClosedFormOracle::new(&bad),
        Err(OracleError::Model(_))
    ));
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 32,
        rng_seed: RngSeed::Fixed(0xc1_05ed),
        failure_persistence: Some(Box::new(FileFailurePersistence::WithSource("proptest-regressions"))),
        ..ProptestConfig::default()
    })]

    /// The backward Lyapunov recursion equals an independent forward second-moment recursion.
    #[test]
    fn finite_horizon_matches_forward_moments(
        n in 1usize..=3,
        l in 1usize..=2,
        xs in prop::collection::vec(-1.0f64..1.0, 40),
        gamma in 0.3f64..0.999,
        h in 1usize..40,
        deterministic in any::<bool>(),
    ) {
        let case = random_case(n, l, &xs, gamma);
        let o = ClosedFormOracle::new(&case.model).unwrap();
        let (ex, sigma) = if deterministic {
            (Exploration::Deterministic, Vec::new())
        } else {
            (gaussian(&case.w), case.w.iter().map(|w| w.exp()).collect())
        };
        let e = o.evaluate(&case.v, &ex, Horizon::Finite(h)).unwrap();
        let j = forward_moments_j(&case.model, &case.v, &sigma, h);
        prop_assert!(relative_eq!(e.j, j, epsilon = 1e-11, max_relative = 1e-11), "{} vs {}", e.j, j);
    }

    /// Gradient, mixed derivative and Hessian against fourth-order central differences:
    /// the gradient from differences of `J`, the Hessian from differences of the gradient.
    #[test]
    fn derivatives_match_finite_differences(
        n in 1usize..=3,
        l in 1usize..=2,
        xs in prop::collection::vec(-1.0f64..1.0, 40),
        gamma in 0.3f64..0.99,
        h in prop_oneof![(1usize..30).prop_map(Horizon::Finite), Just(Horizon::Infinite)],
    ) {
        let case = random_case(n, l, &xs, gamma);
        let o = ClosedFormOracle::new(&case.model).unwrap();
        if h == Horizon::Infinite {
            prop_assume!(o.scaled_spectral_radius(&case.v).unwrap() < 0.9);
        }
        let (v, w) = (case.v.clone(), case.w.clone());
        let m = v.len();
        let at = |v: &[f64], w: &[f64]| o.evaluate(v, &gaussian(w), h).unwrap();
        let e = at(&v, &w);
        let hess = e.hessian.clone().unwrap();
        let theta: Vec<f64> = v.iter().chain(&w).copied().collect();
        let split = |t: &[f64]| (t[..m].to_vec(), t[m..].to_vec());
        let scale = e.j.abs().max(1.0);
        for i in 0..theta.len() {
            let shifted = |d: f64| {
                let mut t = theta.clone();
                t[i] += d;
                let (vv, ww) = split(&t);
                at(&vv, &ww)
            };
            let g = if i < m { e.grad_v[i] } else { e.grad_w[i - m] };
            let ex = fd_excess(g, |d| shifted(d).j);
            prop_assert!(ex <= 1e-9 * scale, "dJ/dθ_{}: {} off by {:e}", i, g, ex);
            for k in 0..theta.len() {
                let ex = fd_excess(hess[(k, i)], |d| {
                    let s = shifted(d);
                    if k < m { s.grad_v[k] } else { s.grad_w[k - m] }
                });
                prop_assert!(ex <= 1e-8 * scale, "H[{},{}] = {} off by {:e}", k, i, hess[(k, i)], ex);
            }
        }
        // Deterministic gradient against differences of the deterministic J.
        let det = o.evaluate(&v, &Exploration::Deterministic, h).unwrap();
        for i in 0..m {
            let ex = fd_excess(det.grad_v[i], |d| {
                let mut vv = v.clone();
                vv[i] += d;
                o.evaluate(&vv, &Exploration::Deterministic, h).unwrap().j
            });
            prop_assert!(ex <= 1e-9 * det.j.abs().max(1.0));
        }
    }
}
