//! Monte Carlo check of the clipped-LQG DP oracle with the crate's rollout engine: N = 10⁶
//! trajectories of H = 20 steps per grid point, one fixed seed per point.
//!
//! Each comparison asserts `|MC mean − exact| ≤ z · SE` with `z = Φ⁻¹(1 − α/(2K))`, a
//! Bonferroni correction over the `K` comparisons of the file for a family-wise false-alarm
//! rate `α = 10⁻³` (for a correct oracle, a different seed fails this file with probability at
//! most 0.1%). With N = 10⁶ the standard errors are ~10⁻³ of |J|, so a sign or factor error
//! in the oracle cannot pass.

use rand_xoshiro::rand_core::{RngCore, SeedableRng};
use sepg_mdp::env::LqgEnv;
use sepg_mdp::lqg_model::LqgModel;
use sepg_mdp::monte_carlo::stream_returns;
use sepg_mdp::oracle::{ClippedDpOracle, ExactOracle, Horizon};
use sepg_mdp::policy::GaussianPolicy;
use sepg_mdp::rng::SeedKey;
use sepg_mdp::rollout::rollout;
use statrs::distribution::{ContinuousCDF, Normal};

const N: usize = 1_000_000;
const H: usize = 20;
/// Family-wise false-alarm rate of the whole file.
const ALPHA: f64 = 1e-3;
/// Comparisons in this file: 13 values of J and 3 derivatives at 2 points.
const K: f64 = 19.0;

fn z_crit() -> f64 {
    Normal::standard().inverse_cdf(1.0 - ALPHA / (2.0 * K))
}

/// Mean and standard error of i.i.d. samples.
fn mean_se(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let m = x.iter().sum::<f64>() / n;
    let var = x.iter().map(|y| (y - m) * (y - m)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

fn check(label: &str, samples: &[f64], exact: f64) {
    let (m, se) = mean_se(samples);
    check_mean(label, m, se, exact);
}

fn check_mean(label: &str, m: f64, se: f64, exact: f64) {
    let z = z_crit();
    println!(
        "{label}: exact {exact:.6}, MC {m:.6} ± {se:.2e} ({:+.2} SE)",
        (m - exact) / se
    );
    assert!(
        (m - exact).abs() <= z * se,
        "{label}: |{m} − {exact}| > {z} · {se}"
    );
}

fn noisy_thesis() -> LqgModel {
    LqgModel::thesis()
        .with_noise(nalgebra::DVector::from_element(1, 0.2))
        .expect("valid noise")
}

/// A general scalar model: `A ≠ 1`, `B ≠ 1`, asymmetric boxes, init box inside the state box.
fn general_model(noise: f64) -> LqgModel {
    use nalgebra::{DMatrix, DVector};
    let m = |x: f64| DMatrix::from_element(1, 1, x);
    let bx = |lo: f64, hi: f64| {
        sepg_mdp::lqg_model::BoxBounds::new(
            DVector::from_element(1, lo),
            DVector::from_element(1, hi),
        )
    };
    LqgModel::new(
        m(0.9),
        m(0.7),
        m(0.3),
        m(0.8),
        bx(-1.5, 2.5),
        bx(-1.0, 0.5),
        bx(-1.0, 2.0),
    )
    .and_then(|x| x.with_noise(DVector::from_element(1, noise)))
    .expect("valid model")
}

#[test]
fn dp_values_agree_with_monte_carlo() {
    // (model, v, σ or None for the deterministic policy); 13 comparisons.
    let grid: Vec<(LqgModel, f64, Option<f64>)> = vec![
        (LqgModel::thesis(), -0.1, Some(0.2)),
        (LqgModel::thesis(), -0.1, Some(1.0)),
        (LqgModel::thesis(), -0.6, Some(0.2)),
        (LqgModel::thesis(), -0.6, Some(1.0)),
        (LqgModel::thesis(), -1.2, Some(0.2)),
        (LqgModel::thesis(), -1.2, Some(1.0)),
        (LqgModel::lqg1d(), -0.3, Some(0.5)),
        (LqgModel::lqg1d(), -1.0, Some(0.5)),
        (LqgModel::thesis(), -1.5, None),
        (LqgModel::lqg1d(), -0.6, None),
        (noisy_thesis(), -0.8, Some(0.4)),
        (general_model(0.0), -0.4, Some(0.3)),
        (general_model(0.1), -0.9, Some(0.6)),
    ];
    let mut seeds = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(20_240_601);
    for (model, v, sigma) in grid {
        let env = LqgEnv::new(model.clone()).unwrap();
        let oracle = ClippedDpOracle::new(&model).unwrap();
        let policy = match sigma {
            Some(s) => GaussianPolicy::scalar(v, s.ln()).unwrap(),
            None => GaussianPolicy::deterministic(vec![v], 1, 1).unwrap(),
        };
        let exact = oracle.evaluate_policy(&policy, Horizon::Finite(H)).unwrap();
        let key = SeedKey::new(seeds.next_u64(), 0, 0);
        let (returns, _) = stream_returns(&env, &policy, N, H, key).unwrap();
        check_mean(
            &format!("J r_max={} v={v} σ={sigma:?}", model.r_max()),
            returns.mean(),
            returns.std_error(),
            exact.j,
        );
    }
}

#[test]
fn dp_derivatives_agree_with_likelihood_ratio_estimates() {
    // Per-trajectory unbiased samples (raw-action scores, docs/CONVENTIONS.md §2):
    //   ∂_v J:  Σ_t γ^t r_t S^v_t              (G(PO)MDP)
    //   ∂_w J:  Σ_t γ^t r_t S^w_t
    //   ∂_w∂_v J = σ h − 2 ∂_v J,  h: Σ_t γ^t r_t (S^w_t/σ) S^v_t   (Appendix B, eq. B.3)
    // with S_t the cumulative scores of the batch. 6 comparisons.
    let chunk = 100_000;
    let mut seeds = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(77);
    for (model, v, sigma) in [
        (LqgModel::thesis(), -0.6, 0.5f64),
        (LqgModel::lqg1d(), -1.0, 0.5),
    ] {
        let env = LqgEnv::new(model.clone()).unwrap();
        let policy = GaussianPolicy::scalar(v, sigma.ln()).unwrap();
        let exact = ClippedDpOracle::new(&model)
            .unwrap()
            .evaluate_policy(&policy, Horizon::Finite(H))
            .unwrap();
        let seed = seeds.next_u64();
        let (mut gv, mut gw, mut mix) = (Vec::new(), Vec::new(), Vec::new());
        for block in 0..(N / chunk) as u64 {
            let b = rollout(&env, &policy, chunk, H, SeedKey::new(seed, 0, block)).unwrap();
            for i in 0..b.n {
                let (mut sv, mut sw, mut sh) = (0.0, 0.0, 0.0);
                for (t, r) in b.rewards(i).iter().enumerate() {
                    let (cv, cw) = (b.score_v(i, t)[0], b.score_w(i, t)[0]);
                    sv += r * cv;
                    sw += r * cw;
                    sh += r * (cw / sigma) * cv;
                }
                gv.push(sv);
                gw.push(sw);
                mix.push(sigma * sh - 2.0 * sv);
            }
        }
        let tag = format!("r_max={} v={v} σ={sigma}", model.r_max());
        check(&format!("∂_v J {tag}"), &gv, exact.grad_v[0]);
        check(&format!("∂_w J {tag}"), &gw, exact.grad_w[0]);
        check(&format!("∂_w∂_v J {tag}"), &mix, exact.mixed_wv[0]);
    }
}
