//! Rollout throughput: scored rollouts (the estimator input) and returns-only rollouts on the
//! `lqg1d` preset, one SEPG-sized batch (N = 100, H = 20) and a large batch (N = 100 000,
//! H = 20), plus Mountain Car on the generic kernel. Throughput is in environment steps.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use sepg_mdp::{
    Batch, LqgEnv, MountainCar,
    policy::GaussianPolicy,
    rng::SeedKey,
    rollout::{rollout_into, rollout_returns_into},
};
use std::hint::black_box;

fn lqg1d(c: &mut Criterion) {
    let env = LqgEnv::lqg1d();
    let pi = GaussianPolicy::scalar(-0.1, 0.0).expect("valid policy");
    let mut group = c.benchmark_group("rollout/lqg1d");
    for &(n, h) in &[(100usize, 20usize), (100_000, 20)] {
        let steps = (n * h) as u64;
        group.throughput(Throughput::Elements(steps));
        let mut batch = Batch::zeros(0, 0, 0, 0, 0.0);
        let mut it = 0u64;
        group.bench_with_input(
            BenchmarkId::new("scores", format!("N{n}_H{h}")),
            &n,
            |b, &n| {
                b.iter(|| {
                    it += 1;
                    rollout_into(&env, &pi, n, h, SeedKey::new(1, it, 0), &mut batch)
                        .expect("valid rollout");
                    black_box(&batch);
                })
            },
        );
        let mut returns = Vec::new();
        group.bench_with_input(
            BenchmarkId::new("returns", format!("N{n}_H{h}")),
            &n,
            |b, &n| {
                b.iter(|| {
                    it += 1;
                    rollout_returns_into(&env, &pi, n, h, SeedKey::new(1, it, 0), &mut returns)
                        .expect("valid rollout");
                    black_box(&returns);
                })
            },
        );
    }
    group.finish();
}

fn mountain_car(c: &mut Criterion) {
    let env = MountainCar::state_bias();
    let pi = GaussianPolicy::new(vec![0.0, 0.0, 0.0], vec![0.2f64.ln()], 3).expect("valid policy");
    let (n, h) = (100usize, 999usize);
    let mut group = c.benchmark_group("rollout/mountain-car");
    group.throughput(Throughput::Elements((n * h) as u64));
    group.sample_size(20);
    let mut batch = Batch::zeros(0, 0, 0, 0, 0.0);
    let mut it = 0u64;
    group.bench_function(BenchmarkId::new("scores", format!("N{n}_H{h}")), |b| {
        b.iter(|| {
            it += 1;
            rollout_into(&env, &pi, n, h, SeedKey::new(1, it, 0), &mut batch)
                .expect("valid rollout");
            black_box(&batch);
        })
    });
    group.finish();
}

criterion_group!(benches, lqg1d, mountain_car);
criterion_main!(benches);
