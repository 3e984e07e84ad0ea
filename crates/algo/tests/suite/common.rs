//! Helpers shared by the integration tests.
use sepg_algo::core::config::{Algorithm, GradientMode, SepgConfig};
use sepg_algo::core::executor::{Collect, Executor};
use sepg_algo::core::options::SepgOptions;
use sepg_algo::core::record::Record;
use sepg_algo::core::state::State;
use sepg_algo::solver::PolicySolver;
use sepg_mdp::env::{AnyEnv, LqgEnv};

/// v* of both LQG presets, (1 − √(1 + 4γ²)) / (2γ) with γ = 0.99 (docs/CONVENTIONS.md §1).
pub fn v_star() -> f64 {
    let g: f64 = 0.99;
    (1.0 - (1.0 + 4.0 * g * g).sqrt()) / (2.0 * g)
}

/// `lqg` (clipped) or its unclipped twin.
pub fn lqg(clipped: bool) -> AnyEnv {
    let e = LqgEnv::thesis();
    if clipped {
        AnyEnv::Lqg(Box::new(e))
    } else {
        AnyEnv::Lqg(Box::new(
            LqgEnv::new(e.model().clone().with_clipping(false)).expect("valid model"),
        ))
    }
}

/// `lqg1d` (clipped) or its unclipped twin.
pub fn lqg1d(clipped: bool) -> AnyEnv {
    let e = LqgEnv::lqg1d();
    if clipped {
        AnyEnv::Lqg(Box::new(e))
    } else {
        AnyEnv::Lqg(Box::new(
            LqgEnv::new(e.model().clone().with_clipping(false)).expect("valid model"),
        ))
    }
}

/// An exact-gradient configuration with σ⁰ and v⁰ = −0.1, with the thesis's bookkeeping
/// (`SepgOptions::estimated`), whose budget is Definition 4.3's.
pub fn exact(env: AnyEnv, algorithm: Algorithm, sigma0: f64) -> SepgConfig {
    SepgConfig {
        gradient: GradientMode::Exact,
        sigma0: vec![sigma0],
        options: SepgOptions::estimated(),
        ..SepgConfig::new(env, algorithm)
    }
}

/// `cfg` with the thesis's bookkeeping (`SepgOptions::estimated`).
pub fn estimated(cfg: SepgConfig) -> SepgConfig {
    SepgConfig {
        options: SepgOptions::estimated(),
        ..cfg
    }
}

/// Runs `iterations` iterations and returns the records and the final state.
pub fn run(cfg: SepgConfig, iterations: u64) -> (Vec<Record>, State) {
    let checked = cfg.check().expect("valid configuration");
    let solver = PolicySolver::new(&checked).expect("solver");
    let mut log = Collect::default();
    let mut exec = Executor::new(solver, checked.initial_state()).observe(&mut log);
    exec.run(iterations).expect("run");
    let (_, state) = exec.into_parts();
    (log.records, state)
}
