//! `memstab spectrum SCENE [--at NAME=VALUE]... [--count N] [--json]`: the tangent's spectrum
//! by irrep at the scene's start state.
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

use super::common::{build_study, load_scene, one_line, parse_at, sci};
use super::CliError;
use clap::Args;
use memstab::adapted::AdaptedBasis;
use memstab::analysis::equilibrium::{held, state_at, StartState};
use memstab::model::Model;
use memstab::stability::{Detail, Stability};
use serde::Serialize;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub(crate) struct SpectrumArgs {
    /// The scene file (TOML; see docs/scenes.md).
    scene: PathBuf,
    /// Set a parameter instead of its start value (repeatable), e.g. `--at p=1.3`.
    #[arg(long = "at", value_name = "NAME=VALUE")]
    at: Vec<String>,
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
    irreps: Vec<IrrepJson>,
}

pub(crate) fn run(args: &SpectrumArgs) -> Result<(), CliError> {
    let scene = load_scene(&args.scene)?;
    let mut study = build_study(scene)?;
    let origin = study.scene.origin.clone();
    let at = parse_at(&args.at, &study.parameters)?;
    let held = held(&study);
    let StartState {
        u,
        params,
        iterations,
    } = state_at(&mut study, &at).map_err(|e| CliError::Failure(one_line(&e.to_string())))?;
    let adapted = AdaptedBasis::new(&study.action, study.model.layout())
        .map_err(|e| CliError::Input(format!("scene '{origin}': {e}")))?;
    let stability = Stability::new(&study.model, &adapted);
    let mut eval = study.model.new_evaluation();
    let spectrum = stability
        .analyse(
            &u,
            &params,
            &study.constraints,
            &mut eval,
            None,
            Detail::Eigenvalues { lowest: args.count },
        )
        .map_err(|e| {
            CliError::Failure(format!(
                "the tangent could not be evaluated: {}",
                one_line(&e.to_string())
            ))
        })?;
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
    if held {
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

/// `1 iteration`, `4 iterations`.
fn plural(n: usize, word: &str) -> String {
    if n == 1 {
        format!("{n} {word}")
    } else {
        format!("{n} {word}s")
    }
}
