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

#![deny(missing_docs)]

pub mod core;
pub mod solver;
