//! Running a study's analysis, collected into a [`PathReport`] with the states to save.
//!
//! - `path`: the start state (the reference scaled by `start.stretch`, every parameter at its
//!   start value, no constraint active) is solved; constraint targets declared `"initial"`
//!   are measured there; the path is followed in the fixed-point space of the scene's group.
//! - `equilibrium`: the start state alone.
//! - `linear-buckling`: the start state held while the control sweeps `[min, max]`; the
//!   lowest eigenvalue of every irrep block at every sample goes into the report's
//!   [`Spectra`](crate::report::Spectra) (what `path.svg` plots for this analysis).
//!
//! At every point the tangent is split by irrep ([`crate::stability`]); where a block's
//! negative count changes, the critical point is localised and classified
//! ([`crate::critical`]).

use crate::adapted::{AdaptedBasis, SymmetricProblem};
use crate::continuation::{follow, solve_at, step, PathOptions, PathPoint, StopReason};
use crate::critical::{classify_on, isotropy, locate_sign_change, CriticalPoint};
use crate::model::{Evaluation, Model};
use crate::report::{
    MeshInfo, PathReport, PathRow, Spectra, SpectrumIrrep, SpectrumRow, TurningRow,
};
use crate::scene::{Analysis, Direction};
use crate::stability::{Detail, Spectrum, Stability};
use crate::study::{Measure, Study};
use nalgebra::DVector;

/// A state to write: path step, control value, full displacement, and a mode for critical
/// points.
#[derive(Debug, Clone)]
pub struct State {
    /// Path step (turning and critical points carry the step before them).
    pub step: usize,
    /// A label: `step N`, `maximum`, `minimum`, or the critical point's kind and irrep.
    pub label: String,
    /// The control's value.
    pub control: f64,
    /// Displacement over the unknowns.
    pub u: Vec<f64>,
    /// The critical mode over the unknowns, for critical points.
    pub mode: Option<Vec<f64>>,
}

/// A finished run.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// What was found.
    pub report: PathReport,
    /// States to write (every `save-every` steps, the last one, turning and critical points).
    pub states: Vec<State>,
}

/// Why a run failed before it produced a path.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The start state could not be solved.
    #[error("the start state did not converge: {0}")]
    Start(String),
}

/// Relative size below which a localised eigenvalue counts as zero.
const ZERO_EIGENVALUE: f64 = 1e-10;

/// Runs the scene's analysis; `progress(step, control)` is called at every converged point.
pub fn run(study: &mut Study, mut progress: impl FnMut(usize, f64)) -> Result<RunResult, RunError> {
    let opts = path_options(study);
    let start = study.start.clone();
    let (u_start, params_start, _) = solve_start(study, &start)?;
    let q_start = study.basis.restrict(&u_start);
    let study: &Study = study;
    let (adapted, stability_note) = match AdaptedBasis::new(&study.action, study.model.layout()) {
        Ok(b) => (Some(b), None),
        Err(e) => (None, Some(format!("stability not analysed: {e}"))),
    };
    let stability = adapted.as_ref().map(|b| Stability::new(&study.model, b));
    let local = stability.as_ref().map(|s| s.new_evaluation());
    let mut runner = Runner {
        study,
        stability,
        eval: study.model.new_evaluation(),
        local,
        opts,
        rows: Vec::new(),
        states: Vec::new(),
        turning: Vec::new(),
        critical: Vec::new(),
        warnings: study.warnings.clone(),
        spectra: Spectra::default(),
    };
    let stop = match &study.scene.analysis {
        Analysis::LinearBuckling(a) => {
            runner.linear_buckling(&u_start, &params_start, a.samples, &mut progress)
        }
        _ => runner.path(&q_start, &params_start, &mut progress)?,
    };
    let Runner {
        rows,
        states,
        turning,
        critical,
        warnings,
        spectra,
        ..
    } = runner;
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
        rows,
        turning_points: turning,
        stop,
        critical,
        warnings,
        stability_note,
        saved: Vec::new(),
        spectra,
    };
    Ok(RunResult { report, states })
}

/// Solves the start state with every parameter at `params` and no constraint active (the
/// reference scaled by `start.stretch` is the first guess), refuses an inside-out solution,
/// and sets the targets of constraints declared `"initial"` there. Returns the displacement,
/// the parameters and Newton's iterations.
pub fn solve_start(
    study: &mut Study,
    params: &[f64],
) -> Result<(Vec<f64>, Vec<f64>, usize), RunError> {
    let opts = path_options(study);
    let u0 = study.start_displacement();
    let q0 = study.basis.restrict(&u0);
    let mut problem = SymmetricProblem::new(
        &study.model,
        &study.basis,
        &[],
        params.to_vec(),
        study.control,
    );
    let lambda = problem.free_values(params);
    let start_opts = PathOptions {
        max_iterations: opts.max_iterations.max(50),
        ..opts
    };
    let (q, lambda, iterations) =
        solve_at(&mut problem, &q0, &lambda, &start_opts).map_err(RunError::Start)?;
    let params = problem.parameters(&lambda);
    let mut u = vec![0.0; study.basis.unknowns()];
    study.basis.expand(&q, &mut u);
    if let Some(k) = study
        .measures
        .iter()
        .position(|(_, m)| *m == Measure::Volume)
    {
        let v = study.measure(&u, &params)[k];
        if v <= 0.0 {
            return Err(RunError::Start(format!(
                "Newton converged to an inside-out membrane (enclosed volume {v:e}); start closer to the intended state (start.stretch, the start values)"
            )));
        }
    }
    study.set_targets(&u, &params);
    Ok((u, params, iterations))
}

/// The path options of a study's analysis (steps, bounds, tolerances, scales).
pub fn path_options(study: &Study) -> PathOptions {
    let scale = state_scale(study);
    match &study.scene.analysis {
        Analysis::Path(p) => {
            let bounds = study
                .control
                .map(|c| &study.scene.parameters[&study.parameters[c]]);
            PathOptions {
                initial_step: p.initial_step,
                min_step: p.min_step,
                max_step: p.max_step,
                max_steps: p.steps,
                max_iterations: p.max_iterations,
                tolerance: p.tolerance,
                bounds: (
                    bounds.and_then(|b| b.min).unwrap_or(f64::NEG_INFINITY),
                    bounds.and_then(|b| b.max).unwrap_or(f64::INFINITY),
                ),
                parameter_scales: vec![1.0; study.free.len()],
                state_scale: scale,
                direction: if p.direction == Direction::Decrease {
                    -1.0
                } else {
                    1.0
                },
            }
        }
        Analysis::Equilibrium(e) => PathOptions {
            tolerance: e.tolerance,
            max_iterations: e.max_iterations,
            state_scale: scale,
            ..PathOptions::default()
        },
        Analysis::LinearBuckling(b) => PathOptions {
            tolerance: b.tolerance,
            max_iterations: b.max_iterations,
            state_scale: scale,
            ..PathOptions::default()
        },
    }
}

struct Runner<'a> {
    study: &'a Study,
    stability: Option<Stability<'a>>,
    /// The model's evaluation buffer, reused by every spectrum of the run (the tangent of a
    /// large mesh is megabytes; a fresh buffer per point would allocate it every time).
    eval: Evaluation,
    /// The evaluation around the orbit representatives, for the index at every path point.
    local: Option<Evaluation>,
    opts: PathOptions,
    rows: Vec<PathRow>,
    states: Vec<State>,
    turning: Vec<TurningRow>,
    critical: Vec<CriticalPoint>,
    warnings: Vec<String>,
    /// The lowest eigenvalue per irrep at every sample (linear buckling only).
    spectra: Spectra,
}

impl Runner<'_> {
    fn control_of(&self, params: &[f64]) -> f64 {
        self.study.control.map_or(0.0, |c| params[c])
    }

    fn spectrum(&mut self, u: &[f64], params: &[f64]) -> Option<Spectrum> {
        let stab = self.stability.as_ref()?;
        stab.spectrum_of(
            u,
            params,
            &self.study.constraints,
            &mut self.eval,
            None,
            false,
        )
        .ok()
    }

    /// The negative count of every block only (sparse inertia, assembly around the orbit
    /// representatives): what every path point needs to detect a change of stability.
    fn index(&mut self, u: &[f64], params: &[f64]) -> Option<Spectrum> {
        let stab = self.stability.as_ref()?;
        let local = self.local.as_mut()?;
        stab.analyse(
            u,
            params,
            &self.study.constraints,
            local,
            None,
            Detail::Inertia,
        )
        .ok()
    }

    fn row(
        &self,
        step: usize,
        arclength: f64,
        u: &[f64],
        params: Vec<f64>,
        iterations: usize,
        index: Option<usize>,
    ) -> PathRow {
        PathRow {
            step,
            arclength,
            measures: self.study.measure(u, &params),
            parameters: params,
            iterations,
            index,
        }
    }

    /// Localises every eigenvalue of every block whose negative count differs between `a`
    /// and `b`, with `state(s)` giving (u, params) for s ∈ [0, s1] (s = 0 at a, s1 at b).
    fn critical_between(
        &mut self,
        a: &Spectrum,
        b: &Spectrum,
        after_step: usize,
        s1: f64,
        mut state: impl FnMut(f64) -> Option<(Vec<f64>, Vec<f64>)>,
    ) {
        let Some(stab) = self.stability.as_ref() else {
            return;
        };
        let eval = &mut self.eval;
        let study = self.study;
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
                let located = locate_sign_change(
                    |s| {
                        let (u, p) = state(s)?;
                        let sp = stab
                            .spectrum_of(&u, &p, &study.constraints, eval, Some(mu), false)
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
                        .spectrum_of(&u, &p, &study.constraints, eval, Some(mu), true)
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
                    kind: classify_on(
                        mu == 0,
                        ib.dim,
                        matches!(study.scene.analysis, Analysis::LinearBuckling(_)),
                    ),
                    irrep: ib.name.clone(),
                    multiplicity: ib.dim,
                    measures: study.measure(&u, &p),
                    parameters: p,
                    after_step,
                    residual_eigenvalue: g_best.abs() / sp.scale,
                    isotropy: isotropy(&study.action, study.model.layout(), &mode),
                    mode,
                    state: u,
                });
            }
        }
        found.sort_by(|x, y| {
            let c = |p: &CriticalPoint| self.control_of(&p.parameters);
            c(x).total_cmp(&c(y))
        });
        self.warnings.extend(warnings);
        for cp in found {
            self.states.push(State {
                step: cp.after_step,
                label: format!("{} in {}", cp.kind, cp.irrep),
                control: self.control_of(&cp.parameters),
                u: cp.state.clone(),
                mode: Some(cp.mode.clone()),
            });
            self.critical.push(cp);
        }
    }

    /// The path analysis (or the single equilibrium).
    fn path(
        &mut self,
        q_start: &DVector<f64>,
        params_start: &[f64],
        progress: &mut impl FnMut(usize, f64),
    ) -> Result<String, RunError> {
        let study = self.study;
        let mut problem = SymmetricProblem::new(
            &study.model,
            &study.basis,
            &study.constraints,
            params_start.to_vec(),
            study.control,
        );
        let probe = SymmetricProblem::new(
            &study.model,
            &study.basis,
            &study.constraints,
            params_start.to_vec(),
            study.control,
        );
        let lambda0 = problem.free_values(params_start);
        let stretch_index = study
            .measures
            .iter()
            .position(|(_, m)| *m == Measure::Stretch);
        let (save_every, stop_stretch) = match &study.scene.analysis {
            Analysis::Path(p) => (p.save_every.max(1), p.stop_stretch),
            _ => (1, None),
        };
        let opts = self.opts.clone();
        let path = if let Analysis::Path(_) = study.scene.analysis {
            let mut count = 0usize;
            follow(
                &mut problem,
                q_start,
                &lambda0,
                &opts,
                |p| match (stop_stretch, stretch_index) {
                    (Some(target), Some(k)) => {
                        let u = probe.displacement(&p.q);
                        study.measure(&u, &probe.parameters(&p.lambda))[k] >= target
                    }
                    _ => false,
                },
                |p| {
                    progress(count, p.lambda[0]);
                    count += 1;
                },
            )
            .map_err(RunError::Start)?
        } else {
            let (q, lambda, iterations) =
                solve_at(&mut problem, q_start, &lambda0, &opts).map_err(RunError::Start)?;
            crate::continuation::Path {
                points: vec![PathPoint {
                    tangent: DVector::zeros(q.len() + lambda.len()),
                    q,
                    lambda,
                    arclength: 0.0,
                    iterations,
                }],
                turning_points: Vec::new(),
                stop: StopReason::Condition,
            }
        };
        let last = path.points.len() - 1;
        // The previous point's index spectrum and state.
        let mut previous: Option<(Spectrum, Vec<f64>, Vec<f64>)> = None;
        for (i, p) in path.points.iter().enumerate() {
            let u = probe.displacement(&p.q);
            let params = probe.parameters(&p.lambda);
            let spectrum = self.index(&u, &params);
            let index = spectrum.as_ref().map(|s| s.index);
            if i % save_every == 0 || i == last {
                self.states.push(State {
                    step: i,
                    label: format!("step {i}"),
                    control: self.control_of(&params),
                    u: u.clone(),
                    mode: None,
                });
            }
            self.rows
                .push(self.row(i, p.arclength, &u, params.clone(), p.iterations, index));
            if let (Some((a, u0, p0)), Some(b)) = (&previous, &spectrum) {
                if a.negatives() != b.negatives() {
                    // The index changed: now the eigenvalues at both points.
                    let ends = (self.spectrum(u0, p0), self.spectrum(&u, &params));
                    if let (Some(a), Some(b)) = ends {
                        let from = &path.points[i - 1];
                        let s1 = p.arclength - from.arclength;
                        let mut local = SymmetricProblem::new(
                            &study.model,
                            &study.basis,
                            &study.constraints,
                            params_start.to_vec(),
                            study.control,
                        );
                        self.critical_between(&a, &b, i - 1, s1, |s| {
                            let q = step(&mut local, from, s, &opts).ok()?;
                            Some((local.displacement(&q.q), local.parameters(&q.lambda)))
                        });
                    }
                }
            }
            previous = spectrum.map(|s| (s, u, params));
        }
        for t in &path.turning_points {
            let u = probe.displacement(&t.point.q);
            let params = probe.parameters(&t.point.lambda);
            let kind = if t.kind > 0.0 { "maximum" } else { "minimum" };
            self.states.push(State {
                step: t.after_step,
                label: kind.to_string(),
                control: self.control_of(&params),
                u: u.clone(),
                mode: None,
            });
            self.turning.push(TurningRow {
                kind: kind.to_string(),
                after_step: t.after_step,
                measures: study.measure(&u, &params),
                parameters: params,
            });
        }
        Ok(match &path.stop {
            StopReason::Bounds => "the control parameter left its [min, max] range (the last point is the first beyond it)".to_string(),
            StopReason::StepBudget => format!("the step budget ({}) was used", opts.max_steps),
            StopReason::Condition if matches!(study.scene.analysis, Analysis::Path(_)) => {
                format!("the stretch reached {}", stop_stretch.unwrap_or(f64::NAN))
            }
            StopReason::Condition => "equilibrium found".to_string(),
            StopReason::StepTooSmall(why) => why.clone(),
        })
    }

    /// The start state held while the control sweeps [min, max] in `samples` steps.
    fn linear_buckling(
        &mut self,
        u: &[f64],
        params_start: &[f64],
        samples: usize,
        progress: &mut impl FnMut(usize, f64),
    ) -> String {
        let study = self.study;
        let Some(c) = study.control else {
            return "no control parameter".into();
        };
        let spec = &study.scene.parameters[&study.parameters[c]];
        let (lo, hi) = (spec.min.unwrap_or(0.0), spec.max.unwrap_or(1.0));
        let at = |value: f64| {
            let mut p = params_start.to_vec();
            p[c] = value;
            p
        };
        let mut previous: Option<(Spectrum, f64)> = None;
        let mut sampled: Vec<(usize, f64, Option<Sample>)> = Vec::with_capacity(samples + 1);
        for i in 0..=samples {
            let value = lo + (hi - lo) * i as f64 / samples as f64;
            progress(i, value);
            let params = at(value);
            let spectrum = self.spectrum(u, &params);
            sampled.push((i, value, spectrum.as_ref().map(Sample::of)));
            let index = spectrum.as_ref().map(|s| s.index);
            self.rows.push(self.row(i, value - lo, u, params, 0, index));
            if let (Some((a, va)), Some(b)) = (&previous, &spectrum) {
                if a.negatives() != b.negatives() {
                    let (a, va) = (a.clone(), *va);
                    let held = u.to_vec();
                    self.critical_between(&a, b, i - 1, value - va, |s| {
                        Some((held.clone(), at(va + s)))
                    });
                }
            }
            previous = spectrum.map(|s| (s, value));
        }
        self.spectra = spectra_of(sampled);
        self.states.push(State {
            step: 0,
            label: "held state".into(),
            control: lo,
            u: u.to_vec(),
            mode: None,
        });
        format!("the control swept [{lo}, {hi}] in {samples} steps")
    }
}

/// What the report keeps of one sample's spectrum: per block, its irrep, its lowest
/// eigenvalue relative to the scale (finite, or none) and its negative count.
struct Sample {
    scale: f64,
    blocks: Vec<(SpectrumIrrep, Option<f64>, usize)>,
}

impl Sample {
    fn of(s: &Spectrum) -> Self {
        Self {
            scale: s.scale,
            blocks: s
                .blocks
                .iter()
                .map(|b| {
                    let irrep = SpectrumIrrep {
                        name: b.irrep.clone(),
                        dim: b.dim,
                        size: b.size,
                        eigenvalues: !b.eigenvalues.is_empty(),
                    };
                    let lowest = b
                        .eigenvalues
                        .first()
                        .map(|l| l / s.scale)
                        .filter(|l| l.is_finite());
                    (irrep, lowest, b.negative)
                })
                .collect(),
        }
    }
}

/// The report's [`Spectra`] from the samples `(step, control, sample)` of a sweep: the irreps
/// of the first analysed sample, a row per sample (all `None` where it was not analysed).
fn spectra_of(sampled: Vec<(usize, f64, Option<Sample>)>) -> Spectra {
    let Some(first) = sampled.iter().find_map(|s| s.2.as_ref()) else {
        return Spectra::default();
    };
    let mut irreps: Vec<SpectrumIrrep> = first.blocks.iter().map(|b| b.0.clone()).collect();
    let n = irreps.len();
    let rows: Vec<SpectrumRow> = sampled
        .into_iter()
        .map(|(step, control, sample)| {
            let sample = sample.filter(|s| s.blocks.len() == n && s.scale.is_finite());
            SpectrumRow {
                step,
                control,
                scale: sample.as_ref().map_or(0.0, |s| s.scale),
                lowest: sample
                    .as_ref()
                    .map_or_else(|| vec![None; n], |s| s.blocks.iter().map(|b| b.1).collect()),
                negative: sample.as_ref().map_or_else(
                    || vec![None; n],
                    |s| s.blocks.iter().map(|b| Some(b.2)).collect(),
                ),
            }
        })
        .collect();
    // A block counts as having eigenvalues if any sample computed them.
    for (mu, irrep) in irreps.iter_mut().enumerate() {
        irrep.eigenvalues = rows.iter().any(|r| r.lowest[mu].is_some());
    }
    Spectra { irreps, rows }
}

/// The unit of the state in the arclength: the mesh radius times √nodes, so that a step is
/// an RMS displacement relative to the mesh size.
pub fn state_scale(study: &Study) -> f64 {
    let r = study
        .model
        .reference()
        .iter()
        .map(|x| x.norm())
        .fold(0.0, f64::max)
        .max(1e-300);
    r * (study.model.reference().len() as f64).sqrt()
}
