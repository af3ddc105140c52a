//! Pseudo-arclength continuation in several parameters (docs/theory.md §7.3–§7.7): a stepping
//! driver, [`Continuation`], that starts from any converged point and tangent of any
//! [`Problem`] — here the fixed-point space of a subgroup of the scene's group
//! (the fixed-point space of a subgroup on a 3-D mesh, a meridian's unknowns) — and advances one accepted point per
//! [`Continuation::step`]. What happens along the way (turning points, changes of stability,
//! stops) is the business of [`crate::continuation::events`], not of the driver.
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
//! A corrector that does not converge, or that ends far from its predictor, halves the step;
//! below `min_step` the driver reports where and why it stalled.

use crate::linalg::bordered::{
    bordered_resolve_all, bordered_solve_all, solve_dense, sparse_lu_solve, SharedFactorization,
};
use crate::linalg::SymmetricPattern;
use crate::model::{ModelError, StateDefect};
use crate::results::PhaseTimes;
use nalgebra::{DMatrix, DVector};
use std::sync::Arc;

/// Largest distance, in steps, between the converged point and the predictor.
const MAX_CORRECTOR_DISTANCE: f64 = 0.5;
/// Smallest cosine between consecutive tangents (about 35°).
const MIN_TANGENT_COSINE: f64 = 0.8;

/// A problem R(q, λ), g(q, λ) with its derivatives, as the path follower sees it.
pub trait Problem {
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
    /// R and g alone at (q, λ), without their derivatives: what the corrector's check of an
    /// iterate it expects to be converged needs (a chord step takes the derivatives of the
    /// iteration before). By default from [`Problem::evaluate`]; a problem whose derivatives
    /// cost more than R and g says so by computing these alone.
    fn residual(
        &mut self,
        q: &DVector<f64>,
        lambda: &DVector<f64>,
    ) -> Result<(DVector<f64>, DVector<f64>), ModelError> {
        let lin = self.evaluate(q, lambda)?;
        Ok((lin.residual, lin.constraints))
    }
    /// Where the evaluations' time went so far (zero unless the problem keeps count).
    fn phase_times(&self) -> PhaseTimes {
        PhaseTimes::default()
    }
    /// Why the converged (q, λ) is not an admissible state (the driver then cuts the step),
    /// or `None`. Every state is admissible unless the problem says otherwise.
    fn defect(&self, _q: &DVector<f64>, _lambda: &DVector<f64>) -> Option<StateDefect> {
        None
    }
    /// How many of the model's switches (nodes in contact with a penalty plane …) differ
    /// between the states `a` and `b`, each (q, λ): where the tangent, and the path's
    /// direction with it, may jump. `None` (the default) for a smooth problem.
    fn switched(
        &self,
        _a: (&DVector<f64>, &DVector<f64>),
        _b: (&DVector<f64>, &DVector<f64>),
    ) -> Option<usize> {
        None
    }
}

impl<P: Problem + ?Sized> Problem for Box<P> {
    fn dim(&self) -> usize {
        (**self).dim()
    }
    fn free_parameters(&self) -> usize {
        (**self).free_parameters()
    }
    fn evaluate(
        &mut self,
        q: &DVector<f64>,
        lambda: &DVector<f64>,
    ) -> Result<Linearization, ModelError> {
        (**self).evaluate(q, lambda)
    }
    fn residual(
        &mut self,
        q: &DVector<f64>,
        lambda: &DVector<f64>,
    ) -> Result<(DVector<f64>, DVector<f64>), ModelError> {
        (**self).residual(q, lambda)
    }
    fn phase_times(&self) -> PhaseTimes {
        (**self).phase_times()
    }
    fn defect(&self, q: &DVector<f64>, lambda: &DVector<f64>) -> Option<StateDefect> {
        (**self).defect(q, lambda)
    }
    fn switched(
        &self,
        a: (&DVector<f64>, &DVector<f64>),
        b: (&DVector<f64>, &DVector<f64>),
    ) -> Option<usize> {
        (**self).switched(a, b)
    }
}

impl<P: Problem + ?Sized> Problem for &mut P {
    fn dim(&self) -> usize {
        (**self).dim()
    }
    fn free_parameters(&self) -> usize {
        (**self).free_parameters()
    }
    fn evaluate(
        &mut self,
        q: &DVector<f64>,
        lambda: &DVector<f64>,
    ) -> Result<Linearization, ModelError> {
        (**self).evaluate(q, lambda)
    }
    fn residual(
        &mut self,
        q: &DVector<f64>,
        lambda: &DVector<f64>,
    ) -> Result<(DVector<f64>, DVector<f64>), ModelError> {
        (**self).residual(q, lambda)
    }
    fn phase_times(&self) -> PhaseTimes {
        (**self).phase_times()
    }
    fn defect(&self, q: &DVector<f64>, lambda: &DVector<f64>) -> Option<StateDefect> {
        (**self).defect(q, lambda)
    }
    fn switched(
        &self,
        a: (&DVector<f64>, &DVector<f64>),
        b: (&DVector<f64>, &DVector<f64>),
    ) -> Option<usize> {
        (**self).switched(a, b)
    }
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

#[cfg(test)]
impl Linearization {
    /// One unknown q and one parameter λ, no augmenting equation: R, ∂R/∂q and ∂R/∂λ (the
    /// scalar problems of the tests).
    pub(crate) fn scalar(residual: f64, r_q: f64, r_lambda: f64) -> Self {
        Self {
            residual: DVector::from_element(1, residual),
            tangent: Tangent::Dense(DMatrix::from_element(1, 1, r_q)),
            loads: DMatrix::from_element(1, 1, r_lambda),
            constraints: DVector::zeros(0),
            constraint_q: DMatrix::zeros(0, 1),
            constraint_lambda: DMatrix::zeros(0, 1),
        }
    }
}

/// A problem of one unknown and one parameter, R(q, λ) given by a function returning
/// (R, ∂R/∂q, ∂R/∂λ) or the model's error: the closed forms the continuation is tested on.
#[cfg(test)]
pub(crate) struct Scalar<F>(pub F);

#[cfg(test)]
impl<F: FnMut(f64, f64) -> Result<(f64, f64, f64), ModelError>> Problem for Scalar<F> {
    fn dim(&self) -> usize {
        1
    }
    fn free_parameters(&self) -> usize {
        1
    }
    fn evaluate(
        &mut self,
        q: &DVector<f64>,
        lambda: &DVector<f64>,
    ) -> Result<Linearization, ModelError> {
        let (r, r_q, r_lambda) = (self.0)(q[0], lambda[0])?;
        Ok(Linearization::scalar(r, r_q, r_lambda))
    }
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

impl Tangent {
    /// K W, the whole tangent (sparse part and rank-one terms) times the columns of `w`.
    pub fn times(&self, w: &DMatrix<f64>) -> DMatrix<f64> {
        match self {
            Tangent::Dense(k) => k * w,
            Tangent::Sparse {
                pattern,
                values,
                rank_one,
                ..
            } => {
                let (cp, ri) = (pattern.col_ptr(), pattern.row_idx());
                let mut kw = DMatrix::zeros(w.nrows(), w.ncols());
                for j in 0..w.nrows() {
                    for p in cp[j]..cp[j + 1] {
                        let i = ri[p];
                        for c in 0..w.ncols() {
                            kw[(i, c)] += values[p] * w[(j, c)];
                        }
                    }
                }
                for (c, a) in rank_one {
                    let aw = w.transpose() * a;
                    kw += a * (aw.transpose() * *c);
                }
                kw
            }
        }
    }

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

/// Why Newton at a fixed control failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolveError {
    /// The model could not be evaluated.
    #[error("{0}")]
    Model(#[from] ModelError),
    /// The extended Jacobian was singular.
    #[error("singular tangent at λ = {control}")]
    Singular {
        /// The control's value.
        control: f64,
    },
    /// The iterates left the finite numbers.
    #[error("Newton diverged at λ = {control}")]
    Diverged {
        /// The control's value.
        control: f64,
    },
    /// The iteration budget was used.
    #[error("Newton did not converge at λ = {control} in {iterations} iterations (residual {residual:.1e} of the force scale, last correction {correction:.1e} of the state scale, tolerance {tolerance:.0e})")]
    NotConverged {
        /// The control's value.
        control: f64,
        /// The budget used (the limit this solve actually had).
        iterations: usize,
        /// max |R| relative to the force scale at the last iterate.
        residual: f64,
        /// The last Newton correction, in the scaled unknowns (state / state scale).
        correction: f64,
        /// The tolerance both had to reach.
        tolerance: f64,
    },
    /// No tangent could be computed at the converged point.
    #[error("singular tangent at the start")]
    SingularTangent,
    /// A signal asked to stop (checked between iterations).
    #[error("interrupted")]
    Interrupted,
    /// The start homotopy's holding force did not vanish along its auxiliary path.
    #[error("the held translation was not released in {steps} steps (holding force {force:e})")]
    NotReleased {
        /// The steps taken.
        steps: usize,
        /// The holding force at the last point.
        force: f64,
    },
}

impl SolveError {
    /// The message with the control parameter named `name` (or, with `None`, the start values)
    /// in place of λ.
    pub fn describe(&self, name: Option<&str>) -> String {
        let at = |v: f64| match name {
            Some(n) => format!("at {n} = {v}"),
            None => "at the start values".to_string(),
        };
        match self {
            Self::Model(e) => e.to_string(),
            Self::Singular { control } => format!("singular tangent {}", at(*control)),
            Self::Diverged { control } => format!("Newton diverged {}", at(*control)),
            Self::NotConverged {
                control,
                iterations,
                residual,
                correction,
                tolerance,
            } => format!(
                "Newton did not converge {} in {iterations} iterations (residual \
                 {residual:.1e} of the force scale, last correction {correction:.1e} of the \
                 state scale, tolerance {tolerance:.0e})",
                at(*control)
            ),
            Self::SingularTangent => "singular tangent at the start".to_string(),
            Self::NotReleased { .. } | Self::Interrupted => self.to_string(),
        }
    }
}

/// Why one predictor–corrector step failed (the driver then cuts the step).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StepError {
    /// The model could not be evaluated.
    #[error("{0}")]
    Model(#[from] ModelError),
    /// The extended Jacobian was singular.
    #[error("singular extended Jacobian")]
    Singular,
    /// The corrector left the finite numbers.
    #[error("the corrector diverged (non-finite state)")]
    Diverged,
    /// No tangent at the converged point.
    #[error("singular tangent system")]
    SingularTangent,
    /// The corrector converged far from its predictor or the tangent turned sharply.
    #[error("the corrector moved {distance:.2} steps from the predictor and the tangent turned by {angle:.0}°: a possible branch jump")]
    BranchJump {
        /// Distance from the predictor, in steps.
        distance: f64,
        /// Angle between the tangents, in degrees.
        angle: f64,
    },
    /// The corrector converged to a state that is not admissible (a membrane collapsed,
    /// torn or turned inside out).
    #[error("the corrector converged to an inadmissible state: {0}")]
    Degenerate(StateDefect),
    /// The iteration budget was used.
    #[error("the corrector did not converge in {iterations} iterations")]
    NotConverged {
        /// The budget.
        iterations: usize,
    },
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
            sparse => sparse.solve_all(&[rhs])?.pop(),
        }
    }

    /// Solves A x = rhs for every rhs in `all` from one factorisation of A; `None` if A is
    /// singular.
    fn solve_all(&self, all: &[&DVector<f64>]) -> Option<Vec<DVector<f64>>> {
        self.solve_with(all, false)
    }

    /// As [`Extended::solve_all`], from the factorisation the last solve of this system left
    /// (a chord step: no factorisation), kept only at a backward error at round-off; a dense
    /// A is factorised again (it is small). `None` where that fails.
    fn resolve_all(&self, all: &[&DVector<f64>]) -> Option<Vec<DVector<f64>>> {
        self.solve_with(all, true)
    }

    fn solve_with(&self, all: &[&DVector<f64>], again: bool) -> Option<Vec<DVector<f64>>> {
        match self {
            Extended::Dense(a) => all.iter().map(|rhs| solve_dense(a.clone(), rhs)).collect(),
            Extended::Sparse {
                pattern,
                values,
                b,
                c,
                d,
                extra,
                solver,
            } => {
                let extra = *extra;
                let m = pattern.n();
                let nb = d.nrows();
                let full: Vec<DVector<f64>> = all
                    .iter()
                    .map(|rhs| {
                        let mut full = DVector::zeros(m + nb);
                        full.rows_mut(0, m + nb - extra)
                            .copy_from(&rhs.rows(0, m + nb - extra));
                        full
                    })
                    .collect();
                let refs: Vec<&DVector<f64>> = full.iter().collect();
                let xs = if again {
                    bordered_resolve_all(pattern, values, b, c, d, solver, &refs)?
                } else {
                    match bordered_solve_all(pattern, values, b, c, d, solver, &refs) {
                        Some(xs) => xs,
                        None => full
                            .iter()
                            .map(|f| sparse_lu_solve(pattern, values, b, c, d, f))
                            .collect::<Option<Vec<_>>>()?,
                    }
                };
                xs.into_iter()
                    .map(|x| {
                        let x = x.rows(0, m + nb - extra).into_owned();
                        x.iter().all(|v| v.is_finite()).then_some(x)
                    })
                    .collect()
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
        let sl = |j: usize| opts.parameter_scale(j);
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
        self.converges(&self.residual, &self.constraints, opts)
    }

    /// Whether R and g (of this point or of one close to it) pass [`Linearization::converged`]
    /// with this point's scales of force and of g.
    fn converges(&self, residual: &DVector<f64>, g: &DVector<f64>, opts: &PathOptions) -> bool {
        let force = (self.loads.amax() * opts.parameter_scale(0))
            .max(self.tangent.amax() * opts.state_scale)
            .max(1e-300);
        let gscale = self
            .constraint_q
            .amax()
            .max(self.constraint_lambda.amax())
            .max(1e-300)
            * opts.state_scale;
        residual.amax() <= opts.tolerance * force && g.amax() <= opts.tolerance * gscale
    }

    /// max |R| relative to the force scale of [`Linearization::converged`].
    fn relative_residual(&self, opts: &PathOptions) -> f64 {
        let force = (self.loads.amax() * opts.parameter_scale(0))
            .max(self.tangent.amax() * opts.state_scale)
            .max(1e-300);
        self.residual.amax() / force
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

/// The continuation settings an analysis takes from its scene: the keys of `[analysis]`
/// that every path-following analysis shares (docs/scenes.md), parsed straight into this
/// type — steps, step sizes, the corrector's tolerance and iterations, the first step's sense
/// (`direction = "increase"` or `"decrease"`) and how often a state is saved. A key left out
/// takes the scene's default ([`Settings::of_scene`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(
    default = "Settings::of_scene",
    deny_unknown_fields,
    rename_all = "kebab-case"
)]
pub struct Settings {
    /// Budget of accepted steps.
    pub steps: usize,
    /// First arclength step.
    pub initial_step: f64,
    /// Smallest step before giving up.
    pub min_step: f64,
    /// Largest step.
    pub max_step: f64,
    /// Relative tolerance of the corrector.
    pub tolerance: f64,
    /// Newton iterations per corrector before the step is cut.
    pub max_iterations: usize,
    /// The first step's sense in the control: +1 increasing, −1 decreasing.
    #[serde(with = "sense")]
    pub direction: f64,
    /// Save every n-th state of a path.
    pub save_every: usize,
}

/// `direction = "increase" | "decrease"` ↔ the sign +1 or −1.
mod sense {
    use serde::{de, Deserialize, Deserializer, Serializer};

    const NAMES: &[&str] = &["increase", "decrease"];

    pub fn serialize<S: Serializer>(sign: &f64, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(if *sign < 0.0 { NAMES[1] } else { NAMES[0] })
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        match String::deserialize(d)?.as_str() {
            "increase" => Ok(1.0),
            "decrease" => Ok(-1.0),
            other => Err(de::Error::unknown_variant(other, NAMES)),
        }
    }
}

impl Default for Settings {
    fn default() -> Self {
        let o = PathOptions::default();
        Self {
            steps: o.max_steps,
            initial_step: o.initial_step,
            min_step: o.min_step,
            max_step: o.max_step,
            tolerance: o.tolerance,
            max_iterations: o.max_iterations,
            direction: o.direction,
            save_every: 10,
        }
    }
}

impl Settings {
    /// The defaults of a scene's `[analysis]` (docs/scenes.md): 200 steps, arclength steps
    /// 0.02 within [1e-6, 0.2], Newton to a relative residual of 1e-9 in at most 25
    /// iterations, the control increasing first, every 10th state saved.
    pub fn of_scene() -> Self {
        Self {
            steps: 200,
            initial_step: 0.02,
            min_step: 1e-6,
            max_step: 0.2,
            tolerance: 1e-9,
            max_iterations: 25,
            direction: 1.0,
            save_every: 10,
        }
    }

    /// Only Newton's tolerance and iterations of these, the driver's defaults for the rest:
    /// what an analysis with one Newton solve and no path runs with.
    pub fn newton_only(&self) -> Self {
        Self {
            tolerance: self.tolerance,
            max_iterations: self.max_iterations,
            ..Self::default()
        }
    }

    /// These with no state saved along the way (`save_every` never reached).
    pub fn saving_no_states(&self) -> Self {
        Self {
            save_every: usize::MAX,
            ..self.clone()
        }
    }
}

impl PathOptions {
    /// The options of a path with `settings`, its control within `bounds`, q in units of
    /// `state_scale` and `free` free parameters in units of one.
    pub fn new(settings: &Settings, bounds: (f64, f64), state_scale: f64, free: usize) -> Self {
        Self {
            initial_step: settings.initial_step,
            min_step: settings.min_step,
            max_step: settings.max_step,
            max_steps: settings.steps,
            max_iterations: settings.max_iterations,
            tolerance: settings.tolerance,
            bounds,
            parameter_scales: vec![1.0; free.max(1)],
            state_scale,
            direction: settings.direction,
        }
    }

    /// The unit of free parameter j (1 where none is given).
    pub fn parameter_scale(&self, j: usize) -> f64 {
        self.parameter_scales.get(j).copied().unwrap_or(1.0)
    }
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

/// Newton in (q, λ_1 … λ_c) at a fixed control λ_0, from (q0, λ0); at least 20 iterations.
/// Returns q, λ and the iterations taken.
pub fn solve_at<P: Problem + ?Sized>(
    problem: &mut P,
    q0: &DVector<f64>,
    lambda0: &DVector<f64>,
    opts: &PathOptions,
) -> Result<(DVector<f64>, DVector<f64>, usize), SolveError> {
    let (mut q, mut lambda) = (q0.clone(), lambda0.clone());
    let budget = opts.max_iterations.max(20);
    let (mut residual, mut correction) = (f64::NAN, f64::NAN);
    for it in 1..=budget {
        let step = newton_step(problem, &q, &lambda, opts)?;
        residual = step.residual;
        let d = step.correction;
        correction = d.amax();
        apply_correction(&mut q, &mut lambda, &d, opts)?;
        if step.converged && d.amax() <= opts.tolerance {
            return Ok((q, lambda, it));
        }
    }
    Err(SolveError::NotConverged {
        control: lambda[0],
        iterations: budget,
        residual,
        correction,
        tolerance: opts.tolerance,
    })
}

/// Relative residual (of the force scale) at which an iterate is taken to be at round-off.
pub const ROUND_OFF: f64 = 1e-11;

/// A state [`solve_at_or_drift`] accepted at round-off: its residual is at round-off of the
/// force scale, but Newton's correction did not become small — the tangent is near-singular
/// along a direction nothing holds (a free rigid motion, a neutral mode), and round-off drives
/// the iterates along it.
#[derive(Debug, Clone)]
pub struct Drift {
    /// max |R| relative to the force scale at the accepted state.
    pub residual: f64,
    /// The last correction over q (in the scaled unknowns: q / state scale): the
    /// near-singular direction.
    pub correction: DVector<f64>,
}

/// What [`solve_at_or_drift`] returns: q, λ, the iterations taken, and the drift when the
/// state was accepted at round-off.
pub type DriftingSolve = (DVector<f64>, DVector<f64>, usize, Option<Drift>);

/// As [`solve_at`], but a state whose residual stays at round-off ([`ROUND_OFF`], and the
/// residual test met) for three iterations while the correction does not become small is
/// accepted, with the [`Drift`] that says so, instead of a failure once the budget is used.
pub fn solve_at_or_drift<P: Problem + ?Sized>(
    problem: &mut P,
    q0: &DVector<f64>,
    lambda0: &DVector<f64>,
    opts: &PathOptions,
) -> Result<DriftingSolve, SolveError> {
    let m = problem.dim();
    let (mut q, mut lambda) = (q0.clone(), lambda0.clone());
    let budget = opts.max_iterations.max(20);
    let (mut residual, mut correction) = (f64::NAN, f64::NAN);
    let mut at_round_off = 0usize;
    for it in 1..=budget {
        let step = newton_step(problem, &q, &lambda, opts)?;
        residual = step.residual;
        let d = step.correction;
        correction = d.amax();
        if step.converged && d.amax() <= opts.tolerance {
            apply_correction(&mut q, &mut lambda, &d, opts)?;
            return Ok((q, lambda, it, None));
        }
        if step.converged && step.residual <= ROUND_OFF {
            at_round_off += 1;
            if at_round_off == 3 {
                // (q, λ) met the residual test before this correction: keep it.
                let drift = Drift {
                    residual: step.residual,
                    correction: d.rows(0, m).into_owned(),
                };
                return Ok((q, lambda, it, Some(drift)));
            }
        } else {
            at_round_off = 0;
        }
        apply_correction(&mut q, &mut lambda, &d, opts)?;
    }
    Err(SolveError::NotConverged {
        control: lambda[0],
        iterations: budget,
        residual,
        correction,
        tolerance: opts.tolerance,
    })
}

/// Adds the scaled correction `d` of (q, λ_0, λ_1 … λ_c) (the control's entry unused) to
/// (q, λ): the update of every Newton solve at a fixed control. Fails when the iterates
/// leave the finite numbers.
pub(super) fn apply_correction(
    q: &mut DVector<f64>,
    lambda: &mut DVector<f64>,
    d: &DVector<f64>,
    opts: &PathOptions,
) -> Result<(), SolveError> {
    let m = q.len();
    *q += d.rows(0, m) * opts.state_scale;
    for j in 1..lambda.len() {
        lambda[j] += d[m + j] * opts.parameter_scale(j);
    }
    if !(q.iter().all(|v| v.is_finite()) && lambda.iter().all(|v| v.is_finite())) {
        return Err(SolveError::Diverged { control: lambda[0] });
    }
    Ok(())
}

/// One Newton step at a fixed control λ_0 from (q, λ).
pub(super) struct NewtonStep {
    /// The scaled correction of (q, λ_0, λ_1 … λ_c), the control's 0.
    pub correction: DVector<f64>,
    /// Whether (q, λ) already met the residual test.
    pub converged: bool,
    /// Its relative residual.
    pub residual: f64,
}

/// The Newton step of [`solve_at`] at (q, λ): the corrector's bordered system with the
/// arclength row replaced by "control fixed".
pub(super) fn newton_step<P: Problem + ?Sized>(
    problem: &mut P,
    q: &DVector<f64>,
    lambda: &DVector<f64>,
    opts: &PathOptions,
) -> Result<NewtonStep, SolveError> {
    // A signal stops every solve at a fixed control between its iterations (not inside a
    // factorisation).
    if super::interrupt::requested() {
        return Err(SolveError::Interrupted);
    }
    let m = problem.dim();
    let lin = problem.evaluate(q, lambda)?;
    let c = lin.constraints.len();
    let mut last = DVector::zeros(m + c + 1);
    last[m] = 1.0;
    let a = lin.extended(opts, &last);
    let mut rhs = DVector::zeros(m + c + 1);
    rhs.rows_mut(0, m).copy_from(&(-&lin.residual));
    rhs.rows_mut(m, c).copy_from(&(-&lin.constraints));
    let correction = a
        .solve(&rhs)
        .ok_or(SolveError::Singular { control: lambda[0] })?;
    super::interrupt::iteration_done();
    Ok(NewtonStep {
        correction,
        converged: lin.converged(opts),
        residual: lin.relative_residual(opts),
    })
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

/// The converged point of `problem` at (q, λ), with its tangent oriented so that the
/// control moves in `opts.direction` (or along `previous`, when given): a start for
/// [`Continuation::new`] from any solution.
pub fn point_at<P: Problem + ?Sized>(
    problem: &mut P,
    q: DVector<f64>,
    lambda: DVector<f64>,
    iterations: usize,
    opts: &PathOptions,
    previous: Option<&DVector<f64>>,
) -> Result<PathPoint, SolveError> {
    let lin = problem.evaluate(&q, &lambda)?;
    let tangent = tangent_at(&lin, opts, previous).ok_or(SolveError::SingularTangent)?;
    Ok(PathPoint {
        q,
        lambda,
        arclength: 0.0,
        iterations,
        tangent,
    })
}

/// One predictor–corrector step from `from` with arclength `s` along `from.tangent`.
pub fn step_from<P: Problem + ?Sized>(
    problem: &mut P,
    from: &PathPoint,
    s: f64,
    opts: &PathOptions,
) -> Result<PathPoint, StepError> {
    step_on_plane(
        problem,
        from,
        &from.tangent,
        &from.tangent,
        s,
        s,
        opts,
        true,
    )
}

/// The converged point of one predictor–corrector step, without the new tangent and the
/// branch-jump guard (its `tangent` is `from`'s): what localising an eigenvalue between two
/// accepted points needs, also next to a branch point of the path, where the tangent is
/// ill-defined.
pub fn corrected_from<P: Problem + ?Sized>(
    problem: &mut P,
    from: &PathPoint,
    s: f64,
    opts: &PathOptions,
) -> Result<PathPoint, StepError> {
    step_on_plane(
        problem,
        from,
        &from.tangent,
        &from.tangent,
        s,
        s,
        opts,
        false,
    )
}

/// A step off a branch point along `direction` (a unit vector in scaled variables, like a
/// tangent) whose corrector stays on the plane `planeᵀ (y − y_from) = planeᵀ direction · s`
/// instead of the plane normal to the direction: with `plane` the kernel direction of a
/// bifurcation (no control component), every other branch through the point — the path
/// itself, whose states have no component along the kernel — is off that plane. The
/// new point's tangent is oriented along `direction`, and the branch-jump guard compares
/// with it.
pub fn step_off<P: Problem + ?Sized>(
    problem: &mut P,
    from: &PathPoint,
    direction: &DVector<f64>,
    plane: &DVector<f64>,
    s: f64,
    opts: &PathOptions,
) -> Result<PathPoint, StepError> {
    let value = plane.dot(direction) * s;
    step_on_plane(problem, from, direction, plane, value, s, opts, true)
}

/// A solve on the plane `planeᵀ (y − y_from) = planeᵀ direction · s` from the predictor
/// y_from + s·direction, without the branch-jump guard (its `tangent` is `direction`): with
/// `plane` a critical mode and no control component, the state at a fixed amplitude along the
/// mode, the control free — wherever it lies, also on another piece of solutions.
pub fn solve_on_plane<P: Problem + ?Sized>(
    problem: &mut P,
    from: &PathPoint,
    direction: &DVector<f64>,
    plane: &DVector<f64>,
    s: f64,
    opts: &PathOptions,
) -> Result<PathPoint, StepError> {
    let value = plane.dot(direction) * s;
    step_on_plane(problem, from, direction, plane, value, s, opts, false)
}

/// Predictor y_from + s·direction, corrector on R = 0, g = 0, planeᵀ (y − y_from) = value
/// (scaled variables; the extended Jacobian's last row is `plane`); when `guarded`, the
/// tangent oriented along `direction` and the branch-jump guard against the predictor and
/// `direction`, else the converged point with `direction` as its tangent.
#[allow(clippy::too_many_arguments)]
fn step_on_plane<P: Problem + ?Sized>(
    problem: &mut P,
    from: &PathPoint,
    direction: &DVector<f64>,
    plane: &DVector<f64>,
    value: f64,
    s: f64,
    opts: &PathOptions,
    guarded: bool,
) -> Result<PathPoint, StepError> {
    let m = problem.dim();
    let nl = from.lambda.len();
    let sq = opts.state_scale;
    let sl = |j: usize| opts.parameter_scale(j);
    let t = direction;
    let mut q = &from.q + t.rows(0, m) * (s * sq);
    let mut lambda = from.lambda.clone();
    for j in 0..nl {
        lambda[j] += t[m + j] * s * sl(j);
    }
    // The step's own direction is its plane's normal: the tangent at a converged iterate
    // then solves the same bordered system, and comes from the same factorisation.
    let same_plane = guarded && std::ptr::eq(plane, direction);
    let arclength_of = |q: &DVector<f64>, lambda: &DVector<f64>| {
        let mut arc = plane.rows(0, m).dot(&(q - &from.q)) / sq - value;
        for j in 0..nl {
            arc += plane[m + j] * (lambda[j] - from.lambda[j]) / sl(j);
        }
        arc
    };
    // G = [R; g; the arclength equation] at (q, λ).
    let stacked = |residual: &DVector<f64>,
                   constraints: &DVector<f64>,
                   q: &DVector<f64>,
                   lambda: &DVector<f64>| {
        let c = constraints.len();
        let mut g = DVector::zeros(m + c + 1);
        g.rows_mut(0, m).copy_from(residual);
        g.rows_mut(m, c).copy_from(constraints);
        g[m + c] = arclength_of(q, lambda);
        g
    };
    let mut e = DVector::zeros(0);
    // The last iteration's system and linearisation, kept when its correction foretells a
    // converged next iterate, and the size of the correction before it.
    let mut chord: Option<(Extended, Linearization)> = None;
    let mut before: Option<f64> = None;
    // The iterate's evaluation when a chord check made it and did not end the corrector.
    let mut evaluated: Option<Linearization> = None;
    for it in 1..=opts.max_iterations {
        match chord.take() {
            None => {}
            Some(_) if same_plane => {
                // Newton's next correction is foretold to be below the tolerance, and the tangent
                // is wanted at the point: the iterate's own system, solved with the kept factors
                // as its preconditioner and refined to round-off, gives the correction and the
                // tangent its factorisation would, without factorising.
                let now = problem.evaluate(&q, &lambda)?;
                if now.converged(opts) {
                    let c = now.constraints.len();
                    let g = stacked(&now.residual, &now.constraints, &q, &lambda);
                    let mut unit = DVector::zeros(m + c + 1);
                    unit[m + c] = 1.0;
                    if let Some(mut xs) = now
                        .extended(opts, plane)
                        .resolve_all(&[&(-&g), &unit])
                        .filter(|xs| xs[0].amax() <= opts.tolerance)
                    {
                        #[cfg(test)]
                        CHORD_ENDED_STEPS.with(|c| c.set(c.get() + 1));
                        let tangent = xs.pop();
                        let d = xs.pop().ok_or(StepError::Singular)?;
                        advance(&mut q, &mut lambda, &d, opts)?;
                        return accept(
                            problem,
                            from,
                            t,
                            (q, lambda),
                            tangent,
                            (s, it),
                            opts,
                            guarded,
                        );
                    }
                }
                evaluated = Some(now);
            }
            Some((a, lin)) => {
                // Newton's next correction is foretold to be below the tolerance: check the
                // iterate on R and g alone and a chord step of the kept factorisation. Where that
                // fails the iteration goes on as if it had not been tried.
                let (residual, constraints) = problem.residual(&q, &lambda)?;
                if lin.converges(&residual, &constraints, opts) {
                    let g = stacked(&residual, &constraints, &q, &lambda);
                    // Only unguarded solves take the chord: no tangent is wanted at the point.
                    if let Some(mut xs) = a
                        .resolve_all(&[&(-&g)])
                        .filter(|xs| xs[0].amax() <= opts.tolerance)
                    {
                        let d = xs.swap_remove(0);
                        advance(&mut q, &mut lambda, &d, opts)?;
                        return accept(problem, from, t, (q, lambda), None, (s, it), opts, guarded);
                    }
                }
            }
        }
        let lin = match evaluated.take() {
            Some(lin) => lin,
            None => problem.evaluate(&q, &lambda)?,
        };
        let c = lin.constraints.len();
        let a = lin.extended(opts, plane);
        let g = stacked(&lin.residual, &lin.constraints, &q, &lambda);
        let converged = lin.converged(opts);
        if e.len() != m + c + 1 {
            e = DVector::zeros(m + c + 1);
            e[m + c] = 1.0;
        }
        let rhs = -&g;
        let (d, tangent) = if same_plane && converged {
            let mut xs = a.solve_all(&[&rhs, &e]).ok_or(StepError::Singular)?;
            let tangent = xs.pop().ok_or(StepError::Singular)?;
            (xs.pop().ok_or(StepError::Singular)?, Some(tangent))
        } else {
            let mut xs = a.solve_all(&[&rhs]).ok_or(StepError::Singular)?;
            (xs.pop().ok_or(StepError::Singular)?, None)
        };
        advance(&mut q, &mut lambda, &d, opts)?;
        if converged && d.amax() <= opts.tolerance {
            return accept(
                problem,
                from,
                t,
                (q, lambda),
                tangent,
                (s, it),
                opts,
                guarded,
            );
        }
        // Quadratic convergence foretells the next correction, |d_{k+1}| ≈ |d_k|³/|d_{k−1}|²
        // (from |d_{k+1}| ≈ C |d_k|², C ≈ |d_k|/|d_{k−1}|²); a next iterate foretold well
        // within the tolerance is checked by a chord step instead of a new factorisation.
        let size = d.amax();
        // Where no tangent is wanted at the point, or where it comes from the step's own
        // system (refined against the iterate's matrix: a tangent from the iterate before
        // would move the next predictor and arclength plane, and with them where the path's
        // points and its branches' points fall). A dense system is factorised again anyway.
        let sparse = matches!(lin.tangent, Tangent::Sparse { .. });
        if let Some(b) =
            before.filter(|&b| (!guarded || same_plane && sparse) && b > 0.0 && size < b)
        {
            if size.powi(3) / (b * b) <= CHORD_MARGIN * opts.tolerance {
                chord = Some((a, lin));
            }
        }
        before = Some(size);
    }
    Err(StepError::NotConverged {
        iterations: opts.max_iterations,
    })
}

/// Adds the scaled correction `d` to (q, λ); an iterate that is not finite has diverged.
fn advance(
    q: &mut DVector<f64>,
    lambda: &mut DVector<f64>,
    d: &DVector<f64>,
    opts: &PathOptions,
) -> Result<(), StepError> {
    let m = q.len();
    *q += d.rows(0, m) * opts.state_scale;
    for j in 0..lambda.len() {
        lambda[j] += d[m + j] * opts.parameter_scale(j);
    }
    if q.iter().all(|v| v.is_finite()) && lambda.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(StepError::Diverged)
    }
}

#[cfg(test)]
thread_local! {
    /// Path steps ended by the preconditioned chord check, on this thread (for the tests).
    static CHORD_ENDED_STEPS: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// How far below the corrector's tolerance the next correction must be foretold before the
/// converged iterate is checked by a chord step (a wrong forecast costs one evaluation of R
/// and g).
const CHORD_MARGIN: f64 = 0.1;

/// The converged point (q, λ) of a step of arclength `s` from `from` along `t`, found at
/// iteration `it`: with the tangent of its last factorisation (`tangent`, or a new one) and
/// the branch-jump guard when `guarded`, else with `t` as its tangent.
#[allow(clippy::too_many_arguments)]
fn accept<P: Problem + ?Sized>(
    problem: &mut P,
    from: &PathPoint,
    t: &DVector<f64>,
    (q, lambda): (DVector<f64>, DVector<f64>),
    tangent: Option<DVector<f64>>,
    (s, it): (f64, usize),
    opts: &PathOptions,
    guarded: bool,
) -> Result<PathPoint, StepError> {
    let m = q.len();
    let nl = lambda.len();
    let sq = opts.state_scale;
    let sl = |j: usize| opts.parameter_scale(j);
    if !guarded {
        return Ok(PathPoint {
            q,
            lambda,
            arclength: from.arclength + s,
            iterations: it,
            tangent: t.clone(),
        });
    }
    // The tangent at the converged iterate, before its last correction (within the
    // corrector's tolerance of the point), from its factorisation; else at the point.
    let tangent = match tangent {
        Some(x) if x.norm() > 0.0 => {
            let x = &x / x.norm();
            if x.dot(t) < 0.0 {
                -x
            } else {
                x
            }
        }
        _ => {
            let lin = problem.evaluate(&q, &lambda)?;
            tangent_at(&lin, opts, Some(t)).ok_or(StepError::SingularTangent)?
        }
    };
    // Stay on the branch: the corrector must end near the predictor and the tangent
    // must not turn sharply; otherwise the step is cut rather than a jump accepted.
    let mut dist2 = (&q - &from.q - t.rows(0, m) * (s * sq)).norm_squared() / (sq * sq);
    for j in 0..nl {
        dist2 += ((lambda[j] - from.lambda[j] - t[m + j] * s * sl(j)) / sl(j)).powi(2);
    }
    if dist2.sqrt() > MAX_CORRECTOR_DISTANCE * s || tangent.dot(t) < MIN_TANGENT_COSINE {
        return Err(StepError::BranchJump {
            distance: dist2.sqrt() / s,
            angle: tangent.dot(t).clamp(-1.0, 1.0).acos().to_degrees(),
        });
    }
    if let Some(defect) = problem.defect(&q, &lambda) {
        return Err(StepError::Degenerate(defect));
    }
    Ok(PathPoint {
        q,
        lambda,
        arclength: from.arclength + s,
        iterations: it,
        tangent,
    })
}

/// Iterations [`zero_on_step`] takes at most before its caller falls back to a search with a
/// converged corrector at every trial.
const ZERO_ITERATIONS: usize = 24;

/// Settled iterates in a row whose test function stays above the tolerance without halving
/// after which [`zero_on_step`] gives up.
const ZERO_STALLS: usize = 3;

/// A state of one step where a test function changes sign: the two sides of the search as
/// (arclength from the earlier point, the function's value there).
#[derive(Debug, Clone, Copy)]
pub struct SignChange {
    /// The side of the earlier end: (s, g).
    pub first: (f64, f64),
    /// The side of the later end: (s, g), g of the other sign.
    pub second: (f64, f64),
    /// |g| at or below which the zero is found.
    pub tolerance: f64,
    /// The arclength to which the zero is located once |g| is within the tolerance: the
    /// search goes on until Newton's next move along the step is shorter (or |g| stops
    /// decreasing, at round-off).
    pub width: f64,
}

/// A converged state on one side of a sign change: (arclength from the earlier point, q, λ).
pub type SideState = (f64, DVector<f64>, DVector<f64>);

/// The test function of [`zero_on_step`]: its value at (q, λ) of the problem, with the
/// iterate's unit tangent.
pub type StepTest<'a, P> =
    dyn FnMut(&P, &DVector<f64>, &DVector<f64>, &DVector<f64>) -> Option<f64> + 'a;

/// A zero found by [`zero_on_step`]: the state, its test-function value, its arclength from
/// the earlier point, and the converged states nearest to it found on each side of the sign
/// change (the first side's, the second side's: `None` where the search found none inside
/// the step, the caller's ends then standing for them).
#[derive(Debug, Clone)]
pub struct ZeroOnStep {
    /// The state.
    pub point: PathPoint,
    /// The test function there.
    pub value: f64,
    /// The nearest converged states found on each side: (s, q, λ).
    pub sides: [Option<SideState>; 2],
    /// Newton iterations taken (evaluations of the problem).
    pub iterations: usize,
}

/// Newton on the augmented system R(y) = 0, g(y) = 0, τ(y) = 0 in y = (q, λ) along the step
/// from `from` (docs/theory.md §11.2): τ's gradient taken along the step's direction t only,
/// ∇τ ≈ τ' t with τ' its secant slope along the arclength, each iteration is one solve of
/// the corrector's bordered system with the arclength row's target moved to
/// s − τ(y)/τ' — one evaluation and one factorisation per iteration, for the state and the
/// crossing together, where a search on the arclength converges a whole corrector at every
/// trial. τ (`test`, at (q, λ) of the problem, with the iterate's unit tangent) is evaluated
/// only at settled iterates: their residual passes the corrector's test and their next
/// correction at a fixed arclength is within the corrector's tolerance (one correction
/// farther off the path, τ of a slowly crossing eigenvalue is off by more than its
/// tolerance); between them the iterates converge the state at the present target. The
/// secant is taken through the last two settled iterates where they lie apart along the
/// step, else through the bracket of settled states of either sign, and the target is kept
/// inside that bracket (regula falsi of the bracket where the secant leaves it). Returns the
/// first settled iterate whose |τ| is at most `change.tolerance` and whose next secant move
/// is within `change.width` (or whose |τ| no longer halves: round-off); `None` if that takes
/// more than [`ZERO_ITERATIONS`] iterations, |τ| stalls above the tolerance for
/// [`ZERO_STALLS`] settled iterates, or any evaluation or solve fails.
pub fn zero_on_step<P: Problem + ?Sized>(
    problem: &mut P,
    from: &PathPoint,
    change: SignChange,
    test: &mut StepTest<'_, P>,
    opts: &PathOptions,
) -> Option<ZeroOnStep> {
    let m = problem.dim();
    let nl = from.lambda.len();
    let sq = opts.state_scale;
    let sl = |j: usize| opts.parameter_scale(j);
    let t = &from.tangent;
    let arclength = |q: &DVector<f64>, lambda: &DVector<f64>| -> f64 {
        let mut s = t.rows(0, m).dot(&(q - &from.q)) / sq;
        for j in 0..nl {
            s += t[m + j] * (lambda[j] - from.lambda[j]) / sl(j);
        }
        s
    };
    // The bracket of converged states: (s, g) on the first side and on the second.
    let (mut lo, mut hi) = (change.first, change.second);
    let regula_falsi = |lo: (f64, f64), hi: (f64, f64)| -> f64 {
        let s = (lo.0 * hi.1 - hi.0 * lo.1) / (hi.1 - lo.1);
        if s.is_finite() && s > lo.0.min(hi.0) && s < lo.0.max(hi.0) {
            s
        } else {
            0.5 * (lo.0 + hi.0)
        }
    };
    let first_sign = change.first.1 > 0.0;
    let mut target = regula_falsi(lo, hi);
    let mut q = &from.q + t.rows(0, m) * (target * sq);
    let mut lambda = from.lambda.clone();
    for j in 0..nl {
        lambda[j] += t[m + j] * target * sl(j);
    }
    let mut sides: [Option<SideState>; 2] = [None, None];
    let mut previous: Option<(f64, f64)> = None;
    // |g| at the last settled iterate, and the settled iterates in a row since |g| last
    // halved.
    let mut last_settled = f64::INFINITY;
    let mut stalled = 0;
    for it in 1..=ZERO_ITERATIONS {
        if super::interrupt::requested() {
            return None;
        }
        let lin = problem.evaluate(&q, &lambda).ok()?;
        let converged = lin.converged(opts);
        let c = lin.constraints.len();
        let here = arclength(&q, &lambda);
        // One factorisation for both: the correction d0 at the present arclength and x with
        // J x = e (the arclength row's unit), the tangent's direction; the correction to a
        // target arclength s is d0 + (s − here) x, the plane's row being linear.
        let mut r = DVector::zeros(m + c + 1);
        r.rows_mut(0, m).copy_from(&lin.residual);
        r.rows_mut(m, c).copy_from(&lin.constraints);
        r.neg_mut();
        let mut e = DVector::zeros(m + c + 1);
        e[m + c] = 1.0;
        let mut xs = lin.extended(opts, t).solve_all(&[&r, &e])?;
        let x = xs.pop()?;
        let d0 = xs.pop()?;
        // Settled: on the path to the corrector's tolerance and with its next correction at
        // this arclength within it — the test the returned point passes. Only there does g
        // say where along the step the zero lies: at a slow crossing, g of a state one
        // correction away from the path is off by more than the tolerance (and can have
        // the other sign), and a secant through it moves the target at random.
        if converged && d0.amax() <= opts.tolerance {
            let norm = x.norm();
            if !(norm > 0.0 && norm.is_finite()) {
                return None;
            }
            let tangent = if x.dot(t) < 0.0 {
                -&x / norm
            } else {
                &x / norm
            };
            let g = test(&*problem, &q, &lambda, &tangent)?;
            if !g.is_finite() {
                return None;
            }
            // A settled state narrows the bracket on its side.
            let side = usize::from((g > 0.0) != first_sign);
            if side == 0 {
                lo = (here, g);
            } else {
                hi = (here, g);
            }
            sides[side] = Some((here, q.clone(), lambda.clone()));
            // The secant through the previous settled state, where the two lie apart along
            // the step (two states at one arclength differ in g by their corrections only);
            // else the bracket's.
            let slope = match previous {
                Some((s0, g0)) if (here - s0).abs() > change.width && g != g0 => {
                    (g - g0) / (here - s0)
                }
                _ => (hi.1 - lo.1) / (hi.0 - lo.0),
            };
            let next = here - g / slope;
            // Within the tolerance, and either at the zero to the width asked for or at
            // round-off (|g| no longer halves from one settled state to the next).
            if g.abs() <= change.tolerance
                && ((next - here).abs() <= change.width || g.abs() > 0.5 * last_settled)
            {
                if problem.defect(&q, &lambda).is_some() {
                    return None;
                }
                return Some(ZeroOnStep {
                    point: PathPoint {
                        q,
                        lambda,
                        arclength: from.arclength + here,
                        iterations: it,
                        tangent,
                    },
                    value: g,
                    sides,
                    iterations: it,
                });
            }
            // |g| above the tolerance and no longer halving: at the noise of its states,
            // not at a zero; the caller's search takes over.
            if g.abs() > change.tolerance && g.abs() > 0.5 * last_settled {
                stalled += 1;
                if stalled == ZERO_STALLS {
                    return None;
                }
            } else {
                stalled = 0;
            }
            last_settled = g.abs();
            let inside = next.is_finite() && next > lo.0.min(hi.0) && next < lo.0.max(hi.0);
            target = if inside { next } else { regula_falsi(lo, hi) };
            previous = Some((here, g));
        }
        let d = d0 + x * (target - here);
        q += d.rows(0, m) * sq;
        for j in 0..nl {
            lambda[j] += d[m + j] * sl(j);
        }
        if !(q.iter().all(|v| v.is_finite()) && lambda.iter().all(|v| v.is_finite())) {
            return None;
        }
    }
    None
}

/// Why the driver could not advance: every step was cut below the minimum.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("step cut below {min_step:e} after point {after} (control = {}): {why}", crate::text::num(*.control))]
pub struct Stalled {
    /// The minimum step.
    pub min_step: f64,
    /// The index of the last accepted point.
    pub after: usize,
    /// The control's value there.
    pub control: f64,
    /// Why the last attempt failed.
    pub why: StepError,
    /// The end of the control's range that the last attempt's predictor crossed, where the
    /// model could not be evaluated, if it did.
    pub bound: Option<f64>,
}

impl From<Stalled> for crate::results::Stalled {
    /// The plain-data record of a stall, the failure kept as its message.
    fn from(s: Stalled) -> Self {
        Self {
            min_step: s.min_step,
            after: s.after,
            control: s.control,
            kind: s.why.failure(),
            why: s.why.to_string(),
        }
    }
}

impl StepError {
    /// Its kind, as plain data.
    pub fn failure(&self) -> crate::results::StepFailure {
        use crate::results::StepFailure as F;
        match self {
            Self::Model(_) => F::Model,
            Self::Singular | Self::SingularTangent => F::Singular,
            Self::Diverged => F::Diverged,
            Self::BranchJump { .. } => F::BranchJump,
            Self::Degenerate(_) => F::Degenerate,
            Self::NotConverged { .. } => F::NotConverged,
        }
    }
}

/// An accepted step.
#[derive(Debug, Clone)]
pub struct Accepted {
    /// The point it started from.
    pub from: PathPoint,
    /// The arclength step it took.
    pub step: f64,
}

/// The stepping driver: from a converged point and its tangent, one accepted point per call
/// of [`Continuation::step`], with step control (grow after easy correctors, shrink after
/// hard ones, halve after failures).
pub struct Continuation<P> {
    problem: P,
    opts: PathOptions,
    point: PathPoint,
    /// Accepted points so far, the start included.
    accepted: usize,
    /// The next step to try.
    next_step: f64,
    /// The zeros [`Continuation::zero_on_step`] located on steps from the current point
    /// (each with the arclength and parameters of the point it stepped from), until the
    /// driver moves.
    located: Vec<(f64, DVector<f64>, ZeroOnStep)>,
}

impl<P: Problem> Continuation<P> {
    /// A driver at `point` (converged, with its unit tangent), stepping first by
    /// `opts.initial_step`.
    pub fn new(problem: P, point: PathPoint, opts: PathOptions) -> Self {
        Self {
            problem,
            next_step: opts.initial_step,
            opts,
            point,
            accepted: 1,
            located: Vec::new(),
        }
    }

    /// Solves (q0, λ0) at its control value, then starts there with the tangent that moves
    /// the control in `opts.direction`. A state at round-off along a direction nothing holds
    /// is accepted ([`solve_at_or_drift`]; the start solve of the study warns of it).
    pub fn start(
        mut problem: P,
        q0: &DVector<f64>,
        lambda0: &DVector<f64>,
        opts: PathOptions,
    ) -> Result<Self, SolveError> {
        let (q, lambda, iterations, _) = solve_at_or_drift(&mut problem, q0, lambda0, &opts)?;
        let point = point_at(&mut problem, q, lambda, iterations, &opts, None)?;
        Ok(Self::new(problem, point, opts))
    }

    /// The current (last accepted) point.
    pub fn point(&self) -> &PathPoint {
        &self.point
    }

    /// The options.
    pub fn options(&self) -> &PathOptions {
        &self.opts
    }

    /// The problem.
    pub fn problem(&self) -> &P {
        &self.problem
    }

    /// The problem, mutably (for evaluations between steps).
    pub fn problem_mut(&mut self) -> &mut P {
        &mut self.problem
    }

    /// Gives the problem back.
    pub fn into_problem(self) -> P {
        self.problem
    }

    /// Accepted points so far, the start included.
    pub fn accepted(&self) -> usize {
        self.accepted
    }

    /// Advances to the next accepted point; the step is halved after each failure, and the
    /// driver stalls when it falls below the minimum. Returns the step taken and the point
    /// it started from; [`Continuation::point`] is the new point.
    pub fn step(&mut self) -> Result<Accepted, Stalled> {
        loop {
            let s = self.next_step;
            match step_from(&mut self.problem, &self.point, s, &self.opts) {
                Ok(next) => {
                    // Step control: grow after easy steps, shrink after hard ones.
                    if next.iterations <= 3 {
                        self.next_step = (s * 1.5).min(self.opts.max_step);
                    } else if next.iterations >= 6 {
                        self.next_step = s * 0.7;
                    }
                    self.accepted += 1;
                    self.located.clear();
                    super::interrupt::step_accepted();
                    let from = std::mem::replace(&mut self.point, next);
                    return Ok(Accepted { from, step: s });
                }
                Err(why) => {
                    self.next_step = s * 0.5;
                    if self.next_step < self.opts.min_step {
                        // Only a model that cannot be evaluated there ends at the bound.
                        let bound = matches!(why, StepError::Model(_))
                            .then(|| self.bound_ahead(s))
                            .flatten();
                        return Err(Stalled {
                            bound,
                            min_step: self.opts.min_step,
                            after: self.accepted - 1,
                            control: self.point.lambda[0],
                            why,
                        });
                    }
                }
            }
        }
    }

    /// The end of the control's range that a step of arclength `s` from the current point
    /// would cross on its predictor, if any.
    fn bound_ahead(&self, s: f64) -> Option<f64> {
        let p = &self.point;
        let ahead = p.lambda[0] + s * p.tangent[p.q.len()] * self.opts.parameter_scale(0);
        let (lo, hi) = self.opts.bounds;
        if ahead < lo {
            Some(lo)
        } else if ahead > hi {
            Some(hi)
        } else {
            None
        }
    }

    /// Takes back the accepted `step`: the driver is at its earlier point again and tries
    /// `factor` times the step next.
    pub fn retreat(&mut self, step: Accepted, factor: f64) {
        self.next_step = step.step * factor;
        self.point = step.from;
        self.accepted -= 1;
        self.located.clear();
    }

    /// The point reached by one predictor–corrector step of arclength `s` from `from` (for
    /// localising an event between two accepted points); the driver's state is unchanged.
    pub fn step_from(&mut self, from: &PathPoint, s: f64) -> Result<PathPoint, StepError> {
        step_from(&mut self.problem, from, s, &self.opts)
    }

    /// The zero of `test` between `from` and the point `s` along its tangent where it has
    /// changed sign ([`zero_on_step`]); the driver's point and step are unchanged.
    ///
    /// A zero located before on a step from the same point is tried first: where `test`
    /// vanishes there too — to its tolerance, and with the secant of the step's ends moving
    /// it by less than the width — that state is the zero, found without iterating (a limit
    /// point is both a turning point of the control and a crossing of the trivial block).
    pub fn zero_on_step(
        &mut self,
        from: &PathPoint,
        change: SignChange,
        test: &mut StepTest<'_, P>,
    ) -> Option<ZeroOnStep> {
        let (lo, hi) = (
            change.first.0.min(change.second.0),
            change.first.0.max(change.second.0),
        );
        let slope = (change.second.1 - change.first.1) / (change.second.0 - change.first.0);
        for (s0, l0, zero) in &self.located {
            let s = zero.point.arclength - from.arclength;
            if *s0 != from.arclength || *l0 != from.lambda || !(s > lo && s < hi) {
                continue;
            }
            let p = &zero.point;
            let Some(g) = test(&self.problem, &p.q, &p.lambda, &p.tangent) else {
                continue;
            };
            if g.abs() <= change.tolerance && (g / slope).abs() <= change.width {
                return Some(ZeroOnStep {
                    value: g,
                    iterations: 0,
                    ..zero.clone()
                });
            }
        }
        let found = zero_on_step(&mut self.problem, from, change, test, &self.opts)?;
        self.located
            .push((from.arclength, from.lambda.clone(), found.clone()));
        Some(found)
    }

    /// As [`Continuation::step_from`] without the new tangent and the branch-jump guard
    /// ([`corrected_from`]).
    pub fn corrected_from(&mut self, from: &PathPoint, s: f64) -> Result<PathPoint, StepError> {
        corrected_from(&mut self.problem, from, s, &self.opts)
    }
}

#[cfg(test)]
mod tests {
    use super::{point_at, zero_on_step, PathOptions, Problem, SignChange, Stalled, StepError};
    use nalgebra::DVector;

    /// R(q, λ) = q² + λ² − 1 (one unknown): a circle, whose λ turns at q = 0, λ = 1.
    fn circle() -> impl Problem {
        super::Scalar(|q: f64, l: f64| Ok((q * q + l * l - 1.0, 2.0 * q, 2.0 * l)))
    }

    /// The circle's state the tests start from, (q, λ) = (Q0, L0).
    const Q0: f64 = -0.8;
    const L0: f64 = 0.6;

    /// The converged point of a circle problem at (Q0, L0), its tangent towards growing λ.
    fn circle_start(circle: &mut (impl Problem + ?Sized), opts: &PathOptions) -> super::PathPoint {
        let at = |v: f64| DVector::from_element(1, v);
        point_at(circle, at(Q0), at(L0), 1, opts, None).unwrap()
    }

    /// The arclength along the tangent at `from` (the circle's start) to the state at angle θ
    /// (q = −cos θ, λ = sin θ).
    fn arclength_to(from: &super::PathPoint, theta: f64) -> f64 {
        let (q, l) = (-theta.cos(), theta.sin());
        from.tangent[0] * (q - Q0) + from.tangent[1] * (l - L0)
    }

    /// Newton on the path's equation and a test function together finds the test function's
    /// zero on the path — a function of the state, and the tangent's control component (a
    /// turning point) — to the tolerance and width asked for, in a few iterations, with the
    /// converged states it passed on each side of the sign change.
    #[test]
    fn zero_on_step_solves_for_a_state_functions_zero_and_for_a_turning_point() {
        let opts = PathOptions::default();
        let mut circle = circle();
        let q0 = Q0;
        let from = circle_start(&mut circle, &opts);
        let s_at = |theta: f64| arclength_to(&from, theta);
        // q = −0.3 on the way: g = q + 0.3.
        let g = |q: &DVector<f64>| q[0] + 0.3;
        let theta1 = 1.5f64;
        let s1 = s_at(theta1);
        let change = SignChange {
            first: (0.0, q0 + 0.3),
            second: (s1, -theta1.cos() + 0.3),
            tolerance: 1e-12,
            width: 1e-12 * s1,
        };
        let zero = zero_on_step(
            &mut circle,
            &from,
            change,
            &mut |_, q, _, _| Some(g(q)),
            &opts,
        )
        .expect("a zero");
        let (q, l) = (zero.point.q[0], zero.point.lambda[0]);
        assert!((q + 0.3).abs() <= 1e-12, "{q}");
        assert!((q * q + l * l - 1.0).abs() <= 1e-10, "{q} {l}");
        // A strongly curved path: a secant move costs a corrector iteration more while it is long.
        assert!(zero.iterations <= 16, "{}", zero.iterations);
        let [first, second] = &zero.sides;
        if let Some((s, q, _)) = first {
            assert!(g(q) < 0.0 && *s >= 0.0 && *s <= s1);
        }
        if let Some((s, q, _)) = second {
            assert!(g(q) > 0.0 && *s >= 0.0 && *s <= s1);
        }
        // The turning point of λ at θ = π/2, past it at θ = 2.
        let theta2 = 2.0f64;
        let t2 = theta2.cos() * from.tangent[1].signum();
        let change = SignChange {
            first: (0.0, from.tangent[1]),
            second: (s_at(theta2), t2),
            tolerance: 1e-12,
            width: 1e-14,
        };
        assert!(from.tangent[1] > 0.0 && t2 < 0.0);
        let turn = zero_on_step(
            &mut circle,
            &from,
            change,
            &mut |_, _, _, tangent| Some(tangent[1]),
            &opts,
        )
        .expect("a turning point");
        assert!(turn.point.tangent[1].abs() <= 1e-12);
        assert!(
            (turn.point.lambda[0] - 1.0).abs() <= 1e-12,
            "{}",
            turn.point.lambda[0]
        );
        assert!(turn.point.q[0].abs() <= 1e-6, "{}", turn.point.q[0]);
    }

    /// The circle R = q² + λ² − 1 counting its evaluations with derivatives and of R alone.
    struct Counted {
        evaluations: usize,
        residuals: usize,
    }

    impl Problem for Counted {
        fn dim(&self) -> usize {
            1
        }
        fn free_parameters(&self) -> usize {
            1
        }
        fn evaluate(
            &mut self,
            q: &DVector<f64>,
            lambda: &DVector<f64>,
        ) -> Result<super::Linearization, crate::model::ModelError> {
            self.evaluations += 1;
            let (q, l) = (q[0], lambda[0]);
            Ok(super::Linearization::scalar(
                q * q + l * l - 1.0,
                2.0 * q,
                2.0 * l,
            ))
        }
        fn residual(
            &mut self,
            q: &DVector<f64>,
            lambda: &DVector<f64>,
        ) -> Result<(DVector<f64>, DVector<f64>), crate::model::ModelError> {
            self.residuals += 1;
            let r = q[0] * q[0] + lambda[0] * lambda[0] - 1.0;
            Ok((DVector::from_element(1, r), DVector::zeros(0)))
        }
    }

    /// The corrector of a solve that wants no tangent at its point checks an iterate that
    /// Newton's convergence foretells converged on R alone and a chord step of the last
    /// factorisation: the same points as without it (R evaluated with its derivatives), to
    /// the corrector's tolerance, with fewer evaluations of the derivatives than iterations,
    /// the iterations counted as before.
    #[test]
    fn a_foretold_converged_iterate_is_checked_by_a_chord_step() {
        let opts = PathOptions::default();
        let mut counted = Counted {
            evaluations: 0,
            residuals: 0,
        };
        let mut plain = circle();
        let from = circle_start(&mut plain, &opts);
        let mut iterations = 0;
        for k in 1..=12 {
            let s = 0.02 * k as f64;
            let a = super::corrected_from(&mut counted, &from, s, &opts).unwrap();
            let b = super::corrected_from(&mut plain, &from, s, &opts).unwrap();
            let (q, l) = (a.q[0], a.lambda[0]);
            assert!((q * q + l * l - 1.0).abs() <= 1e-10, "{q} {l}");
            assert_eq!(a.iterations, b.iterations);
            assert!((a.q[0] - b.q[0]).abs() <= 1e-9 && (a.lambda[0] - b.lambda[0]).abs() <= 1e-9);
            iterations += a.iterations;
        }
        assert!(counted.residuals > 0);
        assert!(
            counted.evaluations < iterations,
            "{} of {iterations}",
            counted.evaluations
        );
    }

    /// A chain of m unknowns, Π = Σ (q_i⁴/12 + q_i²/2) + ε Σ q_i q_{i+1} − λ Σ w_i q_i: its
    /// tangent diag(q_i² + 1) + ε (neighbours), sparse or dense.
    struct Chain {
        sparse: bool,
        pattern: std::sync::Arc<crate::linalg::SymmetricPattern>,
        solver: crate::linalg::bordered::SharedFactorization,
    }

    impl Chain {
        const M: usize = 30;
        const EPS: f64 = 0.3;
        fn new(sparse: bool) -> Self {
            let m = Self::M;
            let entries = (0..m).map(|i| (i, i)).chain((1..m).map(|i| (i, i - 1)));
            Self {
                sparse,
                pattern: std::sync::Arc::new(crate::linalg::SymmetricPattern::from_entries(
                    m, entries,
                )),
                solver: Default::default(),
            }
        }
        fn w(i: usize) -> f64 {
            1.0 + 0.5 * (i as f64 * 0.7).sin()
        }
    }

    impl Problem for Chain {
        fn dim(&self) -> usize {
            Self::M
        }
        fn free_parameters(&self) -> usize {
            1
        }
        fn evaluate(
            &mut self,
            q: &DVector<f64>,
            lambda: &DVector<f64>,
        ) -> Result<super::Linearization, crate::model::ModelError> {
            let m = Self::M;
            let k = nalgebra::DMatrix::from_fn(m, m, |i, j| {
                if i == j {
                    q[i] * q[i] + 1.0
                } else if i.abs_diff(j) == 1 {
                    Self::EPS
                } else {
                    0.0
                }
            });
            let residual = DVector::from_fn(m, |i, _| {
                q[i].powi(3) / 3.0 + q[i] - lambda[0] * Self::w(i)
                    + Self::EPS * (if i > 0 { q[i - 1] } else { 0.0 })
                    + Self::EPS * (if i + 1 < m { q[i + 1] } else { 0.0 })
            });
            let tangent = if self.sparse {
                let (cp, ri) = (self.pattern.col_ptr(), self.pattern.row_idx());
                let mut values = vec![0.0; self.pattern.nnz()];
                for j in 0..m {
                    for p in cp[j]..cp[j + 1] {
                        values[p] = k[(ri[p], j)];
                    }
                }
                super::Tangent::Sparse {
                    pattern: self.pattern.clone(),
                    values,
                    rank_one: Vec::new(),
                    solver: self.solver.clone(),
                }
            } else {
                super::Tangent::Dense(k)
            };
            Ok(super::Linearization {
                residual,
                tangent,
                loads: nalgebra::DMatrix::from_fn(m, 1, |i, _| -Self::w(i)),
                constraints: DVector::zeros(0),
                constraint_q: nalgebra::DMatrix::zeros(0, m),
                constraint_lambda: nalgebra::DMatrix::zeros(0, 1),
            })
        }
    }

    /// A path step that wants its tangent at the point checks an iterate that Newton's
    /// convergence foretells converged with the iterate's own system, solved with the last
    /// factorisation as preconditioner: the same points and tangents as the dense solves that
    /// factorise at every iteration, to the corrector's tolerance and to round-off.
    #[test]
    fn a_path_step_ended_by_a_preconditioned_chord_keeps_its_point_and_tangent() {
        let opts = PathOptions::default();
        let mut sparse = Chain::new(true);
        let mut dense = Chain::new(false);
        let zero = DVector::zeros(Chain::M);
        let start = DVector::from_element(1, 0.0);
        let mut a = point_at(&mut sparse, zero.clone(), start.clone(), 0, &opts, None).unwrap();
        let mut b = point_at(&mut dense, zero, start, 0, &opts, None).unwrap();
        let before = super::CHORD_ENDED_STEPS.with(|c| c.get());
        for _ in 0..12 {
            a = super::step_from(&mut sparse, &a, 0.4, &opts).unwrap();
            b = super::step_from(&mut dense, &b, 0.4, &opts).unwrap();
            assert_eq!(a.iterations, b.iterations);
            assert!((&a.q - &b.q).amax() <= 1e-9 && (&a.lambda - &b.lambda).amax() <= 1e-9);
            assert!(
                (&a.tangent - &b.tangent).amax() <= 1e-12,
                "{:e}",
                (&a.tangent - &b.tangent).amax()
            );
        }
        assert!(a.lambda[0] > 1.0, "the path went on: {}", a.lambda[0]);
        let ended = super::CHORD_ENDED_STEPS.with(|c| c.get()) - before;
        assert!(ended > 0, "no step ended by the chord check");
    }

    /// A slow crossing: g changes by 10⁻⁶ over the whole step, its tolerance spans a hundredth
    /// of it, and off the path g is off by a multiple `c` of the residual (as the test
    /// function of a slowly crossing eigenvalue is off by far more than its tolerance at a
    /// state one correction away from the path). The iteration ends next to the zero, not
    /// anywhere within the tolerance (a secant through two iterates at one arclength), and
    /// does not give up where g off the path is larger than g's whole change (its
    /// unconverged values taken for the zero's).
    #[test]
    fn zero_on_step_locates_a_slow_crossing_next_to_its_zero() {
        let opts = PathOptions::default();
        let mut circle = circle();
        let q0 = Q0;
        let from = circle_start(&mut circle, &opts);
        let s_at = |theta: f64| arclength_to(&from, theta);
        let theta1 = 1.5f64;
        let s1 = s_at(theta1);
        for c in [1e-2, 1e-1, 1.0] {
            // Zero at q = −0.3 on the path.
            let g = |q: &DVector<f64>, l: &DVector<f64>| {
                1e-6 * (q[0] + 0.3) + c * (q[0] * q[0] + l[0] * l[0] - 1.0)
            };
            let change = SignChange {
                first: (0.0, 1e-6 * (q0 + 0.3)),
                second: (s1, 1e-6 * (-theta1.cos() + 0.3)),
                tolerance: 5e-9,
                width: 1e-12 * s1,
            };
            let mut evaluated = 0;
            let zero = zero_on_step(
                &mut circle,
                &from,
                change,
                &mut |_, q, l, _| {
                    evaluated += 1;
                    Some(g(q, l))
                },
                &opts,
            )
            .expect("a zero");
            let (q, l) = (zero.point.q[0], zero.point.lambda[0]);
            // Anywhere within the tolerance, |q + 0.3| could be up to 5e-3.
            assert!((q + 0.3).abs() <= 1e-6, "c = {c}: {q}");
            assert!(zero.value.abs() <= 1e-10, "c = {c}: {}", zero.value);
            assert!((q * q + l * l - 1.0).abs() <= 1e-10, "c = {c}: {q} {l}");
            // g only at settled iterates, not at every one.
            assert!(
                evaluated < zero.iterations,
                "{evaluated} of {}",
                zero.iterations
            );
            let [first, second] = &zero.sides;
            for (side, positive) in [(first, false), (second, true)] {
                if let Some((s, q, l)) = side {
                    assert!((g(q, l) > 0.0) == positive && *s >= 0.0 && *s <= s1);
                }
            }
        }
    }

    /// A zero located on a step is kept until the driver moves: a second test function that
    /// vanishes at the same state (the circle's turning point of λ, where q = 0) takes it
    /// without iterating; one whose zero lies elsewhere on the step iterates as before.
    #[test]
    fn a_second_test_function_with_the_same_zero_takes_the_located_state() {
        let opts = PathOptions::default();
        let mut circle = circle();
        let from = circle_start(&mut circle, &opts);
        let mut driver = super::Continuation::new(circle, from.clone(), opts);
        let theta = 2.0f64;
        let s2 = arclength_to(&from, theta);
        let turning = SignChange {
            first: (0.0, from.tangent[1]),
            second: (s2, theta.cos() * from.tangent[1].signum()),
            tolerance: 1e-12,
            width: 1e-14,
        };
        let turn = driver
            .zero_on_step(&from, turning, &mut |_, _, _, t| Some(t[1]))
            .expect("a turning point");
        assert!(turn.iterations > 0);
        // q = −cos θ changes sign at the same state.
        let crossing = SignChange {
            first: (0.0, Q0),
            second: (s2, -theta.cos()),
            tolerance: 1e-10,
            width: 1e-10,
        };
        let again = driver
            .zero_on_step(&from, crossing, &mut |_, q, _, _| Some(q[0]))
            .expect("the same zero");
        assert_eq!(again.iterations, 0);
        assert_eq!(again.point.q, turn.point.q);
        assert!(again.value.abs() <= 1e-10);
        // q + 0.3 vanishes elsewhere on the step: iterated for.
        let elsewhere = SignChange {
            first: (0.0, Q0 + 0.3),
            second: (s2, -theta.cos() + 0.3),
            tolerance: 1e-12,
            width: 1e-12,
        };
        let other = driver
            .zero_on_step(&from, elsewhere, &mut |_, q, _, _| Some(q[0] + 0.3))
            .expect("a zero");
        assert!(other.iterations > 0 && (other.point.q[0] + 0.3).abs() <= 1e-12);
    }

    /// A stall recorded as plain data reads as the driver's own.
    #[test]
    fn a_stall_is_recorded_in_the_same_words() {
        for why in [
            StepError::Singular,
            StepError::BranchJump {
                distance: 0.734,
                angle: 41.6,
            },
            StepError::NotConverged { iterations: 25 },
        ] {
            let stalled = Stalled {
                min_step: 1e-8,
                after: 17,
                control: 0.1 + 0.2,
                why,
                bound: None,
            };
            let words = stalled.to_string();
            assert_eq!(crate::results::Stalled::from(stalled).to_string(), words);
        }
    }
}
