//! Shared helpers for the sepg criterion benchmarks.
//!
//! - [`fused`]: fused-loop references, written without the engine's abstractions, against
//!   which the engine's throughput is reported as a ratio measured in the same run.
#![deny(missing_docs)]
pub mod fused;
