//! Parameter sweeps: a base scene and a grid over its keys (parameters, meshes, materials),
//! expanded into one run directory per grid point ([`expand`], [`prepare`]), run here in
//! parallel ([`run_all`]) or one task at a time by a scheduler ([`run_task`], with the scripts
//! of [`emit_slurm`] and [`emit_snakemake`]), and collected into one table ([`collect`]).
//!
//! A sweep's directory holds `sweep.json` (the expansion: the keys, and per task its number,
//! directory, swept values and scene), `tasks.tsv` (the task table), and a directory
//! `run_NNNN/` per task with its `scene.toml`; a task runs that scene into its directory as
//! `memstab run` does, then writes `summary.json` (what `run --json` prints) and adds it and
//! the scene to the run's `manifest.json`. A task is *finished* when that manifest lists and
//! matches `path.json`, `summary.json` and `scene.toml` (the task's own scene) and its stop is
//! not an interrupt: such a task is never run again. A task that failed writes `failed.json`
//! (its one-line reason) instead.
//!
//! The format of the sweep file is in docs/scenes.md ("Sweeps").

mod collect;
mod emit;
mod spec;
mod task;

pub use collect::collect;
pub use emit::{emit_slurm, emit_snakemake, SLURM_SCRIPT, SNAKEFILE};
pub use spec::{expand, MAX_POINTS};
pub use task::{
    run_all, run_scene, run_scene_reporting, run_task, status, TaskOutcome, TaskStatus, Tick,
};

use crate::results::sweep::SweptValue;
use std::path::{Path, PathBuf};

/// The expansion's file in a sweep's directory.
pub const SWEEP_JSON: &str = "sweep.json";
/// The task table.
pub const TASKS_TSV: &str = "tasks.tsv";
/// A task's scene, in its run directory.
pub const TASK_SCENE: &str = "scene.toml";
/// A finished task's summary, in its run directory.
pub const SUMMARY_JSON: &str = "summary.json";
/// A failed task's reason, in its run directory.
pub const FAILED_JSON: &str = "failed.json";

/// Why a sweep cannot go on.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SweepError {
    /// Bad input (a bad sweep file, a directory that holds something else): one line.
    #[error("{0}")]
    Input(String),
    /// Something failed that is not the input (a write).
    #[error("{0}")]
    Failure(String),
}

/// One grid point: a task.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Task {
    /// Its number, from 1.
    pub id: usize,
    /// Its directory, relative to the sweep's (`run_0001`).
    pub dir: String,
    /// The swept values, in the order of [`Expanded::keys`].
    pub values: Vec<SweptValue>,
    /// Its scene, as TOML text.
    pub scene: String,
}

/// A sweep file expanded: what `sweep.json` holds.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Expanded {
    /// The version of memstab that expanded it.
    pub version: String,
    /// The sweep's name.
    pub name: String,
    /// The sweep file.
    pub origin: String,
    /// The base scene's file.
    pub scene: String,
    /// The swept keys, in alphabetical order (the last varies fastest over the tasks).
    pub keys: Vec<String>,
    /// The tasks, one per grid point.
    pub tasks: Vec<Task>,
}

impl Expanded {
    /// Task `id`.
    pub fn task(&self, id: usize) -> Option<&Task> {
        self.tasks.get(id.checked_sub(1)?)
    }

    /// Same keys and tasks (the files and versions it came from aside).
    pub fn same_grid(&self, other: &Expanded) -> bool {
        self.keys == other.keys && self.tasks == other.tasks
    }
}

fn write_text(path: &Path, text: &str) -> Result<(), SweepError> {
    meshes::write::write_whole(path, |w| w.write_all(text.as_bytes()))
        .map_err(|e| SweepError::Failure(format!("cannot write {}: {e}", path.display())))
}

/// Reads the expansion of the sweep in `dir` (its `sweep.json`).
pub fn open(dir: &Path) -> Result<Expanded, SweepError> {
    let file = dir.join(SWEEP_JSON);
    let text = crate::output::read_regular_string(&file).map_err(|e| {
        SweepError::Input(format!(
            "'{}': cannot read {}: {e} (not the directory of a memstab sweep)",
            dir.display(),
            file.display()
        ))
    })?;
    serde_json::from_str(&text).map_err(|e| {
        SweepError::Input(format!(
            "{}: not the expansion of a memstab sweep: {e}",
            file.display()
        ))
    })
}

/// Makes `out` the directory of the sweep `expanded`: creates it (its parent must exist) or
/// checks that it is empty or holds the same sweep (a different one is bad input, nothing
/// written), then writes `sweep.json`, `tasks.tsv` and every task's directory with its
/// `scene.toml` (a scene file already there with the same text is left as it is). Returns the
/// files written.
pub fn prepare(expanded: &Expanded, out: &Path) -> Result<Vec<PathBuf>, SweepError> {
    if out.exists() {
        if !out.is_dir() {
            return Err(SweepError::Input(format!(
                "--out '{}' exists and is not a directory",
                out.display()
            )));
        }
        if out.join(SWEEP_JSON).exists() {
            let old = open(out)?;
            if !old.same_grid(expanded) {
                return Err(SweepError::Input(format!(
                    "--out '{}' holds another sweep ('{}' from {}); give a new directory",
                    out.display(),
                    old.name,
                    old.origin
                )));
            }
        } else if std::fs::read_dir(out).map_or(true, |mut d| d.next().is_some()) {
            return Err(SweepError::Input(format!(
                "--out '{}' is not empty and holds no sweep; give a new directory",
                out.display()
            )));
        }
    } else {
        let parent = match out.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        if !parent.is_dir() {
            return Err(SweepError::Input(format!(
                "--out '{}': the parent directory '{}' does not exist",
                out.display(),
                parent.display()
            )));
        }
        std::fs::create_dir(out).map_err(|e| {
            SweepError::Input(format!("--out '{}': cannot create it: {e}", out.display()))
        })?;
    }
    let mut written = Vec::new();
    let json =
        serde_json::to_string_pretty(expanded).map_err(|e| SweepError::Failure(e.to_string()))?;
    write_text(&out.join(SWEEP_JSON), &format!("{json}\n"))?;
    written.push(out.join(SWEEP_JSON));
    let mut tsv = String::from("task\tdir");
    for k in &expanded.keys {
        tsv.push('\t');
        tsv.push_str(k);
    }
    tsv.push('\n');
    for t in &expanded.tasks {
        tsv.push_str(&format!("{}\t{}", t.id, t.dir));
        for v in &t.values {
            tsv.push('\t');
            tsv.push_str(&v.text.replace(['\t', '\n'], " "));
        }
        tsv.push('\n');
    }
    write_text(&out.join(TASKS_TSV), &tsv)?;
    written.push(out.join(TASKS_TSV));
    for t in &expanded.tasks {
        let dir = out.join(&t.dir);
        if !dir.is_dir() {
            std::fs::create_dir(&dir).map_err(|e| {
                SweepError::Failure(format!("cannot create {}: {e}", dir.display()))
            })?;
        }
        let scene = dir.join(TASK_SCENE);
        if crate::output::read_regular_string(&scene).ok().as_deref() != Some(&t.scene) {
            write_text(&scene, &t.scene)?;
            written.push(scene);
        }
    }
    Ok(written)
}
