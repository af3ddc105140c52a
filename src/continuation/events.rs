//! Events along a path, one mechanism for all (docs/theory.md §7.6, §11.1–§11.2): at every
//! accepted step of a [`Continuation`] each [`Detector`] compares the new point with the
//! previous one and reports what happened in between — a turning point of a free parameter, a
//! change of the index of a block (a critical point, [`super::crossings`]), a user's stop —
//! localised between the two points by the one routine [`locate`], on the arclength from the
//! earlier point.
//!
//! [`follow`] runs a driver with a list of detectors until one of them stops it, the step
//! budget is used or the driver stalls; [`trace`] is a path in the control with the usual
//! stops.

use super::driver::{Accepted, Continuation, PathPoint, Problem, SignChange};
use crate::results::{BranchTimes, CriticalPoint, Extremum, StopReason};

/// The factor a rejected step is shortened by before it is tried again.
pub const REJECTED_STEP_FACTOR: f64 = 0.25;
/// The control's component of the unit tangent below which a turning point is localised.
const TURNING_TOLERANCE: f64 = 1e-12;
/// Trials in a row without a smaller tangent component after which a turning point's search
/// by whole steps stops at its best point ([`localise_turning`]).
const TURNING_PATIENCE: usize = 4;
/// The width, as a share of the step, to which a corner of the path is bisected: that of a
/// contact jump's bracket ([`super::crossings`]).
const CORNER_WIDTH: f64 = 1e-10;
/// How far off a corner, as a share of the step, the direction of the parameter on either
/// side of it is taken: far above [`CORNER_WIDTH`], far below a step.
const CORNER_SIDE: f64 = 1e-6;

/// Finds s in (0, s1) where `g` changes sign, given g(0) = g0 and g(s1) = g1 of opposite signs,
/// by the Illinois variant of regula falsi. Stops when |g| ≤ `tol` or after 60 evaluations;
/// returns the best s and g(s) found. Where an evaluation fails (a state that does not
/// converge, as right at a singular point of the path), the trial point is moved halfway
/// towards the best point so far, up to 8 times; `None` only when no trial point inside the
/// bracket could be evaluated.
pub fn locate(
    g: impl FnMut(f64) -> Option<f64>,
    g0: f64,
    s1: f64,
    g1: f64,
    tol: f64,
) -> Option<(f64, f64)> {
    locate_within(g, g0, s1, g1, tol, 1e-14)
}

/// As [`locate`], stopping also when the bracket is narrower than `width` · |s1| (a jump of
/// `g` rather than a zero then shows as a bracket that shrinks while |g| does not).
pub fn locate_within(
    g: impl FnMut(f64) -> Option<f64>,
    g0: f64,
    s1: f64,
    g1: f64,
    tol: f64,
    width: f64,
) -> Option<(f64, f64)> {
    locate_to_noise(g, g0, s1, g1, tol, width, usize::MAX)
}

/// As [`locate_within`], stopping also after `patience` trials in a row that do not improve
/// the best |g| once a trial inside the bracket has been the best: `g` is then at its noise
/// (regula falsi on a smooth zero improves at every trial), and narrowing the bracket
/// further moves the best point only within that noise. The best point returned is then a
/// trial, never an end of the bracket.
fn locate_to_noise(
    mut g: impl FnMut(f64) -> Option<f64>,
    g0: f64,
    s1: f64,
    g1: f64,
    tol: f64,
    width: f64,
    patience: usize,
) -> Option<(f64, f64)> {
    let (mut stale, mut inside) = (0, false);
    let (mut a, mut fa, mut b, mut fb) = (0.0, g0, s1, g1);
    let (mut best, mut fbest) = if fa.abs() < fb.abs() {
        (a, fa)
    } else {
        (b, fb)
    };
    let mut side = 0i8;
    // Every earlier iteration evaluated a trial point.
    for evaluated in 0..60 {
        if fbest.abs() <= tol || (b - a).abs() <= width * s1.abs() || stale >= patience {
            break;
        }
        let s = (a * fb - b * fa) / (fb - fa);
        let mut s = if s > a.min(b) && s < a.max(b) {
            s
        } else {
            0.5 * (a + b)
        };
        let mut fs = g(s);
        for _ in 0..8 {
            if fs.is_some() {
                break;
            }
            s = 0.5 * (s + best);
            fs = g(s);
        }
        let Some(fs) = fs else {
            return (evaluated > 0 || fbest.abs() <= tol).then_some((best, fbest));
        };
        if fs.abs() < fbest.abs() {
            (best, fbest) = (s, fs);
            stale = 0;
            inside = true;
        } else if inside {
            stale += 1;
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
    /// Where the path turns at a corner (a change of the model's switches) rather than
    /// through a zero of the tangent's component: the two states either side of the switch.
    pub corner: Option<Corner>,
}

/// The bracket of a corner of the path (docs/theory.md §8.9): the nearest states found on
/// either side of the change of the model's switches, the earlier one first.
#[derive(Debug, Clone)]
pub struct Corner {
    /// The bracket's width, as a share of the step.
    pub width: f64,
    /// The states on either side, the earlier first.
    pub sides: [PathPoint; 2],
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

/// A detector's verdict on a step before the step is accepted ([`Detector::admit`]).
#[derive(Debug, Clone, PartialEq)]
pub enum Admission {
    /// The step stays on the path.
    Accept,
    /// The step left the connected path: retry from the earlier point with a shorter step.
    Reject,
}

/// What watches a path: called at its first point and after every accepted step.
pub trait Detector<P: Problem> {
    /// Called once at the first point (`driver.point()`).
    fn start(&mut self, _driver: &mut Continuation<P>) -> Vec<Event> {
        Vec::new()
    }

    /// Called after every step of the driver, before any detector checks it: `driver.point()`
    /// is the new point. A detector that sees the step leave the connected path (as over a
    /// nearly symmetric bifurcation that the mesh breaks, docs/theory.md §7.5.2) rejects it;
    /// [`follow`] then retries from `step.from` with a quarter of the step, and no detector
    /// sees the rejected point. A detector must accept once the step is short enough for
    /// what it tests, so that the path goes on.
    fn admit(&mut self, _driver: &mut Continuation<P>, _step: &Accepted) -> Admission {
        Admission::Accept
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
                // Every step across an end of the range failed: the path ends at it.
                branch.stop = match stalled.bound {
                    Some(bound) => StopReason::AtBound {
                        bound,
                        control: stalled.control,
                    },
                    None => StopReason::Stalled(stalled.into()),
                };
                return branch;
            }
        };
        let t = Instant::now();
        let rejected = detectors
            .iter_mut()
            .any(|d| d.admit(driver, &step) != Admission::Accept);
        branch.times.events += t.elapsed();
        if rejected {
            driver.retreat(step, REJECTED_STEP_FACTOR);
            continue;
        }
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
            let corner = locate_corner(driver, &step.from, step.step, m + j);
            if let Some(corner) = corner {
                // The extreme value of the parameter actually reached: the side of the switch
                // farther in the direction the parameter had before it turned.
                let [a, b] = &corner.sides;
                let beyond = (b.lambda[j] - a.lambda[j]) * t0 > 0.0;
                let point = if beyond { b.clone() } else { a.clone() };
                found.push(Event::Turning(TurningPoint {
                    parameter: j,
                    kind,
                    point,
                    after_step: after,
                    corner: Some(corner),
                }));
            } else if let Some(point) = localise_turning(driver, &step.from, step.step, m + j, t1) {
                found.push(Event::Turning(TurningPoint {
                    parameter: j,
                    kind,
                    point,
                    after_step: after,
                    corner: None,
                }));
            }
        }
        found
    }
}

/// The corner of a step over which component `k` of the tangent changes sign, if it turns at
/// one (docs/theory.md §8.9): where the model's switches differ between `from` and the
/// driver's point (a node enters or leaves contact, the tangent jumps), the first change of
/// the switches is bisected on the step length to [`CORNER_WIDTH`] of the step, each trial a
/// step from `from`; the step turns at that corner when the component has the sign of
/// `from`'s on its earlier side and the other sign on its later side. `None` for a step whose
/// switches do not change (a smooth problem always), whose component changes sign elsewhere,
/// or whose trial states could not be found: the turning point is then a zero of the
/// component ([`localise_turning`]).
fn locate_corner<P: Problem>(
    driver: &mut Continuation<P>,
    from: &PathPoint,
    s_hi: f64,
    k: usize,
) -> Option<Corner> {
    let to = driver.point().clone();
    let switched = |driver: &Continuation<P>, p: &PathPoint| {
        driver
            .problem()
            .switched((&from.q, &from.lambda), (&p.q, &p.lambda))
    };
    if switched(driver, &to)? == 0 {
        return None;
    }
    let (mut lo, mut hi) = ((0.0, from.clone()), (s_hi, to));
    while hi.0 - lo.0 > CORNER_WIDTH * s_hi {
        let s = 0.5 * (lo.0 + hi.0);
        let trial = driver.step_from(from, s).ok()?;
        if switched(driver, &trial)? > 0 {
            hi = (s, trial);
        } else {
            lo = (s, trial);
        }
    }
    // The direction of the parameter on either side, from states a little off the corner
    // (the tangent at a state next to it may be that of the other piece): it keeps the sign
    // of `from`'s before and has the other after.
    let j = k - driver.problem().dim();
    let off = CORNER_SIDE * s_hi;
    let before = driver.step_from(from, lo.0 - off).ok()?;
    let after = driver.step_from(from, hi.0 + off).ok()?;
    let sign = from.tangent[k].signum();
    let turns = (lo.1.lambda[j] - before.lambda[j]).signum() == sign
        && (after.lambda[j] - hi.1.lambda[j]).signum() == -sign;
    turns.then(|| Corner {
        width: (hi.0 - lo.0) / s_hi,
        sides: [lo.1, hi.1],
    })
}

/// Localises the turning point between `from` (tangent component `k` of one sign) and the
/// point reached with step `s_hi` (component `t_hi` of the other) where the component
/// vanishes: by Newton on the path's equations and the component together
/// ([`zero_on_step`](super::driver::zero_on_step), the tangent of every iterate from its own
/// factorisation), else by [`locate`] on the step length, each trial a step.
fn localise_turning<P: Problem>(
    driver: &mut Continuation<P>,
    from: &PathPoint,
    s_hi: f64,
    k: usize,
    t_hi: f64,
) -> Option<PathPoint> {
    let change = SignChange {
        first: (0.0, from.tangent[k]),
        second: (s_hi, t_hi),
        tolerance: TURNING_TOLERANCE,
        width: 1e-14 * s_hi.abs(),
    };
    if let Some(zero) = driver.zero_on_step(from, change, &mut |_, _, _, tangent| Some(tangent[k]))
    {
        return Some(zero.point);
    }
    // Each trial is a whole step. Where the path is resolved only to the corrector's
    // tolerance (a branch along a nearly neutral direction, whose control wanders by 10⁻⁷)
    // the component is noise long before TURNING_TOLERANCE, and the bracket would be halved
    // to 10⁻¹⁴ of the step: the search stops once trials stop improving it.
    let (s, _) = locate_to_noise(
        |s| driver.step_from(from, s).ok().map(|p| p.tangent[k]),
        from.tangent[k],
        s_hi,
        t_hi,
        TURNING_TOLERANCE,
        1e-14,
        TURNING_PATIENCE,
    )?;
    driver.step_from(from, s).ok()
}

/// The path of any problem in its control from the driver's point: turning points of the
/// control, the `extra` detectors, and the stops — the control leaving the driver's bounds
/// (the last point is the first beyond them), `stop`, or `max_steps` accepted steps.
pub fn trace<P: Problem>(
    driver: &mut Continuation<P>,
    max_steps: usize,
    mut stop: impl FnMut(&P, &PathPoint) -> Option<StopReason>,
    extra: &mut [&mut (dyn Detector<P> + '_)],
    progress: impl FnMut(&P, &PathPoint),
) -> Branch {
    let bounds = driver.options().bounds;
    let mut stops = StopWhen(move |problem: &P, p: &PathPoint| {
        if super::interrupt::requested() {
            return Some(StopReason::Interrupted);
        }
        if p.lambda[0] < bounds.0 || p.lambda[0] > bounds.1 {
            return Some(StopReason::Bounds);
        }
        stop(problem, p)
    });
    let mut turning = TurningPoints::of_control();
    let mut detectors: Vec<&mut dyn Detector<P>> = vec![&mut turning];
    detectors.extend(extra.iter_mut().map(|d| &mut **d as &mut dyn Detector<P>));
    detectors.push(&mut stops);
    follow(driver, &mut detectors, max_steps, progress)
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

impl<S: States + ?Sized> States for Box<S> {
    fn displacement(&self, q: &nalgebra::DVector<f64>) -> Vec<f64> {
        (**self).displacement(q)
    }
    fn parameters(&self, lambda: &nalgebra::DVector<f64>) -> Vec<f64> {
        (**self).parameters(lambda)
    }
}

/// The measures of a state (u, every parameter), in the report's order.
pub type MeasureFn<'a> = &'a (dyn Fn(&[f64], &[f64]) -> Vec<f64> + Sync);

#[cfg(test)]
mod tests {
    use super::{locate_to_noise, locate_within, trace};
    use crate::continuation::driver::{Continuation, PathOptions, Problem};
    use crate::model::ModelError;
    use crate::results::StopReason;
    use nalgebra::DVector;

    /// R(q, λ) = q − λ, which the model cannot evaluate for λ < 0 (a material constant
    /// below its range), or nowhere below `floor` when one is given.
    fn half_line(floor: f64) -> impl Problem {
        crate::continuation::driver::Scalar(move |q: f64, l: f64| {
            if l < floor {
                return Err(ModelError::Global {
                    effect: "line".into(),
                    what: format!("λ = {l} is out of its range"),
                });
            }
            Ok((q - l, 1.0, -1.0))
        })
    }

    /// A path run into an end of its range where the model cannot be evaluated ends there,
    /// within the minimum step, as reaching that end, not as a stall; a model that fails
    /// inside the range still stalls.
    #[test]
    fn a_path_that_cannot_step_past_the_end_of_its_range_ends_at_it() {
        let follow_down = |floor: f64| {
            let opts = PathOptions {
                bounds: (0.0, 10.0),
                direction: -1.0,
                max_step: 0.1,
                ..PathOptions::default()
            };
            let one = DVector::from_element(1, 1.0);
            let mut driver = Continuation::start(half_line(floor), &one, &one, opts).unwrap();
            trace(&mut driver, 100, |_, _| None, &mut [], |_, _| {})
        };
        let at_end = follow_down(0.0);
        let last = at_end.points.last().unwrap().lambda[0];
        match at_end.stop {
            StopReason::AtBound { bound, control } => {
                assert_eq!(bound, 0.0);
                assert_eq!(control, last);
                assert!((0.0..1e-6).contains(&last), "{last}");
            }
            other => panic!("{other}"),
        }
        let inside = follow_down(0.5);
        assert!(
            matches!(inside.stop, StopReason::Stalled(_)),
            "{}",
            inside.stop
        );
    }

    /// On a smooth zero the search with patience is the search without it: regula falsi
    /// improves at every trial and stops at the tolerance.
    #[test]
    fn patience_changes_nothing_on_a_smooth_zero() {
        let g = |s: f64| Some((s - 0.3) * (1.0 + s * s));
        let (g0, g1) = (g(0.0).unwrap(), g(1.0).unwrap());
        let plain = locate_within(g, g0, 1.0, g1, 1e-12, 1e-14).unwrap();
        let mut trials = 0;
        let patient = locate_to_noise(
            |s| {
                trials += 1;
                g(s)
            },
            g0,
            1.0,
            g1,
            1e-12,
            1e-14,
            4,
        )
        .unwrap();
        assert_eq!(plain, patient);
        assert!(
            patient.1.abs() <= 1e-12 && trials < 15,
            "{patient:?} in {trials}"
        );
    }

    /// A zero resolved only to a noise of 10⁻⁷ (below it the sign is random): the search
    /// stops a few trials after it reaches the noise, at a trial inside the bracket within
    /// the noise's span of the zero, instead of using its whole budget.
    #[test]
    fn a_zero_in_noise_is_left_a_few_trials_after_the_noise_is_reached() {
        let noisy = |s: f64| {
            let hash = ((s * 1e12) as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15) >> 11;
            let r = hash as f64 / (1u64 << 53) as f64 - 0.5;
            (s - 0.3) + 2e-7 * r
        };
        let (mut plain_trials, mut patient_trials) = (0, 0);
        let plain = locate_within(
            |s| {
                plain_trials += 1;
                Some(noisy(s))
            },
            -0.3,
            1.0,
            0.7,
            1e-12,
            1e-14,
        )
        .unwrap();
        let patient = locate_to_noise(
            |s| {
                patient_trials += 1;
                Some(noisy(s))
            },
            -0.3,
            1.0,
            0.7,
            1e-12,
            1e-14,
            4,
        )
        .unwrap();
        assert!((plain.0 - 0.3).abs() < 2e-7, "{plain:?}");
        assert!((patient.0 - 0.3).abs() < 2e-7, "{patient:?}");
        assert!(patient.0 > 0.0 && patient.0 < 1.0);
        assert!(
            patient_trials + 10 < plain_trials,
            "{patient_trials} trials against {plain_trials}"
        );
    }
}
