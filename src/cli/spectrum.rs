//! `memstab spectrum SCENE [--at NAME=VALUE]... [--count N] [--json]`: the tangent's spectrum
//! by irrep at the scene's start state; `memstab spectrum RUN_DIR --point N [--scene FILE]`:
//! at path point N of a finished run, read from its `path.states` (no solve: any point of the
//! path, unstable ones past a turning point included).
//!
//! The state is solved as `memstab run` solves its start (every parameter at its start value,
//! here overridden by `--at`); for a `linear-buckling` scene the start state is held and an
//! `--at` of the control only enters the tangent, exactly as on `run`'s sample at that value.
//! Constraints border the trivial block as on `run`'s first point. Per irrep: its dimension d,
//! the block size m (m·d unknowns in K), the N lowest eigenvalues of the block in units of
//! max |K_ij| (each counts d times in K), the negative count and the rigid-body zero modes
//! found and deflated in that block; then the instability index Σ d·neg.
//!
//! Bad input — a scene that does not load or build, an `--at` naming no parameter or without a
//! number — is one line and exit code 2; a start state that does not converge
//! is exit code 1.

use super::common::{build_study, load_scene, one_line, parse_at, saved_point, sci};
use super::CliError;
use clap::Args;
use memstab::analysis::equilibrium::state_at;
use memstab::study::mesh::SpectrumError;
use memstab::study::Point;
use serde::Serialize;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub(crate) struct SpectrumArgs {
    /// The scene file (TOML; see docs/scenes.md), or with --point the output directory of a
    /// finished `memstab run`.
    #[arg(value_name = "SCENE|RUN_DIR")]
    input: PathBuf,
    /// Set a parameter instead of its start value (repeatable), e.g. `--at p=1.3`.
    #[arg(long = "at", value_name = "NAME=VALUE")]
    at: Vec<String>,
    /// Analyse path point N of the run in RUN_DIR (the row step = N of its path.csv), read
    /// from its path.states.
    #[arg(long, value_name = "N")]
    point: Option<usize>,
    /// With --point: the run's scene file (default: the one recorded in RUN_DIR/path.json).
    #[arg(long, value_name = "FILE")]
    scene: Option<PathBuf>,
    /// How many of each block's lowest eigenvalues to print.
    #[arg(long, default_value_t = 6, value_name = "N")]
    count: usize,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    json: bool,
}

/// One irrep in the `--json` output.
#[derive(Debug, Serialize)]
struct IrrepJson {
    name: String,
    dim: usize,
    /// Block size m (columns of one partner); m·dim unknowns of K.
    size: usize,
    /// The lowest eigenvalues of the block, ascending, in units of `scale`.
    lowest: Vec<f64>,
    negative: usize,
    /// Rigid-body zero modes found (and deflated) in the block; each counts `dim` times in K.
    zero_modes: usize,
    /// max |B_μᵀ K r| over those modes, relative to `scale` (≈ 0 at an equilibrium).
    zero_mode_residual: f64,
    /// Mean motions held (and deflated) in the block: the rolling of a spherical reference.
    held_motions: usize,
}

/// The `--json` output.
#[derive(Debug, Serialize)]
struct SpectrumJson {
    scene: String,
    origin: String,
    group: String,
    order: usize,
    unknowns: usize,
    /// Every parameter at the state, by name.
    parameters: serde_json::Map<String, serde_json::Value>,
    /// Σ dim·negative.
    index: usize,
    /// max |K_ij|: eigenvalues are in this unit.
    scale: f64,
    units: &'static str,
    /// Newton iterations of the start solve.
    iterations: usize,
    /// True for a linear-buckling scene: the start state is held and `parameters` enter the
    /// tangent only.
    held: bool,
    /// With `--point`: the path point analysed, and the index the run recorded there.
    #[serde(skip_serializing_if = "Option::is_none")]
    point: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    run_index: Option<usize>,
    irreps: Vec<IrrepJson>,
}

pub(crate) fn run(args: &SpectrumArgs) -> Result<(), CliError> {
    let (study, at, u, params, iterations, point) = state(args)?;
    let origin = study.scene.origin.clone();
    let held = memstab::analysis::analysis_of(&study.scene.analysis).held();
    let spectrum = study
        .spectrum_at(&u, &params, args.count)
        .map_err(|e| match e {
            SpectrumError::Basis(e) => CliError::Input(format!("scene '{origin}': {e}")),
            e @ SpectrumError::Tangent(_) => CliError::Failure(one_line(&e.to_string())),
        })?;
    // A signal while the blocks were analysed: the blocks not started were skipped, so no
    // part of the spectrum is printed.
    if memstab::continuation::interrupt::requested() {
        return Err(CliError::Interrupted(format!(
            "stopped between the tangent's {} blocks; nothing was printed",
            spectrum.blocks.len()
        )));
    }
    let scale = spectrum.scale;
    let rel = |v: &f64| v / scale;
    if args.json {
        let json = SpectrumJson {
            scene: study.scene.info.name.clone(),
            origin,
            group: study.action.group().name().to_string(),
            order: study.action.group().order(),
            unknowns: study.basis.unknowns(),
            parameters: study
                .parameters
                .iter()
                .zip(&params)
                .map(|(n, v)| (n.clone(), serde_json::Value::from(*v)))
                .collect(),
            index: spectrum.index,
            scale,
            units: "max|K_ij|",
            iterations,
            held,
            point: point.map(|(n, _)| n),
            run_index: point.and_then(|(_, i)| i),
            irreps: spectrum
                .blocks
                .iter()
                .map(|b| IrrepJson {
                    name: b.irrep.clone(),
                    dim: b.dim,
                    size: b.size,
                    lowest: b.eigenvalues.iter().take(args.count).map(rel).collect(),
                    negative: b.negative,
                    zero_modes: b.rigid_modes,
                    zero_mode_residual: b.rigid_residual,
                    held_motions: b.held,
                })
                .collect(),
        };
        let text = serde_json::to_string(&json).map_err(|e| CliError::Failure(e.to_string()))?;
        out!("{text}");
        return Ok(());
    }

    let m = &study.mesh.mesh;
    out!("scene '{}' ({origin})", study.scene.info.name);
    out!(
        "mesh: {} with {} nodes, {} triangles; scene group {} (order {}), {} unknowns",
        study.scene.mesh.generator(),
        m.nodes.len(),
        m.triangles.len(),
        study.action.group().name(),
        study.action.group().order(),
        study.basis.unknowns()
    );
    let values: Vec<String> = study
        .parameters
        .iter()
        .zip(&params)
        .enumerate()
        .map(|(i, (n, v))| {
            let mark = if at.iter().any(|&(j, _)| j == i) {
                " (--at)"
            } else {
                ""
            };
            format!("{n} = {v}{mark}")
        })
        .collect();
    let values = if values.is_empty() {
        "no parameters".to_string()
    } else {
        values.join(", ")
    };
    if let Some((n, index)) = point {
        let recorded = index.map_or_else(
            || "no index recorded there".to_string(),
            |i| format!("the run recorded index {i} there"),
        );
        out!(
            "state: path point {n} of {} (from path.states, no solve): {values}; {recorded}",
            args.input.display()
        );
    } else if held {
        let c = study
            .control
            .map_or("the control", |c| &study.parameters[c]);
        out!(
            "state: the start state (Newton: {}), held as in linear buckling; tangent at \
             {values} ({c} enters the tangent only)",
            plural(iterations, "iteration")
        );
    } else {
        out!(
            "state: {values} (Newton: {} from the start guess)",
            plural(iterations, "iteration")
        );
    }
    if !study.constraints.is_empty() {
        let names: Vec<&str> = study.constraints.iter().map(|c| c.name()).collect();
        out!("constraints border the trivial block: {}", names.join(", "));
    }
    out!(
        "eigenvalues of each irrep's block K_mu, ascending, in units of max|K_ij| = {}; \
         each counts d times in K; rigid-body zero modes are deflated (not among the \
         eigenvalues, not in the index)",
        sci(scale)
    );
    let name_width = spectrum
        .blocks
        .iter()
        .map(|b| b.irrep.len())
        .max()
        .unwrap_or(5)
        .max(5);
    out!(
        "{:<name_width$} {:>2} {:>6} {:>7} {:>4} {:>4}  lowest {} eigenvalues",
        "irrep",
        "d",
        "m",
        "m*d",
        "neg",
        "zero",
        args.count
    );
    for b in &spectrum.blocks {
        let lowest: Vec<String> = b
            .eigenvalues
            .iter()
            .take(args.count)
            .map(|v| format!("{:>10}", sci(v / scale)))
            .collect();
        out!(
            "{:<name_width$} {:>2} {:>6} {:>7} {:>4} {:>4}  {}",
            b.irrep,
            b.dim,
            b.size,
            b.size * b.dim,
            b.negative,
            b.rigid_modes,
            lowest.join(" ")
        );
    }
    let total: usize = spectrum.blocks.iter().map(|b| b.size * b.dim).sum();
    let zero: Vec<String> = spectrum
        .blocks
        .iter()
        .filter(|b| b.rigid_modes > 0)
        .map(|b| format!("{} {}x{}", b.irrep, b.rigid_modes, b.dim))
        .collect();
    let zero_total: usize = spectrum.blocks.iter().map(|b| b.rigid_modes * b.dim).sum();
    out!(
        "sum of m*d = {total} of {} unknowns; rigid-body zero modes: {}",
        study.basis.unknowns(),
        if zero.is_empty() {
            "none".to_string()
        } else {
            format!("{zero_total} ({})", zero.join(", "))
        }
    );
    let held: Vec<String> = spectrum
        .blocks
        .iter()
        .filter(|b| b.held > 0)
        .map(|b| format!("{} {}x{}", b.irrep, b.held, b.dim))
        .collect();
    if !held.is_empty() {
        out!(
            "held mean motions (the rolling of a spherical reference, a drift across a spin \
             axis; deflated like the rigid modes, not in the index): {}",
            held.join(", ")
        );
    }
    out!(
        "instability index {} (sum of d*neg){}",
        spectrum.index,
        if spectrum.index == 0 { ": stable" } else { "" }
    );
    Ok(())
}

/// The state to analyse: with `--point`, path point N of the run in RUN_DIR (its scene
/// rebuilt and checked, the state read from path.states); else the scene's start state with
/// the `--at` overrides. Returns the study, the overrides, u, Λ, Newton's iterations and,
/// with `--point`, the point and the index the run recorded there.
#[allow(clippy::type_complexity)]
fn state(
    args: &SpectrumArgs,
) -> Result<
    (
        memstab::study::mesh::MeshStudy,
        Vec<(usize, f64)>,
        Vec<f64>,
        Vec<f64>,
        usize,
        Option<(usize, Option<usize>)>,
    ),
    CliError,
> {
    if let Some(n) = args.point {
        if !args.at.is_empty() {
            return Err(CliError::Input(format!(
                "--at '{}' with --point {n}: a saved point's parameters are those of the run",
                args.at[0]
            )));
        }
        let p = saved_point(&args.input, args.scene.as_deref(), n)?;
        let index = p.run.index_at(n);
        return Ok((p.study, Vec::new(), p.u, p.params, 0, Some((n, index))));
    }
    if let Some(scene) = &args.scene {
        return Err(CliError::Input(format!(
            "--scene '{}' goes with --point N (the scene of a run directory)",
            scene.display()
        )));
    }
    let mut study = build_study(load_scene(&args.input)?)?;
    let start = super::common::start_of(&study)?;
    let at = parse_at(&args.at, &study.parameters)?;
    let Point {
        u,
        params,
        iterations,
        ..
    } = state_at(&mut study, &at, &start).map_err(|e| not_converged(&e, &at))?;
    Ok((study, at, u, params, iterations, None))
}

/// A start solve that failed: with `--at`, the values may lie where no equilibrium near the
/// start exists (past a turning point of the control), so a saved point is the way there.
pub(super) fn not_converged(e: &memstab::analysis::RunError, at: &[(usize, f64)]) -> CliError {
    let message = one_line(&e.to_string());
    if e.interrupted() {
        return CliError::Interrupted(format!("{message}; nothing was printed or written"));
    }
    let memstab::analysis::RunError::Start { error, control, .. } = e else {
        return CliError::Failure(message);
    };
    if at.is_empty() {
        return CliError::Failure(message);
    }
    // With --at, the cause is said below, for the values given.
    let message = one_line(
        &memstab::analysis::RunError::Start {
            error: error.clone(),
            control: control.clone(),
            cause: None,
        }
        .to_string(),
    );
    CliError::Failure(format!(
        "{message}; with --at the state is solved afresh from the start guess, and no \
         equilibrium may exist there (past a turning point of the control the path does not \
         return to these values, or only on an unstable branch); to analyse a point of a path, \
         run the scene and give `memstab spectrum RUN_DIR --point N` (N a step of its path.csv)"
    ))
}

/// `1 iteration`, `4 iterations`.
fn plural(n: usize, word: &str) -> String {
    if n == 1 {
        format!("{n} {word}")
    } else {
        format!("{n} {word}s")
    }
}
