//! The action checks can fail: wrong groups, moved nodes, flipped triangles and undeclared
//! symmetry are all caught.

use meshes::generators::{disc, icosphere, DiscOptions, IcosphereOptions};
use meshes::{MeshError, SymmetricMesh};
use symmetry::Group;

fn c7v_disc() -> SymmetricMesh {
    disc(&DiscOptions {
        radius: 1.0,
        sectors: 7,
        divisions: 4,
        group: None,
    })
    .expect("disc")
}

#[test]
fn a_group_the_mesh_does_not_have_is_refused() {
    let m = c7v_disc();
    let err =
        SymmetricMesh::new(m.mesh.clone(), Group::cyclic_v(8)).expect_err("C8v on a C7v disc");
    assert!(matches!(err, MeshError::Symmetry(_)), "{err}");
    assert!(SymmetricMesh::new(m.mesh, Group::cyclic(7)).is_ok());
}

#[test]
fn verify_catches_a_moved_node() {
    let mut m = c7v_disc();
    m.verify().expect("the generated mesh verifies");
    let i = m.mesh.nodes.len() / 2;
    m.mesh.nodes[i].x += 1e-7;
    let err = m
        .verify()
        .expect_err("a node moved by 1e-7 breaks the action");
    assert!(err.to_string().contains("differs"), "{err}");
}

#[test]
fn verify_catches_an_inconsistent_orientation() {
    let mut m = c7v_disc();
    m.mesh.triangles[3].swap(1, 2);
    assert!(matches!(m.verify(), Err(MeshError::Topology(_))));
}

#[test]
fn verify_catches_a_node_set_that_is_not_invariant() {
    let mut m = c7v_disc();
    let mut rim = m.mesh.boundaries["rim"].clone();
    rim.pop();
    m.mesh.set_boundary("rim", rim);
    let err = m
        .verify()
        .expect_err("a rim missing one node is not invariant");
    assert!(err.to_string().contains("rim"), "{err}");
}

#[test]
fn hidden_symmetry_is_found_for_an_under_declared_group() {
    let m = c7v_disc();
    let as_c7 = SymmetricMesh::new(m.mesh.clone(), Group::cyclic(7)).unwrap();
    assert_eq!(
        as_c7.hidden_symmetries().len(),
        7,
        "the 7 mirrors of C7v are hidden in C7"
    );
    assert!(m.hidden_symmetries().is_empty());

    let sphere = icosphere(&IcosphereOptions {
        radius: 1.0,
        frequency: 2,
    })
    .unwrap();
    assert!(sphere.hidden_symmetries().is_empty());
    let as_i = SymmetricMesh::new(sphere.mesh, Group::icosahedral()).unwrap();
    assert_eq!(
        as_i.hidden_symmetries().len(),
        60,
        "the 60 improper elements of Ih"
    );
}
