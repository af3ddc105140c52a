//! The gas-amount constraint on the meridian (docs/theory.md §15.15), the 3-D constraint of
//! docs/theory.md §3.3 for a gas alone in a membrane of revolution.
//!
//! A gas effect at the over-pressure p (a parameter) fills the enclosed volume
//! V = −π ∫ r² z_ξ dξ ([`super::volume`]); holding its amount frees p. The augmenting equation
//! and its derivatives are
//!
//! ```text
//!   g(q, p) = (P_atm + p) V(q) − C* = 0,   ∂g/∂q = (P_atm + p) ∇V,   ∂g/∂p = V,
//! ```
//!
//! with C* a number, the amount at the start, or a parameter (∂g/∂C* = −1). The gas's load
//! is ∂R/∂p = −∇V, so the bordered tangent [[K, −∇V], [(P_atm + p) ∇Vᵀ, V]] is the symmetric
//! [[K, −∇V], [−∇Vᵀ, −V/(P_atm + p)]] after its row is scaled by −1/(P_atm + p). Its Schur
//! complement on the border is K + ((P_atm + p)/V) ∇V ∇Vᵀ, the stiffness of the isothermal
//! gas of fixed amount (Π = −C ln V + P_atm V of §3.3 at C = (P_atm + p) V), and the corner
//! is negative: the index at fixed amount is neg of the bordered block less one, as for the
//! hard constraint of §8.3.
//!
//! As for the fluid volume, the first variation of V along a field of wave number m ≥ 1
//! vanishes (∫ cos mθ dθ = 0): the constraint borders the block m = 0 only.

use super::AxisymModel;

/// A gas amount held on the meridian: the gas's pressure parameter and the ambient pressure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GasAmountBorder {
    /// The over-pressure's parameter index (the parameter the constraint frees).
    pub pressure: usize,
    /// The ambient (absolute) pressure P_atm.
    pub ambient: f64,
}

/// The gas-amount row at a state: g, ∂g/∂q and ∂g/∂p (over the free unknowns).
#[derive(Debug, Clone, PartialEq)]
pub struct GasAmountRow {
    /// g = (P_atm + p) V − C*.
    pub value: f64,
    /// ∂g/∂q = (P_atm + p) ∇V.
    pub grad_q: Vec<f64>,
    /// ∂g/∂p = V.
    pub grad_p: f64,
}

impl AxisymModel {
    /// The amount (P_atm + p) V of the gas of `gas` at displacement `q`, parameters `params`.
    pub fn gas_amount(&self, gas: &GasAmountBorder, q: &[f64], params: &[f64]) -> f64 {
        (gas.ambient + params[gas.pressure]) * self.volume(&self.positions(q))
    }

    /// The gas-amount row holding the amount `target` at displacement `q`, parameters
    /// `params`.
    pub fn gas_amount_row(
        &self,
        gas: &GasAmountBorder,
        target: f64,
        q: &[f64],
        params: &[f64],
    ) -> GasAmountRow {
        let pa = gas.ambient + params[gas.pressure];
        let v = self.volume(&self.positions(q));
        GasAmountRow {
            value: pa * v - target,
            grad_q: self.volume_gradient(q).iter().map(|g| pa * g).collect(),
            grad_p: v,
        }
    }

    /// The corner of the block m = 0 bordered by the column α ∇V (kept unknowns),
    /// α = `scale`/`norm`: −α² V/(P_atm + p), so that the Schur complement adds
    /// ((P_atm + p)/V) ∇V ∇Vᵀ to the block.
    pub(super) fn gas_corner(&self, x: &[[f64; 2]], params: &[f64], scale: f64, norm: f64) -> f64 {
        let Some(gas) = self.gas_amount else {
            return 0.0;
        };
        let alpha = scale / norm;
        -alpha * alpha * self.volume(x) / (gas.ambient + params[gas.pressure])
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Meridian, Pressure};
    use super::*;
    use crate::effects::membrane::MooneyRivlin;
    use crate::effects::Quantity;

    /// A sphere stretched off its reference under two gases, the second one's amount held.
    fn generic_balloon() -> (AxisymModel, Vec<f64>, Vec<f64>, GasAmountBorder) {
        let mat = MooneyRivlin::new(1.0, 0.1, 0.01);
        let meridian = Meridian::sphere(1.0, 6, 1.0, mat).unwrap();
        let pressures = vec![
            Pressure::Gas {
                pressure: Quantity::Parameter(0),
            },
            Pressure::Gas {
                pressure: Quantity::Parameter(1),
            },
        ];
        let mut model = AxisymModel::new(meridian, pressures);
        let gas = GasAmountBorder {
            pressure: 1,
            ambient: 0.1,
        };
        model.gas_amount = Some(gas);
        let q: Vec<f64> = (0..model.dim())
            .map(|k| 0.04 * ((k as f64) * 1.3).sin() + 0.1)
            .collect();
        (model, q, vec![0.2, 0.3, 1.9], gas)
    }

    /// g, ∂g/∂q and ∂g/∂p against central differences of g.
    #[test]
    fn the_gas_amount_row_matches_finite_differences() {
        let (model, q, params, gas) = generic_balloon();
        let target = 1.9;
        let row = model.gas_amount_row(&gas, target, &q, &params);
        let g = |q: &[f64], p: &[f64]| model.gas_amount(&gas, q, p) - target;
        assert!((row.value - g(&q, &params)).abs() < 1e-14);
        let h = 1e-6;
        for k in 0..model.dim() {
            let (mut qp, mut qm) = (q.clone(), q.clone());
            qp[k] += h;
            qm[k] -= h;
            let d = (g(&qp, &params) - g(&qm, &params)) / (2.0 * h);
            assert!(
                (d - row.grad_q[k]).abs() < 1e-8 * (1.0 + d.abs()),
                "{k}: {d} vs {}",
                row.grad_q[k]
            );
        }
        let (mut pp, mut pm) = (params.clone(), params.clone());
        pp[1] += h;
        pm[1] -= h;
        let d = (g(&q, &pp) - g(&q, &pm)) / (2.0 * h);
        assert!((d - row.grad_p).abs() < 1e-8 * (1.0 + d.abs()), "{d}");
        assert!(row.grad_q.iter().any(|v| v.abs() > 0.1));
    }

    /// The bordered blocks: one border column for m = 0, none for m ≥ 1, and the Schur
    /// complement of the m = 0 border adds ((P_atm + p)/V) |∇V|² along ∇V (the corner
    /// against an independent evaluation of the fixed-amount stiffness).
    #[test]
    fn the_gas_amount_borders_the_axisymmetric_block_only() {
        let (model, q, params, gas) = generic_balloon();
        for m in 0..4 {
            let layout = model.block_layout(m);
            assert_eq!(layout.border, usize::from(m == 0), "m = {m}");
        }
        let layout = model.block_layout(0);
        let values = model.block_values(&layout, &q, &params).unwrap();
        let d = layout.pattern.to_dense(&values);
        let n = layout.kept;
        let col: Vec<f64> = (0..n).map(|i| d[(i, n)]).collect();
        let corner = d[(n, n)];
        assert!(corner < 0.0, "{corner}");
        // The border column is α ∇V on the kept unknowns: at m = 0 a sphere keeps every free
        // (r, z) unknown as U and W with coefficient 1 (and V, where ∇V has no part).
        let grad = model.volume_gradient(&q);
        let x = model.positions(&q);
        let pa = gas.ambient + params[gas.pressure];
        let added: f64 = col.iter().map(|c| c * c).sum::<f64>() / -corner;
        let expected = pa / model.volume(&x) * grad.iter().map(|g| g * g).sum::<f64>();
        assert!(
            (added / expected - 1.0).abs() < 1e-10,
            "{added} vs {expected}"
        );
    }
}
