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

use crate::linalg::{SymmetricFactorization, SymmetricPattern};
use crate::model::ModelError;
use faer::sparse::{SparseColMat, Triplet};
use nalgebra::{DMatrix, DVector};
use std::sync::{Arc, Mutex};

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
        /// A sparse LBLᵀ on `pattern`, kept by the problem from one evaluation to the next
        /// (the symbolic analysis is done once).
        solver: SharedFactorization,
    },
}

/// A sparse LBLᵀ shared between the evaluations of one problem.
pub type SharedFactorization = Arc<Mutex<Option<SymmetricFactorization>>>;

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
    /// [[A, B], [C, D]] with A = K σ_q sparse symmetric (m × m) and a border of nb rows and
    /// columns: the loads, constraint rows, the arclength row, and one unknown
    /// y_r = c_r σ_q a_rᵀ x per rank-one term (the last `extra` of the border).
    Sparse {
        pattern: Arc<SymmetricPattern>,
        values: Vec<f64>,
        b: DMatrix<f64>,
        c: DMatrix<f64>,
        d: DMatrix<f64>,
        extra: usize,
        solver: SharedFactorization,
    },
}

impl Extended {
    /// Solves A x = rhs (rhs of the extended system's size); `None` if A is singular.
    fn solve(self, rhs: &DVector<f64>) -> Option<DVector<f64>> {
        match self {
            Extended::Dense(a) => solve_dense(a, rhs),
            Extended::Sparse {
                pattern,
                values,
                b,
                c,
                d,
                extra,
                solver,
            } => {
                let m = pattern.n();
                let nb = d.nrows();
                let mut full = DVector::zeros(m + nb);
                full.rows_mut(0, m + nb - extra)
                    .copy_from(&rhs.rows(0, m + nb - extra));
                let x = bordered_solve(&pattern, &values, &b, &c, &d, &solver, &full)
                    .or_else(|| sparse_lu_solve(&pattern, &values, &b, &c, &d, &full))?;
                let x = x.rows(0, m + nb - extra).into_owned();
                x.iter().all(|v| v.is_finite()).then_some(x)
            }
        }
    }
}

/// [[A, B], [C, D]] [x; z] = [r1; r2] by block elimination on a sparse LBLᵀ of A (symbolic
/// analysis kept in `solver`): A X = B, S = D − C X, S z = r2 − C A⁻¹ r1, x = A⁻¹(r1 − B z),
/// then one step of iterative refinement on the whole system (A is nearly singular close
/// to a limit point, which the border makes regular). `None` if A is singular.
fn bordered_solve(
    pattern: &Arc<SymmetricPattern>,
    values: &[f64],
    b: &DMatrix<f64>,
    c: &DMatrix<f64>,
    d: &DMatrix<f64>,
    solver: &SharedFactorization,
    rhs: &DVector<f64>,
) -> Option<DVector<f64>> {
    let m = pattern.n();
    let nb = d.nrows();
    let mut guard = solver.lock().ok()?;
    if guard.as_ref().is_none_or(|f| f.n() != m) {
        *guard = Some(SymmetricFactorization::new(pattern).ok()?);
    }
    let fact = guard.as_mut()?;
    fact.factorize(values).ok()?;
    // X = A⁻¹ B.
    let mut x_b = b.clone();
    fact.solve_many_in_place(x_b.as_mut_slice()).ok()?;
    let schur = d - c * &x_b;
    let lu = schur.lu();
    let solve = |r: &DVector<f64>| -> Option<DVector<f64>> {
        let mut y = r.rows(0, m).into_owned();
        fact.solve_in_place(y.as_mut_slice()).ok()?;
        let z = lu.solve(&(r.rows(m, nb) - c * &y))?;
        let x = y - &x_b * &z;
        let mut out = DVector::zeros(m + nb);
        out.rows_mut(0, m).copy_from(&x);
        out.rows_mut(m, nb).copy_from(&z);
        Some(out)
    };
    let mut sol = solve(rhs)?;
    // One refinement step: r = rhs − M sol.
    let (xs, zs) = (sol.rows(0, m).into_owned(), sol.rows(m, nb).into_owned());
    let mut ax = vec![0.0; m];
    pattern.matvec(values, xs.as_slice(), &mut ax);
    let mut residual = rhs.clone();
    for i in 0..m {
        residual[i] -= ax[i];
    }
    let top = b * &zs;
    let bottom = c * &xs + d * &zs;
    for i in 0..m {
        residual[i] -= top[i];
    }
    for i in 0..nb {
        residual[m + i] -= bottom[i];
    }
    sol += solve(&residual)?;
    Some(sol)
}

/// The same system by faer's sparse LU of the whole matrix (the fallback when A itself is
/// singular).
fn sparse_lu_solve(
    pattern: &SymmetricPattern,
    values: &[f64],
    b: &DMatrix<f64>,
    c: &DMatrix<f64>,
    d: &DMatrix<f64>,
    rhs: &DVector<f64>,
) -> Option<DVector<f64>> {
    let (m, nb) = (pattern.n(), d.nrows());
    let n = m + nb;
    let mut t = Vec::with_capacity(values.len() + 2 * nb * m + nb * nb);
    let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
    for j in 0..m {
        for p in col_ptr[j]..col_ptr[j + 1] {
            t.push(Triplet::new(row_idx[p], j, values[p]));
        }
    }
    for j in 0..nb {
        for i in 0..m {
            if b[(i, j)] != 0.0 {
                t.push(Triplet::new(i, m + j, b[(i, j)]));
            }
            if c[(j, i)] != 0.0 {
                t.push(Triplet::new(m + j, i, c[(j, i)]));
            }
        }
        for i in 0..nb {
            if d[(i, j)] != 0.0 {
                t.push(Triplet::new(m + i, m + j, d[(i, j)]));
            }
        }
    }
    let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &t).ok()?;
    let lu = a.sp_lu().ok()?;
    let rhs = faer::MatRef::from_column_major_slice(rhs.as_slice(), n, 1);
    let x = faer::linalg::solvers::Solve::solve(&lu, rhs);
    Some(DVector::from_fn(n, |i, _| x[(i, 0)]))
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
                solver,
            } => {
                let extra = rank_one.len();
                let nb = c + 1 + extra;
                let mut bm = DMatrix::zeros(m, nb);
                let mut cm = DMatrix::zeros(nb, m);
                let mut dm = DMatrix::zeros(nb, nb);
                for j in 0..=c {
                    bm.set_column(j, &(self.loads.column(j) * sl(j)));
                    for i in 0..c {
                        dm[(i, j)] = self.constraint_lambda[(i, j)] * sl(j);
                    }
                }
                for i in 0..c {
                    cm.set_row(i, &(self.constraint_q.row(i) * sq));
                }
                cm.row_mut(c).copy_from(&last_row.rows(0, m).transpose());
                for j in 0..=c {
                    dm[(c, j)] = last_row[m + j];
                }
                for (r, (cr, a)) in rank_one.iter().enumerate() {
                    bm.set_column(c + 1 + r, a);
                    cm.set_row(c + 1 + r, &(a.transpose() * (cr * sq)));
                    dm[(c + 1 + r, c + 1 + r)] = -1.0;
                }
                Extended::Sparse {
                    pattern: pattern.clone(),
                    values: values.iter().map(|v| v * sq).collect(),
                    b: bm,
                    c: cm,
                    d: dm,
                    extra,
                    solver: solver.clone(),
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

#[cfg(test)]
mod bordered_tests {
    use super::{bordered_solve, sparse_lu_solve, SharedFactorization};
    use crate::linalg::SymmetricPattern;
    use nalgebra::{DMatrix, DVector};
    use std::sync::Arc;

    /// Block elimination on the sparse LBLᵀ, the sparse LU of the whole matrix and a dense
    /// LU agree on an indefinite tridiagonal A with a two-column border.
    #[test]
    fn bordered_and_sparse_lu_solves_agree_with_dense() {
        let m = 40;
        let pattern = Arc::new(SymmetricPattern::from_entries(
            m,
            (1..m).map(|i| (i, i - 1)),
        ));
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let entry = |i: usize, j: usize| {
            if i == j {
                2.0 + (i as f64 * 0.9).sin() - 1.0
            } else {
                -0.7
            }
        };
        let mut values = vec![0.0; pattern.nnz()];
        for j in 0..m {
            for p in col_ptr[j]..col_ptr[j + 1] {
                values[p] = entry(row_idx[p], j);
            }
        }
        let b = DMatrix::from_fn(m, 2, |i, j| ((i + 3 * j) as f64 * 0.37).cos());
        let c = DMatrix::from_fn(2, m, |i, j| ((2 * j + i) as f64 * 0.21).sin());
        let d = DMatrix::from_row_slice(2, 2, &[0.3, -0.1, 0.2, 0.0]);
        let rhs = DVector::from_fn(m + 2, |i, _| (i as f64 * 0.5).sin());
        let mut dense = DMatrix::zeros(m + 2, m + 2);
        for j in 0..m {
            for p in col_ptr[j]..col_ptr[j + 1] {
                dense[(row_idx[p], j)] = values[p];
            }
        }
        dense.view_mut((0, m), (m, 2)).copy_from(&b);
        dense.view_mut((m, 0), (2, m)).copy_from(&c);
        dense.view_mut((m, m), (2, 2)).copy_from(&d);
        let expected = dense.lu().solve(&rhs).unwrap();
        let solver = SharedFactorization::default();
        let x = bordered_solve(&pattern, &values, &b, &c, &d, &solver, &rhs).unwrap();
        assert!((&x - &expected).amax() < 1e-10 * expected.amax());
        // The symbolic analysis is kept for the next solve.
        assert!(solver.lock().unwrap().is_some());
        let y = sparse_lu_solve(&pattern, &values, &b, &c, &d, &rhs).unwrap();
        assert!((&y - &expected).amax() < 1e-10 * expected.amax());
    }
}
