//! A finished run read back from its directory, to switch branches at one of its critical
//! points later (`memstab branch RUN_DIR --critical N`).
//!
//! What is read (docs/scenes.md, "Branches from a finished run"): `path.json` — the scene's
//! origin and name, the group, the unknowns, the parameter names, the control and the index
//! at every path point, and the critical points (irrep, parameters, step); and
//! `critical_NN.vtu` — the state of critical point NN (its points are the displaced nodes
//! X + u) and its mode (the point field `critical_mode`). The scene itself is rebuilt from
//! its file, and must give the same model (name, group, unknowns). What is read is checked
//! against the run's `manifest.json` first: an edited file is refused, naming it.

use crate::results::{PathRow, PrimaryPath, RecordedPoint};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// Why a run directory cannot be reopened (bad input: the message names the file and what
/// is wrong).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct ReopenError(pub String);

/// A finished run's directory, read back.
#[derive(Debug, Clone)]
pub struct FinishedRun {
    /// The directory.
    pub dir: PathBuf,
    /// The scene file the run came from, as recorded.
    pub origin: String,
    /// The scene's name.
    pub scene: String,
    /// The scene's group.
    pub group: String,
    /// The model's unknowns.
    pub unknowns: usize,
    /// The path (control and index at every point).
    pub path: PrimaryPath,
    /// The critical points, in order (critical point N is `critical[N - 1]`).
    pub critical: Vec<RecordedPoint>,
    /// Every row of the path, as written.
    pub rows: Vec<PathRow>,
    /// The irrep blocks of the rows' `negative` counts (empty when no row has them).
    pub irreps: Vec<String>,
    /// Why the path ended, in the run's words.
    pub stop: String,
}

fn field<'a>(v: &'a Value, key: &str, file: &Path) -> Result<&'a Value, ReopenError> {
    v.get(key).ok_or_else(|| {
        ReopenError(format!(
            "{}: no '{key}' (not a path.json of memstab run)",
            file.display()
        ))
    })
}

fn numbers(v: &Value, what: &str, file: &Path) -> Result<Vec<f64>, ReopenError> {
    v.as_array()
        .and_then(|a| a.iter().map(Value::as_f64).collect::<Option<Vec<f64>>>())
        .ok_or_else(|| {
            ReopenError(format!(
                "{}: {what} is not a list of numbers",
                file.display()
            ))
        })
}

fn text(v: &Value, key: &str, file: &Path) -> Result<String, ReopenError> {
    field(v, key, file)?
        .as_str()
        .map(str::to_string)
        .ok_or_else(|| ReopenError(format!("{}: '{key}' is not a string", file.display())))
}

fn count(v: &Value, key: &str, file: &Path) -> Result<usize, ReopenError> {
    field(v, key, file)?
        .as_u64()
        .map(|n| n as usize)
        .ok_or_else(|| ReopenError(format!("{}: '{key}' is not a count", file.display())))
}

impl FinishedRun {
    /// Reads `dir/path.json`.
    pub fn read(dir: &Path) -> Result<Self, ReopenError> {
        let file = dir.join("path.json");
        let data = super::read_regular_string(&file).map_err(|e| {
            ReopenError(format!(
                "'{}': cannot read {}: {e} (RUN_DIR must be the output directory of memstab run)",
                dir.display(),
                file.display()
            ))
        })?;
        super::verify_or_warn(dir, &["path.json"]).map_err(ReopenError)?;
        let v: Value = serde_json::from_str(&data)
            .map_err(|e| ReopenError(format!("{}: not JSON: {e}", file.display())))?;
        let parameters: Vec<String> = field(&v, "parameters", &file)?
            .as_array()
            .and_then(|a| a.iter().map(|p| p.as_str().map(str::to_string)).collect())
            .ok_or_else(|| {
                ReopenError(format!(
                    "{}: 'parameters' is not a list of names",
                    file.display()
                ))
            })?;
        let control = text(&v, "control", &file)?;
        let c = parameters.iter().position(|p| *p == control);
        let rows = field(&v, "rows", &file)?
            .as_array()
            .ok_or_else(|| ReopenError(format!("{}: 'rows' is not a list", file.display())))?;
        let mut values = Vec::with_capacity(rows.len());
        let mut index = Vec::with_capacity(rows.len());
        let mut full = Vec::with_capacity(rows.len());
        for (k, r) in rows.iter().enumerate() {
            let p = numbers(
                field(r, "parameters", &file)?,
                &format!("rows[{k}].parameters"),
                &file,
            )?;
            if p.len() != parameters.len() {
                return Err(ReopenError(format!(
                    "{}: rows[{k}] has {} parameters, the run names {}",
                    file.display(),
                    p.len(),
                    parameters.len()
                )));
            }
            values.push(c.and_then(|c| p.get(c).copied()).unwrap_or(0.0));
            index.push(r.get("index").and_then(Value::as_u64).map(|i| i as usize));
            full.push(
                serde_json::from_value::<PathRow>(r.clone())
                    .map_err(|e| ReopenError(format!("{}: rows[{k}]: {e}", file.display())))?,
            );
        }
        let irreps: Vec<String> = v
            .get("irreps")
            .and_then(Value::as_array)
            .map(|a| {
                a.iter()
                    .filter_map(|m| m.as_str().map(str::to_string))
                    .collect()
            })
            .unwrap_or_default();
        let stop = v
            .get("stop")
            .and_then(Value::as_str)
            .unwrap_or_default()
            .to_string();
        let mut critical = Vec::new();
        let list = field(&v, "critical", &file)?
            .as_array()
            .ok_or_else(|| ReopenError(format!("{}: 'critical' is not a list", file.display())))?;
        let measure_names: Vec<String> = field(&v, "measures", &file)?
            .as_array()
            .map(|a| {
                a.iter()
                    .filter_map(|m| m.as_str().map(str::to_string))
                    .collect()
            })
            .unwrap_or_default();
        for (k, cp) in list.iter().enumerate() {
            let what = |key: &str| format!("critical[{k}].{key}");
            // By name (as written), or a list in the order of the names (older runs).
            let values = |key: &str, names: &[String]| match field(cp, key, &file)? {
                Value::Object(map) => names
                    .iter()
                    .map(|n| map.get(n).and_then(Value::as_f64))
                    .collect::<Option<Vec<f64>>>()
                    .ok_or_else(|| {
                        ReopenError(format!(
                            "{}: {} does not hold a number for every name",
                            file.display(),
                            what(key)
                        ))
                    }),
                list => numbers(list, &what(key), &file),
            };
            let step_key = if cp.get("step").is_some() {
                "step"
            } else {
                "after_step"
            };
            critical.push(RecordedPoint {
                kind: cp
                    .get("kind")
                    .and_then(Value::as_str)
                    .unwrap_or_default()
                    .to_string(),
                irrep: text(cp, "irrep", &file)?,
                parameters: values("parameters", &parameters)?,
                measures: values("measures", &measure_names)?,
                after_step: count(cp, step_key, &file)?,
                residual_eigenvalue: field(cp, "residual_eigenvalue", &file)?
                    .as_f64()
                    .unwrap_or(0.0),
            });
        }
        let measures = field(&v, "measures", &file)?.as_array().map_or(0, Vec::len);
        for (k, c) in critical.iter().enumerate() {
            if c.parameters.len() != parameters.len() || c.measures.len() != measures {
                return Err(ReopenError(format!(
                    "{}: critical[{k}] has {} parameters and {} measures, the run names {} and {measures}",
                    file.display(),
                    c.parameters.len(),
                    c.measures.len(),
                    parameters.len()
                )));
            }
        }
        let scene = text(&v, "scene", &file)?;
        let group = text(&v, "group", &file)?;
        Ok(Self {
            dir: dir.to_path_buf(),
            origin: text(&v, "origin", &file)?,
            unknowns: count(&v, "unknowns", &file)?,
            path: PrimaryPath {
                scene: scene.clone(),
                group: group.clone(),
                mesh: mesh_description(&v),
                control,
                parameters,
                values,
                index,
            },
            scene,
            group,
            critical,
            rows: full,
            irreps,
            stop,
        })
    }

    /// The instability index the run recorded at path point `n` (`None`: not computed there,
    /// or no such point).
    pub fn index_at(&self, n: usize) -> Option<usize> {
        self.path.index.get(n).copied().flatten()
    }
}

/// The mesh of a `path.json` as [`MeshInfo::describe`](crate::results::MeshInfo::describe)
/// names it; empty if the file does not say.
fn mesh_description(v: &serde_json::Value) -> String {
    let m = &v["mesh"];
    match (
        m["generator"].as_str(),
        m["elements"].as_u64(),
        m["group"].as_str(),
    ) {
        (Some(g), Some(n), Some(group)) => format!("{g}, {n} triangles, group {group}"),
        _ => String::new(),
    }
}
