//! Shared machinery of every algorithm: configuration, records, state, executor.
pub mod adam;
pub mod check;
pub mod config;
pub mod defaults;
pub mod error;
pub mod executor;
pub mod names;
pub mod options;
pub mod record;
pub mod seed;
pub mod state;
pub mod statement;
