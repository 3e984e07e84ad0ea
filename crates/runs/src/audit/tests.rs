//! Tests of the audit: the walk against exact J, the tests of failure counts, the verdicts.

use std::collections::BTreeMap;

use sepg_algo::core::config::Requirement;
use sepg_algo::core::statement::{Covers, Scope, Statement, StatementKind};
use sepg_mdp::lqg_model::LqgModel;
use sepg_mdp::oracle::{ClippedDpOracle, ExactOracle, Exploration, Horizon};

use super::walk::{Tally, scale};
use super::*;
use crate::folder::Summary;

const H: usize = 20;
/// w = ln 0.5 throughout.
fn w() -> f64 {
    0.5f64.ln()
}

fn exact(model: &LqgModel) -> ExactJ {
    ExactJ {
        oracle: Box::new(
            ClippedDpOracle::with_config(model, audit_dp_config()).expect("a DP exists"),
        ),
        horizon: Horizon::Finite(H),
        dim_v: 1,
    }
}

/// Exact J of N(v s, e^{2w}) on the clipped `lqg` preset, from the oracle called
/// directly (not through the audit's walk).
fn j(v: f64, w: f64) -> f64 {
    ClippedDpOracle::with_config(&LqgModel::thesis(), audit_dp_config())
        .expect("a DP exists")
        .evaluate(
            &[v],
            &Exploration::Gaussian { w: vec![w] },
            Horizon::Finite(H),
        )
        .expect("exact J")
        .j
}

/// A logged row at θ = (v, w) (target: the deterministic policy).
fn row(t: u64, v: f64, w: f64, guaranteed_w: Option<f64>) -> Row {
    Row {
        iteration: t,
        v: vec![v],
        w: vec![w],
        w_target: vec![f64::NEG_INFINITY],
        budget: 0.0,
        alpha: 1.0,
        beta: 1.0,
        guaranteed_v: None,
        guaranteed_w,
    }
}

fn statement(kind: StatementKind, scope: Scope, delta: Option<f64>, covers: Covers) -> Statement {
    Statement {
        kind,
        scope,
        delta,
        covers,
        requirement: String::new(),
        reasons: Vec::new(),
    }
}

/// Walks the rows `path[k] → path[k + 1]` (w-steps to `w_next[k]`) of requirement `r`
/// with B⁰ = `budget0` through the audit and returns its tallies and failures.
fn walk(
    r: Requirement,
    budget0: f64,
    rows: &[Row],
    next: &[(f64, f64)],
) -> (BTreeMap<&'static str, Tally>, Vec<Violation>) {
    let s = statement(StatementKind::Proven, Scope::Run, None, Covers::Exploratory);
    let plans = plans(Some(r), &s, (1, 1), 2);
    let walk = Walk {
        requirement: Some(r),
        budget0,
    };
    let steps: Vec<Step<'_>> = rows
        .iter()
        .zip(next)
        .map(|(row, &(v, w))| Step {
            row,
            next: Some((vec![v], vec![w])),
        })
        .collect();
    let mut points = Vec::new();
    for s in &steps {
        walk.points(s, &plans, &mut points);
    }
    let js = evaluate_all(&exact(&LqgModel::thesis()), points, 1, &Silent).expect("exact J");
    let j0 = js[&key(&rows[0].v, &rows[0].w)];
    let mut a = Auditor {
        tolerance: DEFAULT_TOLERANCE,
        tallies: BTreeMap::new(),
        failures: Vec::new(),
    };
    for s in &steps {
        walk.step(&mut a, &plans, s, &js, j0).expect("walk");
    }
    (a.tallies, a.failures)
}

/// Mean parameters with J(v_low) < J(v_mid) < J(v_high) at w = ln 0.5 (checked below).
const V_LOW: f64 = -0.05;
const V_MID: f64 = -0.2;
const V_HIGH: f64 = -0.5;

#[test]
fn ordering_of_the_test_parameters() {
    let (lo, mid, hi) = (j(V_LOW, w()), j(V_MID, w()), j(V_HIGH, w()));
    assert!(lo < mid && mid < hi, "{lo} {mid} {hi}");
}

#[test]
fn lb_i_compares_with_the_first_j_not_the_previous_one() {
    // θ⁰ = V_LOW, θ¹ = V_HIGH, θ² = V_MID: J falls from θ¹ to θ² but stays above J(θ⁰),
    // which LB-I allows; a θ³ = V_LOW + 0.1 below J(θ⁰) breaks it.
    let below = V_LOW + 0.1;
    assert!(j(below, w()) < j(V_LOW, w()));
    let path = [V_LOW, V_HIGH, V_MID, below];
    let rows: Vec<Row> = (0..3)
        .map(|t| row(t, path[t as usize], w(), None))
        .collect();
    let next: Vec<(f64, f64)> = path[1..].iter().map(|v| (*v, w())).collect();
    let (tallies, failures) = walk(Requirement::LbI { nu: 0.5 }, 0.0, &rows, &next);
    let t = tallies["lb-i"];
    assert_eq!((t.checked, t.failed), (3, 1));
    assert_eq!(t.worst.expect("worst").0, j(V_LOW, w()) - j(below, w()));
    let its: Vec<u64> = failures.iter().map(|f| f.iteration).collect();
    assert_eq!(its, [2]);
}

#[test]
fn budget_exact_telescopes_from_the_first_j() {
    // LB-II, B⁰ = 0: the floor is J(θ⁰) at both points of every iteration, however J
    // moved in between. θ⁰ = V_LOW, θ¹ = V_HIGH, θ² = V_MID: it holds although J falls at
    // row 1.
    let rows = [row(0, V_LOW, w(), None), row(1, V_HIGH, w(), None)];
    let (tallies, _) = walk(
        Requirement::LbII,
        0.0,
        &rows,
        &[(V_HIGH, w()), (V_MID, w())],
    );
    let t = tallies["budget-exact"];
    assert_eq!((t.checked, t.failed), (2, 0));
    let j0 = j(V_LOW, w());
    let smallest = (j(V_HIGH, w()) - j0).min(j(V_MID, w()) - j0);
    assert_eq!(t.worst.expect("worst").0, -smallest);
    // B⁰ = 0 and a first v-step that loses: broken from row 0 on; a budget B⁰ larger
    // than the loss covers it.
    let rows = [row(0, V_MID, w(), None)];
    let loss = j(V_MID, w()) - j(V_LOW, w());
    let (tallies, _) = walk(Requirement::LbII, 0.0, &rows, &[(V_LOW, w())]);
    assert_eq!(tallies["budget-exact"].failed, 1);
    let (tallies, _) = walk(Requirement::LbII, loss * 1.01, &rows, &[(V_LOW, w())]);
    assert_eq!(tallies["budget-exact"].failed, 0);
}

#[test]
fn the_floors_are_checked_after_the_v_step_too() {
    // θ⁰ = (V_MID, w); the v-step goes to V_LOW (J falls), the w-step to the σ of the
    // grid that raises J(V_LOW, ·) most. With B⁰ putting the floor J(θ⁰) − B⁰ above
    // J(θ⁰⁺½) and below J(θ¹), the point after the v-step breaks LB-II although θ¹ does
    // not.
    let w_back = (0..40)
        .map(|i| w() - 3.0 + 0.1 * f64::from(i))
        .max_by(|a, b| j(V_LOW, *a).total_cmp(&j(V_LOW, *b)))
        .expect("a grid");
    let (j0, j_mid, j_next) = (j(V_MID, w()), j(V_LOW, w()), j(V_LOW, w_back));
    assert!(j_mid + 1e-3 < j0.min(j_next), "{j_mid} {j_next} {j0}");
    let floor = 0.5 * (j_mid + j0.min(j_next));
    let budget0 = j0 - floor;
    let rows = [row(0, V_MID, w(), None)];
    let (tallies, failures) = walk(Requirement::LbII, budget0, &rows, &[(V_LOW, w_back)]);
    assert_eq!(tallies["budget-exact"].failed, 1);
    assert_eq!(failures[0].actual, j_mid);
    assert_eq!(failures[0].required, j0 - budget0);
}

#[test]
fn guarantee_w_measures_the_w_step_from_after_the_v_step() {
    // Row 0 goes from (V_LOW, w) to (V_HIGH, w + 0.1): the w-step's own gain is
    // J(V_HIGH, w + 0.1) − J(V_HIGH, w), much smaller than the gain from J(θ⁰).
    let w1 = w() + 0.1;
    let gain_w = j(V_HIGH, w1) - j(V_HIGH, w());
    let gain_total = j(V_HIGH, w1) - j(V_LOW, w());
    assert!(gain_total > gain_w + 1e-3, "{gain_total} {gain_w}");
    // A guarantee just above the w-step's gain fails; one just below holds.
    for (g, failed) in [(gain_w + 1e-4, 1), (gain_w - 1e-4, 0)] {
        let rows = [row(0, V_LOW, w(), Some(g))];
        let (tallies, _) = walk(Requirement::LbI { nu: 0.5 }, 0.0, &rows, &[(V_HIGH, w1)]);
        let t = tallies["guarantee-w"];
        assert_eq!((t.checked, t.failed), (1, failed), "guarantee {g}");
        assert_eq!(t.worst.expect("worst").0, g - gain_w);
    }
}

#[test]
fn a_guarantee_is_counted_at_every_iteration_but_fails_only_when_its_step_was_taken() {
    // Two iterations claim a v-improvement of 100 they do not deliver; only the first
    // took its step (α ≠ 0).
    let mut rows = [row(0, V_LOW, w(), None), row(1, V_MID, w(), None)];
    rows[0].guaranteed_v = Some(100.0);
    rows[1].guaranteed_v = Some(100.0);
    rows[1].alpha = 0.0;
    let (tallies, _) = walk(Requirement::Mi, 0.0, &rows, &[(V_MID, w()), (V_MID, w())]);
    let t = tallies["guarantee-v"];
    assert_eq!((t.checked, t.steps, t.failed), (2, 1, 1));
}

/// P(X ≥ k) for X ~ Binomial(n, p) summed term by term in f64 (each term from exact
/// binomial coefficients and powers; relative error below n·1e-15 for n ≤ 1000).
fn tail_by_sum(k: u64, n: u64, p: f64) -> f64 {
    let ln_choose =
        |n: u64, i: u64| -> f64 { (1..=i).map(|j| ((n - i + j) as f64 / j as f64).ln()).sum() };
    (k..=n)
        .map(|i| (ln_choose(n, i) + i as f64 * p.ln() + (n - i) as f64 * (1.0 - p).ln()).exp())
        .sum()
}

fn tally(checked: u64, steps: u64, failed: u64, first: Option<u64>) -> Tally {
    Tally {
        checked,
        steps,
        failed,
        first,
        worst: Some((1.0, first.unwrap_or(0))),
        ..Tally::default()
    }
}

#[test]
fn a_per_step_check_of_scope_iteration_divides_by_iterations_not_steps() {
    // δ = 0.2 per width, two widths (v and w) per iteration: the statement's δ is 0.4.
    // 20 failures among 40 steps taken in 300 iterations: the per-step rate 0.5 would be
    // rejected (P(Bin(40, 0.2) ≥ 20) < 1e-4), the per-iteration rate 0.067 is what δ
    // allows.
    let s = statement(
        StatementKind::Proven,
        Scope::Iteration,
        Some(0.4),
        Covers::Exploratory,
    );
    let plans = plans(Some(Requirement::Mi), &s, (1, 1), 2);
    let tests: Vec<(&str, Test, Option<f64>)> =
        plans.iter().map(|p| (p.name, p.test, p.rate)).collect();
    assert_eq!(
        tests,
        [
            ("guarantee-v", Test::Binomial, Some(0.2)),
            ("guarantee-w", Test::Binomial, Some(0.2)),
            ("mi", Test::Binomial, Some(0.4)),
        ]
    );
    assert!(tail_by_sum(20, 40, 0.2) < 1e-4);
    let judged = |failed: u64, kind| {
        let mut tallies = BTreeMap::new();
        tallies.insert("guarantee-v", tally(300, 40, failed, Some(3)));
        judge(&plans, &tallies, kind, 0.01).expect("judged")[0].clone()
    };
    let c = judged(20, StatementKind::Proven);
    let p = c.p_value.expect("p");
    assert!((p - tail_by_sum(20, 300, 0.2)).abs() <= 1e-12 * p, "{p}");
    assert_eq!(c.judgement, Judgement::Holds);
    assert_eq!((c.checked, c.steps), (300, Some(40)));
    // 90 failing iterations of 300: P(Bin(300, 0.2) ≥ 90) is below 0.01/3 (three
    // tested checks, Bonferroni).
    let c = judged(90, StatementKind::Proven);
    let p = c.p_value.expect("p");
    assert!((p - tail_by_sum(90, 300, 0.2)).abs() <= 1e-12 * p, "{p}");
    assert!(p < 0.01 / 3.0);
    assert_eq!(c.judgement, Judgement::Broken);
    // The same under an approximate statement is reported, not broken.
    assert_eq!(
        judged(90, StatementKind::Approximate).judgement,
        Judgement::Exceeded
    );
    // The boundary: the smallest count the test rejects is the first k whose tail is
    // below α/3 by the term-by-term sum.
    let k_min = (0..=300)
        .find(|&k| tail_by_sum(k, 300, 0.2) < 0.01 / 3.0)
        .expect("k");
    assert_eq!(
        judged(k_min, StatementKind::Proven).judgement,
        Judgement::Broken
    );
    assert_eq!(
        judged(k_min - 1, StatementKind::Proven).judgement,
        Judgement::Holds
    );
}

#[test]
fn a_floor_of_scope_iteration_is_tested_by_its_first_failure() {
    let s = statement(
        StatementKind::Proven,
        Scope::Iteration,
        Some(2e-4),
        Covers::Exploratory,
    );
    let plans = plans(Some(Requirement::LbII), &s, (1, 1), 2);
    let floor = plans
        .iter()
        .find(|p| p.name == "budget-exact")
        .expect("plan");
    assert_eq!((floor.test, floor.rate), (Test::FirstFailure, Some(2e-4)));
    // Widths at δ = 1e-4, two per iteration: P(first failure ≤ t) ≤ (t + 1)·2δ: a failure from iteration 9 on (p = 2e-3) is
    // below 0.01/3; one from iteration 49 (p = 1e-2) is not, however long it lasts.
    for (first, judgement) in [(9, Judgement::Broken), (49, Judgement::Holds)] {
        let mut tallies = BTreeMap::new();
        tallies.insert("budget-exact", tally(300, 0, 300 - first, Some(first)));
        let c = judge(&plans, &tallies, StatementKind::Proven, 0.01).expect("judged");
        assert_eq!(c[0].judgement, judgement, "{first}");
        let expected = (first as f64 + 1.0) * 2e-4;
        assert!((c[0].p_value.expect("p") - expected).abs() < 1e-15);
    }
}

#[test]
fn each_statement_promises_exactly_its_checks() {
    let names = |r, s: &Statement| -> Vec<(&str, Test)> {
        plans(Some(r), s, (1, 1), 2)
            .iter()
            .map(|p| (p.name, p.test))
            .collect()
    };
    let run = statement(
        StatementKind::Proven,
        Scope::Run,
        Some(0.2),
        Covers::Exploratory,
    );
    // ZV: its deterministic target and the recorded budget are reported only.
    assert_eq!(
        names(Requirement::Zv, &run),
        [
            ("guarantee-v", Test::OneFailure),
            ("guarantee-w", Test::OneFailure),
            ("budget-exact", Test::OneFailure),
            ("budget-target", Test::Reported),
            ("budget", Test::Reported),
        ]
    );
    // LV covers its target.
    let lv = Statement {
        covers: Covers::ExploratoryAndTarget,
        ..run.clone()
    };
    assert!(names(Requirement::Lv, &lv).contains(&("budget-target", Test::OneFailure)));
    // Exact gradients (δ = null) are a certainty: one failure, whatever the scope.
    let certain = statement(
        StatementKind::Proven,
        Scope::Iteration,
        None,
        Covers::Exploratory,
    );
    assert!(
        names(Requirement::Mi, &certain)
            .iter()
            .all(|(_, t)| *t == Test::OneFailure)
    );
    // Kind none promises nothing; the comparison algorithms have no checks.
    let none = statement(
        StatementKind::None,
        Scope::Run,
        Some(0.2),
        Covers::Exploratory,
    );
    assert!(
        names(Requirement::LbI { nu: 0.5 }, &none)
            .iter()
            .all(|(_, t)| *t == Test::Reported)
    );
    assert!(plans(None, &run, (1, 1), 2).is_empty());
}

#[test]
fn older_summaries_are_read_as_approximate_per_iteration_statements() {
    let derived = statement(
        StatementKind::None,
        Scope::Run,
        Some(0.2),
        Covers::Exploratory,
    );
    let summary: Summary = serde_json::from_value(serde_json::json!({
        "status": "complete", "name": "r", "sepg_version": "0", "iterations": 1,
        "final": {"v": [0.0], "w": [0.0], "sigma": [1.0], "budget": 0.0},
        "v_star": null, "abs_v_error": null, "last_j_explore": null, "last_j_target": null,
        "infeasible_iterations": 0, "below_noise_v_iterations": 0,
        "below_noise_w_iterations": 0, "trajectories": 0, "steps": 0, "wall_time_s": 0.0,
        "iterations_per_s": 0.0, "env_steps_per_s": 0.0
    }))
    .expect("an older summary");
    // δ = 0.2 per width, two widths per iteration: 0.4 per iteration.
    let (s, recorded) = judged_statement(Some(&summary), derived.clone(), 2);
    assert!(!recorded);
    assert_eq!(
        (s.kind, s.scope, s.delta),
        (StatementKind::Approximate, Scope::Iteration, Some(0.4))
    );
    assert_eq!(s.reasons, ["written before statements were recorded"]);
    // A run that promises nothing (SIM-ν, the comparison algorithms) still promises
    // nothing.
    let nothing = Statement {
        covers: Covers::None,
        ..derived
    };
    let (s, _) = judged_statement(Some(&summary), nothing, 2);
    assert_eq!(s.kind, StatementKind::None);
}

#[test]
fn the_verdict_follows_the_statement_and_a_broken_check_comes_first() {
    let check = |judgement| CheckSummary {
        check: "mi",
        test: Test::OneFailure,
        checked: 1,
        steps: None,
        failed: u64::from(judgement != Judgement::Holds),
        first_failure: None,
        longest_run: 0,
        worst_shortfall: 0.0,
        worst_iteration: 0,
        allowed_rate: None,
        p_value: None,
        judgement,
    };
    let st = |kind| statement(kind, Scope::Run, Some(0.2), Covers::Exploratory);
    let v = |j, kind, complete, exact| verdict(&[check(j)], &[], &st(kind), (3, complete), exact).0;
    use StatementKind::{Approximate, None as NoKind, Proven};
    assert_eq!(v(Judgement::Holds, Proven, true, true), Verdict::Holds);
    assert_eq!(v(Judgement::Broken, Proven, false, true), Verdict::Broken);
    assert_eq!(
        v(Judgement::Holds, Proven, false, true),
        Verdict::Incomplete
    );
    assert_eq!(
        v(Judgement::Holds, Proven, true, false),
        Verdict::NotChecked
    );
    assert_eq!(
        v(Judgement::Holds, Approximate, true, true),
        Verdict::Approximate
    );
    assert_eq!(
        v(Judgement::Exceeded, Approximate, true, true),
        Verdict::Approximate
    );
    assert_eq!(v(Judgement::Note, NoKind, true, true), Verdict::NoGuarantee);
}

#[test]
fn exact_j_does_not_depend_on_the_number_of_threads() {
    let points: Vec<Vec<u64>> = (0..24)
        .map(|i| key(&[-1.2 + 0.05 * f64::from(i)], &[w() + 0.01 * f64::from(i)]))
        .collect();
    let e = exact(&LqgModel::lqg1d());
    let many = evaluate_all(&e, points.clone(), 24, &Silent).expect("J");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let one = pool
        .install(|| evaluate_all(&e, points, 24, &Silent))
        .expect("J");
    assert_eq!(many, one);
}

/// The audit's DP against a much finer one (24 nodes, 2.5 times narrower elements, 16
/// quadrature points) on differences J(θ + h) − J(θ): near the optima of both presets
/// (the starts of the review), at small σ, and where the default resolution errs most
/// (closed loops near expansion, v > 0). The error must stay 10 times below the
/// tolerance, and the tolerance must let a failure of 1e-9 be seen.
#[test]
fn the_tolerance_exceeds_the_oracles_error_on_differences() {
    let reference = DpConfig {
        nodes_per_element: 24,
        elements_per_scale: 2.5,
        min_elements: 32,
        max_elements: 16_000,
        quad_points: 16,
    };
    let cases: [(&str, f64, f64, f64, f64); 12] = [
        ("lqg", -1.122_111_597_656_494_6, 2.0, 1e-5, 0.0),
        ("lqg", -0.615, 0.5, 1e-7, 0.0),
        ("lqg", -0.6, 0.05, 0.0, 1e-4),
        ("lqg", 0.1858, 0.3491, 0.0, 0.31),
        ("lqg", 0.0373, 0.0223, 4e-3, 0.0),
        ("lqg", 0.0474, 0.3889, 0.0, 6e-3),
        ("lqg1d", -0.608_896_117_584_795_6, 1.0, 1e-6, 0.0),
        ("lqg1d", -0.1, 1.0, 0.0, 1e-3),
        ("lqg1d", 0.1286, 0.4935, 0.0, -5.5e-4),
        ("lqg1d", -0.0189, 1.3377, 0.42, 0.0),
        ("lqg1d", 0.1502, 0.8124, -2.9e-2, 0.0),
        ("lqg1d", 0.0797, 0.0298, 0.0, 1.6e-2),
    ];
    let mut largest_tolerance: f64 = 0.0;
    for (preset, v, sigma, dv, dw) in cases {
        let model = if preset == "lqg" {
            LqgModel::thesis()
        } else {
            LqgModel::lqg1d()
        };
        let audit_oracle = exact(&model);
        let fine = ExactJ {
            oracle: Box::new(ClippedDpOracle::with_config(&model, reference).expect("DP")),
            horizon: Horizon::Finite(H),
            dim_v: 1,
        };
        let (a, b) = ([v, sigma.ln()], [v + dv, sigma.ln() + dw]);
        let d_audit = audit_oracle.j(&b).expect("J") - audit_oracle.j(&a).expect("J");
        let (ja, jb) = (fine.j(&a).expect("J"), fine.j(&b).expect("J"));
        let tolerance = DEFAULT_TOLERANCE * scale(&[ja, jb]);
        largest_tolerance = largest_tolerance.max(tolerance);
        let error = (d_audit - (jb - ja)).abs();
        assert!(
            error <= tolerance / 10.0,
            "{preset} v = {v} σ = {sigma} ({dv}, {dw}): error {error:e}, tol. {tolerance:e}"
        );
    }
    assert!(largest_tolerance < 1e-9 / 2.0, "{largest_tolerance:e}");
}
