//! Incompressible Mooney-Rivlin membrane on flat 3-node triangles.
//!
//! Reference nodes X1..X3, current x1..x3; edges a = x2 − x1, b = x3 − x1 and the current
//! metric g = [[a·a, a·b], [a·b, b·b]]; G the same from the reference. With an isotropic
//! pre-stretch λ0 the stress-free metric is G0 = G/λ0². Plane stress and incompressibility
//! leave two invariants,
//!
//! ```text
//!   t = tr(G0⁻¹ g) = λ1² + λ2²,     J = det g / det G0 = λ1² λ2²     (λ3² = 1/J)
//!   I1 = t + 1/J,   I2 = J + t/J,   W = c1 (I1 − 3) + c2 (I2 − 3),
//!   μ/2 = c1 + c2,  k = c2/c1,      Π_el = H · A0 · W,  A0 = ½ √det G0
//! ```
//!
//! (H and A0 are the stress-free thickness and area). Gradient and Hessian follow by the chain
//! rule through (g11, g12, g22), in closed form: with W_p = ∂W/∂g_p,
//! ∂Π/∂a = H A0 (2 W_11 a + W_12 b), ∂Π/∂b = H A0 (W_12 a + 2 W_22 b), and the Hessian
//! Σ_pq W_pq ∇g_p ∇g_qᵀ + Σ_p W_p ∇²g_p. Nodes: x1 takes −(∂/∂a + ∂/∂b), x2 ∂/∂a, x3 ∂/∂b.

use super::local::Local;
use crate::model::{Assembler, Effect, ModelError, Vec3};
use nalgebra::{Matrix2, Vector3};
use symmetry::Invariant;

/// Mooney-Rivlin constants and thickness.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MooneyRivlin {
    /// c1 = μ / (2 (1 + k)).
    pub c1: f64,
    /// c2 = k c1.
    pub c2: f64,
    /// Stress-free thickness H.
    pub thickness: f64,
}

impl MooneyRivlin {
    /// From the shear modulus μ, the ratio k = c2/c1 and the thickness.
    pub fn new(mu: f64, k: f64, thickness: f64) -> Self {
        let c1 = 0.5 * mu / (1.0 + k);
        Self {
            c1,
            c2: k * c1,
            thickness,
        }
    }

    /// W and its derivatives in (t, J): (W, W_t, W_J, W_tJ, W_JJ); W_tt = 0.
    fn strain_energy(&self, t: f64, j: f64) -> [f64; 5] {
        let (c1, c2) = (self.c1, self.c2);
        let w = c1 * (t + 1.0 / j - 3.0) + c2 * (j + t / j - 3.0);
        let w_t = c1 + c2 / j;
        let w_j = -c1 / (j * j) + c2 * (1.0 - t / (j * j));
        let w_tj = -c2 / (j * j);
        let w_jj = 2.0 * (c1 + c2 * t) / (j * j * j);
        [w, w_t, w_j, w_tj, w_jj]
    }
}

/// What one triangle needs from its reference state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReferenceTriangle {
    /// G0⁻¹ entries (11, 12, 22).
    g0_inv: [f64; 3],
    /// det G0.
    det_g0: f64,
    /// H · A0 (stress-free volume of the element).
    volume: f64,
}

impl ReferenceTriangle {
    /// From reference positions, pre-stretch λ0 and thickness; `None` for a degenerate triangle.
    pub fn new(x: &[Vector3<f64>; 3], prestretch: f64, thickness: f64) -> Option<Self> {
        let (a, b) = (x[1] - x[0], x[2] - x[0]);
        let s = prestretch * prestretch;
        let g0 = Matrix2::new(a.dot(&a), a.dot(&b), a.dot(&b), b.dot(&b)) / s;
        let det_g0 = g0.determinant();
        if det_g0.is_nan() || det_g0 <= 0.0 {
            return None;
        }
        let inv = g0.try_inverse()?;
        Some(Self {
            g0_inv: [inv[(0, 0)], inv[(0, 1)], inv[(1, 1)]],
            det_g0,
            volume: thickness * 0.5 * det_g0.sqrt(),
        })
    }

    /// The element's energy, its gradient (9, node-major) and Hessian (9×9) at `x`.
    /// `None` if the triangle is inverted or collapsed (J ≤ 0), where W is not defined.
    pub fn energy_gradient_hessian(
        &self,
        mat: &MooneyRivlin,
        x: &[Vector3<f64>; 3],
    ) -> Option<Local> {
        let (a, b) = (x[1] - x[0], x[2] - x[0]);
        let g = [a.dot(&a), a.dot(&b), b.dot(&b)];
        let [i11, i12, i22] = self.g0_inv;
        let d = self.det_g0;
        let t = i11 * g[0] + 2.0 * i12 * g[1] + i22 * g[2];
        let j = (g[0] * g[2] - g[1] * g[1]) / d;
        if j.is_nan() || j <= 0.0 {
            return None;
        }
        let [w, w_t, w_j, w_tj, w_jj] = mat.strain_energy(t, j);
        // First derivatives of t and J in p = (g11, g12, g22).
        let t_p = [i11, 2.0 * i12, i22];
        let j_p = [g[2] / d, -2.0 * g[1] / d, g[0] / d];
        // Second derivatives of J: ∂²J/∂g11∂g22 = 1/D, ∂²J/∂g12² = −2/D.
        let j_pq = [
            [0.0, 0.0, 1.0 / d],
            [0.0, -2.0 / d, 0.0],
            [1.0 / d, 0.0, 0.0],
        ];
        let s = self.volume;
        let mut w_p = [0.0; 3];
        let mut w_pq = [[0.0; 3]; 3];
        for p in 0..3 {
            w_p[p] = s * (w_t * t_p[p] + w_j * j_p[p]);
            for q in 0..3 {
                w_pq[p][q] = s
                    * (w_tj * (t_p[p] * j_p[q] + j_p[p] * t_p[q])
                        + w_jj * j_p[p] * j_p[q]
                        + w_j * j_pq[p][q]);
            }
        }
        // ∇g_p with respect to (a, b) ∈ R⁶.
        let zero = Vector3::zeros();
        let dg: [[Vector3<f64>; 2]; 3] = [[2.0 * a, zero], [b, a], [zero, 2.0 * b]];
        let mut grad_ab = [0.0; 6];
        let mut hess_ab = [[0.0; 6]; 6];
        for p in 0..3 {
            for (u, v) in dg[p].iter().enumerate() {
                for k in 0..3 {
                    grad_ab[3 * u + k] += w_p[p] * v[k];
                }
            }
            for q in 0..3 {
                for (u, vu) in dg[p].iter().enumerate() {
                    for (v, vv) in dg[q].iter().enumerate() {
                        for k in 0..3 {
                            for l in 0..3 {
                                hess_ab[3 * u + k][3 * v + l] += w_pq[p][q] * vu[k] * vv[l];
                            }
                        }
                    }
                }
            }
        }
        // Σ_p W_p ∇²g_p: ∇²g11 = 2 I in (a, a); ∇²g12 = I in (a, b) and (b, a); ∇²g22 = 2 I in (b, b).
        for k in 0..3 {
            hess_ab[k][k] += 2.0 * w_p[0];
            hess_ab[k][3 + k] += w_p[1];
            hess_ab[3 + k][k] += w_p[1];
            hess_ab[3 + k][3 + k] += 2.0 * w_p[2];
        }
        // Map (a, b) to nodes: a = x2 − x1, b = x3 − x1.
        let coef = |node: usize, u: usize| -> f64 {
            match (node, u) {
                (0, _) => -1.0,
                (1, 0) | (2, 1) => 1.0,
                _ => 0.0,
            }
        };
        let mut grad = [0.0; 9];
        let mut hess = [[0.0; 9]; 9];
        for n in 0..3 {
            for k in 0..3 {
                grad[3 * n + k] = (0..2).map(|u| coef(n, u) * grad_ab[3 * u + k]).sum();
            }
        }
        for n in 0..3 {
            for m in 0..3 {
                for u in 0..2 {
                    for v in 0..2 {
                        let c = coef(n, u) * coef(m, v);
                        if c == 0.0 {
                            continue;
                        }
                        for k in 0..3 {
                            for l in 0..3 {
                                hess[3 * n + k][3 * m + l] += c * hess_ab[3 * u + k][3 * v + l];
                            }
                        }
                    }
                }
            }
        }
        let mut local = Local {
            value: s * w,
            grad,
            hess,
        };
        // Symmetric to the last bit, whatever order the terms were summed in.
        local.mirror_upper();
        Some(local)
    }
}

/// The membrane effect: every triangle's Mooney-Rivlin energy.
#[derive(Debug, Clone)]
pub struct Membrane {
    material: MooneyRivlin,
    elements: Vec<ReferenceTriangle>,
}

impl Membrane {
    /// Precomputes every triangle's reference data; fails naming the first degenerate triangle.
    pub fn new(
        reference: &[Vec3],
        triangles: &[[usize; 3]],
        material: MooneyRivlin,
        prestretch: f64,
    ) -> Result<Self, String> {
        let elements = triangles
            .iter()
            .enumerate()
            .map(|(t, &[a, b, c])| {
                ReferenceTriangle::new(
                    &[reference[a], reference[b], reference[c]],
                    prestretch,
                    material.thickness,
                )
                .ok_or_else(|| format!("triangle {t} is degenerate in the reference state"))
            })
            .collect::<Result<_, _>>()?;
        Ok(Self { material, elements })
    }
}

impl Effect for Membrane {
    fn name(&self) -> &str {
        "membrane"
    }

    /// An isotropic material keeps every symmetry of the mesh.
    fn keeps(&self) -> Vec<Invariant> {
        Vec::new()
    }

    /// Strain energy depends only on the metric: every rigid motion keeps it.
    fn rigid_motions(&self) -> Vec<[f64; 6]> {
        crate::model::ALL_RIGID_MOTIONS.to_vec()
    }

    fn assemble(
        &self,
        x: &[Vec3],
        _params: &[f64],
        out: &mut Assembler<'_>,
    ) -> Result<(), ModelError> {
        out.add_triangles(x, [None, None], |t, xt, terms| {
            terms.local = self.elements[t]
                .energy_gradient_hessian(&self.material, xt)
                .ok_or_else(|| "inverted or collapsed element".to_string())?;
            Ok(())
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::local::fd::{check_kernel, perturbed};
    use super::*;
    use proptest::prelude::*;

    fn triangle() -> [Vector3<f64>; 3] {
        [
            Vector3::new(0.1, -0.2, 0.0),
            Vector3::new(1.3, 0.1, 0.05),
            Vector3::new(0.4, 0.9, -0.1),
        ]
    }

    #[test]
    fn equibiaxial_stretch_matches_the_closed_form() {
        let mat = MooneyRivlin::new(1.0, 0.1, 0.01);
        let x0 = triangle();
        let (lambda0, lambda) = (1.1, 1.7);
        let elem = ReferenceTriangle::new(&x0, lambda0, mat.thickness).unwrap();
        // Scaling the reference by λ/λ0 stretches the stress-free state by λ in every direction.
        let x = x0.map(|p| p * (lambda / lambda0));
        let e = elem.energy_gradient_hessian(&mat, &x).unwrap().value;
        let l2 = lambda * lambda;
        let w = mat.c1 * (2.0 * l2 + 1.0 / (l2 * l2) - 3.0) + mat.c2 * (l2 * l2 + 2.0 / l2 - 3.0);
        let a0 = 0.5 * (x0[1] - x0[0]).cross(&(x0[2] - x0[0])).norm() / (lambda0 * lambda0);
        assert!((e - mat.thickness * a0 * w).abs() < 1e-13 * e.abs());
    }

    #[test]
    fn stress_free_state_has_zero_energy_and_force() {
        let mat = MooneyRivlin::new(2.0, 0.3, 0.1);
        let x = triangle();
        let elem = ReferenceTriangle::new(&x, 1.0, mat.thickness).unwrap();
        let Local {
            value: e, grad: g, ..
        } = elem.energy_gradient_hessian(&mat, &x).unwrap();
        assert!(e.abs() < 1e-14);
        assert!(g.iter().all(|v| v.abs() < 1e-13));
    }

    #[test]
    fn degenerate_and_inverted_states_are_refused() {
        let mat = MooneyRivlin::new(1.0, 0.0, 1.0);
        let x = triangle();
        assert!(ReferenceTriangle::new(&[x[0], x[1], x[1]], 1.0, 1.0).is_none());
        let elem = ReferenceTriangle::new(&x, 1.0, 1.0).unwrap();
        assert!(elem
            .energy_gradient_hessian(&mat, &[x[0], x[0], x[2]])
            .is_none());
    }

    proptest! {
        #[test]
        fn gradient_and_hessian_match_finite_differences(
            d in proptest::array::uniform9(-0.3f64..0.3),
            dir in proptest::array::uniform9(-1.0f64..1.0),
            k in 0.0f64..0.5,
            lambda0 in 1.0f64..1.5,
        ) {
            let mat = MooneyRivlin::new(1.0, k, 1.0);
            let x0 = triangle();
            let elem = ReferenceTriangle::new(&x0, lambda0, mat.thickness).unwrap();
            let x = perturbed(&x0, &d, 1.0);
            let step = 1e-6;
            let defined = |s: f64| elem.energy_gradient_hessian(&mat, &perturbed(&x, &dir, s)).is_some();
            // Random states may invert the element, where W is undefined: nothing to compare.
            prop_assume!(defined(0.0) && defined(step) && defined(-step));
            let kernel = |y: &[Vector3<f64>; 3]| elem.energy_gradient_hessian(&mat, y).unwrap_or(Local::ZERO);
            check_kernel(kernel, &x, &dir, step, 1e-6).map_err(TestCaseError::fail)?;
        }
    }
}
