//! Mountain Car with the semantics of gymnasium's `MountainCarContinuous-v0` in f64 (docs/CONVENTIONS.md §1;
//! the experiment of thesis Sec 5.2, Fig 5.4).
//!
//! # Formula
//! ```text
//! force = clip(a, −1, 1)
//! vel  ← clip(vel + 0.0015·force − 0.0025·cos(3·pos), −0.07, 0.07)
//! pos  ← clip(pos + vel, −1.2, 0.6);   if pos = −1.2 and vel < 0 then vel ← 0
//! terminated = pos ≥ 0.45 and vel ≥ 0
//! reward = 100·[terminated] − 0.1·a²        (RAW action a)
//! reset: pos ~ U[−0.6, −0.4], vel = 0;      time limit 999 steps
//! ```

use crate::env::{EnvConstants, EnvError, Environment};
use crate::features::{FeatureMap, RbfGrid};
use crate::rng::{TrajRng, uniform};

/// Lowest position.
pub const MIN_POSITION: f64 = -1.2;
/// Highest position.
pub const MAX_POSITION: f64 = 0.6;
/// Speed limit `|vel| ≤ 0.07`.
pub const MAX_SPEED: f64 = 0.07;
/// Goal position: the episode terminates when `pos ≥ 0.45` with `vel ≥ 0`.
pub const GOAL_POSITION: f64 = 0.45;
/// Engine power multiplying the clipped force.
pub const POWER: f64 = 0.0015;
/// Episode time limit (truncation).
pub const TIME_LIMIT: usize = 999;
/// `R_max` of docs/CONVENTIONS.md §1: the goal reward. The action penalty `0.1·a²` uses the raw action and is
/// not bounded by it for `|a| > 10√10`.
pub const R_MAX: f64 = 100.0;

/// Mountain Car (`MountainCarContinuous-v0`) with a chosen policy feature map over the state
/// `(pos, vel)`.
///
/// # Formula
/// ```text
/// see the module documentation
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct MountainCar {
    features: FeatureMap,
    gamma: f64,
}

impl MountainCar {
    /// Mountain Car with the given feature map (which must read the 2-D state), `γ = 0.99`.
    ///
    /// ```
    /// use sepg_mdp::features::FeatureMap;
    /// use sepg_mdp::mountain_car::MountainCar;
    /// assert!(MountainCar::new(FeatureMap::Identity { dim: 2 }).is_ok());
    /// assert!(MountainCar::new(FeatureMap::Identity { dim: 3 }).is_err());
    /// ```
    pub fn new(features: FeatureMap) -> Result<Self, EnvError> {
        if features.input_dim() != 2 {
            return Err(EnvError::FeatureInputDim {
                expected: 2,
                found: features.input_dim(),
            });
        }
        Ok(MountainCar {
            features,
            gamma: 0.99,
        })
    }

    /// State+bias features `φ(s) = [pos, vel, 1]` (`M_φ = 1.2`).
    ///
    /// ```
    /// use sepg_mdp::env::Environment;
    /// assert_eq!(sepg_mdp::mountain_car::MountainCar::state_bias().feature_dim(), 3);
    /// ```
    pub fn state_bias() -> Self {
        MountainCar {
            features: FeatureMap::StateBias { dim: 2 },
            gamma: 0.99,
        }
    }

    /// A Gaussian RBF grid of `per_dim = [k_pos, k_vel]` centres over the state box
    /// `[−1.2, 0.6] × [−0.07, 0.07]`, plus a bias feature when `bias` is set (`M_φ = 1`).
    ///
    /// ```
    /// use sepg_mdp::env::Environment;
    /// let mc = sepg_mdp::mountain_car::MountainCar::rbf([5, 5], true).unwrap();
    /// assert_eq!(mc.feature_dim(), 26);
    /// assert_eq!(mc.constants().m_phi, 1.0);
    /// ```
    pub fn rbf(per_dim: [usize; 2], bias: bool) -> Result<Self, EnvError> {
        let grid = RbfGrid::new(
            &[MIN_POSITION, -MAX_SPEED],
            &[MAX_POSITION, MAX_SPEED],
            &per_dim,
            bias,
        )?;
        MountainCar::new(FeatureMap::Rbf(grid))
    }

    /// The same environment with discount factor `gamma ∈ [0, 1)`.
    ///
    /// ```
    /// use sepg_mdp::env::Environment;
    /// let mc = sepg_mdp::mountain_car::MountainCar::state_bias().with_gamma(0.999).unwrap();
    /// assert_eq!(mc.constants().gamma, 0.999);
    /// ```
    pub fn with_gamma(mut self, gamma: f64) -> Result<Self, EnvError> {
        if !(0.0..1.0).contains(&gamma) {
            return Err(EnvError::InvalidGamma(gamma));
        }
        self.gamma = gamma;
        Ok(self)
    }

    /// The feature map.
    ///
    /// ```
    /// use sepg_mdp::features::FeatureMap;
    /// let mc = sepg_mdp::mountain_car::MountainCar::state_bias();
    /// assert_eq!(mc.feature_map(), &FeatureMap::StateBias { dim: 2 });
    /// ```
    pub fn feature_map(&self) -> &FeatureMap {
        &self.features
    }
}

impl Environment for MountainCar {
    fn state_dim(&self) -> usize {
        2
    }

    fn action_dim(&self) -> usize {
        1
    }

    fn feature_dim(&self) -> usize {
        self.features.dim()
    }

    fn constants(&self) -> EnvConstants {
        EnvConstants {
            r_max: R_MAX,
            m_phi: self
                .features
                .m_phi(&[MIN_POSITION, -MAX_SPEED], &[MAX_POSITION, MAX_SPEED]),
            action_volume: 2.0,
            gamma: self.gamma,
            horizon: TIME_LIMIT,
        }
    }

    fn gamma(&self) -> f64 {
        self.gamma
    }

    fn time_limit(&self) -> Option<usize> {
        Some(TIME_LIMIT)
    }

    fn reset(&self, rng: &mut TrajRng, state: &mut [f64]) {
        reset(rng, state);
    }

    fn step(
        &self,
        state: &[f64],
        action: &[f64],
        _rng: &mut TrajRng,
        next: &mut [f64],
    ) -> (f64, bool) {
        let (pos, vel, reward, terminated) = transition(state[0], state[1], action[0]);
        next[0] = pos;
        next[1] = vel;
        (reward, terminated)
    }

    fn as_mountain_car(&self) -> Option<&MountainCar> {
        Some(self)
    }

    fn features(&self, state: &[f64], phi: &mut [f64]) {
        self.features.eval_unchecked(state, phi);
    }

    /// The force `a` clipped to `[−1, 1]` (the reward still charges the raw action).
    fn clip_action(&self, _: usize, a: f64) -> f64 {
        a.clamp(-1.0, 1.0)
    }
}

/// One transition from `(pos, vel)` under the raw action `a` (the rules in the module
/// documentation): `(pos′, vel′, reward, terminated)`. Shared by [`Environment::step`] and the
/// fused rollout kernel, so both compute the same bits.
#[inline(always)]
pub(crate) fn transition(pos: f64, vel: f64, a: f64) -> (f64, f64, f64, bool) {
    let (mut pos, mut vel) = (pos, vel);
    let force = a.clamp(-1.0, 1.0);
    vel += force * POWER - 0.0025 * (3.0 * pos).cos();
    vel = vel.clamp(-MAX_SPEED, MAX_SPEED);
    pos += vel;
    pos = pos.clamp(MIN_POSITION, MAX_POSITION);
    if pos == MIN_POSITION && vel < 0.0 {
        vel = 0.0;
    }
    let terminated = pos >= GOAL_POSITION && vel >= 0.0;
    let reward = if terminated { 100.0 } else { 0.0 } - a * a * 0.1;
    (pos, vel, reward, terminated)
}

/// The initial state `(pos, vel) = (U[−0.6, −0.4), 0)` into `state` (length 2).
#[inline(always)]
pub(crate) fn reset(rng: &mut TrajRng, state: &mut [f64]) {
    state[0] = uniform(rng, -0.6, -0.4);
    state[1] = 0.0;
}
