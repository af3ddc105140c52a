//! `memstab sweep SWEEP.toml --out DIR [--jobs N] [--emit slurm|snakemake] [--task N]`,
//! `memstab sweep DIR [--task N]` and `memstab collect DIR [--x KEY]`: parse, call
//! [`memstab::sweep`], print.
//!
//! A bad sweep file (an unknown key, a grid value the scene refuses, a mesh that cannot be
//! built) is one line naming the key and value, exit 2, nothing written. A sweep with failed
//! tasks exits 1 after listing them; a signal stops it after the running tasks have written
//! what they found (exit 130), and a second `memstab sweep` runs only the tasks not finished.

use super::CliError;
use clap::{Args, ValueEnum};
use memstab::results::sweep::{RunStatus, SweepPointKind};
use memstab::sweep::{Expanded, SweepError, TaskOutcome};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum Emit {
    /// A Slurm job array (`sweep.slurm`) over the task table `tasks.tsv`.
    Slurm,
    /// A Snakefile with a rule per task.
    Snakemake,
}

#[derive(Debug, Args)]
pub(crate) struct SweepArgs {
    /// The sweep file (TOML; docs/scenes.md, "Sweeps"), or the directory of a sweep already
    /// expanded (its tasks that are not finished are run).
    sweep: PathBuf,
    /// The sweep's directory (with a sweep file): created if missing, or one that holds this
    /// same sweep (its finished tasks are skipped).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Tasks run at once (default: the machine's cores).
    #[arg(long, value_parser = clap::value_parser!(u16).range(1..=1024))]
    jobs: Option<u16>,
    /// Write the scheduler's script instead of running the tasks here.
    #[arg(long, value_enum)]
    emit: Option<Emit>,
    /// Run only task N (what the scheduler's scripts run).
    #[arg(long, value_name = "N", conflicts_with = "emit")]
    task: Option<usize>,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
    /// Print one JSON object instead of the summary.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Args)]
pub(crate) struct CollectArgs {
    /// The sweep's directory.
    dir: PathBuf,
    /// The swept key the figure is drawn against (default: the first numeric key that varies).
    #[arg(long, value_name = "KEY")]
    x: Option<String>,
    /// Print one JSON object (the table) instead of the summary.
    #[arg(long)]
    json: bool,
}

fn error(e: SweepError) -> CliError {
    match e {
        SweepError::Input(m) => CliError::Input(m),
        SweepError::Failure(m) => CliError::Failure(m),
    }
}

/// `task 3 (run_0003: material.k = 0.1, mesh.divisions = 4)`.
fn describe(expanded: &Expanded, id: usize) -> String {
    let Some(t) = expanded.task(id) else {
        return format!("task {id}");
    };
    let values: Vec<String> = expanded
        .keys
        .iter()
        .zip(&t.values)
        .map(|(k, v)| format!("{k} = {}", v.text))
        .collect();
    format!("task {id} ({}: {})", t.dir, values.join(", "))
}

pub(crate) fn run(args: &SweepArgs) -> Result<(), CliError> {
    let (expanded, dir) = if args.sweep.is_dir() {
        if args.out.is_some() {
            return Err(CliError::Input(format!(
                "--out: '{}' is a sweep's directory already; give the sweep file to expand it elsewhere",
                args.sweep.display()
            )));
        }
        (
            memstab::sweep::open(&args.sweep).map_err(error)?,
            args.sweep.clone(),
        )
    } else {
        let Some(out) = &args.out else {
            return Err(CliError::Input(format!(
                "--out DIR is needed with the sweep file '{}'",
                args.sweep.display()
            )));
        };
        let expanded = memstab::sweep::expand(&args.sweep).map_err(error)?;
        if let Some(n) = args.task.filter(|&n| expanded.task(n).is_none()) {
            return Err(CliError::Input(format!(
                "--task {n}: the sweep has tasks 1 to {}",
                expanded.tasks.len()
            )));
        }
        memstab::sweep::prepare(&expanded, out).map_err(error)?;
        (expanded, out.clone())
    };
    if let Some(n) = args.task {
        return one_task(&expanded, &dir, n, args.json);
    }
    if let Some(emit) = args.emit {
        let binary = std::env::current_exe()
            .map_err(|e| CliError::Failure(format!("cannot find the memstab binary: {e}")))?;
        let files = match emit {
            Emit::Slurm => memstab::sweep::emit_slurm(&expanded, &dir, &binary),
            Emit::Snakemake => memstab::sweep::emit_snakemake(&expanded, &dir, &binary),
        }
        .map_err(error)?;
        if args.json {
            let json = serde_json::json!({ "sweep": expanded.name, "dir": dir, "tasks": expanded.tasks.len(), "files": files });
            out!("{json}");
        } else {
            out!(
                "sweep '{}': {} tasks in {}",
                expanded.name,
                expanded.tasks.len(),
                dir.display()
            );
            for f in &files {
                out!("wrote {}", f.display());
            }
            match emit {
                Emit::Slurm => out!(
                    "submit: sbatch {}",
                    dir.join(memstab::sweep::SLURM_SCRIPT).display()
                ),
                Emit::Snakemake => out!(
                    "run: snakemake --snakefile {} --cores 2",
                    dir.join(memstab::sweep::SNAKEFILE).display()
                ),
            }
            out!("then: memstab collect {}", dir.display());
        }
        return Ok(());
    }
    run_here(&expanded, &dir, args)
}

/// Task `n` alone (a scheduler's job): one line, exit 1 when it failed.
fn one_task(expanded: &Expanded, dir: &Path, n: usize, json: bool) -> Result<(), CliError> {
    let Some(task) = expanded.task(n) else {
        return Err(CliError::Input(format!(
            "--task {n}: the sweep has tasks 1 to {}",
            expanded.tasks.len()
        )));
    };
    let outcome = memstab::sweep::run_task(dir, task).map_err(error)?;
    let what = describe(expanded, n);
    let (status, line) = match &outcome {
        TaskOutcome::Skipped => ("skipped", format!("{what}: finished before, skipped")),
        TaskOutcome::Finished(stop) => ("finished", format!("{what}: finished ({stop})")),
        TaskOutcome::Failed(m) => ("failed", format!("{what}: failed: {m}")),
        TaskOutcome::Interrupted => ("interrupted", format!("{what}: interrupted")),
        TaskOutcome::NotStarted => ("not-started", format!("{what}: not started (a signal)")),
        TaskOutcome::Busy(m) => ("busy", format!("{what}: {m}")),
    };
    if json {
        out!(
            "{}",
            serde_json::json!({ "task": n, "dir": task.dir, "status": status })
        );
    } else {
        out!("{line}");
    }
    match outcome {
        TaskOutcome::Skipped | TaskOutcome::Finished(_) => Ok(()),
        TaskOutcome::Interrupted | TaskOutcome::NotStarted => Err(CliError::Interrupted(line)),
        TaskOutcome::Failed(_) | TaskOutcome::Busy(_) => Err(CliError::Failure(line)),
    }
}

/// Every task here, `--jobs` at a time, with a bar over the tasks.
fn run_here(expanded: &Expanded, dir: &Path, args: &SweepArgs) -> Result<(), CliError> {
    let jobs = args.jobs.map_or_else(
        || std::thread::available_parallelism().map_or(1, |n| n.get()),
        usize::from,
    );
    let n = expanded.tasks.len();
    let bar = if !args.quiet && !args.json && std::io::stderr().is_terminal() {
        let style = indicatif::ProgressStyle::with_template(
            "[{elapsed_precise}] {bar:30.cyan/blue} {pos}/{len} tasks {msg}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
        .progress_chars("#>-");
        indicatif::ProgressBar::new(n as u64).with_style(style)
    } else {
        indicatif::ProgressBar::hidden()
    };
    let done = |id: usize, o: &TaskOutcome| {
        bar.inc(1);
        if let TaskOutcome::Failed(_) = o {
            bar.set_message(format!("(task {id} failed)"));
        }
    };
    let outcomes =
        memstab::sweep::run_all(expanded, dir, jobs.min(n.max(1)), &done).map_err(error)?;
    bar.finish_and_clear();
    let count = |f: fn(&TaskOutcome) -> bool| outcomes.iter().filter(|(_, o)| f(o)).count();
    let ran = count(|o| matches!(o, TaskOutcome::Finished(_)));
    let skipped = count(|o| matches!(o, TaskOutcome::Skipped));
    let listed = |f: fn(&TaskOutcome) -> bool| -> Vec<(usize, String)> {
        outcomes
            .iter()
            .filter(|(_, o)| f(o))
            .map(|(id, o)| {
                (
                    *id,
                    match o {
                        TaskOutcome::Failed(m) | TaskOutcome::Busy(m) => m.clone(),
                        TaskOutcome::Interrupted => "interrupted, what it found is written".into(),
                        _ => "not started".into(),
                    },
                )
            })
            .collect()
    };
    let failed = listed(|o| matches!(o, TaskOutcome::Failed(_) | TaskOutcome::Busy(_)));
    let stopped = listed(|o| matches!(o, TaskOutcome::Interrupted | TaskOutcome::NotStarted));
    if args.json {
        let list = |l: &[(usize, String)]| -> Vec<serde_json::Value> {
            l.iter()
                .map(|(id, m)| serde_json::json!({ "task": id, "dir": expanded.task(*id).map(|t| &t.dir), "message": m }))
                .collect()
        };
        let json = serde_json::json!({
            "sweep": expanded.name, "dir": dir, "tasks": n, "jobs": jobs, "ran": ran,
            "skipped": skipped, "failed": list(&failed), "stopped": list(&stopped),
        });
        out!("{json}");
    } else {
        out!(
            "sweep '{}': {n} tasks in {} ({jobs} at a time)",
            expanded.name,
            dir.display()
        );
        out!(
            "ran {ran}, skipped {skipped} (finished before), failed {}, stopped {}",
            failed.len(),
            stopped.len()
        );
        for (id, m) in &failed {
            out!("  failed: {}: {m}", describe(expanded, *id));
        }
        for (id, m) in &stopped {
            out!("  stopped: {}: {m}", describe(expanded, *id));
        }
        out!("then: memstab collect {}", dir.display());
    }
    if !stopped.is_empty() {
        return Err(CliError::Interrupted(format!(
            "{} of {n} tasks were stopped; `memstab sweep {}` runs the rest",
            stopped.len(),
            dir.display()
        )));
    }
    if !failed.is_empty() {
        return Err(CliError::Failure(format!(
            "{} of {n} tasks failed (listed above)",
            failed.len()
        )));
    }
    Ok(())
}

pub(crate) fn collect(args: &CollectArgs) -> Result<(), CliError> {
    let table = memstab::sweep::collect(&args.dir).map_err(error)?;
    let axis = memstab::output::figure_axis(&table, args.x.as_deref()).map_err(CliError::Input)?;
    let files = memstab::output::write_sweep_table(&args.dir, &table, axis)
        .map_err(|e| CliError::Failure(e.to_string()))?;
    if args.json {
        let json = serde_json::json!({ "table": table, "files": files });
        out!("{json}");
        return Ok(());
    }
    let count = |s: RunStatus| table.runs.iter().filter(|r| r.status == s).count();
    out!(
        "sweep '{}': {} runs: {} finished, {} failed, {} cut short, {} not run",
        table.name,
        table.runs.len(),
        count(RunStatus::Finished),
        count(RunStatus::Failed),
        count(RunStatus::CutShort),
        count(RunStatus::NotRun)
    );
    let of = |k: SweepPointKind| table.points.iter().filter(|p| p.point == k).count();
    let ends = of(SweepPointKind::CuspEnd);
    out!(
        "merged: {} critical and {} turning points of the finished runs{}",
        of(SweepPointKind::Critical),
        of(SweepPointKind::Turning),
        if ends > 0 {
            format!(
                ", and {ends} ends of pairs of cusps (their value: {})",
                table.third.as_deref().unwrap_or("the third parameter")
            )
        } else {
            String::new()
        }
    );
    let unfinished: Vec<_> = table.unfinished().collect();
    if !unfinished.is_empty() {
        out!("not merged:");
        for r in unfinished {
            let values: Vec<String> = table
                .keys
                .iter()
                .zip(&r.values)
                .map(|(k, v)| format!("{k} = {}", v.text))
                .collect();
            let why = r
                .message
                .as_deref()
                .map(|m| format!(": {m}"))
                .unwrap_or_default();
            out!(
                "  task {} ({}: {}) {}{why}",
                r.task,
                r.dir,
                values.join(", "),
                r.status
            );
        }
    }
    let against = axis.map_or("the task number", |k| table.keys[k].as_str());
    for f in &files {
        out!("wrote {}", f.display());
    }
    out!("the figure: the critical and turning values against {against}");
    Ok(())
}
