//! The test modules, grouped so that they compile into the single `lib` test binary.
mod common;
mod config;
mod determinism;
mod exact;
mod sampled;
