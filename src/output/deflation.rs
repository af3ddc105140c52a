//! `deflation.json`, `deflation.csv` and `deflation.svg`: the solutions deflated Newton found
//! at each value of the control it searched ([`DeflationReport`], one per value).

use super::csv::quote;
use super::diagram::{write_bifurcation_diagram, BifurcationDiagram, DiagramLine, DiagramMark};
use super::{write_whole, Num, OutputError};
use crate::results::deflation::DeflationReport;
use crate::results::PathReport;
use std::io;
use std::path::{Path, PathBuf};

/// Writes `deflation.json` (a list: the report of every value searched), `deflation.csv` (a
/// row per point of every solution's piece: `search`, `solution`, the parameters, the
/// measures, `index`) and `deflation.svg` (the measure of `path.svg` against the control: the
/// run's path in black and every piece in colour, stable solid and unstable dashed, each
/// solution marked) into `dir`; returns their paths.
///
/// # Errors
/// [`OutputError::Invalid`] for a non-finite value (nothing is written), else as the other
/// writers.
pub fn write_deflation(
    dir: &Path,
    searches: &[DeflationReport],
    path: &PathReport,
) -> Result<Vec<PathBuf>, OutputError> {
    let json = dir.join("deflation.json");
    let csv = dir.join("deflation.csv");
    for (k, s) in searches.iter().flat_map(|d| d.solutions.iter().enumerate()) {
        let values = s
            .parameters
            .iter()
            .chain(&s.measures)
            .chain(s.distance.iter())
            .chain(
                s.piece
                    .iter()
                    .flat_map(|p| p.parameters.iter().chain(&p.measures)),
            );
        if let Some(v) = values.into_iter().find(|v| !v.is_finite()) {
            return Err(OutputError::invalid(
                &json,
                format!("solution {k}: a value is {v} (not finite)"),
            ));
        }
    }
    let picture = diagram(searches, path);
    write_whole(&json, |w| {
        serde_json::to_writer_pretty(&mut *w, searches).map_err(io::Error::other)?;
        writeln!(w)
    })?;
    write_whole(&csv, |w| {
        let names: Vec<String> = ["search", "solution"]
            .into_iter()
            .chain(path.parameters.iter().map(String::as_str))
            .chain(path.measures.iter().map(String::as_str))
            .chain(std::iter::once("index"))
            .map(quote)
            .collect();
        writeln!(w, "{}", names.join(","))?;
        for (j, d) in searches.iter().enumerate() {
            for (k, s) in d.solutions.iter().enumerate() {
                for p in &s.piece {
                    write!(w, "{j},{k}")?;
                    for &v in p.parameters.iter().chain(&p.measures) {
                        write!(w, ",{}", Num(v))?;
                    }
                    match p.index {
                        Some(i) => writeln!(w, ",{i}")?,
                        None => writeln!(w, ",")?,
                    }
                }
            }
        }
        Ok(())
    })?;
    let svg = write_bifurcation_diagram(dir, &picture)?;
    let png = super::write_png_beside(&svg)?;
    Ok(vec![json, csv, svg, png])
}

/// The run's path and every piece: the measure of the path's diagram (the stretch, the
/// largest displacement or the first measure) against the control.
fn diagram(searches: &[DeflationReport], path: &PathReport) -> BifurcationDiagram {
    let c = path
        .parameters
        .iter()
        .position(|p| *p == path.control)
        .unwrap_or(0);
    let (name, _) = super::default_axes(path);
    let m = path.measures.iter().position(|n| *n == name).unwrap_or(0);
    let at = |parameters: &[f64], measures: &[f64]| {
        (parameters[c], measures.get(m).copied().unwrap_or(0.0))
    };
    let mut lines = vec![DiagramLine {
        class: "path through the start".into(),
        path: true,
        points: path
            .rows
            .iter()
            .map(|r| at(&r.parameters, &r.measures))
            .collect(),
        stable: path.rows.iter().map(|r| r.index.map(|i| i == 0)).collect(),
    }];
    let mut marks = Vec::new();
    for d in searches {
        for (k, s) in d.solutions.iter().enumerate() {
            let (x, y) = at(&s.parameters, &s.measures);
            marks.push(DiagramMark {
                x,
                y,
                label: format!("solution {k}"),
                kind: "solution of deflated Newton".to_string(),
            });
            if s.piece.is_empty() {
                continue;
            }
            lines.push(DiagramLine {
                class: "pieces through the solutions".into(),
                path: false,
                points: s
                    .piece
                    .iter()
                    .map(|p| at(&p.parameters, &p.measures))
                    .collect(),
                stable: s.piece.iter().map(|p| p.index.map(|i| i == 0)).collect(),
            });
        }
    }
    let values: Vec<String> = searches
        .iter()
        .map(|d| super::svg::short(d.value))
        .collect();
    BifurcationDiagram {
        title: format!(
            "{}: the solutions at {} = {}",
            path.scene,
            path.control,
            values.join(", ")
        ),
        caption: super::svg::caption_of(path),
        control: path.control.clone(),
        lines,
        marks,
        y_axis: path.measures.get(m).cloned().unwrap_or_default(),
        file: "deflation.svg".into(),
    }
}
