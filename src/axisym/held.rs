//! The borders of the Fourier blocks (docs/theory.md §15.12): the motions the stability
//! analysis holds and the volume constraint, as dense columns b_j appended to a block K_m,
//!
//! ```text
//!   K̃_m = [[K_m, B], [Bᵀ, 0]],   index(K_m on B^⊥) = neg(K̃_m) − rank B
//! ```
//!
//! (Haynsworth's inertia additivity with the hard-constraint case of docs/theory.md §8.3).
//!
//! A meridian with no clamped end that is not closed (a cap whose edge slides) is a free body
//! in the horizontal directions and about the axis. The 3-D model deflates its rigid motions
//! and holds the drifts of its effects (`Model::held_motions`): on the meridian the rotation
//! about z is the m = 0 field V = r (a null vector of K_0: every axisymmetric potential is
//! invariant under it), the drift along x the m = 1 field U = 1, V = −1, W = 0 (t e_x =
//! t (cos θ e_r − sin θ e_θ)), null without spin and a negative direction with it (the
//! centrifugal potential falls with the distance from the axis). Each border column is the
//! motion weighted by the reference area of its node's ring, a_i = ∫ N_i |X_ξ| R dξ (the
//! L² inner product on the surface, which the nodal inner product of a quasi-uniform 3-D
//! mesh approximates), so that the complement is that of the mean motion.
//!
//! The fluid-volume constraint borders the block m = 0 with the volume's gradient
//! ([`super::volume`]); its first variation vanishes for m ≥ 1 (∫ cos mθ dθ = 0), so it
//! borders no other block. The gas-amount constraint borders it with the same column and the
//! negative corner of [`super::gas`].

use super::model::BlockLayout;
use super::{shape, AxisymModel, GAUSS};

impl AxisymModel {
    /// Whether the meridian is a free body about and across the axis: no clamped end, not
    /// closed.
    fn free_body(&self) -> bool {
        let m = &self.meridian;
        !m.clamped.0 && !m.clamped.1 && !m.closed()
    }

    /// Border columns of the block of wave number m.
    pub(super) fn border_count(&self, m: usize) -> usize {
        let held = usize::from(self.free_body() && m <= 1);
        if m != 0 {
            return held;
        }
        let constraint = usize::from(self.volume_level.is_some() || self.gas_amount.is_some());
        held + self.gas_amount_effects() + constraint
    }

    /// The number of gas-amount effects (each borders the block m = 0 with its rank-one
    /// stiffness).
    fn gas_amount_effects(&self) -> usize {
        self.pressures
            .iter()
            .filter(|p| matches!(p, super::Pressure::GasAmount { .. }))
            .count()
    }

    /// The translation along `sign` e_z as the held field of `[start] hold-translation`
    /// (docs/theory.md §15.16) over the free unknowns: every free height weighted by its
    /// ring's reference area, so that holding wᵀ q / |w|² holds an area-weighted mean height
    /// and the holding force R w is a uniform load per reference area.
    pub fn held_translation(&self, sign: f64) -> nalgebra::DVector<f64> {
        let a = self.ring_areas();
        nalgebra::DVector::from_iterator(
            self.dim(),
            (0..self.dim()).map(|k| match self.free_unknown(k) {
                (i, 1) => sign * a[i],
                _ => 0.0,
            }),
        )
    }

    /// The reference area of every node's ring per radian, ∫ N_i |X_ξ| R dξ.
    fn ring_areas(&self) -> Vec<f64> {
        let nodes = &self.meridian.nodes;
        let mut a = vec![0.0; nodes.len()];
        for e in 0..self.meridian.elements() {
            for &(xi, w) in &GAUSS {
                let (n, dn) = shape(xi);
                let (mut r, mut dr, mut dz) = (0.0, 0.0, 0.0);
                for k in 0..3 {
                    r += n[k] * nodes[2 * e + k][0];
                    dr += dn[k] * nodes[2 * e + k][0];
                    dz += dn[k] * nodes[2 * e + k][1];
                }
                for k in 0..3 {
                    a[2 * e + k] += w * n[k] * dr.hypot(dz) * r;
                }
            }
        }
        a
    }

    /// The border columns of the block of wave number m at the nodes `x`, on its kept
    /// unknowns, each of unit length, with its length before it was made so and the
    /// coefficient c of the rank-one term c g gᵀ (g the column before normalising) that the
    /// Schur complement of its corner adds to the block: infinite for a hard border (a held
    /// motion, a filled fluid's volume; corner 0).
    fn border_vectors(
        &self,
        m: usize,
        x: &[[f64; 2]],
        params: &[f64],
    ) -> Vec<(Vec<f64>, f64, f64)> {
        let (map, cols) = self.kept_map(m);
        let from_full = |full: &dyn Fn(usize, usize) -> f64, c: f64| {
            let mut b = vec![0.0; cols];
            for (j, slot) in map.iter().enumerate() {
                if let Some((col, coefficient)) = slot {
                    b[*col] += coefficient * full(j / 3, j % 3);
                }
            }
            let norm = b.iter().map(|v| v * v).sum::<f64>().sqrt().max(1e-300);
            b.iter_mut().for_each(|v| *v /= norm);
            (b, norm, c)
        };
        fn axisymmetric(g: &[[f64; 2]]) -> impl Fn(usize, usize) -> f64 + '_ {
            move |i: usize, c: usize| match c {
                0 => g[i][0],
                2 => g[i][1],
                _ => 0.0,
            }
        }
        let mut out = Vec::new();
        if self.free_body() && m <= 1 {
            let a = self.ring_areas();
            out.push(if m == 0 {
                // The rotation about z: V = r.
                from_full(
                    &|i, c| if c == 1 { a[i] * x[i][0] } else { 0.0 },
                    f64::INFINITY,
                )
            } else {
                // The drift along x: U = 1, V = −1.
                from_full(
                    &|i, c| match c {
                        0 => a[i],
                        1 => -a[i],
                        _ => 0.0,
                    },
                    f64::INFINITY,
                )
            });
        }
        if m != 0 {
            return out;
        }
        if self.gas_amount_effects() > 0 || self.gas_amount.is_some() {
            let g = self.volume_gradient_nodes(x);
            // A gas amount's rank-one stiffness (C/V_g²) ∇V ∇Vᵀ; the tangent has it as such.
            for gas in self.gas_amounts_at(x, params).unwrap_or_default() {
                out.push(from_full(&axisymmetric(&g), gas.stiffness()));
            }
            // The gas-amount constraint: ((P_atm + p)/V) ∇V ∇Vᵀ (docs/theory.md §15.15).
            if let Some(gas) = self.gas_amount {
                let c = (gas.ambient + params[gas.pressure]) / self.volume(x);
                out.push(from_full(&axisymmetric(&g), c));
            }
        }
        // The fluid-volume constraint: (ρ g/A_s) ∇V_f ∇V_fᵀ, hard for a filled enclosure
        // (A_s = 0; docs/theory.md §8.3, §15.16).
        if let Some(f) = self.held_fluid(x, params) {
            let c = if f.section > 0.0 && f.weight > 0.0 {
                f.weight / f.section
            } else {
                f64::INFINITY
            };
            out.push(from_full(&axisymmetric(&f.gradient), c));
        }
        out
    }

    /// Writes the border of `layout` at the nodes `x` into the block values `v`, each column
    /// scaled to the block's largest entry (α = scale/|g|), with the corner −α²/c of its
    /// rank-one coefficient c, so that the Schur complement adds c g gᵀ.
    pub(super) fn set_border(
        &self,
        layout: &BlockLayout,
        x: &[[f64; 2]],
        params: &[f64],
        v: &mut [f64],
    ) {
        if layout.border == 0 {
            return;
        }
        let scale = v.iter().fold(0.0f64, |s, a| s.max(a.abs())).max(1e-300);
        self.set_border_scaled(layout, x, params, scale, v);
    }

    /// [`AxisymModel::set_border`] with the columns' scale given.
    pub(super) fn set_border_scaled(
        &self,
        layout: &BlockLayout,
        x: &[[f64; 2]],
        params: &[f64],
        scale: f64,
        v: &mut [f64],
    ) {
        let n = layout.kept;
        let borders = self.border_vectors(layout.m, x, params);
        for (j, (b, norm, c)) in borders.iter().enumerate() {
            for (i, bi) in b.iter().enumerate() {
                for (r, col) in [(i, n + j), (n + j, i)] {
                    let k = layout.pattern.position(r, col).expect("a border entry");
                    v[k] = scale * bi;
                }
            }
            let alpha = scale / norm;
            let k = layout
                .pattern
                .position(n + j, n + j)
                .expect("a border corner");
            v[k] = if c.is_finite() {
                -alpha * alpha / c
            } else {
                0.0
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::model::tests::generic_filled;
    use super::super::{AxisymProblem, Meridian, Pressure};
    use super::BlockLayout;
    use crate::continuation::{solve_at, PathOptions};
    use crate::effects::membrane::MooneyRivlin;
    use crate::effects::Quantity;
    use nalgebra::{DMatrix, DVector};

    /// The block of `layout` at (q, params) as a dense matrix, border included.
    fn dense(
        model: &super::AxisymModel,
        layout: &BlockLayout,
        q: &[f64],
        params: &[f64],
    ) -> DMatrix<f64> {
        let values = model.block_values(layout, q, params).unwrap();
        let d = layout.pattern.to_dense(&values);
        let n = layout.kept + layout.border;
        DMatrix::from_fn(n, n, |i, j| d[(i, j)])
    }

    fn negatives(a: &DMatrix<f64>, tol: f64) -> usize {
        let a = (a + a.transpose()) * 0.5;
        a.symmetric_eigenvalues()
            .iter()
            .filter(|&&v| v < -tol)
            .count()
    }

    /// The bordered block's negative count less its border is the index of the block on the
    /// complement of the border (Haynsworth), for the held motions and the volume border.
    #[test]
    fn the_bordered_index_is_the_index_on_the_complement() {
        let (model, q, params) = generic_filled();
        for m in 0..3 {
            let layout = model.block_layout(m);
            let full = dense(&model, &layout, &q, &params);
            let (n, b) = (layout.kept, layout.border);
            assert_eq!(b, [2, 1, 0][m], "border of m = {m}");
            let k = full.view((0, 0), (n, n)).into_owned();
            let scale = k.amax();
            let projected = if b == 0 {
                k.clone()
            } else {
                let bb = full.view((0, n), (n, b)).into_owned();
                let gram = bb.transpose() * &bb;
                let p =
                    DMatrix::identity(n, n) - &bb * gram.try_inverse().unwrap() * bb.transpose();
                &p * &k * &p
            };
            let restricted = negatives(&projected, 1e-9 * scale);
            assert_eq!(negatives(&full, 1e-9 * scale) - b, restricted, "m = {m}");
        }
    }

    /// At an equilibrium of the free cap without spin, the drift along x (m = 1: U = 1,
    /// V = −1, W = 0) and the rotation about z (m = 0: V = r) are null vectors of their
    /// blocks; bordered by them the blocks are regular, so no block is reported singular at
    /// every point.
    #[test]
    fn the_held_motions_are_the_null_vectors_of_the_free_cap() {
        let mat = MooneyRivlin::new(100.0, 0.1, 0.01);
        let mut meridian = Meridian::truncated_sphere(1.0, 0.0, 8, 1.05, mat).unwrap();
        meridian.clamped = (false, false);
        meridian.sliding = (false, true);
        let fluid = Pressure::Fluid {
            density: Quantity::Value(0.2),
            gravity: Quantity::Value(1.0),
            level: Quantity::Value(3.0),
            front: false,
            filled: true,
        };
        let model = super::AxisymModel::new(meridian, vec![fluid]);
        let mut problem = AxisymProblem::new(model.clone(), vec![0.0], 0);
        let q0 = DVector::zeros(model.dim());
        let (q, _, _) = solve_at(
            &mut problem,
            &q0,
            &DVector::from_element(1, 0.0),
            &PathOptions::default(),
        )
        .unwrap();
        let x = model.positions(q.as_slice());
        for m in 0..2 {
            let layout = model.block_layout(m);
            let full = dense(&model, &layout, q.as_slice(), &[0.0]);
            let n = layout.kept;
            let k = full.view((0, 0), (n, n)).into_owned();
            // The motion in the block's unknowns.
            let (map, _) = model.kept_map(m);
            let mut d = DVector::zeros(n);
            for (j, slot) in map.iter().enumerate() {
                if let Some((col, coefficient)) = slot {
                    // The field's component over the column's coefficient (on the axis the
                    // m = 1 column is U = −V).
                    let (i, c) = (j / 3, j % 3);
                    d[*col] = match (m, c) {
                        (0, 1) => x[i][0],
                        (1, 0) => 1.0,
                        (1, 1) => -1.0,
                        _ => 0.0,
                    } / coefficient;
                }
            }
            let residual = (&k * &d).norm() / (k.amax() * d.norm());
            assert!(residual < 1e-8, "m = {m}: |K d| = {residual}");
            let smallest = |a: &DMatrix<f64>| {
                let e = ((a + a.transpose()) * 0.5).symmetric_eigenvalues();
                e.iter().fold(f64::INFINITY, |s, v| s.min(v.abs())) / a.amax()
            };
            assert!(smallest(&k) < 1e-8, "m = {m}: the bare block is singular");
            assert!(
                smallest(&full) > 1e-7,
                "m = {m}: the bordered block is regular"
            );
        }
    }
}
