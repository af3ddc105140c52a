//! Actions of subgroups that are not stabilisers ([`GroupAction::restrict_to`]): the `D5d` of
//! an icosphere's `Ih`, with orbits counted by hand.

use meshes::generators::{icosphere, IcosphereOptions};
use meshes::{GroupAction, MeshError, SymmetricMesh};
use symmetry::{Group, Subgroup};

fn sphere(frequency: usize) -> SymmetricMesh {
    icosphere(&IcosphereOptions {
        radius: 1.0,
        frequency,
    })
    .unwrap()
}

/// The `D5d` class representative of the sphere's `Ih`, as a group of its own.
fn d5d(m: &SymmetricMesh) -> Subgroup {
    let g = m.group();
    let lattice = g.subgroup_lattice();
    let class = &lattice.classes()[lattice.find("D5d").expect("Ih has a D5d")];
    g.subgroup(&class.representative).expect("D5d")
}

fn sizes(orbits: &[Vec<usize>]) -> Vec<usize> {
    let mut s: Vec<usize> = orbits.iter().map(Vec::len).collect();
    s.sort_unstable();
    s
}

/// On the f = 2 icosphere (12 vertices, 30 edge midpoints, 80 triangles), by hand: the 5-fold
/// axis of D5d goes through two opposite vertices {v, −v} (an orbit of 2); the other 10
/// vertices are one orbit (C5 turns each ring, −I swaps the rings); the midpoints of the 10
/// edges at ±v, of the 10 ring edges and of the 10 zigzag edges between the rings are three
/// orbits of 10. Each of the two orbits of 10 faces (the caps at ±v, the belt) is mapped onto
/// itself by a mirror through one corner and the opposite edge midpoint, so its 4 triangles
/// form orbits of 10 (centre), 10 (that corner) and 20 (the other two corners).
#[test]
fn d5d_on_an_icosphere_is_a_verified_action_with_the_expected_orbits() {
    let m = sphere(2);
    let sub = d5d(&m);
    assert_eq!(sub.group.name(), "D5d");
    let action = m
        .action
        .restrict_to(&sub)
        .expect("a subgroup of the mesh's group");
    assert_eq!(action.group().name(), "D5d");
    assert_eq!(action.group().irreps().len(), 8);
    let restricted = SymmetricMesh {
        mesh: m.mesh.clone(),
        action: action.clone(),
    };
    let v = restricted.verify().expect("the D5d action verifies");
    assert!(v.closed);
    assert_eq!(sizes(&action.node_orbits()), [2, 10, 10, 10, 10]);
    assert_eq!(sizes(&action.triangle_orbits()), [10, 10, 10, 10, 20, 20]);
    // Element i acts as the parent's element parent_index[i].
    for (i, &g) in sub.parent_index.iter().enumerate() {
        assert_eq!(action.node_perm(i), m.action.node_perm(g));
        assert_eq!(action.triangle_perm(i), m.action.triangle_perm(g));
    }
}

/// At f = 4 (162 nodes, 320 triangles): every orbit's size divides |D5d| = 20 and equals
/// 20 / |stabiliser| (orbit–stabiliser, the stabiliser counted from the permutations); the
/// number of orbits is Burnside's average number of fixed points; and the displacement
/// representation `χ(g) = #{nodes fixed by g} · tr R_g` has nonnegative integer multiplicities
/// of D5d's irreps adding up to 3 × 162 (what a symmetry-adapted basis of D5d is built from).
#[test]
fn d5d_orbits_on_a_finer_icosphere() {
    let m = sphere(4);
    let sub = d5d(&m);
    let action = m.action.restrict_to(&sub).unwrap();
    let g = action.group();
    SymmetricMesh {
        mesh: m.mesh.clone(),
        action: action.clone(),
    }
    .verify()
    .unwrap();
    let n = m.mesh.nodes.len();
    let fixed = |x: usize| (0..n).filter(|&i| action.node_perm(x)[i] == i).count();
    let orbits = action.node_orbits();
    for orbit in &orbits {
        assert_eq!(g.order() % orbit.len(), 0, "orbit of {}", orbit.len());
        let stabiliser = (0..g.order())
            .filter(|&x| action.node_perm(x)[orbit[0]] == orbit[0])
            .count();
        assert_eq!(orbit.len() * stabiliser, g.order());
    }
    let burnside: usize = (0..g.order()).map(fixed).sum();
    assert_eq!(burnside, orbits.len() * g.order());
    for orbit in action.triangle_orbits() {
        assert_eq!(g.order() % orbit.len(), 0);
    }
    let mut total = 0;
    for irrep in g.irreps() {
        let c = irrep.kind().commutant_dim() as f64;
        let mult: f64 = (0..g.order())
            .map(|x| fixed(x) as f64 * g.element(x).trace() * irrep.character(x))
            .sum::<f64>()
            / g.order() as f64
            / c;
        assert!(
            (mult - mult.round()).abs() < 1e-9 && mult >= 0.0,
            "{}",
            irrep.name()
        );
        total += mult.round() as usize * irrep.dim();
    }
    assert_eq!(total, 3 * n);
}

/// A subgroup of another group (different matrices, or indices out of range) is refused.
#[test]
fn a_subgroup_of_another_group_is_refused() {
    let m = sphere(2);
    let c5v = Group::cyclic_v(5);
    let foreign = c5v.subgroup(&(0..10).collect::<Vec<_>>()).unwrap();
    let err = m
        .action
        .restrict_to(&foreign)
        .expect_err("C5v about z is not in this Ih");
    assert!(matches!(err, MeshError::Symmetry(_)), "{err}");
    let mut bad = d5d(&m);
    bad.parent_index[3] = 1000;
    assert!(m.action.restrict_to(&bad).is_err());
    // The stabiliser route is unchanged: restrict(keep) = restrict_to(stabilizer(keep)).
    let keep = [symmetry::Invariant::Direction(-nalgebra::Vector3::z())];
    let a: GroupAction = m.action.restrict(&keep).unwrap();
    let b = m
        .action
        .restrict_to(&m.group().stabilizer(&keep).unwrap())
        .unwrap();
    assert_eq!(a.group().name(), "C2v");
    for x in 0..a.group().order() {
        assert_eq!(a.node_perm(x), b.node_perm(x));
    }
}
