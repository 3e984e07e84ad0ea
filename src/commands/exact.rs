//! `sepg exact`: exact J and derivatives of a 1-D LQG preset — the closed form for the unclipped
//! model (any horizon) or dynamic programming for the clipped model (finite horizon); the
//! work, the checks of the arguments and the report are `sepg_runs::exact` and
//! `sepg_runs::exact_report`, this file parses and prints.

use clap::Args;
use sepg_runs::exact::ExactSpec;
use sepg_runs::exact_report::exact_report;

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

/// Runs `sepg exact`.
pub fn run(args: &ExactArgs) -> Result<(), CliError> {
    let report = exact_report(&ExactSpec {
        env: args.env.name().to_string(),
        v: args.v,
        sigma: args.sigma,
        horizon: args.horizon.map(|h| h.0),
        eta: args.eta,
        clipped: args.clipped,
    })?;
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
