//! The trajectory of Mountain Car (the rules of gymnasium's `MountainCarContinuous-v0`) from a
//! given state under a given action sequence, as `sepg replay` prints it, with its arguments
//! checked here.

use sepg_mdp::env::Environment;
use sepg_mdp::mountain_car::{MAX_POSITION, MAX_SPEED, MIN_POSITION, MountainCar, TIME_LIMIT};
use sepg_mdp::rng::rng_from_seed;
use serde::Serialize;

use crate::error::{Error, Result};

/// A replayed trajectory. `positions` and `velocities` include the initial state, so they
/// have one more entry than `rewards`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Trajectory {
    /// Positions, from the initial one.
    pub positions: Vec<f64>,
    /// Velocities, from the initial one.
    pub velocities: Vec<f64>,
    /// The reward of each step.
    pub rewards: Vec<f64>,
    /// 0-based index of the action whose step reached the goal, if any.
    pub terminated_at: Option<usize>,
    /// Whether the time limit ([`TIME_LIMIT`] steps) cut the action sequence.
    pub truncated: bool,
}

/// Replays the raw actions `actions` (the force is clip(a, −1, 1); the reward uses the raw
/// action) on the environment `env` from `state` = (position, velocity): at most
/// [`TIME_LIMIT`] steps, stopping at the goal.
///
/// # Errors
/// [`Error::Invalid`] when `env` is not `mountain-car`, `state` does not have two values or
/// lies outside [−1.2, 0.6] × [−0.07, 0.07], or an action is not finite.
pub fn replay(env: &str, state: &[f64], actions: &[f64]) -> Result<Trajectory> {
    if env != "mountain-car" {
        return Err(Error::invalid(format!(
            "replay supports only --env mountain-car, got '{env}'"
        )));
    }
    let [pos, vel] = state[..] else {
        return Err(Error::invalid(format!(
            "--state needs exactly two values POS,VEL, got {}",
            state.len()
        )));
    };
    if !(MIN_POSITION..=MAX_POSITION).contains(&pos) || !(-MAX_SPEED..=MAX_SPEED).contains(&vel) {
        return Err(Error::invalid(format!(
            "--state {pos},{vel} is outside [{MIN_POSITION}, {MAX_POSITION}] x [-{MAX_SPEED}, {MAX_SPEED}]"
        )));
    }
    if let Some(a) = actions.iter().find(|a| !a.is_finite()) {
        return Err(Error::invalid(format!("actions must be finite, got {a}")));
    }
    Ok(run([pos, vel], actions))
}

fn run(state: [f64; 2], actions: &[f64]) -> Trajectory {
    let env = MountainCar::state_bias();
    // Mountain Car's transition is deterministic: the stream is never drawn from.
    let mut rng = rng_from_seed(0);
    let mut s = state;
    let mut t = Trajectory {
        positions: vec![s[0]],
        velocities: vec![s[1]],
        rewards: Vec::new(),
        terminated_at: None,
        truncated: actions.len() > TIME_LIMIT,
    };
    for (i, &a) in actions.iter().take(TIME_LIMIT).enumerate() {
        let mut next = [0.0; 2];
        let (r, done) = env.step(&s, &[a], &mut rng, &mut next);
        s = next;
        t.positions.push(s[0]);
        t.velocities.push(s[1]);
        t.rewards.push(r);
        if done {
            t.terminated_at = Some(i);
            t.truncated = false;
            break;
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_step_follows_the_published_update() {
        // gymnasium: v' = v + 0.0015 f − 0.0025 cos(3x), x' = x + v', reward −0.1 a².
        let t = replay("mountain-car", &[-0.5, 0.0], &[0.5]).unwrap();
        let v1 = 0.0015 * 0.5 - 0.0025 * (3.0f64 * -0.5).cos();
        assert!((t.velocities[1] - v1).abs() < 1e-15);
        assert!((t.positions[1] - (-0.5 + v1)).abs() < 1e-15);
        assert!((t.rewards[0] - (-0.1 * 0.25)).abs() < 1e-15);
        assert_eq!((t.terminated_at, t.truncated), (None, false));
    }

    #[test]
    fn bad_arguments_are_invalid() {
        for (env, state, actions) in [
            ("lqg", &[-0.5, 0.0][..], &[1.0][..]),
            ("mountain-car", &[-0.5][..], &[1.0][..]),
            ("mountain-car", &[-5.0, 0.0][..], &[1.0][..]),
            ("mountain-car", &[-0.5, 0.0][..], &[f64::INFINITY][..]),
        ] {
            assert!(replay(env, state, actions).unwrap_err().is_invalid_input());
        }
    }
}
