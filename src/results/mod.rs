//! What the analyses find, as plain data: the path with its parameters and measures, the
//! turning and critical points, why a path stopped, the states to write, spectra, critical
//! curves, equilibrium surfaces, the branches of bifurcation points, the second pieces of
//! broken bifurcations, and where a run's time
//! went. Writers (see [`crate::output`]) turn it into CSV, JSON, VTU + PVD and SVG diagrams.
//!
//! Nothing here computes beyond simple accessors. Every layer may use it; it uses none of
//! them (std, serde, petgraph and [`crate::text`] only).

mod branches;
mod critical;
mod curve;
mod cusps;
pub mod deflation;
pub mod partner;
mod path;
pub mod refine;
mod run;
mod spectra;
mod state;
mod stop;
mod surface;
pub mod sweep;
pub mod validity;

pub use branches::{
    directory, Bifurcation, BranchGraph, BranchPoint, BranchRun, BranchTurning, Branches,
    Connection, Criticality, Half, Halves, Node, NormalForm, PrimaryPath, RecordedPoint, Reduced,
    Skip, SwitchedBranch, ASYMMETRY,
};
pub use critical::{Bracket, CriticalKind, CriticalPoint, Isotropy};
pub use curve::{CurveEvent, CurveEventKind, CurveReport, CurveRow};
pub use cusps::{CuspCurveReport, CuspSlice, PairEnd, PairEndKind};
pub use path::{
    MeshInfo, PathReport, PathRow, PointState, SavedState, StatesInfo, TurningRow,
    WrinkledCritical, WrinkledPoint, Wrinkling,
};
pub use run::{BranchTimes, Outcome, PhaseTimes, RunResult, RunTimes};
pub use spectra::{Spectra, SpectrumIrrep, SpectrumRow, SPECTRUM_EIGENVALUES};
pub use state::{State, StateKind};
pub use stop::{Extremum, Stalled, StepFailure, StopReason};
pub use surface::{CriticalLine, CriticalLinePoint, SurfacePath, SurfaceReport, SurfaceVertex};
