//! `memstab run` on a scene whose mesh is axisymmetric: builds the axisymmetric model, runs
//! its analysis, writes `path.csv` and `path.json` into DIR and prints the turning points and
//! the critical points by wave number. Bad input (a scene the axisymmetric model refuses, a
//! bad `--out`) is one line and exit code 2 with nothing written; a start that does not
//! converge is exit code 1 and DIR, if this run made it, is removed again.

use super::CliError;
use memstab::axisym::run::{run as run_axisym, AxisymStudy};
use memstab::output::{write_axisym_run, Progress};
use memstab::scene::Scene;
use memstab::text::{one_line, sig_digits};
use std::path::Path;

pub(super) fn run(scene: Scene, out: &Path, quiet: bool, json: bool) -> Result<(), CliError> {
    super::common::check_out(out)?;
    let origin = scene.origin.clone();
    let study = AxisymStudy::build(scene)
        .map_err(|e| CliError::Input(one_line(&format!("{origin}: {e}"))))?;
    let dir = super::common::OutDir::create(out)?;
    let control = study
        .control
        .map_or_else(|| "control".to_string(), |c| study.parameters[c].clone());
    let range = study.control.and_then(|c| {
        let b = study.scene.parameters.get(&study.parameters[c])?;
        Some((b.min?, b.max?))
    });
    let progress = Progress::new(&control, range, quiet);
    let report = match run_axisym(&study, |point, value| progress.set(point + 1, value)) {
        Ok(r) => r,
        Err(e) => {
            progress.finish("failed");
            return Err(dir.failed(&e.to_string()));
        }
    };
    progress.finish(format!("stopped: {}", report.stop));
    let written =
        write_axisym_run(&report, out).map_err(|e| CliError::Failure(one_line(&e.to_string())))?;
    if json {
        let files: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
        let summary = serde_json::json!({
            "scene": report.scene,
            "mesh": report.mesh,
            "points": report.rows.len(),
            "stop": report.stop.to_string(),
            "turning_points": report.turning_points.len(),
            "critical_points": report.critical.len(),
            "files": files,
        });
        out!("{summary}");
        return Ok(());
    }
    out!("scene '{}' ({origin})", report.scene);
    out!(
        "mesh: {} ({} unknowns; stability by wave number m = 0..{})",
        report.mesh,
        report.unknowns,
        report.modes
    );
    out!("{} points; stopped: {}", report.rows.len(), report.stop);
    let k = report.parameters.iter().position(|p| *p == report.control);
    let value = |p: &[f64]| k.map_or_else(String::new, |k| sig_digits(p[k], 8));
    for t in &report.turning_points {
        out!(
            "turning point: {} of {} = {} after step {}",
            t.kind,
            report.control,
            value(&t.parameters),
            t.after_step
        );
    }
    for c in &report.critical {
        out!(
            "critical point: m = {} ({}, multiplicity {}) at {} = {}{}",
            c.m,
            c.kind,
            c.multiplicity,
            report.control,
            value(&c.parameters),
            if c.localised { "" } else { " (not localised)" }
        );
    }
    for w in &report.warnings {
        out!("warning: {w}");
    }
    for p in &written {
        out!("wrote {}", p.display());
    }
    Ok(())
}
