//! The adaptive batch size against the fixed one on `lqg1d` (docs/REPRODUCTION.md "An adaptive
//! batch size under the proven widths"): sampled SEPG with the tight constants, the certified
//! accounting and the proven widths, from v⁰ = −0.1, within the trajectory budget of Table 5.1
//! (10,000 iterations of N = 100; an adaptive run's last iteration takes what is left of it).
//! Each run reports the trajectories it used, |v − v*| at its
//! end, its v-steps and its exact violations: steps whose exact change of J (clipped dynamic
//! programme at the audit's resolution) falls short of the logged guarantee by more than the
//! audit's tolerance 1e-12·max(1, |J|).
//!
//! ```sh
//! cargo run --release -p sepg-algo --example adaptive_batch            # 5 seeds
//! cargo run --release -p sepg-algo --example adaptive_batch -- 10      # 10 seeds
//! ```
use std::collections::HashMap;

use sepg_algo::core::config::{Algorithm, Requirement, SepgConfig, reward_sign};
use sepg_algo::core::executor::Solver;
use sepg_algo::core::options::{BatchRule, ConstantsFamily};
use sepg_algo::core::record::Record;
use sepg_algo::solver::PolicySolver;
use sepg_mdp::env::{AnyEnv, Preset};
use sepg_mdp::oracle::{
    ClippedDpOracle, ClosedFormOracle, DpConfig, ExactOracle, Exploration, Horizon, Needs,
};

/// Table 5.1's trajectory budget: 10,000 iterations of N = 100.
const BUDGET: u64 = 1_000_000;
/// Table 5.1's iterations: the union bound spreads δ over them (δ/(T·K) = 1e-5 for MI), and
/// no run makes more (a block never has fewer than the fixed rule's 50 trajectories).
const ITERATIONS: u64 = 10_000;
/// The audit's relative tolerance on exact differences of J.
const TOLERANCE: f64 = 1e-12;

/// Exact J of `lqg1d` at the audit's resolution, cached by the bits of (v, w).
struct Exact {
    oracle: ClippedDpOracle,
    cache: HashMap<(u64, u64), f64>,
}

impl Exact {
    fn j(&mut self, v: f64, w: f64) -> f64 {
        let oracle = &self.oracle;
        *self
            .cache
            .entry((v.to_bits(), w.to_bits()))
            .or_insert_with(|| {
                let ex = Exploration::Gaussian { w: vec![w] };
                oracle
                    .evaluate_with(&[v], &ex, Horizon::Finite(20), Needs::VALUE)
                    .expect("exact J of lqg1d")
                    .j
            })
    }
}

/// What one run did.
struct Outcome {
    trajectories: u64,
    error: f64,
    sigma: f64,
    v_steps: usize,
    steps_checked: usize,
    violations: usize,
    last_block: usize,
}

/// One run of `req` from σ⁰ = `sigma0` under the rule `batch`; with the adaptive rule, every
/// block size it chooses is multiplied by `scale` (then clamped to the rule's range again), which
/// turns Proposition B's n* = 4b̂²/ĝ² into scale·4b̂²/ĝ² (docs/THEOREMS.md, "Which step").
fn run(
    req: Requirement,
    sigma0: f64,
    (batch, scale): (BatchRule, f64),
    seed: u64,
    exact: &mut Exact,
    v_star: f64,
) -> Outcome {
    let env = Preset::Lqg1d.build();
    let mut cfg = SepgConfig::new(env.clone(), Algorithm::Sepg(req));
    cfg.sigma0 = vec![sigma0];
    cfg.seed = seed;
    cfg.iterations = ITERATIONS;
    cfg.options.constants = ConstantsFamily::Tight {
        rewards: reward_sign(&env),
    };
    let checked = cfg.check().expect("valid configuration");
    let mut state = checked.initial_state();
    let mut solver = PolicySolver::new(&checked)
        .and_then(|s| s.with_batch_rule(batch))
        .expect("solver");
    solver.init(&mut state).expect("init");
    let blocks = req.blocks() as u64;
    let mut records: Vec<Record> = Vec::new();
    let mut last_block = 50;
    while state.iteration < ITERATIONS {
        // the trajectories of the next iteration: N = 100 split, or the adaptive block size
        // times the blocks
        let mut next = state.next_batch.map_or(100, |m| m as u64 * blocks);
        if state.trajectories + next > BUDGET {
            // the last iteration takes what is left of the budget when that still gives every
            // block n_min (a choice made from the past, as Proposition U allows)
            let left = (BUDGET - state.trajectories) / blocks;
            match (state.next_batch.as_mut(), batch) {
                (Some(m), BatchRule::Adaptive { n_min, .. }) if left >= n_min as u64 => {
                    *m = left as usize;
                    next = left * blocks;
                }
                _ => break,
            }
        }
        last_block = (next / blocks) as usize;
        records.push(solver.next_iter(&mut state).expect("iteration"));
        if let (Some(m), BatchRule::Adaptive { n_min, n_max }) = (state.next_batch.as_mut(), batch)
        {
            *m = ((*m as f64 * scale).round() as usize).clamp(n_min, n_max);
        }
    }
    let final_point = (state.v[0], state.w[0]);
    let (v_steps, steps_checked, violations) = audit(&records, final_point, exact);
    Outcome {
        trajectories: state.trajectories,
        error: (state.v[0] - v_star).abs(),
        sigma: state.w[0].exp(),
        v_steps,
        steps_checked,
        violations,
        last_block,
    }
}

/// The v-steps of a run's `records` (ending at `final_point`), the steps with a change that were
/// checked against exact J, and the exact violations among them.
fn audit(records: &[Record], final_point: (f64, f64), exact: &mut Exact) -> (usize, usize, usize) {
    let (mut v_steps, mut steps_checked, mut violations) = (0, 0, 0);
    for r in records {
        let (v0, w0) = (r.v[0], r.w[0]);
        let next = records
            .get(r.iteration as usize + 1)
            .map_or(final_point, |n| (n.v[0], n.w[0]));
        v_steps += usize::from(next.0 != v0);
        // the v-step (vᵗ, wᵗ) → (vᵗ⁺¹, wᵗ), then the w-step → (vᵗ⁺¹, wᵗ⁺¹), each against its
        // logged guarantee (0 when no change was made)
        for ((a, b), g) in [
            (((v0, w0), (next.0, w0)), r.guaranteed_v),
            (((next.0, w0), next), r.guaranteed_w),
        ] {
            if a == b {
                continue;
            }
            steps_checked += 1;
            let (ja, jb) = (exact.j(a.0, a.1), exact.j(b.0, b.1));
            let tol = TOLERANCE * ja.abs().max(1.0);
            if jb - ja < g.unwrap_or(0.0) - tol {
                violations += 1;
            }
        }
    }
    (v_steps, steps_checked, violations)
}

fn main() {
    let seeds: u64 = std::env::args()
        .nth(1)
        .map_or(5, |s| s.parse().expect("a number of seeds"));
    let AnyEnv::Lqg(env) = Preset::Lqg1d.build() else {
        unreachable!("lqg1d is an LQG")
    };
    let model = env.model();
    let v_star = ClosedFormOracle::new(model)
        .and_then(|o| o.optimal_gain())
        .expect("v*")
        .v[0];
    let config = DpConfig {
        nodes_per_element: 14,
        ..DpConfig::default()
    };
    let mut exact = Exact {
        oracle: ClippedDpOracle::with_config(model, config).expect("clipped DP"),
        cache: HashMap::new(),
    };
    println!(
        "| σ⁰ | variant | batch | trajectories (min–max) | |v − v*| (min–max) | final σ (min–max) | v-steps | last block | exact violations / steps checked |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for sigma0 in [1.0, 0.5] {
        for (name, req) in [("MI", Requirement::Mi), ("ZV", Requirement::Zv)] {
            let n_max = (BUDGET / req.blocks() as u64 / 2) as usize;
            let adaptive = BatchRule::Adaptive { n_min: 50, n_max };
            for (label, rule) in [
                ("fixed N = 100".to_owned(), (BatchRule::Fixed, 1.0)),
                (format!("adaptive 4b²/g², [50, {n_max}]"), (adaptive, 1.0)),
                (
                    format!("adaptive (3+2√2)b²/g², [50, {n_max}]"),
                    (adaptive, (3.0 + 2.0 * 2f64.sqrt()) / 4.0),
                ),
                (
                    format!("adaptive (13+3√17)/2·b²/g², [50, {n_max}]"),
                    (adaptive, (13.0 + 3.0 * 17f64.sqrt()) / 8.0),
                ),
            ] {
                let outs: Vec<Outcome> = (0..seeds)
                    .map(|s| run(req, sigma0, rule, s, &mut exact, v_star))
                    .collect();
                let range = |f: &dyn Fn(&Outcome) -> f64| {
                    let lo = outs.iter().map(f).fold(f64::INFINITY, f64::min);
                    let hi = outs.iter().map(f).fold(f64::NEG_INFINITY, f64::max);
                    (lo, hi)
                };
                let (t_lo, t_hi) = range(&|o| o.trajectories as f64);
                let (e_lo, e_hi) = range(&|o| o.error);
                let (g_lo, g_hi) = range(&|o| o.sigma);
                let (s_lo, s_hi) = range(&|o| o.v_steps as f64);
                let (b_lo, b_hi) = range(&|o| o.last_block as f64);
                let viol: usize = outs.iter().map(|o| o.violations).sum();
                let checked: usize = outs.iter().map(|o| o.steps_checked).sum();
                println!(
                    "| {sigma0} | {name} | {label} | {t_lo}–{t_hi} | {e_lo:.5}–{e_hi:.5} | {g_lo:.4}–{g_hi:.4} | {s_lo}–{s_hi} | {b_lo}–{b_hi} | {viol} / {checked} |"
                );
            }
        }
    }
}
