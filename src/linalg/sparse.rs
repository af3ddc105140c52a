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
    /// The pairs are bucketed by column (a counting sort) and each column sorted and
    /// deduplicated on its own: memory of 12 bytes per pair while building, and a result
    /// allocated to its exact size.
    ///
    /// # Panics
    /// If an index is `>= n`, or `n` does not fit `u32`.
    pub fn from_entries(n: usize, entries: impl IntoIterator<Item = (usize, usize)>) -> Self {
        assert!(n < u32::MAX as usize, "n = {n} does not fit u32 indices");
        let pairs: Vec<(u32, u32)> = entries
            .into_iter()
            .map(|(r, c)| {
                assert!(r < n && c < n, "entry ({r}, {c}) out of bounds for n = {n}");
                (r as u32, c as u32)
            })
            .collect();
        // Column j holds its diagonal, the rows r of (r, j) and the columns c of (j, c).
        let mut start = vec![1usize; n + 1];
        start[0] = 0;
        for &(r, c) in &pairs {
            start[c as usize + 1] += 1;
            if r != c {
                start[r as usize + 1] += 1;
            }
        }
        for j in 0..n {
            start[j + 1] += start[j];
        }
        let mut rows = vec![0u32; start[n]];
        let mut next: Vec<usize> = start[..n].to_vec();
        for (j, slot) in next.iter_mut().enumerate() {
            rows[*slot] = j as u32;
            *slot += 1;
        }
        for &(r, c) in &pairs {
            rows[next[c as usize]] = r;
            next[c as usize] += 1;
            if r != c {
                rows[next[r as usize]] = c;
                next[r as usize] += 1;
            }
        }
        drop((pairs, next));
        let mut col_ptr = vec![0usize; n + 1];
        let mut kept = 0;
        for j in 0..n {
            let column = &mut rows[start[j]..start[j + 1]];
            column.sort_unstable();
            let mut last = None;
            for k in start[j]..start[j + 1] {
                let r = rows[k];
                if last != Some(r) {
                    rows[kept] = r;
                    kept += 1;
                    last = Some(r);
                }
            }
            col_ptr[j + 1] = kept;
        }
        let row_idx = rows[..kept].iter().map(|&r| r as usize).collect();
        Self {
            symbolic: SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx),
        }
    }

    /// The pattern with column j's rows `row_idx[col_ptr[j]..col_ptr[j + 1]]`, given sorted
    /// and distinct, both triangles and every diagonal entry present (the caller's
    /// invariants; the symmetry is checked in debug builds).
    ///
    /// # Panics
    /// If faer rejects the structure (`SymbolicSparseColMat::new_checked`).
    pub fn from_sorted_columns(n: usize, col_ptr: Vec<usize>, row_idx: Vec<usize>) -> Self {
        let pattern = Self {
            symbolic: SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx),
        };
        debug_assert!((0..n).all(|j| pattern.position(j, j).is_some()));
        debug_assert!((0..n).all(|j| pattern.row_idx()
            [pattern.col_ptr()[j]..pattern.col_ptr()[j + 1]]
            .iter()
            .all(|&i| pattern.position(j, i).is_some())));
        pattern
    }

    /// The pattern of a sum of dense symmetric element matrices: entry (i, j) is present iff
    /// i and j belong to one clique (or i = j). Entries equal to `absent` are skipped (held
    /// unknowns of a finite element).
    ///
    /// Equal to [`SymmetricPattern::from_entries`] of every pair within every clique, built
    /// without listing the pairs: each index's cliques are found from an incidence list and
    /// a column gathers their members once (marked), so the work and memory are those of the
    /// result, not of the K² pairs per clique.
    ///
    /// # Panics
    /// If an index other than `absent` is `>= n`, or `n` does not fit `u32`.
    pub fn from_cliques<const K: usize>(n: usize, cliques: &[[u32; K]], absent: u32) -> Self {
        assert!(n < u32::MAX as usize, "n = {n} does not fit u32 indices");
        fn members<const K: usize>(c: &[u32; K], absent: u32) -> impl Iterator<Item = u32> + '_ {
            c.iter().copied().filter(move |&i| i != absent)
        }
        // The cliques of every index (CSR).
        let mut inc_ptr = vec![0usize; n + 1];
        for c in cliques {
            for i in members(c, absent) {
                assert!((i as usize) < n, "index {i} out of bounds for n = {n}");
                inc_ptr[i as usize + 1] += 1;
            }
        }
        for j in 0..n {
            inc_ptr[j + 1] += inc_ptr[j];
        }
        let mut incidence = vec![0u32; inc_ptr[n]];
        let mut next: Vec<usize> = inc_ptr[..n].to_vec();
        for (t, c) in cliques.iter().enumerate() {
            for i in members(c, absent) {
                incidence[next[i as usize]] = t as u32;
                next[i as usize] += 1;
            }
        }
        drop(next);
        let mut mark = vec![u32::MAX; n];
        let mut col_ptr = vec![0usize; n + 1];
        let mut row_idx: Vec<usize> = Vec::new();
        let mut column: Vec<u32> = Vec::new();
        for j in 0..n {
            column.clear();
            column.push(j as u32);
            mark[j] = j as u32;
            for &t in &incidence[inc_ptr[j]..inc_ptr[j + 1]] {
                for i in members(&cliques[t as usize], absent) {
                    if mark[i as usize] != j as u32 {
                        mark[i as usize] = j as u32;
                        column.push(i);
                    }
                }
            }
            column.sort_unstable();
            row_idx.extend(column.iter().map(|&i| i as usize));
            col_ptr[j + 1] = row_idx.len();
        }
        row_idx.shrink_to_fit();
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
