//! Streamed Monte Carlo (`sepg_mdp::monte_carlo::stream_gradients`, what `sepg estimate`
//! runs) against the fused-loop references of `sepg_benches::fused`, side by side in one run:
//! the ratio of their throughputs (environment steps per second) is the figure to report.
//!
//! `cargo bench -p sepg-benches --bench stream` (add `RAYON_NUM_THREADS=1` for one thread).

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use sepg_benches::fused;
use sepg_mdp::{
    Batch, LqgEnv, MountainCar,
    monte_carlo::{DEFAULT_PILOT, stream_gradients},
    policy::GaussianPolicy,
    rng::SeedKey,
    rollout::rollout_into,
};
use std::hint::black_box;

fn lqg1d(c: &mut Criterion) {
    let env = LqgEnv::lqg1d();
    let (v, sigma) = (-0.3, 0.5);
    let pi = GaussianPolicy::scalar(v, f64::ln(sigma)).expect("valid policy");
    let (n, h) = (200_000usize, 20usize);
    let zeros = vec![0.0; h];
    let mut group = c.benchmark_group("stream/lqg1d");
    group.throughput(Throughput::Elements((n * h) as u64));
    group.sample_size(20);
    let mut it = 0u64;
    group.bench_function(
        BenchmarkId::new("fused_reference", format!("N{n}_H{h}")),
        |b| {
            b.iter(|| {
                it += 1;
                black_box(fused::lqg1d(
                    v,
                    sigma,
                    n,
                    h,
                    SeedKey::new(1, it, 0),
                    &zeros,
                    &zeros,
                ))
            })
        },
    );
    group.bench_function(
        BenchmarkId::new("stream_gradients", format!("N{n}_H{h}")),
        |b| {
            b.iter(|| {
                it += 1;
                black_box(
                    stream_gradients(&env, &pi, n, h, SeedKey::new(1, it, 0), DEFAULT_PILOT)
                        .expect("valid rollout"),
                )
            })
        },
    );
    group.finish();
}

fn mountain_car(c: &mut Criterion) {
    let env = MountainCar::state_bias();
    let (v, sigma) = ([0.0, 0.0, 0.0], 0.2);
    let pi = GaussianPolicy::new(v.to_vec(), vec![f64::ln(sigma)], 3).expect("valid policy");
    let (n, h) = (200usize, 999usize);
    let (zv, zw) = (vec![0.0; 3 * h], vec![0.0; h]);
    let mut group = c.benchmark_group("stream/mountain-car");
    group.throughput(Throughput::Elements((n * h) as u64));
    group.sample_size(20);
    let mut it = 0u64;
    group.bench_function(
        BenchmarkId::new("fused_reference", format!("N{n}_H{h}")),
        |b| {
            b.iter(|| {
                it += 1;
                black_box(fused::mountain_car(
                    v,
                    sigma,
                    n,
                    h,
                    SeedKey::new(1, it, 0),
                    &zv,
                    &zw,
                ))
            })
        },
    );
    group.bench_function(
        BenchmarkId::new("stream_gradients", format!("N{n}_H{h}")),
        |b| {
            b.iter(|| {
                it += 1;
                black_box(
                    stream_gradients(&env, &pi, n, h, SeedKey::new(1, it, 0), 0)
                        .expect("valid rollout"),
                )
            })
        },
    );
    let mut batch = Batch::zeros(0, 0, 0, 0, 0.0);
    group.bench_function(
        BenchmarkId::new("rollout_batch", format!("N{n}_H{h}")),
        |b| {
            b.iter(|| {
                it += 1;
                rollout_into(&env, &pi, n, h, SeedKey::new(1, it, 0), &mut batch)
                    .expect("valid rollout");
                black_box(&batch);
            })
        },
    );
    group.finish();
}

criterion_group!(benches, lqg1d, mountain_car);
criterion_main!(benches);
