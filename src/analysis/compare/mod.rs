//! One scene on meshes of different symmetry, side by side (docs/theory.md §11.6): the
//! analysis behind `memstab compare`.
//!
//! # Meshes
//!
//! Each mesh ([`MeshChoice`]) is
//! - a group name, `C8v`, `C2v`, `C1v`, `C4` …: the scene's own generator with that group. A
//!   disc takes any subgroup `C<M>v` / `C<M>` of its `C<N>v` with M | N; the group names of one
//!   comparison share one sector count N: the scene's `sectors` if every M divides it, else the
//!   smallest multiple of the least common multiple of the Ms that is at least the scene's
//!   (the ponding scene's 7 sectors become 8 for `C8v,C2v,C1v`). A truncated sphere takes the
//!   name as its `pattern` (a subgroup of its `C8v`). An icosphere has no group option: name
//!   it by a full override.
//! - a full override `GENERATOR:KEY=VALUE,…`, e.g. `disc:sectors=8,divisions=12,group=C2v`:
//!   the scene's mesh options (or the generator's defaults for another generator) with these
//!   keys (the scene file's `[mesh]` keys) replaced. Its commas are its own: a `KEY=VALUE`
//!   item continues the override before it.
//!
//! - `axisymmetric` (or `axisymmetric:elements=N,…`): the scene on its meridian
//!   (docs/theory.md §15.7), the `[mesh]` geometry carried over; its critical points, labelled
//!   by m, are the continuum values that every rung's images are measured against
//!   ([`Image::distances`], [`Rung::orders`]). The meridian's own error is estimated by its
//!   run at twice the elements (the refined level with `refine`, else an extra run,
//!   [`MeshRuns::check`]): [`Rung::continuum_error`] = |value(2N) − value(N)|, flagged
//!   ([`Rung::continuum_coarse`]) when it exceeds a tenth of the smallest 3-D distance.
//!
//! The first mesh is the reference. [`CompareOptions::divisions`] sets the divisions of every
//! disc and truncated sphere (an icosphere's frequency) unless a full override sets them;
//! `refine` runs every mesh again at twice its divisions (frequency). `max` sets the
//! control's upper bound; a linear-buckling sweep then keeps the scene's sample spacing
//! unless `samples` says otherwise.
//!
//! # Matching
//!
//! Every variant is run as `memstab run` runs it ([`crate::analysis::run`]), in parallel. For
//! the disc and the truncated sphere each critical mode is labelled by its wave number m about
//! z (the m = 0…24 whose cos mθ / sin mθ carries most of the mode's cylindrical components).
//! Critical points of one mesh with the same m ≥ 1 and values within 10 % are grouped into a
//! *rung* of multiplicity 2 (the cos/sin pair of an axisymmetric structure), m = 0 into rungs
//! of multiplicity 1. For every rung of the reference mesh, the images on each mesh are the
//! points with the same m nearest in value (within 20 %), taken until their multiplicities
//! reach the rung's. An icosphere's modes get no label: images are then matched by value
//! alone, up to the reference point's multiplicity.
//!
//! Images lie on the same piece of the path as their rung: a point met while the control
//! falls (after a turn) is never the image of one met while it rises, nor paired with it into
//! a rung. Folds are the images of folds, with one exception: a mesh whose trivial irrep
//! holds one mode of an m ≥ 1 pair (cos 2θ on C2v and C1v) does not protect that bifurcation,
//! and its path folds near it instead. Such a fold with the rung's m is its image, reported as
//! "imperfect"; the path turns there, so no further image is sought beyond it. A second pass
//! takes, for a bifurcation rung without image on a mesh, the points of its m on the *other*
//! piece, when the rung lies within the mesh's error at a fold, e = |F_mesh − F_ref|, of that
//! fold and the points within e of F_mesh: the mesh's error has moved the bifurcation across
//! the turn (reported as "met on the other side of the path's turn").
//!
//! A rung's *gap* on a mesh is measured: the spread of the values of its images there. One
//! point in a 2-D irrep is a double by construction ("not split: double … in E1"); two points
//! are "split" when their gap exceeds twice the summed uncertainties of the two ends — on a
//! held state (linear buckling) each point's |eigenvalue| / |d eigenvalue / d control|, else
//! 1e-8 of the value (the localisation's precision) — otherwise "not split (gap 0)" / "(gap at
//! round-off)". With `refine` the observed order of the gap is log2(gap_coarse / gap_fine).
//!
//! Bad input (a mesh that is not a subgroup or does not parse, an equilibrium analysis, a bad
//! `max`) is a [`CompareError::Input`] before anything runs; a start state that does not
//! converge is a [`CompareError::Failure`].
//!
//! # One run on refined meshes
//!
//! [`Refiner`] (`memstab run --refine`) uses the same runs and the same matching for one
//! scene on its own mesh at two or three resolutions: every critical and turning point of a
//! finished run is a rung, its images on the refined meshes give its value per level, and
//! [`estimate`] the observed order, the Richardson value and the error per level.

mod matching;
mod meshes;
mod pieces;
mod refine;

pub use matching::{
    DistanceOrder, Image, MeshImages, Missing, Rung, RungKind, Verdict, VerdictKind,
};
pub use meshes::{parse_meshes, MeshChoice};
pub use refine::{attach, estimate, observed_order, richardson, RefineOptions, Refiner};

use crate::adapted::AdaptedBasis;
use crate::model::Model;
use crate::results::{CriticalKind, CriticalPoint, PathReport, StopReason};
use crate::scene::{MeshSpec, Scene};
use crate::stability::Stability;
use crate::study::meridian::MeridianStudy;
use crate::study::mesh::{MeshStudy, StudyError};
use crate::study::Study as _;
use crate::text::{one_line, sig_digits};
use matching::{match_rungs, measure_distances};
use meshes::{common_sectors, describe, resolution, variant, Common};
use rayon::prelude::*;
use serde::Serialize;
use std::time::Instant;

/// Largest wave number tried when labelling a mode.
const MAX_WAVE_NUMBER: usize = 24;
/// Relative distance within which two points of one mesh with the same m form a rung.
const PAIR_TOLERANCE: f64 = 0.1;
/// Relative distance within which a point on another mesh is an image of a reference rung.
const MATCH_TOLERANCE: f64 = 0.2;
/// A gap at most this fraction of the value is round-off (the localisation's precision).
const ROUND_OFF: f64 = 1e-8;

/// Why a comparison could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CompareError {
    /// The request is wrong (a mesh that does not parse, a bad bound …); nothing ran.
    #[error("{0}")]
    Input(String),
    /// A run failed (a start state did not converge).
    #[error("{0}")]
    Failure(String),
    /// A signal stopped the comparison before every mesh had a run to compare.
    #[error("{0}")]
    Interrupted(String),
}

/// What to compare, besides the scene.
#[derive(Debug, Clone, Default)]
pub struct CompareOptions {
    /// The meshes, the reference first ([`parse_meshes`]).
    pub meshes: Vec<MeshChoice>,
    /// Also run every mesh at twice its divisions and measure how the gaps shrink.
    pub refine: bool,
    /// The control's upper bound (default: the scene's `max`).
    pub max: Option<f64>,
    /// Divisions of every disc or truncated sphere (an icosphere's frequency), unless a full
    /// override sets them.
    pub divisions: Option<usize>,
    /// Samples of a linear-buckling sweep (a path's step budget).
    pub samples: Option<usize>,
    /// Match the flagged critical points too (by default they are listed apart).
    pub include_flagged: bool,
}

/// A critical point as compared.
#[derive(Debug, Clone, Serialize)]
pub struct Point {
    /// Its kind.
    pub kind: CriticalKind,
    /// The irrep of the singular block.
    pub irrep: String,
    /// Its multiplicity in K.
    pub multiplicity: usize,
    /// The control's value.
    pub value: f64,
    /// Wave number of the mode about z (disc, truncated sphere).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub m: Option<usize>,
    /// |eigenvalue| / ‖K‖ at the localised point.
    pub residual_eigenvalue: f64,
    /// Uncertainty of `value` from the localisation: |eigenvalue| / |d eigenvalue / d control|
    /// at the point (held states of a linear-buckling sweep only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub precision: Option<f64>,
    /// The name of the mode's isotropy subgroup.
    pub isotropy: String,
    /// Whether the control rises as the path meets the point (for a limit point: as the path
    /// arrives at it). Images lie on the same piece of the path as their rung: a point met
    /// after a turn is not the image of one met before it.
    pub rising: bool,
    /// Why it may not be a result of the model (docs/theory.md §8.10); a flagged point is
    /// matched only with `include_flagged`.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub flags: Vec<Flag>,
    /// The second piece it lies on (numbered from 1 in [`Level::pieces`]); `None`: on the
    /// path.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub piece: Option<usize>,
}

/// The second piece beside an imperfect fold of one run (docs/theory.md §16.4): a fold whose
/// mode has a wave number m ≥ 1 is the image of a bifurcation that the mesh does not protect,
/// and the solutions beyond it lie on a piece the path does not reach.
#[derive(Debug, Clone, Serialize)]
pub struct Piece {
    /// The fold's control value.
    pub fold: f64,
    /// The fold mode's wave number.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub m: Option<usize>,
    /// The RMS distance over the nodes between the fold's state and the piece's state at the
    /// fold's control value.
    pub gap: f64,
    /// Its points, from the fold's control value on beyond it.
    pub points: usize,
    /// Why it ended.
    pub stop: StopReason,
}

/// Whether the control rises as a path meets the point at `value` localised after the step
/// whose control was `before` (`None` without a control or without that step: taken as
/// rising, the direction a path starts in).
fn rising(before: Option<f64>, value: f64) -> bool {
    before.is_none_or(|b| value >= b)
}

/// One run of one mesh at one resolution.
#[derive(Debug, Clone, Serialize)]
pub struct Level {
    /// The mesh options as one line, e.g. `disc sectors=8 divisions=6 group=C8v`.
    pub mesh: String,
    /// Divisions (an icosphere's frequency).
    pub resolution: usize,
    /// Nodes.
    pub nodes: usize,
    /// Triangles.
    pub triangles: usize,
    /// The scene's group on this mesh.
    pub group: String,
    /// Its order.
    pub order: usize,
    /// Unknowns of the model.
    pub unknowns: usize,
    /// Unknowns of the fixed-point space.
    pub symmetric_unknowns: usize,
    /// Why the run's path ended.
    pub stop: StopReason,
    /// Why stability was not analysed, if it was not.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
    /// Steps where the instability index changes by more than the critical points localised
    /// there account for (a crossing the run could not localise, or a jump of the path).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// Wall time of the run.
    pub seconds: f64,
    /// Its critical points (the valid ones, unless flagged ones are included).
    pub critical: Vec<Point>,
    /// Its flagged critical points, listed apart and not matched.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub flagged: Vec<Point>,
    /// Its turning points of the control, as limit points whose irrep is `maximum` or
    /// `minimum` (what `run --refine` matches across meshes; not part of the comparison).
    #[serde(skip)]
    pub turning: Vec<Point>,
    /// A critical curve's events but its start and end (what `run --refine` matches across
    /// meshes; not part of the comparison).
    #[serde(skip)]
    pub events: Vec<refine::EventPoint>,
    /// The second pieces beside its imperfect folds; their critical points are among
    /// `critical`, each with its `piece`.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub pieces: Vec<Piece>,
}

/// One mesh's runs.
#[derive(Debug, Clone, Serialize)]
pub struct MeshRuns {
    /// The label, as written.
    pub label: String,
    /// Its generator.
    pub generator: String,
    /// One run per resolution.
    pub levels: Vec<Level>,
    /// The meridian's run at twice its elements, without `refine` (whose second level is
    /// that run): its own error estimate, |value(2N) − value(N)|.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub check: Option<Level>,
}

/// A critical point without a counterpart on the reference mesh.
#[derive(Debug, Clone, Serialize)]
pub struct Unmatched {
    /// The mesh's label.
    pub mesh: String,
    /// The run's resolution.
    pub resolution: usize,
    /// The index into that run's `critical`.
    pub point: usize,
    /// Its irrep.
    pub irrep: String,
    /// Its control value.
    pub value: f64,
    /// Its wave number about z.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub m: Option<usize>,
    /// Whether the control rises as the path meets it.
    pub rising: bool,
}

/// A finished comparison.
#[derive(Debug, Clone, Serialize)]
pub struct Comparison {
    /// The scene's name.
    pub scene: String,
    /// Where it came from.
    pub origin: String,
    /// Its analysis.
    pub analysis: &'static str,
    /// The control parameter.
    pub control: String,
    /// The control's range.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub range: Option<[f64; 2]>,
    /// A sweep's samples, a path's step budget.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub samples: Option<usize>,
    /// `m` when modes are labelled by their wave number about z.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub label: Option<&'static str>,
    /// Whether every mesh ran at a second, doubled resolution.
    pub refine: bool,
    /// The reference mesh's label.
    pub reference: String,
    /// Every mesh's runs.
    pub meshes: Vec<MeshRuns>,
    /// The reference's rungs with their images.
    pub rungs: Vec<Rung>,
    /// Points matched to no rung.
    pub unmatched: Vec<Unmatched>,
}

/// The wave number of a critical mode about z (see [`crate::adapted::labels::wave_number`]).
fn wave_number(study: &MeshStudy, mode: &[f64]) -> usize {
    crate::adapted::labels::wave_number(
        study.model.reference(),
        study.model.layout(),
        mode,
        MAX_WAVE_NUMBER,
    )
}

/// Whether modes are labelled by their wave number about z.
fn labelled(scene: &Scene) -> bool {
    matches!(
        scene.mesh,
        MeshSpec::Disc(_) | MeshSpec::TruncatedSphere(_) | MeshSpec::Axisymmetric(_)
    )
}

/// One run of a comparison: a 3-D study or a meridian.
enum Job {
    Solid(Box<MeshStudy>),
    Meridian(Box<MeridianStudy>),
}

impl Job {
    /// Its mesh, as one line.
    fn mesh(&self) -> String {
        match self {
            Job::Solid(s) => describe(&s.scene.mesh),
            Job::Meridian(s) => describe(&s.scene.mesh),
        }
    }

    fn unknowns(&self) -> usize {
        match self {
            Job::Solid(s) => s.basis.unknowns(),
            Job::Meridian(s) => s.model.dim(),
        }
    }

    /// Runs it; `pieces`: also the second pieces of its imperfect folds.
    fn execute(
        self,
        label: &str,
        (label_modes, pieces): (bool, bool),
        progress: &(dyn Fn(&str) + Sync),
    ) -> Result<Level, CompareError> {
        match self {
            Job::Solid(s) => execute(label, *s, pieces, progress),
            Job::Meridian(s) => execute_meridian(label, *s, label_modes, progress),
        }
    }
}

use crate::axisym::blocks::MERIDIAN_GROUP;
use crate::results::validity::Flag;

/// Runs a meridian (docs/theory.md §15) and collects its critical points: each labelled by
/// its wave number m (unless `label_modes` is false: a comparison with unlabelled 3-D
/// modes), irrep `m=M`, multiplicity 1 for m = 0 and 2 for m ≥ 1.
fn execute_meridian(
    label: &str,
    mut study: MeridianStudy,
    label_modes: bool,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Level, CompareError> {
    let start = Instant::now();
    let mesh = describe(&study.scene.mesh);
    let result = super::run(&mut study, |_, _| {}).map_err(|e| {
        CompareError::Failure(format!(
            "mesh '{label}' ({mesh}): {}",
            one_line(&e.to_string())
        ))
    })?;
    let report = &result.report;
    let control = study.control().map(|c| c.index);
    let critical: Vec<Point> = report
        .critical
        .iter()
        .zip(&report.wave_numbers)
        .enumerate()
        .map(|(k, (_, &m))| {
            point_of(
                report,
                control,
                k,
                format!("m={m}"),
                label_modes.then_some(m),
                None,
            )
        })
        .collect();
    let seconds = start.elapsed().as_secs_f64();
    progress(&format!(
        "{label} ({mesh}): {} critical points in {seconds:.1} s",
        critical.len()
    ));
    Ok(Level {
        mesh,
        resolution: resolution(&study.scene.mesh),
        nodes: study.model.meridian.nodes.len(),
        triangles: 0,
        group: MERIDIAN_GROUP.into(),
        order: 0,
        unknowns: report.unknowns,
        symmetric_unknowns: report.unknowns,
        stop: report.stop.clone(),
        note: None,
        warnings: report.warnings.clone(),
        seconds,
        critical,
        flagged: Vec::new(),
        turning: turning_of(report, control),
        events: refine::events_of(&result),
        pieces: Vec::new(),
    })
}

/// Multiplies the resolution of `mesh` by `factor`: a disc's or truncated sphere's divisions,
/// an icosphere's frequency, a meridian's elements. False for a mesh file, which cannot be
/// refined.
fn refine_mesh(mesh: &mut MeshSpec, factor: usize) -> bool {
    match mesh {
        MeshSpec::Disc(d) => d.divisions *= factor,
        MeshSpec::Icosphere(i) => i.frequency *= factor,
        MeshSpec::TruncatedSphere(t) => t.divisions = Some(t.divisions_or_default() * factor),
        MeshSpec::Axisymmetric(a) => a.elements *= factor,
        MeshSpec::File(_) => return false,
    }
    true
}

/// Critical point `k` of `report` as compared, with its irrep, wave number and precision.
fn point_of(
    report: &PathReport,
    control: Option<usize>,
    k: usize,
    irrep: String,
    m: Option<usize>,
    precision: Option<f64>,
) -> Point {
    let cp = &report.critical[k];
    Point {
        flags: report.flags(k),
        kind: cp.kind,
        irrep,
        multiplicity: cp.multiplicity,
        value: control.map_or(f64::NAN, |c| cp.parameters[c]),
        m,
        residual_eigenvalue: cp.residual_eigenvalue,
        precision,
        isotropy: cp.isotropy.name.clone(),
        rising: rising(
            control.and_then(|c| {
                let row = report.rows.iter().find(|r| r.step == cp.after_step)?;
                Some(row.parameters[c])
            }),
            control.map_or(f64::NAN, |c| cp.parameters[c]),
        ),
        piece: None,
    }
}

/// The turning points of `report` as limit points with the irrep `maximum` or `minimum`
/// (met as the control rises or falls), unlabelled: matched by value alone.
fn turning_of(report: &PathReport, control: Option<usize>) -> Vec<Point> {
    report
        .turning_points
        .iter()
        .map(|t| Point {
            kind: CriticalKind::LimitPoint,
            irrep: t.kind.to_string(),
            multiplicity: 1,
            value: control.map_or(f64::NAN, |c| t.parameters[c]),
            m: None,
            residual_eigenvalue: 0.0,
            precision: None,
            isotropy: String::new(),
            rising: t.kind == crate::results::Extremum::Maximum,
            flags: Vec::new(),
            piece: None,
        })
        .collect()
}

/// Runs one variant and collects its critical points.
fn execute(
    label: &str,
    mut study: MeshStudy,
    seek_pieces: bool,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Level, CompareError> {
    let start = Instant::now();
    let mesh = describe(&study.scene.mesh);
    let resolution = resolution(&study.scene.mesh);
    let result = super::run(&mut study, |_, _| {}).map_err(|e| {
        CompareError::Failure(format!(
            "mesh '{label}' ({mesh}): {}",
            one_line(&e.to_string())
        ))
    })?;
    let report = &result.report;
    let control = study.control;
    let label_modes = labelled(&study.scene);
    let precisions = precisions(&study, &report.critical);
    let critical: Vec<Point> = report
        .critical
        .iter()
        .zip(precisions)
        .enumerate()
        .map(
            |(k, (cp, precision)): (usize, (&CriticalPoint, Option<f64>))| {
                let m = label_modes.then(|| wave_number(&study, &cp.mode));
                point_of(report, control, k, cp.irrep.clone(), m, precision)
            },
        )
        .collect();
    let (pieces, on_pieces) = if seek_pieces {
        pieces::second_pieces(&study, &result, &critical, label_modes)
    } else {
        Default::default()
    };
    let mut critical = critical;
    critical.extend(on_pieces);
    let warnings = unaccounted(report);
    let seconds = start.elapsed().as_secs_f64();
    progress(&format!(
        "{label} ({mesh}): {} critical points in {seconds:.1} s",
        critical.len()
    ));
    Ok(Level {
        mesh,
        resolution,
        nodes: report.mesh.nodes,
        triangles: report.mesh.elements,
        group: report.group.clone(),
        order: report.group_order,
        unknowns: report.unknowns,
        symmetric_unknowns: report.symmetric_unknowns,
        stop: report.stop.clone(),
        note: report.stability_note.clone(),
        warnings,
        seconds,
        critical,
        flagged: Vec::new(),
        turning: turning_of(report, control),
        events: refine::events_of(&result),
        pieces,
    })
}

/// Every interval of the path whose change of the instability index exceeds the
/// multiplicities of the critical points localised in it: such a crossing was not localised
/// (or the path jumped), so a comparison of that mesh may miss points.
fn unaccounted(report: &PathReport) -> Vec<String> {
    let control = report.parameters.iter().position(|p| *p == report.control);
    let mut out = Vec::new();
    for w in report.rows.windows(2) {
        let (Some(a), Some(b)) = (w[0].index, w[1].index) else {
            continue;
        };
        let found: usize = report
            .critical
            .iter()
            .filter(|c| c.after_step == w[0].step)
            .map(|c| c.multiplicity)
            .sum();
        if a.abs_diff(b) > found {
            let at = control.map_or_else(String::new, |c| {
                format!(
                    " ({} {} to {})",
                    report.control,
                    sig_digits(w[0].parameters[c], 6),
                    sig_digits(w[1].parameters[c], 6)
                )
            });
            out.push(format!(
                "the index changes from {a} to {b} between steps {} and {}{at} but critical \
                 points of multiplicity {found} were localised there",
                w[0].step, w[1].step
            ));
        }
    }
    out
}

/// The uncertainty of each critical value of a linear-buckling sweep: the localised
/// eigenvalue's |g| / |dg/dλ|, the slope taken by central differences on the held state (the
/// tangent is affine in the control there). `None` for path analyses, whose state moves with
/// the control.
fn precisions(study: &MeshStudy, critical: &[CriticalPoint]) -> Vec<Option<f64>> {
    let none = vec![None; critical.len()];
    let (true, Some(c)) = (study.scene.analysis.holds_state(), study.control) else {
        return none;
    };
    let Ok(adapted) = AdaptedBasis::new(&study.action, study.model.layout()) else {
        return none;
    };
    let stability = Stability::new(&study.model, &adapted);
    let mut eval = study.model.new_evaluation();
    let spec = &study.scene.parameters[&study.parameters[c]];
    let range = match (spec.min, spec.max) {
        (Some(lo), Some(hi)) => (hi - lo).abs(),
        _ => 1.0,
    };
    critical
        .iter()
        .map(|cp| {
            let mu = adapted.irreps.iter().position(|i| i.name == cp.irrep)?;
            let v = cp.parameters[c];
            let delta = 1e-5 * range.max(v.abs()).max(1e-300);
            let mut at = |x: f64| {
                let mut p = cp.parameters.clone();
                p[c] = x;
                let sp = stability
                    .spectrum_of(
                        &cp.state,
                        &p,
                        &study.constraints,
                        &mut eval,
                        Some(mu),
                        false,
                    )
                    .ok()?;
                let g = sp.blocks[mu]
                    .eigenvalues
                    .iter()
                    .copied()
                    .min_by(|a, b| a.abs().total_cmp(&b.abs()))?;
                Some((g, sp.scale))
            };
            let (gp, scale) = at(v + delta)?;
            let (gm, _) = at(v - delta)?;
            let slope = (gp - gm) / (2.0 * delta) / scale;
            (slope != 0.0 && slope.is_finite())
                .then(|| (cp.residual_eigenvalue / slope.abs()).max(4e-16 * v.abs()))
        })
        .collect()
}

/// The control's `[min, max]`, when the scene bounds it on both sides.
fn range_of(scene: &Scene, control: &str) -> Option<[f64; 2]> {
    let p = scene.parameters.get(control)?;
    match (p.min, p.max) {
        (Some(lo), Some(hi)) => Some([lo, hi]),
        _ => None,
    }
}

/// The absolute slack of the matching tolerances: a thousandth of the control's range.
fn floor_of(range: Option<[f64; 2]>) -> f64 {
    range.map_or(1e-12, |[lo, hi]| 1e-3 * (hi - lo).abs())
}

/// Runs `scene` on every mesh of `options` (in parallel; `progress` hears of each run as it
/// ends), matches their critical points to the reference's rungs and measures the gaps.
pub fn compare(
    scene: &Scene,
    options: &CompareOptions,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Comparison, CompareError> {
    let Some(control) = scene.control().map(str::to_string) else {
        return Err(CompareError::Input(format!(
            "scene '{}': compare needs a path or linear-buckling analysis (an equilibrium has \
             no control to compare critical values in)",
            scene.origin
        )));
    };
    if let Some(max) = options.max {
        if !max.is_finite() {
            return Err(CompareError::Input(format!(
                "--max {max}: must be a finite number"
            )));
        }
    }
    if options.divisions == Some(0) {
        return Err(CompareError::Input("--divisions 0: must be >= 1".into()));
    }
    if options.samples == Some(0) {
        return Err(CompareError::Input("--samples 0: must be >= 1".into()));
    }
    if let (Some(max), Some(p)) = (options.max, scene.parameters.get(&control)) {
        if p.min.is_some_and(|lo| max <= lo) || max < p.start {
            return Err(CompareError::Input(format!(
                "--max {max}: the upper bound of {control} must exceed its min{} and be at \
                 least its start value {}",
                p.min.map_or_else(String::new, |lo| format!(" {lo}")),
                p.start
            )));
        }
    }
    let typed = &options.meshes;
    if typed.is_empty() {
        return Err(CompareError::Input("--meshes: no mesh given".into()));
    }
    let common = Common {
        control: control.clone(),
        max: options.max,
        samples: options.samples,
        divisions: options.divisions,
        sectors: match &scene.mesh {
            MeshSpec::Disc(d) => common_sectors(d.sectors, typed),
            _ => 0,
        },
    };
    // Every variant is built (and checked) before anything runs.
    let levels = if options.refine { 2 } else { 1 };
    let mut jobs: Vec<(usize, usize, Job)> = Vec::new();
    let mut first_scene: Option<Scene> = None;
    let mut label_modes = true;
    for (k, t) in typed.iter().enumerate() {
        let coarse = variant(scene, t, &common)?;
        for l in 0..levels {
            let mut s = coarse.clone();
            if l == 1 && !refine_mesh(&mut s.mesh, 2) {
                return Err(CompareError::Input(format!(
                    "mesh '{}': --refine cannot refine a mesh file",
                    t.label
                )));
            }
            if s.start.from.is_some() {
                return Err(CompareError::Input(
                    "'start.from': compare runs the scene on other meshes, which a saved state \
                     does not fit; remove [start] from"
                        .to_string(),
                ));
            }
            label_modes &= labelled(&s);
            let job = if let MeshSpec::Axisymmetric(_) = s.mesh {
                let study = MeridianStudy::build(s).map_err(|e| {
                    CompareError::Input(one_line(&format!("mesh '{}': {e}", t.label)))
                })?;
                Job::Meridian(Box::new(study))
            } else {
                let study = MeshStudy::build(s).map_err(|e| match e {
                    StudyError::Scene(_) | StudyError::Unsupported(_) | StudyError::Limit(_) => {
                        CompareError::Input(one_line(&e.to_string()))
                    }
                })?;
                Job::Solid(Box::new(study))
            };
            jobs.push((k, l, job));
        }
        // Without `refine` the meridian also runs at twice its elements, for its own error.
        if let (1, MeshSpec::Axisymmetric(a)) = (levels, &coarse.mesh) {
            let mut s = coarse.clone();
            if let MeshSpec::Axisymmetric(b) = &mut s.mesh {
                b.elements = a.elements * 2;
            }
            let study = MeridianStudy::build(s)
                .map_err(|e| CompareError::Input(one_line(&format!("mesh '{}': {e}", t.label))))?;
            jobs.push((k, 1, Job::Meridian(Box::new(study))));
        }
        if k == 0 {
            first_scene = Some(coarse);
        }
    }
    let reference_scene = first_scene.expect("at least one mesh");
    // The largest meshes first, so that the parallel runs end together.
    jobs.sort_by_key(|(_, _, s)| std::cmp::Reverse(s.unknowns()));
    // A signal stops the runs under way at their next point and skips those not started (a
    // run its signal cut short before its start converged counts as not run).
    let interrupted = crate::continuation::interrupt::requested;
    let total = jobs.len();
    let results: Vec<Result<(usize, usize, Level), CompareError>> = jobs
        .into_par_iter()
        .filter_map(|(k, l, job)| {
            if interrupted() {
                return None;
            }
            match job.execute(&typed[k].label, (label_modes, true), progress) {
                Err(_) if interrupted() => None,
                r => Some(r.map(|r| (k, l, r))),
            }
        })
        .collect();
    let mut meshes: Vec<MeshRuns> = typed
        .iter()
        .map(|t| MeshRuns {
            label: t.label.clone(),
            generator: String::new(),
            levels: Vec::new(),
            check: None,
        })
        .collect();
    let mut slots: Vec<Vec<Option<Level>>> = vec![vec![None; levels + 1]; typed.len()];
    for r in results {
        let (k, l, mut level) = r?;
        // The flagged points are listed apart, unless asked for.
        if !options.include_flagged {
            let (valid, flagged) = level.critical.into_iter().partition(|p| p.flags.is_empty());
            (level.critical, level.flagged) = (valid, flagged);
        }
        slots[k][l] = Some(level);
    }
    // Interrupted: the levels every mesh has (the coarse ones, or none).
    let levels = slots
        .iter()
        .map(|s| s.iter().take(levels).take_while(|l| l.is_some()).count())
        .min()
        .unwrap_or(0);
    if levels == 0 {
        return Err(CompareError::Interrupted(format!(
            "a signal stopped the comparison before every mesh had run ({} of {} runs ended); nothing to compare",
            slots.iter().flatten().filter(|l| l.is_some()).count(),
            total
        )));
    }
    for (k, mut s) in slots.into_iter().enumerate() {
        // Slot `levels` is the meridian's check run, when there is one.
        meshes[k].check = if levels == 1 { s[1].take() } else { None };
        meshes[k].levels = s
            .into_iter()
            .take(levels)
            .map(|l| l.expect("every mesh has its first `levels` runs"))
            .collect();
        meshes[k].generator = meshes[k].levels[0]
            .mesh
            .split_whitespace()
            .next()
            .unwrap_or("")
            .to_string();
    }
    let range = range_of(&reference_scene, &control);
    let floor = floor_of(range);
    let (mut rung_list, unmatched) = match_rungs(&meshes, floor);
    if let Some(c) = meshes.iter().position(|m| m.generator == "axisymmetric") {
        measure_distances(&meshes, &mut rung_list, c);
    }
    let samples = reference_scene.analysis.budget();
    Ok(Comparison {
        scene: scene.info.name.clone(),
        origin: scene.origin.clone(),
        analysis: reference_scene.analysis.kind(),
        control,
        range,
        samples,
        label: label_modes.then_some("m"),
        refine: options.refine && levels == 2,
        reference: typed[0].label.clone(),
        meshes,
        rungs: rung_list,
        unmatched,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(irrep: &str, multiplicity: usize, value: f64, m: usize) -> Point {
        Point {
            kind: CriticalKind::of(false, multiplicity, false),
            irrep: irrep.into(),
            multiplicity,
            value,
            m: Some(m),
            residual_eigenvalue: 0.0,
            precision: None,
            isotropy: String::new(),
            rising: true,
            flags: Vec::new(),
            piece: None,
        }
    }

    #[test]
    fn full_overrides_keep_their_commas() {
        let t = parse_meshes(&["C8v,disc:sectors=8,divisions=12,group=C2v,C1v".into()]).unwrap();
        let labels: Vec<&str> = t.iter().map(|t| t.label.as_str()).collect();
        assert_eq!(
            labels,
            ["C8v", "disc:sectors=8,divisions=12,group=C2v", "C1v"]
        );
        assert!(parse_meshes(&["C8v,divisions=3".into()]).is_err());
        assert!(parse_meshes(&["C8v,,C2v".into()]).is_err());
        assert!(parse_meshes(&["C2v,C2v".into()]).is_err());
    }

    #[test]
    fn sectors_are_shared() {
        let t = parse_meshes(&["C8v,C2v,C1v".into()]).unwrap();
        assert_eq!(common_sectors(7, &t), 8);
        assert_eq!(common_sectors(8, &t), 8);
        let t = parse_meshes(&["C7v,C1v".into()]).unwrap();
        assert_eq!(common_sectors(7, &t), 7);
        let t = parse_meshes(&["C7v,C2v".into()]).unwrap();
        assert_eq!(common_sectors(7, &t), 14);
    }

    #[test]
    fn a_double_and_its_split_images_are_matched() {
        let reference = vec![
            point("A1", 1, 2.0, 0),
            point("E1", 2, 5.0, 1),
            point("B1", 1, 9.0, 4),
            point("B2", 1, 9.01, 4),
        ];
        let other = vec![
            point("A1", 1, 2.01, 0),
            point("B2", 1, 5.02, 1),
            point("B1", 1, 4.99, 1),
            point("A1", 1, 9.02, 4),
        ];
        let level = |critical: Vec<Point>| Level {
            mesh: String::new(),
            resolution: 6,
            nodes: 0,
            triangles: 0,
            group: String::new(),
            order: 1,
            unknowns: 0,
            symmetric_unknowns: 0,
            stop: StopReason::Condition,
            note: None,
            warnings: Vec::new(),
            seconds: 0.0,
            critical,
            flagged: Vec::new(),
            turning: Vec::new(),
            events: Vec::new(),
            pieces: Vec::new(),
        };
        let meshes = vec![
            MeshRuns {
                label: "C8v".into(),
                generator: "disc".into(),
                levels: vec![level(reference)],
                check: None,
            },
            MeshRuns {
                label: "C2v".into(),
                generator: "disc".into(),
                levels: vec![level(other)],
                check: None,
            },
        ];
        let (rungs, unmatched) = match_rungs(&meshes, 1e-3);
        assert_eq!(rungs.len(), 3);
        assert!(unmatched.is_empty());
        let e1 = &rungs[1].images;
        assert_eq!(
            e1[0].levels[0].verdict.to_string(),
            "not split: double bifurcation in E1"
        );
        assert_eq!(e1[1].levels[0].irreps, ["B1", "B2"]);
        assert!((e1[1].levels[0].gap.unwrap() - 0.03).abs() < 1e-12);
        assert_eq!(e1[1].levels[0].verdict.to_string(), "split");
        let m4 = &rungs[2].images;
        assert_eq!(m4[0].levels[0].irreps, ["B1", "B2"]);
        assert!(m4[1].levels[0]
            .verdict
            .to_string()
            .contains("partner not found"));
    }
}
