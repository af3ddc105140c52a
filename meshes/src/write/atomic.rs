//! Whole-file writes: fill a temporary file in the target's directory, flush it to disk, then
//! rename it over the target. A rename within one directory is atomic on POSIX file systems,
//! so readers see either the old file or the complete new one, and a failed write leaves the
//! old file untouched (the temporary file is deleted when dropped).

use crate::MeshError;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use tempfile::NamedTempFile;

/// A complete temporary file waiting to be renamed over its target.
pub(crate) struct Staged {
    tmp: NamedTempFile,
    target: PathBuf,
}

fn io_err(path: &Path) -> impl FnOnce(io::Error) -> MeshError + '_ {
    move |source| MeshError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Writes a temporary file next to `target` with `fill` and syncs it; nothing is renamed yet.
pub(crate) fn stage(
    target: &Path,
    fill: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> Result<Staged, MeshError> {
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let tmp = NamedTempFile::new_in(dir).map_err(io_err(target))?;
    {
        let mut w = BufWriter::new(tmp.as_file());
        fill(&mut w).map_err(io_err(target))?;
        w.flush().map_err(io_err(target))?;
    }
    let file: &File = tmp.as_file();
    set_mode(file).map_err(io_err(target))?;
    file.sync_all().map_err(io_err(target))?;
    Ok(Staged {
        tmp,
        target: target.to_path_buf(),
    })
}

/// Writes `target` whole: [`stage`] then commit.
pub fn write_whole(
    target: &Path,
    fill: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> Result<(), MeshError> {
    stage(target, fill)?.commit()
}

impl Staged {
    /// Renames the temporary file over the target.
    pub(crate) fn commit(self) -> Result<(), MeshError> {
        let target = self.target;
        self.tmp.persist(&target).map_err(|e| MeshError::Io {
            path: target.clone(),
            source: e.error,
        })?;
        Ok(())
    }
}

/// Temporary files are created private (0600); output files should be world-readable (0644),
/// as if created by `File::create` under the usual umask.
#[cfg(unix)]
fn set_mode(file: &File) -> io::Result<()> {
    use std::os::unix::fs::PermissionsExt;
    file.set_permissions(std::fs::Permissions::from_mode(0o644))
}

#[cfg(not(unix))]
fn set_mode(_file: &File) -> io::Result<()> {
    Ok(())
}
