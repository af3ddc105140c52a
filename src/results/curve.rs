//! A critical point followed in two parameters: the curve's points and its events.

use super::{CriticalKind, Extremum, StopReason};
use serde::Serialize;

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
    /// For a hilltop or an irrep change: the wave number about z of the other block's mode,
    /// where the model has an axis (what names it alike on the 3-D mesh and the meridian).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub m: Option<usize>,
    /// For a hilltop or an irrep change: the other block's localised eigenvalue relative to
    /// max|K_ij|.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub residual_eigenvalue: Option<f64>,
    /// The curve step just before the event.
    #[serde(rename = "step")]
    pub after_step: usize,
    /// The arclength along the curve where it happened (scaled norm, as the rows').
    pub arclength: f64,
    /// Every parameter there (the report's order).
    pub parameters: Vec<f64>,
    /// Every measure there.
    pub measures: Vec<f64>,
    /// The flags of its state (docs/theory.md §8.10: `wrinkled` under the plain energy,
    /// `stretch`; for a hilltop or an irrep change also the other block's `not-localised`):
    /// empty where it is valid or the model does not measure it.
    pub flags: Vec<super::validity::Flag>,
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
