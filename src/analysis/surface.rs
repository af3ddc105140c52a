//! The `surface` analysis (docs/theory.md §11.10): the equilibrium manifold in two parameters
//! (a, b), covered by a family of paths in `a` at a grid of values of `b`.
//!
//! The start state is carried at fixed `a` to every grid value of `b` (Newton from the
//! neighbouring value, the step in `b` halved where Newton fails); from each, the path in `a`
//! is the ordinary path of the study (the path analysis's driver,
//! [`crate::continuation::events::trace`]): pseudo-arclength through its folds, the index by irrep blocks at
//! every point, every critical point where it changes localised and classified. Neighbouring
//! paths are stitched into triangles by the fraction of their own arclength ([`stitch`]), so
//! paths of different lengths still close the strip between them; the critical points of the
//! paths are joined across `b` into critical lines ([`join`]): on a limit line the surface
//! folds over the (a, b) plane, and the index of its vertices changes there.

use super::equilibrium::path_options;
use super::path::{record_branch, start_driver, trace_indexed};
use super::{Analysis, Context, RunError};
use crate::continuation::events::Event;
use crate::continuation::{solve_at, PathOptions, Settings};
use crate::output::{self, Described, OutputError};
use crate::results::{
    CriticalKind, CriticalLine, CriticalLinePoint, CriticalPoint, Outcome, RunResult, StopReason,
    SurfacePath, SurfaceReport, SurfaceVertex,
};
use crate::scene::AnalysisSpec as _;
use crate::scene::Scene;
use crate::scene::SurfaceAnalysis;
use crate::study::{Followed, Free, Point, Study};
use crate::text::num;
use crate::text::sig_digits;
use std::path::Path;
use std::time::Instant;

/// How often the step in `b` is halved, carrying the start state to a grid value, before that
/// value is given up.
const MAX_HALVINGS: usize = 10;

/// Triangles between two neighbouring paths whose vertices are numbered from `first_a` and
/// `first_b` and lie at the arclength fractions `a` and `b` (each ascending from 0 to 1):
/// the two polylines are walked together, always advancing the one whose next vertex comes
/// first in fraction, and every advance closes one triangle. Every vertex of both is used,
/// whatever the two lengths; a path of one vertex gets a fan, two of one vertex nothing.
pub fn stitch(a: &[f64], first_a: usize, b: &[f64], first_b: usize) -> Vec<[usize; 3]> {
    let (n, m) = (a.len(), b.len());
    let mut triangles = Vec::with_capacity((n + m).saturating_sub(2));
    if n == 0 || m == 0 {
        return triangles;
    }
    let (mut i, mut k) = (0, 0);
    while i + 1 < n || k + 1 < m {
        let advance_a = k + 1 == m || (i + 1 < n && a[i + 1] <= b[k + 1]);
        if advance_a {
            triangles.push([first_a + i, first_a + i + 1, first_b + k]);
            i += 1;
        } else {
            triangles.push([first_a + i, first_b + k + 1, first_b + k]);
            k += 1;
        }
    }
    triangles
}

/// The arclength fractions of a path's vertices (0 … 1; all 0 for a path that did not move).
pub fn fractions(vertices: &[SurfaceVertex]) -> Vec<f64> {
    let (first, last) = match (vertices.first(), vertices.last()) {
        (Some(f), Some(l)) => (f.arclength, l.arclength),
        _ => return Vec::new(),
    };
    let span = last - first;
    vertices
        .iter()
        .map(|v| {
            if span > 0.0 {
                (v.arclength - first) / span
            } else {
                0.0
            }
        })
        .collect()
}

/// The critical points of the paths joined across `b`: a point of path j continues the line
/// of a point of path j − 1 when both have the same kind and irrep and the same place in
/// order among their path's points of that kind and irrep. A path without the point ends the
/// line; a later one starts another.
pub fn join(paths: &[SurfacePath]) -> Vec<CriticalLine> {
    let mut lines: Vec<CriticalLine> = Vec::new();
    // For every line still open: its key and the path of its last point.
    let mut open: Vec<((CriticalKind, String, usize), usize, usize)> = Vec::new();
    for (j, path) in paths.iter().enumerate() {
        let mut seen: Vec<(CriticalKind, String)> = Vec::new();
        for (c, cp) in path.critical.iter().enumerate() {
            let ordinal = seen
                .iter()
                .filter(|(k, i)| *k == cp.kind && *i == cp.irrep)
                .count();
            seen.push((cp.kind, cp.irrep.clone()));
            let key = (cp.kind, cp.irrep.clone(), ordinal);
            let point = CriticalLinePoint {
                path: j,
                critical: c,
                parameters: cp.parameters.clone(),
                measures: cp.measures.clone(),
            };
            let continued = open
                .iter_mut()
                .find(|(k, last, _)| *k == key && last + 1 == j);
            match continued {
                Some((_, last, line)) => {
                    *last = j;
                    lines[*line].points.push(point);
                }
                None => {
                    open.push((key, j, lines.len()));
                    lines.push(CriticalLine {
                        kind: cp.kind,
                        irrep: cp.irrep.clone(),
                        points: vec![point],
                    });
                }
            }
        }
        open.retain(|(_, last, _)| *last == j);
    }
    lines
}

/// The state at parameters `params` with `b` (parameter index `b`) moved to `target`,
/// carried from the converged (u, params) by Newton at fixed control, the step in `b` halved
/// where Newton fails.
pub(super) fn carry(
    study: &dyn Study,
    opts: &PathOptions,
    u: &[f64],
    params: &[f64],
    b: usize,
    target: f64,
) -> Result<(Vec<f64>, Vec<f64>), String> {
    let (mut u, mut params) = (u.to_vec(), params.to_vec());
    let mut step = target - params[b];
    let mut halvings = 0;
    while params[b] != target {
        let mut next = params.clone();
        next[b] = if (target - params[b]).abs() <= step.abs() {
            target
        } else {
            params[b] + step
        };
        let free = Free {
            control: study.control().map(|c| c.index),
            constraints: true,
            ..Free::default()
        };
        let mut problem = study.problem(&next, &free);
        let lambda0 = problem.free_values(&next);
        let q0 = problem.coordinates(&u);
        match solve_at(&mut problem, &q0, &lambda0, opts) {
            Ok((q, lambda, _)) => {
                u = problem.displacement(&q);
                params = problem.parameters(&lambda);
            }
            Err(e) if halvings < MAX_HALVINGS => {
                let _ = e;
                step *= 0.5;
                halvings += 1;
            }
            Err(e) => {
                return Err(format!(
                    "the start state could not be carried to {} = {}: {}",
                    study.about().parameters[b],
                    num(next[b]),
                    e.describe(None)
                ))
            }
        }
    }
    Ok((u, params))
}

/// A converged state and its parameters.
pub(super) type Carried = (Vec<f64>, Vec<f64>);

/// The start state carried to each of `values` (ascending) of parameter `b`, outwards from
/// the start's own value in both directions, each from its neighbour; a value that cannot be
/// reached (and every value beyond it) is `None`, with a warning.
pub(super) fn carry_outwards(
    study: &dyn Study,
    opts: &PathOptions,
    start: &Point,
    b: usize,
    values: &[f64],
) -> (Vec<Option<Carried>>, Vec<String>) {
    let mut warnings = Vec::new();
    let mut starts = vec![None; values.len()];
    let split = values.partition_point(|&v| v < start.params[b]);
    let up: Vec<usize> = (split..values.len()).collect();
    let down: Vec<usize> = (0..split).rev().collect();
    for side in [up, down] {
        let mut from = (start.u.clone(), start.params.clone());
        for j in side {
            match carry(study, opts, &from.0, &from.1, b, values[j]) {
                Ok(state) => {
                    from = state.clone();
                    starts[j] = Some(state);
                }
                Err(why) => {
                    warnings.push(why);
                    break;
                }
            }
        }
    }
    (starts, warnings)
}

/// `type = "surface"`.
pub struct Surface(pub SurfaceAnalysis);

impl Analysis for Surface {
    /// Every path of the surface: the ranges' first bounds the paths' parameter.
    fn options(&self, study: &dyn Study) -> PathOptions {
        let a = &self.0;
        let settings: Settings = a.settings();
        let bounds = study
            .control()
            .map_or((f64::NEG_INFINITY, f64::INFINITY), |c| c.bounds());
        path_options(
            study,
            &settings,
            Some((bounds.0.max(a.ranges[0][0]), bounds.1.min(a.ranges[0][1]))),
        )
    }

    /// Follows the surface's paths; the first path is recorded (its rows, states and
    /// critical points are the run's path outputs), the surface put into the record with the
    /// first path's stop.
    fn run(&self, study: &dyn Study, cx: &mut Context<'_>) -> Result<StopReason, RunError> {
        let analysis = &self.0;
        let opts = self.options(study);
        let t0 = Instant::now();
        let index = |name: &str| {
            study
                .about()
                .parameters
                .iter()
                .position(|p| p == name)
                .expect("validated parameter")
        };
        let b = index(analysis.b());
        let measure = analysis
            .measure
            .clone()
            .or_else(|| study.about().measures.first().cloned())
            .unwrap_or_default();
        let values = analysis.b_values();
        // The start state at every value of b, carried outwards from the start's b.
        let (starts, mut warnings) = carry_outwards(study, &opts, &cx.start, b, &values);
        let mut crossings = cx.crossings.take();
        let mut paths: Vec<SurfacePath> = Vec::new();
        let mut recorded: Option<StopReason> = None;
        let mut count = 0usize;
        for (j, start) in starts.iter().enumerate() {
            let Some((u0, p0)) = start else { continue };
            let point = Point {
                u: u0.clone(),
                params: p0.clone(),
                iterations: 0,
                times: Default::default(),
            };
            let max_steps = opts.max_steps;
            let mut driver = match start_driver(study, &point, opts.clone()) {
                Ok(d) => d,
                Err(e) => {
                    warnings.push(format!(
                        "no path at {} = {}: {e}",
                        analysis.b(),
                        num(values[j])
                    ));
                    continue;
                }
            };
            let observer = &mut *cx.observer;
            let (branch, index) = trace_indexed(
                &mut driver,
                &mut crossings,
                max_steps,
                |_, _| None,
                |problem, p| {
                    observer.progress(count, p.lambda[0]);
                    observer.state(&problem.displacement(&p.q), &problem.parameters(&p.lambda));
                    count += 1;
                },
            );
            let problem = driver.into_problem();
            let indices = match index {
                Some(ix) => {
                    cx.times.index += ix.time;
                    ix.indices
                }
                None => vec![None; branch.points.len()],
            };
            cx.times.steps.steps += branch.times.steps;
            cx.times.steps.events += branch.times.events;
            cx.times.steps.progress += branch.times.progress;
            if recorded.is_none() {
                record_branch(
                    study,
                    &mut cx.record,
                    &*problem,
                    &branch,
                    &indices,
                    usize::MAX,
                );
                recorded = Some(branch.stop.clone());
            } else {
                for event in &branch.events {
                    if let Event::Warning(w) = event {
                        warnings.push(format!("{} = {}: {w}", analysis.b(), num(values[j])));
                    }
                }
            }
            let vertices = branch
                .points
                .iter()
                .enumerate()
                .map(|(i, p)| {
                    let u = problem.displacement(&p.q);
                    let params = problem.parameters(&p.lambda);
                    SurfaceVertex {
                        step: i,
                        arclength: p.arclength,
                        measures: study.measure(&u, &params),
                        parameters: params,
                        index: indices.get(i).copied().flatten(),
                    }
                })
                .collect();
            let first_vertex = paths
                .last()
                .map_or(0, |p: &SurfacePath| p.first_vertex + p.vertices.len());
            paths.push(SurfacePath {
                b: values[j],
                first_vertex,
                vertices,
                critical: branch
                    .critical_points()
                    .cloned()
                    .collect::<Vec<CriticalPoint>>(),
                stop: branch.stop.clone(),
            });
        }
        let Some(stop) = recorded else {
            return Err(RunError::Surface(format!(
                "no path could be started: {}",
                warnings.join("; ")
            )));
        };
        if crossings.is_none() {
            warnings.push(
                "the index is not computed: the scene's group allows no stability analysis by \
                 irrep"
                    .into(),
            );
        }
        let mut triangles = Vec::new();
        for pair in paths.windows(2) {
            triangles.extend(stitch(
                &fractions(&pair[0].vertices),
                pair[0].first_vertex,
                &fractions(&pair[1].vertices),
                pair[1].first_vertex,
            ));
        }
        let lines = join(&paths);
        cx.times.path = t0.elapsed();
        cx.record.outcome = Some(Outcome::new(SurfaceReport {
            a: analysis.a().to_string(),
            b: analysis.b().to_string(),
            measure,
            parameters: study.about().parameters.clone(),
            measures: study.about().measures.clone(),
            paths,
            triangles,
            lines,
            warnings,
        }));
        Ok(stop)
    }

    /// `surface.vtu`, `surface.json`, `surface.svg`.
    fn write(
        &self,
        result: &RunResult,
        _drawing: &dyn crate::output::Drawing,
        scene: &Scene,
        out: &Path,
    ) -> Result<Vec<Described>, OutputError> {
        let Some(s) = result.outcome::<SurfaceReport>() else {
            return Ok(Vec::new());
        };
        let what = [
            format!(
                "{} vertices at ({}, {}, {}) with the index, {} triangles, {} critical lines",
                s.vertex_count(),
                s.a,
                s.b,
                s.measure,
                s.triangles.len(),
                s.lines.len()
            ),
            "the surface: its paths, critical points and lines".to_string(),
            format!(
                "{} against {}, coloured by index, critical lines drawn",
                s.measure, s.a
            ),
            "the same figure as an image".to_string(),
        ];
        let files = output::write_surface_with(
            out,
            s,
            &output::Scales::of(scene, &result.report),
            &output::caption_of(&result.report),
        )?;
        Ok(Described::each(files, what))
    }

    /// Its paths, their index ranges and critical lines, its warnings.
    fn summary(&self, result: &RunResult) -> Vec<String> {
        let Some(s) = result.outcome::<SurfaceReport>() else {
            return Vec::new();
        };
        let six = |x: f64| sig_digits(x, 6);
        let mut lines = vec![format!(
            "surface in ({}, {}): {} paths, {} vertices, {} triangles (path.csv is the first path, {} = {})",
            s.a,
            s.b,
            s.paths.len(),
            s.vertex_count(),
            s.triangles.len(),
            s.b,
            s.paths.first().map_or_else(String::new, |p| six(p.b))
        )];
        let a = s.parameter(&s.a);
        for p in &s.paths {
            let indices = p.vertices.iter().filter_map(|v| v.index);
            let range = indices.clone().min().zip(indices.max()).map_or_else(
                || "not computed".to_string(),
                |(lo, hi)| format!("{lo}..{hi}"),
            );
            lines.push(format!(
                "  {} = {}: {} points, index {range}, {} critical points; stopped: {}",
                s.b,
                six(p.b),
                p.vertices.len(),
                p.critical.len(),
                p.stop
            ));
        }
        for l in &s.lines {
            let ends = |i: usize| {
                let p = &l.points[i];
                let x = a.map_or_else(|| "?".to_string(), |a| six(p.parameters[a]));
                format!("{} = {}", s.a, x)
            };
            let (first, last) = (&l.points[0], &l.points[l.points.len() - 1]);
            lines.push(format!(
                "  critical line: {} in {} over {} paths, from {} at {} = {} to {} at {} = {}",
                l.kind,
                l.irrep,
                l.points.len(),
                ends(0),
                s.b,
                six(s.paths[first.path].b),
                ends(l.points.len() - 1),
                s.b,
                six(s.paths[last.path].b)
            ));
        }
        lines.extend(s.warnings.iter().map(|w| format!("warning: {w}")));
        lines
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stitching_uses_every_vertex_of_paths_of_different_lengths() {
        let a = [0.0, 0.5, 1.0];
        let b = [0.0, 0.1, 0.2, 0.6, 0.9, 1.0];
        let t = stitch(&a, 0, &b, 3);
        // A strip of n + m vertices closes with n + m − 2 triangles.
        assert_eq!(t.len(), a.len() + b.len() - 2);
        let mut used = [false; 9];
        for tri in &t {
            for &v in tri {
                used[v] = true;
            }
            // Every triangle has vertices on both paths.
            assert!(
                tri.iter().any(|&v| v < 3) && tri.iter().any(|&v| v >= 3),
                "{tri:?}"
            );
        }
        assert!(used.iter().all(|&u| u));
        // One vertex against three: a fan.
        assert_eq!(stitch(&[0.0], 0, &[0.0, 0.5, 1.0], 1).len(), 2);
        assert!(stitch(&[0.0], 0, &[0.0], 1).is_empty());
    }
}
