//! `sepg estimate`: streamed Monte Carlo estimates of J, ∇_v J and ∇_w J with 95% Student-t
//! confidence intervals (Sec 4.5) and the rollout throughput; the work is
//! `sepg_runs::estimate`, this file parses and prints.

use clap::Args;
use sepg_runs::estimate::{EstimateSpec, Interval, estimate};
use sepg_runs::spec::parse_seed;

use crate::cli::CliError;
use crate::output::to_json_line;

/// Arguments of `sepg estimate`.
#[derive(Debug, Args)]
pub struct EstimateArgs {
    /// Environment preset: `lqg`, `lqg1d` or `mountain-car` (state + bias features).
    #[arg(long)]
    env: String,
    /// Mean parameters v, comma-separated (one per feature; the LQG presets have one).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, num_args = 1)]
    v: Vec<f64>,
    /// Policy standard deviation σ ≥ 0 (0: the deterministic policy, J only).
    #[arg(long, allow_hyphen_values = true)]
    sigma: f64,
    /// Horizon H ≥ 1 (steps per trajectory).
    #[arg(long, allow_negative_numbers = true)]
    horizon: usize,
    /// Number of trajectories N ≥ 2 (streamed: memory does not grow with N).
    #[arg(long, allow_negative_numbers = true)]
    n: usize,
    /// Seed of the batch (trajectory i uses the stream of (seed, 0, 0, i)).
    #[arg(long, allow_hyphen_values = true, value_parser = parse_seed)]
    seed: u64,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    json: bool,
}

fn render(name: &str, i: &Interval) -> String {
    match i {
        Interval::Scalar { mean, ci95 } => {
            format!(
                "{name:<8} {mean:>16.8e}   95% CI [{:.8e}, {:.8e}]\n",
                ci95[0], ci95[1]
            )
        }
        Interval::Vector { mean, ci95 } => mean
            .iter()
            .zip(ci95)
            .enumerate()
            .map(|(k, (m, c))| {
                let label = format!("{name}[{k}]");
                format!(
                    "{label:<8} {m:>16.8e}   95% CI [{:.8e}, {:.8e}]\n",
                    c[0], c[1]
                )
            })
            .collect(),
    }
}

/// Runs `sepg estimate`.
pub fn run(args: &EstimateArgs) -> Result<(), CliError> {
    let r = estimate(&EstimateSpec {
        env: args.env.clone(),
        v: args.v.clone(),
        sigma: args.sigma,
        horizon: args.horizon,
        n: args.n,
        seed: args.seed,
    })?;
    if args.json {
        print!("{}", to_json_line(&r)?);
    } else {
        let mut out = render("J", &r.j);
        for (name, i) in [("grad_v", &r.grad_v), ("grad_w", &r.grad_w)] {
            if let Some(i) = i {
                out.push_str(&render(name, i));
            }
        }
        out.push_str(&format!(
            "{} trajectories, {} steps, {:.3e} steps/s\n",
            r.n, r.steps, r.steps_per_sec
        ));
        print!("{out}");
    }
    Ok(())
}
