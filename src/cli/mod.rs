//! Command-line interface: argument parsing and dispatch.
//!
//! Exit codes: 0 success; 2 bad input (one line on stderr naming the bad value, nothing
//! written); 1 a failure that is not the user's input (a verification or I/O failure).

mod group;
mod mesh;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Stability of pressurized thin membranes, with symmetry-adapted analysis.
#[derive(Debug, Parser)]
#[command(name = "memstab", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Generate a symmetric mesh, verify its group action, optionally write it.
    Mesh(mesh::MeshArgs),
    /// Show a point group: elements, irreps and characters.
    Group(group::GroupArgs),
}

/// An error that ends the command: bad input (exit 2) or a failure (exit 1).
#[derive(Debug)]
pub(crate) enum CliError {
    /// The user's input is wrong; the message names the bad value.
    Input(String),
    /// Something failed that is not the user's input.
    Failure(String),
}

pub(crate) fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(
                e.kind(),
                ErrorKind::DisplayHelp
                    | ErrorKind::DisplayVersion
                    | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
            ) {
                let _ = e.print();
                return if e.use_stderr() {
                    ExitCode::from(2)
                } else {
                    ExitCode::SUCCESS
                };
            }
            // One line naming the bad value, as for every other input error.
            let text = e.render().to_string();
            eprintln!("{}", text.lines().next().unwrap_or("error: bad arguments"));
            return ExitCode::from(2);
        }
    };
    let result = match cli.command {
        Command::Mesh(args) => mesh::run(&args),
        Command::Group(args) => group::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(CliError::Input(m)) => {
            eprintln!("error: {m}");
            ExitCode::from(2)
        }
        Err(CliError::Failure(m)) => {
            eprintln!("error: {m}");
            ExitCode::from(1)
        }
    }
}
