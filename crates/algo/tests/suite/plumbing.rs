//! The sampled mode's plumbing, recomputed in the test from its parts: the Student-t widths at
//! the block sizes SEPG uses against the 60-digit quantile table of
//! `scripts/gen_t_quantiles.py`; one sampled SEPG iteration whose batches the test rolls out
//! again (same seed keys), whose estimates it recomputes with `sepg_estimators`, whose widths
//! it builds from the table, and whose steps, guarantees, requirements and budget it derives
//! through `sepg_bounds`; and the logged requirement of every variant recomputed from the
//! logged J values (Table 4.1, Algorithm 4.3 with the delayed budget updates of Sec 4.4.4).
//!
//! Cost: about 0.5 s.
use approx::{abs_diff_eq, assert_relative_eq, assert_ulps_eq};
use sepg_algo::core::config::{Algorithm, GradientMode, Requirement, SepgConfig};
use sepg_algo::core::options::{SepgOptions, WStep};
use sepg_algo::core::record::Record;
use sepg_algo::core::seed::Block;
use sepg_bounds::constants::{TaskConstants, c, dc_dsigma};
use sepg_bounds::high_probability::{self as hp, HighProbabilityBound, HpForm};
use sepg_bounds::outcome::StepOutcome;
use sepg_estimators::{Estimate, Estimator, GradientSpec, Param, SurrogateEstimate, Width, width};
use sepg_mdp::env::{AnyEnv, Environment, LqgEnv};
use sepg_mdp::policy::GaussianPolicy;
use sepg_mdp::rollout::rollout;

use crate::suite::common::run;
use sepg_algo::core::executor::{Collect, Executor};
use sepg_algo::solver::PolicySolver;

/// The first record of a run of `cfg`, with certified steps (the default) or the f64 steps.
fn first_record(cfg: SepgConfig, certified: bool) -> Record {
    let checked = cfg.check().expect("valid").with_certified_steps(certified);
    let mut log = Collect::default();
    let solver = PolicySolver::new(&checked).expect("solver");
    Executor::new(solver, checked.initial_state())
        .observe(&mut log)
        .run(1)
        .expect("run");
    log.records.remove(0)
}

const TABLE: &str = include_str!("../../../estimators/tests/data/t_quantiles.csv");

/// t(p, ν) from the table (exact match of the binary64 p and ν the table was generated for).
fn t_table(p: f64, nu: f64) -> f64 {
    TABLE
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("nu"))
        .map(|l| {
            let f: Vec<f64> = l.split(',').map(|x| x.parse().expect("number")).collect();
            (f[0], f[1], f[2])
        })
        .find(|&(n, q, _)| n == nu && q == p)
        .unwrap_or_else(|| panic!("t({p}, {nu}) is not in the table"))
        .2
}

/// ε = t(1 − δ/2, n − 1) · √(Var/n) (Sec 4.5, eq. 4.22) from the table.
fn eps(variance: f64, n: usize, delta: f64) -> f64 {
    t_table(1.0 - delta / 2.0, (n - 1) as f64) * (variance / n as f64).sqrt()
}

#[test]
fn widths_match_the_quantile_table_at_sepg_block_sizes() {
    // N = 100 split in 3 blocks (34, 33, 33), in 2 (50, 50), and one block of 100.
    for n in [33, 34, 50, 100] {
        for delta in [0.2, 0.05] {
            for variance in [1e-6, 0.37, 42.0] {
                let got = width(Width::StudentT, variance, n, delta).expect("width");
                assert_relative_eq!(got, eps(variance, n, delta), max_relative = 1e-13);
            }
        }
    }
}

/// `(estimate mean, ε)` of component 0.
fn mean_eps(e: &Estimate, delta: f64) -> (f64, f64) {
    (e.mean()[0], eps(e.variance()[0], e.n(), delta))
}

/// The step size of an outcome as the algorithm takes it: the largest safe step, or the
/// vertex (λ = 0) when the requirement is infeasible; 0 for a direction below its noise.
fn step_of(outcome: StepOutcome) -> f64 {
    match outcome {
        StepOutcome::Feasible(s) => s.largest(),
        StepOutcome::Infeasible { vertex, .. } => vertex,
        StepOutcome::ZeroGradient { .. } | StepOutcome::BelowNoise => 0.0,
    }
}

/// The logged guarantee against the bound at the recomputed step (`None` below the noise).
fn assert_guarantee(logged: Option<f64>, bound: Option<HighProbabilityBound>, step: f64) {
    match (logged, bound) {
        (Some(g), Some(b)) => {
            assert_relative_eq!(
                g,
                b.sign_aware_value(step).expect("value"),
                max_relative = 1e-12
            )
        }
        (None, None) => assert_eq!(step, 0.0),
        (g, b) => panic!("logged guarantee {g:?}, recomputed bound {b:?}"),
    }
}

/// The w-step of Theorem 4.9 (sign-aware) and J(θ⁰) from the first v-block, with no
/// reference batch: the plumbing these tests recompute by hand (the exploring w-step and the
/// reference batch have their own tests in `sepg-bounds` and `options.rs`).
fn thesis_form() -> SepgOptions {
    SepgOptions {
        w_step: WStep::Theorem49,
        reference_batch: 0,
        ..SepgOptions::estimated()
    }
}

/// The first sampled iteration of LB-II (B⁰ = 0.05, two blocks of 50 trajectories, δ = 0.2)
/// and of its naive-w variant, for several seeds, with certified and with f64 steps,
/// recomputed from the batches.
#[test]
fn one_sampled_iteration_recomputed_from_its_batches() {
    let delta = 0.2;
    let b0 = 0.05;
    let env = LqgEnv::thesis();
    let mut w_updates = [0, 0];
    let cases = [false, true]
        .into_iter()
        .flat_map(|n| (0..6).map(move |s| (n, s)))
        .flat_map(|(n, s)| [true, false].map(|c| (n, s, c)));
    for (naive, seed, certified) in cases {
        let alg = if naive {
            Algorithm::SepgNaiveW(Requirement::LbII)
        } else {
            Algorithm::Sepg(Requirement::LbII)
        };
        let cfg = SepgConfig {
            gradient: GradientMode::Sampled { delta },
            sigma0: vec![0.5],
            seed,
            initial_budget: b0,
            options: thesis_form(),
            ..SepgConfig::new(AnyEnv::Lqg(Box::new(env.clone())), alg)
        };
        let checked = cfg.clone().check().expect("valid");
        let k: TaskConstants = *checked.constants();
        let r = &first_record(cfg.clone(), certified);
        let (v0, w0, sigma) = (cfg.v0.clone(), vec![0.5f64.ln()], 0.5);
        let features = env.feature_dim();
        let spec = GradientSpec::default();
        let mut est = Estimator::new();

        // v-block: 50 trajectories at θ⁰.
        let policy = GaussianPolicy::new(v0.clone(), w0.clone(), features).expect("policy");
        let batch = rollout(&env, &policy, 50, 20, Block::V.key(cfg.seed, 0)).expect("rollout");
        let (mut value, mut grad) = (Estimate::new(), Estimate::new());
        est.value(&batch, &mut value).expect("J");
        est.gradient(&batch, Param::V, spec, &mut grad)
            .expect("grad v");
        let j_v = value.mean()[0];
        let (gv, ev) = mean_eps(&grad, delta);
        let required_v = -b0;
        let bound_v = HighProbabilityBound::v_update(&k, sigma, &[gv], ev).expect("bound");
        let alpha = step_of(
            hp::v_safe_step(&k, sigma, &[gv], ev, required_v, HpForm::SignAware).expect("step"),
        );
        assert_eq!(r.j_exploratory, j_v);
        assert_eq!(r.required_v, Some(required_v));
        assert_relative_eq!(r.alpha, alpha, max_relative = 1e-12);
        assert_guarantee(r.guaranteed_v, bound_v, alpha);

        // w-block: 50 trajectories at (v¹, w⁰); B after the delayed v-budget update.
        let v1 = vec![v0[0] + r.alpha * gv];
        let policy = GaussianPolicy::new(v1, w0.clone(), features).expect("policy");
        let batch = rollout(&env, &policy, 50, 20, Block::W.key(cfg.seed, 0)).expect("rollout");
        est.value(&batch, &mut value).expect("J");
        est.gradient(&batch, Param::W, spec, &mut grad)
            .expect("grad w");
        let j_w = value.mean()[0];
        let (gj, ej) = mean_eps(&grad, delta);
        let budget = b0 + (j_w - j_v);
        let required_w = -budget;
        assert_eq!(r.j_after_v, Some(j_w));
        // The same two roundings as the algorithm's bookkeeping: equal up to their order.
        assert_ulps_eq!(r.budget, budget, max_ulps = 2);
        assert_ulps_eq!(
            r.required_w.expect("w requirement"),
            required_w,
            max_ulps = 2
        );
        let (bound_w, beta) = if naive {
            let b = HighProbabilityBound::w_along_j(&k, sigma, gj, ej).expect("bound");
            let s = hp::w_safe_step_along_j(&k, sigma, gj, ej, required_w, HpForm::SignAware);
            (b, step_of(s.expect("step")))
        } else {
            let mut sur = SurrogateEstimate::new();
            let (cc, dc) = (c(&k, sigma).expect("c"), dc_dsigma(&k, sigma).expect("c'"));
            est.surrogate_gradient(&batch, spec, cc, &[dc], &mut sur)
                .expect("grad L");
            let (gl, el) = mean_eps(sur.grad_w_l(), delta);
            let b = HighProbabilityBound::w_along_l(&k, sigma, gj, ej, gl, el).expect("bound");
            let s =
                hp::w_safe_step_along_l(&k, sigma, gj, ej, gl, el, required_w, HpForm::SignAware);
            (b, step_of(s.expect("step")))
        };
        assert_relative_eq!(r.beta, beta, max_relative = 1e-12);
        assert_guarantee(r.guaranteed_w, bound_w, beta);
        w_updates[usize::from(naive)] += usize::from(r.guaranteed_w.is_some());
    }
    // Both w-updates are exercised, not only their below-noise branch.
    assert!(w_updates.iter().all(|&u| u >= 1), "w-updates {w_updates:?}");
}

/// The requirements (C_v, C_w) and the budget each record should log, recomputed from the
/// logged J values alone with B⁰ = `b0`.
fn expected_requirements(req: Requirement, records: &[Record], b0: f64) -> Vec<(f64, f64, f64)> {
    let j0 = records[0].j_exploratory;
    let mut budget = b0;
    let mut last_exploratory: Option<f64> = None;
    let mut last_target: Option<f64> = None;
    records
        .iter()
        .map(|r| {
            let j = r.j_exploratory;
            if let Some(p) = last_exploratory {
                budget += j - p;
            }
            let cv = match req {
                Requirement::Mi => 0.0,
                Requirement::LbI { nu } => (1.0 - nu) * (j0 - j),
                Requirement::Sim { nu } => -nu * budget,
                _ => -budget,
            };
            if matches!(
                req,
                Requirement::Lv | Requirement::Zv | Requirement::Sim { .. }
            ) {
                if let Some(p) = last_target {
                    budget += r.j_target - p;
                }
                last_target = Some(r.j_target);
            }
            let cw = match (req, r.j_after_v) {
                (Requirement::Sim { nu }, _) => {
                    last_exploratory = Some(j);
                    -(1.0 - nu) * budget
                }
                (_, Some(j_after)) => {
                    budget += j_after - j;
                    last_exploratory = Some(j_after);
                    match req {
                        Requirement::Mi => 0.0,
                        Requirement::LbI { nu } => nu * (j0 - j),
                        _ => -budget,
                    }
                }
                (_, None) => panic!("{req:?} logged no J after the v-update"),
            };
            (cv, cw, budget)
        })
        .collect()
}

#[test]
fn logged_requirements_follow_from_the_logged_j() {
    let b0 = 0.02;
    for req in [
        Requirement::Mi,
        Requirement::LbI { nu: 0.3 },
        Requirement::LbII,
        Requirement::Lv,
        Requirement::Zv,
        Requirement::Sim { nu: 0.4 },
    ] {
        let cfg = SepgConfig {
            gradient: GradientMode::Sampled { delta: 0.2 },
            sigma0: vec![0.5],
            seed: 9,
            initial_budget: b0,
            options: thesis_form(),
            ..SepgConfig::new(
                AnyEnv::Lqg(Box::new(LqgEnv::thesis())),
                Algorithm::Sepg(req),
            )
        };
        let (records, _) = run(cfg, 30);
        let j0 = records[0].j_exploratory;
        // LB-I must meet both signs of Cᵗ = J⁰ − Jᵗ: a worsening allowed after an improvement.
        if let Requirement::LbI { .. } = req {
            assert!(records.iter().any(|r| r.j_exploratory > j0));
            assert!(records.iter().any(|r| r.j_exploratory < j0));
        }
        for (r, (cv, cw, budget)) in records.iter().zip(expected_requirements(req, &records, b0)) {
            let tol = 1e-12 * r.j_exploratory.abs().max(1.0);
            for (what, logged, expected) in [
                ("C_v", r.required_v.expect("C_v"), cv),
                ("C_w", r.required_w.expect("C_w"), cw),
                ("B", r.budget, budget),
            ] {
                assert!(
                    abs_diff_eq!(logged, expected, epsilon = tol),
                    "{req:?} iteration {}: {what} logged {logged}, expected {expected}",
                    r.iteration
                );
            }
        }
    }
}

/// The first exact iteration of LB-II (B⁰ = 0.05) and of its naive-w variant, recomputed
/// through `sepg_bounds` from the clipped-LQG oracle's J and derivatives (Theorems 4.2, 4.3,
/// 4.5; ∇_w L of Corollary 4.4 by eq. B.1), with certified and with f64 steps.
#[test]
fn one_exact_iteration_recomputed_from_the_oracle() {
    use sepg_bounds::{surrogate, v_update, w_update};
    use sepg_mdp::oracle::{ClippedDpOracle, ExactOracle, Exploration, Horizon, Needs};
    let b0 = 0.05;
    let env = LqgEnv::thesis();
    let oracle = ClippedDpOracle::new(env.model()).expect("clipped preset");
    let cases = [(false, 0.5), (true, 0.5), (false, 0.2), (true, 1.0)];
    for ((naive, sigma), certified) in cases.into_iter().flat_map(|c| [(c, true), (c, false)]) {
        let alg = if naive {
            Algorithm::SepgNaiveW(Requirement::LbII)
        } else {
            Algorithm::Sepg(Requirement::LbII)
        };
        let cfg = SepgConfig {
            gradient: GradientMode::Exact,
            sigma0: vec![sigma],
            initial_budget: b0,
            options: SepgOptions::estimated(),
            ..SepgConfig::new(AnyEnv::Lqg(Box::new(env.clone())), alg)
        };
        let k: TaskConstants = *cfg.clone().check().expect("valid").constants();
        let r = &first_record(cfg.clone(), certified);
        let at = |v: f64| {
            let ex = Exploration::Gaussian {
                w: vec![sigma.ln()],
            };
            oracle
                .evaluate_with(&[v], &ex, Horizon::Finite(20), Needs::SEPG)
                .expect("oracle")
        };
        let e0 = at(cfg.v0[0]);
        let alpha = step_of(v_update::safe_step(&k, sigma, &e0.grad_v, -b0).expect("v step"));
        assert_relative_eq!(r.alpha, alpha, max_relative = 1e-12);
        assert_relative_eq!(
            r.guaranteed_v.expect("v updated"),
            v_update::bound(&k, sigma, &e0.grad_v, alpha).expect("bound"),
            max_relative = 1e-12
        );
        let e1 = at(cfg.v0[0] + alpha * e0.grad_v[0]);
        let required_w = -(b0 + e1.j - e0.j);
        let gj = e1.grad_w[0];
        let (beta, guaranteed) = if naive {
            let s = step_of(w_update::safe_step_along_j(&k, sigma, gj, required_w).expect("step"));
            (s, w_update::bound_along_j(&k, sigma, gj, s).expect("bound"))
        } else {
            let mixed_sigma = [e1.mixed_wv[0] / sigma];
            let gl = surrogate::grad_w(&k, sigma, &e1.grad_v, &mixed_sigma).expect("grad L");
            let s =
                step_of(w_update::safe_step_along_l(&k, sigma, gj, gl, required_w).expect("step"));
            (
                s,
                w_update::bound_along_l(&k, sigma, gj, gl, s).expect("bound"),
            )
        };
        assert_relative_eq!(r.required_w.expect("C_w"), required_w, max_relative = 1e-12);
        assert_relative_eq!(r.beta, beta, max_relative = 1e-12);
        assert_relative_eq!(
            r.guaranteed_w.expect("w updated"),
            guaranteed,
            max_relative = 1e-12
        );
    }
}
