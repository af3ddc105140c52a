//! Subgroups up to conjugacy: the subgroup lattice of a [`Group`], with Schoenflies names.
//!
//! How the classes are enumerated is documented on [`Group::subgroup_lattice`], how they are
//! named on [`SubgroupClass`].

use crate::group::Group;
use crate::MATRIX_TOL;
use std::collections::{HashMap, HashSet};

/// One conjugacy class of subgroups of a group.
///
/// # Names
/// A subgroup `Σ ⊂ O(3)` is named by its structure, as in chemistry: its rotation subgroup
/// `R = Σ ∩ SO(3)` is `C_k` (cyclic), `D_k` (dihedral, order 2k), `T`, `O` or `I`; if `Σ`
/// has improper elements, either `−I ∈ Σ` (then `Σ = R × {±I}`: `Ci`, `C_kh` for even k,
/// `S_2k` for odd k (`S6 = C3i`, `S10 = C5i`), `D_kh` for even k, `D_kd` for odd k, `Th`, `Oh`,
/// `Ih`), or `Σ ≅ H` for a rotation group `H ⊃ R` of index 2, the improper elements being
/// `−h` for `h ∈ H ∖ R` (`Cs` from `C2 ⊃ C1`; `C_kv` from `D_k ⊃ C_k`; `C_kh` (k odd) or `S_2k`
/// (k even) from `C_2k ⊃ C_k`; `D_kh` (k odd) or `D_kd` (k even) from `D_2k ⊃ D_k`; `Td` from
/// `O ⊃ T`). Everything is read off element orders, determinants and the presence of `−I`.
///
/// In a parent group of type `C_nv` (its rotations about one axis, every improper element a
/// mirror through it) the crate's own convention is kept: a single mirror is `C1v` (= `Cs`),
/// and the `C_mv`-type subgroups, which form **two** classes when `n/m` is even, are told
/// apart by their mirrors. The parent's *first mirror* is its improper element of lowest
/// index (for [`Group::cyclic_v`] the plane y = 0, element `n`). A subgroup whose mirrors
/// include a conjugate of the first mirror is `C<m>v`; one whose mirrors are all of the other
/// class is `C<m>v'`. For [`Group::cyclic_v`]`(n)`, `n` even: the mirror `s r^j` (element
/// `n + j`) is the plane through the z-axis and the direction at angle `−πj/n` from the
/// x-axis; `C<m>v` has its mirrors at the angles `2πi/n` (through the vertices of the regular
/// n-gon with a vertex on the x-axis, y = 0 among them), `C<m>v'` at the odd multiples of
/// `π/n` (through the edge midpoints; e.g. `C1v'` in `C2v` is the plane x = 0). When `n/m` is
/// odd a `C_mv` contains mirrors of both kinds and is named `C<m>v`; for odd n all mirrors are
/// conjugate and no prime occurs.
///
/// [`Group::stabilizer`] names its result as an axial group of its own, so a lone mirror of
/// `Ih` is `C1v` there and `Cs` in the lattice of `Ih`.
#[derive(Debug, Clone, PartialEq)]
pub struct SubgroupClass {
    /// Schoenflies name, e.g. `C5v`, `D3d`, `C2v'` (see the type's documentation).
    pub name: String,
    /// Order of each subgroup in the class.
    pub order: usize,
    /// Number of conjugates (the index of the normaliser of a representative).
    pub size: usize,
    /// Whether the subgroups are cyclic.
    pub cyclic: bool,
    /// The representative: element indices in the parent, sorted. It is the conjugate whose
    /// sorted index list is lexicographically least (for [`Group::cyclic_v`], the `C<m>v`
    /// representative contains the first mirror `n` and the `C<m>v'` one the mirror `n + 1`).
    pub representative: Vec<usize>,
    /// A small set of elements that generates the representative.
    pub generators: Vec<usize>,
    /// All conjugates (the representative first), each sorted.
    pub conjugates: Vec<Vec<usize>>,
}

/// The subgroups of a group up to conjugacy, with the partial order "is contained in, up to
/// conjugacy". Built by [`Group::subgroup_lattice`]; it belongs to that group (element
/// indices refer to it).
#[derive(Debug, Clone)]
pub struct SubgroupLattice {
    group_order: usize,
    classes: Vec<SubgroupClass>,
    index: HashMap<Vec<u64>, usize>,
    /// `below[a]`: the classes with a conjugate inside the representative of `a` (`a` too).
    below: Vec<Vec<usize>>,
}

impl SubgroupLattice {
    /// The classes, by increasing order (ties: by representative); the first is the trivial
    /// subgroup and the last the whole group.
    pub fn classes(&self) -> &[SubgroupClass] {
        &self.classes
    }

    /// Order of the group the lattice belongs to.
    pub fn group_order(&self) -> usize {
        self.group_order
    }

    /// The class of the subgroup with these elements (any order, duplicates allowed), or
    /// `None` if they are not a subgroup of the group.
    pub fn class_of(&self, elements: &[usize]) -> Option<usize> {
        if elements.iter().any(|&g| g >= self.group_order) {
            return None;
        }
        self.index.get(&bits(elements, self.group_order)).copied()
    }

    /// The first class with this name.
    pub fn find(&self, name: &str) -> Option<usize> {
        self.classes.iter().position(|c| c.name == name)
    }

    /// True if some subgroup of class `sub` lies inside some subgroup of class `sup` (then
    /// every subgroup of `sup` contains a conjugate of `sub`). Reflexive. `false` for indices
    /// out of range.
    pub fn is_subconjugate(&self, sub: usize, sup: usize) -> bool {
        self.below.get(sup).is_some_and(|b| b.contains(&sub))
    }

    /// The classes `b` with a conjugate inside class `a`'s subgroups (including `a`), by
    /// increasing index. Empty for an index out of range.
    pub fn subconjugates(&self, a: usize) -> &[usize] {
        self.below.get(a).map_or(&[], Vec::as_slice)
    }

    /// The maximal proper classes below `a`: `b ≠ a` below `a` with no class strictly in
    /// between (the edges of the Hasse diagram of the lattice up to conjugacy).
    pub fn maximal_subconjugates(&self, a: usize) -> Vec<usize> {
        let below = self.subconjugates(a);
        below
            .iter()
            .copied()
            .filter(|&b| {
                b != a
                    && !below
                        .iter()
                        .any(|&c| c != a && c != b && self.is_subconjugate(b, c))
            })
            .collect()
    }
}

/// Schoenflies type of a finite subgroup of O(3), from its structure.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum PointGroup {
    C(usize),
    Cv(usize),
    Ch(usize),
    S(usize),
    D(usize),
    Dh(usize),
    Dd(usize),
    Ci,
    Cs,
    T,
    Th,
    Td,
    O,
    Oh,
    I,
    Ih,
    /// A structure that no finite subgroup of O(3) has (not reached for valid groups).
    Unknown(usize),
}

impl PointGroup {
    pub(crate) fn name(self) -> String {
        match self {
            PointGroup::C(k) => format!("C{k}"),
            PointGroup::Cv(k) => format!("C{k}v"),
            PointGroup::Ch(k) => format!("C{k}h"),
            PointGroup::S(k) => format!("S{k}"),
            PointGroup::D(k) => format!("D{k}"),
            PointGroup::Dh(k) => format!("D{k}h"),
            PointGroup::Dd(k) => format!("D{k}d"),
            PointGroup::Ci => "Ci".into(),
            PointGroup::Cs => "Cs".into(),
            PointGroup::T => "T".into(),
            PointGroup::Th => "Th".into(),
            PointGroup::Td => "Td".into(),
            PointGroup::O => "O".into(),
            PointGroup::Oh => "Oh".into(),
            PointGroup::I => "I".into(),
            PointGroup::Ih => "Ih".into(),
            PointGroup::Unknown(order) => format!("G{order}"),
        }
    }
}

/// How subgroups are named: chemistry's names, or the `C_nv` conventions (`C1v`, primes).
#[derive(Debug, Clone, Copy)]
enum Naming {
    Schoenflies,
    /// A `C_nv` parent; the conjugacy class (in the parent) of its first mirror.
    AxialMirrors {
        first_mirror_class: usize,
    },
}

impl Group {
    /// The subgroup generated by `generators`: sorted element indices (`[0]` for none).
    ///
    /// Panics if an index is out of range.
    pub fn generate(&self, generators: &[usize]) -> Vec<usize> {
        let n = self.order();
        let mut inside = vec![false; n];
        inside[0] = true;
        let mut elements = vec![0];
        let mut next = 0;
        while next < elements.len() {
            let e = elements[next];
            for &g in generators {
                let p = self.mul(g, e);
                if !inside[p] {
                    inside[p] = true;
                    elements.push(p);
                }
            }
            next += 1;
        }
        elements.sort_unstable();
        elements
    }

    /// True if the set of indices `elements` (any order, duplicates allowed) is a subgroup;
    /// false for an empty list or an index out of range.
    pub fn is_subgroup(&self, elements: &[usize]) -> bool {
        let n = self.order();
        if elements.is_empty() || elements.iter().any(|&g| g >= n) {
            return false;
        }
        let set = bits(elements, n);
        elements
            .iter()
            .all(|&a| elements.iter().all(|&b| has(&set, self.mul(a, b))))
    }

    /// The conjugate `g H g⁻¹` of the subgroup `h`, sorted.
    ///
    /// Panics if an index is out of range.
    pub fn conjugate_subgroup(&self, g: usize, h: &[usize]) -> Vec<usize> {
        let gi = self.inverse(g);
        let mut c: Vec<usize> = h.iter().map(|&x| self.mul(self.mul(g, x), gi)).collect();
        c.sort_unstable();
        c
    }

    /// The normaliser `N(H) = {g : g H g⁻¹ = H}` of the subgroup `h`, sorted.
    ///
    /// Panics if an index is out of range.
    pub fn normalizer(&self, h: &[usize]) -> Vec<usize> {
        let n = self.order();
        let set = bits(h, n);
        (0..n)
            .filter(|&g| {
                let gi = self.inverse(g);
                h.iter().all(|&x| has(&set, self.mul(self.mul(g, x), gi)))
            })
            .collect()
    }

    /// The Schoenflies name of the subgroup `elements` of this group (see [`SubgroupClass`]):
    /// by structure, with the `C_nv` conventions (`C1v`; `C<m>v'` when no mirror is conjugate
    /// to the first one) when this group is of type `C_nv`. The elements must form a
    /// subgroup (see [`Group::is_subgroup`]); the name of any other set means nothing.
    ///
    /// Panics if an index is out of range.
    pub fn subgroup_name(&self, elements: &[usize]) -> String {
        self.name_with(elements, self.naming())
    }

    /// All subgroups up to conjugacy (see [`Group::subgroup_lattice`]).
    pub fn subgroup_classes(&self) -> Vec<SubgroupClass> {
        self.subgroup_lattice().classes
    }

    /// The subgroups up to conjugacy, by closure, with their names (see [`SubgroupClass`])
    /// and the containment relation up to conjugacy.
    ///
    /// # Enumeration
    /// Every subgroup is found by closure, up to conjugacy: start from the trivial subgroup and,
    /// for each class representative `H` found so far and each element `g ∉ H`, form the subgroup
    /// `⟨H, g⟩` generated by `H` and `g`. This is complete: a subgroup `K ≠ 1` has a maximal
    /// subgroup `M`, so `K = ⟨M, g⟩` for any `g ∈ K ∖ M`; by induction on the order some
    /// conjugate `yMy⁻¹` is a representative, and then `yKy⁻¹ = ⟨yMy⁻¹, ygy⁻¹⟩` is reached from
    /// it. New subgroups are compared by element set with every conjugate of every class found
    /// so far, so each class is built once. The counts agree with GAP's
    /// `ConjugacyClassesSubgroups` (`scripts/gap_subgroups.g`, tested in `tests/lattice_gap.rs`).
    ///
    /// Cost: for each class, one closure per element of the group, plus all conjugates of
    /// each new class: about 4 ms for `Ih`, 4 ms for `C60v`, 20 ms for `C120v` (less than
    /// building the group itself).
    pub fn subgroup_lattice(&self) -> SubgroupLattice {
        let n = self.order();
        let mut found: Vec<SubgroupClass> = Vec::new();
        let mut index: HashMap<Vec<u64>, usize> = HashMap::new();
        self.add_class(&mut found, &mut index, vec![0], Vec::new());
        let mut next = 0;
        while next < found.len() {
            let rep = bits(&found[next].representative, n);
            let gens = found[next].generators.clone();
            for g in 0..n {
                if has(&rep, g) {
                    continue;
                }
                let mut with_g = gens.clone();
                with_g.push(g);
                let k = self.generate(&with_g);
                if !index.contains_key(&bits(&k, n)) {
                    self.add_class(&mut found, &mut index, k, with_g);
                }
            }
            next += 1;
        }

        // Order by (order, representative) and renumber the index.
        let mut perm: Vec<usize> = (0..found.len()).collect();
        perm.sort_by(|&a, &b| {
            (found[a].order, &found[a].representative)
                .cmp(&(found[b].order, &found[b].representative))
        });
        let mut new_id = vec![0; found.len()];
        for (new, &old) in perm.iter().enumerate() {
            new_id[old] = new;
        }
        let mut slots: Vec<Option<SubgroupClass>> = found.into_iter().map(Some).collect();
        let classes: Vec<SubgroupClass> =
            perm.iter().filter_map(|&old| slots[old].take()).collect();
        for id in index.values_mut() {
            *id = new_id[*id];
        }

        let naming = self.naming();
        let classes: Vec<SubgroupClass> = classes
            .into_iter()
            .map(|mut c| {
                c.name = self.name_with(&c.representative, naming);
                c
            })
            .collect();

        let rep_bits: Vec<Vec<u64>> = classes.iter().map(|c| bits(&c.representative, n)).collect();
        let below = (0..classes.len())
            .map(|a| {
                (0..classes.len())
                    .filter(|&b| {
                        classes[a].order.is_multiple_of(classes[b].order)
                            && classes[b]
                                .conjugates
                                .iter()
                                .any(|k| k.iter().all(|&x| has(&rep_bits[a], x)))
                    })
                    .collect()
            })
            .collect();
        SubgroupLattice {
            group_order: n,
            classes,
            index,
            below,
        }
    }

    /// Records the class of the new subgroup `elements` (generated by `generators`): all its
    /// conjugates, the lexicographically least as representative.
    fn add_class(
        &self,
        found: &mut Vec<SubgroupClass>,
        index: &mut HashMap<Vec<u64>, usize>,
        elements: Vec<usize>,
        generators: Vec<usize>,
    ) {
        let n = self.order();
        let mut seen: HashSet<Vec<u64>> = HashSet::new();
        let mut conjugates: Vec<(Vec<usize>, usize)> = Vec::new();
        for x in 0..n {
            let c = self.conjugate_subgroup(x, &elements);
            if seen.insert(bits(&c, n)) {
                conjugates.push((c, x));
            }
        }
        conjugates.sort();
        let x = conjugates.first().map_or(0, |c| c.1);
        let xi = self.inverse(x);
        let generators: Vec<usize> = generators
            .iter()
            .map(|&g| self.mul(self.mul(x, g), xi))
            .collect();
        let generators = self.reduce_generators(generators);
        let conjugates: Vec<Vec<usize>> = conjugates.into_iter().map(|c| c.0).collect();
        let representative = conjugates.first().cloned().unwrap_or_else(|| vec![0]);
        let order = representative.len();
        let cyclic = representative
            .iter()
            .any(|&g| self.element_order(g) == order);
        let id = found.len();
        for c in &conjugates {
            index.insert(bits(c, n), id);
        }
        found.push(SubgroupClass {
            name: String::new(),
            order,
            size: conjugates.len(),
            cyclic,
            representative,
            generators,
            conjugates,
        });
    }

    /// Drops generators that the others already generate.
    fn reduce_generators(&self, mut gens: Vec<usize>) -> Vec<usize> {
        gens.retain(|&g| g != 0);
        let order = self.generate(&gens).len();
        let mut i = 0;
        while i < gens.len() {
            let mut fewer = gens.clone();
            fewer.remove(i);
            if self.generate(&fewer).len() == order {
                gens = fewer;
            } else {
                i += 1;
            }
        }
        gens
    }

    pub(crate) fn is_minus_identity(&self, g: usize) -> bool {
        (self.element(g) + crate::Matrix3::identity()).abs().max() < MATRIX_TOL
    }

    pub(crate) fn is_proper(&self, g: usize) -> bool {
        self.element(g).determinant() > 0.0
    }

    /// The naming convention for this group's subgroups.
    fn naming(&self) -> Naming {
        let all: Vec<usize> = (0..self.order()).collect();
        match self.point_group(&all) {
            PointGroup::Cv(_) | PointGroup::Cs => (0..self.order())
                .find(|&g| !self.is_proper(g))
                .map_or(Naming::Schoenflies, |m| Naming::AxialMirrors {
                    first_mirror_class: self.class_of(m),
                }),
            _ => Naming::Schoenflies,
        }
    }

    fn name_with(&self, elements: &[usize], naming: Naming) -> String {
        let pg = self.point_group(elements);
        match naming {
            Naming::Schoenflies => pg.name(),
            Naming::AxialMirrors { first_mirror_class } => {
                let mirrors: Vec<usize> = elements
                    .iter()
                    .copied()
                    .filter(|&g| !self.is_proper(g))
                    .collect();
                let mut name = match pg {
                    PointGroup::Cs => "C1v".to_string(),
                    other => other.name(),
                };
                if !mirrors.is_empty()
                    && !mirrors
                        .iter()
                        .any(|&m| self.class_of(m) == first_mirror_class)
                {
                    name.push('\'');
                }
                name
            }
        }
    }

    /// The Schoenflies type of the subgroup `elements`, from element orders, determinants and
    /// the presence of `−I` (see [`SubgroupClass`]).
    pub(crate) fn point_group(&self, elements: &[usize]) -> PointGroup {
        let rotations: Vec<usize> = elements
            .iter()
            .copied()
            .filter(|&g| self.is_proper(g))
            .collect();
        let r = rotations.len();
        let max_order = rotations
            .iter()
            .map(|&g| self.element_order(g))
            .max()
            .unwrap_or(1);
        #[derive(Clone, Copy)]
        enum Rot {
            C(usize),
            D(usize),
            T,
            O,
            I,
        }
        let rot = if max_order == r {
            Rot::C(r)
        } else if r == 12 && max_order == 3 {
            Rot::T
        } else if r == 24 && max_order == 4 {
            Rot::O
        } else if r == 60 && max_order == 5 {
            Rot::I
        } else {
            Rot::D(r / 2)
        };
        if r == elements.len() {
            return match rot {
                Rot::C(k) => PointGroup::C(k),
                Rot::D(k) => PointGroup::D(k),
                Rot::T => PointGroup::T,
                Rot::O => PointGroup::O,
                Rot::I => PointGroup::I,
            };
        }
        if elements.iter().any(|&g| self.is_minus_identity(g)) {
            return match rot {
                Rot::C(1) => PointGroup::Ci,
                Rot::C(k) if k.is_multiple_of(2) => PointGroup::Ch(k),
                Rot::C(k) => PointGroup::S(2 * k),
                Rot::D(k) if k.is_multiple_of(2) => PointGroup::Dh(k),
                Rot::D(k) => PointGroup::Dd(k),
                Rot::T => PointGroup::Th,
                Rot::O => PointGroup::Oh,
                Rot::I => PointGroup::Ih,
            };
        }
        // Σ ≅ H ⊃ R of index 2; H is cyclic iff Σ is.
        let cyclic = elements
            .iter()
            .any(|&g| self.element_order(g) == elements.len());
        match rot {
            Rot::C(1) => PointGroup::Cs,
            Rot::C(k) if !cyclic => PointGroup::Cv(k),
            Rot::C(k) if !k.is_multiple_of(2) => PointGroup::Ch(k),
            Rot::C(k) => PointGroup::S(2 * k),
            Rot::D(k) if !k.is_multiple_of(2) => PointGroup::Dh(k),
            Rot::D(k) => PointGroup::Dd(k),
            Rot::T => PointGroup::Td,
            Rot::O | Rot::I => PointGroup::Unknown(elements.len()),
        }
    }
}

/// The set `elements` of `0..n` as a bit set.
pub(crate) fn bits(elements: &[usize], n: usize) -> Vec<u64> {
    let mut b = vec![0u64; n.div_ceil(64)];
    for &g in elements {
        b[g / 64] |= 1 << (g % 64);
    }
    b
}

/// Membership in a bit set from [`bits`].
pub(crate) fn has(set: &[u64], g: usize) -> bool {
    set.get(g / 64).is_some_and(|w| w & (1 << (g % 64)) != 0)
}
