//! Everything that follows equilibria (docs/architecture.md): the stepping driver
//! ([`continuation`]), the one event mechanism ([`events`]: turning points, critical points,
//! stops), the problem in the fixed-point space of a (sub)group ([`SymmetricProblem`]),
//! classification ([`critical`]), and the analyses a scene asks for — one file each:
//!
//! - [`equilibrium`]: the start state (the one start solve every command uses) or a single
//!   equilibrium;
//! - [`path`]: the path in the control through turning points, with the index by irrep at
//!   every point and the critical points where it changes;
//! - [`buckling`]: the start state held while the control sweeps its range;
//! - [`curve`]: a critical point followed in two parameters (cusps of limit-point curves);
//! - [`surface`]: the equilibrium manifold in two parameters, a family of paths stitched
//!   into triangles, with its critical lines;
//! - [`compare`]: one scene on meshes of different symmetry, critical points matched and
//!   splits measured;
//! - [`branch`]: the branches that leave a path's bifurcation points (`[analysis.branches]`),
//!   by the equivariant branching lemma, each followed in its isotropy subgroup's
//!   fixed-point space.
//!
//! [`run`] dispatches on the scene's analysis and collects a [`RunResult`]: the report, the
//! states to write and where the time went.

pub mod branch;
pub mod buckling;
pub mod compare;
pub mod curve;
pub mod equilibrium;
pub mod modes;
pub mod path;
mod problem;
pub mod surface;

pub use problem::{held_gauge, SymmetricProblem, SPARSE_TANGENT_FROM};

use crate::adapted::AdaptedBasis;
use crate::continuation::crossings::Crossings;
use crate::continuation::SolveError;
use crate::model::Model;
use crate::results::{
    CriticalPoint, CurveReport, MeshInfo, PathReport, PathRow, PointState, RunResult, RunTimes,
    Spectra, State, StateKind, StopReason, SurfaceReport, TurningRow,
};
use crate::scene::Analysis;
use crate::stability::{IrrepBlocks, Stability};
use crate::study::Study;
use std::time::Instant;

/// Why a run failed before it produced a path.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RunError {
    /// Newton did not converge at the start.
    #[error("the start state did not converge: {}", .error.describe(.control.as_deref()))]
    Start {
        /// Why.
        error: SolveError,
        /// The control parameter's name (none for a single equilibrium).
        control: Option<String>,
    },
    /// `start.from` names a saved state that was not loaded into the study.
    #[error("the start state: start.from is set but no saved state was loaded (output::store::load_start)")]
    NotLoaded,
    /// Newton converged to a membrane turned inside out.
    #[error("the start state did not converge: Newton converged to an inside-out membrane (enclosed volume {volume:e}); start closer to the intended state (start.stretch, the start values)")]
    InsideOut {
        /// The enclosed volume found.
        volume: f64,
    },
    /// A critical curve could not be found or started.
    #[error("critical curve: {0}")]
    Curve(String),
    /// No path of a surface could be started.
    #[error("surface: {0}")]
    Surface(String),
    /// Newton converged to a state that is no membrane state.
    #[error("the start state did not converge: Newton converged to an inadmissible state: {0}; check the material (mu, thickness), the mesh's size and start.stretch against the loads")]
    Degenerate(crate::model::StateDefect),
}

impl RunError {
    /// A start failure of `study`'s solve, naming its control parameter.
    pub fn start(study: &Study, error: SolveError) -> Self {
        Self::Start {
            error,
            control: study.control.map(|c| study.parameters[c].clone()),
        }
    }
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

impl<F: FnMut(usize, f64)> Observer for Progress<F> {
    fn progress(&mut self, point: usize, control: f64) {
        (self.0)(point, control)
    }
}

/// Runs the scene's analysis; `progress(step, control)` is called at every converged point.
pub fn run(study: &mut Study, progress: impl FnMut(usize, f64)) -> Result<RunResult, RunError> {
    run_with(study, &mut Progress(progress))
}

/// As [`run`], with an [`Observer`] that also sees every accepted state.
pub fn run_with(study: &mut Study, observer: &mut dyn Observer) -> Result<RunResult, RunError> {
    let mut times = RunTimes::default();
    let t = Instant::now();
    let start = study.start.clone();
    let (u_start, params_start, start_problem) = equilibrium::solve_start_timed(study, &start)?;
    times.start = t.elapsed();
    times.start_problem = start_problem;
    let study: &Study = study;
    let t = Instant::now();
    let (adapted, stability_note) = match AdaptedBasis::new(&study.action, study.model.layout()) {
        Ok(b) => (Some(b), None),
        Err(e) => (None, Some(format!("stability not analysed: {e}"))),
    };
    times.adapted_basis = t.elapsed();
    let measure = |u: &[f64], p: &[f64]| study.measure(u, p);
    let held = matches!(study.scene.analysis, Analysis::LinearBuckling(_));
    let crossings = adapted.as_ref().map(|b| {
        Crossings::new(
            Box::new(IrrepBlocks::new(
                Stability::new(&study.model, b),
                &study.model,
                &study.constraints,
                &study.action,
            )),
            &measure,
            study.control,
            held,
        )
    });
    let mut record = Record::new(study);
    let stop = match &study.scene.analysis {
        Analysis::Path(_) => path::run(
            study,
            &mut record,
            crossings,
            &u_start,
            &params_start,
            observer,
            &mut times,
        )?,
        Analysis::Equilibrium(_) => equilibrium::run(
            study,
            &mut record,
            crossings,
            &u_start,
            &params_start,
            observer,
        )?,
        Analysis::LinearBuckling(a) => buckling::run(
            study,
            &mut record,
            crossings,
            &u_start,
            &params_start,
            a.samples,
            observer,
        ),
        Analysis::CriticalCurve(_) => {
            let (stop, curve) = curve::run(
                study,
                &mut record,
                crossings,
                adapted.as_ref(),
                &u_start,
                &params_start,
                observer,
                &mut times,
            )?;
            record.curve = Some(curve);
            stop
        }
        Analysis::Surface(_) => {
            let (stop, surface) = surface::run(
                study,
                &mut record,
                crossings,
                &u_start,
                &params_start,
                observer,
                &mut times,
            )?;
            record.surface = Some(surface);
            stop
        }
    };
    let mut result = record.finish(study, stop, stability_note, times);
    if let Analysis::Path(p) = &study.scene.analysis {
        if let Some(b) = &p.branches {
            let opts = branch::options(study, Some(b));
            result.branches = Some(branch::run(study, &result.report.critical, opts));
        }
    }
    Ok(result)
}

/// What an analysis collects for the report, in the order it finds it.
pub(crate) struct Record {
    rows: Vec<PathRow>,
    states: Vec<State>,
    points: Vec<PointState>,
    turning: Vec<TurningRow>,
    critical: Vec<CriticalPoint>,
    warnings: Vec<String>,
    spectra: Spectra,
    irreps: Vec<String>,
    control: Option<usize>,
    curve: Option<CurveReport>,
    surface: Option<SurfaceReport>,
}

impl Record {
    fn new(study: &Study) -> Self {
        Self {
            rows: Vec::new(),
            states: Vec::new(),
            points: Vec::new(),
            turning: Vec::new(),
            critical: Vec::new(),
            warnings: study.warnings.clone(),
            spectra: Spectra::default(),
            irreps: Vec::new(),
            control: study.control,
            curve: None,
            surface: None,
        }
    }

    fn control_of(&self, params: &[f64]) -> f64 {
        self.control.map_or(0.0, |c| params[c])
    }

    /// A row of the path table.
    #[allow(clippy::too_many_arguments)]
    fn row(
        &mut self,
        study: &Study,
        step: usize,
        arclength: f64,
        u: &[f64],
        params: Vec<f64>,
        iterations: usize,
        index: Option<usize>,
    ) {
        self.points.push(PointState {
            parameters: params.clone(),
            q: study.basis.restrict(u).iter().copied().collect(),
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
    fn critical(&mut self, cp: CriticalPoint) {
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
        study: &Study,
        stop: StopReason,
        stability_note: Option<String>,
        times: RunTimes,
    ) -> RunResult {
        let m = &study.mesh;
        let report = PathReport {
            scene: study.scene.info.name.clone(),
            origin: study.scene.origin.clone(),
            version: env!("CARGO_PKG_VERSION").to_string(),
            mesh: MeshInfo {
                generator: study.scene.mesh.generator().to_string(),
                nodes: m.mesh.nodes.len(),
                elements: m.mesh.triangles.len(),
                group: m.group().name().to_string(),
                order: m.group().order(),
            },
            group: study.action.group().name().to_string(),
            group_order: study.action.group().order(),
            unknowns: study.basis.unknowns(),
            symmetric_unknowns: study.basis.dim(),
            control: study
                .control
                .map_or_else(String::new, |c| study.parameters[c].clone()),
            parameters: study.parameters.clone(),
            measures: study.measures.iter().map(|(n, _)| n.clone()).collect(),
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
            irreps: self.irreps,
        };
        RunResult {
            report,
            states: self.states,
            points: self.points,
            times,
            curve: self.curve,
            surface: self.surface,
            branches: None,
        }
    }
}
