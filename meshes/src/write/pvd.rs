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
    let mut rows = Vec::with_capacity(entries.len());
    for (k, (time, file)) in entries.iter().enumerate() {
        if !time.is_finite() {
            return Err(MeshError::Invalid(format!(
                "pvd entry {k} ({}) has a non-finite time {time}",
                file.display()
            )));
        }
        rows.push((*time, portable(file)?));
    }
    atomic::stage(path, |w| {
        writeln!(w, "<?xml version=\"1.0\"?>")?;
        writeln!(
            w,
            "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">"
        )?;
        writeln!(w, "<Collection>")?;
        for (time, file) in &rows {
            writeln!(
                w,
                "<DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{}\"/>",
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
