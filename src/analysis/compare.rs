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
//! A rung's *gap* on a mesh is measured: the spread of the values of its images there. One
//! point in a 2-D irrep is a double by construction ("not split: double … in E1"); two points
//! are "split" when their gap exceeds twice the summed uncertainties of the two ends — on a
//! held state (linear buckling) each point's |eigenvalue| / |d eigenvalue / d control|, else
//! 1e-8 of the value (the localisation's precision) — otherwise "not split (gap 0)" / "(gap at
//! round-off)". With `refine` the observed order of the gap is log2(gap_coarse / gap_fine).
//!
//! Bad input (a mesh that is not a subgroup or does not parse, a chiral group, an equilibrium
//! analysis, a bad `max`) is a [`CompareError::Input`] before anything runs; a start state
//! that does not converge is a [`CompareError::Failure`].

use super::critical::{CriticalKind, CriticalPoint};
use super::events::StopReason;
use crate::adapted::AdaptedBasis;
use crate::model::Model;
use crate::report::PathReport;
use crate::scene::{Analysis, Generator, MeshSpec, Scene};
use crate::stability::Stability;
use crate::study::{Study, StudyError};
use crate::text::{one_line, sci, sig_digits};
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

/// How a mesh is named.
#[derive(Debug, Clone, PartialEq)]
enum MeshArg {
    /// A group name for the scene's generator.
    Group(String),
    /// `GENERATOR:KEY=VALUE,…`.
    Full {
        generator: String,
        options: Vec<(String, String)>,
    },
}

/// One mesh of a comparison: its label (as written) and what it means.
#[derive(Debug, Clone)]
pub struct MeshChoice {
    /// The label, as written.
    pub label: String,
    arg: MeshArg,
}

/// A generator that builds meshes (every one but `file`).
fn generated(name: &str) -> Option<Generator> {
    Generator::from_name(name).filter(|g| *g != Generator::File)
}

/// Why a comparison could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CompareError {
    /// The request is wrong (a mesh that does not parse, a bad bound …); nothing ran.
    #[error("{0}")]
    Input(String),
    /// A run failed (a start state did not converge).
    #[error("{0}")]
    Failure(String),
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
}

/// The meshes of comma-separated lists (`C8v,C2v,disc:sectors=8,divisions=12,group=C1v`); a
/// `KEY=VALUE` item continues the full override before it. Errors name the list as
/// `--meshes '…'`.
pub fn parse_meshes(values: &[String]) -> Result<Vec<MeshChoice>, CompareError> {
    let mut out: Vec<MeshChoice> = Vec::new();
    for value in values {
        let mut continuing = false;
        for raw in value.split(',') {
            let item = raw.trim();
            if item.is_empty() {
                return Err(CompareError::Input(format!(
                    "--meshes '{value}': an empty mesh name"
                )));
            }
            if let Some((generator, rest)) = item.split_once(':') {
                let generator = generator.trim().to_string();
                let mut options = Vec::new();
                if !rest.trim().is_empty() {
                    options.push(key_value(rest, value)?);
                }
                out.push(MeshChoice {
                    label: item.to_string(),
                    arg: MeshArg::Full { generator, options },
                });
                continuing = true;
            } else if item.contains('=') {
                let last = out.last_mut().filter(|_| continuing);
                let Some(MeshChoice {
                    label,
                    arg: MeshArg::Full { options, .. },
                }) = last
                else {
                    return Err(CompareError::Input(format!(
                        "--meshes '{value}': '{item}' names no generator; write a full \
                         override as GENERATOR:KEY=VALUE,..., e.g. disc:divisions=12,group=C2v"
                    )));
                };
                options.push(key_value(item, value)?);
                label.push(',');
                label.push_str(item);
            } else if generated(item).is_some() {
                out.push(MeshChoice {
                    label: item.to_string(),
                    arg: MeshArg::Full {
                        generator: item.to_string(),
                        options: Vec::new(),
                    },
                });
                continuing = true;
            } else {
                out.push(MeshChoice {
                    label: item.to_string(),
                    arg: MeshArg::Group(item.to_string()),
                });
                continuing = false;
            }
        }
    }
    for (i, t) in out.iter().enumerate() {
        if out[..i].iter().any(|o| o.label == t.label) {
            return Err(CompareError::Input(format!(
                "--meshes: '{}' is given twice",
                t.label
            )));
        }
    }
    if out.is_empty() {
        return Err(CompareError::Input("--meshes: no mesh given".into()));
    }
    Ok(out)
}

fn key_value(item: &str, value: &str) -> Result<(String, String), CompareError> {
    match item.split_once('=') {
        Some((k, v)) if !k.trim().is_empty() && !v.trim().is_empty() => {
            Ok((k.trim().replace('_', "-"), v.trim().to_string()))
        }
        _ => Err(CompareError::Input(format!(
            "--meshes '{value}': '{item}' is not KEY=VALUE"
        ))),
    }
}

/// A typed option value as TOML: an integer, a float, a boolean, else a string.
fn toml_value(v: &str) -> toml::Value {
    if let Ok(i) = v.parse::<i64>() {
        toml::Value::Integer(i)
    } else if let Ok(f) = v.parse::<f64>() {
        toml::Value::Float(f)
    } else if let Ok(b) = v.parse::<bool>() {
        toml::Value::Boolean(b)
    } else {
        toml::Value::String(v.to_string())
    }
}

/// M of `C<M>` / `C<M>v`, if the name has that form.
fn axial_order(name: &str) -> Option<usize> {
    let rest = name.strip_prefix('C')?;
    let digits = rest.strip_suffix('v').unwrap_or(rest);
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    digits.parse().ok().filter(|&m: &usize| m >= 1)
}

fn gcd(a: usize, b: usize) -> usize {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

/// The sector count shared by the group names: the scene's if every M divides it, else the
/// smallest multiple of lcm(M…) that is at least the scene's.
fn common_sectors(scene_sectors: usize, typed: &[MeshChoice]) -> usize {
    let orders: Vec<usize> = typed
        .iter()
        .filter_map(|t| match &t.arg {
            MeshArg::Group(g) => axial_order(g),
            MeshArg::Full { .. } => None,
        })
        .collect();
    if orders.iter().all(|m| scene_sectors.is_multiple_of(*m)) {
        return scene_sectors;
    }
    let l = orders
        .iter()
        .fold(1usize, |l, &m| (l / gcd(l, m)).saturating_mul(m))
        .max(1);
    scene_sectors.div_ceil(l).saturating_mul(l)
}

/// The resolution of a mesh spec: divisions, or an icosphere's frequency.
fn resolution(spec: &MeshSpec) -> usize {
    match spec {
        MeshSpec::Disc(d) => d.divisions,
        MeshSpec::Icosphere(i) => i.frequency,
        MeshSpec::TruncatedSphere(t) => t.divisions_or_default(),
        MeshSpec::File(_) => 0,
    }
}

/// The mesh options as one line, e.g. `disc sectors=8 divisions=6 group=C8v`.
fn describe(spec: &MeshSpec) -> String {
    match spec {
        MeshSpec::Disc(d) => format!(
            "disc sectors={} divisions={} group={}",
            d.sectors,
            d.divisions,
            d.group
                .clone()
                .unwrap_or_else(|| format!("C{}v", d.sectors))
        ),
        MeshSpec::Icosphere(i) => format!(
            "icosphere frequency={}{}",
            i.frequency,
            i.down.map_or_else(String::new, |d| format!(
                " down={}",
                format!("{d:?}").to_lowercase()
            ))
        ),
        MeshSpec::TruncatedSphere(t) => format!(
            "truncated-sphere pattern={} divisions={} cut-height={}",
            t.pattern,
            t.divisions_or_default(),
            t.cut_height
        ),
        MeshSpec::File(f) => format!("file {} group={}", f.path.display(), f.group),
    }
}

/// The settings shared by every variant.
struct Common {
    control: String,
    max: Option<f64>,
    samples: Option<usize>,
    divisions: Option<usize>,
    sectors: usize,
}

/// The scene with the typed mesh and the common settings, validated again as a whole.
fn variant(scene: &Scene, typed: &MeshChoice, common: &Common) -> Result<Scene, CompareError> {
    let bad = |what: String| CompareError::Input(format!("mesh '{}': {what}", typed.label));
    let mut mesh = toml::Table::try_from(&scene.mesh)
        .map_err(|e| CompareError::Failure(format!("the scene's mesh does not serialise: {e}")))?;
    let own = scene.mesh.generator();
    let mut explicit_resolution = false;
    match &typed.arg {
        MeshArg::Group(name) => match &scene.mesh {
            MeshSpec::Disc(_) => {
                mesh.insert("group".into(), toml::Value::String(name.clone()));
                mesh.insert(
                    "sectors".into(),
                    toml::Value::Integer(common.sectors as i64),
                );
            }
            MeshSpec::TruncatedSphere(_) => {
                mesh.insert("pattern".into(), toml::Value::String(name.clone()));
            }
            // The same file, declared with another group.
            MeshSpec::File(_) => {
                mesh.insert("group".into(), toml::Value::String(name.clone()));
            }
            MeshSpec::Icosphere(_) => {
                return Err(bad(
                    "an icosphere has no group option; name it by a full override, e.g. \
                     icosphere:frequency=4,down=vertex"
                        .into(),
                ))
            }
        },
        MeshArg::Full { generator, options } => {
            let Some(chosen) = generated(generator) else {
                let known: Vec<&str> = Generator::ALL
                    .iter()
                    .filter_map(|g| generated(g.name()).map(|g| g.name()))
                    .collect();
                return Err(bad(format!(
                    "unknown generator '{generator}' ({})",
                    known.join(", ")
                )));
            };
            if chosen != own {
                mesh = toml::Table::new();
                mesh.insert("generator".into(), toml::Value::String(generator.clone()));
            }
            for (k, v) in options {
                if k == "generator" {
                    return Err(bad("the generator goes before the ':'".into()));
                }
                explicit_resolution |= Some(k.as_str()) == chosen.resolution_key();
                mesh.insert(k.clone(), toml_value(v));
            }
        }
    }
    let generator = mesh
        .get("generator")
        .and_then(|g| g.as_str())
        .and_then(Generator::from_name)
        .unwrap_or(own);
    if let (Some(d), false, Some(key)) = (
        common.divisions,
        explicit_resolution,
        generator.resolution_key(),
    ) {
        mesh.insert(key.into(), toml::Value::Integer(d as i64));
    }
    let mut base = scene.clone();
    if let Some(max) = common.max {
        if let Some(p) = base.parameters.get_mut(&common.control) {
            let old = (p.min, p.max);
            p.max = Some(max);
            // Keep the sample spacing of a linear-buckling sweep.
            if let (Analysis::LinearBuckling(b), (Some(lo), Some(hi)), None) =
                (&mut base.analysis, old, common.samples)
            {
                if hi > lo && max > lo {
                    b.samples = ((b.samples as f64) * (max - lo) / (hi - lo))
                        .ceil()
                        .max(1.0) as usize;
                }
            }
        }
    }
    if let Some(n) = common.samples {
        match &mut base.analysis {
            Analysis::LinearBuckling(b) => b.samples = n,
            Analysis::Path(p) => p.steps = n,
            Analysis::Equilibrium(_) => {}
        }
    }
    let mut table = toml::Table::try_from(&base)
        .map_err(|e| CompareError::Failure(format!("the scene does not serialise: {e}")))?;
    table.insert("mesh".into(), toml::Value::Table(mesh));
    let text = toml::to_string(&table)
        .map_err(|e| CompareError::Failure(format!("the scene does not serialise: {e}")))?;
    let origin = format!("{} with mesh '{}'", scene.origin, typed.label);
    Scene::from_toml_str(&text, &origin)
        .map_err(|e| CompareError::Input(one_line(&e.to_string())))
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
    /// Its critical points.
    pub critical: Vec<Point>,
}

/// The wave number of a critical mode about z (see [`super::critical::wave_number`]).
fn wave_number(study: &Study, mode: &[f64]) -> usize {
    super::critical::wave_number(
        study.model.reference(),
        study.model.layout(),
        mode,
        MAX_WAVE_NUMBER,
    )
}

/// Whether modes are labelled by their wave number about z.
fn labelled(scene: &Scene) -> bool {
    matches!(scene.mesh, MeshSpec::Disc(_) | MeshSpec::TruncatedSphere(_))
}

/// Runs one variant and collects its critical points.
fn execute(
    label: &str,
    mut study: Study,
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
        .map(|(cp, precision): (&CriticalPoint, Option<f64>)| Point {
            kind: cp.kind,
            irrep: cp.irrep.clone(),
            multiplicity: cp.multiplicity,
            value: control.map_or(f64::NAN, |c| cp.parameters[c]),
            m: label_modes.then(|| wave_number(&study, &cp.mode)),
            residual_eigenvalue: cp.residual_eigenvalue,
            precision,
            isotropy: cp.isotropy.name.clone(),
        })
        .collect();
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
fn precisions(study: &Study, critical: &[CriticalPoint]) -> Vec<Option<f64>> {
    let none = vec![None; critical.len()];
    let (Analysis::LinearBuckling(_), Some(c)) = (&study.scene.analysis, study.control) else {
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

/// The multiplicity a rung of this point should reach: 2 for a wave number m ≥ 1 (the cos/sin
/// pair), 1 for m = 0, the point's own without a label.
fn expected(p: &Point) -> usize {
    match p.m {
        Some(0) => 1,
        Some(_) => 2,
        None => p.multiplicity,
    }
    .max(p.multiplicity)
}

/// Groups the points of one mesh that are not `taken` into rungs (indices, the first point
/// first).
fn rungs(points: &[Point], floor: f64, taken: &[bool]) -> Vec<Vec<usize>> {
    let mut used = taken.to_vec();
    let mut out = Vec::new();
    for i in 0..points.len() {
        if used[i] {
            continue;
        }
        used[i] = true;
        let mut group = vec![i];
        let target = expected(&points[i]);
        let mut have = points[i].multiplicity;
        let v = points[i].value;
        while have < target {
            let next = (0..points.len())
                .filter(|&j| !used[j] && points[j].m == points[i].m && points[i].m.is_some())
                .filter(|&j| (points[j].value - v).abs() <= PAIR_TOLERANCE * v.abs() + floor)
                .min_by(|&a, &b| {
                    (points[a].value - v)
                        .abs()
                        .total_cmp(&(points[b].value - v).abs())
                });
            let Some(j) = next else { break };
            used[j] = true;
            have += points[j].multiplicity;
            group.push(j);
        }
        out.push(group);
    }
    out
}

/// The images of a rung (label m, value v, multiplicity `target`) among the unused points.
fn images(
    points: &[Point],
    used: &mut [bool],
    m: Option<usize>,
    v: f64,
    target: usize,
    floor: f64,
) -> Vec<usize> {
    let mut found = Vec::new();
    let mut have = 0;
    while have < target {
        let next = (0..points.len())
            .filter(|&j| !used[j] && points[j].m == m)
            .filter(|&j| (points[j].value - v).abs() <= MATCH_TOLERANCE * v.abs() + floor)
            .min_by(|&a, &b| {
                (points[a].value - v)
                    .abs()
                    .total_cmp(&(points[b].value - v).abs())
            });
        let Some(j) = next else { break };
        used[j] = true;
        have += points[j].multiplicity;
        found.push(j);
    }
    found.sort_by(|&a, &b| points[a].value.total_cmp(&points[b].value));
    found
}

/// The images of one rung on one mesh at one resolution, measured.
#[derive(Debug, Clone, Serialize)]
pub struct Image {
    /// The resolution of the run.
    pub resolution: usize,
    /// Indices into that run's `critical`.
    pub points: Vec<usize>,
    /// Their irreps.
    pub irreps: Vec<String>,
    /// Their control values, ascending.
    pub values: Vec<f64>,
    /// Their multiplicities, summed.
    pub multiplicity: usize,
    /// Spread of the values of two or more points; 0 for one point in a d ≥ 2 irrep (double by
    /// construction); absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gap: Option<f64>,
    /// Gap above round-off, for two or more points.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub split: Option<bool>,
    /// What the images say.
    pub verdict: Verdict,
}

/// What a rung's images on one mesh say.
#[derive(Debug, Clone, PartialEq)]
pub struct Verdict {
    /// The measurement.
    pub kind: VerdictKind,
    /// Fewer images than the rung's multiplicity were found in range.
    pub missing: Option<Missing>,
}

/// The measurement of a rung's images.
#[derive(Debug, Clone, PartialEq)]
pub enum VerdictKind {
    /// No image in range.
    NotFound,
    /// One point of a d ≥ 2 irrep: a multiple point by construction.
    Multiple {
        /// Its kind.
        kind: CriticalKind,
        /// Its irrep.
        irrep: String,
    },
    /// One simple point.
    Single(CriticalKind),
    /// Two or more points at exactly the same value.
    NotSplitZero,
    /// Two or more points whose gap is within the localisation's uncertainty.
    NotSplitRoundOff {
        /// The uncertainty.
        precision: f64,
    },
    /// Two or more points whose gap exceeds the localisation's uncertainty.
    Split,
}

/// Which images were not found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Missing {
    /// The partner of a lone simple point.
    Partner,
    /// Some other image.
    Image,
}

impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.kind {
            VerdictKind::NotFound => f.write_str("not found")?,
            VerdictKind::Multiple { kind, irrep } => write!(f, "not split: {kind} in {irrep}")?,
            VerdictKind::Single(kind) => write!(f, "{kind}")?,
            VerdictKind::NotSplitZero => f.write_str("not split (gap 0)")?,
            VerdictKind::NotSplitRoundOff { precision } => {
                write!(f, "not split (gap at round-off, +-{})", sci(*precision))?
            }
            VerdictKind::Split => f.write_str("split")?,
        }
        match self.missing {
            Some(Missing::Partner) => f.write_str("; partner not found in range"),
            Some(Missing::Image) => f.write_str("; an image not found in range"),
            None => Ok(()),
        }
    }
}

impl Serialize for Verdict {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

fn measure(points: &[Point], found: Vec<usize>, target: usize, resolution: usize) -> Image {
    let values: Vec<f64> = found.iter().map(|&j| points[j].value).collect();
    let irreps: Vec<String> = found.iter().map(|&j| points[j].irrep.clone()).collect();
    let multiplicity: usize = found.iter().map(|&j| points[j].multiplicity).sum();
    let (gap, split, kind) = match found.as_slice() {
        [] => (None, None, VerdictKind::NotFound),
        [j] if points[*j].multiplicity >= 2 => (
            Some(0.0),
            None,
            VerdictKind::Multiple {
                kind: points[*j].kind,
                irrep: points[*j].irrep.clone(),
            },
        ),
        [j] => (None, None, VerdictKind::Single(points[*j].kind)),
        _ => {
            let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let gap = hi - lo;
            let scale = values.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            // Resolved when the gap exceeds twice the summed uncertainties of the two ends
            // (or, without them, ROUND_OFF of the value).
            let ends = |x: f64| {
                found
                    .iter()
                    .filter(|&&j| points[j].value == x)
                    .map(|&j| points[j].precision)
                    .next()
                    .flatten()
            };
            let precision = match (ends(lo), ends(hi)) {
                (Some(a), Some(b)) => a + b,
                _ => ROUND_OFF * scale,
            };
            if gap == 0.0 {
                (Some(gap), Some(false), VerdictKind::NotSplitZero)
            } else if gap <= 2.0 * precision {
                (
                    Some(gap),
                    Some(false),
                    VerdictKind::NotSplitRoundOff { precision },
                )
            } else {
                (Some(gap), Some(true), VerdictKind::Split)
            }
        }
    };
    let missing = (!found.is_empty() && multiplicity < target).then_some(
        if found.len() == 1 && multiplicity == 1 {
            Missing::Partner
        } else {
            Missing::Image
        },
    );
    Image {
        resolution,
        points: found,
        irreps,
        values,
        multiplicity,
        gap,
        split,
        verdict: Verdict { kind, missing },
    }
}

/// A rung's images on one mesh, at each resolution, and the observed order of the gap.
#[derive(Debug, Clone, Serialize)]
pub struct MeshImages {
    /// The mesh's label.
    pub mesh: String,
    /// One per resolution.
    pub levels: Vec<Image>,
    /// log2(gap_coarse / gap_fine) when both resolutions split the rung.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub order: Option<f64>,
}

/// A rung of the reference mesh.
#[derive(Debug, Clone, Serialize)]
pub struct Rung {
    /// The wave number about z.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub m: Option<usize>,
    /// The kinds of its points on the reference mesh.
    pub kind: RungKind,
    /// Their irreps.
    pub irreps: Vec<String>,
    /// Their control values.
    pub values: Vec<f64>,
    /// Their multiplicities, summed.
    pub multiplicity: usize,
    /// The reference's resolution where the rung was found (its first, or the refined one).
    pub found_at: usize,
    /// The images on every mesh, the reference first.
    pub images: Vec<MeshImages>,
}

/// The kinds of a rung's points: one kind, or several joined by `+`.
#[derive(Debug, Clone, PartialEq)]
pub struct RungKind(pub Vec<CriticalKind>);

impl std::fmt::Display for RungKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.0.as_slice() {
            [first, rest @ ..] if rest.iter().all(|k| k == first) => write!(f, "{first}"),
            kinds => {
                let names: Vec<String> = kinds.iter().map(|k| k.to_string()).collect();
                f.write_str(&names.join(" + "))
            }
        }
    }
}

impl Serialize for RungKind {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
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

/// Matches every mesh's points to the reference's rungs: those of its first resolution, then
/// (with `--refine`) those of its refined run that the first did not have.
fn match_rungs(meshes: &[MeshRuns], floor: f64) -> (Vec<Rung>, Vec<Unmatched>) {
    // Used points per (mesh, level).
    let mut used: Vec<Vec<Vec<bool>>> = meshes
        .iter()
        .map(|m| {
            m.levels
                .iter()
                .map(|l| vec![false; l.critical.len()])
                .collect()
        })
        .collect();
    let mut out = Vec::new();
    for source in 0..meshes[0].levels.len() {
        let groups = rungs(&meshes[0].levels[source].critical, floor, &used[0][source]);
        for group in &groups {
            out.push(rung(meshes, &mut used, source, group, floor));
        }
    }
    let mut unmatched = Vec::new();
    for (k, mesh) in meshes.iter().enumerate() {
        for (l, level) in mesh.levels.iter().enumerate() {
            for (i, p) in level.critical.iter().enumerate() {
                if !used[k][l][i] {
                    unmatched.push(Unmatched {
                        mesh: mesh.label.clone(),
                        resolution: level.resolution,
                        point: i,
                        irrep: p.irrep.clone(),
                        value: p.value,
                        m: p.m,
                    });
                }
            }
        }
    }
    (out, unmatched)
}

/// The rung `group` of the reference's level `source` with its images on every mesh.
fn rung(
    meshes: &[MeshRuns],
    used: &mut [Vec<Vec<bool>>],
    source: usize,
    group: &[usize],
    floor: f64,
) -> Rung {
    let reference = &meshes[0].levels[source].critical;
    let first = &reference[group[0]];
    let m = first.m;
    let multiplicity: usize = group.iter().map(|&i| reference[i].multiplicity).sum();
    let target = multiplicity.max(expected(first));
    let v = group.iter().map(|&i| reference[i].value).sum::<f64>() / group.len() as f64;
    let mut sorted = group.to_vec();
    sorted.sort_by(|&a, &b| reference[a].value.total_cmp(&reference[b].value));
    let mut all = Vec::new();
    for (k, mesh) in meshes.iter().enumerate() {
        let mut levels = Vec::new();
        for (l, level) in mesh.levels.iter().enumerate() {
            let found = if k == 0 && l == source {
                for &i in &sorted {
                    used[0][source][i] = true;
                }
                sorted.clone()
            } else {
                images(&level.critical, &mut used[k][l], m, v, target, floor)
            };
            levels.push(measure(&level.critical, found, target, level.resolution));
        }
        let order = match levels.as_slice() {
            [a, b] => match (a.split, b.split, a.gap, b.gap) {
                (Some(true), Some(true), Some(ga), Some(gb)) => Some((ga / gb).log2()),
                _ => None,
            },
            _ => None,
        };
        all.push(MeshImages {
            mesh: mesh.label.clone(),
            levels,
            order,
        });
    }
    Rung {
        m,
        kind: RungKind(sorted.iter().map(|&i| reference[i].kind).collect()),
        irreps: sorted.iter().map(|&i| reference[i].irrep.clone()).collect(),
        values: sorted.iter().map(|&i| reference[i].value).collect(),
        multiplicity,
        found_at: meshes[0].levels[source].resolution,
        images: all,
    }
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
    let mut jobs: Vec<(usize, usize, Study)> = Vec::new();
    let mut first_scene: Option<Scene> = None;
    for (k, t) in typed.iter().enumerate() {
        let coarse = variant(scene, t, &common)?;
        for l in 0..levels {
            let mut s = coarse.clone();
            if l == 1 {
                match &mut s.mesh {
                    MeshSpec::Disc(d) => d.divisions *= 2,
                    MeshSpec::Icosphere(i) => i.frequency *= 2,
                    MeshSpec::TruncatedSphere(t) => {
                        t.divisions = Some(t.divisions_or_default() * 2)
                    }
                    MeshSpec::File(_) => {
                        return Err(CompareError::Input(format!(
                            "mesh '{}': --refine cannot refine a mesh file",
                            t.label
                        )))
                    }
                }
            }
            let study = Study::build(s).map_err(|e| match e {
                StudyError::Scene(_) | StudyError::Unsupported(_) => {
                    CompareError::Input(one_line(&e.to_string()))
                }
            })?;
            super::check_real_irreps(&study, &format!("mesh '{}'", t.label))
                .map_err(CompareError::Input)?;
            jobs.push((k, l, study));
        }
        if k == 0 {
            first_scene = Some(coarse);
        }
    }
    let reference_scene = first_scene.expect("at least one mesh");
    // The largest meshes first, so that the parallel runs end together.
    jobs.sort_by_key(|(_, _, s)| std::cmp::Reverse(s.basis.unknowns()));
    let results: Vec<Result<(usize, usize, Level), CompareError>> = jobs
        .into_par_iter()
        .map(|(k, l, study)| execute(&typed[k].label, study, progress).map(|r| (k, l, r)))
        .collect();
    let mut meshes: Vec<MeshRuns> = typed
        .iter()
        .map(|t| MeshRuns {
            label: t.label.clone(),
            generator: String::new(),
            levels: Vec::new(),
        })
        .collect();
    let mut slots: Vec<Vec<Option<Level>>> = vec![vec![None; levels]; typed.len()];
    for r in results {
        let (k, l, level) = r?;
        slots[k][l] = Some(level);
    }
    for (k, s) in slots.into_iter().enumerate() {
        meshes[k].levels = s.into_iter().map(|l| l.expect("every job ran")).collect();
        meshes[k].generator = meshes[k].levels[0]
            .mesh
            .split_whitespace()
            .next()
            .unwrap_or("")
            .to_string();
    }
    let p = &reference_scene.parameters[&control];
    let range = match (p.min, p.max) {
        (Some(lo), Some(hi)) => Some([lo, hi]),
        _ => None,
    };
    let floor = range.map_or(1e-12, |[lo, hi]| 1e-3 * (hi - lo).abs());
    let (rung_list, unmatched) = match_rungs(&meshes, floor);
    let samples = match &reference_scene.analysis {
        Analysis::LinearBuckling(b) => Some(b.samples),
        Analysis::Path(p) => Some(p.steps),
        Analysis::Equilibrium(_) => None,
    };
    Ok(Comparison {
        scene: scene.info.name.clone(),
        origin: scene.origin.clone(),
        analysis: reference_scene.analysis.kind().name(),
        control,
        range,
        samples,
        label: labelled(&reference_scene).then_some("m"),
        refine: options.refine,
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
        };
        let meshes = vec![
            MeshRuns {
                label: "C8v".into(),
                generator: "disc".into(),
                levels: vec![level(reference)],
            },
            MeshRuns {
                label: "C2v".into(),
                generator: "disc".into(),
                levels: vec![level(other)],
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
