//! `path.states`: every path point's state in one compact binary file beside `path.pvd`, and
//! its reader — what `[start] from` restarts from.
//!
//! The file is little-endian throughout:
//!
//! | bytes | content |
//! | --- | --- |
//! | 8 | the magic `MSTATES1` |
//! | 8 | N, the number of unknowns (u64) |
//! | 8 | P, the number of parameters (u64) |
//! | 8 | M, the number of points (u64) |
//! | M × 8 (P + N) | per point, in path order (point k is the row `step = k` of `path.csv`): its P parameters (f64, in the order of `parameters` in `path.json`), then its displacement u over the N unknowns (f64; the unknowns number the free nodes' x, y, z in node order) |
//!
//! `path.json` names the file and repeats N, P and M under `states`, with the parameter names
//! in `parameters`. Every number is finite (a state with a non-finite entry is refused and
//! nothing is written); the file is written whole (temporary file and rename).

use super::{write_whole, OutputError};
use crate::results::{PointState, StatesInfo};
use std::io;
use std::path::{Path, PathBuf};

/// The file's first 8 bytes.
pub const STATES_MAGIC: &[u8; 8] = b"MSTATES1";

/// The name of the states file in a run's directory.
pub const STATES_FILE: &str = "path.states";

/// One saved point: every parameter and the displacement over the unknowns.
#[derive(Debug, Clone, PartialEq)]
pub struct SavedPoint {
    /// The parameters, in the order of the run's `parameters`.
    pub parameters: Vec<f64>,
    /// u over the unknowns.
    pub u: Vec<f64>,
}

/// Writes `dir/path.states`: for every point its parameters (P of them) and its
/// displacement, `expand(q, u)` filling u (N unknowns) from the point's coordinates q.
///
/// # Errors
/// [`OutputError::Invalid`] for a point with the wrong number of parameters or a non-finite
/// entry (naming the point; nothing is written), [`OutputError::Io`] when the file cannot be
/// written.
pub fn write_states(
    dir: &Path,
    points: &[PointState],
    parameters: usize,
    unknowns: usize,
    expand: impl Fn(&[f64], &mut [f64]),
) -> Result<(PathBuf, StatesInfo), OutputError> {
    let path = dir.join(STATES_FILE);
    for (k, p) in points.iter().enumerate() {
        if p.parameters.len() != parameters {
            return Err(OutputError::invalid(
                &path,
                format!(
                    "point {k} has {} parameters, not {parameters}",
                    p.parameters.len()
                ),
            ));
        }
        if let Some(v) = p.parameters.iter().chain(&p.q).find(|v| !v.is_finite()) {
            return Err(OutputError::invalid(
                &path,
                format!("point {k} has a non-finite entry {v}"),
            ));
        }
    }
    write_whole(&path, |w| {
        w.write_all(STATES_MAGIC)?;
        for n in [unknowns, parameters, points.len()] {
            w.write_all(&(n as u64).to_le_bytes())?;
        }
        let mut u = vec![0.0; unknowns];
        let mut buf = Vec::with_capacity(8 * (parameters + unknowns));
        for p in points {
            expand(&p.q, &mut u);
            buf.clear();
            for v in p.parameters.iter().chain(&u) {
                buf.extend_from_slice(&v.to_le_bytes());
            }
            w.write_all(&buf)?;
        }
        Ok(())
    })?;
    let info = StatesInfo {
        file: STATES_FILE.to_string(),
        unknowns,
        parameters,
        points: points.len(),
    };
    Ok((path, info))
}

/// Why saved states could not be read; the message names the file.
#[derive(Debug, thiserror::Error)]
pub enum ReadStatesError {
    /// The file could not be opened or read.
    #[error("cannot read {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: io::Error,
    },
    /// The file does not match the run's manifest (the message names it).
    #[error("{0}")]
    Unverified(String),
    /// The file is not what a run writes.
    #[error("{path}: {message}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
}

/// The saved states of a run, as [`read_states`] finds them.
#[derive(Debug, Clone, PartialEq)]
pub struct SavedRun {
    /// The parameter names (from `path.json`).
    pub parameters: Vec<String>,
    /// Unknowns per state.
    pub unknowns: usize,
    /// Number of points.
    pub points: usize,
    /// The states file.
    pub file: PathBuf,
}

/// Reads the header of the run whose `path.json` is `json`: its parameter names and the
/// states file it names (beside it), checked against its header.
pub fn read_states(json: &Path) -> Result<SavedRun, ReadStatesError> {
    let io_err = |path: &Path, source| ReadStatesError::Io {
        path: path.to_path_buf(),
        source,
    };
    let invalid = |path: &Path, message: String| ReadStatesError::Invalid {
        path: path.to_path_buf(),
        message,
    };
    let text = super::read_regular_string(json).map_err(|e| io_err(json, e))?;
    let doc: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| invalid(json, format!("not JSON: {e}")))?;
    let parameters: Vec<String> = doc["parameters"]
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|v| v.as_str().map(String::from))
                .collect()
        })
        .ok_or_else(|| invalid(json, "no 'parameters' list".into()))?;
    let name = doc["states"]["file"].as_str().ok_or_else(|| {
        invalid(
            json,
            "no 'states' entry: the run saved no states (a branch's path, or written by an older version)".into(),
        )
    })?;
    let dir = json.parent().unwrap_or(Path::new(""));
    let json_name = super::file_name(json);
    super::verify_or_warn(dir, &[json_name.as_str(), name]).map_err(ReadStatesError::Unverified)?;
    let file = dir.join(name);
    let mut f = super::open_regular(&file).map_err(|e| io_err(&file, e))?;
    let mut head = [0u8; 32];
    io::Read::read_exact(&mut f, &mut head).map_err(|e| io_err(&file, e))?;
    if &head[..8] != STATES_MAGIC {
        return Err(invalid(&file, "not a states file (bad magic)".into()));
    }
    let word = |k: usize| u64::from_le_bytes(head[8 * k..8 * k + 8].try_into().expect("8 bytes"));
    let (n, p, m) = (word(1) as usize, word(2) as usize, word(3) as usize);
    if p != parameters.len() {
        return Err(invalid(
            &file,
            format!(
                "{p} parameters per state, path.json names {}",
                parameters.len()
            ),
        ));
    }
    let len = f.metadata().map_err(|e| io_err(&file, e))?.len();
    let expected = 32 + (m as u64) * 8 * (n + p) as u64;
    if len != expected {
        return Err(invalid(
            &file,
            format!("{len} bytes, expected {expected} for {m} states of {n} unknowns"),
        ));
    }
    Ok(SavedRun {
        parameters,
        unknowns: n,
        points: m,
        file,
    })
}

impl SavedRun {
    /// Point `k` of the run.
    pub fn point(&self, k: usize) -> Result<SavedPoint, ReadStatesError> {
        let invalid = |message: String| ReadStatesError::Invalid {
            path: self.file.clone(),
            message,
        };
        if k >= self.points {
            return Err(invalid(format!(
                "has {} points (0 to {}), not point {k}",
                self.points,
                self.points.saturating_sub(1)
            )));
        }
        let p = self.parameters.len();
        let record = 8 * (p + self.unknowns);
        let mut f = super::open_regular(&self.file).map_err(|source| ReadStatesError::Io {
            path: self.file.clone(),
            source,
        })?;
        let mut buf = vec![0u8; record];
        io::Seek::seek(&mut f, io::SeekFrom::Start(32 + (k * record) as u64))
            .and_then(|_| io::Read::read_exact(&mut f, &mut buf))
            .map_err(|source| ReadStatesError::Io {
                path: self.file.clone(),
                source,
            })?;
        let values: Vec<f64> = buf
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
            .collect();
        if let Some(v) = values.iter().find(|v| !v.is_finite()) {
            return Err(invalid(format!("point {k} has a non-finite entry {v}")));
        }
        Ok(SavedPoint {
            parameters: values[..p].to_vec(),
            u: values[p..].to_vec(),
        })
    }
}

/// The first 8 bytes of `critical.states`.
pub const CRITICAL_MAGIC: &[u8; 8] = b"MCRITIC1";

/// The name of the critical states file in a run's directory.
pub const CRITICAL_FILE: &str = "critical.states";

/// One saved critical point: every parameter, the state over the unknowns and the mode (in
/// the coordinates the model keeps it in: over the unknowns of a 3-D mesh, over the kept
/// unknowns of its block on a meridian).
#[derive(Debug, Clone, PartialEq)]
pub struct SavedCritical {
    /// The parameters, in the order of the run's `parameters`.
    pub parameters: Vec<f64>,
    /// u over the unknowns.
    pub u: Vec<f64>,
    /// The unit mode.
    pub mode: Vec<f64>,
}

/// Writes `dir/critical.states`: the run's critical points (numbered from 1, as
/// `critical_NN.vtu`), each with its parameters, state and mode, little-endian: the magic
/// `MCRITIC1`, the count C (u64), then per point the lengths P, N, L (u64) and its P
/// parameters, N state and L mode values (f64) — what `memstab branch` and a critical curve's
/// `from-run` start from.
///
/// # Errors
/// [`OutputError::Invalid`] for a non-finite entry (naming the point; nothing is written),
/// [`OutputError::Io`] when the file cannot be written.
pub fn write_critical_states(
    dir: &Path,
    critical: &[crate::results::CriticalPoint],
) -> Result<PathBuf, OutputError> {
    let path = dir.join(CRITICAL_FILE);
    for (k, cp) in critical.iter().enumerate() {
        let all = cp.parameters.iter().chain(&cp.state).chain(&cp.mode);
        if let Some(v) = all.into_iter().find(|v| !v.is_finite()) {
            return Err(OutputError::invalid(
                &path,
                format!("critical point {} has a non-finite entry {v}", k + 1),
            ));
        }
    }
    write_whole(&path, |w| {
        w.write_all(CRITICAL_MAGIC)?;
        w.write_all(&(critical.len() as u64).to_le_bytes())?;
        for cp in critical {
            for n in [cp.parameters.len(), cp.state.len(), cp.mode.len()] {
                w.write_all(&(n as u64).to_le_bytes())?;
            }
            let mut buf = Vec::new();
            for v in cp.parameters.iter().chain(&cp.state).chain(&cp.mode) {
                buf.extend_from_slice(&v.to_le_bytes());
            }
            w.write_all(&buf)?;
        }
        Ok(())
    })?;
    Ok(path)
}

/// Reads `dir/critical.states` ([`write_critical_states`]).
pub fn read_critical_states(dir: &Path) -> Result<Vec<SavedCritical>, ReadStatesError> {
    let path = dir.join(CRITICAL_FILE);
    let bytes = super::read_regular(&path).map_err(|source| ReadStatesError::Io {
        path: path.clone(),
        source,
    })?;
    super::verify_or_warn(dir, &[CRITICAL_FILE]).map_err(ReadStatesError::Unverified)?;
    let invalid = |message: &str| ReadStatesError::Invalid {
        path: path.clone(),
        message: message.to_string(),
    };
    if bytes.len() < 16 || &bytes[..8] != CRITICAL_MAGIC {
        return Err(invalid("not a critical.states file of memstab run"));
    }
    let mut at = 8;
    let word = |at: &mut usize| -> Option<[u8; 8]> {
        let w = bytes.get(*at..*at + 8)?.try_into().ok()?;
        *at += 8;
        Some(w)
    };
    let truncated = || invalid("the file is cut short");
    let count = u64::from_le_bytes(word(&mut at).ok_or_else(truncated)?) as usize;
    let mut out = Vec::with_capacity(count.min(1 << 16));
    for _ in 0..count {
        let mut lengths = [0usize; 3];
        for l in &mut lengths {
            *l = u64::from_le_bytes(word(&mut at).ok_or_else(truncated)?) as usize;
        }
        let values = |n: usize, at: &mut usize| -> Result<Vec<f64>, ReadStatesError> {
            (0..n)
                .map(|_| word(at).map(f64::from_le_bytes).ok_or_else(truncated))
                .collect()
        };
        let parameters = values(lengths[0], &mut at)?;
        let u = values(lengths[1], &mut at)?;
        let mode = values(lengths[2], &mut at)?;
        out.push(SavedCritical {
            parameters,
            u,
            mode,
        });
    }
    if at != bytes.len() {
        return Err(invalid("the file is longer than its points"));
    }
    Ok(out)
}
