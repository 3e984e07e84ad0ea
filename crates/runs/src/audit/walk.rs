//! The walk over the log: the points each iteration's checks need, and the checks themselves.

use std::collections::{BTreeMap, HashMap};

use sepg_algo::core::config::Requirement;

use super::exact::key;
use super::judge::Plan;
use super::report::Violation;
use crate::error::{Error, Result};
use crate::logcheck::Row;

/// Counts of one check while walking the log.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Tally {
    pub(super) checked: u64,
    pub(super) steps: u64,
    pub(super) failed: u64,
    pub(super) first: Option<u64>,
    pub(super) last_failed: Option<u64>,
    pub(super) streak: u64,
    pub(super) longest: u64,
    /// Largest shortfall and its iteration.
    pub(super) worst: Option<(f64, u64)>,
}

/// max(1, |x| for x in xs): the scale of the tolerance of a comparison of these values.
pub(super) fn scale(xs: &[f64]) -> f64 {
    xs.iter().fold(1.0f64, |m, x| m.max(x.abs()))
}

/// The failures and counts of every check while walking the log.
pub(super) struct Auditor {
    pub(super) tolerance: f64,
    pub(super) tallies: BTreeMap<&'static str, Tally>,
    pub(super) failures: Vec<Violation>,
}

impl Auditor {
    /// Counts one evaluation of check `name` at iteration `t` over the comparisons
    /// `(required, actual, scale)` (none: the iteration cannot fail, e.g. no step taken);
    /// the iteration fails when a shortfall `required − actual` exceeds `tolerance · scale`,
    /// and the largest such shortfall is recorded.
    pub(super) fn check(&mut self, t: u64, name: &'static str, comparisons: &[(f64, f64, f64)]) {
        let tally = self.tallies.entry(name).or_default();
        tally.checked += 1;
        let mut failure: Option<Violation> = None;
        for &(required, actual, scale) in comparisons {
            let shortfall = required - actual;
            if tally.worst.is_none_or(|(w, _)| shortfall > w) {
                tally.worst = Some((shortfall, t));
            }
            if shortfall > self.tolerance * scale
                && failure.as_ref().is_none_or(|f| shortfall > f.shortfall)
            {
                failure = Some(Violation {
                    iteration: t,
                    check: name,
                    required,
                    actual,
                    shortfall,
                });
            }
        }
        if let Some(f) = failure {
            tally.failed += 1;
            tally.first.get_or_insert(t);
            tally.streak = match tally.last_failed {
                Some(prev) if prev + 1 == t => tally.streak + 1,
                _ => 1,
            };
            tally.longest = tally.longest.max(tally.streak);
            tally.last_failed = Some(t);
            self.failures.push(f);
        }
    }

    /// Counts a step taken by check `name`.
    fn step(&mut self, name: &'static str) {
        self.tallies.entry(name).or_default().steps += 1;
    }
}

/// One row of the log with the parameters after its update (`None`: not in the log).
pub(super) struct Step<'r> {
    pub(super) row: &'r Row,
    pub(super) next: Option<(Vec<f64>, Vec<f64>)>,
}

/// What the walk needs to know about the run.
pub(super) struct Walk {
    pub(super) requirement: Option<Requirement>,
    pub(super) budget0: f64,
}

impl Walk {
    /// Whether the run is SIM-ν, whose w-step is measured from θᵗ.
    fn sim(&self) -> bool {
        matches!(self.requirement, Some(Requirement::Sim { .. }))
    }

    /// The points whose exact J the checks of `step` use.
    pub(super) fn points(&self, step: &Step<'_>, plans: &[Plan], out: &mut Vec<Vec<u64>>) {
        let row = step.row;
        out.push(key(&row.v, &row.w));
        if plans.iter().any(|p| p.name == "budget-target") {
            out.push(key(&row.v, &row.w_target));
        }
        if let Some((v, w)) = &step.next {
            out.push(key(v, &row.w));
            out.push(key(v, w));
            if self.sim() {
                out.push(key(&row.v, w));
            }
        }
    }

    /// Every check of one step, with exact J from `js` and J(θ⁰) = `j0`; false when the
    /// step's next parameters are not logged (its checks of the update are skipped).
    pub(super) fn step(
        &self,
        a: &mut Auditor,
        plans: &[Plan],
        step: &Step<'_>,
        js: &HashMap<Vec<u64>, f64>,
        j0: f64,
    ) -> Result<bool> {
        let row = step.row;
        let has = |name: &str| plans.iter().any(|p| p.name == name);
        let floor = j0 - self.budget0;
        if has("budget-target") {
            let jt = lookup(js, &row.v, &row.w_target)?;
            a.check(
                row.iteration,
                "budget-target",
                &[(floor, jt, scale(&[j0, jt, self.budget0]))],
            );
        }
        if has("budget") {
            a.check(row.iteration, "budget", &[(0.0, row.budget, 1.0)]);
        }
        let Some((v_next, w_next)) = &step.next else {
            return Ok(false);
        };
        if plans
            .iter()
            .all(|p| matches!(p.name, "budget" | "budget-target"))
        {
            return Ok(true);
        }
        let path = UpdateJ {
            j_t: lookup(js, &row.v, &row.w)?,
            j_mid: lookup(js, v_next, &row.w)?,
            j_next: lookup(js, v_next, w_next)?,
        };
        if has("guarantee-v") {
            self.guarantee_v(a, row, &path);
        }
        if has("guarantee-w") {
            // SIM-ν measures the w-step from θᵗ: J(vᵗ, wᵗ⁺¹) − J(θᵗ)
            let j_sim = if self.sim() {
                Some(lookup(js, &row.v, w_next)?)
            } else {
                None
            };
            self.guarantee_w(a, row, &path, j_sim);
        }
        self.floors(a, &has, row.iteration, &path, j0);
        Ok(true)
    }

    /// `guarantee-v`: J(θᵗ⁺½) − J(θᵗ) ≥ guaranteed_v, failing only when the v-step was taken.
    fn guarantee_v(&self, a: &mut Auditor, row: &Row, path: &UpdateJ) {
        let taken = row.alpha != 0.0;
        if taken {
            a.step("guarantee-v");
        }
        let comps: Vec<(f64, f64, f64)> = row
            .guaranteed_v
            .filter(|_| taken)
            .map(|g| (g, path.j_mid - path.j_t, scale(&[path.j_mid, path.j_t])))
            .into_iter()
            .collect();
        a.check(row.iteration, "guarantee-v", &comps);
    }

    /// `guarantee-w`: J(θᵗ⁺¹) − J(θᵗ⁺½) ≥ guaranteed_w (SIM-ν: from J(θᵗ) to `j_sim` =
    /// J(vᵗ, wᵗ⁺¹)), failing only when the w-step was taken.
    fn guarantee_w(&self, a: &mut Auditor, row: &Row, path: &UpdateJ, j_sim: Option<f64>) {
        let taken = row.beta != 0.0;
        if taken {
            a.step("guarantee-w");
        }
        let (from, to) = match j_sim {
            Some(to) => (path.j_t, to),
            None => (path.j_mid, path.j_next),
        };
        let comps: Vec<(f64, f64, f64)> = row
            .guaranteed_w
            .filter(|_| taken)
            .map(|g| (g, to - from, scale(&[to, from])))
            .into_iter()
            .collect();
        a.check(row.iteration, "guarantee-w", &comps);
    }

    /// `mi`, `lb-i` and `budget-exact` at iteration `t`: the points after the v-step and
    /// after the update against J(θᵗ), J(θ⁰) and J(θ⁰) − B⁰.
    fn floors(&self, a: &mut Auditor, has: &dyn Fn(&str) -> bool, t: u64, path: &UpdateJ, j0: f64) {
        let UpdateJ { j_t, j_mid, j_next } = *path;
        if has("mi") {
            let s = scale(&[j_t, j_mid, j_next]);
            a.check(t, "mi", &[(j_t, j_mid, s), (j_mid, j_next, s)]);
        }
        for (name, required) in [("lb-i", j0), ("budget-exact", j0 - self.budget0)] {
            if has(name) {
                let s = scale(&[j0, j_mid, j_next, self.budget0]);
                a.check(t, name, &[(required, j_mid, s), (required, j_next, s)]);
            }
        }
    }
}

/// Exact J along one update: at θᵗ, after the v-step θᵗ⁺½ and at θᵗ⁺¹.
#[derive(Debug, Clone, Copy)]
struct UpdateJ {
    j_t: f64,
    j_mid: f64,
    j_next: f64,
}

/// The exact J of `(v, w)` in `js`.
fn lookup(js: &HashMap<Vec<u64>, f64>, v: &[f64], w: &[f64]) -> Result<f64> {
    js.get(&key(v, w))
        .copied()
        .ok_or_else(|| Error::failed(format!("exact J at v = {v:?}, w = {w:?} missing")))
}
