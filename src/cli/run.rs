//! `memstab run SCENE --out DIR [--quiet] [--json]` and `memstab demo [--out DIR] [--quiet]`.
//!
//! Loads and validates a scene, builds the study (mesh, the scene's group, effects, model),
//! follows its path with a progress bar and writes into DIR: `path.csv`, `path.json`,
//! `path.svg`, and a `state_NNNN.vtu` per saved state with the collection `path.pvd`. The SVG
//! of a linear-buckling sweep plots the lowest eigenvalue of every irrep block against the
//! control (the held state's measures are constant); every other analysis gets the path
//! diagram.
//!
//! Bad input — a scene that does not load or cannot be built, an `--out` whose parent does not
//! exist or that is not a directory — is one line and exit code 2, and nothing is written (not
//! even DIR). A start state that does not converge is exit code 1; DIR is then removed again if
//! this run created it, so nothing is left behind. A path that stops early (the step was cut
//! too small) is not a failure: its outputs are written and the reason printed.

use super::CliError;
use clap::Args;
use memstab::output::{
    default_axes, write_critical, write_csv, write_diagram_with, write_json,
    write_spectrum_diagram, Diagram, Marker, MarkerKind, OutputError, Progress, PvdTime, Segment,
    StateWriter, SPECTRUM_AXIS,
};
use memstab::report::PathReport;
use memstab::run::{run as run_study, RunResult};
use memstab::scene::{Effect, MeshSpec, Scene};
use memstab::study::{Study, StudyError};
use meshes::write::Fields;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The demo scene, bundled into the binary so that `memstab demo` works from anywhere.
const DEMO_SCENE: &str = include_str!("../../scenes/demo.toml");
/// How the bundled demo scene is named in messages and in `path.json`.
const DEMO_ORIGIN: &str = "scenes/demo.toml (bundled)";

#[derive(Debug, Args)]
pub(crate) struct RunArgs {
    /// The scene file (TOML; see docs/scenes.md).
    scene: PathBuf,
    /// Output directory; created if missing (its parent must exist).
    #[arg(long)]
    out: PathBuf,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
    /// Print one JSON object instead of the summary.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Args)]
pub(crate) struct DemoArgs {
    /// Output directory; created if missing (its parent must exist).
    #[arg(long, default_value = "memstab-demo")]
    out: PathBuf,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

/// A turning point in the `--json` summary.
#[derive(Debug, Serialize)]
struct TurningJson {
    kind: String,
    after_step: usize,
    /// The control's value there.
    value: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    stretch: Option<f64>,
}

/// The `--json` summary.
#[derive(Debug, Serialize)]
struct RunJson {
    scene: String,
    out: PathBuf,
    files: Vec<PathBuf>,
    points: usize,
    control: String,
    turning_points: Vec<TurningJson>,
    stop: String,
    group: String,
    group_order: usize,
    symmetric_unknowns: usize,
    unknowns: usize,
}

/// What a finished run wrote.
struct Written {
    csv: PathBuf,
    json: PathBuf,
    critical: PathBuf,
    svg: PathBuf,
    /// What the SVG shows, for the summary.
    plotted: String,
    pvd: PathBuf,
    states: Vec<PathBuf>,
}

impl Written {
    /// Every file, in the order written to the summary.
    fn files(&self) -> Vec<PathBuf> {
        let mut files = vec![
            self.csv.clone(),
            self.json.clone(),
            self.critical.clone(),
            self.svg.clone(),
            self.pvd.clone(),
        ];
        files.extend(self.states.iter().cloned());
        files
    }
}

pub(crate) fn run(args: &RunArgs) -> Result<(), CliError> {
    let scene = Scene::load(&args.scene).map_err(|e| CliError::Input(e.to_string()))?;
    let (study, result, written) = execute(scene, &args.out, args.quiet)?;
    if args.json {
        let json = summary_json(&study, &result.report, &args.out, &written);
        let text = serde_json::to_string(&json).map_err(|e| CliError::Failure(e.to_string()))?;
        println!("{text}");
    } else {
        print_summary(&study, &result.report, &args.out, &written);
    }
    Ok(())
}

pub(crate) fn demo(args: &DemoArgs) -> Result<(), CliError> {
    let scene = Scene::from_toml_str(DEMO_SCENE, DEMO_ORIGIN)
        .map_err(|e| CliError::Failure(format!("the bundled demo scene is broken: {e}")))?;
    let (study, result, written) = execute(scene, &args.out, args.quiet)?;
    print_summary(&study, &result.report, &args.out, &written);
    print_closed_form(&study, &result.report);
    Ok(())
}

/// Checks `out`, builds the study, creates `out`, runs and writes every output.
fn execute(scene: Scene, out: &Path, quiet: bool) -> Result<(Study, RunResult, Written), CliError> {
    check_out(out)?;
    let mut study = Study::build(scene).map_err(|e| match e {
        StudyError::Scene(_) | StudyError::Unsupported(_) => CliError::Input(e.to_string()),
    })?;
    let created = !out.exists();
    if created {
        std::fs::create_dir(out).map_err(|e| {
            CliError::Failure(format!(
                "cannot create the output directory '{}': {e}",
                out.display()
            ))
        })?;
    }
    let control = study
        .control
        .map_or_else(|| "control".to_string(), |c| study.parameters[c].clone());
    let total = match &study.scene.analysis {
        memstab::scene::Analysis::Path(p) => p.steps,
        _ => 1,
    };
    let progress = Progress::new(total, quiet);
    let result = run_study(&mut study, |step, value| {
        progress.set(step, format!("{control} = {}", sig(value)));
    });
    let result = match result {
        Ok(r) => r,
        Err(e) => {
            progress.finish("failed");
            // Leave nothing behind: remove DIR if this run made it (it is still empty).
            let removed = created && std::fs::remove_dir(out).is_ok();
            let left = if created && !removed {
                format!("; '{}' was created and is left empty", out.display())
            } else {
                String::new()
            };
            return Err(CliError::Failure(format!(
                "{}; nothing was written{left}",
                one_line(&e.to_string())
            )));
        }
    };
    progress.finish(format!("stopped: {}", result.report.stop));
    let mut result = result;
    let written = write_outputs(&study, &mut result, out)?;
    Ok((study, result, written))
}

/// `--out` must be a directory or not exist yet, and its parent must exist.
fn check_out(out: &Path) -> Result<(), CliError> {
    if out.exists() {
        if out.is_dir() {
            return Ok(());
        }
        return Err(CliError::Input(format!(
            "--out '{}' exists and is not a directory",
            out.display()
        )));
    }
    let parent = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !parent.is_dir() {
        return Err(CliError::Input(format!(
            "--out '{}': the parent directory '{}' does not exist",
            out.display(),
            parent.display()
        )));
    }
    Ok(())
}

/// Writes `path.csv`, the states with `path.pvd`, `path.json` (with the saved states) and
/// `path.svg`, in that order. An error names the file and what was already written.
fn write_outputs(study: &Study, result: &mut RunResult, out: &Path) -> Result<Written, CliError> {
    let mut done: Vec<PathBuf> = Vec::new();
    let fail = |e: OutputError, done: &[PathBuf]| {
        let already = if done.is_empty() {
            "nothing else was written".to_string()
        } else {
            let names: Vec<String> = done.iter().map(|p| file_name(p)).collect::<Vec<_>>();
            format!("already written: {}", names.join(", "))
        };
        CliError::Failure(format!("{}; {already}", one_line(&e.to_string())))
    };
    let csv = write_csv(out, &result.report).map_err(|e| fail(e, &done))?;
    done.push(csv.clone());

    // Path states go into the collection (PVD time = path step: ParaView orders datasets by
    // time, and along a path that turns back in the control — a balloon past its pressure
    // maximum — the control would not follow the path). Turning and critical points are
    // written beside it under their own names; critical states carry their mode.
    let mut writer = StateWriter::new(out, &study.mesh.mesh)
        .map_err(|e| fail(e, &done))?
        .with_time(PvdTime::Step);
    let mut states: Vec<PathBuf> = Vec::new();
    let (mut turning, mut critical) = (0usize, 0usize);
    for s in &result.states {
        let positions = study.model.positions(&s.u);
        let saved = if s.label.starts_with("step ") {
            writer.save(s.step, s.control, &positions, Fields::new())
        } else if let Some(mode) = &s.mode {
            critical += 1;
            let field: Vec<[f64; 3]> = study
                .model
                .positions(mode)
                .iter()
                .zip(study.model.reference())
                .map(|(x, x0)| (x - x0).into())
                .collect();
            let name = format!("critical_{critical:02}");
            writer.save_as(
                &name,
                &s.label,
                false,
                s.step,
                s.control,
                &positions,
                Fields::new().point_vector("critical_mode", field),
            )
        } else {
            // A turning point ("maximum", "minimum"), or the held state of a sweep; file
            // names without spaces.
            let stem: String = s
                .label
                .chars()
                .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
                .collect();
            let name = if matches!(s.label.as_str(), "maximum" | "minimum") {
                turning += 1;
                format!("turning_{turning:02}_{stem}")
            } else {
                stem
            };
            writer.save_as(
                &name,
                &s.label,
                false,
                s.step,
                s.control,
                &positions,
                Fields::new(),
            )
        }
        .map_err(|e| fail(e, &done))?;
        let path = out.join(&saved.file);
        if !states.contains(&path) {
            states.push(path.clone());
            done.push(path);
        }
    }
    let pvd = writer.pvd_path();
    result.report.saved = writer.finish().map_err(|e| fail(e, &done))?;
    done.push(pvd.clone());

    let json = write_json(out, &result.report).map_err(|e| fail(e, &done))?;
    done.push(json.clone());
    let critical_json = write_critical(out, &result.report).map_err(|e| fail(e, &done))?;
    done.push(critical_json.clone());
    let report = &result.report;
    let (svg, plotted) = if report.spectra.is_empty() {
        let axes = axes(report);
        let svg = write_diagram_with(out, report, &diagram(report, &axes));
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
        (write_spectrum_diagram(out, report), plotted)
    };
    let svg = svg.map_err(|e| fail(e, &done))?;
    Ok(Written {
        csv,
        json,
        critical: critical_json,
        svg,
        plotted,
        pvd,
        states,
    })
}

/// The diagram: stable (index 0) and unstable stretches of the path drawn differently, turning
/// points and critical points marked.
fn diagram(report: &PathReport, axes: &(String, String)) -> Diagram {
    let mut segments = Vec::new();
    let mut start = 0;
    for i in 1..=report.rows.len() {
        let stable = |k: usize| report.rows[k].index.is_none_or(|x| x == 0);
        if i == report.rows.len() || stable(i) != stable(start) {
            // Segments share their end rows so that the line is continuous.
            segments.push(Segment {
                first: start,
                last: i.min(report.rows.len() - 1),
                stable: stable(start),
            });
            start = i;
        }
    }
    // A critical point at a turning point of the control (a limit point) shares its marker.
    let control = report.parameters.iter().position(|p| *p == report.control);
    let same = |a: &[f64], b: &[f64]| {
        control.is_some_and(|c| (a[c] - b[c]).abs() <= 1e-6 * a[c].abs().max(1e-12))
    };
    let mut markers: Vec<Marker> = Vec::new();
    for t in &report.turning_points {
        let mut m = Marker::turning(report, t);
        if let Some(cp) = report
            .critical
            .iter()
            .find(|cp| same(&cp.parameters, &t.parameters))
        {
            m.label = format!("{} ({} {})", m.label, short_kind(&cp.kind), cp.irrep);
        }
        markers.push(m);
    }
    for cp in &report.critical {
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
            label: format!("{} {}", short_kind(&cp.kind), cp.irrep),
            kind: if cp.kind == "limit point" {
                MarkerKind::Other
            } else {
                MarkerKind::Bifurcation
            },
        });
    }
    let mut d = Diagram::new(&axes.0, &axes.1).markers(markers);
    d.turning_points = false;
    if report.rows.iter().any(|r| r.index.is_some()) && !report.rows.is_empty() {
        d.segments(segments)
    } else {
        d
    }
}

/// `limit`, `simple`, `double`, `3-fold` …
fn short_kind(kind: &str) -> &str {
    kind.split_whitespace().next().unwrap_or(kind)
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

fn file_name(p: &Path) -> String {
    p.file_name().map_or_else(
        || p.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// Joins the lines of a message into one.
fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// `x` with six significant digits, plain for moderate sizes (`1.35511`, `0.000123457`,
/// `1.23457e7`).
fn sig(x: f64) -> String {
    let a = x.abs();
    if a == 0.0 || !a.is_finite() {
        return format!("{x}");
    }
    let e = a.log10().floor() as i32;
    if (-4..6).contains(&e) {
        let decimals = (5 - e).max(0) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.5e}")
    }
}

/// The index of the measure `stretch`, if the report has it.
fn stretch_index(report: &PathReport) -> Option<usize> {
    report.measures.iter().position(|m| m == "stretch")
}

/// The index of the control among the parameters.
fn control_index(report: &PathReport) -> Option<usize> {
    report.parameters.iter().position(|p| *p == report.control)
}

fn summary_json(study: &Study, report: &PathReport, out: &Path, written: &Written) -> RunJson {
    let s = stretch_index(report);
    let c = control_index(report);
    RunJson {
        scene: report.scene.clone(),
        out: out.to_path_buf(),
        files: written.files(),
        points: report.rows.len(),
        control: report.control.clone(),
        turning_points: report
            .turning_points
            .iter()
            .map(|t| TurningJson {
                kind: t.kind.clone(),
                after_step: t.after_step,
                value: c.map_or(f64::NAN, |c| t.parameters[c]),
                stretch: s.map(|s| t.measures[s]),
            })
            .collect(),
        stop: report.stop.clone(),
        group: report.group.clone(),
        group_order: report.group_order,
        symmetric_unknowns: study.basis.dim(),
        unknowns: study.basis.unknowns(),
    }
}

fn print_summary(study: &Study, report: &PathReport, out: &Path, written: &Written) {
    let m = &report.mesh;
    println!("scene '{}' ({})", report.scene, report.origin);
    println!(
        "mesh: {} with {} nodes, {} triangles, group {} (order {})",
        m.generator, m.nodes, m.elements, m.group, m.order
    );
    println!(
        "scene group {} (order {}): solved in {} symmetric unknowns of {}",
        report.group,
        report.group_order,
        study.basis.dim(),
        study.basis.unknowns()
    );
    let c = control_index(report);
    let s = stretch_index(report);
    let n = report.rows.len();
    let points = if n == 1 {
        "1 point".to_string()
    } else {
        format!("{n} points")
    };
    match (c, report.rows.first(), report.rows.last()) {
        (Some(c), Some(first), Some(last)) if n > 1 => println!(
            "path: {points}, {} from {} to {}",
            report.control,
            sig(first.parameters[c]),
            sig(last.parameters[c])
        ),
        (Some(c), Some(first), _) => {
            println!(
                "path: {points}, {} = {}",
                report.control,
                sig(first.parameters[c])
            )
        }
        _ => println!("equilibrium: {points}"),
    }
    // A closed membrane with a negative enclosed volume has turned inside out: the numbers
    // are finite but not physical.
    if let Some(v) = report.measures.iter().position(|m| m == "volume") {
        if let Some(r) = report.rows.iter().find(|r| r.measures[v] <= 0.0) {
            println!(
                "warning: the enclosed volume is {} at step {}: the membrane is inside out there, \
                 the path is not physical",
                sig(r.measures[v]),
                r.step
            );
        }
    }
    if report.turning_points.is_empty() {
        if c.is_some() {
            println!("turning points of {}: none", report.control);
        }
    } else {
        println!("turning points of {}:", report.control);
        for t in &report.turning_points {
            let value = c.map_or_else(|| "?".to_string(), |c| sig(t.parameters[c]));
            let stretch = s.map_or_else(String::new, |s| {
                format!(" at stretch {}", sig(t.measures[s]))
            });
            println!(
                "  {:<7} {} = {value}{stretch} (after step {})",
                t.kind, report.control, t.after_step
            );
        }
    }
    for w in &report.warnings {
        println!("warning: {w}");
    }
    if let Some(note) = &report.stability_note {
        println!("{note}");
    } else if report.critical.is_empty() {
        println!(
            "critical points: none (the index stays {})",
            report.rows.first().and_then(|r| r.index).unwrap_or(0)
        );
    } else {
        println!("critical points (irrep of the singular block, multiplicity in K, isotropy of the mode):");
        for cp in &report.critical {
            let value = c.map_or_else(|| "?".to_string(), |c| sig(cp.parameters[c]));
            println!(
                "  {:<20} in {:<4} x{} at {} = {value} (isotropy {}, |eigenvalue|/|K| = {:.0e})",
                cp.kind,
                cp.irrep,
                cp.multiplicity,
                report.control,
                cp.isotropy.name,
                cp.residual_eigenvalue
            );
        }
    }
    println!("stopped: {}", report.stop);
    println!(
        "wrote {} files into {}:",
        written.files().len(),
        out.display()
    );
    let header = report
        .parameters
        .iter()
        .chain(&report.measures)
        .map(String::as_str)
        .collect::<Vec<_>>()
        .join(", ");
    println!(
        "  {:<10} {} rows: step, arclength, {header}, iterations",
        file_name(&written.csv),
        report.rows.len()
    );
    println!(
        "  {:<10} the report: metadata, path, turning points, critical points, saved states",
        file_name(&written.json)
    );
    println!(
        "  {:<10} {} critical points: kind, irrep, multiplicity, parameters, step",
        file_name(&written.critical),
        report.critical.len()
    );
    println!("  {:<10} {}", file_name(&written.svg), written.plotted);
    let in_collection = report.saved.iter().filter(|s| s.in_collection).count();
    println!(
        "  {:<10} ParaView collection of the {in_collection} path states (time = path step); turning and critical points beside it",
        file_name(&written.pvd),
    );
    for chunk in written.states.chunks(5) {
        let names: Vec<String> = chunk.iter().map(|p| file_name(p)).collect();
        println!("  {}", names.join(" "));
    }
}

/// The closed-form Mooney–Rivlin sphere: p R/(μH) = 2/(1+k)(λ⁻¹ − λ⁻⁷)(1 + kλ²).
fn sphere_pressure(k: f64, l: f64) -> f64 {
    2.0 / (1.0 + k) * (1.0 / l - l.powi(-7)) * (1.0 + k * l * l)
}

/// The stretches where the closed-form pressure has a maximum or minimum for λ in (1, 20),
/// each with `true` for a maximum.
fn sphere_extremes(k: f64) -> Vec<(f64, bool)> {
    // d/dλ of (λ⁻¹ − λ⁻⁷)(1 + kλ²) = −λ⁻² + 7λ⁻⁸ + k + 5kλ⁻⁶.
    let slope = |l: f64| -l.powi(-2) + 7.0 * l.powi(-8) + k + 5.0 * k * l.powi(-6);
    let mut found = Vec::new();
    let n = 20_000;
    let at = |i: usize| 1.0 + 19.0 * i as f64 / n as f64;
    for i in 1..n {
        let (mut a, mut b) = (at(i), at(i + 1));
        let (fa, fb) = (slope(a), slope(b));
        if fa == 0.0 || fa.signum() == fb.signum() {
            continue;
        }
        let maximum = fa > 0.0;
        for _ in 0..200 {
            let m = 0.5 * (a + b);
            if slope(m).signum() == fa.signum() {
                a = m;
            } else {
                b = m;
            }
        }
        found.push((0.5 * (a + b), maximum));
    }
    found
}

/// Compares the turning points of a balloon under pressure control with the closed form.
fn print_closed_form(study: &Study, report: &PathReport) {
    let scene = &study.scene;
    let MeshSpec::Icosphere(ico) = &scene.mesh else {
        return;
    };
    let (Some(c), Some(s)) = (control_index(report), stretch_index(report)) else {
        return;
    };
    // Only a balloon under pressure control: the control is the pressure of a gas effect.
    let pressure_control = scene.effects.iter().any(
        |e| matches!(e, Effect::Gas(g) if g.pressure.parameter() == Some(report.control.as_str())),
    );
    if !pressure_control || scene.effects.len() != 1 {
        return;
    }
    let mat = &scene.material;
    // The stress-free sphere: radius R/λ0, thickness H.
    let scale = ico.radius / mat.prestretch / (mat.mu * mat.thickness);
    let k = mat.k;
    println!();
    println!(
        "closed form for a Mooney-Rivlin sphere, k = {k}: p R/(mu H) = 2/(1+k) (1/l - 1/l^7) (1 + k l^2)"
    );
    let extremes = sphere_extremes(k);
    let list: Vec<String> = extremes
        .iter()
        .map(|(l, maximum)| {
            format!(
                "{} {:.7} at l = {:.7}",
                if *maximum { "maximum" } else { "minimum" },
                sphere_pressure(k, *l),
                l
            )
        })
        .collect();
    if !list.is_empty() {
        println!("  its {}", list.join(", its "));
    }
    // A polyhedron's pressure scale: p = dW/dV, with dW ∝ area and dV ∝ 3·volume, so the
    // discrete balloon's pressure exceeds the sphere's by R·A/(3V) − 1.
    let mesh = &study.mesh.mesh;
    let polyhedron = ico.radius * mesh.area() / (3.0 * mesh.volume()) - 1.0;
    if report.turning_points.is_empty() {
        println!("memstab found no turning point to compare");
        return;
    }
    println!(
        "memstab's turning points, p R/(mu H) against the closed form at the stretch l memstab found:"
    );
    let mut differences = Vec::new();
    for t in &report.turning_points {
        let l = t.measures[s];
        let found = t.parameters[c] * scale;
        let exact = sphere_pressure(k, l);
        let nearest = extremes
            .iter()
            .filter(|(_, maximum)| *maximum == (t.kind == "maximum"))
            .map(|(le, _)| *le)
            .min_by(|a, b| (a - l).abs().total_cmp(&(b - l).abs()));
        let stretch_diff = nearest.map_or_else(String::new, |le| {
            format!(
                " (l differs by {:+.1e} relative from the closed-form {}'s)",
                l / le - 1.0,
                t.kind
            )
        });
        let difference = found / exact - 1.0;
        println!(
            "  {:<7} {:.7} at l = {:.7}: closed form {:.7}, difference {:+.3} %{stretch_diff}",
            t.kind,
            found,
            l,
            exact,
            100.0 * difference
        );
        differences.push(difference);
    }
    // Is the polyhedron's pressure scale most of the difference?
    let explained = differences
        .iter()
        .all(|d| (d - polyhedron).abs() < 0.5 * d.abs());
    let what = format!(
        "the polyhedron's R A/(3V) exceeds the sphere's 1 by {:.3} %, an error that falls as 1/f^2 \
         with the frequency (f = {} here)",
        100.0 * polyhedron,
        ico.frequency
    );
    if explained {
        println!("most of the difference is the mesh: {what}");
    } else {
        println!("for comparison, {what}");
    }
}
