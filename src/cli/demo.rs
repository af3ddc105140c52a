//! `memstab demo [--out DIR] [--quiet]`: the bundled demo scene run as `memstab run` runs
//! it, then its turning points against the closed form for a sphere.

use super::run::{execute, interrupted};
use super::summary::print_summary;
use super::CliError;
use clap::Args;
use memstab::demo::closed_form_check;
use memstab::results::PathReport;
use memstab::study::Study;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub(crate) struct DemoArgs {
    /// Output directory; created if missing (its parent must exist).
    #[arg(long, default_value = "memstab-demo")]
    out: PathBuf,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

pub(crate) fn demo(args: &DemoArgs) -> Result<(), CliError> {
    let scene = memstab::demo::scene()
        .map_err(|e| CliError::Failure(format!("the bundled demo scene is broken: {e}")))?;
    let (study, result, written) = execute(scene, &args.out, args.quiet)?;
    print_summary(study.scene(), &result, &args.out, &written);
    print_closed_form(&*study, &result.report);
    interrupted(&result, &args.out)?;
    Ok(())
}

/// Prints the closed-form check of a balloon under pressure control.
fn print_closed_form(study: &dyn Study, report: &PathReport) {
    let Some(check) = closed_form_check(study.scene(), study.mesh(), report) else {
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
