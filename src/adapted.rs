//! Symmetry-adapted bases (DESIGN §4.3), here the fixed-point space of the group: the
//! displacements u with T(g) u = u for every g, where (T(g) u)_{π_g(i)} = R_g u_i.
//!
//! The basis is built node orbit by node orbit: for the orbit of node i with stabiliser
//! H_i = {h : π_h(i) = i}, the vectors v ∈ ℝ³ fixed by H_i span the range of the projector
//! P_i = (1/|H_i|) Σ_{h ∈ H_i} R_h; each such v spreads over the orbit as u_{π_g(i)} = R_g v
//! (independent of the choice of g because H_i fixes v), scaled by 1/√|orbit|. Columns are
//! orthonormal and sparse (one orbit each), and their number is Σ_orbits rank P_i — the
//! multiplicity of the trivial irrep in T. Fixed nodes form whole orbits and carry no unknowns.
//!
//! On a G-invariant state the residual lies in this space and the tangent maps it into
//! itself, so a symmetric path can be followed with `B_A^T K B_A` alone.

use crate::model::constraint::Constraint;
use crate::model::{Evaluation, Layout};
use meshes::GroupAction;
use nalgebra::{DMatrix, DVector, Matrix3, SymmetricEigen};

/// An orthonormal basis with sparse columns, each a list of (unknown, value).
#[derive(Debug, Clone)]
pub struct SparseBasis {
    unknowns: usize,
    columns: Vec<Vec<(usize, f64)>>,
}

impl SparseBasis {
    /// The fixed-point space of `action` on the unknowns of `layout`.
    pub fn fixed_point(action: &GroupAction, layout: &Layout) -> Self {
        let group = action.group();
        let mut columns = Vec::new();
        for orbit in action.node_orbits() {
            let i = orbit[0];
            if layout.dof(i, 0).is_none() {
                continue; // a fixed orbit
            }
            let stabiliser: Vec<usize> = (0..group.order()).filter(|&g| action.node_perm(g)[i] == i).collect();
            let p = stabiliser.iter().fold(Matrix3::zeros(), |acc, &h| acc + group.element(h)) / stabiliser.len() as f64;
            let eig = SymmetricEigen::new((p + p.transpose()) * 0.5);
            // One group element carrying i to each node of its orbit.
            let mut carrier = vec![usize::MAX; orbit.len()];
            for g in 0..group.order() {
                let j = action.node_perm(g)[i];
                let k = orbit.binary_search(&j).expect("orbit is closed");
                if carrier[k] == usize::MAX {
                    carrier[k] = g;
                }
            }
            let scale = 1.0 / (orbit.len() as f64).sqrt();
            for e in 0..3 {
                if eig.eigenvalues[e] < 0.5 {
                    continue;
                }
                let v = eig.eigenvectors.column(e).into_owned();
                let mut col = Vec::with_capacity(3 * orbit.len());
                for (k, &j) in orbit.iter().enumerate() {
                    let w = group.element(carrier[k]) * v * scale;
                    for c in 0..3 {
                        let d = layout.dof(j, c).expect("a free orbit has unknowns at every node");
                        if w[c] != 0.0 {
                            col.push((d, w[c]));
                        }
                    }
                }
                col.sort_unstable_by_key(|&(d, _)| d);
                columns.push(col);
            }
        }
        Self {
            unknowns: layout.unknowns(),
            columns,
        }
    }

    /// Number of columns m.
    pub fn dim(&self) -> usize {
        self.columns.len()
    }

    /// Number of rows (the model's unknowns).
    pub fn unknowns(&self) -> usize {
        self.unknowns
    }

    /// The sparse columns.
    pub fn columns(&self) -> &[Vec<(usize, f64)>] {
        &self.columns
    }

    /// Bᵀ v.
    pub fn restrict(&self, v: &[f64]) -> DVector<f64> {
        DVector::from_iterator(self.dim(), self.columns.iter().map(|c| c.iter().map(|&(d, b)| b * v[d]).sum()))
    }

    /// u = B q.
    pub fn expand(&self, q: &DVector<f64>, u: &mut [f64]) {
        u.fill(0.0);
        for (c, &qc) in self.columns.iter().zip(q.iter()) {
            for &(d, b) in c {
                u[d] += b * qc;
            }
        }
    }

    /// Bᵀ K B for the full tangent of an evaluation (sparse part on `layout`'s pattern plus
    /// its rank-one terms), using the sparsity of the columns; `work` is scratch of length N.
    pub fn restrict_tangent(&self, layout: &Layout, eval: &Evaluation, work: &mut Vec<f64>) -> DMatrix<f64> {
        let m = self.dim();
        let pattern = layout.pattern();
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        work.clear();
        work.resize(self.unknowns, 0.0);
        let mut out = DMatrix::zeros(m, m);
        for (j, cj) in self.columns.iter().enumerate() {
            // w = K b_j, touching only the columns of K in b_j's support.
            for &(d, b) in cj {
                for p in col_ptr[d]..col_ptr[d + 1] {
                    work[row_idx[p]] += eval.tangent[p] * b;
                }
            }
            for (i, ci) in self.columns.iter().enumerate() {
                out[(i, j)] = ci.iter().map(|&(d, b)| b * work[d]).sum();
            }
            for &(d, _) in cj {
                for p in col_ptr[d]..col_ptr[d + 1] {
                    work[row_idx[p]] = 0.0;
                }
            }
        }
        for (c, a) in &eval.rank_one {
            let ar = self.restrict(a);
            out += &ar * ar.transpose() * *c;
        }
        (&out + out.transpose()) * 0.5
    }
}

/// A model restricted to the fixed-point space, as a dense problem for the path follower:
/// u = B q, R = Bᵀ F, K_A = Bᵀ K B, L_j = Bᵀ ∂F/∂Λ_j for the free parameters (the control,
/// then the one each constraint governs) and the augmenting equations with G_q = Bᵀ ∂g/∂u.
/// Every other parameter is held at its value in `params`. Without a control (a single
/// equilibrium), λ_0 is a dummy with a zero load column.
pub struct SymmetricProblem<'a> {
    model: &'a crate::model::FeModel,
    basis: &'a SparseBasis,
    constraints: &'a [Box<dyn Constraint>],
    params: Vec<f64>,
    free: Vec<Option<usize>>,
    eval: Evaluation,
    u: Vec<f64>,
    work: Vec<f64>,
}

impl<'a> SymmetricProblem<'a> {
    /// Restricts `model` to `basis` with the given control parameter (if any) and
    /// constraints, each of which frees its parameter.
    pub fn new(
        model: &'a crate::model::FeModel,
        basis: &'a SparseBasis,
        constraints: &'a [Box<dyn Constraint>],
        params: Vec<f64>,
        control: Option<usize>,
    ) -> Self {
        use crate::model::Model;
        let free = std::iter::once(control).chain(constraints.iter().map(|c| Some(c.frees()))).collect();
        Self {
            eval: model.new_evaluation(),
            u: vec![0.0; model.unknowns()],
            work: Vec::new(),
            model,
            basis,
            constraints,
            params,
            free,
        }
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
        DVector::from_iterator(self.free.len(), self.free.iter().map(|i| i.map_or(0.0, |i| params[i])))
    }
}

impl crate::continuation::DenseProblem for SymmetricProblem<'_> {
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
    ) -> Result<crate::continuation::Linearization, crate::model::ModelError> {
        use crate::model::{Model, Request};
        self.basis.expand(q, &mut self.u);
        self.params = self.parameters(lambda);
        self.model.evaluate(&self.u, &self.params, Request::ALL, &mut self.eval)?;
        let (m, nf, c) = (self.basis.dim(), self.free.len(), self.constraints.len());
        let mut loads = DMatrix::zeros(m, nf);
        for (j, i) in self.free.iter().enumerate() {
            if let Some(i) = *i {
                loads.set_column(j, &self.basis.restrict(&self.eval.loads[i]));
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
        Ok(crate::continuation::Linearization {
            residual: self.basis.restrict(&self.eval.residual),
            tangent: self.basis.restrict_tangent(self.model.layout(), &self.eval, &mut self.work),
            loads,
            constraints,
            constraint_q,
            constraint_lambda,
        })
    }
}
