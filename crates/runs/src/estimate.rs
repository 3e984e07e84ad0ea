//! Streamed Monte Carlo estimates of `J`, `∇_v J` and `∇_w J` of one policy on a preset (the
//! `sepg estimate` command), with 95% Student-t confidence intervals (Sec 4.5).
//!
//! No trajectory is stored: the estimates come from `sepg_mdp::monte_carlo::stream_gradients`
//! (G(PO)MDP, Sec 2.3.1, with the variance-optimal per-step baseline fitted on an independent
//! pilot batch of `min(N, 4096)` trajectories, so each per-trajectory sample is exactly
//! unbiased) or, for the deterministic
//! policy, `stream_returns`. Memory does not grow with `n`, and the result is the same bits
//! for any number of threads.
//!
//! # Formula
//! ```text
//! mean ± t(0.975, n − 1) · s/√n     (s: sample standard deviation of the per-trajectory samples)
//! ```

use std::time::Instant;

use sepg_estimators::student_t_quantile;
use sepg_mdp::env::{Environment, Preset};
use sepg_mdp::monte_carlo::{DEFAULT_PILOT, Moments, stream_gradients, stream_returns};
use sepg_mdp::policy::GaussianPolicy;
use sepg_mdp::rng::SeedKey;
use serde::Serialize;

use crate::error::{Error, Result};

/// What to estimate: the policy `N(v·φ(s), σ²)` (deterministic for `σ = 0`) on a preset.
#[derive(Debug, Clone, PartialEq)]
pub struct EstimateSpec {
    /// Preset name: `lqg`, `lqg1d` or `mountain-car` (state + bias features).
    pub env: String,
    /// Mean parameters `v` (one per feature).
    pub v: Vec<f64>,
    /// Policy standard deviation `σ ≥ 0` (0: the deterministic policy, `J` only).
    pub sigma: f64,
    /// Horizon `H ≥ 1` (steps per trajectory).
    pub horizon: usize,
    /// Number of trajectories `N ≥ 2`.
    pub n: usize,
    /// Seed: trajectory `i` uses the streams of key `(seed, 0, 0)`, index `i`.
    pub seed: u64,
}

/// A mean with its 95% confidence interval, per component (a scalar for one component).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Interval {
    /// One component.
    Scalar {
        /// Sample mean.
        mean: f64,
        /// `[mean − half-width, mean + half-width]`.
        ci95: [f64; 2],
    },
    /// Several components.
    Vector {
        /// Sample means.
        mean: Vec<f64>,
        /// Intervals, one per component.
        ci95: Vec<[f64; 2]>,
    },
}

/// The estimates and the throughput of one `sepg estimate`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EstimateReport {
    /// Preset name.
    pub env: String,
    /// Number of trajectories.
    pub n: usize,
    /// Horizon.
    pub horizon: usize,
    /// Seed.
    pub seed: u64,
    /// Environment steps of the `n` trajectories.
    pub steps: u64,
    /// `J` (expected discounted return over the horizon).
    pub j: Interval,
    /// `∇_v J` (absent for the deterministic policy).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub grad_v: Option<Interval>,
    /// `∇_w J`, `w = ln σ` (absent for the deterministic policy).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub grad_w: Option<Interval>,
    /// Environment steps per second of wall time (the pilot batch included in the time).
    pub steps_per_sec: f64,
}

/// The 95% Student-t interval of each component.
fn interval(ms: &[Moments]) -> Result<Interval> {
    let mut out = Vec::with_capacity(ms.len());
    for m in ms {
        let t = student_t_quantile(0.975, (m.count() - 1) as f64)
            .map_err(|e| Error::failed(e.to_string()))?;
        let (mean, half) = (m.mean(), t * m.std_error());
        if !(mean.is_finite() && half.is_finite()) {
            return Err(Error::failed("an estimate is not finite"));
        }
        out.push((mean, [mean - half, mean + half]));
    }
    Ok(match out.as_slice() {
        [(mean, ci95)] => Interval::Scalar {
            mean: *mean,
            ci95: *ci95,
        },
        _ => Interval::Vector {
            mean: out.iter().map(|(m, _)| *m).collect(),
            ci95: out.iter().map(|(_, c)| *c).collect(),
        },
    })
}

/// Streams `spec.n` trajectories and returns the estimates with their intervals.
///
/// # Errors
/// [`Error::Invalid`] for an unknown preset, `n < 2`, `H = 0` or above
/// [`crate::spec::MAX_HORIZON`], `σ` negative or not finite, or
/// `v` of the wrong length; [`Error::Failed`] if the rollouts diverge.
///
/// # Examples
/// ```
/// use sepg_runs::estimate::{EstimateSpec, Interval, estimate};
/// let spec = EstimateSpec { env: "lqg1d".into(), v: vec![-0.3], sigma: 0.5, horizon: 20, n: 2000, seed: 1 };
/// let r = estimate(&spec).unwrap();
/// assert_eq!(r.steps, 40_000);
/// let Interval::Scalar { mean, ci95 } = r.j else { panic!() };
/// assert!(ci95[0] < mean && mean < ci95[1]);
/// ```
pub fn estimate(spec: &EstimateSpec) -> Result<EstimateReport> {
    let preset = Preset::from_name(&spec.env).map_err(|e| Error::invalid(e.to_string()))?;
    let env = preset.build();
    if spec.n < 2 {
        return Err(Error::invalid(format!(
            "--n must be at least 2, got {}",
            spec.n
        )));
    }
    if spec.horizon == 0 {
        return Err(Error::invalid("--horizon must be at least 1"));
    }
    crate::spec::check_horizon(spec.horizon)?;
    if !(spec.sigma.is_finite() && spec.sigma >= 0.0) {
        return Err(Error::invalid(format!(
            "sigma must be finite and >= 0, got {}",
            spec.sigma
        )));
    }
    let p = env.feature_dim();
    let policy = if spec.sigma == 0.0 {
        GaussianPolicy::deterministic(spec.v.clone(), env.action_dim(), p)
    } else {
        GaussianPolicy::new(spec.v.clone(), vec![spec.sigma.ln(); env.action_dim()], p)
    }
    .map_err(|e| Error::invalid_from(format!("invalid policy for {}", spec.env), e))?;
    let key = SeedKey::new(spec.seed, 0, 0);
    let start = Instant::now();
    let rollout_error = |e: sepg_mdp::monte_carlo::McError| Error::failed(e.to_string());
    let (j, grads, steps) = if policy.is_deterministic() {
        let (j, steps) =
            stream_returns(&env, &policy, spec.n, spec.horizon, key).map_err(rollout_error)?;
        (j, None, steps)
    } else {
        let pilot = DEFAULT_PILOT.min(spec.n);
        let g = stream_gradients(&env, &policy, spec.n, spec.horizon, key, pilot)
            .map_err(rollout_error)?;
        (g.j, Some((g.grad_v, g.grad_w)), g.steps)
    };
    let elapsed = start.elapsed().as_secs_f64();
    let (grad_v, grad_w) = match grads {
        Some((gv, gw)) => (Some(interval(&gv)?), Some(interval(&gw)?)),
        None => (None, None),
    };
    Ok(EstimateReport {
        env: spec.env.clone(),
        n: spec.n,
        horizon: spec.horizon,
        seed: spec.seed,
        steps,
        j: interval(&[j])?,
        grad_v,
        grad_w,
        steps_per_sec: steps as f64 / elapsed.max(1e-9),
    })
}
