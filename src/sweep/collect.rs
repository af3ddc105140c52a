//! A sweep's runs read back into one table: every finished run's turning and critical points
//! (from its `summary.json`, checked against its manifest), every other run listed with its
//! status and why.

use super::{status, SweepError, SUMMARY_JSON};
use crate::results::sweep::{RunStatus, SweepPoint, SweepPointKind, SweepRun, SweepTable};
use serde::Deserialize;
use std::path::Path;

/// A flag as `summary.json` writes it: its name is enough here.
#[derive(Deserialize)]
struct FlagIn {
    flag: String,
}

#[derive(Deserialize)]
struct TurningIn {
    kind: String,
    step: usize,
    value: Option<f64>,
    valid: bool,
    flags: Vec<FlagIn>,
}

#[derive(Deserialize)]
struct CriticalIn {
    kind: String,
    irrep: String,
    multiplicity: usize,
    step: usize,
    value: Option<f64>,
    isotropy: String,
    m: Option<usize>,
    valid: bool,
    flags: Vec<FlagIn>,
}

/// The part of a run's `summary.json` (what `memstab run --json` prints) that is collected.
#[derive(Deserialize)]
struct SummaryIn {
    control: String,
    turning_points: Vec<TurningIn>,
    critical: Vec<CriticalIn>,
}

/// The part of a run's `path.json` that names its mesh.
#[derive(Deserialize)]
struct PathIn {
    mesh: crate::results::MeshInfo,
}

/// The mesh of the finished run in `run` (its `path.json`), if it can be read.
fn mesh_of(run: &Path) -> Option<crate::results::MeshInfo> {
    let text = crate::output::read_regular_string(&run.join("path.json")).ok()?;
    serde_json::from_str::<PathIn>(&text).ok().map(|p| p.mesh)
}

/// Collects the sweep in `dir` ([`super::open`]): a run whose summary cannot be read counts
/// as cut short, with the reason.
pub fn collect(dir: &Path) -> Result<SweepTable, SweepError> {
    let expanded = super::open(dir)?;
    let mut table = SweepTable {
        name: expanded.name.clone(),
        keys: expanded.keys.clone(),
        control: None,
        runs: Vec::new(),
        points: Vec::new(),
    };
    for task in &expanded.tasks {
        let mut s = status(dir, task);
        let mut mesh = None;
        if s.status == RunStatus::Finished {
            mesh = mesh_of(&dir.join(&task.dir));
            let file = dir.join(&task.dir).join(SUMMARY_JSON);
            let read = crate::output::read_regular_string(&file)
                .map_err(|e| e.to_string())
                .and_then(|t| serde_json::from_str::<SummaryIn>(&t).map_err(|e| e.to_string()));
            match read {
                Ok(summary) => {
                    table.control.get_or_insert(summary.control);
                    let names = |f: Vec<FlagIn>| f.into_iter().map(|f| f.flag).collect();
                    // A point without a control value (a run without a control) has no place
                    // in the table.
                    for t in summary.turning_points {
                        let Some(value) = t.value else { continue };
                        table.points.push(SweepPoint {
                            task: task.id,
                            point: SweepPointKind::Turning,
                            kind: t.kind,
                            irrep: None,
                            multiplicity: None,
                            isotropy: None,
                            m: None,
                            step: t.step,
                            value,
                            valid: t.valid,
                            flags: names(t.flags),
                        });
                    }
                    for c in summary.critical {
                        let Some(value) = c.value else { continue };
                        table.points.push(SweepPoint {
                            task: task.id,
                            point: SweepPointKind::Critical,
                            kind: c.kind,
                            irrep: Some(c.irrep),
                            multiplicity: Some(c.multiplicity),
                            isotropy: Some(c.isotropy),
                            m: c.m,
                            step: c.step,
                            value,
                            valid: c.valid,
                            flags: names(c.flags),
                        });
                    }
                }
                Err(e) => {
                    s.status = RunStatus::CutShort;
                    s.message = Some(format!("{}: {e}", file.display()));
                }
            }
        }
        table.runs.push(SweepRun {
            task: task.id,
            dir: task.dir.clone(),
            values: task.values.clone(),
            status: s.status,
            stop: s.stop,
            message: s.message,
            mesh,
        });
    }
    Ok(table)
}
