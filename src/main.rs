//! The `sepg` command-line interface.

mod cli;
mod commands;
mod output;
mod progress;

fn main() -> std::process::ExitCode {
    cli::run()
}
