//! Every output of a run, written into its directory in one call: [`write_run`].

use super::Drawing;
use super::{
    default_axes, write_csv, write_diagram_with, write_json, write_spectrum_diagram_with, Diagram,
    Marker, MarkerKind, OutputError, PvdTime, StateWriter, SPECTRUM_AXIS,
};
use crate::results::{
    CriticalKind, Extremum, PathReport, RunResult, StateKind, StopReason, Wrinkling,
};
use crate::scene::Scene;
use std::path::{Path, PathBuf};

/// The files every run writes into its directory, besides its states.
pub const RUN_FILES: [&str; 9] = [
    "path.csv",
    "path.states",
    "path.json",
    "critical.json",
    "critical.states",
    "path.svg",
    "path.png",
    "path.pvd",
    "events.pvd",
];

/// What [`write_run`] wrote.
#[derive(Debug, Clone)]
pub struct Written {
    /// `path.csv`.
    pub csv: PathBuf,
    /// `path.json`.
    pub json: PathBuf,
    /// `critical.json`.
    pub critical: PathBuf,
    /// `critical.states`: every critical point's state and mode, binary.
    pub critical_states: PathBuf,
    /// `path.svg`.
    pub svg: PathBuf,
    /// `path.png`: the same figure as an image.
    pub png: PathBuf,
    /// What the SVG shows, in words.
    pub plotted: String,
    /// `path.pvd`.
    pub pvd: PathBuf,
    /// `events.pvd`: the turning and critical states.
    pub events: PathBuf,
    /// `path.states`: every path point's state (none for a branch).
    pub points: Option<PathBuf>,
    /// The state files, in the order written, each critical state's mode figures
    /// (`critical_NN_mode.svg`, `.png`) after it.
    pub states: Vec<PathBuf>,
    /// The analysis' own files (a critical curve's `curve.csv`, `curve.json`, `curve.svg`; a
    /// surface's `surface.vtu`, `surface.json`, `surface.svg`), each with what it holds.
    pub own: Vec<Described>,
    /// The branches' files, when the run has branches.
    pub branches: Option<super::BranchesWritten>,
    /// `manifest.json`, written last.
    pub manifest: PathBuf,
}

impl Written {
    /// Every file, in the order of the run's summary.
    pub fn files(&self) -> Vec<PathBuf> {
        let mut files = vec![
            self.csv.clone(),
            self.json.clone(),
            self.critical.clone(),
            self.critical_states.clone(),
            self.svg.clone(),
            self.png.clone(),
            self.pvd.clone(),
            self.events.clone(),
        ];
        files.extend(self.points.clone());
        files.extend(self.states.iter().cloned());
        files.extend(self.own.iter().map(|d| d.path.clone()));
        if let Some(b) = &self.branches {
            files.extend(b.files.iter().cloned());
        }
        files.push(self.manifest.clone());
        files
    }
}

/// Why writing a run's outputs stopped: the error, and the files already written.
#[derive(Debug, thiserror::Error)]
#[error("{error}; {}", already(.dir, .done))]
pub struct WriteRunError {
    /// What failed (it names the file).
    pub error: OutputError,
    /// The files written before it (every file the writing left in `dir`).
    pub done: Vec<PathBuf>,
    /// The directory written into: the files are named by their paths in it.
    pub dir: PathBuf,
}

fn already(dir: &Path, done: &[PathBuf]) -> String {
    if done.is_empty() {
        "nothing else was written".to_string()
    } else {
        let names: Vec<String> = done
            .iter()
            .map(|p| super::manifest::relative(dir, p))
            .collect();
        format!("already written: {}", names.join(", "))
    }
}

/// The error of a run's writing into `out` that stopped at `error`: the files written before
/// it (`done`), and every other file under `out` that the writing changed since `since` — a
/// collection rewritten after each state (`path.pvd`), the files of an analysis' own writer
/// or of a branch directory written before the one that failed —, so that the message names
/// every file it left. Its own temporary and lock files are not named.
fn left_behind(
    error: OutputError,
    mut done: Vec<PathBuf>,
    out: &Path,
    since: std::time::SystemTime,
) -> WriteRunError {
    fn walk(dir: &Path, depth: usize, since: std::time::SystemTime, found: &mut Vec<PathBuf>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for e in entries.flatten() {
            let path = e.path();
            let Ok(meta) = e.metadata() else { continue };
            if meta.is_dir() {
                if depth > 0 {
                    walk(&path, depth - 1, since, found);
                }
                continue;
            }
            let ours = e.file_name().to_string_lossy().starts_with(".memstab");
            if !ours && meta.is_file() && meta.modified().is_ok_and(|m| m >= since) {
                found.push(path);
            }
        }
    }
    let mut found = Vec::new();
    // Branch directories (branch_NN/) lie one level down, their own branches one more.
    walk(out, 3, since, &mut found);
    found.sort();
    for f in found {
        if !done.contains(&f) && f != error.path() {
            done.push(f);
        }
    }
    WriteRunError {
        error,
        done,
        dir: out.to_path_buf(),
    }
}

/// The file name of a path, for messages.
pub fn file_name(p: &Path) -> String {
    p.file_name().map_or_else(
        || p.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// Writes `path.csv`, `path.states` (every point's state), the states with `path.pvd`,
/// `path.json` (with the saved states, which it records in the report), `critical.json`,
/// `path.svg` and, last, `manifest.json` into `out`, in that order, after removing the old
/// manifest and the temporary files a killed run left there.
///
/// Path states go into the collection (PVD time = path step: ParaView orders datasets by
/// time, and along a path that turns back in the control — a balloon past its pressure
/// maximum — the control would not follow the path). Turning and critical points are written
/// beside it under their own names; critical states carry their mode.
pub fn write_run(
    drawing: &dyn Drawing,
    scene: &Scene,
    result: &mut RunResult,
    out: &Path,
) -> Result<Written, WriteRunError> {
    write_run_with(drawing, scene, result, out, &[], &|_, _| Ok(Vec::new()))
}

/// A file an analysis wrote, with what it holds (for the run's summary).
#[derive(Debug, Clone, PartialEq)]
pub struct Described {
    /// The file.
    pub path: PathBuf,
    /// What it holds, in words.
    pub what: String,
}

impl Described {
    /// The `files` written, each with its description in `what` (in the same order).
    pub fn each(files: Vec<PathBuf>, what: impl IntoIterator<Item = String>) -> Vec<Described> {
        files
            .into_iter()
            .zip(what)
            .map(|(path, what)| Described { path, what })
            .collect()
    }
}

/// The writer of an analysis' own files: the finished run and the directory → the files
/// written.
pub type OwnFiles<'a> = dyn Fn(&RunResult, &Path) -> Result<Vec<Described>, OutputError> + 'a;

/// As [`write_run`], with an analysis' `curve_events` after the path's critical points in
/// `critical.json` and its `own` files written after the path diagram.
pub fn write_run_with(
    drawing: &dyn Drawing,
    scene: &Scene,
    result: &mut RunResult,
    out: &Path,
    curve_events: &[crate::results::CurveEvent],
    own: &OwnFiles<'_>,
) -> Result<Written, WriteRunError> {
    let mut done: Vec<PathBuf> = Vec::new();
    super::sweep_temporaries(out);
    // A second back, for file systems whose times are coarser than the clock.
    let since = std::time::SystemTime::now() - std::time::Duration::from_secs(1);
    macro_rules! attempt {
        ($e:expr) => {
            match $e {
                Ok(v) => v,
                Err(error) => return Err(left_behind(error, done, out, since)),
            }
        };
    }
    attempt!(super::remove_manifest(out));
    let csv = attempt!(write_csv(out, &result.report));
    done.push(csv.clone());
    // A path solved in the scene's fixed-point space saves every point's state; a branch
    // (solved in a subgroup's space) saves none, and its path.json names no states file.
    let points = if result.points.len() == result.report.rows.len() && !result.points.is_empty() {
        let (points, info) = attempt!(super::store::write_states(
            out,
            &result.points,
            result.report.parameters.len(),
            drawing.unknowns(),
            |q, u| u.copy_from_slice(&drawing.expand(q)),
        ));
        result.report.states = Some(info);
        Some(points)
    } else {
        None
    };
    done.extend(points.clone());
    let mut writer = attempt!(StateWriter::new(out, drawing.mesh())).with_time(PvdTime::Step);
    let mut states: Vec<PathBuf> = Vec::new();
    let (mut turning, mut critical) = (0usize, 0usize);
    for s in &result.states {
        let (positions, fields) = drawing.draw(s);
        // A critical state's mode, drawn once its state is written.
        let mut pending: Option<(String, Vec<[f64; 3]>)> = None;
        let label = s.label();
        let saved = match (&s.kind, &s.mode) {
            (StateKind::Step, _) => writer.save(s.step, s.control, &positions, fields),
            (StateKind::Critical { .. }, Some(_)) => {
                critical += 1;
                let stem = format!("critical_{critical:02}");
                pending = fields
                    .point
                    .iter()
                    .find_map(|f| match (&f.name[..], &f.data) {
                        ("critical_mode", meshes::write::FieldData::Vector(v)) => Some(v.clone()),
                        _ => None,
                    })
                    .map(|m| (stem.clone(), m));
                writer.save_as(&stem, &label, false, s.step, s.control, &positions, fields)
            }
            // The held state of a linear-buckling sweep is the state of every sample: the
            // path collection's one dataset.
            (StateKind::Held, _) => writer.save_as(
                "held_state",
                &label,
                true,
                s.step,
                s.control,
                &positions,
                fields,
            ),
            (StateKind::Turning(_) | StateKind::Critical { .. }, _) => {
                // File names without spaces.
                let stem: String = label
                    .chars()
                    .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
                    .collect();
                let name = if let StateKind::Turning(_) = s.kind {
                    turning += 1;
                    format!("turning_{turning:02}_{stem}")
                } else {
                    stem
                };
                writer.save_as(&name, &label, false, s.step, s.control, &positions, fields)
            }
        };
        let saved = attempt!(saved);
        let path = out.join(&saved.file);
        if !states.contains(&path) {
            states.push(path.clone());
            done.push(path);
        }
        if let Some((stem, mode)) = pending {
            let files = attempt!(mode_figure(
                out, &stem, drawing, s, &positions, &mode, result
            ));
            done.extend(files.iter().cloned());
            states.extend(files);
        }
    }
    let pvd = writer.pvd_path();
    let events = writer.events_path();
    result.report.saved = attempt!(writer.finish());
    done.push(pvd.clone());
    done.push(events.clone());

    let json = attempt!(write_json(out, &result.report));
    done.push(json.clone());
    let critical_json = attempt!(super::write_critical_with(
        out,
        &result.report,
        curve_events
    ));
    done.push(critical_json.clone());
    let critical_states = attempt!(super::store::write_critical_states(
        out,
        &result.report.critical
    ));
    done.push(critical_states.clone());
    let report = &result.report;
    let (svg, plotted) = if report.spectra.is_empty() {
        let axes = axes(report);
        let svg = write_diagram_with(out, report, &diagram(scene, report, &axes));
        let plotted = format!("{} against {}, turning points marked", axes.1, axes.0);
        (svg, plotted)
    } else {
        let skipped: Vec<&str> = report
            .spectra
            .irreps
            .iter()
            .filter(|i| !i.eigenvalues)
            .map(|i| i.name.as_str())
            .collect();
        let skipped = if skipped.is_empty() {
            String::new()
        } else {
            format!(" ({} not plotted: no eigenvalues)", skipped.join(", "))
        };
        let plotted = format!(
            "{SPECTRUM_AXIS} per irrep against {}{skipped}, critical points marked",
            report.control
        );
        let scale = super::Scales::of(scene, report).or_name(&report.control);
        let rungs = ponding_floor(scene, report);
        (
            write_spectrum_diagram_with(out, report, Some(&scale), rungs),
            plotted,
        )
    };
    let svg = attempt!(svg);
    done.push(svg.clone());
    let png = attempt!(super::write_png_beside(&svg));
    done.push(png.clone());
    let mut own = attempt!(own(result, out));
    if let Some(r) = &result.report.refinement {
        let path = attempt!(super::write_refine(out, r));
        let levels: Vec<String> = r.levels.iter().map(|l| l.resolution.to_string()).collect();
        own.push(Described {
            path,
            what: format!(
                "the critical and turning points{} at resolution {}: values, order, \
                 Richardson, error and wall time per level",
                if r.events.is_empty() {
                    ""
                } else {
                    " and the curve's events"
                },
                levels.join(", ")
            ),
        });
    }
    done.extend(own.iter().map(|d| d.path.clone()));
    let branches = match &result.branches {
        Some(b) => {
            let primary = crate::results::PrimaryPath::of(&result.report);
            match super::write_branches(drawing, scene, b, &primary, out) {
                Ok(w) => {
                    done.extend(w.files.iter().cloned());
                    Some(w)
                }
                Err(mut e) => {
                    done.append(&mut e.done);
                    return Err(left_behind(e.error, done, out, since));
                }
            }
        }
        None => None,
    };
    let manifest = attempt!(super::write_manifest(out, &done, &result.report.stop));
    Ok(Written {
        csv,
        json,
        critical: critical_json,
        critical_states,
        svg,
        png,
        plotted,
        pvd,
        events,
        points,
        states,
        own,
        branches,
        manifest,
    })
}

/// The most triangles a mode figure draws: a vector figure of more (a revolved meridian's
/// surface) takes megabytes per mode, and the VTU beside it shows the mode better.
pub const MODE_FIGURE_TRIANGLES: usize = 25_000;

/// `<stem>_mode.svg` and `.png` of the critical state `s` drawn at `positions` with its mode
/// `mode` (the point field `critical_mode`): titled with the critical point's kind, irrep,
/// isotropy and wave number where the report has them. None for a mesh of more than
/// [`MODE_FIGURE_TRIANGLES`] triangles.
fn mode_figure(
    out: &Path,
    stem: &str,
    drawing: &dyn Drawing,
    s: &crate::results::State,
    positions: &[meshes::Vec3],
    mode: &[[f64; 3]],
    result: &RunResult,
) -> Result<Vec<PathBuf>, OutputError> {
    if drawing.mesh().triangles.len() > MODE_FIGURE_TRIANGLES {
        return Ok(Vec::new());
    }
    let report = &result.report;
    let k = report
        .critical
        .iter()
        .position(|cp| cp.parameters == s.params);
    let title = match k.map(|k| (&report.critical[k], report.wave_numbers.get(k))) {
        Some((cp, m)) => {
            let m = m.map_or_else(String::new, |m| format!(", m = {m}"));
            format!(
                "mode of the {} in {}{m}, isotropy {}",
                cp.kind, cp.irrep, cp.isotropy.name
            )
        }
        None => format!("mode of the {}", s.label()),
    };
    super::mode::write_mode(
        out,
        stem,
        (positions, &drawing.mesh().triangles),
        mode,
        &title,
        &super::caption_of(report),
    )
}

/// The unit normal at each node of the surface at positions `x`: the sum of its triangles'
/// area vectors (a × b / 2, the triangles' orientation), normalised; a node of no triangle or
/// of a degenerate neighbourhood gets 0.
pub fn node_normals(x: &[meshes::Vec3], triangles: &[[usize; 3]]) -> Vec<[f64; 3]> {
    let mut n = vec![meshes::Vec3::zeros(); x.len()];
    for &[a, b, c] in triangles {
        let area = (x[b] - x[a]).cross(&(x[c] - x[a])) / 2.0;
        for i in [a, b, c] {
            n[i] += area;
        }
    }
    n.iter()
        .map(|v| {
            let norm = v.norm();
            if norm > 0.0 && norm.is_finite() {
                (v / norm).into()
            } else {
                [0.0; 3]
            }
        })
        .collect()
}

/// The diagram: the path drawn by instability index (a colour and line style per index, the
/// change of index at the critical point), turning points and critical points marked (a
/// critical point's label with its wave number where known: `(m, k)` on a ponding floor,
/// the k-th rung of wave number m), the axes dimensionless where the scene fixes the scale,
/// and the closed form of a balloon under it.
fn diagram(scene: &Scene, report: &PathReport, axes: &(String, String)) -> Diagram {
    // A critical point at a turning point of the control (a limit point) shares its marker.
    let control = report.parameters.iter().position(|p| *p == report.control);
    let same = |a: &[f64], b: &[f64]| {
        control.is_some_and(|c| (a[c] - b[c]).abs() <= 1e-6 * a[c].abs().max(1e-12))
    };
    let ponding = ponding_floor(scene, report);
    let mut rung = std::collections::BTreeMap::<usize, usize>::new();
    let labels: Vec<String> = report
        .critical
        .iter()
        .enumerate()
        .map(|(k, cp)| {
            let base = format!("{} {}", cp.kind.short(), cp.irrep);
            match report.wave_numbers.get(k) {
                Some(&m) if ponding => {
                    let n = rung.entry(m).or_insert(0);
                    *n += 1;
                    format!("{base} (m, k) = ({m}, {n})")
                }
                Some(&m) => format!("{base} m = {m}"),
                None => base,
            }
        })
        .collect();
    let scales = super::Scales::of(scene, report);
    // The turning points' values read off the control's axis when it is the vertical one.
    let control_axis = (axes.1 == report.control).then(|| scales.or_name(&report.control));
    let mut markers: Vec<Marker> = Vec::new();
    for t in &report.turning_points {
        let mut m = Marker::turning_scaled(report, t, control_axis.as_ref());
        if let Some(k) = report
            .critical
            .iter()
            .position(|cp| same(&cp.parameters, &t.parameters))
        {
            m.label = format!("{} ({})", m.label, labels[k]);
            m.switches = true;
        }
        markers.push(m);
    }
    for (cp, label) in report.critical.iter().zip(&labels) {
        if report
            .turning_points
            .iter()
            .any(|t| same(&cp.parameters, &t.parameters))
        {
            continue;
        }
        markers.push(Marker {
            parameters: cp.parameters.clone(),
            measures: cp.measures.clone(),
            label: label.clone(),
            kind: match cp.kind {
                CriticalKind::LimitPoint => MarkerKind::Other,
                CriticalKind::SymmetricBifurcation
                | CriticalKind::SimpleBifurcation
                | CriticalKind::MultipleBifurcation(_) => MarkerKind::Bifurcation,
            },
            after_step: Some(cp.after_step),
            switches: true,
        });
    }
    let mut d = Diagram::new(&axes.0, &axes.1)
        .markers(markers)
        .scales(scales.or_name(&axes.0), scales.or_name(&axes.1));
    d.turning_points = false;
    d.quantities = report
        .parameters
        .iter()
        .chain(&report.measures)
        .map(|q| super::QuantityScale::new(q, &scales.or_name(q)))
        .collect();
    if axes.0 == "stretch" && axes.1 == report.control {
        if let Some(curve) = super::balloon_closed_form(scene, report) {
            d = d.reference(curve);
        }
    }
    if report.rows.iter().any(|r| r.index.is_some()) {
        d.by_index()
    } else {
        d
    }
}

/// True for a ponding floor: a disc under fluid whose density is the control, where the
/// k-th critical point of wave number m is the rung j_{m,k} of the ladder.
fn ponding_floor(scene: &Scene, report: &PathReport) -> bool {
    use crate::scene::{FluidEffect, MeshSpec};
    let disc = match &scene.mesh {
        MeshSpec::Disc(_) => true,
        MeshSpec::Axisymmetric(a) => a.shape == crate::scene::AxisymShape::Disc,
        _ => false,
    };
    disc && scene.effects.iter().any(|e| {
        e.get::<FluidEffect>()
            .is_some_and(|f| f.density.parameter() == Some(report.control.as_str()))
    })
}

/// The diagram's axes: [`default_axes`], except that an equilibrium analysis (no control)
/// plots its first parameter (or, with none, a second measure) instead of the empty control.
fn axes(report: &PathReport) -> (String, String) {
    let (x, y) = default_axes(report);
    if !y.is_empty() {
        return (x, y);
    }
    let y = report
        .parameters
        .first()
        .or_else(|| report.measures.iter().find(|m| **m != x))
        .cloned()
        .unwrap_or_else(|| x.clone());
    (x, y)
}

/// A turning point in [`RunSummary`].
#[derive(Debug, serde::Serialize)]
pub struct TurningSummary {
    /// `maximum` or `minimum`.
    pub kind: Extremum,
    /// The path step before it.
    pub step: usize,
    /// The control's value there.
    pub value: f64,
    /// The stretch there (closed membranes).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stretch: Option<f64>,
    /// No flag raised.
    pub valid: bool,
    /// Why it may not be a result of the model or the mesh.
    pub flags: Vec<crate::results::validity::Flag>,
}

/// A critical point in [`RunSummary`].
#[derive(Debug, serde::Serialize)]
pub struct CriticalSummary {
    /// Its kind.
    pub kind: CriticalKind,
    /// The irrep of the singular block.
    pub irrep: String,
    /// Multiplicity of the zero eigenvalue in K.
    pub multiplicity: usize,
    /// The path step before it.
    pub step: usize,
    /// The control's value there.
    pub value: f64,
    /// The isotropy subgroup of the mode.
    pub isotropy: String,
    /// The mode's wave number about z, where the mesh has an axis.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub m: Option<usize>,
    /// No flag raised: a result of the model as it stands.
    pub valid: bool,
    /// Why it may not be.
    pub flags: Vec<crate::results::validity::Flag>,
}

/// What `memstab run --json` prints: the run in one object.
#[derive(Debug, serde::Serialize)]
pub struct RunSummary {
    /// The scene's name.
    pub scene: String,
    /// The output directory.
    pub out: PathBuf,
    /// Every file written.
    pub files: Vec<PathBuf>,
    /// Path points.
    pub points: usize,
    /// The control parameter.
    pub control: String,
    /// Turning points of the control.
    pub turning_points: Vec<TurningSummary>,
    /// Why the path ended.
    pub stop: StopReason,
    /// The scene's group.
    pub group: String,
    /// Its order.
    pub group_order: usize,
    /// Unknowns of the fixed-point space.
    pub symmetric_unknowns: usize,
    /// Unknowns of the model.
    pub unknowns: usize,
    /// The critical points.
    pub critical: Vec<CriticalSummary>,
    /// Where the membrane wrinkles (left out when the model shows no `wrinkled` field).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wrinkling: Option<Wrinkling>,
    /// The number of branches followed, with `[analysis.branches]` (left out otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub branches: Option<usize>,
    /// The points on the refined meshes, with `--refine` (left out otherwise; as
    /// `refine.json`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refinement: Option<crate::results::refine::Refinement>,
}

impl RunSummary {
    /// The summary of `report`, written into `out` as `written` says.
    pub fn new(report: &PathReport, out: &Path, written: &Written) -> Self {
        let s = report.measures.iter().position(|m| m == "stretch");
        let c = report.parameters.iter().position(|p| *p == report.control);
        Self {
            scene: report.scene.clone(),
            out: out.to_path_buf(),
            files: written.files(),
            points: report.rows.len(),
            control: report.control.clone(),
            turning_points: report
                .turning_points
                .iter()
                .enumerate()
                .map(|(k, t)| TurningSummary {
                    kind: t.kind,
                    step: t.after_step,
                    value: c.map_or(f64::NAN, |c| t.parameters[c]),
                    stretch: s.map(|s| t.measures[s]),
                    valid: report.turning_flags(k).is_empty(),
                    flags: report.turning_flags(k),
                })
                .collect(),
            critical: report
                .critical
                .iter()
                .enumerate()
                .map(|(k, cp)| CriticalSummary {
                    kind: cp.kind,
                    irrep: cp.irrep.clone(),
                    multiplicity: cp.multiplicity,
                    step: cp.after_step,
                    value: c.map_or(f64::NAN, |c| cp.parameters[c]),
                    isotropy: cp.isotropy.name.clone(),
                    m: report.wave_numbers.get(k).copied(),
                    valid: report.flags(k).is_empty(),
                    flags: report.flags(k),
                })
                .collect(),
            wrinkling: report.wrinkling.clone(),
            stop: report.stop.clone(),
            group: report.group.clone(),
            group_order: report.group_order,
            symmetric_unknowns: report.symmetric_unknowns,
            unknowns: report.unknowns,
            branches: written.branches.as_ref().map(|b| b.directories.len()),
            refinement: report.refinement.clone(),
        }
    }
}
