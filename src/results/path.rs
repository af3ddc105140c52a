//! What a path run found, in plain data: the path with its parameters and measures, the
//! turning points, why it stopped, and the states saved for visualisation.

use super::{CriticalPoint, Extremum, Spectra, StopReason};
use serde::Serialize;

/// The mesh a run used.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
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
    /// The largest distance of a node from the centroid of the mesh's surface (its triangles'
    /// centroids weighted by their areas), in the mesh's coordinates (a 3-D mesh's; the
    /// length a figure of a mesh read from a file is scaled by).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f64>,
}

impl MeshInfo {
    /// The largest distance of one of `nodes` from the centroid of the surface of
    /// `triangles` (each triangle's centroid weighted by its area: on an irregular mesh of a
    /// disc or sphere the centre up to the discretisation, where the nodes' mean is off by
    /// their uneven spacing); `None` without triangles or area.
    pub fn radius_of(nodes: &[[f64; 3]], triangles: &[[usize; 3]]) -> Option<f64> {
        let (mut c, mut total) = ([0.0; 3], 0.0);
        for t in triangles {
            let [a, b, d] = t.map(|i| nodes[i]);
            let (u, v) = (
                [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
                [d[0] - a[0], d[1] - a[1], d[2] - a[2]],
            );
            let area = 0.5
                * (u[1] * v[2] - u[2] * v[1])
                    .hypot(u[2] * v[0] - u[0] * v[2])
                    .hypot(u[0] * v[1] - u[1] * v[0]);
            for k in 0..3 {
                c[k] += area * (a[k] + b[k] + d[k]) / 3.0;
            }
            total += area;
        }
        if total.is_nan() || total <= 0.0 {
            return None;
        }
        let c = c.map(|x| x / total);
        let r = nodes
            .iter()
            .map(|p| ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2)).sqrt())
            .fold(0.0, f64::max);
        r.is_finite().then_some(r)
    }

    /// `disc, 1792 triangles, group C7v` (a meridian's `axisymmetric, 64 elements, group
    /// O(2)`): the mesh as a figure's caption names it.
    pub fn describe(&self) -> String {
        let unit = if self.generator == "axisymmetric" {
            "elements"
        } else {
            "triangles"
        };
        format!(
            "{}, {} {unit}, group {}",
            self.generator, self.elements, self.group
        )
    }
}

/// One converged point of the path.
#[derive(Debug, Clone, Serialize, serde::Deserialize)]
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
    /// Where the control turns at a corner of the path, a change of the model's switches
    /// (docs/theory.md §8.9): the states either side of it, the point the one at the extreme
    /// control (`None` for a smooth turning point, a zero of the control's tangent).
    #[serde(skip)]
    pub corner: Option<super::Bracket>,
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
    /// The critical and turning points on refined meshes (`memstab run --refine`), written
    /// into `refine.json`; a point without a counterpart there is flagged not mesh-converged
    /// ([`PathReport::flags`]).
    #[serde(skip)]
    pub refinement: Option<super::refine::Refinement>,
    /// What the study measured of every row's, turning and critical point's state for their
    /// validity (the `stretch` and `contact-jump` flags, `path.csv`'s `flags`); `None` where
    /// it measured nothing.
    #[serde(skip)]
    pub checks: Option<super::validity::Checks>,
}

/// Where the membrane model stops being valid along a path: the triangles whose smaller
/// principal tension is negative (they would wrinkle; the membrane energy does not describe
/// them).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Wrinkling {
    /// The mesh's triangles.
    pub triangles: usize,
    /// The first path point with any wrinkled triangle (`None`: nowhere on the path).
    pub first: Option<WrinkledPoint>,
    /// The critical points that lie in a wrinkled state (numbered from 1, as
    /// `critical_NN.vtu`).
    pub critical: Vec<WrinkledCritical>,
    /// True when the membrane has the relaxed (tension-field) energy: the wrinkled
    /// triangles are those not taut, which that energy describes (left out when false).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub relaxed: bool,
    /// The relaxed energy's switching width δ (docs/theory.md §2.9; left out when 0).
    #[serde(skip_serializing_if = "is_zero")]
    pub width: f64,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

impl Wrinkling {
    /// A warning for every critical point of `critical` (the report's, numbered from 1) that
    /// lies in a wrinkled state: `critical point 2 (simple bifurcation in E1) lies in a
    /// wrinkled state (12 of 320 triangles): the membrane model does not describe it there`.
    /// None with the relaxed energy, which holds wrinkled states.
    pub fn warnings(&self, critical: &[CriticalPoint]) -> Vec<String> {
        if self.relaxed {
            return Vec::new();
        }
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
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct WrinkledCritical {
    /// The critical point's number (1-based, as `critical_NN.vtu`).
    pub critical: usize,
    /// How many triangles are wrinkled there.
    pub wrinkled: usize,
    /// The critical mode's share in the wrinkled region: Σ |φ_n|² over the nodes of the
    /// wrinkled triangles over Σ |φ_n|² (near 1: the instability is the wrinkles' own; 0 for
    /// a point without its mode).
    pub mode: f64,
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
    fn a_mesh_radius_is_taken_about_the_centroid_of_its_surface() {
        // The square [-1, 1]² with three extra nodes on its right edge: the nodes' mean lies
        // at x = 3/7, the surface's centroid at the centre.
        let nodes = [
            [-1.0, -1.0, 0.0],
            [1.0, -1.0, 0.0],
            [1.0, 1.0, 0.0],
            [-1.0, 1.0, 0.0],
            [1.0, -0.5, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 0.5, 0.0],
        ];
        let triangles = [[0, 1, 4], [0, 4, 5], [0, 5, 6], [0, 6, 2], [0, 2, 3]];
        let r = MeshInfo::radius_of(&nodes, &triangles).unwrap();
        assert!((r - 2f64.sqrt()).abs() < 1e-12, "{r}");
        assert_eq!(MeshInfo::radius_of(&nodes, &[]), None);
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
                radius: None,
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
            refinement: None,
            checks: None,
        };
        assert_eq!(r.index_range(), Some((0, 1)));
        r.rows = vec![row(0, Some(2)), row(1, None), row(2, Some(2))];
        assert_eq!(r.index_range(), Some((2, 2)));
        r.rows = vec![row(0, None)];
        assert_eq!(r.index_range(), None);
    }
}
