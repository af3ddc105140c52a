//! Fluid under gravity, one triangle at a time, with exact clipping at the level (docs/theory.md §4).
//!
//! # Potential
//!
//! Gravity points along −z, the free surface is the plane z = h and the fluid pressure is
//! ρ g (h − z)₊. For fluid filling the region Ω enclosed by the membrane,
//!
//! ```text
//!   Π_f = −ρ g ∫_Ω (h − z)₊ dV = ρ g Σ_T φ_T,     φ_T(x; h) = ½ ∫_T (h − z)₊² n_z dA,
//! ```
//!
//! by the divergence theorem with the field (0, 0, −½ (h − z)₊²), whose divergence is
//! (h − z)₊. The normal n points *out of the fluid*: nodes counter-clockwise seen from the dry
//! side. Fluid on the side the normal points to (fluid above a membrane, or a body immersed in
//! a pool) is the same kernel with the orientation flipped, i.e. φ_T → −φ_T.
//!
//! On the flat triangle x(ξ, η) = x1 + ξ a + η b (a = x2 − x1, b = x3 − x1) over the reference
//! triangle R, `n_z dA = N_z dξ dη` with N_z = (a × b)_z constant, and f = h − z =
//! Σ_i f_i λ_i, f_i = h − z_i, is linear in the barycentric coordinates λ. So
//!
//! ```text
//!   φ_T = ½ N_z ∫_W f² dξ dη,      W = {λ ∈ R : f > 0}   (the wet part)
//! ```
//!
//! is a quadratic polynomial integrated over W: the whole of R, nothing, a triangle (one wet
//! node) or a quadrilateral (two wet nodes). Every integral needed is a linear combination of
//! the wet moments M_pq = ∫_W λ_p λ_q dξ dη, which are computed exactly: W is cut into at most
//! two triangles in reference coordinates and on each, for linear u and v with vertex values
//! u_k, v_k, ∫ u v = (area/12) (Σ_k u_k v_k + Σ_k u_k Σ_k v_k) (exact for degree 2). The cut
//! points lie on edges from a wet node (f_i > 0) to a dry one (f_j ≤ 0), at the parameter
//! f_i / (f_i − f_j) ∈ (0, 1]: the denominator is at least f_i > 0, so there is no division
//! by zero whatever the geometry; a waterline through a node gives a zero-area sub-triangle.
//! With I2 = fᵀ M f = ∫_W f², I1_i = (M f)_i = ∫_W f λ_i, I1 = Σ_i I1_i = ∫_W f and
//! I0_i = Σ_q M_iq = ∫_W λ_i:
//!
//! ```text
//!   φ_T        = ½ N_z I2
//!   ∂φ_T/∂(x_i, y_i) = ½ I2 ∂N_z/∂(x_i, y_i),            ∂φ_T/∂z_i = −N_z I1_i
//!   ∇²φ_T      = ½ I2 ∇²N_z − (∇N_z ⊗ I1 + I1 ⊗ ∇N_z)|_z + N_z M|_zz
//!   ∂φ_T/∂h    = N_z I1,
//!   ∂(∇φ_T)/∂h = I1 ∇N_z − N_z I0|_z
//! ```
//!
//! (`|_z` puts a 3-vector on the z dofs; ∇N_z has no z entries.)
//!
//! # Why the moving waterline adds nothing
//!
//! W depends on x and h through its straight edge f = 0. By Reynolds' transport theorem the
//! derivative of ∫_W g over a moving W is ∫_W ∂g plus the boundary integral of g times the
//! normal speed of the boundary; on the fixed edges of R the speed is zero and on the waterline
//! g = N_z f² / 2 = 0. So the gradient (and ∂φ/∂h) is the integral of the differentiated
//! integrand over the frozen W. The differentiated integrands, f² ∂N_z, f λ_i N_z and f N_z,
//! again vanish on the waterline, so differentiating once more again adds no boundary term:
//! the Hessian and ∂(∇φ)/∂h are also integrals over the frozen W. That is why the formulas
//! above hold exactly, without any line integral, and why K is the exact (symmetric) Hessian
//! of the discrete Π_f. (The next derivative would see the integrand λ_i λ_j N_z, which does
//! not vanish on the waterline: third derivatives carry line integrals — see below.)
//!
//! # Smoothness
//!
//! φ_T is C¹ in (x, h) with a Lipschitz gradient. The Hessian (built from M) is continuous
//! when the level crosses a node of a non-horizontal triangle — the wet area changes
//! continuously — but not differentiable there, so finite differences of the gradient across
//! such a crossing are only first-order accurate. It jumps only for a triangle parallel to the
//! level (all z_i equal) exactly at z = h, where the whole triangle becomes wet at once: there
//! the zz block N_z M jumps from 0 to N_z (I + 11ᵀ)/24 (the 1-D kink of (h − z)₊²), and so do
//! ∂(∇φ_T)/∂h, ∇v_T and ∂v_T/∂h below. This code takes f_i = 0 as dry, so that triangle is
//! then dry: those quantities take their limits from below the level (value and gradient are
//! zero on both sides anyway). A nearly horizontal triangle near the level has a continuous
//! but steep Hessian (it changes by O(N_z) while h sweeps the triangle's small height range).
//!
//! # Fluid volume and the h-derivative
//!
//! With min(z, h) = h − (h − z)₊ the contribution to the volume of fluid below the level is
//!
//! ```text
//!   v_T(x; h) = ∫_T min(z, h) n_z dA = N_z (h/2 − I1),
//!   ∇v_T = (h/2 − I1) ∇N_z + N_z I0|_z = (h/2) ∇N_z − ∂(∇φ_T)/∂h,
//!   ∂v_T/∂h = N_z (½ − Σ_pq M_pq)      (N_z times the dry reference area).
//! ```
//!
//! Over a closed, outward surface (divergence theorem with the fields (0, 0, min(z, h)) and
//! (0, 0, (h − z)₊), and ∮ n_z dA = 0):
//!
//! ```text
//!   V_f = Σ_T v_T = −Σ_T ∂φ_T/∂h,   so  ∂Π_f/∂h = ρ g Σ_T ∂φ_T/∂h = −ρ g V_f,
//!   ∂V_f/∂h = Σ_T ∂v_T/∂h = area of the section of Ω by the plane z = h.
//! ```
//!
//! Per triangle v_T = (h/2) N_z − ∂φ_T/∂h: the two differ by h times the projected area, which
//! sums to zero over a closed surface. So the load vector is
//!
//! ```text
//!   ∂F/∂h = ρ g Σ_T ∂(∇φ_T)/∂h = −ρ g ∇V_f + ρ g (h/2) Σ_T ∇N_z,
//! ```
//!
//! and the last sum vanishes identically on a closed surface (Σ_T N_z = 0 for every x) and on
//! the free dofs of an open membrane with a fixed rim (Σ_T N_z, twice the projected area, is
//! fixed by the rim): ∂F/∂h = −ρ g ∇V_f, the fluid-volume border is symmetric. For an open
//! membrane Σ_T v_T differs from the fluid volume by a constant and h times a constant area
//! (the closing surface), which changes ∂V_f/∂h by a constant but not ∇V_f.
//! The Hessian of v_T is not provided: it needs a line integral along the waterline weighted
//! by 1/|∇_ξ f|, which blows up for triangles parallel to the level; the bordered system needs
//! only ∇V_f and ∂V_f/∂h.
//!
//! # Forces (per unit ρ g)
//!
//! The nodal force is −∇φ_T. Summed over a closed surface it is −Σ ∇φ = (0, 0, −V_f) — the
//! weight of the fluid inside, applied to the membrane — and its moment is c_f × (0, 0, −V_f)
//! with c_f the centroid of the fluid. With the orientation flipped (fluid outside) it is
//! Archimedes' buoyancy (0, 0, +V_f) acting at the centre of buoyancy.

use super::local::{area_vector, area_vector_gradient, area_vector_hessian};
use super::spec::{
    self, Build, Built, EffectSpec, Measured, MeridianLoad, Natural, Range, Refusal, Scale,
};
use super::volume::ClosingFace;
use super::Quantity;
use crate::axisym::Pressure;
use crate::model::constraint::{gather, Constraint, ConstraintValue};
use crate::model::Local;
use crate::model::{
    Assembler, CellField, CellQuantity, Effect, Layout, ModelError, NodeField, NodeQuantity, Vec3,
};
use nalgebra::Vector3;
use std::sync::Arc;
use symmetry::Invariant;

/// Which side of the membrane the fluid is on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FluidSide {
    /// Opposite the normal: inside a closed outward-oriented membrane, or below an open
    /// membrane whose normal points up (fluid pushing up).
    Behind,
    /// On the side the normal points to: above an upward-oriented open membrane (the floor
    /// of a container), or a body immersed in a pool.
    Front,
}

/// Fluid under gravity (density ρ, gravity g along −z, level h): Π_f = ±ρ g Σ_T φ_T, the sign
/// plus for fluid [`FluidSide::Behind`] the membrane and minus in [`FluidSide::Front`]. Fixed walls
/// closing the fluid region add only constants; the plate closing an open membrane whose rim
/// slides in its plane is part of the closed surface ([`Fluid::closing`]). Loads:
/// ∂F/∂ρ = ±g ∇φ, ∂F/∂h = ±ρ g ∂∇φ/∂h, ∂F/∂g = ±ρ ∇φ.
///
/// `filled`: the enclosure is completely filled, p = ρ g (h − z) everywhere (h a pressure
/// head, negative pressures allowed): φ_T = ½ ∫_T (h − z)² n_z dA without clipping, and the
/// fluid volume is the enclosed volume (docs/theory.md §4.5).
#[derive(Debug, Clone)]
pub struct Fluid {
    /// Density ρ.
    pub density: Quantity,
    /// Gravitational acceleration g (> 0, along −z).
    pub gravity: Quantity,
    /// Level h of the free surface (the pressure head when `filled`).
    pub level: Quantity,
    /// Side of the membrane the fluid is on.
    pub side: FluidSide,
    /// The pressure is not clipped at the level: the enclosure is full.
    pub filled: bool,
    /// The plate closing an open membrane, when its rim can move (a fixed rim only adds a
    /// constant and needs none).
    pub closing: Option<Arc<ClosingFace>>,
}

impl Fluid {
    /// Fluid behind (`Behind`) or in front of the membrane, clipped at the level, no plate.
    pub fn new(density: Quantity, gravity: Quantity, level: Quantity, side: FluidSide) -> Self {
        Self {
            density,
            gravity,
            level,
            side,
            filled: false,
            closing: None,
        }
    }

    fn sign(&self) -> f64 {
        match self.side {
            FluidSide::Behind => 1.0,
            FluidSide::Front => -1.0,
        }
    }

    /// The fluid pressure ρ g (h − z)₊ at height z (ρ g (h − z) in a filled enclosure).
    pub fn pressure_at(&self, z: f64, params: &[f64]) -> f64 {
        let head = self.level.value(params) - z;
        let head = if self.filled { head } else { head.max(0.0) };
        self.density.value(params) * self.gravity.value(params) * head
    }

    /// The fluid volume V_f below the level (sign-corrected for the side), at positions `x`:
    /// Σ_T v_T over the membrane (fixed walls would add a constant; the closing plate's part is
    /// [`ClosingFace::fluid_volume`]).
    pub fn fluid_volume(&self, triangles: &[[usize; 3]], x: &[Vec3], params: &[f64]) -> f64 {
        let h = self.level.value(params);
        self.sign()
            * triangles
                .iter()
                .map(|&[a, b, c]| fluid_volume_of(&[x[a], x[b], x[c]], h, self.filled).value)
                .sum::<f64>()
    }
}

impl Effect for Fluid {
    fn name(&self) -> &str {
        "fluid"
    }

    /// Gravity keeps the direction −z (rotations about z and vertical mirrors).
    fn keeps(&self) -> Vec<Invariant> {
        vec![Invariant::Direction(-Vector3::z())]
    }

    /// Horizontal translations and rotation about the vertical z-axis keep the level planes.
    fn rigid_motions(&self) -> Vec<[f64; 6]> {
        let m = crate::model::ALL_RIGID_MOTIONS;
        vec![m[0], m[1], m[5]]
    }

    fn assemble(
        &self,
        x: &[Vec3],
        params: &[f64],
        out: &mut Assembler<'_>,
    ) -> Result<(), ModelError> {
        let (rho, h) = (self.density.value(params), self.level.value(params));
        let g = self.gravity.value(params);
        let s = self.sign() * g;
        let face = self
            .closing
            .as_deref()
            .map(|c| (c, c.fluid_coefficients(h, self.filled)));
        out.add_triangles(
            x,
            [
                self.density.parameter(),
                self.level.parameter(),
                self.gravity.parameter(),
            ],
            |t, xt, terms| {
                let f = potential_of(xt, h, self.filled);
                let mut local = f.local;
                let mut d_dh = f.grad_d_dh;
                if let Some((face, (c, c1, _))) = face.filter(|(f, _)| f.touches(t)) {
                    let a = face.area_local(t, xt);
                    local.add_scaled(&a, c);
                    for (g, ga) in d_dh.iter_mut().zip(a.grad) {
                        *g += c1 * ga;
                    }
                }
                terms.local = local.scaled(s * rho);
                terms.loads[0] = local.grad.map(|g| s * g);
                terms.loads[1] = d_dh.map(|g| s * rho * g);
                terms.loads[2] = local.grad.map(|v| self.sign() * rho * v);
                Ok(())
            },
        )
    }

    /// The fluid pressure ρ g (h − z)₊ at each triangle's centroid (unclipped when filled).
    fn cell_fields(&self, x: &[Vec3], triangles: &[[usize; 3]], params: &[f64]) -> Vec<CellField> {
        let values = triangles
            .iter()
            .map(|&[a, b, c]| self.pressure_at((x[a][2] + x[b][2] + x[c][2]) / 3.0, params))
            .collect();
        vec![CellField {
            quantity: CellQuantity::FluidPressure,
            values,
        }]
    }

    /// The fluid pressure at each node, positive when it pushes along the normal (fluid
    /// behind the membrane), negative for fluid in front.
    fn node_fields(&self, x: &[Vec3], _: &[[usize; 3]], params: &[f64]) -> Vec<NodeField> {
        let values = x
            .iter()
            .map(|xi| self.sign() * self.pressure_at(xi[2], params))
            .collect();
        vec![NodeField {
            quantity: NodeQuantity::Pressure,
            values,
        }]
    }
}

/// φ_T with its derivatives in the nodes and in the level h.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FluidPotential {
    /// φ_T = ½ ∫_T (h − z)₊² n_z dA, its gradient and Hessian in the nodes.
    pub local: Local,
    /// ∂φ_T/∂h = ∫_T (h − z)₊ n_z dA (sums to −V_f over a closed surface).
    pub d_dh: f64,
    /// ∂(∇φ_T)/∂h (9).
    pub grad_d_dh: [f64; 9],
}

/// v_T with its gradient and h-derivative.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FluidVolume {
    /// v_T = ∫_T min(z, h) n_z dA (sums to the fluid volume V_f over a closed surface).
    pub value: f64,
    /// ∇v_T (9).
    pub grad: [f64; 9],
    /// ∂v_T/∂h = ∫_T 1(z > h) n_z dA (sums to the waterline section area). For a triangle
    /// lying exactly in the plane z = h, where it jumps, this is the limit from below.
    pub d_dh: f64,
}

/// Integrals over the wet part W of the reference triangle (area ½).
struct WetIntegrals {
    /// M_pq = ∫_W λ_p λ_q.
    m: [[f64; 3]; 3],
    /// f_i = h − z_i.
    f: [f64; 3],
    /// I1_i = ∫_W f λ_i.
    i1: [f64; 3],
    /// I0_i = ∫_W λ_i.
    i0: [f64; 3],
}

impl WetIntegrals {
    /// The integrals over the wet part, or over the whole triangle when `filled` (no
    /// clipping: the same formulas with M = ∫_R λ λᵀ).
    fn new(x: &[Vector3<f64>; 3], h: f64, filled: bool) -> Self {
        let f = [h - x[0].z, h - x[1].z, h - x[2].z];
        let m = if filled {
            wet_moments([1.0; 3])
        } else {
            wet_moments(f)
        };
        let mut i1 = [0.0; 3];
        let mut i0 = [0.0; 3];
        for p in 0..3 {
            for q in 0..3 {
                i1[p] += m[p][q] * f[q];
                i0[p] += m[p][q];
            }
        }
        Self { m, f, i1, i0 }
    }

    /// ∫_W f².
    fn i2(&self) -> f64 {
        (0..3).map(|p| self.f[p] * self.i1[p]).sum()
    }

    /// ∫_W f.
    fn i1_total(&self) -> f64 {
        self.i1.iter().sum()
    }
}

/// Adds ∫ λ λᵀ over the sub-triangle with barycentric vertices `v` and reference area `area`
/// (exact: the integrand is quadratic).
fn add_triangle(m: &mut [[f64; 3]; 3], v: [[f64; 3]; 3], area: f64) {
    let s = [0, 1, 2].map(|p| v[0][p] + v[1][p] + v[2][p]);
    let c = area / 12.0;
    for p in 0..3 {
        for q in 0..3 {
            let corners: f64 = v.iter().map(|k| k[p] * k[q]).sum();
            m[p][q] += c * (corners + s[p] * s[q]);
        }
    }
}

/// M = ∫_W λ λᵀ dξ dη over W = {Σ f_i λ_i > 0} ⊂ R (exact; a node with f_i = 0 counts as dry).
fn wet_moments(f: [f64; 3]) -> [[f64; 3]; 3] {
    let e = |i: usize| {
        let mut v = [0.0; 3];
        v[i] = 1.0;
        v
    };
    // Point on the edge from node i to node j at parameter t.
    let on_edge = |i: usize, j: usize, t: f64| {
        let mut v = [0.0; 3];
        v[i] = 1.0 - t;
        v[j] += t;
        v
    };
    let wet = f.map(|v| v > 0.0);
    let mut m = [[0.0; 3]; 3];
    match wet.iter().filter(|&&w| w).count() {
        3 => add_triangle(&mut m, [e(0), e(1), e(2)], 0.5),
        1 => {
            // Wet node i, dry j and k: the wet triangle (e_i, p_ij, p_ik), similar to R.
            let i = if wet[0] {
                0
            } else if wet[1] {
                1
            } else {
                2
            };
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            let tj = f[i] / (f[i] - f[j]); // f[i] > 0 ≥ f[j]: in (0, 1]
            let tk = f[i] / (f[i] - f[k]);
            add_triangle(
                &mut m,
                [e(i), on_edge(i, j, tj), on_edge(i, k, tk)],
                0.5 * tj * tk,
            );
        }
        2 => {
            // Dry node k, wet i and j: the quadrilateral (e_i, e_j, q_j, q_i), q_· on the
            // edges from k, cut along e_i–q_j.
            let k = if !wet[0] {
                0
            } else if !wet[1] {
                1
            } else {
                2
            };
            let (i, j) = ((k + 1) % 3, (k + 2) % 3);
            let si = f[k] / (f[k] - f[i]); // f[i] > 0 ≥ f[k]: in [0, 1)
            let sj = f[k] / (f[k] - f[j]);
            let (qi, qj) = (on_edge(k, i, si), on_edge(k, j, sj));
            add_triangle(&mut m, [e(i), e(j), qj], 0.5 * (1.0 - sj));
            add_triangle(&mut m, [e(i), qj, qi], 0.5 * sj * (1.0 - si));
        }
        _ => {}
    }
    m
}

/// φ_T(x; h) = ½ ∫_T (h − z)₊² n_z dA with its gradient, Hessian, ∂/∂h and ∂(∇φ_T)/∂h.
/// Π_f = ρ g Σ_T φ_T for fluid on the side opposite to the normal (see the module docs).
pub fn potential(x: &[Vector3<f64>; 3], h: f64) -> FluidPotential {
    potential_of(x, h, false)
}

/// As [`potential`]; with `filled` the integrand is not clipped: φ_T = ½ ∫_T (h − z)² n_z dA.
pub fn potential_of(x: &[Vector3<f64>; 3], h: f64, filled: bool) -> FluidPotential {
    let w = WetIntegrals::new(x, h, filled);
    let nz = area_vector(x).z;
    let gn = area_vector_gradient(x, 2);
    let hn = area_vector_hessian(2);
    let i2 = w.i2();
    let i1 = w.i1_total();
    let mut local = Local {
        value: 0.5 * nz * i2,
        grad: gn.map(|g| 0.5 * i2 * g),
        hess: hn.map(|row| row.map(|v| 0.5 * i2 * v)),
    };
    let mut grad_d_dh = gn.map(|g| i1 * g);
    for i in 0..3 {
        let zi = 3 * i + 2;
        local.grad[zi] -= nz * w.i1[i];
        grad_d_dh[zi] -= nz * w.i0[i];
        for (a, g) in gn.iter().enumerate() {
            local.hess[a][zi] -= g * w.i1[i];
            local.hess[zi][a] -= g * w.i1[i];
        }
        for (j, m) in w.m[i].iter().enumerate() {
            local.hess[zi][3 * j + 2] += nz * m;
        }
    }
    FluidPotential {
        local,
        d_dh: nz * i1,
        grad_d_dh,
    }
}

/// v_T(x; h) = ∫_T min(z, h) n_z dA with its gradient and ∂v_T/∂h (see the module docs).
pub fn fluid_volume(x: &[Vector3<f64>; 3], h: f64) -> FluidVolume {
    fluid_volume_of(x, h, false)
}

/// As [`fluid_volume`]; with `filled`, v_T = ∫_T z n_z dA (the enclosed volume's part, by the
/// field (0, 0, z)) and ∂v_T/∂h = 0.
pub fn fluid_volume_of(x: &[Vector3<f64>; 3], h: f64, filled: bool) -> FluidVolume {
    let w = WetIntegrals::new(x, h, filled);
    let nz = area_vector(x).z;
    let gn = area_vector_gradient(x, 2);
    let c = 0.5 * h - w.i1_total();
    let mut grad = gn.map(|g| c * g);
    for i in 0..3 {
        grad[3 * i + 2] += nz * w.i0[i];
    }
    let wet_area: f64 = w.i0.iter().sum();
    FluidVolume {
        value: nz * c,
        grad,
        d_dh: nz * (0.5 - wet_area),
    }
}

/// Fixed fluid volume of a fluid effect, V_f(u, h) = V* (docs/theory.md §7.1); frees its
/// level. V* is a number (or measured at the start) or the parameter `target_parameter`,
/// which can then be the path's control: the fluid volume as the control, the level an
/// unknown. For a filled enclosure V_f is the enclosed volume and ∂V_f/∂h = 0.
#[derive(Debug, Clone)]
pub struct FluidVolumeConstraint {
    /// The fluid effect (its level must be a parameter).
    pub fluid: Fluid,
    /// The level's parameter index.
    pub level: usize,
    /// V* (when `target_parameter` is `None`).
    pub target: f64,
    /// The parameter that is V*, if any.
    pub target_parameter: Option<usize>,
    /// The face closing an open membrane, if any.
    pub closing: Option<Arc<ClosingFace>>,
}

impl FluidVolumeConstraint {
    fn sign(&self) -> f64 {
        match self.fluid.side {
            FluidSide::Behind => 1.0,
            FluidSide::Front => -1.0,
        }
    }
}

impl Constraint for FluidVolumeConstraint {
    fn name(&self) -> &str {
        "fluid-volume"
    }
    fn frees(&self) -> usize {
        self.level
    }
    fn measure(&self, layout: &Layout, x: &[Vec3], params: &[f64]) -> f64 {
        let closing = self.closing.as_ref().map_or(0.0, |c| {
            let (v, _) =
                c.fluid_volume(layout.triangles(), x, params[self.level], self.fluid.filled);
            self.sign() * v
        });
        self.fluid.fluid_volume(layout.triangles(), x, params) + closing
    }
    fn target(&self) -> f64 {
        self.target
    }
    fn set_target(&mut self, target: f64) {
        self.target = target;
    }
    fn evaluate(&self, layout: &Layout, x: &[Vec3], params: &[f64]) -> ConstraintValue {
        let h = params[self.level];
        let (s, filled) = (self.sign(), self.fluid.filled);
        let mut value = 0.0;
        let mut d_dh = 0.0;
        for &[a, b, c] in layout.triangles() {
            let v = fluid_volume_of(&[x[a], x[b], x[c]], h, filled);
            value += s * v.value;
            d_dh += s * v.d_dh;
        }
        let face = self.closing.as_deref();
        let mut plate_height = 0.0;
        if let Some(c) = face {
            let (v, dv) = c.fluid_volume(layout.triangles(), x, h, filled);
            value += s * v;
            d_dh += s * dv;
            plate_height = if filled { c.z } else { c.z.min(h) };
        }
        let mut grad_params = vec![0.0; params.len()];
        let grad_u = gather(layout, x, &mut grad_params, |t, xt| {
            let mut g = fluid_volume_of(xt, h, filled).grad;
            if let Some(c) = face.filter(|c| c.touches(t)) {
                for (gi, ai) in g.iter_mut().zip(c.area_local(t, xt).grad) {
                    *gi += plate_height * ai;
                }
            }
            g.map(|gi| s * gi)
        });
        grad_params[self.level] += d_dh;
        let target = match self.target_parameter {
            Some(j) => {
                grad_params[j] -= 1.0;
                params[j]
            }
            None => self.target,
        };
        ConstraintValue {
            value: value - target,
            grad_u,
            grad_params,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::local::fd::{
        box_surface, check_kernel, check_parameter, close, nodes, perturbed, rotation, same_local,
        scale, subdivided,
    };
    use super::*;
    use proptest::prelude::*;

    fn assert_finite(p: &FluidPotential, v: &FluidVolume) {
        let all = std::iter::once(p.local.value)
            .chain(p.local.grad)
            .chain(p.local.hess.iter().flatten().copied())
            .chain(std::iter::once(p.d_dh))
            .chain(p.grad_d_dh)
            .chain(std::iter::once(v.value))
            .chain(v.grad)
            .chain(std::iter::once(v.d_dh));
        for (k, a) in all.enumerate() {
            assert!(a.is_finite(), "entry {k} is {a}");
        }
    }

    fn max_diff<'a>(a: impl Iterator<Item = &'a f64>, b: impl Iterator<Item = &'a f64>) -> f64 {
        a.zip(b).fold(0.0f64, |m, (u, v)| m.max((u - v).abs()))
    }

    #[test]
    fn the_fluid_pressure_is_the_head_at_the_centroid_and_the_nodes() {
        let x: Vec<Vector3<f64>> = vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.3),
            Vector3::new(0.0, 1.0, 0.9),
            Vector3::new(1.0, 1.0, 1.5),
        ];
        let t = [[0, 1, 2], [1, 3, 2]];
        // ρ = 2, g = 3 (a parameter), level h = 1.
        for (side, sign) in [(FluidSide::Behind, 1.0), (FluidSide::Front, -1.0)] {
            for filled in [false, true] {
                let mut fluid = Fluid::new(
                    Quantity::Value(2.0),
                    Quantity::Parameter(0),
                    Quantity::Value(1.0),
                    side,
                );
                fluid.filled = filled;
                let head = |z: f64| if filled { 1.0 - z } else { (1.0 - z).max(0.0) };
                let cells = fluid.cell_fields(&x, &t, &[3.0]);
                assert_eq!(cells[0].quantity, CellQuantity::FluidPressure);
                let want = [6.0 * head(0.4), 6.0 * head(0.9)];
                for (got, want) in cells[0].values.iter().zip(want) {
                    assert!((got - want).abs() < 1e-14, "{got} vs {want}");
                }
                let nodes = fluid.node_fields(&x, &t, &[3.0]);
                assert_eq!(nodes[0].quantity, NodeQuantity::Pressure);
                for (got, xi) in nodes[0].values.iter().zip(&x) {
                    let want = sign * 6.0 * head(xi[2]);
                    assert!((got - want).abs() < 1e-14, "{got} vs {want}");
                }
            }
        }
    }

    #[test]
    fn wholly_wet_triangle_matches_the_mean_of_f_squared() {
        let x = nodes(&[0.1, -0.2, -0.4, 1.3, 0.1, -0.95, 0.4, 0.9, -0.1]);
        let h = 0.3;
        let f = x.map(|p| h - p.z);
        let mean =
            (f[0] * f[0] + f[1] * f[1] + f[2] * f[2] + f[0] * f[1] + f[1] * f[2] + f[2] * f[0])
                / 6.0;
        let nz = area_vector(&x).z;
        // ½ ∫ f² n_z dA = ½ (N_z / 2) mean(f²).
        let p = potential(&x, h);
        assert!((p.local.value - 0.25 * nz * mean).abs() < 1e-15);
        // ∂φ/∂h = ∫ f n_z dA = (N_z/2) mean(f).
        assert!((p.d_dh - 0.5 * nz * (f[0] + f[1] + f[2]) / 3.0).abs() < 1e-15);
        // Wholly dry: everything vanishes.
        let dry = potential(&x, -2.0);
        assert_eq!(dry.local, Local::ZERO);
        assert_eq!(dry.d_dh, 0.0);
    }

    #[test]
    fn clipped_triangles_match_closed_forms() {
        // z = ξ + η over the unit right triangle (N_z = 1): the wet part is the corner
        // triangle ξ + η < h, ∫ (h − s)² s ds over [0, h] = h⁴/12.
        let x = nodes(&[0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0, 1.0]);
        for h in [0.1, 0.5, 0.9] {
            let p = potential(&x, h);
            assert!((p.local.value - h.powi(4) / 24.0).abs() < 1e-16, "h = {h}");
            assert!((p.d_dh - h.powi(3) / 6.0).abs() < 1e-16, "h = {h}");
        }
        // z = η: wet strip η < h, ∫ (h − η)² (1 − η) dη = (1 − h) h³/3 + h⁴/4.
        let x = nodes(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0]);
        for h in [0.1, 0.5, 0.9] {
            let p = potential(&x, h);
            let exact = 0.5 * ((1.0 - h) * h.powi(3) / 3.0 + h.powi(4) / 4.0);
            assert!((p.local.value - exact).abs() < 1e-16, "h = {h}");
        }
    }

    /// Triangles with the waterline through nodes, along edges, parallel to it, and nearly
    /// flat or degenerate ones, each at a level h equal to one of its nodes' heights:
    /// (nodes, level, steep, what). `steep`: second derivatives may change by O(1) within
    /// ±1e-12 of the level (a triangle horizontal at it, or one whose heights span less).
    #[rustfmt::skip]
    const AWKWARD: [([f64; 9], f64, bool, &str); 13] = [
        ([0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.3, 1.0, -1.0], 0.0, false, "through the middle node"),
        ([0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.3, 1.0, 0.5], 0.0, false, "through the lowest node"),
        ([0.0, 0.0, 0.0, 1.0, 0.0, -1.0, 0.3, 1.0, -0.5], 0.0, false, "through the top node"),
        ([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.3, 1.0, 1.0], 0.0, false, "along the lower edge"),
        ([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.3, 1.0, -1.0], 0.0, false, "along the upper edge"),
        ([0.0, 0.0, 0.2, 1.0, 0.0, 0.2, 0.3, 1.0, 0.2], 0.2, true, "horizontal at the level"),
        ([0.0, 0.0, 0.2, 1.0, 0.0, 0.2, 0.3, 1.0, 0.2 + 1e-13], 0.2, true, "nearly horizontal"),
        ([0.0, 0.0, 0.2, 1.0, 0.0, 0.2 - 1e-15, 0.3, 1.0, 0.2 + 1e-15], 0.2, true, "nearly flat"),
        ([0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 2.0, 2.0, 2.0], 1.0, false, "collinear nodes"),
        ([0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0], 1.0, false, "two coincident nodes"),
        ([0.0, 0.0, 0.5, 0.0, 0.0, 0.5, 0.0, 0.0, 0.5], 0.5, true, "a point"),
        ([0.0, 0.0, 0.0, 1e-9, 0.0, 1.0, 0.0, 1e-9, -1.0], 0.0, false, "a sliver"),
        ([0.0, 0.0, -1e-300, 1.0, 0.0, 1e-300, 0.3, 1.0, 0.0], 0.0, true, "tiny heights"),
    ];

    #[test]
    fn awkward_geometries_are_finite_and_continuous_in_the_level() {
        for (p, h, steep, k) in AWKWARD {
            let x = nodes(&p);
            let at = |h: f64| (potential(&x, h), fluid_volume(&x, h));
            let (p0, v0) = at(h);
            assert_finite(&p0, &v0);
            let size = 1.0 + scale(&p0.local, 0.0);
            for dh in [1e-12, -1e-12] {
                let (p, v) = at(h + dh);
                assert_finite(&p, &v);
                let tol = 1e-10 * size;
                assert!(
                    (p.local.value - p0.local.value).abs() < tol,
                    "case {k}: value"
                );
                assert!(
                    max_diff(p.local.grad.iter(), p0.local.grad.iter()) < tol,
                    "case {k}: gradient"
                );
                assert!((p.d_dh - p0.d_dh).abs() < tol, "case {k}: ∂φ/∂h");
                assert!(
                    max_diff(p.grad_d_dh.iter(), p0.grad_d_dh.iter()) < 1e-9 * size || steep,
                    "case {k}: ∂∇φ/∂h"
                );
                assert!((v.value - v0.value).abs() < tol, "case {k}: v");
                assert!(
                    max_diff(v.grad.iter(), v0.grad.iter()) < 1e-9 * size || steep,
                    "case {k}: ∇v"
                );
                if !steep {
                    let hd = max_diff(
                        p.local.hess.iter().flatten(),
                        p0.local.hess.iter().flatten(),
                    );
                    assert!(hd < 1e-9 * size, "case {k}: Hessian jumps by {hd}");
                }
            }
            // Nodes moved across the level by ±1e-12 one at a time: continuity in x too.
            for n in 0..3 {
                for dz in [1e-12, -1e-12] {
                    let mut y = x;
                    y[n].z += dz;
                    let p = potential(&y, h);
                    let tol = 1e-10 * size;
                    assert!(
                        (p.local.value - p0.local.value).abs() < tol,
                        "case {k}: node {n} value"
                    );
                    assert!(
                        max_diff(p.local.grad.iter(), p0.local.grad.iter()) < tol,
                        "case {k}: node {n} gradient"
                    );
                }
            }
        }
    }

    #[test]
    fn horizontal_triangle_at_the_level_has_the_documented_hessian_jump() {
        let x = nodes(&[0.0, 0.0, 0.2, 1.0, 0.0, 0.2, 0.3, 1.0, 0.2]);
        let (below, above) = (potential(&x, 0.2 - 1e-12), potential(&x, 0.2 + 1e-12));
        let nz = area_vector(&x).z;
        for i in 0..3 {
            for j in 0..3 {
                let jump =
                    above.local.hess[3 * i + 2][3 * j + 2] - below.local.hess[3 * i + 2][3 * j + 2];
                let expected = nz * if i == j { 2.0 } else { 1.0 } / 24.0;
                assert!(
                    (jump - expected).abs() < 1e-12,
                    "({i}, {j}): {jump} vs {expected}"
                );
            }
        }
    }

    /// A random triangle in [−1, 1]³ and a level with every node farther than `gap` from it.
    fn away_from_nodes(x: &[Vector3<f64>; 3], h: f64, gap: f64) -> bool {
        x.iter().all(|p| (p.z - h).abs() > gap)
    }

    proptest! {
        #[test]
        fn gradient_and_hessian_match_finite_differences(
            p in proptest::array::uniform9(-1.0f64..1.0),
            dir in proptest::array::uniform9(-1.0f64..1.0),
            h in -1.2f64..1.2,
        ) {
            let x = nodes(&p);
            let step = 1e-6;
            // The Hessian is not differentiable where the level crosses a node: keep the
            // differences from straddling that.
            prop_assume!(away_from_nodes(&x, h, 1e-4));
            check_kernel(|x| potential(x, h).local, &x, &dir, step, 1e-6)
                .map_err(TestCaseError::fail)?;
        }

        #[test]
        fn level_derivatives_match_finite_differences(
            p in proptest::array::uniform9(-1.0f64..1.0),
            h in -1.2f64..1.2,
        ) {
            let x = nodes(&p);
            prop_assume!(away_from_nodes(&x, h, 1e-4));
            let step = 1e-6;
            let at = |h: f64| {
                let p = potential(&x, h);
                let mut out = [0.0; 10];
                out[0] = p.local.value;
                out[1..].copy_from_slice(&p.local.grad);
                out
            };
            let p0 = potential(&x, h);
            let mut exact = [0.0; 10];
            exact[0] = p0.d_dh;
            exact[1..].copy_from_slice(&p0.grad_d_dh);
            let tol = 1e-7 * (1.0 + scale(&p0.local, 0.0));
            check_parameter(at, &exact, h, step, tol).map_err(TestCaseError::fail)?;
            // v_T: its h-derivative and the identity v_T = (h/2) N_z − ∂φ_T/∂h.
            let v0 = fluid_volume(&x, h);
            check_parameter(|h| [fluid_volume(&x, h).value], &[v0.d_dh], h, step, tol)
                .map_err(TestCaseError::fail)?;
            close("v_T identity", v0.value, 0.5 * h * area_vector(&x).z - p0.d_dh, 1e-14)
                .map_err(TestCaseError::fail)?;
        }

        #[test]
        fn fluid_volume_gradient_matches_finite_differences(
            p in proptest::array::uniform9(-1.0f64..1.0),
            dir in proptest::array::uniform9(-1.0f64..1.0),
            h in -1.2f64..1.2,
        ) {
            let x = nodes(&p);
            let step = 1e-6;
            let v = fluid_volume(&x, h);
            let fd = (fluid_volume(&perturbed(&x, &dir, step), h).value
                - fluid_volume(&perturbed(&x, &dir, -step), h).value) / (2.0 * step);
            let exact: f64 = (0..9).map(|i| v.grad[i] * dir[i]).sum();
            let size = v.grad.iter().fold(1.0f64, |m, g| m.max(g.abs()));
            close("∇v_T", fd, exact, 1e-6 * size).map_err(TestCaseError::fail)?;
        }

        #[test]
        fn exact_integration_is_additive_under_subdivision(
            p in proptest::array::uniform9(-1.0f64..1.0),
            h in -1.2f64..1.2,
        ) {
            // The four midpoint children see other clipping cases than the parent; an exact
            // integral over the wet part must add up, derivatives included.
            let x = nodes(&p);
            let parent = potential(&x, h);
            let children = subdivided(|y| potential(y, h).local, &x);
            same_local(&children, &parent.local, 1e-12 * (1.0 + scale(&parent.local, 0.0)))
                .map_err(TestCaseError::fail)?;
        }
    }

    proptest! {
        #[test]
        fn filled_kernel_matches_finite_differences(
            p in proptest::array::uniform9(-1.0f64..1.0),
            dir in proptest::array::uniform9(-1.0f64..1.0),
            h in -1.2f64..1.2,
        ) {
            // No clipping: a polynomial, smooth across the level, so no node is kept away.
            let x = nodes(&p);
            check_kernel(|x| potential_of(x, h, true).local, &x, &dir, 1e-6, 1e-6)
                .map_err(TestCaseError::fail)?;
            let at = |h: f64| {
                let p = potential_of(&x, h, true);
                let mut out = [0.0; 10];
                out[0] = p.local.value;
                out[1..].copy_from_slice(&p.local.grad);
                out
            };
            let p0 = potential_of(&x, h, true);
            let mut exact = [0.0; 10];
            exact[0] = p0.d_dh;
            exact[1..].copy_from_slice(&p0.grad_d_dh);
            let tol = 1e-7 * (1.0 + scale(&p0.local, 0.0));
            check_parameter(at, &exact, h, 1e-6, tol).map_err(TestCaseError::fail)?;
            // The filled fluid volume is ∫ z n_z dA, independent of h.
            let v = fluid_volume_of(&x, h, true);
            close("filled ∂v/∂h", v.d_dh, 0.0, 1e-15).map_err(TestCaseError::fail)?;
            let z_nz = area_vector(&x).z * (x[0].z + x[1].z + x[2].z) / 6.0;
            close("filled v_T", v.value, z_nz, 1e-14).map_err(TestCaseError::fail)?;
        }

        #[test]
        fn filled_equals_clipped_where_the_triangle_is_wholly_wet(
            p in proptest::array::uniform9(-1.0f64..1.0),
            h in 1.01f64..2.0,
        ) {
            let x = nodes(&p);
            same_local(&potential_of(&x, h, true).local, &potential(&x, h).local, 1e-14)
                .map_err(TestCaseError::fail)?;
        }
    }

    #[test]
    fn a_filled_box_weighs_its_whole_volume_whatever_the_head() {
        // p = ρ g (h − z) everywhere: Σ φ = −∫ (h − z) dV, and the net force is the weight of
        // the whole box even when h is below its top (where a clipped fluid leaves a void).
        let (lo, hi) = (Vector3::new(-0.5, 0.25, -1.0), Vector3::new(0.7, 1.0, 0.6));
        let r = rotation(0.3, -0.7, 1.1);
        let tris = box_surface(lo, hi, 3, |p| r * p);
        let volume = 1.2 * 0.75 * 1.6;
        let centroid = r * (0.5 * (lo + hi));
        for h in [-2.0, -0.5, 0.0, 0.3, 2.5] {
            let (mut phi, mut force, mut v) = (0.0, Vector3::zeros(), 0.0);
            for t in &tris {
                let p = potential_of(t, h, true);
                phi += p.local.value;
                v += fluid_volume_of(t, h, true).value;
                for n in 0..3 {
                    force -= Vector3::new(
                        p.local.grad[3 * n],
                        p.local.grad[3 * n + 1],
                        p.local.grad[3 * n + 2],
                    );
                }
            }
            let work = volume * (h - centroid.z);
            assert!((phi + work).abs() < 1e-12, "h = {h}: Σφ {phi} vs {}", -work);
            assert!((v - volume).abs() < 1e-12, "h = {h}: volume {v}");
            assert!(
                (force - Vector3::new(0.0, 0.0, -volume)).norm() < 1e-12,
                "h = {h}: {force}"
            );
        }
    }

    // ---- Closed surfaces: Archimedes and the divergence-theorem identities ----

    /// The section of the convex polyhedron bounded by `tris` at height z: (area, ∫x, ∫y),
    /// from the points where the plane cuts the edges, sorted by angle (z must not be a
    /// node height).
    fn section(tris: &[[Vector3<f64>; 3]], z: f64) -> (f64, f64, f64) {
        let mut pts: Vec<(f64, f64)> = Vec::new();
        for t in tris {
            for n in 0..3 {
                let (mut p, mut q) = (t[n], t[(n + 1) % 3]);
                if p.z > q.z {
                    std::mem::swap(&mut p, &mut q);
                }
                if p.z < z && z < q.z {
                    let s = (z - p.z) / (q.z - p.z);
                    let c = p + s * (q - p);
                    pts.push((c.x, c.y));
                }
            }
        }
        if pts.len() < 3 {
            return (0.0, 0.0, 0.0);
        }
        let n = pts.len() as f64;
        let (mx, my) = pts
            .iter()
            .fold((0.0, 0.0), |(a, b), p| (a + p.0 / n, b + p.1 / n));
        pts.sort_by(|a, b| {
            let (ta, tb) = ((a.1 - my).atan2(a.0 - mx), (b.1 - my).atan2(b.0 - mx));
            ta.total_cmp(&tb)
        });
        let (mut area, mut sx, mut sy) = (0.0, 0.0, 0.0);
        for k in 0..pts.len() {
            let (a, b) = (pts[k], pts[(k + 1) % pts.len()]);
            let cr = a.0 * b.1 - b.0 * a.1;
            area += 0.5 * cr;
            sx += (a.0 + b.0) * cr / 6.0;
            sy += (a.1 + b.1) * cr / 6.0;
        }
        (area, sx, sy)
    }

    /// Independent integrals over the part of the convex polyhedron below z = h:
    /// (V_f, ∫ (h − z) dV, centroid of the fluid). Between consecutive node heights the
    /// section's area is quadratic and its first moments cubic in z, so two-point
    /// Gauss-Legendre on each such interval is exact.
    fn submerged(tris: &[[Vector3<f64>; 3]], h: f64) -> (f64, f64, Vector3<f64>) {
        let mut zs: Vec<f64> = tris
            .iter()
            .flatten()
            .map(|p| p.z)
            .filter(|&z| z < h)
            .collect();
        zs.push(h);
        zs.sort_by(f64::total_cmp);
        zs.dedup_by(|a, b| (*a - *b).abs() < 1e-13);
        let g = 0.5 / 3f64.sqrt();
        let (mut v, mut depth, mut m) = (0.0, 0.0, Vector3::zeros());
        for w in zs.windows(2) {
            let (a, b) = (w[0], w[1]);
            for z in [0.5 * (a + b) - g * (b - a), 0.5 * (a + b) + g * (b - a)] {
                let (area, sx, sy) = section(tris, z);
                let wt = 0.5 * (b - a);
                v += wt * area;
                depth += wt * (h - z) * area;
                m += wt * Vector3::new(sx, sy, z * area);
            }
        }
        (v, depth, if v > 0.0 { m / v } else { Vector3::zeros() })
    }

    /// Sums over a triangle soup: (Σ φ, Σ ∂φ/∂h, Σ v, Σ ∂v/∂h, net force −Σ∇φ, its moment).
    fn totals(
        tris: &[[Vector3<f64>; 3]],
        h: f64,
    ) -> (f64, f64, f64, f64, Vector3<f64>, Vector3<f64>) {
        let (mut phi, mut dphi, mut v, mut dv) = (0.0, 0.0, 0.0, 0.0);
        let (mut force, mut moment) = (Vector3::zeros(), Vector3::zeros());
        for x in tris {
            let p = potential(x, h);
            let w = fluid_volume(x, h);
            phi += p.local.value;
            dphi += p.d_dh;
            v += w.value;
            dv += w.d_dh;
            for (n, xn) in x.iter().enumerate() {
                let g = &p.local.grad[3 * n..3 * n + 3];
                let f = -Vector3::new(g[0], g[1], g[2]);
                force += f;
                moment += xn.cross(&f);
            }
        }
        (phi, dphi, v, dv, force, moment)
    }

    #[test]
    fn axis_aligned_box_matches_closed_forms() {
        let (lo, hi) = (Vector3::new(-0.5, 0.25, -1.0), Vector3::new(0.7, 1.0, 0.6));
        let tris = box_surface(lo, hi, 2, |p| p);
        let base = 1.2 * 0.75;
        for h in [-2.0, -1.0, -0.4, 0.0, 0.2, 0.6, 1.5] {
            let depth = (h - lo.z).clamp(0.0, hi.z - lo.z);
            let vf = base * depth;
            // ∫ (h − z)₊ dV over the box.
            let work = base * (0.5 * depth * depth + depth * (h - lo.z - depth));
            let (phi, dphi, v, dv, force, moment) = totals(&tris, h);
            // A horizontal face exactly at the level counts as dry: ∂V_f/∂h is the limit from below.
            let wl = if h > lo.z && h <= hi.z { base } else { 0.0 };
            let c = Vector3::new(0.1, 0.625, lo.z + 0.5 * depth);
            assert!(
                (phi + work).abs() < 1e-13,
                "h = {h}: Π_f/ρg {phi} vs {}",
                -work
            );
            assert!((dphi + vf).abs() < 1e-13, "h = {h}");
            assert!((v - vf).abs() < 1e-13, "h = {h}");
            assert!(
                (dv - wl).abs() < 1e-13,
                "h = {h}: waterline area {dv} vs {wl}"
            );
            assert!(
                (force - Vector3::new(0.0, 0.0, -vf)).norm() < 1e-13,
                "h = {h}: {force}"
            );
            let m_exact = c.cross(&Vector3::new(0.0, 0.0, -vf));
            assert!(
                (moment - m_exact).norm() < 1e-13,
                "h = {h}: {moment} vs {m_exact}"
            );
        }
    }

    #[test]
    fn tilted_box_obeys_archimedes_and_the_level_identity() {
        let (lo, hi) = (Vector3::new(-0.4, -0.3, -0.6), Vector3::new(0.8, 0.5, 0.3));
        let r = rotation(0.4, 0.7, -0.5);
        let t = Vector3::new(0.2, -0.1, 0.05);
        let tris = box_surface(lo, hi, 3, |p| r * p + t);
        let zs: Vec<f64> = tris.iter().flatten().map(|p| p.z).collect();
        let (zmin, zmax) = zs
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &z| (a.min(z), b.max(z)));
        // Levels below, through nodes (exactly), between nodes, and above.
        let mut levels = vec![zmin - 0.1, zmin, zmax, zmax + 0.1];
        levels.extend((1..12).map(|k| zmin + (zmax - zmin) * k as f64 / 12.0));
        levels.extend(tris.iter().step_by(7).map(|t| t[1].z));
        let total = 1.2 * 0.8 * 0.9;
        for h in levels {
            let (vf, work, c) = submerged(&tris, h);
            let (phi, dphi, v, dv, force, moment) = totals(&tris, h);
            let tol = 1e-12;
            assert!(
                (phi + work).abs() < tol,
                "h = {h}: Σφ = {phi} vs −∫(h−z)₊ = {}",
                -work
            );
            // ∂Π_f/∂h = −ρ g V_f: Σ ∂φ_T/∂h = −V_f, and Σ v_T = V_f.
            assert!(
                (dphi + vf).abs() < tol,
                "h = {h}: Σ∂φ/∂h = {dphi} vs −V_f = {}",
                -vf
            );
            assert!((v - vf).abs() < tol, "h = {h}: Σ v = {v} vs {vf}");
            // Weight of the fluid inside (per ρ g), acting at its centroid.
            assert!(
                (force - Vector3::new(0.0, 0.0, -vf)).norm() < tol,
                "h = {h}: force {force}"
            );
            let m_exact = c.cross(&Vector3::new(0.0, 0.0, -vf));
            assert!(
                (moment - m_exact).norm() < tol,
                "h = {h}: moment {moment} vs {m_exact}"
            );
            // Σ ∂v/∂h = waterline section area (by differences of the independent V_f).
            if h > zmin + 1e-3 && h < zmax - 1e-3 {
                let e = 1e-6;
                let wl = (submerged(&tris, h + e).0 - submerged(&tris, h - e).0) / (2.0 * e);
                assert!((dv - wl).abs() < 1e-6, "h = {h}: Σ∂v/∂h {dv} vs {wl}");
            }
            if h > zmax {
                assert!((vf - total).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn immersed_body_feels_buoyancy_upwards() {
        // Fluid outside: flip every triangle. The net force is Archimedes' ρ g V_sub upwards.
        let (lo, hi) = (Vector3::new(-0.4, -0.3, -0.6), Vector3::new(0.8, 0.5, 0.3));
        let r = rotation(-1.0, 0.3, 0.9);
        let tris: Vec<_> = box_surface(lo, hi, 2, |p| r * p)
            .into_iter()
            .map(|t| [t[0], t[2], t[1]])
            .collect();
        let outward: Vec<_> = tris.iter().map(|t| [t[0], t[2], t[1]]).collect();
        for h in [-0.3, 0.0, 0.25] {
            let (vsub, _, c) = submerged(&outward, h);
            let (_, _, _, _, force, moment) = totals(&tris, h);
            assert!(vsub > 0.0);
            assert!(
                (force - Vector3::new(0.0, 0.0, vsub)).norm() < 1e-12,
                "h = {h}: {force}"
            );
            assert!((moment - c.cross(&Vector3::new(0.0, 0.0, vsub))).norm() < 1e-12);
        }
    }
}

/// `[[effect]] type = "fluid"`: fluid under gravity (along −z) up to a level.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct FluidEffect {
    /// Density ρ ≥ 0.
    pub density: spec::Quantity,
    /// Gravitational acceleration g > 0 (gravity acts along −z; a number or a parameter).
    pub gravity: spec::Quantity,
    /// Height h of the free surface; the pressure is ρ g (h − z)₊.
    pub level: spec::Quantity,
    /// Where the fluid is.
    pub side: Side,
    /// The enclosure is completely filled (`side = "inside"` only): the pressure is
    /// ρ g (h − z) everywhere, not clipped at zero, and h is a pressure head. Default false.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub filled: bool,
}

/// `side` of a fluid effect: where the fluid is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Side {
    /// In the enclosed region: inside a closed membrane, or between an open membrane with a
    /// fixed rim and the (fixed) surface spanning its rim, i.e. on the side opposite to the
    /// mesh normals (a truncated sphere on a plate).
    Inside,
    /// Below an open membrane with a fixed rim, pushing it up (a container under it, full up
    /// to `level`).
    Below,
    /// Above an open membrane with a fixed rim, which is the floor of a container; it pushes
    /// the membrane down.
    Above,
}

impl FluidEffect {
    /// The fluid in the 3-D model (the closing plate only for a fluid inside).
    pub fn fluid(&self, cx: &Build) -> Fluid {
        Fluid {
            density: (cx.quantity)(&self.density),
            gravity: (cx.quantity)(&self.gravity),
            level: (cx.quantity)(&self.level),
            side: match self.side {
                Side::Inside | Side::Below => FluidSide::Behind,
                Side::Above => FluidSide::Front,
            },
            filled: self.filled,
            closing: cx.closing.clone().filter(|_| self.side == Side::Inside),
        }
    }
}

impl EffectSpec for FluidEffect {
    fn presses_normally(&self) -> bool {
        true
    }
    fn quantities(&self) -> Vec<(&'static str, &spec::Quantity, Range)> {
        vec![
            ("density", &self.density, Range::NonNegative),
            ("level", &self.level, Range::Finite),
            ("gravity", &self.gravity, Range::Positive),
        ]
    }
    fn check(&mut self) -> Result<(), Refusal> {
        if self.filled && self.side != Side::Inside {
            return Err(Refusal::at(
                "filled",
                "= true needs side = \"inside\" (a completely filled enclosure)",
            ));
        }
        Ok(())
    }
    fn check_mesh(&self, closed: bool, the_mesh: &str) -> Result<(), Refusal> {
        if closed && self.side != Side::Inside {
            let side = if self.side == Side::Below {
                "below"
            } else {
                "above"
            };
            return Err(Refusal::at(
                "side",
                format!(
                    "= \"{side}\" needs an open membrane; {the_mesh} is closed (use \"inside\")"
                ),
            ));
        }
        Ok(())
    }
    fn measures_enclosure(&self) -> bool {
        self.side == Side::Inside
    }
    /// `ρ g a²/(μH)` for the density or the gravity, `h/a` for the level.
    fn scales(&self, n: &Natural) -> Vec<Scale> {
        let (Some(mu_h), Some(a)) = (n.tension, n.length) else {
            return Vec::new();
        };
        let l = n.symbol;
        let mut out = Vec::new();
        let group = format!("ρ g {l}²/(μH)");
        if let (Some(rho), Some(g)) = (self.density.parameter(), self.gravity.number()) {
            out.push(Scale {
                parameter: rho.to_string(),
                group: group.clone(),
                values: vec![("g".into(), g), ("μH".into(), mu_h), (l.into(), a)],
                factor: g * a * a / mu_h,
            });
        }
        if let (Some(g), Some(rho)) = (self.gravity.parameter(), self.density.number()) {
            out.push(Scale {
                parameter: g.to_string(),
                group,
                values: vec![("ρ".into(), rho), ("μH".into(), mu_h), (l.into(), a)],
                factor: rho * a * a / mu_h,
            });
        }
        if let Some(h) = self.level.parameter() {
            out.push(Scale {
                parameter: h.to_string(),
                group: format!("h/{l}"),
                values: vec![(l.into(), a)],
                factor: 1.0 / a,
            });
        }
        out
    }
    fn build(&self, cx: &Build) -> Built {
        let fluid = self.fluid(cx);
        Built {
            effect: Box::new(fluid.clone()),
            measured: Some(Measured::FluidVolume(fluid)),
        }
    }
    fn meridian(&self, cx: &Build) -> Result<MeridianLoad, Refusal> {
        Ok(MeridianLoad::Pressure(Pressure::Fluid {
            filled: self.filled,
            density: (cx.quantity)(&self.density),
            gravity: (cx.quantity)(&self.gravity),
            level: (cx.quantity)(&self.level),
            front: self.side == Side::Above,
        }))
    }
}
