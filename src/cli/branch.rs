//! `memstab branch RUN_DIR --critical N [--scene FILE] [--depth D] [--steps S]
//! [--max-step X] [--out DIR] [--json]`: branch switching at critical point N of a finished
//! run, and the summary of a run's branches (also printed by `memstab run`).
//!
//! The run is read back ([`memstab::output::FinishedRun`]: `path.json` and
//! `critical_NN.vtu`), its scene rebuilt (`--scene`, else the file recorded in `path.json`)
//! and checked against the run, the start state solved again (it sets the targets of
//! `"initial"` constraints), and the branches of point N followed
//! ([`memstab::analysis::branch`]) with the scene's `[analysis.branches]` settings where it
//! has them, overridden by the flags. Writes `branches.json`, `branch_NN/` and `diagram.svg`
//! into DIR (default RUN_DIR) and adds them to its `manifest.json`. What is read of the run is
//! checked against its manifest first (an edited file is bad input, naming it). Bad input (no run in RUN_DIR, N out of range, a scene that does
//! not match the run, a bad flag value) is one line and exit 2, with nothing written; a start
//! state that does not converge is exit 1.

use super::common::{load_scene, one_line, sig_digits};
use super::CliError;
use clap::Args;
use memstab::analysis::branch;
use memstab::output::{write_branches, BranchesWritten};
use memstab::results::{directory, Branches, Node, Skip, StopReason};
use std::path::PathBuf;

#[derive(Debug, Args)]
pub(crate) struct BranchArgs {
    /// The output directory of a finished `memstab run`.
    run_dir: PathBuf,
    /// The critical point to switch at: N of critical_NN.vtu (the N-th of critical.json).
    #[arg(long)]
    critical: usize,
    #[command(flatten)]
    flags: super::common::BranchFlags,
    /// Output directory (default RUN_DIR; it must exist).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Print one JSON object (the files written and the branches) instead of the summary.
    #[arg(long)]
    json: bool,
}

pub(crate) fn run(args: &BranchArgs) -> Result<(), CliError> {
    let (finished, out) = super::common::finished_run(&args.run_dir, args.out.as_deref())?;
    let overrides = args.flags.overrides();
    overrides.check().map_err(CliError::Input)?;
    super::common::check_writable("--out", &out, &out)?;
    // Refused up front when another run writes into the directory.
    let _lock = super::common::lock(&out)?;
    let scene_file = args.flags.scene_file(&finished.origin);
    let mut study = memstab::study::build(load_scene(&scene_file)?)
        .map_err(|e| CliError::Input(one_line(&e)))?;
    let branches = branch::from_run(&mut *study, &finished, args.critical, &overrides).map_err(
        |e| match e {
            branch::BranchError::Input(why) => CliError::Input(one_line(&why)),
            branch::BranchError::Start(e) => {
                CliError::Failure(format!("{}; nothing was written", one_line(&e.to_string())))
            }
        },
    )?;
    let scene = study.scene().clone();
    let written = write_branches(&*study, &scene, &branches, &finished.path, &out)
        .map_err(|e| CliError::Failure(one_line(&e.to_string())))?;
    let interrupted = branch::interrupted(&branches);
    let stop = interrupted.then_some(&StopReason::Interrupted);
    let mut files = written.files.clone();
    files.push(out.join(memstab::output::MANIFEST));
    memstab::output::add_to_manifest(&out, &written.files, stop, "branches followed")
        .map_err(|e| CliError::Failure(one_line(&e.to_string())))?;
    if args.json {
        let files: Vec<String> = files.iter().map(|p| p.display().to_string()).collect();
        let json = serde_json::json!({
            "run": args.run_dir,
            "critical": args.critical,
            "out": out,
            "branches": written.json,
            "diagram": written.diagram,
            "count": branches.runs.len(),
            "files": files,
        });
        println!("{json}");
    } else {
        print_branches(&branches, &written, &finished.path.control);
    }
    if interrupted {
        return Err(CliError::Interrupted(format!(
            "the branches so far are written into {}",
            out.display()
        )));
    }
    Ok(())
}

/// The branches of a run: per switched critical point its branches (isotropy, half, kind,
/// points, the control at the end, stability, why it stopped), the points not switched and
/// why, and what was written.
pub(crate) fn print_branches(b: &Branches, written: &BranchesWritten, control: &str) {
    let g = &b.graph;
    println!(
        "branches (depth {}): {} in {:.1} s",
        b.depth,
        g.branches.len(),
        b.time.as_secs_f64()
    );
    for n in g.graph.node_indices() {
        let Node::Critical {
            on,
            number,
            point,
            skipped,
        } = &g.graph[n]
        else {
            continue;
        };
        let leaving = g.leaving(n);
        let on = on.map_or_else(|| "path".to_string(), directory);
        match skipped {
            Some(why) if leaving.is_empty() => {
                if on == "path" || matches!(why, Skip::NotTransversal(_) | Skip::AtOrigin { .. }) {
                    println!("  {on} #{number} {} in {}: {why}", point.kind, point.irrep);
                }
                continue;
            }
            _ => {}
        }
        let also = skipped
            .as_ref()
            .map_or_else(String::new, |why| format!(" (not every direction: {why})"));
        println!(
            "  {on} #{number} {} in {}: {} branch{}{also}",
            point.kind,
            point.irrep,
            leaving.len(),
            if leaving.len() == 1 { "" } else { "es" }
        );
        for i in leaving {
            let br = &g.branches[i];
            let run = &b.runs[i];
            let last = br.points.last().map_or(0.0, |p| {
                run.report
                    .parameters
                    .iter()
                    .position(|x| x == control)
                    .map_or(0.0, |c| p.parameters[c])
            });
            let unstable = run
                .report
                .rows
                .iter()
                .filter(|r| r.index.is_some_and(|i| i > 0))
                .count();
            let known = run.report.rows.iter().filter(|r| r.index.is_some()).count();
            let stability = match (known, unstable) {
                (0, _) => "stability not analysed".to_string(),
                (_, 0) => "stable".to_string(),
                (k, u) if u == k => "unstable".to_string(),
                (k, u) => format!("unstable at {u} of {k} points"),
            };
            println!(
                "    {} {}{} ({} halves, {}): {} points to {control} = {}, {stability}, isotropy on the states {}; {}",
                run.directory,
                br.isotropy,
                br.half,
                br.halves,
                br.reduced.bifurcation,
                br.points.len(),
                sig_digits(last, 6),
                if br.isotropy_exact() { "exact" } else { "NOT exact" },
                br.stop
            );
            if let Some(nf) = &br.normal_form {
                println!("      normal form: {}", nf.describe(control));
            }
            for w in &br.warnings {
                println!("      warning: {w}");
            }
        }
    }
    println!(
        "wrote {} (the graph), {} (every branch), {} branch directories",
        written.json.display(),
        written.diagram.display(),
        written.directories.len()
    );
}
