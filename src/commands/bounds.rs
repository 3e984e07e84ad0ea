//! `sepg bounds`: every closed-form quantity that the given task constants, σ and gradients
//! determine (Theorems 3.11, 3.13, 3.14, 4.2, 4.3, 4.5, Lemma A.1, Corollary 4.4).

use std::collections::BTreeMap;

use clap::Args;
use sepg_bounds::constants::{self, TaskConstants};
use sepg_bounds::outcome::StepOutcome;
use sepg_bounds::penalties::{Family, Horizon, Rewards, Tight};
use sepg_bounds::{BoundsError, batch_size, papini, pirotta, surrogate, v_update, w_update};
use sepg_certified::Interval;
use sepg_certified::{self as certified, Certified, Quadratic};
use sepg_runs::spec::{ConstantsName, MAX_HORIZON, RewardsName};
use serde::Serialize;

use crate::cli::CliError;
use crate::output::to_json_line;

/// Arguments of `sepg bounds`.
#[derive(Debug, Args)]
pub struct BoundsArgs {
    /// Discount factor γ ∈ [0, 1).
    #[arg(long, allow_hyphen_values = true)]
    gamma: f64,
    /// Maximum absolute reward R (> 0).
    #[arg(long = "r-max", allow_hyphen_values = true)]
    r_max: f64,
    /// Bound M_φ on every feature's absolute value (> 0).
    #[arg(long = "m-phi", allow_hyphen_values = true)]
    m_phi: f64,
    /// Volume |A| of the action space (> 0).
    #[arg(long = "action-volume", allow_hyphen_values = true)]
    action_volume: f64,
    /// Policy standard deviation σ = e^w (> 0).
    #[arg(long, allow_hyphen_values = true)]
    sigma: f64,
    /// Number m of mean parameters (for the surrogate L = ‖∇_v J‖²/(4mc)); defaults to the
    /// length of --grad-v.
    #[arg(long = "dim-v")]
    dim_v: Option<usize>,
    /// Gradient ∇_v J, comma-separated (one value per mean parameter).
    #[arg(long = "grad-v", value_delimiter = ',', allow_hyphen_values = true)]
    grad_v: Option<Vec<f64>>,
    /// Gradient ∇_w J (scalar).
    #[arg(long = "grad-w", allow_hyphen_values = true)]
    grad_w: Option<f64>,
    /// Gradient ∇_w L of the surrogate (scalar); needs --grad-w.
    #[arg(long = "grad-w-l", allow_hyphen_values = true)]
    grad_w_l: Option<f64>,
    /// Improvement C each update must guarantee (negative: a bounded worsening). Default 0.
    #[arg(long, allow_hyphen_values = true, default_value_t = 0.0)]
    required: f64,
    /// Split C between the updates as in (4.13)–(4.14): (1 − ν)C for v, νC for w.
    /// Without it, each update must guarantee C.
    #[arg(long, allow_hyphen_values = true)]
    nu: Option<f64>,
    /// Confidence δ ∈ (0, 1) for the Chebyshev batch sizes (with --eps and --horizon).
    #[arg(long, allow_hyphen_values = true)]
    delta: Option<f64>,
    /// Gradient accuracy ε > 0 for the Chebyshev batch sizes.
    #[arg(long, allow_hyphen_values = true)]
    eps: Option<f64>,
    /// Horizon H ≥ 1 (or `inf`): of the tight constants, and of the Chebyshev batch sizes
    /// (finite there).
    #[arg(long, value_parser = parse_horizon, allow_hyphen_values = true)]
    horizon: Option<Horizon>,
    /// Family of the constants c and d: the thesis's (Theorems 3.14, 4.2, 4.3) or the tight
    /// constants c = ρRM_φ²S_H/σ², d = 2ρRS_H (docs/THEOREMS.md, "Tight constants"), which
    /// need --horizon.
    #[arg(long, value_enum, default_value = "thesis")]
    constants: ConstantsName,
    /// Sign of the rewards for the tight constants: two-sided (ρ = 1, always sound) or
    /// non-positive (every reward in [−R, 0], ρ = 1/2) [default: two-sided].
    #[arg(long, value_enum)]
    rewards: Option<RewardsName>,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    json: bool,
    /// Also print, under `certified`, an outward-rounded enclosure [lo, hi] of ψ, c, d, C_max,
    /// λ and every safe-interval end point, and the certified largest steps with the
    /// enclosure of their bound (docs/THEOREMS.md, Certified steps).
    #[arg(long)]
    certified: bool,
}

/// Parses `--horizon`: a positive integer, or `inf` for H = ∞.
fn parse_horizon(s: &str) -> Result<Horizon, String> {
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

/// Enclosures and certified steps of `sepg bounds --certified`.
#[derive(Debug, Default, Serialize)]
struct CertifiedReport {
    /// Name → [lo, hi] enclosing the exact real value.
    enclosures: BTreeMap<&'static str, [f64; 2]>,
    /// Largest step → its certified outcome.
    steps: BTreeMap<&'static str, CertifiedStepReport>,
}

/// One certified step: `certified`, `uncertifiable`, `infeasible` or `no-step`; the step
/// taken and the enclosure of its bound.
#[derive(Debug, Serialize)]
struct CertifiedStepReport {
    outcome: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    step: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    bound: Option<[f64; 2]>,
}

fn ends(i: Interval) -> [f64; 2] {
    [i.lo(), i.hi()]
}

fn step_report(c: &Certified) -> CertifiedStepReport {
    let outcome = match c {
        Certified::Step(_) => "certified",
        Certified::Uncertifiable { .. } => "uncertifiable",
        Certified::Infeasible { .. } => "infeasible",
        _ => "no-step",
    };
    CertifiedStepReport {
        outcome,
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

fn compute_certified(
    a: &BoundsArgs,
    k: &TaskConstants,
    (required_v, required_w): (f64, f64),
) -> Result<CertifiedReport, CliError> {
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

/// Everything `sepg bounds` reports. Optional fields are absent when the inputs do not
/// determine them.
#[derive(Debug, Default, Serialize)]
struct BoundsReport {
    constants: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    horizon: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    rewards: Option<&'static str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    s_h: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    rho: Option<f64>,
    psi: f64,
    c: f64,
    d: f64,
    dc_dsigma: f64,
    alpha_star: f64,
    beta_star: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    surrogate_coefficient: Option<f64>,
    required_v: f64,
    required_w: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    c_max_v: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    feasible_v: Option<bool>,
    #[serde(skip_serializing_if = "Option::is_none")]
    lambda_v: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    alpha_interval: Option<[f64; 2]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    alpha_bar: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    greedy_index: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    surrogate: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pirotta_alpha: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pirotta_guarantee: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    c_max_w: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    feasible_w: Option<bool>,
    #[serde(skip_serializing_if = "Option::is_none")]
    lambda_w: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    beta_interval_j: Option<[f64; 2]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    beta_bar_j: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    beta_tilde: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    beta_interval: Option<[f64; 2]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    beta_bar: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    batch_reinforce: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    batch_gpomdp: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    certified: Option<CertifiedReport>,
}

fn bad(e: BoundsError) -> CliError {
    CliError::usage(e.to_string())
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
fn requirements(a: &BoundsArgs) -> Result<(f64, f64), CliError> {
    match a.nu {
        Some(nu) => sepg_bounds::budget::split_requirement(a.required, nu).map_err(bad),
        None if !a.required.is_finite() => Err(CliError::usage(format!(
            "required must be finite, got {}",
            a.required
        ))),
        None => Ok((a.required, a.required)),
    }
}

/// The number m of mean parameters: --dim-v, checked against --grad-v, or the length of
/// --grad-v.
fn dim_v(a: &BoundsArgs) -> Result<Option<usize>, CliError> {
    let m = match (&a.grad_v, a.dim_v) {
        (Some(g), Some(m)) if g.len() != m => {
            return Err(CliError::usage(format!(
                "--dim-v {m} does not match the {} components of --grad-v",
                g.len()
            )));
        }
        (Some(g), _) => Some(g.len()),
        (None, m) => m,
    };
    if m == Some(0) {
        return Err(CliError::usage("--dim-v must be at least 1"));
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
) -> Result<(), CliError> {
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
fn fill_w(
    r: &mut BoundsReport,
    a: &BoundsArgs,
    k: &TaskConstants,
    required_w: f64,
) -> Result<(), CliError> {
    let sigma = a.sigma;
    match (a.grad_w, a.grad_w_l) {
        (None, Some(_)) => return Err(CliError::usage("--grad-w-l needs --grad-w")),
        (Some(gj), gl) => {
            r.c_max_w = Some(w_update::c_max(k, sigma, gj).map_err(bad)?);
            let oj = w_update::safe_step_along_j(k, sigma, gj, required_w).map_err(bad)?;
            let (feasible, lambda, interval, bar) = outcome_fields(&oj);
            (r.feasible_w, r.lambda_w, r.beta_interval_j, r.beta_bar_j) =
                (feasible, lambda, interval, bar);
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
fn fill_batch(r: &mut BoundsReport, a: &BoundsArgs, k: &TaskConstants) -> Result<(), CliError> {
    let tight = a.constants == ConstantsName::Tight;
    match (a.delta, a.eps, a.horizon) {
        (Some(delta), Some(eps), Some(horizon)) => {
            let h = match horizon {
                // The batch sizes sum H terms: the limit keeps them under a second.
                Horizon::Finite(h) if h <= MAX_HORIZON as u64 => h as u32,
                Horizon::Finite(_) => {
                    return Err(CliError::usage(format!(
                        "batch sizes need --horizon at most {MAX_HORIZON}"
                    )));
                }
                Horizon::Infinite => {
                    return Err(CliError::usage("batch sizes need a finite --horizon"));
                }
            };
            r.batch_reinforce =
                Some(batch_size::reinforce(k, a.sigma, delta, eps, h).map_err(bad)?);
            r.batch_gpomdp = Some(batch_size::gpomdp(k, a.sigma, delta, eps, h).map_err(bad)?);
            Ok(())
        }
        (None, None, None) => Ok(()),
        (None, None, Some(_)) if tight => Ok(()),
        _ => Err(CliError::usage(
            "batch sizes need all of --delta, --eps and --horizon",
        )),
    }
}

/// The task constants of the arguments, with the family of --constants (the tight family
/// for --horizon and --rewards), and the report's fields naming the family: its name,
/// horizon, reward sign, S_H and ρ.
fn task_constants(a: &BoundsArgs) -> Result<(TaskConstants, BoundsReport), CliError> {
    let k = TaskConstants::new(a.gamma, a.r_max, a.m_phi, a.action_volume).map_err(bad)?;
    match a.constants {
        ConstantsName::Thesis => {
            if a.rewards.is_some() {
                return Err(CliError::usage(
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
                CliError::usage("--constants tight needs --horizon (a positive integer or inf)")
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

fn compute(a: &BoundsArgs) -> Result<BoundsReport, CliError> {
    let (k, family) = task_constants(a)?;
    let sigma = a.sigma;
    let (required_v, required_w) = requirements(a)?;
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
    if let Some(m) = dim_v(a)? {
        r.surrogate_coefficient = Some(1.0 / (4.0 * m as f64 * c));
    }
    if let Some(g) = &a.grad_v {
        fill_v(&mut r, &k, sigma, g, required_v)?;
    }
    fill_w(&mut r, a, &k, required_w)?;
    fill_batch(&mut r, a, &k)?;
    if a.certified {
        r.certified = Some(compute_certified(a, &k, (required_v, required_w))?);
    }
    Ok(r)
}

fn fmt_opt(x: Option<f64>) -> String {
    x.map_or_else(|| "-".to_string(), |v| format!("{v:.6e}"))
}

/// The rows of the quantities that the inputs determine, in table order.
fn push_optional_rows<'a>(r: &BoundsReport, rows: &mut Vec<(&'a str, String, &'a str)>) {
    let opt_rows: [(&str, Option<f64>, &str); 13] = [
        (
            "surrogate_coefficient",
            r.surrogate_coefficient,
            "Cor 4.4: 1/(4mc)",
        ),
        ("c_max_v", r.c_max_v, "(4.9)"),
        ("lambda_v", r.lambda_v, "(4.10)"),
        ("alpha_bar", r.alpha_bar, "(4.20): (1+lambda_v) alpha_star"),
        ("surrogate", r.surrogate, "Cor 4.4: L"),
        ("pirotta_alpha", r.pirotta_alpha, "Cor 3.11"),
        ("pirotta_guarantee", r.pirotta_guarantee, "Cor 3.11"),
        ("c_max_w", r.c_max_w, "(4.16)"),
        ("lambda_w", r.lambda_w, "(4.17)"),
        (
            "beta_bar_j",
            r.beta_bar_j,
            "(4.17): largest step along grad_w J",
        ),
        ("beta_tilde", r.beta_tilde, "Thm 4.5"),
        (
            "beta_bar",
            r.beta_bar,
            "(4.20): beta_tilde + lambda_w |beta_tilde|",
        ),
        (
            "batch_gpomdp",
            r.batch_gpomdp.map(|n| n as f64),
            "Cor 3.13 (G(PO)MDP)",
        ),
    ];
    for (name, value, cite) in opt_rows {
        if value.is_some() {
            rows.push((name, fmt_opt(value), cite));
        }
    }
    if let Some(n) = r.batch_reinforce {
        rows.push((
            "batch_reinforce",
            n.to_string(),
            "Cor 3.13 (REINFORCE, corrected)",
        ));
    }
    if let Some(i) = r.greedy_index {
        rows.push((
            "greedy_index",
            i.to_string(),
            "Thm 3.14: coordinate updated",
        ));
    }
    for (name, feasible) in [("feasible_v", r.feasible_v), ("feasible_w", r.feasible_w)] {
        if let Some(f) = feasible {
            rows.push((name, f.to_string(), "C <= C_max"));
        }
    }
}

fn render_table(r: &BoundsReport) -> String {
    let tight = r.s_h.is_some();
    let (c_cite, d_cite) = if tight {
        ("Thm T: rho R M^2 S_H / sigma^2", "Thm T: 2 rho R S_H")
    } else {
        ("Thm 4.2 (Papini et al. Thm 3.14)", "Thm 4.3")
    };
    let mut rows: Vec<(&str, String, &str)> = vec![(
        "constants",
        r.constants.to_owned(),
        if tight {
            "docs/THEOREMS.md, Tight constants"
        } else {
            "the thesis's c and d"
        },
    )];
    if let (Some(h), Some(sign), Some(s_h), Some(rho)) = (&r.horizon, r.rewards, r.s_h, r.rho) {
        rows.extend([
            ("horizon", h.clone(), "H"),
            ("rewards", sign.to_owned(), "reward sign"),
            ("s_h", format!("{s_h:.6e}"), "sum_{t<H} (t+1) gamma^t"),
            ("rho", format!("{rho}"), "1 two-sided, 1/2 non-positive"),
        ]);
    }
    rows.extend([
        ("psi", format!("{:.10}", r.psi), "Lemma A.1"),
        ("c", format!("{:.6e}", r.c), c_cite),
        ("d", format!("{:.6e}", r.d), d_cite),
        ("dc_dsigma", format!("{:.6e}", r.dc_dsigma), "Appendix B"),
        (
            "alpha_star",
            format!("{:.6e}", r.alpha_star),
            "Thm 4.2: 1/(2c)",
        ),
        (
            "beta_star",
            format!("{:.6e}", r.beta_star),
            "Thm 4.3: 1/(2d)",
        ),
        ("required_v", format!("{:.6e}", r.required_v), "(4.13)"),
        ("required_w", format!("{:.6e}", r.required_w), "(4.14)"),
    ]);
    push_optional_rows(r, &mut rows);
    let mut out = String::new();
    for (name, value, cite) in rows {
        out.push_str(&format!("{name:<22} {value:>16}   {cite}\n"));
    }
    if let Some(c) = &r.certified {
        render_certified(c, &mut out);
    }
    out
}

/// The `certified` part of the table: the enclosures, then the certified steps.
fn render_certified(c: &CertifiedReport, out: &mut String) {
    out.push_str("certified enclosures [lo, hi] (outward-rounded):\n");
    for (name, [lo, hi]) in &c.enclosures {
        out.push_str(&format!("  {name:<20} [{lo:e}, {hi:e}]\n"));
    }
    out.push_str("certified steps:\n");
    for (name, s) in &c.steps {
        let step = s.step.map_or_else(|| "-".to_string(), |x| format!("{x:e}"));
        let bound = s
            .bound
            .map_or_else(|| "-".to_string(), |[lo, hi]| format!("[{lo:e}, {hi:e}]"));
        out.push_str(&format!(
            "  {name:<20} {:<14} step {step}, bound {bound}\n",
            s.outcome
        ));
    }
}

/// Runs `sepg bounds`.
pub fn run(args: &BoundsArgs) -> Result<(), CliError> {
    let report = compute(args)?;
    let text = if args.json {
        to_json_line(&report)?
    } else {
        render_table(&report)
    };
    print!("{text}");
    Ok(())
}
