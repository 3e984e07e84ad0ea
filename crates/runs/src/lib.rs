//! # sepg-runs — run folders, sweeps, audits and the reproduction of the thesis experiments
//!
//! The layers call downward only:
//!
//! ```text
//! report, figure        Table 5.1 and Figures 5.1–5.4, plots of run and sweep folders
//!   ↓
//! reproduce             the experiments of thesis Chapter 5 as sweeps
//!   ↓
//! sweep, merge          products of runs, shards, merging shard folders
//!   ↓
//! run                   one run: execution, checkpoints, resume, stop flag, observer
//!   ↓
//! spec, folder          options and their resolution; the files of a run folder
//! ```
//!
//! [`estimate`] (streamed Monte Carlo estimates of one policy), [`exact`] (exact values of
//! an LQG preset), [`replay`] (a Mountain Car trajectory) and [`bounds_report`] (the
//! closed-form quantities of the bounds at given constants and gradients) stand alone.
//! [`setup`] sets up a new run from a configuration file and options, for the command line
//! and the Python package alike.
//!
//! [`audit`] sits beside them: it reads a run folder ([`folder`], [`spec`]) and re-checks its
//! log against the exact oracles of `sepg-mdp`. Every fallible operation returns an
//! [`Error`]; nothing here prints.

#![deny(missing_docs)]

pub mod audit;
pub mod bounds_report;
pub mod error;
pub mod estimate;
pub mod exact;
pub mod exact_report;
pub mod figure;
pub mod figure_flags;
pub mod folder;
pub mod logcheck;
pub mod merge;
pub mod replay;
pub mod report;
pub mod reproduce;
pub mod run;
pub mod setup;
pub mod spec;
pub mod sweep;

pub use error::{Error, Message, Result, Source};
pub use run::{RunObserver, RunOptions, Silent, resume, start};
pub use spec::{Resolved, RunSpec};
pub use sweep::{SweepOptions, SweepSpec};
