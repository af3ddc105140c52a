//! A rigid frictionless plane with a penalty (docs/theory.md §6).
//!
//! The plane n·x ≥ d (unit normal n, offset d) acts on every node with the gap
//! δ_i = n·x_i − d:
//!
//! ```text
//!   Π_c = Σ_i κ/(q+1) ⟨−δ_i⟩^(q+1),    F_i = −κ ⟨−δ_i⟩^q n,
//!   K_ii = κ q ⟨−δ_i⟩^(q−1) n nᵀ,       ∂F_i/∂d = −κ q ⟨−δ_i⟩^(q−1) n,
//!   ∂F_i/∂κ = −⟨−δ_i⟩^q n
//! ```
//!
//! with q = 1 (force linear in the penetration; K jumps at first touch) or q = 3 (cubic:
//! C² at first touch, smoother fold lines). Only nodes are tested, so a coarse mesh can
//! press an edge through the plane; that is the usual node-to-surface penalty.

use super::spec::{self, Build, Built, EffectSpec, MeridianLoad, Natural, Range, Refusal, Scale};
use super::Quantity;
use crate::axisym::FloorPlane;
use crate::model::{Assembler, CellField, CellQuantity, Effect, ModelError, Placement, Vec3};
use crate::text::key_value;
use symmetry::Invariant;

/// The penalty exponent q.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PenaltyLaw {
    /// q = 1.
    Linear,
    /// q = 3.
    Cubic,
}

/// A rigid plane n·x ≥ d acting through a node-wise penalty.
#[derive(Debug, Clone)]
pub struct Plane {
    /// Unit normal n (pointing to the allowed side).
    pub normal: Vec3,
    /// Offset d (may be a parameter).
    pub offset: Quantity,
    /// Penalty stiffness κ > 0 (may be a parameter).
    pub penalty: Quantity,
    /// Linear or cubic.
    pub law: PenaltyLaw,
}

impl Effect for Plane {
    fn name(&self) -> &str {
        "plane"
    }

    /// The one-sided plane alone keeps its normal as a direction.
    fn keeps(&self) -> Vec<Invariant> {
        vec![Invariant::Direction(self.normal)]
    }

    /// An element R maps the half-space n·x ≥ d onto (R n)·x ≥ d: a plane with the same
    /// offset, penalty and law, normal R n.
    fn placement(&self) -> Option<Placement> {
        let (kind, value) = match self.offset {
            Quantity::Value(v) => (0.0, v),
            Quantity::Parameter(i) => (1.0, i as f64),
        };
        let (penalty_kind, penalty) = match self.penalty {
            Quantity::Value(v) => (0.0, v),
            Quantity::Parameter(i) => (1.0, i as f64),
        };
        let law = match self.law {
            PenaltyLaw::Linear => 1.0,
            PenaltyLaw::Cubic => 3.0,
        };
        Some(Placement {
            kind: "plane",
            normal: self.normal,
            key: vec![kind, value, penalty_kind, penalty, law],
        })
    }

    /// Translations within the plane and rotation about its normal (through the origin).
    fn rigid_motions(&self) -> Vec<[f64; 6]> {
        crate::model::in_plane_motions(self.normal.normalize())
    }

    fn assemble(
        &self,
        x: &[Vec3],
        params: &[f64],
        out: &mut Assembler<'_>,
    ) -> Result<(), ModelError> {
        let d = self.offset.value(params);
        let n = self.normal;
        let (kappa, q) = (
            self.penalty.value(params),
            match self.law {
                PenaltyLaw::Linear => 1,
                PenaltyLaw::Cubic => 3,
            },
        );
        out.add_nodes(
            x,
            [self.offset.parameter(), self.penalty.parameter()],
            |_, xi, terms| {
                let pen = d - n.dot(xi); // ⟨−δ⟩ before clipping
                if pen <= 0.0 {
                    return Ok(());
                }
                let pq1 = pen.powi(q - 1);
                let force = kappa * pq1 * pen; // κ ⟨−δ⟩^q
                let stiff = kappa * q as f64 * pq1; // κ q ⟨−δ⟩^(q−1)
                terms.value = force * pen / (q + 1) as f64;
                for a in 0..3 {
                    terms.grad[a] = -force * n[a];
                    terms.loads[0][a] = -stiff * n[a];
                    // The energy is linear in κ: ∂F/∂κ = F/κ = −⟨−δ⟩^q n.
                    terms.loads[1][a] = -pq1 * pen * n[a];
                    for b in 0..3 {
                        terms.hess[a][b] = stiff * n[a] * n[b];
                    }
                }
                Ok(())
            },
        )
    }

    /// ⟨−δ_i⟩ = max(d − n·x_i, 0) at every node.
    fn penetrations(&self, x: &[Vec3], params: &[f64]) -> Option<Vec<f64>> {
        let d = self.offset.value(params);
        Some(
            x.iter()
                .map(|xi| (d - self.normal.dot(xi)).max(0.0))
                .collect(),
        )
    }

    /// The contact pressure: each node's penalty force κ⟨−δ⟩^q over its tributary area (a
    /// third of its triangles' current areas), averaged over each triangle's nodes.
    fn cell_fields(&self, x: &[Vec3], triangles: &[[usize; 3]], params: &[f64]) -> Vec<CellField> {
        let d = self.offset.value(params);
        let kappa = self.penalty.value(params);
        let q = match self.law {
            PenaltyLaw::Linear => 1,
            PenaltyLaw::Cubic => 3,
        };
        let mut area = vec![0.0; x.len()];
        for &[a, b, c] in triangles {
            let t = (x[b] - x[a]).cross(&(x[c] - x[a])).norm() / 6.0;
            for i in [a, b, c] {
                area[i] += t;
            }
        }
        let pressure: Vec<f64> = x
            .iter()
            .zip(&area)
            .map(|(xi, &ai)| {
                let pen = d - self.normal.dot(xi);
                if pen > 0.0 && ai > 0.0 {
                    kappa * pen.powi(q) / ai
                } else {
                    0.0
                }
            })
            .collect();
        let values = triangles
            .iter()
            .map(|t| t.iter().map(|&i| pressure[i]).sum::<f64>() / 3.0)
            .collect();
        vec![CellField {
            quantity: CellQuantity::ContactPressure,
            values,
        }]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit square of two triangles at height z, and a plane z ≥ 0 with penalty κ.
    fn square(z: [f64; 4]) -> (Vec<Vec3>, Vec<[usize; 3]>) {
        let x = vec![
            Vec3::new(0.0, 0.0, z[0]),
            Vec3::new(1.0, 0.0, z[1]),
            Vec3::new(1.0, 1.0, z[2]),
            Vec3::new(0.0, 1.0, z[3]),
        ];
        (x, vec![[0, 1, 2], [0, 2, 3]])
    }

    fn plane(law: PenaltyLaw) -> Plane {
        Plane {
            normal: Vec3::z(),
            offset: Quantity::Value(0.0),
            penalty: Quantity::Value(50.0),
            law,
        }
    }

    #[test]
    fn the_contact_pressure_carries_the_penalty_forces_and_vanishes_off_contact() {
        for law in [PenaltyLaw::Linear, PenaltyLaw::Cubic] {
            let q = if law == PenaltyLaw::Linear { 1 } else { 3 };
            let p = plane(law);
            let (x, t) = square([-0.01, -0.02, 0.03, -0.005]);
            let f = p.cell_fields(&x, &t, &[]);
            assert_eq!(f.len(), 1);
            assert_eq!(f[0].quantity, CellQuantity::ContactPressure);
            // Σ_T A_T · mean of F_i/A_i over its nodes = Σ_i F_i: the pressure carries the
            // whole contact force.
            let area = |tri: &[usize; 3]| {
                let [a, b, c] = *tri;
                (x[b] - x[a]).cross(&(x[c] - x[a])).norm() / 2.0
            };
            let carried: f64 = t
                .iter()
                .zip(&f[0].values)
                .map(|(tri, v)| area(tri) * v)
                .sum();
            let force: f64 = x.iter().map(|xi| 50.0 * (-xi[2]).max(0.0).powi(q)).sum();
            assert!(
                (carried / force - 1.0).abs() < 1e-12,
                "{carried} vs {force}"
            );
            assert!(f[0].values.iter().all(|v| *v > 0.0));
            // Nothing touches: no pressure.
            let (x, t) = square([0.01, 0.02, 0.0, 0.5]);
            assert!(p.cell_fields(&x, &t, &[])[0]
                .values
                .iter()
                .all(|v| *v == 0.0));
        }
    }
}

/// `[[effect]] type = "plane"`: the half-space n·x ≥ d is allowed; node i penetrating by
/// δ = d − n·x_i > 0 costs κ/(q+1) δ^(q+1).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct PlaneEffect {
    /// Normal n (normalised on loading), pointing to the allowed side.
    pub normal: [f64; 3],
    /// Offset d: the plane is n·x = d.
    pub offset: spec::Quantity,
    /// Penalty κ > 0 (a number or a parameter).
    pub penalty: spec::Quantity,
    /// Exponent q: 1 (force linear in penetration) or 3 (cubic). Default 1.
    #[serde(default = "linear")]
    pub exponent: u32,
}

fn linear() -> u32 {
    1
}

impl EffectSpec for PlaneEffect {
    fn quantities(&self) -> Vec<(&'static str, &spec::Quantity, Range)> {
        vec![
            ("offset", &self.offset, Range::Finite),
            ("penalty", &self.penalty, Range::Positive),
        ]
    }
    /// A finite non-zero normal (made a unit vector) and an exponent of 1 or 3.
    fn check(&mut self) -> Result<(), Refusal> {
        let n = self.normal;
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        if !(len.is_finite() && len > 0.0) {
            return Err(Refusal::at(
                "normal",
                format!(
                    "must be a finite non-zero vector, got [{}, {}, {}]",
                    key_value(n[0]),
                    key_value(n[1]),
                    key_value(n[2])
                ),
            ));
        }
        self.normal = [n[0] / len, n[1] / len, n[2] / len];
        if self.exponent != 1 && self.exponent != 3 {
            return Err(Refusal::at(
                "exponent",
                format!("must be 1 or 3, got {}", self.exponent),
            ));
        }
        Ok(())
    }
    fn needs_enclosure(&self) -> bool {
        false
    }
    /// `d/a`.
    fn scales(&self, n: &Natural) -> Vec<Scale> {
        let (Some(d), Some(a)) = (self.offset.parameter(), n.length) else {
            return Vec::new();
        };
        let l = n.symbol;
        vec![Scale {
            parameter: d.to_string(),
            group: format!("d/{l}"),
            values: vec![(l.into(), a)],
            factor: 1.0 / a,
        }]
    }
    fn build(&self, cx: &Build) -> Built {
        Built {
            effect: Box::new(Plane {
                normal: Vec3::from(self.normal),
                offset: (cx.quantity)(&self.offset),
                penalty: (cx.quantity)(&self.penalty),
                law: if self.exponent == 3 {
                    PenaltyLaw::Cubic
                } else {
                    PenaltyLaw::Linear
                },
            }),
            measured: None,
        }
    }
    /// A plane normal to the axis only.
    fn meridian(&self, cx: &Build) -> Result<MeridianLoad, Refusal> {
        let n = self.normal;
        if n[0].hypot(n[1]) > 1e-12 {
            return Err(Refusal::at(
                "normal",
                format!(
                    "= {n:?}: the axisymmetric model takes a plane normal to the axis only (normal = [0, 0, ±1])"
                ),
            ));
        }
        Ok(MeridianLoad::Plane(FloorPlane {
            normal_z: n[2].signum(),
            offset: (cx.quantity)(&self.offset),
            penalty: (cx.quantity)(&self.penalty),
            exponent: self.exponent,
        }))
    }
}
