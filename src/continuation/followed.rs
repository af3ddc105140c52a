//! A problem as the analyses follow it: the driver's [`Problem`] in its own coordinates q,
//! the states (u, every parameter) its points stand for, and the way back from a state —
//! what a model hands the analyses (a 3-D mesh's fixed-point space, a meridian).

use super::events::States;
use super::Problem;
use crate::model::ModelError;
use nalgebra::DVector;

/// A problem of a study in its own coordinates q, as the driver follows it: the states
/// (u, every parameter) its points stand for, and the way back from a state.
pub trait Followed: Problem + States {
    /// The coordinates q of a state u.
    fn coordinates(&self, u: &[f64]) -> DVector<f64>;
    /// The free parameters' values among every parameter's.
    fn free_values(&self, params: &[f64]) -> DVector<f64>;
    /// The parameter index of every free parameter, in the order of λ.
    fn free_indices(&self) -> Vec<usize>;
    /// Releases the neutral motions held at the start (the start's).
    fn release_held(&mut self) {}
    /// The force that holds the neutral motions at (q, λ), relative to the residual's scale
    /// (docs/theory.md §7.9); `None` when nothing is held.
    fn held_force(
        &mut self,
        _q: &DVector<f64>,
        _lambda: &DVector<f64>,
        _state_scale: f64,
        _parameter_scale: f64,
    ) -> Option<Result<f64, ModelError>> {
        None
    }
}

impl<P: Followed + ?Sized> Followed for Box<P> {
    fn coordinates(&self, u: &[f64]) -> DVector<f64> {
        (**self).coordinates(u)
    }
    fn free_values(&self, params: &[f64]) -> DVector<f64> {
        (**self).free_values(params)
    }
    fn free_indices(&self) -> Vec<usize> {
        (**self).free_indices()
    }
    fn release_held(&mut self) {
        (**self).release_held()
    }
    fn held_force(
        &mut self,
        q: &DVector<f64>,
        lambda: &DVector<f64>,
        state_scale: f64,
        parameter_scale: f64,
    ) -> Option<Result<f64, ModelError>> {
        (**self).held_force(q, lambda, state_scale, parameter_scale)
    }
}
