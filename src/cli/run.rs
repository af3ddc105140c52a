//! `memstab run SCENE --out DIR [--quiet] [--json] [--refine [N]] [--continuum]` (and the run
//! behind `memstab demo`).
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
//!
//! With `--refine` (or the scene's `[refine]`, which the flag overrides) the refined runs ([`Refiner`]) are built and checked before anything is
//! written (a mesh file, `--refine 3`: exit 2) and run after the scene's own, and their
//! findings go into the report (the not-mesh-converged flags) and `refine.json`; a refined run
//! that fails is recorded there (which, and why) with the levels that worked, a signal during
//! them writes the run without its refinement (exit 130).

use super::summary::print_summary;
use super::CliError;
use clap::Args;
use memstab::analysis::compare::{CompareError, RefineOptions, Refiner};
use memstab::analysis::run_from;
use memstab::output::{Progress, RunSummary, Written};
use memstab::results::{RunResult, StopReason};
use memstab::scene::Scene;
use memstab::study::Study;
use memstab::text::one_line;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

#[derive(Debug, Args)]
pub(crate) struct RunArgs {
    /// The scene file (TOML; see docs/scenes.md).
    scene: PathBuf,
    /// Output directory; created if missing (its parent must exist).
    #[arg(long)]
    out: PathBuf,
    /// No progress bar (the summary is still printed; with --json only the object).
    #[arg(long)]
    quiet: bool,
    /// Print one JSON object instead of the summary.
    #[arg(long)]
    json: bool,
    /// Also run the scene on its mesh at twice the divisions (N = 2: and four times) and give
    /// every critical and turning point its value per level, observed order, Richardson value
    /// and error estimate (refine.json; a point the finer mesh lacks is flagged not
    /// mesh-converged).
    #[arg(long, value_name = "N", num_args = 0..=1, default_missing_value = "1")]
    refine: Option<usize>,
    /// With --refine (or the scene's [refine]): also run the scene's meridian and give every
    /// point the continuum value and its distance from it.
    #[arg(long)]
    continuum: bool,
}

pub(crate) fn run(args: &RunArgs) -> Result<(), CliError> {
    let scene = Scene::load(&args.scene).map_err(|e| CliError::Input(e.to_string()))?;
    let refine =
        RefineOptions::resolve(args.refine, args.continuum, &scene).map_err(|e| match e {
            CompareError::Input(m) | CompareError::Failure(m) | CompareError::Interrupted(m) => {
                CliError::Input(m)
            }
        })?;
    let refined = refine.is_some();
    let (study, result, written) = execute_refined(scene, &args.out, args.quiet, refine)?;
    if args.json {
        let json = RunSummary::new(&result.report, &args.out, &written);
        let text = serde_json::to_string(&json).map_err(|e| CliError::Failure(e.to_string()))?;
        out!("{text}");
    } else {
        print_summary(study.scene(), &result, &args.out, &written);
    }
    interrupted(&result, &args.out)?;
    if refined && result.report.refinement.is_none() {
        return Err(CliError::Interrupted(format!(
            "the run is written into {}; its refinement was interrupted and is not",
            args.out.display()
        )));
    }
    Ok(())
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
) -> Result<(Box<dyn Study>, RunResult, Written), CliError> {
    execute_refined(scene, out, quiet, None)
}

/// As [`execute`], and with `refine` the scene's refined runs (built and checked before
/// anything is written) after its own, their findings in the report and `refine.json`.
fn execute_refined(
    scene: Scene,
    out: &Path,
    quiet: bool,
    refine: Option<RefineOptions>,
) -> Result<(Box<dyn Study>, RunResult, Written), CliError> {
    super::common::check_out(out)?;
    let compare_error = |e: CompareError| match e {
        CompareError::Input(m) => CliError::Input(m),
        CompareError::Failure(m) => CliError::Failure(m),
        CompareError::Interrupted(m) => CliError::Interrupted(m),
    };
    let refiner = match &refine {
        Some(options) => {
            if out.is_dir() {
                super::common::check_out_file("--out", &out.join(memstab::output::REFINE_JSON))?;
            }
            Some(Refiner::new(&scene, options).map_err(compare_error)?)
        }
        None => None,
    };
    let mut study = memstab::study::build(scene).map_err(|e| CliError::Input(one_line(&e)))?;
    let start = memstab::analysis::restart::start_of(&*study)
        .map_err(|e| CliError::Input(one_line(&format!("{}: {e}", study.about().origin))))?;
    let dir = super::common::OutDir::create(out)?;
    let clock = std::time::Instant::now();
    let (control, range) = memstab::analysis::progress_control(&*study);
    let progress = Progress::new(&control, range, quiet);
    let result = run_from(
        &mut *study,
        &start,
        &mut memstab::analysis::Progress(|point, value| progress.set(point + 1, value)),
    );
    let result = match result {
        Ok(r) => r,
        Err(e) => {
            progress.finish("failed");
            return Err(dir.failed(&e.to_string()));
        }
    };
    progress.finish(format!("stopped: {}", result.report.stop));
    let mut result = result;
    // A run cut short by a signal is written as it is, without its refinement.
    if let Some(refiner) = refiner.filter(|_| result.report.stop != StopReason::Interrupted) {
        let seconds = clock.elapsed().as_secs_f64();
        let lines = !quiet && std::io::stderr().is_terminal();
        let progress = |line: &str| {
            if lines {
                eprintln!("refine: {line}");
            }
        };
        match refiner.run(&result, seconds, &progress) {
            Ok(Some(r)) => memstab::analysis::compare::attach(&mut result, r),
            Ok(None) => {}
            Err(CompareError::Input(m) | CompareError::Failure(m)) => {
                return Err(dir.failed(&format!("--refine: {m}")))
            }
            // A signal during the refined runs: the base run is written as it is.
            Err(CompareError::Interrupted(_)) => {}
        }
    }
    let written = memstab::analysis::write(&*study, &mut result, out)
        .map_err(|e| CliError::Failure(one_line(&e.to_string())))?;
    Ok((study, result, written))
}
