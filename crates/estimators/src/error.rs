//! The error type of the estimators and confidence widths.

use thiserror::Error;

use crate::quantile::QuantileError;

/// Why an estimate or a confidence width could not be computed.
///
/// Every public function of this crate validates its input and returns one of these instead
/// of panicking or producing NaN.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
#[non_exhaustive]
pub enum EstimatorError {
    /// The batch holds no trajectory or no time step.
    #[error("the batch is empty (no trajectory or zero horizon)")]
    EmptyBatch,
    /// Fewer trajectories than the estimator needs (2 for a sample variance, 4 for the
    /// cross-fitted surrogate gradient).
    #[error("{n} trajectories given, at least {min} needed")]
    TooFewTrajectories {
        /// Number of trajectories in the batch.
        n: usize,
        /// Minimum number needed.
        min: usize,
    },
    /// A buffer or dimension does not have the size the batch layout requires.
    #[error("{what}: expected size {expected}, found {found}")]
    DimensionMismatch {
        /// Which buffer or dimension.
        what: &'static str,
        /// The size it must have.
        expected: usize,
        /// The size it has.
        found: usize,
    },
    /// The batch holds a NaN or an infinity among the values an estimator uses, or an
    /// intermediate result overflowed (detected on the estimate, never returned as NaN).
    #[error("non-finite value in {what}")]
    NonFinite {
        /// Where the non-finite value was found.
        what: &'static str,
    },
    /// A policy standard deviation `σ_j` is not finite and positive.
    #[error("sigma[{index}] = {value} is not finite and positive")]
    InvalidSigma {
        /// Action dimension `j`.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// The confidence level `δ` is not in `(0, 1)`.
    #[error("delta = {delta} is not in (0, 1)")]
    InvalidDelta {
        /// The offending value.
        delta: f64,
    },
    /// A range bound (Hoeffding, empirical Bernstein) is not finite and positive.
    #[error("range = {range} is not finite and positive")]
    InvalidRange {
        /// The offending value.
        range: f64,
    },
    /// A constant of the surrogate objective (`c`, `∂c/∂σ`) is not valid.
    #[error("{what} = {value} is not valid (c must be finite and positive, dc/dsigma finite)")]
    InvalidConstant {
        /// Which constant.
        what: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A constant of the task (`R`, `M_φ`, `γ`, the horizon `H`) is outside its domain: `R`
    /// and `M_φ` finite and positive, `γ ∈ [0, 1)`, `H ≥ 1`.
    #[error("task constant {what} = {value} is outside its domain")]
    InvalidTaskConstant {
        /// Which constant.
        what: &'static str,
        /// The offending value.
        value: f64,
    },
    /// The confidence width needs the per-trajectory samples (e.g. their third moment), not
    /// only the variance: use the methods of [`crate::Estimate`].
    #[error("the {method} width needs the samples: use Estimate::widths_into")]
    NeedsSamples {
        /// The width method.
        method: &'static str,
    },
    /// A closed form of `sepg_bounds` (e.g. `c(σ)`) could not be evaluated.
    #[error(transparent)]
    Bounds(#[from] sepg_bounds::BoundsError),
    /// The Student-t quantile could not be evaluated.
    #[error(transparent)]
    Quantile(#[from] QuantileError),
}
