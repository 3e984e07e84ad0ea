//! Chapter 4 statements that need no environment: the budget identity of Theorem 4.1.

use proptest::prelude::*;
use sepg_bounds::budget::Budget;

use crate::check::{Check, CheckContext, CheckMeta, ClaimKind, Evaluation, Expected, Tolerance};
use crate::search::{Comparison, search};

/// Scale of the dyadic performance values: every J is an integer multiple of 2⁻¹⁰ below 2¹² in
/// magnitude, so every sum below is exact in double precision.
const DYADIC: f64 = 1.0 / 1024.0;

/// A learning history: performances of the exploratory and target policies at t = 0..=T, and
/// an initial budget B⁰.
#[derive(Debug, Clone)]
struct History {
    explore: Vec<f64>,
    target: Vec<f64>,
    initial_budget: f64,
}

impl History {
    /// Budgets B^t maintained by `sepg_bounds::budget::Budget` from the measured performances
    /// (Definition 4.3, eq. (4.6): B^t = B^{t−1} + ΔJ_E + ΔJ_T); `None` if it rejects a value.
    fn budgets(&self) -> Option<Vec<f64>> {
        let mut budget =
            Budget::new(self.initial_budget, self.explore[0], Some(self.target[0])).ok()?;
        let mut out = vec![budget.value()];
        for t in 1..self.explore.len() {
            budget.record_exploratory(self.explore[t]).ok()?;
            budget.record_target(self.target[t]).ok()?;
            out.push(budget.value());
        }
        Some(out)
    }

    /// The baseline of Theorem 4.1, J_B = [J(θ_E⁰) + J(θ_T⁰)]/2.
    fn baseline(&self) -> f64 {
        (self.explore[0] + self.target[0]) / 2.0
    }
}

fn history(initial_budget: BoxedStrategy<f64>) -> impl Strategy<Value = History> {
    (1usize..40, initial_budget).prop_flat_map(|(len, b0)| {
        let values = prop::collection::vec(-(1i32 << 12)..(1i32 << 12), len + 1);
        (values.clone(), values).prop_map(move |(e, t)| History {
            explore: e.iter().map(|&k| f64::from(k) * DYADIC).collect(),
            target: t.iter().map(|&k| f64::from(k) * DYADIC).collect(),
            initial_budget: b0,
        })
    })
}

fn telescoping(ctx: &CheckContext<'_>) -> Evaluation {
    search(ctx, history(Just(0.0).boxed()), |h| {
        h.budgets()
            .unwrap_or_default()
            .iter()
            .enumerate()
            .map(|(t, &b)| {
                let telescoped = h.explore[t] - h.explore[0] + h.target[t] - h.target[0];
                Comparison::new(b, telescoped)
            })
            .collect()
    })
}

/// At every t ≥ 1 with B^t ≥ 0, compare (J_E^t + J_T^t)/2 with J_B (t = 0 is equal by
/// definition).
fn type_ii(h: &History) -> Vec<Comparison> {
    h.budgets()
        .unwrap_or_default()
        .iter()
        .enumerate()
        .skip(1)
        .filter(|&(_, &b)| b >= 0.0)
        .map(|(t, _)| Comparison::new((h.explore[t] + h.target[t]) / 2.0, h.baseline()))
        .collect()
}

fn type_ii_safety(ctx: &CheckContext<'_>) -> Evaluation {
    search(ctx, history(Just(0.0).boxed()), type_ii)
}

fn meta(id: &str, statement: &str, claim: &str, kind: ClaimKind) -> CheckMeta {
    CheckMeta {
        id: id.into(),
        statement: statement.into(),
        location: "Section 4.2.2, Definition 4.3 eq. (4.6) and Theorem 4.1; proof in Appendix A"
            .into(),
        claim: claim.into(),
        ground_truth: "the budget maintained by sepg_bounds::budget::Budget against the \
                       telescoped sum, in exact dyadic arithmetic: every J is k·2⁻¹⁰ with \
                       |k| < 2¹², so all sums are exact in double precision"
            .into(),
        sampling: "proptest: histories of 2–40 iterations, J_E^t and J_T^t independent dyadic \
                   values in [−4, 4)"
            .into(),
        kind,
        cases_full: 2000,
        cases_quick: 200,
        tolerance: Tolerance { abs: 0.0, rel: 0.0 },
        false_alarm_rate: "0: exact arithmetic".into(),
        expected: Expected::Holds,
        notes: String::new(),
        basis: String::new(),
    }
}

/// The Chapter 4 checks of this module, in registry order.
pub(crate) fn checks() -> Vec<Check> {
    let mut tele = meta(
        "thm-4.1-budget-telescoping",
        "Theorem 4.1 proof (budget telescoping)",
        "With B⁰ = 0 and B^t = B^{t−1} + J(θ_E^t) − J(θ_E^{t−1}) + J(θ_T^t) − J(θ_T^{t−1}): \
         B^t = J(θ_E^t) − J(θ_E^0) + J(θ_T^t) − J(θ_T^0) exactly, at every t.",
        ClaimKind::Equality,
    );
    tele.notes = "Holds. Eq. (4.6) as printed sums the t-indexed difference over k (index typo: \
        the summand should use k and the sum start at k = 1)."
        .into();
    let mut safety = meta(
        "thm-4.1-type-ii-safety",
        "Theorem 4.1 (non-negative budget implies type-II safety)",
        "At every t with B^t ≥ 0 (B⁰ = 0): (J(θ_E^t) + J(θ_T^t))/2 ≥ J_B = \
         (J(θ_E^0) + J(θ_T^0))/2.",
        ClaimKind::LowerBound,
    );
    safety.notes = "Holds.".into();
    vec![
        Check::new(tele, telescoping),
        Check::new(safety, type_ii_safety),
    ]
}
