//! The k = 0.1 balloon under icosphere refinement: the pressure maximum and minimum against
//! the closed form ([`crate::reference::P_MAX`], [`crate::reference::P_MIN`]), the time of
//! each level split by phase as [`crate::analysis::run_with`] reports it, and the stability
//! spectra by irrep at every accepted state.

use crate::adapted::AdaptedBasis;
use crate::model::{Model, Request};
use crate::reference::{P_MAX, P_MIN};
use crate::results::{Extremum, StateKind};
use crate::scene::Scene;
use crate::stability::{BlockEigen, Stability};
use crate::study::mesh::MeshStudy;
use std::time::{Duration, Instant};

/// The bundled balloon scene text (k = 0.1, icosphere `frequency = 8`).
pub const BALLOON_TOML: &str = include_str!("../../scenes/balloon.toml");

/// The balloon scene on an icosphere of `frequency`.
pub fn balloon_scene(frequency: usize) -> Result<Scene, String> {
    let text = BALLOON_TOML.replace("frequency = 8 ", &format!("frequency = {frequency} "));
    Scene::from_toml_str(&text, &format!("balloon, frequency {frequency}"))
        .map_err(|e| e.to_string())
}

/// One refinement level of the balloon study.
#[derive(Debug, Clone)]
pub struct BalloonLevel {
    /// Icosphere frequency f.
    pub frequency: usize,
    /// Triangles (20 f²).
    pub elements: usize,
    /// Unknowns N (3 × nodes).
    pub unknowns: usize,
    /// Unknowns of the Ih fixed-point space the path is solved in.
    pub symmetric_unknowns: usize,
    /// Converged path points.
    pub points: usize,
    /// Model evaluations along the path (start and path).
    pub evaluations: usize,
    /// Pressure maximum found (`None` when the path ended before it).
    pub p_max: Option<f64>,
    /// Pressure minimum found (`None` when the path ended before it).
    pub p_min: Option<f64>,
    /// Time of model.evaluate (path + stability).
    pub assembly: Duration,
    /// Time of restrictions to the fixed-point basis during the path.
    pub projection: Duration,
    /// Rest of the path follower: dense factorisations/solves of the fixed-point system, steps.
    pub continuation: Duration,
    /// Building the adapted basis (once).
    pub adapted_basis: Duration,
    /// Stability spectra at every point, without their assembly; `None` when skipped.
    pub eigen: Option<Duration>,
    /// Of `eigen`: the block restrictions (estimated from three points).
    pub eigen_restrict: Option<Duration>,
    /// Wall time of all `spectrum_of` calls, their assembly included (what stability by
    /// irrep costs along the path, the adapted basis excepted); `None` when skipped.
    pub spectra: Option<Duration>,
    /// Wall time of the index by irrep blocks at every point, as `run` computes it
    /// ([`crate::stability::Detail::Inertia`] on the representatives' evaluation, its assembly
    /// included); `None` without stability.
    pub index: Option<Duration>,
    /// The rest of the run's events: turning points, and eigenvalues and localisation where
    /// the index changed.
    pub localisation: Duration,
    /// The instability index by irrep blocks at every point (empty without stability).
    pub indices: Vec<usize>,
    /// The lowest eigenvalue over all blocks at every point (rigid modes deflated; empty
    /// without stability).
    pub lowest: Vec<f64>,
    /// Wall time of the whole level (scene to last spectrum), without the re-timing evaluations.
    pub total: Duration,
    /// The state (u, params) at the pressure maximum (`None` when not reached).
    pub at_max: Option<(Vec<f64>, Vec<f64>)>,
    /// Every converged state (u, params), when asked for ([`LevelOptions::keep_states`]).
    pub states: Vec<(Vec<f64>, Vec<f64>)>,
}

impl BalloonLevel {
    /// Relative error of the pressure maximum against the closed form.
    pub fn err_max(&self) -> Option<f64> {
        self.p_max.map(|p| (p - P_MAX).abs() / P_MAX)
    }
    /// Relative error of the pressure minimum against the closed form.
    pub fn err_min(&self) -> Option<f64> {
        self.p_min.map(|p| (p - P_MIN).abs() / P_MIN)
    }
    /// The rest: total minus the named phases.
    pub fn rest(&self) -> Duration {
        self.total
            .saturating_sub(self.assembly)
            .saturating_sub(self.projection)
            .saturating_sub(self.continuation)
            .saturating_sub(self.adapted_basis)
            .saturating_sub(self.eigen.unwrap_or_default())
            .saturating_sub(self.index.unwrap_or_default())
    }
    /// What `memstab run` pays for this path: everything but the eigenvalue spectra (the
    /// path, the adapted basis and the index by blocks at every point).
    pub fn run_time(&self) -> Duration {
        self.total.saturating_sub(self.spectra.unwrap_or_default())
    }
    /// Path points per second of the per-point work alone: the path (assembly, projection,
    /// continuation) and the index by blocks at every point, without the one-off set-up
    /// (scene, mesh, start solve, adapted basis); `None` without stability.
    pub fn steady_points_per_second(&self) -> Option<f64> {
        let t = self.path_time() + self.index?;
        Some(self.points as f64 / t.as_secs_f64().max(1e-12))
    }
    /// Path points per second of [`BalloonLevel::run_time`].
    pub fn points_per_second(&self) -> f64 {
        self.points as f64 / self.run_time().as_secs_f64().max(1e-12)
    }
    /// The path without stability: assembly (of the path) + projection + continuation. The
    /// assembly re-timed inside the spectra is not counted.
    pub fn path_time(&self) -> Duration {
        let stability_assembly = self
            .spectra
            .zip(self.eigen)
            .map_or(Duration::ZERO, |(s, e)| s.saturating_sub(e));
        self.assembly.saturating_sub(stability_assembly) + self.projection + self.continuation
    }
    /// Stability by irrep along the path: the adapted basis (once) and every spectrum with
    /// its assembly; zero when skipped.
    pub fn stability_time(&self) -> Duration {
        self.adapted_basis + self.index.unwrap_or_default() + self.spectra.unwrap_or_default()
    }
}

/// What [`balloon_level_with`] computes besides the path.
#[derive(Debug, Clone, Copy, Default)]
pub struct LevelOptions {
    /// The spectrum by irrep at every converged point, as `run` computes it.
    pub stability: bool,
    /// Keep every converged state in [`BalloonLevel::states`] (for
    /// [`crate::bench::full_path_stability`]).
    pub keep_states: bool,
    /// Stop after this many converged points, the start included (`None`: where the scene's
    /// path ends, at the stretch 4).
    pub max_points: Option<usize>,
    /// Only the index by blocks at every point, no eigenvalue spectra (the scaling study).
    pub index_only: bool,
}

/// Follows the balloon of `frequency` through its pressure maximum and minimum, timing each
/// phase; with `stability` the spectrum by irrep is computed at every converged point (as
/// `run` does). Returns the level and the study (for the payoff at the maximum). The level
/// must reach both turning points.
pub fn balloon_level(
    frequency: usize,
    stability: bool,
) -> Result<(BalloonLevel, MeshStudy), String> {
    let opts = LevelOptions {
        stability,
        ..LevelOptions::default()
    };
    let (level, study) = balloon_level_with(frequency, &opts)?;
    if level.p_max.is_none() {
        return Err("the path has no pressure maximum".into());
    }
    if level.p_min.is_none() {
        return Err("the path has no pressure minimum".into());
    }
    Ok((level, study))
}

/// As [`balloon_level`], with the options of [`LevelOptions`]; a turning point the path does
/// not reach is `None`.
///
/// The path is what `memstab run` computes ([`crate::analysis::run_with`]: start solve,
/// adapted basis, path with the index by blocks at every point and the critical points
/// localised), with the run's own phase times; the eigenvalue spectra of `stability` are
/// computed by an observer at every accepted state and timed apart.
pub fn balloon_level_with(
    frequency: usize,
    options: &LevelOptions,
) -> Result<(BalloonLevel, MeshStudy), String> {
    if options.max_points == Some(0) {
        return Err("a path has at least one point".into());
    }
    let start = Instant::now();
    let mut scene = balloon_scene(frequency)?;
    if let (Some(n), Some(steps)) = (options.max_points, scene.analysis.budget()) {
        // The path accepts up to `steps` steps after the start.
        scene.analysis.set_budget(steps.min(n - 1));
    }
    let mut study = MeshStudy::build(scene).map_err(|e| e.to_string())?;
    let mut observer = SpectraObserver::default();
    let result = crate::analysis::run_with(&mut study, &mut observer).map_err(|e| e.to_string())?;
    let wall = start.elapsed();
    let study_ref: &MeshStudy = &study;
    let report = &result.report;
    let times = result.times;
    let turning = |kind: Extremum| {
        report
            .turning_points
            .iter()
            .find(|t| t.kind == kind)
            .map(|t| t.parameters[0])
    };
    let at_max = result.states.iter().find_map(|s| match &s.kind {
        StateKind::Turning(Extremum::Maximum) => {
            let mut params = study_ref.start.clone();
            params[0] = s.control;
            Some((s.u.clone(), params))
        }
        _ => None,
    });
    let indices: Vec<usize> = if options.stability {
        report.rows.iter().filter_map(|r| r.index).collect()
    } else {
        Vec::new()
    };
    // The eigenvalue spectra at every state, as a second pass over the states the observer
    // kept (timed apart: not part of what `run` does).
    let (mut eigen, mut eigen_restrict, mut spectra_wall) = (None, None, None);
    let mut lowest = Vec::new();
    let mut retimed_assembly = Duration::ZERO;
    if options.stability && !options.index_only {
        let adapted = AdaptedBasis::new(&study_ref.action, study_ref.model.layout())
            .map_err(|e| e.to_string())?;
        // All eigenvalues of every block: dense whatever their size.
        let stab = Stability::new(&study_ref.model, &adapted).with_block_eigen(BlockEigen::Dense);
        let mut eval = study_ref.model.new_evaluation();
        let (mut spectra, mut restrict) = (Duration::ZERO, Duration::ZERO);
        let n = observer.states.len();
        let sample = [0, n / 2, n.saturating_sub(1)];
        let mut work = Vec::new();
        for (i, ((u, params), index)) in observer.states.iter().zip(&indices).enumerate() {
            let t = Instant::now();
            let spectrum = stab
                .spectrum_of(u, params, &study_ref.constraints, &mut eval, None, false)
                .map_err(|e| e.to_string())?;
            spectra += t.elapsed();
            if spectrum.index != *index {
                return Err(format!(
                    "f = {frequency}, point {i}: the index by eigenvalues {} and by inertia {index} differ",
                    spectrum.index
                ));
            }
            lowest.push(
                spectrum
                    .blocks
                    .iter()
                    .flat_map(|b| b.eigenvalues.first())
                    .copied()
                    .fold(f64::INFINITY, f64::min),
            );
            // The assembly inside spectrum_of, and at three points the dense block
            // restrictions.
            let t = Instant::now();
            study_ref
                .model
                .evaluate(u, params, Request::ALL, &mut eval)
                .map_err(|e| e.to_string())?;
            retimed_assembly += t.elapsed();
            if sample.contains(&i) {
                let t = Instant::now();
                let layout = study_ref.model.layout();
                for ib in &adapted.irreps {
                    std::hint::black_box(ib.first().restrict_tangent(layout, &eval, &mut work));
                }
                restrict += t.elapsed();
            }
        }
        spectra_wall = Some(spectra);
        eigen = Some(spectra.saturating_sub(retimed_assembly));
        eigen_restrict = Some(restrict.mul_f64(n as f64 / sample.len() as f64));
    }
    let problem = {
        let mut p = times.start_problem;
        p += times.steps.steps_problem;
        p
    };
    // The path follower without its evaluations: the start solve and the steps.
    let continuation =
        (times.start + times.steps.steps).saturating_sub(problem.assembly + problem.projection);
    let total = wall.saturating_sub(times.steps.progress);
    let level = BalloonLevel {
        frequency,
        elements: study_ref.model.layout().triangles().len(),
        unknowns: study_ref.basis.unknowns(),
        symmetric_unknowns: study_ref.basis.dim(),
        points: report.rows.len(),
        evaluations: problem.evaluations,
        p_max: turning(Extremum::Maximum),
        p_min: turning(Extremum::Minimum),
        assembly: problem.assembly + retimed_assembly,
        projection: problem.projection,
        continuation,
        adapted_basis: times.adapted_basis,
        eigen,
        eigen_restrict,
        spectra: spectra_wall,
        index: options.stability.then_some(times.index),
        localisation: times.steps.events.saturating_sub(times.index),
        indices,
        lowest,
        total: total + spectra_wall.unwrap_or_default(),
        at_max,
        states: if options.keep_states {
            observer.states
        } else {
            Vec::new()
        },
    };
    Ok((level, study))
}

/// Keeps every accepted state of a run.
#[derive(Default)]
struct SpectraObserver {
    states: Vec<(Vec<f64>, Vec<f64>)>,
}

impl crate::analysis::Observer for SpectraObserver {
    fn state(&mut self, u: &[f64], params: &[f64]) {
        self.states.push((u.to_vec(), params.to_vec()));
    }
}
