//! `manifest.json`, written last into a run's directory: every file of this run with its
//! size and SHA-256, the version and why the run stopped. A directory with no manifest holds
//! a run that was cut short; files whose checksums do not match it are another run's. The
//! old manifest is removed before anything else is written.

use super::{write_whole, OutputError};
use crate::results::StopReason;
use sha2::{Digest, Sha256};
use std::io::Read;
use std::path::{Path, PathBuf};

/// The manifest's file name.
pub const MANIFEST: &str = "manifest.json";

#[derive(serde::Serialize)]
struct Entry {
    file: String,
    bytes: u64,
    sha256: String,
}

#[derive(serde::Serialize)]
struct Manifest<'a> {
    version: &'a str,
    stop: &'a StopReason,
    files: Vec<Entry>,
}

/// Removes `dir/manifest.json` (a regular file only), so that a run cut short leaves none.
pub fn remove_manifest(dir: &Path) -> Result<(), OutputError> {
    let path = dir.join(MANIFEST);
    super::check_target(&path)?;
    match std::fs::remove_file(&path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            Err(OutputError::Io { path, source: e })
        }
        _ => Ok(()),
    }
}

/// The SHA-256 of a file, in hex.
pub fn sha256(path: &Path) -> Result<String, OutputError> {
    let io = |source| OutputError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut file = std::fs::File::open(path).map_err(io)?;
    let mut hasher = Sha256::new();
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let n = file.read(&mut buf).map_err(io)?;
        if n == 0 {
            break;
        }
        hasher.update(&buf[..n]);
    }
    Ok(hasher
        .finalize()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect())
}

/// Writes `dir/manifest.json` for `files` (paths in `dir`) and returns its path.
pub fn write_manifest(
    dir: &Path,
    files: &[PathBuf],
    stop: &StopReason,
) -> Result<PathBuf, OutputError> {
    let path = dir.join(MANIFEST);
    let entries = files
        .iter()
        .map(|f| {
            let bytes = std::fs::metadata(f)
                .map_err(|source| OutputError::Io {
                    path: f.clone(),
                    source,
                })?
                .len();
            Ok(Entry {
                file: super::file_name(f),
                bytes,
                sha256: sha256(f)?,
            })
        })
        .collect::<Result<Vec<_>, OutputError>>()?;
    let manifest = Manifest {
        version: env!("CARGO_PKG_VERSION"),
        stop,
        files: entries,
    };
    write_whole(&path, |w| {
        serde_json::to_writer_pretty(&mut *w, &manifest).map_err(std::io::Error::other)?;
        writeln!(w)
    })?;
    Ok(path)
}

/// Removes the temporary files (`.memstab-*.tmp`) that a killed process left in `dir`;
/// returns how many.
pub fn sweep_temporaries(dir: &Path) -> usize {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return 0;
    };
    entries
        .filter_map(Result::ok)
        .filter(|e| {
            let name = e.file_name();
            let name = name.to_string_lossy();
            name.starts_with(meshes::write::TEMPORARY_PREFIX)
                && name.ends_with(meshes::write::TEMPORARY_SUFFIX)
                && e.file_type().is_ok_and(|t| t.is_file())
        })
        .filter(|e| std::fs::remove_file(e.path()).is_ok())
        .count()
}
