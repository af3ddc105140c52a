//! A finished run and where its time went.

use super::{Branches, CurveReport, PathReport, PointState, State, SurfaceReport};
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
    /// The critical curve of a `critical-curve` analysis.
    pub curve: Option<CurveReport>,
    /// The equilibrium surface of a `surface` analysis.
    pub surface: Option<SurfaceReport>,
    /// The branches of the path's bifurcation points, when the scene asks for them
    /// (`[analysis.branches]`).
    pub branches: Option<Branches>,
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
