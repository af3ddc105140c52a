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

    /// A unit hemisphere-like cap z ≥ c over a polygon rim, as triangles of a fan from the top.
    fn cap(c: f64, sides: usize) -> (Vec<Vector3<f64>>, Vec<[usize; 3]>) {
        let mut x = vec![Vector3::new(0.0, 0.0, 1.0)];
        let r = (1.0 - c * c).sqrt();
        for k in 0..sides {
            let t = 2.0 * std::f64::consts::PI * k as f64 / sides as f64;
            x.push(Vector3::new(
                0.5 * r * t.cos(),
                0.5 * r * t.sin(),
                0.5 * (1.0 + c),
            ));
            x.push(Vector3::new(r * t.cos(), r * t.sin(), c));
        }
        let mut tris = Vec::new();
        for k in 0..sides {
            let (a, b) = (1 + 2 * k, 1 + 2 * ((k + 1) % sides));
            tris.push([0, a, b]);
            tris.push([a, a + 1, b + 1]);
            tris.push([a, b + 1, b]);
        }
        (x, tris)
    }

    #[test]
    fn a_cap_closed_by_its_plate_encloses_the_same_volume_wherever_the_origin_is() {
        // Σ V_T alone depends on the origin for an open surface; with the plate's z_c A_z / 3 it
        // is the enclosed volume. A horizontal shift, and a rim slid within its plane, keep it a
        // closed body: its volume equals that of the explicitly closed polyhedron.
        let (x, tris) = cap(-0.4, 9);
        let face = ClosingFace::new(-0.4, &tris);
        let total = |x: &[Vector3<f64>]| {
            tris.iter()
                .map(|&[a, b, c]| volume(&[x[a], x[b], x[c]]).value)
                .sum::<f64>()
                + face.volume(&tris, x)
        };
        let v0 = total(&x);
        let shifted: Vec<_> = x.iter().map(|p| p + Vector3::new(0.3, -0.2, 0.0)).collect();
        assert!(
            (total(&shifted) - v0).abs() < 1e-14,
            "{} vs {v0}",
            total(&shifted)
        );
        // The rim slid: closing it explicitly by a fan from its centroid gives the same volume.
        let mut slid = x.clone();
        for (k, p) in slid
            .iter_mut()
            .enumerate()
            .filter(|(k, _)| *k > 0 && k % 2 == 0)
        {
            p.x += 0.05 * (k as f64).sin();
            p.y += 0.04 * (k as f64).cos();
        }
        let rim: Vec<usize> = (0..9).map(|k| 2 + 2 * k).collect();
        let centre = rim.iter().map(|&i| slid[i]).sum::<Vector3<f64>>() / 9.0;
        let closed: f64 = tris
            .iter()
            .map(|&[a, b, c]| volume(&[slid[a], slid[b], slid[c]]).value)
            .chain((0..9).map(|k| {
                let (a, b) = (slid[rim[k]], slid[rim[(k + 1) % 9]]);
                volume(&[centre, b, a]).value
            }))
            .sum();
        assert!(
            (total(&slid) - closed).abs() < 1e-14,
            "{} vs {closed}",
            total(&slid)
        );
    }

    proptest! {
        #[test]
        fn the_plate_area_matches_finite_differences(
            p in proptest::array::uniform9(-2.0f64..2.0),
            dir in proptest::array::uniform9(-1.0f64..1.0),
            edges in 1usize..8,
        ) {
            // Any subset of a triangle's edges on the boundary.
            let face = ClosingFace {
                z: 0.3,
                edges: vec![(0..3u8).filter(|k| edges & (1 << k) != 0).collect()],
            };
            check_kernel(|x| face.area_local(0, x), &nodes(&p), &dir, 1e-5, 1e-8)
                .map_err(TestCaseError::fail)?;
        }

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

/// A flat horizontal face (a plate at height z_c) that closes an open membrane along its rim,
/// oriented like the membrane (outward for the closed body; docs/theory.md §3.4). The
/// z-component of its area vector is
///
/// ```text
///   A_z = −½ Σ_{rim edges a→b} (x_a y_b − y_a x_b),
/// ```
///
/// summed over the membrane's boundary edges as they run in its triangles (the plate runs
/// them the other way). Its parts of the quantities the enclosure effects integrate are
/// z_c A_z/3 (enclosed volume, field x/3), min(z_c, h) A_z (fluid volume below h),
/// ½ (h − z_c)₊² A_z (the fluid's φ) and nothing for spin (n_x = n_y = 0 on it). A fixed rim
/// makes them constants; a rim that slides in the plate's plane moves A_z with its nodes, so
/// each rim edge is a term of the triangle it belongs to, with its gradient and Hessian on that
/// triangle's nodes ([`ClosingFace::area_local`]): ∂A_z/∂x_a = −½ y_b, ∂A_z/∂y_a = ½ x_b,
/// ∂A_z/∂x_b = ½ y_a, ∂A_z/∂y_b = −½ x_a, ∂²A_z/∂x_a∂y_b = −½, ∂²A_z/∂y_a∂x_b = ½.
#[derive(Debug, Clone, PartialEq)]
pub struct ClosingFace {
    /// Height z_c of the face.
    pub z: f64,
    /// For every triangle the local indices k of its boundary edges (from node k to k + 1).
    edges: Vec<Vec<u8>>,
}

impl ClosingFace {
    /// The face at height `z` spanning the boundary of the membrane `triangles` (a boundary
    /// edge is a directed edge of a triangle whose reverse is in no triangle).
    pub fn new(z: f64, triangles: &[[usize; 3]]) -> Self {
        let directed: std::collections::HashSet<(usize, usize)> = triangles
            .iter()
            .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
            .collect();
        let edges = triangles
            .iter()
            .map(|t| {
                (0..3u8)
                    .filter(|&k| {
                        let (a, b) = (t[k as usize], t[(k as usize + 1) % 3]);
                        !directed.contains(&(b, a))
                    })
                    .collect()
            })
            .collect();
        Self { z, edges }
    }

    /// The face's A_z with its gradient and Hessian on the nodes of triangle `t` at positions
    /// `x` (zero for a triangle without a boundary edge).
    pub fn area_local(&self, t: usize, x: &[Vector3<f64>; 3]) -> Local {
        let mut out = Local::ZERO;
        for &k in &self.edges[t] {
            let (a, b) = (k as usize, (k as usize + 1) % 3);
            out.value -= 0.5 * (x[a].x * x[b].y - x[a].y * x[b].x);
            out.grad[3 * a] -= 0.5 * x[b].y;
            out.grad[3 * a + 1] += 0.5 * x[b].x;
            out.grad[3 * b] += 0.5 * x[a].y;
            out.grad[3 * b + 1] -= 0.5 * x[a].x;
            out.hess[3 * a][3 * b + 1] -= 0.5;
            out.hess[3 * b + 1][3 * a] -= 0.5;
            out.hess[3 * a + 1][3 * b] += 0.5;
            out.hess[3 * b][3 * a + 1] += 0.5;
        }
        out
    }

    /// True if triangle `t` has a boundary edge.
    pub fn touches(&self, t: usize) -> bool {
        !self.edges[t].is_empty()
    }

    /// A_z at positions `x` of the membrane `triangles`.
    pub fn area_z(&self, triangles: &[[usize; 3]], x: &[Vector3<f64>]) -> f64 {
        triangles
            .iter()
            .enumerate()
            .filter(|(t, _)| self.touches(*t))
            .map(|(t, &[a, b, c])| self.area_local(t, &[x[a], x[b], x[c]]).value)
            .sum()
    }

    /// Its part z_c A_z/3 of the enclosed volume.
    pub fn volume(&self, triangles: &[[usize; 3]], x: &[Vector3<f64>]) -> f64 {
        self.z * self.area_z(triangles, x) / 3.0
    }

    /// Its part of the fluid volume below the level h, min(z_c, h) A_z (z_c A_z when the
    /// enclosure is `filled`), with the derivative in h.
    pub fn fluid_volume(
        &self,
        triangles: &[[usize; 3]],
        x: &[Vector3<f64>],
        h: f64,
        filled: bool,
    ) -> (f64, f64) {
        let a = self.area_z(triangles, x);
        if h < self.z && !filled {
            (h * a, a)
        } else {
            (self.z * a, 0.0)
        }
    }

    /// The coefficients (c, c′, c″) of the face's part of the fluid's φ and its
    /// h-derivatives: φ_face = c A_z with c = ½ (h − z_c)₊² (½ (h − z_c)² when `filled`),
    /// c′ = ∂c/∂h, c″ = ∂²c/∂h².
    pub fn fluid_coefficients(&self, h: f64, filled: bool) -> (f64, f64, f64) {
        let d = h - self.z;
        if filled || d > 0.0 {
            (0.5 * d * d, d, 1.0)
        } else {
            (0.0, 0.0, 0.0)
        }
    }
}
