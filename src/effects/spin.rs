//! Fluid spinning about the z-axis, one triangle at a time (docs/theory.md §5).
//!
//! In the frame rotating at ω the fluid filling Ω has the potential
//! Π_ω = −(ρ ω²/2) ∫_Ω (x² + y²) dV. The divergence theorem with the field (x³/3, y³/3, 0),
//! whose divergence is x² + y², turns it into a sum over an outward triangulation:
//!
//! ```text
//!   Π_ω = ρ ω² Σ_T ψ_T,      ψ_T(x) = −(1/6) ∫_T (x³ n_x + y³ n_y) dA.
//! ```
//!
//! The parameter ω² enters linearly, so ∂F/∂(ω²) = ρ Σ ∇ψ_T and no parameter derivative is
//! needed here. Orientation as for every kernel: nodes counter-clockwise seen from the side the
//! normal points to, which is out of the fluid.
//!
//! On the flat triangle x(ξ, η) = x1 + ξ a + η b over the reference triangle R, n dA =
//! N dξ dη with the constant area vector N = a × b, and each coordinate u (x or y) is linear,
//! u = Σ_i u_i λ_i. The cubic is integrated exactly with the monomial integrals
//! ∫_R λ1^p λ2^q λ3^r = p! q! r! / (p + q + r + 2)!, which give
//!
//! ```text
//!   ∫_R u³ dξ dη = h3(u1, u2, u3) / 20,
//!   h3(u) = Σ_{i≤j≤k} u_i u_j u_k = Σ u_i³ + Σ_{i≠j} u_i² u_j + u1 u2 u3
//!         = (p1³ + 3 p1 p2 + 2 p3)/6       (p_k = Σ_i u_i^k),
//! ```
//!
//! (the complete homogeneous symmetric polynomial of degree 3), so
//!
//! ```text
//!   ψ_T = −(1/120) (N_x h3(x1, x2, x3) + N_y h3(y1, y2, y3)).
//! ```
//!
//! Each term is a product N_c · h3(u^c): its gradient is h3 ∇N_c + N_c ∇h3 and its Hessian
//! h3 ∇²N_c + ∇N_c ∇h3ᵀ + ∇h3 ∇N_cᵀ + N_c ∇²h3, with
//! ∂h3/∂u_i = (p1² + p2)/2 + p1 u_i + u_i² and
//! ∂²h3/∂u_i∂u_j = p1 + u_i + u_j + δ_ij (p1 + 2 u_i). Because the integral is exact, the
//! tangent is the exact Hessian of the discrete potential: symmetric, and the load is
//! conservative (an inexact rule, e.g. the centroid, would lose both).

use super::hydrostatic::FluidSide;
use super::local::{area_vector, area_vector_gradient, area_vector_hessian};
use super::spec::{self, Build, Built, EffectSpec, MeridianLoad, Natural, Range, Refusal, Scale};
use super::Quantity;
use crate::axisym::Pressure;
use crate::model::Local;
use crate::model::{Assembler, Effect, ModelError, Vec3};
use nalgebra::Vector3;
use symmetry::Invariant;

/// Fluid spinning about the z-axis at angular velocity ω (parameter ω²), in the rotating
/// frame: Π_ω = ±ρ ω² Σ_T ψ_T (+ for fluid behind the membrane, − in front), exact for the
/// cubic integrand so that K stays symmetric. Loads: ∂F/∂(ω²) = ±ρ ∇ψ, ∂F/∂ρ = ±ω² ∇ψ.
#[derive(Debug, Clone)]
pub struct Spin {
    /// Density ρ.
    pub density: Quantity,
    /// ω².
    pub omega2: Quantity,
    /// Side of the membrane the fluid is on.
    pub side: FluidSide,
}

impl Effect for Spin {
    fn name(&self) -> &str {
        "spin"
    }

    /// Spin about z keeps the z-axis as a line: rotations about it, vertical mirrors, and
    /// anything mapping z to −z.
    fn keeps(&self) -> Vec<Invariant> {
        vec![Invariant::Axis(Vector3::z())]
    }

    /// Translation along and rotation about the spin axis z.
    fn rigid_motions(&self) -> Vec<[f64; 6]> {
        let m = crate::model::ALL_RIGID_MOTIONS;
        vec![m[2], m[5]]
    }

    /// A translation across the axis lowers Π_ω by (ρ ω²/2) V t² (the body drifts outward):
    /// the trivial instability of the frame's choice of axis, held by the analysis.
    fn drifts(&self) -> Vec<[f64; 6]> {
        let m = crate::model::ALL_RIGID_MOTIONS;
        vec![m[0], m[1]]
    }

    fn assemble(
        &self,
        x: &[Vec3],
        params: &[f64],
        out: &mut Assembler<'_>,
    ) -> Result<(), ModelError> {
        let sign = match self.side {
            FluidSide::Behind => 1.0,
            FluidSide::Front => -1.0,
        };
        let rho = self.density.value(params);
        let w2 = self.omega2.value(params);
        out.add_triangles(
            x,
            [self.omega2.parameter(), self.density.parameter()],
            |_, xt, terms| {
                let psi = potential(xt);
                terms.local = psi.scaled(sign * rho * w2);
                terms.loads[0] = psi.grad.map(|g| sign * rho * g);
                terms.loads[1] = psi.grad.map(|g| sign * w2 * g);
                Ok(())
            },
        )
    }
}

/// h3(u), its gradient and Hessian.
fn h3(u: [f64; 3]) -> (f64, [f64; 3], [[f64; 3]; 3]) {
    let p1 = u[0] + u[1] + u[2];
    let p2 = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
    let p3 = u[0].powi(3) + u[1].powi(3) + u[2].powi(3);
    let value = (p1 * p1 * p1 + 3.0 * p1 * p2 + 2.0 * p3) / 6.0;
    let grad = u.map(|ui| 0.5 * (p1 * p1 + p2) + p1 * ui + ui * ui);
    let mut hess = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            hess[i][j] = p1 + u[i] + u[j];
        }
        hess[i][i] += p1 + 2.0 * u[i];
    }
    (value, grad, hess)
}

/// ψ_T = −(1/6) ∫_T (x³ n_x + y³ n_y) dA with its gradient and Hessian (node-major dofs);
/// Π_ω = ρ ω² Σ_T ψ_T.
pub fn potential(x: &[Vector3<f64>; 3]) -> Local {
    let s = -1.0 / 120.0;
    let n = area_vector(x);
    let mut out = Local::ZERO;
    for c in 0..2 {
        let (hv, hg, hh) = h3([x[0][c], x[1][c], x[2][c]]);
        let gn = area_vector_gradient(x, c);
        let hn = area_vector_hessian(c);
        // ∇h3 lives on the c-dofs 3i + c.
        let mut gh = [0.0; 9];
        for i in 0..3 {
            gh[3 * i + c] = hg[i];
        }
        out.value += s * n[c] * hv;
        for a in 0..9 {
            out.grad[a] += s * (hv * gn[a] + n[c] * gh[a]);
            for b in 0..9 {
                out.hess[a][b] += s * (hv * hn[a][b] + gn[a] * gh[b] + gh[a] * gn[b]);
            }
        }
        for (i, row) in hh.iter().enumerate() {
            for (j, v) in row.iter().enumerate() {
                out.hess[3 * i + c][3 * j + c] += s * n[c] * v;
            }
        }
    }
    out.mirror_upper();
    out
}

#[cfg(test)]
mod tests {
    use super::super::local::fd::{
        box_surface, check_kernel, nodes, rotation, same_local, scale, subdivided,
    };
    use super::*;
    use nalgebra::Matrix3;
    use proptest::prelude::*;

    #[test]
    fn h3_matches_its_expansion() {
        let u = [0.3, -1.2, 0.7];
        let direct = u.iter().map(|v| v * v * v).sum::<f64>()
            + (0..3)
                .flat_map(|i| (0..3).filter(move |&j| j != i).map(move |j| (i, j)))
                .map(|(i, j)| u[i] * u[i] * u[j])
                .sum::<f64>()
            + u[0] * u[1] * u[2];
        assert!((h3(u).0 - direct).abs() < 1e-15);
    }

    /// ∫ x xᵀ dV over the box [lo, hi] moved by p ↦ R p + t.
    fn second_moment(
        lo: Vector3<f64>,
        hi: Vector3<f64>,
        r: &Matrix3<f64>,
        t: &Vector3<f64>,
    ) -> Matrix3<f64> {
        let len = hi - lo;
        let vol = len.x * len.y * len.z;
        // Per axis: mean of p and of p².
        let m1 = Vector3::from_fn(|k, _| 0.5 * (hi[k] + lo[k]));
        let m2 = Vector3::from_fn(|k, _| (hi[k].powi(3) - lo[k].powi(3)) / (3.0 * len[k]));
        let s = Matrix3::from_fn(|i, j| vol * if i == j { m2[i] } else { m1[i] * m1[j] });
        let m = vol * m1;
        r * s * r.transpose()
            + (r * m) * t.transpose()
            + t * (r * m).transpose()
            + vol * t * t.transpose()
    }

    #[test]
    fn closed_boxes_give_the_moment_of_inertia() {
        let (lo, hi) = (Vector3::new(-0.3, 0.2, -1.0), Vector3::new(1.2, 0.7, 0.4));
        let cases = [
            (Matrix3::identity(), Vector3::zeros()),
            (rotation(0.7, 0.0, 0.0), Vector3::new(0.5, -0.3, 2.0)),
            (rotation(0.3, -1.1, 2.0), Vector3::new(3.0, -2.0, 0.5)),
            (rotation(-2.0, 0.4, 0.9), Vector3::new(-0.1, 0.4, -0.7)),
        ];
        for (r, t) in cases {
            let tris = box_surface(lo, hi, 3, |p| r * p + t);
            let psi: f64 = tris.iter().map(|x| potential(x).value).sum();
            let s = second_moment(lo, hi, &r, &t);
            let exact = -0.5 * (s[(0, 0)] + s[(1, 1)]);
            assert!(
                (psi - exact).abs() < 1e-12 * exact.abs(),
                "{psi} vs {exact}"
            );
            // Π_ω is unchanged by translations along the axis: the z-forces cancel.
            let fz: f64 = tris
                .iter()
                .map(|x| {
                    let g = potential(x).grad;
                    g[2] + g[5] + g[8]
                })
                .sum();
            assert!(fz.abs() < 1e-12, "net axial force {fz}");
        }
    }

    proptest! {
        #[test]
        fn gradient_and_hessian_match_finite_differences(
            p in proptest::array::uniform9(-2.0f64..2.0),
            dir in proptest::array::uniform9(-1.0f64..1.0),
        ) {
            check_kernel(potential, &nodes(&p), &dir, 1e-5, 1e-8).map_err(TestCaseError::fail)?;
        }

        #[test]
        fn exact_integration_is_additive_under_subdivision(
            p in proptest::array::uniform9(-2.0f64..2.0),
        ) {
            let x = nodes(&p);
            let parent = potential(&x);
            let children = subdivided(potential, &x);
            same_local(&children, &parent, 1e-12 * (1.0 + scale(&parent, 0.0)))
                .map_err(TestCaseError::fail)?;
        }
    }
}

/// `[[effect]] type = "spin"`: the fluid in the enclosed region spins about the z-axis with
/// angular speed ω; Π = −(ρω²/2) ∫Ω (x² + y²) dV.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct SpinEffect {
    /// Density ρ ≥ 0 of the spinning fluid.
    pub density: spec::Quantity,
    /// ω² ≥ 0 (the potential is linear in it).
    pub omega2: spec::Quantity,
}

impl EffectSpec for SpinEffect {
    fn quantities(&self) -> Vec<(&'static str, &spec::Quantity, Range)> {
        vec![
            ("density", &self.density, Range::NonNegative),
            ("omega2", &self.omega2, Range::NonNegative),
        ]
    }
    /// `ρ ω² a³/(μH)`.
    fn scales(&self, n: &Natural) -> Vec<Scale> {
        let (Some(mu_h), Some(a), Some(w2), Some(rho)) = (
            n.tension,
            n.length,
            self.omega2.parameter(),
            self.density.number(),
        ) else {
            return Vec::new();
        };
        let l = n.symbol;
        vec![Scale {
            parameter: w2.to_string(),
            group: format!("ρ ω² {l}³/(μH)"),
            values: vec![("ρ".into(), rho), ("μH".into(), mu_h), (l.into(), a)],
            factor: rho * a.powi(3) / mu_h,
        }]
    }
    fn build(&self, cx: &Build) -> Built {
        Built {
            effect: Box::new(Spin {
                density: (cx.quantity)(&self.density),
                omega2: (cx.quantity)(&self.omega2),
                side: FluidSide::Behind,
            }),
            measured: None,
        }
    }
    /// The fluid spinning behind the membrane, as the 3-D effect takes it.
    fn meridian(&self, cx: &Build) -> Result<MeridianLoad, Refusal> {
        Ok(MeridianLoad::Pressure(Pressure::Spin {
            density: (cx.quantity)(&self.density),
            omega2: (cx.quantity)(&self.omega2),
        }))
    }
}
