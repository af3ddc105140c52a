//! A sparse symmetric block bordered by constraint columns, and the orthogonal complement of
//! a few columns (docs/theory.md §8.6–§8.8): what the stability analysis of any model needs
//! to count a block's eigenvalues below a shift by the inertia of one sparse LBLᵀ and to find
//! its lowest eigenpairs by shift-invert Lanczos on the same factorisation, on the complement
//! of the border — the 3-D irrep blocks and the meridian's Fourier blocks alike.

use super::eigen::{self, Bordered, EigenError, Operator, ShiftFamily};
use super::{FactorError, SymmetricFactorization, SymmetricPattern};
use nalgebra::{DMatrix, DVector};

/// The bordered sparse matrix of one block at a state (docs/theory.md §8.6):
/// M = [[K_μ, U], [Uᵀ, E]] with U = [P, U_D], P an orthonormal basis of the rigid modes and
/// of zero-C constraint loads (E = 0) and U_D the rank-one vectors and the loads of constraints
/// with an invertible C (E = E_D). Factorised at any shift σ of K_μ's diagonal, its inertia
/// counts the eigenvalues of the restricted matrix below σ.
pub struct BorderedBlock {
    /// Columns m of K_μ.
    pub m: usize,
    /// The orthonormal E = 0 columns (rigid span, zero-C constraints).
    pub constrained: Vec<Vec<f64>>,
    /// Negative eigenvalues of E_D.
    pub d_negative: usize,
    /// Values of M at σ = 0, on the bordered pattern.
    pub values: Vec<f64>,
    /// Positions of K_μ's diagonal in `values`.
    pub diagonal: Vec<usize>,
    /// A complex-type block (docs/theory.md §10.6): K_μ is the real R = [[A, C], [−C, A]],
    /// commuting with J [p; q] = [−q; p], its border is J-invariant, every eigenvalue of the
    /// restricted matrix is double and counts once.
    pub paired: bool,
}

/// x ← J x, J [p; q] = [−q; p]: the partner of real coordinates in a complex-type block's
/// basis [u, v] (multiplication by −i of the complex coordinates z = p − i q).
pub fn partner_in_place(x: &mut [f64]) {
    let m = x.len() / 2;
    let (p, q) = x.split_at_mut(m);
    for (pi, qi) in p.iter_mut().zip(q.iter_mut()) {
        let (a, b) = (*pi, *qi);
        *pi = -b;
        *qi = a;
    }
}

/// The columns of r followed by their partners J r (a J-invariant span).
pub fn with_partners(r: &DMatrix<f64>) -> DMatrix<f64> {
    let mut out = DMatrix::zeros(r.nrows(), 2 * r.ncols());
    for (k, c) in r.column_iter().enumerate() {
        out.set_column(k, &c);
        let mut x: Vec<f64> = c.iter().copied().collect();
        partner_in_place(&mut x);
        out.set_column(r.ncols() + k, &DVector::from_vec(x));
    }
    out
}

impl BorderedBlock {
    /// The values of M with σ subtracted from K_μ's diagonal.
    pub fn shifted(&self, sigma: f64) -> Vec<f64> {
        let mut v = self.values.clone();
        for &p in &self.diagonal {
            v[p] -= sigma;
        }
        v
    }

    /// The eigenvalues of the restricted matrix below σ, from a factorisation of M − σ J:
    /// In(M) = In(E_D) + In(S − σ) + (p, p, 0). A zero pivot (σ an eigenvalue to round-off)
    /// is an error with `strict`, else it counts as neither negative nor positive. A paired
    /// (complex-type) block counts each double eigenvalue once: half the count, which must be
    /// even ([`EigenError::OddPairedCount`] otherwise).
    pub fn count_below(
        &self,
        fact: &mut SymmetricFactorization,
        sigma: f64,
        strict: bool,
    ) -> Result<usize, EigenError> {
        // At σ = 0 the values themselves (no copy: a block's values are hundreds of kB).
        let shifted;
        let values = if sigma == 0.0 {
            &self.values
        } else {
            shifted = self.shifted(sigma);
            &shifted
        };
        match fact.factorize(values) {
            Ok(()) => {}
            Err(e @ FactorError::Singular { .. }) if strict => return Err(EigenError::Factor(e)),
            Err(FactorError::Singular { .. }) => {}
            Err(e) => return Err(EigenError::Factor(e)),
        }
        let inertia = fact
            .inertia()
            .ok_or(EigenError::Factor(FactorError::NotFactorized))?;
        let p = self.constrained.len();
        let below =
            inertia
                .negative
                .checked_sub(p + self.d_negative)
                .ok_or(EigenError::Unverified {
                    attempts: 0,
                    counted: inertia.negative,
                    found: p + self.d_negative,
                })?;
        match self.paired {
            false => Ok(below),
            true if below % 2 == 0 => Ok(below / 2),
            true => Err(EigenError::OddPairedCount { counted: below }),
        }
    }
}

/// A bordered block with its factorisation, as a family of shifted matrices for
/// [`eigen::lowest_eigenpairs`].
pub struct BlockFamily<'b> {
    /// The block.
    pub block: &'b BorderedBlock,
    /// Its factorisation (of the bordered pattern).
    pub fact: &'b mut SymmetricFactorization,
}

impl Operator for BlockFamily<'_> {
    fn dim(&self) -> usize {
        self.block.m
    }
    fn rank(&self) -> usize {
        let rank = Bordered::new(self.fact, self.block.m, &self.block.constrained).rank();
        if self.block.paired {
            rank / 2
        } else {
            rank
        }
    }
    fn apply(&self, x: &mut [f64]) -> Result<(), FactorError> {
        Bordered::new(self.fact, self.block.m, &self.block.constrained).apply(x)
    }
    fn project(&self, x: &mut [f64]) {
        Bordered::new(self.fact, self.block.m, &self.block.constrained).project(x)
    }
    fn partner(&self, x: &mut [f64]) -> bool {
        if self.block.paired {
            partner_in_place(x);
        }
        self.block.paired
    }
}

impl ShiftFamily for BlockFamily<'_> {
    fn factor(&mut self, shift: f64) -> Result<usize, EigenError> {
        self.block.count_below(self.fact, shift, true)
    }
}

/// The orthogonal complement of the columns of an m × c matrix r (c small: rigid modes,
/// constraint gradients), as Q = H_1 ⋯ H_k, a product of Householder reflections from a
/// QR factorisation of r with column pivoting: the first k columns of Q span r's columns,
/// the other m − k their complement. Restricting a block to the complement then costs
/// O(k m²) (a reflection from both sides per column) instead of the O(m³) of forming Z
/// explicitly.
pub struct Complement {
    /// Unit Householder vectors v (H = I − 2 v vᵀ), zero above their pivot row.
    reflectors: Vec<DVector<f64>>,
}

impl Complement {
    /// Columns count when the part of them not yet spanned has squared norm above `floor`
    /// (callers pass columns whose genuine parts are of order one).
    pub fn of(r: &DMatrix<f64>, floor: f64) -> Self {
        let m = r.nrows();
        let mut a = r.clone();
        let mut reflectors = Vec::new();
        for k in 0..r.ncols().min(m) {
            let (pivot, norm2) = (k..a.ncols())
                .map(|j| (j, a.view((k, j), (m - k, 1)).norm_squared()))
                .fold((k, -1.0), |best, x| if x.1 > best.1 { x } else { best });
            if norm2 <= floor {
                break;
            }
            a.swap_columns(k, pivot);
            let mut v = DVector::zeros(m);
            v.rows_mut(k, m - k).copy_from(&a.view((k, k), (m - k, 1)));
            let alpha = -v[k].signum() * norm2.sqrt();
            v[k] -= alpha;
            v /= v.norm();
            let vta = v.transpose() * &a;
            a -= &v * vta * 2.0;
            reflectors.push(v);
        }
        Self { reflectors }
    }

    /// The rank k of r.
    pub fn rank(&self) -> usize {
        self.reflectors.len()
    }

    /// Column k < rank of Q: an orthonormal basis of the span of r.
    pub fn span_column(&self, k: usize, m: usize) -> DVector<f64> {
        let mut x = DVector::zeros(m);
        x[k] = 1.0;
        for v in self.reflectors.iter().rev() {
            let vx = v.dot(&x);
            x -= v * (2.0 * vx);
        }
        x
    }

    /// (Qᵀ K Q) without its first k rows and columns: K on the complement.
    pub fn restrict(&self, mut k: DMatrix<f64>) -> DMatrix<f64> {
        if self.reflectors.is_empty() {
            return k;
        }
        for v in &self.reflectors {
            // H K H = K − 2 v wᵀ − 2 w vᵀ + 4 (vᵀ w) v vᵀ with w = K v.
            let w = &k * v;
            let vw = v.dot(&w);
            k -= (v * w.transpose() + &w * v.transpose()) * 2.0;
            k += v * v.transpose() * (4.0 * vw);
        }
        let (n, r) = (k.nrows(), self.rank());
        k.view((r, r), (n - r, n - r)).into_owned()
    }

    /// (Qᵀ L) without its first k rows: the columns of L in complement coordinates.
    pub fn restrict_columns(&self, mut l: DMatrix<f64>) -> DMatrix<f64> {
        for v in &self.reflectors {
            let vtl = v.transpose() * &l;
            l -= v * vtl * 2.0;
        }
        let r = self.rank();
        l.rows(r, l.nrows() - r).into_owned()
    }

    /// Q [0; y]: complement coordinates back to block coordinates.
    pub fn lift(&self, y: &DMatrix<f64>) -> DMatrix<f64> {
        let r = self.rank();
        let mut x = DMatrix::zeros(y.nrows() + r, y.ncols());
        x.rows_mut(r, y.nrows()).copy_from(y);
        for v in self.reflectors.iter().rev() {
            let vtx = v.transpose() * &x;
            x -= v * vtx * 2.0;
        }
        x
    }
}

/// The pattern of [[K, U], [Uᵀ, E]] for a sparse K and `border` dense columns U and E.
pub fn bordered_pattern(k: &SymmetricPattern, border: usize) -> SymmetricPattern {
    // Column j < m: K's rows, then every border row; a border column: every row. K's rows
    // are below m and sorted, so each column comes out sorted.
    let (m, col_ptr, row_idx) = (k.n(), k.col_ptr(), k.row_idx());
    let n = m + border;
    let mut starts = Vec::with_capacity(n + 1);
    let mut rows = Vec::with_capacity(k.nnz() + 2 * border * m + border * border);
    starts.push(0);
    for j in 0..m {
        rows.extend_from_slice(&row_idx[col_ptr[j]..col_ptr[j + 1]]);
        rows.extend(m..n);
        starts.push(rows.len());
    }
    for _ in m..n {
        rows.extend(0..n);
        starts.push(rows.len());
    }
    SymmetricPattern::from_sorted_columns(n, starts, rows)
}

impl BorderedBlock {
    /// The lowest `wanted` eigenvalues of the restricted matrix (and, with `vectors`, their
    /// eigenvectors in the block's coordinates) by shift-invert Lanczos at `shift` on the
    /// factorisation `fact` of the bordered pattern, certified by its inertia
    /// ([`eigen::lowest_eigenpairs`]); the rank of the restricted matrix (each double
    /// eigenvalue of a paired block once) with it.
    pub fn lowest(
        &self,
        fact: &mut SymmetricFactorization,
        wanted: usize,
        shift: f64,
        vectors: bool,
    ) -> (Result<eigen::Lowest, EigenError>, usize) {
        let mut family = BlockFamily { block: self, fact };
        let found = eigen::lowest_eigenpairs(&mut family, wanted, shift, shift.abs(), vectors);
        (found, family.rank())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bordered pattern is K's pattern with `border` full rows and columns appended.
    #[test]
    fn bordered_pattern_appends_full_rows_and_columns() {
        let k = SymmetricPattern::from_entries(6, [(1, 0), (3, 1), (5, 2), (4, 4), (5, 3)]);
        for border in [0, 1, 3] {
            let n = 6 + border;
            let entries = (0..6)
                .flat_map(|j| {
                    k.row_idx()[k.col_ptr()[j]..k.col_ptr()[j + 1]]
                        .iter()
                        .map(move |&i| (i, j))
                })
                .chain((6..n).flat_map(|j| (0..n).map(move |i| (i, j))));
            let expected = SymmetricPattern::from_entries(n, entries);
            let got = bordered_pattern(&k, border);
            assert_eq!(got.col_ptr(), expected.col_ptr(), "border {border}");
            assert_eq!(got.row_idx(), expected.row_idx(), "border {border}");
        }
    }
}
