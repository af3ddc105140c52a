//! A finished run read back from its directory, to switch branches at one of its critical
//! points later (`memstab branch RUN_DIR --critical N`).
//!
//! What is read (docs/scenes.md, "Branches from a finished run"): `path.json` — the scene's
//! origin and name, the group, the unknowns, the parameter names, the control and the index
//! at every path point, and the critical points (irrep, parameters, step); and
//! `critical_NN.vtu` — the state of critical point NN (its points are the displaced nodes
//! X + u) and its mode (the point field `critical_mode`). The scene itself is rebuilt from
//! its file, and must give the same model (name, group, unknowns).

use crate::model::Model;
use crate::results::{PrimaryPath, RecordedPoint};
use crate::study::Study;
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
        let data = std::fs::read_to_string(&file).map_err(|e| {
            ReopenError(format!(
                "'{}': cannot read {}: {e} (RUN_DIR must be the output directory of memstab run)",
                dir.display(),
                file.display()
            ))
        })?;
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
        for (k, r) in rows.iter().enumerate() {
            let p = numbers(
                field(r, "parameters", &file)?,
                &format!("rows[{k}].parameters"),
                &file,
            )?;
            values.push(c.and_then(|c| p.get(c).copied()).unwrap_or(0.0));
            index.push(r.get("index").and_then(Value::as_u64).map(|i| i as usize));
        }
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
                control,
                parameters,
                values,
                index,
            },
            scene,
            group,
            critical,
        })
    }

    /// Fails unless `study` is the model the run solved — the same scene name, group,
    /// parameters and number of unknowns — and its analysis is a path (a held state's
    /// critical points are not points of a path of equilibria).
    pub fn check(&self, study: &Study) -> Result<(), ReopenError> {
        if !matches!(study.scene.analysis, crate::scene::Analysis::Path(_)) {
            return Err(ReopenError(format!(
                "the scene of the run in '{}' is a {} analysis: branches leave the critical points of a path (type = \"path\") only",
                self.dir.display(),
                study.scene.analysis.kind()
            )));
        }
        self.check_model(study)
    }

    /// Fails unless `study` is the model the run solved: the same scene name, group,
    /// parameters and number of unknowns (any analysis).
    pub fn check_model(&self, study: &Study) -> Result<(), ReopenError> {
        let mismatch = |what: &str, run: String, now: String| {
            ReopenError(format!(
                "the scene does not match the run in '{}': {what} is {now}, the run's was {run} (give the run's scene with --scene)",
                self.dir.display()
            ))
        };
        if study.scene.info.name != self.scene {
            return Err(mismatch(
                "the scene name",
                self.scene.clone(),
                study.scene.info.name.clone(),
            ));
        }
        if study.action.group().name() != self.group {
            return Err(mismatch(
                "the group",
                self.group.clone(),
                study.action.group().name().to_string(),
            ));
        }
        if study.model.unknowns() != self.unknowns {
            return Err(mismatch(
                "the number of unknowns",
                self.unknowns.to_string(),
                study.model.unknowns().to_string(),
            ));
        }
        if study.parameters != self.path.parameters {
            return Err(mismatch(
                "the parameters",
                self.path.parameters.join(", "),
                study.parameters.join(", "),
            ));
        }
        Ok(())
    }

    /// The state of path point `n` (the row `step = n` of `path.csv`) from `path.states`:
    /// the displacement over the unknowns of `study` and every parameter; `n` out of range is
    /// an error naming the range.
    pub fn point(&self, study: &Study, n: usize) -> Result<(Vec<f64>, Vec<f64>), ReopenError> {
        let run = super::store::read_states(&self.dir.join("path.json"))
            .map_err(|e| ReopenError(e.to_string()))?;
        if run.unknowns != study.model.unknowns() {
            return Err(ReopenError(format!(
                "{}: states of {} unknowns, the scene's model has {}",
                run.file.display(),
                run.unknowns,
                study.model.unknowns()
            )));
        }
        if n >= run.points {
            return Err(ReopenError(format!(
                "--point {n}: the run in '{}' has {} path points (0 to {})",
                self.dir.display(),
                run.points,
                run.points.saturating_sub(1)
            )));
        }
        let saved = run.point(n).map_err(|e| ReopenError(e.to_string()))?;
        Ok((saved.u, saved.parameters))
    }

    /// The instability index the run recorded at path point `n` (`None`: not computed there,
    /// or no such point).
    pub fn index_at(&self, n: usize) -> Option<usize> {
        self.path.index.get(n).copied().flatten()
    }

    /// The state and the unit mode of critical point `n` (1-based) from `critical_NN.vtu`,
    /// over the unknowns of `study`; `n` out of range is an error naming the range.
    pub fn state(&self, study: &Study, n: usize) -> Result<(Vec<f64>, Vec<f64>), ReopenError> {
        if n == 0 || n > self.critical.len() {
            return Err(ReopenError(format!(
                "--critical {n}: the run in '{}' has {} critical point{} (numbered from 1)",
                self.dir.display(),
                self.critical.len(),
                if self.critical.len() == 1 { "" } else { "s" }
            )));
        }
        let file = self.dir.join(format!("critical_{n:02}.vtu"));
        let (mesh, mode) = meshes::read::read_vtu_field(&file, "critical_mode")
            .map_err(|e| ReopenError(e.to_string()))?;
        let reference = study.model.reference();
        if mesh.nodes.len() != reference.len() {
            return Err(ReopenError(format!(
                "{}: {} nodes, the scene's mesh has {}",
                file.display(),
                mesh.nodes.len(),
                reference.len()
            )));
        }
        let layout = study.model.layout();
        let mut u = vec![0.0; layout.unknowns()];
        let mut m = vec![0.0; layout.unknowns()];
        for (i, (x, x0)) in mesh.nodes.iter().zip(reference).enumerate() {
            for k in 0..3 {
                if let Some(d) = layout.dof(i, k) {
                    u[d] = x[k] - x0[k];
                    m[d] = mode[i][k];
                }
            }
        }
        let norm = m.iter().map(|v| v * v).sum::<f64>().sqrt();
        if !(norm > 0.0 && norm.is_finite()) {
            return Err(ReopenError(format!(
                "{}: the critical mode is zero",
                file.display()
            )));
        }
        m.iter_mut().for_each(|v| *v /= norm);
        Ok((u, m))
    }
}

/// Loads the critical point a critical curve of `study` starts from with
/// `analysis.from-run` (if any): the run in that directory read back and checked against the
/// model, and its critical point `analysis.from` (0 the first) with its state and mode from
/// `critical_NN.vtu`. The message of an error names `analysis.from-run` or `analysis.from`
/// and the value.
pub fn load_curve_start(study: &mut Study) -> Result<(), String> {
    let crate::scene::Analysis::CriticalCurve(a) = &study.scene.analysis else {
        return Ok(());
    };
    let (Some(dir), crate::scene::CurveStart::Index(i)) = (a.from_run.clone(), a.from.clone())
    else {
        return Ok(());
    };
    let shown = dir.display().to_string();
    let key = |e: ReopenError| format!("'analysis.from-run' = \"{shown}\": {e}");
    let run = FinishedRun::read(&dir).map_err(key)?;
    run.check_model(study).map_err(key)?;
    let Some(point) = run.critical.get(i) else {
        return Err(format!(
            "'analysis.from' = {i}: the run in '{shown}' has {} critical point{} (0 to {})",
            run.critical.len(),
            if run.critical.len() == 1 { "" } else { "s" },
            run.critical.len().saturating_sub(1)
        ));
    };
    let (state, mode) = run.state(study, i + 1).map_err(key)?;
    study.saved_critical = Some(crate::study::SavedCritical {
        number: i + 1,
        irrep: point.irrep.clone(),
        parameters: point.parameters.clone(),
        measures: point.measures.clone(),
        residual_eigenvalue: point.residual_eigenvalue,
        state,
        mode,
    });
    Ok(())
}
