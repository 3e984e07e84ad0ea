//! Exact binomial tail probabilities and confidence bounds (Clopper & Pearson, 1934), used
//! to test an observed failure count against the failure rate a high-probability guarantee
//! allows (the per-step probability δ of Theorems 4.7–4.9).

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
    /// A probability outside `[0, 1]`.
    #[error("probability {0} is outside [0, 1]")]
    Probability(f64),
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

/// Upper tail P(X ≥ k) of X ~ Binomial(n, p): the one-sided p-value of observing `k` or more
/// failures in `n` independent trials whose failure probability is at most `p` (the tail is
/// increasing in p, so the bound p gives the largest p-value). Rejecting when it is below α
/// is the exact binomial test at level α, equivalent to the one-sided Clopper–Pearson lower
/// bound at confidence 1 − α exceeding `p`.
///
/// # Formula
/// ```text
/// P(X ≥ k) = I_p(k, n − k + 1)   for 1 ≤ k ≤ n,     P(X ≥ 0) = 1
/// ```
/// (I the regularised incomplete beta function.)
///
/// # Errors
/// [`StatsError`] for `trials = 0`, `failures > trials` or `p ∉ [0, 1]`.
///
/// # Example
/// ```
/// use sepg_estimators::binomial::upper_tail;
/// // n = 2, p = 0.5: P(X ≥ 1) = 1 − 0.25.
/// assert!((upper_tail(1, 2, 0.5).unwrap() - 0.75).abs() < 1e-15);
/// ```
pub fn upper_tail(failures: u64, trials: u64, p: f64) -> Result<f64, StatsError> {
    if trials == 0 || failures > trials {
        return Err(StatsError::Counts {
            successes: failures,
            trials,
        });
    }
    if !(0.0..=1.0).contains(&p) {
        return Err(StatsError::Probability(p));
    }
    if failures == 0 {
        return Ok(1.0);
    }
    Ok(beta_reg(failures as f64, (trials - failures + 1) as f64, p))
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
/// use sepg_estimators::binomial::clopper_pearson_upper;
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
/// use sepg_estimators::binomial::clopper_pearson_lower;
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

#[cfg(test)]
mod tests {
    use super::*;

    /// P(X ≥ k) summed term by term from the binomial probabilities C(n, i) pⁱ (1 − p)ⁿ⁻ⁱ,
    /// independently of the incomplete beta function.
    fn tail_by_sum(k: u64, n: u64, p: f64) -> f64 {
        let mut total = 0.0;
        let mut choose = 1.0;
        for i in 0..=n {
            if i > 0 {
                choose *= (n - i + 1) as f64 / i as f64;
            }
            if i >= k {
                total += choose * p.powi(i as i32) * (1.0 - p).powi((n - i) as i32);
            }
        }
        total
    }

    #[test]
    fn upper_tail_matches_the_sum_of_binomial_probabilities() {
        for &(n, p) in &[(1u64, 0.3), (10, 0.2), (40, 0.05), (100, 0.2), (60, 0.9)] {
            for k in 0..=n {
                let tail = upper_tail(k, n, p).expect("valid");
                let sum = tail_by_sum(k, n, p);
                assert!(
                    (tail - sum).abs() <= 1e-12 * sum.max(1e-300) + 1e-300,
                    "n = {n}, p = {p}, k = {k}: {tail} vs {sum}"
                );
            }
        }
    }

    #[test]
    fn upper_tail_rejects_bad_counts_and_probabilities() {
        assert!(upper_tail(0, 0, 0.5).is_err());
        assert!(upper_tail(3, 2, 0.5).is_err());
        assert!(upper_tail(1, 2, -0.1).is_err());
        assert!(upper_tail(1, 2, f64::NAN).is_err());
        assert_eq!(upper_tail(2, 2, 0.0), Ok(0.0));
        assert_eq!(upper_tail(2, 2, 1.0), Ok(1.0));
    }
}
