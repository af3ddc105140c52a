//! The equilibrium manifold in two parameters: a family of paths stitched into triangles,
//! with its critical lines.

use super::{CriticalKind, CriticalPoint, StopReason};
use serde::Serialize;

/// One vertex of an equilibrium surface: a point of one of its paths.
#[derive(Debug, Clone, Serialize)]
pub struct SurfaceVertex {
    /// The path step.
    pub step: usize,
    /// Arclength along its path (scaled norm).
    pub arclength: f64,
    /// Every parameter (the report's order).
    pub parameters: Vec<f64>,
    /// Every measure.
    pub measures: Vec<f64>,
    /// The instability index (negative eigenvalues over all blocks), where it was computed.
    pub index: Option<usize>,
}

/// One path of an equilibrium surface: the path in `a` at one value of `b`.
#[derive(Debug, Clone, Serialize)]
pub struct SurfacePath {
    /// The value of `b`.
    pub b: f64,
    /// The number of its first vertex in the surface's numbering (the paths' vertices in
    /// order, path after path).
    pub first_vertex: usize,
    /// Its points.
    pub vertices: Vec<SurfaceVertex>,
    /// The critical points localised on it, in path order.
    pub critical: Vec<CriticalPoint>,
    /// Why it ended.
    pub stop: StopReason,
}

/// A point of a critical line: a critical point of one path.
#[derive(Debug, Clone, Serialize)]
pub struct CriticalLinePoint {
    /// The path (its number in [`SurfaceReport::paths`]).
    pub path: usize,
    /// The critical point's number among the path's critical points.
    pub critical: usize,
    /// Every parameter there.
    pub parameters: Vec<f64>,
    /// Every measure there.
    pub measures: Vec<f64>,
}

/// Critical points of neighbouring paths joined across `b`: the same kind in the same irrep,
/// the same in order among that path's points of that kind and irrep. On a limit line the
/// surface folds over the (a, b) plane.
#[derive(Debug, Clone, Serialize)]
pub struct CriticalLine {
    /// The kind of its points.
    pub kind: CriticalKind,
    /// The irrep whose block is singular along it.
    pub irrep: String,
    /// Its points, one per path, in the order of `b`.
    pub points: Vec<CriticalLinePoint>,
}

/// The equilibrium manifold in two parameters, covered by paths in `a` at a grid of `b`.
#[derive(Debug, Clone, Serialize)]
pub struct SurfaceReport {
    /// The paths' parameter.
    pub a: String,
    /// The grid's parameter.
    pub b: String,
    /// The measure of the third coordinate.
    pub measure: String,
    /// Parameter names (scene order).
    pub parameters: Vec<String>,
    /// Measure names.
    pub measures: Vec<String>,
    /// The paths, in ascending `b`.
    pub paths: Vec<SurfacePath>,
    /// Triangles between neighbouring paths, by vertex number.
    pub triangles: Vec<[usize; 3]>,
    /// The critical lines.
    pub lines: Vec<CriticalLine>,
    /// What went wrong on the way without stopping the surface.
    pub warnings: Vec<String>,
}

impl SurfaceReport {
    /// Every vertex, path after path (the numbering of the triangles).
    pub fn vertices(&self) -> impl Iterator<Item = &SurfaceVertex> {
        self.paths.iter().flat_map(|p| &p.vertices)
    }

    /// The number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.paths.iter().map(|p| p.vertices.len()).sum()
    }

    /// The column of a parameter by name.
    pub fn parameter(&self, name: &str) -> Option<usize> {
        self.parameters.iter().position(|p| p == name)
    }

    /// The column of the chosen measure.
    pub fn measure_column(&self) -> Option<usize> {
        self.measures.iter().position(|m| *m == self.measure)
    }
}
