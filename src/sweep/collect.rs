//! A sweep's runs read back into one table: every finished run's turning and critical points
//! (from its `summary.json`) and, for a `cusp-curve` run, where its pairs of cusps end (from
//! its `cusp_curve.json`), each file checked against the run's manifest; every other run
//! listed with its status and why.

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

/// An end of a pair of cusps as `cusp_curve.json` writes it.
#[derive(Deserialize)]
struct PairEndIn {
    kind: String,
    bracket: [f64; 2],
    estimate: Option<f64>,
}

/// The part of a `cusp-curve` run's `cusp_curve.json` that is collected.
#[derive(Deserialize)]
struct CuspCurveIn {
    third: String,
    irrep: String,
    ends: Vec<PairEndIn>,
}

/// A `cusp-curve` run's report.
pub(crate) const CUSP_CURVE_JSON: &str = "cusp_curve.json";

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

/// Whether the manifest of the run in `run` lists `name` (a file the run wrote).
fn listed(run: &Path, name: &str) -> bool {
    crate::output::read_regular_string(&run.join(crate::output::MANIFEST))
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .is_some_and(|m| lists(&m, name))
}

/// Whether the parsed `manifest` lists `name`.
pub(crate) fn lists(manifest: &serde_json::Value, name: &str) -> bool {
    manifest["files"]
        .as_array()
        .is_some_and(|f| f.iter().any(|e| e["file"] == *name))
}

/// The pair ends of the `cusp-curve` run in `run`, checked against its manifest; `None` for
/// a run of another analysis.
fn cusp_ends(run: &Path) -> Result<Option<CuspCurveIn>, String> {
    if !listed(run, CUSP_CURVE_JSON) && !run.join(CUSP_CURVE_JSON).exists() {
        return Ok(None);
    }
    crate::output::verify(run, &[CUSP_CURVE_JSON])?;
    let file = run.join(CUSP_CURVE_JSON);
    crate::output::read_regular_string(&file)
        .map_err(|e| e.to_string())
        .and_then(|t| serde_json::from_str::<CuspCurveIn>(&t).map_err(|e| e.to_string()))
        .map(Some)
        .map_err(|e| format!("{}: {e}", file.display()))
}

/// Collects the sweep in `dir` ([`super::open`]): a run whose summary (or, for a
/// `cusp-curve` run, its report) cannot be read counts as cut short, with the reason.
pub fn collect(dir: &Path) -> Result<SweepTable, SweepError> {
    let expanded = super::open(dir)?;
    let mut table = SweepTable {
        name: expanded.name.clone(),
        keys: expanded.keys.clone(),
        control: None,
        third: None,
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
                            step: Some(t.step),
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
                            step: Some(c.step),
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
            if s.status == RunStatus::Finished {
                match cusp_ends(&dir.join(&task.dir)) {
                    Ok(None) => {}
                    Ok(Some(curve)) => {
                        table.third.get_or_insert(curve.third);
                        for end in curve.ends {
                            // Without an estimate the bracket's middle, flagged.
                            let value = end
                                .estimate
                                .unwrap_or(0.5 * (end.bracket[0] + end.bracket[1]));
                            table.points.push(SweepPoint {
                                task: task.id,
                                point: SweepPointKind::CuspEnd,
                                kind: end.kind,
                                irrep: Some(curve.irrep.clone()),
                                multiplicity: None,
                                isotropy: None,
                                m: None,
                                step: None,
                                value,
                                valid: end.estimate.is_some(),
                                flags: if end.estimate.is_some() {
                                    Vec::new()
                                } else {
                                    vec!["bracket-only".to_string()]
                                },
                            });
                        }
                    }
                    Err(e) => {
                        table.points.retain(|p| p.task != task.id);
                        s.status = RunStatus::CutShort;
                        s.message = Some(e);
                    }
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
