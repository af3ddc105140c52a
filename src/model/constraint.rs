//! Augmenting equations g(u, Λ) = 0 that free one parameter each (DESIGN §2.6).
//!
//! - Fixed fluid volume: g = V_f(u, h) − V*, V_f = Σ_T v_T (± for the side) plus the part of a
//!   fixed flat face closing an open membrane ([`ClosingFace`]), which frees the level h.
//! - Fixed amount of gas at fixed over-pressure effect: g = (p + P_atm) V(u) − C*, which frees
//!   the pressure p.
//!
//! Each returns g, ∂g/∂u (over the unknowns) and ∂g/∂Λ (over all parameters).

use super::{Layout, Vec3};
use crate::effects::hydrostatic::{fluid_volume, Fluid, FluidSide};
use crate::effects::volume::volume;

/// g, ∂g/∂u and ∂g/∂Λ at a state.
#[derive(Debug, Clone, PartialEq)]
pub struct ConstraintValue {
    /// g.
    pub value: f64,
    /// ∂g/∂u.
    pub grad_u: Vec<f64>,
    /// ∂g/∂Λ_j for every parameter.
    pub grad_params: Vec<f64>,
}

/// An augmenting equation.
pub trait Constraint: Send + Sync {
    /// A short name, e.g. `fluid-volume`.
    fn name(&self) -> &str;
    /// The parameter it frees.
    fn frees(&self) -> usize;
    /// The measured quantity (g + target) at a state, to set `target` from a start state.
    fn measure(&self, layout: &Layout, x: &[Vec3], params: &[f64]) -> f64;
    /// The target value.
    fn target(&self) -> f64;
    /// Sets the target value.
    fn set_target(&mut self, target: f64);
    /// g and its derivatives.
    fn evaluate(&self, layout: &Layout, x: &[Vec3], params: &[f64]) -> ConstraintValue;
}

/// Scatters per-triangle gradients into a vector over the unknowns.
fn gather(layout: &Layout, x: &[Vec3], grad: impl Fn(&[Vec3; 3]) -> [f64; 9]) -> Vec<f64> {
    let mut v = vec![0.0; layout.unknowns()];
    for &[a, b, c] in layout.triangles() {
        let g = grad(&[x[a], x[b], x[c]]);
        for (k, node) in [a, b, c].into_iter().enumerate() {
            for comp in 0..3 {
                if let Some(d) = layout.dof(node, comp) {
                    v[d] += g[3 * k + comp];
                }
            }
        }
    }
    v
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

/// Fixed fluid volume of a fluid effect; frees its level.
#[derive(Debug, Clone)]
pub struct FluidVolume {
    /// The fluid effect (its level must be a parameter).
    pub fluid: Fluid,
    /// The level's parameter index.
    pub level: usize,
    /// V*.
    pub target: f64,
    /// The fixed face closing an open membrane, if any.
    pub closing: Option<ClosingFace>,
}

impl FluidVolume {
    fn sign(&self) -> f64 {
        match self.fluid.side {
            FluidSide::Behind => 1.0,
            FluidSide::Front => -1.0,
        }
    }
}

impl Constraint for FluidVolume {
    fn name(&self) -> &str {
        "fluid-volume"
    }
    fn frees(&self) -> usize {
        self.level
    }
    fn measure(&self, layout: &Layout, x: &[Vec3], params: &[f64]) -> f64 {
        let closing = self
            .closing
            .map_or(0.0, |c| self.sign() * c.fluid_volume(params[self.level]).0);
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
        let s = self.sign();
        let mut value = 0.0;
        let mut d_dh = 0.0;
        for &[a, b, c] in layout.triangles() {
            let v = fluid_volume(&[x[a], x[b], x[c]], h);
            value += s * v.value;
            d_dh += s * v.d_dh;
        }
        if let Some(c) = self.closing {
            let (v, dv) = c.fluid_volume(h);
            value += s * v;
            d_dh += s * dv;
        }
        let grad_u = gather(layout, x, |xt| fluid_volume(xt, h).grad.map(|g| s * g));
        let mut grad_params = vec![0.0; params.len()];
        grad_params[self.level] = d_dh;
        ConstraintValue {
            value: value - self.target,
            grad_u,
            grad_params,
        }
    }
}

/// Fixed amount of gas (P_atm + p) V = C* for a fixed-pressure gas effect; frees p.
#[derive(Debug, Clone)]
pub struct GasAmount {
    /// The pressure's parameter index.
    pub pressure: usize,
    /// Ambient absolute pressure.
    pub ambient: f64,
    /// C*.
    pub target: f64,
    /// Volume between the membrane and fixed walls, added to Σ V_T.
    pub closing_volume: f64,
}

impl Constraint for GasAmount {
    fn name(&self) -> &str {
        "gas-amount"
    }
    fn frees(&self) -> usize {
        self.pressure
    }
    fn measure(&self, layout: &Layout, x: &[Vec3], params: &[f64]) -> f64 {
        let v: f64 = layout
            .triangles()
            .iter()
            .map(|&[a, b, c]| volume(&[x[a], x[b], x[c]]).value)
            .sum();
        (params[self.pressure] + self.ambient) * v
    }
    fn target(&self) -> f64 {
        self.target
    }
    fn set_target(&mut self, target: f64) {
        self.target = target;
    }
    fn evaluate(&self, layout: &Layout, x: &[Vec3], params: &[f64]) -> ConstraintValue {
        let pa = params[self.pressure] + self.ambient;
        let v: f64 = layout
            .triangles()
            .iter()
            .map(|&[a, b, c]| volume(&[x[a], x[b], x[c]]).value)
            .sum();
        let grad_u = gather(layout, x, |xt| volume(xt).grad.map(|g| pa * g));
        let mut grad_params = vec![0.0; params.len()];
        grad_params[self.pressure] = v;
        ConstraintValue {
            value: pa * v - self.target,
            grad_u,
            grad_params,
        }
    }
}
