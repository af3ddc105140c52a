//! The files of an axisymmetric run: `path.csv` (a row per point: parameters, measures,
//! Newton iterations and the index of every wave number's block) and `path.json` (the whole
//! report: the rows, the turning points and the critical points labelled with their wave
//! number and multiplicity). Each is written whole; a non-finite number is refused.

use super::{write_whole, OutputError};
use crate::axisym::run::AxisymReport;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The files an axisymmetric run writes.
pub const AXISYM_RUN_FILES: &[&str] = &["path.csv", "path.json"];

fn check_finite(path: &Path, report: &AxisymReport) -> Result<(), OutputError> {
    let rows = report.rows.iter().map(|r| {
        (
            format!("path row {}", r.step),
            r.parameters.iter().chain(&r.measures).chain([&r.arclength]),
        )
    });
    for (what, mut values) in rows {
        if let Some(v) = values.find(|v| !v.is_finite()) {
            return Err(OutputError::invalid(
                path,
                format!("{what}: {v} (not finite)"),
            ));
        }
    }
    let points = report
        .critical
        .iter()
        .map(|c| {
            c.parameters
                .iter()
                .chain(&c.measures)
                .copied()
                .collect::<Vec<f64>>()
        })
        .chain(
            report
                .turning_points
                .iter()
                .map(|t| t.parameters.iter().chain(&t.measures).copied().collect()),
        );
    for (k, values) in points.enumerate() {
        if let Some(v) = values.iter().find(|v| !v.is_finite()) {
            return Err(OutputError::invalid(
                path,
                format!("critical or turning point {k}: {v} (not finite)"),
            ));
        }
    }
    Ok(())
}

/// Writes `path.csv` and `path.json` into `out`; returns their paths.
pub fn write_axisym_run(report: &AxisymReport, out: &Path) -> Result<Vec<PathBuf>, OutputError> {
    let csv = out.join("path.csv");
    check_finite(&csv, report)?;
    write_whole(&csv, |w: &mut dyn Write| {
        let mut head = vec!["step".to_string(), "arclength".to_string()];
        head.extend(report.parameters.iter().cloned());
        head.extend(report.measures.iter().cloned());
        head.push("iterations".into());
        head.extend((0..=report.modes).map(|m| format!("index_m{m}")));
        writeln!(w, "{}", head.join(","))?;
        for r in &report.rows {
            let mut cells = vec![r.step.to_string(), format!("{:e}", r.arclength)];
            cells.extend(
                r.parameters
                    .iter()
                    .chain(&r.measures)
                    .map(|v| format!("{v:e}")),
            );
            cells.push(r.iterations.to_string());
            match &r.index {
                Some(ix) => cells.extend(ix.iter().map(usize::to_string)),
                None => cells.extend((0..=report.modes).map(|_| String::new())),
            }
            writeln!(w, "{}", cells.join(","))?;
        }
        Ok(())
    })?;
    let json = out.join("path.json");
    let mut value =
        serde_json::to_value(report).map_err(|e| OutputError::invalid(&json, e.to_string()))?;
    super::json::named_points(&mut value, &report.parameters, &report.measures);
    let text = serde_json::to_string_pretty(&value)
        .map_err(|e| OutputError::invalid(&json, e.to_string()))?;
    write_whole(&json, |w: &mut dyn Write| writeln!(w, "{text}"))?;
    Ok(vec![csv, json])
}
