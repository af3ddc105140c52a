//! What a run found, in plain data: the path with its parameters and measures, the turning
//! points, why it stopped, and the states saved for visualisation. Writers (see
//! [`crate::output`]) turn it into CSV, JSON, VTU + PVD and an SVG diagram.

use crate::analysis::critical::{CriticalKind, CriticalPoint};
use crate::analysis::events::{Extremum, StopReason};
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
    /// The negative count of every irrep block, in the order of [`PathReport::irreps`]
    /// (its index part: `index` = Σ_μ d_μ `negative[μ]`), when stability was analysed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub negative: Option<Vec<usize>>,
}

/// A turning point of the control parameter (a fold of the path in the control).
#[derive(Debug, Clone, Serialize)]
pub struct TurningRow {
    /// `maximum` or `minimum` of the control.
    pub kind: Extremum,
    /// The path step just before it (`step` in the outputs).
    #[serde(rename = "step")]
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
    /// The irrep blocks of the rows' `negative` counts (`path.csv`'s `index_<irrep>`
    /// columns); empty when no row has them.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub irreps: Vec<String>,
    /// Turning points of the control.
    pub turning_points: Vec<TurningRow>,
    /// Why the path ended (written in words).
    pub stop: StopReason,
    /// Critical points, localised and classified by irrep.
    pub critical: Vec<CriticalPoint>,
    /// Things the analysis could not settle (a crossing that could not be localised …).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// Why stability was not analysed, if it was not.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stability_note: Option<String>,
    /// States written as VTU files.
    pub saved: Vec<SavedState>,
    /// The lowest eigenvalue of every irrep block at every sample of a linear-buckling sweep
    /// (empty, and left out of `path.json`, for the other analyses).
    #[serde(skip_serializing_if = "Spectra::is_empty")]
    pub spectra: Spectra,
    /// The file with every point's state (`path.states`), once written.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub states: Option<StatesInfo>,
    /// Where the membrane would wrinkle along the path (left out when the model shows no
    /// `wrinkled` field or no point's state was kept).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wrinkling: Option<Wrinkling>,
    /// The wave number m about z of each critical mode (one per critical point), where the
    /// mesh has an axis (a disc, a truncated sphere; empty otherwise). Written into
    /// `critical.json` as each point's `m`.
    #[serde(skip)]
    pub wave_numbers: Vec<usize>,
}

/// Where the membrane model stops being valid along a path: the triangles whose smaller
/// principal tension is negative (they would wrinkle; the membrane energy does not describe
/// them).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Wrinkling {
    /// The mesh's triangles.
    pub triangles: usize,
    /// The first path point with any wrinkled triangle (`None`: nowhere on the path).
    pub first: Option<WrinkledPoint>,
    /// The critical points that lie in a wrinkled state (numbered from 1, as
    /// `critical_NN.vtu`).
    pub critical: Vec<WrinkledCritical>,
}

impl Wrinkling {
    /// A warning for every critical point of `critical` (the report's, numbered from 1) that
    /// lies in a wrinkled state: `critical point 2 (simple bifurcation in E1) lies in a
    /// wrinkled state (12 of 320 triangles): the membrane model does not describe it there`.
    pub fn warnings(&self, critical: &[CriticalPoint]) -> Vec<String> {
        self.critical
            .iter()
            .filter_map(|c| {
                let cp = critical.get(c.critical.checked_sub(1)?)?;
                Some(format!(
                    "critical point {} ({} in {}) lies in a wrinkled state ({} of {} \
                     triangles): the membrane model does not describe it there",
                    c.critical, cp.kind, cp.irrep, c.wrinkled, self.triangles
                ))
            })
            .collect()
    }
}

/// A path point with wrinkled triangles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct WrinkledPoint {
    /// The path step (the row `step` of `path.csv`).
    pub step: usize,
    /// How many triangles are wrinkled there.
    pub wrinkled: usize,
}

/// A critical point in a wrinkled state.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct WrinkledCritical {
    /// The critical point's number (1-based, as `critical_NN.vtu`).
    pub critical: usize,
    /// How many triangles are wrinkled there.
    pub wrinkled: usize,
}

/// What `path.json` records of the file of every point's state (see `output::store`).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct StatesInfo {
    /// The file name, relative to the output directory.
    pub file: String,
    /// Unknowns N per state.
    pub unknowns: usize,
    /// Parameters P per state.
    pub parameters: usize,
    /// Points M (point k is the row `step = k`).
    pub points: usize,
}

/// One path point's state, compactly: every parameter and the coordinates q of u in the
/// fixed-point basis the path was solved in (u = B q).
#[derive(Debug, Clone, PartialEq)]
pub struct PointState {
    /// Every parameter (scene order).
    pub parameters: Vec<f64>,
    /// q.
    pub q: Vec<f64>,
}

impl PathReport {
    /// The smallest and largest instability index of the rows, `None` where no row has one.
    pub fn index_range(&self) -> Option<(usize, usize)> {
        let mut indices = self.rows.iter().filter_map(|r| r.index);
        let first = indices.next()?;
        Some(indices.fold((first, first), |(lo, hi), i| (lo.min(i), hi.max(i))))
    }
}

/// An irrep block as listed in [`Spectra`].
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct SpectrumIrrep {
    /// Irrep name (`A1`, `E2`, `T1u` …).
    pub name: String,
    /// Its dimension d (every eigenvalue of the block is d-fold in K).
    pub dim: usize,
    /// Block size m (columns of one partner).
    pub size: usize,
    /// Whether the block's eigenvalues are computed (at any sample); an empty block, or one
    /// whose eigenvalues could not be computed, has its negative count only and `lowest`
    /// `null` throughout.
    pub eigenvalues: bool,
}

/// The most eigenvalues per block a [`SpectrumRow`] keeps.
pub const SPECTRUM_EIGENVALUES: usize = 6;

/// The spectra of one sample: per irrep (in the order of [`Spectra::irreps`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SpectrumRow {
    /// The path row (sample) this belongs to.
    pub step: usize,
    /// The control's value there.
    pub control: f64,
    /// max |K_ij| of the tangent there, the unit of `lowest`.
    pub scale: f64,
    /// The block's lowest eigenvalue over `scale` (λ/‖K‖, rigid modes excluded), or `None`
    /// where it was not computed (a large block, or no spectrum at this sample).
    pub lowest: Vec<Option<f64>>,
    /// Per block, its lowest eigenvalues over `scale`, ascending, as many as were computed up
    /// to [`SPECTRUM_EIGENVALUES`] (empty where none was): the first is `lowest`, the others
    /// are the higher eigenvalues that cross zero later in the sweep.
    pub eigenvalues: Vec<Vec<f64>>,
    /// The block's number of negative eigenvalues (`None` where no spectrum was computed).
    pub negative: Vec<Option<usize>>,
}

/// The lowest eigenvalue of every irrep block along a linear-buckling sweep: what `path.svg`
/// plots for that analysis, stored in `path.json` so that the two agree.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Spectra {
    /// The irrep blocks, the trivial first.
    pub irreps: Vec<SpectrumIrrep>,
    /// One per sample, matching [`PathReport::rows`] (all `None` where no spectrum was
    /// computed).
    pub rows: Vec<SpectrumRow>,
}

impl Spectra {
    /// True when no spectrum was recorded (every analysis but linear buckling, or a run whose
    /// stability was not analysed).
    pub fn is_empty(&self) -> bool {
        self.irreps.is_empty() || self.rows.is_empty()
    }

    /// The index of the irrep named `name`.
    pub fn irrep(&self, name: &str) -> Option<usize> {
        self.irreps.iter().position(|i| i.name == name)
    }
}

/// What a state to write is.
#[derive(Debug, Clone, PartialEq)]
pub enum StateKind {
    /// A point of the path (every `save-every` steps, and the last one).
    Step,
    /// A turning point of the control.
    Turning(Extremum),
    /// A critical point, written with its mode.
    Critical {
        /// Its kind.
        kind: CriticalKind,
        /// The irrep of the singular block.
        irrep: String,
    },
    /// The held state of a linear-buckling sweep.
    Held,
}

impl StateKind {
    /// The state's label: `step N`, `maximum`, `double bifurcation in E1`, `held state`.
    pub fn label(&self, step: usize) -> String {
        match self {
            Self::Step => format!("step {step}"),
            Self::Turning(e) => e.to_string(),
            Self::Critical { kind, irrep } => format!("{kind} in {irrep}"),
            Self::Held => "held state".into(),
        }
    }
}

/// A state to write: path step, what it is, control value, full displacement, and a mode
/// for critical points.
#[derive(Debug, Clone)]
pub struct State {
    /// Path step (turning and critical points carry the step before them).
    pub step: usize,
    /// What the state is.
    pub kind: StateKind,
    /// The control's value.
    pub control: f64,
    /// Displacement over the unknowns.
    pub u: Vec<f64>,
    /// Every parameter's value there.
    pub params: Vec<f64>,
    /// The critical mode over the unknowns, for critical points.
    pub mode: Option<Vec<f64>>,
}

impl State {
    /// The state's label (see [`StateKind::label`]).
    pub fn label(&self) -> String {
        self.kind.label(self.step)
    }
}

/// What happened along a critical curve.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CurveEventKind {
    /// The first point (the critical point found on the path).
    Start,
    /// A limit-point curve turns in the second parameter: two limit points merge.
    Cusp,
    /// A bifurcation curve turns in the second parameter.
    Fold,
    /// A limit-point curve meets a bifurcation curve (Paper 4's branching point): the
    /// trivial block and another block are singular together.
    Hilltop,
    /// Two bifurcation curves of different irreps cross: on one side of the point the path
    /// in the control meets the curve's irrep first, on the other side the other irrep.
    IrrepChange,
    /// The last point.
    End,
}

impl std::fmt::Display for CurveEventKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Start => "start",
            Self::Cusp => "cusp",
            Self::Fold => "fold",
            Self::Hilltop => "hilltop",
            Self::IrrepChange => "irrep change",
            Self::End => "end",
        })
    }
}

impl Serialize for CurveEventKind {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

/// An event of a critical curve, with the point where it happened.
#[derive(Debug, Clone, Serialize)]
pub struct CurveEvent {
    /// What happened.
    pub kind: CurveEventKind,
    /// For a cusp or fold: whether the second parameter has a maximum or a minimum there.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub extremum: Option<Extremum>,
    /// For a hilltop or an irrep change: the other irrep whose block is singular there.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub irrep: Option<String>,
    /// For a hilltop or an irrep change: the other block's localised eigenvalue relative to
    /// max|K_ij|.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub residual_eigenvalue: Option<f64>,
    /// The curve step just before the event.
    #[serde(rename = "step")]
    pub after_step: usize,
    /// Every parameter there (the report's order).
    pub parameters: Vec<f64>,
    /// Every measure there.
    pub measures: Vec<f64>,
}

/// One point of a critical curve.
#[derive(Debug, Clone, Serialize)]
pub struct CurveRow {
    /// Index along the curve.
    pub step: usize,
    /// Arclength from the first point (scaled norm).
    pub arclength: f64,
    /// Every parameter.
    pub parameters: Vec<f64>,
    /// Every measure.
    pub measures: Vec<f64>,
    /// Newton iterations of the corrector.
    pub iterations: usize,
    /// The block's eigenvalue nearest zero, relative to max|K_ij| (zero on the curve).
    pub critical_eigenvalue: f64,
    /// The block's next eigenvalue in modulus, relative to max|K_ij|: how far the point is from
    /// a higher singularity in the same block.
    pub second_eigenvalue: f64,
}

/// A critical point followed in two parameters.
#[derive(Debug, Clone, Serialize)]
pub struct CurveReport {
    /// The parameter of the path that found the point.
    pub control: String,
    /// The other free parameter.
    pub second: String,
    /// The irrep whose block is singular along the curve.
    pub irrep: String,
    /// The kind of critical point (limit point, double bifurcation …).
    pub kind: CriticalKind,
    /// The multiplicity of the zero eigenvalue in K (the irrep's dimension).
    pub multiplicity: usize,
    /// Parameter names (scene order).
    pub parameters: Vec<String>,
    /// Measure names.
    pub measures: Vec<String>,
    /// The curve's points.
    pub rows: Vec<CurveRow>,
    /// Its events, the start first and the end last.
    pub events: Vec<CurveEvent>,
    /// Why the curve ended.
    pub stop: StopReason,
    /// What went wrong along the curve without stopping it (an event that could not be
    /// localised, a border that could not be refreshed).
    pub warnings: Vec<String>,
}

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

#[cfg(test)]
mod tests {
    use super::*;

    fn row(step: usize, index: Option<usize>) -> PathRow {
        PathRow {
            step,
            arclength: step as f64,
            parameters: vec![],
            measures: vec![],
            iterations: 1,
            index,
            negative: None,
        }
    }

    #[test]
    fn the_index_range_covers_every_row() {
        let mut r = PathReport {
            scene: String::new(),
            origin: String::new(),
            version: String::new(),
            mesh: MeshInfo {
                generator: String::new(),
                nodes: 0,
                elements: 0,
                group: String::new(),
                order: 1,
            },
            group: String::new(),
            group_order: 1,
            unknowns: 0,
            symmetric_unknowns: 0,
            control: String::new(),
            parameters: vec![],
            measures: vec![],
            rows: vec![row(0, Some(0)), row(1, Some(1)), row(2, Some(1))],
            turning_points: vec![],
            stop: StopReason::Condition,
            critical: vec![],
            warnings: vec![],
            stability_note: None,
            saved: vec![],
            spectra: Spectra::default(),
            states: None,
            wrinkling: None,
            wave_numbers: Vec::new(),
            irreps: Vec::new(),
        };
        assert_eq!(r.index_range(), Some((0, 1)));
        r.rows = vec![row(0, Some(2)), row(1, None), row(2, Some(2))];
        assert_eq!(r.index_range(), Some((2, 2)));
        r.rows = vec![row(0, None)];
        assert_eq!(r.index_range(), None);
    }
}
