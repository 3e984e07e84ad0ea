//! Streamed Monte Carlo (`sepg_mdp::monte_carlo::stream_gradients`, what `sepg estimate`
//! runs) against the fused-loop references of `sepg_benches::fused`, side by side in one run:
//! the ratio of their throughputs (environment steps per second) is the figure to report.
//!
//! `cargo bench -p sepg-benches --bench stream` (add `RAYON_NUM_THREADS=1` for one thread).

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use sepg_benches::fused;
use sepg_mdp::{
    Batch, Environment, LqgEnv, MountainCar,
    monte_carlo::{DEFAULT_PILOT, stream_gradients},
    policy::GaussianPolicy,
    rng::SeedKey,
    rollout::rollout_into,
};
use std::hint::black_box;

/// One benchmark group `name` of `n` trajectories of `h` steps (throughput in environment
/// steps): the fused reference `reference(key)`, `stream_gradients` with `pilot` baseline
/// trajectories and, if `batch`, scored rollouts into a `Batch`. Every call draws a new key.
#[allow(clippy::too_many_arguments)]
fn side_by_side<E: Environment, R>(
    c: &mut Criterion,
    name: &str,
    env: &E,
    pi: &GaussianPolicy,
    (n, h): (usize, usize),
    pilot: usize,
    reference: impl Fn(SeedKey) -> R,
    batch: bool,
) {
    let mut group = c.benchmark_group(name);
    group.throughput(Throughput::Elements((n * h) as u64));
    group.sample_size(20);
    let size = format!("N{n}_H{h}");
    let mut it = 0u64;
    let mut key = || {
        it += 1;
        SeedKey::new(1, it, 0)
    };
    group.bench_function(BenchmarkId::new("fused_reference", &size), |b| {
        b.iter(|| black_box(reference(key())))
    });
    group.bench_function(BenchmarkId::new("stream_gradients", &size), |b| {
        b.iter(|| black_box(stream_gradients(env, pi, n, h, key(), pilot).expect("valid rollout")))
    });
    if batch {
        let mut out = Batch::zeros(0, 0, 0, 0, 0.0);
        group.bench_function(BenchmarkId::new("rollout_batch", &size), |b| {
            b.iter(|| {
                rollout_into(env, pi, n, h, key(), &mut out).expect("valid rollout");
                black_box(&out);
            })
        });
    }
    group.finish();
}

fn lqg1d(c: &mut Criterion) {
    let (v, sigma) = (-0.3, 0.5);
    let pi = GaussianPolicy::scalar(v, f64::ln(sigma)).expect("valid policy");
    let (n, h) = (200_000usize, 20usize);
    let zeros = vec![0.0; h];
    let reference = |key| fused::lqg1d(v, sigma, n, h, key, &zeros, &zeros);
    let env = LqgEnv::lqg1d();
    side_by_side(
        c,
        "stream/lqg1d",
        &env,
        &pi,
        (n, h),
        DEFAULT_PILOT,
        reference,
        false,
    );
}

fn mountain_car(c: &mut Criterion) {
    let (v, sigma) = ([0.0, 0.0, 0.0], 0.2);
    let pi = GaussianPolicy::new(v.to_vec(), vec![f64::ln(sigma)], 3).expect("valid policy");
    let (n, h) = (200usize, 999usize);
    let (zv, zw) = (vec![0.0; 3 * h], vec![0.0; h]);
    let reference = |key| fused::mountain_car(v, sigma, n, h, key, &zv, &zw);
    let env = MountainCar::state_bias();
    side_by_side(
        c,
        "stream/mountain-car",
        &env,
        &pi,
        (n, h),
        0,
        reference,
        true,
    );
}

criterion_group!(benches, lqg1d, mountain_car);
criterion_main!(benches);
