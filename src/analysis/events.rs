//! Events along a path, one mechanism for all (docs/theory.md §5.4, §7): at every accepted
//! step of a [`Continuation`] each [`Detector`] compares the new point with the previous one
//! and reports what happened in between — a turning point of a free parameter, a change of
//! the index of an irrep block (a critical point), a user's stop — localised between the two
//! points by the one routine [`locate`], on the arclength from the earlier point.
//!
//! [`follow`] runs a driver with a list of detectors until one of them stops it, the step
//! budget is used or the driver stalls.

use super::continuation::{Accepted, Continuation, PathPoint, Problem, Stalled};
use super::critical::{isotropy, CriticalKind, CriticalPoint};
use crate::model::constraint::Constraint;
use crate::model::{Evaluation, Model};
use crate::stability::{Detail, Spectrum, Stability};
use meshes::GroupAction;
use serde::Serialize;

/// Relative size below which a localised eigenvalue counts as zero.
const ZERO_EIGENVALUE: f64 = 1e-10;
/// The control's component of the unit tangent below which a turning point is localised.
const TURNING_TOLERANCE: f64 = 1e-12;

/// Finds s in (0, s1) where `g` changes sign, given g(0) = g0 and g(s1) = g1 of opposite signs,
/// by the Illinois variant of regula falsi. Stops when |g| ≤ `tol` or after 60 evaluations;
/// returns the best s and g(s) found, or `None` when an evaluation fails.
pub fn locate(
    mut g: impl FnMut(f64) -> Option<f64>,
    g0: f64,
    s1: f64,
    g1: f64,
    tol: f64,
) -> Option<(f64, f64)> {
    let (mut a, mut fa, mut b, mut fb) = (0.0, g0, s1, g1);
    let (mut best, mut fbest) = if fa.abs() < fb.abs() {
        (a, fa)
    } else {
        (b, fb)
    };
    let mut side = 0i8;
    for _ in 0..60 {
        if fbest.abs() <= tol || (b - a).abs() <= 1e-14 * s1.abs() {
            break;
        }
        let s = (a * fb - b * fa) / (fb - fa);
        let s = if s > a.min(b) && s < a.max(b) {
            s
        } else {
            0.5 * (a + b)
        };
        let fs = g(s)?;
        if fs.abs() < fbest.abs() {
            (best, fbest) = (s, fs);
        }
        if fs.signum() == fb.signum() {
            (b, fb) = (s, fs);
            if side == -1 {
                fa *= 0.5;
            }
            side = -1;
        } else {
            (a, fa) = (s, fs);
            if side == 1 {
                fb *= 0.5;
            }
            side = 1;
        }
    }
    Some((best, fbest))
}

/// A maximum or a minimum of a parameter along the path.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Extremum {
    /// The parameter was increasing before the point.
    Maximum,
    /// The parameter was decreasing before the point.
    Minimum,
}

impl std::fmt::Display for Extremum {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Maximum => "maximum",
            Self::Minimum => "minimum",
        })
    }
}

impl Serialize for Extremum {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

/// A turning point of a free parameter, localised where its tangent component vanishes.
#[derive(Debug, Clone)]
pub struct TurningPoint {
    /// The free parameter (0: the control).
    pub parameter: usize,
    /// Maximum or minimum.
    pub kind: Extremum,
    /// The localised point.
    pub point: PathPoint,
    /// The index of the accepted point just before it.
    pub after_step: usize,
}

/// Why a path ended.
#[derive(Debug, Clone, PartialEq)]
pub enum StopReason {
    /// The control left its `[min, max]` range; the last point is the first beyond it.
    Bounds,
    /// The budget of accepted steps was used.
    StepBudget {
        /// The budget.
        steps: usize,
    },
    /// A closed membrane's stretch reached the scene's `stop-stretch`.
    Stretch {
        /// The target.
        target: f64,
    },
    /// The largest displacement reached the scene's `stop-displacement`.
    Displacement {
        /// The target.
        target: f64,
    },
    /// A caller's stop condition held.
    Condition,
    /// The step was cut below the minimum.
    Stalled(Stalled),
    /// A single equilibrium was solved.
    Equilibrium,
    /// A held state's control swept its range.
    Swept {
        /// Lower end.
        min: f64,
        /// Upper end.
        max: f64,
        /// Number of steps.
        samples: usize,
    },
    /// A sweep without a control parameter.
    NoControl,
}

impl std::fmt::Display for StopReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Bounds => f.write_str(
                "the control parameter left its [min, max] range (the last point is the first beyond it)",
            ),
            Self::StepBudget { steps } => write!(f, "the step budget ({steps}) was used"),
            Self::Stretch { target } => write!(f, "the stretch reached {target}"),
            Self::Displacement { target } => write!(f, "the largest displacement reached {target}"),
            Self::Condition => f.write_str("the stop condition held"),
            Self::Stalled(s) => write!(f, "{s}"),
            Self::Equilibrium => f.write_str("equilibrium found"),
            Self::Swept { min, max, samples } => {
                write!(f, "the control swept [{min}, {max}] in {samples} steps")
            }
            Self::NoControl => f.write_str("no control parameter"),
        }
    }
}

impl Serialize for StopReason {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

/// Something a detector found between two accepted points (or at the start).
#[derive(Debug, Clone)]
pub enum Event {
    /// A turning point of a free parameter.
    Turning(TurningPoint),
    /// A localised and classified critical point.
    Critical(CriticalPoint),
    /// The path must end here.
    Stop(StopReason),
    /// Something the analysis could not settle (a crossing that could not be localised …).
    Warning(String),
}

/// What watches a path: called at its first point and after every accepted step.
pub trait Detector<P: Problem> {
    /// Called once at the first point (`driver.point()`).
    fn start(&mut self, _driver: &mut Continuation<P>) -> Vec<Event> {
        Vec::new()
    }

    /// Called after every accepted step: `driver.point()` is the new point, `step` says where
    /// it came from and with which arclength, `after` is the index of the earlier point.
    fn check(&mut self, driver: &mut Continuation<P>, step: &Accepted, after: usize) -> Vec<Event>;
}

/// A followed path: its points, what the detectors found, and why it ended.
#[derive(Debug, Clone)]
pub struct Branch {
    /// Accepted points, the first one first.
    pub points: Vec<PathPoint>,
    /// Events in the order they were found.
    pub events: Vec<Event>,
    /// Why the path ended.
    pub stop: StopReason,
    /// Where [`follow`]'s time went.
    pub times: BranchTimes,
}

/// Where [`follow`]'s time went.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BranchTimes {
    /// The driver's steps (predictor–corrector, step control), wall time.
    pub steps: std::time::Duration,
    /// Of `steps`: the problem's evaluations.
    pub steps_problem: super::continuation::PhaseTimes,
    /// The detectors (localisation included), wall time.
    pub events: std::time::Duration,
    /// The caller's `progress`, wall time.
    pub progress: std::time::Duration,
}

impl Branch {
    /// The turning points found.
    pub fn turning_points(&self) -> impl Iterator<Item = &TurningPoint> {
        self.events.iter().filter_map(|e| match e {
            Event::Turning(t) => Some(t),
            _ => None,
        })
    }

    /// The critical points found.
    pub fn critical_points(&self) -> impl Iterator<Item = &CriticalPoint> {
        self.events.iter().filter_map(|e| match e {
            Event::Critical(c) => Some(c),
            _ => None,
        })
    }
}

/// Follows the driver's path from its current point for at most `max_steps` accepted steps,
/// running every detector at the first point and after every step, until a detector stops
/// it, the budget is used or the driver stalls. `progress` sees every accepted point.
pub fn follow<P: Problem>(
    driver: &mut Continuation<P>,
    detectors: &mut [&mut dyn Detector<P>],
    max_steps: usize,
    mut progress: impl FnMut(&P, &PathPoint),
) -> Branch {
    use std::time::Instant;
    let mut branch = Branch {
        points: vec![driver.point().clone()],
        events: Vec::new(),
        stop: StopReason::StepBudget { steps: max_steps },
        times: BranchTimes::default(),
    };
    let t = Instant::now();
    progress(driver.problem(), driver.point());
    branch.times.progress += t.elapsed();
    let t = Instant::now();
    for d in detectors.iter_mut() {
        branch.events.extend(d.start(driver));
    }
    branch.times.events += t.elapsed();
    while branch.points.len() <= max_steps {
        let (t, before) = (Instant::now(), driver.problem().phase_times());
        let step = driver.step();
        branch.times.steps += t.elapsed();
        branch.times.steps_problem += driver.problem().phase_times() - before;
        let step = match step {
            Ok(step) => step,
            Err(stalled) => {
                branch.stop = StopReason::Stalled(stalled);
                return branch;
            }
        };
        let after = branch.points.len() - 1;
        let mut stop = None;
        let t = Instant::now();
        for d in detectors.iter_mut() {
            for event in d.check(driver, &step, after) {
                match event {
                    Event::Stop(reason) => {
                        stop.get_or_insert(reason);
                    }
                    other => branch.events.push(other),
                }
            }
        }
        branch.times.events += t.elapsed();
        let t = Instant::now();
        progress(driver.problem(), driver.point());
        branch.times.progress += t.elapsed();
        branch.points.push(driver.point().clone());
        if let Some(reason) = stop {
            branch.stop = reason;
            return branch;
        }
    }
    branch
}

/// Turning points of the free parameters `parameters` (0 is the control): a sign change of
/// the parameter's tangent component, localised where it vanishes.
pub struct TurningPoints {
    parameters: Vec<usize>,
}

impl TurningPoints {
    /// Turning points of the control.
    pub fn of_control() -> Self {
        Self {
            parameters: vec![0],
        }
    }

    /// Turning points of the given free parameters.
    pub fn of(parameters: Vec<usize>) -> Self {
        Self { parameters }
    }
}

impl<P: Problem> Detector<P> for TurningPoints {
    fn check(&mut self, driver: &mut Continuation<P>, step: &Accepted, after: usize) -> Vec<Event> {
        let m = driver.problem().dim();
        let mut found = Vec::new();
        for &j in &self.parameters {
            let (t0, t1) = (step.from.tangent[m + j], driver.point().tangent[m + j]);
            if t1.signum() == t0.signum() || t0 == 0.0 {
                continue;
            }
            let kind = if t0 > 0.0 {
                Extremum::Maximum
            } else {
                Extremum::Minimum
            };
            if let Some(point) = localise_turning(driver, &step.from, step.step, m + j, t1) {
                found.push(Event::Turning(TurningPoint {
                    parameter: j,
                    kind,
                    point,
                    after_step: after,
                }));
            }
        }
        found
    }
}

/// Localises the turning point between `from` (tangent component `k` of one sign) and the
/// point reached with step `s_hi` (component `t_hi` of the other) where the component
/// vanishes, by [`locate`] on the step length.
fn localise_turning<P: Problem>(
    driver: &mut Continuation<P>,
    from: &PathPoint,
    s_hi: f64,
    k: usize,
    t_hi: f64,
) -> Option<PathPoint> {
    let (s, _) = locate(
        |s| driver.step_from(from, s).ok().map(|p| p.tangent[k]),
        from.tangent[k],
        s_hi,
        t_hi,
        TURNING_TOLERANCE,
    )?;
    driver.step_from(from, s).ok()
}

/// Stops the path where `test` says so (checked at every accepted point, not localised).
pub struct StopWhen<F>(pub F);

impl<P: Problem, F: FnMut(&P, &PathPoint) -> Option<StopReason>> Detector<P> for StopWhen<F> {
    fn check(&mut self, driver: &mut Continuation<P>, _: &Accepted, _: usize) -> Vec<Event> {
        (self.0)(driver.problem(), driver.point())
            .map(Event::Stop)
            .into_iter()
            .collect()
    }
}

/// A problem whose points are states of a model: the displacement over the model's
/// unknowns and every parameter, for the stability analysis.
pub trait States {
    /// The displacement u at q.
    fn displacement(&self, q: &nalgebra::DVector<f64>) -> Vec<f64>;
    /// Every parameter, with the free ones at `lambda`.
    fn parameters(&self, lambda: &nalgebra::DVector<f64>) -> Vec<f64>;
}

/// The measures of a state (u, every parameter), in the report's order.
pub type MeasureFn<'a> = &'a (dyn Fn(&[f64], &[f64]) -> Vec<f64> + Sync);

/// Index changes of the irrep blocks, localised and classified: the stability analysis of
/// states of one model under one group (docs/theory.md §6–§8).
pub struct Crossings<'a> {
    stability: Stability<'a>,
    constraints: &'a [Box<dyn Constraint>],
    action: &'a GroupAction,
    model: &'a dyn Model,
    measure: MeasureFn<'a>,
    control: Option<usize>,
    held: bool,
    /// The model's evaluation buffer, reused by every spectrum (the tangent of a large mesh
    /// is megabytes; a fresh buffer per point would allocate it every time).
    eval: Evaluation,
    /// The evaluation around the orbit representatives, for the index at every point.
    local: Evaluation,
}

impl<'a> Crossings<'a> {
    /// The analysis of states of `model` (with `constraints` active, parameter `control`
    /// the one a path follows) by `stability`; critical points get the measures of
    /// `measure(u, params)` and the isotropy of their mode under `action`; `held` states
    /// (linear buckling) name a singular trivial block a symmetric bifurcation.
    pub fn new(
        stability: Stability<'a>,
        model: &'a dyn Model,
        constraints: &'a [Box<dyn Constraint>],
        action: &'a GroupAction,
        measure: MeasureFn<'a>,
        control: Option<usize>,
        held: bool,
    ) -> Self {
        Self {
            eval: model.new_evaluation(),
            local: stability.new_evaluation(),
            stability,
            constraints,
            action,
            model,
            measure,
            control,
            held,
        }
    }

    /// The stability analysis.
    pub fn stability(&self) -> &Stability<'a> {
        &self.stability
    }

    /// The negative count of every block only (sparse inertia, assembly around the orbit
    /// representatives): what every path point needs to detect a change of stability.
    pub fn index(&mut self, u: &[f64], params: &[f64]) -> Option<Spectrum> {
        self.stability
            .analyse(
                u,
                params,
                self.constraints,
                &mut self.local,
                None,
                Detail::Inertia,
            )
            .ok()
    }

    /// Every block's eigenvalues (up to the dense limit) and negative count.
    pub fn spectrum(&mut self, u: &[f64], params: &[f64]) -> Option<Spectrum> {
        self.stability
            .spectrum_of(u, params, self.constraints, &mut self.eval, None, false)
            .ok()
    }

    /// Localises every eigenvalue of every block whose negative count differs between `a`
    /// and `b` (spectra with eigenvalues), with `state(s)` giving (u, params) for
    /// s ∈ [0, s1] (s = 0 at a, s1 at b); the critical points sorted by the control, and the
    /// crossings that could not be localised as warnings. `control_turns` says whether the
    /// control turns between `a` and `b`: a zero of the trivial block is a limit point only
    /// there (docs/theory.md §11.3); elsewhere, and on a held state, it is a symmetric
    /// bifurcation.
    pub fn localise(
        &mut self,
        a: &Spectrum,
        b: &Spectrum,
        after_step: usize,
        s1: f64,
        control_turns: bool,
        mut state: impl FnMut(f64) -> Option<(Vec<f64>, Vec<f64>)>,
    ) -> Vec<Event> {
        let stab = &self.stability;
        let eval = &mut self.eval;
        let constraints = self.constraints;
        let mut found = Vec::new();
        let mut warnings = Vec::new();
        for mu in 0..a.blocks.len() {
            let (n0, n1) = (a.blocks[mu].negative, b.blocks[mu].negative);
            if n0 == n1 {
                continue;
            }
            let ends = [&a.blocks[mu].eigenvalues, &b.blocks[mu].eigenvalues];
            if ends[0].is_empty() || ends[1].is_empty() {
                warnings.push(format!(
                    "the index of {} changed between steps {after_step} and {} (by {}); its block has {} columns, more than the {} whose eigenvalues are computed, so the crossing was not localised",
                    a.blocks[mu].irrep,
                    after_step + 1,
                    n1 as i64 - n0 as i64,
                    a.blocks[mu].size,
                    crate::stability::DENSE_BLOCK_LIMIT
                ));
                continue;
            }
            for k in n0.min(n1)..n0.max(n1) {
                let g0 = ends[0].get(k).copied().unwrap_or(0.0);
                let g1 = ends[1].get(k).copied().unwrap_or(0.0);
                let tol = ZERO_EIGENVALUE * a.scale;
                let located = locate(
                    |s| {
                        let (u, p) = state(s)?;
                        let sp = stab
                            .spectrum_of(&u, &p, constraints, eval, Some(mu), false)
                            .ok()?;
                        sp.blocks[mu].eigenvalues.get(k).copied()
                    },
                    g0,
                    s1,
                    g1,
                    tol,
                );
                let not_localised = |why: &str| {
                    format!(
                        "the index of {} changed between steps {after_step} and {} but the crossing could not be localised ({why})",
                        a.blocks[mu].irrep,
                        after_step + 1
                    )
                };
                let Some((s_best, g_best)) = located else {
                    warnings.push(not_localised(
                        "a state inside the interval did not converge",
                    ));
                    continue;
                };
                // Re-evaluate at the best point, with the eigenvectors for the critical mode.
                let evaluated = state(s_best).and_then(|(u, p)| {
                    let sp = stab
                        .spectrum_of(&u, &p, constraints, eval, Some(mu), true)
                        .ok()?;
                    Some((u, p, sp))
                });
                let Some((u, p, sp)) = evaluated else {
                    warnings.push(not_localised("the best point could not be evaluated"));
                    continue;
                };
                let block = &sp.blocks[mu];
                if block.vectors.ncols() == 0 {
                    warnings.push(not_localised("no eigenvector at the best point"));
                    continue;
                }
                let ib = &stab.basis().irreps[mu];
                let v = block
                    .vectors
                    .column(k.min(block.vectors.ncols().saturating_sub(1)));
                let mut mode = vec![0.0; ib.first().unknowns()];
                ib.first().expand(&v.into_owned(), &mut mode);
                let norm = mode.iter().map(|x| x * x).sum::<f64>().sqrt().max(1e-300);
                mode.iter_mut().for_each(|x| *x /= norm);
                found.push(CriticalPoint {
                    kind: CriticalKind::of(mu == 0, ib.dim, self.held || !control_turns),
                    irrep: ib.name.clone(),
                    multiplicity: ib.dim,
                    measures: (self.measure)(&u, &p),
                    parameters: p,
                    after_step,
                    residual_eigenvalue: g_best.abs() / sp.scale,
                    isotropy: isotropy(self.action, self.model.layout(), &mode),
                    mode,
                    state: u,
                });
            }
        }
        let control = |p: &CriticalPoint| self.control.map_or(0.0, |c| p.parameters[c]);
        found.sort_by(|x, y| control(x).total_cmp(&control(y)));
        warnings
            .into_iter()
            .map(Event::Warning)
            .chain(found.into_iter().map(Event::Critical))
            .collect()
    }
}

/// The index of every block at every point, and the critical points where it changes: the
/// [`Crossings`] of a path's states.
pub struct IndexChanges<'a> {
    crossings: Crossings<'a>,
    /// The previous point's index spectrum and state.
    previous: Option<(Spectrum, Vec<f64>, Vec<f64>)>,
    /// The instability index at every point so far (`None` where it could not be computed).
    pub indices: Vec<Option<usize>>,
    /// Time spent on the index at every point (eigenvalues and localisation excepted).
    pub index_time: std::time::Duration,
}

impl<'a> IndexChanges<'a> {
    /// Watches the index with `crossings`.
    pub fn new(crossings: Crossings<'a>) -> Self {
        Self {
            crossings,
            previous: None,
            indices: Vec::new(),
            index_time: Default::default(),
        }
    }

    /// The index at `point`, remembered with its state as the previous point's; returns
    /// the earlier previous point.
    fn observe<P: Problem + States>(
        &mut self,
        problem: &P,
        point: &PathPoint,
    ) -> Option<(Spectrum, Vec<f64>, Vec<f64>)> {
        let t = std::time::Instant::now();
        let u = problem.displacement(&point.q);
        let params = problem.parameters(&point.lambda);
        let spectrum = self.crossings.index(&u, &params);
        self.indices.push(spectrum.as_ref().map(|s| s.index));
        self.index_time += t.elapsed();
        std::mem::replace(&mut self.previous, spectrum.map(|s| (s, u, params)))
    }
}

impl<P: Problem + States> Detector<P> for IndexChanges<'_> {
    fn start(&mut self, driver: &mut Continuation<P>) -> Vec<Event> {
        let point = driver.point().clone();
        self.observe(driver.problem(), &point);
        Vec::new()
    }

    fn check(&mut self, driver: &mut Continuation<P>, step: &Accepted, after: usize) -> Vec<Event> {
        let point = driver.point().clone();
        let previous = self.observe(driver.problem(), &point);
        let (Some((a, u0, p0)), Some((b, u1, p1))) = (&previous, &self.previous) else {
            return Vec::new();
        };
        if a.negatives() == b.negatives() {
            return Vec::new();
        }
        // The index changed: now the eigenvalues at both points.
        let ends = (
            self.crossings.spectrum(u0, p0),
            self.crossings.spectrum(u1, p1),
        );
        let (Some(a), Some(b)) = ends else {
            return Vec::new();
        };
        let s1 = point.arclength - step.from.arclength;
        let m = driver.problem().dim();
        let turns = step.from.tangent[m].signum() != point.tangent[m].signum();
        self.crossings.localise(&a, &b, after, s1, turns, |s| {
            let q = driver.corrected_from(&step.from, s).ok()?;
            let problem = driver.problem();
            Some((problem.displacement(&q.q), problem.parameters(&q.lambda)))
        })
    }
}
