//! The outputs of a global diagram (`type = "diagram"`): `diagram.json` — the graph of
//! `branches.json` with the second pieces beside the path's folds —, one directory per piece
//! found (`partner_01/`, … with the files of a path) and `partners.svg`, the path and every
//! piece in the measure of `path.svg` against the control.

use super::diagram::{write_bifurcation_diagram, BifurcationDiagram, DiagramLine, DiagramMark};
use super::states::Drawing;
use super::{write_run, OutputError};
use crate::results::partner::Partner;
use crate::results::validity::Flag;
use crate::results::{Branches, CriticalKind, PathReport, PrimaryPath, RunResult, StopReason};
use crate::scene::Scene;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A critical point of a piece, as `diagram.json` lists it.
#[derive(Serialize)]
struct PieceCritical<'a> {
    kind: CriticalKind,
    irrep: &'a str,
    multiplicity: usize,
    /// The control's value.
    value: f64,
    /// The wave number of its mode, where the mesh has one.
    #[serde(skip_serializing_if = "Option::is_none")]
    m: Option<usize>,
    /// Whether no flag is raised (docs/theory.md §8.10).
    valid: bool,
    /// Why it may not be a result of the model.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    flags: Vec<Flag>,
}

/// One fold's (or dip's) search, as `diagram.json` lists it.
#[derive(Serialize)]
struct PartnerJson<'a> {
    /// The fold's number among the path's critical points (absent beside a dip).
    #[serde(skip_serializing_if = "Option::is_none")]
    fold: Option<usize>,
    /// The path's step at the dip the search was made beside (docs/theory.md §16.7).
    #[serde(skip_serializing_if = "Option::is_none")]
    dip: Option<usize>,
    /// The control's value there.
    value: f64,
    /// Fixed-amplitude solves tried.
    tried: usize,
    found: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    directory: Option<&'a str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    amplitude: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    gap: Option<f64>,
    /// The piece's first state (at the fold's control value): parameters and measures.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    start: BTreeMap<&'a str, f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    points: Option<usize>,
    critical: Vec<PieceCritical<'a>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    stop: Option<&'a StopReason>,
    #[serde(skip_serializing_if = "Option::is_none")]
    note: Option<&'a str>,
}

fn json_of(p: &Partner) -> PartnerJson<'_> {
    let piece = p.piece.as_ref();
    let report = piece.map(|x| &x.run.report);
    let start = report
        .and_then(|r| {
            r.rows.first().map(|row| {
                r.parameters
                    .iter()
                    .chain(&r.measures)
                    .map(String::as_str)
                    .zip(row.parameters.iter().chain(&row.measures).copied())
                    .collect()
            })
        })
        .unwrap_or_default();
    let critical = report.map_or_else(Vec::new, |r| {
        let c = r.parameters.iter().position(|n| *n == r.control);
        r.critical
            .iter()
            .enumerate()
            .map(|(k, cp)| {
                let flags = r.flags(k);
                PieceCritical {
                    kind: cp.kind,
                    irrep: &cp.irrep,
                    multiplicity: cp.multiplicity,
                    value: c.map_or(0.0, |c| cp.parameters[c]),
                    m: r.wave_numbers.get(k).copied(),
                    valid: flags.is_empty(),
                    flags,
                }
            })
            .collect()
    });
    PartnerJson {
        fold: (p.dip.is_none()).then_some(p.fold),
        dip: p.dip,
        value: p.value,
        tried: p.tried,
        found: piece.is_some(),
        directory: piece.map(|x| x.run.directory.as_str()),
        amplitude: piece.map(|x| x.amplitude),
        gap: piece.map(|x| x.gap),
        start,
        points: report.map(|r| r.rows.len()),
        critical,
        stop: report.map(|r| &r.stop),
        note: p.note.as_deref(),
    }
}

/// Writes the diagram's files into `out`: every piece's directory, `diagram.json` (with the
/// run's `branches`) and `partners.svg` (with the run's `path`); returns the files, in the
/// order written, each with what it holds (empty for a piece's files after its first).
///
/// # Errors
/// The first file that could not be written; a non-finite value (nothing of that file is
/// written).
pub fn write_partners(
    drawing: &dyn Drawing,
    scene: &Scene,
    out: &Path,
    partners: &[Partner],
    branches: Option<&Branches>,
    path: &PathReport,
) -> Result<Vec<(PathBuf, String)>, OutputError> {
    let mut files = Vec::new();
    for p in partners {
        let Some(piece) = &p.piece else { continue };
        let dir = out.join(&piece.run.directory);
        if !dir.is_dir() {
            std::fs::create_dir(&dir).map_err(|source| OutputError::Io {
                path: dir.clone(),
                source,
            })?;
        }
        let mut result = RunResult {
            report: piece.run.report.clone(),
            states: piece.run.states.clone(),
            points: Vec::new(),
            times: Default::default(),
            branches: None,
            outcome: None,
        };
        let written = write_run(drawing, scene, &mut result, &dir).map_err(|e| e.error)?;
        let beside = match p.dip {
            Some(step) => format!("the dip at step {step}"),
            None => format!("critical point {} (a fold", p.fold),
        };
        let what = format!(
            "the second piece beside {beside} at {} = {}{}: gap {}, {} points, {} critical \
             points; the files of a path",
            path.control,
            super::svg::short(p.value),
            if p.dip.is_some() { "" } else { ")" },
            super::svg::short(piece.gap),
            piece.run.report.rows.len(),
            piece.run.report.critical.len()
        );
        for (k, f) in written.files().into_iter().enumerate() {
            files.push((f, if k == 0 { what.clone() } else { String::new() }));
        }
    }
    if let Some(v) = partners
        .iter()
        .flat_map(|p| p.piece.iter().map(|x| x.gap).chain([p.value]))
        .find(|v| !v.is_finite())
    {
        return Err(OutputError::invalid(
            &out.join("diagram.json"),
            format!("a value is {v} (not finite)"),
        ));
    }
    let list: Vec<PartnerJson> = partners.iter().map(json_of).collect();
    let empty = Branches::default();
    let primary = PrimaryPath::of(path);
    let json =
        super::branches::write_diagram_graph(out, branches.unwrap_or(&empty), &primary, &list)?;
    let found = partners.iter().filter(|p| p.piece.is_some()).count();
    files.push((
        json,
        format!(
            "the global diagram: the graph of branches.json and the search beside each of the \
             path's {} folds ({found} second pieces)",
            partners.len()
        ),
    ));
    let mut picture = picture(partners, path);
    let scales = super::Scales::of(scene, path);
    let (xs, ys) = (
        scales.or_name(&picture.control),
        scales.or_name(&picture.y_axis),
    );
    for l in &mut picture.lines {
        for p in &mut l.points {
            *p = (p.0 * xs.factor, p.1 * ys.factor);
        }
    }
    for m in &mut picture.marks {
        (m.x, m.y) = (m.x * xs.factor, m.y * ys.factor);
    }
    (picture.control, picture.y_axis) = (xs.label, ys.label);
    let svg = write_bifurcation_diagram(out, &picture)?;
    let png = super::write_png_beside(&svg)?;
    files.push((
        svg,
        format!(
            "{} against {}: the path and every second piece, stable solid",
            super::default_axes(path).0,
            path.control
        ),
    ));
    files.push((png, "the same figure as an image".to_string()));
    Ok(files)
}

/// The path and every piece: the measure of the path's diagram against the control, the
/// folds and the pieces' critical points marked.
fn picture(partners: &[Partner], path: &PathReport) -> BifurcationDiagram {
    let (name, _) = super::default_axes(path);
    let m = path.measures.iter().position(|n| *n == name).unwrap_or(0);
    let c = path.parameters.iter().position(|p| *p == path.control);
    let at = |parameters: &[f64], measures: &[f64]| {
        (
            c.map_or(0.0, |c| parameters[c]),
            measures.get(m).copied().unwrap_or(0.0),
        )
    };
    let line = |report: &PathReport, class: String, is_path: bool| DiagramLine {
        class,
        path: is_path,
        points: report
            .rows
            .iter()
            .map(|r| at(&r.parameters, &r.measures))
            .collect(),
        stable: report
            .rows
            .iter()
            .map(|r| r.index.map(|i| i == 0))
            .collect(),
    };
    let mut lines = vec![line(path, "path through the start".into(), true)];
    let mut marks = Vec::new();
    for p in partners {
        if let Some(row) = p.dip.and_then(|k| path.rows.get(k)) {
            let (x, y) = at(&row.parameters, &row.measures);
            marks.push(DiagramMark {
                x,
                y,
                label: format!("dip at step {}", row.step),
                kind: "dip of the path".to_string(),
            });
        } else if let Some(cp) = p.fold.checked_sub(1).and_then(|f| path.critical.get(f)) {
            let (x, y) = at(&cp.parameters, &cp.measures);
            marks.push(DiagramMark {
                x,
                y,
                label: format!("fold {}", p.fold),
                kind: "fold of the path".to_string(),
            });
        }
        let Some(piece) = &p.piece else { continue };
        let report = &piece.run.report;
        lines.push(line(report, "second pieces".into(), false));
        for cp in &report.critical {
            let (x, y) = at(&cp.parameters, &cp.measures);
            marks.push(DiagramMark {
                x,
                y,
                label: format!("{} {}", cp.kind.short(), cp.irrep),
                kind: "critical point of a second piece".to_string(),
            });
        }
    }
    BifurcationDiagram {
        title: format!(
            "{}: the path and the second pieces beside its folds",
            path.scene
        ),
        caption: super::svg::caption_of(path),
        control: path.control.clone(),
        lines,
        marks,
        y_axis: path.measures.get(m).cloned().unwrap_or_default(),
        file: "partners.svg".into(),
    }
}
