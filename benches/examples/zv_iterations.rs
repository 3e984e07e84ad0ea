//! Runs sampled SEPG-ZV iterations on `lqg1d` (N = 100, H = 20), the loop of the `algo`
//! criterion bench, for instruction-level profiling on a shared machine:
//!
//! ```text
//! RAYON_NUM_THREADS=1 valgrind --tool=callgrind target/release/examples/zv_iterations 2000
//! ```
//! (instruction counts are reproducible whatever the load). With `--fused` as second argument,
//! runs the whole-iteration reference (`sepg_benches::fused::ZvIteration`, the same bits)
//! instead. Prints the final state's `v`.

use sepg_algo::core::config::{Algorithm, Requirement, SepgConfig};
use sepg_algo::core::executor::Solver;
use sepg_algo::solver::PolicySolver;
use sepg_benches::fused::ZvIteration;
use sepg_mdp::env::Preset;

fn main() {
    let iterations: u64 = match std::env::args().nth(1).map(|a| a.parse()) {
        None => 1000,
        Some(Ok(k)) => k,
        Some(Err(_)) => {
            eprintln!("usage: zv_iterations [ITERATIONS [--fused]]");
            std::process::exit(2);
        }
    };
    let checked = SepgConfig::new(Preset::Lqg1d.build(), Algorithm::Sepg(Requirement::Zv))
        .check()
        .expect("valid configuration");
    let mut state = checked.initial_state();
    if std::env::args().nth(2).as_deref() == Some("--fused") {
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
