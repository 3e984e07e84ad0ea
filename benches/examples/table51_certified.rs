//! Runs every lqg1d run of `sepg reproduce table-5.1` (the same resolved runs: variants, seeds,
//! δ, logging) one after another, with certified steps on (the default) or off, for measuring
//! what certification costs the table in CPU time:
//!
//! ```text
//! /usr/bin/time -f "%U %S" target/release/examples/table51_certified on  OUT_DIR [ITERATIONS] [SEEDS]
//! /usr/bin/time -f "%U %S" target/release/examples/table51_certified off OUT_DIR [ITERATIONS] [SEEDS]
//! ```
//!
//! The command line of `sepg reproduce` has no switch for certified steps, so this example
//! changes only that option of each resolved run (`CheckedConfig::with_certified_steps`); the
//! written `config.toml` files do not record it. ITERATIONS defaults to the table's 10,000,
//! SEEDS to its 10. OUT_DIR must not exist.
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

use sepg_runs::reproduce::{Experiment, LqgPreset, ReproduceOptions, sweep_spec};
use sepg_runs::run::{self, RunOptions, Silent};
use sepg_runs::sweep::{self, Shard};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (certified, out) = match (args.get(1).map(String::as_str), args.get(2)) {
        (Some("on"), Some(out)) => (true, PathBuf::from(out)),
        (Some("off"), Some(out)) => (false, PathBuf::from(out)),
        _ => {
            eprintln!("usage: table51_certified on|off OUT_DIR [ITERATIONS] [SEEDS]");
            std::process::exit(2);
        }
    };
    let number = |i: usize, default: u64| args.get(i).map_or(default, |a| a.parse().unwrap_or(0));
    let opts = ReproduceOptions {
        preset: Some(LqgPreset::Lqg1d),
        iterations: Some(number(3, 10_000)),
        seeds: number(4, 10),
        ..ReproduceOptions::new(Experiment::Table51)
    };
    let spec = sweep_spec(&opts).expect("valid reproduction options");
    let (_, resolved) = sweep::expand(&spec, Shard { index: 0, count: 1 }).expect("sweep");
    let stop = AtomicBool::new(false);
    for (i, mut r) in resolved.into_iter().enumerate() {
        r.checked = r.checked.with_certified_steps(certified);
        let options = RunOptions {
            checkpoint_every: 1_000,
            stop: &stop,
            observer: &Silent,
        };
        run::start(&out.join(format!("run-{i:03}")), &r, options).expect("run");
    }
}
