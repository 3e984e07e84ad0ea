//! Integration tests of the `sepg` command-line interface, compiled into one binary.

mod cli_audit;
mod cli_audit_review;
mod cli_bounds;
mod cli_certified;
mod cli_cluster;
mod cli_constants;
mod cli_errors;
mod cli_exact;
mod cli_reproduce;
mod cli_run;
mod cli_sweep;
mod common;
mod docs;
mod robustness;
