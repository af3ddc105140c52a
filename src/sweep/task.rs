//! One task of a sweep run into its directory as `memstab run` runs a scene, its status read
//! back from its files, and every task run here in parallel.

use super::{Expanded, SweepError, Task, FAILED_JSON, SUMMARY_JSON, TASK_SCENE};
use crate::analysis::compare::{CompareError, RefineOptions, Refiner};
use crate::continuation::interrupt;
use crate::output::{RunSummary, MANIFEST};
use crate::results::sweep::RunStatus;
use crate::results::StopReason;
use crate::scene::Scene;
use rayon::prelude::*;
use std::path::Path;

/// A task's status read from its directory, with why its path stopped (a run that wrote its
/// outputs) and, for a failed or cut-short one, why (one line).
#[derive(Debug, Clone, PartialEq)]
pub struct TaskStatus {
    /// Finished, failed, cut short or not run.
    pub status: RunStatus,
    /// The stop reason its manifest records.
    pub stop: Option<String>,
    /// Why it failed or counts as cut short.
    pub message: Option<String>,
}

/// What [`run_task`] did.
#[derive(Debug, Clone, PartialEq)]
pub enum TaskOutcome {
    /// The task was finished already: nothing was run.
    Skipped,
    /// The task ran to its end; why its path stopped.
    Finished(String),
    /// The task failed; why (one line), also in its `failed.json`.
    Failed(String),
    /// A signal stopped it: what it found is written, its stop is `interrupted`.
    Interrupted,
    /// A signal came before it started: not run.
    NotStarted,
    /// Another process is running it.
    Busy(String),
}

/// The status of `task` in the sweep directory `dir` (see the module [`super`]).
pub fn status(dir: &Path, task: &Task) -> TaskStatus {
    let run = dir.join(&task.dir);
    let of = |status, stop: Option<String>, message: Option<String>| TaskStatus {
        status,
        stop,
        message,
    };
    if run.join(MANIFEST).is_file() {
        let manifest: Option<serde_json::Value> =
            crate::output::read_regular_string(&run.join(MANIFEST))
                .ok()
                .and_then(|t| serde_json::from_str(&t).ok());
        let stop = manifest
            .as_ref()
            .and_then(|m| m["stop"].as_str())
            .map(str::to_string);
        // Every file `collect` reads: a run with one of them edited or gone is run again.
        let mut read = vec!["path.json", SUMMARY_JSON, TASK_SCENE];
        let cusps = super::collect::CUSP_CURVE_JSON;
        let lists = manifest
            .as_ref()
            .is_some_and(|m| super::collect::lists(m, cusps));
        if lists || run.join(cusps).exists() {
            read.push(cusps);
        }
        if let Err(e) = crate::output::verify(&run, &read) {
            return of(RunStatus::CutShort, stop, Some(e));
        }
        if crate::output::read_regular_string(&run.join(TASK_SCENE))
            .ok()
            .as_deref()
            != Some(task.scene.as_str())
        {
            return of(
                RunStatus::CutShort,
                stop,
                Some(format!(
                    "{}: not the task's scene",
                    run.join(TASK_SCENE).display()
                )),
            );
        }
        if stop.as_deref() == Some(StopReason::Interrupted.to_string().as_str()) {
            return of(RunStatus::CutShort, stop, Some("interrupted".into()));
        }
        return of(RunStatus::Finished, stop, None);
    }
    if let Ok(text) = crate::output::read_regular_string(&run.join(FAILED_JSON)) {
        let message = serde_json::from_str::<serde_json::Value>(&text)
            .ok()
            .and_then(|v| v["message"].as_str().map(str::to_string))
            .unwrap_or_else(|| format!("{} is not readable", run.join(FAILED_JSON).display()));
        return of(RunStatus::Failed, None, Some(message));
    }
    if run.join("path.json").exists() {
        return of(
            RunStatus::CutShort,
            None,
            Some(format!(
                "{} has no {MANIFEST}: the run was cut short",
                run.display()
            )),
        );
    }
    of(RunStatus::NotRun, None, None)
}

/// Runs `task` of the sweep in `dir` (prepared by [`super::prepare`]) unless it is finished:
/// loads its scene, builds and runs the study and writes its outputs as `memstab run` does (its
/// `[refine]` included), then `summary.json`, added with the scene to the run's manifest. A
/// failure is written into the task's `failed.json` and returned, never raised: only a write
/// of the sweep's own files is an error.
pub fn run_task(dir: &Path, task: &Task) -> Result<TaskOutcome, SweepError> {
    if status(dir, task).status == RunStatus::Finished {
        return Ok(TaskOutcome::Skipped);
    }
    if interrupt::requested() {
        return Ok(TaskOutcome::NotStarted);
    }
    let run = dir.join(&task.dir);
    if !run.is_dir() {
        std::fs::create_dir(&run)
            .map_err(|e| SweepError::Failure(format!("cannot create {}: {e}", run.display())))?;
    }
    let scene_file = run.join(TASK_SCENE);
    if crate::output::read_regular_string(&scene_file)
        .ok()
        .as_deref()
        != Some(task.scene.as_str())
    {
        super::write_text(&scene_file, &task.scene)?;
    }
    let _lock = match crate::output::RunLock::acquire(&run) {
        Ok(lock) => lock,
        Err(e @ crate::output::LockError::Busy { .. }) => {
            return Ok(TaskOutcome::Busy(e.to_string()))
        }
        Err(e) => return Err(SweepError::Failure(e.to_string())),
    };
    // What an earlier attempt left (an interrupted run's states, a failure's reason) goes:
    // the run directory holds one run, all of it in its manifest.
    clear(&run)?;
    let failed = run.join(FAILED_JSON);
    match execute(&run, &scene_file) {
        Ok(outcome) => Ok(outcome),
        Err(_) if interrupt::requested() => Ok(TaskOutcome::Interrupted),
        Err(message) => {
            let message = crate::text::one_line(&message);
            let json = serde_json::json!({ "task": task.id, "message": message });
            super::write_text(&failed, &format!("{json}\n"))?;
            Ok(TaskOutcome::Failed(message))
        }
    }
}

/// Removes everything in the run directory `run` but its scene and its lock.
fn clear(run: &Path) -> Result<(), SweepError> {
    let entries = std::fs::read_dir(run)
        .map_err(|e| SweepError::Failure(format!("cannot read {}: {e}", run.display())))?;
    for entry in entries.filter_map(Result::ok) {
        let name = entry.file_name();
        if name == TASK_SCENE || name == crate::output::LOCK {
            continue;
        }
        let path = entry.path();
        let removed = if entry.file_type().is_ok_and(|t| t.is_dir()) {
            std::fs::remove_dir_all(&path)
        } else {
            std::fs::remove_file(&path)
        };
        removed
            .map_err(|e| SweepError::Failure(format!("cannot remove {}: {e}", path.display())))?;
    }
    Ok(())
}

/// The run of one task's scene into `run`: an error is the task's failure, one line.
fn execute(run: &Path, scene_file: &Path) -> Result<TaskOutcome, String> {
    let scene = Scene::load(scene_file).map_err(|e| e.to_string())?;
    let stop = run_scene(scene, run)?;
    crate::output::add_to_manifest(run, &[scene_file.to_path_buf()], None, "")
        .map_err(|e| e.to_string())?;
    Ok(if stop == StopReason::Interrupted {
        TaskOutcome::Interrupted
    } else {
        TaskOutcome::Finished(stop.to_string())
    })
}

/// Runs `scene` into the directory `run` (which must exist) as `memstab run` does, its
/// `[refine]` included, and writes `summary.json` there (what `memstab run --json` prints),
/// added to the run's manifest; returns why the path stopped. An error is one line: the scene
/// cannot be built, its start does not converge, a file cannot be written.
pub fn run_scene(scene: Scene, run: &Path) -> Result<StopReason, String> {
    run_scene_reporting(scene, run, &mut |_| {})
}

/// One converged point of a run as a progress display shows it (the command line's bar).
#[derive(Debug, Clone, PartialEq)]
pub struct Tick {
    /// The points converged so far.
    pub points: usize,
    /// The control's value at the last one.
    pub value: f64,
    /// Where that value lies in the control's range, in [0, 1] (`None` without a range).
    pub fraction: Option<f64>,
    /// The bar's message: `p = 1.35510 in [0, 2], 120 points`.
    pub message: String,
}

/// As [`run_scene`], calling `report` at every converged point of the path.
pub fn run_scene_reporting(
    scene: Scene,
    run: &Path,
    report: &mut dyn FnMut(&Tick),
) -> Result<StopReason, String> {
    let compare = |e: CompareError| match e {
        CompareError::Input(m) | CompareError::Failure(m) | CompareError::Interrupted(m) => m,
    };
    let refiner = match RefineOptions::resolve(None, false, &scene).map_err(compare)? {
        Some(options) => Some(Refiner::new(&scene, &options).map_err(compare)?),
        None => None,
    };
    let mut study = crate::study::build(scene)?;
    let start = crate::analysis::restart::start_of(&*study)
        .map_err(|e| format!("{}: {e}", study.about().origin))?;
    let clock = std::time::Instant::now();
    let (control, range) = crate::analysis::progress_control(&*study);
    let range = range.filter(|(a, b)| b > a);
    let mut result = crate::analysis::run_from(
        &mut *study,
        &start,
        &mut crate::analysis::Progress(|point: usize, value: f64| {
            report(&Tick {
                points: point + 1,
                value,
                fraction: crate::output::progress_fraction(value, range),
                message: crate::output::progress_message(&control, value, range, point + 1),
            })
        }),
    )
    .map_err(|e| e.to_string())?;
    let interrupted = result.report.stop == StopReason::Interrupted;
    if let Some(refiner) = refiner.filter(|_| !interrupted) {
        let seconds = clock.elapsed().as_secs_f64();
        match refiner.run(&result, seconds, &|_| {}) {
            Ok(Some(r)) => crate::analysis::compare::attach(&mut result, r),
            Ok(None) => {}
            Err(CompareError::Interrupted(_)) => {}
            Err(CompareError::Input(m) | CompareError::Failure(m)) => {
                return Err(format!("refinement: {m}"))
            }
        }
    }
    let written = crate::analysis::write(&*study, &mut result, run).map_err(|e| e.to_string())?;
    let summary = RunSummary::new(&result.report, run, &written);
    let text = serde_json::to_string_pretty(&summary).map_err(|e| e.to_string())?;
    let file = run.join(SUMMARY_JSON);
    super::write_text(&file, &format!("{text}\n")).map_err(|e| e.to_string())?;
    crate::output::add_to_manifest(run, &[file], None, "").map_err(|e| e.to_string())?;
    Ok(result.report.stop)
}

/// Runs every task of the sweep in `dir`, `jobs` at a time (with one, in task order and each
/// task's own work parallel where it is), skipping finished ones; after a signal no task starts. `done` is called
/// after each task with its number and outcome. Returns the outcomes in task order.
pub fn run_all(
    expanded: &Expanded,
    dir: &Path,
    jobs: usize,
    done: &(dyn Fn(usize, &TaskOutcome) + Sync),
) -> Result<Vec<(usize, TaskOutcome)>, SweepError> {
    let one = |t: &super::Task| -> Result<(usize, TaskOutcome), SweepError> {
        let outcome = run_task(dir, t)?;
        done(t.id, &outcome);
        Ok((t.id, outcome))
    };
    if jobs <= 1 {
        // In task order, each task's own parallel work on every core.
        return expanded.tasks.iter().map(one).collect();
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .build()
        .map_err(|e| SweepError::Failure(format!("cannot start {jobs} threads: {e}")))?;
    pool.install(|| expanded.tasks.par_iter().with_max_len(1).map(one).collect())
}
