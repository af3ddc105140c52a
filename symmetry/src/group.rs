//! The [`Group`] type: elements, multiplication table, inverses, classes and irreps.

use crate::irrep::Irrep;
use crate::MATRIX_TOL;

/// A 3×3 real matrix (an element of O(3)).
pub type Matrix3 = nalgebra::Matrix3<f64>;

/// Errors from building or naming groups.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum GroupError {
    /// A group name that is not one of `C<n>`, `C<n>v`, `I`, `Ih`.
    #[error("unknown group '{0}': expected C<n>, C<n>v (n >= 1), I or Ih")]
    UnknownName(String),
    /// The matrices given are not closed under multiplication (or not orthogonal).
    #[error("the matrices do not form a group: {0}")]
    NotAGroup(String),
    /// A subgroup whose structure is not one of the supported families.
    #[error("unsupported subgroup structure: {0}")]
    Unsupported(String),
    /// An irrep or subgroup lattice used with a group it does not belong to.
    #[error("mismatched group data: {0}")]
    Mismatch(String),
}

/// A finite subgroup of O(3) with a complete set of real irreducible representations.
///
/// Elements are indexed `0..order()`; element 0 is the identity. Products follow matrix
/// multiplication: `mul(a, b)` is the index of `elements[a] * elements[b]` (apply `b`, then
/// `a`), and every irrep satisfies `D(mul(a, b)) = D(a) D(b)`.
#[derive(Debug, Clone)]
pub struct Group {
    name: String,
    elements: Vec<Matrix3>,
    table: Vec<usize>,
    inverse: Vec<usize>,
    classes: Vec<Vec<usize>>,
    class_of: Vec<usize>,
    irreps: Vec<Irrep>,
}

impl Group {
    /// Builds a group from its elements (identity first) and its irreps.
    ///
    /// Computes the multiplication table, inverses and conjugacy classes; fails if the
    /// elements are not orthogonal or not closed under multiplication. The irreps are
    /// trusted here and checked by the test suite.
    pub(crate) fn from_parts(
        name: impl Into<String>,
        elements: Vec<Matrix3>,
        irreps: Vec<Irrep>,
    ) -> Result<Self, GroupError> {
        let name = name.into();
        let n = elements.len();
        if n == 0 || (elements[0] - Matrix3::identity()).abs().max() > MATRIX_TOL {
            return Err(GroupError::NotAGroup(format!(
                "{name}: element 0 is not the identity"
            )));
        }
        for (i, g) in elements.iter().enumerate() {
            if (g.transpose() * g - Matrix3::identity()).abs().max() > MATRIX_TOL {
                return Err(GroupError::NotAGroup(format!(
                    "{name}: element {i} is not orthogonal"
                )));
            }
        }
        let mut table = vec![0; n * n];
        for a in 0..n {
            for b in 0..n {
                let p = elements[a] * elements[b];
                table[a * n + b] = find(&elements, &p).ok_or_else(|| {
                    GroupError::NotAGroup(format!("{name}: product of {a} and {b} is missing"))
                })?;
            }
        }
        let inverse: Vec<usize> = (0..n)
            .map(|a| (0..n).find(|&b| table[a * n + b] == 0))
            .collect::<Option<_>>()
            .ok_or_else(|| GroupError::NotAGroup(format!("{name}: an inverse is missing")))?;
        let mut class_of = vec![usize::MAX; n];
        let mut classes: Vec<Vec<usize>> = Vec::new();
        for a in 0..n {
            if class_of[a] != usize::MAX {
                continue;
            }
            let mut class: Vec<usize> = (0..n)
                .map(|g| table[table[g * n + a] * n + inverse[g]])
                .collect();
            class.sort_unstable();
            class.dedup();
            for &c in &class {
                class_of[c] = classes.len();
            }
            classes.push(class);
        }
        Ok(Self {
            name,
            elements,
            table,
            inverse,
            classes,
            class_of,
            irreps,
        })
    }

    /// Replaces the irreps (for groups whose irreps are computed from their table and
    /// classes, see [`Group::subgroup`]).
    pub(crate) fn set_irreps(&mut self, irreps: Vec<Irrep>) {
        self.irreps = irreps;
    }

    /// The order of the group `name` (as [`Group::by_name`] reads it) without building it;
    /// `None` for a name that is not a group.
    pub fn order_of(name: &str) -> Option<usize> {
        match name {
            "I" => return Some(60),
            "Ih" => return Some(120),
            _ => {}
        }
        let rest = name.strip_prefix('C')?;
        let (digits, mirrors) = match rest.strip_suffix('v') {
            Some(d) => (d, true),
            None => (rest, false),
        };
        if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
            return None;
        }
        let n: usize = digits.parse().ok().filter(|&n| n > 0 && n <= 10_000)?;
        Some(if mirrors { 2 * n } else { n })
    }

    /// Parses `C<n>`, `C<n>v` (n ≥ 1), `I` or `Ih` (case of the letters as written here).
    pub fn by_name(name: &str) -> Result<Self, GroupError> {
        let unknown = || GroupError::UnknownName(name.to_string());
        match name {
            "I" => return Ok(Self::icosahedral()),
            "Ih" => return Ok(Self::icosahedral_full()),
            _ => {}
        }
        let rest = name.strip_prefix('C').ok_or_else(unknown)?;
        let (digits, mirrors) = match rest.strip_suffix('v') {
            Some(d) => (d, true),
            None => (rest, false),
        };
        if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
            return Err(unknown());
        }
        let n: usize = digits.parse().map_err(|_| unknown())?;
        if n == 0 || n > 10_000 {
            return Err(unknown());
        }
        Ok(if mirrors {
            Self::cyclic_v(n)
        } else {
            Self::cyclic(n)
        })
    }

    /// The group's name, e.g. `C7v`, `Ih`.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Number of elements.
    pub fn order(&self) -> usize {
        self.elements.len()
    }

    /// All elements as orthogonal matrices; index 0 is the identity.
    pub fn elements(&self) -> &[Matrix3] {
        &self.elements
    }

    /// The matrix of element `g`.
    pub fn element(&self, g: usize) -> &Matrix3 {
        &self.elements[g]
    }

    /// Index of the product `a·b` (apply `b` first).
    pub fn mul(&self, a: usize, b: usize) -> usize {
        self.table[a * self.order() + b]
    }

    /// Index of the inverse of `a`.
    pub fn inverse(&self, a: usize) -> usize {
        self.inverse[a]
    }

    /// The order of element `g`: the least k ≥ 1 with g^k = identity.
    pub fn element_order(&self, g: usize) -> usize {
        let mut k = 1;
        let mut p = g;
        while p != 0 {
            p = self.mul(g, p);
            k += 1;
        }
        k
    }

    /// Conjugacy classes, each a sorted list of element indices; the first is `{identity}`.
    pub fn classes(&self) -> &[Vec<usize>] {
        &self.classes
    }

    /// Index (into [`Group::classes`]) of the class of element `g`.
    pub fn class_of(&self, g: usize) -> usize {
        self.class_of[g]
    }

    /// The real irreducible representations; the first is the trivial one.
    pub fn irreps(&self) -> &[Irrep] {
        &self.irreps
    }

    /// The irrep with the given name, if any.
    pub fn irrep(&self, name: &str) -> Option<&Irrep> {
        self.irreps.iter().find(|r| r.name() == name)
    }

    /// The index of the element whose matrix is `m` (within [`MATRIX_TOL`]).
    pub fn find(&self, m: &Matrix3) -> Option<usize> {
        find(&self.elements, m)
    }

    /// The same abstract group acting in rotated coordinates: every element `R` becomes
    /// `Q R Qᵀ` (`Q` orthogonal). Irrep matrices, table and classes are unchanged, so a mesh
    /// rotated by `Q` carries this group.
    pub fn conjugated(&self, q: &Matrix3, name: impl Into<String>) -> Self {
        let mut g = self.clone();
        g.name = name.into();
        for e in &mut g.elements {
            *e = q * *e * q.transpose();
        }
        g
    }
}

fn find(elements: &[Matrix3], m: &Matrix3) -> Option<usize> {
    elements
        .iter()
        .position(|e| (e - m).abs().max() < MATRIX_TOL)
}
