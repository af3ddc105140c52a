//! Representation theory checks for every group family: group axioms, homomorphism and
//! orthogonality of irrep matrices, Schur's relations (by irrep kind), completeness
//! (Σ d²/c = |G|), character orthogonality, and class functions.

use nalgebra::DMatrix;
use proptest::prelude::*;
use symmetry::{Group, IrrepKind};

const TOL: f64 = 1e-10;

fn close(a: &DMatrix<f64>, b: &DMatrix<f64>) -> bool {
    (a - b).abs().max() < TOL
}

/// Group axioms from the table: identity, inverses, associativity, table = matrix product.
pub(crate) fn check_group(g: &Group) {
    let n = g.order();
    for a in 0..n {
        assert_eq!(g.mul(0, a), a);
        assert_eq!(g.mul(a, 0), a);
        assert_eq!(g.mul(a, g.inverse(a)), 0);
        for b in 0..n {
            let p = g.element(a) * g.element(b);
            assert!((p - g.element(g.mul(a, b))).abs().max() < TOL);
        }
    }
    // Associativity on a sample (all triples for small groups).
    let step = if n > 24 { 7 } else { 1 };
    for a in (0..n).step_by(step) {
        for b in (0..n).step_by(step) {
            for c in (0..n).step_by(step) {
                assert_eq!(g.mul(g.mul(a, b), c), g.mul(a, g.mul(b, c)));
            }
        }
    }
    // Classes partition the group and are closed under conjugation.
    let total: usize = g.classes().iter().map(Vec::len).sum();
    assert_eq!(total, n);
    assert_eq!(g.classes()[0], vec![0]);
}

/// Every irrep: orthogonal matrices, D(gh) = D(g) D(h), constant characters on classes.
pub(crate) fn check_homomorphism(g: &Group) {
    for irrep in g.irreps() {
        let d = irrep.dim();
        assert!(
            close(irrep.matrix(0), &DMatrix::identity(d, d)),
            "{} of {}: D(e) != I",
            irrep.name(),
            g.name()
        );
        for a in 0..g.order() {
            let m = irrep.matrix(a);
            assert!(
                close(&(m.transpose() * m), &DMatrix::identity(d, d)),
                "{}: D({a}) not orthogonal",
                irrep.name()
            );
            for b in 0..g.order() {
                let lhs = irrep.matrix(g.mul(a, b));
                let rhs = m * irrep.matrix(b);
                assert!(
                    close(lhs, &rhs),
                    "{} of {}: D({a}·{b}) != D({a}) D({b})",
                    irrep.name(),
                    g.name()
                );
            }
        }
        for class in g.classes() {
            let chi0 = irrep.character(class[0]);
            assert!(class
                .iter()
                .all(|&c| (irrep.character(c) - chi0).abs() < TOL));
        }
    }
}

/// Schur's relations: (1/|G|) Σ_g D^μ_ij(g) D^ν_kl(g) = 0 for μ ≠ ν, and for μ = ν
/// δ_ik δ_jl / d (real type) or (δ_ik δ_jl + J_ik J_jl) / d (complex type).
pub(crate) fn check_schur(g: &Group) {
    let order = g.order() as f64;
    for (m, mu) in g.irreps().iter().enumerate() {
        for (n, nu) in g.irreps().iter().enumerate() {
            let (dm, dn) = (mu.dim(), nu.dim());
            // kron(D^μ, D^ν)[(i·dn + k), (j·dn + l)] = D^μ_ij D^ν_kl
            let mut avg = DMatrix::<f64>::zeros(dm * dn, dm * dn);
            for e in 0..g.order() {
                avg += mu.matrix(e).kronecker(nu.matrix(e)) / order;
            }
            let expected = DMatrix::from_fn(dm * dn, dm * dn, |r, c| {
                if m != n {
                    return 0.0;
                }
                let (i, k, j, l) = (r / dn, r % dn, c / dn, c % dn);
                let delta = |a: usize, b: usize| f64::from(u8::from(a == b));
                let base = delta(i, k) * delta(j, l);
                let extra = match mu.kind() {
                    IrrepKind::Real => 0.0,
                    IrrepKind::Complex => {
                        let jm = mu.complex_structure().expect("complex type has J");
                        jm[(i, k)] * jm[(j, l)]
                    }
                };
                (base + extra) / dm as f64
            });
            assert!(
                (&avg - &expected).abs().max() < TOL,
                "Schur fails for {} x {} in {}",
                mu.name(),
                nu.name(),
                g.name()
            );
        }
        if let Some(j) = mu.complex_structure() {
            let d = mu.dim();
            assert!(close(&(j * j), &(-DMatrix::identity(d, d))));
            for e in 0..g.order() {
                assert!(close(&(j * mu.matrix(e)), &(mu.matrix(e) * j)));
            }
        } else {
            assert_eq!(mu.kind(), IrrepKind::Real);
        }
    }
}

/// Characters: (1/|G|) Σ χ_μ χ_ν = c_μ δ_μν (c = commutant dimension); Σ d²/c = |G|;
/// Σ c = number of classes (the real irreps account for every complex one).
pub(crate) fn check_characters(g: &Group) {
    let order = g.order() as f64;
    let mut sum_d2 = 0.0;
    let mut sum_c = 0;
    for (m, mu) in g.irreps().iter().enumerate() {
        let c = mu.kind().commutant_dim();
        sum_d2 += (mu.dim() * mu.dim()) as f64 / c as f64;
        sum_c += c;
        for (n, nu) in g.irreps().iter().enumerate() {
            let ip: f64 = (0..g.order())
                .map(|e| mu.character(e) * nu.character(e))
                .sum::<f64>()
                / order;
            let expected = if m == n { c as f64 } else { 0.0 };
            assert!(
                (ip - expected).abs() < TOL,
                "<χ_{}, χ_{}> = {ip} in {}",
                mu.name(),
                nu.name(),
                g.name()
            );
        }
    }
    assert!(
        (sum_d2 - order).abs() < TOL,
        "Σ d²/c = {sum_d2} != |G| = {order} for {}",
        g.name()
    );
    assert_eq!(
        sum_c,
        g.classes().len(),
        "irreps do not cover the classes of {}",
        g.name()
    );
    assert!(g.irreps()[0].is_trivial());
}

pub(crate) fn check_all(g: &Group) {
    check_group(g);
    check_homomorphism(g);
    check_schur(g);
    check_characters(g);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, failure_persistence: None, .. ProptestConfig::default() })]

    #[test]
    fn cyclic_groups_are_consistent(n in 1usize..=12) {
        let g = Group::cyclic(n);
        prop_assert_eq!(g.order(), n);
        prop_assert_eq!(g.name(), format!("C{n}"));
        check_all(&g);
    }

    #[test]
    fn cyclic_v_groups_are_consistent(n in 1usize..=12) {
        let g = Group::cyclic_v(n);
        prop_assert_eq!(g.order(), 2 * n);
        // Real irreps of C_nv: A1, A2, (B1, B2 for even n), E_1 .. E_{ceil(n/2)-1}.
        let expected = 2 + if n % 2 == 0 { 2 } else { 0 } + (n.div_ceil(2) - 1);
        prop_assert_eq!(g.irreps().len(), expected);
        prop_assert!(g.irreps().iter().all(|r| r.kind() == IrrepKind::Real));
        check_all(&g);
    }
}

#[test]
fn first_mirror_of_cnv_contains_the_x_axis() {
    for n in 1..=6 {
        let g = Group::cyclic_v(n);
        let s = g.element(n);
        assert!((s * nalgebra::Vector3::x() - nalgebra::Vector3::x()).norm() < TOL);
        assert!((s * nalgebra::Vector3::y() + nalgebra::Vector3::y()).norm() < TOL);
    }
}

#[test]
fn icosahedral_groups_are_consistent() {
    let i = Group::icosahedral();
    assert_eq!(i.order(), 60);
    assert_eq!(i.classes().len(), 5);
    let dims: Vec<usize> = i.irreps().iter().map(|r| r.dim()).collect();
    assert_eq!(dims, vec![1, 3, 3, 4, 5]);
    check_all(&i);

    let ih = Group::icosahedral_full();
    assert_eq!(ih.order(), 120);
    assert_eq!(ih.classes().len(), 10);
    let names: Vec<&str> = ih.irreps().iter().map(|r| r.name()).collect();
    assert_eq!(
        names,
        ["Ag", "T1g", "T2g", "Gg", "Hg", "Au", "T1u", "T2u", "Gu", "Hu"]
    );
    check_all(&ih);
    // T1u is the defining representation.
    let t1u = ih.irrep("T1u").expect("T1u");
    for (e, r) in ih.elements().iter().enumerate() {
        let m = t1u.matrix(e);
        assert!((0..3).all(|a| (0..3).all(|b| (m[(a, b)] - r[(a, b)]).abs() < TOL)));
    }
}

#[test]
fn names_parse_and_bad_names_are_rejected() {
    assert_eq!(Group::by_name("C7v").map(|g| g.order()), Ok(14));
    assert_eq!(Group::by_name("C7").map(|g| g.order()), Ok(7));
    assert_eq!(Group::by_name("C1v").map(|g| g.order()), Ok(2));
    assert_eq!(Group::by_name("Ih").map(|g| g.order()), Ok(120));
    assert_eq!(Group::by_name("I").map(|g| g.order()), Ok(60));
    for bad in [
        "",
        "C",
        "C0",
        "C0v",
        "Cv",
        "D7",
        "c7v",
        "C-1",
        "C7x",
        "Oh",
        "C99999999999999999999",
    ] {
        let err = Group::by_name(bad).expect_err(bad).to_string();
        assert!(err.contains(&format!("'{bad}'")), "{err}");
    }
}

#[test]
fn conjugated_group_keeps_its_irreps() {
    let q = *nalgebra::Rotation3::from_euler_angles(0.3, -1.1, 0.7).matrix();
    let g = Group::icosahedral_full().conjugated(&q, "Ih'");
    check_group(&g);
    check_homomorphism(&g);
}
