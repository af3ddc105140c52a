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
use nalgebra::{DMatrix, DVector, Matrix3, SymmetricEigen, Vector3};

/// An orthonormal basis with sparse columns, each a list of (unknown, value).
#[derive(Debug, Clone)]
pub struct SparseBasis {
    unknowns: usize,
    columns: Vec<Vec<(usize, f64)>>,
    /// For each unknown, the columns whose support contains it (built on first use).
    by_dof: std::sync::OnceLock<Vec<Vec<u32>>>,
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
            let stabiliser: Vec<usize> = (0..group.order())
                .filter(|&g| action.node_perm(g)[i] == i)
                .collect();
            let p = stabiliser
                .iter()
                .fold(Matrix3::zeros(), |acc, &h| acc + group.element(h))
                / stabiliser.len() as f64;
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
                        let d = layout
                            .dof(j, c)
                            .expect("a free orbit has unknowns at every node");
                        if w[c] != 0.0 {
                            col.push((d, w[c]));
                        }
                    }
                }
                col.sort_unstable_by_key(|&(d, _)| d);
                columns.push(col);
            }
        }
        Self::from_columns(layout.unknowns(), columns)
    }

    fn from_columns(unknowns: usize, columns: Vec<Vec<(usize, f64)>>) -> Self {
        Self {
            unknowns,
            columns,
            by_dof: std::sync::OnceLock::new(),
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
        DVector::from_iterator(
            self.dim(),
            self.columns
                .iter()
                .map(|c| c.iter().map(|&(d, b)| b * v[d]).sum()),
        )
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
    pub fn restrict_tangent(
        &self,
        layout: &Layout,
        eval: &Evaluation,
        work: &mut Vec<f64>,
    ) -> DMatrix<f64> {
        let out = self.restrict_tangent_to(self, layout, eval, work);
        (&out + out.transpose()) * 0.5
    }

    /// The columns containing each unknown.
    fn columns_by_dof(&self) -> &Vec<Vec<u32>> {
        self.by_dof.get_or_init(|| {
            let mut by_dof = vec![Vec::new(); self.unknowns];
            for (i, c) in self.columns.iter().enumerate() {
                for &(d, _) in c {
                    by_dof[d].push(i as u32);
                }
            }
            by_dof
        })
    }

    /// Bᵀ K C for another basis C over the same unknowns (off-diagonal blocks, for checks).
    ///
    /// Sparse: w = K c_j touches only the rows coupled to c_j's support, and only the columns
    /// of B that contain one of those rows can meet it, so the block costs O(nnz of the block ×
    /// support) rather than O(m² × support).
    pub fn restrict_tangent_to(
        &self,
        other: &SparseBasis,
        layout: &Layout,
        eval: &Evaluation,
        work: &mut Vec<f64>,
    ) -> DMatrix<f64> {
        let pattern = layout.pattern();
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let by_dof = self.columns_by_dof();
        work.clear();
        work.resize(self.unknowns, 0.0);
        let mut touched: Vec<usize> = Vec::new();
        let mut mark = vec![usize::MAX; self.dim()];
        let mut candidates: Vec<usize> = Vec::new();
        let mut out = DMatrix::zeros(self.dim(), other.dim());
        for (j, cj) in other.columns.iter().enumerate() {
            touched.clear();
            candidates.clear();
            for &(d, b) in cj {
                let range = col_ptr[d]..col_ptr[d + 1];
                for (&r, &k) in row_idx[range.clone()].iter().zip(&eval.tangent[range]) {
                    if work[r] == 0.0 {
                        touched.push(r);
                    }
                    work[r] += k * b;
                }
            }
            for &r in &touched {
                for &i in &by_dof[r] {
                    let i = i as usize;
                    if mark[i] != j {
                        mark[i] = j;
                        candidates.push(i);
                    }
                }
            }
            for &i in &candidates {
                out[(i, j)] = self.columns[i].iter().map(|&(d, b)| b * work[d]).sum();
            }
            for &r in &touched {
                work[r] = 0.0;
            }
        }
        for (c, a) in &eval.rank_one {
            let (ar, ao) = (self.restrict(a), other.restrict(a));
            out += &ar * ao.transpose() * *c;
        }
        out
    }
}

/// The columns of one partner of one irrep, and the blocks of every irrep (DESIGN §4.3).
#[derive(Debug, Clone)]
pub struct IrrepBasis {
    /// Irrep name.
    pub name: String,
    /// Irrep dimension d.
    pub dim: usize,
    /// The multiplicity predicted by the characters, (1/|G|) Σ χ_T(g) χ_μ(g).
    pub multiplicity: usize,
    /// One basis per partner a = 0..d; `partners[0]` spans the first copy, and
    /// `partners[a] = P_{a0} partners[0]`.
    pub partners: Vec<SparseBasis>,
}

/// The symmetry-adapted basis of the free unknowns, by irrep.
#[derive(Debug, Clone)]
pub struct AdaptedBasis {
    /// One entry per irrep of the group, in the group's order (the trivial one first).
    pub irreps: Vec<IrrepBasis>,
}

/// Errors building an adapted basis.
#[derive(Debug, Clone, thiserror::Error, PartialEq)]
pub enum AdaptedError {
    /// Complex-type irreps (the E_k of a chiral C_n) need a complex basis, not built yet.
    #[error(
        "irrep {0} of {1} is of complex type (a chiral group); its block is not supported yet"
    )]
    ComplexType(String, String),
    /// The projected basis does not have the size the characters predict.
    #[error("irrep {irrep}: built {built} columns but the characters predict {predicted}")]
    Count {
        /// Irrep.
        irrep: String,
        /// Columns built.
        built: usize,
        /// Character formula.
        predicted: usize,
    },
}

impl AdaptedBasis {
    /// Builds, orbit by orbit, the sparse orthonormal bases B_{μa} of every irrep μ and
    /// partner a from the operators P^μ_{ab} = (d/|G|) Σ_g D^μ_ab(g) T(g): on an orbit with
    /// representative i, the first copy is spanned by P^μ_{0b} e_{i,c} (b < d, c < 3),
    /// orthonormalised; partner a by P^μ_{a0} of those columns. Fixed orbits are skipped.
    pub fn new(action: &GroupAction, layout: &Layout) -> Result<Self, AdaptedError> {
        let group = action.group();
        let order = group.order() as f64;
        let orbits: Vec<Vec<usize>> = action
            .node_orbits()
            .into_iter()
            .filter(|o| layout.dof(o[0], 0).is_some())
            .collect();
        let free_nodes: Vec<usize> = orbits.iter().flatten().copied().collect();
        let node_of = layout_node_map(layout);
        let mut irreps = Vec::new();
        for irrep in group.irreps() {
            if irrep.kind() != symmetry::IrrepKind::Real {
                return Err(AdaptedError::ComplexType(
                    irrep.name().into(),
                    group.name().into(),
                ));
            }
            let d = irrep.dim();
            // Character formula over the free nodes.
            let chi_t = |g: usize| -> f64 {
                free_nodes
                    .iter()
                    .filter(|&&i| action.node_perm(g)[i] == i)
                    .count() as f64
                    * group.element(g).trace()
            };
            let m: f64 = (0..group.order())
                .map(|g| chi_t(g) * irrep.character(g))
                .sum::<f64>()
                / order;
            let multiplicity = m.round() as usize;
            let mut first: Vec<Vec<(usize, f64)>> = Vec::new();
            for orbit in &orbits {
                let i = orbit[0];
                let local = |j: usize| orbit.binary_search(&j).expect("orbit closed");
                // W: 3|O| × 3d candidates P_{0b} e_{i,c}.
                let rows = 3 * orbit.len();
                let mut w = DMatrix::<f64>::zeros(rows, 3 * d);
                for g in 0..group.order() {
                    let j = local(action.node_perm(g)[i]);
                    let r = group.element(g);
                    let dm = irrep.matrix(g);
                    for b in 0..d {
                        let coef = d as f64 / order * dm[(0, b)];
                        if coef == 0.0 {
                            continue;
                        }
                        for c in 0..3 {
                            for k in 0..3 {
                                w[(3 * j + k, 3 * b + c)] += coef * r[(k, c)];
                            }
                        }
                    }
                }
                // The candidates are projections of unit vectors (norm ≤ 1); a direction they
                // really span has a Gram eigenvalue of order 1/|G|, round-off one of 1e-30.
                let gram = w.transpose() * &w;
                let eig = SymmetricEigen::new(gram);
                for (e, &lam) in eig.eigenvalues.iter().enumerate() {
                    if lam <= 1e-10 {
                        continue;
                    }
                    let v = &w * eig.eigenvectors.column(e) / lam.sqrt();
                    let mut col = Vec::new();
                    for (jl, &j) in orbit.iter().enumerate() {
                        for k in 0..3 {
                            let val = v[3 * jl + k];
                            if val.abs() > 1e-15 {
                                col.push((layout.dof(j, k).expect("free orbit"), val));
                            }
                        }
                    }
                    col.sort_unstable_by_key(|&(dof, _)| dof);
                    first.push(col);
                }
            }
            if first.len() != multiplicity {
                return Err(AdaptedError::Count {
                    irrep: irrep.name().into(),
                    built: first.len(),
                    predicted: multiplicity,
                });
            }
            let unknowns = layout.unknowns();
            let mut partners = vec![SparseBasis::from_columns(unknowns, first.clone())];
            for a in 1..d {
                let cols = first
                    .iter()
                    .map(|col| {
                        apply_projector(action, layout, &node_of, irrep.matrices(), a, 0, col)
                    })
                    .collect();
                partners.push(SparseBasis::from_columns(unknowns, cols));
            }
            irreps.push(IrrepBasis {
                name: irrep.name().into(),
                dim: d,
                multiplicity,
                partners,
            });
        }
        Ok(Self { irreps })
    }
}

/// P_{ab} v = (d/|G|) Σ_g D_ab(g) T(g) v for a sparse v, with (T(g) v)_{π_g(j)} = R_g v_j.
fn apply_projector(
    action: &GroupAction,
    layout: &Layout,
    node_of: &[(usize, usize)],
    matrices: &[DMatrix<f64>],
    a: usize,
    b: usize,
    v: &[(usize, f64)],
) -> Vec<(usize, f64)> {
    let group = action.group();
    let d = matrices[0].nrows() as f64;
    // Gather v by node.
    let mut by_node: std::collections::BTreeMap<usize, Vector3<f64>> =
        std::collections::BTreeMap::new();
    for &(dof, val) in v {
        let (node, k) = node_of[dof];
        by_node.entry(node).or_insert_with(Vector3::zeros)[k] += val;
    }
    let mut out: std::collections::BTreeMap<usize, f64> = std::collections::BTreeMap::new();
    for (g, dm) in matrices.iter().enumerate() {
        let coef = d / group.order() as f64 * dm[(a, b)];
        if coef == 0.0 {
            continue;
        }
        let r = group.element(g);
        for (&j, vj) in &by_node {
            let target = action.node_perm(g)[j];
            let w = r * vj * coef;
            for k in 0..3 {
                let dof = layout
                    .dof(target, k)
                    .expect("free orbits map to free nodes");
                *out.entry(dof).or_insert(0.0) += w[k];
            }
        }
    }
    out.into_iter().filter(|(_, x)| x.abs() > 1e-15).collect()
}

/// For each unknown, its (node, component).
fn layout_node_map(layout: &Layout) -> Vec<(usize, usize)> {
    let mut map = vec![(0, 0); layout.unknowns()];
    let nodes = layout.nodes();
    for i in 0..nodes {
        for k in 0..3 {
            if let Some(d) = layout.dof(i, k) {
                map[d] = (i, k);
            }
        }
    }
    map
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
    /// Where the evaluations' time went (for `memstab bench`).
    pub times: PhaseTimes,
}

/// Time spent by a [`SymmetricProblem`]'s evaluations, by phase.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PhaseTimes {
    /// In `model.evaluate` (assembly).
    pub assembly: std::time::Duration,
    /// Restricting residual, loads, constraints and tangent to the basis (projection).
    pub projection: std::time::Duration,
    /// Number of evaluations.
    pub evaluations: usize,
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
        let free = std::iter::once(control)
            .chain(constraints.iter().map(|c| Some(c.frees())))
            .collect();
        Self {
            eval: model.new_evaluation(),
            u: vec![0.0; model.unknowns()],
            work: Vec::new(),
            model,
            basis,
            constraints,
            params,
            free,
            times: PhaseTimes::default(),
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
        DVector::from_iterator(
            self.free.len(),
            self.free.iter().map(|i| i.map_or(0.0, |i| params[i])),
        )
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
        let lin = crate::continuation::Linearization {
            residual: self.basis.restrict(&self.eval.residual),
            tangent: self
                .basis
                .restrict_tangent(self.model.layout(), &self.eval, &mut self.work),
            loads,
            constraints,
            constraint_q,
            constraint_lambda,
        };
        self.times.projection += t1.elapsed();
        Ok(lin)
    }
}
