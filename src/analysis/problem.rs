//! A model restricted to the fixed-point space of a (sub)group, for the path follower.

use crate::adapted::SparseBasis;
use crate::analysis::continuation::{Linearization, PhaseTimes, Problem, Tangent};
use crate::linalg::bordered::SharedFactorization;
use crate::linalg::SymmetricFactorization;
use crate::model::constraint::Constraint;
use crate::model::{Evaluation, Subset};
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
        use crate::model::Request;
        let t0 = std::time::Instant::now();
        self.basis.expand(q, &mut self.u);
        self.params = self.parameters(lambda);
        self.model
            .evaluate(&self.u, &self.params, Request::ALL, &mut self.eval)?;
        let t1 = std::time::Instant::now();
        self.times.assembly += t1 - t0;
        self.times.evaluations += 1;
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
            let x = self.model.positions(&self.u);
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
        let lin = Linearization {
            residual: self.basis.restrict_invariant(&self.eval.residual),
            tangent: self.restricted_tangent(),
            loads,
            constraints,
            constraint_q,
            constraint_lambda,
        };
        self.times.projection += t1.elapsed();
        Ok(lin)
    }

    fn defect(
        &self,
        q: &DVector<f64>,
        _lambda: &DVector<f64>,
    ) -> Option<crate::model::StateDefect> {
        self.model.state_defect(&self.displacement(q))
    }
}

impl crate::analysis::events::States for SymmetricProblem<'_> {
    fn displacement(&self, q: &DVector<f64>) -> Vec<f64> {
        SymmetricProblem::displacement(self, q)
    }

    fn parameters(&self, lambda: &DVector<f64>) -> Vec<f64> {
        SymmetricProblem::parameters(self, lambda)
    }
}
