//! Shared helpers for the sepg criterion benchmarks.
