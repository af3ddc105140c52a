//! Enclosed volume, one triangle at a time (docs/theory.md §3).
//!
//! ```text
//!   V_T = (1/6) x1·(x2 × x3) = (1/6) ε_{ijk} x1_i x2_j x3_k
//! ```
//!
//! is the signed volume of the tetrahedron (origin, x1, x2, x3). By the divergence theorem
//! with the field x/3, Σ_T V_T over a closed triangulation whose normals point outward (nodes
//! counter-clockwise seen from outside) is the enclosed volume, whatever the origin.
//!
//! Gradient and Hessian are closed-form: ∂V_T/∂x1 = (x2 × x3)/6, ∂V_T/∂x2 = (x3 × x1)/6,
//! ∂V_T/∂x3 = (x1 × x2)/6; the diagonal node blocks of the Hessian vanish and the off-diagonal
//! ones are ∂²V_T/∂x1_i∂x2_j = ε_{ijk} x3_k / 6 (and cyclically: the (2, 3) block carries x1,
//! the (3, 1) block x2).
//!
//! Gas uses the assembled V: at fixed over-pressure p, Π = −p V, F = −p ∇V, K = −p ∇²V and
//! ∂F/∂p = −∇V; at a fixed amount (isothermal, absolute pressure C/V),
//! Π = −C ln V + P_atm V, whose derivatives need V itself and so are formed after summation:
//! F = (P_atm − C/V) ∇V, K = (P_atm − C/V) ∇²V + (C/V²) ∇V ∇Vᵀ.
//! For an open membrane with a fixed rim, the closing surface only adds a constant to V.

use crate::model::Local;
use nalgebra::Vector3;

/// Signed volume V_T = x1·(x2 × x3)/6 with its gradient and Hessian (node-major dofs).
pub fn volume(x: &[Vector3<f64>; 3]) -> Local {
    let mut out = Local::ZERO;
    out.value = x[0].dot(&x[1].cross(&x[2])) / 6.0;
    for n in 0..3 {
        let (p, q) = (x[(n + 1) % 3], x[(n + 2) % 3]);
        let g = p.cross(&q) / 6.0;
        for i in 0..3 {
            out.grad[3 * n + i] = g[i];
        }
        // Block (n+1, n+2) carries the remaining node n: ∂²V/∂p_i∂q_j = ε_{ijk} x_n,k / 6,
        // i.e. the matrix −[x_n]× / 6 (with [w]× v = w × v), and its transpose below.
        let (r, c) = ((n + 1) % 3, (n + 2) % 3);
        let w = x[n] / 6.0;
        let block = [[0.0, w.z, -w.y], [-w.z, 0.0, w.x], [w.y, -w.x, 0.0]];
        for (i, row) in block.iter().enumerate() {
            for (j, &v) in row.iter().enumerate() {
                out.hess[3 * r + i][3 * c + j] = v;
                out.hess[3 * c + j][3 * r + i] = v;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::local::fd::{
        box_surface, check_kernel, nodes, rotation, same_local, subdivided,
    };
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn closed_box_encloses_its_volume_wherever_it_is() {
        let (lo, hi) = (Vector3::new(-0.3, 0.2, 1.0), Vector3::new(1.2, 0.7, 1.9));
        let r = rotation(0.3, -1.1, 2.0);
        let t = Vector3::new(3.0, -2.0, 0.5);
        let tris = box_surface(lo, hi, 3, |p| r * p + t);
        let v: f64 = tris.iter().map(|x| volume(x).value).sum();
        let exact = 1.5 * 0.5 * 0.9;
        assert!((v - exact).abs() < 1e-13, "{v} vs {exact}");
        // Translation invariance: the gradients sum to zero over a closed surface.
        for k in 0..3 {
            let f: f64 = tris
                .iter()
                .map(|x| (0..3).map(|n| volume(x).grad[3 * n + k]).sum::<f64>())
                .sum();
            assert!(f.abs() < 1e-13);
        }
    }

    #[test]
    fn euler_identity_and_translation_of_one_triangle() {
        // V_T is cubic and homogeneous: Σ x·∇V = 3 V, and H x = 2 ∇V.
        let x = nodes(&[0.1, -0.2, 0.4, 1.3, 0.1, 0.05, 0.4, 0.9, -0.1]);
        let l = volume(&x);
        let flat: Vec<f64> = x.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
        let euler: f64 = (0..9).map(|i| flat[i] * l.grad[i]).sum();
        assert!((euler - 3.0 * l.value).abs() < 1e-14);
        for i in 0..9 {
            let hx: f64 = (0..9).map(|j| l.hess[i][j] * flat[j]).sum();
            assert!((hx - 2.0 * l.grad[i]).abs() < 1e-14);
        }
    }

    proptest! {
        #[test]
        fn gradient_and_hessian_match_finite_differences(
            p in proptest::array::uniform9(-2.0f64..2.0),
            dir in proptest::array::uniform9(-1.0f64..1.0),
        ) {
            check_kernel(volume, &nodes(&p), &dir, 1e-5, 1e-8).map_err(TestCaseError::fail)?;
        }

        #[test]
        fn subdivision_adds_up(p in proptest::array::uniform9(-2.0f64..2.0)) {
            let x = nodes(&p);
            same_local(&subdivided(volume, &x), &volume(&x), 1e-12).map_err(TestCaseError::fail)?;
        }
    }
}

/// A fixed flat horizontal face that closes an open membrane along its fixed rim (a plate),
/// oriented like the membrane: the z-component of its area vector and its height.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosingFace {
    /// Height z_c of the face.
    pub z: f64,
    /// z-component of its area vector (signed by the outward orientation of the closed body).
    pub area_z: f64,
}

impl ClosingFace {
    /// Its contribution (1/3)∫ x·n dA = z_c A_z / 3 to the enclosed volume.
    pub fn volume(&self) -> f64 {
        self.z * self.area_z / 3.0
    }

    /// Its contribution ∫ min(z, h) n_z dA = min(z_c, h) A_z to the fluid volume below h,
    /// and the derivative in h.
    pub fn fluid_volume(&self, h: f64) -> (f64, f64) {
        if h < self.z {
            (h * self.area_z, self.area_z)
        } else {
            (self.z * self.area_z, 0.0)
        }
    }
}
