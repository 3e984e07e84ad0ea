//! Run options and their resolution: [`RunSpec`] holds every option of a run (as a TOML
//! table and, with the `clap` feature, as command-line flags of the same names);
//! [`RunSpec::resolve`] fills in the defaults of the thesis's protocol (Sec 5.1), rejects
//! options that do not apply to the chosen algorithm, and validates the result into the
//! [`CheckedConfig`](sepg_algo::core::config::CheckedConfig) that `sepg-algo` runs.
//!
//! The module is organised by concern: the names of the options' values (`names`), the
//! numeric option values (`values`), the table of options itself (`run_spec`), the limits on
//! sizes (`limits`), the resolution (`resolve`, with the options that do not apply in
//! `applicability` and the SEPG options in `option_values`) and the resolved configuration
//! (`resolved`).

mod applicability;
mod limits;
mod names;
mod option_values;
mod resolve;
mod resolved;
mod run_spec;
mod values;

pub use limits::{
    MAX_BATCH_BYTES, MAX_HORIZON, MAX_ITERATIONS, VERSION, batch_bytes, check_batch_memory,
    check_horizon,
};
pub use names::{
    AccountingName, AlgoName, BaselineName, BatchRuleName, ConfidenceName, ConstantsName, EnvName,
    EstimatorName, FitName, GradientsName, Lb1Name, OnContradictionName, RequirementName,
    RewardsName, ScheduleName, ScoresName, VDirectionName, WDirectionName, WStepName,
};
pub use resolved::Resolved;
pub use run_spec::{RunSpec, toml_message};
pub use values::{Values, parse_seed, parse_values};

#[cfg(test)]
mod tests;
