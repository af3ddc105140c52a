//! The start state — the one start solve that `run`, `spectrum`, `export-matrix`, `compare`
//! and `bench` share — and the `equilibrium` analysis, which is that state alone with its
//! stability.
//!
//! The start state is solved with every parameter at its start value (or a caller's
//! override), no constraint active, from the reference scaled by `start.stretch`, by Newton
//! in the fixed-point space of the scene's group; an inside-out solution is refused; the
//! targets of constraints declared `"initial"` are then measured there.

use super::continuation::{
    point_at, solve_at, Continuation, Linearization, PathOptions, PhaseTimes, Problem, SolveError,
};
use super::events::{locate, Crossings, StopReason};
use super::{Observer, Record, RunError, SymmetricProblem};
use crate::model::Model;
use crate::report::StateKind;
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
            released(&mut problem, &q0, &lambda, w, &start_opts)
                .map_err(|e| RunError::start(study, e))?
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

/// A problem with the mean translation along a direction held (docs/theory.md §7.8): its
/// unknowns are the inner problem's q, the held mean displacement ζ (the control) and the
/// uniform force R that holds it (free), with
///
/// ```text
///   R_held(q, ζ, R) = R_inner(q) − R w,      g = wᵀ q / |w|² − ζ = 0,
/// ```
///
/// w = Bᵀ e the restricted translation field e_i = d. The inner problem's own free
/// parameters stay at the values given.
struct HeldTranslation<'p, 'a> {
    inner: &'p mut SymmetricProblem<'a>,
    lambda: nalgebra::DVector<f64>,
    w: nalgebra::DVector<f64>,
}

impl Problem for HeldTranslation<'_, '_> {
    fn dim(&self) -> usize {
        self.inner.dim()
    }

    fn free_parameters(&self) -> usize {
        2
    }

    fn evaluate(
        &mut self,
        q: &nalgebra::DVector<f64>,
        lambda: &nalgebra::DVector<f64>,
    ) -> Result<Linearization, crate::model::ModelError> {
        let lin = self.inner.evaluate(q, &self.lambda)?;
        let m = q.len();
        let w2 = self.w.norm_squared();
        let mut loads = nalgebra::DMatrix::zeros(m, 2);
        loads.set_column(1, &(-&self.w));
        let mut constraint_lambda = nalgebra::DMatrix::zeros(1, 2);
        constraint_lambda[(0, 0)] = -1.0;
        Ok(Linearization {
            residual: lin.residual - &self.w * lambda[1],
            tangent: lin.tangent,
            loads,
            constraints: nalgebra::DVector::from_element(1, self.w.dot(q) / w2 - lambda[0]),
            constraint_q: nalgebra::DMatrix::from_row_slice(1, m, (&self.w / w2).as_slice()),
            constraint_lambda,
        })
    }
}

/// The start homotopy of `[start] hold-translation` (docs/theory.md §7.8): from `q0`, solve
/// with the mean translation along `w` held at its start value; then move the held position
/// along an auxiliary path until the holding force vanishes, and return that state (the
/// caller solves the free problem from it). A free body resting on a plane has a singular
/// tangent until it touches the plane; held, it has none.
fn released(
    problem: &mut SymmetricProblem<'_>,
    q0: &nalgebra::DVector<f64>,
    lambda: &nalgebra::DVector<f64>,
    w: nalgebra::DVector<f64>,
    opts: &PathOptions,
) -> Result<nalgebra::DVector<f64>, SolveError> {
    if w.norm() == 0.0 {
        return Err(SolveError::Model(crate::model::ModelError::Global {
            effect: "start".into(),
            what: "start.hold-translation: the scene's group moves that direction, so the \
                   symmetric states cannot translate along it"
                .into(),
        }));
    }
    let zeta = w.dot(q0) / w.norm_squared();
    let mut held = HeldTranslation {
        inner: problem,
        lambda: lambda.clone(),
        w,
    };
    let start = nalgebra::DVector::from_vec(vec![zeta, 0.0]);
    let (q, l, _) = solve_at(&mut held, q0, &start, opts)?;
    let force = |l: &nalgebra::DVector<f64>| l[1];
    let scale = held.w.norm() * opts.state_scale;
    let mut point = point_at(&mut held, q, l, 0, opts, None)?;
    if force(&point.lambda) == 0.0 {
        return Ok(point.q);
    }
    // Move ζ the way that reduces |R|.
    if point.tangent[point.q.len() + 1] * force(&point.lambda) > 0.0 {
        point.tangent = -point.tangent;
    }
    let release_opts = PathOptions {
        bounds: (f64::NEG_INFINITY, f64::INFINITY),
        ..opts.clone()
    };
    let mut driver = Continuation::new(held, point, release_opts);
    for _ in 0..RELEASE_STEPS {
        let Ok(step) = driver.step() else { break };
        let (f0, f1) = (force(&step.from.lambda), force(&driver.point().lambda));
        if f0.signum() == f1.signum() {
            continue;
        }
        let s1 = driver.point().arclength - step.from.arclength;
        let from = step.from.clone();
        let tol = 1e-12 * (f0.abs().max(f1.abs())).max(scale * 1e-300);
        let (s, _) = locate(
            |s| driver.step_from(&from, s).ok().map(|p| force(&p.lambda)),
            f0,
            s1,
            f1,
            tol,
        )
        .ok_or(SolveError::SingularTangent)?;
        return driver
            .step_from(&from, s)
            .map(|p| p.q)
            .map_err(|_| SolveError::SingularTangent);
    }
    Err(SolveError::NotReleased {
        steps: RELEASE_STEPS,
        force: force(&driver.point().lambda),
    })
}

/// Steps the release of a held translation may take.
const RELEASE_STEPS: usize = 400;

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
