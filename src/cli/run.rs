//! `memstab run SCENE --out DIR [--quiet] [--json]` (and the run behind `memstab demo`).
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
use memstab::analysis::events::StopReason;
use memstab::analysis::{run as run_study, RunResult};
use memstab::output::{file_name, write_run, Progress, RunSummary, Written, RUN_FILES};
use memstab::report::{CurveReport, PathReport};
use memstab::scene::Scene;
use memstab::study::Study;
use memstab::text::{one_line, sig_digits};
use std::path::{Path, PathBuf};

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

pub(crate) fn run(args: &RunArgs) -> Result<(), CliError> {
    let scene = Scene::load(&args.scene).map_err(|e| CliError::Input(e.to_string()))?;
    let (study, result, written) = execute(scene, &args.out, args.quiet)?;
    if args.json {
        let json = RunSummary::new(&result.report, &args.out, &written);
        let text = serde_json::to_string(&json).map_err(|e| CliError::Failure(e.to_string()))?;
        out!("{text}");
    } else {
        print_summary(&study, &result, &args.out, &written);
    }
    interrupted(&result, &args.out)
}

/// Exit code 130 after a run that a signal stopped (its outputs are written).
pub(super) fn interrupted(result: &RunResult, out: &Path) -> Result<(), CliError> {
    if result.report.stop == StopReason::Interrupted {
        return Err(CliError::Interrupted(format!(
            "the path so far is written into {}",
            out.display()
        )));
    }
    Ok(())
}

/// Checks `out`, builds the study, creates `out`, runs and writes every output.
pub(super) fn execute(
    scene: Scene,
    out: &Path,
    quiet: bool,
) -> Result<(Study, RunResult, Written), CliError> {
    check_out(out)?;
    let mut study = super::common::build_study(scene)?;
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
        progress.set(step, format!("{control} = {}", sig_digits6(value)));
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
    let written = write_run(&study, &mut result, out)
        .map_err(|e| CliError::Failure(one_line(&e.to_string())))?;
    Ok((study, result, written))
}

/// `--out` must be a directory or not exist yet, and its parent must exist.
fn check_out(out: &Path) -> Result<(), CliError> {
    if out.exists() {
        if out.is_dir() {
            for name in RUN_FILES {
                super::common::check_out_file("--out", &out.join(name))?;
            }
            return Ok(());
        }
        return Err(CliError::Input(format!(
            "--out '{}' exists and is not a directory",
            out.display()
        )));
    }
    if std::fs::symlink_metadata(out).is_ok() {
        return Err(CliError::Input(format!(
            "--out '{}' is a symbolic link to nothing; give a directory",
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

/// The index of the measure `stretch`, if the report has it.
fn stretch_index(report: &PathReport) -> Option<usize> {
    report.measures.iter().position(|m| m == "stretch")
}

/// The index of the control among the parameters.
fn control_index(report: &PathReport) -> Option<usize> {
    report.parameters.iter().position(|p| *p == report.control)
}

pub(super) fn print_summary(study: &Study, result: &RunResult, out: &Path, written: &Written) {
    let report = &result.report;
    let m = &report.mesh;
    out!("scene '{}' ({})", report.scene, report.origin);
    out!(
        "mesh: {} with {} nodes, {} triangles, group {} (order {})",
        m.generator,
        m.nodes,
        m.elements,
        m.group,
        m.order
    );
    out!(
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
        (Some(c), Some(first), Some(last)) if n > 1 => out!(
            "path: {points}, {} from {} to {}",
            report.control,
            sig_digits6(first.parameters[c]),
            sig_digits6(last.parameters[c])
        ),
        (Some(c), Some(first), _) => {
            out!(
                "path: {points}, {} = {}",
                report.control,
                sig_digits6(first.parameters[c])
            )
        }
        _ => out!("equilibrium: {points}"),
    }
    // A closed membrane with a negative enclosed volume has turned inside out: the numbers
    // are finite but not physical.
    if let Some(v) = report.measures.iter().position(|m| m == "volume") {
        if let Some(r) = report.rows.iter().find(|r| r.measures[v] <= 0.0) {
            out!(
                "warning: the enclosed volume is {} at step {}: the membrane is inside out there, \
                 the path is not physical",
                sig_digits6(r.measures[v]),
                r.step
            );
        }
    }
    if report.turning_points.is_empty() {
        if c.is_some() {
            out!("turning points of {}: none", report.control);
        }
    } else {
        out!("turning points of {}:", report.control);
        for t in &report.turning_points {
            let value = c.map_or_else(|| "?".to_string(), |c| sig_digits6(t.parameters[c]));
            let stretch = s.map_or_else(String::new, |s| {
                format!(" at stretch {}", sig_digits6(t.measures[s]))
            });
            out!(
                "  {:<7} {} = {value}{stretch} (after step {})",
                t.kind,
                report.control,
                t.after_step
            );
        }
    }
    for w in &report.warnings {
        out!("warning: {w}");
    }
    if let Some(note) = &report.stability_note {
        out!("{note}");
    } else if report.critical.is_empty() {
        match report.index_range() {
            Some((lo, hi)) if lo == hi => out!("critical points: none (the index stays {lo})"),
            Some((lo, hi)) => out!(
                "critical points: none localised, although the index ranges from {lo} to {hi} \
                 along the path (see the warnings)"
            ),
            None => out!("critical points: none (no index was computed)"),
        }
    } else {
        out!("critical points (irrep of the singular block, multiplicity in K, isotropy of the mode):");
        for cp in &report.critical {
            let value = c.map_or_else(|| "?".to_string(), |c| sig_digits6(cp.parameters[c]));
            out!(
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
    out!("stopped: {}", report.stop);
    if let Some(curve) = &result.curve {
        print_curve(curve);
    }
    out!(
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
    out!(
        "  {:<10} {} rows: step, arclength, {header}, iterations",
        file_name(&written.csv),
        report.rows.len()
    );
    out!(
        "  {:<10} the report: metadata, path, turning points, critical points, saved states",
        file_name(&written.json)
    );
    let events = result.curve.as_ref().map_or_else(String::new, |c| {
        format!(" and the curve's {} events", c.events.len())
    });
    out!(
        "  {:<10} {} critical points{events}: kind, irrep, multiplicity, parameters, step",
        file_name(&written.critical),
        report.critical.len()
    );
    out!("  {:<10} {}", file_name(&written.svg), written.plotted);
    let in_collection = report.saved.iter().filter(|s| s.in_collection).count();
    out!(
        "  {:<10} ParaView collection of the {in_collection} path states (time = path step); turning and critical points beside it",
        file_name(&written.pvd),
    );
    if let Some(points) = &written.points {
        out!(
            "  {:<10} every point's parameters and displacement, binary ([start] from reads it)",
            file_name(points),
        );
    }
    for chunk in written.states.chunks(5) {
        let names: Vec<String> = chunk.iter().map(|p| file_name(p)).collect();
        out!("  {}", names.join(" "));
    }
    if let Some(curve) = &result.curve {
        let described = [
            format!(
                "{} rows: both parameters, the measures, the block's eigenvalues",
                curve.rows.len()
            ),
            "the curve: its points and events".to_string(),
            format!("{} against {}, events marked", curve.second, curve.control),
        ];
        for (path, what) in written.curve.iter().zip(described) {
            out!("  {:<10} {what}", file_name(path));
        }
    }
    if let (Some(b), Some(w)) = (&result.branches, &written.branches) {
        super::branch::print_branches(b, w, &report.control);
    }
}

/// The critical curve: what was followed, its extent and its events.
fn print_curve(curve: &CurveReport) {
    let column = |name: &str| curve.parameters.iter().position(|p| p == name);
    out!(
        "critical curve of the {} in {} x{} in ({}, {}): {} points",
        curve.kind,
        curve.irrep,
        curve.multiplicity,
        curve.control,
        curve.second,
        curve.rows.len()
    );
    let (Some(c), Some(s)) = (column(&curve.control), column(&curve.second)) else {
        return;
    };
    for e in &curve.events {
        let extremum = e
            .extremum
            .map_or_else(String::new, |x| format!(" ({x} of {})", curve.second));
        out!(
            "  {:<9} {} = {}, {} = {}{extremum} (after curve step {})",
            e.kind.to_string(),
            curve.control,
            sig_digits6(e.parameters[c]),
            curve.second,
            sig_digits6(e.parameters[s]),
            e.after_step
        );
    }
    out!("curve stopped: {}", curve.stop);
}

/// Six significant digits.
pub(super) fn sig_digits6(x: f64) -> String {
    sig_digits(x, 6)
}
