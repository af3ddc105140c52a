//! The derivatives of the area vector that the per-triangle kernels share. A kernel sees one
//! flat triangle `x = [x1, x2, x3]` whose nodes run counter-clockwise seen from the side its
//! normal points to (outward for a closed surface) and returns a [`crate::model::Local`]: a value with its
//! gradient (9) and Hessian (9×9) in node-major order x1, y1, z1, x2, …, z3.
//!
//! The area vector of the triangle is
//!
//! ```text
//!   N = a × b = x1×x2 + x2×x3 + x3×x1,     a = x2 − x1, b = x3 − x1,
//! ```
//!
//! so that ∫_T n dA = N/2 and, with x(ξ, η) = x1 + ξ a + η b on the reference triangle
//! R = {ξ, η ≥ 0, ξ + η ≤ 1}, `n dA = N dξ dη`. Its components are bilinear in the nodes:
//! ∂N_c/∂x_{i,j} = ε_{cjk} (x_{i+1,k} − x_{i−1,k}) and ∂²N_c/∂x_{i,j}∂x_{m,k} =
//! ε_{cjk} (δ_{m,i+1} − δ_{m,i−1}) (node indices cyclic), a constant matrix.

use nalgebra::Vector3;

/// Levi-Civita symbol ε_{cjk} for indices in 0..3.
fn levi_civita(c: usize, j: usize, k: usize) -> f64 {
    match (c, j, k) {
        (0, 1, 2) | (1, 2, 0) | (2, 0, 1) => 1.0,
        (0, 2, 1) | (2, 1, 0) | (1, 0, 2) => -1.0,
        _ => 0.0,
    }
}

/// The area vector N = (x2 − x1) × (x3 − x1) (twice the vector area of the triangle).
pub fn area_vector(x: &[Vector3<f64>; 3]) -> Vector3<f64> {
    (x[1] - x[0]).cross(&(x[2] - x[0]))
}

/// Gradient of the component N_c (c = 0, 1, 2 for x, y, z) of the area vector.
pub fn area_vector_gradient(x: &[Vector3<f64>; 3], c: usize) -> [f64; 9] {
    let mut g = [0.0; 9];
    for i in 0..3 {
        let d = x[(i + 1) % 3] - x[(i + 2) % 3];
        for j in 0..3 {
            g[3 * i + j] = (0..3).map(|k| levi_civita(c, j, k) * d[k]).sum();
        }
    }
    g
}

/// Hessian of the component N_c of the area vector (constant).
pub fn area_vector_hessian(c: usize) -> [[f64; 9]; 9] {
    let mut h = [[0.0; 9]; 9];
    for i in 0..3 {
        let (next, prev) = ((i + 1) % 3, (i + 2) % 3);
        for j in 0..3 {
            for k in 0..3 {
                let e = levi_civita(c, j, k);
                h[3 * i + j][3 * next + k] += e;
                h[3 * i + j][3 * prev + k] -= e;
            }
        }
    }
    h
}

/// Finite-difference checks shared by every kernel's tests.
#[cfg(test)]
pub(crate) mod fd {
    use crate::model::Local;
    use nalgebra::Vector3;

    /// x + s·d with d a 9-vector in node-major order.
    pub(crate) fn perturbed(x: &[Vector3<f64>; 3], d: &[f64; 9], s: f64) -> [Vector3<f64>; 3] {
        [0, 1, 2].map(|n| x[n] + s * Vector3::new(d[3 * n], d[3 * n + 1], d[3 * n + 2]))
    }

    /// Nodes from a flat array (node-major).
    pub(crate) fn nodes(p: &[f64; 9]) -> [Vector3<f64>; 3] {
        [0, 1, 2].map(|n| Vector3::new(p[3 * n], p[3 * n + 1], p[3 * n + 2]))
    }

    /// Largest absolute entry of the gradient and Hessian (at least `floor`).
    pub(crate) fn scale(l: &Local, floor: f64) -> f64 {
        l.grad
            .iter()
            .chain(l.hess.iter().flatten())
            .fold(floor, |m, v| m.max(v.abs()))
    }

    /// `|fd − exact| ≤ tol` or a message naming `what`.
    pub(crate) fn close(what: &str, fd: f64, exact: f64, tol: f64) -> Result<(), String> {
        if (fd - exact).abs() <= tol {
            Ok(())
        } else {
            Err(format!(
                "{what}: finite difference {fd:e} vs exact {exact:e} (tol {tol:e})"
            ))
        }
    }

    /// Checks a kernel at `x` along `dir` with central differences of step `step`:
    /// the directional derivative of the value against grad·dir, the differences of the
    /// gradient against H·dir, and the symmetry of H. Tolerances are `rel_tol` times the
    /// largest entry of the gradient and Hessian at `x` (at least 1); symmetry must be exact.
    pub(crate) fn check_kernel(
        kernel: impl Fn(&[Vector3<f64>; 3]) -> Local,
        x: &[Vector3<f64>; 3],
        dir: &[f64; 9],
        step: f64,
        rel_tol: f64,
    ) -> Result<(), String> {
        let l = kernel(x);
        let (p, m) = (
            kernel(&perturbed(x, dir, step)),
            kernel(&perturbed(x, dir, -step)),
        );
        let tol = rel_tol * scale(&l, 1.0);
        let exact: f64 = (0..9).map(|i| l.grad[i] * dir[i]).sum();
        close("value", (p.value - m.value) / (2.0 * step), exact, tol)?;
        for i in 0..9 {
            let exact: f64 = (0..9).map(|j| l.hess[i][j] * dir[j]).sum();
            let fd = (p.grad[i] - m.grad[i]) / (2.0 * step);
            close(&format!("gradient row {i}"), fd, exact, tol)?;
            for j in 0..i {
                close(
                    &format!("symmetry ({i}, {j})"),
                    l.hess[i][j],
                    l.hess[j][i],
                    1e-12 * tol,
                )?;
            }
        }
        Ok(())
    }

    /// Checks the derivative of an array-valued function of one scalar parameter at `p`
    /// (central differences with step `step`) against `exact`, within `tol`.
    pub(crate) fn check_parameter<const N: usize>(
        f: impl Fn(f64) -> [f64; N],
        exact: &[f64; N],
        p: f64,
        step: f64,
        tol: f64,
    ) -> Result<(), String> {
        let (fp, fm) = (f(p + step), f(p - step));
        for i in 0..N {
            close(
                &format!("parameter derivative {i}"),
                (fp[i] - fm[i]) / (2.0 * step),
                exact[i],
                tol,
            )?;
        }
        Ok(())
    }

    /// The kernel summed over the four midpoint children of `x`, pulled back to the parent's
    /// dofs (the children's nodes are fixed affine combinations of the parent's). An exact
    /// integral over the triangle is additive, so this must reproduce `kernel(x)` exactly.
    pub(crate) fn subdivided(
        kernel: impl Fn(&[Vector3<f64>; 3]) -> Local,
        x: &[Vector3<f64>; 3],
    ) -> Local {
        // Rows: the children's nodes as weights of the parent nodes.
        let (v1, v2, v3) = ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]);
        let (m12, m23, m31) = ([0.5, 0.5, 0.0], [0.0, 0.5, 0.5], [0.5, 0.0, 0.5]);
        let children = [
            [v1, m12, m31],
            [m12, v2, m23],
            [m31, m23, v3],
            [m12, m23, m31],
        ];
        let mut out = Local::ZERO;
        for w in children {
            let xc = w.map(|r| r[0] * x[0] + r[1] * x[1] + r[2] * x[2]);
            let l = kernel(&xc);
            out.value += l.value;
            for (n, wn) in w.iter().enumerate() {
                for (p, &wnp) in wn.iter().enumerate() {
                    for k in 0..3 {
                        out.grad[3 * p + k] += wnp * l.grad[3 * n + k];
                    }
                }
                for (m, wm) in w.iter().enumerate() {
                    for (p, &wnp) in wn.iter().enumerate() {
                        for (q, &wmq) in wm.iter().enumerate() {
                            let c = wnp * wmq;
                            if c == 0.0 {
                                continue;
                            }
                            for k in 0..3 {
                                for l2 in 0..3 {
                                    out.hess[3 * p + k][3 * q + l2] +=
                                        c * l.hess[3 * n + k][3 * m + l2];
                                }
                            }
                        }
                    }
                }
            }
        }
        out
    }

    /// `a` and `b` agree entry by entry within `tol` (value, gradient and Hessian).
    pub(crate) fn same_local(a: &Local, b: &Local, tol: f64) -> Result<(), String> {
        close("value", a.value, b.value, tol)?;
        for i in 0..9 {
            close(&format!("gradient {i}"), a.grad[i], b.grad[i], tol)?;
            for j in 0..9 {
                close(
                    &format!("Hessian ({i}, {j})"),
                    a.hess[i][j],
                    b.hess[i][j],
                    tol,
                )?;
            }
        }
        Ok(())
    }

    /// A closed, outward-oriented triangle soup of the box [lo, hi], each face cut into n×n
    /// squares of two triangles, mapped by `map` (a rigid motion keeps it closed and outward).
    pub(crate) fn box_surface(
        lo: Vector3<f64>,
        hi: Vector3<f64>,
        n: usize,
        map: impl Fn(Vector3<f64>) -> Vector3<f64>,
    ) -> Vec<[Vector3<f64>; 3]> {
        let d = hi - lo;
        let (ex, ey, ez) = (
            Vector3::new(d.x, 0.0, 0.0),
            Vector3::new(0.0, d.y, 0.0),
            Vector3::new(0.0, 0.0, d.z),
        );
        // (corner, u, v) with u × v pointing out of the box.
        let faces = [
            (lo, ey, ex),      // z = lo.z, normal −z
            (lo + ez, ex, ey), // z = hi.z, normal +z
            (lo, ex, ez),      // y = lo.y, normal −y
            (lo + ey, ez, ex), // y = hi.y, normal +y
            (lo, ez, ey),      // x = lo.x, normal −x
            (lo + ex, ey, ez), // x = hi.x, normal +x
        ];
        let mut tris = Vec::new();
        for (o, u, v) in faces {
            let p =
                |i: usize, j: usize| map(o + u * (i as f64 / n as f64) + v * (j as f64 / n as f64));
            for i in 0..n {
                for j in 0..n {
                    tris.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
                    tris.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
                }
            }
        }
        tris
    }

    /// A rotation matrix from Euler-like angles about z, then y, then x (any proper rotation).
    pub(crate) fn rotation(a: f64, b: f64, c: f64) -> nalgebra::Matrix3<f64> {
        let rz = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), a);
        let ry = nalgebra::Rotation3::from_axis_angle(&Vector3::y_axis(), b);
        let rx = nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), c);
        (rx * ry * rz).into_inner()
    }
}

#[cfg(test)]
mod tests {
    use super::fd::{check_kernel, nodes};
    use super::*;
    use crate::model::Local;
    use proptest::prelude::*;

    /// The area-vector component as a kernel (a check of the helpers themselves).
    fn component(x: &[Vector3<f64>; 3], c: usize) -> Local {
        Local {
            value: area_vector(x)[c],
            grad: area_vector_gradient(x, c),
            hess: area_vector_hessian(c),
        }
    }

    proptest! {
        #[test]
        fn area_vector_derivatives_match_finite_differences(
            p in proptest::array::uniform9(-2.0f64..2.0),
            dir in proptest::array::uniform9(-1.0f64..1.0),
            c in 0usize..3,
        ) {
            let x = nodes(&p);
            check_kernel(|x| component(x, c), &x, &dir, 1e-5, 1e-8)
                .map_err(TestCaseError::fail)?;
        }
    }
}
