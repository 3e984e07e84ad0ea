//! Statements about estimated gradients: unbiasedness of the estimators (REINFORCE, G(PO)MDP,
//! PGT, ĥ of Theorem B.1 and its baseline B.2), the summation theorem, the coverage of the
//! t-intervals (Assumption 4.6), Chebyshev batch sizes (Corollary 3.13) and the
//! high-probability bounds (Theorems 3.12, 4.7–4.9), against exact oracle values.
//!
//! Probabilistic claims are tested by a one-sided exact binomial (Clopper–Pearson) test on the
//! observed violation rate; unbiasedness by a z-test on the mean of many independent batches,
//! with a Bonferroni correction across components.

use std::fmt::Write as _;

use proptest::prelude::*;
use sepg_bounds::batch_size;
use sepg_bounds::high_probability::{HighProbabilityBound, HpForm};
use sepg_bounds::outcome::StepOutcome;
use sepg_bounds::pirotta::{self, AdaptiveStep};
use sepg_estimators::{
    Baseline, BaselineFit, Estimate, Estimator, GradientSpec, Kind, Param, SurrogateEstimate, Width,
};
use sepg_mdp::Batch;
use sepg_mdp::policy::GaussianPolicy;
use sepg_mdp::rng::SeedKey;
use sepg_mdp::rollout::rollout;

use crate::check::{
    Check, CheckContext, CheckMeta, ClaimKind, Evaluation, Expected, Figure, Outcome, Tolerance,
    fmt_f64,
};
use crate::lqg::Setting;
use crate::lqg::{HORIZON, Preset, Task};
use crate::search::{Comparison, search};
use crate::stats::{
    Freq, ZTest, clopper_pearson_lower, clopper_pearson_upper, frequency_outcome, z_outcome,
};

/// Family-wise false-alarm rate of every statistical check in this module (Bonferroni across the family).
pub(crate) const FAMILY_ALPHA: f64 = 1e-3;

/// Trajectories per batch of the sampled checks (the experiments' N).
pub(crate) const N: usize = 100;

pub(crate) fn estimate(
    est: &mut Estimator,
    batch: &Batch,
    param: Param,
    spec: GradientSpec,
) -> Option<Estimate> {
    let mut out = Estimate::new();
    est.gradient(batch, param, spec, &mut out).ok()?;
    Some(out)
}

const NO_BASELINE: GradientSpec = GradientSpec {
    kind: Kind::Gpomdp,
    baseline: Baseline::None,
    fit: BaselineFit::PlugIn,
};

fn assumption_4_6(ctx: &CheckContext<'_>) -> Evaluation {
    let settings = [
        (Preset::Lqg, 1.0, -0.1),
        (Preset::Lqg, 0.2, -0.6),
        (Preset::Lqg1d, 0.5, -0.3),
    ];
    let mut tests = Vec::new();
    for (si, &(preset, sigma, v)) in settings.iter().enumerate() {
        let Some(s) = Setting::new(preset, 0.99, sigma, v, true) else {
            continue;
        };
        let deltas = [0.2, 0.05];
        // counts[delta][param] = (violations, trials)
        let mut counts = [[(0u64, 0u64); 2]; 2];
        let mut est = Estimator::new();
        for b in 0..u64::from(ctx.cases) {
            let Some(batch) = s.batch(N, ctx.seed ^ si as u64, b) else {
                continue;
            };
            for (p, (param, truth)) in
                [(Param::V, s.exact.grad_v[0]), (Param::W, s.exact.grad_w[0])]
                    .into_iter()
                    .enumerate()
            {
                let Some(e) = estimate(&mut est, &batch, param, GradientSpec::default()) else {
                    continue;
                };
                for (di, &delta) in deltas.iter().enumerate() {
                    let Ok(conf) = e.confidence(Width::StudentT, delta) else {
                        continue;
                    };
                    counts[di][p].1 += 1;
                    if (e.mean()[0] - truth).abs() > conf.eps {
                        counts[di][p].0 += 1;
                    }
                }
            }
        }
        for (di, &delta) in deltas.iter().enumerate() {
            for (p, name) in ["∇_v J", "∇_w J"].iter().enumerate() {
                tests.push(Freq {
                    name: format!("{preset:?} σ = {sigma}, v = {v}, δ = {delta}, {name}"),
                    violations: counts[di][p].0,
                    trials: counts[di][p].1,
                    allowed: delta,
                });
            }
        }
    }
    frequency_outcome(&tests, FAMILY_ALPHA)
}

/// Batch sizes of the Gaussian coverage check: small, where a wrong width is far from exact.
const GAUSSIAN_NS: [usize; 3] = [3, 5, 10];

/// Assumption 4.6 for the t-width on Gaussian per-trajectory samples, where Student's theorem
/// makes the t-interval exact: the miss rate must equal δ, tested on both sides (a width too
/// narrow or too wide fails).
fn assumption_4_6_gaussian(ctx: &CheckContext<'_>) -> Evaluation {
    let deltas = [0.2, 0.05];
    let tests = GAUSSIAN_NS.len() * deltas.len();
    let confidence = 1.0 - FAMILY_ALPHA / (2 * tests) as f64;
    let mut rng = sepg_mdp::rng::rng_from_seed(ctx.seed);
    let mut figures = Vec::new();
    let mut worst: Option<(f64, String)> = None;
    let mut margin = f64::INFINITY;
    let mut trials_total = 0;
    let mut x = Vec::new();
    for &n in &GAUSSIAN_NS {
        let (misses, trials) = gaussian_misses(&mut rng, &mut x, n, ctx.cases, &deltas);
        trials_total += trials;
        for (di, &delta) in deltas.iter().enumerate() {
            let (Ok(lo), Ok(hi)) = (
                clopper_pearson_lower(misses[di], trials, confidence),
                clopper_pearson_upper(misses[di], trials, confidence),
            ) else {
                continue;
            };
            let rate = misses[di] as f64 / trials as f64;
            let name = format!("N = {n}, δ = {delta}");
            figures.push(Figure {
                name: name.clone(),
                value: format!(
                    "{}/{} misses, rate {}, two-sided {} interval [{}, {}]",
                    misses[di],
                    trials,
                    fmt_f64(rate),
                    fmt_f64(2.0 * confidence - 1.0),
                    fmt_f64(lo),
                    fmt_f64(hi)
                ),
            });
            margin = margin.min((hi - delta).min(delta - lo));
            if lo > delta || hi < delta {
                let amount = (rate - delta).abs();
                if worst.as_ref().is_none_or(|(a, _)| amount > *a) {
                    worst = Some((
                        amount,
                        format!(
                            "{name}: miss rate {} outside [{}, {}]",
                            fmt_f64(rate),
                            fmt_f64(lo),
                            fmt_f64(hi)
                        ),
                    ));
                }
            }
        }
    }
    let outcome = match worst {
        Some((amount, counterexample)) => Outcome::Violated {
            counterexample,
            amount,
        },
        None => Outcome::HoldsWithMargin {
            margin,
            relative_margin: margin,
        },
    };
    Evaluation {
        outcome,
        cases: trials_total,
        figures,
    }
}

/// Draws `cases` batches of `n` independent N(0.5, 2²) samples and counts, for each δ of
/// `deltas`, the batches whose Student-t interval at level δ misses the mean 0.5; returns the
/// miss counts and the number of batches.
fn gaussian_misses(
    rng: &mut sepg_mdp::rng::TrajRng,
    x: &mut Vec<f64>,
    n: usize,
    cases: u32,
    deltas: &[f64; 2],
) -> ([u64; 2], u64) {
    let mut misses = [0u64; 2];
    let mut trials = 0u64;
    for _ in 0..cases {
        x.clear();
        x.extend((0..n).map(|_| 0.5 + 2.0 * sepg_mdp::rng::standard_normal(rng)));
        let mean = x.iter().sum::<f64>() / n as f64;
        let var = x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n as f64 - 1.0);
        trials += 1;
        for (di, &delta) in deltas.iter().enumerate() {
            let Ok(eps) = sepg_estimators::width(Width::StudentT, var, n, delta) else {
                continue;
            };
            if (mean - 0.5).abs() > eps {
                misses[di] += 1;
            }
        }
    }
    (misses, trials)
}

/// Which high-probability theorem.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Hp {
    /// Theorem 4.7: v-update along ∇̂_v J.
    V,
    /// Theorem 4.8: w-update along ∇̂_w J.
    WJ,
    /// Theorem 4.9: w-update along ∇̂_w L.
    WL,
}

/// Which requirement and which end of the safe interval.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Requirement {
    /// C = 0 at the largest step (hi) and C = C_max at the vertex.
    NonNegative,
    /// C = −C_max/10 at the end of the interval opposite to the favoured direction.
    Negative,
}

/// Runs `batches` batches of one high-probability theorem and counts realised violations.
#[allow(clippy::too_many_arguments)]
fn hp_counts(
    s: &Setting,
    which: Hp,
    form: HpForm,
    req: Requirement,
    delta: f64,
    seed: u64,
    batches: u32,
    scale: f64,
) -> Vec<(u64, u64, &'static str)> {
    let mut counts = match req {
        Requirement::NonNegative => {
            vec![(0, 0, "C = 0, largest step"), (0, 0, "C = C_max, vertex")]
        }
        Requirement::Negative => vec![(0, 0, "C = −C_max/10, step opposite to the estimate")],
    };
    let mut est = Estimator::new();
    let tol = 1e-9 * s.exact.j.abs().max(1.0);
    for b in 0..u64::from(batches) {
        let Some(batch) = s.batch(N, seed, b) else {
            continue;
        };
        let (Some(gv), Some(gw)) = (
            estimate(&mut est, &batch, Param::V, GradientSpec::default()),
            estimate(&mut est, &batch, Param::W, GradientSpec::default()),
        ) else {
            continue;
        };
        let (Ok(cv), Ok(cw)) = (
            gv.confidence(Width::StudentT, delta),
            gw.confidence(Width::StudentT, delta),
        ) else {
            continue;
        };
        let Some((bound, direction)) = hp_bound(
            s,
            which,
            &mut est,
            &batch,
            (&gv, &gw),
            (cv.eps, cw.eps, delta),
        ) else {
            continue;
        };
        let c_max = bound.c_max();
        let plan: Vec<(f64, bool)> = match req {
            Requirement::NonNegative => vec![(0.0, true), (c_max, false)],
            Requirement::Negative => vec![(-0.1 * c_max, true)],
        };
        for (i, (required, far)) in plan.into_iter().enumerate() {
            let Ok(StepOutcome::Feasible(interval)) = bound.safe_step(required, form) else {
                continue;
            };
            let x = match req {
                Requirement::NonNegative if far => interval.hi,
                Requirement::NonNegative => interval.vertex,
                Requirement::Negative => {
                    if bound.direction > 0.0 {
                        interval.lo
                    } else {
                        interval.hi
                    }
                }
            };
            let step = scale * x * direction;
            let j1 = match which {
                Hp::V => s.task.j(s.v + step, s.w),
                Hp::WJ | Hp::WL => s.task.j(s.v, s.w + step),
            };
            let Some(j1) = j1 else { continue };
            counts[i].1 += 1;
            if j1 - s.exact.j < required - tol {
                counts[i].0 += 1;
            }
        }
    }
    counts
}

/// The high-probability bound of theorem `which` on one batch, from the batch's gradient
/// estimates `(∇̂_v J, ∇̂_w J)` and `(ε_v, ε_wJ, δ)`, with the estimated direction of its step;
/// `None` when an estimate or the bound is unavailable.
fn hp_bound(
    s: &Setting,
    which: Hp,
    est: &mut Estimator,
    batch: &Batch,
    (gv, gw): (&Estimate, &Estimate),
    (eps_v, eps_w, delta): (f64, f64, f64),
) -> Option<(HighProbabilityBound, f64)> {
    let (bound, direction) = match which {
        Hp::V => (
            HighProbabilityBound::v_update(s.k(), s.sigma, gv.mean(), eps_v),
            gv.mean()[0],
        ),
        Hp::WJ => (
            HighProbabilityBound::w_along_j(s.k(), s.sigma, gw.mean()[0], eps_w),
            gw.mean()[0],
        ),
        Hp::WL => {
            let mut sur = SurrogateEstimate::new();
            if est
                .surrogate_gradient_for_task(batch, GradientSpec::default(), s.k(), &mut sur)
                .is_err()
            {
                return None;
            }
            let Ok(cl) = sur.grad_w_l().confidence(Width::StudentT, delta) else {
                return None;
            };
            let gl = sur.grad_w_l().mean()[0];
            (
                HighProbabilityBound::w_along_l(s.k(), s.sigma, gw.mean()[0], eps_w, gl, cl.eps),
                gl,
            )
        }
    };
    let Ok(Some(bound)) = bound else {
        return None;
    };
    Some((bound, direction))
}

pub(crate) fn hp_settings() -> [(Preset, f64, f64); 2] {
    [(Preset::Lqg, 1.0, -0.1), (Preset::Lqg1d, 0.5, -0.3)]
}

/// Allowed violation rate: (1 − δ)^m guarantee with m estimated gradients.
fn allowed(which: Hp, delta: f64) -> f64 {
    match which {
        Hp::V | Hp::WJ => delta,
        Hp::WL => 1.0 - (1.0 - delta) * (1.0 - delta),
    }
}

/// Power control of the frequency checks: the same steps multiplied by these factors (what a
/// c or d that many times too small would produce), tried in turn until the check sees the
/// guarantee fail; the first factor detected is reported.
const POWER_SCALES: [f64; 4] = [30.0, 100.0, 1000.0, 10_000.0];

/// Batches of the power control (per setting, theorem and factor).
const POWER_BATCHES: u32 = 100;

/// The frequency tests of `theorems` on the high-probability settings, steps × `scale`.
fn hp_tests(
    ctx: &CheckContext<'_>,
    theorems: &[Hp],
    form: HpForm,
    req: Requirement,
    batches: u32,
    scale: f64,
) -> Vec<Freq> {
    let delta = 0.2;
    let mut tests = Vec::new();
    for (si, &(preset, sigma, v)) in hp_settings().iter().enumerate() {
        let Some(s) = Setting::new(preset, 0.9, sigma, v, true) else {
            continue;
        };
        for &which in theorems {
            let seed = ctx.seed ^ si as u64;
            let counts = hp_counts(&s, which, form, req, delta, seed, batches, scale);
            for (violations, trials, label) in counts {
                let prefix = if scale == 1.0 {
                    String::new()
                } else {
                    format!("power control (steps × {scale}): ")
                };
                tests.push(Freq {
                    name: format!(
                        "{prefix}{which:?} on {preset:?} σ = {sigma}, v = {v}, δ = {delta}, \
                         {label}"
                    ),
                    violations,
                    trials,
                    allowed: allowed(which, delta),
                });
            }
        }
    }
    tests
}

fn hp_check(ctx: &CheckContext<'_>, theorems: &[Hp], form: HpForm, req: Requirement) -> Evaluation {
    let mut eval = frequency_outcome(
        &hp_tests(ctx, theorems, form, req, ctx.cases, 1.0),
        FAMILY_ALPHA,
    );
    if !matches!(eval.outcome, Outcome::HoldsWithMargin { .. }) {
        return eval;
    }
    // Power control: the check must be able to see a guarantee fail.
    let batches = ctx.cases.min(POWER_BATCHES);
    let mut detected_at = None;
    for scale in POWER_SCALES {
        let control = frequency_outcome(
            &hp_tests(ctx, theorems, form, req, batches, scale),
            FAMILY_ALPHA,
        );
        if matches!(control.outcome, Outcome::Violated { .. }) {
            detected_at = Some(scale);
            eval.figures.extend(control.figures);
            break;
        }
    }
    eval.figures.push(Figure {
        name: "power control: smallest step factor whose violations the check detects".into(),
        value: detected_at.map_or_else(|| "none up to 10000".into(), |x| format!("{x}")),
    });
    eval
}

fn thm_4_7(ctx: &CheckContext<'_>) -> Evaluation {
    hp_check(ctx, &[Hp::V], HpForm::SignAware, Requirement::NonNegative)
}

fn thm_4_8(ctx: &CheckContext<'_>) -> Evaluation {
    hp_check(ctx, &[Hp::WJ], HpForm::SignAware, Requirement::NonNegative)
}

fn thm_4_9(ctx: &CheckContext<'_>) -> Evaluation {
    hp_check(ctx, &[Hp::WL], HpForm::SignAware, Requirement::NonNegative)
}

fn negative_c_printed(ctx: &CheckContext<'_>) -> Evaluation {
    hp_check(
        ctx,
        &[Hp::V, Hp::WJ, Hp::WL],
        HpForm::Thesis,
        Requirement::Negative,
    )
}

fn negative_c_sign_aware(ctx: &CheckContext<'_>) -> Evaluation {
    hp_check(
        ctx,
        &[Hp::V, Hp::WJ, Hp::WL],
        HpForm::SignAware,
        Requirement::Negative,
    )
}

fn thm_3_12(ctx: &CheckContext<'_>) -> Evaluation {
    let delta = 0.2;
    let mut tests = Vec::new();
    for (si, &(preset, sigma, v)) in hp_settings().iter().enumerate() {
        let Some(s) = Setting::new(preset, 0.9, sigma, v, true) else {
            continue;
        };
        let (mut violations, mut trials) = (0, 0);
        let mut est = Estimator::new();
        let tol = 1e-9 * s.exact.j.abs().max(1.0);
        for b in 0..u64::from(ctx.cases) {
            let Some(batch) = s.batch(N, ctx.seed ^ si as u64, b) else {
                continue;
            };
            let Some(g) = estimate(&mut est, &batch, Param::V, GradientSpec::default()) else {
                continue;
            };
            let Ok(conf) = g.confidence(Width::StudentT, delta) else {
                continue;
            };
            let Ok(AdaptiveStep::Step { alpha, guarantee }) =
                pirotta::hp_optimal_step(s.k(), sigma, g.mean(), &[conf.eps])
            else {
                continue;
            };
            let Some(j1) = s.task.j(v + alpha * g.mean()[0], s.w) else {
                continue;
            };
            trials += 1;
            if j1 - s.exact.j < guarantee - tol {
                violations += 1;
            }
        }
        tests.push(Freq {
            name: format!("{preset:?} σ = {sigma}, v = {v}, δ = {delta}, α* = vertex"),
            violations,
            trials,
            allowed: delta,
        });
    }
    frequency_outcome(&tests, FAMILY_ALPHA)
}

/// Chebyshev batch sizes (Corollary 3.13): the batch size for ε, δ and the violation count of
/// |∇̂ − ∇| > ε over independent batches of that size.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Chebyshev {
    Gpomdp,
    ReinforceCorrected,
    ReinforcePrinted,
}

fn cor_3_13(ctx: &CheckContext<'_>, which: Chebyshev) -> Evaluation {
    let (gamma, sigma, v, delta) = (0.5, 1.0, -0.3, 0.2);
    let Some(s) = Setting::new(Preset::Lqg, gamma, sigma, v, true) else {
        return frequency_outcome(&[], FAMILY_ALPHA);
    };
    let k = *s.k();
    let (eps, kind) = match which {
        Chebyshev::Gpomdp => (1.5, Kind::Gpomdp),
        Chebyshev::ReinforceCorrected | Chebyshev::ReinforcePrinted => (4.0, Kind::Reinforce),
    };
    let n = match which {
        Chebyshev::Gpomdp => batch_size::gpomdp(&k, sigma, delta, eps, HORIZON as u32),
        Chebyshev::ReinforceCorrected => {
            batch_size::reinforce(&k, sigma, delta, eps, HORIZON as u32)
        }
        Chebyshev::ReinforcePrinted => {
            let (r, m) = (k.r_max(), k.m_phi());
            let h = HORIZON as f64;
            let printed = r * r * m * m * h * gamma.powi(2 * HORIZON as i32)
                / (delta * eps * eps * sigma * sigma * (1.0 - delta).powi(2));
            Ok(printed.ceil().max(1.0) as u64)
        }
    };
    let Ok(n) = n else {
        return frequency_outcome(&[], FAMILY_ALPHA);
    };
    let spec = GradientSpec {
        kind,
        ..NO_BASELINE
    };
    let batch_n = usize::try_from(n).unwrap_or(usize::MAX).max(2);
    let (mut violations, mut trials) = (0, 0);
    let mut est = Estimator::new();
    let batches = ctx.cases;
    for b in 0..u64::from(batches) {
        let Some(batch) = s.batch(batch_n, ctx.seed, b) else {
            continue;
        };
        let Some(g) = estimate(&mut est, &batch, Param::V, spec) else {
            continue;
        };
        trials += 1;
        if (g.mean()[0] - s.exact.grad_v[0]).abs() > eps {
            violations += 1;
        }
    }
    let mut eval = frequency_outcome(
        &[Freq {
            name: format!("{which:?}: N = {n} (batches of max(N, 2)), ε = {eps}, δ = {delta}"),
            violations,
            trials,
            allowed: delta,
        }],
        FAMILY_ALPHA,
    );
    eval.figures.push(Figure {
        name: "batch size N from the formula".into(),
        value: n.to_string(),
    });
    eval
}

fn cor_3_13_gpomdp(ctx: &CheckContext<'_>) -> Evaluation {
    cor_3_13(ctx, Chebyshev::Gpomdp)
}

fn cor_3_13_reinforce(ctx: &CheckContext<'_>) -> Evaluation {
    cor_3_13(ctx, Chebyshev::ReinforceCorrected)
}

fn cor_3_13_reinforce_printed(ctx: &CheckContext<'_>) -> Evaluation {
    cor_3_13(ctx, Chebyshev::ReinforcePrinted)
}

/// PGT and G(PO)MDP samples are equal trajectory by trajectory (summation theorem).
fn summation(ctx: &CheckContext<'_>) -> Evaluation {
    let strategy = (
        prop_oneof![Just(Preset::Lqg), Just(Preset::Lqg1d)],
        prop_oneof![Just(0.99), 0.0..0.999f64],
        prop_oneof![Just(0.1), 0.05..2.0f64],
        -1.8..0.2f64,
        any::<u64>(),
        prop_oneof![
            Just(Baseline::None),
            Just(Baseline::Mean),
            Just(Baseline::Optimal)
        ],
    );
    search(
        ctx,
        strategy,
        |&(preset, gamma, sigma, v, seed, baseline)| {
            let Some(task) = Task::new(preset, gamma) else {
                return vec![];
            };
            let (Some(env), Ok(policy)) = (task.env(), GaussianPolicy::scalar(v, sigma.ln()))
            else {
                return vec![];
            };
            let Ok(batch) = rollout(&env, &policy, 20, HORIZON, SeedKey::new(seed, 0, 0)) else {
                return vec![];
            };
            let mut est = Estimator::new();
            let mut out = Vec::new();
            for param in [Param::V, Param::W] {
                let spec = |kind| GradientSpec {
                    kind,
                    baseline,
                    fit: BaselineFit::LeaveOneOut,
                };
                let (Some(p), Some(g)) = (
                    estimate(&mut est, &batch, param, spec(Kind::Pgt)),
                    estimate(&mut est, &batch, param, spec(Kind::Gpomdp)),
                ) else {
                    return vec![];
                };
                let scale = g
                    .samples()
                    .iter()
                    .fold(f64::MIN_POSITIVE, |m, x| m.max(x.abs()));
                out.extend(
                    p.samples()
                        .iter()
                        .zip(g.samples())
                        .map(|(a, b)| Comparison::new(a / scale, b / scale)),
                );
            }
            out
        },
    )
}

/// Batch means of one estimator over `batches` independent batches.
fn batch_means(
    s: &Setting,
    seed: u64,
    batches: u32,
    mut f: impl FnMut(&mut Estimator, &Batch) -> Option<f64>,
) -> Vec<f64> {
    let mut est = Estimator::new();
    (0..u64::from(batches))
        .filter_map(|b| {
            let batch = s.batch(N, seed, b)?;
            f(&mut est, &batch)
        })
        .collect()
}

fn unbiased(ctx: &CheckContext<'_>) -> Evaluation {
    let mut tests = Vec::new();
    for (preset, sigma, v) in [(Preset::Lqg, 0.5, -0.3), (Preset::Lqg1d, 1.0, -0.6)] {
        let Some(s) = Setting::new(preset, 0.9, sigma, v, false) else {
            continue;
        };
        for kind in [Kind::Reinforce, Kind::Gpomdp, Kind::Pgt] {
            for baseline in [Baseline::None, Baseline::Mean, Baseline::Optimal] {
                for (param, truth) in [(Param::V, s.exact.grad_v[0]), (Param::W, s.exact.grad_w[0])]
                {
                    let spec = GradientSpec {
                        kind,
                        baseline,
                        fit: BaselineFit::LeaveOneOut,
                    };
                    tests.push(ZTest {
                        name: format!("{preset:?} (unclipped) {kind:?} {baseline:?} {param:?}"),
                        samples: batch_means(&s, ctx.seed, ctx.cases, |est, batch| {
                            estimate(est, batch, param, spec).map(|e| e.mean()[0])
                        }),
                        truth,
                    });
                }
            }
        }
    }
    z_outcome(&tests, FAMILY_ALPHA)
}

/// h(θ) = ∂_σ∇_vJ + (2/σ)∇_vJ from the oracle (Appendix B).
fn exact_h(s: &Setting) -> f64 {
    s.exact.mixed_sigma_v()[0] + 2.0 * s.exact.grad_v[0] / s.sigma
}

fn h_settings() -> [(Preset, f64, f64, bool); 3] {
    [
        (Preset::Lqg, 0.5, -0.3, true),
        (Preset::Lqg1d, 1.0, -0.6, true),
        (Preset::Lqg, 0.5, -0.3, false),
    ]
}

fn h_mean(est: &mut Estimator, batch: &Batch, baseline: Baseline) -> Option<Estimate> {
    let mut out = Estimate::new();
    est.h(batch, baseline, BaselineFit::LeaveOneOut, &mut out)
        .ok()?;
    Some(out)
}

fn thm_b_1(ctx: &CheckContext<'_>) -> Evaluation {
    let mut tests = Vec::new();
    for (preset, sigma, v, clipped) in h_settings() {
        let Some(s) = Setting::new(preset, 0.9, sigma, v, clipped) else {
            continue;
        };
        tests.push(ZTest {
            name: format!("{preset:?} clipped = {clipped}, σ = {sigma}, v = {v}: ĥ (B.3)"),
            samples: batch_means(&s, ctx.seed, ctx.cases, |est, batch| {
                h_mean(est, batch, Baseline::None).map(|e| e.mean()[0])
            }),
            truth: exact_h(&s),
        });
    }
    z_outcome(&tests, FAMILY_ALPHA)
}

fn baseline_b_2(ctx: &CheckContext<'_>) -> Evaluation {
    let mut tests = Vec::new();
    let mut ratios = String::new();
    let mut worst_ratio = 0.0f64;
    for (preset, sigma, v, clipped) in h_settings() {
        let Some(s) = Setting::new(preset, 0.9, sigma, v, clipped) else {
            continue;
        };
        let (mut var_none, mut var_opt) = (0.0, 0.0);
        let samples = batch_means(&s, ctx.seed, ctx.cases, |est, batch| {
            let none = h_mean(est, batch, Baseline::None)?;
            let opt = h_mean(est, batch, Baseline::Optimal)?;
            var_none += none.variance()[0];
            var_opt += opt.variance()[0];
            Some(opt.mean()[0])
        });
        let ratio = var_opt / var_none;
        worst_ratio = worst_ratio.max(ratio);
        let _ = write!(
            ratios,
            "{preset:?} clipped = {clipped}: {}; ",
            fmt_f64(ratio)
        );
        tests.push(ZTest {
            name: format!(
                "{preset:?} clipped = {clipped}, σ = {sigma}, v = {v}: ĥ with baseline B.2"
            ),
            samples,
            truth: exact_h(&s),
        });
    }
    let mut eval = z_outcome(&tests, FAMILY_ALPHA);
    eval.figures.push(Figure {
        name: "per-trajectory variance with the B.2 baseline / without".into(),
        value: ratios,
    });
    if !matches!(eval.outcome, Outcome::Violated { .. })
        && (worst_ratio.is_nan() || worst_ratio >= 1.0)
    {
        eval.outcome = Outcome::Violated {
            counterexample: format!("variance ratio {} ≥ 1", fmt_f64(worst_ratio)),
            amount: worst_ratio - 1.0,
        };
    }
    eval
}

/// Basis of the expected outcome of the high-probability checks.
pub(crate) const BASIS_HP: &str = "theory, conditional on Assumption 4.6: at these settings (σ \
    below the thresholds of docs/ERRATA.md §27) the bounds hold for the true gradient, so a step \
    can fail its guarantee only when a confidence interval misses the true gradient, and the \
    failure rate is at most the intervals' miss rate; the t-interval's miss rate on these \
    batches is close to but not exactly δ (assumption-4.6-t-coverage measures it), so the \
    expected outcome also relies on the slack of c and d, measured against exact J by the exact \
    checks (thm-4.2-v-update, thm-4.3-w-update-*), an independent computation";

pub(crate) fn meta(
    id: &str,
    statement: &str,
    location: &str,
    claim: &str,
    ground_truth: &str,
) -> CheckMeta {
    CheckMeta {
        id: id.into(),
        statement: statement.into(),
        location: location.into(),
        claim: claim.into(),
        ground_truth: ground_truth.into(),
        sampling: String::new(),
        kind: ClaimKind::UpperBound,
        cases_full: 2000,
        cases_quick: 200,
        tolerance: Tolerance { abs: 0.0, rel: 0.0 },
        false_alarm_rate: format!(
            "{FAMILY_ALPHA} family-wise: one-sided Clopper–Pearson test of each claimed rate, \
             Bonferroni across the tests of the check"
        ),
        expected: Expected::Holds,
        notes: String::new(),
        basis: String::new(),
    }
}

pub(crate) const DP_TRUTH: &str = "exact J_H and gradients of the clipped preset (DP oracle), \
realised improvement J(θ′) − J(θ) evaluated exactly for the step computed from each batch";

const Z_FAR: &str = "1e-3 family-wise: two-sided z-test of the mean of independent batch \
estimates (N = 100 each), Bonferroni across components";

/// The checks of this module, in registry order.
/// Settings of the Appendix B checks (Theorem B.1 and the baseline B.2).
const B_SAMPLING: &str = "lqg (σ = 0.5, v = −0.3) clipped and unclipped, lqg1d (σ = 1, v = −0.6) \
        clipped, γ = 0.9; independent batches of N = 100 (one per case)";

const HP_SAMPLING: &str = "fixed settings lqg (σ = 1, v = −0.1) and lqg1d (σ = 0.5, v = −0.3), \
        γ = 0.9, N = 100 trajectories per batch, G(PO)MDP with the leave-one-out optimal \
        baseline, t-widths at δ = 0.2; independent batches (one per case)";
const CHEB_SAMPLING: &str = "lqg (clipped), γ = 0.5, σ = 1, v = −0.3, H = 20, δ = 0.2, no \
        baseline; independent batches (one per case) of the formula's size N (at least 2)";

pub(crate) fn checks() -> Vec<Check> {
    vec![
        thm_3_12_check(),
        cor_3_13_gpomdp_check(),
        cor_3_13_reinforce_check(),
        cor_3_13_reinforce_printed_check(),
        assumption_4_6_check(),
        assumption_4_6_gaussian_check(),
        thm_4_7_check(),
        thm_4_8_check(),
        thm_4_9_check(),
        negative_c_printed_check(),
        negative_c_sign_aware_check(),
        summation_check(),
        unbiased_check(),
        thm_b_1_check(),
        baseline_b_2_check(),
    ]
}

/// The check `thm-3.12-hp-adaptive-step`.
fn thm_3_12_check() -> Check {
    let mut t312 = meta(
        "thm-3.12-hp-adaptive-step",
        "Theorem 3.12 (high-probability adaptive step, vertex form)",
        "Section 3.4.1",
        "With per-component t-widths, the step α* maximising the printed bound (vertex, \
         sepg_bounds::pirotta::hp_optimal_step) improves J by at least its guarantee except with \
         probability ≤ 1 − (1 − δ)^m (m = 1).",
        DP_TRUTH,
    );
    t312.sampling = HP_SAMPLING.into();
    t312.basis = BASIS_HP.into();
    t312.notes = "Holds (the printed α*, with ‖∇⁻‖₁² in the denominator, is not the vertex: see \
        ERRATA.md)."
        .into();
    Check::new(t312, thm_3_12)
}

/// The check `cor-3.13-gpomdp-batch-size`.
fn cor_3_13_gpomdp_check() -> Check {
    let mut c313g = meta(
        "cor-3.13-gpomdp-batch-size",
        "Corollary 3.13, G(PO)MDP/PGT batch size",
        "Section 3.4.1",
        "With N from the G(PO)MDP formula for ε = 1.5, P(|∇̂ − ∇| > ε) ≤ δ.",
        "exact ∇_vJ of the clipped preset (DP oracle)",
    );
    c313g.sampling = CHEB_SAMPLING.into();
    c313g.notes = "Holds with a large margin (Chebyshev is loose).".into();
    Check::new(c313g, cor_3_13_gpomdp)
}

/// The check `cor-3.13-reinforce-batch-size`.
fn cor_3_13_reinforce_check() -> Check {
    let mut c313r = meta(
        "cor-3.13-reinforce-batch-size",
        "Corollary 3.13, REINFORCE batch size as in the source (H(1−γ^H)²/(1−γ)²)",
        "Section 3.4.1; Pirotta et al. 2013, Theorem 5.4",
        "With N from the corrected REINFORCE formula for ε = 4, P(|∇̂ − ∇| > ε) ≤ δ.",
        "exact ∇_vJ of the clipped preset (DP oracle)",
    );
    c313r.sampling = CHEB_SAMPLING.into();
    c313r.notes = "Holds.".into();
    Check::new(c313r, cor_3_13_reinforce)
}

/// The check `cor-3.13-reinforce-printed`.
fn cor_3_13_reinforce_printed_check() -> Check {
    let mut c313p = meta(
        "cor-3.13-reinforce-printed",
        "Corollary 3.13, REINFORCE batch size as printed (H(γ^H)²/(δε²σ²(1−δ)²))",
        "Section 3.4.1",
        "With N from the printed REINFORCE formula for ε = 4, P(|∇̂ − ∇| > ε) ≤ δ.",
        "exact ∇_vJ of the clipped preset (DP oracle)",
    );
    c313p.sampling = CHEB_SAMPLING.into();
    c313p.expected = Expected::Violated;
    c313p.notes = "Violated: the printed count vanishes as H grows (N = 1 here; batches of 2 are \
        used) and the error exceeds ε far more often than δ. See ERRATA.md."
        .into();
    Check::new(c313p, cor_3_13_reinforce_printed)
}

/// The check `assumption-4.6-t-coverage`.
fn assumption_4_6_check() -> Check {
    let mut a46 = meta(
        "assumption-4.6-t-coverage",
        "Assumption 4.6 with the t-based widths of Section 4.5",
        "Section 4.5, eq. (4.22) and the t-interval",
        "P(|∇̂_i − ∇_i| > ε_i) ≤ δ with ε_i = t(1−δ/2, N−1)·√(Var̂/N), for ∇_v J and ∇_w J.",
        "exact gradients of the clipped presets (DP oracle)",
    );
    a46.sampling = "lqg (σ = 1, v = −0.1), lqg (σ = 0.2, v = −0.6), lqg1d (σ = 0.5, v = −0.3), \
        γ = 0.99, N = 100, G(PO)MDP with the leave-one-out optimal baseline, δ ∈ {0.2, 0.05}; \
        independent batches (one per case)"
        .into();
    a46.cases_quick = 2000;
    a46.expected = Expected::Violated;
    a46.notes = "Violated: at N = 100 the t-interval under-covers (realised miss rates up to \
        0.085 for δ = 0.05 and 0.236 for δ = 0.2): the returns and scores are skewed and \
        heavy-tailed, and the t-interval is only asymptotically valid, as Section 4.5 concedes. \
        The high-probability guarantees built on it still hold on these tasks \
        (thm-4.7-hp-v-update, …) because the bounds are conservative. See ERRATA.md."
        .into();
    a46.basis = "independent computation: the coverage study of \
        crates/estimators/tests/coverage.rs (other batches and seeds) measures the same \
        under-coverage at N = 100; theory explains it (the t-interval is exact only for Gaussian \
        samples, and these per-trajectory samples are skewed, with excess kurtosis ≈ 10) but does \
        not give its size. The width itself is checked against theory by \
        assumption-4.6-t-coverage-gaussian"
        .into();
    Check::new(a46, assumption_4_6)
}

/// The check `assumption-4.6-t-coverage-gaussian`.
fn assumption_4_6_gaussian_check() -> Check {
    let mut a46g = meta(
        "assumption-4.6-t-coverage-gaussian",
        "Assumption 4.6 with the t-based widths of Section 4.5, on Gaussian samples",
        "Section 4.5, eq. (4.22) and the t-interval",
        "For Gaussian per-trajectory samples, P(|x̄ − μ| > ε) = δ exactly with \
         ε = t(1−δ/2, N−1)·√(Var̂/N) (sepg_estimators::width, Width::StudentT).",
        "Student's theorem: (x̄ − μ)/√(Var̂/N) has the t distribution with N − 1 degrees of freedom",
    );
    a46g.sampling =
        "N ∈ {3, 5, 10} independent N(0.5, 2²) samples per batch, δ ∈ {0.2, 0.05}; the \
        case count is the number of batches per N"
            .into();
    a46g.kind = ClaimKind::Equality;
    a46g.cases_quick = 4000;
    a46g.cases_full = 20_000;
    a46g.false_alarm_rate = "1e-3 family-wise: two-sided Clopper–Pearson test of each miss rate \
        against δ, Bonferroni over 6 settings × 2 sides"
        .into();
    a46g.notes = "Holds. Two-sided, so a width with the wrong degrees of freedom (N instead of \
        N − 1: miss rate ≈ 0.10 instead of 0.05 at N = 3) or the wrong level fails."
        .into();
    a46g.basis = "theory: Student's theorem (exact coverage 1 − δ for Gaussian samples)".into();
    Check::new(a46g, assumption_4_6_gaussian)
}

/// The check `thm-4.7-hp-v-update`.
fn thm_4_7_check() -> Check {
    let mut t47 = meta(
        "thm-4.7-hp-v-update",
        "Theorem 4.7, eqs. (4.24)–(4.26) (sign-aware form, docs/CONVENTIONS.md §4 vertex)",
        "Section 4.5",
        "With the estimated gradient and ε, the v-step at the vertex (C = C_max) and the largest \
         step for C = 0 realise J(θ′) − J(θ) ≥ C except with probability ≤ 1 − (1 − δ)^m (m = 1).",
        DP_TRUTH,
    );
    t47.sampling = HP_SAMPLING.into();
    t47.basis = BASIS_HP.into();
    t47.notes = "Holds.".into();
    Check::new(t47, thm_4_7)
}

/// The check `thm-4.8-hp-w-update`.
fn thm_4_8_check() -> Check {
    let mut t48 = meta(
        "thm-4.8-hp-w-update",
        "Theorem 4.8, eqs. (4.27)–(4.29)",
        "Section 4.5",
        "The w-step along ∇̂_wJ at the vertex (C = C_max) and the largest step for C = 0 realise \
         J(θ′) − J(θ) ≥ C except with probability ≤ δ.",
        DP_TRUTH,
    );
    t48.sampling = HP_SAMPLING.into();
    t48.basis = BASIS_HP.into();
    t48.notes = "Holds.".into();
    Check::new(t48, thm_4_8)
}

/// The check `thm-4.9-hp-w-along-l`.
fn thm_4_9_check() -> Check {
    let mut t49 = meta(
        "thm-4.9-hp-w-along-l",
        "Theorem 4.9, eq. (4.30)",
        "Section 4.5",
        "The w-step along ∇̂_wL (cross-fitted estimator of sepg-estimators) at the vertex and the \
         largest step for C = 0 realise J(θ′) − J(θ) ≥ C except with probability ≤ 1 − (1 − δ)².",
        DP_TRUTH,
    );
    t49.sampling = HP_SAMPLING.into();
    t49.basis = BASIS_HP.into();
    t49.notes = "Holds.".into();
    Check::new(t49, thm_4_9)
}

/// The check `thm-4.7-4.9-negative-c-printed`.
fn negative_c_printed_check() -> Check {
    let mut neg_p = meta(
        "thm-4.7-4.9-negative-c-printed",
        "Theorems 4.7–4.9 for C < 0, intervals (4.26), (4.29), (4.30) as printed",
        "Section 4.5",
        "For a bounded worsening C = −C_max/10 the end of the printed interval on the side \
         opposite to the estimated direction realises J(θ′) − J(θ) ≥ C except with probability \
         ≤ 1 − (1 − δ)^m.",
        DP_TRUTH,
    );
    neg_p.sampling = HP_SAMPLING.into();
    neg_p.expected = Expected::Violated;
    neg_p.notes = "Violated: on the side opposite to the estimate the valid linear term is \
        −|x|(‖∇̂‖⁺)², not the printed −|x|(‖∇̂‖⁻)², so the printed end point realises less than C \
        whenever the true gradient is larger than the lower-corrected estimate (most batches). \
        See ERRATA.md; sepg uses the sign-aware interval (thm-4.7-4.9-negative-c-sign-aware)."
        .into();
    Check::new(neg_p, negative_c_printed)
}

/// The check `thm-4.7-4.9-negative-c-sign-aware`.
fn negative_c_sign_aware_check() -> Check {
    let mut neg_s = meta(
        "thm-4.7-4.9-negative-c-sign-aware",
        "Theorems 4.7–4.9 for C < 0 with the sign-aware interval (docs/CONVENTIONS.md §4)",
        "Section 4.5; sepg_bounds::high_probability::HpForm::SignAware",
        "Same as thm-4.7-4.9-negative-c-printed with the sign-aware interval.",
        DP_TRUTH,
    );
    neg_s.sampling = HP_SAMPLING.into();
    neg_s.basis = BASIS_HP.into();
    neg_s.notes = "Holds.".into();
    Check::new(neg_s, negative_c_sign_aware)
}

/// The check `summation-theorem-pgt-gpomdp`.
fn summation_check() -> Check {
    let mut sum = meta(
        "summation-theorem-pgt-gpomdp",
        "Summation theorem: PGT = G(PO)MDP (Section 2.3.1, used in Section 3.4.1)",
        "Section 2.3.1; sepg_estimators::Kind::{Pgt, Gpomdp}",
        "Per trajectory, the PGT sample equals the G(PO)MDP sample (same per-step baseline), for \
         ∇_v J and ∇_w J, to 1e-12 relative to the largest sample of the batch.",
        "algebraic identity Σ_k ΔS_k Σ_{l≥k} F_l = Σ_l S_l F_l",
    );
    sum.kind = ClaimKind::Equality;
    sum.sampling = "proptest: preset lqg or lqg1d, γ ∈ {0.99} or U[0, 0.999], σ ∈ {0.1} or \
        U[0.05, 2], v ∈ U[−1.8, 0.2], batch seed, baseline none/mean/optimal (leave-one-out); \
        batches of 20 trajectories"
        .into();
    sum.tolerance = Tolerance {
        abs: 1e-12,
        rel: 0.0,
    };
    sum.cases_full = 1000;
    sum.cases_quick = 100;
    sum.false_alarm_rate = "0: deterministic; rounding of 20-term sums is ≈ 1e-15 relative".into();
    sum.notes = "Holds.".into();
    Check::new(sum, summation)
}

/// The check `reinforce-gpomdp-unbiased`.
fn unbiased_check() -> Check {
    let mut unb = meta(
        "reinforce-gpomdp-unbiased",
        "REINFORCE (2.1), G(PO)MDP and PGT with baselines are unbiased",
        "Section 2.3.1–2.3.2; used by Section 4.5",
        "E[∇̂] = ∇J for REINFORCE, G(PO)MDP, PGT with no, mean or optimal baseline \
         (leave-one-out), for ∇_v J and ∇_w J.",
        "closed-form J_H and gradients of the unclipped presets (ClosedFormOracle)",
    );
    unb.kind = ClaimKind::Equality;
    unb.sampling = "unclipped lqg (σ = 0.5, v = −0.3) and lqg1d (σ = 1, v = −0.6), γ = 0.9, \
        H = 20; independent batches of N = 100 (one per case); 36 components"
        .into();
    unb.false_alarm_rate = Z_FAR.into();
    unb.notes = "Holds.".into();
    Check::new(unb, unbiased)
}

/// The check `thm-b.1-h-unbiased`.
fn thm_b_1_check() -> Check {
    let mut b1 = meta(
        "thm-b.1-h-unbiased",
        "Theorem B.1: ĥ of (B.3) is unbiased for h(θ)",
        "Appendix B.1",
        "E[ĥ] = h(θ) = ∂_σ∇_vJ + (2/σ)∇_vJ (no baseline).",
        "exact ∇_vJ and ∂_σ∇_vJ: DP oracle (clipped) and closed form (unclipped)",
    );
    b1.kind = ClaimKind::Equality;
    b1.sampling = B_SAMPLING.into();
    b1.false_alarm_rate = Z_FAR.into();
    b1.notes = "Holds.".into();
    Check::new(b1, thm_b_1)
}

/// The check `app-b.2-baseline`.
fn baseline_b_2_check() -> Check {
    let mut b2 = meta(
        "app-b.2-baseline",
        "Appendix B.2: the baseline b_t = b̃_t(G_t + H_t)/(G_tH_t) keeps ĥ unbiased and reduces \
         its variance",
        "Appendix B.2",
        "E[ĥ_B.2] = h(θ) (leave-one-out fit of the optimal b̃_t), and the per-trajectory \
         variance with the baseline is below the variance without.",
        "exact h(θ) as in thm-b.1-h-unbiased; pooled sample variances",
    );
    b2.kind = ClaimKind::Equality;
    b2.sampling = B_SAMPLING.into();
    b2.false_alarm_rate = Z_FAR.into();
    b2.notes = "Holds.".into();
    Check::new(b2, baseline_b_2)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// P(X ≥ k) for X ~ Binomial(n, p), summed term by term (independent of `crate::stats`).
    fn upper_tail(k: u64, n: u64, p: f64) -> f64 {
        let mut pmf = (1.0 - p).powi(n as i32);
        let mut tail = if k == 0 { pmf } else { 0.0 };
        for j in 1..=n {
            pmf *= (n - j + 1) as f64 / j as f64 * p / (1.0 - p);
            if j >= k {
                tail += pmf;
            }
        }
        tail
    }

    /// `others` clean tests (0 violations in 1000 trials) and one with `k` violations in 100
    /// trials, each allowed a rate of 0.05.
    fn family(k: u64, others: usize) -> Vec<Freq> {
        let mut tests: Vec<Freq> = (0..others)
            .map(|i| Freq {
                name: format!("clean {i}"),
                violations: 0,
                trials: 1000,
                allowed: 0.05,
            })
            .collect();
        tests.push(Freq {
            name: "tested".into(),
            violations: k,
            trials: 100,
            allowed: 0.05,
        });
        tests
    }

    fn rejected(tests: &[Freq]) -> bool {
        matches!(
            frequency_outcome(tests, FAMILY_ALPHA).outcome,
            Outcome::Violated { .. }
        )
    }

    #[test]
    fn frequency_tests_are_bonferroni_corrected() {
        // The one-sided Clopper–Pearson lower bound at confidence 1 − a exceeds p₀ exactly when
        // P(X ≥ k | p₀) < a. With m tests at family-wise 1e-3, a = 1e-3/m.
        let (t13, t14, t16) = (
            upper_tail(13, 100, 0.05),
            upper_tail(14, 100, 0.05),
            upper_tail(16, 100, 0.05),
        );
        assert!(t13 > 1e-3 && t13 < 1e-2, "{t13}");
        assert!(t14 > 1e-4 && t14 < 1e-3, "{t14}");
        assert!(t16 < 1e-4, "{t16}");
        // Alone (a = 1e-3): 14 violations are rejected, 13 are not.
        assert!(rejected(&family(14, 0)));
        assert!(!rejected(&family(13, 0)));
        // Among 10 tests (a = 1e-4): 14 is no longer rejected, 16 still is; 13 is not (it
        // would be at a = 1e-2, the level of a correction that multiplies instead of divides).
        assert!(!rejected(&family(14, 9)));
        assert!(!rejected(&family(13, 9)));
        assert!(rejected(&family(16, 9)));
    }
}
