//! A rigid frictionless plane normal to the axis on the meridian (docs/theory.md §15.11), the
//! 3-D plane effect ([`crate::effects::plane`]) for a membrane of revolution.
//!
//! The plane n_z z ≥ d (n_z = ±1, the normal ±e_z pointing to the allowed side) acts on
//! every node of the meridian — a ring of the surface — through the node-wise penalty of the
//! 3-D effect, with the gap δ_i = n_z z_i − d:
//!
//! ```text
//!   Π_c = Σ_i κ/(q+1) ⟨−δ_i⟩^(q+1),   ∂Π_c/∂z_i = −κ ⟨−δ_i⟩^q n_z,
//!   ∂²Π_c/∂z_i² = κ q ⟨−δ_i⟩^(q−1),   ∂²Π_c/∂z_i∂d = −κ q ⟨−δ_i⟩^(q−1) n_z,
//!   ∂²Π_c/∂z_i∂κ = −⟨−δ_i⟩^q n_z,
//! ```
//!
//! q = 1 or 3. The ring's potential is the mean over θ of the node's, (1/2π) ∫ Π_c(δ(θ)) dθ
//! per unit 2π, so that the block of wave number m carries κ q ⟨−δ_i⟩^(q−1) times
//! (1/2π) ∫ cos² mθ dθ · 2π on the node's W: the full value for m = 0 (the tangent's) and
//! half of it for m ≥ 1, as the θ integrals of the other blocks (π for m ≥ 1, 2π for m = 0)
//! are normalised. A node-wise penalty is a mesh-level enforcement of the contact, not a
//! continuum load: with a stiff penalty both discretisations approach the hard contact.

use crate::effects::Quantity;

/// The plane n_z z ≥ d on the meridian.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FloorPlane {
    /// n_z = +1 (the allowed side above) or −1 (below).
    pub normal_z: f64,
    /// Offset d.
    pub offset: Quantity,
    /// Penalty κ.
    pub penalty: Quantity,
    /// Exponent q (1 or 3).
    pub exponent: u32,
}

/// A node's contribution: Π, ∂Π/∂z, ∂²Π/∂z² and ∂²Π/∂z∂λ_j per parameter.
pub(super) struct NodeContact {
    pub energy: f64,
    pub gradient: f64,
    pub stiffness: f64,
    pub loads: Vec<f64>,
}

impl FloorPlane {
    /// The penalty at a node of height z.
    pub(super) fn at(&self, z: f64, params: &[f64]) -> NodeContact {
        let (d, kappa) = (self.offset.value(params), self.penalty.value(params));
        let q = self.exponent as i32;
        let pen = (d - self.normal_z * z).max(0.0);
        let mut loads = vec![0.0; params.len()];
        if pen > 0.0 {
            if let Some(j) = self.offset.parameter() {
                loads[j] += -kappa * f64::from(q) * pen.powi(q - 1) * self.normal_z;
            }
            if let Some(j) = self.penalty.parameter() {
                loads[j] += -pen.powi(q) * self.normal_z;
            }
        }
        NodeContact {
            energy: kappa / f64::from(q + 1) * pen.powi(q + 1),
            gradient: -kappa * pen.powi(q) * self.normal_z,
            stiffness: if pen > 0.0 {
                kappa * f64::from(q) * pen.powi(q - 1)
            } else {
                0.0
            },
            loads,
        }
    }

    /// The factor of the node's stiffness in the block of wave number m.
    pub(super) fn block_factor(m: usize) -> f64 {
        if m == 0 {
            1.0
        } else {
            0.5
        }
    }
}
