//! A finished run and where its time went.

use super::{Branches, PathReport, PointState, State};
use std::any::Any;
use std::fmt;
use std::sync::Arc;
use std::time::Duration;

/// A finished run.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// What was found.
    pub report: PathReport,
    /// States to write (every `save-every` steps, the last one, turning and critical points).
    pub states: Vec<State>,
    /// Every path row's state (parameters and fixed-point coordinates), for `path.states`.
    pub points: Vec<PointState>,
    /// Where the time went.
    pub times: RunTimes,
    /// What the analysis found beyond its path (a critical curve's
    /// [`CurveReport`](super::CurveReport), a surface's [`SurfaceReport`](super::SurfaceReport)).
    pub outcome: Option<Outcome>,
    /// The branches of the path's bifurcation points, when the scene asks for them
    /// (`[analysis.branches]`).
    pub branches: Option<Branches>,
}

impl RunResult {
    /// The analysis' own result, if it is a `T`: `result.outcome::<CurveReport>()`.
    pub fn outcome<T: 'static>(&self) -> Option<&T> {
        self.outcome.as_ref()?.get()
    }
}

/// An analysis' own result beyond its path: plain data of the analysis' own type, which the
/// analysis that made it writes and summarises; [`RunResult::outcome`] reads it back as that
/// type.
#[derive(Clone)]
pub struct Outcome(Arc<dyn Value>);

/// Any plain result: shown in debug output, read back as its type.
trait Value: Any + fmt::Debug + Send + Sync {
    fn as_any(&self) -> &dyn Any;
}

impl<T: Any + fmt::Debug + Send + Sync> Value for T {
    fn as_any(&self) -> &dyn Any {
        self
    }
}

impl Outcome {
    /// The result `value`.
    pub fn new<T: Any + fmt::Debug + Send + Sync>(value: T) -> Self {
        Outcome(Arc::new(value))
    }

    /// The result, if it is a `T`.
    pub fn get<T: 'static>(&self) -> Option<&T> {
        // Through the box: an `Arc` is itself a `Value`.
        (*self.0).as_any().downcast_ref()
    }
}

impl fmt::Debug for Outcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.fmt(f)
    }
}

/// Where a run's time went, by phase (what `memstab bench` reports).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RunTimes {
    /// The start solve (wall time).
    pub start: Duration,
    /// Of `start`: the evaluations of the fixed-point problem.
    pub start_problem: PhaseTimes,
    /// Building the symmetry-adapted basis of every irrep (once).
    pub adapted_basis: Duration,
    /// The path (wall time of its correction at fixed control, the steps and the events).
    pub path: Duration,
    /// Of `path`: the steps of the driver (wall time), and of those the evaluations.
    pub steps: BranchTimes,
    /// Of `path`'s events: the index by irrep blocks at every point.
    pub index: Duration,
}

/// Where [`follow`](crate::continuation::events::follow)'s time went.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BranchTimes {
    /// The driver's steps (predictor–corrector, step control), wall time.
    pub steps: std::time::Duration,
    /// Of `steps`: the problem's evaluations.
    pub steps_problem: PhaseTimes,
    /// The detectors (localisation included), wall time.
    pub events: std::time::Duration,
    /// The caller's `progress`, wall time.
    pub progress: std::time::Duration,
}

/// Time spent by a problem's evaluations, by phase.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PhaseTimes {
    /// Assembling the model (`Model::evaluate`).
    pub assembly: std::time::Duration,
    /// Restricting residual, loads, constraints and tangent to the problem's basis.
    pub projection: std::time::Duration,
    /// Number of evaluations.
    pub evaluations: usize,
}

impl std::ops::Sub for PhaseTimes {
    type Output = PhaseTimes;
    fn sub(self, o: PhaseTimes) -> PhaseTimes {
        PhaseTimes {
            assembly: self.assembly.saturating_sub(o.assembly),
            projection: self.projection.saturating_sub(o.projection),
            evaluations: self.evaluations.saturating_sub(o.evaluations),
        }
    }
}

impl std::ops::AddAssign for PhaseTimes {
    fn add_assign(&mut self, o: PhaseTimes) {
        self.assembly += o.assembly;
        self.projection += o.projection;
        self.evaluations += o.evaluations;
    }
}

#[cfg(test)]
mod tests {
    use super::Outcome;

    #[test]
    fn an_outcome_reads_back_as_its_own_type_only() {
        let o = Outcome::new(vec![1.5_f64, 2.5]);
        assert_eq!(o.get::<Vec<f64>>(), Some(&vec![1.5, 2.5]));
        assert_eq!(o.get::<Vec<f32>>(), None);
        assert_eq!(format!("{o:?}"), "[1.5, 2.5]");
    }
}
