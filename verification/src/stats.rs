//! The statistical tests of the sampled checks: exact binomial confidence bounds (Clopper &
//! Pearson, 1934), shared with the audit of run folders (they live in
//! [`sepg_estimators::binomial`] and are re-exported here), the family-wise binomial test of
//! claimed violation rates and the z-test of unbiasedness claims.

pub use sepg_estimators::binomial::{StatsError, clopper_pearson_lower, clopper_pearson_upper};
use sepg_estimators::normal_quantile;

use crate::check::{Evaluation, Figure, Outcome, fmt_f64};

/// One binomial test: `violations` out of `trials`, claimed rate at most `allowed`.
pub(crate) struct Freq {
    pub(crate) name: String,
    pub(crate) violations: u64,
    pub(crate) trials: u64,
    pub(crate) allowed: f64,
}

/// Clopper–Pearson test of every [`Freq`] at family-wise level `family_alpha` (Bonferroni):
/// a claim is rejected when the one-sided lower confidence bound on its violation rate exceeds
/// the allowed rate.
pub(crate) fn frequency_outcome(tests: &[Freq], family_alpha: f64) -> Evaluation {
    let confidence = 1.0 - family_alpha / tests.len().max(1) as f64;
    let mut figures = Vec::new();
    let mut worst: Option<(f64, String)> = None;
    let (mut margin, mut relative) = (f64::INFINITY, f64::INFINITY);
    let mut trials = 0;
    for t in tests.iter().filter(|t| t.trials > 0) {
        trials += t.trials;
        let rate = t.violations as f64 / t.trials as f64;
        let (Ok(lo), Ok(hi)) = (
            clopper_pearson_lower(t.violations, t.trials, confidence),
            clopper_pearson_upper(t.violations, t.trials, 0.95),
        ) else {
            continue;
        };
        figures.push(Figure {
            name: t.name.clone(),
            value: format!(
                "{}/{} violations, rate {}, 95% upper bound {}, allowed {}",
                t.violations,
                t.trials,
                fmt_f64(rate),
                fmt_f64(hi),
                fmt_f64(t.allowed)
            ),
        });
        if lo > t.allowed {
            let amount = rate - t.allowed;
            if worst.as_ref().is_none_or(|(a, _)| amount > *a) {
                worst = Some((
                    amount,
                    format!(
                        "{}: {}/{} violations (rate {}, one-sided {} lower bound {}) > allowed {}",
                        t.name,
                        t.violations,
                        t.trials,
                        fmt_f64(rate),
                        fmt_f64(confidence),
                        fmt_f64(lo),
                        fmt_f64(t.allowed)
                    ),
                ));
            }
        }
        margin = margin.min(t.allowed - rate);
        relative = relative.min((t.allowed - rate) / t.allowed);
    }
    let outcome = match worst {
        Some((amount, counterexample)) => Outcome::Violated {
            counterexample,
            amount,
        },
        None if trials == 0 => Outcome::Inconclusive {
            reason: "no informative trial".into(),
        },
        None => Outcome::HoldsWithMargin {
            margin,
            relative_margin: relative,
        },
    };
    Evaluation {
        outcome,
        cases: trials,
        figures,
    }
}

/// One z-test of an unbiasedness claim: the mean of `samples` (independent batch estimates)
/// against the exact value.
pub(crate) struct ZTest {
    pub(crate) name: String,
    pub(crate) samples: Vec<f64>,
    pub(crate) truth: f64,
}

/// Two-sided z-test of every [`ZTest`] at family-wise level `family_alpha` (Bonferroni): a
/// claim is rejected when its |z| exceeds the critical value.
pub(crate) fn z_outcome(tests: &[ZTest], family_alpha: f64) -> Evaluation {
    let m = tests.len().max(1) as f64;
    let z_crit = normal_quantile(1.0 - family_alpha / (2.0 * m)).unwrap_or(f64::INFINITY);
    let mut figures = vec![Figure {
        name: "critical |z| (two-sided, Bonferroni)".into(),
        value: fmt_f64(z_crit),
    }];
    let mut max_error = 0.0f64;
    let mut worst: Option<(f64, String)> = None;
    let mut cases = 0;
    for t in tests {
        let n = t.samples.len() as f64;
        cases += t.samples.len() as u64;
        let mean = t.samples.iter().sum::<f64>() / n;
        let var = t.samples.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
        let se = (var / n).sqrt();
        let z = (mean - t.truth) / se;
        max_error = max_error.max((mean - t.truth).abs());
        figures.push(Figure {
            name: t.name.clone(),
            value: format!(
                "mean {} ± {} (s.e.), exact {}, z = {}",
                fmt_f64(mean),
                fmt_f64(se),
                fmt_f64(t.truth),
                fmt_f64(z)
            ),
        });
        let rejected = z.is_nan() || z.abs() > z_crit;
        if rejected && worst.as_ref().is_none_or(|(a, _)| z.abs() > *a) {
            worst = Some((
                z.abs(),
                format!(
                    "{}: mean {} vs exact {} (z = {})",
                    t.name,
                    fmt_f64(mean),
                    fmt_f64(t.truth),
                    fmt_f64(z)
                ),
            ));
        }
    }
    let outcome = match worst {
        Some((z, counterexample)) => Outcome::Violated {
            counterexample,
            amount: z - z_crit,
        },
        None => Outcome::Holds { max_error },
    };
    Evaluation {
        outcome,
        cases,
        figures,
    }
}
