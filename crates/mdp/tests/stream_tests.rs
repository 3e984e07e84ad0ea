//! Streamed Monte Carlo (`monte_carlo::stream_*`): bit-identical for any thread count, equal to
//! an independent computation from stored batches, and unbiased against the exact clipped-LQG
//! oracle.

use approx::{abs_diff_eq, assert_abs_diff_eq, assert_relative_eq};
use rand_xoshiro::Xoshiro256PlusPlus;
use rand_xoshiro::rand_core::{RngCore, SeedableRng};
use sepg_mdp::Batch;
use sepg_mdp::env::{AnyEnv, LqgEnv};
use sepg_mdp::lqg_model::LqgModel;
use sepg_mdp::monte_carlo::{
    BLOCK, GradientMoments, Moments, estimate_j_difference, pilot_key, stream_gradients,
    stream_returns,
};
use sepg_mdp::mountain_car::MountainCar;
use sepg_mdp::oracle::{ClippedDpOracle, ExactOracle, Horizon};
use sepg_mdp::policy::GaussianPolicy;
use sepg_mdp::rng::SeedKey;
use sepg_mdp::rollout::{rollout, rollout_returns};
use statrs::distribution::{ContinuousCDF, Normal};

mod common;
use common::{lqg_2d, pool};

/// (environment, policy, n, horizon): the fused scalar kernel (n crosses a 64-item round and
/// is not a multiple of the block or of the lane count), the generic kernel with two actions
/// and noise, and Mountain Car with early terminations (energy pumping, μ = 100·vel) and a
/// horizon longer than some episodes.
fn cases() -> Vec<(AnyEnv, GaussianPolicy, usize, usize)> {
    vec![
        (
            AnyEnv::Lqg(Box::new(LqgEnv::lqg1d())),
            GaussianPolicy::scalar(-0.3, -0.5).unwrap(),
            64 * BLOCK + 1003,
            4,
        ),
        (
            AnyEnv::Lqg(Box::new(lqg_2d())),
            GaussianPolicy::new(vec![-0.5, 0.1, 0.0, -0.4], vec![-1.0, -0.5], 2).unwrap(),
            2 * BLOCK + 7,
            9,
        ),
        (
            AnyEnv::MountainCar(MountainCar::state_bias()),
            GaussianPolicy::new(vec![0.0, 100.0, 0.0], vec![-3.0], 3).unwrap(),
            BLOCK + 5,
            150,
        ),
    ]
}

fn bits(m: &Moments) -> [u64; 3] {
    [m.count(), m.mean().to_bits(), m.variance().to_bits()]
}

fn all_bits(g: &GradientMoments) -> Vec<[u64; 3]> {
    std::iter::once(&g.j)
        .chain(&g.grad_v)
        .chain(&g.grad_w)
        .map(bits)
        .collect()
}

#[test]
fn streamed_estimates_are_identical_for_any_thread_count() {
    let key = SeedKey::new(9, 3, 1);
    for (env, pi, n, h) in cases() {
        let run = |threads: usize| {
            pool(threads).install(|| {
                let g = stream_gradients(&env, &pi, n, h, key, 300).unwrap();
                let (r, steps) = stream_returns(&env, &pi, n, h, key).unwrap();
                let other = GaussianPolicy::new(
                    pi.v().iter().map(|x| x * 0.9).collect(),
                    pi.w().unwrap().to_vec(),
                    pi.feature_dim(),
                )
                .unwrap();
                let d = estimate_j_difference(&env, &pi, &other, n, h, key, 0.95).unwrap();
                (
                    all_bits(&g),
                    g.steps,
                    bits(&r),
                    steps,
                    d.mean.to_bits(),
                    d.std_error.to_bits(),
                )
            })
        };
        let one = run(1);
        assert_eq!(one, run(2));
        assert_eq!(one, run(3));
    }
}

/// Per-trajectory samples of an independent computation from stored batches: the pilot batch
/// (key `pilot_key(key)`) gives `b_t = Σ S_t² γ^t r_t / Σ S_t²`, the main batch the samples
/// `Σ_t S_t (γ^t r_t − b_t)` (rows of a `Batch` are padded after termination).
fn from_batches(
    env: &AnyEnv,
    pi: &GaussianPolicy,
    n: usize,
    h: usize,
    key: SeedKey,
    pilot: usize,
) -> Vec<Vec<f64>> {
    let p = rollout(env, pi, pilot, h, pilot_key(key)).unwrap();
    let baseline = |scores: &dyn Fn(&Batch, usize, usize) -> &[f64], d: usize| {
        let (mut num, mut den) = (vec![0.0; h * d], vec![0.0; h * d]);
        for i in 0..pilot {
            for t in 0..h {
                for k in 0..d {
                    let s = scores(&p, i, t)[k];
                    num[t * d + k] += s * s * p.rewards(i)[t];
                    den[t * d + k] += s * s;
                }
            }
        }
        num.iter()
            .zip(&den)
            .map(|(a, b)| if *b == 0.0 { 0.0 } else { a / b })
            .collect::<Vec<f64>>()
    };
    let (dv, dw) = (pi.dim_v(), pi.dim_w());
    let bv = baseline(&|b, i, t| b.score_v(i, t), dv);
    let bw = baseline(&|b, i, t| b.score_w(i, t), dw);
    let b = rollout(env, pi, n, h, key).unwrap();
    let mut comps = vec![(0..n).map(|i| b.discounted_return(i)).collect::<Vec<_>>()];
    let sample = |i: usize, k: usize, d: usize, base: &[f64], v: bool| {
        (0..h).fold(0.0, |acc, t| {
            let s = if v { b.score_v(i, t) } else { b.score_w(i, t) }[k];
            acc + s * (b.rewards(i)[t] - base[t * d + k])
        })
    };
    for k in 0..dv {
        comps.push((0..n).map(|i| sample(i, k, dv, &bv, true)).collect());
    }
    for k in 0..dw {
        comps.push((0..n).map(|i| sample(i, k, dw, &bw, false)).collect());
    }
    comps
}

#[test]
fn streamed_gradients_equal_an_independent_computation_from_batches() {
    // The per-trajectory samples are the same floating-point operations in the same order;
    // only the reduction differs (blocks merged pairwise vs one two-pass sum), so means and
    // variances agree to a few ulps of the sums involved.
    let key = SeedKey::new(4, 0, 2);
    for (env, pi, n, h) in cases() {
        let n = n.min(3 * BLOCK + 11);
        for pilot in [0, 257] {
            let g = stream_gradients(&env, &pi, n, h, key, pilot).unwrap();
            let want = from_batches(&env, &pi, n, h, key, pilot.max(1));
            let want: Vec<Moments> = if pilot == 0 {
                // No pilot: plain G(PO)MDP, i.e. the batch samples against a zero baseline.
                let b = rollout(&env, &pi, n, h, key).unwrap();
                let mut comps = vec![(0..n).map(|i| b.discounted_return(i)).collect::<Vec<_>>()];
                for k in 0..pi.dim_v() {
                    comps.push(
                        (0..n)
                            .map(|i| {
                                (0..h).fold(0.0, |a, t| {
                                    a + b.score_v(i, t)[k] * (b.rewards(i)[t] - 0.0)
                                })
                            })
                            .collect(),
                    );
                }
                for k in 0..pi.dim_w() {
                    comps.push(
                        (0..n)
                            .map(|i| {
                                (0..h).fold(0.0, |a, t| {
                                    a + b.score_w(i, t)[k] * (b.rewards(i)[t] - 0.0)
                                })
                            })
                            .collect(),
                    );
                }
                comps.iter().map(|c| Moments::from_samples(c)).collect()
            } else {
                want.iter().map(|c| Moments::from_samples(c)).collect()
            };
            let got: Vec<&Moments> = std::iter::once(&g.j)
                .chain(&g.grad_v)
                .chain(&g.grad_w)
                .collect();
            assert_eq!(got.len(), want.len());
            for (c, (a, b)) in got.iter().zip(&want).enumerate() {
                let close =
                    |x: f64, y: f64, scale: f64| abs_diff_eq!(x, y, epsilon = 1e-12 * scale);
                let sd = b.variance().sqrt();
                assert_eq!(a.count(), n as u64);
                assert!(
                    close(a.mean(), b.mean(), sd + b.mean().abs()),
                    "component {c}, pilot {pilot}: mean {} vs {}",
                    a.mean(),
                    b.mean()
                );
                assert!(
                    close(a.variance(), b.variance(), b.variance()),
                    "component {c}, pilot {pilot}: variance {} vs {}",
                    a.variance(),
                    b.variance()
                );
            }
            let steps: usize = rollout(&env, &pi, n, h, key).unwrap().steps();
            assert_eq!(g.steps, steps as u64);
        }
    }
}

#[test]
fn streamed_returns_equal_the_stored_returns() {
    let key = SeedKey::new(12, 1, 0);
    for (env, pi, n, h) in cases() {
        let n = n.min(2 * BLOCK + 3);
        let g = rollout_returns(&env, &pi, n, h, key).unwrap();
        let want = Moments::from_samples(&g);
        let (got, _) = stream_returns(&env, &pi, n, h, key).unwrap();
        let sd = want.variance().sqrt();
        assert_abs_diff_eq!(
            got.mean(),
            want.mean(),
            epsilon = 1e-12 * (sd + want.mean().abs())
        );
        assert_relative_eq!(got.variance(), want.variance(), max_relative = 1e-12);
    }
}

#[test]
fn merged_moments_equal_the_moments_of_the_whole_sample() {
    // Arbitrary splits of 10,000 values with a large common offset (where a naive Σx² formula
    // would lose every digit: ε·(10⁸)²/(1/12) ≈ 27): the merge agrees with the two-pass
    // moments of the whole set to the resolution of the data, ulp(10⁸)/sd ≈ 5·10⁻⁸ (observed
    // ≈ 2·10⁻⁹).
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(5);
    let x: Vec<f64> = (0..10_000)
        .map(|_| 1e8 + (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
        .collect();
    let whole = Moments::from_samples(&x);
    for _ in 0..20 {
        let mut merged = Moments::default();
        let mut start = 0;
        while start < x.len() {
            let len = 1 + (rng.next_u64() % 700) as usize;
            let end = (start + len).min(x.len());
            merged.merge(&Moments::from_samples(&x[start..end]));
            start = end;
        }
        assert_eq!(merged.count(), whole.count());
        assert_abs_diff_eq!(
            merged.mean(),
            whole.mean(),
            epsilon = 4.0 * f64::EPSILON * 1e8
        );
        assert_relative_eq!(merged.variance(), whole.variance(), max_relative = 1e-7);
    }
    // Uniform on [0, 1) + 1e8: variance 1/12 (sampling error ~ 1/12 · √(2/n)).
    assert_abs_diff_eq!(
        whole.variance(),
        1.0 / 12.0,
        epsilon = 5.0 * (1.0 / 12.0) * (2.0f64 / 1e4).sqrt()
    );
}

#[test]
fn streamed_gradients_agree_with_the_exact_clipped_oracle() {
    // N = 4·10⁵ trajectories of H = 20 (plus a 4096-trajectory pilot) at two points; 6
    // comparisons at family-wise false-alarm rate 10⁻³ (Bonferroni, two-sided): |mean − exact|
    // ≤ z·SE with z = Φ⁻¹(1 − 10⁻³/12) ≈ 3.76.
    let (n, h) = (400_000, 20);
    let z = Normal::standard().inverse_cdf(1.0 - 1e-3 / 12.0);
    let mut seeds = Xoshiro256PlusPlus::seed_from_u64(31);
    for (model, v, sigma) in [
        (LqgModel::thesis(), -0.6, 0.5f64),
        (LqgModel::lqg1d(), -0.3, 0.8),
    ] {
        let env = LqgEnv::new(model.clone()).unwrap();
        let pi = GaussianPolicy::scalar(v, sigma.ln()).unwrap();
        let exact = ClippedDpOracle::new(&model)
            .unwrap()
            .evaluate_policy(&pi, Horizon::Finite(h))
            .unwrap();
        let key = SeedKey::new(seeds.next_u64(), 0, 0);
        let g = stream_gradients(&env, &pi, n, h, key, 4096).unwrap();
        for (name, m, truth) in [
            ("J", &g.j, exact.j),
            ("∂_v J", &g.grad_v[0], exact.grad_v[0]),
            ("∂_w J", &g.grad_w[0], exact.grad_w[0]),
        ] {
            let dev = (m.mean() - truth) / m.std_error();
            println!(
                "{name} v={v} σ={sigma}: {} vs exact {truth} ({dev:+.2} SE)",
                m.mean()
            );
            assert!(dev.abs() <= z, "{name}: {} vs {truth}, {dev} SE", m.mean());
        }
    }
}
