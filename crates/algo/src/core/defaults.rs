//! Every default of a run, defined once: the library ([`SepgConfig::new`],
//! [`SepgOptions::default`]), the run options of `sepg-runs` and the Python package read
//! them from here (docs/CONVENTIONS.md §6 and the protocol of the thesis's Sec 5.1).
//!
//! [`SepgConfig::new`]: crate::core::config::SepgConfig::new
//! [`SepgOptions::default`]: crate::core::options::SepgOptions::default

use crate::core::names::{AlgoName, ConstantsName, RequirementName};

/// Confidence δ ∈ (0, 1) of the sampled gradients (Sec 5.1).
pub const DEFAULT_DELTA: f64 = 0.2;

/// Split ν ∈ [0, 1] of LB-I (share of C for the w-update) and SIM-ν (share of B for the
/// v-update), Table 4.1.
pub const DEFAULT_NU: f64 = 0.5;

/// Initial mean parameter v⁰ of every component (Sec 5.1).
pub const DEFAULT_V0: f64 = -0.1;

/// Initial standard deviation σ⁰ > 0 of every action component (Sec 5.1).
pub const DEFAULT_SIGMA0: f64 = 1.0;

/// Initial budget B⁰ ≥ 0 of the LQG presets and of a library configuration
/// (docs/CONVENTIONS.md §5).
pub const DEFAULT_BUDGET0: f64 = 0.0;

/// Trajectories per iteration N (Sec 5.1).
pub const DEFAULT_N_TRAJECTORIES: usize = 100;

/// Iterations of a run (Sec 5.1).
pub const DEFAULT_ITERATIONS: u64 = 10_000;

/// Seed of a run.
pub const DEFAULT_SEED: u64 = 0;

/// Trajectories N₀ of the reference batch that estimates J(θ⁰).
pub const DEFAULT_REFERENCE_BATCH: usize = 1000;

/// Multiplier of the Student-t quantile of the widths (Sec 4.5).
pub const DEFAULT_QUANTILE_FACTOR: f64 = 1.0;

/// Clipping threshold of the metagradient's last term.
pub const DEFAULT_METAGRADIENT_CLIP: f64 = 100.0;

/// First-moment decay β₁ ∈ [0, 1) of Adam (G(PO)MDP with Adam and safe Adam).
pub const DEFAULT_ADAM_BETA1: f64 = 0.9;

/// Second-moment decay β₂ ∈ [0, 1) of Adam.
pub const DEFAULT_ADAM_BETA2: f64 = 0.999;

/// Denominator offset ε > 0 of Adam, in units of the gradient.
pub const DEFAULT_ADAM_EPS: f64 = 1e-8;

/// The family of constants of [`SepgOptions::default`](crate::core::options::SepgOptions::default):
/// the thesis's. The library keeps the thesis's constants so that a configuration built in
/// code states the bounds of the thesis unless it asks for more; a run resolved from options
/// takes [`RUN_CONSTANTS`] instead.
pub const LIBRARY_CONSTANTS: ConstantsName = ConstantsName::Thesis;

/// The family of constants a run takes when its options name none: the tight constants of
/// Theorem T (docs/THEOREMS.md, "Tight constants"), which are smaller and equally proven. It
/// differs from [`LIBRARY_CONSTANTS`] because a run writes its family into its configuration,
/// while a configuration built in code keeps the thesis's unless told; a configuration file
/// written before the option existed is read with [`ConstantsName::legacy`].
pub const RUN_CONSTANTS: ConstantsName = ConstantsName::Tight;

/// The algorithm of a run whose options name none: SEPG-ZV (Table 4.1).
pub const DEFAULT_ALGO: AlgoName = AlgoName::SepgZv;

/// The requirement of `sepg-naive-w` and of a Python trainer when none is named: ZV.
pub const DEFAULT_REQUIREMENT: RequirementName = RequirementName::Zv;
