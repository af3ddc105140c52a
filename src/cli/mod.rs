//! Command-line interface: argument parsing and dispatch.
//!
//! Exit codes: 0 success; 2 bad input (one line on stderr naming the bad value, nothing
//! written); 1 a failure that is not the user's input (a verification or I/O failure).

/// `println!` for the commands' output: when stdout is a pipe whose reader has gone (`memstab
/// demo | head -1`), the process ends quietly with exit code 0 instead of panicking.
macro_rules! out {
    () => {
        $crate::cli::print_line(format_args!(""))
    };
    ($($arg:tt)*) => {
        $crate::cli::print_line(format_args!($($arg)*))
    };
}

mod bench;
mod branch;
mod common;
mod compare;
mod demo;
mod diagram;
mod export;
mod group;
mod mesh;
mod run;
mod spectrum;
mod summary;
mod sweep;

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
    /// Run a scene: follow its path and write path.csv, path.json, path.svg, VTUs + path.pvd.
    Run(run::RunArgs),
    /// Switch branches at a critical point of a finished run: branches.json, branch_NN/, diagram.svg.
    Branch(branch::BranchArgs),
    /// The global diagram of a finished path run: every branch to a depth, the second pieces beside its folds.
    Diagram(diagram::DiagramArgs),
    /// Run the bundled demo (a k = 0.1 balloon) and compare it with the closed form.
    Demo(demo::DemoArgs),
    /// The tangent's spectrum by irrep at the scene's start state (or at --at values).
    Spectrum(spectrum::SpectrumArgs),
    /// The same scene on meshes of different symmetry: critical points matched, splits measured.
    Compare(compare::CompareArgs),
    /// What accuracy costs in time: balloon refinement study, symmetry payoff, ponding ladder.
    Bench(bench::BenchArgs),
    /// Write the full tangent K at the scene's start state in Matrix Market format.
    ExportMatrix(export::ExportArgs),
    /// A base scene over a grid of its keys: one run per point, here or by a scheduler.
    Sweep(sweep::SweepArgs),
    /// A sweep's finished runs in one table and figure; the others listed.
    Collect(sweep::CollectArgs),
}

/// Writes one line to stdout; a closed pipe ends the process quietly (exit 0), any other
/// write error with exit code 1.
pub(crate) fn print_line(args: std::fmt::Arguments<'_>) {
    use std::io::Write;
    let mut stdout = std::io::stdout().lock();
    if let Err(e) = stdout
        .write_fmt(args)
        .and_then(|()| stdout.write_all(b"\n"))
    {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(0);
        }
        eprintln!("error: cannot write to stdout: {e}");
        std::process::exit(1);
    }
}

/// An error that ends the command: bad input (exit 2) or a failure (exit 1).
#[derive(Debug)]
pub(crate) enum CliError {
    /// The user's input is wrong; the message names the bad value.
    Input(String),
    /// Something failed that is not the user's input.
    Failure(String),
    /// A signal stopped the command after it wrote what it had (exit code 130).
    Interrupted(String),
}

pub(crate) fn main() -> ExitCode {
    // SIGINT and SIGTERM: the analyses stop at their next point and their outputs are
    // written; a second signal ends the process at once.
    let _ = ctrlc::set_handler(|| {
        if memstab::continuation::interrupt::requested() {
            std::process::exit(130);
        }
        memstab::continuation::interrupt::request();
    });
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
            // The lines before the first blank one, joined: clap puts the bad value or the
            // missing argument on a line of its own.
            let text = e.render().to_string();
            let first: Vec<&str> = text
                .lines()
                .take_while(|l| !l.trim().is_empty())
                .map(str::trim)
                .collect();
            let line = if first.is_empty() {
                "error: bad arguments".to_string()
            } else {
                first.join(" ")
            };
            eprintln!("{line}");
            return ExitCode::from(2);
        }
    };
    let result = match cli.command {
        Command::Mesh(args) => mesh::run(&args),
        Command::Group(args) => group::run(&args),
        Command::Run(args) => run::run(&args),
        Command::Branch(args) => branch::run(&args),
        Command::Diagram(args) => diagram::run(&args),
        Command::Demo(args) => demo::demo(&args),
        Command::Spectrum(args) => spectrum::run(&args),
        Command::Compare(args) => compare::run(&args),
        Command::Bench(args) => bench::run(&args),
        Command::ExportMatrix(args) => export::run(&args),
        Command::Sweep(args) => sweep::run(&args),
        Command::Collect(args) => sweep::collect(&args),
    };
    // A command that a signal stopped (its work cut short at the next safe point, or a
    // solve it ended) exits 130, whatever it returned; bad input stays bad input.
    let result = match result {
        Ok(()) | Err(CliError::Failure(_)) if memstab::continuation::interrupt::requested() => {
            Err(CliError::Interrupted(match result {
                Err(CliError::Failure(m)) => m,
                _ => "stopped at a signal; what was found is printed or written".into(),
            }))
        }
        other => other,
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(CliError::Input(m)) => {
            eprintln!("error: {}", memstab::text::message(&m));
            ExitCode::from(2)
        }
        Err(CliError::Failure(m)) => {
            eprintln!("error: {}", memstab::text::message(&m));
            ExitCode::from(1)
        }
        Err(CliError::Interrupted(m)) => {
            eprintln!("interrupted: {}", memstab::text::message(&m));
            ExitCode::from(130)
        }
    }
}
