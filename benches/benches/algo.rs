//! One sampled SEPG-ZV iteration on `lqg1d` with N = 100, H = 20 (three blocks: v, target, w).
//!
//! Single-threaded figure: `RAYON_NUM_THREADS=1 cargo bench -p sepg-benches --bench algo`.
use criterion::{Criterion, criterion_group, criterion_main};
use sepg_algo::core::config::{Algorithm, Requirement, SepgConfig};
use sepg_algo::core::executor::Solver;
use sepg_algo::solver::PolicySolver;
use sepg_mdp::env::Preset;

fn sepg_zv_iteration(c: &mut Criterion) {
    let checked = SepgConfig::new(Preset::Lqg1d.build(), Algorithm::Sepg(Requirement::Zv))
        .check()
        .expect("valid configuration");
    let mut solver = PolicySolver::new(&checked).expect("solver");
    let start = checked.initial_state();
    c.bench_function("sepg_zv_iteration_lqg1d_n100_h20", |b| {
        let mut state = start.clone();
        b.iter(|| {
            // Restart periodically so the benchmark stays near the reproduction's start.
            if state.iteration >= 1000 {
                state = start.clone();
            }
            solver.next_iter(&mut state).expect("iteration")
        })
    });
}

criterion_group!(benches, sepg_zv_iteration);
criterion_main!(benches);
