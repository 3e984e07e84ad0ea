//! Certified safe steps against the `f64` steps they wrap, measured in the same run:
//! `cargo bench -p sepg-benches --bench certified`. The goal is a ratio ≤ 2
//! (certified / uncertified) for the steps SEPG takes: the exact v- and w-steps (Theorems 4.2,
//! 4.5), the sampled v-step (Theorem 4.7) and the default sampled w-step (the exploring
//! w-update). The last group measures what certification costs one SEPG iteration.
use criterion::{Criterion, criterion_group, criterion_main};
use sepg_algo::core::config::{Algorithm, Requirement, SepgConfig};
use sepg_algo::core::executor::Solver;
use sepg_algo::solver::PolicySolver;
use sepg_bounds::constants::TaskConstants;
use sepg_bounds::high_probability::{self as hp, HpForm};
use sepg_bounds::{exploring, v_update, w_update};
use sepg_certified as certified;
use sepg_mdp::env::Preset;
use std::hint::black_box;

fn steps(c: &mut Criterion) {
    let k = TaskConstants::new(0.99, 28.8, 4.0, 8.0).expect("lqg1d constants");
    // the certified steps decide the range of the rounding analysis once, as the uncertified
    // ones validate the constants once
    let task = certified::CertifiedTask::new(&k);
    let (sigma, grad, required) = (0.5, [-3.7], 0.0);
    let mut g = c.benchmark_group("v_step");
    g.bench_function("uncertified", |b| {
        b.iter(|| v_update::safe_step(&k, black_box(sigma), black_box(&grad), required))
    });
    g.bench_function("certified", |b| {
        b.iter(|| certified::v_safe_step(&task, black_box(sigma), black_box(&grad), required))
    });
    g.finish();
    let mut g = c.benchmark_group("w_step_along_l");
    g.bench_function("uncertified", |b| {
        b.iter(|| w_update::safe_step_along_l(&k, black_box(sigma), 0.3, black_box(-2.0), -0.1))
    });
    g.bench_function("certified", |b| {
        b.iter(|| {
            certified::w_safe_step_along_l(&task, black_box(sigma), 0.3, black_box(-2.0), -0.1)
        })
    });
    g.finish();
    let mut g = c.benchmark_group("hp_v_step");
    g.bench_function("uncertified", |b| {
        b.iter(|| {
            hp::v_safe_step(
                &k,
                black_box(sigma),
                black_box(&grad),
                0.4,
                required,
                HpForm::SignAware,
            )
        })
    });
    g.bench_function("certified", |b| {
        b.iter(|| {
            certified::hp_v_safe_step(
                &task,
                black_box(sigma),
                black_box(&grad),
                0.4,
                required,
                HpForm::SignAware,
            )
        })
    });
    g.finish();
    let mut g = c.benchmark_group("exploring_w_step");
    g.bench_function("uncertified", |b| {
        b.iter(|| {
            exploring::w_exploring_step(&k, black_box(sigma), -0.3, 0.1, black_box(0.4), -0.01)
        })
    });
    g.bench_function("certified", |b| {
        b.iter(|| {
            certified::exploring_safe_step(
                &task,
                black_box(sigma),
                -0.3,
                0.1,
                black_box(0.4),
                -0.01,
            )
        })
    });
    g.finish();
}

/// One sampled SEPG-ZV iteration on `lqg1d` (N = 100, H = 20) with and without certified
/// steps: the cost that matters for Table 5.1.
fn iteration(c: &mut Criterion) {
    let checked = SepgConfig::new(Preset::Lqg1d.build(), Algorithm::Sepg(Requirement::Zv))
        .check()
        .expect("valid configuration");
    let mut g = c.benchmark_group("sepg_zv_iteration");
    for (name, on) in [("uncertified", false), ("certified", true)] {
        let checked = checked.clone().with_certified_steps(on);
        let mut solver = PolicySolver::new(&checked).expect("solver");
        let start = checked.initial_state();
        let mut state = start.clone();
        g.bench_function(name, |b| {
            b.iter(|| {
                if state.iteration >= 1000 {
                    state = start.clone();
                }
                solver.next_iter(&mut state).expect("iteration")
            })
        });
    }
    g.finish();
}

criterion_group!(benches, steps, iteration);
criterion_main!(benches);
