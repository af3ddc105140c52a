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
use memstab::analysis::events::StopReason;
use memstab::analysis::{run as run_study, RunResult};
use memstab::demo::closed_form_check;
use memstab::output::{file_name, write_run, Progress, RunSummary, Written};
use memstab::report::PathReport;
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

#[derive(Debug, Args)]
pub(crate) struct DemoArgs {
    /// Output directory; created if missing (its parent must exist).
    #[arg(long, default_value = "memstab-demo")]
    out: PathBuf,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

pub(crate) fn run(args: &RunArgs) -> Result<(), CliError> {
    let scene = Scene::load(&args.scene).map_err(|e| CliError::Input(e.to_string()))?;
    if let memstab::scene::MeshSpec::Axisymmetric(_) = scene.mesh {
        return super::axisym::run(scene, &args.out, args.quiet, args.json);
    }
    let (study, result, written) = execute(scene, &args.out, args.quiet)?;
    if args.json {
        let json = RunSummary::new(&result.report, &args.out, &written);
        let text = serde_json::to_string(&json).map_err(|e| CliError::Failure(e.to_string()))?;
        out!("{text}");
    } else {
        print_summary(
            &study,
            &result.report,
            result.branches.as_ref(),
            &args.out,
            &written,
        );
    }
    interrupted(&result, &args.out)
}

/// Exit code 130 after a run that a signal stopped (its outputs are written).
fn interrupted(result: &RunResult, out: &Path) -> Result<(), CliError> {
    if result.report.stop == StopReason::Interrupted {
        return Err(CliError::Interrupted(format!(
            "the path so far is written into {}",
            out.display()
        )));
    }
    Ok(())
}

pub(crate) fn demo(args: &DemoArgs) -> Result<(), CliError> {
    let scene = memstab::demo::scene()
        .map_err(|e| CliError::Failure(format!("the bundled demo scene is broken: {e}")))?;
    let (study, result, written) = execute(scene, &args.out, args.quiet)?;
    print_summary(&study, &result.report, None, &args.out, &written);
    print_closed_form(&study, &result.report);
    interrupted(&result, &args.out)?;
    Ok(())
}

/// Checks `out`, builds the study, creates `out`, runs and writes every output.
fn execute(scene: Scene, out: &Path, quiet: bool) -> Result<(Study, RunResult, Written), CliError> {
    super::common::check_out(out)?;
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

/// The index of the measure `stretch`, if the report has it.
fn stretch_index(report: &PathReport) -> Option<usize> {
    report.measures.iter().position(|m| m == "stretch")
}

/// The index of the control among the parameters.
fn control_index(report: &PathReport) -> Option<usize> {
    report.parameters.iter().position(|p| *p == report.control)
}

fn print_summary(
    study: &Study,
    report: &PathReport,
    branches: Option<&memstab::analysis::branch::Branches>,
    out: &Path,
    written: &Written,
) {
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
    out!(
        "  {:<10} {} critical points: kind, irrep, multiplicity, parameters, step",
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
    if let (Some(b), Some(w)) = (branches, &written.branches) {
        super::branch::print_branches(b, w, &report.control);
    }
}

/// Prints the closed-form check of a balloon under pressure control.
fn print_closed_form(study: &Study, report: &PathReport) {
    let Some(check) = closed_form_check(study, report) else {
        return;
    };
    out!();
    out!(
        "closed form for a Mooney-Rivlin sphere, k = {}: p R/(mu H) = 2/(1+k) (1/l - 1/l^7) (1 + k l^2)",
        check.k
    );
    let list: Vec<String> = check
        .extrema
        .iter()
        .map(|e| {
            let kind = if e.maximum { "maximum" } else { "minimum" };
            format!("{kind} {:.7} at l = {:.7}", e.pressure, e.stretch)
        })
        .collect();
    if !list.is_empty() {
        out!("  its {}", list.join(", its "));
    }
    if check.turning.is_empty() {
        out!("memstab found no turning point to compare");
        return;
    }
    out!(
        "memstab's turning points, p R/(mu H) against the closed form at the stretch l memstab found:"
    );
    for t in &check.turning {
        let stretch_diff = t.stretch_difference.map_or_else(String::new, |d| {
            format!(
                " (l differs by {d:+.1e} relative from the closed-form {}'s)",
                t.kind
            )
        });
        out!(
            "  {:<7} {:.7} at l = {:.7}: closed form {:.7}, difference {:+.3} %{stretch_diff}",
            t.kind.to_string(),
            t.pressure,
            t.stretch,
            t.exact,
            100.0 * t.difference()
        );
    }
    let what = format!(
        "the polyhedron's R A/(3V) exceeds the sphere's 1 by {:.3} %, an error that falls as 1/f^2 \
         with the frequency (f = {} here)",
        100.0 * check.polyhedron,
        check.frequency
    );
    if check.explained_by_mesh() {
        out!("most of the difference is the mesh: {what}");
    } else {
        out!("for comparison, {what}");
    }
}

/// Six significant digits.
fn sig_digits6(x: f64) -> String {
    sig_digits(x, 6)
}
