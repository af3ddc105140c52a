//! `manifest.json`, written last into a run's directory: every file of this run (by its path
//! relative to the directory, `/`-separated, branch directories included) with its size and
//! SHA-256, the version and why the run stopped. A directory with no manifest holds a run that
//! was cut short (or one of an older version); files whose checksums do not match it are
//! another run's or were edited. The old manifest is removed before anything else is written.
//! The readers of a finished run check what they read against it ([`verify`]).

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
    let mut file = super::open_regular(path).map_err(io)?;
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
                file: relative(dir, f),
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

/// The path of `file` relative to `dir`, `/`-separated (its file name when it lies elsewhere).
pub(super) fn relative(dir: &Path, file: &Path) -> String {
    match file.strip_prefix(dir) {
        Ok(rel) if rel.components().next().is_some() => rel
            .components()
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect::<Vec<_>>()
            .join("/"),
        _ => super::file_name(file),
    }
}

/// Adds `files` (paths in `dir`) to `dir/manifest.json`, replacing the entries of the same
/// paths, or writes a new manifest of them when there is none (with stop reason `stop`, or
/// `default` when `stop` is `None`) — but none into a run directory of an older version that
/// has no manifest; an existing manifest keeps its stop reason unless `stop` is given. What
/// `memstab branch` does after writing into a finished run's directory.
pub fn add_to_manifest(
    dir: &Path,
    files: &[PathBuf],
    stop: Option<&StopReason>,
    default: &str,
) -> Result<PathBuf, OutputError> {
    let path = dir.join(MANIFEST);
    let old: Option<serde_json::Value> = super::read_regular_string(&path)
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok());
    if old.is_none() && dir.join("path.json").is_file() {
        // A run of an older version, without a manifest: one listing only these files would
        // leave the run's own files unlisted, and its readers would refuse them.
        return Ok(path);
    }
    let mut entries: Vec<serde_json::Value> = old
        .as_ref()
        .and_then(|m| m["files"].as_array().cloned())
        .unwrap_or_default();
    for f in files {
        let name = relative(dir, f);
        let bytes = std::fs::metadata(f)
            .map_err(|source| OutputError::Io {
                path: f.clone(),
                source,
            })?
            .len();
        let entry = serde_json::json!({ "file": name, "bytes": bytes, "sha256": sha256(f)? });
        match entries.iter_mut().find(|e| e["file"] == name.as_str()) {
            Some(e) => *e = entry,
            None => entries.push(entry),
        }
    }
    let stop = match (stop, old.as_ref().map(|m| m["stop"].clone())) {
        (Some(s), _) => serde_json::Value::String(s.to_string()),
        (None, Some(s @ serde_json::Value::String(_))) => s,
        (None, _) => serde_json::Value::String(default.to_string()),
    };
    let manifest = serde_json::json!({
        "version": env!("CARGO_PKG_VERSION"),
        "stop": stop,
        "files": entries,
    });
    write_whole(&path, |w| {
        serde_json::to_writer_pretty(&mut *w, &manifest).map_err(std::io::Error::other)?;
        writeln!(w)
    })?;
    Ok(path)
}

/// What [`verify`] found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Verified {
    /// Every file asked for is listed in the manifest with its checksum.
    Listed,
    /// The directory has no manifest (a run of an older version, or one cut short): the files
    /// are read unchecked; the text says so, for a warning.
    NoManifest(String),
}

/// Checks the files `names` (paths relative to `dir`, `/`-separated) against
/// `dir/manifest.json`: each must be listed with its size and SHA-256. The error is one line
/// naming the file (edited after the run, another run's, or not listed) or the manifest (not
/// readable).
pub fn verify(dir: &Path, names: &[&str]) -> Result<Verified, String> {
    let path = dir.join(MANIFEST);
    let text = match super::read_regular_string(&path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Ok(Verified::NoManifest(format!(
                "'{}' has no {MANIFEST} (a run of an older version, or one cut short): {} read unchecked",
                dir.display(),
                names.join(", ")
            )));
        }
        Err(e) => return Err(format!("cannot read {}: {e}", path.display())),
    };
    let manifest: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| format!("{}: not a manifest of memstab run: {e}", path.display()))?;
    let files = manifest["files"].as_array().ok_or_else(|| {
        format!(
            "{}: no 'files' list (not a manifest of memstab run)",
            path.display()
        )
    })?;
    for name in names {
        let file = dir.join(name);
        let Some(entry) = files.iter().find(|e| e["file"] == *name) else {
            return Err(format!(
                "{}: not listed in {} (not written by this run)",
                file.display(),
                path.display()
            ));
        };
        let edited = || {
            format!(
                "{}: does not match its checksum in {} (edited after the run, or another run's); run the scene again",
                file.display(),
                path.display()
            )
        };
        if let Some(what) = crate::scene::not_regular(&file) {
            return Err(format!(
                "cannot read {}: it is {what}, not a regular file (replaced after the run); run \
                 the scene again",
                file.display()
            ));
        }
        let bytes = std::fs::metadata(&file)
            .map_err(|e| format!("cannot read {}: {e}", file.display()))?
            .len();
        if entry["bytes"].as_u64() != Some(bytes) {
            return Err(edited());
        }
        let sum = sha256(&file).map_err(|e| e.to_string())?;
        if entry["sha256"].as_str() != Some(sum.as_str()) {
            return Err(edited());
        }
    }
    Ok(Verified::Listed)
}

/// As [`verify`], with the warning of a directory without a manifest printed (once per
/// directory) on stderr: what the readers of a finished run call.
pub fn verify_or_warn(dir: &Path, names: &[&str]) -> Result<(), String> {
    use std::sync::Mutex;
    static WARNED: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
    if let Verified::NoManifest(why) = verify(dir, names)? {
        let mut warned = WARNED.lock().unwrap_or_else(|e| e.into_inner());
        if !warned.iter().any(|d| d == dir) {
            warned.push(dir.to_path_buf());
            eprintln!("warning: {why}");
        }
    }
    Ok(())
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
