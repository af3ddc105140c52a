//! Symmetry-adapted bases (DESIGN §4.3): the fixed-point space of the group — the
//! displacements u with T(g) u = u for every g, where (T(g) u)_{π_g(i)} = R_g u_i — and, for
//! every irrep μ, the blocks on which the tangent at a symmetric state is block diagonal.
//!
//! **Orbit-local form.** Every column is built on one node orbit O with representative node
//! i₀ (its smallest node) from a *seed*: d vectors s_b ∈ ℝ³ at i₀, with
//!
//!   b = Σ_b P^μ_{0b} s_b,   P^μ_{ab} = (d/|G|) Σ_g D^μ_{ab}(g) T(g).
//!
//! The seeds come from the Gram matrix of the candidates P^μ_{0b} e_{i₀,c}, which only needs
//! the stabiliser H of i₀: ⟨P_{0b} e_{i₀c}, P_{0b'} e_{i₀c'}⟩ = (d/|G|) Σ_{h∈H} D_{bb'}(h) (R_h)_{cc'}
//! (because P_{0b}ᵀ P_{0b'} = P_{bb'}); its eigenvectors with nonzero eigenvalue λ, scaled by
//! λ^{-1/2}, are orthonormal seeds. Partner a of a column is P_{a0} b = Σ_b P_{ab} s_b.
//!
//! **Block restriction from the representatives.** K commutes with every T(g) at a symmetric
//! state, so with P_{0b}ᵀ = P_{b0}:
//!
//!   (Bᵀ K B)_{fe} = Σ_b ⟨P_{b0} b_f, K s_{e,b}⟩
//!                 = (d/|G|) Σ_{b,b'} Σ_g D_{b'b}(g) ⟨s_{f,b'}, T(g) K s_{e,b}⟩.
//!
//! K s_{e,b} lives on the neighbours j of i₀ only, and ⟨s_f, T(g) w⟩ needs π_g(j) to be the
//! representative of f's orbit: a block costs the three columns of K at each representative,
//! independent of the orbit size — |G| times less than forming B_μᵀ K B_μ column by column.
//!
//! The fixed-point space is the trivial irrep's block (d = 1, D = 1). Fixed nodes form whole
//! orbits and carry no unknowns.

use crate::linalg::SymmetricPattern;
use crate::model::constraint::Constraint;
use crate::model::{Evaluation, Layout, Subset};
use meshes::GroupAction;
use nalgebra::{DMatrix, DVector, Matrix3, SymmetricEigen, Vector3};
use rayon::prelude::*;
use std::ops::Range;
use std::sync::Arc;

/// What the orbit-local formulas need of a group action, shared by all blocks of one basis.
#[derive(Debug)]
struct OrbitFrame {
    /// |G|.
    order: usize,
    /// R_g.
    rotations: Vec<Matrix3<f64>>,
    /// For each unknown, its (node, component).
    node_of: Vec<(u32, u8)>,
    /// For each node, the index of its orbit (in `GroupAction::node_orbits` order).
    orbit_of: Vec<u32>,
    /// For each node j, the elements g with π_g(j) = representative of j's orbit, as a CSR
    /// list: `to_rep[to_rep_ptr[j]..to_rep_ptr[j + 1]]` (|H| elements per node).
    to_rep_ptr: Vec<u32>,
    to_rep: Vec<u16>,
}

impl OrbitFrame {
    fn new(action: &GroupAction, layout: &Layout, orbits: &[Vec<usize>]) -> Self {
        let group = action.group();
        let nodes = layout.nodes();
        let mut orbit_of = vec![u32::MAX; nodes];
        let mut rep = vec![usize::MAX; nodes];
        for (o, orbit) in orbits.iter().enumerate() {
            for &j in orbit {
                orbit_of[j] = o as u32;
                rep[j] = orbit[0];
            }
        }
        let mut to_rep_ptr = vec![0u32; nodes + 1];
        let mut to_rep = Vec::with_capacity(nodes);
        for j in 0..nodes {
            if rep[j] != usize::MAX {
                to_rep.extend(
                    (0..group.order())
                        .filter(|&g| action.node_perm(g)[j] == rep[j])
                        .map(|g| g as u16),
                );
            }
            to_rep_ptr[j + 1] = to_rep.len() as u32;
        }
        let mut node_of = vec![(0, 0); layout.unknowns()];
        for i in 0..nodes {
            for k in 0..3 {
                if let Some(d) = layout.dof(i, k) {
                    node_of[d] = (i as u32, k as u8);
                }
            }
        }
        Self {
            order: group.order(),
            rotations: group.elements().to_vec(),
            node_of,
            orbit_of,
            to_rep_ptr,
            to_rep,
        }
    }

    fn to_rep(&self, j: usize) -> &[u16] {
        &self.to_rep[self.to_rep_ptr[j] as usize..self.to_rep_ptr[j + 1] as usize]
    }
}

/// The orbit-local description of a block's columns (see the module docs).
#[derive(Debug, Clone)]
struct Seeds {
    frame: Arc<OrbitFrame>,
    /// Irrep dimension d.
    d: usize,
    /// D(g), row-major d × d per element.
    matrices: Arc<Vec<f64>>,
    /// Representative node of each column's orbit.
    rep: Vec<u32>,
    /// The unknowns of each column's representative node.
    rep_dofs: Vec<[u32; 3]>,
    /// Seeds, d per column: `seeds[e * d + b]` = s_{e,b}.
    seeds: Vec<Vector3<f64>>,
    /// The columns on each orbit (contiguous, as they are built orbit by orbit).
    by_orbit: Vec<Range<u32>>,
    /// For each b < d, (d/|G|) Σ_g D_{b0}(g) R_g and (d/|G|) Σ_g D_{b0}(g) det(R_g) R_g: how
    /// P_{b0} acts on the translation and the rotation of a rigid motion.
    rigid_maps: Vec<(Matrix3<f64>, Matrix3<f64>)>,
}

impl Seeds {
    fn dmat(&self, g: usize) -> &[f64] {
        &self.matrices[g * self.d * self.d..(g + 1) * self.d * self.d]
    }

    /// Column e of Bᵀ K B (module docs) added into `out_col`: w_b = K s_{e,b} gathered by
    /// node (the neighbours j of e's representative), then ⟨s_{f,b'}, T(g) w_b⟩ for the
    /// elements g carrying j to the representative of the columns f on j's orbit.
    fn tangent_column(
        &self,
        e: usize,
        layout: &Layout,
        tangent: &[f64],
        scratch: &mut ColumnScratch,
        out_col: &mut [f64],
    ) {
        let frame = &*self.frame;
        let d = self.d;
        let coef = d as f64 / frame.order as f64;
        let pattern = layout.pattern();
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let i0 = self.rep[e] as usize;
        let s_e = &self.seeds[e * d..(e + 1) * d];
        let ColumnScratch { touched, w, v, u } = scratch;
        touched.clear();
        w.clear();
        for c in 0..3 {
            let dof = layout.dof(i0, c).expect("a free orbit has unknowns");
            let range = col_ptr[dof]..col_ptr[dof + 1];
            for (&r, &k) in row_idx[range.clone()].iter().zip(&tangent[range]) {
                let (j, comp) = frame.node_of[r];
                let t = match touched.iter().position(|&n| n == j) {
                    Some(t) => t,
                    None => {
                        touched.push(j);
                        w.resize(w.len() + d, Vector3::zeros());
                        touched.len() - 1
                    }
                };
                for (b, s) in s_e.iter().enumerate() {
                    w[t * d + b][comp as usize] += k * s[c];
                }
            }
        }
        for (t, &j) in touched.iter().enumerate() {
            let cols = self.by_orbit[frame.orbit_of[j as usize] as usize].clone();
            if cols.is_empty() {
                continue;
            }
            for &g in frame.to_rep(j as usize) {
                let r = &frame.rotations[g as usize];
                let dm = self.dmat(g as usize);
                for b in 0..d {
                    v[b] = r * w[t * d + b];
                }
                for b2 in 0..d {
                    u[b2] = (0..d).fold(Vector3::zeros(), |acc, b| acc + v[b] * dm[b2 * d + b]);
                }
                for f in cols.clone() {
                    let s_f = &self.seeds[f as usize * d..(f as usize + 1) * d];
                    let x: f64 = s_f.iter().zip(u.iter()).map(|(s, u)| s.dot(u)).sum();
                    out_col[f as usize] += coef * x;
                }
            }
        }
    }

    /// The pattern of Bᵀ K B: column e meets every column on an orbit that holds a
    /// neighbour of e's representative (by K's pattern).
    fn block_pattern(&self, layout: &Layout) -> SymmetricPattern {
        let pattern = layout.pattern();
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let mut entries = Vec::new();
        let mut orbits: Vec<u32> = Vec::new();
        for e in 0..self.rep.len() {
            let i0 = self.rep[e] as usize;
            orbits.clear();
            for c in 0..3 {
                let dof = layout.dof(i0, c).expect("a free orbit has unknowns");
                for &r in &row_idx[col_ptr[dof]..col_ptr[dof + 1]] {
                    let o = self.frame.orbit_of[self.frame.node_of[r].0 as usize];
                    if !orbits.contains(&o) {
                        orbits.push(o);
                    }
                }
            }
            for &o in &orbits {
                entries.extend(self.by_orbit[o as usize].clone().map(|f| (f as usize, e)));
            }
        }
        SymmetricPattern::from_entries(self.rep.len(), entries)
    }

    /// Partner a of column e, Σ_b P_{ab} s_{e,b}, summed over the whole group.
    fn column(
        &self,
        action: &GroupAction,
        layout: &Layout,
        e: usize,
        a: usize,
    ) -> Vec<(usize, f64)> {
        let d = self.d;
        let coef = d as f64 / self.frame.order as f64;
        let i0 = self.rep[e] as usize;
        let s = &self.seeds[e * d..(e + 1) * d];
        let mut at: Vec<(usize, Vector3<f64>)> = Vec::new();
        for g in 0..self.frame.order {
            let dm = self.dmat(g);
            let mut v = Vector3::zeros();
            for (b, sb) in s.iter().enumerate() {
                v += sb * dm[a * d + b];
            }
            if v == Vector3::zeros() {
                continue;
            }
            let j = action.node_perm(g)[i0];
            let w = self.frame.rotations[g] * v * coef;
            match at.iter_mut().find(|(n, _)| *n == j) {
                Some((_, x)) => *x += w,
                None => at.push((j, w)),
            }
        }
        let mut col = Vec::with_capacity(3 * at.len());
        for (j, w) in at {
            for k in 0..3 {
                if w[k].abs() > 1e-15 {
                    col.push((layout.dof(j, k).expect("free orbit"), w[k]));
                }
            }
        }
        col.sort_unstable_by_key(|&(dof, _)| dof);
        col
    }
}

/// Per-thread scratch of [`Seeds::tangent_column`].
struct ColumnScratch {
    touched: Vec<u32>,
    w: Vec<Vector3<f64>>,
    v: Vec<Vector3<f64>>,
    u: Vec<Vector3<f64>>,
}

impl ColumnScratch {
    fn new(d: usize) -> Self {
        Self {
            touched: Vec::new(),
            w: Vec::new(),
            v: vec![Vector3::zeros(); d],
            u: vec![Vector3::zeros(); d],
        }
    }
}

/// Builds the seeds and first-partner columns of one real irrep (given by its matrices
/// D(g), d × d) on the free orbits.
fn orbit_basis(
    action: &GroupAction,
    layout: &Layout,
    frame: &Arc<OrbitFrame>,
    orbits: &[Vec<usize>],
    matrices: &[DMatrix<f64>],
) -> SparseBasis {
    let group = action.group();
    let d = matrices[0].nrows();
    let order = group.order() as f64;
    let flat: Vec<f64> = matrices
        .iter()
        .flat_map(|m| (0..d * d).map(move |k| m[(k / d, k % d)]))
        .collect();
    let mut seeds = Seeds {
        frame: frame.clone(),
        d,
        matrices: Arc::new(flat),
        rep: Vec::new(),
        rep_dofs: Vec::new(),
        seeds: Vec::new(),
        by_orbit: Vec::with_capacity(orbits.len()),
        rigid_maps: (0..d)
            .map(|b| {
                (0..group.order()).fold((Matrix3::zeros(), Matrix3::zeros()), |(t, w), g| {
                    let c = matrices[g][(b, 0)] * d as f64 / order;
                    let r = group.element(g);
                    (t + r * c, w + r * (c * r.determinant()))
                })
            })
            .collect(),
    };
    for orbit in orbits {
        let i0 = orbit[0];
        let start = seeds.rep.len() as u32;
        // Gram matrix of the candidates P_{0b} e_{i0,c} (index 3b + c), from the stabiliser.
        let mut gram = DMatrix::<f64>::zeros(3 * d, 3 * d);
        for h in (0..group.order()).filter(|&h| action.node_perm(h)[i0] == i0) {
            let r = group.element(h);
            let dm = &matrices[h];
            for b in 0..d {
                for b2 in 0..d {
                    let x = dm[(b, b2)] * d as f64 / order;
                    if x == 0.0 {
                        continue;
                    }
                    for c in 0..3 {
                        for c2 in 0..3 {
                            gram[(3 * b + c, 3 * b2 + c2)] += x * r[(c, c2)];
                        }
                    }
                }
            }
        }
        let eig = SymmetricEigen::new((&gram + gram.transpose()) * 0.5);
        // Genuine directions have eigenvalues of order d|H|/|G|, round-off ones of 1e-16.
        for (k, &lam) in eig.eigenvalues.iter().enumerate() {
            if lam <= 1e-10 {
                continue;
            }
            let y = eig.eigenvectors.column(k) / lam.sqrt();
            seeds.rep.push(i0 as u32);
            seeds
                .rep_dofs
                .push([0, 1, 2].map(|c| layout.dof(i0, c).expect("free orbit") as u32));
            for b in 0..d {
                seeds
                    .seeds
                    .push(Vector3::new(y[3 * b], y[3 * b + 1], y[3 * b + 2]));
            }
        }
        seeds.by_orbit.push(start..seeds.rep.len() as u32);
    }
    let columns = (0..seeds.rep.len())
        .into_par_iter()
        .map(|e| seeds.column(action, layout, e, 0))
        .collect();
    SparseBasis {
        unknowns: layout.unknowns(),
        columns,
        by_dof: std::sync::OnceLock::new(),
        seeds: Some(seeds),
        pattern: std::sync::OnceLock::new(),
    }
}

/// The free orbits of `action` on `layout` (fixed orbits carry no unknowns).
fn free_orbits(action: &GroupAction, layout: &Layout) -> Vec<Vec<usize>> {
    action
        .node_orbits()
        .into_iter()
        .filter(|o| layout.dof(o[0], 0).is_some())
        .collect()
}

/// An orthonormal basis with sparse columns, each a list of (unknown, value).
#[derive(Debug, Clone)]
pub struct SparseBasis {
    unknowns: usize,
    columns: Vec<Vec<(usize, f64)>>,
    /// For each unknown, the columns whose support contains it (built on first use).
    by_dof: std::sync::OnceLock<Vec<Vec<u32>>>,
    /// The orbit-local form, when the basis was built from a group action.
    seeds: Option<Seeds>,
    /// The sparsity pattern of Bᵀ K B (built on first use),
    /// and for each stored entry the slot of its transpose.
    pattern: std::sync::OnceLock<(Arc<SymmetricPattern>, Vec<u32>)>,
}

impl SparseBasis {
    /// The fixed-point space of `action` on the unknowns of `layout`: for the orbit of node i
    /// with stabiliser H_i, the vectors v fixed by H_i spread over the orbit as
    /// u_{π_g(i)} = R_g v / √|orbit| (the trivial irrep's block).
    pub fn fixed_point(action: &GroupAction, layout: &Layout) -> Self {
        let orbits = free_orbits(action, layout);
        let frame = Arc::new(OrbitFrame::new(action, layout, &orbits));
        let trivial = vec![DMatrix::from_element(1, 1, 1.0); action.group().order()];
        orbit_basis(action, layout, &frame, &orbits, &trivial)
    }

    fn from_columns(unknowns: usize, columns: Vec<Vec<(usize, f64)>>) -> Self {
        Self {
            unknowns,
            columns,
            by_dof: std::sync::OnceLock::new(),
            seeds: None,
            pattern: std::sync::OnceLock::new(),
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

    /// Bᵀ v for a G-invariant v (T(g) v = v, such as the residual and the load vectors at a
    /// symmetric state), from v's entries at the orbit representatives only: with b = Σ_b
    /// P_{0b} s_b, ⟨b, v⟩ = Σ_b ⟨s_b, P_{b0} v⟩, which is ⟨s, v⟩ for the trivial irrep and 0
    /// for any other (Σ_g D(g) = 0). Falls back to [`SparseBasis::restrict`] for a basis
    /// without orbit-local form.
    pub fn restrict_invariant(&self, v: &[f64]) -> DVector<f64> {
        let Some(seeds) = &self.seeds else {
            return self.restrict(v);
        };
        if seeds.d != 1 || seeds.matrices.iter().any(|&x| x != 1.0) {
            return DVector::zeros(self.dim());
        }
        DVector::from_iterator(
            self.dim(),
            seeds
                .rep_dofs
                .iter()
                .zip(&seeds.seeds)
                .map(|(dofs, s)| (0..3).map(|c| s[c] * v[dofs[c] as usize]).sum()),
        )
    }

    /// Bᵀ v for the rigid motion v_i = t + ω × x_i (`motion` = [t, ω]) at a state x the
    /// group keeps, in O(columns): T(g) maps it to the rigid motion (R_g t, det(R_g) R_g ω)
    /// because x_{π_g(i)} = R_g x_i, so P_{b0} v is the rigid motion (t_b, ω_b) of
    /// `rigid_maps` and ⟨b, v⟩ = Σ_b s_b · (t_b + ω_b × x_rep). Without orbit-local form, the
    /// field is built and restricted explicitly.
    pub fn restrict_rigid(
        &self,
        motion: &[f64; 6],
        x: &[Vector3<f64>],
        layout: &Layout,
    ) -> DVector<f64> {
        let t = Vector3::new(motion[0], motion[1], motion[2]);
        let w = Vector3::new(motion[3], motion[4], motion[5]);
        let Some(seeds) = &self.seeds else {
            let mut v = vec![0.0; self.unknowns];
            for (i, xi) in x.iter().enumerate() {
                let vi = t + w.cross(xi);
                for k in 0..3 {
                    if let Some(d) = layout.dof(i, k) {
                        v[d] = vi[k];
                    }
                }
            }
            return self.restrict(&v);
        };
        let moved: Vec<(Vector3<f64>, Vector3<f64>)> = seeds
            .rigid_maps
            .iter()
            .map(|(a, b)| (a * t, b * w))
            .collect();
        let d = seeds.d;
        DVector::from_iterator(
            self.dim(),
            (0..self.dim()).map(|e| {
                let xr = x[seeds.rep[e] as usize];
                moved
                    .iter()
                    .zip(&seeds.seeds[e * d..(e + 1) * d])
                    .map(|((tb, wb), s)| s.dot(&(tb + wb.cross(&xr))))
                    .sum()
            }),
        )
    }

    /// The representative nodes of the orbits the columns live on (`None` for a basis
    /// without orbit-local form): F, ∂F/∂Λ and K's columns there are all that
    /// [`SparseBasis::restrict_invariant`] and [`SparseBasis::restrict_tangent`] read.
    pub fn representatives(&self) -> Option<Vec<usize>> {
        let seeds = self.seeds.as_ref()?;
        let mut reps: Vec<usize> = seeds.rep.iter().map(|&i| i as usize).collect();
        reps.dedup();
        Some(reps)
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
    /// its rank-one terms) at a state that the basis's group keeps; `work` is scratch.
    ///
    /// A basis built from a group action uses the orbit-local formula of the module docs
    /// (only K's columns at the orbit representatives are read); any other basis the
    /// column-by-column product of [`SparseBasis::restrict_tangent_to`].
    pub fn restrict_tangent(
        &self,
        layout: &Layout,
        eval: &Evaluation,
        work: &mut Vec<f64>,
    ) -> DMatrix<f64> {
        let out = match &self.seeds {
            Some(seeds) => self.restrict_tangent_seeded(seeds, layout, eval),
            None => self.restrict_tangent_to(self, layout, eval, work),
        };
        (&out + out.transpose()) * 0.5
    }

    /// The orbit-local Bᵀ K B (module docs), one column per rayon task.
    fn restrict_tangent_seeded(
        &self,
        seeds: &Seeds,
        layout: &Layout,
        eval: &Evaluation,
    ) -> DMatrix<f64> {
        let m = self.dim();
        let mut out = DMatrix::zeros(m, m);
        if m == 0 {
            return out;
        }
        out.as_mut_slice()
            .par_chunks_mut(m)
            .enumerate()
            .for_each_init(
                || ColumnScratch::new(seeds.d),
                |scratch, (e, out_col)| {
                    seeds.tangent_column(e, layout, &eval.tangent, scratch, out_col)
                },
            );
        for (c, a) in &eval.rank_one {
            let ar = self.restrict(a);
            out += &ar * ar.transpose() * *c;
        }
        out
    }

    /// The sparse part of Bᵀ K B (without `eval`'s rank-one terms) on its own pattern, for
    /// a basis built from a group action (`None` otherwise). The pattern — column e meets
    /// the columns on the orbits next to e's representative — is computed on first use.
    pub fn restrict_tangent_sparse(
        &self,
        layout: &Layout,
        eval: &Evaluation,
    ) -> Option<(Arc<SymmetricPattern>, Vec<f64>)> {
        let seeds = self.seeds.as_ref()?;
        let (pattern, transpose) = self.pattern.get_or_init(|| {
            let pattern = seeds.block_pattern(layout);
            let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
            let mut transpose = vec![0u32; pattern.nnz()];
            for e in 0..pattern.n() {
                for p in col_ptr[e]..col_ptr[e + 1] {
                    transpose[p] = pattern
                        .position(e, row_idx[p])
                        .expect("the block pattern is symmetric")
                        as u32;
                }
            }
            (Arc::new(pattern), transpose)
        });
        let pattern = pattern.clone();
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let m = self.dim();
        let columns: Vec<Vec<f64>> = (0..m)
            .into_par_iter()
            .map_init(
                || (ColumnScratch::new(seeds.d), vec![0.0; m]),
                |(scratch, dense), e| {
                    seeds.tangent_column(e, layout, &eval.tangent, scratch, dense);
                    let rows = &row_idx[col_ptr[e]..col_ptr[e + 1]];
                    let values = rows.iter().map(|&r| dense[r]).collect();
                    rows.iter().for_each(|&r| dense[r] = 0.0);
                    values
                },
            )
            .collect();
        // Symmetrise: the two triangles agree up to round-off.
        let raw: Vec<f64> = columns.concat();
        let values = raw
            .iter()
            .zip(transpose)
            .map(|(v, &q)| 0.5 * (v + raw[q as usize]))
            .collect();
        Some((pattern, values))
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
    /// The first partner's columns: the block's basis. The other partners hold the same
    /// block again (they are built on demand by [`IrrepBasis::partners`]; kept, they would
    /// take d times the memory, ≈ 2 GB at f = 128 for Ih).
    first: SparseBasis,
}

impl IrrepBasis {
    /// The block's basis: the columns of the first partner.
    pub fn first(&self) -> &SparseBasis {
        &self.first
    }

    /// All d partners (a = 0..d, the first one included), partner a = P_{a0} of the first:
    /// together with the other irreps', an orthonormal basis of the unknowns. For checks;
    /// the analysis needs only [`IrrepBasis::first`].
    pub fn partners(&self, action: &GroupAction, layout: &Layout) -> Vec<SparseBasis> {
        let seeds = self.first.seeds.as_ref().expect("built from seeds");
        std::iter::once(self.first.clone())
            .chain((1..self.dim).map(|a| {
                let columns = (0..self.first.dim())
                    .into_par_iter()
                    .map(|e| seeds.column(action, layout, e, a))
                    .collect();
                SparseBasis::from_columns(layout.unknowns(), columns)
            }))
            .collect()
    }
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
    /// partner a from the operators P^μ_{ab} = (d/|G|) Σ_g D^μ_ab(g) T(g) in orbit-local form
    /// (module docs): the first copy from the seeds of each orbit, partner a as
    /// P^μ_{a0} of those columns. Fixed orbits are skipped.
    pub fn new(action: &GroupAction, layout: &Layout) -> Result<Self, AdaptedError> {
        let group = action.group();
        let order = group.order() as f64;
        let orbits = free_orbits(action, layout);
        let frame = Arc::new(OrbitFrame::new(action, layout, &orbits));
        // χ_T(g) = #{free nodes fixed by g} · tr R_g.
        let chi_t: Vec<f64> = (0..group.order())
            .map(|g| {
                let fixed = orbits
                    .iter()
                    .flatten()
                    .filter(|&&i| action.node_perm(g)[i] == i)
                    .count();
                fixed as f64 * group.element(g).trace()
            })
            .collect();
        let mut irreps = Vec::new();
        for irrep in group.irreps() {
            if irrep.kind() != symmetry::IrrepKind::Real {
                return Err(AdaptedError::ComplexType(
                    irrep.name().into(),
                    group.name().into(),
                ));
            }
            let d = irrep.dim();
            // Character formula: the multiplicity of μ in T.
            let m: f64 = (0..group.order())
                .map(|g| chi_t[g] * irrep.character(g))
                .sum::<f64>()
                / order;
            let multiplicity = m.round() as usize;
            let first = orbit_basis(action, layout, &frame, &orbits, irrep.matrices());
            if first.dim() != multiplicity {
                return Err(AdaptedError::Count {
                    irrep: irrep.name().into(),
                    built: first.dim(),
                    predicted: multiplicity,
                });
            }
            irreps.push(IrrepBasis {
                name: irrep.name().into(),
                dim: d,
                multiplicity,
                first,
            });
        }
        Ok(Self { irreps })
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
    /// From this many columns on the restricted tangent is passed on sparse.
    sparse_from: usize,
    /// The sparse LBLᵀ of the restricted tangent, its symbolic analysis done once.
    solver: crate::continuation::SharedFactorization,
    /// Where the evaluations' time went (for `memstab bench`).
    pub times: PhaseTimes,
}

/// Default [`SymmetricProblem::with_sparse_tangent_from`]: below this size a dense LU of the
/// extended system is cheaper than a sparse one (f = 32: 272 columns; f = 64: 1 056).
pub const SPARSE_TANGENT_FROM: usize = 600;

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
            sparse_from: SPARSE_TANGENT_FROM,
            solver: Default::default(),
            model,
            basis,
            constraints,
            params,
            free,
            times: PhaseTimes::default(),
        }
    }

    /// Assembles the whole mesh at every evaluation instead of only the triangles around the
    /// orbit representatives (for checks and timing comparisons).
    pub fn with_full_assembly(mut self) -> Self {
        use crate::model::Model;
        self.eval = self.model.new_evaluation();
        self
    }

    /// Passes the restricted tangent on as a sparse matrix (to a sparse LU of the extended
    /// system) when the basis has at least `columns` columns; `usize::MAX` keeps it dense.
    pub fn with_sparse_tangent_from(mut self, columns: usize) -> Self {
        self.sparse_from = columns;
        self
    }

    /// Bᵀ K B of the last evaluation, sparse for a large basis built from a group action.
    fn restricted_tangent(&mut self) -> crate::continuation::Tangent {
        use crate::continuation::Tangent;
        let layout = self.model.layout();
        if self.basis.dim() >= self.sparse_from {
            if let Some((pattern, values)) = self.basis.restrict_tangent_sparse(layout, &self.eval)
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
        let lin = crate::continuation::Linearization {
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
}
