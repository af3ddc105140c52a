//! Fluid spinning about z on the meridian (docs/theory.md §15.8), the 3-D spin effect's
//! potential ([`crate::effects::spin`]) for a membrane of revolution.
//!
//! In the frame rotating at ω, the fluid filling the region V behind the membrane (the side
//! n = x_ξ × x_θ points away from, as the 3-D effect takes it) has the potential
//!
//! ```text
//!   Π_ω = −(ρ ω²/2) ∫_V r² dV = (π/4) ρ ω² ∫ r⁴ z_ξ dξ,
//! ```
//!
//! by the divergence theorem with the field F = (r³/4) e_r (div F = (1/r) ∂(r F_r)/∂r = r²):
//! ∫_V r² dV = ∮ F·n dA, n dA·e_r = −r z_ξ dξ dθ, and F·n = 0 on a horizontal disc that
//! closes an open meridian at its rim (so V is the region between the membrane and its rim
//! plane, as for the gas). Its first variation is −∫ p n·δx dA with the centrifugal pressure
//! p = ρ ω² r²/2: a pressure that depends on r, which the p(z) potentials of the model cannot
//! hold. On one Gauss point (weight w, shape functions N_k) with k = (π/4) w ρ ω²:
//!
//! ```text
//!   Π = k r⁴ z_ξ,   ∂Π/∂r_k = 4 k r³ z_ξ N_k,   ∂Π/∂z_k = k r⁴ N_k',
//!   ∂²Π/∂r_k∂r_l = 12 k r² z_ξ N_k N_l,   ∂²Π/∂r_k∂z_l = 4 k r³ N_k N_l',   ∂²Π/∂z_k∂z_l = 0.
//! ```
//!
//! The parameter loads are the same gradient with ρ ω² replaced by its derivative along the
//! parameter (ω² for ρ, ρ for ω²).

use nalgebra::SMatrix;

/// One Gauss point of the spin potential with coefficient `k` = (π/4) w ρ ω² at radius `r`
/// and z_ξ = `dz`, shape functions `n` and their derivatives `dn`: adds Π to `energy`, its
/// gradient over the element's (r, z) per node to `gradient` and, when given, its Hessian to
/// `tangent`.
#[allow(clippy::too_many_arguments)]
pub(super) fn add_point(
    k: f64,
    r: f64,
    dz: f64,
    n: &[f64; 3],
    dn: &[f64; 3],
    energy: &mut f64,
    gradient: &mut [f64; 6],
    tangent: Option<&mut SMatrix<f64, 6, 6>>,
) {
    let (r2, r3) = (r * r, r * r * r);
    *energy += k * r2 * r2 * dz;
    for a in 0..3 {
        gradient[2 * a] += 4.0 * k * r3 * dz * n[a];
        gradient[2 * a + 1] += k * r2 * r2 * dn[a];
    }
    if let Some(t) = tangent {
        for a in 0..3 {
            for b in 0..3 {
                t[(2 * a, 2 * b)] += 12.0 * k * r2 * dz * n[a] * n[b];
                let rz = 4.0 * k * r3 * n[a] * dn[b];
                t[(2 * a, 2 * b + 1)] += rz;
                t[(2 * b + 1, 2 * a)] += rz;
            }
        }
    }
}
