//! `sepg exact`: exact J and derivatives of a 1-D LQG preset — the closed form for the unclipped
//! model (any horizon) or dynamic programming for the clipped model (finite horizon).

use clap::Args;
use nalgebra::DVector;
use sepg_mdp::LqgModel;
use sepg_mdp::oracle::{
    ClippedDpOracle, ClosedFormOracle, ExactEval, ExactOracle, Exploration, Horizon, OracleError,
};
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

/// Maps an oracle error to the CLI contract: input problems exit 2, numerical failures exit 1.
fn oracle_error(e: OracleError) -> CliError {
    match e {
        OracleError::NotConverged { .. }
        | OracleError::Overflow
        | OracleError::ResolutionExceeded { .. } => CliError::failure(e.to_string()),
        _ => CliError::usage(e.to_string()),
    }
}

fn evaluate(args: &ExactArgs) -> Result<(ExactEval, Horizon), CliError> {
    if !args.v.is_finite() {
        return Err(CliError::usage(format!("v must be finite, got {}", args.v)));
    }
    if !(args.sigma.is_finite() && args.sigma >= 0.0) {
        return Err(CliError::usage(format!(
            "sigma must be finite and >= 0, got {}",
            args.sigma
        )));
    }
    if !(args.eta.is_finite() && args.eta >= 0.0) {
        return Err(CliError::usage(format!(
            "eta must be finite and >= 0, got {}",
            args.eta
        )));
    }
    let model: LqgModel = args
        .env
        .model()
        .with_noise(DVector::from_element(1, args.eta))
        .map_err(|e| CliError::usage(e.to_string()))?;
    let exploration = if args.sigma == 0.0 {
        Exploration::Deterministic
    } else {
        Exploration::Gaussian {
            w: vec![args.sigma.ln()],
        }
    };
    let horizon = match (args.horizon, args.clipped) {
        (Some(h), _) => h.0,
        (None, true) => Horizon::Finite(20),
        (None, false) => Horizon::Infinite,
    };
    let eval = if args.clipped {
        if horizon == Horizon::Infinite {
            return Err(CliError::usage(
                "the clipped model needs a finite --horizon",
            ));
        }
        ClippedDpOracle::new(&model)
            .map_err(oracle_error)?
            .evaluate(&[args.v], &exploration, horizon)
    } else {
        ClosedFormOracle::new(&model)
            .map_err(oracle_error)?
            .evaluate(&[args.v], &exploration, horizon)
    }
    .map_err(oracle_error)?;
    Ok((eval, horizon))
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
