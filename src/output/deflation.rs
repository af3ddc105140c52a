//! `deflation.json`, `deflation.csv` and `deflation.svg`: the solutions deflated Newton found
//! at one value of the control ([`DeflationReport`]).

use super::csv::quote;
use super::diagram::{write_bifurcation_diagram, BifurcationDiagram, DiagramLine, DiagramMark};
use super::{write_whole, Num, OutputError};
use crate::results::deflation::DeflationReport;
use crate::results::PathReport;
use std::io;
use std::path::{Path, PathBuf};

/// Writes `deflation.json` (the whole report), `deflation.csv` (a row per point of every
/// solution's piece: `solution`, the parameters, the measures, `index`) and `deflation.svg`
/// (the measure of `path.svg` against the control: the run's path in black and every piece in
/// colour, stable solid and unstable dashed, each solution marked) into `dir`; returns their
/// paths.
///
/// # Errors
/// [`OutputError::Invalid`] for a non-finite value (nothing is written), else as the other
/// writers.
pub fn write_deflation(
    dir: &Path,
    d: &DeflationReport,
    path: &PathReport,
) -> Result<Vec<PathBuf>, OutputError> {
    let json = dir.join("deflation.json");
    let csv = dir.join("deflation.csv");
    for (k, s) in d.solutions.iter().enumerate() {
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
    let picture = diagram(d, path);
    write_whole(&json, |w| {
        serde_json::to_writer_pretty(&mut *w, d).map_err(io::Error::other)?;
        writeln!(w)
    })?;
    write_whole(&csv, |w| {
        let names: Vec<String> = std::iter::once("solution")
            .chain(d.parameters.iter().map(String::as_str))
            .chain(d.measures.iter().map(String::as_str))
            .chain(std::iter::once("index"))
            .map(quote)
            .collect();
        writeln!(w, "{}", names.join(","))?;
        for (k, s) in d.solutions.iter().enumerate() {
            for p in &s.piece {
                write!(w, "{k}")?;
                for &v in p.parameters.iter().chain(&p.measures) {
                    write!(w, ",{}", Num(v))?;
                }
                match p.index {
                    Some(i) => writeln!(w, ",{i}")?,
                    None => writeln!(w, ",")?,
                }
            }
        }
        Ok(())
    })?;
    let svg = write_bifurcation_diagram(dir, &picture)?;
    Ok(vec![json, csv, svg])
}

/// The run's path and every piece: the measure of the path's diagram (the stretch, the
/// largest displacement or the first measure) against the control.
fn diagram(d: &DeflationReport, path: &PathReport) -> BifurcationDiagram {
    let c = d
        .parameters
        .iter()
        .position(|p| *p == d.control)
        .unwrap_or(0);
    let (name, _) = super::default_axes(path);
    let m = d.measures.iter().position(|n| *n == name).unwrap_or(0);
    let line =
        |class: String, on_path: bool, points: Vec<(f64, f64)>, stable: Vec<Option<bool>>| {
            DiagramLine {
                class,
                path: on_path,
                points,
                stable,
            }
        };
    let mut lines = vec![line(
        "path through the start".into(),
        true,
        path.rows
            .iter()
            .map(|r| (r.parameters[c], r.measures.get(m).copied().unwrap_or(0.0)))
            .collect(),
        path.rows.iter().map(|r| r.index.map(|i| i == 0)).collect(),
    )];
    for (k, s) in d.solutions.iter().enumerate().skip(1) {
        if s.piece.is_empty() {
            continue;
        }
        lines.push(line(
            format!("piece through solution {k}"),
            false,
            s.piece
                .iter()
                .map(|p| (p.parameters[c], p.measures.get(m).copied().unwrap_or(0.0)))
                .collect(),
            s.piece.iter().map(|p| p.index.map(|i| i == 0)).collect(),
        ));
    }
    let marks = d
        .solutions
        .iter()
        .enumerate()
        .map(|(k, s)| DiagramMark {
            x: s.parameters[c],
            y: s.measures.get(m).copied().unwrap_or(0.0),
            label: format!("solution {k}"),
        })
        .collect();
    BifurcationDiagram {
        title: format!(
            "{}: the solutions at {} = {}",
            path.scene,
            d.control,
            super::svg::short(d.value)
        ),
        control: d.control.clone(),
        lines,
        marks,
        y_axis: d.measures.get(m).cloned().unwrap_or_default(),
        file: "deflation.svg".into(),
    }
}
