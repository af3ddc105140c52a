//! Any subgroup as a group of its own, with real irreps computed by decomposition.
//!
//! [`Group::subgroup`] turns a subgroup `Σ ⊂ G` (given by element indices) into a [`Group`]
//! with its own table, classes and a complete set of real irreps. Axial subgroups (`C_n`,
//! `C_nv` about one axis) are built exactly as [`Group::stabilizer`] builds them, with the
//! closed-form irreps of the `axial` module. For every other subgroup (`D_n`, `D_nd`, `D_nh`,
//! `C_nh`, `S_2n`, `Ci`, `T`, `Th`, `I`, …) the irreps are computed as follows.
//!
//! # Every irrep of Σ is in the restriction of an irrep of G
//! Let `ψ` be a complex irrep of `Σ`. By Frobenius reciprocity `⟨Res Ψ, ψ⟩_Σ = ⟨Ψ, Ind ψ⟩_G`,
//! and `Ind ψ ≠ 0` contains some complex irrep `Ψ` of `G`, so `ψ ⊂ Res Ψ`; `Ψ` lies in the
//! complexification of some real irrep `R` of `G`, so `ψ ⊂ (Res R) ⊗ ℂ`. A real irrep `ρ` of
//! `Σ` with `ψ ⊂ ρ ⊗ ℂ` is then a summand of `Res R` (real irreps with a common complex
//! constituent are equivalent). So decomposing the restrictions of `G`'s irreps (orthogonal
//! matrices, of dimension ≤ 5 for the groups of this crate) finds every real irrep of `Σ`;
//! the search stops when `Σ_ρ d_ρ² / c_ρ = |Σ|` (`c` the commutant dimension), which holds
//! exactly for a complete set.
//!
//! # Splitting a representation into irreducibles
//! For an orthogonal representation `ρ` of `Σ` on `ℝⁿ` and a symmetric `X`, the average
//! `S = (1/|Σ|) Σ_σ ρ(σ) X ρ(σ)ᵀ` is symmetric and commutes with every `ρ(σ)`: it is the
//! orthogonal projection (Frobenius inner product) of `X` onto the commutant. Write
//! `ρ ≅ ⊕_μ μ ⊗ 𝔽_μ^{m_μ}` with `𝔽_μ = ℝ, ℂ` or `ℍ` the commutant of the irrep `μ`; the
//! symmetric part of the commutant of `ρ` is `⊕_μ H_μ`, with `H_μ` an `m_μ × m_μ` Hermitian
//! matrix over `𝔽_μ` acting on the copies. For a random `X` these Hermitian matrices have simple
//! eigenvalues, distinct across `μ`, and then each eigenspace of `S` is one irreducible
//! invariant subspace: isotypic components and the copies inside them are split in one step.
//! Eigenvalues closer than [`CLUSTER_GAP`] (relative) are kept together, so that eigenvectors
//! are accurate; a piece found reducible is split again with a fresh `X`.
//!
//! With `Q` an orthonormal basis (columns) of an invariant subspace, `σ ↦ Qᵀ ρ(σ) Q` is an
//! orthogonal representation: the irrep's matrices, in the parent irrep's coordinates.
//!
//! # Irreducibility and kind, from characters
//! `χ(σ) = tr ρ(σ)`. The commutant has dimension `c = (1/|Σ|) Σ_σ χ(σ)²` and its symmetric part
//! dimension `s = (1/|Σ|) Σ_σ (χ(σ)² + χ(σ²)) / 2` (the invariants of `Sym² ρ`). A real irrep
//! has commutant ℝ, ℂ or ℍ and transposition acts on it as conjugation, so `s = 1`; a reducible
//! `ρ` has `s ≥ 2`. Hence `ρ` is irreducible iff `s = 1`, and then `c = 1` (real type), `2`
//! (complex type) or `4` (quaternionic type, which no finite subgroup of O(3) has in its real
//! irreps; it is reported as an error).
//!
//! For complex type the complex structure `J` is the antisymmetric part of the commutant:
//! `K = (1/|Σ|) Σ_σ ρ(σ) Y ρ(σ)ᵀ` for a random antisymmetric `Y` is antisymmetric and commutes
//! with `ρ`, so `K = t J` with `J² = −I`, `t² = −tr(K²) / d`. In dimension 2 the sign is chosen so
//! that `J = [[0, −1], [1, 0]]`, as for the `E_k` of `C_n`.
//!
//! # Determinism
//! The random matrices come from a fixed-seed generator, so the irreps (and their bases, which
//! are otherwise arbitrary orthonormal bases of the invariant subspaces) are the same on every
//! run. One-dimensional matrices are rounded to exactly ±1.

use crate::group::{Group, GroupError};
use crate::irrep::IrrepKind;
use crate::mulliken;
use crate::subgroup::{rotation_axis, Subgroup};
use nalgebra::{DMatrix, SymmetricEigen, Vector3};

/// Tolerance for characters and character sums (exact values are integers or algebraic
/// numbers of size O(1)).
const CHAR_TOL: f64 = 1e-6;

/// Relative gap below which eigenvalues of the averaged matrix are treated as one cluster.
const CLUSTER_GAP: f64 = 1e-3;

/// Largest allowed residual `‖ρ(σ) Q − Q Qᵀ ρ(σ) Q‖` of an extracted invariant subspace.
const INVARIANCE_TOL: f64 = 1e-10;

/// Random restarts allowed per representation (each succeeds with probability close to 1).
const MAX_TRIES: usize = 64;

/// A real irrep found by decomposition, before it is named.
#[derive(Debug, Clone)]
pub(crate) struct RawIrrep {
    /// `D(σ)` for every element of the subgroup, in its order.
    pub(crate) matrices: Vec<DMatrix<f64>>,
    /// `χ(σ) = tr D(σ)`.
    pub(crate) characters: Vec<f64>,
    /// Real or complex type.
    pub(crate) kind: IrrepKind,
    /// `J` for complex type.
    pub(crate) complex_structure: Option<DMatrix<f64>>,
}

impl RawIrrep {
    pub(crate) fn dim(&self) -> usize {
        self.matrices[0].nrows()
    }

    /// True for the trivial representation.
    pub(crate) fn is_trivial(&self) -> bool {
        self.dim() == 1 && self.characters.iter().all(|&c| c == 1.0)
    }
}

impl Group {
    /// The subgroup with these elements (indices into this group, any order, duplicates
    /// allowed) as a group of its own, with its multiplication table, classes and a complete
    /// set of real irreps given by explicit orthogonal matrices (see the `decompose` module).
    ///
    /// - The whole group: a copy of this group, `parent_index = 0..order()`.
    /// - An axial subgroup (`C_n`, `C_nv` about one axis, including `C1` and a single mirror):
    ///   exactly what [`Group::stabilizer`] gives for the same elements when the direction it
    ///   keeps points along the axis as oriented here: the subgroup's own element order
    ///   (`r^k`, then `s r^k`, see the `axial` module), the names `C<n>` / `C<n>v` (a mirror is
    ///   `C1v`, and no primes: the subgroup is named as a group of its own) and the axial
    ///   irreps `A1, A2, B1, B2, E1, …`. The axis is oriented with a positive z component
    ///   (if it has none, positive y, then x); use [`Group::subgroup_along`] to choose it.
    /// - Any other subgroup: elements in increasing parent index (so the identity first),
    ///   named by [`Group::subgroup_name`] (`D5d`, `Th`, `S10`, …), irreps computed by
    ///   decomposing the restrictions of this group's irreps and named with Mulliken labels
    ///   (see the `mulliken` module), the trivial irrep first. Irreps of complex type (in `T`,
    ///   `Th`, `S_2n`, `C_nh`, …) carry their complex structure `J`.
    ///
    /// Errors: [`GroupError::NotAGroup`] if the elements are not a subgroup (empty, out of range
    /// or not closed); [`GroupError::Unsupported`] if the decomposition fails (a quaternionic
    /// irrep, or no complete set found — neither happens for subgroups of O(3) with a complete
    /// set of irreps in the parent).
    pub fn subgroup(&self, elements: &[usize]) -> Result<Subgroup, GroupError> {
        self.subgroup_with_hint(elements, None)
    }

    /// As [`Group::subgroup`], with the axis of an axial subgroup oriented along `axis` (its
    /// positive half-space): for the elements of `self.stabilizer(&[Invariant::Direction(v)])`
    /// and `axis = v` the two results agree exactly. Ignored for the whole group and for
    /// subgroups that are not axial.
    ///
    /// [`Invariant::Direction(v)`]: crate::Invariant::Direction
    pub fn subgroup_along(
        &self,
        elements: &[usize],
        axis: Vector3<f64>,
    ) -> Result<Subgroup, GroupError> {
        self.subgroup_with_hint(elements, Some(axis))
    }

    fn subgroup_with_hint(
        &self,
        elements: &[usize],
        hint: Option<Vector3<f64>>,
    ) -> Result<Subgroup, GroupError> {
        let mut members = elements.to_vec();
        members.sort_unstable();
        members.dedup();
        if !self.is_subgroup(&members) {
            return Err(GroupError::NotAGroup(format!(
                "{} elements of {} (order {}) that are not a subgroup",
                elements.len(),
                self.name(),
                self.order()
            )));
        }
        if members.len() == self.order() {
            return Ok(Subgroup {
                group: self.clone(),
                parent_index: members,
            });
        }
        let hint = hint.or_else(|| self.default_axis(&members));
        if let Ok(axial) = self.axial_subgroup(&members, hint) {
            return Ok(axial);
        }
        self.decomposed_subgroup(members)
    }

    /// The axis of the first rotation ≠ identity among `members`, with a positive z component
    /// (if zero, positive y, then x); `None` if there is no such rotation.
    fn default_axis(&self, members: &[usize]) -> Option<Vector3<f64>> {
        let g = members.iter().copied().find(|&g| {
            g != 0
                && self.is_proper(g)
                && (self.element(g) - crate::Matrix3::identity()).amax() > 1e-9
        })?;
        let a = rotation_axis(self.element(g));
        let first = [a.z, a.y, a.x]
            .into_iter()
            .find(|c| c.abs() > 1e-9)
            .unwrap_or(1.0);
        Some(if first < 0.0 { -a } else { a })
    }

    /// A non-axial subgroup: elements in parent order, irreps by decomposition, Mulliken names.
    fn decomposed_subgroup(&self, members: Vec<usize>) -> Result<Subgroup, GroupError> {
        let name = self.subgroup_name(&members);
        let elements = members.iter().map(|&g| *self.element(g)).collect();
        let mut group = Group::from_parts(name, elements, Vec::new())?;
        let restrictions = self
            .irreps()
            .iter()
            .map(|mu| members.iter().map(|&g| mu.matrix(g).clone()).collect());
        let raw = real_irreps(&group, restrictions)?;
        group.set_irreps(mulliken::named_irreps(&group, raw));
        Ok(Subgroup {
            group,
            parent_index: members,
        })
    }
}

/// A complete set of real irreps of `group`, from orthogonal representations of it that
/// together contain every irrep (see the module documentation).
pub(crate) fn real_irreps(
    group: &Group,
    reps: impl IntoIterator<Item = Vec<DMatrix<f64>>>,
) -> Result<Vec<RawIrrep>, GroupError> {
    let order = group.order() as f64;
    let mut rng = SplitMix64(0x6d65_6d73_7461_6221);
    let mut found: Vec<RawIrrep> = Vec::new();
    let mut covered = 0.0;
    for rep in reps {
        if (covered - order).abs() < CHAR_TOL {
            break;
        }
        if rep.len() != group.order() {
            return Err(GroupError::Mismatch(format!(
                "a representation with {} matrices for {} of order {}",
                rep.len(),
                group.name(),
                group.order()
            )));
        }
        if made_of_known(group, &characters(&rep), &found) {
            continue;
        }
        for piece in split(group, rep, &mut rng)? {
            let chi = characters(&piece);
            if found.iter().any(|f| same(&f.characters, &chi)) {
                continue;
            }
            let c = inner(&chi, &chi) / order;
            let d = piece[0].nrows();
            let (kind, complex_structure) = match c.round() as usize {
                1 => (IrrepKind::Real, None),
                2 => (
                    IrrepKind::Complex,
                    Some(complex_structure(group, &piece, &mut rng)?),
                ),
                4 => {
                    return Err(GroupError::Unsupported(format!(
                        "{}: an irrep of dimension {d} is of quaternionic type",
                        group.name()
                    )))
                }
                _ => {
                    return Err(GroupError::Unsupported(format!(
                        "{}: a piece with character norm {c} is not irreducible",
                        group.name()
                    )))
                }
            };
            covered += (d * d) as f64 / c.round();
            let (matrices, characters) = if d == 1 {
                // A real 1-D orthogonal representation takes the values ±1.
                let m: Vec<DMatrix<f64>> = piece
                    .iter()
                    .map(|m| DMatrix::from_element(1, 1, m[(0, 0)].signum()))
                    .collect();
                let chi = m.iter().map(|m| m[(0, 0)]).collect();
                (m, chi)
            } else {
                (piece, chi)
            };
            found.push(RawIrrep {
                matrices,
                characters,
                kind,
                complex_structure,
            });
        }
    }
    if (covered - order).abs() > CHAR_TOL {
        return Err(GroupError::Unsupported(format!(
            "{}: the representations given contain irreps with Σ d²/c = {covered}, not {order}",
            group.name()
        )));
    }
    Ok(found)
}

/// Splits an orthogonal representation into irreducible ones (module documentation).
fn split(
    group: &Group,
    rep: Vec<DMatrix<f64>>,
    rng: &mut SplitMix64,
) -> Result<Vec<Vec<DMatrix<f64>>>, GroupError> {
    let mut done = Vec::new();
    let mut todo = vec![rep];
    let mut tries = 0;
    while let Some(r) = todo.pop() {
        if (symmetric_commutant_dim(group, &r) - 1.0).abs() < CHAR_TOL {
            done.push(r);
            continue;
        }
        tries += 1;
        if tries > MAX_TRIES {
            return Err(GroupError::Unsupported(format!(
                "{}: a representation of dimension {} did not split after {MAX_TRIES} tries",
                group.name(),
                r[0].nrows()
            )));
        }
        let n = r[0].nrows();
        let s = average(&r, &rng.symmetric(n));
        let eig = SymmetricEigen::new((&s + s.transpose()) * 0.5);
        let mut idx: Vec<usize> = (0..n).collect();
        idx.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
        let scale = eig.eigenvalues.amax().max(f64::MIN_POSITIVE);
        let mut clusters: Vec<Vec<usize>> = Vec::new();
        for (k, &i) in idx.iter().enumerate() {
            let gap =
                k == 0 || eig.eigenvalues[i] - eig.eigenvalues[idx[k - 1]] > CLUSTER_GAP * scale;
            match clusters.last_mut() {
                Some(last) if !gap => last.push(i),
                _ => clusters.push(vec![i]),
            }
        }
        let pieces: Vec<Vec<DMatrix<f64>>> = clusters
            .iter()
            .map(|c| {
                let q = DMatrix::from_fn(n, c.len(), |i, j| eig.eigenvectors[(i, c[j])]);
                invariant_part(&r, &q)
            })
            .collect::<Option<_>>()
            .unwrap_or_default();
        if pieces.len() < 2 {
            // One cluster (or an inaccurate split): try again with another random matrix.
            todo.push(r);
        } else {
            todo.extend(pieces);
        }
    }
    Ok(done)
}

/// `σ ↦ Qᵀ ρ(σ) Q` if the columns of `q` span an invariant subspace (to [`INVARIANCE_TOL`]).
fn invariant_part(rep: &[DMatrix<f64>], q: &DMatrix<f64>) -> Option<Vec<DMatrix<f64>>> {
    let mut out = Vec::with_capacity(rep.len());
    for m in rep {
        let mq = m * q;
        let small = q.transpose() * &mq;
        if (&mq - q * &small).amax() > INVARIANCE_TOL {
            return None;
        }
        out.push(small);
    }
    Some(out)
}

/// The complex structure `J` of a complex-type irrep (module documentation).
fn complex_structure(
    group: &Group,
    rep: &[DMatrix<f64>],
    rng: &mut SplitMix64,
) -> Result<DMatrix<f64>, GroupError> {
    let d = rep[0].nrows();
    let id = DMatrix::<f64>::identity(d, d);
    for _ in 0..MAX_TRIES {
        let k = average(rep, &rng.antisymmetric(d));
        let k = (&k - k.transpose()) * 0.5;
        let t2 = -(&k * &k).trace() / d as f64;
        if t2 < 1e-4 {
            continue;
        }
        let mut j = k / t2.sqrt();
        if d == 2 {
            // ±[[0, −1], [1, 0]] (the only antisymmetric orthogonal 2×2 matrices); both
            // commute with the irrep, so take the standard one.
            j = DMatrix::from_row_slice(2, 2, &[0.0, -1.0, 1.0, 0.0]);
        }
        let commutes = rep.iter().all(|m| (&j * m - m * &j).amax() < 1e-9);
        if (&j * &j + &id).amax() < 1e-9 && commutes {
            return Ok(j);
        }
    }
    Err(GroupError::Unsupported(format!(
        "{}: no complex structure found for a complex-type irrep of dimension {d}",
        group.name()
    )))
}

/// `(1/|Σ|) Σ_σ ρ(σ) X ρ(σ)ᵀ`: the projection of `X` onto the commutant of `ρ`.
fn average(rep: &[DMatrix<f64>], x: &DMatrix<f64>) -> DMatrix<f64> {
    let n = x.nrows();
    let mut s = DMatrix::<f64>::zeros(n, n);
    for m in rep {
        s += m * x * m.transpose();
    }
    s / rep.len() as f64
}

/// `(1/|Σ|) Σ_σ (χ(σ)² + χ(σ²)) / 2`: the dimension of the symmetric part of the commutant.
fn symmetric_commutant_dim(group: &Group, rep: &[DMatrix<f64>]) -> f64 {
    let chi = characters(rep);
    let sum: f64 = (0..group.order())
        .map(|g| 0.5 * (chi[g] * chi[g] + chi[group.mul(g, g)]))
        .sum();
    sum / group.order() as f64
}

/// True if `chi` is a sum of the characters of irreps in `known` (with nonnegative
/// multiplicities `⟨χ, χ_μ⟩ / c_μ`).
fn made_of_known(group: &Group, chi: &[f64], known: &[RawIrrep]) -> bool {
    let order = group.order() as f64;
    let mut rest = chi.to_vec();
    for k in known {
        let c = inner(&k.characters, &k.characters) / order;
        let m = (inner(chi, &k.characters) / order / c).round();
        for (r, &x) in rest.iter_mut().zip(&k.characters) {
            *r -= m * x;
        }
    }
    rest.iter().all(|r| r.abs() < CHAR_TOL)
}

fn characters(rep: &[DMatrix<f64>]) -> Vec<f64> {
    rep.iter().map(|m| m.trace()).collect()
}

fn inner(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn same(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < CHAR_TOL)
}

/// SplitMix64 (Steele, Lea & Flood 2014): a small fixed-seed generator, so that the
/// decomposition (and the bases it picks) is the same on every run.
struct SplitMix64(u64);

impl SplitMix64 {
    /// Uniform in [−1, 1).
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }

    fn symmetric(&mut self, n: usize) -> DMatrix<f64> {
        let mut x = DMatrix::zeros(n, n);
        for i in 0..n {
            for j in i..n {
                let v = self.next();
                x[(i, j)] = v;
                x[(j, i)] = v;
            }
        }
        x
    }

    fn antisymmetric(&mut self, n: usize) -> DMatrix<f64> {
        let mut x = DMatrix::zeros(n, n);
        for i in 0..n {
            for j in i + 1..n {
                let v = self.next();
                x[(i, j)] = v;
                x[(j, i)] = -v;
            }
        }
        x
    }
}
