//! A fixed sparsity pattern of a symmetric matrix, stored in full (both triangles).

use faer::sparse::{SparseColMatRef, SymbolicSparseColMat, SymbolicSparseColMatRef};
use faer::Mat;

/// The CSC sparsity pattern of a symmetric `n × n` matrix, storing **both** triangles.
///
/// The pattern is fixed once built: the finite-element assembler precomputes the slot of
/// every local entry with [`position`](Self::position) and then writes values into a
/// `Vec<f64>` of length [`nnz`](Self::nnz) aligned with [`row_idx`](Self::row_idx).
/// Invariants: row indices within a column are sorted and unique, the pattern is
/// symmetric (`(i, j)` present ⇔ `(j, i)` present) and every diagonal entry is present.
/// Values are expected to be symmetric too; the factorisation reads only the lower triangle.
#[derive(Clone, Debug)]
pub struct SymmetricPattern {
    symbolic: SymbolicSparseColMat<usize>,
}

impl SymmetricPattern {
    /// Builds the pattern from `(row, col)` pairs: duplicates are merged, the transpose of
    /// every entry is added and the diagonal is always present.
    ///
    /// # Panics
    /// If an index is `>= n`.
    pub fn from_entries(n: usize, entries: impl IntoIterator<Item = (usize, usize)>) -> Self {
        // (col, row) keys, so that sorting orders by column and then row.
        let mut keys: Vec<(usize, usize)> = (0..n).map(|i| (i, i)).collect();
        for (r, c) in entries {
            assert!(r < n && c < n, "entry ({r}, {c}) out of bounds for n = {n}");
            keys.push((c, r));
            if r != c {
                keys.push((r, c));
            }
        }
        keys.sort_unstable();
        keys.dedup();
        let mut col_ptr = vec![0usize; n + 1];
        for &(c, _) in &keys {
            col_ptr[c + 1] += 1;
        }
        for j in 0..n {
            col_ptr[j + 1] += col_ptr[j];
        }
        let row_idx = keys.into_iter().map(|(_, r)| r).collect();
        Self {
            symbolic: SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx),
        }
    }

    /// Dimension `n`.
    pub fn n(&self) -> usize {
        self.symbolic.nrows()
    }

    /// Number of stored entries (both triangles).
    pub fn nnz(&self) -> usize {
        self.symbolic.row_idx().len()
    }

    /// Column pointers, length `n + 1`.
    pub fn col_ptr(&self) -> &[usize] {
        self.symbolic.col_ptr()
    }

    /// Row indices, length [`nnz`](Self::nnz), sorted within each column.
    pub fn row_idx(&self) -> &[usize] {
        self.symbolic.row_idx()
    }

    /// The slot of entry `(row, col)` in the value array, if it is in the pattern.
    pub fn position(&self, row: usize, col: usize) -> Option<usize> {
        if col >= self.n() {
            return None;
        }
        let start = self.col_ptr()[col];
        let rows = &self.row_idx()[start..self.col_ptr()[col + 1]];
        rows.binary_search(&row).ok().map(|k| start + k)
    }

    /// The faer symbolic view of the pattern.
    pub fn symbolic(&self) -> SymbolicSparseColMatRef<'_, usize> {
        self.symbolic.as_ref()
    }

    /// Views `(pattern, values)` as a faer sparse matrix.
    ///
    /// # Panics
    /// If `values.len() != self.nnz()`.
    pub fn as_faer<'a>(&'a self, values: &'a [f64]) -> SparseColMatRef<'a, usize, f64> {
        SparseColMatRef::new(self.symbolic(), values)
    }

    /// `y = A x` with `A` given by `(self, values)`.
    ///
    /// # Panics
    /// On mismatched lengths.
    pub fn matvec(&self, values: &[f64], x: &[f64], y: &mut [f64]) {
        let n = self.n();
        assert!(values.len() == self.nnz() && x.len() == n && y.len() == n);
        let (col_ptr, row_idx) = (self.col_ptr(), self.row_idx());
        y.fill(0.0);
        for (j, &xj) in x.iter().enumerate() {
            for k in col_ptr[j]..col_ptr[j + 1] {
                y[row_idx[k]] += values[k] * xj;
            }
        }
    }

    /// The dense matrix of `(self, values)` (for tests and small problems).
    pub fn to_dense(&self, values: &[f64]) -> Mat<f64> {
        assert_eq!(values.len(), self.nnz());
        let (col_ptr, row_idx) = (self.col_ptr(), self.row_idx());
        let mut a = Mat::zeros(self.n(), self.n());
        for j in 0..self.n() {
            for k in col_ptr[j]..col_ptr[j + 1] {
                a[(row_idx[k], j)] = values[k];
            }
        }
        a
    }
}
