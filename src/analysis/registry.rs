//! The one place that maps a scene's `[analysis]` to the analysis that runs it: a new
//! analysis is its keys (a file of `src/scene/analyses/`, one line of its registry) and its
//! run (a file here implementing [`Analysis`], and one line below).

use super::{buckling, curve, equilibrium, path, surface, Analysis};
use crate::scene::{self, Analysis as Spec};

/// The analysis of the scene's `[analysis]`.
pub fn analysis(spec: &Spec) -> Box<dyn Analysis> {
    None.or_else(|| of(spec, path::Path))
        .or_else(|| of(spec, equilibrium::Equilibrium))
        .or_else(|| of(spec, buckling::Buckling))
        .or_else(|| of(spec, curve::Curve))
        .or_else(|| of(spec, surface::Surface))
        .unwrap_or_else(|| unreachable!("no analysis runs `type = \"{}\"`", spec.kind()))
}

/// `make` of the keys, if `spec` is of type `S`.
fn of<S: Clone + 'static, A: Analysis + 'static>(
    spec: &Spec,
    make: fn(S) -> A,
) -> Option<Box<dyn Analysis>> {
    spec.get::<S>()
        .map(|s| Box::new(make(s.clone())) as Box<dyn Analysis>)
}

/// The path analysis of the scene's `[analysis]`, if it is one (branches leave the critical
/// points of a path).
pub fn path(spec: &Spec) -> Option<path::Path> {
    spec.get::<scene::PathAnalysis>().cloned().map(path::Path)
}
