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
