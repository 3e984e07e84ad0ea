//! `sepg estimate`: Monte Carlo estimates of J, ∇_v J and ∇_w J from one batch of rollouts,
//! with 95% Student-t confidence intervals (Sec 4.5) and the rollout throughput.

use std::time::Instant;

use clap::Args;
use sepg_estimators::{Estimate, Estimator, GradientSpec, Param, Width, student_t_quantile};
use sepg_mdp::env::{Environment, Preset};
use sepg_mdp::policy::GaussianPolicy;
use sepg_mdp::rng::SeedKey;
use sepg_mdp::rollout::{rollout, rollout_returns};
use serde::Serialize;

use crate::cli::CliError;
use crate::output::to_json_line;
use sepg_runs::spec::parse_seed;

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
    /// Number of trajectories N ≥ 2.
    #[arg(long, allow_negative_numbers = true)]
    n: usize,
    /// Seed of the batch (trajectory i uses the stream of (seed, 0, 0, i)).
    #[arg(long, allow_hyphen_values = true, value_parser = parse_seed)]
    seed: u64,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    json: bool,
}

/// A mean with its 95% confidence interval, per component (scalars for one component).
#[derive(Debug, Serialize)]
#[serde(untagged)]
enum Interval {
    Scalar { mean: f64, ci95: [f64; 2] },
    Vector { mean: Vec<f64>, ci95: Vec<[f64; 2]> },
}

#[derive(Debug, Serialize)]
struct EstimateReport {
    env: String,
    n: usize,
    horizon: usize,
    seed: u64,
    /// Environment steps of the batch (not counted for the deterministic policy, whose
    /// returns are simulated without scores).
    #[serde(skip_serializing_if = "Option::is_none")]
    steps: Option<usize>,
    j: Interval,
    #[serde(skip_serializing_if = "Option::is_none")]
    grad_v: Option<Interval>,
    #[serde(skip_serializing_if = "Option::is_none")]
    grad_w: Option<Interval>,
    #[serde(skip_serializing_if = "Option::is_none")]
    steps_per_sec: Option<f64>,
}

/// The mean of the returns `g` with its 95% Student-t interval (Sec 4.5):
/// ḡ ± t(0.975, n − 1)·√(s²/n), s² the unbiased sample variance.
fn returns_interval(g: &[f64]) -> Result<Interval, CliError> {
    let n = g.len() as f64;
    let mean = g.iter().sum::<f64>() / n;
    let var = g.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0);
    let t = student_t_quantile(0.975, n - 1.0).map_err(|e| CliError::failure(e.to_string()))?;
    let half = t * (var / n).sqrt();
    Ok(Interval::Scalar {
        mean,
        ci95: [mean - half, mean + half],
    })
}

fn interval(e: &Estimate) -> Result<Interval, CliError> {
    let mut half = vec![0.0; e.dim()];
    e.widths_into(Width::StudentT, 0.05, &mut half)
        .map_err(|err| CliError::failure(err.to_string()))?;
    let ci: Vec<[f64; 2]> = e
        .mean()
        .iter()
        .zip(&half)
        .map(|(m, h)| [m - h, m + h])
        .collect();
    Ok(if e.dim() == 1 {
        Interval::Scalar {
            mean: e.mean()[0],
            ci95: ci[0],
        }
    } else {
        Interval::Vector {
            mean: e.mean().to_vec(),
            ci95: ci,
        }
    })
}

fn estimate(args: &EstimateArgs) -> Result<EstimateReport, CliError> {
    let preset = Preset::from_name(&args.env).map_err(|e| CliError::usage(e.to_string()))?;
    let env = preset.build();
    if args.n < 2 {
        return Err(CliError::usage(format!(
            "--n must be at least 2, got {}",
            args.n
        )));
    }
    if args.horizon == 0 {
        return Err(CliError::usage("--horizon must be at least 1"));
    }
    if !(args.sigma.is_finite() && args.sigma >= 0.0) {
        return Err(CliError::usage(format!(
            "sigma must be finite and >= 0, got {}",
            args.sigma
        )));
    }
    let p = env.feature_dim();
    let policy = if args.sigma == 0.0 {
        GaussianPolicy::deterministic(args.v.clone(), env.action_dim(), p)
    } else {
        GaussianPolicy::new(args.v.clone(), vec![args.sigma.ln(); env.action_dim()], p)
    }
    .map_err(|e| CliError::usage(format!("invalid policy for {}: {e}", args.env)))?;

    let key = SeedKey::new(args.seed, 0, 0);
    if policy.is_deterministic() {
        // J only: the deterministic policy has no score, so its returns are simulated alone.
        let g = rollout_returns(&env, &policy, args.n, args.horizon, key)
            .map_err(|e| CliError::usage(e.to_string()))?;
        return Ok(EstimateReport {
            env: args.env.clone(),
            n: args.n,
            horizon: args.horizon,
            seed: args.seed,
            steps: None,
            j: returns_interval(&g)?,
            grad_v: None,
            grad_w: None,
            steps_per_sec: None,
        });
    }
    let start = Instant::now();
    let batch = rollout(&env, &policy, args.n, args.horizon, key)
        .map_err(|e| CliError::usage(e.to_string()))?;
    let elapsed = start.elapsed().as_secs_f64();
    let steps = batch.steps();

    let mut estimator = Estimator::new();
    let mut est = Estimate::new();
    let fail = |e: sepg_estimators::EstimatorError| CliError::failure(e.to_string());
    estimator.value(&batch, &mut est).map_err(fail)?;
    let j = interval(&est)?;
    let spec = GradientSpec::default();
    estimator
        .gradient(&batch, Param::V, spec, &mut est)
        .map_err(fail)?;
    let gv = interval(&est)?;
    estimator
        .gradient(&batch, Param::W, spec, &mut est)
        .map_err(fail)?;
    let (grad_v, grad_w) = (Some(gv), Some(interval(&est)?));
    Ok(EstimateReport {
        env: args.env.clone(),
        n: args.n,
        horizon: args.horizon,
        seed: args.seed,
        steps: Some(steps),
        j,
        grad_v,
        grad_w,
        steps_per_sec: Some(steps as f64 / elapsed.max(1e-9)),
    })
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
    let r = estimate(args)?;
    if args.json {
        print!("{}", to_json_line(&r)?);
    } else {
        let mut out = render("J", &r.j);
        for (name, i) in [("grad_v", &r.grad_v), ("grad_w", &r.grad_w)] {
            if let Some(i) = i {
                out.push_str(&render(name, i));
            }
        }
        match (r.steps, r.steps_per_sec) {
            (Some(steps), Some(rate)) => out.push_str(&format!(
                "{} trajectories, {steps} steps, {rate:.3e} steps/s\n",
                r.n
            )),
            _ => out.push_str(&format!(
                "{} trajectories of the deterministic policy\n",
                r.n
            )),
        }
        print!("{out}");
    }
    Ok(())
}
