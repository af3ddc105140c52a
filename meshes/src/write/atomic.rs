//! Whole-file writes: fill a temporary file in the target's directory, flush it to disk, then
//! rename it over the target. A rename within one directory is atomic on POSIX file systems,
//! so readers see either the old file or the complete new one, and a failed write leaves the
//! old file untouched (the temporary file is deleted when dropped).
//!
//! Only regular files are replaced: a target that exists as anything else — a directory, a
//! device, a FIFO, a socket, a symbolic link — is refused before anything is written, so a
//! write never turns `/dev/null` or a link into a regular file. Temporary files are named
//! `.memstab-*.tmp` ([`TEMPORARY_PREFIX`], [`TEMPORARY_SUFFIX`]), so that the debris of a killed
//! process can be recognised and swept.

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

/// The start of every temporary file's name.
pub const TEMPORARY_PREFIX: &str = ".memstab-";
/// The end of every temporary file's name.
pub const TEMPORARY_SUFFIX: &str = ".tmp";

/// Fails with [`MeshError::Target`] when `target` exists and is not a regular file (a
/// symbolic link counts as not regular, whatever it points to).
pub fn check_target(target: &Path) -> Result<(), MeshError> {
    let Ok(meta) = std::fs::symlink_metadata(target) else {
        return Ok(());
    };
    let t = meta.file_type();
    if t.is_file() {
        return Ok(());
    }
    let what = if t.is_symlink() {
        "a symbolic link"
    } else if t.is_dir() {
        "a directory"
    } else {
        special_kind(&t)
    };
    Err(MeshError::Target {
        path: target.to_path_buf(),
        what,
    })
}

#[cfg(unix)]
fn special_kind(t: &std::fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    if t.is_fifo() {
        "a FIFO"
    } else if t.is_socket() {
        "a socket"
    } else if t.is_char_device() || t.is_block_device() {
        "a device"
    } else {
        "not a regular file"
    }
}

#[cfg(not(unix))]
fn special_kind(_: &std::fs::FileType) -> &'static str {
    "not a regular file"
}

/// Writes a temporary file next to `target` with `fill` and syncs it; nothing is renamed yet.
pub(crate) fn stage(
    target: &Path,
    fill: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> Result<Staged, MeshError> {
    check_target(target)?;
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let tmp = tempfile::Builder::new()
        .prefix(TEMPORARY_PREFIX)
        .suffix(TEMPORARY_SUFFIX)
        .tempfile_in(dir)
        .map_err(io_err(target))?;
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
        // Checked again: the target may have appeared since the file was staged.
        check_target(&target)?;
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
