//! Exact binomial confidence bounds (Clopper & Pearson, 1934).

use statrs::function::beta::beta_reg;
use thiserror::Error;

/// Errors of the statistical helpers.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum StatsError {
    /// `trials` was zero or `successes > trials`.
    #[error("invalid counts: {successes} successes out of {trials} trials")]
    Counts {
        /// Successes.
        successes: u64,
        /// Trials.
        trials: u64,
    },
    /// The confidence level was not in `(0, 1)`.
    #[error("confidence {0} is outside (0, 1)")]
    Confidence(f64),
}

fn validate(successes: u64, trials: u64, confidence: f64) -> Result<(), StatsError> {
    if trials == 0 || successes > trials {
        return Err(StatsError::Counts { successes, trials });
    }
    if !(confidence > 0.0 && confidence < 1.0) {
        return Err(StatsError::Confidence(confidence));
    }
    Ok(())
}

/// Quantile of the Beta(a, b) distribution: the `x ∈ [0, 1]` with `I_x(a, b) = p`, found by
/// bisection on the regularised incomplete beta function (monotone in x), to full double
/// precision (bisection stops when the bracket no longer shrinks).
fn beta_quantile(p: f64, a: f64, b: f64) -> f64 {
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    loop {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            return mid;
        }
        if beta_reg(a, b, mid) < p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
}

/// One-sided exact (Clopper–Pearson) upper confidence bound on a binomial proportion: the
/// largest `p` such that observing at most `successes` in `trials` has probability ≥ 1 − level.
///
/// # Formula
/// ```text
/// p_U = Beta⁻¹(confidence; k + 1, n − k)   for k < n,     p_U = 1 for k = n
/// (k = 0: p_U = 1 − (1 − confidence)^{1/n})
/// ```
///
/// # Errors
/// [`StatsError`] for `trials = 0`, `successes > trials` or `confidence ∉ (0, 1)`.
///
/// # Example
/// ```
/// use sepg_verification::stats::clopper_pearson_upper;
/// // Zero failures in 100 trials: p < 1 − 0.05^(1/100) ≈ 0.0295 at 95%.
/// let p = clopper_pearson_upper(0, 100, 0.95).unwrap();
/// assert!((p - (1.0 - 0.05f64.powf(0.01))).abs() < 1e-12);
/// ```
pub fn clopper_pearson_upper(
    successes: u64,
    trials: u64,
    confidence: f64,
) -> Result<f64, StatsError> {
    validate(successes, trials, confidence)?;
    if successes == trials {
        return Ok(1.0);
    }
    Ok(beta_quantile(
        confidence,
        successes as f64 + 1.0,
        (trials - successes) as f64,
    ))
}

/// One-sided exact (Clopper–Pearson) lower confidence bound on a binomial proportion.
///
/// # Formula
/// ```text
/// p_L = Beta⁻¹(1 − confidence; k, n − k + 1)   for k > 0,     p_L = 0 for k = 0
/// ```
///
/// # Errors
/// [`StatsError`] for `trials = 0`, `successes > trials` or `confidence ∉ (0, 1)`.
///
/// # Example
/// ```
/// use sepg_verification::stats::clopper_pearson_lower;
/// // All of 10 trials succeed: p > 0.05^(1/10) ≈ 0.741 at 95%.
/// let p = clopper_pearson_lower(10, 10, 0.95).unwrap();
/// assert!((p - 0.05f64.powf(0.1)).abs() < 1e-12);
/// ```
pub fn clopper_pearson_lower(
    successes: u64,
    trials: u64,
    confidence: f64,
) -> Result<f64, StatsError> {
    validate(successes, trials, confidence)?;
    if successes == 0 {
        return Ok(0.0);
    }
    Ok(beta_quantile(
        1.0 - confidence,
        successes as f64,
        (trials - successes + 1) as f64,
    ))
}
