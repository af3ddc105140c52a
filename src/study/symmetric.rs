//! A model restricted to the fixed-point space of a (sub)group, for the path follower.

use crate::adapted::SparseBasis;
use crate::continuation::{Linearization, Problem, Tangent};
use crate::linalg::bordered::SharedFactorization;
use crate::linalg::SymmetricFactorization;
use crate::model::constraint::Constraint;
use crate::model::{Evaluation, Subset};
use crate::results::PhaseTimes;
use nalgebra::{DMatrix, DVector};
use std::sync::Arc;

/// A model restricted to the fixed-point space, as a dense problem for the path follower:
/// u = B q, R = Bᵀ F, K_A = Bᵀ K B, L_j = Bᵀ ∂F/∂Λ_j for the free parameters (the control,
/// then the one each constraint governs) and the augmenting equations with G_q = Bᵀ ∂g/∂u.
/// Every other parameter is held at its value in `params`. Without a control (a single
/// equilibrium), λ_0 is a dummy with a zero load column.
pub struct SymmetricProblem<'a> {
    model: &'a dyn crate::model::Model,
    basis: &'a SparseBasis,
    constraints: &'a [Box<dyn Constraint>],
    params: Vec<f64>,
    free: Vec<Option<usize>>,
    eval: Evaluation,
    u: Vec<f64>,
    work: Vec<f64>,
    /// From this many columns on the restricted tangent is passed on sparse (`None`: when the
    /// sparse solve is estimated cheaper, [`sparse_is_cheaper`]).
    sparse_from: Option<usize>,
    /// The choice by cost, made at the first evaluation.
    sparse_by_cost: Option<bool>,
    /// The sparse LBLᵀ of the restricted tangent, its symbolic analysis done once.
    solver: SharedFactorization,
    /// Where the evaluations' time went (for `memstab bench`).
    pub times: PhaseTimes,
    /// The neutral motions held in the fixed-point space (docs/theory.md §7.9): an
    /// orthonormal basis W (m × k) of the restricted fields of the model's rigid motions (and,
    /// at the start, of its held motions) that the fixed-point space contains; empty for most
    /// groups.
    gauge: DMatrix<f64>,
    /// The rigid motions' part of the gauge, held everywhere.
    rigid: DMatrix<f64>,
    /// Wᵀ R at the last evaluation: the multipliers, the forces that hold the gauge.
    held: DVector<f64>,
}

/// A restricted motion field counts as lying in the fixed-point space when its norm is at
/// least this fraction of the whole field's.
const IN_FIXED_POINT_SPACE: f64 = 1e-8;

/// The orthonormal basis W of the fields t + ω × X_i (at the reference positions) of the
/// model's rigid motions and gauge motions ([`Model::gauge_motions`]: the relabellings of a
/// spherical reference), and of its held motions with `held`, that the fixed-point space of
/// `basis` contains (docs/theory.md §7.9): none for a group that moves each of them.
///
/// [`Model::gauge_motions`]: crate::model::Model::gauge_motions
pub fn held_gauge(
    model: &dyn crate::model::Model,
    basis: &SparseBasis,
    held: bool,
) -> DMatrix<f64> {
    let reference = model.reference();
    let layout = model.layout();
    let mut motions = model.rigid_motions();
    motions.extend(model.gauge_motions());
    if held {
        motions.extend(model.held_motions());
    }
    let columns: Vec<DVector<f64>> = motions
        .iter()
        .filter_map(|motion| {
            let t = nalgebra::Vector3::new(motion[0], motion[1], motion[2]);
            let w = nalgebra::Vector3::new(motion[3], motion[4], motion[5]);
            let whole = (0..reference.len())
                .filter(|&i| layout.dof(i, 0).is_some())
                .map(|i| (t + w.cross(&reference[i])).norm_squared())
                .sum::<f64>()
                .sqrt();
            let v = basis.restrict_rigid(motion, reference, layout);
            (whole > 0.0 && v.norm() > IN_FIXED_POINT_SPACE * whole).then_some(v)
        })
        .collect();
    let m = basis.dim();
    if columns.is_empty() || m == 0 {
        return DMatrix::zeros(m, 0);
    }
    let a = DMatrix::from_columns(&columns);
    let scale = a.column_iter().map(|c| c.norm()).fold(0.0, f64::max);
    let svd = a.svd(true, false);
    let u = svd.u.expect("U requested");
    let kept: Vec<DVector<f64>> = (0..svd.singular_values.len())
        .filter(|&k| svd.singular_values[k] > IN_FIXED_POINT_SPACE * scale)
        .map(|k| u.column(k).into_owned())
        .collect();
    if kept.is_empty() {
        DMatrix::zeros(m, 0)
    } else {
        DMatrix::from_columns(&kept)
    }
}

/// Below this size the fixed-point system is always solved dense (its LU takes microseconds);
/// from it on, dense or sparse by estimated cost ([`sparse_is_cheaper`]).
pub const SPARSE_TANGENT_FROM: usize = 128;

/// Seconds per flop of the dense LU of the extended system (2/3 n³ flops), an estimate for
/// the project's 2-core machine (BENCHMARKS.md §7; a crossover benchmark in `benches/` is
/// still to be written).
const DENSE_LU_SECONDS_PER_FLOP: f64 = 2.5e-10;
/// Seconds per estimated flop of a numeric sparse LBLᵀ, estimated as above.
const SPARSE_FACTOR_SECONDS_PER_FLOP: f64 = 1.0e-9;
/// Seconds per stored factor value of one sparse solve, estimated as above.
const SPARSE_SOLVE_SECONDS_PER_VALUE: f64 = 4.0e-9;

/// Whether a Newton step of the fixed-point system of m unknowns with `border` rows and
/// columns (loads, constraints, arclength, rank-one terms) costs less by block elimination on
/// the sparse LBLᵀ `factorization` (symbolic analysis done: one numeric factorisation and
/// about 2 (border + 2) solves) than by a dense LU of the whole extended system.
pub fn sparse_is_cheaper(m: usize, border: usize, factorization: &SymmetricFactorization) -> bool {
    let n = (m + border) as f64;
    let dense = DENSE_LU_SECONDS_PER_FLOP * 2.0 / 3.0 * n * n * n;
    let solves = 2.0 * (border as f64 + 2.0);
    let sparse = SPARSE_FACTOR_SECONDS_PER_FLOP * factorization.flops()
        + solves * SPARSE_SOLVE_SECONDS_PER_VALUE * factorization.factor_len() as f64;
    sparse < dense
}

impl<'a> SymmetricProblem<'a> {
    /// Restricts `model` to `basis` with the given control parameter (if any) and
    /// constraints, each of which frees its parameter.
    pub fn new(
        model: &'a dyn crate::model::Model,
        basis: &'a SparseBasis,
        constraints: &'a [Box<dyn Constraint>],
        params: Vec<f64>,
        control: Option<usize>,
    ) -> Self {
        let free = std::iter::once(control)
            .chain(constraints.iter().map(|c| Some(c.frees())))
            .collect();
        let eval = match basis.representatives() {
            Some(reps) => model
                .new_evaluation()
                .restricted_to(Arc::new(Subset::around(model.layout(), &reps))),
            None => model.new_evaluation(),
        };
        Self {
            eval,
            u: vec![0.0; model.unknowns()],
            work: Vec::new(),
            sparse_from: None,
            sparse_by_cost: None,
            solver: Default::default(),
            model,
            basis,
            constraints,
            params,
            free,
            times: PhaseTimes::default(),
            gauge: DMatrix::zeros(basis.dim(), 0),
            rigid: DMatrix::zeros(basis.dim(), 0),
            held: DVector::zeros(0),
        }
        .with_rigid_gauge()
    }

    fn with_rigid_gauge(mut self) -> Self {
        self.rigid = held_gauge(self.model, self.basis, false);
        self.gauge = self.rigid.clone();
        self
    }

    /// Holds the model's held motions that lie in the fixed-point space too, besides its
    /// rigid motions (docs/theory.md §7.9): for the start solve and the start of a path,
    /// where a drift may be exactly neutral.
    pub fn holding_neutral(mut self) -> Self {
        self.gauge = held_gauge(self.model, self.basis, true);
        self
    }

    /// Releases the held motions, keeping the rigid motions held: the path beyond its start,
    /// where a drift has a stiffness of its own and the free equilibrium is regular.
    pub fn release_held(&mut self) {
        self.gauge = self.rigid.clone();
    }

    /// The number of held motions beyond the rigid motions and relabellings (those
    /// [`Self::holding_neutral`] adds in this fixed-point space).
    pub fn held_beyond_rigid(&self) -> usize {
        self.gauge.ncols().saturating_sub(self.rigid.ncols())
    }

    /// The number of neutral motions held in the fixed-point space (docs/theory.md §7.9).
    pub fn held_motions(&self) -> usize {
        self.gauge.ncols()
    }

    /// The forces that hold them at (q, λ), |Wᵀ R|, relative to the scale of the residual
    /// (max |R| tolerated at convergence is the tolerance times that scale): zero at a free
    /// equilibrium. `None` when nothing is held.
    pub fn held_force(
        &mut self,
        q: &DVector<f64>,
        lambda: &DVector<f64>,
        state_scale: f64,
        parameter_scale: f64,
    ) -> Option<Result<f64, crate::model::ModelError>> {
        if self.gauge.ncols() == 0 {
            return None;
        }
        Some(self.evaluate(q, lambda).map(|lin| {
            let scale = (lin.loads.column(0).amax() * parameter_scale)
                .max(lin.tangent.amax() * state_scale)
                .max(1e-300);
            self.held.amax() / scale
        }))
    }

    /// Holds the gauge: R → P R, K → P K P + s W Wᵀ, L → P L, G_q → G_q P with
    /// P = I − W Wᵀ, so that every Newton step keeps Wᵀ q, and keeps Wᵀ R (the multipliers).
    fn hold(&mut self, lin: &mut Linearization) {
        let w = &self.gauge;
        let project = |v: &mut DVector<f64>| {
            let c = w.transpose() * &*v;
            *v -= w * c;
        };
        self.held = w.transpose() * &lin.residual;
        project(&mut lin.residual);
        for mut col in lin.loads.column_iter_mut() {
            let mut v = col.clone_owned();
            project(&mut v);
            col.copy_from(&v);
        }
        for mut row in lin.constraint_q.row_iter_mut() {
            let mut v = row.transpose();
            project(&mut v);
            row.copy_from(&v.transpose());
        }
        let s = lin.tangent.amax().max(1e-300);
        let kw = lin.tangent.times(w);
        match &mut lin.tangent {
            Tangent::Dense(k) => {
                let wkw = w.transpose() * &kw;
                let mut pkp = &*k - w * kw.transpose() - &kw * w.transpose()
                    + w * (wkw + DMatrix::identity(w.ncols(), w.ncols()) * s) * w.transpose();
                pkp = (&pkp + pkp.transpose()) * 0.5;
                *k = pkp;
            }
            Tangent::Sparse { rank_one, .. } => {
                // The old rank-one terms projected, then − W (KW)ᵀ − (KW) Wᵀ + W M Wᵀ with
                // M = Wᵀ K W + s I, written as Z C Zᵀ (Z = [W, KW]) and C diagonalised.
                for (_, a) in rank_one.iter_mut() {
                    project(a);
                }
                let k = w.ncols();
                let m = w.transpose() * &kw + DMatrix::identity(k, k) * s;
                let mut c = DMatrix::zeros(2 * k, 2 * k);
                c.view_mut((0, 0), (k, k))
                    .copy_from(&((&m + m.transpose()) * 0.5));
                for i in 0..k {
                    c[(i, k + i)] = -1.0;
                    c[(k + i, i)] = -1.0;
                }
                let mut z = DMatrix::zeros(w.nrows(), 2 * k);
                z.view_mut((0, 0), (w.nrows(), k)).copy_from(w);
                z.view_mut((0, k), (w.nrows(), k)).copy_from(&kw);
                let eig = nalgebra::SymmetricEigen::new(c);
                let top = eig.eigenvalues.amax().max(1e-300);
                for (i, &ci) in eig.eigenvalues.iter().enumerate() {
                    if ci.abs() > 1e-14 * top {
                        rank_one.push((ci, &z * eig.eigenvectors.column(i)));
                    }
                }
            }
        }
    }

    /// Frees one more parameter, after the control and the ones the constraints govern (a
    /// critical curve's second parameter: the problem then has one equation fewer than its
    /// free parameters need, which the caller's augmenting equation supplies).
    pub fn with_free_parameter(mut self, parameter: usize) -> Self {
        self.free.push(Some(parameter));
        self
    }

    /// Assembles the whole mesh at every evaluation instead of only the triangles around the
    /// orbit representatives (for checks and timing comparisons).
    pub fn with_full_assembly(mut self) -> Self {
        self.eval = self.model.new_evaluation();
        self
    }

    /// Passes the restricted tangent on as a sparse matrix (to a sparse LU of the extended
    /// system) when the basis has at least `columns` columns; `usize::MAX` keeps it dense.
    /// By default the choice is by estimated cost ([`sparse_is_cheaper`]).
    pub fn with_sparse_tangent_from(mut self, columns: usize) -> Self {
        self.sparse_from = Some(columns);
        self
    }

    /// Whether the tangent goes on sparse: as asked, or by cost (decided once, at the first
    /// sparse restriction, from the symbolic analysis it needs anyway).
    fn sparse(&mut self, pattern: &crate::linalg::SymmetricPattern) -> bool {
        let m = self.basis.dim();
        if let Some(from) = self.sparse_from {
            return m >= from;
        }
        if m < SPARSE_TANGENT_FROM {
            return false;
        }
        if let Some(choice) = self.sparse_by_cost {
            return choice;
        }
        let border = self.free.len() + self.constraints.len() + self.eval.rank_one.len();
        let choice = match SymmetricFactorization::new(pattern) {
            Ok(f) => {
                let cheaper = sparse_is_cheaper(m, border, &f);
                if cheaper {
                    if let Ok(mut guard) = self.solver.lock() {
                        *guard = Some(f);
                    }
                }
                cheaper
            }
            Err(_) => false,
        };
        self.sparse_by_cost = Some(choice);
        choice
    }

    /// Bᵀ K B of the last evaluation, sparse for a large basis built from a group action.
    fn restricted_tangent(&mut self) -> Tangent {
        let layout = self.model.layout();
        let candidate = match (self.sparse_from, self.sparse_by_cost) {
            (Some(from), _) => self.basis.dim() >= from,
            (None, Some(choice)) => choice,
            (None, None) => self.basis.dim() >= SPARSE_TANGENT_FROM,
        };
        if candidate {
            if let Some((pattern, values)) = self
                .basis
                .restrict_tangent_sparse(layout, &self.eval)
                .filter(|(pattern, _)| self.sparse(pattern))
            {
                let rank_one = self
                    .eval
                    .rank_one
                    .iter()
                    .map(|(c, a)| (*c, self.basis.restrict(a)))
                    .collect();
                return Tangent::Sparse {
                    pattern,
                    values,
                    rank_one,
                    solver: self.solver.clone(),
                };
            }
        }
        Tangent::Dense(
            self.basis
                .restrict_tangent(layout, &self.eval, &mut self.work),
        )
    }

    /// The model evaluated at the state B q and the parameters with the free ones at
    /// `lambda`, as `request` asks, its time counted as assembly; returns when it ended.
    fn assemble(
        &mut self,
        q: &DVector<f64>,
        lambda: &DVector<f64>,
        request: crate::model::Request,
    ) -> Result<std::time::Instant, crate::model::ModelError> {
        let t0 = std::time::Instant::now();
        self.basis.expand(q, &mut self.u);
        self.params = self.parameters(lambda);
        self.model
            .evaluate(&self.u, &self.params, request, &mut self.eval)?;
        let t1 = std::time::Instant::now();
        self.times.assembly += t1 - t0;
        self.times.evaluations += 1;
        Ok(t1)
    }

    /// The full displacement u = B q.
    pub fn displacement(&self, q: &DVector<f64>) -> Vec<f64> {
        let mut u = vec![0.0; self.basis.unknowns()];
        self.basis.expand(q, &mut u);
        u
    }

    /// All parameters with the free ones set to `lambda`.
    pub fn parameters(&self, lambda: &DVector<f64>) -> Vec<f64> {
        let mut p = self.params.clone();
        for (j, i) in self.free.iter().enumerate() {
            if let Some(i) = *i {
                p[i] = lambda[j];
            }
        }
        p
    }

    /// The free parameters' values in `params` (the dummy control is 0).
    pub fn free_values(&self, params: &[f64]) -> DVector<f64> {
        DVector::from_iterator(
            self.free.len(),
            self.free.iter().map(|i| i.map_or(0.0, |i| params[i])),
        )
    }
}

impl Problem for SymmetricProblem<'_> {
    fn phase_times(&self) -> PhaseTimes {
        self.times
    }

    fn dim(&self) -> usize {
        self.basis.dim()
    }

    fn free_parameters(&self) -> usize {
        self.free.len()
    }

    fn evaluate(
        &mut self,
        q: &DVector<f64>,
        lambda: &DVector<f64>,
    ) -> Result<Linearization, crate::model::ModelError> {
        let t1 = self.assemble(q, lambda, crate::model::Request::ALL)?;
        let (m, nf, c) = (self.basis.dim(), self.free.len(), self.constraints.len());
        let mut loads = DMatrix::zeros(m, nf);
        for (j, i) in self.free.iter().enumerate() {
            if let Some(i) = *i {
                loads.set_column(j, &self.basis.restrict_invariant(&self.eval.loads[i]));
            }
        }
        let mut constraints = DVector::zeros(c);
        let mut constraint_q = DMatrix::zeros(c, m);
        let mut constraint_lambda = DMatrix::zeros(c, nf);
        if c > 0 {
            let x = self.model.positions(&self.u, &self.params);
            for (k, con) in self.constraints.iter().enumerate() {
                let v = con.evaluate(self.model.layout(), &x, &self.params);
                constraints[k] = v.value;
                constraint_q.set_row(k, &self.basis.restrict(&v.grad_u).transpose());
                for (j, i) in self.free.iter().enumerate() {
                    if let Some(i) = *i {
                        constraint_lambda[(k, j)] = v.grad_params[i];
                    }
                }
            }
        }
        let mut lin = Linearization {
            residual: self.basis.restrict_invariant(&self.eval.residual),
            tangent: self.restricted_tangent(),
            loads,
            constraints,
            constraint_q,
            constraint_lambda,
        };
        if self.gauge.ncols() > 0 {
            self.hold(&mut lin);
        }
        self.times.projection += t1.elapsed();
        Ok(lin)
    }

    /// R and g without K, L or ∂g: the model assembled for its gradient alone, restricted
    /// and held as in [`Problem::evaluate`].
    fn residual(
        &mut self,
        q: &DVector<f64>,
        lambda: &DVector<f64>,
    ) -> Result<(DVector<f64>, DVector<f64>), crate::model::ModelError> {
        let t1 = self.assemble(q, lambda, crate::model::Request::RESIDUAL)?;
        let mut constraints = DVector::zeros(self.constraints.len());
        if !self.constraints.is_empty() {
            let x = self.model.positions(&self.u, &self.params);
            for (k, con) in self.constraints.iter().enumerate() {
                constraints[k] = con.evaluate(self.model.layout(), &x, &self.params).value;
            }
        }
        let mut residual = self.basis.restrict_invariant(&self.eval.residual);
        if self.gauge.ncols() > 0 {
            let w = &self.gauge;
            self.held = w.transpose() * &residual;
            residual -= w * &self.held;
        }
        self.times.projection += t1.elapsed();
        Ok((residual, constraints))
    }

    fn defect(&self, q: &DVector<f64>, lambda: &DVector<f64>) -> Option<crate::model::StateDefect> {
        self.model
            .state_defect(&self.displacement(q), &self.parameters(lambda))
    }

    /// The model's switches (nodes in contact with a penalty plane) that differ.
    fn switched(
        &self,
        a: (&DVector<f64>, &DVector<f64>),
        b: (&DVector<f64>, &DVector<f64>),
    ) -> Option<usize> {
        let before = self
            .model
            .switches(&self.displacement(a.0), &self.parameters(a.1))?;
        let after = self
            .model
            .switches(&self.displacement(b.0), &self.parameters(b.1))?;
        Some(before.iter().zip(&after).filter(|(x, y)| x != y).count())
    }
}

impl crate::continuation::events::States for SymmetricProblem<'_> {
    fn displacement(&self, q: &DVector<f64>) -> Vec<f64> {
        SymmetricProblem::displacement(self, q)
    }

    fn parameters(&self, lambda: &DVector<f64>) -> Vec<f64> {
        SymmetricProblem::parameters(self, lambda)
    }
}

impl super::Followed for SymmetricProblem<'_> {
    fn coordinates(&self, u: &[f64]) -> DVector<f64> {
        self.basis.restrict(u)
    }

    fn free_values(&self, params: &[f64]) -> DVector<f64> {
        SymmetricProblem::free_values(self, params)
    }

    fn free_indices(&self) -> Vec<usize> {
        self.free.iter().map(|f| f.unwrap_or(0)).collect()
    }

    fn release_held(&mut self) {
        SymmetricProblem::release_held(self)
    }

    fn held_force(
        &mut self,
        q: &DVector<f64>,
        lambda: &DVector<f64>,
        state_scale: f64,
        parameter_scale: f64,
    ) -> Option<Result<f64, crate::model::ModelError>> {
        SymmetricProblem::held_force(self, q, lambda, state_scale, parameter_scale)
    }
}
