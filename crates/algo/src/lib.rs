//! Safely-Exploring Policy Gradient (SEPG, Algorithm 4.3 of the thesis) and the comparison
//! algorithms of Chapter 5, organised as a solver/executor pair.
//!
//! - [`core`] holds what every algorithm shares: the validated configuration
//!   ([`core::config::SepgConfig`] → [`core::config::CheckedConfig`]), the per-iteration
//!   [`core::record::Record`], the resumable [`core::state::State`] (checkpoint), the
//!   [`core::executor::Solver`] trait, the [`core::executor::Executor`] and its
//!   [`core::executor::Observer`]s.
//! - [`solver`] holds the algorithms: SEPG with every safety requirement of Table 4.1, SEPG with
//!   the naive variance update (4.12), G(PO)MDP with constant step or Adam, and the adaptive
//!   step of Pirotta et al. (Corollary 3.11, Theorem 3.12).
//!
//! The vocabulary a user needs is re-exported here: a run is a [`SepgConfig`] with its
//! [`SepgOptions`], checked into a [`CheckedConfig`], solved by a [`PolicySolver`] that an
//! [`Executor`] drives, producing one [`Record`] per iteration and the [`Statement`] the run can
//! make; a [`BatchCollector`] feeds batches collected outside the crate.

#![deny(missing_docs)]

pub mod core;
pub mod solver;

pub use core::config::{Algorithm, CheckedConfig, GradientMode, Requirement, SepgConfig};
pub use core::defaults::*;
pub use core::error::{ConfigError, RunError};
pub use core::executor::{Collect, Executor, Observer, Solver};
pub use core::names::{AlgoName, ConstantsName, RequirementName, UnknownName};
pub use core::options::{
    Accounting, BatchRule, ConstantsFamily, Schedule, SepgOptions, VDirection, WDirection, WStep,
};
pub use core::record::Record;
pub use core::state::State;
pub use core::statement::{Statement, StatementKind};
pub use solver::PolicySolver;
pub use solver::sampled::{BatchCollector, BatchRequest};
