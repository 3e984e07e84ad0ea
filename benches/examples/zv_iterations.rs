//! Runs sampled SEPG-ZV iterations on `lqg1d` (N = 100, H = 20), the loop of the `algo`
//! criterion bench, for instruction-level profiling on a shared machine:
//!
//! ```text
//! RAYON_NUM_THREADS=1 valgrind --tool=callgrind target/release/examples/zv_iterations 2000
//! ```
//! (instruction counts are reproducible whatever the load). With `--fused` as second argument,
//! runs the whole-iteration reference (`sepg_benches::fused::ZvIteration`, the same bits)
//! instead; with `--rollout-only`, the rollout-only fused loop over the same 2,000 steps per
//! iteration (`sepg_benches::fused::lqg1d`, as in the bench). Prints the final state's `v` (or
//! the reference's last G(PO)MDP means).
//!
//! As whole processes, side by side (the ratio of CPU times is the figure to quote):
//!
//! ```text
//! RAYON_NUM_THREADS=1 target/release/examples/zv_iterations 200000
//! RAYON_NUM_THREADS=1 target/release/examples/zv_iterations 200000 --rollout-only
//! ```

use sepg_algo::core::config::{Algorithm, Requirement, SepgConfig};
use sepg_algo::core::executor::Solver;
use sepg_algo::solver::PolicySolver;
use sepg_benches::fused::ZvIteration;
use sepg_mdp::env::Preset;
use sepg_mdp::rng::SeedKey;

fn main() {
    let iterations: u64 = match std::env::args().nth(1).map(|a| a.parse()) {
        None => 1000,
        Some(Ok(k)) => k,
        Some(Err(_)) => {
            eprintln!("usage: zv_iterations [ITERATIONS [--fused | --rollout-only]]");
            std::process::exit(2);
        }
    };
    let checked = SepgConfig::new(Preset::Lqg1d.build(), Algorithm::Sepg(Requirement::Zv))
        .check()
        .expect("valid configuration");
    let mut state = checked.initial_state();
    let mode = std::env::args().nth(2);
    if mode.as_deref() == Some("--rollout-only") {
        let zeros = [0.0; 20];
        let mut last = [0.0; 3];
        for it in 1..=iterations {
            let key = SeedKey::new(1, it, 0);
            last = sepg_benches::fused::lqg1d(-0.1, 1.0, 100, 20, key, &zeros, &zeros).mean();
        }
        println!("means = {last:?}");
        return;
    }
    if mode.as_deref() == Some("--fused") {
        let mut fused = ZvIteration::new(&checked).expect("supported configuration");
        for _ in 0..iterations {
            fused.iterate(&mut state).expect("iteration");
        }
    } else {
        let mut solver = PolicySolver::new(&checked).expect("solver");
        for _ in 0..iterations {
            solver.next_iter(&mut state).expect("iteration");
        }
    }
    println!("v = {:?}", state.v);
}
