//! Runs one certified step, or the uncertified step it wraps, a given number of times, for
//! counting instructions per call under callgrind (reproducible on a loaded machine):
//!
//! ```text
//! valgrind --tool=callgrind --callgrind-out-file=/dev/null target/release/examples/certified_instructions STEP on|off N
//! ```
//!
//! STEP is one of `v`, `w_l`, `hp_v`, `exploring` (the steps of the `certified` criterion bench, with
//! the same inputs). Instructions per call = (count at N₁ − count at N₀)/(N₁ − N₀).
use sepg_bounds::constants::TaskConstants;
use sepg_bounds::high_probability::{self as hp, HpForm};
use sepg_bounds::{exploring, v_update, w_update};
use sepg_certified as certified;
use std::hint::black_box;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (Some(step), Some(on), Some(n)) = (
        args.get(1),
        args.get(2).map(|a| a == "on"),
        args.get(3).and_then(|a| a.parse::<u64>().ok()),
    ) else {
        eprintln!("usage: certified_instructions v|w_l|hp_v|exploring on|off N");
        std::process::exit(2);
    };
    let k = TaskConstants::new(0.99, 28.8, 4.0, 8.0).expect("lqg1d constants");
    // the certified steps decide the range of the rounding analysis once, as the uncertified
    // ones validate the constants once
    let task = certified::CertifiedTask::new(&k);
    let (sigma, grad, required) = (0.5, [-3.7], 0.0);
    let mut sink = 0.0;
    for _ in 0..n {
        let s = black_box(sigma);
        let x = match (step.as_str(), on) {
            ("v", false) => v_update::safe_step(&k, s, black_box(&grad), required)
                .ok()
                .and_then(|o| o.chosen_step()),
            ("v", true) => certified::v_safe_step(&task, s, black_box(&grad), required)
                .ok()
                .and_then(|o| o.chosen_step()),
            ("w_l", false) => w_update::safe_step_along_l(&k, s, 0.3, black_box(-2.0), -0.1)
                .ok()
                .and_then(|o| o.chosen_step()),
            ("w_l", true) => certified::w_safe_step_along_l(&task, s, 0.3, black_box(-2.0), -0.1)
                .ok()
                .and_then(|o| o.chosen_step()),
            ("hp_v", false) => {
                hp::v_safe_step(&k, s, black_box(&grad), 0.4, required, HpForm::SignAware)
                    .ok()
                    .and_then(|o| o.chosen_step())
            }
            ("hp_v", true) => certified::hp_v_safe_step(
                &task,
                s,
                black_box(&grad),
                0.4,
                required,
                HpForm::SignAware,
            )
            .ok()
            .and_then(|o| o.chosen_step()),
            ("exploring", false) => {
                exploring::w_exploring_step(&k, s, -0.3, 0.1, black_box(0.4), -0.01)
                    .ok()
                    .and_then(|o| o.chosen_step())
            }
            ("exploring", true) => {
                certified::exploring_safe_step(&task, s, -0.3, 0.1, black_box(0.4), -0.01)
                    .ok()
                    .and_then(|o| o.chosen_step())
            }
            _ => {
                eprintln!("unknown step {step}");
                std::process::exit(2);
            }
        };
        sink += x.unwrap_or(0.0);
    }
    black_box(sink);
}
