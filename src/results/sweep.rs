//! A parameter sweep's collected results: every finished run's turning and critical points
//! with the swept values as columns, and every run's status (finished, failed, cut short, not
//! run), so that no run is merged or left out silently.

use serde::{Deserialize, Serialize};

/// One swept value of a grid point: its text (a number as TOML writes it, a string as is, a
/// table as an inline TOML table) and its number, when it is one.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweptValue {
    /// The value as text, the table's cell.
    pub text: String,
    /// The value as a number (an integer or a float), for a figure's axis.
    pub number: Option<f64>,
}

/// What became of one run of a sweep.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RunStatus {
    /// Its outputs and manifest are written and match, and it was not interrupted.
    Finished,
    /// The run failed (its start did not converge, its scene could not be built …).
    Failed,
    /// A signal stopped it, or it was killed, or its files no longer match its manifest.
    CutShort,
    /// Nothing of it is there.
    NotRun,
}

impl std::fmt::Display for RunStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Finished => "finished",
            Self::Failed => "failed",
            Self::CutShort => "cut-short",
            Self::NotRun => "not-run",
        })
    }
}

/// One run of a sweep: its task number, directory, swept values and status.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepRun {
    /// The task number (from 1).
    pub task: usize,
    /// Its directory, relative to the sweep's.
    pub dir: String,
    /// The swept values, in the order of [`SweepTable::keys`].
    pub values: Vec<SweptValue>,
    /// What became of it.
    pub status: RunStatus,
    /// Why its path stopped (a finished or interrupted run).
    pub stop: Option<String>,
    /// Why it failed or counts as cut short (one line).
    pub message: Option<String>,
    /// The mesh it ran on (a finished run's, from its `path.json`).
    #[serde(default)]
    pub mesh: Option<super::MeshInfo>,
}

/// Which list of a run a [`SweepPoint`] comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SweepPointKind {
    /// A critical point (a singular block of the tangent).
    Critical,
    /// A turning point of the control.
    Turning,
    /// Where a pair of cusps ends, from a `cusp-curve` run: its value is the run's third
    /// parameter there, not the control.
    CuspEnd,
}

impl std::fmt::Display for SweepPointKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Critical => "critical",
            Self::Turning => "turning",
            Self::CuspEnd => "cusp-end",
        })
    }
}

/// One turning or critical point of a finished run, or the end of a pair of cusps of a
/// `cusp-curve` run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepPoint {
    /// The run's task number.
    pub task: usize,
    /// Critical or turning.
    pub point: SweepPointKind,
    /// Its kind: `maximum`/`minimum` for a turning point, what the pair ends in for a cusp end
    /// (`swallowtail`, `lips-or-beaks`, `undecided`), the critical kind otherwise.
    pub kind: String,
    /// The irrep of the singular block (critical points; a cusp end: its curve's).
    pub irrep: Option<String>,
    /// The multiplicity of the zero eigenvalue in K (critical points).
    pub multiplicity: Option<usize>,
    /// The isotropy subgroup of the mode (critical points).
    pub isotropy: Option<String>,
    /// The mode's wave number about z, where the mesh has an axis.
    pub m: Option<usize>,
    /// The path step before it (none for a cusp end).
    pub step: Option<usize>,
    /// The control's value there; a cusp end's: the third parameter's where the pair ends
    /// (its estimate, or the middle of its bracket where there is none).
    pub value: f64,
    /// No flag raised.
    pub valid: bool,
    /// The names of the flags raised.
    pub flags: Vec<String>,
}

/// A sweep's collected results.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepTable {
    /// The sweep's name.
    pub name: String,
    /// The swept keys (scene keys such as `material.k`), the table's value columns.
    pub keys: Vec<String>,
    /// The control parameter of the runs (the first finished run's).
    pub control: Option<String>,
    /// The third parameter of the `cusp-curve` runs (the first one's): the value of their
    /// cusp ends.
    #[serde(default)]
    pub third: Option<String>,
    /// Every run, in task order.
    pub runs: Vec<SweepRun>,
    /// The points of the finished runs, in task order.
    pub points: Vec<SweepPoint>,
}

impl SweepTable {
    /// The run of task `task`.
    pub fn run(&self, task: usize) -> Option<&SweepRun> {
        self.runs.iter().find(|r| r.task == task)
    }

    /// The runs with a status other than finished.
    pub fn unfinished(&self) -> impl Iterator<Item = &SweepRun> {
        self.runs.iter().filter(|r| r.status != RunStatus::Finished)
    }
}
