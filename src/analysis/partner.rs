//! The second piece beside a fold of the path (docs/theory.md §16.4): at an imperfect
//! bifurcation — one mode of a multiple point in the path's own fixed-point space, as cos 2θ
//! of a spinning cap's m = 2 double on a C2v mesh — the path turns at a fold, and the
//! solutions beyond it lie on a piece the path never reaches.
//!
//! Near such a fold the reduced equation is an imperfect pitchfork, λ x + x³ + ε = 0 in the
//! mode's amplitude x (signs aside): the path's piece has the fold at x = s = (ε/2)^(1/3), and
//! the other piece passes λ_f at x = −2s and goes on beyond it. On the plane of fixed amplitude
//! along the fold's mode the control is free, and each amplitude has one solution (λ = −x² −
//! ε/x): solves at growing amplitudes on both sides of the fold meet the other piece where
//! the control lies beyond the fold, which the path's own piece does not reach near it. From
//! there deflated Newton at the fold's control value, the fold's state deflated (a double
//! root there), gives the piece's state at λ_f — its distance from the fold's is the *gap*,
//! 3s in the normal form — and the piece is followed from it beyond the fold with its index
//! and its critical points, as the path is.

use super::deflation::{on_path, path_states_at};
use super::path::{measure_stops, record_branch, start_driver, trace_indexed};
use super::{Record, RunError};
use crate::continuation::crossings::Crossings;
use crate::continuation::deflation::{deflated_solve_at, scaled, Deflation};
use crate::continuation::near_miss::{beside_dip, dips};
use crate::continuation::{interrupt, solve_on_plane, Followed, PathOptions, PathPoint};
use crate::results::partner::{Partner, PartnerPiece};
use crate::results::{
    BranchRun, CriticalKind, CriticalPoint, PathRow, PointState, RunResult, RunTimes, StopReason,
};
use crate::study::{Free, Point, Study};
use nalgebra::DVector;

/// The fixed amplitudes tried on each side of a fold: h·2^k for k in [`FIRST`]..=[`LAST`],
/// h the path's step at the fold.
const FIRST: i32 = -3;
/// See [`FIRST`].
const LAST: i32 = 5;

/// Two states closer than this (scaled units) are one.
const SAME: f64 = 1e-6;

/// How each second piece is followed.
#[derive(Debug, Clone)]
pub struct Follow {
    /// Steps beyond the fold.
    pub steps: usize,
    /// Every `save_every`-th state is saved.
    pub save_every: usize,
    /// The path's stops on a measure (its index, the target and the reason, [`super::path::Path::limits`]):
    /// a piece stops where it passes the target from its start's side.
    pub limits: Vec<(usize, f64, StopReason)>,
}

/// The second piece beside every fold (limit point) among the `critical` points of the
/// `path` (its rows and their states) for which `which(k)` holds (k: the point's index),
/// each followed as `follow` says, with the index by blocks where `crossings` has them.
pub fn partners(
    study: &dyn Study,
    opts: &PathOptions,
    path: (&[PathRow], &[PointState]),
    critical: &[CriticalPoint],
    crossings: &mut Option<Crossings<'_>>,
    follow: &Follow,
    which: &dyn Fn(usize) -> bool,
) -> Vec<Partner> {
    let Some(c) = study.control().map(|c| c.index) else {
        return Vec::new();
    };
    let mut found: Vec<Partner> = Vec::new();
    for (k, cp) in critical.iter().enumerate() {
        if cp.kind != CriticalKind::LimitPoint || !which(k) {
            continue;
        }
        if interrupt::requested() {
            break;
        }
        let pieces = found.iter().filter(|p| p.piece.is_some()).count();
        let search = Search::new(study, opts, path, c, follow, pieces + 1);
        found.push(search.at(crossings, k + 1, cp));
    }
    found
}

/// The second piece beside every dip of the path (docs/theory.md §16.7): a clear local
/// minimum of the |eigenvalue| nearest zero of the path's own (trivial) block with no change
/// of its negative count, whose mode has a wave number m ≥ 1 — a double broken into the
/// path's block that the path passes without a fold. Beside each, solves at fixed amplitude
/// along the mode ([`beside_dip`]) seek a state the path does not have, with the control
/// within the path's range, and the piece through it is followed towards the dip's control
/// (where its fold lies) as `follow` says; its directories are numbered from `first`.
pub fn near_misses(
    study: &dyn Study,
    opts: &PathOptions,
    path: (&[PathRow], &[PointState]),
    crossings: &mut Option<Crossings<'_>>,
    follow: &Follow,
    first: usize,
) -> Vec<Partner> {
    let (rows, points) = path;
    let Some(c) = study.control().map(|c| c.index) else {
        return Vec::new();
    };
    let Some(cr) = crossings.as_mut() else {
        return Vec::new();
    };
    if rows.len() < 3 || points.len() < rows.len() {
        return Vec::new();
    }
    let free = Free::path(Some(c));
    let displacer = study.problem(&rows[0].parameters, &free);
    let mut sigma = Vec::with_capacity(rows.len());
    let mut negatives = Vec::with_capacity(rows.len());
    for (row, point) in rows.iter().zip(points) {
        if interrupt::requested() {
            return Vec::new();
        }
        let u = displacer.displacement(&DVector::from_vec(point.q.clone()));
        match cr.nearest_zero(&u, &row.parameters, 0, false, row.step) {
            Some((s, n, _)) => {
                sigma.push(s);
                negatives.push(n);
            }
            None => {
                sigma.push(f64::NAN);
                negatives.push(usize::MAX);
            }
        }
    }
    drop(displacer);
    let (lo, hi) = rows
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), r| {
            (lo.min(r.parameters[c]), hi.max(r.parameters[c]))
        });
    let mut found: Vec<Partner> = Vec::new();
    for k in dips(&sigma, &negatives) {
        if interrupt::requested() {
            break;
        }
        let row = &rows[k];
        let problem = study.problem(&row.parameters, &free);
        let u = problem.displacement(&DVector::from_vec(points[k].q.clone()));
        drop(problem);
        let Some((_, _, Some(mode))) = crossings
            .as_mut()
            .and_then(|cr| cr.nearest_zero(&u, &row.parameters, 0, true, k))
        else {
            continue;
        };
        if study.wave_number(&mode).is_none_or(|m| m == 0) {
            continue;
        }
        let pieces = found.iter().filter(|p| p.piece.is_some()).count();
        let search = Search::new(study, opts, path, c, follow, first + pieces);
        found.push(search.at_dip(crossings, k, &u, &mode, (lo, hi), &free));
    }
    found
}

/// One fold's search: the study, the path it lies on, the control and how a piece is
/// followed and named.
struct Search<'s> {
    study: &'s dyn Study,
    opts: &'s PathOptions,
    path: (&'s [PathRow], &'s [PointState]),
    c: usize,
    follow: Follow,
    directory: String,
}

impl<'s> Search<'s> {
    /// The search for the `number`-th second piece (1-based: its directory
    /// `partner_NN`) beside the `path` in control `c`.
    fn new(
        study: &'s dyn Study,
        opts: &'s PathOptions,
        path: (&'s [PathRow], &'s [PointState]),
        c: usize,
        follow: &Follow,
        number: usize,
    ) -> Self {
        Self {
            study,
            opts,
            path,
            c,
            follow: follow.clone(),
            directory: format!("partner_{number:02}"),
        }
    }

    /// The search beside the fold `cp`, critical point `number` of the path.
    fn at(
        &self,
        crossings: &mut Option<Crossings<'_>>,
        number: usize,
        cp: &CriticalPoint,
    ) -> Partner {
        let (study, opts, c) = (self.study, self.opts, self.c);
        let value = cp.parameters[c];
        let mut partner = Partner {
            fold: number,
            dip: None,
            value,
            tried: 0,
            piece: None,
            note: None,
        };
        // A fold in a wrinkled state is no result of the membrane energy (docs/theory.md
        // §8.10): nothing is sought beside it.
        if let Some(n) = study.wrinkled(&cp.state, &cp.parameters).filter(|&n| n > 0) {
            partner.note = Some(format!(
                "not sought: the fold's state is wrinkled ({n} triangles with a negative \
                 principal tension), where the membrane energy does not describe it"
            ));
            return partner;
        }
        // The path arrives from one side of the fold; the other piece is met on the other.
        let rows = self.path.0;
        let before = rows.get(cp.after_step).map(|r| r.parameters[c]);
        let beyond = match before {
            Some(b) if b != value => (value - b).signum(),
            _ => {
                partner.note = Some("the path's side of the fold is not known".into());
                return partner;
            }
        };
        // The step of the path at the fold sets the amplitudes' scale.
        let h = match (rows.get(cp.after_step), rows.get(cp.after_step + 1)) {
            (Some(a), Some(b)) if b.arclength > a.arclength => b.arclength - a.arclength,
            _ => opts.initial_step,
        };
        let (from, mut problem) = match solved_again(study, &cp.state, &cp.parameters, opts) {
            Ok(again) => again,
            Err(e) => {
                partner.note = Some(format!("the fold's state could not be solved again: {e}"));
                return partner;
            }
        };
        // The fold's mode: the state part of its tangent (the control's part vanishes there).
        let m = from.q.len();
        let mut phi = DVector::zeros(from.tangent.len());
        phi.rows_mut(0, m).copy_from(&from.tangent.rows(0, m));
        let norm = phi.norm();
        if norm == 0.0 || !norm.is_finite() {
            partner.note = Some("the fold's tangent has no state part".into());
            return partner;
        }
        phi /= norm;
        let z_fold = scaled(&from.q, &from.lambda, opts);
        let deflation = Deflation {
            roots: vec![z_fold.clone()],
            power: 2.0,
            shift: 1.0,
        };
        let budget = (4 * opts.max_iterations).max(50);
        let free = Free {
            control: Some(c),
            constraints: true,
            ..Free::default()
        };
        for sign in [1.0, -1.0] {
            let direction = &phi * sign;
            for k in FIRST..=LAST {
                if interrupt::requested() {
                    return partner;
                }
                let s = h * 2f64.powi(k);
                partner.tried += 1;
                let Ok(p) = solve_on_plane(&mut *problem, &from, &direction, &phi, s, opts) else {
                    continue;
                };
                // On the path's side of the fold: the path's own piece (or not told apart).
                if problem.defect(&p.q, &p.lambda).is_some()
                    || (p.lambda[0] - value) * beyond <= 0.0
                {
                    continue;
                }
                let mut lambda = p.lambda.clone();
                lambda[0] = value;
                let Ok((q, l, _)) = deflated_solve_at(
                    &mut *problem,
                    &p.q,
                    &lambda,
                    opts,
                    &deflation,
                    opts.max_step,
                    budget,
                ) else {
                    continue;
                };
                let z = scaled(&q, &l, opts);
                if (&z - &z_fold).norm() <= SAME
                    || problem.defect(&q, &l).is_some()
                    || on_path(study, self.path, opts, &free, &z, value).is_some()
                {
                    continue;
                }
                let u = problem.displacement(&q);
                let gap = rms_difference(&u, &cp.state);
                let start = Point {
                    u,
                    params: problem.parameters(&l),
                    iterations: 0,
                    times: Default::default(),
                };
                match self.piece(crossings, &start, beyond) {
                    Ok(run) => {
                        partner.piece = Some(PartnerPiece {
                            amplitude: sign * s,
                            gap,
                            run,
                        })
                    }
                    Err(e) => {
                        partner.note = Some(format!(
                            "a second piece lies at an RMS distance {gap:.4e} from the fold, \
                             but it could not be followed: {e}"
                        ))
                    }
                }
                return partner;
            }
        }
        partner.note = Some(format!(
            "no second piece: the {} fixed-amplitude solves on both sides of the fold met the \
             path's own piece or did not converge (a fold of the path alone)",
            partner.tried
        ));
        partner
    }

    /// The search beside the dip at row `k` of the path (state `u`, its mode carried by
    /// `dip` as a critical point's), accepting states whose control lies in `range`.
    fn at_dip(
        &self,
        crossings: &mut Option<Crossings<'_>>,
        k: usize,
        u: &[f64],
        dip: &CriticalPoint,
        range: (f64, f64),
        free: &Free,
    ) -> Partner {
        let (study, opts, c) = (self.study, self.opts, self.c);
        let rows = self.path.0;
        let value = rows[k].parameters[c];
        let mut partner = Partner {
            fold: 0,
            dip: Some(k),
            value,
            tried: 0,
            piece: None,
            note: None,
        };
        // The path's direction in the control there: the piece's fold lies ahead.
        let ahead = (rows[k + 1].parameters[c] - rows[k - 1].parameters[c]).signum();
        if ahead == 0.0 || !ahead.is_finite() {
            partner.note = Some("the path's direction at the dip is not known".into());
            return partner;
        }
        let h = rows[k + 1].arclength - rows[k].arclength;
        let h = if h > 0.0 { h } else { opts.initial_step };
        let (from, mut problem) = match solved_again(study, u, &rows[k].parameters, opts) {
            Ok(again) => again,
            Err(e) => {
                partner.note = Some(format!("the dip's state could not be solved again: {e}"));
                return partner;
            }
        };
        let m = from.q.len();
        let q_mode = problem.coordinates(&dip.mode);
        let mut phi = DVector::zeros(from.tangent.len());
        if q_mode.len() != m {
            partner.note = Some("the dip's mode is not over the path's unknowns".into());
            return partner;
        }
        phi.rows_mut(0, m).copy_from(&q_mode);
        let norm = phi.norm();
        if norm == 0.0 || !norm.is_finite() {
            partner.note = Some("the dip's mode vanishes on the path's unknowns".into());
            return partner;
        }
        phi /= norm;
        let mut accept = |problem: &mut Box<dyn crate::continuation::Followed + '_>,
                          p: &crate::continuation::PathPoint| {
            let l = p.lambda[0];
            let z = scaled(&p.q, &p.lambda, opts);
            let _ = problem;
            (range.0..=range.1).contains(&l)
                && on_path(study, self.path, opts, free, &z, l).is_none()
        };
        let beside = beside_dip(&mut problem, &from, &phi, h, opts, &mut accept);
        partner.tried = beside.tried;
        let Some((p, amplitude)) = beside.found else {
            partner.note = Some(format!(
                "no second piece: the {} fixed-amplitude solves on both sides of the dip met \
                 the path's own piece, left the path's range or did not converge",
                partner.tried
            ));
            return partner;
        };
        let piece_u = problem.displacement(&p.q);
        let params = problem.parameters(&p.lambda);
        drop(problem);
        // The gap: to the path's state at the piece's first control value.
        let gap = path_states_at(study, self.path, opts, free, p.lambda[0])
            .map(|(_, problem, q, _)| rms_difference(&piece_u, &problem.displacement(&q)))
            .fold(f64::INFINITY, f64::min);
        let start = Point {
            u: piece_u,
            params,
            iterations: 0,
            times: Default::default(),
        };
        match self.piece(crossings, &start, -ahead) {
            Ok(run) if gap.is_finite() => {
                partner.piece = Some(PartnerPiece {
                    amplitude,
                    gap,
                    run,
                })
            }
            Ok(_) => {
                partner.note = Some(
                    "a second piece was met, but the path's state at its control could not \
                     be solved for the gap"
                        .into(),
                )
            }
            Err(e) => {
                partner.note = Some(format!(
                    "a second piece was met beside the dip, but it could not be followed: {e}"
                ))
            }
        }
        partner
    }

    /// The piece through `start` (at the fold's control value), followed in the direction
    /// `beyond` of the control with its index and critical points.
    fn piece(
        &self,
        crossings: &mut Option<Crossings<'_>>,
        start: &Point,
        beyond: f64,
    ) -> Result<BranchRun, RunError> {
        let study = self.study;
        let steps = self.follow.steps;
        let o = PathOptions {
            direction: beyond,
            max_steps: steps,
            ..self.opts.clone()
        };
        let mut driver = start_driver(study, start, o)?;
        let stops = measure_stops(study, &self.follow.limits, start);
        let (branch, index) = trace_indexed(&mut driver, crossings, steps, stops, |_, _| {});
        let mut record = Record::new(study);
        let (indices, negatives) = match index {
            Some(ix) => {
                record.irreps = ix.irreps;
                (ix.indices, ix.negatives)
            }
            None => (vec![None; branch.points.len()], Vec::new()),
        };
        let problem = driver.into_problem();
        record_branch(
            study,
            &mut record,
            &*problem,
            &branch,
            &indices,
            self.follow.save_every,
        );
        for (row, negative) in record.rows.iter_mut().zip(negatives) {
            row.negative = negative;
        }
        let mut result = record.finish(study, branch.stop, None, RunTimes::default());
        study.annotate(&mut result);
        Ok(BranchRun {
            report: result.report,
            states: result.states,
            directory: self.directory.clone(),
        })
    }
}

/// The root mean square over the nodes of the difference of two displacements (three
/// components a node): a distance between states that does not grow with the mesh.
fn rms_difference(a: &[f64], b: &[f64]) -> f64 {
    let nodes = (a.len() / 3).max(1) as f64;
    let sum: f64 = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum();
    (sum / nodes).sqrt()
}

/// The second pieces beside the folds of a finished `result` of `study` for which
/// `which(k)` holds (k: the fold's index among the critical points), as [`partners`] finds
/// them, with the study's blocks for the index: what `compare` seeks at an imperfect fold.
pub fn partners_of_run(
    study: &dyn Study,
    result: &RunResult,
    follow: Follow,
    which: &dyn Fn(usize) -> bool,
) -> Vec<Partner> {
    let opts = super::analysis_of(&study.scene().analysis).options(study);
    let follow = Follow {
        limits: super::path_of(&study.scene().analysis).map_or_else(Vec::new, |p| p.limits(study)),
        ..follow
    };
    let measure = |u: &[f64], p: &[f64]| study.measure(u, p);
    let control = study.control().map(|c| c.index);
    let mut crossings = study
        .blocks()
        .ok()
        .map(|b| Crossings::new(b, &measure, control, false));
    partners(
        study,
        &opts,
        (&result.report.rows, &result.points),
        &result.report.critical,
        &mut crossings,
        &follow,
        which,
    )
}

/// The state (u, params) of the path solved again as the first point of a path: that point,
/// with its tangent, and the problem it was solved in.
fn solved_again<'a>(
    study: &'a dyn Study,
    u: &[f64],
    params: &[f64],
    opts: &PathOptions,
) -> Result<(PathPoint, Box<dyn Followed + 'a>), RunError> {
    let at = Point {
        u: u.to_vec(),
        params: params.to_vec(),
        iterations: 0,
        times: Default::default(),
    };
    let driver = start_driver(study, &at, opts.clone())?;
    let from = driver.point().clone();
    Ok((from, driver.into_problem()))
}
