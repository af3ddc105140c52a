//! `memstab export-matrix SCENE [--at NAME=VALUE]... --out K.mtx`: the full tangent K at the
//! scene's start state in Matrix Market format, so that an external solver (scipy `eigsh`,
//! `scripts/peer_eigsh.py`) works on exactly our matrix; `memstab export-matrix RUN_DIR
//! --point N [--scene FILE] --out K.mtx`: at path point N of a finished run (from its
//! `path.states`, no solve).
//!
//! The state is the one `memstab spectrum` analyses
//! ([`memstab::analysis::equilibrium::state_at`]): solved as `memstab run` solves its start,
//! with `--at` overriding start values; on a `linear-buckling` scene the start state is held
//! and an `--at` of its control enters only the tangent.
//! The file is `coordinate real symmetric`, the lower triangle of the pattern (explicit zeros
//! included), 1-based, written whole (temporary file + rename). Rank-one terms of K (a
//! `gas-amount` effect: K = S + Σ c_k a_k a_kᵀ, dense) go into a companion file next to it,
//! `K.rank1.mtx` (see [`memstab::output::write_matrix_market`] and the `--help` text).

use super::common::{build_study, check_out_file, load_scene, parse_at, saved_point};
use super::CliError;
use clap::Args;
use memstab::analysis::equilibrium::state_at;
use memstab::model::{Model, Request};
use memstab::output::{rank_one_path, write_matrix_market};
use memstab::study::Point;
use std::path::PathBuf;

/// Arguments of `memstab export-matrix`.
#[derive(Debug, Args)]
#[command(after_long_help = EXPORT_HELP)]
pub(crate) struct ExportArgs {
    /// The scene file (TOML), or with --point the output directory of a finished `memstab run`.
    #[arg(value_name = "SCENE|RUN_DIR")]
    input: PathBuf,
    /// Set a parameter instead of its start value (repeatable), e.g. `--at p=1.3`.
    #[arg(long = "at", value_name = "NAME=VALUE")]
    at: Vec<String>,
    /// Export at path point N of the run in RUN_DIR (the row step = N of its path.csv), read
    /// from its path.states.
    #[arg(long, value_name = "N")]
    point: Option<usize>,
    /// With --point: the run's scene file (default: the one recorded in RUN_DIR/path.json).
    #[arg(long, value_name = "FILE")]
    scene: Option<PathBuf>,
    /// The Matrix Market file to write (its directory must exist); rank-one terms of K, if
    /// any, go to a companion file next to it (K.mtx → K.rank1.mtx), see below.
    #[arg(long, value_name = "K.mtx")]
    out: PathBuf,
}

/// The file formats, shown by `memstab export-matrix --help`.
const EXPORT_HELP: &str = "\
Files:
  K.mtx        the sparse part S of K: Matrix Market `coordinate real symmetric`, the lower
               triangle of K's pattern (explicit zeros included), 1-based, 17 digits.
  K.rank1.mtx  only when K has rank-one terms (a `gas-amount` effect adds c a a^T, which is
               dense): K = S + sum_k c_k a_k a_k^T. Matrix Market `array real general`, n rows
               and one column a_k per term (column-major), with the coefficients on the
               comment line `% coefficients: c_1 ... c_r`. K.mtx then names it on a comment
               line `% rank-one file: K.rank1.mtx`; that line is what says K has rank-one terms
               (a companion file left by an earlier export is not read).

`python3 scripts/peer_eigsh.py K.mtx [--k 20] [--sigma=S]` runs scipy eigsh (shift-invert) on
K and prints JSON; it finds the rank-one file by that comment line and inverts K - sigma I by a
sparse LU of S - sigma I and the Sherman-Morrison-Woodbury formula.";

pub(crate) fn run(args: &ExportArgs) -> Result<(), CliError> {
    check_out_file("--out", &args.out)?;
    check_out_file("--out (its rank-one file)", &rank_one_path(&args.out))?;
    let (study, u, params) = match args.point {
        Some(n) => {
            if let Some(a) = args.at.first() {
                return Err(CliError::Input(format!(
                    "--at '{a}' with --point {n}: a saved point's parameters are those of the run"
                )));
            }
            let p = saved_point(&args.input, args.scene.as_deref(), n)?;
            refuse_sliding(&p.study.scene)?;
            (p.study, p.u, p.params)
        }
        None => {
            if let Some(scene) = &args.scene {
                return Err(CliError::Input(format!(
                    "--scene '{}' goes with --point N (the scene of a run directory)",
                    scene.display()
                )));
            }
            let scene = load_scene(&args.input)?;
            refuse_sliding(&scene)?;
            let mut study = build_study(scene)?;
            let start = super::common::start_of(&study)?;
            let at = parse_at(&args.at, &study.parameters)?;
            let Point { u, params, .. } = state_at(&mut study, &at, &start)
                .map_err(|e| super::spectrum::not_converged(&e, &at))?;
            (study, u, params)
        }
    };
    let mut eval = study.model.new_evaluation();
    study
        .model
        .evaluate(&u, &params, Request::ALL, &mut eval)
        .map_err(|e| CliError::Failure(format!("evaluating the tangent: {e}")))?;
    // A signal after the solve: nothing is written (a started write finishes whole).
    if memstab::continuation::interrupt::requested() {
        return Err(CliError::Interrupted(format!(
            "stopped before {} was written; nothing was written",
            args.out.display()
        )));
    }
    let comment = format!(
        "memstab {} export-matrix: tangent K of scene '{}' at {}",
        env!("CARGO_PKG_VERSION"),
        study.scene.info.name,
        study
            .parameters
            .iter()
            .zip(&params)
            .map(|(n, v)| format!("{n}={v}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let files = write_matrix_market(
        &args.out,
        study.model.pattern(),
        &eval.tangent,
        &eval.rank_one,
        &comment,
    )
    .map_err(|e| CliError::Failure(e.to_string()))?;
    let n = study.model.unknowns();
    match &files.rank_one {
        None => out!(
            "wrote {} ({n} x {n}, {} entries in the lower triangle)",
            args.out.display(),
            files.entries
        ),
        Some((file, r)) => out!(
            "wrote {} ({n} x {n}, {} entries in the lower triangle: the sparse part S) and {} \
             ({r} rank-one term(s) c a a^T: K = S + sum_k c_k a_k a_k^T)",
            args.out.display(),
            files.entries,
            file.display()
        ),
    }
    Ok(())
}

/// K over all unknowns ignores a sliding constraint: such a scene is refused (exit 2).
fn refuse_sliding(scene: &memstab::scene::Scene) -> Result<(), CliError> {
    if scene.boundary.slide.is_empty() {
        return Ok(());
    }
    Err(CliError::Input(format!(
        "{}: 'boundary.slide': export-matrix writes K over all unknowns, but a sliding node \
         keeps only its in-plane ones; remove [[boundary.slide]] (or fix the set) to export",
        scene.origin
    )))
}
