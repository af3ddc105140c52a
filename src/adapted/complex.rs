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

use super::SparseBasis;
use crate::model::Layout;
use meshes::GroupAction;
use nalgebra::{Complex, DMatrix, Matrix3, SymmetricEigen, Vector3};
use rayon::prelude::*;

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

/// The real columns [u_1 … u_m, v_1 … v_m] of the isotypic component of the complex-type
/// irrep with character `chi` on the free `orbits` (module docs).
pub(super) fn complex_basis(
    action: &GroupAction,
    layout: &Layout,
    orbits: &[Vec<usize>],
    chi: &[C64],
) -> SparseBasis {
    let group = action.group();
    let order = group.order() as f64;
    let mut seeds: Vec<(usize, Vector3<C64>)> = Vec::new();
    for orbit in orbits {
        let i0 = orbit[0];
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
    SparseBasis::from_columns(layout.unknowns(), u.into_iter().chain(v).collect())
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
