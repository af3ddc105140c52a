//! Generalised pseudo-arclength path following for a small dense problem — here the
//! fixed-point space of the scene's group (see [`crate::adapted`]) — in several parameters
//! (DESIGN §2.6).
//!
//! Unknowns y = (q, λ) with q ∈ ℝ^m and the free parameters λ ∈ ℝ^{c+1}; equations
//! R(q, λ) = 0 (m) and c augmenting equations g(q, λ) = 0 (fixed fluid volume, fixed amount
//! of gas …); λ_0 is the control parameter. From a point y_k with unit tangent t_k, the
//! predictor is y_k + s t_k and the corrector solves, by Newton,
//!
//! ```text
//!   R = 0,  g = 0,  t_kᵀ (y − y_k) − s = 0,     J = [[K, L], [G_q, G_λ], [t_kᵀ]],
//! ```
//!
//! with K = ∂R/∂q, L = ∂R/∂λ, G = ∂g/∂(q, λ). The new tangent is the null vector of the
//! first m + c rows, found from J t = [0, …, 0, 1], normalised and oriented by continuity
//! (t·t_k > 0), so limit points and snap-backs are passed, not stopped at. q and λ_j are
//! measured in units of `state_scale` and `parameter_scales[j]` in the arclength.
//! A corrector that does not converge halves the step; below `min_step` the path stops
//! with a report of where and why. Turning points of λ (sign changes of t_λ) are localised
//! by a secant search on the step length until t_λ vanishes.

use crate::linalg::SymmetricPattern;
use crate::model::ModelError;
use faer::sparse::{SparseColMat, Triplet};
use nalgebra::{DMatrix, DVector};
use std::sync::Arc;

/// Largest distance, in steps, between the converged point and the predictor.
const MAX_CORRECTOR_DISTANCE: f64 = 0.5;
/// Smallest cosine between consecutive tangents (about 35°).
const MIN_TANGENT_COSINE: f64 = 0.8;

/// A dense problem R(q, λ), g(q, λ) with its derivatives.
pub trait DenseProblem {
    /// Dimension m of q.
    fn dim(&self) -> usize;
    /// Number of free parameters (augmenting equations + 1).
    fn free_parameters(&self) -> usize;
    /// R, g and their derivatives at (q, λ).
    fn evaluate(
        &mut self,
        q: &DVector<f64>,
        lambda: &DVector<f64>,
    ) -> Result<Linearization, ModelError>;
}

/// R, K, L and the augmenting equations at a point.
#[derive(Debug, Clone)]
pub struct Linearization {
    /// R(q, λ) (m).
    pub residual: DVector<f64>,
    /// ∂R/∂q (m × m, symmetric).
    pub tangent: Tangent,
    /// ∂R/∂λ (m × (c+1)).
    pub loads: DMatrix<f64>,
    /// g(q, λ) (c).
    pub constraints: DVector<f64>,
    /// ∂g/∂q (c × m).
    pub constraint_q: DMatrix<f64>,
    /// ∂g/∂λ (c × (c+1)).
    pub constraint_lambda: DMatrix<f64>,
}

/// ∂R/∂q: dense for small problems; for large ones sparse, plus rank-one terms
/// Σ c a aᵀ (a gas amount's stiffness) kept apart so that they do not fill the matrix.
#[derive(Debug, Clone)]
pub enum Tangent {
    /// A dense symmetric matrix.
    Dense(DMatrix<f64>),
    /// A symmetric sparse matrix (both triangles stored) and rank-one terms (c, a).
    Sparse {
        /// The pattern.
        pattern: Arc<SymmetricPattern>,
        /// Values aligned with the pattern's row indices.
        values: Vec<f64>,
        /// The terms c a aᵀ.
        rank_one: Vec<(f64, DVector<f64>)>,
    },
}

impl Tangent {
    /// max |K_ij| (of the sparse part and of each rank-one term).
    pub fn amax(&self) -> f64 {
        match self {
            Tangent::Dense(k) => k.amax(),
            Tangent::Sparse {
                values, rank_one, ..
            } => rank_one
                .iter()
                .map(|(c, a)| c.abs() * a.amax().powi(2))
                .fold(values.iter().fold(0.0, |m, v| m.max(v.abs())), f64::max),
        }
    }
}

/// An extended Jacobian ready to solve.
enum Extended {
    Dense(DMatrix<f64>),
    /// n equations, of which the first `n - extra` are the extended system and the last
    /// `extra` define y_r = c_r σ_q a_rᵀ x for the rank-one terms.
    Sparse {
        n: usize,
        extra: usize,
        triplets: Vec<Triplet<usize, usize, f64>>,
    },
}

impl Extended {
    /// Solves A x = rhs (rhs of the extended system's size); `None` if A is singular.
    fn solve(self, rhs: &DVector<f64>) -> Option<DVector<f64>> {
        match self {
            Extended::Dense(a) => solve_dense(a, rhs),
            Extended::Sparse { n, extra, triplets } => {
                let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets).ok()?;
                let lu = a.sp_lu().ok()?;
                let mut b = faer::Mat::<f64>::zeros(n, 1);
                for i in 0..n - extra {
                    b[(i, 0)] = rhs[i];
                }
                let x = faer::linalg::solvers::Solve::solve(&lu, &b);
                let x = DVector::from_fn(n - extra, |i, _| x[(i, 0)]);
                x.iter().all(|v| v.is_finite()).then_some(x)
            }
        }
    }
}

impl Linearization {
    /// [[K σ_q, L diag(σ_λ)], [G_q σ_q, G_λ diag(σ_λ)], [last_rowᵀ]]: the Jacobian in the
    /// scaled unknowns, with `last_row` (the arclength or "control fixed" equation) last.
    fn extended(&self, opts: &PathOptions, last_row: &DVector<f64>) -> Extended {
        let (m, c) = (self.residual.len(), self.constraints.len());
        let n = m + c + 1;
        let sq = opts.state_scale;
        let sl = |j: usize| opts.parameter_scales.get(j).copied().unwrap_or(1.0);
        match &self.tangent {
            Tangent::Dense(k) => {
                let mut a = DMatrix::zeros(n, n);
                a.view_mut((0, 0), (m, m)).copy_from(&(k * sq));
                a.view_mut((m, 0), (c, m))
                    .copy_from(&(&self.constraint_q * sq));
                for j in 0..=c {
                    a.view_mut((0, m + j), (m, 1))
                        .copy_from(&(self.loads.column(j) * sl(j)));
                    a.view_mut((m, m + j), (c, 1))
                        .copy_from(&(self.constraint_lambda.column(j) * sl(j)));
                }
                a.row_mut(n - 1).copy_from(&last_row.transpose());
                Extended::Dense(a)
            }
            Tangent::Sparse {
                pattern,
                values,
                rank_one,
            } => {
                let extra = rank_one.len();
                let mut t = Vec::with_capacity(values.len() + (2 * c + 3 + 2 * extra) * m);
                let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
                for j in 0..m {
                    for p in col_ptr[j]..col_ptr[j + 1] {
                        t.push(Triplet::new(row_idx[p], j, values[p] * sq));
                    }
                }
                let push_dense = |t: &mut Vec<Triplet<usize, usize, f64>>, i, j, v: f64| {
                    if v != 0.0 {
                        t.push(Triplet::new(i, j, v));
                    }
                };
                for j in 0..=c {
                    for i in 0..m {
                        push_dense(&mut t, i, m + j, self.loads[(i, j)] * sl(j));
                    }
                    for i in 0..c {
                        push_dense(&mut t, m + i, m + j, self.constraint_lambda[(i, j)] * sl(j));
                    }
                }
                for i in 0..c {
                    for j in 0..m {
                        push_dense(&mut t, m + i, j, self.constraint_q[(i, j)] * sq);
                    }
                }
                for (j, &v) in last_row.iter().enumerate() {
                    push_dense(&mut t, n - 1, j, v);
                }
                for (r, (cr, a)) in rank_one.iter().enumerate() {
                    for (i, &ai) in a.iter().enumerate() {
                        push_dense(&mut t, i, n + r, ai);
                        push_dense(&mut t, n + r, i, cr * sq * ai);
                    }
                    t.push(Triplet::new(n + r, n + r, -1.0));
                }
                Extended::Sparse {
                    n: n + extra,
                    extra,
                    triplets: t,
                }
            }
        }
    }

    /// |R| small against the forces a unit scaled change of q or λ makes (‖K‖ σ_q and
    /// ‖L‖ σ_λ), and |g| small against its derivatives.
    fn converged(&self, opts: &PathOptions) -> bool {
        let force = (self.loads.amax() * opts.parameter_scales.first().copied().unwrap_or(1.0))
            .max(self.tangent.amax() * opts.state_scale)
            .max(1e-300);
        let gscale = self
            .constraint_q
            .amax()
            .max(self.constraint_lambda.amax())
            .max(1e-300)
            * opts.state_scale;
        self.residual.amax() <= opts.tolerance * force
            && self.constraints.amax() <= opts.tolerance * gscale
    }
}

/// Settings of the path follower.
#[derive(Debug, Clone)]
pub struct PathOptions {
    /// First arclength step.
    pub initial_step: f64,
    /// Smallest step before giving up.
    pub min_step: f64,
    /// Largest step.
    pub max_step: f64,
    /// Budget of accepted steps.
    pub max_steps: usize,
    /// Newton iterations per corrector before the step is cut.
    pub max_iterations: usize,
    /// Relative tolerance of the corrector (on R, relative to the load scale, and on Δy).
    pub tolerance: f64,
    /// Range of the control parameter λ_0; the path stops on leaving it.
    pub bounds: (f64, f64),
    /// Unit of each free parameter λ_j in the arclength norm.
    pub parameter_scales: Vec<f64>,
    /// Unit of q in the arclength norm (e.g. R·√nodes, so that a step is an RMS
    /// displacement).
    pub state_scale: f64,
    /// Initial direction of the control λ_0: +1 increasing, −1 decreasing.
    pub direction: f64,
}

impl Default for PathOptions {
    fn default() -> Self {
        Self {
            initial_step: 0.05,
            min_step: 1e-8,
            max_step: 0.5,
            max_steps: 500,
            max_iterations: 10,
            tolerance: 1e-10,
            bounds: (f64::NEG_INFINITY, f64::INFINITY),
            parameter_scales: vec![1.0],
            state_scale: 1.0,
            direction: 1.0,
        }
    }
}

/// One converged point of the path.
#[derive(Debug, Clone)]
pub struct PathPoint {
    /// q.
    pub q: DVector<f64>,
    /// The free parameters, the control first.
    pub lambda: DVector<f64>,
    /// Arclength from the start (in the scaled norm).
    pub arclength: f64,
    /// Newton iterations the corrector took.
    pub iterations: usize,
    /// Unit tangent in scaled variables (q/σ_q, λ_j/σ_j).
    pub tangent: DVector<f64>,
}

/// A turning point of the control λ_0 along the path.
#[derive(Debug, Clone)]
pub struct TurningPoint {
    /// The localised point (t_λ ≈ 0).
    pub point: PathPoint,
    /// +1 for a maximum of λ_0, −1 for a minimum.
    pub kind: f64,
    /// Index of the path point just before it.
    pub after_step: usize,
}

/// Why the path ended.
#[derive(Debug, Clone, PartialEq)]
pub enum StopReason {
    /// The control left its bounds.
    Bounds,
    /// The step budget was used.
    StepBudget,
    /// The caller's stop condition held.
    Condition,
    /// The step was cut below the minimum; the message says where and why.
    StepTooSmall(String),
}

/// A traced path.
#[derive(Debug, Clone)]
pub struct Path {
    /// Converged points, the start first.
    pub points: Vec<PathPoint>,
    /// Localised turning points of the control.
    pub turning_points: Vec<TurningPoint>,
    /// Why it ended.
    pub stop: StopReason,
}

/// Newton in (q, λ_1 … λ_c) at a fixed control λ_0, from (q0, λ0).
pub fn solve_at<P: DenseProblem>(
    problem: &mut P,
    q0: &DVector<f64>,
    lambda0: &DVector<f64>,
    opts: &PathOptions,
) -> Result<(DVector<f64>, DVector<f64>, usize), String> {
    let m = problem.dim();
    let (mut q, mut lambda) = (q0.clone(), lambda0.clone());
    let budget = opts.max_iterations.max(20);
    for it in 1..=budget {
        let lin = problem.evaluate(&q, &lambda).map_err(|e| e.to_string())?;
        let c = lin.constraints.len();
        // The arclength row becomes "control fixed".
        let mut last = DVector::zeros(m + c + 1);
        last[m] = 1.0;
        let a = lin.extended(opts, &last);
        let mut rhs = DVector::zeros(m + c + 1);
        rhs.rows_mut(0, m).copy_from(&(-&lin.residual));
        rhs.rows_mut(m, c).copy_from(&(-&lin.constraints));
        let d = a
            .solve(&rhs)
            .ok_or_else(|| format!("singular tangent at λ = {}", lambda[0]))?;
        q += d.rows(0, m) * opts.state_scale;
        for j in 1..=c {
            lambda[j] += d[m + j] * opts.parameter_scales.get(j).copied().unwrap_or(1.0);
        }
        if !(q.iter().all(|v| v.is_finite()) && lambda.iter().all(|v| v.is_finite())) {
            return Err(format!("Newton diverged at λ = {}", lambda[0]));
        }
        if lin.converged(opts) && d.amax() <= opts.tolerance {
            return Ok((q, lambda, it));
        }
    }
    Err(format!(
        "Newton did not converge at λ = {} in {budget} iterations",
        lambda[0]
    ))
}

/// Above this size the extended system is solved by faer's blocked, multi-threaded LU
/// (the fixed-point space of an f = 128 icosphere has ≈ 4 200 unknowns: nalgebra's
/// unblocked LU takes seconds there); below it by nalgebra's, which is faster on tiny ones.
const BLOCKED_LU_FROM: usize = 256;

/// A x = rhs by LU with partial pivoting; `None` for a singular A (a zero pivot, or a
/// non-finite solution).
fn solve_dense(a: DMatrix<f64>, rhs: &DVector<f64>) -> Option<DVector<f64>> {
    let n = a.nrows();
    if n < BLOCKED_LU_FROM {
        return a.lu().solve(rhs);
    }
    let lu = faer::MatRef::from_column_major_slice(a.as_slice(), n, n).partial_piv_lu();
    let b = faer::MatRef::from_column_major_slice(rhs.as_slice(), n, 1);
    let x = faer::linalg::solvers::Solve::solve(&lu, b);
    let x = DVector::from_fn(n, |i, _| x[(i, 0)]);
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// The unit tangent of the path at a solution, oriented along `previous` (or so that the
/// control moves in `opts.direction` when there is none).
fn tangent_at(
    lin: &Linearization,
    opts: &PathOptions,
    previous: Option<&DVector<f64>>,
) -> Option<DVector<f64>> {
    let (m, c) = (lin.residual.len(), lin.constraints.len());
    let n = m + c + 1;
    let mut rhs = DVector::zeros(n);
    rhs[n - 1] = 1.0;
    let last = match previous {
        Some(t) => t.clone(),
        None => {
            let mut e = DVector::zeros(n);
            e[m] = 1.0;
            e
        }
    };
    let mut t = lin.extended(opts, &last).solve(&rhs)?;
    t /= t.norm();
    let sign = match previous {
        Some(p) => t.dot(p),
        None => t[m] * opts.direction,
    };
    if sign < 0.0 {
        t = -t;
    }
    Some(t)
}

/// Predictor–corrector from `from` with step `s` along `from.tangent`.
pub fn step<P: DenseProblem>(
    problem: &mut P,
    from: &PathPoint,
    s: f64,
    opts: &PathOptions,
) -> Result<PathPoint, String> {
    let m = problem.dim();
    let nl = from.lambda.len();
    let sq = opts.state_scale;
    let sl = |j: usize| opts.parameter_scales.get(j).copied().unwrap_or(1.0);
    let t = &from.tangent;
    let mut q = &from.q + t.rows(0, m) * (s * sq);
    let mut lambda = from.lambda.clone();
    for j in 0..nl {
        lambda[j] += t[m + j] * s * sl(j);
    }
    for it in 1..=opts.max_iterations {
        let lin = problem.evaluate(&q, &lambda).map_err(|e| e.to_string())?;
        let c = lin.constraints.len();
        let a = lin.extended(opts, t);
        let mut g = DVector::zeros(m + c + 1);
        g.rows_mut(0, m).copy_from(&lin.residual);
        g.rows_mut(m, c).copy_from(&lin.constraints);
        let mut arc = t.rows(0, m).dot(&(&q - &from.q)) / sq - s;
        for j in 0..nl {
            arc += t[m + j] * (lambda[j] - from.lambda[j]) / sl(j);
        }
        g[m + c] = arc;
        let converged = lin.converged(opts);
        let d = a.solve(&(-&g)).ok_or("singular extended Jacobian")?;
        q += d.rows(0, m) * sq;
        for j in 0..nl {
            lambda[j] += d[m + j] * sl(j);
        }
        if !(q.iter().all(|v| v.is_finite()) && lambda.iter().all(|v| v.is_finite())) {
            return Err("the corrector diverged (non-finite state)".into());
        }
        if converged && d.amax() <= opts.tolerance {
            let lin = problem.evaluate(&q, &lambda).map_err(|e| e.to_string())?;
            let tangent = tangent_at(&lin, opts, Some(t)).ok_or("singular tangent system")?;
            // Stay on the branch: the corrector must end near the predictor and the tangent
            // must not turn sharply; otherwise the step is cut rather than a jump accepted.
            let mut dist2 = (&q - &from.q - t.rows(0, m) * (s * sq)).norm_squared() / (sq * sq);
            for j in 0..nl {
                dist2 += ((lambda[j] - from.lambda[j] - t[m + j] * s * sl(j)) / sl(j)).powi(2);
            }
            if dist2.sqrt() > MAX_CORRECTOR_DISTANCE * s || tangent.dot(t) < MIN_TANGENT_COSINE {
                return Err(format!(
                    "the corrector moved {:.2} steps from the predictor and the tangent turned by {:.0}°: a possible branch jump",
                    dist2.sqrt() / s,
                    tangent.dot(t).clamp(-1.0, 1.0).acos().to_degrees()
                ));
            }
            return Ok(PathPoint {
                q,
                lambda,
                arclength: from.arclength + s,
                iterations: it,
                tangent,
            });
        }
    }
    Err(format!(
        "the corrector did not converge in {} iterations",
        opts.max_iterations
    ))
}

/// Localises the turning point between `from` (t_λ of one sign) and a point reached with
/// step `s_hi` (t_λ of the other) by a secant search on the step length.
fn localise_turning<P: DenseProblem>(
    problem: &mut P,
    from: &PathPoint,
    s_hi: f64,
    t_hi: f64,
    opts: &PathOptions,
) -> Option<PathPoint> {
    let m = problem.dim();
    let (mut s0, mut f0) = (0.0, from.tangent[m]);
    let (mut s1, mut f1) = (s_hi, t_hi);
    let mut best = None;
    for _ in 0..40 {
        let s = if (f1 - f0).abs() > 0.0 {
            s1 - f1 * (s1 - s0) / (f1 - f0)
        } else {
            0.5 * (s0 + s1)
        };
        // Keep the secant inside the bracket; fall back to bisection.
        let s = if s <= s0.min(s1) || s >= s0.max(s1) {
            0.5 * (s0 + s1)
        } else {
            s
        };
        let p = step(problem, from, s, opts).ok()?;
        let f = p.tangent[m];
        let done = f.abs() < 1e-12 || (s1 - s0).abs() < 1e-14 * s_hi;
        best = Some(p);
        if done {
            break;
        }
        if f.signum() == f0.signum() {
            (s0, f0) = (s, f);
        } else {
            (s1, f1) = (s, f);
        }
    }
    best
}

/// Follows the path from (q0, λ0) (corrected first at fixed λ0) until the bounds, the step
/// budget, or `stop(point)` returns true.
pub fn follow<P: DenseProblem>(
    problem: &mut P,
    q0: &DVector<f64>,
    lambda0: &DVector<f64>,
    opts: &PathOptions,
    mut stop: impl FnMut(&PathPoint) -> bool,
    mut progress: impl FnMut(&PathPoint),
) -> Result<Path, String> {
    let m = problem.dim();
    let (q, lambda, iterations) = solve_at(problem, q0, lambda0, opts)?;
    let lin = problem.evaluate(&q, &lambda).map_err(|e| e.to_string())?;
    let tangent = tangent_at(&lin, opts, None).ok_or("singular tangent at the start")?;
    let start = PathPoint {
        q,
        lambda,
        arclength: 0.0,
        iterations,
        tangent,
    };
    progress(&start);
    let mut path = Path {
        points: vec![start],
        turning_points: Vec::new(),
        stop: StopReason::StepBudget,
    };
    let mut s = opts.initial_step;
    while path.points.len() <= opts.max_steps {
        let last = path.points.last().expect("the path has a start");
        let next = match step(problem, last, s, opts) {
            Ok(p) => p,
            Err(why) => {
                s *= 0.5;
                if s < opts.min_step {
                    path.stop = StopReason::StepTooSmall(format!(
                        "step cut below {:e} after point {} (control = {}): {why}",
                        opts.min_step,
                        path.points.len() - 1,
                        last.lambda[0]
                    ));
                    return Ok(path);
                }
                continue;
            }
        };
        if next.tangent[m].signum() != last.tangent[m].signum() && last.tangent[m] != 0.0 {
            let kind = last.tangent[m].signum();
            let after = path.points.len() - 1;
            if let Some(p) = localise_turning(problem, last, s, next.tangent[m], opts) {
                path.turning_points.push(TurningPoint {
                    point: p,
                    kind,
                    after_step: after,
                });
            }
        }
        // Step control: grow after easy steps, shrink after hard ones.
        if next.iterations <= 3 {
            s = (s * 1.5).min(opts.max_step);
        } else if next.iterations >= 6 {
            s *= 0.7;
        }
        let out_of_bounds = next.lambda[0] < opts.bounds.0 || next.lambda[0] > opts.bounds.1;
        let done = stop(&next);
        progress(&next);
        path.points.push(next);
        if out_of_bounds {
            path.stop = StopReason::Bounds;
            return Ok(path);
        }
        if done {
            path.stop = StopReason::Condition;
            return Ok(path);
        }
    }
    Ok(path)
}

#[cfg(test)]
mod solve_tests {
    use super::{solve_dense, BLOCKED_LU_FROM};
    use nalgebra::{DMatrix, DVector};

    /// Both LU paths solve a well-conditioned system to round-off, and refuse a singular one.
    #[test]
    fn blocked_and_small_lu_agree_and_refuse_singular_matrices() {
        for n in [BLOCKED_LU_FROM - 1, BLOCKED_LU_FROM + 44] {
            let a = DMatrix::from_fn(n, n, |i, j| {
                ((i * 31 + j * 17) as f64 * 0.13).sin() + if i == j { n as f64 } else { 0.0 }
            });
            let x = DVector::from_fn(n, |i, _| (i as f64 * 0.7).cos());
            let b = &a * &x;
            let y = solve_dense(a.clone(), &b).expect("regular");
            assert!((y - &x).amax() < 1e-12, "n = {n}");
            let mut singular = a;
            singular.row_mut(3).fill(0.0);
            assert!(solve_dense(singular, &b).is_none(), "n = {n}");
        }
    }
}
