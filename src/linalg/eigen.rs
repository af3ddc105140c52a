//! The eigenvalues of a sparse symmetric matrix A nearest a shift σ, by shift-invert Lanczos.
//!
//! # The method
//! The eigenpairs (λ, x) of A and those of the inverse of the shifted matrix are the same
//! vectors with
//!
//! ```text
//!     (A − σI)⁻¹ x = θ x,   θ = 1 / (λ − σ),   λ = σ + 1/θ,
//! ```
//!
//! so the eigenvalues of A nearest σ are the θ of largest |θ|, the ones a Krylov method finds
//! first. One sparse `LBLᵀ` factorisation of A − σI ([`SymmetricFactorization`]) gives the
//! operator: each Lanczos step is one solve.
//!
//! [`nearest_eigenvalues`] runs Lanczos on (A − σI)⁻¹ with **full reorthogonalisation**: with
//! V_m = [v_1 … v_m] orthonormal and T_m tridiagonal (diagonal α_j, off-diagonal β_j),
//!
//! ```text
//!     (A − σI)⁻¹ V_m = V_m T_m + β_m v_{m+1} e_mᵀ,
//! ```
//!
//! every new vector is orthogonalised against all earlier ones (classical Gram–Schmidt,
//! twice), so no spurious copies of converged Ritz values appear. The Ritz values θ_i of T_m
//! (eigenvector s_i) approximate eigenvalues of (A − σI)⁻¹ with residual
//! ‖(A − σI)⁻¹ V_m s_i − θ_i V_m s_i‖ = |β_m s_mi|; an eigenvalue is accepted when that is at
//! most 1e-8 max|θ|, which makes the error of θ_i of the order of its square over the gap.
//!
//! **Restarts on breakdown.** When β_j ≈ 0 (below 1e-12 max|α|) the Krylov space is an
//! invariant subspace. With a symmetric A this is common: a single start vector reaches one
//! direction per *distinct* eigenvalue (e.g. only 130 of the 486 of a frequency-4 icosphere
//! balloon's tangent), so repeated eigenvalues would be found once. The iteration then goes
//! on from a fresh pseudo-random direction orthogonal to V_j (β_j = 0 is kept in T, whose
//! relation above still holds), so it never stalls and finds further copies of degenerate
//! eigenvalues. The space grows from max(3n, 60) by max(n, 30) vectors at a time until the
//! n Ritz values of largest |θ| have converged or the space is the whole space.
//!
//! **The shift.** The tolerance is relative to the largest |θ|, so σ must be a distance from
//! the spectrum comparable to the gaps of the wanted eigenvalues: with σ an eigenvalue of A
//! to round-off, that one θ is huge and the other Ritz values pass the test unconverged.
//! A σ that is an eigenvalue exactly fails the factorisation ([`EigenError::Factor`]).
//!
//! [`nearest_eigenvalues_faer`] is faer's `partial_self_adjoint_eigen` (thick-restart
//! Lanczos) on the same operator, kept for comparison: it can loop forever in its
//! reorthogonalisation once the Krylov space is exhausted, so it is only for matrices whose
//! wanted eigenvalues are simple.
//!
//! Nothing here knows of a model: the matrix is a [`SymmetricPattern`] with its values, or a
//! factorisation of A − σI made by the caller.

use super::{FactorError, SymmetricFactorization, SymmetricPattern};

/// A Ritz value has converged when its residual |β_m s_mi| is at most this times max|θ|.
const RESIDUAL_TOLERANCE: f64 = 1e-8;
/// β_j below this times max|α| is a breakdown of the Lanczos recurrence.
const BREAKDOWN_TOLERANCE: f64 = 1e-12;
/// The state of the pseudo-random directions (xorshift), fixed: results are reproducible.
const SEED: u64 = 0x2545_F491_4F6C_DD1D;

/// Why the eigenvalues could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EigenError {
    /// The values do not match the pattern.
    #[error("{values} values for a pattern of {nnz} entries")]
    Length {
        /// Values given.
        values: usize,
        /// Entries of the pattern.
        nnz: usize,
    },
    /// The symbolic analysis or the numeric factorisation of A − σI failed (σ is an
    /// eigenvalue of A to round-off, or the factorisation broke down).
    #[error("factorising A − σI: {0}")]
    Factor(FactorError),
    /// A solve with the factorisation failed (it was not factorised, or its last
    /// factorisation failed).
    #[error("solving with A − σI: {0}")]
    Solve(FactorError),
    /// faer's iteration needs more unknowns than its Krylov space
    /// ([`nearest_eigenvalues_faer`]).
    #[error("{dim} unknowns: faer's Lanczos needs more than its Krylov space of {krylov}")]
    TooSmall {
        /// Unknowns of A.
        dim: usize,
        /// The largest Krylov space, max(4n, 64).
        krylov: usize,
    },
    /// No start vector could be drawn.
    #[error("empty start vector")]
    StartVector,
    /// The dense eigenproblem of the Lanczos tridiagonal matrix failed.
    #[error("Lanczos tridiagonal eigen: {0}")]
    Tridiagonal(String),
}

/// The eigenvalues of A nearest the shift.
#[derive(Debug, Clone, PartialEq)]
pub struct Nearest {
    /// At most the number asked for, ascending.
    pub values: Vec<f64>,
    /// How many of them converged (all of them unless the space was exhausted first).
    pub converged: usize,
}

/// The values of A − `shift`·I on `pattern` (A's values in `values`, aligned with the
/// pattern's row indices; every diagonal entry is in a [`SymmetricPattern`]).
pub fn shifted_values(
    pattern: &SymmetricPattern,
    values: &[f64],
    shift: f64,
) -> Result<Vec<f64>, EigenError> {
    if values.len() != pattern.nnz() {
        return Err(EigenError::Length {
            values: values.len(),
            nnz: pattern.nnz(),
        });
    }
    let mut shifted = values.to_vec();
    for i in 0..pattern.n() {
        let p = pattern.position(i, i).expect("diagonal in pattern");
        shifted[p] -= shift;
    }
    Ok(shifted)
}

/// The (at most) `n` eigenvalues of A nearest `shift`, ascending: A − σI factorised
/// (symbolic analysis and numeric `LBLᵀ`), then [`nearest_eigenvalues`].
pub fn shift_invert(
    pattern: &SymmetricPattern,
    values: &[f64],
    shift: f64,
    n: usize,
) -> Result<Nearest, EigenError> {
    let shifted = shifted_values(pattern, values, shift)?;
    let mut f = SymmetricFactorization::new(pattern).map_err(EigenError::Factor)?;
    f.factorize(&shifted).map_err(EigenError::Factor)?;
    nearest_eigenvalues(&f, shift, n)
}

/// The `n` values of `values` nearest `shift`, ascending: the reference selection to compare
/// a shift-invert result with (e.g. every eigenvalue of a dense solve, or of blocks, each as
/// often as its multiplicity).
pub fn nearest(values: impl IntoIterator<Item = f64>, shift: f64, n: usize) -> Vec<f64> {
    let mut v: Vec<f64> = values.into_iter().collect();
    v.sort_by(|a, b| (a - shift).abs().total_cmp(&(b - shift).abs()));
    v.truncate(n);
    v.sort_by(f64::total_cmp);
    v
}

/// The (at most) `n` eigenvalues of A nearest `shift`, ascending, from a factorisation `f` of
/// A − shift·I: Lanczos on (A − shift·I)⁻¹ with full reorthogonalisation, restarted from a
/// fresh direction on breakdown (see the [module documentation](self)). Returns the values and
/// how many of them converged; fewer than asked converge only when the Krylov space is the
/// whole space (then every value is exact to round-off anyway) or no direction is left.
pub fn nearest_eigenvalues(
    f: &SymmetricFactorization,
    shift: f64,
    n: usize,
) -> Result<Nearest, EigenError> {
    let dim = f.n();
    let k = n.min(dim);
    if k == 0 {
        return Ok(Nearest {
            values: Vec::new(),
            converged: 0,
        });
    }
    let mut rng = SEED;
    let mut target = (3 * k).max(60).min(dim);
    // Columns 0..=m: the Lanczos vectors and the next one.
    let mut v = faer::Mat::<f64>::zeros(dim, target + 1);
    let start = fresh_direction(v.as_ref(), 0, &mut rng).ok_or(EigenError::StartVector)?;
    v.col_mut(0).copy_from(&start);
    let (mut alpha, mut beta): (Vec<f64>, Vec<f64>) = (Vec::new(), Vec::new());
    let mut exhausted = false;
    let mut largest = 0.0f64;
    let mut w = vec![0.0; dim];
    loop {
        if v.ncols() < target + 1 {
            v.resize_with(dim, target + 1, |_, _| 0.0);
        }
        while alpha.len() < target && !exhausted {
            let j = alpha.len();
            for (wi, vi) in w.iter_mut().zip(v.col(j).iter()) {
                *wi = *vi;
            }
            f.solve_in_place(&mut w).map_err(EigenError::Solve)?;
            let mut wc = faer::ColMut::from_slice_mut(&mut w);
            let a = v.col(j).transpose() * wc.as_ref();
            alpha.push(a);
            largest = largest.max(a.abs());
            orthogonalise(v.as_ref(), j + 1, wc.as_mut());
            let b = wc.norm_l2();
            if b > BREAKDOWN_TOLERANCE * largest {
                wc /= faer::Scale(b);
                beta.push(b);
                v.col_mut(j + 1).copy_from(wc.as_ref());
            } else {
                beta.push(0.0);
                match fresh_direction(v.as_ref(), j + 1, &mut rng) {
                    Some(r) => v.col_mut(j + 1).copy_from(&r),
                    None => exhausted = true,
                }
            }
        }
        let m = alpha.len();
        let t = faer::Mat::<f64>::from_fn(m, m, |i, j| {
            if i == j {
                alpha[i]
            } else if i == j + 1 || j == i + 1 {
                beta[i.min(j)]
            } else {
                0.0
            }
        });
        let eig = t
            .self_adjoint_eigen(faer::Side::Lower)
            .map_err(|e| EigenError::Tridiagonal(format!("{e:?}")))?;
        let (theta, s) = (eig.S(), eig.U());
        let trailing = beta[m - 1];
        let mut order: Vec<usize> = (0..m).collect();
        order.sort_by(|&x, &y| theta[y].abs().total_cmp(&theta[x].abs()));
        order.truncate(k);
        let top = order.first().map_or(0.0, |&i| theta[i].abs());
        let converged = order
            .iter()
            .filter(|&&i| (trailing * s[(m - 1, i)]).abs() <= RESIDUAL_TOLERANCE * top)
            .count();
        if converged == order.len() || exhausted || m >= dim {
            let mut values: Vec<f64> = order.iter().map(|&i| shift + 1.0 / theta[i]).collect();
            values.sort_by(f64::total_cmp);
            return Ok(Nearest { values, converged });
        }
        target = (target + k.max(30)).min(dim);
    }
}

/// As [`nearest_eigenvalues`], by faer's `partial_self_adjoint_eigen` (thick-restart Lanczos)
/// on (A − shift·I)⁻¹, with a Krylov space of 2n to 4n vectors (at least 32 to 64), tolerance
/// 1e-12 and up to 1000 restarts; only the values faer reports converged are returned. A
/// must have more unknowns than that space ([`EigenError::TooSmall`] otherwise: faer would
/// panic).
///
/// faer's iteration can loop forever in its reorthogonalisation when the Krylov space is
/// exhausted (a single start vector of a symmetric A with repeated eigenvalues): use
/// [`nearest_eigenvalues`] unless the matrix is known to be free of that.
pub fn nearest_eigenvalues_faer(
    f: &SymmetricFactorization,
    shift: f64,
    n: usize,
) -> Result<Nearest, EigenError> {
    let dim = f.n();
    let n = n.min(dim);
    if n == 0 {
        return Ok(Nearest {
            values: Vec::new(),
            converged: 0,
        });
    }
    let krylov = (4 * n).max(64);
    if dim <= krylov {
        return Err(EigenError::TooSmall { dim, krylov });
    }
    // The operator cannot report a failed solve to faer: check once that solves work (a
    // factorisation either solves every right-hand side or none).
    f.solve_in_place(&mut vec![0.0; dim])
        .map_err(EigenError::Solve)?;
    let op = InverseOp(f);
    let params = faer::matrix_free::eigen::PartialEigenParams {
        min_dim: (2 * n).max(32).min(dim),
        max_dim: (4 * n).max(64).min(dim),
        max_restarts: 1000,
        ..Default::default()
    };
    let par = faer::Par::Seq;
    let mut vecs = faer::Mat::<f64>::zeros(dim, n);
    let mut vals = vec![0.0; n];
    let v0 = faer::Col::<f64>::from_fn(dim, |i| 1.0 + ((i * 7919) % 101) as f64 / 101.0);
    let mut mem = faer::dyn_stack::MemBuffer::new(
        faer::matrix_free::eigen::partial_self_adjoint_eigen_scratch(&op, n, par, params),
    );
    let info = faer::matrix_free::eigen::partial_self_adjoint_eigen(
        vecs.as_mut(),
        &mut vals,
        &op,
        v0.as_ref(),
        1e-12,
        par,
        faer::dyn_stack::MemStack::new(&mut mem),
        params,
    );
    let mut values: Vec<f64> = vals
        .iter()
        .take(info.n_converged_eigen)
        .map(|&theta| shift + 1.0 / theta)
        .collect();
    values.sort_by(f64::total_cmp);
    Ok(Nearest {
        values,
        converged: info.n_converged_eigen,
    })
}

/// The operator (A − σI)⁻¹ by a sparse `LBLᵀ` factorisation (whose solves are known to work).
#[derive(Debug)]
struct InverseOp<'a>(&'a SymmetricFactorization);

impl faer::matrix_free::LinOp<f64> for InverseOp<'_> {
    fn apply_scratch(&self, _rhs_ncols: usize, _par: faer::Par) -> faer::dyn_stack::StackReq {
        faer::dyn_stack::StackReq::EMPTY
    }
    fn nrows(&self) -> usize {
        self.0.n()
    }
    fn ncols(&self) -> usize {
        self.0.n()
    }
    fn apply(
        &self,
        mut out: faer::MatMut<'_, f64>,
        rhs: faer::MatRef<'_, f64>,
        _par: faer::Par,
        _stack: &mut faer::dyn_stack::MemStack,
    ) {
        out.copy_from(rhs);
        self.0
            .solve_mat_in_place(out)
            .expect("the shifted matrix was factorised");
    }
    fn conj_apply(
        &self,
        out: faer::MatMut<'_, f64>,
        rhs: faer::MatRef<'_, f64>,
        par: faer::Par,
        stack: &mut faer::dyn_stack::MemStack,
    ) {
        self.apply(out, rhs, par, stack);
    }
}

/// `w` minus its projections on the first `j` (orthonormal) columns of `v`, twice (classical
/// Gram–Schmidt with reorthogonalisation, as two matrix–vector products each).
fn orthogonalise(v: faer::MatRef<'_, f64>, j: usize, mut w: faer::ColMut<'_, f64>) {
    use faer::linalg::matmul::matmul;
    if j == 0 {
        return;
    }
    let vj = v.subcols(0, j);
    let mut c = faer::Col::<f64>::zeros(j);
    for _ in 0..2 {
        matmul(
            c.as_mut(),
            faer::Accum::Replace,
            vj.transpose(),
            w.as_ref(),
            1.0,
            faer::Par::Seq,
        );
        matmul(
            w.as_mut(),
            faer::Accum::Add,
            vj,
            c.as_ref(),
            -1.0,
            faer::Par::Seq,
        );
    }
}

/// A pseudo-random unit vector orthogonal to the first `j` columns of `v` (xorshift state
/// `rng`), or `None` when they span the space.
fn fresh_direction(v: faer::MatRef<'_, f64>, j: usize, rng: &mut u64) -> Option<faer::Col<f64>> {
    let mut r = faer::Col::<f64>::from_fn(v.nrows(), |_| {
        *rng ^= *rng << 13;
        *rng ^= *rng >> 7;
        *rng ^= *rng << 17;
        (*rng >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    });
    let before = r.norm_l2();
    orthogonalise(v, j, r.as_mut());
    let norm = r.norm_l2();
    if norm.is_nan() || norm <= 1e-8 * before {
        return None;
    }
    r /= faer::Scale(norm);
    Some(r)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sparse symmetric matrix: its pattern and values, from a function of (i, j) on the
    /// entries (i, j) of `entries` (both triangles and the diagonal added).
    fn matrix(
        n: usize,
        entries: &[(usize, usize)],
        value: impl Fn(usize, usize) -> f64,
    ) -> (SymmetricPattern, Vec<f64>) {
        let pattern = SymmetricPattern::from_entries(n, entries.iter().copied());
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let mut values = vec![0.0; pattern.nnz()];
        for j in 0..n {
            for p in col_ptr[j]..col_ptr[j + 1] {
                let i = row_idx[p];
                values[p] = value(i.min(j), i.max(j));
            }
        }
        (pattern, values)
    }

    /// An indefinite sparse matrix of `n` unknowns: a tridiagonal band with a diagonal
    /// running from negative to positive, and a long-range coupling (i, i + 7).
    fn indefinite(n: usize) -> (SymmetricPattern, Vec<f64>) {
        let mut entries = Vec::new();
        for i in 0..n {
            if i + 1 < n {
                entries.push((i + 1, i));
            }
            if i + 7 < n {
                entries.push((i + 7, i));
            }
        }
        matrix(n, &entries, |i, j| {
            if i == j {
                0.37 * (i as f64 - 0.4 * n as f64) + 0.01 * ((i * 31) % 7) as f64
            } else if j == i + 1 {
                1.0
            } else {
                0.3
            }
        })
    }

    fn dense_eigenvalues(pattern: &SymmetricPattern, values: &[f64]) -> Vec<f64> {
        let mut v = pattern
            .to_dense(values)
            .self_adjoint_eigenvalues(faer::Side::Lower)
            .unwrap();
        v.sort_by(f64::total_cmp);
        v
    }

    fn assert_close(found: &[f64], expected: &[f64], scale: f64, tol: f64) {
        assert_eq!(found.len(), expected.len(), "{found:?} vs {expected:?}");
        for (a, b) in found.iter().zip(expected) {
            assert!(
                (a - b).abs() <= tol * scale,
                "{a} vs {b} ({found:?} vs {expected:?})"
            );
        }
    }

    /// The eigenvalues nearest a shift inside an indefinite spectrum are the dense ones, for
    /// a Krylov space smaller than the matrix (the convergence test decides) and for one
    /// that is the whole space.
    #[test]
    fn nearest_eigenvalues_are_the_dense_ones() {
        for (dim, shift, count) in [(40, 0.1, 6), (200, 0.05, 5), (200, -3.17, 12)] {
            let (pattern, values) = indefinite(dim);
            let dense = dense_eigenvalues(&pattern, &values);
            assert!(dense[0] < 0.0 && dense[dim - 1] > 0.0, "indefinite");
            let scale = dense.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let expected = nearest(dense.iter().copied(), shift, count);
            let found = shift_invert(&pattern, &values, shift, count).unwrap();
            assert_eq!(found.converged, count, "n = {dim}, σ = {shift}");
            assert_close(&found.values, &expected, scale, 1e-10);
            // faer's thick-restart Lanczos agrees on this matrix (simple eigenvalues), when it
            // is larger than faer's Krylov space.
            if dim <= 64 {
                continue;
            }
            let shifted = shifted_values(&pattern, &values, shift).unwrap();
            let mut f = SymmetricFactorization::new(&pattern).unwrap();
            f.factorize(&shifted).unwrap();
            let faer = nearest_eigenvalues_faer(&f, shift, count).unwrap();
            assert_eq!(faer.converged, count);
            assert_close(&faer.values, &expected, scale, 1e-10);
        }
    }

    /// Three uncoupled copies of one block: every eigenvalue is triple, which a single
    /// start vector cannot reach; the restarts on breakdown find every copy.
    #[test]
    fn repeated_eigenvalues_are_found_with_their_multiplicity() {
        let (block, copies) = (5, 3);
        let n = block * copies;
        let mut entries = Vec::new();
        for c in 0..copies {
            for i in 0..block {
                for j in 0..i {
                    entries.push((c * block + i, c * block + j));
                }
            }
        }
        let (pattern, values) = matrix(n, &entries, |i, j| {
            let (a, b) = (i % block, j % block);
            if a == b {
                a as f64 - 2.2
            } else {
                0.5 / (1.0 + a.abs_diff(b) as f64)
            }
        });
        let dense = dense_eigenvalues(&pattern, &values);
        let shift = 0.05;
        let expected = nearest(dense.iter().copied(), shift, 6);
        // Two distinct values, three copies each.
        assert!((expected[0] - expected[2]).abs() < 1e-12);
        assert!((expected[3] - expected[5]).abs() < 1e-12);
        let found = shift_invert(&pattern, &values, shift, 6).unwrap();
        assert_close(&found.values, &expected, 3.0, 1e-10);
    }

    #[test]
    fn counts_are_capped_by_the_dimension() {
        let (pattern, values) = indefinite(8);
        let dense = dense_eigenvalues(&pattern, &values);
        let found = shift_invert(&pattern, &values, 0.1, 20).unwrap();
        assert_close(&found.values, &dense, 10.0, 1e-10);
        let none = shift_invert(&pattern, &values, 0.1, 0).unwrap();
        assert!(none.values.is_empty() && none.converged == 0);
    }

    #[test]
    fn errors_name_the_cause() {
        let (pattern, values) = indefinite(10);
        assert_eq!(
            shift_invert(&pattern, &values[1..], 0.0, 3),
            Err(EigenError::Length {
                values: values.len() - 1,
                nnz: pattern.nnz()
            })
        );
        // A shift at an eigenvalue: A − σI is singular.
        let diagonal = matrix(4, &[], |i, _| i as f64).1;
        let diagonal_pattern = SymmetricPattern::from_entries(4, []);
        assert!(matches!(
            shift_invert(&diagonal_pattern, &diagonal, 2.0, 2),
            Err(EigenError::Factor(_))
        ));
        // A factorisation that was never made cannot be solved with.
        let f = SymmetricFactorization::new(&pattern).unwrap();
        assert!(matches!(
            nearest_eigenvalues(&f, 0.0, 3),
            Err(EigenError::Solve(FactorError::NotFactorized))
        ));
        let large = indefinite(100).0;
        let f = SymmetricFactorization::new(&large).unwrap();
        assert!(matches!(
            nearest_eigenvalues_faer(&f, 0.0, 3),
            Err(EigenError::Solve(FactorError::NotFactorized))
        ));
        // faer's Lanczos on a matrix no larger than its Krylov space.
        let mut f = SymmetricFactorization::new(&pattern).unwrap();
        f.factorize(&shifted_values(&pattern, &values, 0.1).unwrap())
            .unwrap();
        assert_eq!(
            nearest_eigenvalues_faer(&f, 0.1, 3),
            Err(EigenError::TooSmall {
                dim: 10,
                krylov: 64
            })
        );
    }

    #[test]
    fn nearest_selects_by_distance_and_sorts() {
        assert_eq!(
            nearest([5.0, -1.0, 0.2, 3.0, -0.1], 0.0, 3),
            vec![-1.0, -0.1, 0.2]
        );
        assert_eq!(nearest([1.0, 2.0], 0.0, 5), vec![1.0, 2.0]);
    }
}
