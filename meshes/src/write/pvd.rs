//! ParaView data collections (`.pvd`): a time series of VTU files
//! (<https://www.paraview.org/Wiki/ParaView/Data_formats#PVD_File_Format>).
//!
//! ```xml
//! <VTKFile type="Collection" version="0.1" byte_order="LittleEndian">
//!   <Collection>
//!     <DataSet timestep="0.5" group="" part="0" file="step_0001.vtu"/>
//!   </Collection>
//! </VTKFile>
//! ```
//!
//! `file` is resolved by ParaView against the `.pvd`'s directory, so relative names keep a
//! result directory movable. `timestep` is any real number; entries are written in the order
//! given.

use super::{atomic, xml_escape, Num};
use crate::MeshError;
use std::path::{Component, Path, PathBuf};

/// Writes a ParaView collection of `(time, file)` entries to `path`, whole (temporary file +
/// rename). File names should be relative to the `.pvd`'s directory; they are written with `/`
/// separators and must be UTF-8. Times must be finite. The listed files are not opened: write
/// them before or after, as suits the caller. An empty list is a valid, empty collection.
///
/// # Errors
/// [`MeshError::Invalid`] for a non-finite time or a file name that is not UTF-8 or names no
/// file; [`MeshError::Io`] if `path` cannot be written.
pub fn write_pvd(path: &Path, entries: &[(f64, PathBuf)]) -> Result<(), MeshError> {
    let named: Vec<(f64, PathBuf, String)> = entries
        .iter()
        .map(|(t, f)| (*t, f.clone(), String::new()))
        .collect();
    write_pvd_named(path, &named)
}

/// As [`write_pvd`], with a name for each entry (`(time, file, name)`), written as the
/// DataSet's `name` attribute, which ParaView shows as the block's name; an empty name writes
/// no attribute.
///
/// # Errors
/// As [`write_pvd`]; a name with a control character is [`MeshError::Invalid`].
pub fn write_pvd_named(path: &Path, entries: &[(f64, PathBuf, String)]) -> Result<(), MeshError> {
    let mut rows = Vec::with_capacity(entries.len());
    for (k, (time, file, name)) in entries.iter().enumerate() {
        if name.chars().any(char::is_control) {
            return Err(MeshError::Invalid(format!(
                "pvd entry {k} ({}): control character in the name {name:?}",
                file.display()
            )));
        }
        if !time.is_finite() {
            return Err(MeshError::Invalid(format!(
                "pvd entry {k} ({}) has a non-finite time {time}",
                file.display()
            )));
        }
        rows.push((*time, portable(file)?, name));
    }
    atomic::stage(path, |w| {
        writeln!(w, "<?xml version=\"1.0\"?>")?;
        writeln!(
            w,
            "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">"
        )?;
        writeln!(w, "<Collection>")?;
        for (time, file, name) in &rows {
            let name = if name.is_empty() {
                String::new()
            } else {
                format!(" name=\"{}\"", xml_escape(name))
            };
            writeln!(
                w,
                "<DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{}\"{name}/>",
                Num(*time),
                xml_escape(file)
            )?;
        }
        writeln!(w, "</Collection>")?;
        writeln!(w, "</VTKFile>")
    })?
    .commit()
}

/// The path as a `/`-separated UTF-8 string.
fn portable(file: &Path) -> Result<String, MeshError> {
    let bad = || {
        MeshError::Invalid(format!(
            "pvd entry {}: not a UTF-8 file name",
            file.display()
        ))
    };
    let mut parts = Vec::new();
    for c in file.components() {
        match c {
            Component::RootDir => parts.push(""),
            Component::CurDir => {}
            Component::ParentDir => parts.push(".."),
            Component::Normal(s) => parts.push(s.to_str().ok_or_else(bad)?),
            Component::Prefix(p) => parts.push(p.as_os_str().to_str().ok_or_else(bad)?),
        }
    }
    let s = parts.join("/");
    if s.is_empty() || s.ends_with('/') || file.as_os_str().as_encoded_bytes().ends_with(b"/") {
        return Err(MeshError::Invalid(format!(
            "pvd entry {}: names no file",
            file.display()
        )));
    }
    if s.chars().any(char::is_control) {
        return Err(MeshError::Invalid(format!(
            "pvd entry {s:?}: control character in the file name"
        )));
    }
    Ok(s)
}
