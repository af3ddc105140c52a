//! Complex-type irreps (docs/theory.md §10.6): the real 2-D irrep E_k of a chiral group
//! (D(g) = c_g I + s_g J, J² = −I) is over ℂ the sum of the 1-D irrep χ(g) = c_g + i s_g and
//! its conjugate. Its isotypic component of T is the real part of the χ-isotypic component of
//! T ⊗ ℂ, whose orthogonal projector is
//!
//!   P = (1/|G|) Σ_g conj χ(g) T(g),   P = Pᴴ = P²,  P K = K P.
//!
//! Per orbit, complex seeds s ∈ ℂ³ at the representative i₀ come from the Hermitian Gram
//! matrix of the candidates P e_{i₀c}, ⟨P e_c, P e_c'⟩ = e_cᵀ P e_c' = (1/|G|) Σ_{h ∈ H}
//! conj χ(h) (R_h)_{cc'} (only the stabiliser H of i₀ contributes): its eigenvectors with
//! eigenvalue λ > 0, scaled by λ^{-1/2}, give orthonormal complex columns b_e = P s_e.
//!
//! Real columns: u_e = √2 Re b_e and v_e = √2 Im b_e. They are orthonormal (b_fᵀ b_e = 0,
//! b̄_f lying in the conjugate isotypic component), and span the real isotypic component of
//! E_k (2m real dimensions for m complex columns). In the real basis [u, v] the block is
//!
//!   R = [[A, C], [−C, A]],   A = uᵀ K u = vᵀ K v,   C = uᵀ K v = −Cᵀ,
//!
//! the realification of the Hermitian m × m block H = bᴴ K b = A + i C. H's eigenvalues are
//! R's, each once instead of twice: every eigenvalue of E_k's block is double in K by
//! construction. An eigenvector z of H is the real field Σ_e Re(z_e) u_e − Im(z_e) v_e, i.e.
//! the real coordinates [Re z; −Im z] in [u, v]; its partner (i z) is [Im z; Re z].
//!
//! **Orbit-local form.** As for the real irreps (module docs of [`crate::adapted`]), H needs
//! K only at the orbit representatives: with P Hermitian, P² = P and P K = K P,
//!
//!   H_{fe} = (P s_f)ᴴ K P s_e = s_fᴴ P K s_e = (1/|G|) Σ_g conj χ(g) s_fᴴ (T(g) K s_e)_{i_f},
//!
//! where K s_e lives on the neighbours j of e's representative and only the elements g with
//! π_g(j) = i_f (f's representative) contribute. R is then [[Re H, Im H], [−Im H, Re H]] on
//! the pattern of H repeated four times.

use super::orbit::OrbitFrame;
use super::SparseBasis;
use crate::linalg::SymmetricPattern;
use crate::model::Layout;
use meshes::GroupAction;
use nalgebra::{Complex, DMatrix, Matrix3, SymmetricEigen, Vector3};
use rayon::prelude::*;
use std::ops::Range;
use std::sync::Arc;

type C64 = Complex<f64>;

/// Sparse real columns: (unknown, value) pairs.
type Column = Vec<(usize, f64)>;

/// χ(g) = (tr D(g) − i tr(J D(g)))/2 for every element: the eigenvalue of D(g) on the
/// eigenvector of J with eigenvalue i (D(g) = c I + s J gives c + i s).
pub(super) fn character(matrices: &[DMatrix<f64>], j: &DMatrix<f64>) -> Vec<C64> {
    matrices
        .iter()
        .map(|d| C64::new(d.trace() / 2.0, -(j * d).trace() / 2.0))
        .collect()
}

/// The orbit-local form of a complex-type block (module docs): per complex column e its
/// representative node and complex seed s_e (b_e = P s_e), and conj χ(g)/|G| per element.
#[derive(Debug, Clone)]
pub(super) struct ComplexSeeds {
    frame: Arc<OrbitFrame>,
    /// conj χ(g)/|G|.
    coef: Vec<C64>,
    /// Representative node of each complex column's orbit.
    pub(super) rep: Vec<u32>,
    /// The complex seed of each column at its representative.
    seeds: Vec<Vector3<C64>>,
    /// The complex columns on each free orbit (contiguous).
    by_orbit: Vec<Range<u32>>,
}

/// Per-thread scratch of [`ComplexSeeds::hermitian_column`]: the nodes touched by K s_e and
/// K s_e at them.
#[derive(Default)]
pub(super) struct HermitianScratch {
    touched: Vec<u32>,
    blocks: Vec<Matrix3<f64>>,
    w: Vec<Vector3<C64>>,
}

impl ComplexSeeds {
    /// Number m of complex columns.
    pub(super) fn len(&self) -> usize {
        self.rep.len()
    }

    /// Column e of H = bᴴ K b (module docs) added into `out` (length m).
    pub(super) fn hermitian_column(
        &self,
        e: usize,
        layout: &Layout,
        tangent: &[f64],
        scratch: &mut HermitianScratch,
        out: &mut [C64],
    ) {
        let frame = &*self.frame;
        let i0 = self.rep[e] as usize;
        let s = self.seeds[e];
        let HermitianScratch { touched, blocks, w } = scratch;
        frame.neighbour_blocks(layout, tangent, i0, touched, blocks);
        w.clear();
        w.extend(blocks.iter().map(|b| b.map(C64::from) * s));
        for (t, &j) in touched.iter().enumerate() {
            let cols = self.by_orbit[frame.orbit_of[j as usize] as usize].clone();
            if cols.is_empty() {
                continue;
            }
            for &g in frame.to_rep(j as usize) {
                let r = &frame.rotations[g as usize];
                let wt = &w[t];
                let x = Vector3::from_fn(|a, _| {
                    (0..3).map(|c| wt[c] * r[(a, c)]).sum::<C64>() * self.coef[g as usize]
                });
                for f in cols.clone() {
                    let sf = &self.seeds[f as usize];
                    out[f as usize] += (0..3).map(|c| sf[c].conj() * x[c]).sum::<C64>();
                }
            }
        }
    }

    /// The pattern of H: column e meets every column on an orbit that holds a neighbour of
    /// e's representative (by K's pattern).
    fn hermitian_pattern(&self, layout: &Layout) -> Vec<(usize, usize)> {
        self.frame
            .column_neighbours(layout, &self.rep, &self.by_orbit)
    }

    /// The pattern of the real R = [[A, C], [−C, A]] (2m × 2m): H's pattern in each quarter.
    pub(super) fn real_pattern(&self, layout: &Layout) -> SymmetricPattern {
        let m = self.len();
        let entries = self.hermitian_pattern(layout);
        SymmetricPattern::from_entries(
            2 * m,
            entries
                .into_iter()
                .flat_map(|(f, e)| [(f, e), (f, m + e), (m + f, e), (m + f, m + e)]),
        )
    }

    /// The dense H = bᴴ K b from the representatives' columns of K (without rank-one terms).
    pub(super) fn hermitian_dense(&self, layout: &Layout, tangent: &[f64]) -> DMatrix<C64> {
        let m = self.len();
        let mut h = DMatrix::<C64>::zeros(m, m);
        if m == 0 {
            return h;
        }
        h.as_mut_slice()
            .par_chunks_mut(m)
            .enumerate()
            .for_each_init(HermitianScratch::default, |scratch, (e, col)| {
                self.hermitian_column(e, layout, tangent, scratch, col)
            });
        h
    }
}

/// The real 2m × 2m R = [[Re H, Im H], [−Im H, Re H]] of a Hermitian m × m H (module docs).
pub(super) fn realify(h: &DMatrix<C64>) -> DMatrix<f64> {
    let m = h.nrows();
    DMatrix::from_fn(2 * m, 2 * m, |i, j| {
        let (f, e) = (i % m, j % m);
        match (i < m, j < m) {
            (true, true) | (false, false) => h[(f, e)].re,
            (true, false) => h[(f, e)].im,
            (false, true) => -h[(f, e)].im,
        }
    })
}

/// The real columns [u_1 … u_m, v_1 … v_m] of the isotypic component of the complex-type
/// irrep with character `chi` on the free `orbits` (module docs), with their orbit-local
/// form.
pub(super) fn complex_basis(
    action: &GroupAction,
    layout: &Layout,
    frame: &Arc<OrbitFrame>,
    orbits: &[Vec<usize>],
    chi: &[C64],
) -> SparseBasis {
    let group = action.group();
    let order = group.order() as f64;
    let mut seeds: Vec<(usize, Vector3<C64>)> = Vec::new();
    let mut by_orbit = Vec::with_capacity(orbits.len());
    for orbit in orbits {
        let i0 = orbit[0];
        let start = seeds.len() as u32;
        let mut gram = DMatrix::<C64>::zeros(3, 3);
        for h in (0..group.order()).filter(|&h| action.node_perm(h)[i0] == i0) {
            let r = group.element(h);
            let x = chi[h].conj() / order;
            for c in 0..3 {
                for c2 in 0..3 {
                    gram[(c, c2)] += x * r[(c, c2)];
                }
            }
        }
        // A node sliding in a plane: only candidates within the plane (u·n = 0).
        if let Some(n) = layout.slide_normal(i0) {
            let p = DMatrix::<C64>::from_fn(3, 3, |c, c2| {
                let delta = if c == c2 { 1.0 } else { 0.0 };
                C64::new(delta - n[c] * n[c2], 0.0)
            });
            gram = &p * gram * &p;
        }
        let gram = (&gram + gram.adjoint()) * C64::new(0.5, 0.0);
        let eig = SymmetricEigen::new(gram);
        // Genuine directions have eigenvalues of order |H|/|G|, round-off ones of 1e-16.
        for (k, &lam) in eig.eigenvalues.iter().enumerate() {
            if lam <= 1e-10 {
                continue;
            }
            let y = eig.eigenvectors.column(k) / C64::new(lam.sqrt(), 0.0);
            seeds.push((i0, Vector3::new(y[0], y[1], y[2])));
        }
        by_orbit.push(start..seeds.len() as u32);
    }
    let rotations: Vec<Matrix3<f64>> = group.elements().to_vec();
    let columns: Vec<(Column, Column)> = seeds
        .par_iter()
        .map(|&(i0, s)| {
            // b = P s = (1/|G|) Σ_g conj χ(g) T(g) s, gathered by node.
            let mut at: Vec<(usize, Vector3<C64>)> = Vec::new();
            for (g, r) in rotations.iter().enumerate() {
                let rs = Vector3::new(
                    (0..3).map(|c| s[c] * r[(0, c)]).sum::<C64>(),
                    (0..3).map(|c| s[c] * r[(1, c)]).sum::<C64>(),
                    (0..3).map(|c| s[c] * r[(2, c)]).sum::<C64>(),
                );
                let w = rs * (chi[g].conj() / order);
                let j = action.node_perm(g)[i0];
                match at.iter_mut().find(|(n, _)| *n == j) {
                    Some((_, x)) => *x += w,
                    None => at.push((j, w)),
                }
            }
            let (mut u, mut v) = (Vec::new(), Vec::new());
            for (j, w) in at {
                for k in 0..3 {
                    let dof = layout.dof(j, k).expect("free orbit");
                    let (re, im) = (
                        w[k].re * std::f64::consts::SQRT_2,
                        w[k].im * std::f64::consts::SQRT_2,
                    );
                    if re.abs() > 1e-15 {
                        u.push((dof, re));
                    }
                    if im.abs() > 1e-15 {
                        v.push((dof, im));
                    }
                }
            }
            u.sort_unstable_by_key(|&(d, _)| d);
            v.sort_unstable_by_key(|&(d, _)| d);
            (u, v)
        })
        .collect();
    let (u, v): (Vec<_>, Vec<_>) = columns.into_iter().unzip();
    let complex = ComplexSeeds {
        frame: frame.clone(),
        coef: chi.iter().map(|c| c.conj() / order).collect(),
        rep: seeds.iter().map(|&(i, _)| i as u32).collect(),
        seeds: seeds.iter().map(|&(_, s)| s).collect(),
        by_orbit,
    };
    SparseBasis::with_complex_seeds(layout.unknowns(), u.into_iter().chain(v).collect(), complex)
}

/// The Hermitian m × m block H = A + i C of the real 2m × 2m block R = [[A, C], [−C, A]] in
/// the basis [u, v] (module docs), each of A and C averaged over its two copies in R.
pub fn hermitian(r: &DMatrix<f64>) -> DMatrix<C64> {
    let m = r.nrows() / 2;
    DMatrix::from_fn(m, m, |f, e| {
        let a = 0.25 * (r[(f, e)] + r[(e, f)] + r[(m + f, m + e)] + r[(m + e, m + f)]);
        let c = 0.25 * (r[(f, m + e)] - r[(e, m + f)] - r[(m + f, e)] + r[(m + e, f)]);
        C64::new(a, c)
    })
}

/// Real coordinates x = [p; q] in [u, v] (the field Σ p_e u_e + q_e v_e) as the complex
/// coordinates z = p − i q (module docs).
pub fn to_complex(x: &[f64]) -> Vec<C64> {
    let m = x.len() / 2;
    (0..m).map(|e| C64::new(x[e], -x[m + e])).collect()
}

/// Complex coordinates z back to the real coordinates [Re z; −Im z] in [u, v].
pub fn to_real(z: &[C64]) -> Vec<f64> {
    z.iter()
        .map(|c| c.re)
        .chain(z.iter().map(|c| -c.im))
        .collect()
}
