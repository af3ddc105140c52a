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

use super::Quantity;
use crate::model::{Assembler, Effect, ModelError, Placement, Vec3};
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
}
