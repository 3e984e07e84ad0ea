//! One iteration of SEPG (Algorithm 4.3 with the delayed budget updates of Sec 4.4.4).
use crate::core::adam::AdamMoments;
use crate::core::config::Requirement;
use crate::core::error::RunError;
use crate::core::options::{Accounting, BatchRule, Lb1Requirement, SepgOptions, VDirection};
use crate::core::record::Record;
use crate::core::seed::Block;
use crate::core::state::State;
use sepg_bounds::budget::{Budget, split_requirement};
use sepg_bounds::constants::TaskConstants;
use sepg_bounds::direction::{Direction, DirectionBound, FeatureNorm};
use sepg_bounds::outcome::StepOutcome;
use sepg_certified::Certified;

use crate::solver::batch::next_batch;
use crate::solver::realise::{CoordinateBound, DirectionalBound, realise, realise_along};
use crate::solver::source::{BlockEstimate, Grad, GradientSource, Need, Query};
use crate::solver::steps::{self, Plan};

/// Trajectories of each block: `n` split evenly, the remainder going to the first blocks.
pub(crate) fn split(n: usize, blocks: usize) -> Vec<usize> {
    (0..blocks)
        .map(|b| n / blocks + usize::from(b < n % blocks))
        .collect()
}

/// Fields of a [`Record`] produced by one update block.
#[derive(Debug, Clone, Copy, Default)]
struct BlockLog {
    size: f64,
    lambda: Option<f64>,
    guaranteed: Option<f64>,
    infeasible: bool,
    below_noise: bool,
    certified: Option<bool>,
}

impl BlockLog {
    fn from_plan(plan: &Plan) -> Self {
        match plan {
            Plan::BelowNoise => BlockLog {
                below_noise: true,
                ..BlockLog::default()
            },
            Plan::Update(s) => BlockLog {
                size: s.size,
                lambda: s.lambda,
                guaranteed: Some(s.guaranteed),
                infeasible: s.infeasible,
                below_noise: false,
                certified: s.certified,
            },
        }
    }
}

fn apply(x: &mut [f64], plan: &Plan) {
    if let Plan::Update(s) = plan {
        x[s.index] += s.delta;
    }
}

fn min_sigma(w: &[f64]) -> f64 {
    w.iter().fold(f64::INFINITY, |m, &wi| m.min(wi.exp()))
}

/// The fixed inputs of every SEPG iteration of a run.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Setup<'a> {
    /// Task constants of the bounds.
    pub(crate) k: &'a TaskConstants,
    /// The safety requirement.
    pub(crate) req: Requirement,
    /// The w-update along ∇_w J (eq. 4.12) instead of ∇_w L (eq. 4.20).
    pub(crate) naive_w: bool,
    /// Trajectories per iteration.
    pub(crate) n: usize,
    /// The remaining choices ([`SepgOptions`]).
    pub(crate) opts: &'a SepgOptions,
    /// Certified steps (`sepg_certified`).
    pub(crate) certify: bool,
    /// p, the number of features of one action (the v-space of one action has p
    /// components): the feature 2-norm of a step along a non-coordinate direction is bounded
    /// by √p·M_φ.
    pub(crate) features: usize,
    /// How many trajectories each block draws (the certified iteration only).
    pub(crate) batch: BatchRule,
}

/// The v-update of a block whose estimate `e` holds ∇_v J, from (`v`, `w`) for `required`:
/// its plan, the new v and its step size α (0 when it makes no update).
fn v_update(
    setup: &Setup,
    v: &[f64],
    w: &[f64],
    e: &BlockEstimate,
    required: f64,
) -> Result<(Plan, Vec<f64>, f64), RunError> {
    let grad_v = e.grad_v.as_ref().ok_or(RunError::Estimator(
        "the v-block returned no gradient".into(),
    ))?;
    let plan = steps::v_step(setup.k, min_sigma(w), grad_v, required, setup.certify)?;
    let mut v_new = v.to_vec();
    apply(&mut v_new, &plan);
    let alpha = match plan {
        Plan::Update(s) => s.size,
        Plan::BelowNoise => 0.0,
    };
    Ok((plan, v_new, alpha))
}

/// `Err` unless every new parameter is finite.
fn check_finite(v_new: &[f64], w_new: &[f64], iteration: u64) -> Result<(), RunError> {
    if v_new.iter().chain(w_new).any(|x| !x.is_finite()) {
        return Err(RunError::NonFinite {
            what: "policy parameters",
            iteration,
        });
    }
    Ok(())
}

/// The fields of a [`Record`] that do not come from the update blocks' logs.
struct Row {
    iteration: u64,
    v: Vec<f64>,
    w: Vec<f64>,
    sigma: Vec<f64>,
    j_exploratory: f64,
    j_after_v: Option<f64>,
    j_target: f64,
    w_target: Option<Vec<f64>>,
    budget: f64,
    required_v: Option<f64>,
    required_w: Option<f64>,
    trajectories: u64,
    steps: u64,
}

impl Row {
    /// The row of iteration `state.iteration` at θᵗ = (`state.v`, `state.w`) with σ =
    /// `sigma`, Ĵ(θᵗ) = `j_exploratory` and the target's `j_target` and `w_target`; the other
    /// fields as the state holds them before the iteration (no requirement, no Ĵ(vᵗ⁺¹, wᵗ)).
    fn start(
        state: &State,
        sigma: Vec<f64>,
        j_exploratory: f64,
        j_target: f64,
        w_target: Option<Vec<f64>>,
    ) -> Self {
        Row {
            iteration: state.iteration,
            v: state.v.clone(),
            w: state.w.clone(),
            sigma,
            j_exploratory,
            j_after_v: None,
            j_target,
            w_target,
            budget: state.budget,
            required_v: None,
            required_w: None,
            trajectories: state.trajectories,
            steps: state.steps,
        }
    }
}

/// The record of an iteration from its row and the logs of its v- and w-blocks.
fn record(row: Row, v_log: BlockLog, w_log: BlockLog) -> Record {
    Record {
        iteration: row.iteration,
        v: row.v,
        w: row.w,
        sigma: row.sigma,
        j_exploratory: row.j_exploratory,
        j_after_v: row.j_after_v,
        j_target: row.j_target,
        w_target: row.w_target,
        budget: row.budget,
        required_v: row.required_v,
        required_w: row.required_w,
        alpha: v_log.size,
        beta: w_log.size,
        lambda_v: v_log.lambda,
        lambda_w: w_log.lambda,
        guaranteed_v: v_log.guaranteed,
        guaranteed_w: w_log.guaranteed,
        infeasible_v: v_log.infeasible,
        infeasible_w: w_log.infeasible,
        below_noise_v: v_log.below_noise,
        below_noise_w: w_log.below_noise,
        trajectories: row.trajectories,
        steps: row.steps,
        certified_v: v_log.certified,
        certified_w: w_log.certified,
    }
}

/// Before the first iteration of LB-I and the type-II requirements, estimates J(θ⁰) from a
/// reference batch of `opts.reference_batch` trajectories and stores its upper confidence
/// bound Û⁰ = Ĵ⁰ + ε₀ as LB-I's J(θ⁰) and as the reference of the budget's first exploratory
/// difference; with a deterministic target (ZV, SIM-ν) the first target is treated likewise.
/// On the events J(θ⁰) ≤ Û⁰ (probability ≥ 1 − δ each) the requirements built on J(θ⁰)
/// are at least as strict as with the exact value (docs/THEOREMS.md).
fn reference(
    source: &mut dyn GradientSource,
    req: Requirement,
    opts: &SepgOptions,
    state: &mut State,
) -> Result<(), RunError> {
    if state.j0.is_some() || opts.reference_batch == 0 || req == Requirement::Mi {
        return Ok(());
    }
    let need = Need {
        j_width: true,
        ..Need::default()
    };
    let mut upper = |block, w: Option<&[f64]>, state: &mut State| -> Result<f64, RunError> {
        let e = source.estimate(&Query {
            iteration: state.iteration,
            block,
            v: &state.v,
            w,
            n: opts.reference_batch,
            need,
        })?;
        state.trajectories += e.trajectories;
        state.steps += e.steps;
        Ok(e.j + e.j_width)
    };
    let w = state.w.clone();
    let j0 = upper(Block::Reference, Some(&w), state)?;
    state.j0 = Some(j0);
    if req.is_type_two() {
        state.pending = Some(j0);
    }
    if matches!(req, Requirement::Zv | Requirement::Sim { .. }) {
        state.target_prev = Some(upper(Block::ReferenceTarget, None, state)?);
    }
    Ok(())
}

/// One block of iteration t at (v, w) from `n` trajectories, counted into `counts`
/// (trajectories, environment steps).
fn counted(
    source: &mut dyn GradientSource,
    q: &Query<'_>,
    counts: (&mut u64, &mut u64),
) -> Result<BlockEstimate, RunError> {
    let e = source.estimate(q)?;
    *counts.0 += e.trajectories;
    *counts.1 += e.steps;
    Ok(e)
}

/// The v-block of iteration t: Ĵ and ∇̂_v J at (v, w), plus the w-gradients SIM-ν (both) and
/// LV (∇̂_w J, for its target) need from this batch.
fn v_block(
    source: &mut dyn GradientSource,
    setup: &Setup,
    (iteration, v, w, n): (u64, &[f64], &[f64], usize),
    counts: (&mut u64, &mut u64),
) -> Result<BlockEstimate, RunError> {
    let sim = matches!(setup.req, Requirement::Sim { .. });
    let need = Need {
        grad_v: true,
        grad_wj: sim || setup.req == Requirement::Lv,
        grad_wl: sim && !setup.naive_w,
        j_width: false,
    };
    let q = Query {
        iteration,
        block: Block::V,
        v,
        w: Some(w),
        n,
        need,
    };
    counted(source, &q, counts)
}

/// The w-block of iteration t: Ĵ, ∇̂_w J and (unless `naive_w`) ∇̂_w L at (v, w).
fn w_block(
    source: &mut dyn GradientSource,
    naive_w: bool,
    (iteration, v, w, n): (u64, &[f64], &[f64], usize),
    counts: (&mut u64, &mut u64),
) -> Result<BlockEstimate, RunError> {
    let need = Need {
        grad_v: false,
        grad_wj: true,
        grad_wl: !naive_w,
        j_width: false,
    };
    let q = Query {
        iteration,
        block: Block::W,
        v,
        w: Some(w),
        n,
        need,
    };
    counted(source, &q, counts)
}

/// The target block of iteration t (LV, ZV, SIM-ν): Ĵ of the target policy (v, `w`; `None`
/// is the deterministic policy) from `n` trajectories, counted into `counts` (trajectories,
/// environment steps).
fn target_j(
    source: &mut dyn GradientSource,
    (iteration, v, w, n): (u64, &[f64], Option<&[f64]>, usize),
    counts: (&mut u64, &mut u64),
) -> Result<f64, RunError> {
    let q = Query {
        iteration,
        block: Block::Target,
        v,
        w,
        n,
        need: Need::default(),
    };
    Ok(counted(source, &q, counts)?.j)
}

/// Runs SEPG iteration `state.iteration` with the fixed inputs `setup`.
pub(crate) fn iterate(
    source: &mut dyn GradientSource,
    setup: &Setup,
    state: &mut State,
) -> Result<Record, RunError> {
    let Setup { req, n, opts, .. } = *setup;
    if opts.accounting == Accounting::Certified {
        return iterate_certified(source, setup, state);
    }
    reference(source, req, opts, state)?;
    if opts.alternating {
        return iterate_alternating(source, setup, state);
    }
    let t = state.iteration;
    let sizes = split(n, req.blocks());
    let mut j0 = state.j0;
    let (mut trajectories, mut env_steps) = (state.trajectories, state.steps);

    // v-block: J(vᵗ, wᵗ) and ∇_v J (plus the w-gradients SIM-ν and LV need from this batch).
    let ev = v_block(
        source,
        setup,
        (t, &state.v, &state.w, sizes[0]),
        (&mut trajectories, &mut env_steps),
    )?;
    let j_t = ev.j;
    let j_base = *j0.get_or_insert(j_t);
    let mut budget = opening_budget(state, j_t)?;
    let sigmas = state.sigma();
    let type_one = type_one_split(req, opts.lb1_requirement, j_base - j_t)?;
    let required_v = estimated_required_v(req, type_one, &budget);
    let (v_plan, v_new, alpha) = v_update(setup, &state.v, &state.w, &ev, required_v)?;
    let v_log = BlockLog::from_plan(&v_plan);

    // Target block (LV, ZV, SIM-ν): evaluate θ_Tᵗ = (vᵗ, w_T) and update the budget (line 12).
    // LV's target takes the step of (4.17) for the budget's requirement, unrealised.
    let (w_target, j_target) = target_block(
        source,
        setup,
        (state, &sigmas, &ev),
        (budget.required_improvement(), false),
        &sizes,
        (&mut trajectories, &mut env_steps),
    )?;
    if has_target(req) && state.target_prev.is_some() {
        budget.record_target(j_target).map_err(budget_error(t))?;
    }
    let wu = estimated_w_update(
        source,
        setup,
        (state, &sigmas, &ev, &v_new),
        (type_one, j_base, alpha, sizes[sizes.len() - 1]),
        &mut budget,
        (&mut trajectories, &mut env_steps),
    )?;

    check_finite(&v_new, &wu.w_new, t)?;
    let mut row = Row::start(state, sigmas, ev.j, j_target, w_target);
    row.j_after_v = wu.j_after_v;
    row.budget = budget.value();
    row.required_v = Some(required_v);
    row.required_w = Some(wu.required_w);
    row.trajectories = trajectories;
    row.steps = env_steps;
    let record = record(row, v_log, wu.log);
    advance(state, (v_new, wu.w_new), budget.value(), &record, alpha);
    state.j0 = j0;
    state.pending = Some(wu.pending);
    if has_target(req) {
        state.target_prev = Some(j_target);
    }
    Ok(record)
}

/// The error of a budget update of iteration `iteration` that would leave B non-finite.
fn budget_error<E>(iteration: u64) -> impl Fn(E) -> RunError {
    move |_| RunError::NonFinite {
        what: "budget",
        iteration,
    }
}

/// The budget B (Definition 4.3) at the start of an iteration of the thesis's accounting
/// whose exploratory J estimate is `j_t`. B measures differences from the last J of each
/// tracked policy; the delayed w-budget update of the previous iteration comes first
/// (Sec 4.4.4).
fn opening_budget(state: &State, j_t: f64) -> Result<Budget, RunError> {
    let t = state.iteration;
    let mut budget = Budget::new(
        state.budget,
        state.pending.unwrap_or(j_t),
        state.target_prev,
    )
    .map_err(budget_error(t))?;
    if state.pending.is_some() {
        budget.record_exploratory(j_t).map_err(budget_error(t))?;
    }
    Ok(budget)
}

/// The type-I requirement Cᵗ (Table 4.1) split (1 − ν)C / νC between the v- and w-steps
/// (eqs. 4.13, 4.14): MI requires 0 of each; LB-I requires `lb1_gap` = J(θ⁰) − Ĵ(θᵗ) of the
/// two (all of it to the v-step with [`Lb1Requirement::Full`], the w-step then measuring its
/// own); `None` for the type-II requirements.
fn type_one_split(
    req: Requirement,
    lb1: Lb1Requirement,
    lb1_gap: f64,
) -> Result<Option<(f64, f64)>, RunError> {
    let full = lb1 == Lb1Requirement::Full;
    match req {
        Requirement::Mi => Some(split_requirement(0.0, 0.0)),
        Requirement::LbI { nu } => Some(split_requirement(lb1_gap, if full { 0.0 } else { nu })),
        _ => None,
    }
    .transpose()
    .map_err(|e| RunError::Bounds(e.to_string()))
}

/// The v-step's requirement under the thesis's accounting: the type-I share, SIM-ν's −νB
/// (Sec 5.1.3), or −B for the other type-II requirements.
fn estimated_required_v(req: Requirement, type_one: Option<(f64, f64)>, budget: &Budget) -> f64 {
    match (type_one, req) {
        (Some((cv, _)), _) => cv,
        (None, Requirement::Sim { nu }) => -nu * budget.value(),
        (None, _) => budget.required_improvement(),
    }
}

/// The outcome of the w-block of an iteration of the thesis's accounting.
struct WUpdate {
    /// wᵗ⁺¹.
    w_new: Vec<f64>,
    /// Ĵ(vᵗ⁺¹, wᵗ), measured by the w-block (`None` for SIM-ν, which has none).
    j_after_v: Option<f64>,
    /// The w-step's requirement.
    required_w: f64,
    /// The w-block's log.
    log: BlockLog,
    /// The J whose successor the next iteration's delayed budget update measures.
    pending: f64,
}

/// The w-block of an iteration of the thesis's accounting, after the v-step to `v_new`:
/// SIM-ν steps from the v-block's batch for −(1 − ν)B; the others estimate at (vᵗ⁺¹, wᵗ)
/// from `n_w` trajectories, apply the delayed v-budget update right after J(vᵗ⁺¹, wᵗ) is
/// known (Sec 4.4.4), and step for the type-I share (`type_one`), LB-I's own
/// J(θ⁰) − Ĵ(vᵗ⁺¹, wᵗ) with [`Lb1Requirement::Full`], or −B.
fn estimated_w_update(
    source: &mut dyn GradientSource,
    setup: &Setup,
    (state, sigmas, ev, v_new): (&State, &[f64], &BlockEstimate, &[f64]),
    (type_one, j_base, alpha, n_w): (Option<(f64, f64)>, f64, f64, usize),
    budget: &mut Budget,
    counts: (&mut u64, &mut u64),
) -> Result<WUpdate, RunError> {
    let mut w_new = state.w.clone();
    if let Requirement::Sim { nu } = setup.req {
        let required_w = -(1.0 - nu) * budget.value();
        let plan = w_plan(setup, sigmas, ev, required_w, alpha)?;
        apply(&mut w_new, &plan);
        let log = BlockLog::from_plan(&plan);
        let (j_after_v, pending) = (None, ev.j);
        return Ok(WUpdate {
            w_new,
            j_after_v,
            required_w,
            log,
            pending,
        });
    }
    let t = state.iteration;
    let ew = w_block(source, setup.naive_w, (t, v_new, &state.w, n_w), counts)?;
    budget.record_exploratory(ew.j).map_err(budget_error(t))?;
    let full = setup.opts.lb1_requirement == Lb1Requirement::Full;
    let required_w = match (setup.req, full) {
        (Requirement::LbI { .. }, true) => j_base - ew.j,
        _ => type_one.map_or(budget.required_improvement(), |(_, cw)| cw),
    };
    let plan = w_plan(setup, sigmas, &ew, required_w, alpha)?;
    apply(&mut w_new, &plan);
    Ok(WUpdate {
        w_new,
        j_after_v: Some(ew.j),
        required_w,
        log: BlockLog::from_plan(&plan),
        pending: ew.j,
    })
}

/// Moves `state` past the iteration that produced `record`: θᵗ⁺¹ = `(v, w)`, the budget, the
/// counts of the record and the v-step size `alpha`.
fn advance(
    state: &mut State,
    (v, w): (Vec<f64>, Vec<f64>),
    budget: f64,
    record: &Record,
    alpha: f64,
) {
    state.iteration += 1;
    state.v = v;
    state.w = w;
    state.budget = budget;
    state.trajectories = record.trajectories;
    state.steps = record.steps;
    state.last_alpha = Some(alpha);
}

/// One half-iteration of alternating SEPG-MI or SEPG-LB-I (the thesis-era code's schedule):
/// even iterations update v, odd ones w, each from one batch of all `n` trajectories, with
/// the requirement measured at its own start (LB-I: J(θ⁰) − Ĵ, times 1 − ν or ν unless
/// `Lb1Requirement::Full`). Each half-step keeps J ≥ J(θ⁰) on its own, since
/// J_after ≥ J_before + ν(J(θ⁰) − J_before) ≥ J(θ⁰) whenever J_before ≥ J(θ⁰).
fn iterate_alternating(
    source: &mut dyn GradientSource,
    setup: &Setup,
    state: &mut State,
) -> Result<Record, RunError> {
    let Setup {
        req,
        naive_w,
        n,
        opts,
        ..
    } = *setup;
    let t = state.iteration;
    let v_turn = t.is_multiple_of(2);
    let e = source.estimate(&Query {
        iteration: t,
        block: if v_turn { Block::V } else { Block::W },
        v: &state.v,
        w: Some(&state.w),
        n,
        need: Need {
            grad_v: v_turn,
            grad_wj: !v_turn,
            grad_wl: !v_turn && !naive_w,
            j_width: false,
        },
    })?;
    let j_base = *state.j0.get_or_insert(e.j);
    let share = match (req, opts.lb1_requirement) {
        (Requirement::LbI { .. }, Lb1Requirement::Full) => 1.0,
        (Requirement::LbI { nu }, Lb1Requirement::Split) => {
            if v_turn {
                1.0 - nu
            } else {
                nu
            }
        }
        _ => 0.0,
    };
    let required = share * (j_base - e.j);
    let sigmas = state.sigma();
    let (mut v_new, mut w_new) = (state.v.clone(), state.w.clone());
    let plan = if v_turn {
        let (plan, v, alpha) = v_update(setup, &state.v, &state.w, &e, required)?;
        v_new = v;
        state.last_alpha = Some(alpha);
        plan
    } else {
        let alpha = state.last_alpha.unwrap_or(0.0);
        let plan = w_plan(setup, &sigmas, &e, required, alpha)?;
        apply(&mut w_new, &plan);
        plan
    };
    check_finite(&v_new, &w_new, t)?;
    let log = BlockLog::from_plan(&plan);
    let idle = BlockLog::default();
    let (v_log, w_log) = if v_turn { (log, idle) } else { (idle, log) };
    state.trajectories += e.trajectories;
    state.steps += e.steps;
    let row = Row {
        iteration: t,
        v: state.v.clone(),
        w: state.w.clone(),
        sigma: sigmas,
        j_exploratory: e.j,
        j_after_v: None,
        j_target: e.j,
        w_target: Some(state.w.clone()),
        budget: state.budget,
        required_v: v_turn.then_some(required),
        required_w: (!v_turn).then_some(required),
        trajectories: state.trajectories,
        steps: state.steps,
    };
    let record = record(row, v_log, w_log);
    state.iteration += 1;
    state.v = v_new;
    state.w = w_new;
    Ok(record)
}

/// The w-update of a block whose estimate holds ∇_w J (and ∇_w L unless `setup.naive_w`),
/// along the direction and in the form `setup.opts` selects; `alpha` is the latest v-step size
/// (for the metagradient direction).
fn w_plan(
    setup: &Setup,
    sigmas: &[f64],
    e: &BlockEstimate,
    required: f64,
    alpha: f64,
) -> Result<Plan, RunError> {
    let Setup {
        k,
        naive_w: naive,
        certify,
        opts,
        ..
    } = *setup;
    let missing = || RunError::Estimator("the w-block returned no w-gradient".into());
    let gj = e.grad_wj.as_ref().ok_or_else(missing)?;
    if naive {
        steps::w_step_naive(k, sigmas, gj, required, certify)
    } else {
        let cross = e.grad_wl.as_ref().ok_or_else(missing)?;
        let gl = steps::w_direction(
            k,
            sigmas,
            opts.w_direction,
            cross,
            e.parts.as_ref(),
            gj,
            alpha,
        )?;
        steps::w_step_surrogate(k, sigmas, &gl, gj, required, certify, opts.w_step)
    }
}

/// a + g rounded down: a lower bound of the exact sum (the error term of TwoSum decides).
fn add_down(a: f64, g: f64) -> f64 {
    let s = a + g;
    let bb = s - a;
    let err = (a - (s - bb)) + (g - bb);
    if err < 0.0 { s.next_down() } else { s }
}

/// Splits a budget b ≥ 0 into (b − x, x) with x ≈ share·b, both rounded down, so that the two
/// parts add up to at most b exactly (share ∈ [0, 1]).
fn split_down(b: f64, share: f64) -> (f64, f64) {
    if b.is_nan() || b <= 0.0 {
        return (0.0, 0.0);
    }
    let p = share * b;
    let x = if share.mul_add(b, -p) < 0.0 {
        p.next_down()
    } else {
        p
    };
    let x = x.max(0.0);
    (add_down(b, -x).max(0.0), x)
}

/// The requirement C = −allowance of a step allowed to lose `allowance` (C = −allowance when
/// the allowance is positive; a negative allowance, a broken budget, requires an improvement).
fn allowed(allowance: f64) -> f64 {
    -allowance
}

/// The block log and new coordinate values of a plan whose step is certified again at the
/// change it realises (`realise`), with `bound` the rigorous bound of the moved coordinate.
/// Returns the log, the guaranteed improvement of the applied change (0 for no change) and
/// the realised step size (0 for no change).
fn apply_realised(
    x: &mut [f64],
    plan: &Plan,
    bound: impl FnOnce(usize) -> Result<CoordinateBound, RunError>,
    required: f64,
    certify: bool,
) -> Result<(BlockLog, f64, f64), RunError> {
    let Plan::Update(s) = plan else {
        return Ok((BlockLog::from_plan(plan), 0.0, 0.0));
    };
    if !certify {
        x[s.index] += s.delta;
        return Ok((BlockLog::from_plan(plan), s.guaranteed, s.size));
    }
    let b = bound(s.index)?;
    let x0 = x[s.index];
    let r = realise(x0, s.delta, &b, required, s.certified == Some(true));
    x[s.index] = r.value;
    let moved = r.value - x0;
    let size = if s.delta == 0.0 {
        0.0
    } else {
        s.size * (moved / s.delta)
    };
    let mut log = BlockLog::from_plan(plan);
    log.size = size;
    log.guaranteed = Some(r.guaranteed);
    log.certified = Some(r.meets && !s.infeasible);
    Ok((log, r.guaranteed, size))
}

/// The v-update along the proposed direction `u` (SEPG's Adam v-direction): the largest
/// step t ∈ [0, 1] whose bound along u meets `required` (certified when `setup.certify`), the
/// change t·u realised and certified again (`realise_along`). Returns the block log, the
/// guaranteed improvement of the applied change and the t applied (0 for no change).
fn along_direction(
    setup: &Setup,
    sigma: f64,
    grad: &Grad,
    u: &[f64],
    required: f64,
    v: &mut [f64],
) -> Result<(BlockLog, f64, f64), RunError> {
    let be = |e: sepg_bounds::BoundsError| RunError::Bounds(e.to_string());
    if u.iter().all(|&x| x == 0.0) {
        // Adam proposes no change (every gradient so far exactly 0)
        let log = BlockLog {
            below_noise: true,
            ..BlockLog::default()
        };
        return Ok((log, 0.0, 0.0));
    }
    let d = Direction {
        direction: u,
        grad_hat: &grad.value,
        eps: &grad.eps,
        features: FeatureNorm::FromMax {
            features: setup.features,
        },
    };
    if !setup.certify {
        let s = DirectionBound::new(setup.k, sigma, &d)
            .and_then(|b| b.safe_step(required, 1.0))
            .map_err(be)?;
        for (x, &ui) in v.iter_mut().zip(u) {
            *x += s.step * ui;
        }
        let (lambda, infeasible) = match s.outcome {
            StepOutcome::Feasible(i) => (i.lambda, false),
            _ => (Some(0.0), true),
        };
        let log = BlockLog {
            size: s.step,
            lambda,
            guaranteed: Some(s.guaranteed),
            infeasible,
            below_noise: false,
            certified: None,
        };
        return Ok((log, s.guaranteed, s.step));
    }
    let outcome =
        sepg_certified::direction_safe_step(setup.k, sigma, &d, required, 1.0).map_err(be)?;
    let (lambda, infeasible) = match outcome {
        Certified::Step(s) => (s.interval.lambda, false),
        _ => (Some(0.0), true),
    };
    let bound = DirectionalBound::new(setup.k, sigma, &d).map_err(be)?;
    let t = outcome.chosen_step().unwrap_or(0.0);
    let r = realise_along(v, u, t, &bound, required, outcome.is_certified());
    v.copy_from_slice(&r.values);
    let log = BlockLog {
        size: r.step,
        lambda,
        guaranteed: Some(r.guaranteed),
        infeasible,
        below_noise: false,
        certified: Some(r.meets && outcome.is_certified()),
    };
    Ok((log, r.guaranteed, r.step))
}

/// ε = max_i ε_i of a gradient.
fn eps_max(g: &crate::solver::source::Grad) -> f64 {
    g.eps.iter().fold(0.0, |m: f64, &e| m.max(e))
}

/// One SEPG iteration with the certified accounting (`Accounting::Certified`,
/// docs/THEOREMS.md "Statements over a whole run"): `state.budget` holds the certified budget
/// B = B⁰ + S (LB-I: its surplus), S the sum of the guaranteed improvements of the applied
/// changes, rounded down. MI requires 0 of each step; LB-I gives the v-step
/// −(1 − ν)B and the w-step −νB (both from the B at the iteration's start); the type-II
/// requirements give each step −B of the moment; SIM-ν splits νB / (1 − ν)B. Every step is
/// certified again at its realised change against a rigorous bound (`realise`), and
/// its guarantee is added to B, so on the confidence events B ≤ J(θ) − J(θ⁰) + B⁰ at every
/// point of the run. Estimated J is logged, never used.
fn iterate_certified(
    source: &mut dyn GradientSource,
    setup: &Setup,
    state: &mut State,
) -> Result<Record, RunError> {
    let req = setup.req;
    let t = state.iteration;
    let sizes = block_sizes(setup, state);
    let (mut trajectories, mut env_steps) = (state.trajectories, state.steps);
    // LB-I's surplus starts at 0 whatever B⁰ (its requirement is J ≥ J(θ⁰), Table 4.1); the
    // type-II budgets start at B⁰
    let b0 = if t == 0 && matches!(req, Requirement::LbI { .. }) {
        0.0
    } else {
        state.budget
    };
    let (cv, cw) = certified_shares(req, setup.opts.lb1_requirement, b0);
    let required_v = allowed(cv);

    let ev = v_block(
        source,
        setup,
        (t, &state.v, &state.w, sizes[0]),
        (&mut trajectories, &mut env_steps),
    )?;
    let mut v_new = state.v.clone();
    let (v_log, g_v, alpha) = certified_v_update(setup, state, &ev, required_v, &mut v_new)?;
    let b1 = add_down(b0, g_v);

    let sigmas = state.sigma();
    // Target block (LV, ZV, SIM-ν): its J is logged; LV's target is guaranteed from the
    // budget at the iteration's start (J(θ_T) ≥ J(θᵗ) − B ≥ J(θ⁰) − B⁰).
    let (w_target, j_target) = target_block(
        source,
        setup,
        (state, &sigmas, &ev),
        (allowed(b0), setup.certify),
        &sizes,
        (&mut trajectories, &mut env_steps),
    )?;

    // w-block (SIM-ν: from the v-block's batch).
    let required_w = if cw.is_nan() {
        allowed(b1)
    } else {
        allowed(cw)
    };
    let mut w_new = state.w.clone();
    let (j_after_v, w_log, g_w) = certified_w_update(
        source,
        setup,
        (state, &sigmas, &ev, &v_new),
        (required_w, alpha, sizes[sizes.len() - 1]),
        &mut w_new,
        (&mut trajectories, &mut env_steps),
    )?;
    let b2 = add_down(b1, g_w);

    check_finite(&v_new, &w_new, t)?;
    let batch = adapted_batch(setup, &ev, sizes[0])?;
    let mut row = Row::start(state, sigmas, ev.j, j_target, w_target);
    row.j_after_v = j_after_v;
    row.budget = b2;
    row.required_v = Some(required_v);
    row.required_w = Some(required_w);
    row.trajectories = trajectories;
    row.steps = env_steps;
    let record = record(row, v_log, w_log);
    advance(state, (v_new, w_new), b2, &record, alpha);
    state.next_batch = batch;
    Ok(record)
}

/// The batch sizes of the blocks of the iteration `state` is at: all `state.next_batch` under
/// [`BatchRule::Adaptive`] once chosen, otherwise N split evenly ([`split`]).
fn block_sizes(setup: &Setup, state: &State) -> Vec<usize> {
    match (setup.batch, state.next_batch) {
        (BatchRule::Adaptive { .. }, Some(m)) => vec![m; setup.req.blocks()],
        _ => split(setup.n, setup.req.blocks()),
    }
}

/// Under [`BatchRule::Adaptive`], the block size of the next iteration from this iteration's
/// v-block estimate `ev` of `n_v` trajectories ([`next_batch`]); `None` under the fixed rule.
fn adapted_batch(setup: &Setup, ev: &BlockEstimate, n_v: usize) -> Result<Option<usize>, RunError> {
    let BatchRule::Adaptive { n_min, n_max } = setup.batch else {
        return Ok(None);
    };
    let grad_v = ev.grad_v.as_ref().ok_or(RunError::Estimator(
        "the v-block returned no gradient".into(),
    ))?;
    next_batch(grad_v, n_v, n_min, n_max)
        .map(Some)
        .map_err(|e| RunError::Estimator(e.to_string()))
}

/// The allowances (v-step, w-step) of the certified accounting out of the budget `b0` at
/// the iteration's start: MI none; LB-I with [`Lb1Requirement::Split`] (1 − ν)B and νB;
/// SIM-ν νB and (1 − ν)B; the others all of B to the v-step and NaN for the w-step, whose
/// allowance is then the budget after the v-step.
fn certified_shares(req: Requirement, lb1: Lb1Requirement, b0: f64) -> (f64, f64) {
    match (req, lb1) {
        (Requirement::Mi, _) => (0.0, 0.0),
        (Requirement::LbI { nu }, Lb1Requirement::Split) => split_down(b0, nu),
        (Requirement::Sim { nu }, _) => {
            let (rest, v_share) = split_down(b0, nu);
            (v_share, rest)
        }
        _ => (b0, f64::NAN),
    }
}

/// The v-step of the certified accounting from the v-block's estimate `ev`, applied to
/// `v_new` (a copy of vᵗ): greedy (Theorem 4.2 on the best coordinate) or along Adam's
/// direction (whose moments live in `state`), realised and certified again. Returns the
/// block log, the guaranteed improvement of the applied change and the step size.
fn certified_v_update(
    setup: &Setup,
    state: &mut State,
    ev: &BlockEstimate,
    required_v: f64,
    v_new: &mut [f64],
) -> Result<(BlockLog, f64, f64), RunError> {
    let Setup { k, certify, .. } = *setup;
    let grad_v = ev.grad_v.as_ref().ok_or(RunError::Estimator(
        "the v-block returned no gradient".into(),
    ))?;
    let sigma_v = min_sigma(&state.w);
    match setup.opts.v_direction {
        VDirection::Greedy => {
            let v_plan = steps::v_step(k, sigma_v, grad_v, required_v, certify)?;
            let eps_v = eps_max(grad_v);
            apply_realised(
                v_new,
                &v_plan,
                |i| CoordinateBound::mean(k, sigma_v, grad_v.value[i], eps_v).map_err(bounds),
                required_v,
                certify,
            )
        }
        VDirection::Adam {
            lr,
            beta1,
            beta2,
            eps,
        } => {
            let moments = state
                .adam_v
                .get_or_insert_with(|| AdamMoments::zeros(grad_v.value.len()));
            let u = moments.step(&grad_v.value, lr, beta1, beta2, eps);
            along_direction(setup, sigma_v, grad_v, &u, required_v, v_new)
        }
    }
}

/// The error of the bounds crate as a [`RunError`].
fn bounds(e: sepg_bounds::BoundsError) -> RunError {
    RunError::Bounds(e.to_string())
}

/// The w-step of the certified accounting for `required_w`, applied to `w_new` (a copy of
/// wᵗ): from a w-block of `n_w` trajectories at (vᵗ⁺¹ = `v_new`, wᵗ), or from the v-block's
/// batch `ev` for SIM-ν, realised and certified again against the rigorous w-bound. Returns
/// Ĵ(vᵗ⁺¹, wᵗ) (`None` for SIM-ν), the block log and the guaranteed improvement.
fn certified_w_update(
    source: &mut dyn GradientSource,
    setup: &Setup,
    (state, sigmas, ev, v_new): (&State, &[f64], &BlockEstimate, &[f64]),
    (required_w, alpha, n_w): (f64, f64, usize),
    w_new: &mut [f64],
    counts: (&mut u64, &mut u64),
) -> Result<(Option<f64>, BlockLog, f64), RunError> {
    let ew = if matches!(setup.req, Requirement::Sim { .. }) {
        None
    } else {
        let q = (state.iteration, v_new, &state.w[..], n_w);
        Some(w_block(source, setup.naive_w, q, counts)?)
    };
    let e_w = ew.as_ref().unwrap_or(ev);
    let gj = e_w.grad_wj.as_ref().ok_or(RunError::Estimator(
        "the w-block returned no w-gradient".into(),
    ))?;
    let plan = w_plan(setup, sigmas, e_w, required_w, alpha)?;
    let k = setup.k;
    let (log, g_w, _) = apply_realised(
        w_new,
        &plan,
        |h| CoordinateBound::log_sigma(k, sigmas[h], gj.value[h], gj.eps[h]).map_err(bounds),
        required_w,
        setup.certify,
    )?;
    Ok((ew.map(|e| e.j), log, g_w))
}

/// Whether the variant evaluates a target policy θ_Tᵗ (LV, ZV, SIM-ν).
fn has_target(req: Requirement) -> bool {
    matches!(
        req,
        Requirement::Lv | Requirement::Zv | Requirement::Sim { .. }
    )
}

/// The target block of an iteration (LV, ZV, SIM-ν; the exploratory policy itself for the
/// other variants; `sizes` the batch sizes of the iteration's blocks): θ_Tᵗ's log σ and its J.
/// LV's target is a step along the v-block's ∇̂_w J that may lose at most `allowance`
/// (the budget's requirement), applied as it is or, with `realised`, through the certificate
/// of the rounded update; ZV's and SIM-ν's is the deterministic policy.
fn target_block(
    source: &mut dyn GradientSource,
    setup: &Setup,
    (state, sigmas, ev): (&State, &[f64], &BlockEstimate),
    (allowance, realised): (f64, bool),
    sizes: &[usize],
    counts: (&mut u64, &mut u64),
) -> Result<(Option<Vec<f64>>, f64), RunError> {
    let Setup {
        k, req, certify, ..
    } = *setup;
    if !has_target(req) {
        return Ok((Some(state.w.clone()), ev.j));
    }
    let w_target = if req == Requirement::Lv {
        let gwj = ev.grad_wj.as_ref().ok_or(RunError::Estimator(
            "the v-block returned no w-gradient".into(),
        ))?;
        let mut wt = state.w.clone();
        if let Some((h, dw)) = steps::lv_target(k, sigmas, gwj, allowance, certify)? {
            if realised {
                let b = CoordinateBound::log_sigma(k, sigmas[h], gwj.value[h], gwj.eps[h])
                    .map_err(|e| RunError::Bounds(e.to_string()))?;
                wt[h] = realise(wt[h], dw, &b, allowance, true).value;
            } else {
                wt[h] += dw;
            }
        }
        Some(wt)
    } else {
        None
    };
    let j_target = target_j(
        source,
        (state.iteration, &state.v, w_target.as_deref(), sizes[1]),
        counts,
    )?;
    Ok((w_target, j_target))
}

#[cfg(test)]
mod tests {
    use super::split;

    #[test]
    fn add_down_is_a_lower_bound_of_the_exact_sum() {
        use super::add_down;
        // 1 + 2⁻⁶⁰ rounds to 1 (below the exact sum): kept; 1 − 2⁻⁶⁰ rounds to 1 (above): moved
        assert_eq!(add_down(1.0, 2f64.powi(-60)), 1.0);
        assert_eq!(add_down(1.0, -(2f64.powi(-60))), 1.0f64.next_down());
        assert_eq!(add_down(0.5, 0.25), 0.75);
    }

    #[test]
    fn split_down_parts_add_up_to_at_most_the_budget() {
        use super::split_down;
        for (b, share) in [
            (1.0, 0.1),
            (0.3, 0.7),
            (1e-300, 0.5),
            (7.0, 1.0),
            (7.0, 0.0),
        ] {
            let (a, x) = split_down(b, share);
            assert!(a >= 0.0 && x >= 0.0);
            // exact check in two f64 with TwoSum: a + x ≤ b
            let s = a + x;
            let bb = s - a;
            let err = (a - (s - bb)) + (x - bb);
            assert!(s < b || (s == b && err <= 0.0), "{b} {share}: {a} + {x}");
        }
        assert_eq!(split_down(-1.0, 0.5), (0.0, 0.0));
    }

    #[test]
    fn split_is_even_with_remainder_first() {
        assert_eq!(split(100, 3), vec![34, 33, 33]);
        assert_eq!(split(100, 2), vec![50, 50]);
        assert_eq!(split(7, 1), vec![7]);
    }
}
