//! Any subgroup as a group of its own ([`Group::subgroup`]): complete sets of real irreps for
//! every subgroup class of `Ih`, `I`, `C8v`, `C7v`, `C6v` (the checks of `representations`),
//! Mulliken labels against standard character tables written out by hand, and axial subgroups
//! identical to what the stabiliser gives.

use crate::representations::check_all;
use nalgebra::{DMatrix, Rotation3, Vector3};
use std::time::Instant;
use symmetry::{Group, GroupError, Invariant, IrrepKind, Matrix3, Subgroup};

const TOL: f64 = 1e-10;

/// The golden ratio φ = (1 + √5)/2; 2 cos 72° = φ − 1, 2 cos 144° = −φ.
const PHI: f64 = 1.618_033_988_749_895;

fn parents() -> Vec<Group> {
    vec![
        Group::icosahedral_full(),
        Group::icosahedral(),
        Group::cyclic_v(8),
        Group::cyclic_v(7),
        Group::cyclic_v(6),
    ]
}

/// The subgroup's elements are the parent's (in `parent_index` order) and its table is the
/// parent's.
fn check_embedding(g: &Group, sub: &Subgroup) {
    let s = &sub.group;
    assert_eq!(sub.parent_index.len(), s.order());
    for (i, &p) in sub.parent_index.iter().enumerate() {
        assert!((s.element(i) - g.element(p)).amax() < TOL);
    }
    for a in 0..s.order() {
        for b in 0..s.order() {
            assert_eq!(
                sub.parent_index[s.mul(a, b)],
                g.mul(sub.parent_index[a], sub.parent_index[b])
            );
        }
    }
}

/// A subgroup is axial when its rotations share one axis and its improper elements are
/// mirrors through it (or there are none): then it is named as the stabiliser names it.
fn is_axial(g: &Group, elements: &[usize]) -> bool {
    let rotations: Vec<&Matrix3> = elements
        .iter()
        .map(|&x| g.element(x))
        .filter(|m| m.determinant() > 0.0)
        .collect();
    let improper: Vec<&Matrix3> = elements
        .iter()
        .map(|&x| g.element(x))
        .filter(|m| m.determinant() < 0.0)
        .collect();
    let axis = rotations
        .iter()
        .find(|m| (**m - Matrix3::identity()).amax() > 1e-9)
        .map(|m| axis_of(m));
    let mirrors_ok = improper.iter().all(|m| {
        (m.trace() - 1.0).abs() < 1e-9 && axis.is_none_or(|a| (**m * a - a).amax() < 1e-9)
    });
    let shared = axis.is_none_or(|a| rotations.iter().all(|m| (**m * a - a).amax() < 1e-9));
    shared && mirrors_ok && (improper.is_empty() || improper.len() == rotations.len())
}

/// The unit axis of a rotation ≠ I (up to sign).
fn axis_of(r: &Matrix3) -> Vector3<f64> {
    let m = r + r.transpose() - Matrix3::identity() * (r.trace() - 1.0);
    let col = (0..3)
        .max_by(|&a, &b| m.column(a).norm().total_cmp(&m.column(b).norm()))
        .unwrap();
    m.column(col).normalize()
}

/// Every subgroup class of the five parents gives a group whose irreps pass every check of
/// `representations` (group axioms; homomorphism; orthogonal matrices; characters constant on
/// classes; Schur's relations by kind, with J² = −I commuting with D for complex type;
/// ⟨χ_μ, χ_ν⟩ = c_μ δ_μν; Σ d²/c = |Σ|; Σ c = number of classes; trivial irrep first), with
/// unique names, as many irreps as classes when all are of real type, and the lattice's name
/// (the stabiliser's for axial subgroups: `C1v` for `Cs`, no primes).
#[test]
fn every_subgroup_class_has_a_complete_set_of_irreps() {
    for g in parents() {
        let lattice = g.subgroup_lattice();
        let start = Instant::now();
        for class in lattice.classes() {
            let sub = g.subgroup(&class.representative).expect("a subgroup");
            let s = &sub.group;
            let mut sorted = sub.parent_index.clone();
            sorted.sort_unstable();
            assert_eq!(
                sorted,
                class.representative,
                "{} in {}",
                class.name,
                g.name()
            );
            check_embedding(&g, &sub);
            check_all(s);
            let mut names: Vec<&str> = s.irreps().iter().map(|r| r.name()).collect();
            names.sort_unstable();
            names.dedup();
            assert_eq!(
                names.len(),
                s.irreps().len(),
                "{}: duplicate names",
                s.name()
            );
            assert!(names.iter().all(|n| !n.contains('#')), "{}", s.name());
            if s.irreps().iter().all(|r| r.kind() == IrrepKind::Real) {
                assert_eq!(s.irreps().len(), s.classes().len(), "{}", s.name());
            }
            let expected_name = if class.order == g.order() {
                g.name().to_string()
            } else if is_axial(&g, &class.representative) {
                match class.name.trim_end_matches('\'') {
                    "Cs" => "C1v".to_string(),
                    other => other.to_string(),
                }
            } else {
                class.name.clone()
            };
            assert_eq!(s.name(), expected_name, "in {}", g.name());
            // Non-axial subgroups keep the parent's order of elements.
            if !is_axial(&g, &class.representative) {
                assert_eq!(sub.parent_index, class.representative);
            }
        }
        println!(
            "{}: {} subgroup classes as groups in {:.1} ms",
            g.name(),
            lattice.classes().len(),
            start.elapsed().as_secs_f64() * 1e3
        );
    }
}

/// Conjugate subgroups are isomorphic by conjugation, which keeps every geometric quantity
/// the labels are read from: all 164 subgroups of `Ih` pass the checks, with the same labels
/// (and kinds and dimensions) as their class representative.
#[test]
fn conjugate_subgroups_get_the_same_labels() {
    let g = Group::icosahedral_full();
    let lattice = g.subgroup_lattice();
    let summary = |s: &Group| -> Vec<(String, usize, IrrepKind)> {
        s.irreps()
            .iter()
            .map(|r| (r.name().to_string(), r.dim(), r.kind()))
            .collect()
    };
    let mut count = 0;
    for class in lattice.classes() {
        let rep = g.subgroup(&class.representative).unwrap();
        for c in &class.conjugates {
            let sub = g.subgroup(c).unwrap();
            check_embedding(&g, &sub);
            check_all(&sub.group);
            assert_eq!(sub.group.name(), rep.group.name());
            assert_eq!(summary(&sub.group), summary(&rep.group), "{}", class.name);
            count += 1;
        }
    }
    assert_eq!(count, 164);
}

/// Restricting an irrep μ of the parent to Σ decomposes it into Σ's irreps with nonnegative
/// integer multiplicities `m_ν = ⟨χ_μ|Σ, χ_ν⟩ / c_ν` and `Σ_ν m_ν d_ν = d_μ`; the trivial
/// irrep's multiplicity is `dim Fix_μ(Σ)` (as the isotropy module computes it).
#[test]
fn restrictions_decompose_into_the_subgroup_irreps() {
    for g in parents() {
        let lattice = g.subgroup_lattice();
        for class in lattice.classes() {
            let sub = g.subgroup(&class.representative).unwrap();
            let s = &sub.group;
            let order = s.order() as f64;
            for mu in g.irreps() {
                let chi: Vec<f64> = sub.parent_index.iter().map(|&p| mu.character(p)).collect();
                let mut dim = 0;
                for (k, nu) in s.irreps().iter().enumerate() {
                    let c = nu.kind().commutant_dim() as f64;
                    let m = (0..s.order())
                        .map(|x| chi[x] * nu.character(x))
                        .sum::<f64>()
                        / order
                        / c;
                    assert!((m - m.round()).abs() < 1e-9 && m > -1e-9);
                    dim += m.round() as usize * nu.dim();
                    if k == 0 {
                        assert_eq!(m.round() as usize, g.fixed_dim(mu, &class.representative));
                    }
                }
                assert_eq!(dim, mu.dim(), "{} restricted to {}", mu.name(), s.name());
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// Standard character tables, written out by hand.
//
// Every non-axial subgroup of Ih is a rotation group K (C1, C2, C3, C5, D2, D3, D5, T, I) or
// K × Ci. The tables of K are the textbook ones, by geometric class of a rotation (its angle,
// from the trace 1 + 2 cos θ, and for D2 its axis); for K × Ci the irreps are μg, μu with
// χ(−R) = ±χ(R), listed all g then all u. Complex-type irreps (the pair ¹E, ²E of C3, C5, T as
// one real 2-D irrep) have the character of the pair, 2 cos(2πk/n) at C_n.
// ---------------------------------------------------------------------------------------

/// Geometric class of a rotation: `E`, `C5` (72°), `C5^2` (144°), `C3` (120°), `C2` (180°),
/// and for D2 the half-turn axis, `C2z`, `C2y`, `C2x`.
fn class_key(r: &Matrix3, d2: bool) -> &'static str {
    let t = r.trace();
    let is = |v: f64| (t - v).abs() < 1e-6;
    if is(3.0) {
        "E"
    } else if is(PHI) {
        "C5"
    } else if is(1.0 - PHI) {
        "C5^2"
    } else if is(0.0) {
        "C3"
    } else if is(-1.0) && d2 {
        let a = axis_of(r);
        let c = (0..3)
            .max_by(|&i, &j| a[i].abs().total_cmp(&a[j].abs()))
            .unwrap();
        assert!(
            (a[c].abs() - 1.0).abs() < 1e-9,
            "D2's axes are the coordinate axes"
        );
        ["C2x", "C2y", "C2z"][c]
    } else if is(-1.0) {
        "C2"
    } else {
        panic!("not a rotation of I: trace {t}")
    }
}

/// A row of a table: label, characters by column, complex type.
type Row = (&'static str, Vec<f64>, bool);

struct Table {
    columns: Vec<&'static str>,
    rows: Vec<Row>,
}

fn rotation_table(k: &str) -> Table {
    let (a, b) = (PHI - 1.0, -PHI); // 2 cos 72°, 2 cos 144°
    let (columns, rows): (Vec<&str>, Vec<Row>) = match k {
        "C1" => (vec!["E"], vec![("A", vec![1.0], false)]),
        "C2" => (
            vec!["E", "C2"],
            vec![("A", vec![1.0, 1.0], false), ("B", vec![1.0, -1.0], false)],
        ),
        "C3" => (
            vec!["E", "C3"],
            vec![("A", vec![1.0, 1.0], false), ("E", vec![2.0, -1.0], true)],
        ),
        "C5" => (
            vec!["E", "C5", "C5^2"],
            vec![
                ("A", vec![1.0, 1.0, 1.0], false),
                ("E1", vec![2.0, a, b], true),
                ("E2", vec![2.0, b, a], true),
            ],
        ),
        "D2" => (
            vec!["E", "C2z", "C2y", "C2x"],
            vec![
                ("A", vec![1.0, 1.0, 1.0, 1.0], false),
                ("B1", vec![1.0, 1.0, -1.0, -1.0], false),
                ("B2", vec![1.0, -1.0, 1.0, -1.0], false),
                ("B3", vec![1.0, -1.0, -1.0, 1.0], false),
            ],
        ),
        "D3" => (
            vec!["E", "C3", "C2"],
            vec![
                ("A1", vec![1.0, 1.0, 1.0], false),
                ("A2", vec![1.0, 1.0, -1.0], false),
                ("E", vec![2.0, -1.0, 0.0], false),
            ],
        ),
        "D5" => (
            vec!["E", "C5", "C5^2", "C2"],
            vec![
                ("A1", vec![1.0, 1.0, 1.0, 1.0], false),
                ("A2", vec![1.0, 1.0, 1.0, -1.0], false),
                ("E1", vec![2.0, a, b, 0.0], false),
                ("E2", vec![2.0, b, a, 0.0], false),
            ],
        ),
        "T" => (
            vec!["E", "C3", "C2"],
            vec![
                ("A", vec![1.0, 1.0, 1.0], false),
                ("E", vec![2.0, -1.0, 2.0], true),
                ("T", vec![3.0, 0.0, -1.0], false),
            ],
        ),
        "I" => (
            vec!["E", "C5", "C5^2", "C3", "C2"],
            vec![
                ("A", vec![1.0, 1.0, 1.0, 1.0, 1.0], false),
                ("T1", vec![3.0, PHI, 1.0 - PHI, 0.0, -1.0], false),
                ("T2", vec![3.0, 1.0 - PHI, PHI, 0.0, -1.0], false),
                ("G", vec![4.0, -1.0, -1.0, 1.0, 0.0], false),
                ("H", vec![5.0, 0.0, 0.0, -1.0, 1.0], false),
            ],
        ),
        _ => unreachable!("{k}"),
    };
    Table { columns, rows }
}

/// Checks the subgroup named `name` of `Ih` (class representative) against the table of its
/// rotation group `k`, times Ci when `with_inversion`.
fn check_table(name: &str, k: &str, with_inversion: bool) -> Vec<String> {
    let g = Group::icosahedral_full();
    let lattice = g.subgroup_lattice();
    let class = &lattice.classes()[lattice.find(name).expect(name)];
    let sub = g.subgroup(&class.representative).expect(name);
    let s = &sub.group;
    assert_eq!(s.name(), name);
    let table = rotation_table(k);
    let mut expected: Vec<(String, Vec<f64>, bool, f64)> = Vec::new();
    let parities: &[(&str, f64)] = if with_inversion {
        &[("g", 1.0), ("u", -1.0)]
    } else {
        &[("", 1.0)]
    };
    for &(mark, sign) in parities {
        for (label, chi, complex) in &table.rows {
            expected.push((format!("{label}{mark}"), chi.clone(), *complex, sign));
        }
    }
    let names: Vec<String> = s.irreps().iter().map(|r| r.name().to_string()).collect();
    let expected_names: Vec<String> = expected.iter().map(|e| e.0.clone()).collect();
    assert_eq!(
        names, expected_names,
        "{name}: labels in the standard order"
    );
    let d2 = k == "D2";
    for (irrep, (label, chi, complex, sign)) in s.irreps().iter().zip(&expected) {
        assert_eq!(
            irrep.kind(),
            if *complex {
                IrrepKind::Complex
            } else {
                IrrepKind::Real
            },
            "{name} {label}: kind"
        );
        for x in 0..s.order() {
            let m = s.element(x);
            let (rotation, factor) = if m.determinant() > 0.0 {
                (*m, 1.0)
            } else {
                (-m, *sign)
            };
            let col = table
                .columns
                .iter()
                .position(|c| *c == class_key(&rotation, d2))
                .expect("a class of the table");
            let want = factor * chi[col];
            assert!(
                (irrep.character(x) - want).abs() < 1e-9,
                "{name} {label}: χ = {} at element {x}, table {want}",
                irrep.character(x)
            );
        }
    }
    names
}

#[test]
fn d5d_d3d_d2h_th_t_c2h_match_the_standard_tables() {
    check_table("D5d", "D5", true);
    check_table("D3d", "D3", true);
    check_table("D2h", "D2", true);
    check_table("Th", "T", true);
    check_table("T", "T", false);
    check_table("C2h", "C2", true);
}

#[test]
fn other_non_axial_subgroups_match_the_standard_tables() {
    check_table("S10", "C5", true);
    check_table("S6", "C3", true);
    check_table("Ci", "C1", true);
    check_table("D2", "D2", false);
    check_table("D3", "D3", false);
    check_table("D5", "D5", false);
    check_table("I", "I", false);
    // The rotation subgroups of I: same tables.
    let i = Group::icosahedral();
    let lattice = i.subgroup_lattice();
    for name in ["D2", "D3", "D5", "T"] {
        let class = &lattice.classes()[lattice.find(name).unwrap()];
        let sub = i.subgroup(&class.representative).unwrap();
        let labels: Vec<&str> = sub.group.irreps().iter().map(|r| r.name()).collect();
        let table = rotation_table(name);
        let want: Vec<&str> = table.rows.iter().map(|r| r.0).collect();
        assert_eq!(labels, want, "{name} in I");
    }
}

// ---------------------------------------------------------------------------------------
// Axial subgroups: exactly the stabiliser's result.
// ---------------------------------------------------------------------------------------

fn assert_same(a: &Subgroup, b: &Subgroup, what: &str) {
    assert_eq!(a.group.name(), b.group.name(), "{what}");
    assert_eq!(a.parent_index, b.parent_index, "{what}");
    assert_eq!(a.group.elements(), b.group.elements(), "{what}");
    assert_eq!(a.group.irreps().len(), b.group.irreps().len(), "{what}");
    for (x, y) in a.group.irreps().iter().zip(b.group.irreps()) {
        assert_eq!(x.name(), y.name(), "{what}");
        assert_eq!(x.kind(), y.kind(), "{what}");
        assert_eq!(x.matrices(), y.matrices(), "{what} {}", x.name());
        assert_eq!(x.complex_structure(), y.complex_structure(), "{what}");
    }
}

/// Directions to keep: every rotation axis of the group (both ways), a few generic directions
/// in mirror planes and a generic direction.
fn directions(g: &Group) -> Vec<Vector3<f64>> {
    let mut out = Vec::new();
    for m in g.elements() {
        if m.determinant() > 0.0 && (m - Matrix3::identity()).amax() > 1e-9 {
            let a = axis_of(m);
            out.push(a);
            out.push(-a);
        }
        if m.determinant() < 0.0 && (m.trace() - 1.0).abs() < 1e-9 {
            // A point of the mirror plane: w − (w·n) n for the normal n (axis of −m).
            let n = axis_of(&(-m));
            let w = Vector3::new(0.31, -0.52, 0.77);
            out.push((w - n * w.dot(&n)).normalize());
        }
    }
    out.push(Vector3::new(0.213, -0.377, 0.901).normalize());
    out
}

/// For every direction `v`, `subgroup_along(elements, v)` of the stabiliser's elements is
/// exactly the stabiliser of `v` (same name, element order, irreps, matrices), and
/// `subgroup` agrees with it when `v` is oriented as `subgroup` orients the axis (positive z,
/// else y, else x). In `Ih` this covers C5v, C3v, C2v, C1v and C1, in `I` C5, C3, C2 and C1.
#[test]
fn axial_subgroups_are_exactly_the_stabilisers() {
    let q = *Rotation3::from_euler_angles(0.3, -1.1, 0.7).matrix();
    let mut groups = parents();
    groups.push(Group::icosahedral_full().conjugated(&q, "Ih (rotated)"));
    for g in groups {
        let mut names = std::collections::BTreeSet::new();
        for v in directions(&g) {
            let st = g.stabilizer(&[Invariant::Direction(v)]).unwrap();
            let along = g.subgroup_along(&st.parent_index, v).unwrap();
            assert_same(&along, &st, &format!("{} along {v:?}", g.name()));
            let canonical = [v.z, v.y, v.x]
                .into_iter()
                .find(|c| c.abs() > 1e-9)
                .is_some_and(|c| c > 0.0);
            if canonical {
                let plain = g.subgroup(&st.parent_index).unwrap();
                assert_same(&plain, &st, &format!("{} at {v:?}", g.name()));
            }
            names.insert(st.group.name().to_string());
        }
        println!("{}: stabilisers compared: {names:?}", g.name());
        if g.name() == "Ih" {
            let want = ["C1", "C1v", "C2v", "C3v", "C5v"];
            assert!(want.iter().all(|n| names.contains(*n)), "{names:?}");
        }
        if g.name() == "I" {
            let want = ["C1", "C2", "C3", "C5"];
            assert!(want.iter().all(|n| names.contains(*n)), "{names:?}");
        }
    }
}

/// In `C_nv` (axis z, first mirror y = 0) the rotation subgroup `C_m` and the `C_mv` through
/// the first mirror are the crate's own `Group::cyclic(m)` and `Group::cyclic_v(m)`: same
/// elements in the same order, same irreps and matrices.
#[test]
fn axial_subgroups_of_cnv_are_the_crate_axial_groups() {
    for n in [6, 7, 8, 12] {
        let g = Group::cyclic_v(n);
        for m in (1..=n).filter(|m| n.is_multiple_of(*m)) {
            let step = n / m;
            let rotations: Vec<usize> = (0..n).step_by(step).collect();
            let mut with_mirror = rotations.clone();
            with_mirror.extend(rotations.iter().map(|k| n + k));
            for (elements, model) in [
                (rotations, Group::cyclic(m)),
                (with_mirror, Group::cyclic_v(m)),
            ] {
                let sub = g.subgroup(&elements).unwrap();
                let what = format!("{} in C{n}v", model.name());
                assert_eq!(sub.group.name(), model.name(), "{what}");
                for (a, b) in sub.group.elements().iter().zip(model.elements()) {
                    assert!((a - b).amax() < 1e-12, "{what}");
                }
                for (x, y) in sub.group.irreps().iter().zip(model.irreps()) {
                    assert_eq!(x.name(), y.name());
                    assert_eq!(x.matrices(), y.matrices(), "{what}");
                }
            }
        }
    }
}

/// Subgroups of a computed subgroup: the parent's irreps are themselves computed, and the
/// result is again complete (D5d → D5, S10, C5v, C2h, …; Th → D2h, T, S6, …).
#[test]
fn subgroups_of_computed_subgroups() {
    let ih = Group::icosahedral_full();
    let lattice = ih.subgroup_lattice();
    for name in ["D5d", "Th", "D3d", "D2h"] {
        let class = &lattice.classes()[lattice.find(name).unwrap()];
        let parent = ih.subgroup(&class.representative).unwrap().group;
        for c in parent.subgroup_lattice().classes() {
            let sub = parent.subgroup(&c.representative).unwrap();
            check_embedding(&parent, &sub);
            check_all(&sub.group);
        }
    }
}

#[test]
fn sets_that_are_not_subgroups_are_errors() {
    let g = Group::icosahedral_full();
    for bad in [vec![], vec![1], vec![0, 1], vec![0, 500]] {
        let err = g.subgroup(&bad).expect_err("not a subgroup");
        assert!(matches!(err, GroupError::NotAGroup(_)), "{err}");
    }
    // Duplicates and any order are accepted.
    let lattice = g.subgroup_lattice();
    let d5d = &lattice.classes()[lattice.find("D5d").unwrap()];
    let mut shuffled: Vec<usize> = d5d.representative.iter().rev().copied().collect();
    shuffled.push(0);
    let sub = g.subgroup(&shuffled).unwrap();
    assert_eq!(sub.parent_index, d5d.representative);
}

/// A 2-D complex-type irrep has the standard complex structure, and the decomposition is
/// deterministic (the same matrices on every call).
#[test]
fn complex_structure_and_determinism() {
    let g = Group::icosahedral_full();
    let lattice = g.subgroup_lattice();
    for name in ["T", "Th", "S10", "S6"] {
        let rep = &lattice.classes()[lattice.find(name).unwrap()].representative;
        let a = g.subgroup(rep).unwrap();
        let b = g.subgroup(rep).unwrap();
        assert_same(&a, &b, name);
        for r in a.group.irreps() {
            if r.kind() == IrrepKind::Complex {
                let j = DMatrix::from_row_slice(2, 2, &[0.0, -1.0, 1.0, 0.0]);
                assert_eq!(r.complex_structure(), Some(&j), "{name} {}", r.name());
            }
        }
    }
}
