//! Isotropy subgroups and fixed-point spaces against results derived by hand.
//!
//! Expected values come from the theory (Golubitsky, Stewart & Schaeffer vol. II, ch. XIII:
//! `D_m` on the plane; the icosahedral tables of Hoyle, *Pattern Formation*, 2006) and from
//! character sums done by hand, written out in each test; none is read off the
//! implementation's output. Generic checks (fixed spaces are invariant, the isotropy criterion
//! agrees with a numerical stabiliser, `±v` conjugacy by brute force over the whole group)
//! close the file.

use nalgebra::{DMatrix, DVector};
use symmetry::{Group, GroupError, IrrepIsotropy, IrrepKind};

const TOL: f64 = 1e-9;

/// Isotropy classes expected for one irrep: (name, dim Fix, ±v conjugate).
type Expected = Vec<(&'static str, usize, bool)>;

fn gcd(a: usize, b: usize) -> usize {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

fn isotropy(g: &Group, irrep: &str) -> IrrepIsotropy {
    let lattice = g.subgroup_lattice();
    let r = g.irrep(irrep).expect("irrep exists");
    g.isotropy(&lattice, r).expect("same group")
}

/// The isotropy classes as (name, dim Fix, ±v conjugate), in the crate's order.
fn summary(iso: &IrrepIsotropy) -> Vec<(String, usize, bool)> {
    iso.subgroups
        .iter()
        .map(|s| (s.name.clone(), s.fixed_dim, s.halves_conjugate()))
        .collect()
}

fn owned(expected: &[(&str, usize, bool)]) -> Vec<(String, usize, bool)> {
    expected
        .iter()
        .map(|&(n, d, h)| (n.to_string(), d, h))
        .collect()
}

/// Some element of the whole group maps `v` to `−v` (brute force, no normaliser).
fn reversed_by_some_element(g: &Group, irrep: &str, v: &DVector<f64>) -> bool {
    let r = g.irrep(irrep).expect("irrep");
    (0..g.order()).any(|x| (r.matrix(x) * v + v).amax() < TOL)
}

/// `C_nv` on `E_k`: the image of `C_nv` is `D_m`, `m = n / gcd(n, k)`, acting faithfully on the
/// plane, and the kernel is the rotations by multiples of `2π / gcd(n, k)`, i.e. `r^j` with
/// `m | j` (`D(r^j)` is the rotation by `2πjk/n`). Isotropy subgroups of `D_m` on ℝ²: the
/// identity (generic points, Fix = the plane) and the stabilisers of points on mirror lines,
/// a single mirror each — one class of mirrors for m odd, two for m even. Pulled back to
/// `C_nv`: `C_dv` (d = gcd) with the kernel; for m even also `C_dv'`. Reversal of `v` on a
/// mirror line: for m even the half-turn of `D_m` (central) maps `v` to `−v`; for m odd no
/// element of `D_m` does (the rotations move the line, the mirrors through `−v`'s line are the
/// same as through `v`'s and fix it; `D_m` has no −I) — two distinct half-branches.
#[test]
fn cnv_on_two_dimensional_irreps() {
    let cases = [
        (7, 1),
        (7, 2),
        (7, 3),
        (8, 1),
        (8, 2),
        (8, 3),
        (6, 1),
        (6, 2),
        (3, 1),
        (4, 1),
        (5, 1),
        (5, 2),
        (12, 1),
        (12, 2),
        (12, 3),
        (12, 4),
        (12, 5),
    ];
    for (n, k) in cases {
        let g = Group::cyclic_v(n);
        let e = format!("E{k}");
        let iso = isotropy(&g, &e);
        let d = gcd(n, k);
        let m = n / d;
        let kernel: Vec<usize> = (0..n).filter(|j| j.is_multiple_of(m)).collect();
        assert_eq!(iso.kernel, kernel, "C{n}v {e}: kernel");
        let (cdv, cdv2, cd) = (format!("C{d}v"), format!("C{d}v'"), format!("C{d}"));
        let expected = if !m.is_multiple_of(2) {
            vec![(cdv.as_str(), 1, false), (cd.as_str(), 2, false)]
        } else {
            vec![
                (cdv.as_str(), 1, true),
                (cdv2.as_str(), 1, true),
                (cd.as_str(), 2, false),
            ]
        };
        assert_eq!(summary(&iso), owned(&expected), "C{n}v {e}");

        // The representatives: the kernel with the mirrors s r^j (element n + j), j ≡ 0 mod m
        // (unprimed, it contains the first mirror s) or j ≡ 1 mod m (primed).
        let with_mirrors = |offset: usize| -> Vec<usize> {
            let mut s = kernel.clone();
            s.extend(kernel.iter().map(|j| n + j + offset));
            s
        };
        let axial: Vec<_> = iso.axial().collect();
        assert_eq!(axial[0].elements, with_mirrors(0), "C{n}v {e}: C{d}v");
        // D(s) = diag(1, −1) fixes e1: the fixed line of C_dv is the first coordinate axis.
        let v0 = axial[0].axis().expect("axial");
        assert!((v0[0].abs() - 1.0).abs() < TOL, "C{n}v {e}: v = ±e1");
        if m.is_multiple_of(2) {
            assert_eq!(axial[1].elements, with_mirrors(1), "C{n}v {e}: C{d}v'");
            // D(s r) = diag(1, −1) R(2πk/n) fixes the direction at angle −πk/n.
            let v1 = axial[1].axis().expect("axial");
            let t = -std::f64::consts::PI * k as f64 / n as f64;
            assert!(
                (v1[0] * t.cos() + v1[1] * t.sin()).abs() > 1.0 - TOL,
                "C{n}v {e}: v' at angle −πk/n"
            );
        }
        for s in &axial {
            let v = s.axis().expect("axial");
            assert_eq!(
                reversed_by_some_element(&g, &e, &v),
                m.is_multiple_of(2),
                "C{n}v {e} {}: ±v conjugate iff m even",
                s.name
            );
        }
        // The generic stabiliser is the kernel itself.
        assert_eq!(iso.subgroups.last().map(|s| &s.elements), Some(&kernel));
    }
}

/// `C_nv` on A2, B1, B2: `V = ℝ`, the stabiliser of any `v ≠ 0` is the kernel of the character
/// (a normal subgroup of index 2), which is therefore the only isotropy subgroup, axial;
/// an element with character −1 maps `v` to `−v`. Kernels: A2 — the rotations `C_n`; B1 —
/// `r^(2i)` and `s r^(2i)`, i.e. `C_(n/2)v` with the first mirror; B2 — `r^(2i)` and
/// `s r^(2i+1)`, the other mirrors: `C_(n/2)v'`.
#[test]
fn cnv_on_one_dimensional_irreps() {
    for n in [1, 2, 3, 4, 6, 7, 8, 12] {
        let g = Group::cyclic_v(n);
        let even: Vec<usize> = (0..n).filter(|j| j.is_multiple_of(2)).collect();
        let mut cases = vec![("A2", (0..n).collect::<Vec<_>>(), format!("C{n}"))];
        if n.is_multiple_of(2) {
            let h = n / 2;
            let b1: Vec<usize> = even
                .iter()
                .copied()
                .chain(even.iter().map(|j| n + j))
                .collect();
            let b2: Vec<usize> = even
                .iter()
                .copied()
                .chain(even.iter().map(|j| n + j + 1))
                .collect();
            cases.push(("B1", b1, format!("C{h}v")));
            cases.push(("B2", b2, format!("C{h}v'")));
        }
        for (irrep, kernel, name) in cases {
            let iso = isotropy(&g, irrep);
            assert_eq!(iso.kernel, kernel, "C{n}v {irrep}: kernel");
            assert_eq!(
                summary(&iso),
                owned(&[(name.as_str(), 1, true)]),
                "C{n}v {irrep}"
            );
            let s = &iso.subgroups[0];
            assert_eq!(s.elements, kernel);
            let rev = s.reversing.expect("an element reverses v");
            let chi = g.irrep(irrep).expect("irrep").character(rev);
            assert!((chi + 1.0).abs() < TOL, "C{n}v {irrep}: χ(reversing) = −1");
        }
    }
}

/// The trivial irrep: `V = ℝ` with everything acting as 1, so the group itself is the only
/// isotropy subgroup, axial, and nothing reverses `v`.
#[test]
fn trivial_irrep() {
    for g in [
        Group::cyclic(5),
        Group::cyclic_v(6),
        Group::icosahedral(),
        Group::icosahedral_full(),
    ] {
        let name = g.name().to_string();
        let trivial = g.irreps()[0].name().to_string();
        let iso = isotropy(&g, &trivial);
        assert_eq!(summary(&iso), owned(&[(name.as_str(), 1, false)]), "{name}");
        assert_eq!(iso.kernel, (0..g.order()).collect::<Vec<_>>());
    }
}

/// `C_n`: the 2-D `E_k` are of complex type. A rotation acting as a nontrivial rotation of the
/// plane fixes only 0, so every fixed space is 0 or the whole plane (a complex subspace), the
/// kernel `r^j`, `m | j` (`m = n / gcd(n, k)`) is the only isotropy subgroup, with dimension 2,
/// and there is no axial subgroup. On B (n even), the kernel `C_(n/2)` is axial and `r` (χ = −1)
/// reverses `v`.
#[test]
fn cyclic_groups_complex_type() {
    for n in [3, 5, 6, 8, 12] {
        let g = Group::cyclic(n);
        let lattice = g.subgroup_lattice();
        for k in 1..n.div_ceil(2) {
            let e = format!("E{k}");
            let r = g.irrep(&e).expect("irrep");
            assert_eq!(r.kind(), IrrepKind::Complex);
            let m = n / gcd(n, k);
            let iso = g.isotropy(&lattice, r).expect("same group");
            let kernel: Vec<usize> = (0..n).filter(|j| j.is_multiple_of(m)).collect();
            assert_eq!(iso.kernel, kernel);
            let cd = format!("C{}", gcd(n, k));
            assert_eq!(summary(&iso), owned(&[(cd.as_str(), 2, false)]), "C{n} {e}");
            assert_eq!(iso.axial().count(), 0);
            for c in lattice.classes() {
                let d = g.fixed_dim(r, &c.representative);
                assert!(d == 0 || d == 2, "C{n} {e} {}: dim {d}", c.name);
            }
        }
        if n.is_multiple_of(2) {
            let iso = isotropy(&g, "B");
            let h = format!("C{}", n / 2);
            assert_eq!(summary(&iso), owned(&[(h.as_str(), 1, true)]));
            assert_eq!(iso.subgroups[0].reversing, Some(1));
        }
    }
}

/// The golden ratio.
const PHI: f64 = 1.618_033_988_749_895;

/// Characters of `I` by class E, C5 (72°), C5² (144°), C3, C2 (the standard table).
fn chi_i(irrep: &str) -> [f64; 5] {
    match irrep {
        "A" => [1.0, 1.0, 1.0, 1.0, 1.0],
        "T1" => [3.0, PHI, 1.0 - PHI, 0.0, -1.0],
        "T2" => [3.0, 1.0 - PHI, PHI, 0.0, -1.0],
        "G" => [4.0, -1.0, -1.0, 1.0, 0.0],
        "H" => [5.0, 0.0, 0.0, -1.0, 1.0],
        _ => unreachable!(),
    }
}

/// Element content of the subgroups of `Ih` by hand: numbers of rotations `R` and of improper
/// elements `−R` in the classes E, C5, C5², C3, C2 of `R`. A rotation group K contributes its
/// own content (C5 = {E, 2C5, 2C5²}, D_k adds k half-turns, T = {E, 8C3, 3C2}); K × Ci repeats
/// it with signs; the twisted groups `C_kv` (from `D_k ⊃ C_k`) and `Cs` (from `C2 ⊃ C1`) have
/// `−(half-turns)` = mirrors.
fn content(name: &str) -> ([usize; 5], [usize; 5]) {
    let rot = |n: &str| -> [usize; 5] {
        match n {
            "C1" => [1, 0, 0, 0, 0],
            "C2" => [1, 0, 0, 0, 1],
            "C3" => [1, 0, 0, 2, 0],
            "D2" => [1, 0, 0, 0, 3],
            "C5" => [1, 2, 2, 0, 0],
            "D3" => [1, 0, 0, 2, 3],
            "D5" => [1, 2, 2, 0, 5],
            "T" => [1, 0, 0, 8, 3],
            "I" => [1, 12, 12, 20, 15],
            _ => unreachable!(),
        }
    };
    let none = [0; 5];
    match name {
        "C1" | "C2" | "C3" | "D2" | "C5" | "D3" | "D5" | "T" | "I" => (rot(name), none),
        "Ci" => (rot("C1"), rot("C1")),
        "C2h" => (rot("C2"), rot("C2")),
        "S6" => (rot("C3"), rot("C3")),
        "D2h" => (rot("D2"), rot("D2")),
        "S10" => (rot("C5"), rot("C5")),
        "D3d" => (rot("D3"), rot("D3")),
        "D5d" => (rot("D5"), rot("D5")),
        "Th" => (rot("T"), rot("T")),
        "Ih" => (rot("I"), rot("I")),
        "Cs" => (rot("C1"), [0, 0, 0, 0, 1]),
        "C2v" => (rot("C2"), [0, 0, 0, 0, 2]),
        "C3v" => (rot("C3"), [0, 0, 0, 0, 3]),
        "C5v" => (rot("C5"), [0, 0, 0, 0, 5]),
        _ => unreachable!(),
    }
}

const IH_CLASSES: [&str; 22] = [
    "C1", "C2", "C3", "D2", "C5", "D3", "D5", "T", "I", "Ci", "C2h", "S6", "D2h", "S10", "D3d",
    "D5d", "Th", "Ih", "Cs", "C2v", "C3v", "C5v",
];

/// The class of a rotation of `I` (E, C5, C5², C3, C2) from its trace `1 + 2 cos θ`.
fn rotation_class(trace: f64) -> usize {
    [3.0, PHI, 1.0 - PHI, 0.0, -1.0]
        .iter()
        .position(|t| (t - trace).abs() < 1e-6)
        .expect("an icosahedral rotation")
}

/// Every class of subgroups of `Ih` has the element content written above (this checks the
/// names), and `dim Fix` of every irrep is the character sum
/// `(1/|Σ|) [Σ_c n_c χ(c) ± Σ_c m_c χ(c)]` (+ for μg, − for μu) from the hand table.
/// E.g. Hg on D2h = {E, 3C2, i, 3σ}: (5 + 3 + 5 + 3)/8 = 2; on D5d: (5 + 5·1)·2/20 = 1;
/// on D3d: (5 − 2 + 3)·2/12 = 1; T1u on C5v = {E, 2C5, 2C5², 5σ}, χ(σ) = −χ(C2) = 1:
/// (3 + 2φ + 2(1 − φ) + 5)/10 = 1.
#[test]
fn ih_fixed_dimensions_from_the_character_table() {
    let g = Group::icosahedral_full();
    let lattice = g.subgroup_lattice();
    for name in IH_CLASSES {
        let c = &lattice.classes()[lattice.find(name).expect(name)];
        let (rot, imp) = content(name);
        let mut ours = ([0usize; 5], [0usize; 5]);
        for &x in &c.representative {
            let m = g.element(x);
            if m.determinant() > 0.0 {
                ours.0[rotation_class(m.trace())] += 1;
            } else {
                ours.1[rotation_class(-m.trace())] += 1;
            }
        }
        assert_eq!(ours, (rot, imp), "{name}: element content");
        let order: usize = rot.iter().chain(&imp).sum();
        for base in ["A", "T1", "T2", "G", "H"] {
            let chi = chi_i(base);
            for (parity, sign) in [("g", 1.0), ("u", -1.0)] {
                let sum: f64 = (0..5)
                    .map(|c| rot[c] as f64 * chi[c] + sign * imp[c] as f64 * chi[c])
                    .sum();
                let expected = sum / order as f64;
                assert!((expected - expected.round()).abs() < 1e-9);
                let irrep = g.irrep(&format!("{base}{parity}")).expect("irrep");
                assert_eq!(
                    g.fixed_dim(irrep, &c.representative) as f64,
                    expected.round(),
                    "{base}{parity} on {name}"
                );
            }
        }
    }
    // The dimensions quoted in the brief, by hand.
    let hg = g.irrep("Hg").expect("Hg");
    let dim = |n: &str| {
        g.fixed_dim(
            hg,
            &lattice.classes()[lattice.find(n).expect(n)].representative,
        )
    };
    assert_eq!(
        (dim("D2h"), dim("D5d"), dim("D3d"), dim("Th")),
        (2, 1, 1, 0)
    );
}

/// Isotropy subgroups of every irrep of `Ih`, derived by hand from the fixed dimensions of the
/// previous test and the containments between the 22 classes (Σ is isotropy iff no subgroup
/// strictly containing it has the same dim Fix):
/// - u irreps: `−I` acts as −1 and is central, so it lies in every normaliser and reverses
///   every axial `v` (halves conjugate). g irreps: `−I` acts trivially (kernel ⊇ Ci).
/// - T1u (vectors): C5v, C3v, C2v (vertex, face, edge axes) axial; Cs (a mirror plane, dim 2);
///   C1 (3). C_k ⊂ C_kv has the same fixed line, so the rotation groups are not isotropy.
///   T2u has the same dimensions (Galois conjugate characters), hence the same list.
/// - T1g (pseudovectors): S10, S6, C2h axial (`C_k × Ci`, and `Cs ⊂ C2h` with the same line);
///   reversed by a half-turn perpendicular to the axis, which normalises them. Ci (3).
/// - Hg: D5d, D3d axial; D2h (dim 2, inside Th with dim 0); C2h (3); Ci (5). D5d and D3d are
///   self-normalising (6 and 10 conjugates: |N| = 120/6 = 20, 120/10 = 12) and act trivially on
///   their fixed lines: the two halves are distinct (transcritical).
/// - Gg: Th, D3d axial (self-normalising, 5 and 10 conjugates: halves distinct); S6 (2),
///   C2h (2); Ci (4). D2h ⊂ Th with the same line is not isotropy.
/// - Hu: D5, D3, C2v axial; D2 (2), Cs (2), C2 (3), C1 (5).
/// - Gu: T, D3, C3v, C2v axial; C3 (2), Cs (2), C2 (2), C1 (4). D2 ⊂ T with the same line.
/// - Au: I, axial (the kernel), reversed by −I.
#[test]
fn ih_isotropy_subgroups_by_hand() {
    let g = Group::icosahedral_full();
    let t = false;
    let expected: [(&str, Expected); 10] = [
        ("Ag", vec![("Ih", 1, t)]),
        (
            "T1g",
            vec![
                ("S10", 1, true),
                ("S6", 1, true),
                ("C2h", 1, true),
                ("Ci", 3, t),
            ],
        ),
        (
            "T2g",
            vec![
                ("S10", 1, true),
                ("S6", 1, true),
                ("C2h", 1, true),
                ("Ci", 3, t),
            ],
        ),
        (
            "Gg",
            vec![
                ("Th", 1, false),
                ("D3d", 1, false),
                ("S6", 2, t),
                ("C2h", 2, t),
                ("Ci", 4, t),
            ],
        ),
        (
            "Hg",
            vec![
                ("D5d", 1, false),
                ("D3d", 1, false),
                ("D2h", 2, t),
                ("C2h", 3, t),
                ("Ci", 5, t),
            ],
        ),
        ("Au", vec![("I", 1, true)]),
        (
            "T1u",
            vec![
                ("C5v", 1, true),
                ("C3v", 1, true),
                ("C2v", 1, true),
                ("Cs", 2, t),
                ("C1", 3, t),
            ],
        ),
        (
            "T2u",
            vec![
                ("C5v", 1, true),
                ("C3v", 1, true),
                ("C2v", 1, true),
                ("Cs", 2, t),
                ("C1", 3, t),
            ],
        ),
        (
            "Gu",
            vec![
                ("T", 1, true),
                ("C3v", 1, true),
                ("D3", 1, true),
                ("C2v", 1, true),
                ("C3", 2, t),
                ("Cs", 2, t),
                ("C2", 2, t),
                ("C1", 4, t),
            ],
        ),
        (
            "Hu",
            vec![
                ("D5", 1, true),
                ("D3", 1, true),
                ("C2v", 1, true),
                ("D2", 2, t),
                ("Cs", 2, t),
                ("C2", 3, t),
                ("C1", 5, t),
            ],
        ),
    ];
    let lattice = g.subgroup_lattice();
    for (irrep, list) in expected {
        let iso = g
            .isotropy(&lattice, g.irrep(irrep).expect("irrep"))
            .expect("same group");
        let mut ours = summary(&iso);
        let mut want = owned(&list);
        ours.sort();
        want.sort();
        assert_eq!(ours, want, "Ih {irrep}");
        let kernel = if irrep.ends_with('g') {
            if irrep == "Ag" {
                "Ih"
            } else {
                "Ci"
            }
        } else if irrep == "Au" {
            "I"
        } else {
            "C1"
        };
        assert_eq!(g.subgroup_name(&iso.kernel), kernel, "Ih {irrep}: kernel");
    }
}

/// Isotropy subgroups of the irreps of `I` (rotations only), by the same hand computation:
/// dims on C1, C2, C3, D2, C5, D3, D5, T, I are T1: 3 1 1 0 1 0 0 0 0, G: 4 2 2 1 0 1 0 1 0,
/// H: 5 3 1 2 1 1 1 0 0. T1, T2: C5, C3, C2 axial, reversed by a perpendicular half-turn (in
/// N(C_k) = D_k); G: T, D3 axial (self-normalising: halves distinct), C3, C2 (2); H: D5, D3
/// axial (self-normalising), D2 (2), C2 (3).
#[test]
fn i_isotropy_subgroups_by_hand() {
    let g = Group::icosahedral();
    let f = false;
    let expected: [(&str, Expected); 5] = [
        ("A", vec![("I", 1, f)]),
        (
            "T1",
            vec![
                ("C5", 1, true),
                ("C3", 1, true),
                ("C2", 1, true),
                ("C1", 3, f),
            ],
        ),
        (
            "T2",
            vec![
                ("C5", 1, true),
                ("C3", 1, true),
                ("C2", 1, true),
                ("C1", 3, f),
            ],
        ),
        (
            "G",
            vec![
                ("T", 1, false),
                ("D3", 1, false),
                ("C3", 2, f),
                ("C2", 2, f),
                ("C1", 4, f),
            ],
        ),
        (
            "H",
            vec![
                ("D5", 1, false),
                ("D3", 1, false),
                ("D2", 2, f),
                ("C2", 3, f),
                ("C1", 5, f),
            ],
        ),
    ];
    for (irrep, list) in expected {
        let mut ours = summary(&isotropy(&g, irrep));
        let mut want = owned(&list);
        ours.sort();
        want.sort();
        assert_eq!(ours, want, "I {irrep}");
    }
}

/// T1u is the defining representation: the fixed lines of C5v, C3v, C2v are a vertex
/// (0, ±1, ±φ) direction, a face centre (1, 1, 1)-type direction and an edge midpoint
/// (a coordinate axis, up to the class), each the stabiliser's rotation axis.
#[test]
fn t1u_axial_lines_are_the_symmetry_axes() {
    let g = Group::icosahedral_full();
    let iso = isotropy(&g, "T1u");
    for s in iso.axial() {
        let v = s.axis().expect("axial");
        let v3 = nalgebra::Vector3::new(v[0], v[1], v[2]);
        // A rotation of Σ other than the identity has v as its axis.
        let rot = s
            .elements
            .iter()
            .copied()
            .find(|&x| x != 0 && g.element(x).determinant() > 0.0)
            .expect("a rotation");
        assert!((g.element(rot) * v3 - v3).amax() < TOL, "{}", s.name);
        // Its angle: 72°, 120°, 180° (trace 1 + 2 cos θ) for some rotation of Σ.
        let traces: Vec<f64> = s.elements.iter().map(|&x| g.element(x).trace()).collect();
        let want = match s.name.as_str() {
            "C5v" => PHI,
            "C3v" => 0.0,
            "C2v" => -1.0,
            other => panic!("unexpected axial class {other}"),
        };
        assert!(traces.iter().any(|t| (t - want).abs() < 1e-9), "{}", s.name);
    }
}

/// Generic properties for every irrep of a range of groups:
/// - the fixed basis is orthonormal, has `fixed_dim` columns and is fixed by every σ ∈ Σ;
/// - Σ is exactly the numerical stabiliser of its fixed space (`D(g) B = B`), and for classes
///   with `dim Fix > 0` that are *not* reported, the stabiliser is strictly larger;
/// - every isotropy subgroup contains the kernel;
/// - for the axial ones, `reversing` (found in the normaliser) agrees with a brute-force
///   search over the whole group, and maps `v` to `−v`.
#[test]
fn isotropy_agrees_with_numerical_stabilisers() {
    let groups = [
        Group::cyclic(6),
        Group::cyclic(7),
        Group::cyclic_v(1),
        Group::cyclic_v(2),
        Group::cyclic_v(5),
        Group::cyclic_v(6),
        Group::cyclic_v(8),
        Group::icosahedral(),
        Group::icosahedral_full(),
    ];
    for g in &groups {
        let lattice = g.subgroup_lattice();
        for r in g.irreps() {
            let iso = g.isotropy(&lattice, r).expect("same group");
            let stabiliser = |b: &DMatrix<f64>| -> Vec<usize> {
                (0..g.order())
                    .filter(|&x| (r.matrix(x) * b - b).abs().max() < 1e-8)
                    .collect()
            };
            for (i, c) in lattice.classes().iter().enumerate() {
                let k = g.fixed_dim(r, &c.representative);
                let b = g.fixed_space(r, &c.representative);
                assert_eq!(b.ncols(), k);
                assert!(
                    (b.transpose() * &b - DMatrix::identity(k, k)).abs().max() < 1e-10,
                    "{} {}: orthonormal",
                    g.name(),
                    r.name()
                );
                for &s in &c.representative {
                    assert!((r.matrix(s) * &b - &b).abs().max() < 1e-10);
                }
                if k == 0 {
                    continue;
                }
                let reported = iso.subgroups.iter().find(|s| s.class == i);
                let stab = stabiliser(&b);
                assert_eq!(
                    reported.is_some(),
                    stab == c.representative,
                    "{} {} on {}: isotropy iff Σ is the stabiliser of Fix(Σ)",
                    g.name(),
                    r.name(),
                    c.name
                );
            }
            for s in &iso.subgroups {
                assert!(iso.kernel.iter().all(|x| s.elements.contains(x)));
                if let Some(v) = s.axis() {
                    let brute = (0..g.order()).any(|x| (r.matrix(x) * &v + &v).amax() < 1e-9);
                    assert_eq!(s.halves_conjugate(), brute, "{} {}", g.name(), s.name);
                    if let Some(x) = s.reversing {
                        assert!(s.normalizer.contains(&x));
                        assert!((r.matrix(x) * &v + &v).amax() < 1e-9);
                    }
                } else {
                    assert!(s.reversing.is_none());
                }
            }
        }
    }
}

/// Invariant cubics (the multiplicity of the trivial irrep in Sym³ V), by hand:
/// - `D_m` on ℂ (`C_nv` on `E_k`, m = n / gcd(n, k)): the invariants are generated by `|z|²`
///   and `Re z^m`, so a cubic exists iff m = 3; 1-D irreps: `χ³ = χ` averages to 0 unless
///   trivial.
/// - `I`: Sym³ characters `(χ³ + 3χ(g²)χ + 2χ(g³))/6` on E, C5, C5², C3, C2 are
///   T1: 10, 0, 0, 1, −2 → 0; G: 20, 0, 0, 2, 0 → 1; H: 35, 0, 0, 2, 3 → 2 (as for SO(3):
///   Sym³(ℓ=2) = ℓ 6 + 4 + 3 + 2 + 0, and ℓ = 6 has one icosahedral invariant).
/// - `Ih`: g irreps as for `I`; u irreps 0 (`−I` acts as −1 on cubics).
#[test]
fn invariant_cubics_by_hand() {
    for (n, k) in [
        (3, 1),
        (6, 2),
        (9, 3),
        (12, 4),
        (7, 1),
        (7, 2),
        (8, 1),
        (8, 2),
        (5, 1),
    ] {
        let g = Group::cyclic_v(n);
        let m = n / gcd(n, k);
        let e = g.irrep(&format!("E{k}")).expect("irrep");
        assert_eq!(g.invariant_cubics(e), usize::from(m == 3), "C{n}v E{k}");
    }
    for n in [2, 3, 4, 7, 8] {
        let g = Group::cyclic_v(n);
        for r in g.irreps().iter().filter(|r| r.dim() == 1) {
            assert_eq!(
                g.invariant_cubics(r),
                usize::from(r.is_trivial()),
                "C{n}v {}",
                r.name()
            );
        }
    }
    let i = Group::icosahedral();
    for (name, want) in [("A", 1), ("T1", 0), ("T2", 0), ("G", 1), ("H", 2)] {
        assert_eq!(
            i.invariant_cubics(i.irrep(name).expect(name)),
            want,
            "I {name}"
        );
    }
    let ih = Group::icosahedral_full();
    for (name, want) in [("A", 1), ("T1", 0), ("T2", 0), ("G", 1), ("H", 2)] {
        let g = format!("{name}g");
        let u = format!("{name}u");
        assert_eq!(
            ih.invariant_cubics(ih.irrep(&g).expect("g")),
            want,
            "Ih {g}"
        );
        assert_eq!(ih.invariant_cubics(ih.irrep(&u).expect("u")), 0, "Ih {u}");
    }
}

#[test]
fn mismatched_irrep_or_lattice_is_an_error() {
    let c7v = Group::cyclic_v(7);
    let c8v = Group::cyclic_v(8);
    let lattice = c7v.subgroup_lattice();
    let e1 = c8v.irrep("E1").expect("E1");
    assert!(matches!(
        c7v.isotropy(&lattice, e1),
        Err(GroupError::Mismatch(_))
    ));
    assert!(matches!(
        c8v.isotropy(&lattice, e1),
        Err(GroupError::Mismatch(_))
    ));
    // An empty list imposes nothing.
    assert_eq!(c8v.fixed_dim(e1, &[]), 2);
    assert_eq!(c8v.fixed_space(e1, &[]), DMatrix::<f64>::identity(2, 2));
}
