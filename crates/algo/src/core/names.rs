//! The names of the algorithms and of the safety requirements, one table for every face:
//! configurations and the command line (`sepg-runs`), the Python package, and the names the
//! thesis prints (SEPG-MI, SEPG-LB-I, …; Table 4.1). Each name parses with [`FromStr`],
//! prints with [`Display`](fmt::Display) and reads and writes with serde, all from the same
//! strings.

use std::fmt;
use std::str::FromStr;

#[cfg(feature = "clap")]
use clap::ValueEnum;
use serde::{Deserialize, Serialize};

use crate::core::config::Requirement;
use crate::core::defaults::DEFAULT_NU;
use crate::core::options::{ConstantsFamily, RewardSign};

/// A name that is not in its table: `what` ("algorithm", "requirement", …), the text, and
/// the names expected.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown {what} {text:?}: expected {expected}")]
pub struct UnknownName {
    /// What was named.
    pub what: &'static str,
    /// The text given.
    pub text: String,
    /// The names expected, as an English list ("a, b or c").
    pub expected: String,
}

/// The names `names` as an English list: "a, b or c".
///
/// ```
/// assert_eq!(sepg_algo::core::names::one_of(&["a", "b", "c"]), "a, b or c");
/// assert_eq!(sepg_algo::core::names::one_of(&["a"]), "a");
/// ```
pub fn one_of(names: &[&str]) -> String {
    match names {
        [] => String::new(),
        [one] => (*one).to_owned(),
        [init @ .., last] => format!("{} or {last}", init.join(", ")),
    }
}

/// Algorithms accepted by `--algo`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum AlgoName {
    /// SEPG, monotonic improvement.
    SepgMi,
    /// SEPG, lower-bounded I (split ν).
    SepgLb1,
    /// SEPG, lower-bounded II (budget).
    SepgLb2,
    /// SEPG, low-variance target.
    SepgLv,
    /// SEPG, zero-variance (deterministic) target.
    SepgZv,
    /// SEPG with simultaneous updates from one batch (budget split ν).
    SepgSim,
    /// SEPG with the naive variance update along ∇_w J (eq. 4.12).
    SepgNaiveW,
    /// G(PO)MDP with constant steps α, β.
    GpomdpConst,
    /// G(PO)MDP with Adam.
    GpomdpAdam,
    /// The adaptive step of Pirotta et al. with fixed σ.
    Adastep,
}

impl AlgoName {
    /// Every algorithm, in the order of the command line's help.
    pub const ALL: [AlgoName; 10] = [
        AlgoName::SepgMi,
        AlgoName::SepgLb1,
        AlgoName::SepgLb2,
        AlgoName::SepgLv,
        AlgoName::SepgZv,
        AlgoName::SepgSim,
        AlgoName::SepgNaiveW,
        AlgoName::GpomdpConst,
        AlgoName::GpomdpAdam,
        AlgoName::Adastep,
    ];

    /// The name of the algorithm in configurations, on the command line and in Python.
    ///
    /// ```
    /// assert_eq!(sepg_algo::AlgoName::SepgNaiveW.name(), "sepg-naive-w");
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            AlgoName::SepgMi => "sepg-mi",
            AlgoName::SepgLb1 => "sepg-lb1",
            AlgoName::SepgLb2 => "sepg-lb2",
            AlgoName::SepgLv => "sepg-lv",
            AlgoName::SepgZv => "sepg-zv",
            AlgoName::SepgSim => "sepg-sim",
            AlgoName::SepgNaiveW => "sepg-naive-w",
            AlgoName::GpomdpConst => "gpomdp-const",
            AlgoName::GpomdpAdam => "gpomdp-adam",
            AlgoName::Adastep => "adastep",
        }
    }

    /// The names of [`AlgoName::ALL`].
    pub fn names() -> [&'static str; 10] {
        AlgoName::ALL.map(AlgoName::name)
    }

    /// The algorithm of a name without its `sepg-` prefix (`mi`, …, `sim`, `naive-w`,
    /// `gpomdp-const`, `gpomdp-adam`, `adastep`), as the variants of a sweep are labelled.
    ///
    /// ```
    /// use sepg_algo::AlgoName;
    /// assert_eq!(AlgoName::from_short_name("naive-w"), Some(AlgoName::SepgNaiveW));
    /// assert_eq!(AlgoName::from_short_name("sepg-mi"), None);
    /// ```
    pub fn from_short_name(short: &str) -> Option<AlgoName> {
        AlgoName::ALL
            .into_iter()
            .find(|a| a.name().strip_prefix("sepg-").unwrap_or(a.name()) == short)
    }

    /// The name under which the thesis shows the algorithm: SEPG-MI, …, SEPG-SIM (Table
    /// 4.1), SEPG naive w, G(PO)MDP, G(PO)MDP-Adam, adaptive step (fixed σ).
    pub fn thesis_name(self) -> &'static str {
        match (self.sepg_requirement(), self) {
            (Some(r), _) => r.thesis_name(),
            (None, AlgoName::SepgNaiveW) => "SEPG naive w",
            (None, AlgoName::GpomdpConst) => "G(PO)MDP",
            (None, AlgoName::GpomdpAdam) => "G(PO)MDP-Adam",
            (None, _) => "adaptive step (fixed σ)",
        }
    }

    /// Whether the algorithm is a SEPG variant (the SEPG options apply).
    pub fn is_sepg(self) -> bool {
        self == AlgoName::SepgNaiveW || self.sepg_requirement().is_some()
    }

    /// The requirement of a SEPG variant named by its requirement (`sepg-mi` … `sepg-sim`);
    /// `None` for `sepg-naive-w`, whose requirement is an option, and the comparison
    /// algorithms.
    pub fn sepg_requirement(self) -> Option<RequirementName> {
        Some(match self {
            AlgoName::SepgMi => RequirementName::Mi,
            AlgoName::SepgLb1 => RequirementName::Lb1,
            AlgoName::SepgLb2 => RequirementName::Lb2,
            AlgoName::SepgLv => RequirementName::Lv,
            AlgoName::SepgZv => RequirementName::Zv,
            AlgoName::SepgSim => RequirementName::Sim,
            _ => return None,
        })
    }

    /// Whether the algorithm splits its requirement with ν (LB-I and SIM-ν, Table 4.1, also
    /// as the requirement of `sepg-naive-w`, given as `requirement`).
    pub fn uses_nu(self, requirement: Option<RequirementName>) -> bool {
        matches!(self, AlgoName::SepgLb1 | AlgoName::SepgSim)
            || (self == AlgoName::SepgNaiveW
                && matches!(
                    requirement,
                    Some(RequirementName::Lb1 | RequirementName::Sim)
                ))
    }
}

impl fmt::Display for AlgoName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for AlgoName {
    type Err = UnknownName;

    fn from_str(s: &str) -> Result<Self, UnknownName> {
        AlgoName::ALL
            .into_iter()
            .find(|a| a.name() == s)
            .ok_or_else(|| UnknownName {
                what: "algorithm",
                text: s.to_owned(),
                expected: one_of(&AlgoName::names()),
            })
    }
}

/// Safety requirements accepted by `--requirement` (the requirement of `sepg-naive-w`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum RequirementName {
    /// Monotonic improvement.
    Mi,
    /// Lower-bounded I.
    Lb1,
    /// Lower-bounded II.
    Lb2,
    /// Low variance.
    Lv,
    /// Zero variance.
    Zv,
    /// Simultaneous updates.
    Sim,
}

impl RequirementName {
    /// Every requirement, in the order of Table 4.1.
    pub const ALL: [RequirementName; 6] = [
        RequirementName::Mi,
        RequirementName::Lb1,
        RequirementName::Lb2,
        RequirementName::Lv,
        RequirementName::Zv,
        RequirementName::Sim,
    ];

    /// The short name (`mi`, `lb1`, `lb2`, `lv`, `zv`, `sim`).
    pub fn name(self) -> &'static str {
        match self {
            RequirementName::Mi => "mi",
            RequirementName::Lb1 => "lb1",
            RequirementName::Lb2 => "lb2",
            RequirementName::Lv => "lv",
            RequirementName::Zv => "zv",
            RequirementName::Sim => "sim",
        }
    }

    /// The names of [`RequirementName::ALL`].
    pub fn names() -> [&'static str; 6] {
        RequirementName::ALL.map(RequirementName::name)
    }

    /// The name under which the thesis shows SEPG with this requirement (Table 4.1):
    /// SEPG-MI, SEPG-LB-I, SEPG-LB-II, SEPG-LV, SEPG-ZV, SEPG-SIM.
    ///
    /// ```
    /// assert_eq!(sepg_algo::RequirementName::Lb2.thesis_name(), "SEPG-LB-II");
    /// ```
    pub fn thesis_name(self) -> &'static str {
        match self {
            RequirementName::Mi => "SEPG-MI",
            RequirementName::Lb1 => "SEPG-LB-I",
            RequirementName::Lb2 => "SEPG-LB-II",
            RequirementName::Lv => "SEPG-LV",
            RequirementName::Zv => "SEPG-ZV",
            RequirementName::Sim => "SEPG-SIM",
        }
    }

    /// The requirement of the algorithm, with the split ν of LB-I and SIM-ν (default
    /// [`DEFAULT_NU`]).
    pub fn requirement(self, nu: Option<f64>) -> Requirement {
        let nu = nu.unwrap_or(DEFAULT_NU);
        match self {
            RequirementName::Mi => Requirement::Mi,
            RequirementName::Lb1 => Requirement::LbI { nu },
            RequirementName::Lb2 => Requirement::LbII,
            RequirementName::Lv => Requirement::Lv,
            RequirementName::Zv => Requirement::Zv,
            RequirementName::Sim => Requirement::Sim { nu },
        }
    }
}

impl fmt::Display for RequirementName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for RequirementName {
    type Err = UnknownName;

    fn from_str(s: &str) -> Result<Self, UnknownName> {
        RequirementName::ALL
            .into_iter()
            .find(|r| r.name() == s)
            .ok_or_else(|| UnknownName {
                what: "requirement",
                text: s.to_owned(),
                expected: one_of(&RequirementName::names()),
            })
    }
}

/// The family of constants c and d of the bounds, accepted by `--constants`
/// (docs/THEOREMS.md, "Tight constants").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum ConstantsName {
    /// c of Theorems 3.14 / 4.2 and d of Theorem 4.3 (the thesis).
    Thesis,
    /// c = ρ R M_φ² S_H / σ² and d = 2ρ R S_H (Theorem T) for the run's horizon H.
    Tight,
}

impl ConstantsName {
    /// The family's name in configurations and reports.
    pub fn name(self) -> &'static str {
        match self {
            ConstantsName::Thesis => "thesis",
            ConstantsName::Tight => "tight",
        }
    }

    /// The family of a configuration written before the option existed: the thesis's.
    pub fn legacy() -> Self {
        ConstantsName::Thesis
    }

    /// The algorithm's family of this name; `rewards` is the reward sign of the tight
    /// constants (unused by the thesis's).
    pub fn family(self, rewards: RewardSign) -> ConstantsFamily {
        match self {
            ConstantsName::Thesis => ConstantsFamily::Thesis,
            ConstantsName::Tight => ConstantsFamily::Tight { rewards },
        }
    }
}

impl fmt::Display for ConstantsName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for ConstantsName {
    type Err = UnknownName;

    fn from_str(s: &str) -> Result<Self, UnknownName> {
        [ConstantsName::Thesis, ConstantsName::Tight]
            .into_iter()
            .find(|c| c.name() == s)
            .ok_or_else(|| UnknownName {
                what: "constants family",
                text: s.to_owned(),
                expected: one_of(&["thesis", "tight"]),
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every name parses back to its value, and serde writes and reads the same string.
    #[test]
    fn every_name_round_trips_through_from_str_display_and_serde() {
        for a in AlgoName::ALL {
            assert_eq!(a.to_string().parse::<AlgoName>(), Ok(a));
            let json = serde_json::to_string(&a).expect("json");
            assert_eq!(json, format!("\"{a}\""));
            assert_eq!(serde_json::from_str::<AlgoName>(&json).expect("parse"), a);
        }
        for c in [ConstantsName::Thesis, ConstantsName::Tight] {
            assert_eq!(c.to_string().parse::<ConstantsName>(), Ok(c));
            let json = serde_json::to_string(&c).expect("json");
            assert_eq!(
                serde_json::from_str::<ConstantsName>(&json).expect("parse"),
                c
            );
        }
        for r in RequirementName::ALL {
            assert_eq!(r.to_string().parse::<RequirementName>(), Ok(r));
            let json = serde_json::to_string(&r).expect("json");
            assert_eq!(json, format!("\"{r}\""));
            assert_eq!(
                serde_json::from_str::<RequirementName>(&json).expect("parse"),
                r
            );
        }
    }

    /// The names are distinct, and the SEPG variants named by a requirement are those of
    /// Table 4.1, as "sepg-" and the requirement's name.
    #[test]
    fn names_are_distinct_and_sepg_variants_carry_their_requirement() {
        let mut algos = AlgoName::names().to_vec();
        algos.sort_unstable();
        algos.dedup();
        assert_eq!(algos.len(), AlgoName::ALL.len());
        for r in RequirementName::ALL {
            let algo: AlgoName = format!("sepg-{r}").parse().expect("a SEPG variant");
            assert_eq!(algo.sepg_requirement(), Some(r));
            assert!(algo.is_sepg());
        }
        let e = "sepg-xx".parse::<AlgoName>().expect_err("unknown");
        assert_eq!(
            e.to_string(),
            "unknown algorithm \"sepg-xx\": expected sepg-mi, sepg-lb1, sepg-lb2, sepg-lv, \
             sepg-zv, sepg-sim, sepg-naive-w, gpomdp-const, gpomdp-adam or adastep"
        );
        let e = "lb3".parse::<RequirementName>().expect_err("unknown");
        assert_eq!(
            e.to_string(),
            "unknown requirement \"lb3\": expected mi, lb1, lb2, lv, zv or sim"
        );
    }
}
