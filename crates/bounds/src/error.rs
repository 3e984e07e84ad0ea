//! The error type shared by every function of the crate.
//!
//! Bad input (a σ that is not positive, a γ outside `[0, 1)`, a non-finite value, an empty or
//! mismatched gradient vector, ...) and results that overflow `f64` are reported through
//! [`BoundsError`]. An improvement requirement that no step can meet is *not* an error: it is the
//! [`StepOutcome::Infeasible`](crate::outcome::StepOutcome::Infeasible) outcome.

use thiserror::Error;

/// Why a bound could not be computed.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
#[non_exhaustive]
pub enum BoundsError {
    /// An input was NaN or infinite.
    #[error("{name} must be finite, got {value}")]
    NonFinite {
        /// Name of the offending input.
        name: &'static str,
        /// The value received.
        value: f64,
    },
    /// An input was finite but outside its domain (e.g. σ ≤ 0, γ ∉ [0, 1), δ ∉ (0, 1)).
    #[error("{name} = {value} is outside its domain {domain}")]
    OutOfDomain {
        /// Name of the offending input.
        name: &'static str,
        /// The value received.
        value: f64,
        /// The domain the value must belong to, in words.
        domain: &'static str,
    },
    /// A gradient (or other) vector was empty.
    #[error("{name} must not be empty")]
    EmptyVector {
        /// Name of the offending input.
        name: &'static str,
    },
    /// Two vectors that must have the same length did not.
    #[error("{left} has length {left_len} but {right} has length {right_len}")]
    LengthMismatch {
        /// Name of the first vector.
        left: &'static str,
        /// Its length.
        left_len: usize,
        /// Name of the second vector.
        right: &'static str,
        /// Its length.
        right_len: usize,
    },
    /// The horizon H was zero.
    #[error("the horizon H must be at least 1")]
    ZeroHorizon,
    /// A result overflowed to ±∞ (or is not representable, e.g. a batch size beyond `u64`).
    #[error("{quantity} overflows the floating-point range")]
    Overflow {
        /// The quantity that overflowed.
        quantity: &'static str,
    },
    /// A target-policy operation was requested on a budget that tracks no target policy.
    #[error("this budget tracks no separate target policy")]
    NoTargetPolicy,
    /// A step along a direction with several non-zero entries was asked of the thesis's
    /// constants, whose c (Theorems 3.14, 4.2) is proven for the greedy coordinate only
    /// (docs/THEOREMS.md, "A step along any direction").
    #[error("the thesis's c is proven for a coordinate direction only: use the tight constants")]
    UnprovenDirection,
}

/// Returns `value` if it is finite, otherwise [`BoundsError::NonFinite`] naming the input
/// `name`. The validation every function of the crate (and of the crates built on it) applies
/// to its `f64` inputs.
#[inline]
pub fn finite(name: &'static str, value: f64) -> Result<f64, BoundsError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(BoundsError::NonFinite { name, value })
    }
}

/// Returns `value` if it is finite and strictly positive, otherwise
/// [`BoundsError::NonFinite`] or [`BoundsError::OutOfDomain`] (domain (0, +∞)).
#[inline]
pub fn positive(name: &'static str, value: f64) -> Result<f64, BoundsError> {
    finite(name, value)?;
    if value > 0.0 {
        Ok(value)
    } else {
        Err(BoundsError::OutOfDomain {
            name,
            value,
            domain: "(0, +inf)",
        })
    }
}

/// Returns `value` if it is finite and non-negative, otherwise [`BoundsError::NonFinite`]
/// or [`BoundsError::OutOfDomain`] (domain [0, +∞)).
#[inline]
pub fn non_negative(name: &'static str, value: f64) -> Result<f64, BoundsError> {
    finite(name, value)?;
    if value >= 0.0 {
        Ok(value)
    } else {
        Err(BoundsError::OutOfDomain {
            name,
            value,
            domain: "[0, +inf)",
        })
    }
}

/// Returns `value` if it lies in the closed unit interval.
pub(crate) fn unit_closed(name: &'static str, value: f64) -> Result<f64, BoundsError> {
    finite(name, value)?;
    if (0.0..=1.0).contains(&value) {
        Ok(value)
    } else {
        Err(BoundsError::OutOfDomain {
            name,
            value,
            domain: "[0, 1]",
        })
    }
}

/// Returns `value` if it lies in the open unit interval.
pub(crate) fn unit_open(name: &'static str, value: f64) -> Result<f64, BoundsError> {
    finite(name, value)?;
    if value > 0.0 && value < 1.0 {
        Ok(value)
    } else {
        Err(BoundsError::OutOfDomain {
            name,
            value,
            domain: "(0, 1)",
        })
    }
}

/// Checks that a vector is non-empty ([`BoundsError::EmptyVector`]) and all its entries are
/// finite ([`BoundsError::NonFinite`]).
#[inline]
pub fn finite_vector(name: &'static str, values: &[f64]) -> Result<(), BoundsError> {
    if values.is_empty() {
        return Err(BoundsError::EmptyVector { name });
    }
    for &v in values {
        finite(name, v)?;
    }
    Ok(())
}

/// Checks that two vectors have the same length.
pub(crate) fn same_length(
    left: &'static str,
    left_values: &[f64],
    right: &'static str,
    right_values: &[f64],
) -> Result<(), BoundsError> {
    if left_values.len() == right_values.len() {
        Ok(())
    } else {
        Err(BoundsError::LengthMismatch {
            left,
            left_len: left_values.len(),
            right,
            right_len: right_values.len(),
        })
    }
}

/// Returns `value` if it is finite, otherwise [`BoundsError::Overflow`] naming `quantity`.
#[inline]
pub fn no_overflow(quantity: &'static str, value: f64) -> Result<f64, BoundsError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(BoundsError::Overflow { quantity })
    }
}

/// ‖x‖∞ of a validated vector (overflow-free: a maximum of finite magnitudes).
#[inline]
pub fn inf_norm(values: &[f64]) -> f64 {
    values.iter().fold(0.0_f64, |m, v| m.max(v.abs()))
}
