//! Typed errors of configuration validation and of a run.
use thiserror::Error;

/// Why a [`SepgConfig`](crate::core::config::SepgConfig) was rejected by
/// [`check`](crate::core::config::SepgConfig::check), before any trajectory is run.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum ConfigError {
    /// The split coefficient ν of LB-I or SIM-ν (eqs. 4.13–4.14, Sec 5.1.3) is not in `[0, 1]`.
    #[error("split coefficient nu = {nu} is not in [0, 1]")]
    NuOutOfRange {
        /// The rejected value.
        nu: f64,
    },
    /// `N` trajectories cannot be split among the blocks that run: each needs at least
    /// `per_block` (2, so that sample variances and confidence widths exist; 4 for a block
    /// of SEPG, whose ∇_w L is cross-fitted on two halves), so N ≥ `blocks · per_block`.
    #[error(
        "N = {n} trajectories cannot give {blocks} block(s) at least {per_block} trajectories each \
         (this algorithm needs N >= {})",
        blocks * per_block
    )]
    TooFewTrajectories {
        /// Trajectories per iteration requested.
        n: usize,
        /// Blocks that run in one iteration.
        blocks: usize,
        /// Trajectories each block needs at least.
        per_block: usize,
    },
    /// An initial standard deviation σ⁰ is not a finite positive number.
    #[error("initial standard deviation sigma0[{index}] = {value} is not finite and positive")]
    InvalidSigma {
        /// Action dimension of the offending entry.
        index: usize,
        /// The rejected value.
        value: f64,
    },
    /// The confidence parameter δ of the sampled mode is not in `(0, 1)`.
    #[error("confidence parameter delta = {delta} is not in (0, 1)")]
    InvalidDelta {
        /// The rejected value.
        delta: f64,
    },
    /// The run was asked for zero iterations.
    #[error("the number of iterations must be positive")]
    ZeroIterations,
    /// The horizon `H` is zero.
    #[error("the horizon H must be positive")]
    ZeroHorizon,
    /// The initial budget B⁰ is negative or not finite.
    #[error("initial budget B0 = {value} is not finite and non-negative")]
    InvalidBudget {
        /// The rejected value.
        value: f64,
    },
    /// An initial mean parameter is not finite.
    #[error("initial mean parameter v0[{index}] = {value} is not finite")]
    InvalidMean {
        /// Index of the offending entry.
        index: usize,
        /// The rejected value.
        value: f64,
    },
    /// A parameter vector does not have the length the environment and policy require.
    #[error("{what} has length {got}, expected {expected}")]
    DimensionMismatch {
        /// Which vector.
        what: &'static str,
        /// Length required by the environment's action and feature dimensions.
        expected: usize,
        /// Length given.
        got: usize,
    },
    /// A step size, learning rate or Adam coefficient is out of its domain.
    #[error("hyper-parameter {name} = {value} is out of its domain ({domain})")]
    InvalidHyperParameter {
        /// Name of the hyper-parameter.
        name: &'static str,
        /// The rejected value.
        value: f64,
        /// The allowed domain in words.
        domain: &'static str,
    },
    /// The exact gradient mode needs an exact oracle, which this environment does not have.
    #[error("exact gradients are not available for environment {env}")]
    ExactUnsupported {
        /// Name of the environment.
        env: String,
    },
    /// The environment could not be built from its specification.
    #[error("invalid environment: {0}")]
    Environment(String),
    /// An option of [`SepgOptions`](crate::core::options::SepgOptions) does not apply to the
    /// chosen algorithm or environment.
    #[error("option {option} is not supported here: {reason}")]
    UnsupportedOption {
        /// The option.
        option: &'static str,
        /// Why, in words.
        reason: &'static str,
    },
}

/// Why an iteration could not be carried out.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum RunError {
    /// A closed-form bound rejected its input.
    #[error("bound computation failed: {0}")]
    Bounds(String),
    /// Rollouts or the exact oracle failed.
    #[error("environment or oracle failed: {0}")]
    Mdp(String),
    /// A gradient estimator failed.
    #[error("estimator failed: {0}")]
    Estimator(String),
    /// A quantity of the iteration became non-finite (the run is stopped instead of
    /// propagating NaN).
    #[error("{what} became non-finite at iteration {iteration}")]
    NonFinite {
        /// Which quantity.
        what: &'static str,
        /// Iteration at which it happened.
        iteration: u64,
    },
    /// A checkpoint does not fit the configuration it is resumed with.
    #[error("checkpoint does not match the configuration: {0}")]
    Checkpoint(String),
    /// An observed reward or feature contradicts the declared constants and the run stops on
    /// a contradiction (option `on-contradiction`, docs/RELIABILITY.md).
    #[error(
        "constants contradicted: {0}; the bounds need true constants (raise the constant, or \
         on-contradiction = continue runs on without a guarantee)"
    )]
    ConstantsContradicted(Box<crate::core::check::Offence>),
}
