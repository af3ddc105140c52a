//! `path.json`: the whole report with its metadata.

use super::{check_finite, write_whole, OutputError};
use crate::report::PathReport;
use std::io;
use std::path::{Path, PathBuf};

/// Writes `dir/path.json` — the whole [`PathReport`] as pretty-printed JSON (scene, origin,
/// version, mesh, group, unknowns, control, parameter and measure names, rows, turning points,
/// stop reason, saved states) — and returns its path. Numbers are written with the fewest
/// digits that parse back to the same `f64`.
///
/// # Errors
/// [`OutputError::NoDirectory`] if `dir` does not exist, [`OutputError::Invalid`] if a value is
/// not finite (JSON has no NaN; nothing is written), [`OutputError::Io`] if the file cannot be
/// written.
pub fn write_json(dir: &Path, report: &PathReport) -> Result<PathBuf, OutputError> {
    let path = dir.join("path.json");
    check_finite(&path, report)?;
    write_whole(&path, |w| {
        serde_json::to_writer_pretty(&mut *w, report).map_err(io::Error::other)?;
        writeln!(w)
    })?;
    Ok(path)
}

/// One critical point as written to `critical.json`.
#[derive(serde::Serialize)]
struct CriticalJson<'a> {
    kind: crate::analysis::critical::CriticalKind,
    irrep: &'a str,
    multiplicity: usize,
    parameters: std::collections::BTreeMap<&'a str, f64>,
    measures: std::collections::BTreeMap<&'a str, f64>,
    step: usize,
    residual_eigenvalue: f64,
    isotropy: &'a str,
    isotropy_order: usize,
}

/// Writes `dir/critical.json`: a list of the critical points (kind, irrep, multiplicity,
/// parameters and measures by name, the path step before the point, the relative size of the
/// localised eigenvalue, and the isotropy subgroup of the critical mode).
///
/// # Errors
/// As [`write_json`]; a non-finite value is refused and nothing is written.
pub fn write_critical(dir: &Path, report: &PathReport) -> Result<PathBuf, OutputError> {
    let path = dir.join("critical.json");
    let list: Vec<CriticalJson> = report
        .critical
        .iter()
        .map(|c| CriticalJson {
            kind: c.kind,
            irrep: &c.irrep,
            multiplicity: c.multiplicity,
            parameters: report
                .parameters
                .iter()
                .map(String::as_str)
                .zip(c.parameters.iter().copied())
                .collect(),
            measures: report
                .measures
                .iter()
                .map(String::as_str)
                .zip(c.measures.iter().copied())
                .collect(),
            step: c.after_step,
            residual_eigenvalue: c.residual_eigenvalue,
            isotropy: &c.isotropy.name,
            isotropy_order: c.isotropy.order,
        })
        .collect();
    for c in &list {
        if let Some((name, v)) = c
            .parameters
            .iter()
            .chain(&c.measures)
            .find(|(_, v)| !v.is_finite())
        {
            return Err(OutputError::invalid(
                &path,
                format!(
                    "critical point ({} in {}): {name} is {v} (not finite)",
                    c.kind, c.irrep
                ),
            ));
        }
    }
    write_whole(&path, |w| {
        serde_json::to_writer_pretty(&mut *w, &list).map_err(io::Error::other)?;
        writeln!(w)
    })?;
    Ok(path)
}
