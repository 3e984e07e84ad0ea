//! Chapter 3.4–3.5 and Chapter 4.3 bounds with exact gradients, checked against the exact
//! finite-horizon J of the clipped LQG presets (dynamic-programming oracle of `sepg-mdp`).
//!
//! Every bound is checked as "true improvement ≥ claimed bound" and "true improvement ≥ C" at
//! the steps the statement prescribes (α*, the largest safe step, the other end of the safe
//! interval) and at a step drawn inside the safe interval.

use std::cell::Cell;

use proptest::prelude::*;
use sepg_bounds::constants::{TaskConstants, c, d};
use sepg_bounds::outcome::{SafeInterval, StepOutcome};
use sepg_bounds::pirotta::{self, AdaptiveStep};
use sepg_bounds::{papini, rigorous, surrogate, v_update, w_update};

use crate::check::{
    Check, CheckContext, CheckMeta, ClaimKind, Evaluation, Expected, Figure, Outcome, Tolerance,
    fmt_f64,
};
use crate::lqg::{Preset, Task};
use crate::search::{Comparison, search};

/// One configuration: preset, γ, σ, the mean parameter v, the required improvement as a
/// multiple of C_max, a position in the safe interval, and a split ν.
#[derive(Debug, Clone)]
struct Case {
    preset: Preset,
    gamma: f64,
    sigma: f64,
    v: f64,
    c_frac: f64,
    u: f64,
    nu: f64,
}

fn case() -> impl Strategy<Value = Case> {
    let preset = prop_oneof![Just(Preset::Lqg), Just(Preset::Lqg1d)];
    let gamma = prop_oneof![
        Just(0.0),
        Just(0.5),
        Just(0.9),
        Just(0.99),
        Just(0.999),
        0.0..0.999f64
    ];
    let sigma = prop_oneof![Just(0.05), Just(0.1), Just(1.0), Just(4.0), 0.05..4.0f64];
    let v = prop_oneof![Just(-1.8), Just(-1e-3), -1.8..0.2f64];
    let c_frac = prop_oneof![Just(0.0), Just(1.0), Just(-1.0), -3.0..1.0f64];
    let u = prop_oneof![Just(0.5), Just(1.0), Just(0.0), 0.0..1.0f64];
    let nu = prop_oneof![Just(0.5), Just(0.0), Just(1.0), 0.0..1.0f64];
    (preset, gamma, sigma, v, c_frac, u, nu).prop_map(|(preset, gamma, sigma, v, c_frac, u, nu)| {
        Case {
            preset,
            gamma,
            sigma,
            v,
            c_frac,
            u,
            nu,
        }
    })
}

/// An improvement smaller than this fraction of |J| is below the oracle's resolution
/// (the DP oracle is accurate to ≈ 3e-11·|J|); such cases are skipped as degenerate.
const RESOLUTION: f64 = 1e-7;

fn resolvable(c_max: f64, j: f64) -> bool {
    c_max.abs() > RESOLUTION * j.abs().max(1.0)
}

/// The steps checked in a safe interval: a drawn one, the vertex and both ends.
fn steps(s: &SafeInterval, u: f64) -> [f64; 4] {
    [s.lo + u * (s.hi - s.lo), s.vertex, s.hi, s.lo]
}

/// Records the effective penalty κ = (first-order term − truth)/step², relative to the bound's
/// penalty: the bound holds with any penalty ≥ κ, so max κ/penalty says how conservative it is.
fn record_ratio(cell: &Cell<f64>, first_order: f64, truth: f64, step_sq_penalty: f64) {
    if step_sq_penalty > 0.0 {
        let r = (first_order - truth) / step_sq_penalty;
        if r.is_finite() {
            cell.set(cell.get().max(r));
        }
    }
}

fn ratio_figure(cell: &Cell<f64>, what: &str) -> Figure {
    Figure {
        name: format!(
            "max over cases of the effective penalty / the bound's penalty {what} (the bound \
             still holds on every case with its penalty multiplied by this)"
        ),
        value: fmt_f64(cell.get()),
    }
}

/// Divisor of the bound's penalty in the power control of the exact lower-bound checks.
const POWER_DIVISOR: f64 = 30.0;

/// Exact J of the clipped `lqg` preset at γ = 0, in closed form, independent of the DP oracle
/// and of sepg-bounds: only the first reward counts, so with s₀ ~ U[−2, 2] and a ~ N(v s₀, σ²)
///
/// ```text
/// J = −½ (E[s₀²] + E[f(v s₀)]),   f(μ) = E[clip(μ + σz, −2, 2)²]
///   f(μ) = (μ² + σ²)(Φ(b) − Φ(a)) + 2μσ(φ(a) − φ(b)) + σ²(aφ(a) − bφ(b)) + 4(Φ(a) + 1 − Φ(b)),
///   a = (−2 − μ)/σ, b = (2 − μ)/σ
/// ```
///
/// (the truncated second moment plus the clipped tails); E over s₀ by composite Simpson's rule
/// with 2000 intervals (the integrand is analytic; error below 1e-12).
fn j_lqg_gamma0(v: f64, sigma: f64) -> f64 {
    let cdf = |x: f64| 0.5 * statrs::function::erf::erfc(-x / std::f64::consts::SQRT_2);
    let pdf = |x: f64| (-0.5 * x * x).exp() / (2.0 * std::f64::consts::PI).sqrt();
    let f = |mu: f64| {
        let (a, b) = ((-2.0 - mu) / sigma, (2.0 - mu) / sigma);
        (mu * mu + sigma * sigma) * (cdf(b) - cdf(a))
            + 2.0 * mu * sigma * (pdf(a) - pdf(b))
            + sigma * sigma * (a * pdf(a) - b * pdf(b))
            + 4.0 * (cdf(a) + 1.0 - cdf(b))
    };
    let n = 2000;
    let h = 4.0 / n as f64;
    let sum: f64 = (0..=n)
        .map(|i| {
            let s = -2.0 + i as f64 * h;
            let weight = if i == 0 || i == n {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            weight * -0.5 * (s * s + f(v * s))
        })
        .sum();
    sum * h / 3.0 / 4.0
}

/// One comparison of the power control: a step on `lqg` at γ = 0 with its first-order term
/// (step·gradient²), the bound under test and the true improvement from the DP oracle and
/// from the closed form [`j_lqg_gamma0`].
struct Control {
    label: String,
    first_order: f64,
    bound: f64,
    dp: f64,
    closed: f64,
}

/// Power control of an exact lower-bound check. At the control configurations (`lqg`, γ = 0)
/// the true curvature is a sizeable fraction of the penalty (up to ≈ 5% of c at σ ≥ 2 and ≈ 7%
/// of d at σ = 1 on these steps), so by Taylor's theorem the bound with its penalty divided by
/// [`POWER_DIVISOR`] over-promises there. The expected violations come from the closed form,
/// not from the DP: every control step must (1) satisfy the bound itself against the DP, (2) be
/// predicted violated with the penalty ÷ 30 by the closed form, and (3) be seen violated by the
/// check's comparison with the DP. A failure of (2) or (3) (the check could not see a penalty 30
/// times too small) makes the outcome inconclusive; a failure of (1) is a violation.
fn power_control(ctx: &CheckContext<'_>, controls: &[Control], eval: &mut Evaluation) {
    let tol = ctx.tolerance;
    let kind = ClaimKind::LowerBound;
    let mut detected = 0;
    let mut smallest = f64::INFINITY;
    let mut problem = controls
        .is_empty()
        .then(|| "power control: the control configurations could not be evaluated".to_owned());
    for c in controls {
        let reduced = c.first_order - (c.first_order - c.bound) / POWER_DIVISOR;
        let predicted = Comparison::new(c.closed, reduced).fails(kind, tol);
        let seen = Comparison::new(c.dp, reduced).fails(kind, tol);
        if Comparison::new(c.dp, c.bound).fails(kind, tol) {
            if !matches!(eval.outcome, Outcome::Violated { .. }) {
                eval.outcome = Outcome::Violated {
                    counterexample: format!(
                        "power-control step {}: true improvement {} < bound {}",
                        c.label,
                        fmt_f64(c.dp),
                        fmt_f64(c.bound)
                    ),
                    amount: c.bound - c.dp,
                };
            }
            continue;
        }
        if predicted && seen {
            detected += 1;
            smallest = smallest.min((reduced - c.dp) / reduced.abs().max(c.dp.abs()));
        } else if problem.is_none() {
            problem = Some(format!(
                "power control: at {} the closed form {} the bound with the penalty ÷ \
                 {POWER_DIVISOR} and the check {} it (true improvement {} (DP) / {} (closed \
                 form), bound {})",
                c.label,
                if predicted {
                    "violates"
                } else {
                    "does not violate"
                },
                if seen { "sees" } else { "does not see" },
                fmt_f64(c.dp),
                fmt_f64(c.closed),
                fmt_f64(reduced)
            ));
        }
    }
    eval.figures.push(Figure {
        name: format!(
            "power control: lqg control steps at γ = 0 (expected violations predicted by the \
             closed-form J, not the DP) where the bound with its penalty ÷ {POWER_DIVISOR} is \
             violated and the check sees it; smallest relative violation"
        ),
        value: format!(
            "{detected} of {} detected; {}",
            controls.len(),
            fmt_f64(smallest)
        ),
    });
    if let Some(reason) = problem
        && !matches!(eval.outcome, Outcome::Violated { .. })
    {
        eval.outcome = Outcome::Inconclusive { reason };
    }
}

/// `lqg` at γ = 0 with its exact evaluation at (v, ln σ).
fn gamma0(v: f64, sigma: f64) -> Option<(Task, sepg_mdp::oracle::ExactEval)> {
    let task = Task::new(Preset::Lqg, 0.0)?;
    let e = task.eval(v, sigma.ln())?;
    Some((task, e))
}

/// Control steps of Theorem 4.2: the vertex of the interval for the penalty c/30 (step
/// 30/(2c)) and half of it, at σ ∈ {2, 4}, v = 0.1 (the closed form gives relative
/// violations 8–55% with c/30).
fn thm_4_2_controls(b: &crate::BoundFns) -> Option<Vec<Control>> {
    let mut out = Vec::new();
    for sigma in [2.0, 4.0] {
        let v = 0.1;
        let (task, e) = gamma0(v, sigma)?;
        let g = e.grad_v[0];
        let cc = c(&task.k, sigma).ok()?;
        for t in [0.5, 1.0] {
            let alpha = t * POWER_DIVISOR / (2.0 * cc);
            out.push(Control {
                label: format!("σ = {sigma}, v = {v}, α = {t}·30/(2c)"),
                first_order: alpha * g * g,
                bound: (b.v_update_bound)(&task.k, sigma, &[g], alpha).ok()?,
                dp: task.j(v + alpha * g, sigma.ln())? - e.j,
                closed: j_lqg_gamma0(v + alpha * g, sigma) - j_lqg_gamma0(v, sigma),
            });
        }
    }
    Some(out)
}

/// Control steps of Theorem 4.3 along ∇_wJ: step β = t·30/(2d) with t ∈ {0.1, 1} for the thesis
/// form (σ = 1, v = −0.1 and σ = 1.5, v = −1; closed form: relative violations 5–53% with
/// d/30), t = 0.1 for the rigorous form (σ = 1, v ∈ {−0.1, −0.5}; 4–6%).
fn thm_4_3_controls(rigorous_form: bool) -> Option<Vec<Control>> {
    let (configs, ts): (&[(f64, f64)], &[f64]) = if rigorous_form {
        (&[(1.0, -0.1), (1.0, -0.5)], &[0.1])
    } else {
        (&[(1.0, -0.1), (1.5, -1.0)], &[0.1, 1.0])
    };
    let mut out = Vec::new();
    for &(sigma, v) in configs {
        let (task, e) = gamma0(v, sigma)?;
        let gw = e.grad_w[0];
        let dd = d(&task.k, sigma).ok()?;
        for &t in ts {
            let beta = t * POWER_DIVISOR / (2.0 * dd);
            let dw = beta * gw;
            let bound = if rigorous_form {
                rigorous::bound(&task.k, sigma, gw, dw).ok()?
            } else {
                w_update::bound_along_j(&task.k, sigma, gw, beta).ok()?
            };
            out.push(Control {
                label: format!("σ = {sigma}, v = {v}, β = {t}·30/(2d)"),
                first_order: dw * gw,
                bound,
                dp: task.j(v, sigma.ln() + dw)? - e.j,
                closed: j_lqg_gamma0(v, sigma * dw.exp()) - j_lqg_gamma0(v, sigma),
            });
        }
    }
    Some(out)
}

fn thm_4_2(ctx: &CheckContext<'_>) -> Evaluation {
    let b = ctx.bounds;
    let ratio = Cell::new(f64::NEG_INFINITY);
    let mut eval = search(ctx, case(), |cs| {
        let Some(task) = Task::new(cs.preset, cs.gamma) else {
            return vec![];
        };
        let w = cs.sigma.ln();
        let Some(e) = task.eval(cs.v, w) else {
            return vec![];
        };
        let g = [e.grad_v[0]];
        let Ok(StepOutcome::Feasible(top)) = (b.v_safe_step)(&task.k, cs.sigma, &g, 0.0) else {
            return vec![];
        };
        if !resolvable(top.c_max, e.j) {
            return vec![];
        }
        let required = cs.c_frac * top.c_max;
        let Ok(StepOutcome::Feasible(s)) = (b.v_safe_step)(&task.k, cs.sigma, &g, required) else {
            return vec![];
        };
        let Ok(cc) = c(&task.k, cs.sigma) else {
            return vec![];
        };
        let mut out = Vec::new();
        for alpha in steps(&s, cs.u) {
            let (Some(j1), Ok(bound)) = (
                task.j(cs.v + alpha * g[0], w),
                (b.v_update_bound)(&task.k, cs.sigma, &g, alpha),
            ) else {
                return vec![];
            };
            let truth = j1 - e.j;
            record_ratio(
                &ratio,
                alpha * g[0] * g[0],
                truth,
                alpha * alpha * cc * g[0] * g[0],
            );
            out.push(Comparison::new(truth, bound));
            out.push(Comparison::new(truth, required));
        }
        out
    });
    eval.figures.push(ratio_figure(&ratio, "c(σ)"));
    let controls = thm_4_2_controls(b).unwrap_or_default();
    power_control(ctx, &controls, &mut eval);
    eval
}

/// Theorem 4.2 as implemented against the printed formulas (4.8)–(4.10), with c(σ) recomputed
/// here from its printed definition.
fn thm_4_2_closed_form(ctx: &CheckContext<'_>) -> Evaluation {
    let b = ctx.bounds;
    let strategy = (
        prop_oneof![Just(0.0), Just(0.99), 0.0..0.999f64],
        0.01..10.0f64,
        -50.0..50.0f64,
        -3.0..1.0f64,
        0.0..1.0f64,
    );
    search(ctx, strategy, |&(gamma, sigma, g, c_frac, u)| {
        let Ok(k) = TaskConstants::new(gamma, 4.0, 2.0, 4.0) else {
            return vec![];
        };
        let printed_c = 4.0 * 4.0 / ((1.0 - gamma).powi(2) * sigma * sigma)
            * (4.0 / ((2.0 * std::f64::consts::PI).sqrt() * sigma) + gamma / (2.0 * (1.0 - gamma)));
        let alpha_star = 1.0 / (2.0 * printed_c);
        let c_max = g * g / (4.0 * printed_c);
        let required = c_frac * c_max;
        let lambda = (1.0 - required / c_max).sqrt();
        let (lo, hi) = ((1.0 - lambda) * alpha_star, (1.0 + lambda) * alpha_star);
        let alpha = lo + u * (hi - lo);
        let printed_bound = alpha * g * g - alpha * alpha * printed_c * g * g;
        let (Ok(bound), Ok(StepOutcome::Feasible(s))) = (
            (b.v_update_bound)(&k, sigma, &[g], alpha),
            (b.v_safe_step)(&k, sigma, &[g], required),
        ) else {
            return vec![];
        };
        vec![
            Comparison::new(printed_bound, bound),
            Comparison::new(alpha_star, s.vertex),
            Comparison::new(c_max, s.c_max),
            Comparison::new(hi, s.hi),
        ]
    })
}

fn thm_3_10(ctx: &CheckContext<'_>) -> Evaluation {
    let ratio = Cell::new(f64::NEG_INFINITY);
    let mut eval = search(ctx, case(), |cs| {
        let Some(task) = Task::new(cs.preset, cs.gamma) else {
            return vec![];
        };
        let w = cs.sigma.ln();
        let Some(e) = task.eval(cs.v, w) else {
            return vec![];
        };
        let g = [e.grad_v[0]];
        let Ok(AdaptiveStep::Step { alpha, guarantee }) =
            pirotta::optimal_step(&task.k, cs.sigma, &g)
        else {
            return vec![];
        };
        if !resolvable(guarantee, e.j) {
            return vec![];
        }
        let Ok(cc) = c(&task.k, cs.sigma) else {
            return vec![];
        };
        let mut out = Vec::new();
        for a in [alpha, 2.0 * alpha * cs.u] {
            let (Some(j1), Ok(bound)) = (
                task.j(cs.v + a * g[0], w),
                pirotta::bound(&task.k, cs.sigma, &g, a),
            ) else {
                return vec![];
            };
            let truth = j1 - e.j;
            record_ratio(&ratio, a * g[0] * g[0], truth, a * a * cc * g[0] * g[0]);
            out.push(Comparison::new(truth, bound));
            if a == alpha {
                out.push(Comparison::new(truth, guarantee));
            }
        }
        out
    });
    eval.figures.push(ratio_figure(&ratio, "c(σ)"));
    eval
}

fn thm_3_14(ctx: &CheckContext<'_>) -> Evaluation {
    search(ctx, case(), |cs| {
        let Some(task) = Task::new(cs.preset, cs.gamma) else {
            return vec![];
        };
        let w = cs.sigma.ln();
        let Some(e) = task.eval(cs.v, w) else {
            return vec![];
        };
        let g = [e.grad_v[0]];
        let Ok(step) = papini::greedy_step(&task.k, cs.sigma, &g) else {
            return vec![];
        };
        if !resolvable(step.guarantee, e.j) {
            return vec![];
        }
        let mut out = Vec::new();
        for a in [step.alpha, 2.0 * step.alpha * cs.u] {
            let (Some(j1), Ok(bound)) = (
                task.j(cs.v + a * g[0], w),
                papini::bound(&task.k, cs.sigma, &g, &[a]),
            ) else {
                return vec![];
            };
            out.push(Comparison::new(j1 - e.j, bound));
            if a == step.alpha {
                out.push(Comparison::new(j1 - e.j, step.guarantee));
            }
        }
        out
    })
}

/// Theorem 4.3 along ∇_w J: thesis form (`rigorous = false`) or the rigorous variant.
fn w_update_along_j(ctx: &CheckContext<'_>, rigorous_form: bool) -> Evaluation {
    let ratio = Cell::new(f64::NEG_INFINITY);
    let gap = Cell::new(f64::NEG_INFINITY);
    let mut eval = search(ctx, case(), |cs| {
        let Some(task) = Task::new(cs.preset, cs.gamma) else {
            return vec![];
        };
        let w = cs.sigma.ln();
        let Some(e) = task.eval(cs.v, w) else {
            return vec![];
        };
        let gw = e.grad_w[0];
        let (Ok(c_max), Ok(dd)) = (w_update::c_max(&task.k, cs.sigma, gw), d(&task.k, cs.sigma))
        else {
            return vec![];
        };
        if !resolvable(c_max, e.j) {
            return vec![];
        }
        let required = cs.c_frac * c_max;
        let outcome = if rigorous_form {
            rigorous::safe_step_along_j(&task.k, cs.sigma, gw, required)
        } else {
            w_update::safe_step_along_j(&task.k, cs.sigma, gw, required)
        };
        let Ok(StepOutcome::Feasible(s)) = outcome else {
            return vec![];
        };
        let mut out = Vec::new();
        for beta in steps(&s, cs.u) {
            let dw = beta * gw;
            let (Some(j1), Ok(thesis), Ok(rig)) = (
                task.j(cs.v, w + dw),
                w_update::bound_along_j(&task.k, cs.sigma, gw, beta),
                rigorous::bound(&task.k, cs.sigma, gw, dw),
            ) else {
                return vec![];
            };
            let truth = j1 - e.j;
            record_ratio(&ratio, beta * gw * gw, truth, beta * beta * dd * gw * gw);
            gap.set(gap.get().max((thesis - rig) / c_max));
            out.push(Comparison::new(
                truth,
                if rigorous_form { rig } else { thesis },
            ));
            out.push(Comparison::new(truth, required));
        }
        out
    });
    eval.figures.push(ratio_figure(&ratio, "d(σ)"));
    eval.figures.push(Figure {
        name: "max over tested steps of (thesis bound − rigorous bound)/C_max^w (the neglected \
               part; positive = the thesis form over-promises)"
            .into(),
        value: fmt_f64(gap.get()),
    });
    let controls = thm_4_3_controls(rigorous_form).unwrap_or_default();
    power_control(ctx, &controls, &mut eval);
    eval
}

fn thm_4_3_thesis(ctx: &CheckContext<'_>) -> Evaluation {
    w_update_along_j(ctx, false)
}

fn thm_4_3_rigorous(ctx: &CheckContext<'_>) -> Evaluation {
    w_update_along_j(ctx, true)
}

/// The neglected terms of Theorem 4.3 against the true J: at the thesis's own safe steps
/// (4.17), on the steps where the thesis bound exceeds the rigorous one (the neglected terms
/// would matter), the exact J of the DP oracle must still improve by the thesis bound.
fn thm_4_3_neglected(ctx: &CheckContext<'_>) -> Evaluation {
    let strategy = (
        prop_oneof![Just(Preset::Lqg), Just(Preset::Lqg1d)],
        prop_oneof![Just(0.0), Just(0.5), 0.0..0.9f64],
        prop_oneof![Just(0.05), Just(0.1), Just(3.0), 0.05..4.0f64],
        prop_oneof![Just(-1.8), Just(-1e-3), -1.8..0.2f64],
        prop_oneof![Just(0.0), Just(1.0), -3.0..1.0f64],
        prop_oneof![Just(1.0), Just(0.0), 0.0..1.0f64],
    );
    let worst = Cell::new(f64::NEG_INFINITY);
    let relevant = Cell::new(0u64);
    let mut eval = search(ctx, strategy, |&(preset, gamma, sigma, v, c_frac, u)| {
        let Some(task) = Task::new(preset, gamma) else {
            return vec![];
        };
        let w = sigma.ln();
        let Some(e) = task.eval(v, w) else {
            return vec![];
        };
        let gw = e.grad_w[0];
        let Ok(c_max) = w_update::c_max(&task.k, sigma, gw) else {
            return vec![];
        };
        if !resolvable(c_max, e.j) {
            return vec![];
        }
        let Ok(StepOutcome::Feasible(s)) =
            w_update::safe_step_along_j(&task.k, sigma, gw, c_frac * c_max)
        else {
            return vec![];
        };
        let mut out = Vec::new();
        for beta in steps(&s, u) {
            let (Ok(thesis), Ok(rig)) = (
                w_update::bound_along_j(&task.k, sigma, gw, beta),
                rigorous::bound(&task.k, sigma, gw, beta * gw),
            ) else {
                return vec![];
            };
            if thesis <= rig {
                continue;
            }
            let Some(j1) = task.j(v, w + beta * gw) else {
                return vec![];
            };
            relevant.set(relevant.get() + 1);
            worst.set(worst.get().max((thesis - rig) / c_max));
            out.push(Comparison::new(j1 - e.j, thesis));
        }
        out
    });
    eval.figures.push(Figure {
        name: "steps where the thesis bound exceeds the rigorous bound (compared with the true J)"
            .into(),
        value: relevant.get().to_string(),
    });
    eval.figures.push(Figure {
        name: "max over those steps of (thesis − rigorous)/C_max^w".into(),
        value: fmt_f64(worst.get()),
    });
    eval
}

/// ∇_w L from the exact mixed derivative (Appendix B, docs/CONVENTIONS.md §3).
fn grad_w_l(k: &TaskConstants, sigma: f64, e: &sepg_mdp::oracle::ExactEval) -> Option<f64> {
    surrogate::grad_w(k, sigma, &e.grad_v, &e.mixed_sigma_v()).ok()
}

fn cor_4_4(ctx: &CheckContext<'_>) -> Evaluation {
    search(ctx, case(), |cs| {
        let Some(task) = Task::new(cs.preset, cs.gamma) else {
            return vec![];
        };
        let w = cs.sigma.ln();
        let Some(e) = task.eval(cs.v, w) else {
            return vec![];
        };
        let (Ok(l), Ok(alpha)) = (
            surrogate::surrogate(&task.k, cs.sigma, &e.grad_v),
            v_update::alpha_star(&task.k, cs.sigma),
        ) else {
            return vec![];
        };
        if !resolvable(l, e.j) {
            return vec![];
        }
        let Some(j1) = task.j(cs.v + alpha * e.grad_v[0], w) else {
            return vec![];
        };
        vec![Comparison::new(j1 - e.j, l)]
    })
}

/// c(σ) and dc/dw = σ·dc/dσ from the printed definition of Theorem 4.2, written here
/// independently of sepg-bounds.
fn c_and_dc_dw(k: &TaskConstants, sigma: f64) -> (f64, f64) {
    let (g, r, m, a) = (k.gamma(), k.r_max(), k.m_phi(), k.action_volume());
    let front = r * m * m / (1.0 - g).powi(2);
    let s2pi = (2.0 * std::f64::consts::PI).sqrt();
    // c = front·(a/(√(2π)σ³) + g/(2(1−g)σ²))
    let c = front * (a / (s2pi * sigma.powi(3)) + g / (2.0 * (1.0 - g) * sigma * sigma));
    // σ·dc/dσ = front·(−3a/(√(2π)σ³) − g/((1−g)σ²))
    let dc_dw = front * (-3.0 * a / (s2pi * sigma.powi(3)) - g / ((1.0 - g) * sigma * sigma));
    (c, dc_dw)
}

/// ∇_w L of `sepg_bounds::surrogate::grad_w` (given the exact ∂_σ∇_vJ) against the chain rule
/// written in the harness: d/dw [g²/(4mc)] = 2g·∂_w g/(4mc) − g²·(dc/dw)/(4mc²), with
/// ∂_w g = ∂²J/∂w∂v taken directly from the DP oracle (not through ∂_σ) and c, dc/dw from the
/// printed formula; and against a Richardson central difference of that harness-side L.
fn surrogate_gradient(ctx: &CheckContext<'_>) -> Evaluation {
    search(ctx, case(), |cs| {
        let Some(task) = Task::new(cs.preset, cs.gamma) else {
            return vec![];
        };
        let w = cs.sigma.ln();
        let Some(e) = task.eval(cs.v, w) else {
            return vec![];
        };
        let Some(analytic) = grad_w_l(&task.k, cs.sigma, &e) else {
            return vec![];
        };
        let (g, dg_dw) = (e.grad_v[0], e.mixed_wv[0]);
        let (c, dc_dw) = c_and_dc_dw(&task.k, cs.sigma);
        let chain = 2.0 * g * dg_dw / (4.0 * c) - g * g * dc_dw / (4.0 * c * c);
        let l_at = |dw: f64| -> Option<f64> {
            let e = task.eval(cs.v, w + dw)?;
            Some(e.grad_v[0] * e.grad_v[0] / (4.0 * c_and_dc_dw(&task.k, (w + dw).exp()).0))
        };
        let h = 1e-2;
        let fd = |h: f64| -> Option<f64> { Some((l_at(h)? - l_at(-h)?) / (2.0 * h)) };
        let (Some(f1), Some(f2)) = (fd(h), fd(2.0 * h)) else {
            return vec![];
        };
        vec![
            Comparison::new(chain, analytic),
            Comparison::new((4.0 * f1 - f2) / 3.0, analytic),
        ]
    })
}

/// Theorem 4.5 along ∇_w L, thesis form and rigorous variant.
fn thm_4_5(ctx: &CheckContext<'_>) -> Evaluation {
    search(ctx, case(), |cs| {
        let Some(task) = Task::new(cs.preset, cs.gamma) else {
            return vec![];
        };
        let w = cs.sigma.ln();
        let Some(e) = task.eval(cs.v, w) else {
            return vec![];
        };
        let gw = e.grad_w[0];
        let (Some(gl), Ok(c_max)) = (
            grad_w_l(&task.k, cs.sigma, &e),
            w_update::c_max(&task.k, cs.sigma, gw),
        ) else {
            return vec![];
        };
        if !resolvable(c_max, e.j) || gl == 0.0 {
            return vec![];
        }
        let required = cs.c_frac * c_max;
        let mut out = Vec::new();
        let thesis = w_update::safe_step_along_l(&task.k, cs.sigma, gw, gl, required);
        let rig = rigorous::safe_step_along_l(&task.k, cs.sigma, gw, gl, required);
        for (outcome, rigorous_form) in [(thesis, false), (rig, true)] {
            let Ok(StepOutcome::Feasible(s)) = outcome else {
                return vec![];
            };
            for beta in steps(&s, cs.u) {
                let bound = if rigorous_form {
                    rigorous::bound(&task.k, cs.sigma, gw, beta * gl)
                } else {
                    w_update::bound_along_l(&task.k, cs.sigma, gw, gl, beta)
                };
                let (Some(j1), Ok(bound)) = (task.j(cs.v, w + beta * gl), bound) else {
                    return vec![];
                };
                out.push(Comparison::new(j1 - e.j, bound));
                out.push(Comparison::new(j1 - e.j, required));
            }
        }
        out
    })
}

/// The combined update (4.20): largest safe v-step for (1 − ν)C, then the largest safe w-step
/// along ∇_w L at v^{t+1} for νC; the whole iteration must improve J by at least C.
fn eq_4_20(ctx: &CheckContext<'_>) -> Evaluation {
    search(ctx, case(), |cs| {
        let Some(task) = Task::new(cs.preset, cs.gamma) else {
            return vec![];
        };
        let w = cs.sigma.ln();
        let Some(e0) = task.eval(cs.v, w) else {
            return vec![];
        };
        let g = [e0.grad_v[0]];
        let (Ok(cv), Ok(cw)) = (
            v_update::c_max(&task.k, cs.sigma, &g),
            w_update::c_max(&task.k, cs.sigma, e0.grad_w[0]),
        ) else {
            return vec![];
        };
        let c_all = cs.c_frac * cv.min(cw);
        if !resolvable(cv.min(cw), e0.j) {
            return vec![];
        }
        let Ok(StepOutcome::Feasible(sv)) =
            v_update::safe_step(&task.k, cs.sigma, &g, (1.0 - cs.nu) * c_all)
        else {
            return vec![];
        };
        let v1 = cs.v + sv.hi * g[0];
        let Some(e1) = task.eval(v1, w) else {
            return vec![];
        };
        let Some(gl) = grad_w_l(&task.k, cs.sigma, &e1) else {
            return vec![];
        };
        let Ok(StepOutcome::Feasible(sw)) =
            w_update::safe_step_along_l(&task.k, cs.sigma, e1.grad_w[0], gl, cs.nu * c_all)
        else {
            return vec![];
        };
        let Some(j2) = task.j(v1, w + sw.hi * gl) else {
            return vec![];
        };
        vec![
            Comparison::new(e1.j - e0.j, (1.0 - cs.nu) * c_all),
            Comparison::new(j2 - e1.j, cs.nu * c_all),
            Comparison::new(j2 - e0.j, c_all),
        ]
    })
}

const SAMPLING: &str = "proptest: preset lqg or lqg1d (clipped); γ ∈ {0, 0.5, 0.9, 0.99, 0.999} \
or U[0, 0.999]; σ ∈ {0.05, 0.1, 1, 4} or U[0.05, 4]; v ∈ {−1.8, −0.001} or U[−1.8, 0.2]; \
C = κ·C_max with κ ∈ {0, 1 (C = C_max), −1 (bounded worsening)} or U[−3, 1]; step at \
position u ∈ {0.5, 1, 0} or U[0, 1] of the safe interval, plus its vertex and both ends; \
ν ∈ {0.5, 0, 1} or U[0, 1]. Improvements below 1e-7·|J| (beyond the oracle's resolution) are \
skipped as degenerate";

const GROUND_TRUTH: &str = "exact finite-horizon J_H (H = 20) of the clipped LQG by the \
dynamic-programming oracle of sepg-mdp (ClippedDpOracle, accurate to ≈ 3e-11·|J|); the bounds \
are stated for infinite-horizon J but J_H is the J of the time-augmented MDP with the same R, \
M_φ, |A| and policy, so they apply verbatim; R, M_φ, |A| from the preset";

const FAR: &str = "0: exact oracle values; the relative tolerance 1e-4 on improvements larger \
than 1e-7·|J| exceeds the oracle error by three orders of magnitude";

/// Basis of the expected outcome of the checks with the printed c (Theorems 3.10, 3.14, 4.2,
/// Corollary 4.4).
const BASIS_C: &str = "theory for σ ≤ 1.649 on lqg and σ ≤ 3.297 on lqg1d, where the box term of \
    c bounds the curvature of the Gaussian on ℝ (docs/ERRATA.md §27); for the larger σ sampled \
    (up to 4) the printed c is unproven for clipped Gaussians, and the expected outcome there \
    rests on the exact J of the DP oracle, an independent computation of the truth (not of the \
    bound); the power control of thm-4.2-v-update (closed-form J at γ = 0) shows that this \
    comparison sees a c 30 times too small";

/// Basis of the expected outcome of the checks with the thesis form of the w-bound.
const BASIS_D: &str = "theory where the thesis form is at most the rigorous bound \
    (sepg_bounds::rigorous, proven for every σ with the real-line constant K_W) and, for c, \
    below the thresholds of docs/ERRATA.md §27; where the thesis form exceeds the rigorous \
    bound (ERRATA §10, §27; thm-4.3-neglected-terms isolates those steps) the statement is \
    unproven and the expected outcome rests on the exact J of the DP oracle, an independent \
    computation of the truth; thm-4.3-w-update-thesis's power control (closed-form J at \
    γ = 0) shows that this comparison sees a d 30 times too small";

fn meta(id: &str, statement: &str, location: &str, claim: &str) -> CheckMeta {
    CheckMeta {
        id: id.into(),
        statement: statement.into(),
        location: location.into(),
        claim: claim.into(),
        ground_truth: GROUND_TRUTH.into(),
        sampling: SAMPLING.into(),
        kind: ClaimKind::LowerBound,
        cases_full: 1500,
        cases_quick: 150,
        tolerance: Tolerance {
            abs: 1e-13,
            rel: 1e-4,
        },
        false_alarm_rate: FAR.into(),
        expected: Expected::Holds,
        notes: String::new(),
        basis: String::new(),
    }
}

/// The checks of this module, in registry order.
pub(crate) fn checks() -> Vec<Check> {
    vec![
        thm_3_10_check(),
        thm_3_14_check(),
        thm_4_2_check(),
        thm_4_2_closed_form_check(),
        thm_4_3_thesis_check(),
        thm_4_3_rigorous_check(),
        thm_4_3_neglected_check(),
        cor_4_4_check(),
        surrogate_gradient_check(),
        thm_4_5_check(),
        eq_4_20_check(),
    ]
}

/// The check `thm-3.10-cor-3.11-adaptive-step`.
fn thm_3_10_check() -> Check {
    let mut t310 = meta(
        "thm-3.10-cor-3.11-adaptive-step",
        "Theorem 3.10 and Corollary 3.11 (Pirotta et al.'s adaptive step)",
        "Section 3.4",
        "J(θ + α∇J) − J(θ) ≥ α‖∇J‖₂² − α²c‖∇J‖₁² for α ∈ {α*, drawn in [0, 2α*]}, and at \
         α* = ‖∇‖₂²/(2c‖∇‖₁²) the improvement is ≥ α*‖∇J‖₂²/2 (sepg_bounds::pirotta).",
    );
    t310.basis = BASIS_C.into();
    t310.notes = "Holds with a large margin (see the penalty ratio). The clipped presets have one \
        mean parameter (m = 1), so ‖·‖₁ = ‖·‖₂ = ‖·‖∞ here."
        .into();
    Check::new(t310, thm_3_10)
}

/// The check `thm-3.14-diagonal-step`.
fn thm_3_14_check() -> Check {
    let mut t314 = meta(
        "thm-3.14-diagonal-step",
        "Theorem 3.14 (Papini et al.'s non-scalar step)",
        "Section 3.5",
        "J(θ + Λ∇J) − J(θ) ≥ ∇JᵀΛ∇J − c‖Λ∇J‖₁² for Λ = α_k (greedy coordinate, α_k = 1/(2c)) \
         and drawn α ∈ [0, 1/c], and the greedy step gains ≥ ‖∇J‖∞²/(4c) (sepg_bounds::papini).",
    );
    t314.basis = BASIS_C.into();
    t314.notes = "Holds (m = 1 on the clipped presets).".into();
    Check::new(t314, thm_3_14)
}

/// The check `thm-4.2-v-update`.
fn thm_4_2_check() -> Check {
    let mut t42 = meta(
        "thm-4.2-v-update",
        "Theorem 4.2, eqs. (4.8)–(4.10) (v-update with fixed σ)",
        "Section 4.3.1",
        "For α in the safe interval of (4.10) for C (its vertex α* = 1/(2c), both ends — the \
         largest ᾱ = (1 + λ_v)α* — and a drawn step): J(v + α∇_vJ, w) − J(v, w) ≥ (4.8) and ≥ C.",
    );
    t42.basis = BASIS_C.into();
    t42.notes = "Holds. The penalty ratio shows how conservative c is: the true curvature stays \
        below 6% of c on these tasks, so a c divided by 2 is not caught by the true J \
        (thm-4.2-closed-form catches it)."
        .into();
    Check::new(t42, thm_4_2)
}

/// The check `thm-4.2-closed-form`.
fn thm_4_2_closed_form_check() -> Check {
    let mut t42c = meta(
        "thm-4.2-closed-form",
        "Theorem 4.2 implementation vs the printed (4.8)–(4.10)",
        "Section 4.3.1",
        "sepg_bounds::v_update::{bound, safe_step} equal (4.8), α* = 1/(2c), C_max^v = \
         ‖∇‖∞²/(4c) and ᾱ = (1 + λ_v)α* with c recomputed from its printed definition.",
    );
    t42c.kind = ClaimKind::Equality;
    t42c.ground_truth = "the printed formulas evaluated independently in the harness".into();
    t42c.sampling = "proptest: γ ∈ {0, 0.99} or U[0, 0.999], σ ∈ U[0.01, 10], ∇ ∈ U[−50, 50], \
        C = κC_max, κ ∈ U[−3, 1], step position U[0, 1]; R = 4, M_φ = 2, |A| = 4"
        .into();
    t42c.tolerance = Tolerance {
        abs: 1e-300,
        rel: 1e-10,
    };
    t42c.cases_full = 4000;
    t42c.cases_quick = 500;
    t42c.false_alarm_rate = "0: closed forms; the tolerance absorbs rounding".into();
    t42c.notes = "Holds.".into();
    Check::new(t42c, thm_4_2_closed_form)
}

/// The check `thm-4.3-w-update-thesis`.
fn thm_4_3_thesis_check() -> Check {
    let mut t43 = meta(
        "thm-4.3-w-update-thesis",
        "Theorem 4.3, eqs. (4.15)–(4.17), thesis form (o(Δw³) neglected)",
        "Section 4.3.2; Appendix A",
        "For β in the safe interval (4.17) (vertex β* = 1/(2d), both ends, a drawn step): \
         J(v, w + β∇_wJ) − J(v, w) ≥ β∇_wJ² − β²d∇_wJ² and ≥ C.",
    );
    t43.basis = BASIS_D.into();
    t43.notes = "Holds against the true J on the presets even where the thesis form exceeds the \
        rigorous bound (figure 'neglected part'): d is far larger than the true curvature."
        .into();
    Check::new(t43, thm_4_3_thesis)
}

/// The check `thm-4.3-w-update-rigorous`.
fn thm_4_3_rigorous_check() -> Check {
    let mut t43r = meta(
        "thm-4.3-w-update-rigorous",
        "Theorem 4.3, rigorous variant (docs/CONVENTIONS.md §4: remainder at min(σ, σ'), KL direction chosen)",
        "Section 4.3.2 and Appendix A; sepg_bounds::rigorous",
        "For Δw = β∇_wJ with β in the rigorous safe interval: J(v, w + Δw) − J(v, w) ≥ f(Δw) \
         (sepg_bounds::rigorous::bound) and ≥ C.",
    );
    t43r.notes = "Holds.".into();
    t43r.basis = "theory: the rigorous bound is proven for every σ with the real-line constant \
        K_W (docs/CONVENTIONS.md §4, docs/ERRATA.md §27); the power control (closed-form J at \
        γ = 0) shows that the comparison with the exact J sees its penalty divided by 30"
        .into();
    Check::new(t43r, thm_4_3_rigorous)
}

/// The check `thm-4.3-neglected-terms`.
fn thm_4_3_neglected_check() -> Check {
    let mut t43n = meta(
        "thm-4.3-neglected-terms",
        "Theorem 4.3: the neglected o(Δw³) terms",
        "Section 4.3.2 footnote 2; Appendix A eqs. (A.9)–(A.11)",
        "At the thesis's safe steps (4.17), on every step where the thesis bound \
         β∇_wJ² − β²d∇_wJ² exceeds the provable (rigorous) bound, the true improvement \
         J(v, w + β∇_wJ) − J(v, w) is still at least the thesis bound.",
    );
    t43n.sampling = "proptest: preset lqg or lqg1d (clipped); γ ∈ {0, 0.5} or U[0, 0.9] (small \
        γ makes the neglected terms matter); σ ∈ {0.05, 0.1, 3} or U[0.05, 4]; v ∈ {−1.8, −0.001} \
        or U[−1.8, 0.2]; C = κC_max^w, κ ∈ {0, 1} or U[−3, 1]; the drawn step, the vertex and both \
        ends of the interval; only steps where the thesis bound exceeds sepg_bounds::rigorous \
        are compared"
        .into();
    t43n.notes = "Holds against the true J: where the thesis form exceeds the rigorous bound \
        (for Δw < 0 when ψ|A|/σ > (4/3)γ/(1−γ), and for σ above ψ|A|/K_W on the real line), \
        the statement is unproven (ERRATA §10, §27) but not violated on these tasks, because d is \
        far above the true curvature."
        .into();
    t43n.basis = "independent computation: the exact J of the clipped presets by the DP oracle; \
        theory does not decide these steps (the thesis form exceeds the provable bound there, \
        see the figures)"
        .into();
    Check::new(t43n, thm_4_3_neglected)
}

/// The check `cor-4.4-surrogate`.
fn cor_4_4_check() -> Check {
    let mut c44 = meta(
        "cor-4.4-surrogate",
        "Corollary 4.4 (surrogate L as guaranteed improvement)",
        "Section 4.3.3",
        "The v-update with α* = 1/(2c) improves J by at least L = ‖∇_vJ‖₂²/(4mc).",
    );
    c44.basis = BASIS_C.into();
    c44.notes = "Holds (m = 1, so L = C_max^v).".into();
    Check::new(c44, cor_4_4)
}

/// The check `app-b-surrogate-gradient`.
fn surrogate_gradient_check() -> Check {
    let mut gl = meta(
        "app-b-surrogate-gradient",
        "Appendix B (B.1) and ∂_σ∇_vJ = h − (2/σ)∇_vJ: the exact ∇_w L",
        "Appendix B; docs/CONVENTIONS.md §3",
        "sepg_bounds::surrogate::grad_w with the exact mixed derivative ∂_σ∇_vJ equals \
         d/dw [‖∇_vJ(v, w)‖²/(4m c(e^w))].",
    );
    gl.kind = ClaimKind::Equality;
    gl.ground_truth = "the chain rule 2g·∂²J/∂w∂v/(4mc) − g²(dc/dw)/(4mc²) written in the harness \
        with the DP oracle's exact ∂²J/∂w∂v and c, dc/dw from the printed formula of Theorem 4.2 \
        (no sepg-bounds code); and Richardson-extrapolated central differences (h = 1e-2, 2e-2) \
        of that harness-side L(v, w) = g²/(4mc(e^w))"
        .into();
    gl.basis =
        "theory: Corollary 4.4's L differentiated by the chain rule, computed independently \
        of the code under test"
            .into();
    gl.tolerance = Tolerance {
        abs: 1e-13,
        rel: 1e-5,
    };
    gl.cases_full = 600;
    gl.cases_quick = 60;
    gl.false_alarm_rate = "0: deterministic; finite-difference error O(h⁴) ≈ 1e-8 and the \
        oracle error amplified by 1/h (≈ 1e-8 relative) are below the 1e-5 relative tolerance"
        .into();
    gl.notes = "Holds.".into();
    Check::new(gl, surrogate_gradient)
}

/// The check `thm-4.5-w-update-along-l`.
fn thm_4_5_check() -> Check {
    let mut t45 = meta(
        "thm-4.5-w-update-along-l",
        "Theorem 4.5 and (4.19), thesis form and rigorous variant",
        "Section 4.3.3",
        "For β in the safe interval (4.19) around β̃ = ∇_wJ/(2d∇_wL) (vertex, both ends — the \
         largest β̄ = β̃ + λ_w|β̃| — and a drawn step): J(v, w + β∇_wL) − J(v, w) ≥ \
         β∇_wL∇_wJ − β²d∇_wL² and ≥ νC; the same with the rigorous interval and bound.",
    );
    t45.basis = BASIS_D.into();
    t45.notes = "Holds.".into();
    Check::new(t45, thm_4_5)
}

/// The check `eq-4.20-combined-update`.
fn eq_4_20_check() -> Check {
    let mut e420 = meta(
        "eq-4.20-combined-update",
        "Update (4.20) with the split (4.13)–(4.14)",
        "Section 4.3.3",
        "v-step ᾱ = (1 + λ_v)α* for (1 − ν)C, then w-step β̄ along ∇_wL(v^{t+1}, w) for νC, for \
         C = κ·min(C_max^v, C_max^w): each half meets its share and J(θ^{t+1}) − J(θ^t) ≥ C.",
    );
    e420.basis = BASIS_D.into();
    e420.notes = "Holds (cases where νC exceeds C_max^w at v^{t+1} are skipped).".into();
    Check::new(e420, eq_4_20)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn closed_form_at_gamma_zero_matches_the_dp_oracle() {
        // Two independent computations of the same J: the DP oracle of sepg-mdp and the
        // harness's closed form, at the control configurations and beyond the clipping.
        let task = Task::new(Preset::Lqg, 0.0).unwrap();
        for (v, sigma) in [
            (0.1, 2.0),
            (0.1, 4.0),
            (-0.1, 1.0),
            (-1.0, 1.5),
            (-1.8, 0.05),
        ] {
            let dp = task.j(v, f64::ln(sigma)).unwrap();
            assert_relative_eq!(j_lqg_gamma0(v, sigma), dp, max_relative = 1e-9);
        }
    }
}
