//! `refine.json`: a run's critical and turning points on refined meshes
//! ([`Refinement`], `memstab run --refine`).

use super::{write_whole, OutputError};
use crate::results::refine::Refinement;
use std::io;
use std::path::{Path, PathBuf};

/// The file's name.
pub const REFINE_JSON: &str = "refine.json";

/// Writes `dir/refine.json`: the [`Refinement`] as pretty-printed JSON (the levels with their
/// meshes and wall times, every critical and turning point with its value per level, the
/// observed order, the Richardson value, the error per level and what the estimate rests on;
/// a critical curve's events with both coordinates so)
/// and returns its path.
///
/// # Errors
/// [`OutputError::Invalid`] for a non-finite value (nothing is written), else as the other
/// writers.
pub fn write_refine(dir: &Path, refinement: &Refinement) -> Result<PathBuf, OutputError> {
    let path = dir.join(REFINE_JSON);
    let numbers = refinement
        .critical
        .iter()
        .chain(&refinement.turning)
        .flat_map(|p| {
            p.series
                .numbers()
                .chain(p.distances.iter().flatten())
                .chain(&p.continuum)
                .chain(&p.continuum_error)
        })
        .chain(refinement.events.iter().flat_map(|e| {
            let continuum = e.continuum.iter().flat_map(|c| {
                [&c.control, &c.second].into_iter().flat_map(|v| {
                    std::iter::once(&v.value)
                        .chain(&v.error)
                        .chain(v.distances.iter().flatten())
                })
            });
            e.control
                .numbers()
                .chain(e.second.numbers())
                .chain(continuum)
        }))
        .chain(refinement.levels.iter().map(|l| &l.seconds));
    if let Some(v) = numbers.into_iter().find(|v| !v.is_finite()) {
        return Err(OutputError::invalid(
            &path,
            format!("a value is {v} (not finite)"),
        ));
    }
    write_whole(&path, |w| {
        serde_json::to_writer_pretty(&mut *w, refinement).map_err(io::Error::other)?;
        writeln!(w)
    })?;
    Ok(path)
}
