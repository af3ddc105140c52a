//! Running a study's analysis: the start solve, then the path (or the single equilibrium),
//! collected into a [`PathReport`] with the states to save.
//!
//! The start state is the reference scaled by `start.stretch`, solved with every parameter at
//! its start value. Constraint targets declared `"initial"` are measured there. The path is
//! then followed in the fixed-point space of the scene's group with the control and the
//! constraint-governed parameters free.

use crate::adapted::SymmetricProblem;
use crate::continuation::{follow, solve_at, PathOptions, PathPoint, StopReason};
use crate::report::{MeshInfo, PathReport, PathRow, TurningRow};
use crate::scene::{Analysis, Direction};
use crate::study::{Measure, Study};
use nalgebra::DVector;

/// A state to write: path step, control value, full displacement.
#[derive(Debug, Clone)]
pub struct State {
    /// Path step (turning points carry the step before them).
    pub step: usize,
    /// A label: `step` or `maximum` / `minimum`.
    pub label: String,
    /// The control's value.
    pub control: f64,
    /// Displacement over the unknowns.
    pub u: Vec<f64>,
}

/// A finished run.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// What was found.
    pub report: PathReport,
    /// States to write (every `save-every` steps, the last one, and the turning points).
    pub states: Vec<State>,
}

/// Why a run failed before it produced a path.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The start state could not be solved.
    #[error("the start state did not converge: {0}")]
    Start(String),
}

/// Runs the scene's analysis; `progress(step, control)` is called at every converged point.
pub fn run(study: &mut Study, mut progress: impl FnMut(usize, f64)) -> Result<RunResult, RunError> {
    let (opts, save_every, stop_stretch, direction) = match &study.scene.analysis {
        Analysis::Path(p) => {
            let control = study.control.expect("a path analysis has a control");
            let bounds = &study.scene.parameters[&study.parameters[control]];
            (
                PathOptions {
                    initial_step: p.initial_step,
                    min_step: p.min_step,
                    max_step: p.max_step,
                    max_steps: p.steps,
                    max_iterations: p.max_iterations,
                    tolerance: p.tolerance,
                    bounds: (bounds.min.unwrap_or(f64::NEG_INFINITY), bounds.max.unwrap_or(f64::INFINITY)),
                    parameter_scales: vec![1.0; study.free.len()],
                    state_scale: state_scale(study),
                    direction: if p.direction == Direction::Decrease { -1.0 } else { 1.0 },
                },
                p.save_every.max(1),
                p.stop_stretch,
                p.direction,
            )
        }
        Analysis::Equilibrium(e) => (
            PathOptions {
                tolerance: e.tolerance,
                max_iterations: e.max_iterations,
                state_scale: state_scale(study),
                ..PathOptions::default()
            },
            1,
            None,
            Direction::Increase,
        ),
    };
    let _ = direction;
    // 1. The start: every parameter at its start value, no constraint active.
    let u0 = study.start_displacement();
    let q0 = study.basis.restrict(&u0);
    let (q_start, params_start) = {
        let mut problem = SymmetricProblem::new(&study.model, &study.basis, &[], study.start.clone(), study.control);
        let lambda = problem.free_values(&study.start);
        let start_opts = PathOptions {
            max_iterations: opts.max_iterations.max(50),
            ..opts.clone()
        };
        let (q, lambda, _) = solve_at(&mut problem, &q0, &lambda, &start_opts).map_err(RunError::Start)?;
        (q.clone(), problem.parameters(&lambda))
    };
    let u_start = {
        let mut u = vec![0.0; study.basis.unknowns()];
        study.basis.expand(&q_start, &mut u);
        u
    };
    study.set_targets(&u_start, &params_start);
    // 2. The path (or the single point).
    let study_ref: &Study = study;
    let mut problem = SymmetricProblem::new(&study_ref.model, &study_ref.basis, &study_ref.constraints, params_start.clone(), study_ref.control);
    let lambda0 = problem.free_values(&params_start);
    let probe = SymmetricProblem::new(&study_ref.model, &study_ref.basis, &study_ref.constraints, params_start.clone(), study_ref.control);
    let stretch_index = study_ref.measures.iter().position(|(_, m)| *m == Measure::Stretch);
    let row = |step: usize, p: &PathPoint| -> (PathRow, Vec<f64>) {
        let u = probe.displacement(&p.q);
        let params = probe.parameters(&p.lambda);
        let measures = study_ref.measure(&u, &params);
        (
            PathRow {
                step,
                arclength: p.arclength,
                parameters: params,
                measures,
                iterations: p.iterations,
            },
            u,
        )
    };
    let path = if matches!(study_ref.scene.analysis, Analysis::Path(_)) {
        let mut count = 0usize;
        follow(
            &mut problem,
            &q_start,
            &lambda0,
            &opts,
            |p| match (stop_stretch, stretch_index) {
                (Some(target), Some(k)) => row(0, p).0.measures[k] >= target,
                _ => false,
            },
            |p| {
                progress(count, p.lambda[0]);
                count += 1;
            },
        )
        .map_err(RunError::Start)?
    } else {
        let (q, lambda, iterations) = solve_at(&mut problem, &q_start, &lambda0, &opts).map_err(RunError::Start)?;
        crate::continuation::Path {
            points: vec![PathPoint {
                tangent: DVector::zeros(q.len() + lambda.len()),
                q,
                lambda,
                arclength: 0.0,
                iterations,
            }],
            turning_points: Vec::new(),
            stop: StopReason::Condition,
        }
    };
    let mut rows = Vec::with_capacity(path.points.len());
    let mut states = Vec::new();
    let control = study_ref.control;
    let last = path.points.len() - 1;
    for (step, p) in path.points.iter().enumerate() {
        let (r, u) = row(step, p);
        if step % save_every == 0 || step == last {
            states.push(State {
                step,
                label: format!("step {step}"),
                control: control.map_or(0.0, |c| r.parameters[c]),
                u,
            });
        }
        rows.push(r);
    }
    let mut turning_points = Vec::new();
    for t in &path.turning_points {
        let (r, u) = row(t.after_step, &t.point);
        let kind = if t.kind > 0.0 { "maximum" } else { "minimum" };
        states.push(State {
            step: t.after_step,
            label: kind.to_string(),
            control: control.map_or(0.0, |c| r.parameters[c]),
            u,
        });
        turning_points.push(TurningRow {
            kind: kind.to_string(),
            after_step: t.after_step,
            parameters: r.parameters,
            measures: r.measures,
        });
    }
    let stop = match &path.stop {
        StopReason::Bounds => "the control parameter reached its bound".to_string(),
        StopReason::StepBudget => format!("the step budget ({}) was used", opts.max_steps),
        StopReason::Condition if matches!(study_ref.scene.analysis, Analysis::Path(_)) => {
            format!("the stretch reached {}", stop_stretch.unwrap_or(f64::NAN))
        }
        StopReason::Condition => "equilibrium found".to_string(),
        StopReason::StepTooSmall(why) => why.clone(),
    };
    let m = &study_ref.mesh;
    let report = PathReport {
        scene: study_ref.scene.info.name.clone(),
        origin: study_ref.scene.origin.clone(),
        version: env!("CARGO_PKG_VERSION").to_string(),
        mesh: MeshInfo {
            generator: study_ref.scene.mesh.generator().to_string(),
            nodes: m.mesh.nodes.len(),
            elements: m.mesh.triangles.len(),
            group: m.group().name().to_string(),
            order: m.group().order(),
        },
        group: study_ref.action.group().name().to_string(),
        group_order: study_ref.action.group().order(),
        unknowns: study_ref.basis.unknowns(),
        symmetric_unknowns: study_ref.basis.dim(),
        control: control.map_or_else(String::new, |c| study_ref.parameters[c].clone()),
        parameters: study_ref.parameters.clone(),
        measures: study_ref.measures.iter().map(|(n, _)| n.clone()).collect(),
        rows,
        turning_points,
        stop,
        saved: Vec::new(),
    };
    Ok(RunResult { report, states })
}

/// The unit of the state in the arclength: the mesh radius times √nodes, so that a step is
/// an RMS displacement relative to the mesh size.
fn state_scale(study: &Study) -> f64 {
    let r = study.model.reference().iter().map(|x| x.norm()).fold(0.0, f64::max).max(1e-300);
    r * (study.model.reference().len() as f64).sqrt()
}
