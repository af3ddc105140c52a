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
    let text = std::fs::read_to_string(json).map_err(|e| io_err(json, e))?;
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
    let file = json.parent().unwrap_or(Path::new("")).join(name);
    let mut f = std::fs::File::open(&file).map_err(|e| io_err(&file, e))?;
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
        let mut f = std::fs::File::open(&self.file).map_err(|source| ReadStatesError::Io {
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
