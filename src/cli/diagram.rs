//! `memstab diagram RUN_DIR [--scene FILE] [--depth D] [--steps S] [--max-step X]
//! [--partner-steps P] [--no-partners] [--out DIR] [--json]`: the global diagram of a finished
//! path run — what `type = "diagram"` adds to its path, computed from the path on disk.
//!
//! The run is read back whole (`path.json`, `path.states`, `critical.states`, each checked
//! against its manifest), its scene rebuilt (`--scene`, else the file recorded in
//! `path.json`) and checked against the run, the start state solved again, and then the
//! branches of every bifurcation point followed to the depth (each branch once) and the
//! second piece sought beside every fold ([`memstab::analysis::diagram::from_run`]). The
//! settings are the scene's when it is a diagram, else the path's with the diagram's
//! defaults, overridden by the flags. Writes `branches.json`, `branch_NN/`, `diagram.svg`,
//! `diagram.json`, `partner_NN/` and `partners.svg` into DIR (default RUN_DIR) and adds them
//! to its `manifest.json`. Bad input (no run in RUN_DIR, a run without its states, a scene
//! that does not match, a bad flag value) is one line and exit 2 with nothing written; a
//! start state that does not converge is exit 1.

use super::branch::print_branches;
use super::common::{load_scene, one_line};
use super::CliError;
use clap::Args;
use memstab::analysis::{diagram, AfterError, Progress};
use std::path::PathBuf;

#[derive(Debug, Args)]
pub(crate) struct DiagramArgs {
    /// The output directory of a finished `memstab run` of a path (or a diagram).
    run_dir: PathBuf,
    #[command(flatten)]
    flags: super::common::BranchFlags,
    /// Points of each second piece beyond its fold (default: the scene's, else 60).
    #[arg(long)]
    partner_steps: Option<usize>,
    /// Do not seek the second piece beside the path's folds.
    #[arg(long)]
    no_partners: bool,
    /// Output directory (default RUN_DIR; it must exist).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Print one JSON object (the files written and the counts) instead of the summary.
    #[arg(long)]
    json: bool,
}

pub(crate) fn run(args: &DiagramArgs) -> Result<(), CliError> {
    let (finished, out) = super::common::finished_run(&args.run_dir, args.out.as_deref())?;
    let scene_file = args.flags.scene_file(&finished.origin);
    let scene = load_scene(&scene_file)?;
    let overrides = diagram::Overrides {
        branches: args.flags.overrides(),
        partners: args.no_partners.then_some(false),
        partner_steps: args.partner_steps,
    };
    let settings = diagram::settings_for(&scene.analysis, &overrides)
        .map_err(|e| CliError::Input(one_line(&e)))?;
    super::common::check_writable("--out", &out, &out)?;
    // Refused up front when another run writes into the directory.
    let _lock = super::common::lock(&out)?;
    let mut study = memstab::study::build(scene).map_err(|e| CliError::Input(one_line(&e)))?;
    let result = diagram::from_run(&mut *study, &finished, settings, &mut Progress(|_, _| {}))
        .map_err(|e| match e {
            AfterError::Input(why) => CliError::Input(one_line(&why)),
            AfterError::Start(e) | AfterError::Run(e) => {
                CliError::Failure(format!("{}; nothing was written", one_line(&e.to_string())))
            }
        })?;
    let scene = study.scene().clone();
    let (branches, files) = diagram::write_from_run(&*study, &scene, &result, &out)
        .map_err(|e| CliError::Failure(one_line(&e.to_string())))?;
    let interrupted = result.report.stop == memstab::results::StopReason::Interrupted;
    let mut written = branches.files.clone();
    written.extend(files.iter().map(|d| d.path.clone()));
    let stop = interrupted.then_some(&memstab::results::StopReason::Interrupted);
    memstab::output::add_to_manifest(&out, &written, stop, "the global diagram")
        .map_err(|e| CliError::Failure(one_line(&e.to_string())))?;
    written.push(out.join(memstab::output::MANIFEST));
    if args.json {
        let listed: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
        let json = serde_json::json!({
            "run": args.run_dir,
            "out": out,
            "branches": result.branches.as_ref().map_or(0, |b| b.runs.len()),
            "diagram": out.join("diagram.json"),
            "files": listed,
        });
        println!("{json}");
    } else {
        if let Some(b) = &result.branches {
            print_branches(b, &branches, &result.report.control);
        }
        for line in diagram::summary(&result) {
            println!("{line}");
        }
        for d in files.iter().filter(|d| !d.what.is_empty()) {
            println!("  {} {}", relative(&d.path, &out), d.what);
        }
    }
    if interrupted {
        return Err(CliError::Interrupted(format!(
            "the diagram so far is written into {}",
            out.display()
        )));
    }
    Ok(())
}

/// `path` relative to `dir` where it lies inside it.
fn relative(path: &std::path::Path, dir: &std::path::Path) -> String {
    path.strip_prefix(dir).unwrap_or(path).display().to_string()
}
