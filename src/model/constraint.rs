//! Augmenting equations g(u, Λ) = 0 that free one parameter each (docs/theory.md §7.1): the
//! trait the path follower and the stability analysis see, and the scatter of per-triangle
//! gradients the implementations share. The constraints themselves live with their effects
//! (a fixed fluid volume with the fluid, a fixed amount of gas with the gas).
//!
//! Each returns g, ∂g/∂u (over the unknowns) and ∂g/∂Λ (over all parameters).

use super::{Layout, Vec3};

/// g, ∂g/∂u and ∂g/∂Λ at a state.
#[derive(Debug, Clone, PartialEq)]
pub struct ConstraintValue {
    /// g.
    pub value: f64,
    /// ∂g/∂u.
    pub grad_u: Vec<f64>,
    /// ∂g/∂Λ_j for every parameter.
    pub grad_params: Vec<f64>,
}

/// An augmenting equation.
pub trait Constraint: Send + Sync {
    /// A short name, e.g. `fluid-volume`.
    fn name(&self) -> &str;
    /// The parameter it frees.
    fn frees(&self) -> usize;
    /// The measured quantity (g + target) at a state, to set `target` from a start state.
    fn measure(&self, layout: &Layout, x: &[Vec3], params: &[f64]) -> f64;
    /// The target value.
    fn target(&self) -> f64;
    /// Sets the target value.
    fn set_target(&mut self, target: f64);
    /// g and its derivatives.
    fn evaluate(&self, layout: &Layout, x: &[Vec3], params: &[f64]) -> ConstraintValue;
}

/// Scatters per-triangle gradients `grad(t, x_t)` into a vector over the unknowns, and adds
/// the quantity's rate along the layout's held motion to `grad_params` at its parameter
/// (docs/theory.md §2.8): held coordinates that move with Λ_p move g with them.
pub fn gather(
    layout: &Layout,
    x: &[Vec3],
    grad_params: &mut [f64],
    grad: impl Fn(usize, &[Vec3; 3]) -> [f64; 9],
) -> Vec<f64> {
    let g = layout.gather(x, grad);
    if let Some(p) = layout.held_parameter() {
        grad_params[p] += g.along_held;
    }
    g.unknowns
}
