//! One module per `sepg` subcommand.

pub mod audit;
pub mod bounds;
pub mod estimate;
pub mod exact;
pub mod merge;
pub mod parse;
pub mod plot;
pub mod replay;
pub mod reproduce;
pub mod run;
pub mod sweep;
pub mod verify;
