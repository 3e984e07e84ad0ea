//! `sepg replay`: the trajectory of an environment from a given state under a given action
//! sequence (Mountain Car, the rules of gymnasium's `MountainCarContinuous-v0`).

use clap::Args;
use sepg_mdp::env::Environment;
use sepg_mdp::mountain_car::{MAX_POSITION, MAX_SPEED, MIN_POSITION, MountainCar, TIME_LIMIT};
use sepg_mdp::rng::rng_from_seed;
use serde::Serialize;

use crate::cli::CliError;
use crate::output::to_json_line;

/// Arguments of `sepg replay`.
#[derive(Debug, Args)]
pub struct ReplayArgs {
    /// The environment; only `mountain-car` has a replay.
    #[arg(long)]
    env: String,
    /// Initial state `POS,VEL` (position in [−1.2, 0.6], velocity in [−0.07, 0.07]).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, num_args = 1)]
    state: Vec<f64>,
    /// Raw actions `a1,a2,...` (the force is clip(a, −1, 1); the reward uses the raw action).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, num_args = 1)]
    actions: Vec<f64>,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    json: bool,
}

/// The replayed trajectory. `positions` and `velocities` include the initial state, so they
/// have one more entry than `rewards`.
#[derive(Debug, Serialize)]
struct Trajectory {
    positions: Vec<f64>,
    velocities: Vec<f64>,
    rewards: Vec<f64>,
    /// 0-based index of the action whose step reached the goal, if any.
    terminated_at: Option<usize>,
    /// Whether the 999-step time limit cut the action sequence.
    truncated: bool,
}

fn replay(state: [f64; 2], actions: &[f64]) -> Trajectory {
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

/// Runs `sepg replay`.
pub fn run(args: &ReplayArgs) -> Result<(), CliError> {
    if args.env != "mountain-car" {
        return Err(CliError::usage(format!(
            "replay supports only --env mountain-car, got '{}'",
            args.env
        )));
    }
    let [pos, vel] = args.state[..] else {
        return Err(CliError::usage(format!(
            "--state needs exactly two values POS,VEL, got {}",
            args.state.len()
        )));
    };
    if !(MIN_POSITION..=MAX_POSITION).contains(&pos) || !(-MAX_SPEED..=MAX_SPEED).contains(&vel) {
        return Err(CliError::usage(format!(
            "--state {pos},{vel} is outside [{MIN_POSITION}, {MAX_POSITION}] x [-{MAX_SPEED}, {MAX_SPEED}]"
        )));
    }
    if let Some(a) = args.actions.iter().find(|a| !a.is_finite()) {
        return Err(CliError::usage(format!("actions must be finite, got {a}")));
    }
    let t = replay([pos, vel], &args.actions);
    if args.json {
        print!("{}", to_json_line(&t)?);
    } else {
        println!(
            "{:>5} {:>22} {:>22} {:>14}",
            "step", "position", "velocity", "reward"
        );
        println!(
            "{:>5} {:>22.17} {:>22.17}",
            0, t.positions[0], t.velocities[0]
        );
        for (i, r) in t.rewards.iter().enumerate() {
            println!(
                "{:>5} {:>22.17} {:>22.17} {:>14.6}",
                i + 1,
                t.positions[i + 1],
                t.velocities[i + 1],
                r
            );
        }
        match t.terminated_at {
            Some(i) => println!("terminated at action {i}"),
            None if t.truncated => println!("truncated at the {TIME_LIMIT}-step time limit"),
            None => println!("not terminated"),
        }
    }
    Ok(())
}
