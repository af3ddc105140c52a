//! The start state — the one start solve that `run`, `spectrum`, `export-matrix`, `compare`
//! and `bench` share — and the `equilibrium` analysis, which is that state alone with its
//! stability.
//!
//! The start state is solved with every parameter at its start value (or a caller's
//! override), no constraint active, from the reference scaled by `start.stretch`, by Newton
//! in the fixed-point space of the scene's group; an inside-out solution is refused; the
//! targets of constraints declared `"initial"` are then measured there.

use super::{Observer, Record, RunError, SymmetricProblem};
use crate::continuation::crossings::Crossings;
use crate::continuation::{solve_at, PathOptions};
use crate::model::Model;
use crate::results::{PhaseTimes, StateKind, StopReason};
use crate::scene::{Analysis, Direction};
use crate::study::{Measure, Study};

/// The start state: the displacement over the model's unknowns, every parameter, and the
/// Newton iterations it took.
#[derive(Debug, Clone)]
pub struct StartState {
    /// Displacement over the unknowns.
    pub u: Vec<f64>,
    /// Every parameter (scene order).
    pub params: Vec<f64>,
    /// Newton iterations.
    pub iterations: usize,
}

/// Solves the start state with every parameter at `params` and no constraint active (the
/// reference scaled by `start.stretch` is the first guess), refuses an inside-out solution,
/// and sets the targets of constraints declared `"initial"` there. Returns the displacement,
/// the parameters and Newton's iterations.
pub fn solve_start(
    study: &mut Study,
    params: &[f64],
) -> Result<(Vec<f64>, Vec<f64>, usize), RunError> {
    solve_start_with(study, params).map(|(u, p, it, _)| (u, p, it))
}

/// As [`solve_start`], returning the time its evaluations took instead of the iterations.
pub fn solve_start_timed(
    study: &mut Study,
    params: &[f64],
) -> Result<(Vec<f64>, Vec<f64>, PhaseTimes), RunError> {
    solve_start_with(study, params).map(|(u, p, _, t)| (u, p, t))
}

fn solve_start_with(
    study: &mut Study,
    params: &[f64],
) -> Result<(Vec<f64>, Vec<f64>, usize, PhaseTimes), RunError> {
    if study.scene.start.from.is_some() && study.saved_start.is_none() {
        return Err(RunError::NotLoaded);
    }
    let opts = path_options(study);
    let u0 = study.start_displacement();
    let q0 = study.basis.restrict(&u0);
    let mut problem = SymmetricProblem::new(
        &study.model,
        &study.basis,
        &[],
        params.to_vec(),
        study.control,
    )
    .holding_neutral();
    let lambda = problem.free_values(params);
    let start_opts = PathOptions {
        max_iterations: opts.max_iterations.max(50),
        ..opts
    };
    let q0 = match study.scene.start.hold_translation {
        Some(d) => {
            let mut e = vec![0.0; study.basis.unknowns()];
            for i in 0..study.model.reference().len() {
                for (c, dc) in d.iter().enumerate() {
                    if let Some(k) = study.model.layout().dof(i, c) {
                        e[k] = *dc;
                    }
                }
            }
            let w = study.basis.restrict(&e);
            crate::continuation::release::released(&mut problem, &q0, &lambda, w, &start_opts)
                .map_err(|e| RunError::start(study, e))?
                .0
        }
        None => q0,
    };
    let (q, lambda, iterations) =
        solve_at(&mut problem, &q0, &lambda, &start_opts).map_err(|e| RunError::start(study, e))?;
    let params = problem.parameters(&lambda);
    let times = problem.times;
    let mut u = vec![0.0; study.basis.unknowns()];
    study.basis.expand(&q, &mut u);
    // A closed membrane with a negative enclosed volume is inside out (an open one closed by
    // its plate may enclose a negative volume: a disc sagging below its rim).
    if let Some(k) = study
        .measures
        .iter()
        .position(|(_, m)| *m == Measure::Volume)
        .filter(|_| study.closed())
    {
        let volume = study.measure(&u, &params)[k];
        if volume <= 0.0 {
            return Err(RunError::InsideOut { volume });
        }
    }
    if let Some(defect) = study.model.state_defect(&u, &params) {
        return Err(RunError::Degenerate(defect));
    }
    study.set_targets(&u, &params);
    Ok((u, params, iterations, times))
}

/// The state that a one-point command (`spectrum`, `export-matrix`) analyses, with
/// `overrides` (parameter index, value) in place of start values — the state `run` would
/// start from if the scene's start values were those. On a `linear-buckling` scene the start
/// state is held: it is solved with the control at its start value, and the control's
/// override enters only the tangent (`params`), as on `run`'s sample at that value.
pub fn state_at(study: &mut Study, overrides: &[(usize, f64)]) -> Result<StartState, RunError> {
    let mut params = study.start.clone();
    for &(i, v) in overrides {
        params[i] = v;
    }
    let mut solve_params = params.clone();
    if let (true, Some(c)) = (held(study), study.control) {
        solve_params[c] = study.start[c];
    }
    let (u, _, iterations) = solve_start(study, &solve_params)?;
    Ok(StartState {
        u,
        params,
        iterations,
    })
}

/// True for a scene whose state is held while its control sweeps (linear buckling).
pub fn held(study: &Study) -> bool {
    matches!(study.scene.analysis, Analysis::LinearBuckling(_))
}

/// The path options of a study's analysis (steps, bounds, tolerances, scales).
pub fn path_options(study: &Study) -> PathOptions {
    let scale = state_scale(study);
    let bounds = study
        .control
        .map(|c| &study.scene.parameters[&study.parameters[c]]);
    let bounds = (
        bounds.and_then(|b| b.min).unwrap_or(f64::NEG_INFINITY),
        bounds.and_then(|b| b.max).unwrap_or(f64::INFINITY),
    );
    match &study.scene.analysis {
        Analysis::Path(p) => PathOptions {
            initial_step: p.initial_step,
            min_step: p.min_step,
            max_step: p.max_step,
            max_steps: p.steps,
            max_iterations: p.max_iterations,
            tolerance: p.tolerance,
            bounds,
            parameter_scales: vec![1.0; study.free.len()],
            state_scale: scale,
            direction: match p.direction {
                Direction::Decrease => -1.0,
                Direction::Increase => 1.0,
            },
        },
        // The path that finds the curve's first point: the control increasing from the start.
        Analysis::CriticalCurve(c) => PathOptions {
            initial_step: c.initial_step,
            min_step: c.min_step,
            max_step: c.max_step,
            max_steps: c.path_steps,
            max_iterations: c.max_iterations,
            tolerance: c.tolerance,
            bounds,
            parameter_scales: vec![1.0; study.free.len()],
            state_scale: scale,
            direction: 1.0,
        },
        // Every path of the surface: the ranges' first bounds the paths' parameter.
        Analysis::Surface(a) => PathOptions {
            initial_step: a.initial_step,
            min_step: a.min_step,
            max_step: a.max_step,
            max_steps: a.steps,
            max_iterations: a.max_iterations,
            tolerance: a.tolerance,
            bounds: (bounds.0.max(a.ranges[0][0]), bounds.1.min(a.ranges[0][1])),
            parameter_scales: vec![1.0; study.free.len()],
            state_scale: scale,
            direction: match a.direction {
                Direction::Decrease => -1.0,
                Direction::Increase => 1.0,
            },
        },
        Analysis::Equilibrium(e) => PathOptions {
            tolerance: e.tolerance,
            max_iterations: e.max_iterations,
            state_scale: scale,
            ..PathOptions::default()
        },
        Analysis::LinearBuckling(b) => PathOptions {
            tolerance: b.tolerance,
            max_iterations: b.max_iterations,
            state_scale: scale,
            ..PathOptions::default()
        },
    }
}

/// The unit of the state in the arclength: the mesh radius times √nodes, so that a step is
/// an RMS displacement relative to the mesh size.
pub fn state_scale(study: &Study) -> f64 {
    let r = study
        .model
        .reference()
        .iter()
        .map(|x| x.norm())
        .fold(0.0, f64::max)
        .max(1e-300);
    r * (study.model.reference().len() as f64).sqrt()
}

/// The `equilibrium` analysis: the start state solved again with the constraints active,
/// its row, its index and its state.
pub(super) fn run(
    study: &Study,
    record: &mut Record,
    mut crossings: Option<Crossings<'_>>,
    u_start: &[f64],
    params_start: &[f64],
    observer: &mut dyn Observer,
) -> Result<StopReason, RunError> {
    let mut problem = SymmetricProblem::new(
        &study.model,
        &study.basis,
        &study.constraints,
        params_start.to_vec(),
        study.control,
    );
    let lambda0 = problem.free_values(params_start);
    let q_start = study.basis.restrict(u_start);
    let (q, lambda, iterations) = solve_at(&mut problem, &q_start, &lambda0, &path_options(study))
        .map_err(|e| RunError::start(study, e))?;
    let u = problem.displacement(&q);
    let params = problem.parameters(&lambda);
    observer.progress(0, lambda[0]);
    observer.state(&u, &params);
    let index = crossings
        .as_mut()
        .and_then(|c| c.index(&u, &params))
        .map(|s| s.index);
    record.state(0, StateKind::Step, u.clone(), &params);
    record.row(study, 0, 0.0, &u, params, iterations, index);
    Ok(StopReason::Equilibrium)
}
