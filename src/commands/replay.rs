//! `sepg replay`: the trajectory of an environment from a given state under a given action
//! sequence (Mountain Car, the rules of gymnasium's `MountainCarContinuous-v0`); the work and
//! the checks of the arguments are [`sepg_runs::replay`], this file parses and prints.

use clap::Args;
use sepg_mdp::mountain_car::TIME_LIMIT;
use sepg_runs::replay::replay;

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

/// Runs `sepg replay`.
pub fn run(args: &ReplayArgs) -> Result<(), CliError> {
    let t = replay(&args.env, &args.state, &args.actions)?;
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
