//! The numeric option values: one number or one per component, and seeds.

use serde::{Deserialize, Deserializer, Serialize};

use crate::error::{Error, Result};

/// One value broadcast to every component, or one value per component.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Values {
    /// The same value for every component.
    One(f64),
    /// One value per component.
    Many(Vec<f64>),
}

impl Values {
    pub(super) fn expand(&self, dim: usize, what: &str) -> Result<Vec<f64>> {
        match self {
            Values::One(x) => Ok(vec![*x; dim]),
            Values::Many(v) if v.len() == 1 => Ok(vec![v[0]; dim]),
            Values::Many(v) if v.len() == dim => Ok(v.clone()),
            Values::Many(v) if dim == 1 => Err(Error::invalid(format!(
                "{what} has {} values, the environment needs 1",
                v.len()
            ))),
            Values::Many(v) => Err(Error::invalid(format!(
                "{what} has {} values, the environment needs 1 or {dim}",
                v.len()
            ))),
        }
    }
}

impl<'de> Deserialize<'de> for Values {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            One(f64),
            Many(Vec<f64>),
        }
        match Raw::deserialize(d) {
            Ok(Raw::One(x)) => Ok(Values::One(x)),
            Ok(Raw::Many(v)) => Ok(Values::Many(v)),
            Err(_) => Err(serde::de::Error::custom(
                "expected a number or an array of numbers",
            )),
        }
    }
}

/// Parses the command-line form of [`Values`]: one number, or numbers separated by commas.
///
/// # Errors
/// A message naming the text when a part is not a number.
pub fn parse_values(s: &str) -> Result<Values, String> {
    let v: Result<Vec<f64>, _> = s.split(',').map(|x| x.trim().parse::<f64>()).collect();
    match v {
        Ok(v) if v.len() == 1 => Ok(Values::One(v[0])),
        Ok(v) => Ok(Values::Many(v)),
        Err(e) => Err(format!(
            "{s:?} is not a comma-separated list of numbers: {e}"
        )),
    }
}

/// Parses a seed: a non-negative integer below 2⁶⁴ (seeds index the random streams of
/// `sepg_mdp::rng`, which are keyed by unsigned 64-bit integers). The message says why a
/// negative or non-integer value is refused.
///
/// # Errors
/// A one-line message for anything else.
///
/// # Example
/// ```
/// use sepg_runs::spec::parse_seed;
/// assert_eq!(parse_seed("7"), Ok(7));
/// assert!(parse_seed("-1").unwrap_err().contains("non-negative"));
/// ```
pub fn parse_seed(s: &str) -> std::result::Result<u64, String> {
    s.trim().parse::<u64>().map_err(|_| {
        let why = if s.trim().parse::<i128>().is_ok_and(|x| x < 0) {
            "it is negative"
        } else if s.trim().parse::<i128>().is_ok() {
            "it is too large"
        } else {
            "it is not an integer"
        };
        format!("a seed is a non-negative integer in 0..=18446744073709551615 (u64), and {why}")
    })
}
