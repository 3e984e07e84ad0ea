//! The test modules, grouped so that they compile into the single `lib` test binary.
mod batch;
mod certified;
mod common;
mod comparison;
mod config;
mod determinism;
mod exact;
mod mountain_car;
mod options;
mod plumbing;
mod safe_adam;
mod safety;
mod sampled;
mod score_action;
