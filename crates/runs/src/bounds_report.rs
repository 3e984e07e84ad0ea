//! The report of `sepg bounds` and of `sepg.bounds.bounds_report`: every closed-form quantity
//! that task constants, σ and gradients determine (Theorems 3.11, 3.13, 3.14, 4.2, 4.3, 4.5,
//! Lemma A.1, Corollary 4.4), and optionally the outward-rounded enclosures and certified
//! steps of docs/THEOREMS.md ("Certified steps").
//!
//! [`report`] builds a [`BoundsReport`] from a [`BoundsQuery`]; [`BoundsReport::rows`] lists
//! its scalar quantities in table order, each with its citation, for a face to format. The
//! report serialises to the JSON object of `sepg bounds --json`. Nothing here prints.

use std::collections::BTreeMap;

#[cfg(feature = "clap")]
use clap::Args;
use sepg_bounds::constants::{self, TaskConstants};
use sepg_bounds::outcome::StepOutcome;
use sepg_bounds::penalties::{Family, Horizon, Rewards, Tight};
use sepg_bounds::{BoundsError, batch_size, papini, pirotta, surrogate, v_update, w_update};
use sepg_certified::{self as certified, Certified, Interval, Quadratic};
use serde::Serialize;

use crate::error::{Error, Result};
use crate::spec::{ConstantsName, MAX_HORIZON, RewardsName};

/// The inputs of a bounds report: the task constants (γ, R, M_φ, |A|), σ, the optional
/// gradients and the options of the requirement, the batch sizes and the family of the
/// constants. Each field is the command-line flag of the same name.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "clap", derive(Args))]
pub struct BoundsQuery {
    /// Discount factor γ ∈ [0, 1).
    #[cfg_attr(feature = "clap", arg(long, allow_hyphen_values = true))]
    pub gamma: f64,
    /// Maximum absolute reward R (> 0).
    #[cfg_attr(feature = "clap", arg(long = "r-max", allow_hyphen_values = true))]
    pub r_max: f64,
    /// Bound M_φ on every feature's absolute value (> 0).
    #[cfg_attr(feature = "clap", arg(long = "m-phi", allow_hyphen_values = true))]
    pub m_phi: f64,
    /// Volume |A| of the action space (> 0).
    #[cfg_attr(
        feature = "clap",
        arg(long = "action-volume", allow_hyphen_values = true)
    )]
    pub action_volume: f64,
    /// Policy standard deviation σ = e^w (> 0).
    #[cfg_attr(feature = "clap", arg(long, allow_hyphen_values = true))]
    pub sigma: f64,
    /// Number m of mean parameters (for the surrogate L = ‖∇_v J‖²/(4mc)); defaults to the
    /// length of --grad-v.
    #[cfg_attr(feature = "clap", arg(long = "dim-v"))]
    pub dim_v: Option<usize>,
    /// Gradient ∇_v J, comma-separated (one value per mean parameter).
    #[cfg_attr(
        feature = "clap",
        arg(long = "grad-v", value_delimiter = ',', allow_hyphen_values = true)
    )]
    pub grad_v: Option<Vec<f64>>,
    /// Gradient ∇_w J (scalar).
    #[cfg_attr(feature = "clap", arg(long = "grad-w", allow_hyphen_values = true))]
    pub grad_w: Option<f64>,
    /// Gradient ∇_w L of the surrogate (scalar); needs --grad-w.
    #[cfg_attr(feature = "clap", arg(long = "grad-w-l", allow_hyphen_values = true))]
    pub grad_w_l: Option<f64>,
    /// Improvement C each update must guarantee (negative: a bounded worsening). Default 0.
    #[cfg_attr(
        feature = "clap",
        arg(long, allow_hyphen_values = true, default_value_t = 0.0)
    )]
    pub required: f64,
    /// Split C between the updates as in (4.13)–(4.14): (1 − ν)C for v, νC for w.
    /// Without it, each update must guarantee C.
    #[cfg_attr(feature = "clap", arg(long, allow_hyphen_values = true))]
    pub nu: Option<f64>,
    /// Confidence δ ∈ (0, 1) for the Chebyshev batch sizes (with --eps and --horizon).
    #[cfg_attr(feature = "clap", arg(long, allow_hyphen_values = true))]
    pub delta: Option<f64>,
    /// Gradient accuracy ε > 0 for the Chebyshev batch sizes.
    #[cfg_attr(feature = "clap", arg(long, allow_hyphen_values = true))]
    pub eps: Option<f64>,
    /// Horizon H ≥ 1 (or `inf`): of the tight constants, and of the Chebyshev batch sizes
    /// (finite there).
    #[cfg_attr(
        feature = "clap",
        arg(long, value_parser = parse_horizon, allow_hyphen_values = true)
    )]
    pub horizon: Option<Horizon>,
    /// Family of the constants c and d: the thesis's (Theorems 3.14, 4.2, 4.3) or the tight
    /// constants c = ρRM_φ²S_H/σ², d = 2ρRS_H (docs/THEOREMS.md, "Tight constants"), which
    /// need --horizon.
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "thesis"))]
    pub constants: ConstantsName,
    /// Sign of the rewards for the tight constants: two-sided (ρ = 1, always sound) or
    /// non-positive (every reward in [−R, 0], ρ = 1/2) [default: two-sided].
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    pub rewards: Option<RewardsName>,
}

impl BoundsQuery {
    /// The query of the task constants (γ, R, M_φ, |A|) at σ, without gradients: required
    /// improvement 0, the thesis's constants, no batch sizes.
    pub fn new(gamma: f64, r_max: f64, m_phi: f64, action_volume: f64, sigma: f64) -> Self {
        BoundsQuery {
            gamma,
            r_max,
            m_phi,
            action_volume,
            sigma,
            dim_v: None,
            grad_v: None,
            grad_w: None,
            grad_w_l: None,
            required: 0.0,
            nu: None,
            delta: None,
            eps: None,
            horizon: None,
            constants: ConstantsName::Thesis,
            rewards: None,
        }
    }
}

/// Parses a horizon: a positive integer, or `inf` (or `infinite`) for H = ∞.
///
/// # Errors
/// A message naming the text when it is neither.
pub fn parse_horizon(s: &str) -> std::result::Result<Horizon, String> {
    match s.trim() {
        "inf" | "infinite" => Ok(Horizon::Infinite),
        t => match t.parse::<u64>() {
            Ok(h) if h >= 1 => Ok(Horizon::Finite(h)),
            _ => Err(format!(
                "the horizon is a positive integer or inf, got {s:?}"
            )),
        },
    }
}

/// The outcome of a certified largest step (docs/THEOREMS.md, Certified steps), as the
/// report names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum StepVerdict {
    /// The bound at the step, evaluated in interval arithmetic, is at least C.
    Certified,
    /// C ≤ C_max as computed, but no float step has an enclosure at least C (the vertex).
    Uncertifiable,
    /// C > C_max: no step guarantees C (the vertex).
    Infeasible,
    /// No update: the direction is zero or within its confidence width.
    NoStep,
}

impl StepVerdict {
    /// The verdict of a certified step computation.
    pub fn of(c: &Certified) -> Self {
        match c {
            Certified::Step(_) => StepVerdict::Certified,
            Certified::Uncertifiable { .. } => StepVerdict::Uncertifiable,
            Certified::Infeasible { .. } => StepVerdict::Infeasible,
            _ => StepVerdict::NoStep,
        }
    }

    /// The verdict's name: `certified`, `uncertifiable`, `infeasible` or `no-step`.
    pub fn label(self) -> &'static str {
        match self {
            StepVerdict::Certified => "certified",
            StepVerdict::Uncertifiable => "uncertifiable",
            StepVerdict::Infeasible => "infeasible",
            StepVerdict::NoStep => "no-step",
        }
    }
}

/// One certified largest step: its verdict, the step taken (units of the parameter) and the
/// enclosure [lo, hi] of its guaranteed improvement (units of J).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CertifiedStepReport {
    /// The verdict.
    pub outcome: StepVerdict,
    /// The step to take, absent when there is none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub step: Option<f64>,
    /// The enclosure of the bound at the step, absent without a step.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bound: Option<[f64; 2]>,
}

/// The enclosures and certified steps of a report asked with `certified`.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct CertifiedReport {
    /// Name → [lo, hi] enclosing the exact real value (ψ, c, d, C_max, λ, end points).
    pub enclosures: BTreeMap<&'static str, [f64; 2]>,
    /// Name of the largest step (`alpha_bar`, `beta_bar_j`, `beta_bar`) → its certificate.
    pub steps: BTreeMap<&'static str, CertifiedStepReport>,
}

/// Everything a bounds report holds. Optional fields are absent when the inputs do not
/// determine them; steps are in units of the parameters, improvements in units of J.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct BoundsReport {
    /// The family of the constants: `thesis` or `tight`.
    pub constants: &'static str,
    /// The horizon of the tight constants (an integer or `inf`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub horizon: Option<String>,
    /// The reward sign of the tight constants: `two-sided` or `non-positive`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rewards: Option<&'static str>,
    /// S_H = Σ_{t<H} (t+1)γᵗ of the tight constants.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub s_h: Option<f64>,
    /// ρ of the tight constants: 1 two-sided, 1/2 non-positive.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rho: Option<f64>,
    /// ψ of Lemma A.1.
    pub psi: f64,
    /// c(σ) (Theorem 4.2, or the tight c).
    pub c: f64,
    /// d(σ) (Theorem 4.3, or the tight d).
    pub d: f64,
    /// ∂c/∂σ (Appendix B).
    pub dc_dsigma: f64,
    /// α* = 1/(2c) (Theorem 4.2).
    pub alpha_star: f64,
    /// β* = 1/(2d) (Theorem 4.3).
    pub beta_star: f64,
    /// 1/(4mc) of Corollary 4.4.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub surrogate_coefficient: Option<f64>,
    /// C_v of (4.13).
    pub required_v: f64,
    /// C_w of (4.14).
    pub required_w: f64,
    /// C_max of the v-update (4.9).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub c_max_v: Option<f64>,
    /// Whether C_v can be guaranteed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub feasible_v: Option<bool>,
    /// λ_v of (4.10).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lambda_v: Option<f64>,
    /// The safe v-steps [lo, hi].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alpha_interval: Option<[f64; 2]>,
    /// The largest safe v-step (4.20), or the vertex when infeasible.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alpha_bar: Option<f64>,
    /// The coordinate the greedy step updates (Theorem 3.14).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub greedy_index: Option<usize>,
    /// The surrogate L of Corollary 4.4.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub surrogate: Option<f64>,
    /// The adaptive step of Corollary 3.11.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pirotta_alpha: Option<f64>,
    /// The improvement it guarantees.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pirotta_guarantee: Option<f64>,
    /// C_max of the w-update along ∇_w J (4.16).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub c_max_w: Option<f64>,
    /// Whether C_w can be guaranteed along ∇_w J.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub feasible_w: Option<bool>,
    /// λ_w of (4.17).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lambda_w: Option<f64>,
    /// The safe w-steps along ∇_w J [lo, hi].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub beta_interval_j: Option<[f64; 2]>,
    /// The largest safe w-step along ∇_w J (4.17), or the vertex when infeasible.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub beta_bar_j: Option<f64>,
    /// β̃ of Theorem 4.5.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub beta_tilde: Option<f64>,
    /// The safe w-steps along ∇_w L [lo, hi].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub beta_interval: Option<[f64; 2]>,
    /// The largest safe w-step along ∇_w L (4.20).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub beta_bar: Option<f64>,
    /// The REINFORCE batch size of Corollary 3.13.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub batch_reinforce: Option<u64>,
    /// The G(PO)MDP batch size of Corollary 3.13.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub batch_gpomdp: Option<u64>,
    /// The enclosures and certified steps, when asked for.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub certified: Option<CertifiedReport>,
}

/// The value of a row of [`BoundsReport::rows`], by how it is meant to be written.
#[derive(Debug, Clone, PartialEq)]
pub enum RowValue {
    /// A real quantity, written in scientific notation.
    Real(f64),
    /// ψ, a constant written with ten decimals.
    Constant(f64),
    /// An exact short value (ρ), written as is.
    Exact(f64),
    /// A count or an index.
    Count(u64),
    /// A yes/no answer.
    Flag(bool),
    /// A name.
    Name(String),
}

/// One row of the table of a report: the quantity's name, its value and where it is defined.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// The quantity's name (its JSON key).
    pub name: &'static str,
    /// Its value.
    pub value: RowValue,
    /// The theorem or equation that defines it.
    pub cite: &'static str,
}

fn row(name: &'static str, value: RowValue, cite: &'static str) -> Row {
    Row { name, value, cite }
}

impl BoundsReport {
    /// The scalar quantities of the report in table order, with their citations: the family
    /// of the constants, the quantities of σ, then those the gradients and options determine.
    /// The certified part is [`BoundsReport::certified`].
    pub fn rows(&self) -> Vec<Row> {
        let tight = self.s_h.is_some();
        let (family_cite, c_cite, d_cite) = if tight {
            (
                "docs/THEOREMS.md, Tight constants",
                "Thm T: rho R M^2 S_H / sigma^2",
                "Thm T: 2 rho R S_H",
            )
        } else {
            (
                "the thesis's c and d",
                "Thm 4.2 (Papini et al. Thm 3.14)",
                "Thm 4.3",
            )
        };
        let mut rows = vec![row(
            "constants",
            RowValue::Name(self.constants.to_owned()),
            family_cite,
        )];
        if let (Some(h), Some(sign), Some(s_h), Some(rho)) =
            (&self.horizon, self.rewards, self.s_h, self.rho)
        {
            rows.extend([
                row("horizon", RowValue::Name(h.clone()), "H"),
                row("rewards", RowValue::Name(sign.to_owned()), "reward sign"),
                row("s_h", RowValue::Real(s_h), "sum_{t<H} (t+1) gamma^t"),
                row("rho", RowValue::Exact(rho), "1 two-sided, 1/2 non-positive"),
            ]);
        }
        rows.extend([
            row("psi", RowValue::Constant(self.psi), "Lemma A.1"),
            row("c", RowValue::Real(self.c), c_cite),
            row("d", RowValue::Real(self.d), d_cite),
            row("dc_dsigma", RowValue::Real(self.dc_dsigma), "Appendix B"),
            row(
                "alpha_star",
                RowValue::Real(self.alpha_star),
                "Thm 4.2: 1/(2c)",
            ),
            row(
                "beta_star",
                RowValue::Real(self.beta_star),
                "Thm 4.3: 1/(2d)",
            ),
            row("required_v", RowValue::Real(self.required_v), "(4.13)"),
            row("required_w", RowValue::Real(self.required_w), "(4.14)"),
        ]);
        self.push_optional_rows(&mut rows);
        rows
    }

    /// The rows of the quantities that the inputs determine, in table order.
    fn push_optional_rows(&self, rows: &mut Vec<Row>) {
        let reals: [(&'static str, Option<f64>, &'static str); 13] = [
            (
                "surrogate_coefficient",
                self.surrogate_coefficient,
                "Cor 4.4: 1/(4mc)",
            ),
            ("c_max_v", self.c_max_v, "(4.9)"),
            ("lambda_v", self.lambda_v, "(4.10)"),
            (
                "alpha_bar",
                self.alpha_bar,
                "(4.20): (1+lambda_v) alpha_star",
            ),
            ("surrogate", self.surrogate, "Cor 4.4: L"),
            ("pirotta_alpha", self.pirotta_alpha, "Cor 3.11"),
            ("pirotta_guarantee", self.pirotta_guarantee, "Cor 3.11"),
            ("c_max_w", self.c_max_w, "(4.16)"),
            ("lambda_w", self.lambda_w, "(4.17)"),
            (
                "beta_bar_j",
                self.beta_bar_j,
                "(4.17): largest step along grad_w J",
            ),
            ("beta_tilde", self.beta_tilde, "Thm 4.5"),
            (
                "beta_bar",
                self.beta_bar,
                "(4.20): beta_tilde + lambda_w |beta_tilde|",
            ),
            (
                "batch_gpomdp",
                self.batch_gpomdp.map(|n| n as f64),
                "Cor 3.13 (G(PO)MDP)",
            ),
        ];
        for (name, value, cite) in reals {
            if let Some(v) = value {
                rows.push(row(name, RowValue::Real(v), cite));
            }
        }
        if let Some(n) = self.batch_reinforce {
            let cite = "Cor 3.13 (REINFORCE, corrected)";
            rows.push(row("batch_reinforce", RowValue::Count(n), cite));
        }
        if let Some(i) = self.greedy_index {
            let cite = "Thm 3.14: coordinate updated";
            rows.push(row("greedy_index", RowValue::Count(i as u64), cite));
        }
        for (name, feasible) in [
            ("feasible_v", self.feasible_v),
            ("feasible_w", self.feasible_w),
        ] {
            if let Some(f) = feasible {
                rows.push(row(name, RowValue::Flag(f), "C <= C_max"));
            }
        }
    }
}

fn bad(e: BoundsError) -> Error {
    Error::invalid(e.to_string())
}

/// The report of `query`, with the enclosures and certified steps when `certified`.
///
/// # Errors
/// [`Error::Invalid`] for constants, σ, gradients or options out of their domains (the
/// message of the formula that rejects them), for options that need others (--grad-w-l
/// without --grad-w, part of --delta/--eps/--horizon, the tight constants without a horizon)
/// and for --rewards with the thesis's constants.
pub fn report(query: &BoundsQuery, certified: bool) -> Result<BoundsReport> {
    let (k, family) = task_constants(query)?;
    let sigma = query.sigma;
    let (required_v, required_w) = requirements(query)?;
    let c = constants::c(&k, sigma).map_err(bad)?;
    let mut r = BoundsReport {
        psi: constants::psi(),
        c,
        d: constants::d(&k, sigma).map_err(bad)?,
        dc_dsigma: constants::dc_dsigma(&k, sigma).map_err(bad)?,
        alpha_star: v_update::alpha_star(&k, sigma).map_err(bad)?,
        beta_star: w_update::beta_star(&k, sigma).map_err(bad)?,
        required_v,
        required_w,
        ..family
    };
    if let Some(m) = dim_v(query)? {
        r.surrogate_coefficient = Some(1.0 / (4.0 * m as f64 * c));
    }
    if let Some(g) = &query.grad_v {
        fill_v(&mut r, &k, sigma, g, required_v)?;
    }
    fill_w(&mut r, query, &k, required_w)?;
    fill_batch(&mut r, query, &k)?;
    if certified {
        r.certified = Some(certified_report(query, &k, (required_v, required_w))?);
    }
    Ok(r)
}

fn ends(i: Interval) -> [f64; 2] {
    [i.lo(), i.hi()]
}

fn step_report(c: &Certified) -> CertifiedStepReport {
    CertifiedStepReport {
        outcome: StepVerdict::of(c),
        step: c.chosen_step(),
        bound: c.bound().map(ends),
    }
}

/// Enclosures of a quadratic bound's C_max, λ and end points for the requirement C.
fn quadratic_enclosures(
    out: &mut BTreeMap<&'static str, [f64; 2]>,
    q: &Quadratic,
    required: f64,
    names: [&'static str; 4],
) {
    let [c_max, lambda, lo, hi] = names;
    out.insert(c_max, ends(q.c_max()));
    if let Some((l, h)) = q.end_points(required) {
        out.insert(lambda, ends(q.lambda(required)));
        out.insert(lo, ends(l));
        out.insert(hi, ends(h));
    }
}

fn certified_report(
    a: &BoundsQuery,
    k: &TaskConstants,
    (required_v, required_w): (f64, f64),
) -> Result<CertifiedReport> {
    let sigma = a.sigma;
    let mut r = CertifiedReport::default();
    r.enclosures.insert("psi", ends(certified::psi()));
    r.enclosures
        .insert("c", ends(certified::c(k, sigma).map_err(bad)?));
    r.enclosures
        .insert("d", ends(certified::d(k, sigma).map_err(bad)?));
    if let Some(g) = &a.grad_v {
        let q = Quadratic::v_update(k, sigma, g).map_err(bad)?;
        let names = ["c_max_v", "lambda_v", "alpha_lo", "alpha_hi"];
        quadratic_enclosures(&mut r.enclosures, &q, required_v, names);
        let o = certified::v_safe_step(k, sigma, g, required_v).map_err(bad)?;
        r.steps.insert("alpha_bar", step_report(&o));
    }
    if let Some(gj) = a.grad_w {
        let q = Quadratic::w_along_j(k, sigma, gj).map_err(bad)?;
        let names = ["c_max_w", "lambda_w", "beta_lo_j", "beta_hi_j"];
        quadratic_enclosures(&mut r.enclosures, &q, required_w, names);
        let o = certified::w_safe_step_along_j(k, sigma, gj, required_w).map_err(bad)?;
        r.steps.insert("beta_bar_j", step_report(&o));
        if let Some(gl) = a.grad_w_l {
            let q = Quadratic::w_along_l(k, sigma, gj, gl).map_err(bad)?;
            let names = ["c_max_w_l", "lambda_w_l", "beta_lo", "beta_hi"];
            quadratic_enclosures(&mut r.enclosures, &q, required_w, names);
            let o = certified::w_safe_step_along_l(k, sigma, gj, gl, required_w).map_err(bad)?;
            r.steps.insert("beta_bar", step_report(&o));
        }
    }
    Ok(r)
}

/// Fields describing a safe-step outcome: (feasible, λ, interval, chosen step).
type OutcomeFields = (Option<bool>, Option<f64>, Option<[f64; 2]>, Option<f64>);

fn outcome_fields(o: &StepOutcome) -> OutcomeFields {
    match o {
        StepOutcome::Feasible(s) => (Some(true), s.lambda, Some([s.lo, s.hi]), Some(s.hi)),
        StepOutcome::Infeasible { vertex, .. } => (Some(false), None, None, Some(*vertex)),
        StepOutcome::ZeroGradient { requirement_met } => (Some(*requirement_met), None, None, None),
        StepOutcome::BelowNoise => (Some(false), None, None, None),
    }
}

/// The required improvements (C_v, C_w): C for both, or split by ν (eqs. 4.13–4.14).
fn requirements(a: &BoundsQuery) -> Result<(f64, f64)> {
    match a.nu {
        Some(nu) => sepg_bounds::budget::split_requirement(a.required, nu).map_err(bad),
        None if !a.required.is_finite() => Err(Error::invalid(format!(
            "required must be finite, got {}",
            a.required
        ))),
        None => Ok((a.required, a.required)),
    }
}

/// The number m of mean parameters: --dim-v, checked against --grad-v, or the length of
/// --grad-v.
fn dim_v(a: &BoundsQuery) -> Result<Option<usize>> {
    let m = match (&a.grad_v, a.dim_v) {
        (Some(g), Some(m)) if g.len() != m => {
            return Err(Error::invalid(format!(
                "--dim-v {m} does not match the {} components of --grad-v",
                g.len()
            )));
        }
        (Some(g), _) => Some(g.len()),
        (None, m) => m,
    };
    if m == Some(0) {
        return Err(Error::invalid("--dim-v must be at least 1"));
    }
    Ok(m)
}

/// The quantities of ∇_v J: C_max, the safe v-steps, the greedy coordinate, the surrogate
/// and the adaptive step of Corollary 3.11.
fn fill_v(
    r: &mut BoundsReport,
    k: &TaskConstants,
    sigma: f64,
    g: &[f64],
    required_v: f64,
) -> Result<()> {
    r.c_max_v = Some(v_update::c_max(k, sigma, g).map_err(bad)?);
    let o = v_update::safe_step(k, sigma, g, required_v).map_err(bad)?;
    (r.feasible_v, r.lambda_v, r.alpha_interval, r.alpha_bar) = outcome_fields(&o);
    r.greedy_index = Some(papini::greedy_step(k, sigma, g).map_err(bad)?.index);
    r.surrogate = Some(surrogate::surrogate(k, sigma, g).map_err(bad)?);
    if let pirotta::AdaptiveStep::Step { alpha, guarantee } =
        pirotta::optimal_step(k, sigma, g).map_err(bad)?
    {
        r.pirotta_alpha = Some(alpha);
        r.pirotta_guarantee = Some(guarantee);
    }
    Ok(())
}

/// The quantities of ∇_w J (and ∇_w L): C_max and the safe w-steps along each.
fn fill_w(r: &mut BoundsReport, a: &BoundsQuery, k: &TaskConstants, required_w: f64) -> Result<()> {
    let sigma = a.sigma;
    match (a.grad_w, a.grad_w_l) {
        (None, Some(_)) => return Err(Error::invalid("--grad-w-l needs --grad-w")),
        (Some(gj), gl) => {
            r.c_max_w = Some(w_update::c_max(k, sigma, gj).map_err(bad)?);
            let oj = w_update::safe_step_along_j(k, sigma, gj, required_w).map_err(bad)?;
            (r.feasible_w, r.lambda_w, r.beta_interval_j, r.beta_bar_j) = outcome_fields(&oj);
            if let Some(gl) = gl {
                r.beta_tilde = Some(w_update::beta_tilde(k, sigma, gj, gl).map_err(bad)?);
                let ol = w_update::safe_step_along_l(k, sigma, gj, gl, required_w).map_err(bad)?;
                let (_, _, interval, bar) = outcome_fields(&ol);
                (r.beta_interval, r.beta_bar) = (interval, bar);
            }
        }
        (None, None) => {}
    }
    Ok(())
}

/// The batch sizes of Corollary 3.13, when --delta, --eps and --horizon are all given.
fn fill_batch(r: &mut BoundsReport, a: &BoundsQuery, k: &TaskConstants) -> Result<()> {
    let tight = a.constants == ConstantsName::Tight;
    match (a.delta, a.eps, a.horizon) {
        (Some(delta), Some(eps), Some(horizon)) => {
            let h = match horizon {
                // The batch sizes sum H terms: the limit keeps them under a second.
                Horizon::Finite(h) if h <= MAX_HORIZON as u64 => h as u32,
                Horizon::Finite(_) => {
                    return Err(Error::invalid(format!(
                        "batch sizes need --horizon at most {MAX_HORIZON}"
                    )));
                }
                Horizon::Infinite => {
                    return Err(Error::invalid("batch sizes need a finite --horizon"));
                }
            };
            r.batch_reinforce =
                Some(batch_size::reinforce(k, a.sigma, delta, eps, h).map_err(bad)?);
            r.batch_gpomdp = Some(batch_size::gpomdp(k, a.sigma, delta, eps, h).map_err(bad)?);
            Ok(())
        }
        (None, None, None) => Ok(()),
        (None, None, Some(_)) if tight => Ok(()),
        _ => Err(Error::invalid(
            "batch sizes need all of --delta, --eps and --horizon",
        )),
    }
}

/// The task constants of the query, with the family of `constants` (the tight family for
/// `horizon` and `rewards`), and the report's fields naming the family: its name, horizon,
/// reward sign, S_H and ρ.
fn task_constants(a: &BoundsQuery) -> Result<(TaskConstants, BoundsReport)> {
    let k = TaskConstants::new(a.gamma, a.r_max, a.m_phi, a.action_volume).map_err(bad)?;
    match a.constants {
        ConstantsName::Thesis => {
            if a.rewards.is_some() {
                return Err(Error::invalid(
                    "--rewards applies to --constants tight only",
                ));
            }
            let r = BoundsReport {
                constants: "thesis",
                ..BoundsReport::default()
            };
            Ok((k, r))
        }
        ConstantsName::Tight => {
            let horizon = a.horizon.ok_or_else(|| {
                Error::invalid("--constants tight needs --horizon (a positive integer or inf)")
            })?;
            let (rewards, name, rho) = match a.rewards.unwrap_or(RewardsName::TwoSided) {
                RewardsName::TwoSided => (Rewards::TwoSided, "two-sided", 1.0),
                RewardsName::NonPositive => (Rewards::NonPositive, "non-positive", 0.5),
            };
            let k = k
                .with_family(Family::Tight(Tight::new(horizon, rewards)))
                .map_err(bad)?;
            let r = BoundsReport {
                constants: "tight",
                horizon: Some(match horizon {
                    Horizon::Finite(h) => h.to_string(),
                    Horizon::Infinite => "inf".to_owned(),
                }),
                rewards: Some(name),
                s_h: Some(k.horizon_weight()),
                rho: Some(rho),
                ..BoundsReport::default()
            };
            Ok((k, r))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn query() -> BoundsQuery {
        BoundsQuery::new(0.9, 2.0, 1.5, 3.0, 0.7)
    }

    #[test]
    fn the_quantities_of_sigma_follow_their_closed_forms() {
        // Theorem 4.2 at γ = 1/2, R = M_φ = |A| = σ = 1: R M²/((1−γ)²σ²) = 4 times the
        // bracket |A|/(σ√(2π)) + γ/(2(1−γ)) = 1/√(2π) + 1/2.
        let q = BoundsQuery {
            dim_v: Some(3),
            ..BoundsQuery::new(0.5, 1.0, 1.0, 1.0, 1.0)
        };
        let r = report(&q, false).unwrap();
        let c = 4.0 * (1.0 / (2.0 * std::f64::consts::PI).sqrt() + 0.5);
        assert!((r.c - c).abs() < 1e-14 * c);
        assert!((2.0 * r.c * r.alpha_star - 1.0).abs() < 1e-15);
        assert!((2.0 * r.d * r.beta_star - 1.0).abs() < 1e-15);
        let coefficient = r.surrogate_coefficient.unwrap();
        assert!((coefficient * 12.0 * r.c - 1.0).abs() < 1e-15);
        assert_eq!((r.constants, r.certified), ("thesis", None));
    }

    #[test]
    fn nu_splits_the_requirement_as_in_4_13_and_4_14() {
        let q = BoundsQuery {
            required: 0.01,
            nu: Some(0.25),
            ..query()
        };
        let r = report(&q, false).unwrap();
        assert!((r.required_v - 0.0075).abs() < 1e-17);
        assert!((r.required_w - 0.0025).abs() < 1e-17);
    }

    #[test]
    fn the_tight_family_reports_its_horizon_weight_and_rho() {
        let q = BoundsQuery {
            constants: ConstantsName::Tight,
            horizon: Some(Horizon::Finite(20)),
            rewards: Some(RewardsName::NonPositive),
            ..query()
        };
        let r = report(&q, false).unwrap();
        let s_h: f64 = (0..20).map(|t| (t + 1) as f64 * 0.9f64.powi(t)).sum();
        assert!((r.s_h.unwrap() - s_h).abs() < 1e-12 * s_h);
        assert_eq!(
            (r.rho, r.rewards, r.horizon.as_deref()),
            (Some(0.5), Some("non-positive"), Some("20"))
        );
        // d = 2ρRS_H (docs/THEOREMS.md, Tight constants)
        assert!((r.d - 2.0 * 0.5 * 2.0 * s_h).abs() < 1e-12 * r.d);
    }

    #[test]
    fn a_certified_step_is_labelled_certified_and_its_bound_meets_the_requirement() {
        let q = BoundsQuery {
            grad_v: Some(vec![0.3, -0.8]),
            grad_w: Some(0.4),
            grad_w_l: Some(-1.2),
            required: -0.01,
            ..query()
        };
        let r = report(&q, true).unwrap();
        let cert = r.certified.as_ref().unwrap();
        for (name, float_step) in [
            ("alpha_bar", r.alpha_bar),
            ("beta_bar_j", r.beta_bar_j),
            ("beta_bar", r.beta_bar),
        ] {
            let s = &cert.steps[name];
            assert_eq!(s.outcome, StepVerdict::Certified, "{name}");
            assert!(s.bound.unwrap()[0] >= -0.01, "{name}");
            // the certified step is the float largest step, or moved from it toward the vertex
            assert!(s.step.unwrap().abs() <= float_step.unwrap().abs(), "{name}");
        }
        let json = serde_json::to_value(&r).unwrap();
        assert_eq!(
            json["certified"]["steps"]["alpha_bar"]["outcome"],
            "certified"
        );
        assert_eq!(StepVerdict::Certified.label(), "certified");
    }

    #[test]
    fn an_infeasible_requirement_is_reported_as_such_on_both_layers() {
        let q = BoundsQuery {
            grad_v: Some(vec![0.3, -0.8]),
            required: 5.0,
            ..query()
        };
        let r = report(&q, true).unwrap();
        assert_eq!(r.feasible_v, Some(false));
        let s = &r.certified.unwrap().steps["alpha_bar"];
        assert_eq!(
            (s.outcome, s.outcome.label()),
            (StepVerdict::Infeasible, "infeasible")
        );
    }

    #[test]
    fn every_row_is_the_json_value_of_its_name() {
        let q = BoundsQuery {
            grad_v: Some(vec![0.3, -0.8]),
            grad_w: Some(0.4),
            grad_w_l: Some(-1.2),
            delta: Some(0.2),
            eps: Some(0.1),
            horizon: Some(Horizon::Finite(20)),
            ..query()
        };
        let tight = BoundsQuery {
            constants: ConstantsName::Tight,
            rewards: Some(RewardsName::NonPositive),
            ..q.clone()
        };
        // 9 rows of σ, 13 of the gradients and batch sizes, 4 of counts and answers; the
        // tight family adds its horizon, reward sign, S_H and ρ
        for (q, count) in [(q, 26), (tight, 30)] {
            let r = report(&q, false).unwrap();
            let json = serde_json::to_value(&r).unwrap();
            let rows = r.rows();
            assert_eq!(rows.len(), count);
            for row in rows {
                let (value, name) = (&json[row.name], row.name);
                match row.value {
                    RowValue::Real(x) | RowValue::Constant(x) | RowValue::Exact(x) => {
                        assert_eq!(value.as_f64(), Some(x), "{name}")
                    }
                    RowValue::Count(n) => assert_eq!(value.as_u64(), Some(n), "{name}"),
                    RowValue::Flag(b) => assert_eq!(value.as_bool(), Some(b), "{name}"),
                    RowValue::Name(s) => assert_eq!(value.as_str(), Some(s.as_str()), "{name}"),
                }
            }
        }
    }

    #[test]
    fn options_that_need_others_are_invalid() {
        let cases = [
            BoundsQuery {
                grad_w_l: Some(0.3),
                ..query()
            },
            BoundsQuery {
                rewards: Some(RewardsName::TwoSided),
                ..query()
            },
            BoundsQuery {
                constants: ConstantsName::Tight,
                ..query()
            },
            BoundsQuery {
                delta: Some(0.2),
                ..query()
            },
            BoundsQuery {
                delta: Some(0.2),
                eps: Some(0.1),
                horizon: Some(Horizon::Infinite),
                ..query()
            },
        ];
        for q in cases {
            assert!(report(&q, false).unwrap_err().is_invalid_input(), "{q:?}");
        }
        assert_eq!(parse_horizon("inf"), Ok(Horizon::Infinite));
        assert_eq!(parse_horizon(" 7"), Ok(Horizon::Finite(7)));
        assert!(parse_horizon("0").is_err());
    }
}
