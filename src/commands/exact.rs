//! `sepg exact`: exact J and derivatives of a 1-D LQG preset — the closed form for the unclipped
//! model (any horizon) or dynamic programming for the clipped model (finite horizon); the
//! work and the checks of the arguments are `sepg_runs::exact`, this file parses and prints.

use clap::Args;
use sepg_mdp::oracle::{ExactEval, Horizon};
use sepg_runs::exact::{ExactSpec, exact};
use serde::Serialize;

use crate::cli::CliError;
use crate::commands::parse::{HorizonArg, LqgPreset};
use crate::output::to_json_line;

/// Arguments of `sepg exact`.
#[derive(Debug, Args)]
pub struct ExactArgs {
    /// The LQG preset: `lqg` (thesis Sec 5.1 as written) or `lqg1d` (the public code's LQG).
    #[arg(long)]
    env: LqgPreset,
    /// Mean parameter v of the policy a ~ N(v s, σ²).
    #[arg(long, allow_hyphen_values = true)]
    v: f64,
    /// Standard deviation σ ≥ 0 of the policy (0: the deterministic policy a = v s).
    #[arg(long, allow_hyphen_values = true)]
    sigma: f64,
    /// Horizon H ≥ 1, or `inf` for the infinite discounted sum. Default: `inf` for the
    /// unclipped closed form, 20 with --clipped.
    #[arg(long)]
    horizon: Option<HorizonArg>,
    /// Standard deviation η₀ ≥ 0 of the transition noise (default 0: the presets are noiseless).
    #[arg(long, allow_hyphen_values = true, default_value_t = 0.0)]
    eta: f64,
    /// Use the clipped model (state and action boxes of the preset), evaluated by dynamic
    /// programming; without it the closed form of the unclipped model is used.
    #[arg(long)]
    clipped: bool,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Serialize)]
struct ExactReport {
    env: &'static str,
    oracle: &'static str,
    horizon: String,
    v: f64,
    sigma: f64,
    eta: f64,
    j: f64,
    grad_v: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    grad_w: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    grad_sigma: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    mixed_wv: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    hessian: Option<Vec<Vec<f64>>>,
}

fn evaluate(args: &ExactArgs) -> Result<(ExactEval, Horizon), CliError> {
    Ok(exact(&ExactSpec {
        env: args.env.name().to_string(),
        v: args.v,
        sigma: args.sigma,
        horizon: args.horizon.map(|h| h.0),
        eta: args.eta,
        clipped: args.clipped,
    })?)
}

/// Runs `sepg exact`.
pub fn run(args: &ExactArgs) -> Result<(), CliError> {
    let (eval, horizon) = evaluate(args)?;
    let report = ExactReport {
        env: args.env.name(),
        oracle: if args.clipped {
            "clipped-dp"
        } else {
            "closed-form"
        },
        horizon: match horizon {
            Horizon::Finite(h) => h.to_string(),
            Horizon::Infinite => "inf".to_string(),
        },
        v: args.v,
        sigma: args.sigma,
        eta: args.eta,
        j: eval.j,
        grad_v: eval.grad_v[0],
        grad_w: eval.grad_w.first().copied(),
        grad_sigma: eval.grad_sigma().first().copied(),
        mixed_wv: eval.mixed_wv.first().copied(),
        hessian: eval.hessian.as_ref().map(|h| {
            (0..h.nrows())
                .map(|i| (0..h.ncols()).map(|j| h[(i, j)]).collect())
                .collect()
        }),
    };
    if args.json {
        print!("{}", to_json_line(&report)?);
    } else {
        println!(
            "env       {} ({} oracle, horizon {})",
            report.env, report.oracle, report.horizon
        );
        println!("J         {:.12e}", report.j);
        println!("grad_v    {:.12e}", report.grad_v);
        if let (Some(gw), Some(gs)) = (report.grad_w, report.grad_sigma) {
            println!("grad_w    {gw:.12e}");
            println!("grad_sig  {gs:.12e}");
        }
        if let Some(m) = report.mixed_wv {
            println!("d2J/dwdv  {m:.12e}");
        }
    }
    Ok(())
}
