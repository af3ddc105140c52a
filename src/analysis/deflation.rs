//! `type = "deflation"`: the solutions at chosen control values besides a known one
//! (docs/theory.md §16). The path through the start is followed first, as `type = "path"`
//! follows it; then, at every value of `at` (the start's control value by default), from a
//! solution known there, deflated Newton ([`crate::continuation::deflation`]) is run from first
//! guesses that scale each known solution's displacement, with every known solution deflated;
//! each solution found is checked against the path (does the path through the start reach
//! it?) and, if asked, the piece of path through it is followed.

use super::path::{start_driver, trace_indexed, Path};
use super::{Analysis, Context, RunError};
use crate::continuation::crossings::Crossings;
use crate::continuation::deflation::{deflated_solve_at, scaled, Deflation};
use crate::continuation::{interrupt, solve_at, PathOptions};
use crate::output::{self, Described, OutputError};
use crate::results::deflation::{DeflationReport, PiecePoint, Solution};
use crate::results::{Outcome, PathRow, PointState, RunResult, StopReason};
use crate::scene::analyses::deflation::DeflationAnalysis;
use crate::scene::{PathAnalysis, Scene};
use crate::study::{Followed, Free, Point, Study};
use crate::text::sig_digits;
use nalgebra::DVector;
use std::path::Path as FilePath;

/// Two solutions closer than this (scaled units: a displacement's RMS over the mesh's
/// size) are one.
const SAME: f64 = 1e-6;

/// `type = "deflation"`.
pub struct Deflate(pub DeflationAnalysis);

impl Deflate {
    /// The path through the start, as `type = "path"` with the same settings.
    fn path(&self) -> Path {
        Path(PathAnalysis {
            control: self.0.control.clone(),
            stop_stretch: None,
            stop_displacement: None,
            branches: None,
            settings: self.0.settings.clone(),
        })
    }
}

impl Analysis for Deflate {
    fn options(&self, study: &dyn Study) -> PathOptions {
        self.path().options_of(study)
    }

    fn run(&self, study: &dyn Study, cx: &mut Context<'_>) -> Result<StopReason, RunError> {
        let stop = self.path().run(study, cx)?;
        let opts = self.options(study);
        let control = study.control().map(|c| c.index);
        let start = control.map_or(0.0, |c| cx.start.params[c]);
        let values = if self.0.at.is_empty() {
            vec![start]
        } else {
            self.0.at.clone()
        };
        let mut searches = Vec::new();
        for value in values {
            if interrupt::requested() {
                break;
            }
            match known_at(study, &opts, cx, value) {
                Ok((u, params)) => searches.push(search(&self.0, study, &opts, cx, &u, &params)),
                Err(why) => cx.record.warnings.push(format!(
                    "no deflation at {} = {}: {why}",
                    study.about().parameters[control.unwrap_or(0)],
                    sig_digits(value, 6)
                )),
            }
        }
        cx.record.outcome = Some(Outcome::new(searches));
        Ok(stop)
    }

    /// `deflation.json`, `deflation.csv`, `deflation.svg`.
    fn write(
        &self,
        result: &RunResult,
        _drawing: &dyn crate::output::Drawing,
        _scene: &Scene,
        out: &FilePath,
    ) -> Result<Vec<Described>, OutputError> {
        let Some(searches) = result.outcome::<Vec<DeflationReport>>() else {
            return Ok(Vec::new());
        };
        let files = output::write_deflation(out, searches, &result.report)?;
        let what = [
            format!(
                "the solutions of {} searches: state, index, whether the path reaches them, their pieces",
                searches.len()
            ),
            "every piece's points: solution, parameters, measures, index".to_string(),
            format!(
                "{} against {}: the path and every piece, stable solid",
                output::default_axes(&result.report).0,
                result.report.control
            ),
            "the same figure as an image".to_string(),
        ];
        Ok(Described::each(files, what))
    }

    fn summary(&self, result: &RunResult) -> Vec<String> {
        let Some(searches) = result.outcome::<Vec<DeflationReport>>() else {
            return Vec::new();
        };
        searches
            .iter()
            .flat_map(|d| summary_of(d, result))
            .collect()
    }
}

/// The summary lines of one search.
fn summary_of(d: &DeflationReport, result: &RunResult) -> Vec<String> {
    let mut lines = vec![format!(
        "deflation at {} = {}: {} solutions ({} first guesses)",
        d.control,
        sig_digits(d.value, 6),
        d.solutions.len(),
        d.guesses
    )];
    if !d.rejected.is_empty() {
        lines.push(format!(
            "  set aside: {} solutions of the equations that are no state of the membrane ({})",
            d.rejected.len(),
            d.rejected.join("; ")
        ));
    }
    // The measure of the path's diagram first.
    let first = output::default_axes(&result.report).0;
    let mut order: Vec<usize> = (0..d.measures.len()).collect();
    order.sort_by_key(|&i| d.measures[i] != first);
    for (k, s) in d.solutions.iter().enumerate() {
        let measures: Vec<String> = order
            .iter()
            .take(2)
            .map(|&i| format!("{} = {}", d.measures[i], sig_digits(s.measures[i], 6)))
            .collect();
        let index = s.negative.as_ref().map_or_else(
            || "index not computed".to_string(),
            |n| {
                let names: Vec<String> = d
                    .blocks
                    .iter()
                    .zip(n)
                    .filter(|(_, &c)| c > 0)
                    .map(|(b, c)| format!("{c} in {b}"))
                    .collect();
                if names.is_empty() {
                    "stable".to_string()
                } else {
                    format!("negative {}", names.join(", "))
                }
            },
        );
        let reach = match (k, s.on_path) {
            (0, _) => "the start state".to_string(),
            (_, Some(row)) => format!("on the path (row {row})"),
            (_, None) => "not reached by the path".to_string(),
        };
        let piece = match (&s.piece_stop, s.piece.len()) {
            (Some(stop), n) => format!("; its piece: {n} points, stopped: {stop}"),
            (None, _) => String::new(),
        };
        let wrinkled = match s.wrinkled {
            Some(n) if n > 0 => format!(
                "; wrinkled ({n} triangles with a negative principal tension: the membrane energy does not describe it)"
            ),
            _ => String::new(),
        };
        let stretch: String = s
            .flags
            .iter()
            .filter(|f| f.name() == "stretch")
            .map(|f| format!("; flagged: {f}"))
            .collect();
        lines.push(format!(
            "  solution {k}: {}; {index}; {reach}{piece}{wrinkled}{stretch}",
            measures.join(", ")
        ));
    }
    lines.extend(d.warnings.iter().map(|w| format!("warning: {w}")));
    lines
}

/// A solution at the control `value`: the start state at its own value; else the path's
/// state where its step first crosses the value (solved there from the row before); else the
/// start state carried to the value at fixed control.
fn known_at(
    study: &dyn Study,
    opts: &PathOptions,
    cx: &Context<'_>,
    value: f64,
) -> Result<(Vec<f64>, Vec<f64>), String> {
    let Some(c) = study.control().map(|c| c.index) else {
        return Ok((cx.start.u.clone(), cx.start.params.clone()));
    };
    if cx.start.params[c] == value {
        return Ok((cx.start.u.clone(), cx.start.params.clone()));
    }
    let free = Free {
        control: Some(c),
        constraints: true,
        ..Free::default()
    };
    if let Some((_, problem, q, l)) =
        path_states_at(study, cx.record.path(), opts, &free, value).next()
    {
        return Ok((problem.displacement(&q), problem.parameters(&l)));
    }
    super::surface::carry(study, opts, &cx.start.u, &cx.start.params, c, value)
}

/// Deflated Newton at the control value of the solution (u, params), from the first guesses
/// of every known solution in turn, until `solutions` are found or every guess is spent.
fn search(
    keys: &DeflationAnalysis,
    study: &dyn Study,
    opts: &PathOptions,
    cx: &mut Context<'_>,
    u0: &[f64],
    params0: &[f64],
) -> DeflationReport {
    let about = study.about();
    let control = study.control().map(|c| c.index);
    let params0 = params0.to_vec();
    let value = control.map_or(0.0, |c| params0[c]);
    let free = Free {
        control,
        constraints: true,
        ..Free::default()
    };
    let mut problem = study.problem(&params0, &free);
    let lambda0 = problem.free_values(&params0);
    let q0 = problem.coordinates(u0);
    let mut deflation = Deflation {
        roots: vec![scaled(&q0, &lambda0, opts)],
        power: keys.power,
        shift: keys.shift,
    };
    let z0 = scaled(&q0, &lambda0, opts);
    let mut known = vec![(q0, lambda0)];
    let mut crossings = cx.crossings.take();
    let negative = |c: &mut Option<Crossings>, u: &[f64], p: &[f64]| {
        c.as_mut()
            .and_then(|c| c.index(u, p))
            .map(|s| s.negatives())
    };
    let start = Solution {
        parameters: params0.clone(),
        measures: study.measure(u0, &params0),
        negative: negative(&mut crossings, u0, &params0),
        wrinkled: study.wrinkled(u0, &params0),
        flags: study.state_flags(u0, &params0),
        iterations: 0,
        distance: None,
        on_path: on_path(study, cx.record.path(), opts, &free, &z0, value).or((cx
            .start
            .u
            .as_slice()
            == u0)
            .then_some(0)),
        piece: Vec::new(),
        piece_stop: None,
    };
    let mut solutions = vec![start];
    let mut warnings = Vec::new();
    let mut rejected = Vec::new();
    let budget = (4 * opts.max_iterations).max(50);
    let mut guesses = 0usize;
    let mut next = 0usize;
    'search: while next < known.len() && solutions.len() <= keys.solutions {
        let (q, lambda) = known[next].clone();
        next += 1;
        // The first guesses: the state scaled, then moved along the path's tangent there (at a
        // fold, its mode: where the other piece of a broken pair lies), by each offset.
        let along = tangent_at(study, &problem, &q, &lambda, opts);
        let size = q.norm();
        let mut firsts: Vec<DVector<f64>> = keys.offsets.iter().map(|a| &q * (1.0 + a)).collect();
        if let Some(t) = &along {
            firsts.extend(keys.offsets.iter().map(|a| &q + t * (a * size)));
        }
        for guess in firsts {
            if solutions.len() > keys.solutions || interrupt::requested() {
                break 'search;
            }
            guesses += 1;
            let Ok((q1, l1, iterations)) = deflated_solve_at(
                &mut problem,
                &guess,
                &lambda,
                opts,
                &deflation,
                opts.max_step,
                budget,
            ) else {
                continue;
            };
            let z = scaled(&q1, &l1, opts);
            let distance = deflation.distance(&z);
            if distance <= SAME {
                continue;
            }
            // A solution of the equations that is no state of the membrane (inside out, or
            // stretched beyond the model's range) is deflated too, and set aside.
            if let Some(defect) = problem.defect(&q1, &l1) {
                rejected.push(defect.to_string());
                deflation.roots.push(z);
                continue;
            }
            let u = problem.displacement(&q1);
            let params = problem.parameters(&l1);
            solutions.push(Solution {
                measures: study.measure(&u, &params),
                negative: negative(&mut crossings, &u, &params),
                wrinkled: study.wrinkled(&u, &params),
                flags: study.state_flags(&u, &params),
                iterations,
                distance: Some(distance),
                on_path: on_path(study, cx.record.path(), opts, &free, &z, value),
                parameters: params,
                piece: Vec::new(),
                piece_stop: None,
            });
            deflation.roots.push(z);
            known.push((q1, l1));
        }
    }
    if keys.follow {
        // The known states are the solutions', in the same order.
        for (s, (q, _)) in solutions.iter_mut().zip(&known).skip(1) {
            if interrupt::requested() {
                break;
            }
            let point = Point {
                u: problem.displacement(q),
                params: s.parameters.clone(),
                iterations: 0,
                times: Default::default(),
            };
            match piece(study, &point, opts, &mut crossings) {
                Ok((points, stop)) => {
                    s.piece = points;
                    s.piece_stop = Some(stop);
                }
                Err(e) => warnings.push(format!("a piece could not be followed: {e}")),
            }
        }
    }
    cx.crossings = crossings;
    DeflationReport {
        control: about.parameters[control.unwrap_or(0)].clone(),
        value,
        parameters: about.parameters.clone(),
        measures: about.measures.clone(),
        blocks: cx.record.irreps.clone(),
        solutions,
        guesses,
        rejected,
        warnings,
    }
}

/// The unit state part of the path's tangent at (q, λ) (in the problem's coordinates), if
/// the path can be started there.
fn tangent_at(
    study: &dyn Study,
    problem: &dyn Followed,
    q: &DVector<f64>,
    lambda: &DVector<f64>,
    opts: &PathOptions,
) -> Option<DVector<f64>> {
    let point = Point {
        u: problem.displacement(q),
        params: problem.parameters(lambda),
        iterations: 0,
        times: Default::default(),
    };
    let driver = start_driver(study, &point, opts.clone()).ok()?;
    let t = driver.point().tangent.rows(0, q.len()).into_owned();
    let n = t.norm();
    (n > 0.0 && t.len() == q.len()).then(|| t / n)
}

/// The path's states at the control `value`: for every row whose step crosses it, the row
/// and the state there (q and the free parameters), solved at the value from the row's.
pub(super) fn path_states_at<'a>(
    study: &'a dyn Study,
    (rows, points): (&'a [PathRow], &'a [PointState]),
    opts: &'a PathOptions,
    free: &'a Free,
    value: f64,
) -> impl Iterator<Item = (usize, Box<dyn Followed + 'a>, DVector<f64>, DVector<f64>)> + 'a {
    let c = study.control().map(|c| c.index);
    (0..rows.len().saturating_sub(1)).filter_map(move |i| {
        let c = c?;
        let (a, b) = (
            rows[i].parameters[c] - value,
            rows[i + 1].parameters[c] - value,
        );
        if a * b > 0.0 {
            return None;
        }
        let mut params = rows[i].parameters.clone();
        params[c] = value;
        let mut problem = study.problem(&params, free);
        let lambda = problem.free_values(&params);
        let q = DVector::from_vec(points.get(i)?.q.clone());
        let (q, l, _) = solve_at(&mut problem, &q, &lambda, opts).ok()?;
        Some((i, problem, q, l))
    })
}

/// The row of the path whose step crosses the control value at the state `z`, if the path
/// reaches it: the path's state at the value is `z`.
pub(super) fn on_path(
    study: &dyn Study,
    path: (&[PathRow], &[PointState]),
    opts: &PathOptions,
    free: &Free,
    z: &DVector<f64>,
    value: f64,
) -> Option<usize> {
    path_states_at(study, path, opts, free, value)
        .find(|(_, _, q, l)| (scaled(q, l, opts) - z).norm() <= SAME.max(1e3 * opts.tolerance))
        .map(|(row, ..)| row)
}

/// The piece of path through `point` in the control, with the index at every point.
fn piece(
    study: &dyn Study,
    point: &Point,
    opts: &PathOptions,
    crossings: &mut Option<Crossings<'_>>,
) -> Result<(Vec<PiecePoint>, StopReason), RunError> {
    let mut driver = start_driver(study, point, opts.clone())?;
    let (branch, index) = trace_indexed(
        &mut driver,
        crossings,
        opts.max_steps,
        |_, _| None,
        |_, _| {},
    );
    let indices = index.map_or_else(|| vec![None; branch.points.len()], |ix| ix.indices);
    let problem = driver.into_problem();
    let points = branch
        .points
        .iter()
        .zip(indices)
        .map(|(p, index)| {
            let u = problem.displacement(&p.q);
            let parameters = problem.parameters(&p.lambda);
            PiecePoint {
                measures: study.measure(&u, &parameters),
                parameters,
                index,
            }
        })
        .collect();
    Ok((points, branch.stop))
}
