//! The one place that maps a scene's `[analysis]` to the analysis that runs it. A new analysis
//! is a file of its own (its spec in the scene, its [`Analysis`] here) and one line below.

use super::{buckling, curve, equilibrium, path, surface, Analysis};
use crate::scene;

/// The analysis of the scene's `[analysis]`.
pub fn analysis(spec: &scene::Analysis) -> Box<dyn Analysis> {
    match spec {
        scene::Analysis::Path(a) => Box::new(path::Path(a.clone())),
        scene::Analysis::Equilibrium(a) => Box::new(equilibrium::Equilibrium(a.clone())),
        scene::Analysis::LinearBuckling(a) => Box::new(buckling::Buckling(a.clone())),
        scene::Analysis::CriticalCurve(a) => Box::new(curve::Curve(a.clone())),
        scene::Analysis::Surface(a) => Box::new(surface::Surface(a.clone())),
    }
}

/// The path analysis of the scene's `[analysis]`, if it is one (branches leave the critical
/// points of a path).
pub fn path(spec: &scene::Analysis) -> Option<path::Path> {
    match spec {
        scene::Analysis::Path(a) => Some(path::Path(a.clone())),
        _ => None,
    }
}
