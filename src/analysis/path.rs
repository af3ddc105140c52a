//! The `path` analysis: the equilibrium path in the control from the start state, in the
//! fixed-point space of the scene's group, through turning points, with the index by irrep
//! at every point and every critical point where it changes localised and classified
//! (docs/theory.md §7, §8, §11).

use super::{Observer, Record, RunError, SymmetricProblem};
use crate::continuation::crossings::{Crossings, IndexChanges};
use crate::continuation::events::{Branch, Detector, Event};
use crate::continuation::{Continuation, PathPoint};
use crate::results::{RunTimes, StateKind, StopReason, TurningRow};
use crate::scene::Analysis;
use crate::study::{Measure, Study};
use crate::text::{num, sig_digits};
use std::time::Instant;

/// The path driver in the scene group's fixed-point space, started at the converged start
/// state (u_start, params_start) with the study's path options, and its step budget.
pub(super) fn start_driver<'a>(
    study: &'a Study,
    u_start: &[f64],
    params_start: &[f64],
) -> Result<(Continuation<SymmetricProblem<'a>>, usize), RunError> {
    let opts = super::equilibrium::path_options(study);
    let problem = SymmetricProblem::new(
        &study.model,
        &study.basis,
        &study.constraints,
        params_start.to_vec(),
        study.control,
    )
    .holding_neutral();
    let lambda0 = problem.free_values(params_start);
    let q_start = study.basis.restrict(u_start);
    let max_steps = opts.max_steps;
    let mut driver = Continuation::start(problem, &q_start, &lambda0, opts)
        .map_err(|e| RunError::start(study, e))?;
    // The start's tangent is taken with the neutral motions held; beyond it the path is free.
    driver.problem_mut().release_held();
    Ok((driver, max_steps))
}

/// Follows the path from the start state (u_start, params_start); returns why it stopped.
pub(super) fn run(
    study: &Study,
    record: &mut Record,
    crossings: Option<Crossings<'_>>,
    u_start: &[f64],
    params_start: &[f64],
    observer: &mut dyn Observer,
    times: &mut RunTimes,
) -> Result<StopReason, RunError> {
    let Analysis::Path(analysis) = &study.scene.analysis else {
        unreachable!("path::run runs path analyses")
    };
    let t0 = Instant::now();
    let (mut driver, max_steps) = start_driver(study, u_start, params_start)?;
    let stretch = study
        .measures
        .iter()
        .position(|(_, m)| *m == Measure::Stretch);
    let displacement = study
        .measures
        .iter()
        .position(|(_, m)| *m == Measure::MaxDisplacement);
    // A stop is reached where its measure passes the target from the start's side.
    let start_measures = study.measure(u_start, params_start);
    let side = |target: f64, k: usize| (target, k, (start_measures[k] - target).signum());
    let stop_stretch = analysis.stop_stretch.zip(stretch).map(|(t, k)| side(t, k));
    let stop_displacement = analysis
        .stop_displacement
        .zip(displacement)
        .map(|(t, k)| side(t, k));
    let stops = |problem: &SymmetricProblem, p: &PathPoint| {
        if stop_stretch.is_none() && stop_displacement.is_none() {
            return None;
        }
        let u = problem.displacement(&p.q);
        let now = study.measure(&u, &problem.parameters(&p.lambda));
        let passed = |stop: Option<(f64, usize, f64)>| {
            stop.and_then(|(target, k, side)| ((now[k] - target) * side <= 0.0).then_some(target))
        };
        passed(stop_stretch)
            .map(|target| StopReason::Stretch { target })
            .or_else(|| passed(stop_displacement).map(|target| StopReason::Displacement { target }))
    };
    let mut index = crossings.map(IndexChanges::new);
    let mut count = 0usize;
    let branch = {
        let mut extra: Vec<&mut dyn Detector<SymmetricProblem>> = Vec::new();
        if let Some(index) = index.as_mut() {
            extra.push(index);
        }
        crate::continuation::events::trace(
            &mut driver,
            max_steps,
            stops,
            &mut extra,
            |problem, p| {
                observer.progress(count, p.lambda[0]);
                observer.state(&problem.displacement(&p.q), &problem.parameters(&p.lambda));
                count += 1;
            },
        )
    };
    let mut problem = driver.into_problem();
    times.steps = branch.times;
    if let Some(w) = held_force_warning(study, &mut problem, &branch) {
        record.warnings.push(w);
    }
    let (indices, negatives) = match &index {
        Some(ix) => {
            times.index = ix.index_time;
            record.irreps.clone_from(&ix.irreps);
            (ix.indices.clone(), ix.negatives.clone())
        }
        None => (vec![None; branch.points.len()], Vec::new()),
    };
    record_branch(
        study,
        record,
        &problem,
        &branch,
        &indices,
        analysis.save_every,
    );
    let first = record.rows.len() - branch.points.len().min(record.rows.len());
    for (row, negative) in record.rows[first..].iter_mut().zip(negatives) {
        row.negative = negative;
    }
    if let (Some((target, k, _)), false) = (
        stop_stretch,
        matches!(branch.stop, StopReason::Stretch { .. }),
    ) {
        let (lo, hi) = record
            .rows
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), r| {
                (a.min(r.measures[k]), b.max(r.measures[k]))
            });
        record.warnings.push(format!(
            "analysis.stop-stretch = {} was not reached: the stretch ran over [{}, {}]",
            num(target),
            sig_digits(lo, 6),
            sig_digits(hi, 6)
        ));
    }
    times.path = t0.elapsed();
    Ok(branch.stop)
}

/// Largest force, relative to the residual's scale, that may hold the neutral motions at a
/// point of a path (docs/theory.md §7.9): at a free equilibrium it is zero, up to the solve.
pub const HELD_FORCE_TOLERANCE: f64 = 1e-6;

/// The largest force that holds the neutral motions along `branch` (docs/theory.md §7.9),
/// relative to the residual's scale, and the control where it is taken; `None` when the
/// fixed-point space holds none.
pub fn held_force(
    study: &Study,
    problem: &mut SymmetricProblem,
    branch: &Branch,
) -> Option<(f64, f64)> {
    let opts = super::equilibrium::path_options(study);
    let sigma = opts.parameter_scales.first().copied().unwrap_or(1.0);
    let mut worst: Option<(f64, f64)> = None;
    for p in &branch.points {
        let f = problem.held_force(&p.q, &p.lambda, opts.state_scale, sigma)?;
        let f = f.unwrap_or(f64::INFINITY);
        if worst.is_none_or(|(w, _)| f > w) {
            worst = Some((f, p.lambda[0]));
        }
    }
    worst
}

/// A warning when the neutral motions held along `branch` need a force above
/// [`HELD_FORCE_TOLERANCE`]: the path is then an equilibrium of the held body, not of the
/// free one.
fn held_force_warning(
    study: &Study,
    problem: &mut SymmetricProblem,
    branch: &Branch,
) -> Option<String> {
    let (force, at) = held_force(study, problem, branch)?;
    (force > HELD_FORCE_TOLERANCE).then(|| {
        format!(
            "the neutral motions held in the fixed-point space need a force of {} of the \
             residual's scale at {} = {}: the path is held there, not free",
            sig_digits(force, 3),
            study.parameters[study.control.unwrap_or(0)],
            sig_digits(at, 6)
        )
    })
}

/// Records a followed branch of `problem`: a row per point (with its index), every
/// `save_every`-th state and the last, the critical points after the rows they follow, the
/// warnings, and the turning points with their states.
pub(super) fn record_branch(
    study: &Study,
    record: &mut Record,
    problem: &SymmetricProblem,
    branch: &Branch,
    indices: &[Option<usize>],
    save_every: usize,
) {
    let save_every = save_every.max(1);
    let last = branch.points.len() - 1;
    let mut critical = branch
        .critical_points()
        .cloned()
        .collect::<Vec<_>>()
        .into_iter()
        .peekable();
    for (i, p) in branch.points.iter().enumerate() {
        let u = problem.displacement(&p.q);
        let params = problem.parameters(&p.lambda);
        if i % save_every == 0 || i == last {
            record.state(i, StateKind::Step, u.clone(), &params);
        }
        let index = indices.get(i).copied().flatten();
        record.row(study, i, p.arclength, &u, params, p.iterations, index);
        while let Some(cp) = critical.next_if(|cp| cp.after_step + 1 == i) {
            record.critical(cp);
        }
    }
    for event in &branch.events {
        if let Event::Warning(w) = event {
            record.warnings.push(w.clone());
        }
    }
    for t in branch.turning_points() {
        let u = problem.displacement(&t.point.q);
        let params = problem.parameters(&t.point.lambda);
        record.state(t.after_step, StateKind::Turning(t.kind), u.clone(), &params);
        record.turning.push(TurningRow {
            kind: t.kind,
            after_step: t.after_step,
            measures: study.measure(&u, &params),
            parameters: params,
        });
    }
}
