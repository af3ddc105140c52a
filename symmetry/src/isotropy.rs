//! Fixed-point spaces and isotropy subgroups of irreps, for equivariant branch switching.
//!
//! The mathematics is documented on [`IrrepIsotropy`].

use crate::group::{Group, GroupError};
use crate::irrep::Irrep;
use crate::lattice::{bits, has, SubgroupLattice};
use nalgebra::{DMatrix, DVector};

/// Tolerance for comparing irrep matrices (orthogonal, entries O(1)).
const TOL: f64 = 1e-9;

/// One conjugacy class of isotropy subgroups of an irrep.
#[derive(Debug, Clone)]
pub struct IsotropySubgroup {
    /// Index of the class in the [`SubgroupLattice`].
    pub class: usize,
    /// The class's name, e.g. `D5d`, `C1v`.
    pub name: String,
    /// The class representative (sorted element indices); the data below are for it.
    pub elements: Vec<usize>,
    /// `dim Fix_V(Σ)` (≥ 1).
    pub fixed_dim: usize,
    /// An orthonormal basis of `Fix_V(Σ)`, as the columns of a `d × fixed_dim` matrix in the
    /// irrep's coordinates (pivoted Gram–Schmidt on the columns of the projector: the first
    /// column has a positive entry where the projector's largest column is).
    pub fixed_basis: DMatrix<f64>,
    /// The normaliser `N(Σ)` in the group, sorted; it maps `Fix(Σ)` to itself.
    pub normalizer: Vec<usize>,
    /// For an axial subgroup: an element of `N(Σ)` that maps `v` to `−v` (the least index), if
    /// any. `None` when no element does — the half-branches along `±v` are distinct — and
    /// always `None` when `Σ` is not axial.
    pub reversing: Option<usize>,
}

impl IsotropySubgroup {
    /// `dim Fix(Σ) = 1`.
    pub fn is_axial(&self) -> bool {
        self.fixed_dim == 1
    }

    /// For an axial subgroup: whether `+v` and `−v` are conjugate (some element maps one to
    /// the other), i.e. whether the two half-branches are one branch up to symmetry.
    pub fn halves_conjugate(&self) -> bool {
        self.reversing.is_some()
    }

    /// For an axial subgroup, the unit vector `v` spanning `Fix(Σ)`.
    pub fn axis(&self) -> Option<DVector<f64>> {
        self.is_axial()
            .then(|| self.fixed_basis.column(0).into_owned())
    }
}

/// The isotropy subgroups (up to conjugacy) of one irrep, from [`Group::isotropy`].
///
/// Let `μ` be a real irrep of `G` on `V = ℝ^d` (matrices `D(g)`) and `Σ ⊂ G` a subgroup.
/// - The fixed-point space `Fix(Σ) = {v : D(σ) v = v ∀σ ∈ Σ}` is the range of the orthogonal
///   projector `P = (1/|Σ|) Σ_σ D(σ)` (symmetric, as `D(σ)ᵀ = D(σ⁻¹)`), and
///   `dim Fix(Σ) = tr P = (1/|Σ|) Σ_σ χ(σ)`.
/// - `Σ` is an *isotropy subgroup* of `μ` if it is the full stabiliser `{g : D(g) v = v}` of
///   some `v ≠ 0` (so `dim Fix(Σ) > 0`). Equivalently `Σ` is the pointwise stabiliser of
///   `Fix(Σ)`, i.e. no strictly larger subgroup has the same fixed space: a generic `v` in
///   `Fix(Σ)` avoids the finitely many proper subspaces `Fix(⟨Σ, g⟩)`, `g ∉ Σ`. As
///   `Fix(⟨Σ, g⟩) ⊂ Fix(Σ)`, the test used here is exact: `dim Fix(⟨Σ, g⟩) < dim Fix(Σ)` for
///   every `g ∉ Σ`, by characters. The property is invariant under conjugation
///   (`D(g) Fix(Σ) = Fix(gΣg⁻¹)`), so it is decided once per class of the subgroup lattice.
/// - *Axial*: `dim Fix(Σ) = 1`. The equivariant branching lemma gives a branch with isotropy
///   exactly `Σ`, tangent to `Fix(Σ) = span{v}` (when the critical eigenvalue crosses
///   transversally). If `D(g) v = −v` then `gΣg⁻¹ = Stab(D(g) v) = Stab(−v) = Stab(v) = Σ`,
///   so the elements that reverse `v` lie in the normaliser `N(Σ)`, which maps the line to
///   itself and acts on it by ±1. If one does, `±v` are conjugate (one branch up to symmetry, and the
///   quadratic coefficient of the reduced equation vanishes); if none does, the half-branches
///   along `+v` and `−v` are distinct.
/// - The kernel `{g : D(g) = I}` fixes all of `V` and lies in every isotropy subgroup.
///
/// Complex-type irreps (`E_k` of `C_n`, see [`crate::IrrepKind`]): the real 2-D matrices are
/// what is used. They commute with the complex structure `J`, so every fixed space is
/// `J`-invariant — a complex subspace of `V ≅ ℂ`, of real dimension 0 or 2. A rotation fixes a
/// nonzero vector only if it acts as the identity, so the only isotropy subgroup is the
/// kernel, with `Fix = V` (dimension 2), and there are no axial subgroups: the branching
/// lemma predicts nothing there (the reduced equation on `ℂ` is `Z_m`-equivariant,
/// `m = n / gcd(n, k)`; whatever branches it has must be found from that equation, not from a
/// fixed-point space).
#[derive(Debug, Clone)]
pub struct IrrepIsotropy {
    /// The irrep's name.
    pub irrep: String,
    /// The irrep's dimension.
    pub dim: usize,
    /// The kernel `{g : D(g) = I}`, sorted; it lies in every isotropy subgroup.
    pub kernel: Vec<usize>,
    /// Isotropy subgroup classes, by decreasing order (ties: by class index in the lattice).
    pub subgroups: Vec<IsotropySubgroup>,
}

impl IrrepIsotropy {
    /// The axial isotropy subgroups (`dim Fix = 1`).
    pub fn axial(&self) -> impl Iterator<Item = &IsotropySubgroup> {
        self.subgroups.iter().filter(|s| s.is_axial())
    }

    /// The isotropy subgroup class with this name.
    pub fn find(&self, name: &str) -> Option<&IsotropySubgroup> {
        self.subgroups.iter().find(|s| s.name == name)
    }
}

impl Group {
    /// `dim Fix_V(Σ) = (1/|Σ|) Σ_σ χ(σ)` for the subgroup `subgroup` of this group acting in the
    /// irrep `irrep` (one of this group's irreps). An empty list imposes nothing: the result is
    /// the irrep's dimension.
    ///
    /// Panics if an index is out of range for the irrep.
    pub fn fixed_dim(&self, irrep: &Irrep, subgroup: &[usize]) -> usize {
        if subgroup.is_empty() {
            return irrep.dim();
        }
        let sum: f64 = subgroup.iter().map(|&g| irrep.character(g)).sum();
        (sum / subgroup.len() as f64).round().max(0.0) as usize
    }

    /// An orthonormal basis of `Fix_V(Σ)` as the columns of a `d × dim Fix` matrix: the range
    /// of the projector `(1/|Σ|) Σ_σ D(σ)`, by Gram–Schmidt on its columns, largest first.
    /// An empty list gives the identity.
    ///
    /// Panics if an index is out of range for the irrep.
    pub fn fixed_space(&self, irrep: &Irrep, subgroup: &[usize]) -> DMatrix<f64> {
        let d = irrep.dim();
        if subgroup.is_empty() {
            return DMatrix::identity(d, d);
        }
        let mut p = DMatrix::<f64>::zeros(d, d);
        for &g in subgroup {
            p += irrep.matrix(g);
        }
        p /= subgroup.len() as f64;
        range_basis(&p, self.fixed_dim(irrep, subgroup))
    }

    /// The dimension of the space of `G`-invariant cubic forms on `V_μ`: the multiplicity of
    /// the trivial irrep in `Sym³ V_μ`, `(1/|G|) Σ_g (χ(g)³ + 3 χ(g²) χ(g) + 2 χ(g³)) / 6`.
    ///
    /// The quadratic coefficient of the reduced equation along an axial line,
    /// `c₂ ∝ D³Π[φ, φ, φ]`, is the value at `v` of an invariant cubic. So `c₂ = 0` by symmetry
    /// whenever this is 0, even if no element maps `v` to `−v` (e.g. `C_nv` on `E_k` with
    /// `m = n / gcd(n, k)` odd and ≥ 5: two distinct half-branches, yet `λ(a)` along them is
    /// even in `a` below order `a^(m−2)`, the first term of `z̄^(m−1)` on the line).
    /// Conversely, a conjugate pair `±v` forces `c₂ = 0` whatever this number is.
    ///
    /// Panics if the irrep has fewer matrices than the group has elements.
    pub fn invariant_cubics(&self, irrep: &Irrep) -> usize {
        let sum: f64 = (0..self.order())
            .map(|g| {
                let g2 = self.mul(g, g);
                let (c1, c2, c3) = (
                    irrep.character(g),
                    irrep.character(g2),
                    irrep.character(self.mul(g, g2)),
                );
                (c1 * c1 * c1 + 3.0 * c2 * c1 + 2.0 * c3) / 6.0
            })
            .sum();
        (sum / self.order() as f64).round().max(0.0) as usize
    }

    /// The kernel of the irrep: the elements with `D(g) = I`, sorted.
    pub fn irrep_kernel(&self, irrep: &Irrep) -> Vec<usize> {
        let d = irrep.dim();
        let id = DMatrix::<f64>::identity(d, d);
        (0..irrep.matrices().len())
            .filter(|&g| (irrep.matrix(g) - &id).abs().max() < TOL)
            .collect()
    }

    /// The isotropy subgroups of the irrep up to conjugacy, with fixed spaces, normalisers
    /// and, for the axial ones, whether `±v` are conjugate (see [`IrrepIsotropy`]).
    ///
    /// `lattice` must be this group's [`Group::subgroup_lattice`] and `irrep` one of its
    /// irreps; a size mismatch is [`GroupError::Mismatch`].
    pub fn isotropy(
        &self,
        lattice: &SubgroupLattice,
        irrep: &Irrep,
    ) -> Result<IrrepIsotropy, GroupError> {
        let n = self.order();
        if irrep.matrices().len() != n {
            return Err(GroupError::Mismatch(format!(
                "irrep {} has {} matrices, group {} has {n} elements",
                irrep.name(),
                irrep.matrices().len(),
                self.name()
            )));
        }
        if lattice.group_order() != n {
            return Err(GroupError::Mismatch(format!(
                "the lattice is of a group of order {}, {} has order {n}",
                lattice.group_order(),
                self.name()
            )));
        }
        let mut subgroups = Vec::new();
        for (class, c) in lattice.classes().iter().enumerate() {
            let sigma = &c.representative;
            let k = self.fixed_dim(irrep, sigma);
            if k == 0 {
                continue;
            }
            let inside = bits(sigma, n);
            let isotropy = (0..n).filter(|&g| !has(&inside, g)).all(|g| {
                let mut gens = c.generators.clone();
                gens.push(g);
                self.fixed_dim(irrep, &self.generate(&gens)) < k
            });
            if !isotropy {
                continue;
            }
            let fixed_basis = self.fixed_space(irrep, sigma);
            let normalizer = self.normalizer(sigma);
            let reversing = if k == 1 {
                let v = fixed_basis.column(0);
                normalizer
                    .iter()
                    .copied()
                    .find(|&g| v.dot(&(irrep.matrix(g) * v)) < 0.0)
            } else {
                None
            };
            subgroups.push(IsotropySubgroup {
                class,
                name: c.name.clone(),
                elements: sigma.clone(),
                fixed_dim: k,
                fixed_basis,
                normalizer,
                reversing,
            });
        }
        subgroups.sort_by_key(|s| (std::cmp::Reverse(s.elements.len()), s.class));
        Ok(IrrepIsotropy {
            irrep: irrep.name().to_string(),
            dim: irrep.dim(),
            kernel: self.irrep_kernel(irrep),
            subgroups,
        })
    }
}

/// An orthonormal basis of the range of the projector `p`, of dimension `k`: modified
/// Gram–Schmidt on its columns, each step taking the column of largest remaining norm (the
/// first of near-equal ones), with a second orthogonalisation pass.
fn range_basis(p: &DMatrix<f64>, k: usize) -> DMatrix<f64> {
    let d = p.nrows();
    let mut cols: Vec<DVector<f64>> = (0..p.ncols()).map(|j| p.column(j).into_owned()).collect();
    let mut basis: Vec<DVector<f64>> = Vec::with_capacity(k);
    for _ in 0..k {
        let mut best = 0;
        let mut best_norm = -1.0;
        for (j, c) in cols.iter().enumerate() {
            if c.norm() > best_norm + 1e-12 {
                best = j;
                best_norm = c.norm();
            }
        }
        if best_norm < 1e-12 {
            break;
        }
        let mut v = cols[best].clone();
        for b in &basis {
            let dot = b.dot(&v);
            v -= b * dot;
        }
        let v = v.normalize();
        for c in cols.iter_mut() {
            let dot = v.dot(c);
            *c -= &v * dot;
        }
        basis.push(v);
    }
    if basis.is_empty() {
        return DMatrix::zeros(d, 0);
    }
    DMatrix::from_columns(&basis)
}
