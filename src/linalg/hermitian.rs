//! Dense Hermitian eigenvalues on the orthogonal complement of a few vectors (the block of a
//! complex-type irrep with its rigid modes deflated; docs/theory.md §10.6).
//!
//! The complement of span{r_1 … r_c} is Q = H_1 ⋯ H_k from a pivoted Householder QR of the
//! columns over ℂ (H = I − 2 v vᴴ with ‖v‖ = 1, Hermitian and unitary): the first k columns
//! of Q span the r's, the other n − k their complement. The eigenvalues of Zᴴ A Z on the
//! complement come from faer's dense self-adjoint solver, ascending.

use nalgebra::{Complex, DMatrix, DVector};

type C64 = Complex<f64>;

/// The complement of the span of some columns, as Householder reflections.
pub struct ComplexComplement {
    /// Unit Householder vectors (zero above their pivot row).
    reflectors: Vec<DVector<C64>>,
}

impl ComplexComplement {
    /// Columns count when the part of them not yet spanned has squared norm above `floor`
    /// (callers pass columns whose genuine parts are of order one).
    pub fn of(r: &DMatrix<C64>, floor: f64) -> Self {
        let n = r.nrows();
        let mut a = r.clone();
        let mut reflectors = Vec::new();
        for k in 0..r.ncols().min(n) {
            let (pivot, norm2) = (k..a.ncols())
                .map(|j| (j, a.view((k, j), (n - k, 1)).norm_squared()))
                .fold((k, -1.0), |best, x| if x.1 > best.1 { x } else { best });
            if norm2 <= floor {
                break;
            }
            a.swap_columns(k, pivot);
            let mut v = DVector::<C64>::zeros(n);
            v.rows_mut(k, n - k).copy_from(&a.view((k, k), (n - k, 1)));
            let x0 = v[k];
            let phase = if x0.norm() > 0.0 {
                x0 / x0.norm()
            } else {
                C64::new(1.0, 0.0)
            };
            v[k] += phase * norm2.sqrt();
            let nv = v.norm();
            v /= C64::new(nv, 0.0);
            let vha = v.adjoint() * &a;
            a -= &v * vha * C64::new(2.0, 0.0);
            reflectors.push(v);
        }
        Self { reflectors }
    }

    /// The rank k of the columns.
    pub fn rank(&self) -> usize {
        self.reflectors.len()
    }

    /// Qᴴ A Q without its first k rows and columns: A on the complement.
    pub fn restrict(&self, mut a: DMatrix<C64>) -> DMatrix<C64> {
        let two = C64::new(2.0, 0.0);
        for v in &self.reflectors {
            // H A H with H = I − 2 v vᴴ, from the left and then from the right.
            let vha = v.adjoint() * &a;
            a -= v * vha * two;
            let av = &a * v;
            a -= av * v.adjoint() * two;
        }
        let (n, k) = (a.nrows(), self.rank());
        a.view((k, k), (n - k, n - k)).into_owned()
    }

    /// Q [0; y]: complement coordinates back to the full ones.
    pub fn lift(&self, y: &DMatrix<C64>) -> DMatrix<C64> {
        let k = self.rank();
        let mut x = DMatrix::<C64>::zeros(y.nrows() + k, y.ncols());
        x.rows_mut(k, y.nrows()).copy_from(y);
        for v in self.reflectors.iter().rev() {
            let vhx = v.adjoint() * &x;
            x -= v * vhx * C64::new(2.0, 0.0);
        }
        x
    }
}

/// The eigenvalues of a Hermitian matrix, ascending, and with `with_vectors` its
/// eigenvectors (columns, same order); empty-safe.
pub fn hermitian_eigen(a: &DMatrix<C64>, with_vectors: bool) -> (Vec<f64>, DMatrix<C64>) {
    let n = a.nrows();
    if n == 0 {
        return (Vec::new(), DMatrix::zeros(0, 0));
    }
    let m = faer::Mat::<faer::c64>::from_fn(n, n, |i, j| {
        let x = (a[(i, j)] + a[(j, i)].conj()) * 0.5;
        faer::c64::new(x.re, x.im)
    });
    if !with_vectors {
        if let Ok(values) = m.self_adjoint_eigenvalues(faer::Side::Lower) {
            let mut values = values;
            values.sort_by(f64::total_cmp);
            return (values, DMatrix::zeros(n, 0));
        }
    }
    match m.self_adjoint_eigen(faer::Side::Lower) {
        Ok(eig) => {
            let (s, u) = (eig.S(), eig.U());
            let values = (0..n).map(|k| s[k].re).collect();
            let vectors = DMatrix::from_fn(n, n, |i, j| {
                let x = u[(i, j)];
                C64::new(x.re, x.im)
            });
            (values, vectors)
        }
        Err(_) => {
            let eig = nalgebra::SymmetricEigen::new(a.clone());
            let mut idx: Vec<usize> = (0..n).collect();
            idx.sort_by(|&x, &y| eig.eigenvalues[x].total_cmp(&eig.eigenvalues[y]));
            let values = idx.iter().map(|&k| eig.eigenvalues[k]).collect();
            let vectors = DMatrix::from_fn(n, n, |i, j| eig.eigenvectors[(i, idx[j])]);
            (values, vectors)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(re: f64, im: f64) -> C64 {
        C64::new(re, im)
    }

    /// Q is unitary, its last n − k columns are orthogonal to r, `restrict` is Zᴴ A Z and the
    /// eigenvalues of a Hermitian matrix are those of its realification, each once.
    #[test]
    fn complement_and_eigenvalues_over_c() {
        let n = 7;
        let f = |i: usize, j: usize| ((i * 7 + j * 3) as f64 * 0.37).sin();
        let mut r = DMatrix::from_fn(n, 3, |i, j| c(f(i, j), f(j + 2, i)));
        // A complex multiple of the others does not count.
        let dep = r.column(0) * c(0.3, -1.2) + r.column(1) * c(0.0, 0.5);
        r.set_column(2, &dep);
        let q = ComplexComplement::of(&r, 1e-12);
        assert_eq!(q.rank(), 2);
        let z = q.lift(&DMatrix::identity(n - 2, n - 2));
        assert!((z.adjoint() * &z - DMatrix::identity(n - 2, n - 2)).camax() < 1e-14);
        assert!((z.adjoint() * &r).camax() < 1e-14);
        let b = DMatrix::from_fn(n, n, |i, j| c(f(i + j, i * j), f(i * j + 1, i + 2 * j)));
        let a = &b + b.adjoint();
        assert!((q.restrict(a.clone()) - z.adjoint() * &a * &z).camax() < 1e-13);
        let (values, vectors) = hermitian_eigen(&a, true);
        for (k, &lam) in values.iter().enumerate() {
            let x = vectors.column(k);
            assert!((&a * x - x * c(lam, 0.0)).camax() < 1e-12);
        }
        let real = DMatrix::from_fn(2 * n, 2 * n, |i, j| {
            let (x, bi, bj) = (a[(i % n, j % n)], i / n, j / n);
            match (bi, bj) {
                (0, 0) | (1, 1) => x.re,
                (0, 1) => -x.im,
                _ => x.im,
            }
        });
        let mut doubled: Vec<f64> = values.iter().flat_map(|&v| [v, v]).collect();
        let mut direct: Vec<f64> = real.symmetric_eigenvalues().iter().copied().collect();
        doubled.sort_by(f64::total_cmp);
        direct.sort_by(f64::total_cmp);
        for (x, y) in doubled.iter().zip(&direct) {
            assert!((x - y).abs() < 1e-12, "{x} vs {y}");
        }
    }
}
