//! One module per `sepg` subcommand.

pub mod bounds;
pub mod verify;
