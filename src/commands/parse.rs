//! Value parsers shared by several commands.

use std::str::FromStr;

use sepg_mdp::oracle::Horizon;

pub use sepg_mdp::env::LqgPreset;

/// A horizon: a positive integer or `inf`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HorizonArg(pub Horizon);

impl FromStr for HorizonArg {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        if s == "inf" {
            return Ok(HorizonArg(Horizon::Infinite));
        }
        match s.parse::<usize>() {
            Ok(0) => Err("the horizon must be at least 1".to_string()),
            Ok(h) => Ok(HorizonArg(Horizon::Finite(h))),
            Err(_) => Err(format!(
                "invalid horizon '{s}' (expected a positive integer or inf)"
            )),
        }
    }
}
