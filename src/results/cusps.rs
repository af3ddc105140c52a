//! A cusp of a limit-point curve followed in a third parameter, slice by slice: the cusps of
//! each slice's critical curve, and where a pair of neighbouring cusps is born or dies.

use super::{CurveEvent, StopReason};
use serde::Serialize;

/// One slice: the critical curve in (control, second) at one value of the third parameter.
#[derive(Debug, Clone, Serialize)]
pub struct CuspSlice {
    /// The third parameter's value.
    pub third: f64,
    /// Added between two slices of the grid to narrow where a pair of cusps ends.
    pub refined: bool,
    /// The cusps of its curve, in curve order.
    pub cusps: Vec<CurveEvent>,
    /// Each cusp's arclength along the curve (that of the curve point just before it).
    pub arclengths: Vec<f64>,
    /// The fold line: (control, second) at every curve point.
    pub line: Vec<[f64; 2]>,
    /// The curve's largest step (smaller on a refined slice, to resolve a close pair).
    pub max_step: f64,
    /// Why its curve ended (none where the slice has no curve).
    pub stop: Option<StopReason>,
    /// Why the slice has no curve (its path found no point, or a solve failed); the slice
    /// is then left out of every count.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
}

/// What a pair of cusps ends in, from two independent signs (docs/theory.md §11.12).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum PairEndKind {
    /// The pair's distance in the parameters falls as the 3/2 power of its distance in the
    /// state, and the fold line crosses itself beside the pair: a swallowtail point.
    Swallowtail,
    /// The distance falls as the 1/2 power and the fold line does not cross itself: lips
    /// or beaks, where the cusp curve turns at an ordinary point of the cusp edge.
    LipsOrBeaks,
    /// The two signs disagree, or too few slices hold the pair to measure an order.
    Undecided,
}

impl std::fmt::Display for PairEndKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Swallowtail => "swallowtail",
            Self::LipsOrBeaks => "lips or beaks",
            Self::Undecided => "undecided",
        })
    }
}

/// Where a pair of neighbouring cusps (a maximum and a minimum of the second parameter)
/// merges and vanishes as the third parameter varies.
#[derive(Debug, Clone, Serialize)]
pub struct PairEnd {
    /// What the pair ends in.
    pub kind: PairEndKind,
    /// The last slice with the pair and the first without it (third parameter).
    pub bracket: [f64; 2],
    /// Where the pair's separation along the curve vanishes, by its square-root law from
    /// the two slices with the pair nearest the bracket.
    pub estimate: Option<f64>,
    /// The difference from the estimate by the next two slices with the pair: the
    /// estimate's error.
    pub error: Option<f64>,
    /// The observed orders of the pair's distance in the control and in the second
    /// parameter against its distance along the curve squared (3/2 at a swallowtail, 1/2 at
    /// lips or beaks).
    pub orders: Option<[f64; 2]>,
    /// Whether the fold line crosses itself beside the pair on the slice nearest the end.
    pub self_crossing: bool,
    /// The pair on the slice nearest the end: both cusps' parameters (the report's order).
    pub nearest: [Vec<f64>; 2],
    /// The slices (third parameter) that measured it, nearest first.
    pub slices: Vec<f64>,
}

/// The cusps of a critical curve followed in a third parameter.
#[derive(Debug, Clone, Serialize)]
pub struct CuspCurveReport {
    /// The parameter of the paths.
    pub control: String,
    /// The second parameter of each slice's curve.
    pub second: String,
    /// The parameter of the slices.
    pub third: String,
    /// The irrep whose block is singular along the curves.
    pub irrep: String,
    /// Parameter names (scene order).
    pub parameters: Vec<String>,
    /// Measure names.
    pub measures: Vec<String>,
    /// The slices, in increasing third parameter.
    pub slices: Vec<CuspSlice>,
    /// Where pairs of cusps end between slices.
    pub ends: Vec<PairEnd>,
    /// What went wrong without stopping the study.
    pub warnings: Vec<String>,
}
