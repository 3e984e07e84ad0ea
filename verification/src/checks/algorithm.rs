//! Algorithm-level claims (SEPG, Algorithm 4.3, run by `sepg-algo`) and the thesis's numerical
//! claims (v*, J(v*), the qualitative ordering of Table 5.1).

use sepg_algo::core::config::{Algorithm, GradientMode, Requirement, SepgConfig};
use sepg_algo::core::executor::{Collect, Executor};
use sepg_algo::core::options::SepgOptions;
use sepg_algo::core::record::Record;
use sepg_algo::solver::PolicySolver;
use sepg_mdp::env::{AnyEnv, LqgEnv};
use sepg_mdp::lqg_model::LqgModel;
use sepg_mdp::oracle::ClosedFormOracle;

use crate::check::{
    Check, CheckContext, CheckMeta, ClaimKind, Evaluation, Expected, Figure, Tolerance, fmt_f64,
};
use crate::checks::sampled::FAMILY_ALPHA;
use crate::lqg::{HORIZON, Preset, Task};
use crate::search::{Comparison, fixed};
use crate::stats::{Freq, frequency_outcome};

fn env(preset: Preset, clipped: bool) -> Option<AnyEnv> {
    let model = match preset {
        Preset::Lqg => LqgModel::thesis(),
        Preset::Lqg1d => LqgModel::lqg1d(),
    }
    .with_clipping(clipped);
    Some(AnyEnv::Lqg(Box::new(LqgEnv::new(model).ok()?)))
}

/// Runs SEPG with `req` for `iterations` iterations and returns its records.
fn run(
    preset: Preset,
    clipped: bool,
    req: Requirement,
    sigma0: f64,
    gradient: GradientMode,
    iterations: u64,
    seed: u64,
) -> Option<Vec<Record>> {
    run_with_budget(
        preset, clipped, req, sigma0, gradient, iterations, seed, None,
    )
}

/// [`run`] from v⁰ (default −0.1 when `None`) with an initial budget B⁰.
#[allow(clippy::too_many_arguments)]
fn run_with_budget(
    preset: Preset,
    clipped: bool,
    req: Requirement,
    sigma0: f64,
    gradient: GradientMode,
    iterations: u64,
    seed: u64,
    start: Option<(f64, f64)>,
) -> Option<Vec<Record>> {
    let base = SepgConfig::new(env(preset, clipped)?, Algorithm::Sepg(req));
    let (v0, initial_budget) = start.map_or((base.v0.clone(), base.initial_budget), |(v, b)| {
        (vec![v], b)
    });
    let cfg = SepgConfig {
        gradient,
        sigma0: vec![sigma0],
        seed,
        horizon: HORIZON,
        v0,
        initial_budget,
        // the thesis's algorithm as it states it: budgets from measured J (Definition 4.3)
        options: SepgOptions::estimated(),
        ..base
    };
    let checked = cfg.check().ok()?;
    let solver = PolicySolver::new(&checked).ok()?;
    let mut log = Collect::default();
    let mut exec = Executor::new(solver, checked.initial_state()).observe(&mut log);
    exec.run(iterations).ok()?;
    drop(exec);
    Some(log.records)
}

const PRESETS: [Preset; 2] = [Preset::Lqg, Preset::Lqg1d];
const SIGMAS: [f64; 2] = [0.2, 1.0];

/// Exact-mode runs of `req` on both clipped presets and σ⁰ ∈ {0.2, 1}; `claim` maps a run's
/// records to comparisons.
fn exact_runs(
    ctx: &CheckContext<'_>,
    reqs: &[Requirement],
    claim: impl Fn(&[Record]) -> Vec<Comparison>,
) -> Evaluation {
    let mut comparisons = Vec::new();
    for preset in PRESETS {
        for &req in reqs {
            for sigma0 in SIGMAS {
                let label = format!("{preset:?} {req:?} σ⁰ = {sigma0}");
                let Some(records) = run(
                    preset,
                    true,
                    req,
                    sigma0,
                    GradientMode::Exact,
                    u64::from(ctx.cases),
                    0,
                ) else {
                    continue;
                };
                comparisons.extend(
                    claim(&records)
                        .into_iter()
                        .enumerate()
                        .map(|(t, c)| (format!("{label}, iteration {}", t + 1), c)),
                );
            }
        }
    }
    fixed(ctx, &comparisons)
}

fn mi_monotone(ctx: &CheckContext<'_>) -> Evaluation {
    exact_runs(ctx, &[Requirement::Mi], |r| {
        r.windows(2)
            .map(|w| Comparison::new(w[1].j_exploratory, w[0].j_exploratory))
            .collect()
    })
}

fn lb_i(ctx: &CheckContext<'_>) -> Evaluation {
    exact_runs(ctx, &[Requirement::LbI { nu: 0.5 }], |r| {
        r.iter()
            .skip(1)
            .map(|x| Comparison::new(x.j_exploratory, r[0].j_exploratory))
            .collect()
    })
}

/// The type-II budget of a run recomputed from the DP oracle's J at the recorded parameters,
/// independently of the budget the algorithm keeps: after iteration t (its delayed v-update
/// included), B^t = B⁰ + J(v^{t+1}, w^t) − J(v⁰, w⁰) + J(v^t, w_T^t) − J(v⁰, w_T⁰), the last two
/// terms only for a separate target policy (LV, ZV). One value per iteration whose successor
/// is recorded.
fn budgets_from_oracle(task: &Task, records: &[Record], initial: f64) -> Vec<f64> {
    let Some(first) = records.first() else {
        return Vec::new();
    };
    let target_w = |r: &Record| r.w_target.as_ref().map(|w| w[0]);
    let separate_target = first.w_target.as_ref() != Some(&first.w);
    let (Some(j0), Some(jt0)) = (
        task.j(first.v[0], first.w[0]),
        task.j_of(first.v[0], target_w(first)),
    ) else {
        return Vec::new();
    };
    records
        .windows(2)
        .map_while(|p| {
            let explore = task.j(p[1].v[0], p[0].w[0])? - j0;
            let target = if separate_target {
                task.j_of(p[0].v[0], target_w(&p[0]))? - jt0
            } else {
                0.0
            };
            Some(initial + explore + target)
        })
        .collect()
}

/// Exact-mode runs of `reqs` on the given configurations; the claim is B^t ≥ 0 for the budget
/// recomputed from the oracle ([`budgets_from_oracle`]).
fn budget_runs(
    ctx: &CheckContext<'_>,
    reqs: &[Requirement],
    configs: &[(Preset, f64)],
    iterations: u64,
) -> Evaluation {
    let mut comparisons = Vec::new();
    let mut lowest = f64::INFINITY;
    for &(preset, sigma0) in configs {
        let Some(task) = Task::new(preset, 0.99) else {
            continue;
        };
        for &req in reqs {
            let Some(records) = run(
                preset,
                true,
                req,
                sigma0,
                GradientMode::Exact,
                iterations,
                0,
            ) else {
                continue;
            };
            let label = format!("{preset:?} {req:?} σ⁰ = {sigma0}");
            for (t, b) in budgets_from_oracle(&task, &records, 0.0)
                .into_iter()
                .enumerate()
            {
                lowest = lowest.min(b);
                comparisons.push((
                    format!("{label}, iteration {t}: B^t from the DP oracle"),
                    Comparison::new(b, 0.0),
                ));
            }
        }
    }
    let mut eval = fixed(ctx, &comparisons);
    eval.figures.push(Figure {
        name: "lowest budget recomputed from the DP oracle".into(),
        value: fmt_f64(lowest),
    });
    eval
}

fn type_ii_budget(ctx: &CheckContext<'_>) -> Evaluation {
    let configs: Vec<(Preset, f64)> = PRESETS
        .iter()
        .flat_map(|&p| SIGMAS.iter().map(move |&s| (p, s)))
        .collect();
    budget_runs(
        ctx,
        &[Requirement::LbII, Requirement::Zv],
        &configs,
        u64::from(ctx.cases),
    )
}

/// Iterations of the LV run: past iteration 531, where the exact budget of LV on lqg with
/// σ⁰ = 1 first goes negative (found by a 10,000-iteration exact run, ERRATA §25).
const LV_ITERATIONS: u64 = 560;

fn lv_budget(ctx: &CheckContext<'_>) -> Evaluation {
    budget_runs(
        ctx,
        &[Requirement::Lv],
        &[(Preset::Lqg, 1.0)],
        LV_ITERATIONS,
    )
}

/// Initial budget of the Theorem 4.1 check with B⁰ > 0.
const INITIAL_BUDGET: f64 = 1.0;

/// Starting mean parameter of that check: near the optimum, where little improvement is left
/// to pay for exploration, so a budget spent shows in J.
const START_V: f64 = -0.6;

/// Theorem 4.1's type-II guarantee (J(θ_E^t) + J(θ_T^t))/2 ≥ J_B for exact SEPG started with
/// B⁰ > 0, every J from the DP oracle at the recorded parameters.
fn initial_budget_runs(ctx: &CheckContext<'_>) -> Evaluation {
    let mut comparisons = Vec::new();
    for (preset, sigma0) in [(Preset::Lqg, 1.0), (Preset::Lqg1d, 0.5)] {
        let Some(task) = Task::new(preset, 0.99) else {
            continue;
        };
        for req in [Requirement::LbII, Requirement::Zv] {
            let Some(records) = run_with_budget(
                preset,
                true,
                req,
                sigma0,
                GradientMode::Exact,
                u64::from(ctx.cases),
                0,
                Some((START_V, INITIAL_BUDGET)),
            ) else {
                continue;
            };
            let target_w = |r: &Record| r.w_target.as_ref().map(|w| w[0]);
            let js: Option<Vec<(f64, f64)>> = records
                .iter()
                .map(|r| Some((task.j(r.v[0], r.w[0])?, task.j_of(r.v[0], target_w(r))?)))
                .collect();
            let Some(js) = js else {
                continue;
            };
            let baseline = (js[0].0 + js[0].1) / 2.0;
            for (t, (je, jt)) in js.iter().enumerate().skip(1) {
                comparisons.push((
                    format!("{preset:?} {req:?} σ⁰ = {sigma0}, B⁰ = {INITIAL_BUDGET}, t = {t}"),
                    Comparison::new((je + jt) / 2.0, baseline),
                ));
            }
        }
    }
    fixed(ctx, &comparisons)
}

/// Sampled-mode SEPG: realised per-iteration violations of MI (J(θ^{t+1}) < J(θ^t)) and LB-I
/// (J(θ^t) < J(θ⁰)), measured with the DP oracle at the recorded parameters.
fn sampled_violations(ctx: &CheckContext<'_>) -> Evaluation {
    let delta = 0.2;
    let mut tests = Vec::new();
    for preset in PRESETS {
        let Some(task) = Task::new(preset, 0.99) else {
            continue;
        };
        for (req, name) in [
            (Requirement::Mi, "MI: J(θ^{t+1}) ≥ J(θ^t)"),
            (Requirement::LbI { nu: 0.5 }, "LB-I: J(θ^t) ≥ J(θ⁰)"),
        ] {
            let Some(records) = run(
                preset,
                true,
                req,
                1.0,
                GradientMode::Sampled { delta },
                u64::from(ctx.cases),
                ctx.seed,
            ) else {
                continue;
            };
            let j: Vec<f64> = records
                .iter()
                .filter_map(|r| task.j(r.v[0], r.w[0]))
                .collect();
            let tol = 1e-9 * j.first().map_or(1.0, |x| x.abs().max(1.0));
            let (violations, trials) = match req {
                Requirement::Mi => j.windows(2).fold((0, 0), |(v, n), w| {
                    (v + u64::from(w[1] < w[0] - tol), n + 1)
                }),
                _ => j
                    .iter()
                    .skip(1)
                    .fold((0, 0), |(v, n), x| (v + u64::from(*x < j[0] - tol), n + 1)),
            };
            tests.push(Freq {
                name: format!("{preset:?} σ⁰ = 1, δ = {delta}, {name}"),
                violations,
                trials,
                allowed: 1.0 - (1.0 - delta).powi(3),
            });
        }
    }
    frequency_outcome(&tests, FAMILY_ALPHA)
}

fn v_star_claims(ctx: &CheckContext<'_>) -> Evaluation {
    let gamma: f64 = 0.99;
    let v_star = (1.0 - (1.0 + 4.0 * gamma * gamma).sqrt()) / (2.0 * gamma);
    let mut comparisons = vec![(
        "v* = (1 − √(1+4γ²))/(2γ) vs printed −0.615".to_string(),
        Comparison::new(v_star, -0.615),
    )];
    let mut figures = Vec::new();
    let mut lqg1d_j = -7.753;
    for (preset, model) in [("lqg", LqgModel::thesis()), ("lqg1d", LqgModel::lqg1d())] {
        let Ok(opt) =
            ClosedFormOracle::new(&model.with_clipping(false)).and_then(|o| o.optimal_gain())
        else {
            continue;
        };
        comparisons.push((
            format!("{preset}: Riccati optimal gain vs printed v* = −0.615"),
            Comparison::new(opt.v[0], -0.615),
        ));
        figures.push(Figure {
            name: format!("{preset}: v*, J(v*, −∞) (unclipped, infinite horizon)"),
            value: format!("{}, {}", fmt_f64(opt.v[0]), fmt_f64(opt.j_deterministic)),
        });
        if preset == "lqg1d" {
            lqg1d_j = opt.j_deterministic;
            comparisons.push((
                "lqg1d: J(v*, −∞) vs printed −7.753".into(),
                Comparison::new(opt.j_deterministic, -7.753),
            ));
        }
    }
    // The thesis leaves the transition noise η₀ open. J(v*) of the unclipped infinite-horizon
    // LQG is affine in η₀² (J = −E[s₀ᵀPs₀] − γ/(1−γ)·P·η₀² for the scalar case), so the η₀ at
    // which `lqg` reproduces a value follows from two evaluations.
    let lqg_j = |eta: f64| -> Option<(f64, f64)> {
        let model = LqgModel::thesis()
            .with_clipping(false)
            .with_noise(nalgebra::DVector::from_element(1, eta))
            .ok()?;
        let opt = ClosedFormOracle::new(&model).ok()?.optimal_gain().ok()?;
        Some((opt.v[0], opt.j_deterministic))
    };
    if let (Some((_, j_zero)), Some((_, j_one))) = (lqg_j(0.0), lqg_j(1.0)) {
        let slope = j_zero - j_one;
        for (what, target) in [("the printed −7.753", -7.753), ("lqg1d's J(v*)", lqg1d_j)] {
            let eta = ((j_zero - target) / slope).sqrt();
            if let Some((v, j)) = lqg_j(eta) {
                comparisons.push((
                    format!("lqg with η₀ = {eta:.15}: J(v*, −∞) vs printed −7.753"),
                    Comparison::new(j, -7.753),
                ));
                comparisons.push((
                    format!("lqg with η₀ = {eta:.15}: v* vs printed −0.615"),
                    Comparison::new(v, -0.615),
                ));
                figures.push(Figure {
                    name: format!("η₀ at which lqg reproduces {what}; J(v*, −∞) there"),
                    value: format!("{eta:.15}, {}", fmt_f64(j)),
                });
            }
        }
    }
    let mut eval = fixed(ctx, &comparisons);
    eval.figures.extend(figures);
    eval
}

/// |v_t − v*| at the checkpoints t of one exact run (unclipped lqg1d, closed form, fast).
fn errors_at(req: Requirement, sigma0: f64, checkpoints: &[u64]) -> Option<Vec<f64>> {
    let gamma: f64 = 0.99;
    let v_star = (1.0 - (1.0 + 4.0 * gamma * gamma).sqrt()) / (2.0 * gamma);
    let last = *checkpoints.last()?;
    let records = run(
        Preset::Lqg1d,
        false,
        req,
        sigma0,
        GradientMode::Exact,
        last,
        0,
    )?;
    checkpoints
        .iter()
        .map(|&t| {
            let r = records.get(usize::try_from(t).ok()?.checked_sub(1)?)?;
            Some((r.v[0] - v_star).abs())
        })
        .collect()
}

/// The qualitative claims of Table 5.1 that the published table shows in every row and the
/// text states (Section 5.1.2: "MI is in general the slowest to converge"; "our algorithms
/// perform better with higher initial values of σ"), checked at five checkpoints of one run so
/// that a claim that holds only for some T fails.
fn table_5_1(ctx: &CheckContext<'_>) -> Evaluation {
    let t = u64::from(ctx.cases);
    let checkpoints: Vec<u64> = (1..=5).map(|k| k * t / 5).collect();
    let err = |req, s| errors_at(req, s, &checkpoints);
    let lb1 = Requirement::LbI { nu: 0.5 };
    let others = [
        ("LB-I", lb1),
        ("LB-II", Requirement::LbII),
        ("LV", Requirement::Lv),
        ("ZV", Requirement::Zv),
    ];
    let (Some(mi), Some(mi_small), Some(lb1_small)) = (
        err(Requirement::Mi, 1.0),
        err(Requirement::Mi, 0.1),
        err(lb1, 0.1),
    ) else {
        return fixed(ctx, &[]);
    };
    let mut comparisons = Vec::new();
    let mut figures = Vec::new();
    let mut lb1_big = None;
    for (name, req) in others {
        let Some(e) = err(req, 1.0) else {
            return fixed(ctx, &[]);
        };
        for (k, (&tk, &x)) in checkpoints.iter().zip(&e).enumerate() {
            comparisons.push((
                format!("T = {tk}: |v−v*| of {name} ≤ MI (σ⁰ = 1)"),
                Comparison::new(x, mi[k]),
            ));
        }
        figures.push(Figure {
            name: format!("|v_T − v*| of {name}, σ⁰ = 1, at T = {checkpoints:?}"),
            value: e.iter().map(|x| fmt_f64(*x)).collect::<Vec<_>>().join(", "),
        });
        if name == "LB-I" {
            lb1_big = Some(e);
        }
    }
    let Some(lb1_big) = lb1_big else {
        return fixed(ctx, &[]);
    };
    for (k, &tk) in checkpoints.iter().enumerate() {
        comparisons.push((
            format!("T = {tk}: |v−v*| of MI, σ⁰ = 1 ≤ σ⁰ = 0.1"),
            Comparison::new(mi[k], mi_small[k]),
        ));
        comparisons.push((
            format!("T = {tk}: |v−v*| of LB-I, σ⁰ = 1 ≤ σ⁰ = 0.1"),
            Comparison::new(lb1_big[k], lb1_small[k]),
        ));
    }
    for (name, e) in [
        ("MI, σ⁰ = 1", &mi),
        ("MI, σ⁰ = 0.1", &mi_small),
        ("LB-I, σ⁰ = 0.1", &lb1_small),
    ] {
        figures.push(Figure {
            name: format!("|v_T − v*| of {name} at T = {checkpoints:?}"),
            value: e.iter().map(|x| fmt_f64(*x)).collect::<Vec<_>>().join(", "),
        });
    }
    let mut eval = fixed(ctx, &comparisons);
    eval.figures.extend(figures);
    eval
}

fn meta(id: &str, statement: &str, location: &str, claim: &str, ground_truth: &str) -> CheckMeta {
    CheckMeta {
        id: id.into(),
        statement: statement.into(),
        location: location.into(),
        claim: claim.into(),
        ground_truth: ground_truth.into(),
        sampling: "exact-gradient SEPG (sepg-algo, GradientMode::Exact) on the clipped presets \
            lqg and lqg1d, σ⁰ ∈ {0.2, 1}, v⁰ = −0.1, H = 20, γ = 0.99; the case count is the \
            number of iterations per run"
            .into(),
        kind: ClaimKind::LowerBound,
        cases_full: 300,
        cases_quick: 40,
        tolerance: Tolerance {
            abs: 1e-9,
            rel: 1e-10,
        },
        false_alarm_rate: "0: exact oracle values; the tolerance absorbs the oracle's rounding \
            (≈ 3e-11·|J|)"
            .into(),
        expected: Expected::Holds,
        notes: "Holds.".into(),
        basis: String::new(),
    }
}

const EXACT: &str =
    "J of the recorded parameters by the clipped DP oracle (sepg-algo's exact mode)";
const BUDGET_TRUTH: &str = "the budget recomputed from the DP oracle's J at the recorded parameters, \
        B^t = J(v^{t+1}, w^t) − J(v⁰, w⁰) + J(v^t, w_T^t) − J(v⁰, w_T⁰) (target terms for LV, ZV), \
        not the budget the algorithm keeps";

/// The checks of this module, in registry order.
pub(crate) fn checks() -> Vec<Check> {
    vec![
        mi_monotone_check(),
        lb_i_check(),
        type_ii_budget_check(),
        lv_budget_check(),
        initial_budget_runs_check(),
        sampled_violations_check(),
        v_star_claims_check(),
        table_5_1_check(),
    ]
}

/// The check `sepg-mi-monotone-exact`.
fn mi_monotone_check() -> Check {
    let mi = meta(
        "sepg-mi-monotone-exact",
        "SEPG-MI (Table 4.1, C = 0) is monotone with exact gradients",
        "Section 4.2.1, Table 4.1, Algorithm 4.3",
        "J(θ^{t+1}) ≥ J(θ^t) at every iteration.",
        EXACT,
    );
    Check::new(mi, mi_monotone)
}

/// The check `sepg-lb-i-exact`.
fn lb_i_check() -> Check {
    let lb1 = meta(
        "sepg-lb-i-exact",
        "SEPG LB-I (C = J(θ⁰) − J(θ^t)) stays above J(θ⁰) with exact gradients",
        "Section 4.2.1, Table 4.1, Algorithm 4.3",
        "J(θ^t) ≥ J(θ⁰) at every iteration (ν = 0.5).",
        EXACT,
    );
    Check::new(lb1, lb_i)
}

/// The check `sepg-type-ii-budget-exact`.
fn type_ii_budget_check() -> Check {
    let mut b2 = meta(
        "sepg-type-ii-budget-exact",
        "SEPG LB-II and ZV keep the budget non-negative with exact gradients (Theorem 4.1)",
        "Section 4.2.2, Table 4.1, Algorithm 4.3",
        "B^t ≥ 0 at every iteration (B⁰ = 0), hence type-II safety by Theorem 4.1.",
        BUDGET_TRUTH,
    );
    b2.notes = "Holds. LV is checked separately (sepg-lv-budget-exact).".into();
    b2.basis = "independent computation: 10,000-iteration exact runs of LB-II and ZV on both \
        clipped presets and σ⁰ ∈ {0.1, 0.2, 0.5, 1} keep B ≥ 0 \
        (crates/algo/tests/suite/exact.rs::guarantees_hold_clipped_dp_10000_iterations); theory \
        covers LB-II's charges (each is bounded by its step's requirement C = −B, up to the \
        neglected terms of Theorem 4.3 for Δw < 0) but not ZV's target charge \
        J(v^t, −∞) − J(v^{t−1}, −∞), which no theorem bounds"
        .into();
    Check::new(b2, type_ii_budget)
}

/// The check `sepg-lv-budget-exact`.
fn lv_budget_check() -> Check {
    let mut lv = meta(
        "sepg-lv-budget-exact",
        "SEPG-LV keeps the budget non-negative with exact gradients (Theorem 4.1, Table 4.1)",
        "Section 4.4.2, Table 4.1, Algorithm 4.3",
        "B^t ≥ 0 at every iteration (B⁰ = 0) for the low-variance target.",
        BUDGET_TRUTH,
    );
    lv.sampling = "exact-gradient SEPG-LV on clipped lqg, σ⁰ = 1, v⁰ = −0.1, H = 20, γ = 0.99, \
        560 iterations in both modes (past iteration 531)"
        .into();
    lv.cases_quick = 560;
    lv.cases_full = 560;
    lv.expected = Expected::Violated;
    lv.notes = "Violated at iteration 531 (B ≈ −8.6e-5): the LV target lowers w, where the \
        thesis form of Theorem 4.3 neglects a positive third-order term, and the budget is \
        charged J(θ_Tᵗ) − J(θ_Tᵗ⁻¹) whereas (4.17) only bounds J(θ_Tᵗ) − J(θ_Eᵗ). See ERRATA §25."
        .into();
    lv.basis = "theory: no theorem bounds LV's budget charge J(θ_Tᵗ) − J(θ_Tᵗ⁻¹) (ERRATA §25), \
        so Theorem 4.1's premise B ≥ 0 is not guaranteed; the iteration of the first violation \
        comes from an independent 10,000-iteration exact run \
        (crates/algo/tests/suite/exact.rs::lv_budget_goes_negative_clipped_dp_10000_iterations)"
        .into();
    Check::new(lv, lv_budget)
}

/// The check `thm-4.1-initial-budget`.
fn initial_budget_runs_check() -> Check {
    let mut b0 = meta(
        "thm-4.1-initial-budget",
        "Theorem 4.1 with an initial budget B⁰ > 0 (Section 4.4.4, Mountain Car uses B⁰ = 1)",
        "Section 4.2.2 and 4.4.4, Theorem 4.1, Algorithm 4.3",
        "SEPG started with B⁰ = 1 (as Section 4.4.4 does): (J(θ_E^t) + J(θ_T^t))/2 ≥ J_B = \
         (J(θ_E⁰) + J(θ_T⁰))/2 at every iteration, as Theorem 4.1 is invoked for it.",
        "J of the recorded exploratory and target parameters by the DP oracle",
    );
    b0.sampling = "exact-gradient SEPG LB-II and ZV with B⁰ = 1 on clipped lqg (σ⁰ = 1) and \
        lqg1d (σ⁰ = 0.5), started near the optimum at v⁰ = −0.6 (from v⁰ = −0.1 the early \
        improvements pay for every exploration step and the printed form holds), H = 20, \
        γ = 0.99; the case count is the number of iterations"
        .into();
    b0.expected = Expected::Violated;
    b0.notes = "Violated: with B⁰ > 0 the first requirements are C = −B⁰ < 0, and the algorithm \
        spends the initial budget on bounded worsening; B^t ≥ 0 only gives \
        (J_E^t + J_T^t)/2 ≥ J_B − B⁰/2. See ERRATA §7."
        .into();
    b0.basis = "theory: B^t = B⁰ + 2[(J_E^t + J_T^t)/2 − J_B] (telescoping, \
        thm-4.1-budget-telescoping), so the guarantee is J_B − B⁰/2, and the requirement C = −B \
        lets the steps lose up to B; that the algorithm does lose performance below J_B comes \
        from the exact runs of this check (DP oracle, independent of the algorithm's own J)"
        .into();
    Check::new(b0, initial_budget_runs)
}

/// The check `sepg-sampled-violations`.
fn sampled_violations_check() -> Check {
    let mut sv = meta(
        "sepg-sampled-violations",
        "SEPG-MI and LB-I with sampled gradients: realised per-iteration violations vs δ",
        "Section 4.5, Algorithm 4.3",
        "The per-iteration guarantee (MI: J(θ^{t+1}) ≥ J(θ^t); LB-I: J(θ^t) ≥ J(θ⁰)) fails at most \
         at rate 1 − (1 − δ)³ (three estimated gradients per iteration), δ = 0.2.",
        "J of the recorded parameters evaluated exactly by the DP oracle",
    );
    sv.kind = ClaimKind::UpperBound;
    sv.sampling = "sampled SEPG (N = 100, G(PO)MDP with the leave-one-out optimal baseline, \
        t-widths at δ = 0.2) on clipped lqg and lqg1d, σ⁰ = 1, v⁰ = −0.1; the case count is the \
        number of iterations"
        .into();
    sv.cases_quick = 100;
    sv.basis = "theory, conditional on Assumption 4.6, as for the high-probability checks \
        (see thm-4.7-hp-v-update): an iteration can fail only when one of its three confidence \
        intervals misses the true gradient or a bound over-promises beyond docs/ERRATA.md §27's \
        thresholds; the J's judged are exact (DP oracle), an independent computation"
        .into();
    sv.cases_full = 500;
    sv.false_alarm_rate = "1e-3 family-wise: one-sided Clopper–Pearson test, Bonferroni across \
        the four runs (iterations of one run are treated as independent trials)"
        .into();
    Check::new(sv, sampled_violations)
}

/// The check `claim-v-star`.
fn v_star_claims_check() -> Check {
    let mut vs = meta(
        "claim-v-star",
        "Numerical claims v* ≈ −0.615 and J(v*, −∞) ≈ −7.753 (Chapter 5)",
        "Section 5.1, Table 5.1",
        "v* = (1 − √(1+4γ²))/(2γ) = −0.615 to the printed precision on both presets; \
         J(v*, −∞) = −7.753 on lqg1d, and on lqg with the transition noise η₀ that reproduces it \
         (lqg without noise gives −1.0768, see the figures).",
        "discounted Riccati iteration and closed-form J of the unclipped presets (ClosedFormOracle)",
    );
    vs.kind = ClaimKind::Equality;
    vs.tolerance = Tolerance {
        abs: 5e-4,
        rel: 0.0,
    };
    vs.sampling = "deterministic".into();
    vs.false_alarm_rate = "0: the tolerance is half a unit of the printed last digit".into();
    vs.notes = "Holds, but does not identify the setup: the printed −7.753 is lqg1d's value \
        (no transition noise), and also the value of the thesis's stated setup (lqg) with \
        transition noise η₀ = 0.28898… (figures give η₀ to full precision), which the thesis \
        leaves open; without noise lqg gives −1.0768. v* does not depend on η₀ (certainty \
        equivalence)."
        .into();
    vs.basis = "theory: v* = (1 − √(1+4γ²))/(2γ) from the scalar discounted Riccati equation, \
        and J(v*) = −E[s₀²]P − γ/(1−γ)·P·η₀² in closed form; the check compares the printed \
        values with the oracle's Riccati iteration"
        .into();
    Check::new(vs, v_star_claims)
}

/// The check `table-5.1-ordering`.
fn table_5_1_check() -> Check {
    let mut t51 = meta(
        "table-5.1-ordering",
        "Table 5.1's qualitative ordering",
        "Section 5.1.2, Table 5.1",
        "With exact gradients on lqg1d, at every checkpoint T ∈ {T/5, 2T/5, …, T}: |v−v*| of \
         LB-I, LB-II, LV and ZV ≤ that of MI (σ⁰ = 1); |v−v*| of MI and of LB-I with σ⁰ = 1 ≤ \
         with σ⁰ = 0.1.",
        "|v_T − v*| of exact-gradient runs (unclipped closed-form oracle, v* = −0.6153)",
    );
    t51.kind = ClaimKind::UpperBound;
    t51.sampling = "exact SEPG on unclipped lqg1d, v⁰ = −0.1, H = 20; the case count is the \
        last checkpoint T (the published table uses 10,000 sampled iterations)"
        .into();
    t51.cases_quick = 2000;
    t51.cases_full = 10_000;
    t51.tolerance = Tolerance { abs: 0.0, rel: 0.0 };
    t51.false_alarm_rate = "0: deterministic exact runs".into();
    t51.notes = "Holds. Only the orderings the published table shows in every row are asserted: \
        MI has the largest |v−v*| of the SEPG columns at every σ⁰, and MI and LB-I improve \
        monotonically with σ⁰. The published row σ⁰ = 1 has LB-I (0.01) below LB-II (0.021), so \
        no ordering among the faster variants is asserted; with exact gradients LB-I and LB-II \
        change order between T = 1000 and T = 5000."
        .into();
    t51.basis = "independent computation: the published Table 5.1 (orderings present in every \
        row) and the text of Section 5.1.2; theory supports both: a type-I requirement \
        C = J(θ⁰) − J(θ^t) ≤ 0 and a type-II requirement C = −B ≤ 0 give λ ≥ 1, so their safe \
        steps contain MI's at the same θ, and c(σ), d(σ) decrease in σ, so larger σ allows \
        larger steps"
        .into();
    Check::new(t51, table_5_1)
}
