//! Enclosed gas (docs/theory.md §3), with V = Σ_T V_T the enclosed volume ([`super::volume`]).
//!
//! - Fixed over-pressure p (a parameter): `Π = −p V`, so `F = −p ∇V`, `K = −p ∇²V`,
//!   `∂F/∂p = −∇V`.
//! - Fixed amount of gas, isothermal (absolute pressure P = C/V_g, ambient P_atm) in the gas
//!   volume V_g = V − V*: `Π = −C ln V_g + P_atm V_g`, so `F = −p ∇V` with the over-pressure
//!   `p = C/V_g − P_atm`, `K = −p ∇²V + (C/V_g²) ∇V ∇Vᵀ` (a rank-one term, handed to the solver
//!   as such), `∂F/∂C = −∇V / V_g` and `∂F/∂V* = −(C/V_g²) ∇V`. V* is the volume of fluid in
//!   the same enclosure (0 without one): the fluid's *amount*, which a fluid-volume constraint
//!   holds, not V_f(u, h) at a fixed level — the gas pressure acts on the fluid's surface and
//!   through it on the wet membrane, which `F = −p ∇V` says (docs/theory.md §3.5).
//!
//! For an open membrane the plate closing it is part of V ([`ClosingFace`]): a constant for a
//! fixed rim, a function of the rim nodes for a rim sliding in the plate's plane.

use super::spec::{
    self, Build, Built, EffectSpec, Measured, MeridianLoad, Natural, Range, Refusal, Scale,
};
use super::volume::{volume, ClosingFace};
use super::Quantity;
use crate::axisym::Pressure;
use crate::model::constraint::{gather, Constraint, ConstraintValue};
use crate::model::{Assembler, Effect, Layout, ModelError, NodeField, NodeQuantity, Vec3};
use std::sync::Arc;
use symmetry::Invariant;

/// Gas at a fixed over-pressure p (parameter index `pressure`).
#[derive(Debug, Clone)]
pub struct GasPressure {
    /// The over-pressure.
    pub pressure: Quantity,
    /// The plate closing an open membrane whose rim can move (a fixed rim needs none).
    pub closing: Option<Arc<ClosingFace>>,
}

impl GasPressure {
    /// Gas at over-pressure `pressure`, without a closing plate.
    pub fn new(pressure: Quantity) -> Self {
        Self {
            pressure,
            closing: None,
        }
    }
}

/// V_T of triangle `t`, with the part z_c A_z/3 of the closing face on its rim edges.
fn enclosed(closing: Option<&ClosingFace>, t: usize, xt: &[Vec3; 3]) -> crate::model::Local {
    let mut v = volume(xt);
    if let Some(c) = closing.filter(|c| c.touches(t)) {
        v.add_scaled(&c.area_local(t, xt), c.z / 3.0);
    }
    v
}

/// The enclosed volume Σ_T V_T plus the closing face's part.
pub fn enclosed_volume(closing: Option<&ClosingFace>, triangles: &[[usize; 3]], x: &[Vec3]) -> f64 {
    triangles
        .iter()
        .map(|&[a, b, c]| volume(&[x[a], x[b], x[c]]).value)
        .sum::<f64>()
        + closing.map_or(0.0, |c| c.volume(triangles, x))
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
        let closing = self.closing.as_deref();
        out.add_triangles(x, [self.pressure.parameter(), None], |t, xt, terms| {
            let v = enclosed(closing, t, xt);
            terms.local = v.scaled(-p);
            terms.loads[0] = v.grad.map(|g| -g);
            Ok(())
        })
    }

    /// The over-pressure p, the same at every node.
    fn node_fields(&self, x: &[Vec3], _: &[[usize; 3]], params: &[f64]) -> Vec<NodeField> {
        vec![NodeField {
            quantity: NodeQuantity::Pressure,
            values: vec![self.pressure.value(params); x.len()],
        }]
    }
}

/// A fixed amount of gas at constant temperature: absolute pressure `C/V_g`, V_g = V − V*.
#[derive(Debug, Clone)]
pub struct GasAmount {
    /// C = P·V_g (absolute pressure times gas volume).
    pub amount: Quantity,
    /// Ambient (absolute) pressure P_atm.
    pub ambient: f64,
    /// The plate closing an open membrane (its part of V).
    pub closing: Option<Arc<ClosingFace>>,
    /// V*: the volume of fluid in the same enclosure, if any (a number or a parameter).
    pub fluid: Option<Quantity>,
}

impl GasAmount {
    /// C of gas with ambient pressure `ambient`, alone in a closed membrane.
    pub fn new(amount: Quantity, ambient: f64) -> Self {
        Self {
            amount,
            ambient,
            closing: None,
            fluid: None,
        }
    }

    /// The enclosed volume V at positions `x` (closing plate included).
    pub fn volume(&self, triangles: &[[usize; 3]], x: &[Vec3]) -> f64 {
        enclosed_volume(self.closing.as_deref(), triangles, x)
    }

    /// The gas volume V_g = V − V* at positions `x` and parameters `params`.
    pub fn gas_volume(&self, triangles: &[[usize; 3]], x: &[Vec3], params: &[f64]) -> f64 {
        self.volume(triangles, x) - self.fluid.map_or(0.0, |f| f.value(params))
    }

    /// The over-pressure C/V_g − P_atm.
    pub fn over_pressure(&self, triangles: &[[usize; 3]], x: &[Vec3], params: &[f64]) -> f64 {
        self.amount.value(params) / self.gas_volume(triangles, x, params) - self.ambient
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
        let v = self.gas_volume(out.triangles(), x, params);
        if v.is_nan() || v <= 0.0 {
            return Err(ModelError::Global {
                effect: self.name().into(),
                what: format!("the gas volume {v:e} is not positive"),
            });
        }
        let p = c / v - self.ambient;
        let closing = self.closing.as_deref();
        out.add_energy(-c * v.ln() + self.ambient * v);
        let fluid = self.fluid.and_then(|f| f.parameter());
        out.add_triangles(x, [self.amount.parameter(), fluid], |t, xt, terms| {
            let vt = enclosed(closing, t, xt);
            // Energy is added once above; the triangles carry −p ∇V and −p ∇²V.
            terms.local = vt.scaled(-p);
            terms.local.value = 0.0;
            terms.loads[0] = vt.grad.map(|g| -g / v);
            terms.loads[1] = vt.grad.map(|g| -g * c / (v * v));
            Ok(())
        })?;
        if out.request().tangent {
            let grad_v = out.gradient_vector(x, |t, xt| enclosed(closing, t, xt).grad);
            out.add_rank_one(c / (v * v), grad_v);
        }
        Ok(())
    }

    /// The over-pressure C/V_g − P_atm, the same at every node.
    fn node_fields(&self, x: &[Vec3], triangles: &[[usize; 3]], params: &[f64]) -> Vec<NodeField> {
        vec![NodeField {
            quantity: NodeQuantity::Pressure,
            values: vec![self.over_pressure(triangles, x, params); x.len()],
        }]
    }
}

/// Fixed amount of gas (P_atm + p)(V − V*) = C* for a fixed-pressure gas effect; frees p.
/// V includes the closing plate, V* is the fluid in the same enclosure (as in [`GasAmount`]).
#[derive(Debug, Clone)]
pub struct GasAmountConstraint {
    /// The pressure's parameter index.
    pub pressure: usize,
    /// Ambient absolute pressure.
    pub ambient: f64,
    /// C* (when `target_parameter` is `None`).
    pub target: f64,
    /// The parameter that is C*, if any.
    pub target_parameter: Option<usize>,
    /// The plate closing an open membrane (its part of V).
    pub closing: Option<Arc<ClosingFace>>,
    /// V*: the volume of fluid in the same enclosure, if any.
    pub fluid: Option<Quantity>,
}

impl GasAmountConstraint {
    /// The gas volume V − V*.
    fn gas_volume(&self, layout: &Layout, x: &[Vec3], params: &[f64]) -> f64 {
        enclosed_volume(self.closing.as_deref(), layout.triangles(), x)
            - self.fluid.map_or(0.0, |f| f.value(params))
    }
}

impl Constraint for GasAmountConstraint {
    fn name(&self) -> &str {
        "gas-amount"
    }
    fn frees(&self) -> usize {
        self.pressure
    }
    fn measure(&self, layout: &Layout, x: &[Vec3], params: &[f64]) -> f64 {
        (params[self.pressure] + self.ambient) * self.gas_volume(layout, x, params)
    }
    fn target(&self) -> f64 {
        self.target
    }
    fn set_target(&mut self, target: f64) {
        self.target = target;
    }
    fn evaluate(&self, layout: &Layout, x: &[Vec3], params: &[f64]) -> ConstraintValue {
        let pa = params[self.pressure] + self.ambient;
        let v = self.gas_volume(layout, x, params);
        let closing = self.closing.as_deref();
        let mut grad_params = vec![0.0; params.len()];
        let grad_u = gather(layout, x, &mut grad_params, |t, xt| {
            enclosed(closing, t, xt).grad.map(|g| pa * g)
        });
        grad_params[self.pressure] += v;
        if let Some(j) = self.fluid.and_then(|f| f.parameter()) {
            grad_params[j] -= pa;
        }
        let target = match self.target_parameter {
            Some(j) => {
                grad_params[j] -= 1.0;
                params[j]
            }
            None => self.target,
        };
        ConstraintValue {
            value: pa * v - target,
            grad_u,
            grad_params,
        }
    }
}

/// `[[effect]] type = "gas"`: gas at a fixed over-pressure, Π = −p V.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct GasEffect {
    /// Over-pressure p (inside minus outside); positive inflates.
    pub pressure: spec::Quantity,
}

impl EffectSpec for GasEffect {
    fn presses_normally(&self) -> bool {
        true
    }
    fn quantities(&self) -> Vec<(&'static str, &spec::Quantity, Range)> {
        vec![("pressure", &self.pressure, Range::Finite)]
    }
    fn measures_enclosure(&self) -> bool {
        true
    }
    /// `p a/(μH)`.
    fn scales(&self, n: &Natural) -> Vec<Scale> {
        let (Some(p), Some(mu_h), Some(a)) = (self.pressure.parameter(), n.tension, n.length)
        else {
            return Vec::new();
        };
        let l = n.symbol;
        vec![Scale {
            parameter: p.to_string(),
            group: format!("p {l}/(μH)"),
            values: vec![("μH".into(), mu_h), (l.into(), a)],
            factor: a / mu_h,
        }]
    }
    fn build(&self, cx: &Build) -> Built {
        Built {
            effect: Box::new(GasPressure {
                pressure: (cx.quantity)(&self.pressure),
                closing: cx.closing.clone(),
            }),
            measured: None,
        }
    }
    fn meridian(&self, cx: &Build) -> Result<MeridianLoad, Refusal> {
        Ok(MeridianLoad::Pressure(Pressure::Gas {
            pressure: (cx.quantity)(&self.pressure),
        }))
    }
}

/// `[[effect]] type = "gas-amount"`: a fixed amount of gas (isothermal),
/// Π = −C ln V + P_atm V.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct GasAmountEffect {
    /// Amount C > 0 (absolute pressure × volume, P = C/V).
    pub amount: spec::Quantity,
    /// Ambient (absolute) pressure P_atm ≥ 0; over-pressure p = C/V − P_atm.
    pub ambient_pressure: f64,
}

impl EffectSpec for GasAmountEffect {
    fn presses_normally(&self) -> bool {
        true
    }
    fn quantities(&self) -> Vec<(&'static str, &spec::Quantity, Range)> {
        vec![("amount", &self.amount, Range::Positive)]
    }
    fn check(&mut self) -> Result<(), Refusal> {
        spec::non_negative("ambient-pressure", self.ambient_pressure)
    }
    fn measures_enclosure(&self) -> bool {
        true
    }
    fn build(&self, cx: &Build) -> Built {
        let gas = GasAmount {
            amount: (cx.quantity)(&self.amount),
            ambient: self.ambient_pressure,
            closing: cx.closing.clone(),
            fluid: cx.fluid_amount,
        };
        Built {
            effect: Box::new(gas.clone()),
            measured: Some(Measured::GasPressure(gas)),
        }
    }
    /// The fluid's amount a fluid-volume constraint holds is what the gas leaves out of the
    /// enclosure.
    fn meridian(&self, cx: &Build) -> Result<MeridianLoad, Refusal> {
        Ok(MeridianLoad::Pressure(Pressure::GasAmount {
            amount: (cx.quantity)(&self.amount),
            ambient: self.ambient_pressure,
            fluid: cx.fluid_amount,
        }))
    }
}
