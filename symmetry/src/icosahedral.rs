//! The icosahedral rotation group `I` (order 60) and the full group `Ih = I × {E, −E}` (120).
//!
//! Orientation: the icosahedron with vertices at the cyclic permutations of (0, ±1, ±φ); its
//! 2-fold axes include x, y and z, so the coordinate planes are mirrors of `Ih`.
//!
//! Irreps of `I` are built constructively: `A` trivial, `T1` the rotation matrices themselves,
//! `H` the 5-dimensional part of `T1 ⊗ T1 = A + T1 + H` (traceless symmetric tensors), and `T2`,
//! `G` the parts of `T1 ⊗ H = T1 + T2 + G + H`, each cut out by its character projector.
//! Characters of `I` by class (rotation angle):
//!
//! | class | E | C5 (72°) | C5² (144°) | C3 | C2 |
//! |-------|---|----------|------------|----|----|
//! | T1    | 3 | φ        | 1 − φ      | 0  | −1 |
//! | T2    | 3 | 1 − φ    | φ          | 0  | −1 |
//! | G     | 4 | −1       | −1         | 1  | 0  |
//! | H     | 5 | 0        | 0          | −1 | 1  |
//!
//! `Ih` irreps: `μg(±R) = μ(R)`, `μu(±R) = ±μ(R)`; `T1u` is the defining 3×3 representation.

use crate::group::{Group, Matrix3};
use crate::irrep::{extract_irrep, Irrep};
use crate::MATRIX_TOL;
use nalgebra::{DMatrix, Rotation3, Unit, Vector3};
use std::f64::consts::PI;

/// The golden ratio φ = (1 + √5)/2.
const PHI: f64 = 1.618_033_988_749_895;

/// The 60 rotations of the icosahedron, identity first, in breadth-first order from a 5-fold
/// rotation about the vertex (0, 1, φ) and the half-turn about z.
fn rotations() -> Vec<Matrix3> {
    let five = Rotation3::from_axis_angle(
        &Unit::new_normalize(Vector3::new(0.0, 1.0, PHI)),
        2.0 * PI / 5.0,
    )
    .into_inner();
    let two = Matrix3::from_diagonal(&Vector3::new(-1.0, -1.0, 1.0));
    let mut elements = vec![Matrix3::identity()];
    let mut next = 0;
    while next < elements.len() {
        for gen in [five, two] {
            let p = gen * elements[next];
            if !elements.iter().any(|e| (e - p).abs().max() < MATRIX_TOL) {
                elements.push(p);
            }
        }
        next += 1;
    }
    assert_eq!(
        elements.len(),
        60,
        "the icosahedral rotation group has 60 elements"
    );
    elements
}

/// Character of the irrep `which` of `I` at a rotation with trace `tr`.
fn character(which: &str, tr: f64) -> f64 {
    // Class from the rotation angle: tr = 1 + 2 cos θ.
    let class = [3.0, PHI, 1.0 - PHI, 0.0, -1.0]
        .iter()
        .position(|&t| (t - tr).abs() < 1e-6)
        .expect("trace of an icosahedral rotation");
    let row: [f64; 5] = match which {
        "T2" => [3.0, 1.0 - PHI, PHI, 0.0, -1.0],
        "G" => [4.0, -1.0, -1.0, 1.0, 0.0],
        "H" => [5.0, 0.0, 0.0, -1.0, 1.0],
        _ => unreachable!("only T2, G, H are extracted"),
    };
    row[class]
}

/// Irreps of `I` on the given rotations: A, T1, T2, G, H (in this order).
fn rotation_irreps(rot: &[Matrix3]) -> Vec<(&'static str, Vec<DMatrix<f64>>)> {
    let t1: Vec<DMatrix<f64>> = rot
        .iter()
        .map(|r| DMatrix::from_column_slice(3, 3, r.as_slice()))
        .collect();
    let traces: Vec<f64> = rot.iter().map(|r| r.trace()).collect();
    let chi = |which: &str| -> Vec<f64> { traces.iter().map(|&t| character(which, t)).collect() };
    let t1t1: Vec<DMatrix<f64>> = t1.iter().map(|m| m.kronecker(m)).collect();
    let h = extract_irrep(&t1t1, &chi("H"), 5);
    let t1h: Vec<DMatrix<f64>> = t1.iter().zip(&h).map(|(a, b)| a.kronecker(b)).collect();
    let t2 = extract_irrep(&t1h, &chi("T2"), 3);
    let g = extract_irrep(&t1h, &chi("G"), 4);
    let a = vec![DMatrix::from_element(1, 1, 1.0); rot.len()];
    vec![("A", a), ("T1", t1), ("T2", t2), ("G", g), ("H", h)]
}

impl Group {
    /// `I`: the 60 rotations of the icosahedron.
    pub fn icosahedral() -> Self {
        let rot = rotations();
        let irreps = rotation_irreps(&rot)
            .into_iter()
            .map(|(name, m)| Irrep::real(name, m))
            .collect();
        Group::from_parts("I", rot, irreps).expect("I is closed by construction")
    }

    /// `Ih`: the 120 symmetries of the icosahedron; elements `0..60` are the rotations `R` of
    /// [`Group::icosahedral`] and `60..120` the improper `−R` in the same order.
    pub fn icosahedral_full() -> Self {
        let rot = rotations();
        let mut elements = rot.clone();
        elements.extend(rot.iter().map(|r| -r));
        let mut irreps = Vec::new();
        let base = rotation_irreps(&rot);
        for (parity, sign) in [("g", 1.0), ("u", -1.0)] {
            for (name, m) in &base {
                let mut all = m.clone();
                all.extend(m.iter().map(|d| d * sign));
                irreps.push(Irrep::real(format!("{name}{parity}"), all));
            }
        }
        Group::from_parts("Ih", elements, irreps).expect("Ih is closed by construction")
    }
}
