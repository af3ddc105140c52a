//! What a run found, in plain data: the path with its parameters and measures, the turning
//! points, why it stopped, and the states saved for visualisation. Writers (see
//! [`crate::output`]) turn it into CSV, JSON, VTU + PVD and an SVG diagram.

use serde::Serialize;

/// The mesh a run used.
#[derive(Debug, Clone, Serialize)]
pub struct MeshInfo {
    /// Generator name (`disc`, `icosphere`, `truncated-sphere`).
    pub generator: String,
    /// Number of nodes.
    pub nodes: usize,
    /// Number of triangles.
    pub elements: usize,
    /// The mesh's own symmetry group.
    pub group: String,
    /// Its order.
    pub order: usize,
}

/// One converged point of the path.
#[derive(Debug, Clone, Serialize)]
pub struct PathRow {
    /// Index along the path (0 = start).
    pub step: usize,
    /// Arclength from the start (scaled norm).
    pub arclength: f64,
    /// Every parameter's value, in the order of [`PathReport::parameters`].
    pub parameters: Vec<f64>,
    /// Every measure's value, in the order of [`PathReport::measures`].
    pub measures: Vec<f64>,
    /// Newton iterations of the corrector.
    pub iterations: usize,
    /// Instability index Σ_μ d_μ neg_μ (rigid modes excluded), when stability was analysed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub index: Option<usize>,
}

/// A turning point of the control parameter (a fold of the path in the control).
#[derive(Debug, Clone, Serialize)]
pub struct TurningRow {
    /// `maximum` or `minimum` of the control.
    pub kind: String,
    /// The path step just before it.
    pub after_step: usize,
    /// Parameters at the localised point.
    pub parameters: Vec<f64>,
    /// Measures at the localised point.
    pub measures: Vec<f64>,
}

/// A state written as a VTU file.
#[derive(Debug, Clone, Serialize)]
pub struct SavedState {
    /// Path step.
    pub step: usize,
    /// The control's value (the PVD "time").
    pub control: f64,
    /// File name relative to the output directory.
    pub file: String,
    /// What the state is: `step N`, `maximum`, `double bifurcation in E1` …
    pub label: String,
    /// True for the states of the path collection (`path.pvd`); turning and critical points
    /// are written beside it.
    pub in_collection: bool,
}

/// Everything a path run found.
#[derive(Debug, Clone, Serialize)]
pub struct PathReport {
    /// Scene name.
    pub scene: String,
    /// Where the scene came from (file path).
    pub origin: String,
    /// memstab's version.
    pub version: String,
    /// The mesh.
    pub mesh: MeshInfo,
    /// The group of the scene (the mesh group restricted to what every effect keeps).
    pub group: String,
    /// Its order.
    pub group_order: usize,
    /// Unknowns of the full model and of the fixed-point space the path was solved in.
    pub unknowns: usize,
    /// Dimension of the fixed-point space.
    pub symmetric_unknowns: usize,
    /// The control parameter.
    pub control: String,
    /// Parameter names (all of them, in scene order).
    pub parameters: Vec<String>,
    /// Measure names (e.g. `volume`, `stretch`, `max_displacement`).
    pub measures: Vec<String>,
    /// The path.
    pub rows: Vec<PathRow>,
    /// Turning points of the control.
    pub turning_points: Vec<TurningRow>,
    /// Why the path ended, in words.
    pub stop: String,
    /// Critical points, localised and classified by irrep.
    pub critical: Vec<crate::critical::CriticalPoint>,
    /// Things the analysis could not settle (a crossing that could not be localised …).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// Why stability was not analysed, if it was not.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stability_note: Option<String>,
    /// States written as VTU files.
    pub saved: Vec<SavedState>,
}
