//! Exact binomial confidence bounds (Clopper & Pearson, 1934), shared with the audit of run
//! folders: they live in [`sepg_estimators::binomial`] and are re-exported here.

pub use sepg_estimators::binomial::{StatsError, clopper_pearson_lower, clopper_pearson_upper};
