//! Sparse symmetric-indefinite factorisation `P A Pᵀ = L B Lᵀ` with inertia.
//!
//! # faer functions used, and why
//! - `amd::order` (or a custom order, see below): the fill-reducing ordering P, the one
//!   faer's own symbolic analysis with [`SymmetricOrdering::Amd`] would take.
//! - [`factorize_symbolic_cholesky`] of P A Pᵀ with [`SymmetricOrdering::Identity`] and a
//!   supernodal threshold of `-∞` (always supernodal when `n > 0`): the symbolic analysis
//!   (elimination tree, supernodes), done once per pattern. The supernodal layout is
//!   forced because faer's pivoted factorisation only pivots on that path (on the simplicial
//!   path `factorize_numeric_intranode_lblt` silently falls back to unpivoted `LDLᵀ`).
//! - [`SymbolicCholesky::factorize_numeric_intranode_lblt`]: the numeric factorisation into
//!   our own buffers, with Bunch–Kaufman pivoting (1×1 and 2×2 pivots) *within each
//!   supernode's dense diagonal block*. It never fails by itself: a zero pivot gives
//!   infinities, which [`SymmetricFactorization::factorize`] detects and reports.
//! - The numeric factorisation works on P A Pᵀ gathered by us into the lower triangle of
//!   its own pattern (built by a counting sort), analysed with the identity ordering: faer
//!   would otherwise permute the whole matrix at every numeric factorisation, a sizeable
//!   part of its cost for the small, fairly dense blocks of the stability analysis.
//! - [`IntranodeLbltRef::solve_in_place_with_conj`]: the solve of the permuted system, which
//!   applies the pivoting permutation; the elimination order is applied around it.
//!
//! Plain `LDLᵀ` (`factorize_numeric_ldlt`) was not chosen: without pivoting an indefinite
//! matrix with a zero leading pivot (a bordered system, a saddle point) breaks down.
//!
//! # Zero diagonals and the limits of pivoting
//! Pivoting is restricted to the diagonal block of each supernode (no delayed pivots across
//! supernodes, unlike MA57/MUMPS). AMD likes to eliminate a Lagrange multiplier (zero
//! diagonal, few neighbours) first, alone in its supernode, where no pivoting can help. So
//! when a factorisation fails and the matrix has zero diagonal entries, the elimination
//! order is changed once so that each such unknown comes right after a "partner" neighbour
//! with a nonzero diagonal, the symbolic analysis is redone and the factorisation retried
//! (see [`SymmetricFactorization::factorize`]). KKT / saddle-point / bordered systems then
//! factorise. What remains: a pivot that is zero or tiny by cancellation in a supernode
//! too small to find a better one, or matrices with many mutually coupled zero diagonals,
//! are reported as [`FactorError::Singular`] / [`FactorError::NonFinite`] even if the
//! matrix is nonsingular (≈ 0.1 % of random sparse indefinite matrices with up to 25 %
//! zero diagonals). Never a silently wrong answer: every pivot is checked.
//!
//! The inertia is counted from the block diagonal `B`: by Sylvester's law of inertia it
//! equals the numbers of negative, zero and positive eigenvalues of `A`. A 2×2 block is
//! counted by its two eigenvalues.

use std::sync::{Mutex, PoisonError};

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::lblt::factor::LbltParams;
use faer::perm::PermRef;
use faer::reborrow::ReborrowMut;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, IntranodeLbltRef, SymbolicCholesky,
    SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side, Spec};

use super::sparse::SymmetricPattern;

/// Right-hand sides solved together (the solve scratch is sized for this many columns).
const SOLVE_BLOCK: usize = 8;

/// Numbers of negative, zero and positive eigenvalues of a symmetric matrix.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Inertia {
    pub negative: usize,
    pub zero: usize,
    pub positive: usize,
}

/// Why a factorisation or a solve failed.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum FactorError {
    /// A pivot eigenvalue has `|λ| <= threshold` (= `zero_pivot_tolerance · max|aᵢⱼ|`).
    /// `index` is the unknown (original numbering) eliminated at that pivot. The inertia,
    /// counting such pivots as zero, is still available.
    #[error("numerically singular matrix: pivot {value:e} at unknown {index} (|pivot| <= {threshold:e})")]
    Singular {
        index: usize,
        value: f64,
        threshold: f64,
    },
    /// A pivot is NaN or infinite (non-finite input, or a breakdown after a zero pivot).
    #[error("non-finite pivot {value} at unknown {index}")]
    NonFinite { index: usize, value: f64 },
    /// [`SymmetricFactorization::factorize`] has not been called successfully yet.
    #[error("no factorisation available")]
    NotFactorized,
    /// The symbolic analysis failed (out of memory or index overflow).
    #[error("symbolic analysis failed: {0}")]
    Symbolic(&'static str),
}

/// Options of [`SymmetricFactorization`].
#[derive(Clone, Copy, Debug)]
pub struct FactorOptions {
    /// A pivot eigenvalue `λ` counts as zero when `|λ| <= zero_pivot_tolerance · max|aᵢⱼ|`.
    /// Default `1e-13`: roughly the round-off level of the pivots of an exactly singular
    /// matrix of a few thousand unknowns, far below any physical pivot of a stiffness matrix.
    pub zero_pivot_tolerance: f64,
    /// Parallelism of faer's kernels. Default [`Par::Seq`]: measured faster than rayon on
    /// 2 cores for FE matrices of ~10⁴ unknowns.
    pub par: Par,
}

impl Default for FactorOptions {
    fn default() -> Self {
        Self {
            zero_pivot_tolerance: 1e-13,
            par: Par::Seq,
        }
    }
}

/// What the pivots of the last numeric factorisation say.
#[derive(Clone, Copy, Debug)]
struct PivotSummary {
    inertia: Inertia,
    log_abs_det: f64,
    /// First pivot judged zero or non-finite, as the error to report.
    failure: Option<FactorError>,
}

/// Sparse symmetric (indefinite) `LBLᵀ` factorisation on a fixed [`SymmetricPattern`].
///
/// Built once per pattern ([`new`](Self::new): symbolic analysis and all buffers), then
/// [`factorize`](Self::factorize) for each new set of values; neither `factorize` nor the
/// solves allocate.
pub struct SymmetricFactorization {
    pattern: SymmetricPattern,
    /// The symbolic analysis of the permuted lower triangle (identity ordering).
    symbolic: SymbolicCholesky<usize>,
    /// The elimination order: position k eliminates unknown `order_fwd[k]`.
    order_fwd: Vec<usize>,
    /// The lower triangle of P A Pᵀ: its pattern, for each of its entries the index of the
    /// value in A's `values`, and the buffer its values are gathered into.
    permuted: SymbolicSparseColMat<usize>,
    gather: Vec<usize>,
    permuted_values: Vec<f64>,
    options: FactorOptions,
    l_values: Vec<f64>,
    subdiag: Vec<f64>,
    /// The pivoting permutation of the numeric factorisation (within supernodes, in the
    /// elimination order).
    perm_fwd: Vec<usize>,
    perm_inv: Vec<usize>,
    factor_mem: MemBuffer,
    /// The solves' scratch: faer's, and the permuted right-hand sides.
    solve_mem: Mutex<(MemBuffer, Vec<f64>)>,
    /// `None` until a numeric factorisation was done (or when the last one had a non-finite
    /// pivot).
    pivots: Option<PivotSummary>,
}

impl std::fmt::Debug for SymmetricFactorization {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SymmetricFactorization")
            .field("n", &self.pattern.n())
            .field("nnz", &self.pattern.nnz())
            .field("factor_len", &self.l_values.len())
            .field("pivots", &self.pivots)
            .finish()
    }
}

impl SymmetricFactorization {
    /// Symbolic analysis of `pattern` with default options.
    pub fn new(pattern: &SymmetricPattern) -> Result<Self, FactorError> {
        Self::with_options(pattern, FactorOptions::default())
    }

    /// Symbolic analysis of `pattern` (AMD ordering, supernodes) and allocation of every
    /// buffer the numeric factorisation and the solves need.
    pub fn with_options(
        pattern: &SymmetricPattern,
        options: FactorOptions,
    ) -> Result<Self, FactorError> {
        Self::analyse(pattern, options, None)
    }

    /// Symbolic analysis with AMD (`order == None`) or with the given elimination order.
    fn analyse(
        pattern: &SymmetricPattern,
        options: FactorOptions,
        order: Option<&[usize]>,
    ) -> Result<Self, FactorError> {
        let n = pattern.n();
        let params = CholeskySymbolicParams {
            // Not `FORCE_SUPERNODAL` (= 0): faer compares `flops / nnz(L) > threshold`, which
            // picks the simplicial layout for a matrix without fill (e.g. diagonal, n = 1).
            supernodal_flop_ratio_threshold: SupernodalThreshold(f64::NEG_INFINITY),
            ..Default::default()
        };
        // The fill-reducing ordering of A (faer's AMD, which its own analysis would take);
        // the numeric factorisations then work on P A Pᵀ gathered by us, with an identity
        // ordering (faer would otherwise permute the whole matrix at every factorisation, a
        // sizeable part of it for the small, dense-ish blocks).
        let order_fwd: Vec<usize> = match order {
            Some(fwd) => fwd.to_vec(),
            None => amd_order(pattern, params.amd_params)?,
        };
        debug_assert!(
            {
                let mut seen = vec![false; n];
                order_fwd.len() == n
                    && order_fwd
                        .iter()
                        .all(|&i| !std::mem::replace(&mut seen[i], true))
            },
            "an elimination order is a permutation"
        );
        let (permuted, gather) = permuted_lower(pattern, &order_fwd);
        // faer analyses the upper triangle of a matrix it is given unpermuted.
        let symbolic = factorize_symbolic_cholesky(
            transposed(&permuted).as_ref(),
            Side::Lower,
            SymmetricOrdering::Identity,
            params,
        )
        .map_err(|e| FactorError::Symbolic(faer_error_name(e)))?;
        let par = options.par;
        let factor_req =
            symbolic.factorize_numeric_intranode_lblt_scratch::<f64>(par, Spec::default());
        let solve_req = symbolic.solve_in_place_scratch::<f64>(SOLVE_BLOCK, par);
        Ok(Self {
            l_values: vec![0.0; symbolic.len_val()],
            subdiag: vec![0.0; n],
            perm_fwd: (0..n).collect(),
            perm_inv: (0..n).collect(),
            order_fwd,
            permuted_values: vec![0.0; gather.len()],
            permuted,
            gather,
            factor_mem: MemBuffer::new(factor_req),
            solve_mem: Mutex::new((MemBuffer::new(solve_req), vec![0.0; n * SOLVE_BLOCK])),
            pattern: pattern.clone(),
            symbolic,
            options,
            pivots: None,
        })
    }

    /// Dimension `n`.
    pub fn n(&self) -> usize {
        self.pattern.n()
    }

    /// The pattern this factorisation was built for.
    pub fn pattern(&self) -> &SymmetricPattern {
        &self.pattern
    }

    /// Number of stored values of the factor `L` (supernodal, including explicit zeros).
    pub fn factor_len(&self) -> usize {
        self.l_values.len()
    }

    /// The floating-point operations of one numeric factorisation, from the symbolic
    /// structure: a supernode of c columns and r rows (c + its off-diagonal pattern) costs
    /// c³/3 for its diagonal block, (r − c) c² for the panel and (r − c)² c for the update of
    /// its ancestors. A cost estimate (for choosing between sparse and dense solvers), not a
    /// count of what faer executes.
    pub fn flops(&self) -> f64 {
        let SymbolicCholeskyRaw::Supernodal(sn) = self.symbolic.raw() else {
            return 0.0;
        };
        (0..sn.n_supernodes())
            .map(|s| {
                let c = (sn.supernode_end()[s] - sn.supernode_begin()[s]) as f64;
                let below = sn.supernode(s).pattern().len() as f64;
                c * c * c / 3.0 + below * c * c + below * below * c
            })
            .sum()
    }

    /// Numeric factorisation of the matrix with `values` (aligned with the pattern; only the
    /// lower triangle is read), reusing the symbolic analysis and the buffers.
    ///
    /// Every pivot is checked: `Err(Singular)` if one is zero within the tolerance (the
    /// inertia is then still available, counting it as zero), `Err(NonFinite)` if one is NaN
    /// or infinite (no inertia). Solves are refused after either error.
    ///
    /// Zero diagonal entries (Lagrange multipliers, `[[K, Cᵀ], [C, 0]]`) defeat pivoting
    /// within supernodes when AMD eliminates such an unknown before its neighbours. On a
    /// failure with such unknowns, the elimination order is changed so that each comes right
    /// after its own partner neighbour with a nonzero diagonal (see `protecting_order`),
    /// the symbolic analysis is redone and the factorisation retried, once per call; the new
    /// order is kept for later factorisations. Only that failure path allocates.
    ///
    /// # Panics
    /// If `values.len() != pattern.nnz()`.
    pub fn factorize(&mut self, values: &[f64]) -> Result<(), FactorError> {
        assert_eq!(
            values.len(),
            self.pattern.nnz(),
            "values do not match the pattern"
        );
        let result = self.factorize_numeric(values);
        if result.is_err() {
            if let Some(order) = self.protecting_order(values) {
                *self = Self::analyse(&self.pattern, self.options, Some(&order))?;
                return self.factorize_numeric(values);
            }
        }
        result
    }

    fn factorize_numeric(&mut self, values: &[f64]) -> Result<(), FactorError> {
        self.pivots = None;
        // faer's Bunch–Kaufman leaves `subdiag` untouched for a 1×1 pivot with nothing to
        // eliminate, so stale 2×2 markers from a previous factorisation must be cleared.
        self.subdiag.fill(0.0);
        // The lower triangle gathered, and max|a_ij| (of a symmetric A) with it.
        let mut scale = 0.0f64;
        for (x, &k) in self.permuted_values.iter_mut().zip(&self.gather) {
            *x = values[k];
            // Not `f64::max`: its NaN rule keeps the loop from running ahead. A NaN is
            // skipped here as there, and found among the pivots.
            let a = x.abs();
            if a > scale {
                scale = a;
            }
        }
        let _ = self.symbolic.factorize_numeric_intranode_lblt(
            &mut self.l_values,
            &mut self.subdiag,
            &mut self.perm_fwd,
            &mut self.perm_inv,
            SparseColMatRef::new(self.permuted.as_ref(), &self.permuted_values),
            Side::Lower,
            self.options.par,
            MemStack::new(&mut self.factor_mem),
            Spec::<LbltParams, f64>::default(),
        );
        let summary = self.scan_pivots(self.options.zero_pivot_tolerance * scale);
        match summary.failure {
            Some(err @ FactorError::NonFinite { .. }) => Err(err),
            failure => {
                self.pivots = Some(summary);
                failure.map_or(Ok(()), Err)
            }
        }
    }

    fn zero_threshold(&self, values: &[f64]) -> f64 {
        let scale = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        self.options.zero_pivot_tolerance * scale
    }

    /// An elimination order (position → unknown) derived from the current one in which every
    /// unknown `z` with a zero diagonal (`|a_zz| <=` the zero-pivot threshold) comes right
    /// after its own *partner*: a neighbour `v` (`a_vz != 0`) with a nonzero diagonal that
    /// partners no other such unknown. Then every leading block of the order is covered by
    /// nonzero diagonals and disjoint 2×2 blocks `[[a_vv, a_vz], [a_vz, 0]]`, hence is
    /// generically nonsingular, and `z`'s pivot is generically nonzero (for `[[K, Cᵀ], [C, 0]]`
    /// with `K` positive definite and `C` selecting unknowns: `−a_vz² / d_v`). Unknowns that
    /// find no partner go last, where the root supernode gives the pivoting most room.
    /// `None` if the order would not change.
    fn protecting_order(&self, values: &[f64]) -> Option<Vec<usize>> {
        let n = self.n();
        let (col_ptr, row_idx) = (self.pattern.col_ptr(), self.pattern.row_idx());
        let threshold = self.zero_threshold(values);
        let zero_diag: Vec<bool> = (0..n)
            .map(|i| values[self.pattern.position(i, i).expect("diagonal")].abs() <= threshold)
            .collect();
        // Off-diagonal neighbours of `v` through nonzero entries.
        let neighbours = |v: usize| {
            (col_ptr[v]..col_ptr[v + 1])
                .filter(move |&p| values[p] != 0.0 && row_idx[p] != v)
                .map(|p| row_idx[p])
        };
        let current = self.order_fwd.clone();
        // `free[v]`: v is placed, has a nonzero diagonal and partners nobody yet.
        let (mut placed, mut free, mut waiting) = (vec![false; n], vec![false; n], vec![false; n]);
        let mut order = Vec::with_capacity(n);
        for &i in &current {
            if !zero_diag[i] {
                placed[i] = true;
                order.push(i);
                free[i] = true;
                if let Some(z) = neighbours(i).find(|&z| waiting[z] && !placed[z]) {
                    free[i] = false;
                    placed[z] = true;
                    order.push(z);
                }
            } else if let Some(v) = neighbours(i).find(|&v| free[v]) {
                free[v] = false;
                placed[i] = true;
                order.push(i);
            } else {
                waiting[i] = true;
            }
        }
        order.extend(current.iter().filter(|&&i| !placed[i]));
        debug_assert_eq!(order.len(), n);
        (order != current).then_some(order)
    }

    /// Walks the block diagonal `B`, stored on the diagonal of each supernode's dense block
    /// with the 2×2 off-diagonals in `subdiag`.
    fn scan_pivots(&self, threshold: f64) -> PivotSummary {
        let mut out = PivotSummary {
            inertia: Inertia::default(),
            log_abs_det: 0.0,
            failure: None,
        };
        let SymbolicCholeskyRaw::Supernodal(sn) = self.symbolic.raw() else {
            // Only reachable for n == 0 (faer then picks the simplicial layout).
            debug_assert_eq!(self.n(), 0);
            return out;
        };
        // Unknown (original numbering) eliminated at pivot position i.
        let original = |i: usize| self.order_fwd[self.perm_fwd[i]];
        let mut record = |lambda: f64, index: usize| {
            if !lambda.is_finite() {
                // The first non-finite pivot wins over any zero pivot: no inertia then.
                if !matches!(out.failure, Some(FactorError::NonFinite { .. })) {
                    out.failure = Some(FactorError::NonFinite {
                        index,
                        value: lambda,
                    });
                }
            } else if lambda.abs() <= threshold {
                out.inertia.zero += 1;
                if out.failure.is_none() {
                    out.failure = Some(FactorError::Singular {
                        index,
                        value: lambda,
                        threshold,
                    });
                }
            } else if lambda < 0.0 {
                out.inertia.negative += 1;
            } else {
                out.inertia.positive += 1;
            }
            out.log_abs_det += lambda.abs().ln();
        };
        for s in 0..sn.n_supernodes() {
            let start = sn.supernode_begin()[s];
            let ncols = sn.supernode_end()[s] - start;
            let nrows = ncols + sn.supernode(s).pattern().len();
            let block = &self.l_values[sn.col_ptr_for_val()[s]..];
            let diag = |k: usize| block[k * nrows + k];
            let mut k = 0;
            while k < ncols {
                let b = self.subdiag[start + k];
                if b == 0.0 {
                    record(diag(k), original(start + k));
                    k += 1;
                } else {
                    let (l1, l2) = sym2_eigenvalues(diag(k), b, diag(k + 1));
                    record(l1, original(start + k));
                    record(l2, original(start + k + 1));
                    k += 2;
                }
            }
        }
        out
    }

    /// Inertia of the last factorised matrix (`None` if there is none or it had a
    /// non-finite pivot). Pivots with `|λ| <= tolerance · max|aᵢⱼ|` count as zero.
    pub fn inertia(&self) -> Option<Inertia> {
        self.pivots.map(|p| p.inertia)
    }

    /// `ln |det A|` (`-∞` if a pivot is exactly zero).
    pub fn log_abs_det(&self) -> Option<f64> {
        self.pivots.map(|p| p.log_abs_det)
    }

    /// Sign of `det A`: `-1`, `1`, or `0` when a pivot counts as zero.
    pub fn determinant_sign(&self) -> Option<i8> {
        self.inertia().map(|i| match (i.zero, i.negative % 2) {
            (0, 0) => 1,
            (0, _) => -1,
            _ => 0,
        })
    }

    /// Solves `A x = rhs` in place (`rhs.len() == n`).
    pub fn solve_in_place(&self, rhs: &mut [f64]) -> Result<(), FactorError> {
        let n = self.n();
        assert_eq!(rhs.len(), n, "rhs length must be n");
        self.solve_mat_in_place(MatMut::from_column_major_slice_mut(rhs, n, 1))
    }

    /// Solves for several right-hand sides stored column-major in `rhs` (`n · k` values).
    pub fn solve_many_in_place(&self, rhs: &mut [f64]) -> Result<(), FactorError> {
        let n = self.n();
        assert!(
            rhs.len().checked_rem(n) == Some(0),
            "rhs length must be a multiple of n > 0"
        );
        let k = rhs.len() / n;
        self.solve_mat_in_place(MatMut::from_column_major_slice_mut(rhs, n, k))
    }

    /// Solves `A X = rhs` in place for a faer matrix of right-hand sides.
    ///
    /// Refused (`Err`, `rhs` untouched) unless the last [`factorize`](Self::factorize)
    /// succeeded, so a singular matrix never yields a NaN/∞ "solution".
    pub fn solve_mat_in_place(&self, mut rhs: MatMut<'_, f64>) -> Result<(), FactorError> {
        let n = self.n();
        assert_eq!(rhs.nrows(), n, "rhs must have n rows");
        match self.pivots {
            None => return Err(FactorError::NotFactorized),
            Some(PivotSummary {
                failure: Some(err), ..
            }) => return Err(err),
            Some(_) => {}
        }
        // The factor is of P A Pᵀ (the elimination order); faer applies the pivoting.
        let perm = PermRef::new_checked(&self.perm_fwd, &self.perm_inv, n);
        let lblt = IntranodeLbltRef::new(&self.symbolic, &self.l_values, &self.subdiag, perm);
        let mut guard = self
            .solve_mem
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        let (mem, work) = &mut *guard;
        let mut j = 0;
        while j < rhs.ncols() {
            let k = SOLVE_BLOCK.min(rhs.ncols() - j);
            let mut x = MatMut::from_column_major_slice_mut(&mut work[..n * k], n, k);
            for c in 0..k {
                for (i, &unknown) in self.order_fwd.iter().enumerate() {
                    x[(i, c)] = rhs[(unknown, j + c)];
                }
            }
            lblt.solve_in_place_with_conj(
                Conj::No,
                x.rb_mut(),
                self.options.par,
                MemStack::new(mem),
            );
            for c in 0..k {
                for (i, &unknown) in self.order_fwd.iter().enumerate() {
                    rhs[(unknown, j + c)] = x[(i, c)];
                }
            }
            j += k;
        }
        Ok(())
    }
}

/// The lower triangle of P A Pᵀ for the elimination order `fwd` (position k eliminates
/// unknown `fwd[k]`), A given by its full symmetric `pattern`: its CSC pattern (rows sorted)
/// and, for each entry, the index of its value in A's values.
fn permuted_lower(
    pattern: &SymmetricPattern,
    fwd: &[usize],
) -> (SymbolicSparseColMat<usize>, Vec<usize>) {
    let n = pattern.n();
    let mut inv = vec![0; n];
    for (k, &i) in fwd.iter().enumerate() {
        inv[i] = k;
    }
    let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
    // Entry (r, c) of A goes to (inv r, inv c); kept where inv r >= inv c, in column inv c,
    // its value read from A's column c. The kept entries are bucketed by their row in B
    // first, then appended to their columns going through the rows in increasing order:
    // every column's rows come out sorted, without a comparison sort.
    let mut by_row_ptr = vec![0usize; n + 1];
    let mut new_ptr = vec![0usize; n + 1];
    for (j, &c) in fwd.iter().enumerate() {
        for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
            if inv[r] >= j {
                by_row_ptr[inv[r] + 1] += 1;
                new_ptr[j + 1] += 1;
            }
        }
    }
    for k in 0..n {
        by_row_ptr[k + 1] += by_row_ptr[k];
        new_ptr[k + 1] += new_ptr[k];
    }
    let nnz = new_ptr[n];
    // For each kept entry, by its row in B: (its column in B, its position in A).
    let mut by_row = vec![(0usize, 0usize); nnz];
    let mut next = by_row_ptr[..n].to_vec();
    for (j, &c) in fwd.iter().enumerate() {
        for p in col_ptr[c]..col_ptr[c + 1] {
            let k = inv[row_idx[p]];
            if k >= j {
                by_row[next[k]] = (j, p);
                next[k] += 1;
            }
        }
    }
    let mut next = new_ptr[..n].to_vec();
    let mut gather = vec![0usize; nnz];
    let mut rows = vec![0usize; nnz];
    for k in 0..n {
        for &(j, p) in &by_row[by_row_ptr[k]..by_row_ptr[k + 1]] {
            rows[next[j]] = k;
            gather[next[j]] = p;
            next[j] += 1;
        }
    }
    // The column pointers are nondecreasing, the rows sorted and in range by construction.
    let symbolic = SymbolicSparseColMat::new_checked(n, n, new_ptr, None, rows);
    (symbolic, gather)
}

/// faer's AMD ordering (position k eliminates unknown `fwd[k]`) of a symmetric pattern
/// stored in full with sorted rows.
fn amd_order(
    pattern: &SymmetricPattern,
    control: faer::sparse::linalg::amd::Control,
) -> Result<Vec<usize>, FactorError> {
    use faer::sparse::linalg::amd;
    let n = pattern.n();
    let (mut fwd, mut inv) = (vec![0usize; n], vec![0usize; n]);
    let mut mem = MemBuffer::try_new(amd::order_scratch::<usize>(n, pattern.nnz()))
        .map_err(|_| FactorError::Symbolic("out of memory"))?;
    amd::order(
        &mut fwd,
        &mut inv,
        pattern.symbolic(),
        control,
        MemStack::new(&mut mem),
    )
    .map_err(|e| FactorError::Symbolic(faer_error_name(e)))?;
    Ok(fwd)
}

/// The transpose of an n × n sparsity pattern (rows sorted).
fn transposed(a: &SymbolicSparseColMat<usize>) -> SymbolicSparseColMat<usize> {
    let n = a.ncols();
    let (col_ptr, row_idx) = (a.col_ptr(), a.row_idx());
    let mut ptr = vec![0usize; n + 1];
    for &r in row_idx {
        ptr[r + 1] += 1;
    }
    for k in 0..n {
        ptr[k + 1] += ptr[k];
    }
    let mut next = ptr[..n].to_vec();
    let mut rows = vec![0usize; row_idx.len()];
    for c in 0..n {
        for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
            rows[next[r]] = c;
            next[r] += 1;
        }
    }
    SymbolicSparseColMat::new_checked(n, n, ptr, None, rows)
}

/// Eigenvalues of the symmetric 2×2 matrix `[[a, b], [b, c]]`, the smaller in magnitude
/// computed from the determinant to avoid cancellation.
fn sym2_eigenvalues(a: f64, b: f64, c: f64) -> (f64, f64) {
    let mean = 0.5 * (a + c);
    let radius = (0.5 * (a - c)).hypot(b);
    let big = if mean >= 0.0 {
        mean + radius
    } else {
        mean - radius
    };
    let small = if big == 0.0 {
        0.0
    } else {
        (a * c - b * b) / big
    };
    (big, small)
}

fn faer_error_name(e: faer::sparse::FaerError) -> &'static str {
    match e {
        faer::sparse::FaerError::IndexOverflow => "index overflow",
        faer::sparse::FaerError::OutOfMemory => "out of memory",
        _ => "unknown faer error",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lower triangle of P A Pᵀ and its gather, built by a comparison sort per column.
    fn permuted_lower_by_sorting(
        pattern: &SymmetricPattern,
        fwd: &[usize],
    ) -> (Vec<usize>, Vec<usize>, Vec<usize>) {
        let n = pattern.n();
        let mut inv = vec![0; n];
        for (k, &i) in fwd.iter().enumerate() {
            inv[i] = k;
        }
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let (mut ptr, mut rows, mut gather) = (vec![0], Vec::new(), Vec::new());
        for (j, &c) in fwd.iter().enumerate() {
            let mut entries: Vec<(usize, usize)> = (col_ptr[c]..col_ptr[c + 1])
                .filter(|&p| inv[row_idx[p]] >= j)
                .map(|p| (inv[row_idx[p]], p))
                .collect();
            entries.sort_unstable();
            rows.extend(entries.iter().map(|&(r, _)| r));
            gather.extend(entries.iter().map(|&(_, p)| p));
            ptr.push(rows.len());
        }
        (ptr, rows, gather)
    }

    /// The ordering taken from faer's AMD directly is the one of faer's own symbolic
    /// analysis, which computed it before along with what it was not used for.
    #[test]
    fn amd_order_is_the_symbolic_analysis_order() {
        let grid = |w: usize| {
            let n = w * w;
            let entries = (0..n).flat_map(move |i| {
                let (x, y) = (i % w, i / w);
                let right = (x + 1 < w).then_some((i, i + 1));
                let up = (y + 1 < w).then_some((i, i + w));
                let diagonal = (x + 1 < w && y + 1 < w).then_some((i, i + w + 1));
                [right, up, diagonal].into_iter().flatten()
            });
            SymmetricPattern::from_entries(n, entries)
        };
        for pattern in [grid(1), grid(2), grid(7), grid(20)] {
            let params = CholeskySymbolicParams::default();
            let faer_order: Vec<usize> = factorize_symbolic_cholesky(
                pattern.symbolic(),
                Side::Lower,
                SymmetricOrdering::Amd,
                params,
            )
            .unwrap()
            .perm()
            .map_or_else(|| (0..pattern.n()).collect(), |p| p.arrays().0.to_vec());
            assert_eq!(amd_order(&pattern, params.amd_params).unwrap(), faer_order);
        }
    }

    /// The counting-sort construction of P A Pᵀ's lower triangle reads the same entries of A
    /// into the same places as sorting each column, for random patterns and orders.
    #[test]
    fn permuted_lower_matches_sorting_each_column() {
        let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = move |k: usize| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed % k as u64) as usize
        };
        for n in [1, 2, 5, 17, 60] {
            for _ in 0..20 {
                let entries: Vec<(usize, usize)> = (0..3 * n)
                    .map(|_| (next(n), next(n)))
                    .chain((0..n).map(|i| (i, i)))
                    .collect();
                let pattern = SymmetricPattern::from_entries(n, entries);
                let mut fwd: Vec<usize> = (0..n).collect();
                for i in (1..n).rev() {
                    fwd.swap(i, next(i + 1));
                }
                let (fast, gather) = permuted_lower(&pattern, &fwd);
                let (ptr, rows, slow_gather) = permuted_lower_by_sorting(&pattern, &fwd);
                assert_eq!(fast.col_ptr(), ptr.as_slice(), "n = {n}");
                assert_eq!(fast.row_idx(), rows.as_slice(), "n = {n}");
                assert_eq!(gather, slow_gather, "n = {n}");
            }
        }
    }
}
