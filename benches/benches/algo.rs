//! One sampled SEPG-ZV iteration on `lqg1d` with N = 100, H = 20 (three blocks: v, target, w),
//! and, in the same run, its two references: the fused loop (`sepg_benches::fused::lqg1d`)
//! over the same number of environment steps (100 trajectories of 20 steps at σ = 1 with their
//! G(PO)MDP sums), and the whole-iteration reference (`sepg_benches::fused::ZvIteration`: the
//! same iteration, the same bits, written as plain loops). Report the ratios iteration ÷
//! reference.
//!
//! Single-threaded figure: `RAYON_NUM_THREADS=1 cargo bench -p sepg-benches --bench algo`.
use criterion::{Criterion, criterion_group, criterion_main};
use sepg_algo::core::config::{Algorithm, Requirement, SepgConfig};
use sepg_algo::core::executor::Solver;
use sepg_algo::solver::PolicySolver;
use sepg_benches::fused;
use sepg_mdp::env::Preset;
use sepg_mdp::rng::SeedKey;
use std::hint::black_box;

fn sepg_zv_iteration(c: &mut Criterion) {
    let checked = SepgConfig::new(Preset::Lqg1d.build(), Algorithm::Sepg(Requirement::Zv))
        .check()
        .expect("valid configuration");
    let mut solver = PolicySolver::new(&checked).expect("solver");
    let start = checked.initial_state();
    let mut group = c.benchmark_group("sepg_zv_iteration_lqg1d_n100_h20");
    let zeros = [0.0; 20];
    let mut it = 0u64;
    // Run on a one-thread pool's own thread, so that the reference, like the iteration's
    // blocks of at most 64 trajectories, makes no round trip to a thread pool.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("thread pool");
    group.bench_function("fused_reference", |b| {
        pool.install(|| {
            b.iter(|| {
                it += 1;
                let key = SeedKey::new(1, it, 0);
                black_box(fused::lqg1d(-0.1, 1.0, 100, 20, key, &zeros, &zeros))
            })
        })
    });
    group.bench_function("whole_iteration_reference", |b| {
        let mut fused = fused::ZvIteration::new(&checked).expect("supported configuration");
        let mut state = start.clone();
        b.iter(|| {
            if state.iteration >= 1000 {
                state = start.clone();
            }
            fused.iterate(&mut state).expect("iteration")
        })
    });
    group.bench_function("iteration", |b| {
        let mut state = start.clone();
        b.iter(|| {
            // Restart periodically so the benchmark stays near the reproduction's start.
            if state.iteration >= 1000 {
                state = start.clone();
            }
            solver.next_iter(&mut state).expect("iteration")
        })
    });
    group.finish();
}

criterion_group!(benches, sepg_zv_iteration);
criterion_main!(benches);
