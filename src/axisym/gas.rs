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

use super::{AxisymError, AxisymModel, Pressure};
use crate::effects::Quantity;

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
}

/// A gas-amount effect at a state: C, P_atm, V* and the gas volume V_g = V − V*.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct GasAmountAt {
    pub amount: f64,
    pub ambient: f64,
    pub gas_volume: f64,
    /// The parameters C and V* are (if they are).
    pub amount_parameter: Option<usize>,
    pub fluid_parameter: Option<usize>,
}

impl GasAmountAt {
    /// The over-pressure C/V_g − P_atm.
    pub fn pressure(&self) -> f64 {
        self.amount / self.gas_volume - self.ambient
    }

    /// The coefficient C/V_g² of the rank-one stiffness along ∇V.
    pub fn stiffness(&self) -> f64 {
        self.amount / (self.gas_volume * self.gas_volume)
    }
}

impl AxisymModel {
    /// Every gas-amount effect at the nodes `x` (a gas volume that is not positive is an
    /// error: the fluid fills the enclosure).
    pub(super) fn gas_amounts_at(
        &self,
        x: &[[f64; 2]],
        params: &[f64],
    ) -> Result<Vec<GasAmountAt>, AxisymError> {
        let mut out = Vec::new();
        let mut volume = None;
        for load in &self.pressures {
            let Pressure::GasAmount {
                amount,
                ambient,
                fluid,
            } = *load
            else {
                continue;
            };
            let v = *volume.get_or_insert_with(|| self.volume(x));
            let gas_volume = v - fluid.map_or(0.0, |f| f.value(params));
            if gas_volume.is_nan() || gas_volume <= 0.0 {
                return Err(AxisymError::Input(format!(
                    "the gas volume {gas_volume:e} (enclosed {v:e} less the fluid's) is not positive"
                )));
            }
            out.push(GasAmountAt {
                amount: amount.value(params),
                ambient,
                gas_volume,
                amount_parameter: amount.parameter(),
                fluid_parameter: fluid.and_then(|f| f.parameter()),
            });
        }
        Ok(out)
    }

    /// The over-pressure C/(V − V*) − P_atm of the first gas-amount effect at the nodes `x`
    /// (NaN without one, or where its gas volume is not positive).
    pub fn gas_pressure(&self, x: &[[f64; 2]], params: &[f64]) -> f64 {
        self.gas_amounts_at(x, params)
            .ok()
            .and_then(|g| g.first().map(GasAmountAt::pressure))
            .unwrap_or(f64::NAN)
    }

    /// The pressures with every gas-amount effect replaced by a gas at its over-pressure at
    /// the nodes `x` (what the integrals along the meridian and the blocks see).
    pub(super) fn resolved_pressures(
        &self,
        x: &[[f64; 2]],
        params: &[f64],
    ) -> Result<Vec<Pressure>, AxisymError> {
        if !self
            .pressures
            .iter()
            .any(|p| matches!(p, Pressure::GasAmount { .. }))
        {
            return Ok(self.pressures.clone());
        }
        let mut gases = self.gas_amounts_at(x, params)?.into_iter();
        Ok(self
            .pressures
            .iter()
            .map(|p| match p {
                Pressure::GasAmount { .. } => Pressure::Gas {
                    pressure: Quantity::Value(gases.next().expect("one per effect").pressure()),
                },
                other => *other,
            })
            .collect())
    }

    /// The gas-amount effects' global terms, after the integrals of the resolved gases
    /// (which gave −p ∇V, −p ∇²V and the energy −p V): the energy −C ln V_g + P_atm V_g in
    /// place of −p V, the loads ∂R/∂C = −∇V/V_g and ∂R/∂V* = −(C/V_g²) ∇V, and the rank-one
    /// stiffness (C/V_g²) ∇V ∇Vᵀ.
    pub(super) fn add_gas_amounts(
        &self,
        q: &[f64],
        x: &[[f64; 2]],
        params: &[f64],
        out: &mut super::Evaluated,
    ) -> Result<(), AxisymError> {
        let gases = self.gas_amounts_at(x, params)?;
        if gases.is_empty() {
            return Ok(());
        }
        let v = self.volume(x);
        let grad = self.volume_gradient(q);
        for g in gases {
            let p = g.pressure();
            out.energy += p * v - g.amount * g.gas_volume.ln() + g.ambient * g.gas_volume;
            for (j, c) in [
                (g.amount_parameter, -1.0 / g.gas_volume),
                (g.fluid_parameter, -g.stiffness()),
            ] {
                if let Some(j) = j {
                    for (k, dv) in grad.iter().enumerate() {
                        out.loads[(k, j)] += c * dv;
                    }
                }
            }
            out.rank_one.push((g.stiffness(), grad.clone()));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::Meridian;
    use super::*;
    use crate::effects::membrane::MooneyRivlin;

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

    /// The block m = 0 of the sphere on its plane, bordered by the gas amount's rank-one
    /// stiffness and the fluid volume: its negative count less the two borders is the index
    /// of (K + (C/V_g²) ∇V ∇Vᵀ) bordered by the fluid's L = −ρ g ∇V_f and C = −ρ g A_s
    /// (docs/theory.md §8.3), evaluated independently from the dense tangent.
    #[test]
    fn the_gas_amount_and_fluid_borders_give_the_constrained_index() {
        use super::super::model::tests::generic_paper2;
        use nalgebra::DMatrix;
        let (model, q, params) = generic_paper2();
        assert_eq!(model.block_layout(0).border, 2);
        assert_eq!(model.block_layout(1).border, 0);
        let layout = model.block_layout(0);
        let values = model.block_values(&layout, &q, &params).unwrap();
        let n = layout.kept + layout.border;
        let d = layout.pattern.to_dense(&values);
        let full = DMatrix::from_fn(n, n, |i, j| d[(i, j)]);
        let negatives = |a: &DMatrix<f64>| {
            let tol = 1e-9 * a.amax();
            a.clone()
                .symmetric_eigenvalues()
                .iter()
                .filter(|v| **v < -tol)
                .count()
        };
        // The independent count: the dense tangent (rank-one term included) bordered by the
        // level's load and ∂g/∂h, on the free unknowns (the block m = 0 keeps every one of
        // them and the twist V, whose block is positive: add its count apart).
        let e = model.evaluate(&q, &params).unwrap();
        let x = model.positions(&q);
        let fluid = model.held_fluid(&x, &params).unwrap();
        let m = model.dim();
        let mut k = DMatrix::zeros(m + 1, m + 1);
        k.view_mut((0, 0), (m, m)).copy_from(&e.tangent);
        let l = model.free_part(&fluid.gradient);
        for i in 0..m {
            k[(i, m)] = -fluid.weight * l[i];
            k[(m, i)] = -fluid.weight * l[i];
        }
        k[(m, m)] = -fluid.weight * fluid.section;
        let constrained = negatives(&k) - 1;
        // The twist block (V only) of the bare m = 0 block.
        let (map, _) = model.kept_map(0);
        let twist: Vec<usize> = (0..map.len())
            .filter(|j| j % 3 == 1)
            .filter_map(|j| map[j].map(|c| c.0))
            .collect();
        let t = DMatrix::from_fn(twist.len(), twist.len(), |i, j| d[(twist[i], twist[j])]);
        assert_eq!(negatives(&full) - 2, constrained + negatives(&t));
        // Each corner's Schur complement adds c |g|² along its column: C/V_g² for the gas,
        // ρ g/A_s for the fluid.
        let gas = model.gas_amounts_at(&x, &params).unwrap()[0];
        let gv = model.volume_gradient(&q);
        let norm2 = |g: &[f64]| g.iter().map(|v| v * v).sum::<f64>();
        let expected = [
            gas.stiffness() * norm2(&gv),
            fluid.weight / fluid.section * norm2(&l),
        ];
        for (j, want) in expected.iter().enumerate() {
            let c = layout.kept + j;
            let col = (0..layout.kept).map(|i| d[(i, c)].powi(2)).sum::<f64>();
            let added = col / -d[(c, c)];
            assert!((added / want - 1.0).abs() < 1e-10, "{j}: {added} vs {want}");
        }
        assert!(fluid.section > 0.0 && gas.gas_volume > 0.0);
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
