//! Where a run starts when it starts from an earlier one (docs/scenes.md): a saved path point
//! of a finished run (`[start] from`), a critical point of a finished run (a critical curve's
//! `analysis.from-run`, `memstab branch`), read back with the readers of [`crate::output`] and
//! checked against the study before anything is computed — the [`Start`] the analyses take.

use crate::output::store::{read_critical_states, read_states, SavedCritical, CRITICAL_FILE};
use crate::output::{FinishedRun, ReopenError};
use crate::results::{CriticalPoint, PathRow, PointState, RecordedPoint};
use crate::study::{Start, Study};

/// The start the scene asks for: a critical point of `analysis.from-run`, a saved point of
/// `[start] from`, or the solve from the scene's first guess. The message of an error names
/// the key (`start.from`, `start.point`, `analysis.from-run`, `analysis.from`) and the value.
pub fn start_of(study: &dyn Study) -> Result<Start, String> {
    if let Some(cp) = curve_start(study)? {
        return Ok(Start::Critical(Box::new(cp)));
    }
    saved_start(study)
}

/// The start of `[start] from`, if the scene has one: the saved point `point` of that run is
/// the first guess, its parameters the start values (by name; a parameter the run did not
/// have keeps the scene's start value).
pub fn saved_start(study: &dyn Study) -> Result<Start, String> {
    let start = &study.scene().start;
    let (Some(from), Some(point)) = (start.from.clone(), start.point) else {
        return Ok(Start::Solve);
    };
    let shown = from.display().to_string();
    let run = read_states(&from).map_err(|e| format!("'start.from' = \"{shown}\": {e}"))?;
    let unknowns = study.about().unknowns;
    if run.unknowns != unknowns {
        return Err(format!(
            "'start.from' = \"{shown}\": its states have {} unknowns, this scene's model {unknowns} \
             (another mesh or other fixed nodes)",
            run.unknowns
        ));
    }
    let saved = run
        .point(point)
        .map_err(|e| format!("'start.point' = {point}: {e}"))?;
    let names = &study.about().parameters;
    let mut params = study.start_values().to_vec();
    for (name, value) in run.parameters.iter().zip(&saved.parameters) {
        if let Some(k) = names.iter().position(|p| p == name) {
            params[k] = *value;
        }
    }
    Ok(Start::From { u: saved.u, params })
}

/// Fails unless `study` is the model the run solved — the same scene name, group,
/// parameters and number of unknowns — and its analysis is a path (a held state's critical
/// points are not points of a path of equilibria).
pub fn check(run: &FinishedRun, study: &dyn Study) -> Result<(), ReopenError> {
    let analysis = &study.scene().analysis;
    if super::path_of(analysis).is_none() {
        return Err(ReopenError(format!(
            "the scene of the run in '{}' is a {} analysis: branches leave the critical points of a path (type = \"path\") only",
            run.dir.display(),
            analysis.kind()
        )));
    }
    check_model(run, study)
}

/// Fails unless `study` is the model the run solved: the same scene name, group, parameters
/// and number of unknowns (any analysis).
pub fn check_model(run: &FinishedRun, study: &dyn Study) -> Result<(), ReopenError> {
    let mismatch = |what: &str, was: String, now: String| {
        ReopenError(format!(
            "the scene does not match the run in '{}': {what} is {now}, the run's was {was} (give the run's scene with --scene)",
            run.dir.display()
        ))
    };
    let about = study.about();
    if about.scene != run.scene {
        return Err(mismatch(
            "the scene name",
            run.scene.clone(),
            about.scene.clone(),
        ));
    }
    if about.group != run.group {
        return Err(mismatch(
            "the group",
            run.group.clone(),
            about.group.clone(),
        ));
    }
    if about.unknowns != run.unknowns {
        return Err(mismatch(
            "the number of unknowns",
            run.unknowns.to_string(),
            about.unknowns.to_string(),
        ));
    }
    if about.parameters != run.path.parameters {
        return Err(mismatch(
            "the parameters",
            run.path.parameters.join(", "),
            about.parameters.join(", "),
        ));
    }
    Ok(())
}

/// The state of path point `n` (the row `step = n` of `path.csv`) from `path.states`: the
/// displacement over the unknowns of `study` and every parameter; `n` out of range is an
/// error naming the range.
pub fn point(
    run: &FinishedRun,
    study: &dyn Study,
    n: usize,
) -> Result<(Vec<f64>, Vec<f64>), ReopenError> {
    let states = read_states(&run.dir.join("path.json")).map_err(|e| ReopenError(e.to_string()))?;
    let unknowns = study.about().unknowns;
    if states.unknowns != unknowns {
        return Err(ReopenError(format!(
            "{}: states of {} unknowns, the scene's model has {unknowns}",
            states.file.display(),
            states.unknowns,
        )));
    }
    if n >= states.points {
        return Err(ReopenError(format!(
            "--point {n}: the run in '{}' has {} path points (0 to {})",
            run.dir.display(),
            states.points,
            states.points.saturating_sub(1)
        )));
    }
    let saved = states.point(n).map_err(|e| ReopenError(e.to_string()))?;
    Ok((saved.u, saved.parameters))
}

/// The state and the unit mode of critical point `n` (1-based) of `run`, as its
/// `critical.states` keeps them, over the unknowns of `study`; `n` out of range is an error
/// naming the range.
pub fn critical_state(
    run: &FinishedRun,
    study: &dyn Study,
    n: usize,
) -> Result<(Vec<f64>, Vec<f64>), ReopenError> {
    if n == 0 || n > run.critical.len() {
        return Err(ReopenError(format!(
            "--critical {n}: the run in '{}' has {} critical point{} (numbered from 1)",
            run.dir.display(),
            run.critical.len(),
            if run.critical.len() == 1 { "" } else { "s" }
        )));
    }
    let saved = read_critical_states(&run.dir).map_err(|e| ReopenError(e.to_string()))?;
    checked_critical(run, study, &saved, n)
}

/// Critical point `n` (1-based, in range) of `saved` (the run's `critical.states`) checked
/// against `study`: its state and unit mode.
fn checked_critical(
    run: &FinishedRun,
    study: &dyn Study,
    saved: &[SavedCritical],
    n: usize,
) -> Result<(Vec<f64>, Vec<f64>), ReopenError> {
    let file = run.dir.join(CRITICAL_FILE);
    let Some(point) = saved.get(n - 1) else {
        return Err(ReopenError(format!(
            "{}: {} critical points, path.json names {}",
            file.display(),
            saved.len(),
            run.critical.len()
        )));
    };
    let unknowns = study.about().unknowns;
    if point.u.len() != unknowns {
        return Err(ReopenError(format!(
            "{}: critical point {n} has a state of {} unknowns, the scene's model has {unknowns}",
            file.display(),
            point.u.len()
        )));
    }
    let norm = point.mode.iter().map(|v| v * v).sum::<f64>().sqrt();
    if !(norm > 0.0 && norm.is_finite()) {
        return Err(ReopenError(format!(
            "{}: the mode of critical point {n} is zero",
            file.display()
        )));
    }
    Ok((
        point.u.clone(),
        point.mode.iter().map(|v| v / norm).collect(),
    ))
}

/// The critical point a critical curve of `study` starts from with
/// `analysis.from-run` (if any): the run in that directory read back and checked against the
/// model, and its critical point `analysis.from` (0 the first) with its state and mode from
/// `critical_NN.vtu`. The message of an error names `analysis.from-run` or `analysis.from`
/// and the value.
fn curve_start(study: &dyn Study) -> Result<Option<CriticalPoint>, String> {
    let Some((dir, i)) = super::analysis_of(&study.scene().analysis).restarts_from() else {
        return Ok(None);
    };
    let shown = dir.display().to_string();
    let key = |e: ReopenError| format!("'analysis.from-run' = \"{shown}\": {e}");
    let run = FinishedRun::read(&dir).map_err(key)?;
    check_model(&run, study).map_err(key)?;
    let Some(point) = run.critical.get(i) else {
        return Err(format!(
            "'analysis.from' = {i}: the run in '{shown}' has {} critical point{} (0 to {})",
            run.critical.len(),
            if run.critical.len() == 1 { "" } else { "s" },
            run.critical.len().saturating_sub(1)
        ));
    };
    let (state, mode) = critical_state(&run, study, i + 1).map_err(key)?;
    let recorded = RecordedPoint {
        kind: point.kind.clone(),
        irrep: point.irrep.clone(),
        parameters: point.parameters.clone(),
        measures: study.measure(&state, &point.parameters),
        after_step: 0,
        residual_eigenvalue: point.residual_eigenvalue,
    };
    let mut points = study
        .recorded(&[recorded], 1, state, mode)
        .map_err(|e| format!("'analysis.from' = {i}: critical point {}: {e}", i + 1))?;
    Ok(Some(points.remove(0)))
}

/// A finished path read back whole: its rows, every row's state in the fixed-point
/// coordinates of the study, and its critical points each with its state and mode — what a
/// later analysis of the path (`memstab diagram RUN_DIR`) starts from, as if the path had
/// just been followed.
#[derive(Debug, Clone)]
pub struct Reloaded {
    /// The rows, as written.
    pub rows: Vec<PathRow>,
    /// Every row's state.
    pub points: Vec<PointState>,
    /// The critical points, with their states and modes.
    pub critical: Vec<CriticalPoint>,
}

/// The path of `run` read back for `study` (checked against it first: [`check_model`]): its
/// rows from `path.json`, every row's state from `path.states`, every critical point from
/// `critical.states`. A run that kept no states, or states that do not fit the rows, is an
/// error naming the file.
pub fn reload(run: &FinishedRun, study: &dyn Study) -> Result<Reloaded, ReopenError> {
    check_model(run, study)?;
    let states = read_states(&run.dir.join("path.json")).map_err(|e| ReopenError(e.to_string()))?;
    let unknowns = study.about().unknowns;
    if states.unknowns != unknowns || states.points != run.rows.len() {
        return Err(ReopenError(format!(
            "{}: {} states of {} unknowns, path.json has {} rows and the scene's model {unknowns} unknowns",
            states.file.display(),
            states.points,
            states.unknowns,
            run.rows.len()
        )));
    }
    let mut points = Vec::with_capacity(states.points);
    for k in 0..states.points {
        let saved = states.point(k).map_err(|e| ReopenError(e.to_string()))?;
        points.push(PointState {
            q: study.coordinates(&saved.u),
            parameters: saved.parameters,
        });
    }
    let saved = read_critical_states(&run.dir).map_err(|e| ReopenError(e.to_string()))?;
    let mut critical = Vec::with_capacity(run.critical.len());
    for n in 1..=run.critical.len() {
        let (state, mode) = checked_critical(run, study, &saved, n)?;
        let mut all = study
            .recorded(&run.critical, n, state, mode)
            .map_err(ReopenError)?;
        critical.push(all.swap_remove(n - 1));
    }
    Ok(Reloaded {
        rows: run.rows.clone(),
        points,
        critical,
    })
}
