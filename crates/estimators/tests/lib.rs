//! Integration tests of sepg-estimators (one binary).
mod constant_baseline;
mod coverage;
mod hand;
mod loo;
mod props;
mod proven;
mod proven_coverage;
mod quantile_table;
mod stability;
mod support;
mod unbiased;
mod variance;
