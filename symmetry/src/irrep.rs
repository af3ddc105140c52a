//! Real irreducible representations given by explicit orthogonal matrices.

use nalgebra::DMatrix;

/// How a real irrep behaves over the complex numbers.
///
/// The commutant (matrices commuting with every `D(g)`) of a real irrep is ℝ, ℂ or ℍ.
/// Its dimension is `(1/|G|) Σ_g χ(g)²` (1, 2 or 4).
/// - [`IrrepKind::Real`]: absolutely irreducible. Schur: `(1/|G|) Σ_g D_ij(g) D_kl(g) = δ_ik δ_jl / d`.
/// - [`IrrepKind::Complex`]: the 2-D `E_k` of `C_n`, a rotation by `2πk/n`; its commutant is spanned
///   by `I` and the quarter turn `J`, and `(1/|G|) Σ_g D_ij D_kl = (δ_ik δ_jl + J_ik J_jl) / d`.
///   Over ℂ it splits into two conjugate 1-D irreps; a real symmetric matrix that commutes with
///   the action still has every eigenvalue on this isotypic component twice.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IrrepKind {
    /// Absolutely irreducible.
    Real,
    /// Real form of a pair of complex-conjugate irreps (commutant ≅ ℂ).
    Complex,
}

impl IrrepKind {
    /// Dimension of the commutant: 1 (real type) or 2 (complex type).
    pub fn commutant_dim(self) -> usize {
        match self {
            IrrepKind::Real => 1,
            IrrepKind::Complex => 2,
        }
    }
}

/// A real irreducible representation: a name, and an orthogonal `d×d` matrix per element.
#[derive(Debug, Clone)]
pub struct Irrep {
    name: String,
    kind: IrrepKind,
    matrices: Vec<DMatrix<f64>>,
    complex_structure: Option<DMatrix<f64>>,
}

impl Irrep {
    /// An absolutely irreducible representation.
    pub(crate) fn real(name: impl Into<String>, matrices: Vec<DMatrix<f64>>) -> Self {
        Self {
            name: name.into(),
            kind: IrrepKind::Real,
            matrices,
            complex_structure: None,
        }
    }

    /// A complex-type irrep with its complex structure `J` (`J² = −I`, commuting with every
    /// `D(g)`).
    pub(crate) fn complex(
        name: impl Into<String>,
        matrices: Vec<DMatrix<f64>>,
        j: DMatrix<f64>,
    ) -> Self {
        Self {
            name: name.into(),
            kind: IrrepKind::Complex,
            matrices,
            complex_structure: Some(j),
        }
    }

    /// Name such as `A1`, `E2`, `T1u`.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Dimension d.
    pub fn dim(&self) -> usize {
        self.matrices[0].nrows()
    }

    /// Real or complex type (see [`IrrepKind`]).
    pub fn kind(&self) -> IrrepKind {
        self.kind
    }

    /// For a complex-type irrep, the orthogonal `J` with `J² = −I` that commutes with every
    /// `D(g)` (multiplication by i); `None` for real type.
    pub fn complex_structure(&self) -> Option<&DMatrix<f64>> {
        self.complex_structure.as_ref()
    }

    /// `D(g)` for element index `g`.
    pub fn matrix(&self, g: usize) -> &DMatrix<f64> {
        &self.matrices[g]
    }

    /// All matrices, in the order of the group's elements.
    pub fn matrices(&self) -> &[DMatrix<f64>] {
        &self.matrices
    }

    /// The character `χ(g) = tr D(g)`.
    pub fn character(&self, g: usize) -> f64 {
        self.matrices[g].trace()
    }

    /// Characters of all elements, in the order of the group's elements.
    pub fn characters(&self) -> Vec<f64> {
        self.matrices.iter().map(|m| m.trace()).collect()
    }

    /// True for the trivial representation (every matrix is `[1]`).
    pub fn is_trivial(&self) -> bool {
        self.dim() == 1
            && self
                .matrices
                .iter()
                .all(|m| (m[(0, 0)] - 1.0).abs() < 1e-12)
    }
}

/// Extracts an irrep of multiplicity one from an orthogonal representation `rep`.
///
/// With `χ` the irrep's character and `d` its dimension, `P = (d/|G|) Σ_g χ(g) rep(g)` is the
/// orthogonal projector onto the isotypic component, here `d`-dimensional. With `Q` an
/// orthonormal basis of its range, `g ↦ Qᵀ rep(g) Q` is the irrep in that basis.
pub(crate) fn extract_irrep(rep: &[DMatrix<f64>], chi: &[f64], d: usize) -> Vec<DMatrix<f64>> {
    let n = rep[0].nrows();
    let order = rep.len() as f64;
    let mut p = DMatrix::<f64>::zeros(n, n);
    for (m, &c) in rep.iter().zip(chi) {
        p += m * c;
    }
    p *= d as f64 / order;
    let p = (&p + p.transpose()) * 0.5;
    let eig = nalgebra::SymmetricEigen::new(p);
    let mut idx: Vec<usize> = (0..n).collect();
    idx.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let q = DMatrix::from_fn(n, d, |i, j| eig.eigenvectors[(i, idx[j])]);
    debug_assert!((eig.eigenvalues[idx[d - 1]] - 1.0).abs() < 1e-8);
    debug_assert!(d == n || eig.eigenvalues[idx[d]].abs() < 1e-8);
    rep.iter().map(|m| q.transpose() * m * &q).collect()
}
