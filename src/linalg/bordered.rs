//! Solves of bordered and general systems for the path follower and the extended systems
//! built on it: [[A, B], [C, D]] with A sparse symmetric and a border of a few dense rows
//! and columns ([`bordered_solve`]: a zero pivot of A shifted and the shift bordered; falling
//! back to [`sparse_lu_solve`]), and dense LU ([`solve_dense`]).

use super::{SymmetricFactorization, SymmetricPattern};
use faer::sparse::{SparseColMat, Triplet};
use nalgebra::{DMatrix, DVector};
use std::sync::{Arc, Mutex};

/// A sparse LBLᵀ kept between the solves of one problem (its symbolic analysis done once).
pub type SharedFactorization = Arc<Mutex<Option<SymmetricFactorization>>>;

/// [[A, B], [C, D]] [x; z] = [r1; r2] by block elimination on a sparse LBLᵀ of A (symbolic
/// analysis kept in `solver`): A X = B, S = D − C X, S z = r2 − C A⁻¹ r1, x = A⁻¹(r1 − B z),
/// then one step of iterative refinement on the whole system. A singular to round-off (close
/// to a limit point, or along a held rigid motion, which the border makes regular) has its
/// zero pivots shifted and the shift bordered (docs/theory.md §7.7). `None` if that fails.
pub fn bordered_solve(
    pattern: &Arc<SymmetricPattern>,
    values: &[f64],
    b: &DMatrix<f64>,
    c: &DMatrix<f64>,
    d: &DMatrix<f64>,
    solver: &SharedFactorization,
    rhs: &DVector<f64>,
) -> Option<DVector<f64>> {
    bordered_solve_all(pattern, values, b, c, d, solver, &[rhs])?.pop()
}

/// As [`bordered_solve`] for several right-hand sides from one factorisation of A (each
/// solution refined and, on a near-singular A, checked on its own); `None` if any of them
/// fails.
pub fn bordered_solve_all(
    pattern: &Arc<SymmetricPattern>,
    values: &[f64],
    b: &DMatrix<f64>,
    c: &DMatrix<f64>,
    d: &DMatrix<f64>,
    solver: &SharedFactorization,
    all: &[&DVector<f64>],
) -> Option<Vec<DVector<f64>>> {
    let m = pattern.n();
    let nb = d.nrows();
    let mut guard = solver.lock().ok()?;
    if guard.as_ref().is_none_or(|f| f.n() != m) {
        *guard = Some(SymmetricFactorization::new(pattern).ok()?);
    }
    let fact = guard.as_mut()?;
    // A singular to round-off — a limit point, where the border makes the system regular, or
    // a rigid motion the border holds: each zero pivot's unknown e_k has its diagonal shifted
    // by s = max|A|, A' = A + s E Eᵀ, and the shift is undone exactly by k more border rows
    // and columns, [[A', B, −E], [C, D, 0], [s Eᵀ, 0, −I]] [x; z; t] = [r1; r2; 0] (t = s Eᵀ x),
    // so that block elimination runs on a regular A'. Only when that fails is `None` returned
    // (the caller's sparse LU).
    let scale = values.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let mut shifted: Vec<usize> = Vec::new();
    let mut own: Option<Vec<f64>> = None;
    loop {
        let now = own.as_deref().unwrap_or(values);
        match fact.factorize(now) {
            Ok(()) => break,
            Err(super::FactorError::Singular { index, .. })
                if shifted.len() < MAX_SHIFTED_PIVOTS && !shifted.contains(&index) =>
            {
                let mut v = own.take().unwrap_or_else(|| values.to_vec());
                v[pattern.position(index, index)?] += scale;
                own = Some(v);
                shifted.push(index);
            }
            Err(_) => return None,
        }
    }
    let k = shifted.len();
    if k == 0 {
        return batched((pattern, values, b, c, d), fact, all, None);
    }
    let (b, c, d) = {
        let (mut b2, mut c2) = (DMatrix::zeros(m, nb + k), DMatrix::zeros(nb + k, m));
        b2.view_mut((0, 0), (m, nb)).copy_from(b);
        c2.view_mut((0, 0), (nb, m)).copy_from(c);
        let mut d2 = DMatrix::zeros(nb + k, nb + k);
        d2.view_mut((0, 0), (nb, nb)).copy_from(d);
        for (j, &i) in shifted.iter().enumerate() {
            b2[(i, nb + j)] = -1.0;
            c2[(nb + j, i)] = scale;
            d2[(nb + j, nb + j)] = -1.0;
        }
        (b2, c2, d2)
    };
    let values = own.as_deref().unwrap_or(values);
    let nk = nb + k;
    // X = A⁻¹ B.
    let mut x_b = b.clone();
    fact.solve_many_in_place(x_b.as_mut_slice()).ok()?;
    let schur = &d - &c * &x_b;
    // With shifted pivots J is singular exactly when the Schur complement is (det J = det A′
    // det S): a system the border leaves singular is refused here, not solved into a huge
    // step.
    if !regular(&schur) {
        return None;
    }
    let lu = schur.lu();
    let solve = |r: &DVector<f64>| -> Option<DVector<f64>> {
        let mut y = r.rows(0, m).into_owned();
        fact.solve_in_place(y.as_mut_slice()).ok()?;
        let z = lu.solve(&(r.rows(m, nk) - &c * &y))?;
        let x = y - &x_b * &z;
        let mut out = DVector::zeros(m + nk);
        out.rows_mut(0, m).copy_from(&x);
        out.rows_mut(m, nk).copy_from(&z);
        Some(out)
    };
    let norm = max_entry((pattern, values, &b, &c, &d));
    all.iter()
        .map(|rhs| {
            let mut padded = DVector::zeros(m + nk);
            padded.rows_mut(0, m + nb).copy_from(rhs);
            let sol = refined((pattern, values, &b, &c, &d), &solve, &padded, true, norm)?;
            Some(sol.rows(0, m + nb).into_owned())
        })
        .collect()
}

/// As [`bordered_solve_all`], but with the factorisation of A that `solver` already holds
/// from the last [`bordered_solve_all`] of this problem, without factorising again: the
/// system given (`pattern`, `values`, B, C, D) is that of the held factorisation (a chord
/// step of Newton's method) or one close to it (the next iterate's), and the held factors
/// serve as its preconditioner. The solutions are refined against the system given until
/// their normwise backward error on it is at most [`NEAR_SINGULAR_BACKWARD_ERROR`], in at most
/// [`MAX_CHORD_REFINEMENTS`] steps, each by one batched solve: the held factors of the same
/// matrix need one step, those of a close one a few (the error falls by ‖A_held⁻¹ (A − A_held)‖
/// per step), those of another one (or of A with shifted pivots) fail. `None` if that fails or
/// nothing is held.
pub fn bordered_resolve_all(
    pattern: &Arc<SymmetricPattern>,
    values: &[f64],
    b: &DMatrix<f64>,
    c: &DMatrix<f64>,
    d: &DMatrix<f64>,
    solver: &SharedFactorization,
    all: &[&DVector<f64>],
) -> Option<Vec<DVector<f64>>> {
    let m = pattern.n();
    let guard = solver.lock().ok()?;
    let fact = guard.as_ref().filter(|f| f.n() == m)?;
    batched(
        (&**pattern, values, b, c, d),
        fact,
        all,
        Some(NEAR_SINGULAR_BACKWARD_ERROR),
    )
}

/// The most refinement steps [`bordered_resolve_all`] takes towards its backward error.
pub const MAX_CHORD_REFINEMENTS: usize = 4;

type System<'a> = (
    &'a SymmetricPattern,
    &'a [f64],
    &'a DMatrix<f64>,
    &'a DMatrix<f64>,
    &'a DMatrix<f64>,
);

/// The block elimination of [`bordered_solve_all`] on a regular A (no shifted pivot) for
/// every right-hand side at once, refined once: A⁻¹ [B, r₁, …, r_k] (the top rows of each
/// right-hand side) in one multi-column solve, the Schur complement and each solution from
/// it, then the residuals of the whole system and their corrections, again in one solve.
/// The same arithmetic as solving each right-hand side on its own, but the factor is read
/// twice in all instead of once per column and solve: the solves were a tenth of a path
/// step on the 7 803-unknown caps (BENCHMARKS.md §7.4).
///
/// With `until`, the refinement is repeated until every solution's normwise backward error
/// ‖r‖∞ / (max|M_ij| ‖x‖∞ + ‖rhs‖∞) is at most it, in at most [`MAX_CHORD_REFINEMENTS`] steps
/// (`None` if not reached).
fn batched(
    (pattern, values, b, c, d): System<'_>,
    fact: &SymmetricFactorization,
    all: &[&DVector<f64>],
    until: Option<f64>,
) -> Option<Vec<DVector<f64>>> {
    let (m, nb, k) = (pattern.n(), d.nrows(), all.len());
    let mut stack = vec![0.0; m * (nb + k)];
    stack[..m * nb].copy_from_slice(b.as_slice());
    for (j, r) in all.iter().enumerate() {
        stack[m * (nb + j)..m * (nb + j + 1)].copy_from_slice(&r.as_slice()[..m]);
    }
    fact.solve_many_in_place(&mut stack).ok()?;
    let x_b = DMatrix::from_column_slice(m, nb, &stack[..m * nb]);
    let lu = (d - c * &x_b).lu();
    // The solutions [x; z] from A⁻¹ of their top rows (`tops`, column-major) and the
    // right-hand sides' bottom rows.
    let finish = |tops: &[f64], rs: &[&DVector<f64>]| -> Option<Vec<DVector<f64>>> {
        rs.iter()
            .zip(tops.chunks_exact(m))
            .map(|(r, y)| {
                let y = DVector::from_column_slice(y);
                let z = lu.solve(&(r.rows(m, nb) - c * &y))?;
                let mut out = DVector::zeros(m + nb);
                out.rows_mut(0, m).copy_from(&(y - &x_b * &z));
                out.rows_mut(m, nb).copy_from(&z);
                Some(out)
            })
            .collect()
    };
    let mut sols = finish(&stack[m * nb..], all)?;
    let norm = until.map(|_| max_entry((pattern, values, b, c, d)));
    let mut steps = 0;
    loop {
        if until.is_none() && steps == 1 {
            return Some(sols);
        }
        // A refinement step: r = rhs − M sol for every solution, corrected together.
        let residuals: Vec<DVector<f64>> = all
            .iter()
            .zip(&sols)
            .map(|(rhs, sol)| residual((pattern, values, b, c, d), rhs, sol))
            .collect();
        if let (Some(target), Some(norm)) = (until, norm) {
            // NaN (a non-finite solution) is refused too.
            let worst = residuals
                .iter()
                .zip(all.iter().zip(&sols))
                .map(|(r, (rhs, sol))| backward_error(r, rhs, sol, norm))
                .fold(
                    0.0,
                    |w: f64, e| if e.is_nan() { f64::NAN } else { w.max(e) },
                );
            if worst <= target {
                return Some(sols);
            }
            if worst.is_nan() || steps == MAX_CHORD_REFINEMENTS {
                return None;
            }
        }
        let mut tops = vec![0.0; m * k];
        for (r, top) in residuals.iter().zip(tops.chunks_exact_mut(m)) {
            top.copy_from_slice(&r.as_slice()[..m]);
        }
        fact.solve_many_in_place(&mut tops).ok()?;
        let refs: Vec<&DVector<f64>> = residuals.iter().collect();
        for (sol, correction) in sols.iter_mut().zip(finish(&tops, &refs)?) {
            *sol += correction;
        }
        steps += 1;
    }
}

/// rhs − M sol of the bordered system M = [[A, B], [C, D]].
fn residual(
    (pattern, values, b, c, d): System<'_>,
    rhs: &DVector<f64>,
    sol: &DVector<f64>,
) -> DVector<f64> {
    let (m, nb) = (pattern.n(), d.nrows());
    let (xs, zs) = (sol.rows(0, m), sol.rows(m, nb));
    let mut ax = vec![0.0; m];
    pattern.matvec(values, xs.as_slice(), &mut ax);
    let (top, bottom) = (b * zs, c * xs + d * zs);
    let mut r = rhs.clone();
    for i in 0..m {
        r[i] = r[i] - ax[i] - top[i];
    }
    for i in 0..nb {
        r[m + i] -= bottom[i];
    }
    r
}

/// The normwise backward error ‖r‖∞ / (max|M_ij| ‖x‖∞ + ‖rhs‖∞) of a solution `sol` of
/// M x = `rhs` with residual `r` (`norm` = max|M_ij|).
fn backward_error(r: &DVector<f64>, rhs: &DVector<f64>, sol: &DVector<f64>, norm: f64) -> f64 {
    r.amax() / (norm * sol.amax() + rhs.amax()).max(1e-300)
}

/// max|M_ij| of the bordered system M = [[A, B], [C, D]].
fn max_entry((_, values, b, c, d): System<'_>) -> f64 {
    values
        .iter()
        .chain(b.iter())
        .chain(c.iter())
        .chain(d.iter())
        .fold(0.0f64, |a, v| a.max(v.abs()))
}

/// Whether the small dense `s` is regular to working precision: its singular values' ratio
/// above [`SINGULAR_SCHUR`].
fn regular(s: &DMatrix<f64>) -> bool {
    let sv = s.singular_values();
    let (lo, hi) = sv.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
        (lo.min(*v), hi.max(*v))
    });
    hi > 0.0 && lo.is_finite() && lo > SINGULAR_SCHUR * hi
}

/// The smallest ratio of a Schur complement's singular values that [`bordered_solve_all`]
/// takes for regular after shifted pivots.
const SINGULAR_SCHUR: f64 = 1e-13;

/// The most zero pivots [`bordered_solve_all`] shifts and borders before it gives up.
const MAX_SHIFTED_PIVOTS: usize = 8;

/// The solution of [[A, B], [C, D]] x = rhs from `solve` (block elimination), refined once
/// (twice after zero pivots were shifted, where it is kept only at a normwise backward error
/// below [`NEAR_SINGULAR_BACKWARD_ERROR`]; `norm` = max|M_ij|).
fn refined(
    (pattern, values, b, c, d): System<'_>,
    solve: &dyn Fn(&DVector<f64>) -> Option<DVector<f64>>,
    rhs: &DVector<f64>,
    near_singular: bool,
    norm: f64,
) -> Option<DVector<f64>> {
    let residual_of = |sol: &DVector<f64>| residual((pattern, values, b, c, d), rhs, sol);
    let mut sol = solve(rhs)?;
    // One refinement step (two on a near-singular A).
    for _ in 0..1 + usize::from(near_singular) {
        sol += solve(&residual_of(&sol))?;
    }
    if near_singular {
        // The normwise backward error of the whole system, at round-off or refused.
        let error = backward_error(&residual_of(&sol), rhs, &sol, norm);
        // NaN (a non-finite solution) is refused too.
        if error.is_nan() || error > NEAR_SINGULAR_BACKWARD_ERROR {
            return None;
        }
    }
    Some(sol)
}

/// The largest normwise backward error ‖r‖∞ / (max|M_ij| ‖x‖∞ + ‖rhs‖∞) of a bordered solve
/// by block elimination after shifted pivots that [`bordered_solve`] keeps (a few hundred
/// times the unit round-off).
const NEAR_SINGULAR_BACKWARD_ERROR: f64 = 1e-13;

/// The same system by faer's sparse LU of the whole matrix (the fallback when block
/// elimination fails even with shifted pivots).
pub fn sparse_lu_solve(
    pattern: &SymmetricPattern,
    values: &[f64],
    b: &DMatrix<f64>,
    c: &DMatrix<f64>,
    d: &DMatrix<f64>,
    rhs: &DVector<f64>,
) -> Option<DVector<f64>> {
    let (m, nb) = (pattern.n(), d.nrows());
    let n = m + nb;
    let mut t = Vec::with_capacity(values.len() + 2 * nb * m + nb * nb);
    let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
    for j in 0..m {
        for p in col_ptr[j]..col_ptr[j + 1] {
            t.push(Triplet::new(row_idx[p], j, values[p]));
        }
    }
    for j in 0..nb {
        for i in 0..m {
            if b[(i, j)] != 0.0 {
                t.push(Triplet::new(i, m + j, b[(i, j)]));
            }
            if c[(j, i)] != 0.0 {
                t.push(Triplet::new(m + j, i, c[(j, i)]));
            }
        }
        for i in 0..nb {
            if d[(i, j)] != 0.0 {
                t.push(Triplet::new(m + i, m + j, d[(i, j)]));
            }
        }
    }
    let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &t).ok()?;
    let lu = a.sp_lu().ok()?;
    let rhs = faer::MatRef::from_column_major_slice(rhs.as_slice(), n, 1);
    let x = faer::linalg::solvers::Solve::solve(&lu, rhs);
    Some(DVector::from_fn(n, |i, _| x[(i, 0)]))
}

/// Above this size the extended system is solved by faer's blocked, multi-threaded LU
/// (the fixed-point space of an f = 128 icosphere has ≈ 4 200 unknowns: nalgebra's
/// unblocked LU takes seconds there); below it by nalgebra's, which is faster on tiny ones.
pub const BLOCKED_LU_FROM: usize = 256;

/// The minimally augmented test function of a square matrix K with a border b
/// (docs/theory.md §11.7): [[K, b], [bᵀ, 0]] [v; σ] = [0; 1], σ zero exactly where K is
/// singular (b not orthogonal to its kernel), v its null vector there. `None` where the
/// bordered matrix is singular.
pub fn test_function(k: &DMatrix<f64>, border: &DVector<f64>) -> Option<(f64, DVector<f64>)> {
    let m = k.nrows();
    let mut a = DMatrix::zeros(m + 1, m + 1);
    a.view_mut((0, 0), (m, m)).copy_from(k);
    a.view_mut((0, m), (m, 1)).copy_from(border);
    a.view_mut((m, 0), (1, m)).copy_from(&border.transpose());
    let mut rhs = DVector::zeros(m + 1);
    rhs[m] = 1.0;
    let x = solve_dense(a, &rhs).filter(|x| x.iter().all(|v| v.is_finite()))?;
    Some((x[m], x.rows(0, m).into_owned()))
}

/// A x = rhs by LU with partial pivoting; `None` for a singular A (a zero pivot, or a
/// non-finite solution).
pub fn solve_dense(a: DMatrix<f64>, rhs: &DVector<f64>) -> Option<DVector<f64>> {
    let n = a.nrows();
    if n < BLOCKED_LU_FROM {
        return a.lu().solve(rhs);
    }
    let lu = faer::MatRef::from_column_major_slice(a.as_slice(), n, n).partial_piv_lu();
    let b = faer::MatRef::from_column_major_slice(rhs.as_slice(), n, 1);
    let x = faer::linalg::solvers::Solve::solve(&lu, b);
    let x = DVector::from_fn(n, |i, _| x[(i, 0)]);
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod solve_tests {
    use super::{solve_dense, BLOCKED_LU_FROM};
    use nalgebra::{DMatrix, DVector};

    /// Both LU paths solve a well-conditioned system to round-off, and refuse a singular one.
    #[test]
    fn blocked_and_small_lu_agree_and_refuse_singular_matrices() {
        for n in [BLOCKED_LU_FROM - 1, BLOCKED_LU_FROM + 44] {
            let a = DMatrix::from_fn(n, n, |i, j| {
                ((i * 31 + j * 17) as f64 * 0.13).sin() + if i == j { n as f64 } else { 0.0 }
            });
            let x = DVector::from_fn(n, |i, _| (i as f64 * 0.7).cos());
            let b = &a * &x;
            let y = solve_dense(a.clone(), &b).expect("regular");
            assert!((y - &x).amax() < 1e-12, "n = {n}");
            let mut singular = a;
            singular.row_mut(3).fill(0.0);
            assert!(solve_dense(singular, &b).is_none(), "n = {n}");
        }
    }
}

#[cfg(test)]
mod bordered_tests {
    use super::{bordered_resolve_all, bordered_solve, sparse_lu_solve, SharedFactorization};
    use crate::linalg::SymmetricPattern;
    use nalgebra::{DMatrix, DVector};
    use std::sync::Arc;

    /// Block elimination on the sparse LBLᵀ, the sparse LU of the whole matrix and a dense
    /// LU agree on an indefinite tridiagonal A with a two-column border.
    #[test]
    fn bordered_and_sparse_lu_solves_agree_with_dense() {
        let m = 40;
        let pattern = Arc::new(SymmetricPattern::from_entries(
            m,
            (1..m).map(|i| (i, i - 1)),
        ));
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let entry = |i: usize, j: usize| {
            if i == j {
                2.0 + (i as f64 * 0.9).sin() - 1.0
            } else {
                -0.7
            }
        };
        let mut values = vec![0.0; pattern.nnz()];
        for j in 0..m {
            for p in col_ptr[j]..col_ptr[j + 1] {
                values[p] = entry(row_idx[p], j);
            }
        }
        let b = DMatrix::from_fn(m, 2, |i, j| ((i + 3 * j) as f64 * 0.37).cos());
        let c = DMatrix::from_fn(2, m, |i, j| ((2 * j + i) as f64 * 0.21).sin());
        let d = DMatrix::from_row_slice(2, 2, &[0.3, -0.1, 0.2, 0.0]);
        let rhs = DVector::from_fn(m + 2, |i, _| (i as f64 * 0.5).sin());
        let mut dense = DMatrix::zeros(m + 2, m + 2);
        for j in 0..m {
            for p in col_ptr[j]..col_ptr[j + 1] {
                dense[(row_idx[p], j)] = values[p];
            }
        }
        dense.view_mut((0, m), (m, 2)).copy_from(&b);
        dense.view_mut((m, 0), (2, m)).copy_from(&c);
        dense.view_mut((m, m), (2, 2)).copy_from(&d);
        let expected = dense.clone().lu().solve(&rhs).unwrap();
        let solver = SharedFactorization::default();
        let x = bordered_solve(&pattern, &values, &b, &c, &d, &solver, &rhs).unwrap();
        assert!((&x - &expected).amax() < 1e-10 * expected.amax());
        // The symbolic analysis is kept for the next solve.
        assert!(solver.lock().unwrap().is_some());
        let y = sparse_lu_solve(&pattern, &values, &b, &c, &d, &rhs).unwrap();
        assert!((&y - &expected).amax() < 1e-10 * expected.amax());
        // A chord solve from the kept factorisation: the same solution for another
        // right-hand side, without factorising.
        let rhs2 = DVector::from_fn(m + 2, |i, _| (i as f64 * 1.3).cos());
        let fresh = dense.clone().lu().solve(&rhs2).unwrap();
        let again = bordered_resolve_all(&pattern, &values, &b, &c, &d, &solver, &[&rhs2])
            .unwrap()
            .pop()
            .unwrap();
        assert!((&again - &fresh).amax() < 1e-12 * fresh.amax());
        // The factors of A, refined, solve a matrix one part in 10⁸ or in 10³ off A to
        // round-off (the error falls a thousandfold per step), and are refused, not returned,
        // for a matrix a tenth off (a tenfold fall per step is too slow).
        for (change, kept) in [(1e-8, true), (1e-3, true), (0.1, false)] {
            let changed: Vec<f64> = values.iter().map(|v| v * (1.0 + change)).collect();
            let again = bordered_resolve_all(&pattern, &changed, &b, &c, &d, &solver, &[&rhs2]);
            assert_eq!(again.is_some(), kept, "{change}");
            if let Some(mut x) = again {
                let mut other = dense.clone();
                other.view_mut((0, 0), (m, m)).scale_mut(1.0 + change);
                let fresh = other.lu().solve(&rhs2).unwrap();
                assert!((x.pop().unwrap() - &fresh).amax() < 1e-12 * fresh.amax());
            }
        }
        // Nothing factorised yet: nothing to solve with.
        let empty = SharedFactorization::default();
        assert!(bordered_resolve_all(&pattern, &values, &b, &c, &d, &empty, &[&rhs2]).is_none());
    }
}

#[cfg(test)]
mod near_singular_tests {
    use super::{bordered_solve, solve_dense, SharedFactorization};
    use crate::linalg::{FactorError, SymmetricFactorization, SymmetricPattern};
    use nalgebra::{DMatrix, DVector};
    use std::sync::Arc;

    /// A chain Laplacian with free ends is singular (the constant vector is its kernel); a
    /// perturbation of its first diagonal entry far below the zero-pivot threshold leaves
    /// it singular to round-off. Bordered by a column not orthogonal to the kernel, the
    /// system is regular: block elimination on the tiny pivot, refined, gives the dense
    /// solution, and is kept.
    #[test]
    fn a_border_that_makes_a_singular_matrix_regular_is_solved_by_elimination() {
        let n = 40;
        let entries = (0..n).map(|i| (i, i)).chain((1..n).map(|i| (i, i - 1)));
        let pattern = Arc::new(SymmetricPattern::from_entries(n, entries));
        let mut values = vec![0.0; pattern.nnz()];
        let mut dense = DMatrix::zeros(n + 1, n + 1);
        for i in 0..n {
            let d = if i == 0 || i == n - 1 { 1.0 } else { 2.0 } + if i == 0 { 3e-16 } else { 0.0 };
            values[pattern.position(i, i).unwrap()] = d;
            dense[(i, i)] = d;
            if i > 0 {
                values[pattern.position(i, i - 1).unwrap()] = -1.0;
                values[pattern.position(i - 1, i).unwrap()] = -1.0;
                dense[(i, i - 1)] = -1.0;
                dense[(i - 1, i)] = -1.0;
            }
        }
        let mut plain = SymmetricFactorization::new(&pattern).unwrap();
        assert!(matches!(
            plain.factorize(&values),
            Err(FactorError::Singular { .. })
        ));
        let b = DMatrix::from_fn(n, 1, |i, _| 1.0 + (i as f64 * 0.7).sin());
        let c = b.transpose();
        let d = DMatrix::zeros(1, 1);
        for i in 0..n {
            dense[(i, n)] = b[(i, 0)];
            dense[(n, i)] = b[(i, 0)];
        }
        let rhs = DVector::from_fn(n + 1, |i, _| (i as f64 * 1.3).cos());
        let solver = SharedFactorization::default();
        let x = bordered_solve(&pattern, &values, &b, &c, &d, &solver, &rhs)
            .expect("the bordered system is regular");
        let expected = solve_dense(dense, &rhs).unwrap();
        assert!(
            (&x - &expected).amax() <= 1e-10 * expected.amax(),
            "{:e}",
            (&x - &expected).amax()
        );
    }
}
