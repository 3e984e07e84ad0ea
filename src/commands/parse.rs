//! Value parsers shared by several commands.

use std::str::FromStr;

use sepg_mdp::oracle::Horizon;

/// A 1-D LQG preset name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LqgPreset {
    /// `lqg`: thesis Sec 5.1 as written (S, A = [−2, 2], reward −0.5(s² + a²)).
    Lqg,
    /// `lqg1d`: the public code's 1-D LQG (S, A = [−4, 4], reward −0.9(s² + a²)).
    Lqg1d,
}

impl LqgPreset {
    /// The preset's name as typed on the command line.
    pub fn name(self) -> &'static str {
        match self {
            LqgPreset::Lqg => "lqg",
            LqgPreset::Lqg1d => "lqg1d",
        }
    }
}

impl FromStr for LqgPreset {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "lqg" => Ok(LqgPreset::Lqg),
            "lqg1d" => Ok(LqgPreset::Lqg1d),
            other => Err(format!(
                "unknown LQG preset '{other}' (expected lqg or lqg1d)"
            )),
        }
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
