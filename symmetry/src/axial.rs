//! Axial groups `C_n` and `C_nv` and their real irreps.
//!
//! Elements are ordered `r^0, r^1, …, r^(n-1)` followed (for `C_nv`) by
//! `s r^0, s r^1, …, s r^(n-1)`, where `r` is the rotation by `2π/n` about the axis and `s`
//! the first mirror. With `s r = r⁻¹ s`, the element `s^e r^k` is mapped to:
//!
//! | irrep | `r^k`                | `s r^k`                        |
//! |-------|----------------------|--------------------------------|
//! | A1 (A)| 1                    | 1                              |
//! | A2    | 1                    | −1                             |
//! | B1 (B)| (−1)^k               | (−1)^k                         |
//! | B2    | (−1)^k               | −(−1)^k                        |
//! | E_j   | R(2πjk/n)            | diag(1, −1) R(2πjk/n)          |
//!
//! B irreps exist for even n, `E_j` for `j = 1 … ⌈n/2⌉ − 1`. For `C_n` the `E_j` are of complex
//! type; for `C_nv` every irrep is absolutely irreducible.

use crate::group::{Group, Matrix3};
use crate::irrep::Irrep;
use nalgebra::{DMatrix, Rotation3, Unit, Vector3};
use std::f64::consts::PI;

impl Group {
    /// `C_n`: the n rotations about the z-axis by multiples of 2π/n.
    pub fn cyclic(n: usize) -> Self {
        axial(format!("C{n}"), n, &Vector3::z(), None)
    }

    /// `C_nv`: `C_n` about z plus n vertical mirrors; the first mirror is the plane y = 0
    /// (it contains the x-axis). `C1v` is that single mirror.
    pub fn cyclic_v(n: usize) -> Self {
        let s = Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, 1.0));
        axial(format!("C{n}v"), n, &Vector3::z(), Some(s))
    }
}

/// Builds `C_n` (no mirror) or `C_nv` (mirror `s`, which must contain `axis`) about `axis`.
pub(crate) fn axial(name: String, n: usize, axis: &Vector3<f64>, s: Option<Matrix3>) -> Group {
    assert!(n >= 1, "an axial group needs n >= 1");
    // Each power from its own angle, not by repeated products, so that images of a
    // fundamental domain coincide to rounding.
    let axis = Unit::new_normalize(*axis);
    let rotations: Vec<Matrix3> = (0..n)
        .map(|k| {
            if k == 0 {
                Matrix3::identity()
            } else {
                Rotation3::from_axis_angle(&axis, 2.0 * PI * k as f64 / n as f64).into_inner()
            }
        })
        .collect();
    let mut elements = rotations.clone();
    if let Some(s) = s {
        elements.extend(rotations.iter().map(|m| s * m));
    }
    let mirrors = s.is_some();
    let order = elements.len();
    let mirror_of = |g: usize| g >= n;
    let power = |g: usize| g % n;
    let one = |f: &dyn Fn(usize) -> f64| -> Vec<DMatrix<f64>> {
        (0..order)
            .map(|g| DMatrix::from_element(1, 1, f(g)))
            .collect()
    };
    let sign = |k: usize| if k.is_multiple_of(2) { 1.0 } else { -1.0 };

    let mut irreps = Vec::new();
    let (a1, b1) = if mirrors { ("A1", "B1") } else { ("A", "B") };
    irreps.push(Irrep::real(a1, one(&|_| 1.0)));
    if mirrors {
        irreps.push(Irrep::real(
            "A2",
            one(&|g| if mirror_of(g) { -1.0 } else { 1.0 }),
        ));
    }
    if n.is_multiple_of(2) {
        irreps.push(Irrep::real(b1, one(&|g| sign(power(g)))));
        if mirrors {
            irreps.push(Irrep::real(
                "B2",
                one(&|g| sign(power(g)) * if mirror_of(g) { -1.0 } else { 1.0 }),
            ));
        }
    }
    for j in 1..n.div_ceil(2) {
        let matrices = (0..order)
            .map(|g| {
                let t = 2.0 * PI * (j * power(g)) as f64 / n as f64;
                let (sn, c) = t.sin_cos();
                let rot = DMatrix::from_row_slice(2, 2, &[c, -sn, sn, c]);
                if mirror_of(g) {
                    DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, -1.0]) * rot
                } else {
                    rot
                }
            })
            .collect();
        let name = format!("E{j}");
        irreps.push(if mirrors {
            Irrep::real(name, matrices)
        } else {
            // Rotations commute with the quarter turn: the irrep is of complex type.
            Irrep::complex(
                name,
                matrices,
                DMatrix::from_row_slice(2, 2, &[0.0, -1.0, 1.0, 0.0]),
            )
        });
    }
    Group::from_parts(name, elements, irreps).expect("axial groups are closed by construction")
}
