//! Same configuration and seed ⇒ identical records, for any thread count and across a
//! checkpoint/resume.
use sepg_algo::core::config::{Algorithm, Requirement, SepgConfig};
use sepg_algo::core::executor::{Collect, Executor};
use sepg_algo::core::state::State;
use sepg_algo::solver::PolicySolver;

use crate::suite::common::{lqg1d, run};

fn cfg(alg: Algorithm) -> SepgConfig {
    SepgConfig {
        seed: 42,
        // Several rollout chunks of 64 trajectories per block, so threads really split work.
        n_trajectories: 300,
        ..SepgConfig::new(lqg1d(true), alg)
    }
}

#[test]
fn records_do_not_depend_on_thread_count() {
    for alg in [
        Algorithm::Sepg(Requirement::Zv),
        Algorithm::Sepg(Requirement::Sim { nu: 0.5 }),
        Algorithm::adam(1e-3, 1e-3),
    ] {
        let in_pool = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool")
                .install(|| run(cfg(alg), 25))
        };
        let (r1, s1) = in_pool(1);
        let (r2, s2) = in_pool(2);
        assert_eq!(r1, r2, "{alg:?}");
        assert_eq!(s1, s2, "{alg:?}");
    }
}

#[test]
fn resuming_from_a_serialised_checkpoint_is_bit_identical() {
    for alg in [
        Algorithm::Sepg(Requirement::Lv),
        Algorithm::adam(1e-3, 1e-3),
    ] {
        let (straight, end) = run(cfg(alg), 20);
        let checked = cfg(alg).check().expect("valid");
        let mut first = Collect::default();
        let mut exec = Executor::new(
            PolicySolver::new(&checked).expect("solver"),
            checked.initial_state(),
        )
        .observe(&mut first);
        exec.run(12).expect("run");
        let json = serde_json::to_string(exec.state()).expect("serialise");
        drop(exec);
        let restored: State = serde_json::from_str(&json).expect("deserialise");
        let mut second = Collect::default();
        let mut exec = Executor::new(PolicySolver::new(&checked).expect("solver"), restored)
            .observe(&mut second);
        exec.run(8).expect("run");
        let resumed_end = exec.state().clone();
        drop(exec);
        let mut joined = first.records;
        joined.extend(second.records);
        assert_eq!(joined, straight, "{alg:?}");
        assert_eq!(resumed_end, end, "{alg:?}");
    }
}

#[test]
fn different_seeds_give_different_runs() {
    let (a, _) = run(cfg(Algorithm::Sepg(Requirement::Zv)), 3);
    let (b, _) = run(
        SepgConfig {
            seed: 43,
            ..cfg(Algorithm::Sepg(Requirement::Zv))
        },
        3,
    );
    assert_ne!(a[0].j_exploratory, b[0].j_exploratory);
}
