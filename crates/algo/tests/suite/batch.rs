//! The adaptive batch size (`BatchRule::Adaptive`, docs/THEOREMS.md "An adaptive batch
//! size"): the rule against an independent maximisation of the guaranteed improvement per
//! trajectory, its range, and its use by the sampled SEPG solver.
use sepg_algo::core::config::{Algorithm, CheckedConfig, Requirement, SepgConfig};
use sepg_algo::core::error::ConfigError;
use sepg_algo::core::executor::{Collect, Executor};
use sepg_algo::core::options::{Accounting, BatchRule, Confidence, SepgOptions};
use sepg_algo::core::state::State;
use sepg_algo::solver::PolicySolver;
use sepg_algo::solver::batch::{improvement_per_trajectory, next_batch, optimal_batch};
use sepg_algo::solver::source::Grad;

use crate::suite::common::lqg1d;

/// G(m)·4c = max(0, g − b/√m)²/m, written out here rather than taken from the crate.
fn per_trajectory(g: f64, b: f64, m: usize) -> f64 {
    let slack = g - b / (m as f64).sqrt();
    if slack <= 0.0 {
        0.0
    } else {
        slack * slack / m as f64
    }
}

/// The cases of the brute-force comparison: every combination of ĝ, the width at n, n and the
/// range, from a gradient far below its width to one far above, ranges below, around and
/// above the optimum.
fn cases() -> Vec<(f64, f64, usize, usize, usize)> {
    let mut out = Vec::new();
    for g in [0.01, 0.7, 266.0, 3.0e4] {
        for ratio in [0.001, 0.05, 0.5, 1.0, 3.0, 22.5, 160.0] {
            for n in [2usize, 50, 333, 4096] {
                for (n_min, n_max) in [(1, 1), (2, 40), (7, 3000), (50, 20_000), (900, 901)] {
                    out.push((g, ratio * g, n, n_min, n_max));
                }
            }
        }
    }
    out
}

#[test]
fn next_batch_maximises_the_guaranteed_improvement_per_trajectory_over_its_range() {
    for (g, eps, n, n_min, n_max) in cases() {
        let grad = Grad {
            value: vec![-g, 0.25 * g],
            eps: vec![eps, 0.5 * eps],
        };
        let chosen = next_batch(&grad, n, n_min, n_max).expect("valid inputs");
        assert!(
            (n_min..=n_max).contains(&chosen),
            "{chosen} outside [{n_min}, {n_max}]"
        );
        // b = max ε · √n; the step's gradient is the largest |ĝ_k| = g
        let b = eps * (n as f64).sqrt();
        let best = (n_min..=n_max)
            .map(|m| per_trajectory(g, b, m))
            .fold(0.0f64, f64::max);
        let got = per_trajectory(g, b, chosen);
        // the two evaluations of one formula agree to rounding: a relative 1e-12
        assert!(
            got >= best * (1.0 - 1e-12),
            "g {g}, ε {eps}, n {n}, [{n_min}, {n_max}]: chose {chosen} with {got}, best {best}"
        );
    }
}

#[test]
fn the_real_maximiser_is_four_b_squared_over_g_squared() {
    // golden-section search of G over ln n, independent of the closed form
    for (g, b) in [(266.0, 42_400.0), (1.0, 1.0), (0.3, 17.0), (5.0, 20.0)] {
        let f = |ln_n: f64| {
            let n = ln_n.exp();
            let s = (g - b / n.sqrt()).max(0.0);
            s * s / n
        };
        // G > 0 beyond (b/g)², so the maximum lies in [(b/g)², 100 (b/g)²]
        let (mut lo, mut hi) = (2.0 * (b / g).ln(), 2.0 * (b / g).ln() + 100f64.ln());
        let phi = (5f64.sqrt() - 1.0) / 2.0;
        for _ in 0..200 {
            let (x1, x2) = (hi - phi * (hi - lo), lo + phi * (hi - lo));
            if f(x1) < f(x2) {
                lo = x1;
            } else {
                hi = x2;
            }
        }
        let numeric = (0.5 * (lo + hi)).exp();
        let closed = optimal_batch(g, b).expect("valid").expect("g > 0");
        // the search brackets ln n* to 1e-9; the flat top costs a relative 1e-6 or so
        assert!(
            (numeric / closed - 1.0).abs() < 1e-5,
            "g {g}, b {b}: numeric {numeric}, closed form {closed}"
        );
        // at n* the width b/√n* is g/2 and G·4c = g⁴/(16 b²)
        let at = improvement_per_trajectory(g, b, 1.0, closed).expect("valid") * 4.0;
        let expected = g.powi(4) / (16.0 * b * b);
        assert!((at / expected - 1.0).abs() < 1e-12, "{at} vs {expected}");
    }
}

#[test]
fn extreme_inputs_stay_in_range() {
    let extremes = [
        0.0,
        f64::MIN_POSITIVE,
        1e-300,
        1e-8,
        1.0,
        1e8,
        1e300,
        f64::MAX,
    ];
    for &g in &extremes {
        for &eps in &extremes {
            for (n, n_min, n_max) in [(1, 1, 1), (5, 2, usize::MAX), (1 << 40, 3, 7)] {
                let grad = Grad {
                    value: vec![g],
                    eps: vec![eps],
                };
                let m = next_batch(&grad, n, n_min, n_max).expect("finite inputs");
                assert!((n_min..=n_max).contains(&m), "g {g} ε {eps}: {m}");
            }
        }
    }
}

/// SEPG-MI on `lqg1d` with Student-t widths (so that it steps at small batches), N = 40.
fn checked(seed: u64) -> CheckedConfig {
    let mut cfg = SepgConfig::new(lqg1d(true), Algorithm::Sepg(Requirement::Mi));
    cfg.seed = seed;
    cfg.iterations = 12;
    cfg.n_trajectories = 40;
    cfg.options.confidence = Confidence::StudentT { factor: 1.0 };
    cfg.check().expect("valid")
}

fn solver(checked: &CheckedConfig, rule: BatchRule) -> PolicySolver {
    PolicySolver::new(checked)
        .expect("solver")
        .with_batch_rule(rule)
        .expect("valid rule")
}

#[test]
fn adaptive_runs_draw_every_later_block_within_the_range_and_resume_bit_for_bit() {
    let (n_min, n_max) = (10, 300);
    let rule = BatchRule::Adaptive { n_min, n_max };
    let checked = checked(3);
    let mut log = Collect::default();
    let mut exec = Executor::new(solver(&checked, rule), checked.initial_state()).observe(&mut log);
    exec.run(12).expect("run");
    drop(exec);
    let mut before = 0;
    let mut sizes = Vec::new();
    for r in &log.records {
        let used = r.trajectories - before;
        before = r.trajectories;
        sizes.push(used);
    }
    // iteration 0 splits N = 40 into two blocks of 20; later ones use 2 blocks of m
    assert_eq!(sizes[0], 40);
    for &s in &sizes[1..] {
        assert_eq!(s % 2, 0);
        assert!(
            (2 * n_min as u64..=2 * n_max as u64).contains(&s),
            "{sizes:?}"
        );
    }
    assert!(
        sizes[1..].iter().any(|&s| s != 40),
        "the rule never changed the batch: {sizes:?}"
    );

    // 5 iterations, the state through JSON (the checkpoint), 7 more: the same records
    let mut first = Collect::default();
    let mut exec =
        Executor::new(solver(&checked, rule), checked.initial_state()).observe(&mut first);
    exec.run(5).expect("run");
    let json = serde_json::to_string(exec.state()).expect("serialise");
    drop(exec);
    assert!(json.contains("next_batch"));
    let state: State = serde_json::from_str(&json).expect("deserialise");
    let mut rest = Collect::default();
    let mut exec = Executor::new(solver(&checked, rule), state).observe(&mut rest);
    exec.run(7).expect("run");
    drop(exec);
    first.records.extend(rest.records);
    assert_eq!(first.records, log.records);
}

#[test]
fn the_fixed_rule_writes_no_batch_into_the_state() {
    let checked = checked(0);
    let mut exec = Executor::new(solver(&checked, BatchRule::Fixed), checked.initial_state());
    exec.run(2).expect("run");
    assert_eq!(exec.state().next_batch, None);
    let state = serde_json::to_value(exec.state()).expect("serialise");
    assert!(state.get("next_batch").is_none());
    let rule = BatchRule::Adaptive {
        n_min: 50,
        n_max: 500,
    };
    let json = serde_json::to_value(rule).expect("serialise");
    assert_eq!(
        json,
        serde_json::json!({"adaptive": {"n_min": 50, "n_max": 500}})
    );
}

#[test]
fn bad_adaptive_rules_are_refused() {
    let checked = checked(0);
    for (n_min, n_max) in [(1, 10), (0, 10), (20, 19)] {
        let rule = BatchRule::Adaptive { n_min, n_max };
        assert!(
            matches!(
                PolicySolver::new(&checked)
                    .expect("solver")
                    .with_batch_rule(rule),
                Err(ConfigError::InvalidHyperParameter { .. })
            ),
            "[{n_min}, {n_max}]"
        );
    }
    let rule = BatchRule::Adaptive {
        n_min: 2,
        n_max: 10,
    };
    // the solver's own options but for the accounting
    let estimated = SepgOptions {
        accounting: Accounting::Estimated,
        ..checked.config().options
    };
    assert!(matches!(
        rule.validate(Accounting::Estimated),
        Err(ConfigError::UnsupportedOption {
            option: "batch",
            ..
        })
    ));
    // and an adaptive solver refuses to be switched to the estimated accounting
    let adaptive = solver(&checked, rule);
    assert!(matches!(
        adaptive.with_options(estimated),
        Err(ConfigError::UnsupportedOption {
            option: "batch",
            ..
        })
    ));
}
