//! The `equilibrium` analysis — the start state solved again with the constraints active,
//! with its stability — and the state a one-point command (`spectrum`, `export-matrix`)
//! analyses.

use super::{analysis_of, Analysis, Context, RunError};
use crate::continuation::{solve_at, PathOptions, Settings};
use crate::results::{StateKind, StopReason};
use crate::scene::AnalysisSpec as _;
use crate::scene::EquilibriumAnalysis;
use crate::study::{Free, Point, Start, Study};

/// The options of a path of `study` with `settings`, its control within `bounds` (the
/// control's own bounds with `None`).
pub fn path_options(
    study: &dyn Study,
    settings: &Settings,
    bounds: Option<(f64, f64)>,
) -> PathOptions {
    let bounds = bounds.unwrap_or_else(|| {
        study
            .control()
            .map_or((f64::NEG_INFINITY, f64::INFINITY), |c| c.bounds())
    });
    PathOptions::new(settings, bounds, study.state_scale(), 1)
}

/// The state that a one-point command (`spectrum`, `export-matrix`) analyses, with
/// `overrides` (parameter index, value) in place of start values — the state `run` would
/// start from if the scene's start values were those. On a `linear-buckling` scene the start
/// state is held: it is solved with the control at its start value, and the control's
/// override enters only the tangent (`params`), as on `run`'s sample at that value. A `start`
/// from a saved state ([`Start::From`]) gives the first guess and the start values.
pub fn state_at(
    study: &mut dyn Study,
    overrides: &[(usize, f64)],
    start: &Start,
) -> Result<Point, RunError> {
    let analysis = analysis_of(&study.scene().analysis);
    let opts = analysis.options(study);
    let (guess, start) = match start {
        Start::From { u, params } => (Some(u.as_slice()), params.clone()),
        Start::Solve | Start::Critical(_) => (None, study.start_values().to_vec()),
    };
    let mut params = start.clone();
    for &(i, v) in overrides {
        params[i] = v;
    }
    let mut solve_params = params.clone();
    if let (true, Some(c)) = (analysis.held(), study.control().map(|c| c.index)) {
        solve_params[c] = start[c];
    }
    let point = study.solve_start(guess, &solve_params, &opts)?;
    Ok(Point { params, ..point })
}

/// `type = "equilibrium"`: one state.
pub struct Equilibrium(pub EquilibriumAnalysis);

impl Equilibrium {
    fn settings(&self) -> Settings {
        self.0.settings()
    }
}

impl Analysis for Equilibrium {
    fn options(&self, study: &dyn Study) -> PathOptions {
        path_options(
            study,
            &self.settings(),
            Some((f64::NEG_INFINITY, f64::INFINITY)),
        )
    }

    /// The start state solved again with the constraints active: its row, its index and its
    /// state.
    fn run(&self, study: &dyn Study, cx: &mut Context<'_>) -> Result<StopReason, RunError> {
        let start = &cx.start;
        let free = Free {
            control: study.control().map(|c| c.index),
            constraints: true,
            ..Free::default()
        };
        let mut problem = study.problem(&start.params, &free);
        let lambda0 = problem.free_values(&start.params);
        let q_start = problem.coordinates(&start.u);
        let (q, lambda, iterations) =
            solve_at(&mut problem, &q_start, &lambda0, &self.options(study))
                .map_err(|e| RunError::start(study, e))?;
        let u = problem.displacement(&q);
        let params = problem.parameters(&lambda);
        cx.observer.progress(0, lambda[0]);
        cx.observer.state(&u, &params);
        let index = cx
            .crossings
            .as_mut()
            .and_then(|c| c.index(&u, &params))
            .map(|s| s.index);
        cx.record.state(0, StateKind::Step, u.clone(), &params);
        cx.record.row(study, 0, 0.0, &u, params, iterations, index);
        Ok(StopReason::Equilibrium)
    }
}
