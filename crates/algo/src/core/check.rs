//! The declared constants checked against the data a run sees (docs/RELIABILITY.md,
//! "Declared constants checked against the data").
//!
//! Every bound of the thesis (Theorems 3.14, 4.2, 4.3) and of Theorem T (docs/THEOREMS.md,
//! "Tight constants", conditions (i) and (iv)) needs R_max and M_φ to be true bounds: every
//! reward satisfies |r_t| ≤ R_max (and r_t ≤ 0 when the rewards are declared non-positive),
//! every feature vector satisfies |φ_i(s)| ≤ M_φ (the greedy-coordinate update) or
//! ‖φ(s)‖₂ ≤ M_φ (a step along any other direction). A run sees every sampled reward and
//! feature, so an observed violation is noticed: [`ConstantsCheck`] counts them and keeps the
//! first. A bound never exceeded in the sample is not proven by it.
use serde::{Deserialize, Serialize};

use sepg_bounds::TaskConstants;
use sepg_bounds::penalties::{Family, Rewards};
use sepg_mdp::Batch;

use crate::core::error::RunError;
use crate::core::options::{SepgOptions, VDirection};
use crate::core::seed::Block;

/// What a run does when its data contradict its declared constants (option
/// `on-contradiction`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OnContradiction {
    /// The run stops with an error at the first contradicting value (the default).
    #[default]
    Stop,
    /// The run goes on, marked "constants contradicted: no guarantee".
    Continue,
}

impl OnContradiction {
    /// Whether this is the default ([`OnContradiction::Stop`]); options serialise it only when
    /// it is not.
    pub fn is_stop(&self) -> bool {
        *self == OnContradiction::Stop
    }
}

/// The declared constant an observed value contradicts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Constant {
    /// |r_t| > R_max.
    RMax,
    /// r_t > 0 although the rewards are declared non-positive (the tight constants' ρ = 1/2).
    RewardSign,
    /// A feature vector above M_φ in the norm the v-update needs ([`FeatureNorm`]).
    MPhi,
}

impl Constant {
    /// The name used in messages and in `summary.json` (`r-max`, `reward-sign`, `m-phi`).
    pub fn name(self) -> &'static str {
        match self {
            Constant::RMax => "r-max",
            Constant::RewardSign => "reward-sign",
            Constant::MPhi => "m-phi",
        }
    }
}

/// The norm of φ(s) that M_φ must bound (docs/THEOREMS.md, "Tight constants", condition (iv)).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FeatureNorm {
    /// max_i |φ_i(s)|: the greedy-coordinate update (eq. 3.14).
    MaxAbs,
    /// ‖φ(s)‖₂: a step along any other direction of the v-space (safe Adam).
    Euclidean,
}

/// The bounds the data are checked against, from the task constants and the v-direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// R_max: the largest |reward| (units of reward).
    pub r_max: f64,
    /// Whether every reward is declared ≤ 0 (tight constants with non-positive rewards).
    pub non_positive: bool,
    /// M_φ: the largest feature norm.
    pub m_phi: f64,
    /// The norm M_φ bounds.
    pub norm: FeatureNorm,
}

impl Limits {
    /// The limits the bounds of a run with constants `k` and options `options` rest on.
    ///
    /// # Examples
    /// ```
    /// use sepg_algo::core::check::{FeatureNorm, Limits};
    /// use sepg_algo::core::options::SepgOptions;
    /// let k = sepg_bounds::TaskConstants::new(0.9, 2.0, 3.0, 4.0)?;
    /// let l = Limits::of(&k, &SepgOptions::default());
    /// assert_eq!((l.r_max, l.m_phi, l.norm, l.non_positive), (2.0, 3.0, FeatureNorm::MaxAbs, false));
    /// # Ok::<(), sepg_bounds::BoundsError>(())
    /// ```
    pub fn of(k: &TaskConstants, options: &SepgOptions) -> Self {
        let non_positive =
            matches!(k.family(), Family::Tight(t) if t.rewards() == Rewards::NonPositive);
        let norm = match options.v_direction {
            VDirection::Greedy => FeatureNorm::MaxAbs,
            VDirection::Adam { .. } => FeatureNorm::Euclidean,
        };
        Limits {
            r_max: k.r_max(),
            non_positive,
            m_phi: k.m_phi(),
            norm,
        }
    }
}

/// The first value of a run that contradicted a declared constant, and where it was seen.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Offence {
    /// The constant contradicted.
    pub what: Constant,
    /// The observed value: the reward r_t, or the feature norm of the [`FeatureNorm`] in force.
    pub value: f64,
    /// The declared bound it exceeds (R_max, 0 for the reward sign, M_φ).
    pub bound: f64,
    /// The iteration whose batch held it.
    pub iteration: u64,
    /// The block of the iteration (`v`, `target`, `w`, `reference`, `reference-target`).
    pub block: String,
    /// The trajectory within the batch (0-based).
    pub trajectory: usize,
    /// The step within the trajectory (0-based).
    pub step: usize,
}

impl std::fmt::Display for Offence {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let what = match self.what {
            Constant::RMax => format!(
                "|reward| = {} exceeds r-max = {}",
                self.value.abs(),
                self.bound
            ),
            Constant::RewardSign => format!(
                "reward {} is positive although the rewards are declared non-positive",
                self.value
            ),
            Constant::MPhi => format!("feature norm {} exceeds m-phi = {}", self.value, self.bound),
        };
        write!(
            f,
            "{what} (iteration {}, block {}, trajectory {}, step {})",
            self.iteration, self.block, self.trajectory, self.step
        )
    }
}

/// Counts of the observed values that contradict the declared constants, with the first one
/// (`constants_check` of `summary.json` and of the checkpoint).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct ConstantsCheck {
    /// Rewards seen (steps of the checked batches).
    pub rewards_checked: u64,
    /// Feature vectors seen.
    pub features_checked: u64,
    /// Rewards with |r_t| > R_max.
    pub r_max: u64,
    /// Positive rewards although the rewards are declared non-positive.
    pub reward_sign: u64,
    /// Feature vectors above M_φ.
    pub m_phi: u64,
    /// The first contradicting value.
    pub first: Option<Offence>,
}

impl ConstantsCheck {
    /// Whether any observed value contradicted a declared constant.
    ///
    /// # Examples
    /// ```
    /// use sepg_algo::core::check::ConstantsCheck;
    /// assert!(!ConstantsCheck::default().contradicted());
    /// ```
    pub fn contradicted(&self) -> bool {
        self.first.is_some()
    }

    /// Whether nothing was checked and nothing contradicted (checkpoints omit such a check).
    pub fn is_empty(&self) -> bool {
        *self == ConstantsCheck::default()
    }

    /// The reason a contradicted run states no guarantee, in one line; `None` when nothing
    /// contradicted.
    pub fn reason(&self) -> Option<String> {
        self.first
            .as_ref()
            .map(|o| format!("constants contradicted: no guarantee (first: {o})"))
    }

    /// Adds the counts of `other` and keeps the earlier first offence.
    pub fn merge(&mut self, other: &ConstantsCheck) {
        self.rewards_checked += other.rewards_checked;
        self.features_checked += other.features_checked;
        self.r_max += other.r_max;
        self.reward_sign += other.reward_sign;
        self.m_phi += other.m_phi;
        if self.first.is_none() {
            self.first.clone_from(&other.first);
        }
    }

    /// Counts `offence` (the value a run stopped at) and keeps it if it is the first.
    ///
    /// # Examples
    /// ```
    /// use sepg_algo::core::check::{Constant, ConstantsCheck, Offence};
    /// let mut c = ConstantsCheck::default();
    /// c.record(Offence { what: Constant::RMax, value: -3.0, bound: 1.0, iteration: 2,
    ///     block: "v".into(), trajectory: 0, step: 5 });
    /// assert_eq!((c.r_max, c.contradicted()), (1, true));
    /// ```
    pub fn record(&mut self, offence: Offence) {
        self.count(offence.what, || offence);
    }

    fn count(&mut self, what: Constant, offence: impl FnOnce() -> Offence) {
        match what {
            Constant::RMax => self.r_max += 1,
            Constant::RewardSign => self.reward_sign += 1,
            Constant::MPhi => self.m_phi += 1,
        }
        if self.first.is_none() {
            self.first = Some(offence());
        }
    }
}

/// The raw per-step data a batch collected outside the crate was built from
/// ([`BatchCollector::collect_raw`](crate::solver::sampled::BatchCollector::collect_raw)):
/// row-major, trajectory first, each trajectory stored over the batch's horizon and valid for
/// its first `lengths[i]` steps (the batch's lengths).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RawSteps {
    /// Raw rewards r_t, `n · horizon` (units of reward).
    pub rewards: Vec<f64>,
    /// Features φ(s_t), `n · horizon · p`, or empty when the block needs no scores.
    pub features: Vec<f64>,
    /// Number of features p per step (0 when `features` is empty).
    pub p: usize,
}

/// The relative slack of every comparison: a value within 8 units in the last place of its
/// bound (relative 1.8e-15) is not counted, so that an environment whose reward or feature
/// reaches its bound exactly, computed in another order than the bound, raises no false alarm.
pub const SLACK: f64 = 1.0 + 8.0 * f64::EPSILON;

/// The check of one run: its limits, what to do on a contradiction and the counts so far.
#[derive(Debug, Clone, Default)]
pub(crate) struct Checker {
    limits: Option<Limits>,
    stop: bool,
    pub(crate) tally: ConstantsCheck,
    /// γᵗ of the steps of the last batch checked (reused buffer).
    discs: Vec<f64>,
    /// The bound of each step's discounted reward (reused buffer).
    bounds: Vec<f64>,
}

/// Where the data of a scan come from.
#[derive(Debug, Clone, Copy)]
pub(crate) struct At {
    pub(crate) iteration: u64,
    pub(crate) block: Block,
}

fn block_name(b: Block) -> &'static str {
    match b {
        Block::V => "v",
        Block::Target => "target",
        Block::W => "w",
        Block::Reference => "reference",
        Block::ReferenceTarget => "reference-target",
    }
}

/// The offence of `value` against `bound` at step `t` of trajectory `i` of the batch `at`.
fn offence(at: At, what: Constant, value: f64, bound: f64, i: usize, t: usize) -> Offence {
    Offence {
        what,
        value,
        bound,
        iteration: at.iteration,
        block: block_name(at.block).to_owned(),
        trajectory: i,
        step: t,
    }
}

impl Checker {
    /// Sets the limits of the coming iteration and what a contradiction does.
    pub(crate) fn arm(&mut self, limits: Limits, on: OnContradiction) {
        self.limits = Some(limits);
        self.stop = on == OnContradiction::Stop;
    }

    /// The error that stops the run at `offence`, when the run stops on a contradiction.
    pub(crate) fn verdict(&self, offence: Option<Offence>) -> Result<(), RunError> {
        match offence {
            Some(o) if self.stop => Err(RunError::ConstantsContradicted(Box::new(o))),
            _ => Ok(()),
        }
    }

    /// Takes the counts gathered since the last call.
    pub(crate) fn take(&mut self) -> ConstantsCheck {
        std::mem::take(&mut self.tally)
    }

    /// Checks the rewards of a batch of the built-in rollout engine, which keeps the
    /// discounted rewards γᵗ r_t computed as `disc · r` with `disc` the running product of γ.
    /// Rounding is monotone, so |fl(disc · r)| > fl(disc · R') implies |r| > R' (R' = R_max
    /// times [`SLACK`]): no false alarm; the reported value is fl(disc · r)/disc, within two
    /// roundings of r. Steps whose γᵗ underflows to 0 cannot be checked and are skipped.
    pub(crate) fn scan_batch(&mut self, batch: &Batch, at: At) -> Option<Offence> {
        let limits = self.limits?;
        let before = self.tally.first.is_some();
        let slack = limits.r_max * SLACK;
        // γᵗ as the rollout engine computes it, and the bound fl(γᵗ · R_max · SLACK) of each
        // step; a step whose γᵗ is 0 is not checked.
        self.discs.clear();
        let mut disc = 1.0_f64;
        for _ in 0..batch.horizon {
            if disc == 0.0 {
                break;
            }
            self.discs.push(disc);
            disc *= batch.gamma;
        }
        self.bounds.clear();
        self.bounds.extend(self.discs.iter().map(|d| d * slack));
        let sign = limits.non_positive;
        let lengths = batch.lengths[..batch.n].iter();
        let checked: usize = lengths.map(|&l| l.min(self.bounds.len())).sum();
        self.tally.rewards_checked += checked as u64;
        // the common case in branch-free passes; the offending steps only when there are
        let mut from = 0;
        while let Some(i) = next_offending(batch, &self.bounds, sign, from) {
            from = i + 1;
            let row = batch.rewards(i);
            let len = batch.lengths[i].min(self.bounds.len());
            let steps = row[..len].iter().zip(&self.discs).zip(&self.bounds);
            for (t, ((&dr, &disc), &bound)) in steps.enumerate() {
                Self::count_reward(
                    &mut self.tally,
                    at,
                    (i, t),
                    dr / disc,
                    dr.abs() > bound,
                    &limits,
                );
            }
        }
        self.new_first(before)
    }

    /// Checks the raw rewards and features of a collected batch (`batch` gives the horizon
    /// and the trajectory lengths).
    pub(crate) fn scan_steps(
        &mut self,
        steps: &RawSteps,
        batch: &Batch,
        at: At,
    ) -> Option<Offence> {
        let limits = self.limits?;
        let before = self.tally.first.is_some();
        let (h, p) = (batch.horizon, steps.p);
        // ‖φ‖₂ is computed with p + 1 roundings: a norm exactly at M_φ may round above it by
        // at most (p + 2)u relatively, which is not counted either.
        let r_max = limits.r_max * SLACK;
        let m_phi = limits.m_phi * SLACK;
        let m_phi_2 = limits.m_phi * (SLACK + (p as f64 + 2.0) * f64::EPSILON);
        for (i, &len) in batch.lengths.iter().enumerate() {
            for t in 0..len.min(h) {
                let c = i * h + t;
                let Some(&r) = steps.rewards.get(c) else {
                    break;
                };
                self.tally.rewards_checked += 1;
                Self::count_reward(&mut self.tally, at, (i, t), r, r.abs() > r_max, &limits);
                let Some(phi) = steps.features.get(c * p..(c + 1) * p).filter(|_| p > 0) else {
                    continue;
                };
                self.tally.features_checked += 1;
                let norm = match limits.norm {
                    FeatureNorm::MaxAbs => phi.iter().fold(0.0_f64, |m, x| m.max(x.abs())),
                    FeatureNorm::Euclidean => phi.iter().map(|x| x * x).sum::<f64>().sqrt(),
                };
                let over = match limits.norm {
                    FeatureNorm::MaxAbs => norm > m_phi,
                    FeatureNorm::Euclidean => norm > m_phi_2,
                };
                if over {
                    self.tally.count(Constant::MPhi, || {
                        offence(at, Constant::MPhi, norm, limits.m_phi, i, t)
                    });
                }
            }
        }
        self.new_first(before)
    }

    /// Counts the reward `value` at step `t` of trajectory `i`: beyond R_max when `beyond`
    /// (decided by the caller with its slack), otherwise positive where the rewards are
    /// declared non-positive.
    fn count_reward(
        tally: &mut ConstantsCheck,
        at: At,
        (i, t): (usize, usize),
        value: f64,
        beyond: bool,
        limits: &Limits,
    ) {
        if beyond {
            tally.count(Constant::RMax, || {
                offence(at, Constant::RMax, value, limits.r_max, i, t)
            });
        } else if limits.non_positive && value > 0.0 {
            tally.count(Constant::RewardSign, || {
                offence(at, Constant::RewardSign, value, 0.0, i, t)
            });
        }
    }

    fn new_first(&self, before: bool) -> Option<Offence> {
        if before {
            None
        } else {
            self.tally.first.clone()
        }
    }
}

/// The first trajectory `i ≥ from` of `batch` with a discounted reward beyond its bound
/// (`|γᵗ r_t| > bounds[t]`) or, when `sign`, above 0; each row is read up to its length and
/// `bounds.len()`. On x86-64 processors with AVX2 the comparisons run in a build for AVX2
/// (four lanes; a comparison does not round, so the answer is the same).
fn next_offending(batch: &Batch, bounds: &[f64], sign: bool, from: usize) -> Option<usize> {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the processor supports AVX2, the only feature `next_offending_avx2` is
        // built for.
        return unsafe { next_offending_avx2(batch, bounds, sign, from) };
    }
    next_offending_any(batch, bounds, sign, from)
}

/// [`next_offending`] built for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn next_offending_avx2(batch: &Batch, bounds: &[f64], sign: bool, from: usize) -> Option<usize> {
    next_offending_any(batch, bounds, sign, from)
}

#[inline(always)]
fn next_offending_any(batch: &Batch, bounds: &[f64], sign: bool, from: usize) -> Option<usize> {
    (from..batch.n).find(|&i| {
        let len = batch.lengths[i].min(bounds.len());
        let row = &batch.rewards(i)[..len];
        row.iter().zip(bounds).fold(false, |bad, (dr, b)| {
            bad | (dr.abs() > *b) | (sign & (*dr > 0.0))
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits(norm: FeatureNorm) -> Limits {
        Limits {
            r_max: 1.0,
            non_positive: true,
            m_phi: 1.0,
            norm,
        }
    }

    /// Hand-made steps: a positive reward, then |r| = 2 > 1, a feature (0.8, 0.8) within M_φ
    /// componentwise but of norm 1.131 > 1.
    #[test]
    fn raw_steps_are_counted_by_kind_with_the_first_kept() {
        let at = At {
            iteration: 3,
            block: Block::W,
        };
        let rewards = [-0.5, 0.25, -2.0, 9.0];
        let features = [0.1, 0.1, 0.2, 0.2, 0.8, 0.8, 5.0, 5.0];
        let steps = RawSteps {
            rewards: rewards.to_vec(),
            features: features.to_vec(),
            p: 2,
        };
        let batch = Batch::from_steps(2, 1.0, &[], &rewards, &[], &[], &[2, 1]).expect("batch");
        let mut c = Checker::default();
        c.arm(limits(FeatureNorm::MaxAbs), OnContradiction::Continue);
        let first = c.scan_steps(&steps, &batch, at).expect("a contradiction");
        assert_eq!(
            (first.what, first.value, first.trajectory, first.step),
            (Constant::RewardSign, 0.25, 0, 1)
        );
        assert_eq!(
            (c.tally.reward_sign, c.tally.r_max, c.tally.m_phi),
            (1, 1, 0)
        );
        assert_eq!((c.tally.rewards_checked, c.tally.features_checked), (3, 3));
        assert!(
            c.scan_steps(&steps, &batch, at).is_none(),
            "the first is reported once"
        );
        let mut e = Checker::default();
        e.arm(limits(FeatureNorm::Euclidean), OnContradiction::Stop);
        let stop = e.scan_steps(&steps, &batch, at);
        assert!(matches!(
            e.verdict(stop),
            Err(RunError::ConstantsContradicted(_))
        ));
        assert_eq!(e.tally.m_phi, 1);
        assert_eq!(e.tally.first.as_ref().map(|o| o.block.as_str()), Some("w"));
    }

    /// A batch of discounted rewards: the reward is recovered as fl(γᵗ r)/γᵗ, a reward exactly
    /// at R_max is never counted, one above it is.
    #[test]
    fn discounted_rewards_are_checked_without_false_alarms() {
        let gamma = 0.9;
        let rewards = [-1.0, -1.0, -1.0, 0.0, -1.0, -1.5];
        let b = Batch::from_steps(3, gamma, &[], &rewards, &[], &[], &[3, 3]).expect("batch");
        let mut c = Checker::default();
        c.arm(limits(FeatureNorm::MaxAbs), OnContradiction::Continue);
        let at = At {
            iteration: 0,
            block: Block::V,
        };
        let o = c.scan_batch(&b, at).expect("a contradiction");
        assert_eq!((o.trajectory, o.step, o.what), (1, 2, Constant::RMax));
        assert!((o.value + 1.5).abs() <= 4.0 * f64::EPSILON * 1.5);
        assert_eq!((c.tally.r_max, c.tally.rewards_checked), (1, 6));
    }

    /// The first offending trajectory from every starting row, with and without the sign
    /// check, against a plain loop over the steps; on processors with AVX2, the AVX2 build
    /// and the portable one agree.
    #[test]
    fn the_first_offending_trajectory_is_found_from_every_row() {
        let (n, h) = (9, 7);
        let mut b = Batch::zeros(n, h, 1, 1, 0.9);
        for (k, x) in b.disc_rewards.iter_mut().enumerate() {
            *x = -((k % 5) as f64) * 0.1;
        }
        b.disc_rewards[2 * h + 6] = -3.0; // beyond the bound, at the last step
        b.disc_rewards[5 * h + 1] = 2.5; // beyond the bound and positive
        b.disc_rewards[7 * h] = 0.25; // positive only
        b.disc_rewards[8 * h + 5] = -9.0; // beyond the bound, but past the row's length
        b.lengths = vec![7, 7, 7, 6, 7, 7, 7, 7, 5];
        let bounds = [1.0, 1.0, 1.0, 1.0, 1.0, 1.0];
        let plain = |sign: bool, from: usize| {
            (from..n).find(|&i| {
                let len = b.lengths[i].min(bounds.len());
                (0..len).any(|t| {
                    let r = b.disc_rewards[i * h + t];
                    r.abs() > bounds[t] || (sign && r > 0.0)
                })
            })
        };
        let mut found = Vec::new();
        for sign in [false, true] {
            for from in 0..=n {
                let got = next_offending(&b, &bounds, sign, from);
                assert_eq!(got, plain(sign, from), "sign {sign} from {from}");
                #[cfg(target_arch = "x86_64")]
                assert_eq!(got, next_offending_any(&b, &bounds, sign, from));
                found.push(got);
            }
        }
        // row 2's offence is at step 6, beyond the 6 bounds: never seen; row 8's is past its
        // length
        assert_eq!(found[0], Some(5));
        assert_eq!(found[n + 1 + 6], Some(7));
        assert_eq!(found[8], None);
    }

    /// Values within [`SLACK`] of their bound are not counted, values beyond it are.
    #[test]
    fn values_within_eight_ulps_of_the_bound_are_not_counted() {
        let at = At {
            iteration: 0,
            block: Block::V,
        };
        let near = 1.0 + 4.0 * f64::EPSILON;
        let far = 1.0 + 16.0 * f64::EPSILON;
        for (value, counted) in [(near, 0), (far, 1)] {
            let steps = RawSteps {
                rewards: vec![-value],
                features: vec![value],
                p: 1,
            };
            let batch = Batch::from_steps(1, 0.5, &[], &[-value], &[], &[], &[1]).expect("batch");
            let mut c = Checker::default();
            c.arm(limits(FeatureNorm::MaxAbs), OnContradiction::Continue);
            c.scan_steps(&steps, &batch, at);
            c.scan_batch(&batch, at);
            assert_eq!(
                (c.tally.r_max, c.tally.m_phi),
                (2 * counted, counted),
                "{value}"
            );
        }
    }
}
