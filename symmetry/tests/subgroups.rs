//! Stabilisers of directions and planes, recognised as axial groups with their own irreps.

use nalgebra::{Rotation3, Unit, Vector3};
use symmetry::{Group, Invariant, Matrix3};

const PHI: f64 = 1.618_033_988_749_895;

/// A rotation taking unit vector `from` to `to`.
fn rotation_between(from: Vector3<f64>, to: Vector3<f64>) -> Matrix3 {
    *Rotation3::rotation_between(&from, &to)
        .unwrap_or_else(|| {
            Rotation3::from_axis_angle(&Unit::new_normalize(Vector3::x()), std::f64::consts::PI)
        })
        .matrix()
}

fn stabilizer_of_down(point_down: Vector3<f64>) -> (String, usize, Vec<String>) {
    let q = rotation_between(point_down.normalize(), -Vector3::z());
    let g = Group::icosahedral_full().conjugated(&q, "Ih (rotated)");
    let sub = g
        .stabilizer(&[Invariant::Direction(-Vector3::z())])
        .expect("axial");
    // The subgroup's elements are the parent's, and form a group of their own.
    for (i, &p) in sub.parent_index.iter().enumerate() {
        assert_eq!(sub.group.element(i), g.element(p));
    }
    for a in 0..sub.group.order() {
        for b in 0..sub.group.order() {
            let ab = sub.group.mul(a, b);
            assert_eq!(
                sub.parent_index[ab],
                g.mul(sub.parent_index[a], sub.parent_index[b])
            );
            for r in sub.group.irreps() {
                let lhs = r.matrix(ab);
                let rhs = r.matrix(a) * r.matrix(b);
                assert!((lhs - rhs).abs().max() < 1e-10);
            }
        }
    }
    let names = sub
        .group
        .irreps()
        .iter()
        .map(|r| r.name().to_string())
        .collect();
    (sub.group.name().to_string(), sub.group.order(), names)
}

#[test]
fn icosphere_resting_on_a_vertex_face_or_edge() {
    let (name, order, irreps) = stabilizer_of_down(Vector3::new(0.0, 1.0, PHI));
    assert_eq!((name.as_str(), order), ("C5v", 10));
    assert_eq!(irreps, ["A1", "A2", "E1", "E2"]);
    let (name, order, _) = stabilizer_of_down(Vector3::new(1.0, 1.0, 1.0));
    assert_eq!((name.as_str(), order), ("C3v", 6));
    let (name, order, irreps) = stabilizer_of_down(Vector3::new(0.0, 0.0, 1.0));
    assert_eq!((name.as_str(), order), ("C2v", 4));
    assert_eq!(irreps, ["A1", "A2", "B1", "B2"]);
}

#[test]
fn generic_directions_give_a_mirror_or_nothing() {
    // In the mirror plane x = 0 of Ih but on no axis: C1v.
    let (name, order, _) = stabilizer_of_down(Vector3::new(0.0, 0.3, 0.9));
    assert_eq!((name.as_str(), order), ("C1v", 2));
    let (name, order, irreps) = stabilizer_of_down(Vector3::new(0.2, 0.3, 0.9));
    assert_eq!((name.as_str(), order), ("C1", 1));
    assert_eq!(irreps, ["A"]);
}

#[test]
fn gravity_keeps_all_of_cnv_and_an_off_origin_plane_too() {
    let g = Group::cyclic_v(7);
    let down = g
        .stabilizer(&[Invariant::Direction(-Vector3::z())])
        .unwrap();
    assert_eq!(down.group.name(), "C7v");
    assert_eq!(down.parent_index, (0..14).collect::<Vec<_>>());
    let plane = Invariant::Plane {
        normal: Vector3::z(),
        offset: -0.4,
    };
    assert_eq!(g.stabilizer(&[plane]).unwrap().group.order(), 14);
}

#[test]
fn a_horizontal_plane_through_the_centre_keeps_more_than_one_above_it() {
    let ih = Group::icosahedral_full();
    let through = Invariant::Plane {
        normal: Vector3::z(),
        offset: 0.0,
    };
    // z = 0 is a mirror of Ih: elements keeping the plane include those flipping z; that is
    // not an axial group but D2h, which the stabiliser builds as a group of its own (with
    // `Group::subgroup`), named and with its irreps, not as a misnamed axial group.
    let flips_or_keeps_z: Vec<usize> = (0..ih.order())
        .filter(|&g| (ih.element(g) * Vector3::z()).z.abs() > 1.0 - 1e-9)
        .collect();
    let d2h = ih.subgroup(&flips_or_keeps_z).expect("D2h");
    assert_eq!((d2h.group.name(), d2h.group.order()), ("D2h", 8));
    assert_eq!(d2h.group.irreps().len(), 8);
    let kept = ih
        .stabilizer(&[through])
        .expect("the stabiliser of the plane");
    assert_eq!(kept.group.name(), "D2h");
    assert_eq!(kept.parent_index, d2h.parent_index);
    let above = Invariant::Plane {
        normal: Vector3::z(),
        offset: 0.5,
    };
    assert_eq!(ih.stabilizer(&[above]).unwrap().group.name(), "C2v");
}
