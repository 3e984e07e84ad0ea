//! What a run promises about the exact performance J, and how firmly (docs/THEOREMS.md,
//! "Statements over a whole run").
//!
//! Every run records a [`Statement`] in its `summary.json`: the requirement it promises, the
//! kind of justification ([`StatementKind`]), its scope ([`Scope`]) and the confidence δ, and a
//! [`SelfCheck`] of its own certified bookkeeping. `sepg audit` judges the run against exact J
//! by exactly this statement.
use sepg_mdp::env::Environment;
use serde::{Deserialize, Serialize};

use crate::core::check::ConstantsCheck;
use crate::core::config::{Algorithm, CheckedConfig, GradientMode, Requirement};
use crate::core::options::{Accounting, Confidence, Schedule};

/// How firmly a run's statement is justified.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum StatementKind {
    /// Proven: every step is certified against a valid bound, every confidence width is
    /// valid at every batch size under the stated constants, every union bound is taken.
    Proven,
    /// The same accounting with confidence widths that hold only asymptotically (Student-t,
    /// docs/ERRATA.md §14): the stated probability is approximate.
    Approximate,
    /// No statement about exact J (point-estimate bookkeeping, ε = 0, SIM-ν, the comparison
    /// algorithms).
    None,
}

/// Over what a statement's probability is taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Scope {
    /// P(every requirement of every iteration holds) ≥ 1 − δ: one exact violation breaks the
    /// run's promise.
    Run,
    /// Each iteration meets its requirement with probability ≥ 1 − δ (the thesis's reading):
    /// failures are counted against δ per iteration.
    Iteration,
}

/// Which policies the statement covers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Covers {
    /// The exploratory policy only (MI, LB-I, LB-II; ZV, whose deterministic target has no
    /// curvature bound).
    Exploratory,
    /// The exploratory policy and the target (LV).
    ExploratoryAndTarget,
    /// Nothing.
    None,
}

/// The promise a run makes about exact J, recorded in `summary.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Statement {
    /// How firmly it is justified.
    pub kind: StatementKind,
    /// Whether δ bounds the probability of any failure in the whole run or per iteration.
    pub scope: Scope,
    /// The confidence δ ∈ (0, 1); `None` with exact gradients (a certainty) or kind `none`.
    pub delta: Option<f64>,
    /// Which policies are covered.
    pub covers: Covers,
    /// The requirement, in words (e.g. "J ≥ J(θ⁰) − B⁰ at every point of the run").
    pub requirement: String,
    /// Why the statement is not proven (empty when it is).
    pub reasons: Vec<String>,
}

impl Statement {
    /// This statement, unless `check` saw a value that contradicts the declared constants:
    /// then a statement of kind `none` whose reason names the first offending value (the
    /// bounds rest on constants the data refute; docs/RELIABILITY.md).
    ///
    /// # Examples
    /// ```
    /// use sepg_algo::core::check::ConstantsCheck;
    /// use sepg_algo::core::config::{Algorithm, Requirement, SepgConfig};
    /// use sepg_algo::core::statement::StatementKind;
    /// let cfg = SepgConfig::new(sepg_mdp::env::Preset::Lqg1d.build(), Algorithm::Sepg(Requirement::Zv));
    /// let s = cfg.check()?.statement();
    /// assert_eq!(s.clone().checked_against(&ConstantsCheck::default()), s);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn checked_against(self, check: &ConstantsCheck) -> Statement {
        match check.reason() {
            Some(reason) => Statement {
                kind: StatementKind::None,
                delta: None,
                covers: Covers::None,
                reasons: vec![reason],
                ..self
            },
            None => self,
        }
    }
}

/// The run's own certified bookkeeping: a certified surplus or budget below zero means the
/// run knows it broke its requirement (possible only with point-estimate bookkeeping, or
/// when a requirement could not be met).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct SelfCheck {
    /// Whether the run's own budget or surplus went below zero.
    pub broken: bool,
    /// The first iteration at which it did.
    pub first_iteration: Option<u64>,
    /// The budget or surplus there.
    pub value: Option<f64>,
}

impl SelfCheck {
    /// Records the bookkeeping `value` of `iteration`: the first negative value is kept.
    ///
    /// # Examples
    /// ```
    /// use sepg_algo::core::statement::SelfCheck;
    /// let mut s = SelfCheck::default();
    /// s.observe(3, 0.5);
    /// s.observe(4, -1e-6);
    /// s.observe(5, -2.0);
    /// assert!(s.broken);
    /// assert_eq!((s.first_iteration, s.value), (Some(4), Some(-1e-6)));
    /// ```
    pub fn observe(&mut self, iteration: u64, value: f64) {
        if value < 0.0 && !self.broken {
            self.broken = true;
            self.first_iteration = Some(iteration);
            self.value = Some(value);
        }
    }
}

/// The requirement of `req`, in words, with the initial budget `b0` (Table 4.1 as sepg
/// states it against exact J).
fn requirement_text(req: Requirement, b0: f64) -> String {
    match req {
        Requirement::Mi => "J never decreases: J(θᵗ⁺¹) ≥ J(θᵗ) at every half-step".into(),
        Requirement::LbI { .. } => "J(θᵗ) ≥ J(θ⁰) at every point of the run".into(),
        Requirement::LbII => {
            format!("J(θᵗ) ≥ J(θ⁰) − B⁰ (B⁰ = {b0}) at every point of the run")
        }
        Requirement::Zv => format!(
            "J(θᵗ) ≥ J(θ⁰) − B⁰ (B⁰ = {b0}) at every point of the run; nothing about the deterministic target"
        ),
        Requirement::Lv => format!(
            "J(θᵗ) ≥ J(θ⁰) − B⁰ and J(θ_Tᵗ) ≥ J(θ⁰) − B⁰ (B⁰ = {b0}) at every point of the run"
        ),
        Requirement::Sim { .. } => "none".into(),
    }
}

/// The statement of a checked configuration (see [`CheckedConfig::statement`]).
pub(crate) fn classify(checked: &CheckedConfig) -> Statement {
    let cfg = checked.config();
    let opts = &cfg.options;
    let req = match cfg.algorithm {
        Algorithm::Sepg(r) | Algorithm::SepgNaiveW(r) => r,
        _ => return none_statement("a comparison algorithm: no safety requirement"),
    };
    if matches!(req, Requirement::Sim { .. }) {
        return none_statement("SIM-ν moves v and w together from one batch: no joint bound");
    }
    if opts.accounting == Accounting::Estimated {
        let mut s = none_statement(
            "requirements built on estimated J (the thesis's bookkeeping, Sec 4.4.4)",
        );
        s.requirement = requirement_text(req, cfg.initial_budget);
        return s;
    }
    let mut reasons = Vec::new();
    let (delta, scope) = match cfg.gradient {
        GradientMode::Exact => (None, Scope::Run),
        GradientMode::Sampled { delta } => match sampled_level(checked, req, delta, &mut reasons) {
            Ok(level) => level,
            Err(statement) => return statement,
        },
    };
    if !checked.certified() {
        reasons.push("steps are not certified: rounding can break a bound".to_string());
    }
    reasons.extend(assumption_reasons(checked));
    Statement {
        kind: if reasons.is_empty() {
            StatementKind::Proven
        } else {
            StatementKind::Approximate
        },
        scope,
        delta,
        covers: match req {
            Requirement::Lv => Covers::ExploratoryAndTarget,
            _ => Covers::Exploratory,
        },
        requirement: requirement_text(req, cfg.initial_budget),
        reasons,
    }
}

/// The statement `none`, for `reason`.
fn none_statement(reason: &str) -> Statement {
    Statement {
        kind: StatementKind::None,
        scope: Scope::Iteration,
        delta: None,
        covers: Covers::None,
        requirement: "none".into(),
        reasons: vec![reason.into()],
    }
}

/// The level and scope of a sampled run's statement, with the reasons that make it
/// approximate pushed to `reasons`; `Err` with the statement `none` when its widths bound
/// nothing.
fn sampled_level(
    checked: &CheckedConfig,
    req: Requirement,
    delta: f64,
    reasons: &mut Vec<String>,
) -> Result<(Option<f64>, Scope), Statement> {
    let cfg = checked.config();
    let opts = &cfg.options;
    match opts.confidence {
        Confidence::None => {
            return Err(none_statement(
                "confidence none: estimates are used as if exact",
            ));
        }
        Confidence::StudentT { .. } => reasons
            .push("Student-t widths cover only asymptotically (docs/ERRATA.md §14)".to_string()),
        Confidence::SubGaussian => {
            if opts.w_step == crate::core::options::WStep::Theorem49
                && matches!(cfg.algorithm, Algorithm::Sepg(_))
            {
                reasons.push("Theorem 4.9's step reads the Student-t width of ∇̂_w L".to_string());
            }
        }
    }
    match opts.schedule {
        Schedule::Run => Ok((Some(delta), Scope::Run)),
        // Per-iteration widths bound MI's per-step requirement at K·δ per iteration
        // (union over its K statements); the cumulative requirements get nothing.
        Schedule::Iteration if req == Requirement::Mi => {
            let k = crate::solver::statements_per_iteration(
                cfg.algorithm,
                opts,
                (cfg.v0.len(), cfg.sigma0.len()),
            );
            Ok((Some((k as f64 * delta).min(1.0)), Scope::Iteration))
        }
        Schedule::Iteration => {
            let mut s = none_statement(
                "widths at level δ each (schedule iteration) do not bound a cumulative \
                 requirement",
            );
            s.requirement = requirement_text(req, cfg.initial_budget);
            Err(s)
        }
    }
}

/// Why the assumptions of the statement may fail for `checked`: constants overridden below
/// the environment's, scores at the clipped action, rewards the environment does not bound.
fn assumption_reasons(checked: &CheckedConfig) -> Vec<String> {
    let cfg = checked.config();
    let env = cfg.env.constants();
    let o = cfg.options.overrides;
    let mut reasons = Vec::new();
    let below = |over: Option<f64>, own: f64| over.is_some_and(|x| x < own);
    if below(o.r_max, env.r_max)
        || below(o.m_phi, env.m_phi)
        || below(o.action_volume, env.action_volume)
        || o.psi.is_some_and(|p| p < sepg_bounds::constants::psi())
    {
        reasons.push(
            "constants overridden below the environment's: the bounds hold only if they are \
             true bounds"
                .to_string(),
        );
    }
    if matches!(cfg.gradient, GradientMode::Sampled { .. })
        && cfg.score_action == sepg_mdp::rollout::ScoreAction::Clipped
    {
        reasons.push("scores at the clipped action: the estimators are biased".to_string());
    }
    if matches!(
        cfg.options.v_direction,
        crate::core::options::VDirection::Adam { .. }
    ) && checked.constants().family() == sepg_bounds::Family::Thesis
    {
        reasons.push(
            "the Adam v-direction with the thesis's constants: their c is proven for the \
             greedy coordinate only (Theorem T proves the tight c for every direction)"
                .to_string(),
        );
    }
    if matches!(cfg.env, sepg_mdp::env::AnyEnv::MountainCar(_)) {
        reasons.push(
            "Mountain Car's reward −0.1a² with the raw action is not bounded by R \
             (docs/ERRATA.md §19)"
                .to_string(),
        );
    }
    reasons
}
