//! Enclosed gas (docs/theory.md §3), with V = Σ_T V_T the enclosed volume ([`super::volume`]).
//!
//! - Fixed over-pressure p (a parameter): `Π = −p V`, so `F = −p ∇V`, `K = −p ∇²V`,
//!   `∂F/∂p = −∇V`.
//! - Fixed amount of gas, isothermal (absolute pressure P = C/V, ambient P_atm):
//!   `Π = −C ln V + P_atm V`, so `F = −p ∇V` with the over-pressure `p = C/V − P_atm`,
//!   `K = −p ∇²V + (C/V²) ∇V ∇Vᵀ` (a rank-one term, handed to the solver as such) and
//!   `∂F/∂C = −∇V / V`.
//!
//! For an open membrane with a fixed rim the closing surface is fixed: it changes V by a
//! constant only, which shifts Π by a constant (fixed pressure) or is part of V
//! (fixed amount: give it as `closing_volume`).

use super::volume::volume;
use super::Quantity;
use crate::model::constraint::{gather, Constraint, ConstraintValue};
use crate::model::{Assembler, Effect, Layout, ModelError, Vec3};
use symmetry::Invariant;

/// Gas at a fixed over-pressure p (parameter index `pressure`).
#[derive(Debug, Clone)]
pub struct GasPressure {
    /// The over-pressure.
    pub pressure: Quantity,
}

impl Effect for GasPressure {
    fn name(&self) -> &str {
        "gas"
    }

    /// A uniform pressure keeps every symmetry.
    fn keeps(&self) -> Vec<Invariant> {
        Vec::new()
    }

    /// The enclosed volume is invariant under rigid motions.
    fn rigid_motions(&self) -> Vec<[f64; 6]> {
        crate::model::ALL_RIGID_MOTIONS.to_vec()
    }

    fn assemble(
        &self,
        x: &[Vec3],
        params: &[f64],
        out: &mut Assembler<'_>,
    ) -> Result<(), ModelError> {
        let p = self.pressure.value(params);
        out.add_triangles(x, [self.pressure.parameter(), None], |_, xt, terms| {
            let v = volume(xt);
            terms.local = v.scaled(-p);
            terms.loads[0] = v.grad.map(|g| -g);
            Ok(())
        })
    }
}

/// A fixed amount of gas at constant temperature: absolute pressure `C/V`.
#[derive(Debug, Clone)]
pub struct GasAmount {
    /// C = P·V (absolute pressure times volume).
    pub amount: Quantity,
    /// Ambient (absolute) pressure P_atm.
    pub ambient: f64,
    /// Volume enclosed between the membrane and fixed walls, added to Σ V_T.
    pub closing_volume: f64,
}

impl GasAmount {
    /// The enclosed volume at positions `x`.
    pub fn volume(&self, triangles: &[[usize; 3]], x: &[Vec3]) -> f64 {
        self.closing_volume
            + triangles
                .iter()
                .map(|&[a, b, c]| x[a].dot(&x[b].cross(&x[c])) / 6.0)
                .sum::<f64>()
    }
}

impl Effect for GasAmount {
    fn name(&self) -> &str {
        "gas-amount"
    }

    fn keeps(&self) -> Vec<Invariant> {
        Vec::new()
    }

    fn rigid_motions(&self) -> Vec<[f64; 6]> {
        crate::model::ALL_RIGID_MOTIONS.to_vec()
    }

    fn assemble(
        &self,
        x: &[Vec3],
        params: &[f64],
        out: &mut Assembler<'_>,
    ) -> Result<(), ModelError> {
        let c = self.amount.value(params);
        let v = self.volume(out.triangles(), x);
        if v.is_nan() || v <= 0.0 {
            return Err(ModelError::Global {
                effect: self.name().into(),
                what: format!("the enclosed volume {v:e} is not positive"),
            });
        }
        let p = c / v - self.ambient;
        out.add_energy(-c * v.ln() + self.ambient * v);
        out.add_triangles(x, [self.amount.parameter(), None], |_, xt, terms| {
            let vt = volume(xt);
            // Energy is added once above; the triangles carry −p ∇V and −p ∇²V.
            terms.local = vt.scaled(-p);
            terms.local.value = 0.0;
            terms.loads[0] = vt.grad.map(|g| -g / v);
            Ok(())
        })?;
        if out.request().tangent {
            let grad_v = out.gradient_vector(x, |xt| volume(xt).grad);
            out.add_rank_one(c / (v * v), grad_v);
        }
        Ok(())
    }
}

/// Fixed amount of gas (P_atm + p) V = C* for a fixed-pressure gas effect; frees p.
#[derive(Debug, Clone)]
pub struct GasAmountConstraint {
    /// The pressure's parameter index.
    pub pressure: usize,
    /// Ambient absolute pressure.
    pub ambient: f64,
    /// C*.
    pub target: f64,
    /// Volume between the membrane and fixed walls, added to Σ V_T.
    pub closing_volume: f64,
}

impl Constraint for GasAmountConstraint {
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
