//! The analyses a scene asks for, each written once against the study seam
//! ([`crate::study::Study`]), so that the 3-D mesh and the meridian run the same code
//! (docs/architecture.md):
//!
//! - [`equilibrium`]: the start state alone, with its stability;
//! - [`path`]: the path in the control through turning points, with the index by block at
//!   every point and the critical points where it changes, and the branches that leave its
//!   bifurcation points (`[analysis.branches]`);
//! - [`buckling`]: the start state held while the control sweeps its range;
//! - [`curve`]: a critical point followed in two parameters (cusps of limit-point curves);
//! - [`diagram`]: the path, the branches of its bifurcation points to a depth and the
//!   second pieces beside its folds ([`partner`]);
//! - [`surface`]: the equilibrium manifold in two parameters, a family of paths stitched
//!   into triangles, with its critical lines;
//! - [`compare`]: one scene on meshes of different symmetry, critical points matched and
//!   splits measured.
//!
//! Each analysis implements [`Analysis`]; [`analysis_of`] maps a scene's
//! `[analysis]` to it — the one place that names the scene's analysis types. [`run`] solves
//! the start state, hands the analysis a [`Context`] and collects a [`RunResult`]: the report,
//! the states to write and where the time went.

pub mod branch;
pub mod buckling;
pub mod compare;
pub mod curve;
pub mod cusps;
pub mod deflation;
pub mod diagram;
pub mod equilibrium;
pub mod partner;
pub mod path;
pub mod restart;
pub mod surface;

pub use crate::study::RunError;

use crate::continuation::crossings::Crossings;
use crate::continuation::PathOptions;
use crate::output::{self, Described, OutputError, WriteRunError, Written};
use crate::results::{
    CriticalPoint, CurveEvent, Outcome, PathReport, PathRow, PointState, RunResult, RunTimes,
    Spectra, State, StateKind, StopReason, TurningRow,
};
use crate::scene::{self, Scene};
use crate::study::{Point, Start, Study};
use std::path::Path;
use std::time::Instant;

/// The analysis that runs the scene's `[analysis]`: the one place that maps the scene's
/// analysis types to their runs. A new analysis is its keys (a file of `src/scene/analyses/`
/// and one line of that module's registry) and its run (a file here implementing
/// [`Analysis`], its `pub mod` line above and one line below).
pub fn analysis_of(spec: &scene::Analysis) -> Box<dyn Analysis> {
    None.or_else(|| of(spec, path::Path))
        .or_else(|| of(spec, equilibrium::Equilibrium))
        .or_else(|| of(spec, buckling::Buckling))
        .or_else(|| of(spec, curve::Curve))
        .or_else(|| of(spec, cusps::Cusps))
        .or_else(|| of(spec, surface::Surface))
        .or_else(|| of(spec, deflation::Deflate))
        .or_else(|| of(spec, diagram::Diagram))
        .unwrap_or_else(|| unreachable!("no analysis runs `type = \"{}\"`", spec.kind()))
}

/// `make` of the keys, if `spec` is of type `S`.
fn of<S: Clone + 'static, A: Analysis + 'static>(
    spec: &scene::Analysis,
    make: fn(S) -> A,
) -> Option<Box<dyn Analysis>> {
    spec.get::<S>()
        .map(|s| Box::new(make(s.clone())) as Box<dyn Analysis>)
}

/// The path analysis of the scene's `[analysis]`, if it is one (branches leave the critical
/// points of a path).
pub fn path_of(spec: &scene::Analysis) -> Option<path::Path> {
    spec.get::<scene::PathAnalysis>()
        .cloned()
        .or_else(|| spec.get::<scene::DiagramAnalysis>().map(|d| d.path()))
        .map(path::Path)
}

/// What a caller sees of a run while it goes: the progress, and every accepted state.
pub trait Observer {
    /// A point converged: its index along the path and the control's value.
    fn progress(&mut self, _point: usize, _control: f64) {}
    /// The state (u over the model's unknowns, every parameter) of every accepted point.
    fn state(&mut self, _u: &[f64], _params: &[f64]) {}
}

/// An [`Observer`] that only reports progress.
pub struct Progress<F>(pub F);

/// The control a progress display of `study`'s run follows: its name (`control` without one)
/// and its bounds when both are finite; or what its analysis reports instead
/// ([`Analysis::progress_axis`]).
pub fn progress_control(study: &dyn Study) -> (String, Option<(f64, f64)>) {
    if let Some(axis) = analysis_of(&study.scene().analysis).progress_axis() {
        return axis;
    }
    let handle = study.control();
    let control = handle.map_or_else(|| "control".to_string(), |c| c.name.clone());
    let range = handle
        .map(|c| (c.min, c.max))
        .filter(|(a, b)| a.is_finite() && b.is_finite());
    (control, range)
}

impl<F: FnMut(usize, f64)> Observer for Progress<F> {
    fn progress(&mut self, point: usize, control: f64) {
        (self.0)(point, control)
    }
}

/// One analysis of a study: what it needs before the start, and its run.
pub trait Analysis {
    /// The continuation options of its path (or of the start solve alone): the scene's
    /// settings, the control's bounds, the study's state scale.
    fn options(&self, study: &dyn Study) -> PathOptions;
    /// Whether the start state is held while the control sweeps (linear buckling): a singular
    /// trivial block is then a symmetric bifurcation, and a one-point command analyses the
    /// held state at the control it is given.
    fn held(&self) -> bool {
        false
    }
    /// The finished run and the number (from 0) of its critical point the analysis starts
    /// from, if it starts from one (a critical curve's `from-run`).
    fn restarts_from(&self) -> Option<(std::path::PathBuf, usize)> {
        None
    }
    /// What a progress display of its run follows when it is not the control, by name and
    /// range: the parameter its [`Observer::progress`] reports (a cusp curve's third, one
    /// slice after another).
    fn progress_axis(&self) -> Option<(String, Option<(f64, f64)>)> {
        None
    }
    /// Runs from the converged start state in `cx`, recording into it; returns why it
    /// stopped.
    fn run(&self, study: &dyn Study, cx: &mut Context<'_>) -> Result<StopReason, RunError>;
    /// The events it adds to `critical.json` after the path's critical points (a critical
    /// curve's cusps, folds and hilltops).
    fn events<'r>(&self, _result: &'r RunResult) -> &'r [CurveEvent] {
        &[]
    }
    /// Writes its own files into `out`, beside those of every run; returns each with what it
    /// holds, in the order written.
    fn write(
        &self,
        _result: &RunResult,
        _drawing: &dyn crate::output::Drawing,
        _scene: &Scene,
        _out: &Path,
    ) -> Result<Vec<Described>, OutputError> {
        Ok(Vec::new())
    }
    /// Its lines of the run's summary, after the path's.
    fn summary(&self, _result: &RunResult) -> Vec<String> {
        Vec::new()
    }
}

/// Writes every file of a finished run into `out`: those of every run
/// ([`output::write_run_with`]), with the analysis' events in `critical.json` and its own
/// files beside them, and the manifest last.
///
/// # Errors
/// The first file that could not be written, with those written before it.
pub fn write(
    study: &dyn Study,
    result: &mut RunResult,
    out: &Path,
) -> Result<Written, WriteRunError> {
    let analysis = analysis_of(&study.scene().analysis);
    let events = analysis.events(result).to_vec();
    let own = |result: &RunResult, out: &Path| analysis.write(result, study, study.scene(), out);
    output::write_run_with(study, study.scene(), result, out, &events, &own)
}

/// The analysis' own lines of a finished run's summary ([`Analysis::summary`]) and the number
/// of events it added to `critical.json`.
pub fn summary(scene: &Scene, result: &RunResult) -> (Vec<String>, usize) {
    let analysis = analysis_of(&scene.analysis);
    (analysis.summary(result), analysis.events(result).len())
}

/// What an analysis works with: the start state, the stability by blocks (if the study has
/// it), the record it fills, the caller's observer and the clock.
pub struct Context<'a> {
    /// The converged start state.
    pub start: Point,
    /// A critical point of a finished run to start from ([`Start::Critical`]).
    pub from: Option<CriticalPoint>,
    /// The index by blocks and its crossings, unless the study allows no stability analysis.
    pub crossings: Option<Crossings<'a>>,
    /// What the run found so far.
    pub record: Record,
    /// The caller's view of the run.
    pub observer: &'a mut dyn Observer,
    /// Where the time went.
    pub times: RunTimes,
}

/// Runs the scene's analysis from its start state; `progress(step, control)` is called at
/// every converged point.
pub fn run(study: &mut dyn Study, progress: impl FnMut(usize, f64)) -> Result<RunResult, RunError> {
    run_from(study, &Start::Solve, &mut Progress(progress))
}

/// As [`run`], with an [`Observer`] that also sees every accepted state.
pub fn run_with(study: &mut dyn Study, observer: &mut dyn Observer) -> Result<RunResult, RunError> {
    run_from(study, &Start::Solve, observer)
}

/// Runs the scene's analysis from `start`, with an [`Observer`].
pub fn run_from(
    study: &mut dyn Study,
    start: &Start,
    observer: &mut dyn Observer,
) -> Result<RunResult, RunError> {
    let analysis = analysis_of(&study.scene().analysis);
    let mut times = RunTimes::default();
    let t = Instant::now();
    let opts = analysis.options(study);
    let (guess, params) = match start {
        Start::From { u, params } => (Some(u.as_slice()), params.clone()),
        Start::Solve | Start::Critical(_) => (None, study.start_values().to_vec()),
    };
    let point = study.solve_start(guess, &params, &opts)?;
    times.start = t.elapsed();
    times.start_problem = point.times;
    let from = match start {
        Start::Critical(cp) => Some((**cp).clone()),
        Start::Solve | Start::From { .. } => None,
    };
    let study: &dyn Study = study;
    let record = Record::new(study);
    let stage = |study: &dyn Study, cx: &mut Context<'_>| analysis.run(study, cx);
    let held = analysis.held();
    with_context(
        study,
        (point, from),
        record,
        observer,
        times,
        held,
        &opts,
        stage,
    )
}

/// Runs `stage` in a [`Context`] on `study` from the converged `start` (and the critical
/// point it starts from, if any), `record` holding what is known so far, with the index by
/// blocks if the study has it (`held`: states held at their control, as linear buckling's);
/// then the result, its stop as `stage` and a signal leave it, annotated by the study.
#[allow(clippy::too_many_arguments)]
fn with_context(
    study: &dyn Study,
    (start, from): (Point, Option<CriticalPoint>),
    record: Record,
    observer: &mut dyn Observer,
    mut times: RunTimes,
    held: bool,
    opts: &PathOptions,
    stage: impl FnOnce(&dyn Study, &mut Context<'_>) -> Result<StopReason, RunError>,
) -> Result<RunResult, RunError> {
    let t = Instant::now();
    let blocks = study.blocks();
    times.adapted_basis = t.elapsed();
    let stability_note = blocks
        .as_ref()
        .err()
        .map(|e| format!("stability not analysed: {e}"));
    let measure = |u: &[f64], p: &[f64]| study.measure(u, p);
    let control = study.control().map(|c| c.index);
    let crossings = blocks
        .ok()
        .map(|b| Crossings::new(b, &measure, control, held));
    let mut cx = Context {
        start,
        from,
        crossings,
        record,
        observer,
        times,
    };
    // A signal during a later phase (the branches of a finished path, a curve's or a
    // surface's second parameter) ends the run as interrupted, whatever its path's stop was;
    // a solve it cut short ends it so too, with what was found before (none: the error).
    let stop = match stage(study, &mut cx) {
        _ if crate::continuation::interrupt::requested() && !cx.record.rows.is_empty() => {
            StopReason::Interrupted
        }
        Ok(_) if crate::continuation::interrupt::requested() => StopReason::Interrupted,
        Ok(stop) => stop,
        Err(e) => return Err(e),
    };
    // A path that stalled: say which known cause fits.
    if let StopReason::Stalled(s) = &stop {
        let control = study.control().map_or("the control", |c| c.name.as_str());
        let hint = if s.after == 0 && study.start_drifted() {
            crate::study::stall_hint_unheld(study.scene(), s, control)
        } else {
            crate::study::stall_hint(study.scene(), s, control, opts)
        };
        cx.record.warnings.push(hint);
    }
    let mut result = cx.record.finish(study, stop, stability_note, cx.times);
    study.annotate(&mut result);
    Ok(result)
}

/// Runs `stage` on the finished path `run` of `study`, read back as if just followed (its
/// rows, states and critical points in the record; [`restart::reload`]), from the start
/// state solved again (it sets the targets of `"initial"` constraints) — the next analysis
/// of a path starting from its last result (`memstab diagram RUN_DIR`). The result's path is
/// the run's, its stop the run's words.
///
/// # Errors
/// [`AfterError::Input`] when the run does not fit the study; [`AfterError::Start`] when the
/// start state does not converge again; [`AfterError::Run`] when `stage` fails.
pub fn after_finished(
    study: &mut dyn Study,
    run: &crate::output::FinishedRun,
    opts: &PathOptions,
    observer: &mut dyn Observer,
    stage: impl FnOnce(&dyn Study, &mut Context<'_>) -> Result<StopReason, RunError>,
) -> Result<RunResult, AfterError> {
    let input = |e: crate::output::ReopenError| AfterError::Input(e.to_string());
    restart::check(run, study).map_err(input)?;
    let reloaded = restart::reload(run, study).map_err(input)?;
    let mut times = RunTimes::default();
    let t = Instant::now();
    let params = study.start_values().to_vec();
    let point = study
        .solve_start(None, &params, opts)
        .map_err(AfterError::Start)?;
    times.start = t.elapsed();
    times.start_problem = point.times;
    let study: &dyn Study = study;
    let mut record = Record::new(study);
    record.rows = reloaded.rows;
    record.points = reloaded.points;
    record.critical = reloaded.critical;
    record.irreps = run.irreps.clone();
    with_context(
        study,
        (point, None),
        record,
        observer,
        times,
        false,
        opts,
        stage,
    )
    .map_err(AfterError::Run)
}

/// Why an analysis of a finished path could not run ([`after_finished`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AfterError {
    /// The run or the scene does not fit (bad input).
    #[error("{0}")]
    Input(String),
    /// The start state did not converge again.
    #[error("{0}")]
    Start(RunError),
    /// The analysis failed.
    #[error("{0}")]
    Run(RunError),
}

/// What an analysis collects for the report, in the order it finds it.
pub struct Record {
    rows: Vec<PathRow>,
    states: Vec<State>,
    points: Vec<PointState>,
    turning: Vec<TurningRow>,
    critical: Vec<CriticalPoint>,
    /// What could not be settled on the way.
    pub warnings: Vec<String>,
    spectra: Spectra,
    irreps: Vec<String>,
    control: Option<usize>,
    /// The analysis' own result beyond its path (a critical curve, a surface).
    pub outcome: Option<Outcome>,
    /// The branches of the path's bifurcation points.
    pub branches: Option<crate::results::Branches>,
}

impl Record {
    fn new(study: &dyn Study) -> Self {
        Self {
            rows: Vec::new(),
            states: Vec::new(),
            points: Vec::new(),
            turning: Vec::new(),
            critical: Vec::new(),
            warnings: study.warnings().to_vec(),
            spectra: Spectra::default(),
            irreps: Vec::new(),
            control: study.control().map(|c| c.index),
            outcome: None,
            branches: None,
        }
    }

    /// The critical points found so far.
    pub fn critical(&self) -> &[CriticalPoint] {
        &self.critical
    }

    /// The path so far: its rows and every row's state.
    pub fn path(&self) -> (&[PathRow], &[PointState]) {
        (&self.rows, &self.points)
    }

    fn control_of(&self, params: &[f64]) -> f64 {
        self.control.map_or(0.0, |c| params[c])
    }

    /// A row of the path table.
    #[allow(clippy::too_many_arguments)]
    fn row(
        &mut self,
        study: &dyn Study,
        step: usize,
        arclength: f64,
        u: &[f64],
        params: Vec<f64>,
        iterations: usize,
        index: Option<usize>,
    ) {
        self.points.push(PointState {
            parameters: params.clone(),
            q: study.coordinates(u),
        });
        self.rows.push(PathRow {
            step,
            arclength,
            measures: study.measure(u, &params),
            parameters: params,
            iterations,
            index,
            negative: None,
        });
    }

    /// A state to write.
    fn state(&mut self, step: usize, kind: StateKind, u: Vec<f64>, params: &[f64]) {
        self.states.push(State {
            step,
            kind,
            control: self.control_of(params),
            u,
            params: params.to_vec(),
            mode: None,
        });
    }

    /// A critical point, with its state and mode to write.
    fn add_critical(&mut self, cp: CriticalPoint) {
        self.states.push(State {
            step: cp.after_step,
            kind: StateKind::Critical {
                kind: cp.kind,
                irrep: cp.irrep.clone(),
            },
            control: self.control_of(&cp.parameters),
            u: cp.state.clone(),
            params: cp.parameters.clone(),
            mode: Some(cp.mode.clone()),
        });
        self.critical.push(cp);
    }

    fn finish(
        self,
        study: &dyn Study,
        stop: StopReason,
        stability_note: Option<String>,
        times: RunTimes,
    ) -> RunResult {
        let about = study.about();
        let report = PathReport {
            scene: about.scene.clone(),
            origin: about.origin.clone(),
            version: env!("CARGO_PKG_VERSION").to_string(),
            mesh: about.mesh.clone(),
            group: about.group.clone(),
            group_order: about.group_order,
            unknowns: about.unknowns,
            symmetric_unknowns: about.symmetric_unknowns,
            control: study.control().map_or_else(String::new, |c| c.name.clone()),
            parameters: about.parameters.clone(),
            measures: about.measures.clone(),
            rows: self.rows,
            turning_points: self.turning,
            stop,
            critical: self.critical,
            warnings: self.warnings,
            stability_note,
            saved: Vec::new(),
            spectra: self.spectra,
            states: None,
            wrinkling: None,
            wave_numbers: Vec::new(),
            refinement: None,
            checks: None,
            irreps: self.irreps,
        };
        RunResult {
            report,
            states: self.states,
            points: self.points,
            times,
            outcome: self.outcome,
            branches: self.branches,
        }
    }
}
