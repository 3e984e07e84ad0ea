//! Value parsers shared by several commands.

use std::str::FromStr;

use sepg_mdp::oracle::Horizon;

/// An LQG preset of `sepg_mdp` as a plain argument: parsed with [`FromStr`], whose message
/// names the expected presets, where the preset's `ValueEnum` would list them instead.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LqgPreset(pub sepg_mdp::env::LqgPreset);

impl LqgPreset {
    /// The preset's name as typed on the command line.
    pub fn name(self) -> &'static str {
        self.0.name()
    }
}

impl FromStr for LqgPreset {
    type Err = sepg_mdp::env::EnvError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        s.parse().map(LqgPreset)
    }
}

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
