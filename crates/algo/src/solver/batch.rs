//! The adaptive batch size of sampled SEPG (docs/THEOREMS.md "An adaptive batch size",
//! Propositions B and U; future work in the thesis's Chapter 6, after Papini, Pirotta and
//! Restelli, "Adaptive batch size for safe policy gradients", NIPS 2017, which the thesis's
//! Sec 3.5 describes).
//!
//! With a confidence width ε(n) = b/√n of the v-gradient estimate from n trajectories and
//! g = ‖∇_v J‖∞ > 0, the best guarantee of the greedy v-step under the coordinate bound that
//! the certified accounting credits (Theorem 4.2 with the width) is max(0, g − b/√n)²/(4c);
//! per trajectory it is largest at n* = 4b²/g², where the width is g/2. g is unknown:
//! [`next_batch`] plugs in the estimate of the previous iteration and clamps the result to
//! `[n_min, n_max]`. Choosing n from the past keeps the run's union bound (Proposition U).
use thiserror::Error;

use crate::solver::source::Grad;

/// Why an adaptive batch size could not be computed.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum BatchError {
    /// An input outside its domain.
    #[error("{what} = {value} is outside {domain}")]
    OutOfDomain {
        /// Which input.
        what: &'static str,
        /// Its value.
        value: f64,
        /// Its domain, in words.
        domain: &'static str,
    },
}

fn out(what: &'static str, value: f64, domain: &'static str) -> BatchError {
    BatchError::OutOfDomain {
        what,
        value,
        domain,
    }
}

/// The guaranteed improvement per trajectory of the greedy v-step from a block of `n`
/// trajectories whose width is `b/√n`, at the step that maximises the bound (return units per
/// trajectory).
///
/// # Formula
/// ```text
/// G(n) = max(0, g − b/√n)² / (4 c n)
/// ```
/// (the maximum over α of α(g − ε) − cα², Theorem 4.2 with ε = b/√n, divided by n).
///
/// # Errors
/// [`BatchError::OutOfDomain`] unless `g ≥ 0` (|∇_v J|, return units per parameter unit),
/// `b ≥ 0` (same units times √trajectories), `c > 0` (the penalty of Theorem 4.2) and
/// `n ≥ 1` are finite.
///
/// # Examples
/// ```
/// use sepg_algo::solver::batch::improvement_per_trajectory;
/// // g = 2, b = 4, n = 16: width 1, (2 − 1)²/(4·1·16)
/// assert_eq!(improvement_per_trajectory(2.0, 4.0, 1.0, 16.0)?, 1.0 / 64.0);
/// # Ok::<(), sepg_algo::solver::batch::BatchError>(())
/// ```
pub fn improvement_per_trajectory(g: f64, b: f64, c: f64, n: f64) -> Result<f64, BatchError> {
    if !(g.is_finite() && g >= 0.0) {
        return Err(out("g", g, "[0, inf)"));
    }
    if !(b.is_finite() && b >= 0.0) {
        return Err(out("b", b, "[0, inf)"));
    }
    if !(c.is_finite() && c > 0.0) {
        return Err(out("c", c, "(0, inf)"));
    }
    if !(n.is_finite() && n >= 1.0) {
        return Err(out("n", n, "[1, inf)"));
    }
    let slack = (g - b / n.sqrt()).max(0.0);
    Ok(slack * slack / (4.0 * c * n))
}

/// The real batch size n* > 0 that maximises [`improvement_per_trajectory`] over n > 0
/// (trajectories; it does not depend on c). `None` when no batch size guarantees an
/// improvement (`g = 0`).
///
/// # Formula
/// ```text
/// n* = 4 b² / g²      (the width at n* is g/2)
/// ```
///
/// # Errors
/// [`BatchError::OutOfDomain`] unless `g ≥ 0` and `b ≥ 0` are finite.
///
/// # Examples
/// ```
/// use sepg_algo::solver::batch::optimal_batch;
/// assert_eq!(optimal_batch(2.0, 4.0)?, Some(16.0));
/// assert_eq!(optimal_batch(0.0, 4.0)?, None);
/// # Ok::<(), sepg_algo::solver::batch::BatchError>(())
/// ```
pub fn optimal_batch(g: f64, b: f64) -> Result<Option<f64>, BatchError> {
    if !(g.is_finite() && g >= 0.0) {
        return Err(out("g", g, "[0, inf)"));
    }
    if !(b.is_finite() && b >= 0.0) {
        return Err(out("b", b, "[0, inf)"));
    }
    if g == 0.0 {
        return Ok(None);
    }
    let ratio = b / g;
    Ok(Some(4.0 * ratio * ratio))
}

/// The block size of the next iteration under
/// [`BatchRule::Adaptive`](crate::core::options::BatchRule::Adaptive), from the v-gradient
/// estimate `grad` of this iteration's v-block of `n` trajectories: with ĝ = ‖∇̂_v J‖∞ and
/// b̂ = max_i ε_i · √n (the step's width `max_i ε_i` times √n), the integer in
/// `[n_min, n_max]` that maximises max(0, ĝ − b̂/√m)²/m over m (trajectories per block).
///
/// The objective is 0 up to (b̂/ĝ)², rises to its maximum at n* = 4b̂²/ĝ² and falls after,
/// so the best integer in the range is ⌊n*⌋ or ⌈n*⌉ clamped to it. With ĝ = 0 no size
/// guarantees an improvement and the largest, `n_max`, is returned; exact gradients (every
/// ε = 0) give `n_min`.
///
/// # Errors
/// [`BatchError::OutOfDomain`] for `n = 0`, `n_min = 0`, `n_max < n_min`, an empty gradient,
/// or a non-finite or negative component or width.
///
/// # Examples
/// ```
/// use sepg_algo::solver::{batch::next_batch, source::Grad};
/// // ĝ = 2, ε = 1 at n = 16: b̂ = 4, n* = 16
/// let g = Grad { value: vec![-2.0, 0.5], eps: vec![1.0, 0.5] };
/// assert_eq!(next_batch(&g, 16, 2, 1000)?, 16);
/// assert_eq!(next_batch(&g, 16, 20, 1000)?, 20);
/// assert_eq!(next_batch(&g, 16, 2, 10)?, 10);
/// # Ok::<(), sepg_algo::solver::batch::BatchError>(())
/// ```
pub fn next_batch(grad: &Grad, n: usize, n_min: usize, n_max: usize) -> Result<usize, BatchError> {
    if n == 0 {
        return Err(out("n", 0.0, "[1, inf)"));
    }
    if n_min == 0 {
        return Err(out("n_min", 0.0, "[1, n_max]"));
    }
    if n_max < n_min {
        return Err(out("n_max", n_max as f64, "[n_min, inf)"));
    }
    if grad.value.is_empty() || grad.value.len() != grad.eps.len() {
        return Err(out(
            "gradient length",
            grad.value.len() as f64,
            "= widths, ≥ 1",
        ));
    }
    let mut g = 0.0f64;
    let mut eps = 0.0f64;
    for (&x, &e) in grad.value.iter().zip(&grad.eps) {
        if !x.is_finite() {
            return Err(out("gradient component", x, "finite"));
        }
        if !(e.is_finite() && e >= 0.0) {
            return Err(out("width", e, "[0, inf)"));
        }
        g = g.max(x.abs());
        eps = eps.max(e);
    }
    let b = eps * (n as f64).sqrt();
    if b.is_infinite() {
        // a width beyond every f64 gradient: no batch in range guarantees anything
        return Ok(n_max);
    }
    let Some(star) = optimal_batch(g, b)? else {
        return Ok(n_max);
    };
    let clamp = |m: f64| {
        if m <= n_min as f64 {
            n_min
        } else if m >= n_max as f64 {
            n_max
        } else {
            // n_min < m < n_max, so m is an integer within the range
            m as usize
        }
    };
    let (lo, hi) = (clamp(star.floor()), clamp(star.ceil()));
    let per = |m: usize| improvement_per_trajectory(g, b, 1.0, m as f64);
    Ok(if per(hi)? > per(lo)? { hi } else { lo })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inputs_out_of_their_domains_are_refused() {
        let g = Grad {
            value: vec![1.0],
            eps: vec![1.0],
        };
        assert!(next_batch(&g, 0, 2, 10).is_err());
        assert!(next_batch(&g, 10, 0, 10).is_err());
        assert!(next_batch(&g, 10, 11, 10).is_err());
        let nan = Grad {
            value: vec![f64::NAN],
            eps: vec![1.0],
        };
        assert!(next_batch(&nan, 10, 2, 10).is_err());
        let neg = Grad {
            value: vec![1.0],
            eps: vec![-1.0],
        };
        assert!(next_batch(&neg, 10, 2, 10).is_err());
        let empty = Grad {
            value: vec![],
            eps: vec![],
        };
        assert!(next_batch(&empty, 10, 2, 10).is_err());
        assert!(improvement_per_trajectory(1.0, 1.0, 0.0, 1.0).is_err());
        assert!(improvement_per_trajectory(1.0, 1.0, 1.0, 0.5).is_err());
        assert!(optimal_batch(f64::INFINITY, 1.0).is_err());
    }

    #[test]
    fn zero_gradient_takes_the_largest_and_exact_gradients_the_smallest_batch() {
        let zero = Grad {
            value: vec![0.0, 0.0],
            eps: vec![3.0, 1.0],
        };
        assert_eq!(next_batch(&zero, 50, 7, 900).expect("valid"), 900);
        let exact = Grad::exact(vec![266.0]);
        assert_eq!(next_batch(&exact, 50, 7, 900).expect("valid"), 7);
    }
}
