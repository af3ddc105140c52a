//! Symmetry-adapted bases (docs/theory.md §10): the fixed-point space of the group — the
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
//! orbits and carry no unknowns; at a node that slides in a plane the candidates are projected
//! onto the plane, so every column has u·n = 0 there (the group maps the plane's normal to
//! ±itself, so the projection commutes with the stabiliser).
//!
//! **Complex type.** The 2-D irreps E_k of a chiral group have commutant ℂ, and the formulas
//! above (which rest on Schur's P_{ab} P_{cd} = δ_{bc} P_{ad}) do not hold for them; their
//! isotypic component is built from the complex projector of their 1-D complex character
//! instead, and their block is Hermitian (see `complex.rs` and docs/theory.md §10.6). Its
//! columns have an orbit-local form of their own (complex seeds), from which the real block
//! R = [[A, C], [−C, A]] is restricted, dense or sparse, from the representatives as above.

mod complex;
pub mod labels;
mod orbit;

pub use complex::{hermitian, to_complex, to_real};

use crate::linalg::SymmetricPattern;
use crate::model::{Evaluation, Layout};
use meshes::GroupAction;
use nalgebra::{DMatrix, DVector, Vector3};
use orbit::{orbit_basis, ColumnScratch, OrbitFrame, OrbitScratch, Seeds};
use rayon::prelude::*;
use std::sync::Arc;

/// The free orbits of `action` on `layout` (fixed orbits carry no unknowns).
fn free_orbits(action: &GroupAction, layout: &Layout) -> Vec<Vec<usize>> {
    action
        .node_orbits()
        .into_iter()
        .filter(|o| layout.dof(o[0], 0).is_some())
        .collect()
}

/// An orthonormal basis with sparse columns, each a list of (unknown, value).
///
/// A basis built from a group action keeps its orbit-local form (seeds) and builds the
/// explicit columns only when asked ([`SparseBasis::columns`], [`SparseBasis::restrict`],
/// [`SparseBasis::expand`]): each has 3|orbit| entries, ≈ 750 MB for every block at f = 128
/// under Ih, and the restrictions of the tangent, residual and rigid motions never read them.
#[derive(Debug, Clone)]
pub struct SparseBasis {
    unknowns: usize,
    /// Number of columns m.
    dim: usize,
    columns: std::sync::OnceLock<Vec<Vec<(usize, f64)>>>,
    /// For each unknown, the columns whose support contains it (built on first use).
    by_dof: std::sync::OnceLock<Vec<Vec<u32>>>,
    /// The orbit-local form, when the basis was built from a group action.
    seeds: Option<Seeds>,
    /// The orbit-local form of a complex-type block's columns [u, v] (complex.rs).
    complex: Option<complex::ComplexSeeds>,
    /// The sparsity pattern of Bᵀ K B and how its triangles are made symmetric (built on
    /// first use, or by [`SparseBasis::prepare_pattern`]).
    pattern: std::sync::OnceLock<(Arc<SymmetricPattern>, Mirror)>,
    /// Whether the basis is the identity (decided on first use).
    identity: std::sync::OnceLock<bool>,
}

/// How the restriction of the tangent onto a block pattern is made symmetric.
#[derive(Debug, Clone)]
enum Mirror {
    /// The identity basis: K is taken as assembled.
    Identity,
    /// A seeded block: its entries below the diagonal of orbits are computed, those above
    /// copied from their transposes ([`orbit::Seeds::mirror`]).
    Orbits(orbit::OrbitRows),
    /// A complex-type block: both triangles are computed, each entry averaged with its
    /// transpose, whose slot this holds for every stored entry.
    Transposes(Vec<u32>),
}

/// The size of an entry of `Seeds::rigid_maps` below which it is round-off: the maps are
/// (d/|G|) Σ_g D_{b0}(g) R_g, of order one where the irrep occurs in the translations or the
/// rotations and zero by Schur's orthogonality where it does not.
const RIGID_MAP_ZERO: f64 = 1e-10;

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

    fn with_seeds(unknowns: usize, seeds: Seeds) -> Self {
        Self {
            unknowns,
            dim: seeds.rep.len(),
            columns: std::sync::OnceLock::new(),
            by_dof: std::sync::OnceLock::new(),
            seeds: Some(seeds),
            complex: None,
            pattern: std::sync::OnceLock::new(),
            identity: std::sync::OnceLock::new(),
        }
    }

    fn with_complex_seeds(
        unknowns: usize,
        columns: Vec<Vec<(usize, f64)>>,
        complex: complex::ComplexSeeds,
    ) -> Self {
        Self {
            unknowns,
            dim: columns.len(),
            columns: columns.into(),
            by_dof: std::sync::OnceLock::new(),
            seeds: None,
            complex: Some(complex),
            pattern: std::sync::OnceLock::new(),
            identity: std::sync::OnceLock::new(),
        }
    }

    /// Whether the columns are the [u, v] of a complex-type block (docs/theory.md §10.6):
    /// then Bᵀ K B = [[A, C], [−C, A]] commutes with J [p; q] = [−q; p] and every eigenvalue
    /// is double.
    pub fn is_complex(&self) -> bool {
        self.complex.is_some()
    }

    fn from_columns(unknowns: usize, columns: Vec<Vec<(usize, f64)>>) -> Self {
        Self {
            unknowns,
            dim: columns.len(),
            columns: columns.into(),
            by_dof: std::sync::OnceLock::new(),
            seeds: None,
            complex: None,
            pattern: std::sync::OnceLock::new(),
            identity: std::sync::OnceLock::new(),
        }
    }

    /// Number of columns m.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Number of rows (the model's unknowns).
    pub fn unknowns(&self) -> usize {
        self.unknowns
    }

    /// Whether the basis is the identity: a column per unknown, column i the unit vector e_i
    /// (the trivial group on every unknown). Builds the columns only when there are as many
    /// as unknowns.
    pub fn is_identity(&self) -> bool {
        *self.identity.get_or_init(|| {
            self.dim == self.unknowns
                && self
                    .columns()
                    .iter()
                    .enumerate()
                    .all(|(i, c)| c.as_slice() == [(i, 1.0)])
        })
    }

    /// The sparse columns (built from the seeds on first use, in parallel).
    pub fn columns(&self) -> &[Vec<(usize, f64)>] {
        self.columns.get_or_init(|| {
            let seeds = self
                .seeds
                .as_ref()
                .expect("a basis without seeds is built with its columns");
            (0..self.dim)
                .into_par_iter()
                .map(|e| seeds.column(e, 0))
                .collect()
        })
    }

    /// Bᵀ v.
    pub fn restrict(&self, v: &[f64]) -> DVector<f64> {
        DVector::from_iterator(
            self.dim(),
            self.columns()
                .iter()
                .map(|c| c.iter().map(|&(d, b)| b * v[d]).sum()),
        )
    }

    /// Bᵀ v for a G-invariant v (T(g) v = v, such as the residual and the load vectors at a
    /// symmetric state), from v's entries at the orbit representatives only: with b = Σ_b
    /// P_{0b} s_b, ⟨b, v⟩ = Σ_b ⟨s_b, P_{b0} v⟩, which is ⟨s, v⟩ for the trivial irrep and 0
    /// for any other (Σ_g D(g) = 0), a complex-type block included (Σ_g conj χ(g) = 0).
    /// Falls back to [`SparseBasis::restrict`] for a basis without orbit-local form.
    pub fn restrict_invariant(&self, v: &[f64]) -> DVector<f64> {
        if self.complex.is_some() {
            return DVector::zeros(self.dim());
        }
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

    /// Whether a rigid motion can have a nonzero restriction to this basis: false for a
    /// basis with orbit-local form whose irrep occurs in neither the translations nor the
    /// rotations (its projections of both vanish, `Seeds::rigid_maps`), where
    /// [`SparseBasis::restrict_rigid`] is zero for every motion at every state.
    pub fn holds_rigid_motions(&self) -> bool {
        self.seeds.as_ref().is_none_or(|seeds| {
            seeds
                .rigid_maps
                .iter()
                .any(|(t, w)| t.amax().max(w.amax()) > RIGID_MAP_ZERO)
        })
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
        let rep = match (&self.seeds, &self.complex) {
            (Some(seeds), _) => &seeds.rep,
            (None, Some(complex)) => &complex.rep,
            (None, None) => return None,
        };
        let mut reps: Vec<usize> = rep.iter().map(|&i| i as usize).collect();
        reps.dedup();
        Some(reps)
    }

    /// u = B q.
    pub fn expand(&self, q: &DVector<f64>, u: &mut [f64]) {
        u.fill(0.0);
        for (c, &qc) in self.columns().iter().zip(q.iter()) {
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
        let out = match (&self.seeds, &self.complex) {
            (Some(seeds), _) => self.restrict_tangent_seeded(seeds, layout, eval),
            (None, Some(complex)) => {
                let mut out = complex::realify(&complex.hermitian_dense(layout, &eval.tangent));
                for (c, a) in &eval.rank_one {
                    let ar = self.restrict(a);
                    out += &ar * ar.transpose() * *c;
                }
                out
            }
            (None, None) => self.restrict_tangent_to(self, layout, eval, work),
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
    /// A complex-type block gives its real R = [[A, C], [−C, A]] (complex.rs). The identity
    /// (the trivial group's only block) gives K as assembled, on the model's pattern: the
    /// same values and pattern as the restriction, without the work.
    pub fn restrict_tangent_sparse(
        &self,
        layout: &Layout,
        eval: &Evaluation,
    ) -> Option<(Arc<SymmetricPattern>, Vec<f64>)> {
        self.restrict_tangent_sparse_into(layout, eval, Vec::new())
    }

    /// Builds the pattern of Bᵀ K B for `layout` now, where the block has an orbit-local
    /// form (it is otherwise built by the first restriction): the structure of the block, as
    /// the layout's pattern is K's.
    pub fn prepare_pattern(&self, layout: &Layout) {
        let _ = self.block_pattern(layout);
    }

    /// The pattern of Bᵀ K B and how its restriction is made symmetric (built on first use);
    /// `None` without an orbit-local form.
    fn block_pattern(&self, layout: &Layout) -> Option<&(Arc<SymmetricPattern>, Mirror)> {
        if self.seeds.is_none() && self.complex.is_none() {
            return None;
        }
        Some(self.pattern.get_or_init(|| {
            if self.is_identity() {
                return (Arc::new(layout.pattern().clone()), Mirror::Identity);
            }
            let complex = match (&self.seeds, &self.complex) {
                (Some(seeds), _) => {
                    let (pattern, rows) = seeds.block_pattern(layout);
                    return (Arc::new(pattern), Mirror::Orbits(rows));
                }
                (None, Some(complex)) => complex,
                (None, None) => unreachable!("checked above"),
            };
            let pattern = complex.real_pattern(layout);
            // The transpose of entry (r, e) is (e, r): going through the columns in order,
            // column r meets its rows e in increasing order, one after the other.
            let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
            let mut transpose = vec![0u32; pattern.nnz()];
            let mut next = col_ptr[..pattern.n()].to_vec();
            for e in 0..pattern.n() {
                for p in col_ptr[e]..col_ptr[e + 1] {
                    let r = row_idx[p];
                    assert_eq!(row_idx[next[r]], e, "the block pattern is symmetric");
                    transpose[p] = next[r] as u32;
                    next[r] += 1;
                }
            }
            (Arc::new(pattern), Mirror::Transposes(transpose))
        }))
    }

    /// As [`SparseBasis::restrict_tangent_sparse`], its values written into `buffer` (resized;
    /// its earlier contents ignored) for a block with orbit-local form: a caller that restricts
    /// at every path point keeps one buffer instead of a fresh allocation per point (one that
    /// the allocator maps and the kernel zeroes anew while its size is above the allocator's
    /// mapping threshold).
    pub fn restrict_tangent_sparse_into(
        &self,
        layout: &Layout,
        eval: &Evaluation,
        buffer: Vec<f64>,
    ) -> Option<(Arc<SymmetricPattern>, Vec<f64>)> {
        let (pattern, mirror) = self.block_pattern(layout)?;
        let pattern = pattern.clone();
        let transpose = match mirror {
            Mirror::Identity => return Some((pattern, eval.tangent.clone())),
            Mirror::Orbits(rows) => {
                let seeds = self.seeds.as_ref().expect("a seeded block");
                let mut values = self.seeded_lower(seeds, rows, &pattern, layout, eval, buffer);
                seeds.mirror(rows, pattern.col_ptr(), &mut values);
                return Some((pattern, values));
            }
            Mirror::Transposes(transpose) => transpose,
        };
        let complex = self
            .complex
            .as_ref()
            .expect("a block with transposes is complex-type");
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        // Column e of H gives the real columns e and m + e of R.
        let columns: Vec<Vec<f64>> = {
            let mc = complex.len();
            let halves: Vec<(Vec<f64>, Vec<f64>)> = (0..mc)
                .into_par_iter()
                .map_init(
                    || {
                        (
                            complex::HermitianScratch::default(),
                            vec![nalgebra::Complex::new(0.0, 0.0); mc],
                        )
                    },
                    |(scratch, h), e| {
                        complex.hermitian_column(e, layout, &eval.tangent, scratch, h);
                        let pick = |col: usize| -> Vec<f64> {
                            row_idx[col_ptr[col]..col_ptr[col + 1]]
                                .iter()
                                .map(|&r| match (r < mc, col < mc) {
                                    (true, true) | (false, false) => h[r % mc].re,
                                    (true, false) => h[r].im,
                                    (false, true) => -h[r - mc].im,
                                })
                                .collect()
                        };
                        let out = (pick(e), pick(mc + e));
                        h.iter_mut()
                            .for_each(|x| *x = nalgebra::Complex::new(0.0, 0.0));
                        out
                    },
                )
                .collect();
            let (u, v): (Vec<_>, Vec<_>) = halves.into_iter().unzip();
            u.into_iter().chain(v).collect()
        };
        // Symmetrise: the two triangles agree up to round-off.
        let raw: Vec<f64> = columns.concat();
        let values = raw
            .iter()
            .zip(transpose)
            .map(|(v, &q)| 0.5 * (v + raw[q as usize]))
            .collect();
        Some((pattern, values))
    }

    /// The values of the sparse Bᵀ K B of a real seeded block on its `pattern` (laid out by
    /// `rows`), on and below the diagonal of orbits ([`Seeds::tangent_orbit_lower`], each
    /// orbit's columns written in place; the entries above it are left as they were), in
    /// tasks of several orbits.
    fn seeded_lower(
        &self,
        seeds: &Seeds,
        rows: &orbit::OrbitRows,
        pattern: &SymmetricPattern,
        layout: &Layout,
        eval: &Evaluation,
        mut raw: Vec<f64>,
    ) -> Vec<f64> {
        let col_ptr = pattern.col_ptr();
        // Each orbit's columns are contiguous in the values: one slice per orbit, filled by
        // its task.
        raw.resize(pattern.nnz(), 0.0);
        let mut slices: Vec<(usize, &mut [f64])> = Vec::with_capacity(seeds.by_orbit.len());
        let mut rest: &mut [f64] = &mut raw;
        for (o, cols) in seeds.by_orbit.iter().enumerate() {
            let (start, end) = (cols.start as usize, cols.end as usize);
            let (part, tail) =
                std::mem::take(&mut rest).split_at_mut(col_ptr[end] - col_ptr[start]);
            slices.push((o, part));
            rest = tail;
        }
        // Orbits in tasks of at least ORBITS_PER_TASK: the blocks are themselves restricted in
        // parallel, and a task per few orbits costs more (its scratch, rayon's splitting)
        // than the orbits of a small block.
        const ORBITS_PER_TASK: usize = 64;
        slices
            .into_par_iter()
            .with_min_len(ORBITS_PER_TASK)
            .for_each_init(
                || OrbitScratch::new(seeds.d),
                |scratch, (o, part)| {
                    seeds.tangent_orbit_lower(o, layout, &eval.tangent, rows, scratch, part);
                },
            );
        raw
    }

    /// The columns containing each unknown.
    fn columns_by_dof(&self) -> &Vec<Vec<u32>> {
        self.by_dof.get_or_init(|| {
            let mut by_dof = vec![Vec::new(); self.unknowns];
            for (i, c) in self.columns().iter().enumerate() {
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
        let columns = self.columns();
        for (j, cj) in other.columns().iter().enumerate() {
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
                out[(i, j)] = columns[i].iter().map(|&(d, b)| b * work[d]).sum();
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

/// The columns of one partner of one irrep, and the blocks of every irrep (docs/theory.md §10).
#[derive(Debug, Clone)]
pub struct IrrepBasis {
    /// Irrep name.
    pub name: String,
    /// Irrep dimension d.
    pub dim: usize,
    /// How often the irrep occurs in T: (1/|G|) Σ χ_T(g) χ_μ(g) divided by the dimension of
    /// μ's commutant (1 for real type, 2 for complex type).
    pub multiplicity: usize,
    /// Complex type (docs/theory.md §10.6): `first` holds the whole isotypic component as
    /// 2m real columns [u, v] and the block is the Hermitian m × m [`hermitian`] of its
    /// real 2m × 2m restriction; there are no other partners.
    pub complex: bool,
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
    /// the analysis needs only [`IrrepBasis::first`]. A complex-type irrep has the one
    /// "partner" `first`, which already spans its isotypic component.
    pub fn partners(&self, layout: &Layout) -> Vec<SparseBasis> {
        if self.complex {
            return vec![self.first.clone()];
        }
        let seeds = self.first.seeds.as_ref().expect("built from seeds");
        std::iter::once(self.first.clone())
            .chain((1..self.dim).map(|a| {
                let columns = (0..self.first.dim())
                    .into_par_iter()
                    .map(|e| seeds.column(e, a))
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
    /// A complex-type irrep that is not 2-D with a complex structure (no point group has
    /// one; the E_k of C_n and the like are 2-D).
    #[error("irrep {0} of {1} is of complex type but not 2-D with a complex structure")]
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
    /// P^μ_{a0} of those columns. A complex-type irrep gets the 2m real columns of its
    /// whole isotypic component from the complex projector of its character
    /// (docs/theory.md §10.6), in an orbit-local form of complex seeds. Fixed orbits are
    /// skipped.
    pub fn new(action: &GroupAction, layout: &Layout) -> Result<Self, AdaptedError> {
        let group = action.group();
        let order = group.order() as f64;
        let orbits = free_orbits(action, layout);
        let frame = Arc::new(OrbitFrame::new(action, layout, &orbits));
        // χ_T(g) = Σ over the free nodes fixed by g of tr R_g on the node's displacements:
        // tr R_g, or tr R_g − n·R_g n for a node sliding in the plane with normal n.
        let chi_t: Vec<f64> = (0..group.order())
            .map(|g| {
                let r = group.element(g);
                orbits
                    .iter()
                    .flatten()
                    .filter(|&&i| action.node_perm(g)[i] == i)
                    .map(|&i| match layout.slide_normal(i) {
                        Some(n) => r.trace() - n.dot(&(r * n)),
                        None => r.trace(),
                    })
                    .sum()
            })
            .collect();
        let mut irreps = Vec::new();
        for irrep in group.irreps() {
            let d = irrep.dim();
            // Character formula: (1/|G|) Σ χ_T χ_μ = multiplicity × dim of the commutant.
            let m: f64 = (0..group.order())
                .map(|g| chi_t[g] * irrep.character(g))
                .sum::<f64>()
                / order;
            let predicted = m.round() as usize;
            let (first, multiplicity, complex) = match irrep.kind() {
                symmetry::IrrepKind::Real => (
                    orbit_basis(action, layout, &frame, &orbits, irrep.matrices()),
                    predicted,
                    false,
                ),
                symmetry::IrrepKind::Complex => {
                    let j = irrep
                        .complex_structure()
                        .filter(|_| d == 2)
                        .ok_or_else(|| {
                            AdaptedError::ComplexType(irrep.name().into(), group.name().into())
                        })?;
                    let chi = complex::character(irrep.matrices(), j);
                    let first = complex::complex_basis(action, layout, &frame, &orbits, &chi);
                    (first, predicted / 2, true)
                }
            };
            if first.dim() != predicted {
                return Err(AdaptedError::Count {
                    irrep: irrep.name().into(),
                    built: first.dim(),
                    predicted,
                });
            }
            irreps.push(IrrepBasis {
                name: irrep.name().into(),
                dim: d,
                multiplicity,
                complex,
                first,
            });
        }
        Ok(Self { irreps })
    }
}
