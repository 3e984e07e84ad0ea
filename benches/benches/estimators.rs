//! Cost of the estimators on a batch of N = 100 trajectories of H = 20 steps (m = 1 and m = 4
//! mean parameters), next to the cost of generating such a batch with the rollout engine.
//!
//! `w_block` is what one SEPG w-block computes from its batch: `Ĵ`, `∇̂_w J` and `∇̂_w L`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use sepg_estimators::{
    Baseline, BaselineFit, Estimate, Estimator, GradientSpec, Param, SurrogateEstimate, Width,
};
use sepg_mdp::Batch;
use sepg_mdp::env::LqgEnv;
use sepg_mdp::policy::GaussianPolicy;
use sepg_mdp::rng::SeedKey;
use sepg_mdp::rollout::{rollout, rollout_into};

const N: usize = 100;
const H: usize = 20;

/// A batch of `N × H` steps with `m` mean parameters and one action, filled with a fixed
/// smooth pattern (the cost of the estimators does not depend on the values).
fn synthetic(m: usize) -> Batch {
    let mut b = Batch::zeros(N, H, m, 1, 0.99);
    b.sigma[0] = 0.5;
    for (k, x) in b.disc_rewards.iter_mut().enumerate() {
        *x = -(1.0 + (k as f64 * 0.37).sin());
    }
    for (k, x) in b.cum_score_v.iter_mut().enumerate() {
        *x = (k as f64 * 0.11).cos();
    }
    for (k, x) in b.cum_score_w.iter_mut().enumerate() {
        *x = (k as f64 * 0.23).sin();
    }
    b
}

fn bench_estimators(c: &mut Criterion) {
    let env = LqgEnv::lqg1d();
    let policy = GaussianPolicy::scalar(-0.1, 0.0).expect("valid policy");
    let lqg_batch = rollout(&env, &policy, N, H, SeedKey::new(1, 0, 0)).expect("rollout");
    let mut reference = Batch::zeros(0, 0, 0, 0, 0.0);
    c.bench_function("reference/rollout_lqg1d_n100_h20", |bch| {
        bch.iter(|| {
            rollout_into(&env, &policy, N, H, SeedKey::new(1, 0, 0), &mut reference)
                .expect("rollout");
            black_box(&reference);
        })
    });

    for (label, batch) in [("m1", lqg_batch), ("m4", synthetic(4))] {
        let mut est = Estimator::new();
        let mut out = Estimate::new();
        let mut sur = SurrogateEstimate::new();
        let spec = GradientSpec::default();
        c.bench_function(
            &format!("estimators/{label}/grad_v_gpomdp_opt_loo"),
            |bch| {
                bch.iter(|| {
                    est.gradient(black_box(&batch), Param::V, spec, &mut out)
                        .expect("estimate");
                    black_box(out.mean()[0]);
                })
            },
        );
        c.bench_function(&format!("estimators/{label}/grad_v_plus_t_width"), |bch| {
            bch.iter(|| {
                est.gradient(black_box(&batch), Param::V, spec, &mut out)
                    .expect("estimate");
                black_box(out.confidence(Width::StudentT, 0.05).expect("width"));
            })
        });
        c.bench_function(
            &format!("estimators/{label}/grad_w_gpomdp_opt_loo"),
            |bch| {
                bch.iter(|| {
                    est.gradient(black_box(&batch), Param::W, spec, &mut out)
                        .expect("estimate");
                    black_box(out.mean()[0]);
                })
            },
        );
        c.bench_function(&format!("estimators/{label}/value"), |bch| {
            bch.iter(|| {
                est.value(black_box(&batch), &mut out).expect("estimate");
                black_box(out.mean()[0]);
            })
        });
        c.bench_function(&format!("estimators/{label}/grad_w_surrogate"), |bch| {
            bch.iter(|| {
                est.surrogate_gradient(black_box(&batch), spec, 2.0, &[-1.0], &mut sur)
                    .expect("estimate");
                black_box(sur.grad_w_l().mean()[0]);
            })
        });
        c.bench_function(&format!("estimators/{label}/h_opt_loo"), |bch| {
            bch.iter(|| {
                let (baseline, fit) = (Baseline::Optimal, BaselineFit::LeaveOneOut);
                est.h(black_box(&batch), baseline, fit, &mut out)
                    .expect("estimate");
                black_box(out.mean()[0]);
            })
        });
        let mut value = Estimate::new();
        c.bench_function(&format!("estimators/{label}/w_block"), |bch| {
            bch.iter(|| {
                let batch = black_box(&batch);
                est.value(batch, &mut value).expect("estimate");
                est.gradient(batch, Param::W, spec, &mut out)
                    .expect("estimate");
                est.surrogate_gradient(batch, spec, 2.0, &[-1.0], &mut sur)
                    .expect("estimate");
                black_box((value.mean()[0], out.mean()[0], sur.grad_w_l().mean()[0]));
            })
        });
    }
}

criterion_group!(benches, bench_estimators);
criterion_main!(benches);
