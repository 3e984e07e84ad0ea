//! The `sepg` command-line interface.

mod cli;
mod commands;
mod output;

fn main() -> std::process::ExitCode {
    cli::run()
}
