//! The `path` analysis: the equilibrium path in the control from the start state, in the
//! study's symmetric space, through turning points, with the index by block at every point and
//! every critical point where it changes localised and classified (docs/theory.md §7, §8,
//! §11); and, with `[analysis.branches]`, the branches that leave its bifurcation points
//! (docs/theory.md §14).

use super::equilibrium::path_options;
use super::{Analysis, Context, Record, RunError};
use crate::continuation::crossings::{Crossings, IndexChanges};
use crate::continuation::events::{trace, Branch, Detector, Event};
use crate::continuation::{Continuation, PathOptions, PathPoint, Settings};
use crate::results::{Bracket, StateKind, StopReason, TurningRow};
use crate::scene::AnalysisSpec as _;
use crate::scene::{BranchesAnalysis, PathAnalysis};
use crate::study::{BranchOptions, Followed, Free, Point, Study};
use crate::text::{num, sig_digits};
use std::time::Instant;

/// The path driver of `study`, started at the converged state `start` with `opts`, the
/// neutral motions held for the start's tangent and released beyond it.
pub(super) fn start_driver<'a>(
    study: &'a dyn Study,
    start: &Point,
    opts: PathOptions,
) -> Result<Continuation<Box<dyn Followed + 'a>>, RunError> {
    let problem = study.problem(&start.params, &Free::path(study.control().map(|c| c.index)));
    let lambda0 = problem.free_values(&start.params);
    let q_start = problem.coordinates(&start.u);
    let mut driver = Continuation::start(problem, &q_start, &lambda0, opts)
        .map_err(|e| RunError::start(study, e))?;
    // The start's tangent is taken with the neutral motions held; beyond it the path is free.
    driver.problem_mut().release_held();
    Ok(driver)
}

/// `type = "path"`.
pub struct Path(pub PathAnalysis);

impl Path {
    /// Its options on `study` (as its `options` of [`Analysis`]).
    pub fn options_of(&self, study: &dyn Study) -> PathOptions {
        self.options(study)
    }

    fn settings(&self) -> Settings {
        self.0.settings()
    }

    /// Its stops on a measure (`stop-stretch`, `stop-displacement`): the measure's index in
    /// the study's measures, the target and the stop reason there.
    pub fn limits(&self, study: &dyn Study) -> Vec<(usize, f64, StopReason)> {
        let measures = &study.about().measures;
        let at = |name: &str| measures.iter().position(|m| m == name);
        let stretch = self
            .0
            .stop_stretch
            .map(|target| (target, StopReason::Stretch { target }));
        let displacement = self
            .0
            .stop_displacement
            .map(|target| (target, StopReason::Displacement { target }));
        [
            (at("stretch"), stretch),
            (at("max_displacement"), displacement),
        ]
        .into_iter()
        .filter_map(|(k, stop)| k.zip(stop).map(|(k, (t, r))| (k, t, r)))
        .collect()
    }

    /// The branch options of `[analysis.branches]` (or `branches`, overriding it), with the
    /// path's continuation settings where the branches give none.
    pub fn branch_options(
        &self,
        study: &dyn Study,
        branches: Option<&BranchesAnalysis>,
    ) -> BranchOptions {
        branch_options(
            study,
            &self.options(study),
            branches.or(self.0.branches.as_ref()),
            self.0.settings.save_every,
        )
    }
}

/// The branch options of a path with `path` options: `branches`' depth, steps, largest step
/// and points (the defaults without them), each branch saving every `save_every`-th state.
pub fn branch_options(
    study: &dyn Study,
    path: &PathOptions,
    branches: Option<&BranchesAnalysis>,
    save_every: usize,
) -> BranchOptions {
    let _ = study;
    let default = BranchesAnalysis {
        depth: 1,
        steps: 40,
        max_step: None,
        points: None,
    };
    let b = branches.unwrap_or(&default);
    let max_step = b.max_step.unwrap_or(path.max_step);
    BranchOptions {
        depth: b.depth,
        steps: b.steps,
        points: b.points.clone(),
        path: PathOptions {
            max_step,
            initial_step: path.initial_step.min(max_step),
            min_step: path.min_step.min(max_step),
            max_steps: b.steps,
            ..path.clone()
        },
        save_every,
    }
}

impl Analysis for Path {
    fn options(&self, study: &dyn Study) -> PathOptions {
        path_options(study, &self.settings(), None)
    }

    /// Follows the path from the start state; returns why it stopped. With
    /// `[analysis.branches]`, then the branches of its critical points.
    fn run(&self, study: &dyn Study, cx: &mut Context<'_>) -> Result<StopReason, RunError> {
        let analysis = &self.0;
        let t0 = Instant::now();
        let opts = self.options(study);
        let max_steps = opts.max_steps;
        let mut driver = start_driver(study, &cx.start, opts)?;
        let limits = self.limits(study);
        let stops = measure_stops(study, &limits, &cx.start);
        let mut count = 0usize;
        let observer = &mut *cx.observer;
        let (branch, index) = trace_indexed(
            &mut driver,
            &mut cx.crossings,
            max_steps,
            stops,
            |problem, p| {
                observer.progress(count, p.lambda[0]);
                observer.state(&problem.displacement(&p.q), &problem.parameters(&p.lambda));
                count += 1;
            },
        );
        let mut problem = driver.into_problem();
        cx.times.steps = branch.times;
        if let Some(w) = held_force_warning(study, &self.options(study), &mut problem, &branch) {
            cx.record.warnings.push(w);
        }
        let record = &mut cx.record;
        let (indices, negatives) = match index {
            Some(ix) => {
                cx.times.index = ix.time;
                record.irreps = ix.irreps;
                (ix.indices, ix.negatives)
            }
            None => (vec![None; branch.points.len()], Vec::new()),
        };
        record_branch(
            study,
            record,
            &problem,
            &branch,
            &indices,
            analysis.settings.save_every,
        );
        let first = record.rows.len() - branch.points.len().min(record.rows.len());
        for (row, negative) in record.rows[first..].iter_mut().zip(negatives) {
            row.negative = negative;
        }
        let stretch = limits.iter().find_map(|(k, target, stop)| {
            matches!(stop, StopReason::Stretch { .. }).then_some((*target, *k))
        });
        if let (Some((target, k)), false) =
            (stretch, matches!(branch.stop, StopReason::Stretch { .. }))
        {
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
        cx.times.path = t0.elapsed();
        if analysis.branches.is_some() {
            let options = self.branch_options(study, None);
            let critical = cx.record.critical.clone();
            cx.record.branches = Some(
                study
                    .branches(&critical, options)
                    .map_err(RunError::Branches)?,
            );
        }
        Ok(branch.stop)
    }
}

/// The stops of a path on its measures ([`Path::limits`]): the first whose measure passes
/// its target from the side of the `start` state.
pub(super) fn measure_stops<'s>(
    study: &'s dyn Study,
    limits: &'s [(usize, f64, StopReason)],
    start: &Point,
) -> impl FnMut(&Box<dyn Followed + '_>, &PathPoint) -> Option<StopReason> + 's {
    let first = study.measure(&start.u, &start.params);
    // The driver's problem is boxed: the stop sees it as the driver holds it.
    #[allow(clippy::borrowed_box)]
    move |problem: &Box<dyn Followed + '_>, p: &PathPoint| {
        if limits.is_empty() {
            return None;
        }
        let u = problem.displacement(&p.q);
        let now = study.measure(&u, &problem.parameters(&p.lambda));
        limits.iter().find_map(|(k, target, stop)| {
            let side = (first[*k] - target).signum();
            ((now[*k] - target) * side <= 0.0).then(|| stop.clone())
        })
    }
}

/// The index by blocks along a branch traced by [`trace_indexed`].
pub(super) struct Indexed {
    /// The instability index at every point.
    pub indices: Vec<Option<usize>>,
    /// The negative count of every block at every point.
    pub negatives: Vec<Option<Vec<usize>>>,
    /// The blocks' irreps.
    pub irreps: Vec<String>,
    /// Time spent on the index.
    pub time: std::time::Duration,
}

/// Traces `driver` for at most `max_steps` steps with `stop` and `progress` ([`trace`]),
/// with the index by blocks at every point where `crossings` has them (taken for the
/// trace and handed back).
pub(super) fn trace_indexed<'a>(
    driver: &mut Continuation<Box<dyn Followed + 'a>>,
    crossings: &mut Option<Crossings<'_>>,
    max_steps: usize,
    stop: impl FnMut(&Box<dyn Followed + 'a>, &PathPoint) -> Option<StopReason>,
    progress: impl FnMut(&Box<dyn Followed + 'a>, &PathPoint),
) -> (Branch, Option<Indexed>) {
    let mut watch = crossings.take().map(IndexChanges::new);
    let branch = {
        let mut extra: Vec<&mut dyn Detector<Box<dyn Followed + 'a>>> = Vec::new();
        if let Some(w) = watch.as_mut() {
            extra.push(w);
        }
        trace(driver, max_steps, stop, &mut extra, progress)
    };
    let indexed = watch.as_ref().map(|w| Indexed {
        indices: w.indices.clone(),
        negatives: w.negatives.clone(),
        irreps: w.irreps.clone(),
        time: w.index_time,
    });
    *crossings = watch.map(IndexChanges::into_crossings);
    (branch, indexed)
}

/// Largest force, relative to the residual's scale, that may hold the neutral motions at a
/// point of a path (docs/theory.md §7.9): at a free equilibrium it is zero, up to the solve.
pub const HELD_FORCE_TOLERANCE: f64 = 1e-6;

/// The largest force that holds the neutral motions along `branch` (docs/theory.md §7.9),
/// relative to the residual's scale, and the control where it is taken; `None` when the
/// problem holds none.
pub fn held_force(
    opts: &PathOptions,
    problem: &mut dyn Followed,
    branch: &Branch,
) -> Option<(f64, f64)> {
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
    study: &dyn Study,
    opts: &PathOptions,
    problem: &mut dyn Followed,
    branch: &Branch,
) -> Option<String> {
    let (force, at) = held_force(opts, problem, branch)?;
    (force > HELD_FORCE_TOLERANCE).then(|| {
        format!(
            "the neutral motions held in the fixed-point space need a force of {} of the \
             residual's scale at {} = {}: the path is held there, not free",
            sig_digits(force, 3),
            study.about().parameters[study.control().map_or(0, |c| c.index)],
            sig_digits(at, 6)
        )
    })
}

/// Records a followed branch of `problem`: a row per point (with its index), every
/// `save_every`-th state and the last, the critical points after the rows they follow, the
/// warnings, and the turning points with their states.
pub(super) fn record_branch(
    study: &dyn Study,
    record: &mut Record,
    problem: &dyn Followed,
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
            record.add_critical(cp);
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
        let corner = t.corner.as_ref().map(|c| {
            let [a, b] = &c.sides;
            let state = |p: &PathPoint| (problem.displacement(&p.q), problem.parameters(&p.lambda));
            Bracket {
                width: c.width,
                ends: [state(a), state(b)],
            }
        });
        record.turning.push(TurningRow {
            kind: t.kind,
            after_step: t.after_step,
            measures: study.measure(&u, &params),
            parameters: params,
            corner,
        });
    }
}
