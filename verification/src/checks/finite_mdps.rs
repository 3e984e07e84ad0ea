//! Chapter 3 statements checked exactly on random finite MDPs (Sections 3.2, 3.3, 3.4, 3.6).

use std::cell::Cell;

use crate::check::{
    Check, CheckContext, CheckMeta, ClaimKind, Evaluation, Expected, Figure, Tolerance, fmt_f64,
};
use crate::finite_mdp::{PolicyEvaluation, RewardRange, Scenario, TabularPolicy, scenario};
use crate::search::{Comparison, search};

const MAX_STATES: usize = 8;
const MAX_ACTIONS: usize = 4;
const EXACT_TOL: Tolerance = Tolerance {
    abs: 1e-10,
    rel: 1e-9,
};
const EQUALITY_TOL: Tolerance = Tolerance {
    abs: 1e-10,
    rel: 1e-10,
};
const EXACT_FAR: &str = "0: exact linear-algebra evaluation; the tolerance only absorbs \
floating-point rounding (condition number of I − γP_π at most (1+γ)/(1−γ) ≤ 199)";
const SAMPLING: &str = "proptest over random finite MDPs: 1–8 states, 1–4 actions; \
transition rows dense, sparse or deterministic; γ ∈ {0, 0.5, 0.9, 0.99} or U[0, 0.99]; μ dense \
or a point mass; policies with dense, sparse or deterministic rows; α ∈ {0, 1} or U[0, 1]; \
rewards uniform on the check's range (default [−1, 1]) or exactly at its end points or 0; shrinking towards 1 state, 1 action, γ = 0, zero rewards";
const FULL: u32 = 4000;
/// Policy advantages below this fraction of the value scale R/(1−γ) are rounding noise (π is
/// already greedy); such cases are skipped as degenerate.
const DEGENERATE: f64 = 1e-9;
const QUICK: u32 = 400;

fn eval(s: &Scenario, pi: &TabularPolicy) -> Option<PolicyEvaluation> {
    s.mdp.evaluate(pi).ok()
}

/// Improvement J(π') − J(π) and the evaluation of π.
fn improvement(
    s: &Scenario,
    pi: &TabularPolicy,
    new: &TabularPolicy,
) -> Option<(f64, PolicyEvaluation)> {
    let e = eval(s, pi)?;
    let e_new = eval(s, new)?;
    Some((e_new.j() - e.j(), e))
}

fn meta(id: &str, statement: &str, location: &str, claim: &str, ground_truth: &str) -> CheckMeta {
    CheckMeta {
        id: id.into(),
        statement: statement.into(),
        location: location.into(),
        claim: claim.into(),
        ground_truth: ground_truth.into(),
        sampling: SAMPLING.into(),
        kind: ClaimKind::LowerBound,
        cases_full: FULL,
        cases_quick: QUICK,
        tolerance: EXACT_TOL,
        false_alarm_rate: EXACT_FAR.into(),
        expected: Expected::Holds,
        notes: String::new(),
        basis: String::new(),
    }
}

/// Case counts for the CPI step checks, whose counterexamples need γ ≳ 0.8, a large advantage
/// and near-deterministic dynamics (≈ 1 drawn case in 400): 4000 quick cases miss with
/// probability ≈ e⁻¹⁰, 20000 full cases ≈ e⁻⁵⁰.
fn rare(mut m: CheckMeta) -> CheckMeta {
    m.cases_quick = 4000;
    m.cases_full = 20_000;
    m
}

fn with(mut m: CheckMeta, kind: ClaimKind, expected: Expected, notes: &str) -> CheckMeta {
    m.kind = kind;
    m.expected = expected;
    m.notes = notes.into();
    if kind == ClaimKind::Equality {
        m.tolerance = EQUALITY_TOL;
    }
    m
}

/// `ε = max_s |E_{a∼π̄} A_π(s, a)|` (eq. 3.4).
fn cpi_epsilon(e: &PolicyEvaluation, target: &TabularPolicy) -> f64 {
    e.policy_advantage_by_state(target)
        .iter()
        .fold(0.0, |m, x| m.max(x.abs()))
}

fn thm_3_1(ctx: &CheckContext<'_>) -> Evaluation {
    let b = ctx.bounds;
    search(
        ctx,
        scenario(MAX_STATES, MAX_ACTIONS, RewardRange::Signed, 1),
        |s| {
            let pi = &s.policies[0];
            let Some(e) = eval(s, pi) else { return vec![] };
            let bar = e.greedy();
            let adv = e.policy_advantage(&bar);
            let eps = cpi_epsilon(&e, &bar);
            let Ok(new) = pi.mixture(&bar, s.alpha) else {
                return vec![];
            };
            let Some(e_new) = eval(s, &new) else {
                return vec![];
            };
            vec![Comparison::new(
                e_new.j() - e.j(),
                (b.cpi_bound)(s.alpha, adv, eps, s.mdp.gamma()),
            )]
        },
    )
}

/// CPI step and guarantee; `r_of` gives the reward constant R used in (3.5)–(3.6).
fn cpi_step(ctx: &CheckContext<'_>, rewards: RewardRange) -> Evaluation {
    let b = ctx.bounds;
    let worst_ratio = Cell::new(f64::INFINITY);
    let mut evaluation = search(ctx, scenario(MAX_STATES, MAX_ACTIONS, rewards, 1), |s| {
        let pi = &s.policies[0];
        let r = s.mdp.r_max();
        let Some(e) = eval(s, pi) else { return vec![] };
        let bar = e.greedy();
        let adv = e.policy_advantage(&bar);
        if r <= 0.0 || adv <= DEGENERATE * r / (1.0 - s.mdp.gamma()) {
            return vec![];
        }
        let alpha = (b.cpi_alpha_star)(adv, r, s.mdp.gamma()).clamp(0.0, 1.0);
        let Ok(new) = pi.mixture(&bar, alpha) else {
            return vec![];
        };
        let Some(e_new) = eval(s, &new) else {
            return vec![];
        };
        let gain = e_new.j() - e.j();
        let guarantee = (b.cpi_guarantee)(adv, r);
        worst_ratio.set(worst_ratio.get().min(gain / guarantee));
        vec![Comparison::new(gain, guarantee)]
    });
    evaluation.figures.push(Figure {
        name: "min over cases of true gain / guaranteed gain".into(),
        value: fmt_f64(worst_ratio.get()),
    });
    evaluation
}

fn thm_3_2(ctx: &CheckContext<'_>) -> Evaluation {
    cpi_step(ctx, RewardRange::Signed)
}

fn thm_3_2_nonneg(ctx: &CheckContext<'_>) -> Evaluation {
    cpi_step(ctx, RewardRange::NonNegative)
}

fn thm_3_3(ctx: &CheckContext<'_>) -> Evaluation {
    search(
        ctx,
        scenario(MAX_STATES, MAX_ACTIONS, RewardRange::Signed, 2),
        |s| {
            let (pi, tilde) = (&s.policies[0], &s.policies[1]);
            let Some((gain, e)) = improvement(s, pi, tilde) else {
                return vec![];
            };
            let Some(e_tilde) = eval(s, tilde) else {
                return vec![];
            };
            let rhs = e.weighted_policy_advantage(e_tilde.state_distribution(), tilde)
                / (1.0 - s.mdp.gamma());
            vec![Comparison::new(gain, rhs)]
        },
    )
}

fn lemma_3_15(ctx: &CheckContext<'_>) -> Evaluation {
    search(
        ctx,
        scenario(MAX_STATES, MAX_ACTIONS, RewardRange::Signed, 2),
        |s| {
            let (pi, tilde) = (&s.policies[0], &s.policies[1]);
            let Some(e) = eval(s, pi) else { return vec![] };
            let Some(e_tilde) = eval(s, tilde) else {
                return vec![];
            };
            let per_state = e.policy_advantage_by_state(tilde);
            let Ok(trajectory) = s.mdp.discounted_sum_along(tilde, &per_state) else {
                return vec![];
            };
            let distribution = e.weighted_policy_advantage(e_tilde.state_distribution(), tilde)
                / (1.0 - s.mdp.gamma());
            vec![
                Comparison::new(e_tilde.j(), e.j() + trajectory),
                Comparison::new(e_tilde.j(), e.j() + distribution),
            ]
        },
    )
}

fn l1(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).sum()
}

fn thm_3_4(ctx: &CheckContext<'_>) -> Evaluation {
    let b = ctx.bounds;
    let worst = Cell::new(0.0f64);
    let mut evaluation = search(
        ctx,
        scenario(MAX_STATES, MAX_ACTIONS, RewardRange::Signed, 2),
        |s| {
            let (pi, new) = (&s.policies[0], &s.policies[1]);
            let (Some(e), Some(e_new)) = (eval(s, pi), eval(s, new)) else {
                return vec![];
            };
            let Ok(d_inf) = pi.sup_l1_distance(new) else {
                return vec![];
            };
            let dist = l1(e.state_distribution(), e_new.state_distribution());
            let gamma = s.mdp.gamma();
            if gamma > 0.0 && d_inf > 0.0 {
                worst.set(worst.get().max(dist / (gamma / (1.0 - gamma) * d_inf)));
            }
            vec![Comparison::new(
                dist,
                (b.state_distribution_bound)(d_inf, gamma),
            )]
        },
    );
    evaluation.figures.push(Figure {
        name: "max over cases of ‖d' − d‖₁ / (γ D_∞ / (1 − γ)) (normalised form)".into(),
        value: fmt_f64(worst.get()),
    });
    evaluation
}

fn thm_3_4_tight(ctx: &CheckContext<'_>) -> Evaluation {
    search(
        ctx,
        scenario(MAX_STATES, MAX_ACTIONS, RewardRange::Signed, 2),
        |s| {
            let (pi, new) = (&s.policies[0], &s.policies[1]);
            let (Some(e), Some(e_new)) = (eval(s, pi), eval(s, new)) else {
                return vec![];
            };
            let Ok(d_inf) = pi.sup_l1_distance(new) else {
                return vec![];
            };
            let gamma = s.mdp.gamma();
            vec![Comparison::new(
                l1(e.state_distribution(), e_new.state_distribution()),
                gamma / (1.0 - gamma) * d_inf,
            )]
        },
    )
}

fn thm_3_5(ctx: &CheckContext<'_>) -> Evaluation {
    let b = ctx.bounds;
    search(
        ctx,
        scenario(MAX_STATES, MAX_ACTIONS, RewardRange::Signed, 3),
        |s| {
            let (pi, new, base) = (&s.policies[0], &s.policies[1], &s.policies[2]);
            let Some((gain, e)) = improvement(s, pi, new) else {
                return vec![];
            };
            let Some(e_base) = eval(s, base) else {
                return vec![];
            };
            let Ok(d_inf) = base.sup_l1_distance(new) else {
                return vec![];
            };
            let weighted = e.weighted_policy_advantage(e_base.state_distribution(), new);
            let bound = (b.pirotta_advantage_bound)(
                weighted,
                d_inf,
                e.advantage_spread(new),
                s.mdp.gamma(),
            );
            vec![Comparison::new(gain, bound)]
        },
    )
}

/// Which reading of ‖Q^π‖_∞ to use in eq. (3.12).
#[derive(Clone, Copy)]
enum QNorm {
    /// `sup_{s,a} Q(s, a)` as printed.
    Sup,
    /// `sup_{s,a} |Q(s, a)|`.
    SupAbs,
}

/// Pirotta's Q bound; `step` maps the second drawn policy to π' (arbitrary or a small step).
fn pirotta_q(
    ctx: &CheckContext<'_>,
    rewards: RewardRange,
    norm: QNorm,
    small_step: bool,
) -> Evaluation {
    let b = ctx.bounds;
    search(ctx, scenario(MAX_STATES, MAX_ACTIONS, rewards, 2), |s| {
        let pi = &s.policies[0];
        let new = if small_step {
            match pi.mixture(&s.policies[1], 0.1 * s.alpha) {
                Ok(p) => p,
                Err(_) => return vec![],
            }
        } else {
            s.policies[1].clone()
        };
        let Some((gain, e)) = improvement(s, pi, &new) else {
            return vec![];
        };
        let Ok(d_inf) = pi.sup_l1_distance(&new) else {
            return vec![];
        };
        let q = match norm {
            QNorm::Sup => e.q_sup(),
            QNorm::SupAbs => e.q_sup_abs(),
        };
        let bound = (b.pirotta_q_bound)(e.policy_advantage(&new), d_inf, q, s.mdp.gamma());
        vec![Comparison::new(gain, bound)]
    })
}

fn thm_3_6_sup(ctx: &CheckContext<'_>) -> Evaluation {
    pirotta_q(ctx, RewardRange::Signed, QNorm::Sup, false)
}

fn thm_3_6_abs(ctx: &CheckContext<'_>) -> Evaluation {
    pirotta_q(ctx, RewardRange::Signed, QNorm::SupAbs, false)
}

fn thm_3_6_nonneg(ctx: &CheckContext<'_>) -> Evaluation {
    pirotta_q(ctx, RewardRange::NonNegative, QNorm::Sup, false)
}

fn thm_3_8_sup(ctx: &CheckContext<'_>) -> Evaluation {
    pirotta_q(ctx, RewardRange::NonPositive, QNorm::Sup, true)
}

fn thm_3_8_abs(ctx: &CheckContext<'_>) -> Evaluation {
    pirotta_q(ctx, RewardRange::Signed, QNorm::SupAbs, true)
}

fn thm_3_7(ctx: &CheckContext<'_>) -> Evaluation {
    let b = ctx.bounds;
    let full_steps = Cell::new(0u64);
    let partial_steps = Cell::new(0u64);
    let mut evaluation = search(
        ctx,
        scenario(MAX_STATES, MAX_ACTIONS, RewardRange::Signed, 1),
        |s| {
            let pi = &s.policies[0];
            let gamma = s.mdp.gamma();
            let Some(e) = eval(s, pi) else { return vec![] };
            let bar = e.greedy();
            let adv = e.policy_advantage(&bar);
            if adv <= DEGENERATE * s.mdp.r_max() / (1.0 - gamma) {
                return vec![];
            }
            let Ok(d_inf) = pi.sup_l1_distance(&bar) else {
                return vec![];
            };
            let spread = e.advantage_spread(&bar);
            let alpha_star = if gamma * d_inf * spread > 0.0 {
                (b.uspi_alpha_star)(adv, d_inf, spread, gamma)
            } else {
                f64::INFINITY
            };
            let (alpha, guarantee) = if alpha_star <= 1.0 {
                partial_steps.set(partial_steps.get() + 1);
                (alpha_star, (b.uspi_guarantee)(adv, d_inf, spread, gamma))
            } else {
                full_steps.set(full_steps.get() + 1);
                (1.0, (b.pirotta_advantage_bound)(adv, d_inf, spread, gamma))
            };
            let Ok(new) = pi.mixture(&bar, alpha) else {
                return vec![];
            };
            let Some(e_new) = eval(s, &new) else {
                return vec![];
            };
            vec![Comparison::new(e_new.j() - e.j(), guarantee)]
        },
    );
    evaluation.figures.push(Figure {
        name: "cases with α* ≤ 1 / with a full step".into(),
        value: format!("{} / {}", partial_steps.get(), full_steps.get()),
    });
    evaluation
}

fn thm_3_16(ctx: &CheckContext<'_>) -> Evaluation {
    let b = ctx.bounds;
    search(
        ctx,
        scenario(MAX_STATES, MAX_ACTIONS, RewardRange::Signed, 2),
        |s| {
            let pi = &s.policies[0];
            let Ok(tilde) = pi.mixture(&s.policies[1], s.alpha) else {
                return vec![];
            };
            let (Some(e), Some(e_tilde)) = (eval(s, pi), eval(s, &tilde)) else {
                return vec![];
            };
            let Ok(kl) = pi.max_kl(&tilde) else {
                return vec![];
            };
            if !kl.is_finite() {
                return vec![];
            }
            let gamma = s.mdp.gamma();
            let surrogate = e.j() + e.policy_advantage(&tilde) / (1.0 - gamma);
            let c = (b.trpo_penalty)(e.max_abs_advantage(), gamma);
            vec![Comparison::new(e_tilde.j(), surrogate - c * kl)]
        },
    )
}

const GT_EXACT: &str = "exact policy evaluation by LU solves of (I − γP_π) V = r_π and \
(I − γP_π)ᵀ x = μ on the sampled MDP";

/// The Chapter 3 checks, in registry order.
pub(crate) fn checks() -> Vec<Check> {
    vec![
        thm_3_1_check(),
        thm_3_2_check(),
        thm_3_2_nonneg_check(),
        thm_3_3_check(),
        thm_3_4_check(),
        thm_3_4_tight_check(),
        thm_3_5_check(),
        thm_3_6_sup_check(),
        thm_3_6_abs_check(),
        thm_3_6_nonneg_check(),
        thm_3_7_check(),
        thm_3_8_sup_check(),
        thm_3_8_abs_check(),
        lemma_3_15_check(),
        thm_3_16_check(),
    ]
}

/// The check `thm-3.1-cpi-bound`.
fn thm_3_1_check() -> Check {
    Check::new(
        with(
            meta(
                "thm-3.1-cpi-bound",
                "Theorem 3.1 (Kakade & Langford CPI bound)",
                "Section 3.2, eqs. (3.2)–(3.4)",
                "For π' = (1−α)π + απ̄ with π̄ greedy w.r.t. Q^π and every α ∈ [0,1]: \
                     J(π') − J(π) ≥ α/(1−γ)·(𝔸 − 2αγε/(1−γ(1−α))), 𝔸 = Σ_s d^π(s) Σ_a π̄(a|s) A^π(s,a) \
                     with the normalised d, ε = max_s |Σ_a π̄(a|s) A^π(s,a)| (printed form).",
                GT_EXACT,
            ),
            ClaimKind::LowerBound,
            Expected::Holds,
            "The printed form is scale-consistent with the normalised d (both sides are \
                 homogeneous of degree one in the rewards) and holds.",
        ),
        thm_3_1,
    )
}

/// The check `thm-3.2-cpi-step`.
fn thm_3_2_check() -> Check {
    Check::new(
        rare(with(
            meta(
                "thm-3.2-cpi-step",
                "Theorem 3.2 (CPI step α* and guarantee)",
                "Section 3.2, eqs. (3.5)–(3.6)",
                "With R = max|R(s,a)|, rewards in [−R, R] and α = min(α*, 1), \
                     α* = (1−γ)𝔸/(4R): J(π') − J(π) ≥ 𝔸²/(8R) (printed form).",
                GT_EXACT,
            ),
            ClaimKind::LowerBound,
            Expected::Violated,
            "Printed constants mix Kakade & Langford's normalised values ((1−γ)-scaled V, \
                 rewards in [0, R]) with the thesis's unnormalised J. In the thesis's units the \
                 derivation from (3.2) with ε ≤ R_span/(1−γ) gives α* = (1−γ)²𝔸/(4R_span) and \
                 J(π') − J(π) ≥ (1−γ)𝔸²/(8R_span), R_span the reward range (2R for rewards \
                 in [−R, R]).",
        )),
        thm_3_2,
    )
}

/// The check `thm-3.2-cpi-step-nonneg-rewards`.
fn thm_3_2_nonneg_check() -> Check {
    Check::new(
        rare(with(
            meta(
                "thm-3.2-cpi-step-nonneg-rewards",
                "Theorem 3.2 (CPI step α* and guarantee), rewards in [0, R]",
                "Section 3.2, eqs. (3.5)–(3.6)",
                "Same as thm-3.2-cpi-step with rewards in [0, R] (Kakade & Langford's \
                     convention): J(π') − J(π) ≥ 𝔸²/(8R) at α = min((1−γ)𝔸/(4R), 1).",
                GT_EXACT,
            ),
            ClaimKind::LowerBound,
            Expected::Violated,
            "Non-negative rewards do not rescue the printed form: the missing factors are \
                 powers of (1−γ) from the normalisation of values, not the reward sign.",
        )),
        thm_3_2_nonneg,
    )
}

/// The check `thm-3.3-performance-difference`.
fn thm_3_3_check() -> Check {
    Check::new(
        with(
            meta(
                "thm-3.3-performance-difference",
                "Theorem 3.3 (performance difference lemma)",
                "Section 3.2, eq. (3.7)",
                "For any π, π̃: J(π̃) − J(π) = 1/(1−γ) Σ_s d^{π̃}(s) Σ_a π̃(a|s) A^π(s,a) \
                     (equality, normalised d).",
                GT_EXACT,
            ),
            ClaimKind::Equality,
            Expected::Holds,
            "Exact identity.",
        ),
        thm_3_3,
    )
}

/// The check `thm-3.4-state-distribution`.
fn thm_3_4_check() -> Check {
    Check::new(
        with(
            meta(
                "thm-3.4-state-distribution",
                "Theorem 3.4 (future-state distribution bound)",
                "Section 3.3, eqs. (3.8)–(3.9)",
                "‖d^{π'} − d^π‖₁ ≤ γ/(1−γ)² · D_∞^{π,π'}, D_∞ = max_s ‖π'(·|s) − π(·|s)‖₁ \
                     (printed form, normalised d).",
                GT_EXACT,
            ),
            ClaimKind::UpperBound,
            Expected::Holds,
            "Holds, as printed (no error). For the normalised d of Definition 2.5 the \
                 sharper γ/(1−γ) also holds (thm-3.4-normalised-form); the printed γ/(1−γ)² is \
                 Pirotta et al.'s constant, larger, hence also valid.",
        ),
        thm_3_4,
    )
}

/// The check `thm-3.4-normalised-form`.
fn thm_3_4_tight_check() -> Check {
    Check::new(
        with(
            meta(
                "thm-3.4-normalised-form",
                "Theorem 3.4, normalised restatement",
                "Section 3.3, eq. (3.8) with the normalisation of Definition 2.5",
                "‖d^{π'} − d^π‖₁ ≤ γ/(1−γ) · D_∞^{π,π'} for the normalised d \
                     (from (d' − d)ᵀ = γ dᵀ(P_{π'} − P_π)(I − γP_{π'})^{-1}).",
                GT_EXACT,
            ),
            ClaimKind::UpperBound,
            Expected::Holds,
            "The correct constant for the normalised distribution used throughout the thesis.",
        ),
        thm_3_4_tight,
    )
}

/// The check `thm-3.5-pirotta-advantage-bound`.
fn thm_3_5_check() -> Check {
    Check::new(
        with(
            meta(
                "thm-3.5-pirotta-advantage-bound",
                "Theorem 3.5 (Pirotta et al., bound with a baseline policy)",
                "Section 3.3, eqs. (3.10)–(3.11)",
                "For any π, π', π_b: J(π') − J(π) ≥ Σ_s d^{π_b}(s) A^{π'}_π(s)/(1−γ) − \
                     γ/(1−γ)² · D_∞^{π_b,π'} · ΔA^{π'}_π / 2, ΔA = max_s A^{π'}_π(s) − min_s A^{π'}_π(s).",
                GT_EXACT,
            ),
            ClaimKind::LowerBound,
            Expected::Holds,
            "Holds as printed (the normalised d and the 1/(1−γ)² constant are consistent \
                 here because the first term carries 1/(1−γ)).",
        ),
        thm_3_5,
    )
}

/// The check `thm-3.6-q-bound-sup-q`.
fn thm_3_6_sup_check() -> Check {
    Check::new(
        with(
            meta(
                "thm-3.6-q-bound-sup-q",
                "Theorem 3.6 (Pirotta et al., Q-based bound), ‖Q‖_∞ = sup Q as printed",
                "Section 3.3, eq. (3.12)",
                "J(π') − J(π) ≥ 𝔸^{π'}_{π,μ}/(1−γ) − γ/(1−γ)² · (D_∞^{π,π'})² · ‖Q^π‖_∞/2 \
                     with ‖Q^π‖_∞ read as sup_{s,a} Q^π(s,a) (no absolute value), signed rewards.",
                GT_EXACT,
            ),
            ClaimKind::LowerBound,
            Expected::Violated,
            "With negative rewards sup Q < 0 turns the penalty into a bonus; the printed \
                 definition needs an absolute value.",
        ),
        thm_3_6_sup,
    )
}

/// The check `thm-3.6-q-bound-abs-q`.
fn thm_3_6_abs_check() -> Check {
    Check::new(
        with(
            meta(
                "thm-3.6-q-bound-abs-q",
                "Theorem 3.6 (Pirotta et al., Q-based bound), ‖Q‖_∞ = sup |Q|",
                "Section 3.3, eq. (3.12)",
                "Same bound with ‖Q^π‖_∞ = sup_{s,a} |Q^π(s,a)|, signed rewards.",
                GT_EXACT,
            ),
            ClaimKind::LowerBound,
            Expected::Holds,
            "Holds on every MDP tried. Note the rigorous derivation from Theorem 3.5 with \
                 signed rewards only gives ΔA ≤ 2 D_∞ ‖Q‖_∞ (penalty without the 1/2); the 1/2 is \
                 guaranteed for Q ≥ 0.",
        ),
        thm_3_6_abs,
    )
}

/// The check `thm-3.6-q-bound-nonneg-rewards`.
fn thm_3_6_nonneg_check() -> Check {
    Check::new(
        with(
            meta(
                "thm-3.6-q-bound-nonneg-rewards",
                "Theorem 3.6 (Pirotta et al., Q-based bound), rewards in [0, 1]",
                "Section 3.3, eq. (3.12)",
                "Same bound with rewards in [0, 1], where sup Q = sup |Q| (the setting of \
                     Pirotta et al.).",
                GT_EXACT,
            ),
            ClaimKind::LowerBound,
            Expected::Holds,
            "Holds: with Q ≥ 0 the per-state spread of Q is at most ‖Q‖_∞.",
        ),
        thm_3_6_nonneg,
    )
}

/// The check `thm-3.7-uspi`.
fn thm_3_7_check() -> Check {
    Check::new(
        with(
            meta(
                "thm-3.7-uspi",
                "Theorem 3.7 (USPI step size and guarantee)",
                "Section 3.3, Theorem 3.7 and eq. (3.13)",
                "π' = (1−α)π + απ̄, α = min(α*, 1), α* = (1−γ)𝔸/(γ D_∞^{π,π̄} ΔA^{π̄}_π): \
                     if α* ≤ 1, J(π') − J(π) ≥ 𝔸²/(2γ D_∞ ΔA); otherwise the bound (3.13) with \
                     π' = π̄ (𝔸, D_∞, ΔA all taken w.r.t. the greedy π̄).",
                GT_EXACT,
            ),
            ClaimKind::LowerBound,
            Expected::Holds,
            "Holds with the normalised d: the (1−γ) in α* is exactly the factor the \
                 thesis's footnote on normalisation refers to. Printed typos: 'update rule 3.2' \
                 means (3.1); α* and the guarantee's numerator are written with π' where π̄ is \
                 meant (the π' reading gives a weaker, also valid, guarantee).",
        ),
        thm_3_7,
    )
}

/// The check `thm-3.8-q-bound-sup-q-costs`.
fn thm_3_8_sup_check() -> Check {
    Check::new(
        with(
            meta(
                "thm-3.8-q-bound-sup-q-costs",
                "Theorem 3.8 (continuous version of Pirotta's bound) on finite MDPs, sup Q",
                "Section 3.4, Theorem 3.8",
                "For a small step π' = (1−0.1α)π + 0.1απ₂ and rewards in [−1, 0] (costs, as in \
                     the LQG): J(π') − J(π) ≥ 1/(1−γ) Σ_s d^π(s) A^{π'}_π(s) − γ/(2(1−γ)²) \
                     ‖π' − π‖²_∞ ‖Q^π‖_∞, ‖Q‖_∞ = sup Q as printed.",
                GT_EXACT,
            ),
            ClaimKind::LowerBound,
            Expected::Violated,
            "With costs, sup Q ≤ 0 so the printed penalty has the wrong sign; the absolute \
                 value is needed (see thm-3.8-q-bound-abs-q).",
        ),
        thm_3_8_sup,
    )
}

/// The check `thm-3.8-q-bound-abs-q`.
fn thm_3_8_abs_check() -> Check {
    Check::new(
        with(
            meta(
                "thm-3.8-q-bound-abs-q",
                "Theorem 3.8 (continuous version of Pirotta's bound) on finite MDPs, sup |Q|",
                "Section 3.4, Theorem 3.8",
                "Small steps π' = (1−0.1α)π + 0.1απ₂, signed rewards, ‖Q‖_∞ = sup |Q|.",
                GT_EXACT,
            ),
            ClaimKind::LowerBound,
            Expected::Holds,
            "Holds for small policy steps with the absolute-value reading.",
        ),
        thm_3_8_abs,
    )
}

/// The check `lemma-3.15-trajectory-form`.
fn lemma_3_15_check() -> Check {
    Check::new(
        with(
            meta(
                "lemma-3.15-trajectory-form",
                "Lemma 3.15 (performance of π̃ through the advantage of π)",
                "Section 3.6, Lemma 3.15",
                "J(π̃) = J(π) + E_{τ∼π̃}[Σ_t γ^t A_π(s_t, a_t)] = J(π) + 1/(1−γ) Σ_s d^{π̃}(s) \
                     Σ_a π̃(a|s) A_π(s,a) (both equalities).",
                "exact evaluation; the trajectory form by propagating the state \
                     distribution of π̃ step by step until γ^t < 1e-18 (no linear solve)",
            ),
            ClaimKind::Equality,
            Expected::Holds,
            "Exact identity.",
        ),
        lemma_3_15,
    )
}

/// The check `thm-3.16-trpo-bound`.
fn thm_3_16_check() -> Check {
    Check::new(
        with(
            meta(
                "thm-3.16-trpo-bound",
                "Theorem 3.16 (TRPO lower bound)",
                "Section 3.6, Theorem 3.16",
                "J(π̃) ≥ L_π(π̃) − C·max_s KL(π(·|s) ‖ π̃(·|s)), C = 4εγ/(1−γ)², \
                     ε = max_{s,a} |A_π(s,a)|, L_π(π̃) = J(π) + 1/(1−γ) Σ_s d^π(s) Σ_a π̃(a|s) A_π(s,a); \
                     π̃ = (1−α)π + απ₂ (cases with infinite KL are skipped).",
                GT_EXACT,
            ),
            ClaimKind::LowerBound,
            Expected::Holds,
            "Holds as printed (Schulman et al.'s unnormalised statement is equivalent).",
        ),
        thm_3_16,
    )
}
