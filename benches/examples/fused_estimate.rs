//! The fused-loop reference of `sepg estimate --env lqg1d` as a whole process, for a
//! process-level comparison (`scripts/perf-estimate.sh`):
//!
//! ```text
//! fused_estimate N H V SIGMA SEED
//! ```
//! prints the means of `J`, `∂J/∂v`, `∂J/∂w` (no baseline) and the number of steps.

use sepg_benches::fused;
use sepg_mdp::rng::SeedKey;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let parsed = (|| -> Option<(usize, usize, f64, f64, u64)> {
        match args.as_slice() {
            [n, h, v, s, seed] => Some((
                n.parse().ok()?,
                h.parse().ok()?,
                v.parse().ok()?,
                s.parse().ok()?,
                seed.parse().ok()?,
            )),
            _ => None,
        }
    })();
    let Some((n, h, v, sigma, seed)) = parsed else {
        eprintln!("usage: fused_estimate N H V SIGMA SEED");
        std::process::exit(2);
    };
    let zeros = vec![0.0; h];
    let s = fused::lqg1d(v, sigma, n, h, SeedKey::new(seed, 0, 0), &zeros, &zeros);
    let [j, gv, gw] = s.mean();
    println!(
        "j {j:.10e} grad_v {gv:.10e} grad_w {gw:.10e} steps {}",
        s.steps
    );
}
