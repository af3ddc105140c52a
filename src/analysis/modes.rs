//! Stability by wave number (docs/theory.md §15.3): paths of a problem whose second
//! variation splits into blocks indexed by a wave number m = 0..M, each block standing for
//! `multiplicity(m)` identical copies in the full problem (a Fourier pair for m ≥ 1). The
//! index of every block is the number of its negative pivots (Sylvester's law on a sparse
//! LBLᵀ); where it changes between two points of the path, the crossing is localised on the
//! arclength by [`locate`] on the block's eigenvalue nearest zero and classified as in 3-D
//! (docs/theory.md §11.3): m = 0 a limit point where the control turns, else a symmetric
//! bifurcation; m ≥ 1 a bifurcation of the block's multiplicity.
//!
//! The analysis knows blocks and wave numbers only, not what makes them: any
//! [`ModeProblem`] is followed.

use crate::continuation::events::{locate, Detector, Event};
use crate::continuation::{Accepted, Continuation, PathOptions, PathPoint, Problem, SolveError};
use crate::linalg::eigen::shift_invert;
use crate::linalg::{FactorError, SymmetricFactorization, SymmetricPattern};
use crate::model::ModelError;
use crate::results::{CriticalKind, Extremum, StopReason};
use nalgebra::DVector;
use rayon::prelude::*;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Relative size of the localised eigenvalue below which it counts as zero.
const ZERO_EIGENVALUE: f64 = 1e-10;

/// A symmetric block: its pattern and its values aligned with the pattern's row indices.
pub type ModeBlock = (Arc<SymmetricPattern>, Vec<f64>);

/// A [`Problem`] whose second variation splits by wave number.
pub trait ModeProblem: Problem {
    /// The largest wave number M analysed.
    fn modes(&self) -> usize;
    /// How many copies of block m the full problem holds (1 for m = 0, 2 for m ≥ 1).
    fn multiplicity(&self, m: usize) -> usize {
        if m == 0 {
            1
        } else {
            2
        }
    }
    /// How many border columns (held motions, constraints) the block of wave number m
    /// carries after the block proper: its index is the bordered matrix's negative count
    /// less this (Haynsworth, docs/theory.md §8.3 and §15.12). None by default.
    fn border(&self, _m: usize) -> usize {
        0
    }
    /// The symmetric block of wave number m at (q, λ).
    fn block(
        &mut self,
        m: usize,
        q: &DVector<f64>,
        lambda: &DVector<f64>,
    ) -> Result<(Arc<SymmetricPattern>, Vec<f64>), ModelError>;
    /// The blocks of every wave number m = 0..=M at (q, λ), in order (by default one
    /// [`Self::block`] each; a problem that shares work between them says so here).
    fn blocks(
        &mut self,
        q: &DVector<f64>,
        lambda: &DVector<f64>,
    ) -> Result<Vec<ModeBlock>, ModelError> {
        (0..=self.modes())
            .map(|m| self.block(m, q, lambda))
            .collect()
    }
}

/// A critical point of a path by wave number.
#[derive(Debug, Clone, PartialEq)]
pub struct ModeCritical {
    /// The wave number m.
    pub m: usize,
    /// Its multiplicity in the full problem.
    pub multiplicity: usize,
    /// The kind (docs/theory.md §11.3).
    pub kind: CriticalKind,
    /// The index of the accepted point before it.
    pub after_step: usize,
    /// The free parameters there (the control first).
    pub lambda: Vec<f64>,
    /// The displacement there.
    pub q: Vec<f64>,
    /// The eigenvalue of the block there, relative to the block's largest entry.
    pub eigenvalue: f64,
    /// Whether the crossing was localised (else the later point is reported).
    pub localised: bool,
}

/// A turning point of the control.
#[derive(Debug, Clone, PartialEq)]
pub struct ModeTurning {
    /// Maximum or minimum.
    pub kind: Extremum,
    /// The index of the accepted point before it.
    pub after_step: usize,
    /// The free parameters there.
    pub lambda: Vec<f64>,
    /// The displacement there.
    pub q: Vec<f64>,
}

/// A path with its index by wave number.
#[derive(Debug, Clone)]
pub struct ModePath {
    /// The accepted points.
    pub points: Vec<PathPoint>,
    /// The index (negative count) of every block m = 0..=M at every point (None where a
    /// block could not be evaluated).
    pub index: Vec<Option<Vec<usize>>>,
    /// Turning points of the control.
    pub turning: Vec<ModeTurning>,
    /// Critical points, in path order.
    pub critical: Vec<ModeCritical>,
    /// Why the path ended.
    pub stop: StopReason,
    /// What could not be settled.
    pub warnings: Vec<String>,
    /// Time spent on the blocks (assembly, factorisation, localisation).
    pub block_time: Duration,
}

/// The negative count of a block and a reusable factorisation.
fn negatives(
    cache: &mut Option<SymmetricFactorization>,
    pattern: &SymmetricPattern,
    values: &[f64],
) -> Option<usize> {
    if cache
        .as_ref()
        .is_none_or(|f| f.n() != pattern.n() || f.pattern().nnz() != pattern.nnz())
    {
        *cache = Some(SymmetricFactorization::new(pattern).ok()?);
    }
    let f = cache.as_mut()?;
    match f.factorize(values) {
        Ok(()) | Err(FactorError::Singular { .. }) => f.inertia().map(|i| i.negative),
        Err(_) => None,
    }
}

/// The eigenvalue of a block nearest zero, relative to its largest entry.
fn nearest_zero(pattern: &SymmetricPattern, values: &[f64]) -> Option<f64> {
    let scale = values
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()))
        .max(1e-300);
    let near = shift_invert(pattern, values, 0.0, 2).ok()?;
    near.values
        .iter()
        .min_by(|a, b| a.abs().total_cmp(&b.abs()))
        .map(|v| v / scale)
}

/// The index of every block, and the detector that localises its changes.
struct ModeIndex {
    caches: Vec<Option<SymmetricFactorization>>,
    index: Vec<Option<Vec<usize>>>,
    critical: Vec<ModeCritical>,
    warnings: Vec<String>,
    time: Duration,
}

impl ModeIndex {
    fn at<P: ModeProblem>(&mut self, problem: &mut P, p: &PathPoint) -> Option<Vec<usize>> {
        let t = Instant::now();
        let mut out = Vec::with_capacity(problem.modes() + 1);
        let borders: Vec<usize> = (0..=problem.modes()).map(|m| problem.border(m)).collect();
        let Ok(blocks) = problem.blocks(&p.q, &p.lambda) else {
            self.time += t.elapsed();
            return None;
        };
        // The blocks are independent: their factorisations run side by side.
        let counts: Vec<Option<usize>> = self
            .caches
            .par_iter_mut()
            .zip(blocks.par_iter())
            .map(|(cache, (pattern, values))| negatives(cache, pattern, values))
            .collect();
        for (neg, border) in counts.into_iter().zip(borders) {
            let Some(neg) = neg else {
                self.time += t.elapsed();
                return None;
            };
            out.push(neg.saturating_sub(border));
        }
        self.time += t.elapsed();
        Some(out)
    }
}

impl<P: ModeProblem> Detector<P> for ModeIndex {
    fn start(&mut self, driver: &mut Continuation<P>) -> Vec<Event> {
        let p = driver.point().clone();
        let ix = self.at(driver.problem_mut(), &p);
        self.index.push(ix);
        Vec::new()
    }

    fn check(&mut self, driver: &mut Continuation<P>, step: &Accepted, after: usize) -> Vec<Event> {
        let p = driver.point().clone();
        let now = self.at(driver.problem_mut(), &p);
        let before = self.index.last().cloned().flatten();
        self.index.push(now.clone());
        let (Some(before), Some(now)) = (before, now) else {
            return Vec::new();
        };
        let k = driver.problem().dim();
        let turns = step.from.tangent[k].signum() != p.tangent[k].signum();
        let t = Instant::now();
        for m in 0..before.len() {
            if before[m] == now[m] {
                continue;
            }
            let multiplicity = driver.problem().multiplicity(m);
            let kind = CriticalKind::of(m == 0, multiplicity, !turns);
            // A fold (m = 0 where the control turns) is where the control's tangent
            // component vanishes, K being singular exactly there; elsewhere the block's
            // eigenvalue nearest zero crosses.
            let fold = m == 0 && turns;
            // The ends are the accepted points themselves (no corrector at s = 0 or the step).
            let at_point = |problem: &mut P, x: &PathPoint| -> Option<f64> {
                if fold {
                    return Some(x.tangent[k]);
                }
                let (pattern, values) = problem.block(m, &x.q, &x.lambda).ok()?;
                nearest_zero(&pattern, &values)
            };
            let g0 = at_point(driver.problem_mut(), &step.from);
            let g1 = at_point(driver.problem_mut(), &p);
            let mut g = |s: f64| -> Option<f64> {
                let x = driver.step_from(&step.from, s).ok()?;
                if fold {
                    return Some(x.tangent[k]);
                }
                let (pattern, values) = driver.problem_mut().block(m, &x.q, &x.lambda).ok()?;
                nearest_zero(&pattern, &values)
            };
            let ends = g0.zip(g1);
            let found = ends
                .filter(|(g0, g1)| g0.signum() != g1.signum())
                .and_then(|(g0, g1)| locate(&mut g, g0, step.step, g1, ZERO_EIGENVALUE))
                .and_then(|(s, gs)| Some((driver.step_from(&step.from, s).ok()?, gs)));
            let (x, eigenvalue, localised) = match found {
                Some((x, gs)) if fold => {
                    let (pattern, values) =
                        driver.problem_mut().block(m, &x.q, &x.lambda).ok().unzip();
                    let e = pattern
                        .zip(values)
                        .and_then(|(p, v)| nearest_zero(&p, &v))
                        .unwrap_or(gs);
                    (x, e, true)
                }
                Some((x, gs)) => (x, gs, true),
                None => {
                    self.warnings.push(format!(
                        "the index of wave number {m} changed ({} → {}) after step {after} but the crossing was not localised; the later point is reported",
                        before[m], now[m]
                    ));
                    (p.clone(), f64::NAN, false)
                }
            };
            self.critical.push(ModeCritical {
                m,
                multiplicity,
                kind,
                after_step: after,
                lambda: x.lambda.iter().copied().collect(),
                q: x.q.iter().copied().collect(),
                eigenvalue,
                localised,
            });
        }
        self.time += t.elapsed();
        Vec::new()
    }
}

/// Follows the path of `problem` from (q0, λ0) with the index of every block at every point
/// and the critical points where it changes, the turning points of the control, and `stop`
/// besides the bounds and the step budget.
pub fn follow<P: ModeProblem>(
    problem: P,
    q0: &DVector<f64>,
    lambda0: &DVector<f64>,
    opts: PathOptions,
    stop: impl FnMut(&P, &PathPoint) -> Option<StopReason>,
    progress: impl FnMut(&P, &PathPoint),
) -> Result<(ModePath, P), SolveError> {
    let max_steps = opts.max_steps;
    let mut driver = Continuation::start(problem, q0, lambda0, opts)?;
    let mut ix = ModeIndex {
        caches: (0..=driver.problem().modes()).map(|_| None).collect(),
        index: Vec::new(),
        critical: Vec::new(),
        warnings: Vec::new(),
        time: Duration::ZERO,
    };
    let branch = {
        let mut extra: Vec<&mut dyn Detector<P>> = vec![&mut ix];
        crate::continuation::events::trace(&mut driver, max_steps, stop, &mut extra, progress)
    };
    let turning = branch
        .turning_points()
        .filter(|t| t.parameter == 0)
        .map(|t| ModeTurning {
            kind: t.kind,
            after_step: t.after_step,
            lambda: t.point.lambda.iter().copied().collect(),
            q: t.point.q.iter().copied().collect(),
        })
        .collect();
    let mut warnings = ix.warnings;
    warnings.extend(branch.events.iter().filter_map(|e| match e {
        Event::Warning(w) => Some(w.clone()),
        _ => None,
    }));
    Ok((
        ModePath {
            points: branch.points,
            index: ix.index,
            turning,
            critical: ix.critical,
            stop: branch.stop,
            warnings,
            block_time: ix.time,
        },
        driver.into_problem(),
    ))
}

/// A held state (q, λ with its control swept over `[min, max]` in `samples` steps): the
/// index of every block at every sample, and the control values where it changes,
/// localised by [`locate`] on the control (linear buckling).
pub fn sweep<P: ModeProblem>(
    problem: &mut P,
    q: &DVector<f64>,
    lambda: &DVector<f64>,
    range: (f64, f64),
    samples: usize,
) -> ModePath {
    let t = Instant::now();
    let samples = samples.max(1);
    let at = |c: f64| {
        let mut l = lambda.clone();
        l[0] = c;
        l
    };
    let mut caches: Vec<Option<SymmetricFactorization>> =
        (0..=problem.modes()).map(|_| None).collect();
    let mut points = Vec::new();
    let mut index: Vec<Option<Vec<usize>>> = Vec::new();
    let mut critical = Vec::new();
    let mut warnings = Vec::new();
    let tangent = DVector::zeros(q.len() + lambda.len());
    for i in 0..=samples {
        let c = range.0 + (range.1 - range.0) * i as f64 / samples as f64;
        let l = at(c);
        let ix: Option<Vec<usize>> = problem.blocks(q, &l).ok().and_then(|blocks| {
            blocks
                .iter()
                .enumerate()
                .map(|(m, (pattern, values))| {
                    negatives(&mut caches[m], pattern, values)
                        .map(|n| n.saturating_sub(problem.border(m)))
                })
                .collect()
        });
        if let (Some(Some(before)), Some(now)) = (index.last(), ix.as_ref()) {
            let c0 = points.last().map_or(c, |p: &PathPoint| p.lambda[0]);
            for m in 0..before.len() {
                if before[m] == now[m] {
                    continue;
                }
                let mut g = |s: f64| -> Option<f64> {
                    let (pattern, values) = problem.block(m, q, &at(c0 + s)).ok()?;
                    nearest_zero(&pattern, &values)
                };
                let found = g(0.0)
                    .zip(g(c - c0))
                    .filter(|(g0, g1)| g0.signum() != g1.signum())
                    // On a held state a block evaluation is cheap and exact in the control:
                    // localise to round-off (a relative eigenvalue of 1e-10 would leave the
                    // control uncertain by ~1e-5 where the load block is weak).
                    .and_then(|(g0, g1)| locate(&mut g, g0, c - c0, g1, 0.0));
                let (value, eigenvalue, localised) = match found {
                    Some((s, gs)) => (c0 + s, gs, true),
                    None => {
                        warnings.push(format!(
                            "the index of wave number {m} changed between samples {} and {i} but the crossing was not localised",
                            i - 1
                        ));
                        (c, f64::NAN, false)
                    }
                };
                let mut lam: Vec<f64> = lambda.iter().copied().collect();
                lam[0] = value;
                critical.push(ModeCritical {
                    m,
                    multiplicity: problem.multiplicity(m),
                    kind: CriticalKind::of(m == 0, problem.multiplicity(m), true),
                    after_step: i - 1,
                    lambda: lam,
                    q: q.iter().copied().collect(),
                    eigenvalue,
                    localised,
                });
            }
        }
        index.push(ix);
        points.push(PathPoint {
            q: q.clone(),
            lambda: l,
            tangent: tangent.clone(),
            arclength: c - range.0,
            iterations: 0,
        });
    }
    critical.sort_by(|a, b| {
        a.after_step
            .cmp(&b.after_step)
            .then(a.lambda[0].total_cmp(&b.lambda[0]))
    });
    ModePath {
        points,
        index,
        turning: Vec::new(),
        critical,
        stop: StopReason::Swept {
            min: range.0,
            max: range.1,
            samples,
        },
        warnings,
        block_time: t.elapsed(),
    }
}
