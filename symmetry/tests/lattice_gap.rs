//! Subgroup lattices against GAP, an independent source.
//!
//! `tests/data/gap_subgroups.json` was written by `scripts/gap_subgroups.g` (GAP 4.12,
//! `ConjugacyClassesSubgroups` of matrix groups in the crate's coordinates, each checked in GAP
//! to be isomorphic to `DihedralGroup(2n)`, `CyclicGroup(n)`, `AlternatingGroup(5)` or
//! `SmallGroup(120, 35)`). For each group the tests compare
//! - the number of classes and the multiset of (order, class size);
//! - a bijection of classes that keeps order, class size, cyclicity, the numbers of rotations
//!   and of mirrors, `−I ∈ Σ` (icosahedral), whether a conjugate of the first mirror y = 0 lies
//!   in Σ (`C_nv`; it must be exactly the unprimed names) and the abstract structure
//!   (GAP's `StructureDescription`, against the structure each Schoenflies name stands for),
//!   and that maps the relation "contains a conjugate of" onto GAP's.

use serde_json::Value;
use symmetry::{Group, SubgroupLattice};

/// The attributes compared, for one class.
#[derive(Debug, Clone, PartialEq)]
struct Class {
    order: usize,
    size: usize,
    cyclic: bool,
    structure: String,
    rotations: usize,
    mirrors: usize,
    inversion: Option<bool>,
    first_mirror: Option<bool>,
}

struct Lattice {
    classes: Vec<Class>,
    /// `below[i][j]`: class j has a conjugate inside class i.
    below: Vec<Vec<bool>>,
}

fn gap_data() -> Value {
    serde_json::from_str(include_str!("data/gap_subgroups.json")).expect("valid JSON")
}

fn gap_lattice(all: &Value, name: &str) -> Lattice {
    let classes = all[name]["classes"].as_array().expect("classes");
    let n = classes.len();
    let int = |v: &Value| v.as_u64().expect("integer") as usize;
    let mut below = vec![vec![false; n]; n];
    let classes = classes
        .iter()
        .enumerate()
        .map(|(i, c)| {
            for j in c["subconjugate"].as_array().expect("list") {
                below[i][int(j)] = true;
            }
            Class {
                order: int(&c["order"]),
                size: int(&c["size"]),
                cyclic: c["cyclic"].as_bool().expect("bool"),
                structure: c["structure"].as_str().expect("string").to_string(),
                rotations: int(&c["rotations"]),
                mirrors: int(&c["mirrors"]),
                inversion: c.get("inversion").map(|v| v.as_bool().expect("bool")),
                first_mirror: c.get("first_mirror").map(|v| v.as_bool().expect("bool")),
            }
        })
        .collect();
    Lattice { classes, below }
}

/// The abstract group a Schoenflies name stands for, in GAP's `StructureDescription` notation
/// (`D2k` is the dihedral group of order 2k, `S3` that of order 6). Derived by hand:
/// `C_kv ≅ D_k ≅ D(2k)`,
/// `C2v ≅ D2 ≅ C2h ≅ C2 × C2`, `S6 = C3 × Ci ≅ C6`, `S10 ≅ C10`, `D2h ≅ C2³`,
/// `D3d = D3 × Ci ≅ D12`, `D5d ≅ D20`, `T ≅ A4`, `Th ≅ C2 × A4`, `I ≅ A5`, `Ih ≅ C2 × A5`.
fn structure_of(name: &str) -> String {
    let name = name.trim_end_matches('\'');
    let k = |s: &str| -> usize { s.parse().expect("an integer in the name") };
    match name {
        "C1" => "1".into(),
        "Ci" | "Cs" | "C1v" => "C2".into(),
        "C2v" | "D2" | "C2h" => "C2 x C2".into(),
        "C3v" | "D3" => "S3".into(),
        "S6" => "C6".into(),
        "S10" => "C10".into(),
        "D2h" => "C2 x C2 x C2".into(),
        "D3d" => "D12".into(),
        "D5d" => "D20".into(),
        "T" => "A4".into(),
        "Th" => "C2 x A4".into(),
        "I" => "A5".into(),
        "Ih" => "C2 x A5".into(),
        _ => {
            if let Some(m) = name.strip_prefix('C').and_then(|r| r.strip_suffix('v')) {
                format!("D{}", 2 * k(m))
            } else if let Some(m) = name.strip_prefix('C') {
                format!("C{}", k(m))
            } else if let Some(m) = name.strip_prefix('D') {
                format!("D{}", 2 * k(m))
            } else {
                panic!("no structure known for {name}")
            }
        }
    }
}

fn our_lattice(g: &Group, lattice: &SubgroupLattice, three_d: bool, mirrors_v: bool) -> Lattice {
    let first_mirror = (0..g.order()).find(|&x| g.element(x).determinant() < 0.0);
    let classes = lattice
        .classes()
        .iter()
        .map(|c| {
            let rep = &c.representative;
            let det = |x: usize| g.element(x).determinant();
            let is_mirror = |x: usize| det(x) < 0.0 && (g.element(x).trace() - 1.0).abs() < 1e-9;
            let minus_i = rep
                .iter()
                .any(|&x| (g.element(x) + symmetry::Matrix3::identity()).abs().max() < 1e-9);
            let has_first =
                first_mirror.is_some_and(|s| rep.iter().any(|&x| g.class_of(x) == g.class_of(s)));
            if mirrors_v && rep.iter().any(|&x| det(x) < 0.0) {
                // The prime in the name says exactly that no first-type mirror is present.
                assert_eq!(
                    c.name.ends_with('\''),
                    !has_first,
                    "{}: {}",
                    g.name(),
                    c.name
                );
            }
            Class {
                order: c.order,
                size: c.size,
                cyclic: c.cyclic,
                structure: structure_of(&c.name),
                rotations: rep.iter().filter(|&&x| det(x) > 0.0).count(),
                mirrors: rep.iter().filter(|&&x| is_mirror(x)).count(),
                inversion: three_d.then_some(minus_i),
                first_mirror: mirrors_v.then_some(has_first),
            }
        })
        .collect();
    let n = lattice.classes().len();
    let below = (0..n)
        .map(|i| (0..n).map(|j| lattice.is_subconjugate(j, i)).collect())
        .collect();
    Lattice { classes, below }
}

/// Backtracking for a bijection `perm` (ours → GAP's) keeping the attributes and the relation.
fn find_bijection(a: &Lattice, b: &Lattice, perm: &mut Vec<usize>, used: &mut [bool]) -> bool {
    let i = perm.len();
    if i == a.classes.len() {
        return true;
    }
    for j in 0..b.classes.len() {
        if used[j] || a.classes[i] != b.classes[j] {
            continue;
        }
        let consistent =
            perm.iter().enumerate().all(|(i2, &j2)| {
                a.below[i][i2] == b.below[j][j2] && a.below[i2][i] == b.below[j2][j]
            }) && a.below[i][i] == b.below[j][j];
        if !consistent {
            continue;
        }
        used[j] = true;
        perm.push(j);
        if find_bijection(a, b, perm, used) {
            return true;
        }
        perm.pop();
        used[j] = false;
    }
    false
}

fn group_for(key: &str) -> Group {
    Group::by_name(key).expect("a group name the crate parses")
}

fn compare(key: &str) -> (usize, usize) {
    let all = gap_data();
    let g = group_for(key);
    let lattice = g.subgroup_lattice();
    let three_d = key.starts_with('I');
    let mirrors_v = key.ends_with('v');
    let ours = our_lattice(&g, &lattice, three_d, mirrors_v);
    let gap = gap_lattice(&all, key);
    assert_eq!(
        ours.classes.len(),
        gap.classes.len(),
        "{key}: number of classes of subgroups"
    );
    assert_eq!(
        all[key]["abstract_class_count"].as_u64(),
        Some(gap.classes.len() as u64),
        "{key}: GAP's matrix group and abstract group agree"
    );
    let pairs = |l: &Lattice| {
        let mut p: Vec<(usize, usize)> = l.classes.iter().map(|c| (c.order, c.size)).collect();
        p.sort_unstable();
        p
    };
    assert_eq!(
        pairs(&ours),
        pairs(&gap),
        "{key}: (order, class size) pairs"
    );
    let cyc = |l: &Lattice| {
        let mut p: Vec<(usize, bool)> = l.classes.iter().map(|c| (c.order, c.cyclic)).collect();
        p.sort_unstable();
        p
    };
    assert_eq!(cyc(&ours), cyc(&gap), "{key}: cyclic classes");
    let mut used = vec![false; gap.classes.len()];
    assert!(
        find_bijection(&ours, &gap, &mut Vec::new(), &mut used),
        "{key}: no bijection of classes keeps every attribute and the containment relation"
    );
    let total: usize = ours.classes.iter().map(|c| c.size).sum();
    (ours.classes.len(), total)
}

#[test]
fn c7v_lattice_matches_gap() {
    // D7: C1, C7, the 7 conjugate mirrors, C7v itself; 1 + 1 + 7 + 1 = 10 subgroups.
    assert_eq!(compare("C7v"), (4, 10));
}

#[test]
fn c8v_lattice_matches_gap() {
    // τ(8) + σ(8) = 4 + 15 = 19 subgroups in 11 classes.
    assert_eq!(compare("C8v"), (11, 19));
}

#[test]
fn icosahedral_lattices_match_gap() {
    // A5: 59 subgroups in 9 classes; A5 × C2: 22 classes.
    assert_eq!(compare("I"), (9, 59));
    assert_eq!(compare("Ih").0, 22);
}

#[test]
fn other_axial_lattices_match_gap() {
    let all = gap_data();
    let keys: Vec<String> = all
        .as_object()
        .expect("object")
        .keys()
        .filter(|k| k.starts_with('C'))
        .cloned()
        .collect();
    assert!(keys.len() >= 10);
    for key in keys {
        compare(&key);
    }
}

#[test]
fn a_wrong_lattice_is_detected() {
    let all = gap_data();
    // C8v is not C7v.
    let c8v = Group::cyclic_v(8);
    let l8 = c8v.subgroup_lattice();
    let ours = our_lattice(&c8v, &l8, false, true);
    assert_ne!(ours.classes.len(), gap_lattice(&all, "C7v").classes.len());
    // One containment edge removed: C2 no longer below C2v (both kinds) in C8v.
    let gap = gap_lattice(&all, "C8v");
    let mut broken = ours;
    let c2 = l8.find("C2").expect("C2");
    for name in ["C2v", "C2v'"] {
        let i = l8.find(name).expect(name);
        broken.below[i][c2] = false;
    }
    let mut used = vec![false; gap.classes.len()];
    assert!(!find_bijection(&broken, &gap, &mut Vec::new(), &mut used));
    // Swapped primes (C2v ↔ C2v' attributes) are detected too.
    let mut swapped = our_lattice(&c8v, &l8, false, true);
    let (a, b) = (l8.find("C2v").expect("C2v"), l8.find("C1v").expect("C1v"));
    swapped.classes[a].first_mirror = Some(false);
    swapped.classes[b].first_mirror = Some(false);
    let mut used = vec![false; gap.classes.len()];
    assert!(!find_bijection(&swapped, &gap, &mut Vec::new(), &mut used));
}
