//! Monte Carlo oracle for the performance `J(θ)` (eq. 2.1's expected discounted return,
//! truncated at the horizon) and for performance differences `J(θ′) − J(θ)` with common random
//! numbers.
//!
//! Differences are estimated from paired samples: trajectory `i` of both policies uses the same
//! streams `key.rngs(i)`, so both see the same initial state and transition noise and their
//! Gaussian perturbations `z` come from the same policy stream. The paired differences
//! `d_i = G_i(θ′) − G_i(θ)` are i.i.d., and their variance is usually far smaller than the sum
//! of the two variances.
//!
//! Confidence intervals rely on the central limit theorem: the estimate is treated as normal
//! with the sample standard error, `mean ± z_{(1+level)/2} · s/√n`. This is asymptotic; for
//! the bounded returns of the presets and `n` in the hundreds or more it is accurate, and the
//! tests of this crate check it against closed forms.
//!
//! # Formula
//! ```text
//! Ĵ = (1/n) Σ_i G_i,   s² = Σ_i (G_i − Ĵ)² / (n − 1),   SE = s/√n
//! CI = [Ĵ − z SE, Ĵ + z SE],   z = Φ⁻¹((1 + level)/2)
//! ```

use statrs::distribution::{ContinuousCDF, Normal};

use crate::env::Environment;
use crate::policy::GaussianPolicy;
use crate::rng::SeedKey;
use crate::rollout::{RolloutError, rollout_returns};

/// Errors of the Monte Carlo oracle.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum McError {
    /// The rollout failed.
    #[error("rollout failed: {0}")]
    Rollout(#[from] RolloutError),
    /// Fewer than two samples: no variance estimate.
    #[error("a Monte Carlo estimate needs at least 2 samples (got {0})")]
    TooFewSamples(usize),
    /// The confidence level is outside `(0, 1)`.
    #[error("confidence level {0} is outside (0, 1)")]
    InvalidLevel(f64),
    /// A sample is NaN or infinite.
    #[error("a sample is not finite")]
    NonFinite,
    /// The two policies do not have the same dimensions.
    #[error("the two policies have different feature or action dimensions")]
    PolicyShape,
}

/// A Monte Carlo estimate with its standard error and a normal (CLT) confidence interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct McEstimate {
    /// Sample mean.
    pub mean: f64,
    /// Standard error `s/√n` (sample standard deviation with `n − 1`).
    pub std_error: f64,
    /// Lower end of the confidence interval.
    pub ci_low: f64,
    /// Upper end of the confidence interval.
    pub ci_high: f64,
    /// Confidence level of the interval.
    pub level: f64,
    /// Number of samples.
    pub n: usize,
}

impl McEstimate {
    /// Half-width `z · SE` of the confidence interval.
    ///
    /// ```
    /// let e = sepg_mdp::monte_carlo::summarize(&[1.0, 2.0, 3.0], 0.95).unwrap();
    /// assert!((e.half_width() - (e.ci_high - e.mean)).abs() < 1e-15);
    /// ```
    pub fn half_width(&self) -> f64 {
        0.5 * (self.ci_high - self.ci_low)
    }

    /// Whether `x` lies in the confidence interval.
    ///
    /// ```
    /// let e = sepg_mdp::monte_carlo::summarize(&[1.0, 2.0, 3.0], 0.95).unwrap();
    /// assert!(e.contains(2.0));
    /// ```
    pub fn contains(&self, x: f64) -> bool {
        self.ci_low <= x && x <= self.ci_high
    }
}

/// Mean, standard error and normal confidence interval at `level ∈ (0, 1)` of i.i.d. samples
/// (`n ≥ 2`, all finite). The variance uses a two-pass sum.
///
/// # Formula
/// ```text
/// mean ± Φ⁻¹((1 + level)/2) · √(Σ (x_i − mean)² / (n − 1)) / √n
/// ```
///
/// ```
/// let e = sepg_mdp::monte_carlo::summarize(&[1.0, 2.0, 3.0, 4.0], 0.95).unwrap();
/// assert_eq!(e.mean, 2.5);
/// assert!((e.std_error - (5.0f64 / 3.0 / 4.0).sqrt()).abs() < 1e-15);
/// ```
pub fn summarize(samples: &[f64], level: f64) -> Result<McEstimate, McError> {
    let n = samples.len();
    if n < 2 {
        return Err(McError::TooFewSamples(n));
    }
    if !(level > 0.0 && level < 1.0) {
        return Err(McError::InvalidLevel(level));
    }
    if !samples.iter().all(|x| x.is_finite()) {
        return Err(McError::NonFinite);
    }
    let nf = n as f64;
    let mean = samples.iter().sum::<f64>() / nf;
    let ss: f64 = samples.iter().map(|x| (x - mean) * (x - mean)).sum();
    let std_error = (ss / (nf - 1.0) / nf).sqrt();
    // The upper quantile from the tail probability (1 − level)/2, exact in f64 even for a
    // level within an ulp of 1, where 0.5 + 0.5·level would round to 1 and give z = ∞.
    let z = -Normal::standard().inverse_cdf(0.5 * (1.0 - level));
    let (ci_low, ci_high) = (mean - z * std_error, mean + z * std_error);
    if ![mean, std_error, z, ci_low, ci_high]
        .iter()
        .all(|x| x.is_finite())
    {
        return Err(McError::NonFinite);
    }
    Ok(McEstimate {
        mean,
        std_error,
        ci_low,
        ci_high,
        level,
        n,
    })
}

/// Monte Carlo estimate of `J(θ)` from `n ≥ 2` trajectories of `horizon` steps.
///
/// # Formula
/// ```text
/// Ĵ(θ) = (1/n) Σ_i Σ_t γ^t r_{i,t}
/// ```
///
/// ```
/// use sepg_mdp::{env::LqgEnv, monte_carlo::estimate_j, policy::GaussianPolicy, rng::SeedKey};
/// let pi = GaussianPolicy::scalar(-0.6, -1.0).unwrap();
/// let e = estimate_j(&LqgEnv::thesis(), &pi, 1000, 20, SeedKey::default(), 0.95).unwrap();
/// assert!(e.ci_low < e.mean && e.mean < e.ci_high);
/// ```
pub fn estimate_j<E: Environment + ?Sized>(
    env: &E,
    policy: &GaussianPolicy,
    n: usize,
    horizon: usize,
    key: SeedKey,
    level: f64,
) -> Result<McEstimate, McError> {
    check_args(n, level)?;
    summarize(&rollout_returns(env, policy, n, horizon, key)?, level)
}

/// Monte Carlo estimate of `J(v, −∞)`, the deterministic policy acting the mean of `policy`
/// (Sec 4.3.1).
///
/// # Formula
/// ```text
/// Ĵ(v, −∞) = (1/n) Σ_i Σ_t γ^t r(s_{i,t}, μ(s_{i,t}))
/// ```
///
/// ```
/// use sepg_mdp::{env::LqgEnv, monte_carlo::estimate_j_deterministic, policy::GaussianPolicy, rng::SeedKey};
/// let pi = GaussianPolicy::scalar(-0.6, 0.0).unwrap();
/// let e = estimate_j_deterministic(&LqgEnv::thesis(), &pi, 1000, 20, SeedKey::default(), 0.95).unwrap();
/// assert!(e.mean < 0.0);
/// ```
pub fn estimate_j_deterministic<E: Environment + ?Sized>(
    env: &E,
    policy: &GaussianPolicy,
    n: usize,
    horizon: usize,
    key: SeedKey,
    level: f64,
) -> Result<McEstimate, McError> {
    estimate_j(env, &policy.to_deterministic(), n, horizon, key, level)
}

/// Monte Carlo estimate of `J(θ′) − J(θ)` (`candidate` minus `base`) from paired trajectories
/// with common random numbers (same key, same trajectory index).
///
/// # Formula
/// ```text
/// d_i = G_i(θ′) − G_i(θ),   Δ̂ = (1/n) Σ_i d_i,   CI from the d_i
/// ```
///
/// ```
/// use sepg_mdp::{env::LqgEnv, monte_carlo::estimate_j_difference, policy::GaussianPolicy, rng::SeedKey};
/// let base = GaussianPolicy::scalar(-0.1, -1.0).unwrap();
/// let better = GaussianPolicy::scalar(-0.5, -1.0).unwrap();
/// let d = estimate_j_difference(&LqgEnv::thesis(), &base, &better, 500, 20, SeedKey::default(), 0.99).unwrap();
/// assert!(d.ci_low > 0.0);
/// ```
pub fn estimate_j_difference<E: Environment + ?Sized>(
    env: &E,
    base: &GaussianPolicy,
    candidate: &GaussianPolicy,
    n: usize,
    horizon: usize,
    key: SeedKey,
    level: f64,
) -> Result<McEstimate, McError> {
    check_args(n, level)?;
    if base.feature_dim() != candidate.feature_dim() || base.action_dim() != candidate.action_dim()
    {
        return Err(McError::PolicyShape);
    }
    let g_base = rollout_returns(env, base, n, horizon, key)?;
    let mut d = rollout_returns(env, candidate, n, horizon, key)?;
    for (di, gb) in d.iter_mut().zip(&g_base) {
        *di -= gb;
    }
    summarize(&d, level)
}

fn check_args(n: usize, level: f64) -> Result<(), McError> {
    if n < 2 {
        return Err(McError::TooFewSamples(n));
    }
    if !(level > 0.0 && level < 1.0) {
        return Err(McError::InvalidLevel(level));
    }
    Ok(())
}
