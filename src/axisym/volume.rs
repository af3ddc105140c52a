//! The fluid-volume constraint on the meridian (docs/theory.md §15.10), the 3-D constraint
//! of docs/theory.md §4.4 and §8.3 for a completely filled membrane of revolution.
//!
//! The fluid fills the region behind the membrane, whose volume is V = −π ∫ r² z_ξ dξ (closed
//! at an open meridian's rim by the plane of the rim, as for the gas); holding it at V* frees
//! the head h. The augmented potential and the augmenting equation are
//!
//! ```text
//!   Π̂(q, h) = Π(q, h) + ρ g V* h,     ∂Π̂/∂h = −ρ g (V(q) − V*) = 0,
//! ```
//!
//! since ∂Π/∂h = π ρ g ∫ r² z_ξ dξ = −ρ g V for the filled fluid behind the membrane
//! (Π = π ∫ r² ρ g (h − z) z_ξ dξ). The row g = −ρ g (V − V*) then has ∂g/∂q = −ρ g ∇V, the
//! load ∂R/∂h: the border is symmetric, and ∂g/∂h = 0 (V of the filled region does not
//! depend on h), the hard constraint of §8.3 whose index is neg(K̃) − 1. On a Gauss point,
//!
//! ```text
//!   ∂V/∂r_k = −2π r z_ξ N_k,    ∂V/∂z_k = −π r² N_k′.
//! ```
//!
//! The volume's first variation along a field of wave number m ≥ 1 is ∫ n·δx dA with
//! n·δx ∝ cos mθ, whose θ integral vanishes: the constraint borders the block m = 0 only.

use super::{shape, AxisymModel, Pressure, GAUSS};
use std::f64::consts::PI;

impl AxisymModel {
    /// ∂V/∂(r_i, z_i) at every node of the nodes `x`.
    pub fn volume_gradient_nodes(&self, x: &[[f64; 2]]) -> Vec<[f64; 2]> {
        let mut g = vec![[0.0; 2]; x.len()];
        for e in 0..self.meridian.elements() {
            for p in volume_points(x, e) {
                for k in 0..3 {
                    g[2 * e + k][0] -= 2.0 * PI * p.r * p.dz * p.n[k] * p.w;
                    g[2 * e + k][1] -= PI * p.r * p.r * p.dn[k] * p.w;
                }
            }
        }
        g
    }

    /// ∂V/∂q over the free unknowns at displacement `q`.
    pub fn volume_gradient(&self, q: &[f64]) -> Vec<f64> {
        self.free_part(&self.volume_gradient_nodes(&self.positions(q)))
    }
}

/// The volume a fluid-volume constraint holds at a state: V_f, its gradient over the nodes
/// (r, z) and the section ∂V_f/∂h.
#[derive(Debug, Clone)]
pub struct HeldFluid {
    /// V_f.
    pub volume: f64,
    /// ∂V_f/∂(r_i, z_i) at every node.
    pub gradient: Vec<[f64; 2]>,
    /// ∂V_f/∂h, the area of the section at the level (0 for a filled enclosure).
    pub section: f64,
    /// ρ g of the fluid.
    pub weight: f64,
}

impl AxisymModel {
    /// The volume of fluid below the level `h` at the nodes `x`, V_f = −π ∫_wet r² z_ξ dξ
    /// (docs/theory.md §15.16), its gradient over the nodes and ∂V_f/∂h. The limits of the wet
    /// part move with the state: at a wetting line ξ* (z(ξ*) = h), ∂ξ*/∂z_l = −N_l/z_ξ and
    /// ∂ξ*/∂h = 1/z_ξ, which add π r² N_l sgn z_ξ to ∂V_f/∂z_l and −π r² sgn z_ξ to ∂V_f/∂h
    /// (+ at an upper limit of a wet part, where z rises through h).
    pub fn fluid_volume(&self, x: &[[f64; 2]], h: f64) -> (f64, Vec<[f64; 2]>, f64) {
        let mut v = 0.0;
        let mut g = vec![[0.0; 2]; x.len()];
        let mut section = 0.0;
        for e in 0..self.meridian.elements() {
            let zs = [x[2 * e][1], x[2 * e + 1][1], x[2 * e + 2][1]];
            let wet = super::wet_part(zs, h);
            for &(xi, w) in &wet.rule {
                let p = volume_point(x, e, xi, w);
                v -= PI * p.r * p.r * p.dz * p.w;
                for k in 0..3 {
                    g[2 * e + k][0] -= 2.0 * PI * p.r * p.dz * p.n[k] * p.w;
                    g[2 * e + k][1] -= PI * p.r * p.r * p.dn[k] * p.w;
                }
            }
            for &(xi, slope) in &wet.crossings {
                let p = volume_point(x, e, xi, 0.0);
                let c = PI * p.r * p.r * slope.signum();
                for k in 0..3 {
                    g[2 * e + k][1] += c * p.n[k];
                }
                section -= c;
            }
        }
        (v, g, section)
    }

    /// The fluid the fluid-volume constraint holds at the nodes `x` (the fluid whose level is
    /// the parameter [`Self::volume_level`]): below its level, or the whole enclosure for a
    /// filled one.
    pub fn held_fluid(&self, x: &[[f64; 2]], params: &[f64]) -> Option<HeldFluid> {
        let level = self.volume_level?;
        let (filled, weight) = self.pressures.iter().find_map(|p| match p {
            Pressure::Fluid {
                density,
                gravity,
                level: l,
                filled,
                ..
            } if l.parameter() == Some(level) => {
                Some((*filled, density.value(params) * gravity.value(params)))
            }
            _ => None,
        })?;
        let (volume, gradient, section) = if filled {
            (self.volume(x), self.volume_gradient_nodes(x), 0.0)
        } else {
            self.fluid_volume(x, params[level])
        };
        Some(HeldFluid {
            volume,
            gradient,
            section,
            weight,
        })
    }

    /// Node gradients over the free unknowns.
    pub fn free_part(&self, g: &[[f64; 2]]) -> Vec<f64> {
        (0..self.dim())
            .map(|k| {
                let (i, c) = self.free_unknown(k);
                g[i][c]
            })
            .collect()
    }
}

/// The point ξ (weight w) of element `e` of the nodes `x`.
fn volume_point(x: &[[f64; 2]], e: usize, xi: f64, w: f64) -> VolumePoint {
    let (n, dn) = shape(xi);
    let (mut r, mut dz) = (0.0, 0.0);
    for k in 0..3 {
        r += n[k] * x[2 * e + k][0];
        dz += dn[k] * x[2 * e + k][1];
    }
    VolumePoint { w, n, dn, r, dz }
}

/// A Gauss point of element `e` of the nodes `x`: its weight, the shape functions and their
/// derivatives, the radius r and z_ξ there (what V = −π ∫ r² z_ξ dξ and its gradient need).
pub(super) struct VolumePoint {
    pub w: f64,
    pub n: [f64; 3],
    pub dn: [f64; 3],
    pub r: f64,
    pub dz: f64,
}

/// The Gauss points of element `e` of the nodes `x`.
pub(super) fn volume_points(x: &[[f64; 2]], e: usize) -> impl Iterator<Item = VolumePoint> + '_ {
    GAUSS.iter().map(move |&(xi, w)| volume_point(x, e, xi, w))
}

#[cfg(test)]
mod tests {
    use super::super::model::tests::{generic_filled, generic_paper2};
    use super::super::perturbation;
    use super::*;

    /// ∇V against central differences of V.
    #[test]
    fn the_volume_gradient_matches_finite_differences() {
        let (model, q, _) = generic_filled();
        let g = model.volume_gradient(&q);
        let h = 1e-6;
        for k in 0..model.dim() {
            let (mut qp, mut qm) = (q.clone(), q.clone());
            qp[k] += h;
            qm[k] -= h;
            let d = (model.volume(&model.positions(&qp)) - model.volume(&model.positions(&qm)))
                / (2.0 * h);
            assert!(
                (d - g[k]).abs() < 1e-8 * (1.0 + d.abs()),
                "{k}: {d} vs {}",
                g[k]
            );
        }
        assert!(g.iter().any(|v| v.abs() > 0.1));
    }

    /// The volume of fluid below a level crossing an element: ∇V_f and ∂V_f/∂h against
    /// central differences of V_f, and ∇V_f is the level's load over −ρ g (docs/theory.md
    /// §4.4), the wetting line's terms included.
    #[test]
    fn the_fluid_volume_below_the_level_matches_finite_differences() {
        let (model, q, params) = generic_paper2();
        let h = params[3];
        let vf = |q: &[f64], h: f64| model.fluid_volume(&model.positions(q), h).0;
        let (v, g, section) = model.fluid_volume(&model.positions(&q), h);
        let g = model.free_part(&g);
        let total = model.volume(&model.positions(&q));
        assert!(v > 0.1 * total && v < 0.9 * total, "{v} of {total}");
        let d = 1e-6;
        for k in 0..model.dim() {
            let (mut qp, mut qm) = (q.clone(), q.clone());
            qp[k] += d;
            qm[k] -= d;
            let fd = (vf(&qp, h) - vf(&qm, h)) / (2.0 * d);
            assert!(
                (fd - g[k]).abs() < 1e-8 * (1.0 + fd.abs()),
                "{k}: {fd} vs {}",
                g[k]
            );
        }
        let fd = (vf(&q, h + d) - vf(&q, h - d)) / (2.0 * d);
        assert!((fd - section).abs() < 1e-8 * fd.abs(), "{fd} vs {section}");
        assert!(section > 0.1);
        // ∂R/∂h = −ρ g ∇V_f.
        let e = model.evaluate(&q, &params).unwrap();
        let weight = params[2] * 1.3;
        for (k, gk) in g.iter().enumerate() {
            let load = e.loads[(k, 3)];
            assert!(
                (load + weight * gk).abs() < 1e-10 * (1.0 + load.abs()),
                "{k}: {load} vs {}",
                -weight * gk
            );
        }
        let held = model.held_fluid(&model.positions(&q), &params).unwrap();
        assert_eq!(held.volume, v);
        assert!((held.weight - weight).abs() < 1e-15);
        // A filled fluid holds the whole enclosure.
        let (filled, qf, pf) = generic_filled();
        let xf = filled.positions(&qf);
        let held = filled.held_fluid(&xf, &pf).unwrap();
        assert_eq!((held.volume, held.section), (filled.volume(&xf), 0.0));
    }

    /// The volume's first variation ∫ n·δx dA, sampled in θ, is ∇V·(U, W) for m = 0 and
    /// vanishes for m ≥ 1: the constraint borders the block m = 0 only.
    #[test]
    fn the_volume_varies_with_the_axisymmetric_block_only() {
        let (model, q, _) = generic_filled();
        let x = model.positions(&q);
        let grad = model.volume_gradient_nodes(&x);
        // A generic field (U, V, W) per node.
        let n = x.len();
        // W = 0 at the sliding edge, where the end term −π [r² δz] of the integration by
        // parts would remain.
        let mut field: Vec<f64> = (0..3 * n).map(|k| ((k as f64) * 0.37).cos()).collect();
        field[3 * n - 1] = 0.0;
        for m in 0..4 {
            let nt = 2 * m + 4;
            let mut dv = 0.0;
            for e in 0..model.meridian.elements() {
                for p in super::super::points(&model.meridian, &x, e) {
                    let nda = p.x_xi.cross(&nalgebra::Vector3::new(0.0, p.r, 0.0));
                    for t in 0..nt {
                        let theta = 2.0 * PI * t as f64 / nt as f64;
                        let [dx, _, _] = perturbation(&p, m, theta, 0.0);
                        let local = nalgebra::SVector::<f64, 9>::from_fn(|i, _| field[6 * e + i]);
                        dv += nda.dot(&(dx * local)) * p.weight * 2.0 * PI / nt as f64;
                    }
                }
            }
            // δV = ∫ n·δx dA, n = x_ξ × x_θ pointing away from the enclosed region.
            let axisym: f64 = (0..n)
                .map(|i| grad[i][0] * field[3 * i] + grad[i][1] * field[3 * i + 2])
                .sum();
            if m == 0 {
                assert!(
                    (dv - axisym).abs() < 1e-10 * axisym.abs(),
                    "{dv} vs {axisym}"
                );
            } else {
                assert!(dv.abs() < 1e-12 * axisym.abs(), "m = {m}: {dv}");
            }
        }
    }
}
