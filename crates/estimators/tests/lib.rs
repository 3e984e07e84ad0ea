//! Integration tests of sepg-estimators (one binary).
mod coverage;
mod hand;
mod loo;
mod props;
mod quantile_table;
mod stability;
mod support;
mod unbiased;
mod variance;
