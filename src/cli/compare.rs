//! `memstab compare SCENE --meshes A,B,… [--refine] [--max X] [--divisions D] [--samples N]
//! [--include-flagged] [--json] [--quiet]`: the same scene on meshes of different symmetry,
//! side by side (the critical points flagged as not results of the model listed apart, and
//! matched only with `--include-flagged`). The meshes, the matching of critical points and
//! the measured gaps are
//! [`memstab::analysis::compare`]'s; this prints them as a table or one JSON object.
//!
//! Bad input (a scene that does not load or build, a mesh that is not a subgroup or does not
//! parse, an equilibrium analysis, a bad `--max`) is one line and exit code 2,
//! before anything runs; a start state that does not converge is exit code 1.

use super::common::{load_scene, sci, sig_digits};
use super::CliError;
use clap::Args;
use memstab::analysis::compare::{
    compare, parse_meshes, CompareError, CompareOptions, Comparison, Image,
};
use memstab::scene::Generator;
use std::io::IsTerminal;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub(crate) struct CompareArgs {
    /// The scene file (TOML; see docs/scenes.md).
    scene: PathBuf,
    /// The meshes, comma-separated, the first the reference: group names (C8v, C2v, C1v: the
    /// scene's generator with that group or pattern) or full overrides
    /// GENERATOR:KEY=VALUE,... (e.g. disc:sectors=8,divisions=12,group=C2v); `axisymmetric`
    /// (or axisymmetric:elements=N) runs the scene on its meridian as the continuum reference.
    #[arg(long, required = true, value_name = "A,B,...")]
    meshes: Vec<String>,
    /// Also run every mesh at twice its divisions and report how the gaps shrink.
    #[arg(long)]
    refine: bool,
    /// The control's upper bound (default: the scene's `max`).
    #[arg(long, value_name = "VALUE", allow_negative_numbers = true)]
    max: Option<f64>,
    /// Divisions of every disc or truncated sphere (an icosphere's frequency), unless a full
    /// override sets them.
    #[arg(long, value_name = "D")]
    divisions: Option<usize>,
    /// Samples of a linear-buckling sweep (a path's step budget); default: the scene's, scaled
    /// with --max to keep the sample spacing.
    #[arg(long, value_name = "N")]
    samples: Option<usize>,
    /// Match the critical points flagged as not results of the model (wrinkled, not
    /// localised) too; by default they are listed apart.
    #[arg(long)]
    include_flagged: bool,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    json: bool,
    /// No progress lines on stderr.
    #[arg(long)]
    quiet: bool,
}

pub(crate) fn run(args: &CompareArgs) -> Result<(), CliError> {
    let scene = load_scene(&args.scene)?;
    let error = |e: CompareError| match e {
        CompareError::Input(m) => CliError::Input(m),
        CompareError::Failure(m) => CliError::Failure(m),
        CompareError::Interrupted(m) => CliError::Interrupted(m),
    };
    let options = CompareOptions {
        meshes: parse_meshes(&args.meshes).map_err(error)?,
        refine: args.refine,
        max: args.max,
        divisions: args.divisions,
        samples: args.samples,
        include_flagged: args.include_flagged,
    };
    let quiet = args.quiet || !std::io::stderr().is_terminal();
    let progress = |line: &str| {
        if !quiet {
            eprintln!("compare: {line}");
        }
    };
    let comparison = compare(&scene, &options, &progress).map_err(error)?;
    if args.json {
        let text =
            serde_json::to_string(&comparison).map_err(|e| CliError::Failure(e.to_string()))?;
        out!("{text}");
    } else {
        print_table(&comparison);
    }
    Ok(())
}

/// Values with seven significant digits, joined.
fn values(v: &[f64]) -> String {
    if v.is_empty() {
        return "-".into();
    }
    v.iter()
        .map(|x| sig_digits(*x, 7))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Distances from the continuum, joined.
fn distances(d: &[f64]) -> String {
    d.iter().map(|d| sci(*d)).collect::<Vec<_>>().join(", ")
}

fn gap_text(image: &Image) -> String {
    match (image.gap, image.points.len()) {
        (Some(g), n) if n >= 2 => sci(g),
        (Some(_), _) => format!("0 (d={})", image.multiplicity),
        (None, _) => "-".into(),
    }
}

fn print_table(c: &Comparison) {
    let what = match (c.analysis, c.range, c.samples) {
        ("linear-buckling", Some([lo, hi]), Some(n)) => {
            format!(
                "linear buckling, {} swept over [{lo}, {hi}] in {n} samples",
                c.control
            )
        }
        ("path", range, Some(n)) => format!(
            "path in {}{}, at most {n} steps",
            c.control,
            range.map_or_else(String::new, |[lo, hi]| format!(" within [{lo}, {hi}]"))
        ),
        _ => format!("control {}", c.control),
    };
    out!("compare '{}' ({}): {what}", c.scene, c.origin);
    out!("meshes (the first is the reference):");
    let lw = c
        .meshes
        .iter()
        .map(|m| m.label.len())
        .max()
        .unwrap_or(4)
        .max(4);
    let mw = c
        .meshes
        .iter()
        .flat_map(|m| m.levels.iter().map(|l| l.mesh.len()))
        .max()
        .unwrap_or(4)
        .max(4);
    out!(
        "  {:<lw$}  {:<mw$}  {:<12} {:>6} {:>8} {:>8} {:>7}",
        "mesh",
        "options",
        "group",
        "nodes",
        "unknowns",
        "critical",
        "time"
    );
    for m in &c.meshes {
        for (l, level) in m.levels.iter().enumerate() {
            out!(
                "  {:<lw$}  {:<mw$}  {:<12} {:>6} {:>8} {:>8} {:>6.1}s",
                if l == 0 { m.label.as_str() } else { "" },
                level.mesh,
                if level.order == 0 {
                    format!("{} (inf)", level.group)
                } else {
                    format!("{} ({})", level.group, level.order)
                },
                level.nodes,
                level.unknowns,
                level.critical.len(),
                level.seconds
            );
            if let Some(note) = &level.note {
                out!("  {:<lw$}  {note}", "");
            }
            if level.critical.is_empty() && level.flagged.is_empty() {
                out!("  {:<lw$}  no critical point; stopped: {}", "", level.stop);
            } else if level.stop == memstab::results::StopReason::Interrupted {
                out!(
                    "  {:<lw$}  stopped: interrupted (points past its last one are not found)",
                    ""
                );
            } else if level.critical.is_empty() {
                out!(
                    "  {:<lw$}  no valid critical point ({} flagged below); stopped: {}",
                    "",
                    level.flagged.len(),
                    level.stop
                );
            }
            for w in &level.warnings {
                out!("  {:<lw$}  warning: {w}", "");
            }
            for p in &level.flagged {
                let why: Vec<String> = p.flags.iter().map(ToString::to_string).collect();
                out!(
                    "  {:<lw$}  flagged, not matched: {} in {} at {} = {} ({})",
                    "",
                    p.kind,
                    p.irrep,
                    c.control,
                    sig_digits(p.value, 6),
                    why.join("; ")
                );
            }
        }
    }
    if c.label.is_some() {
        out!(
            "images are matched by the wave number m of the critical mode about z and the \
             nearest {} on the same piece of the path; a gap is measured between the images on \
             a mesh, never inferred from its group",
            c.control
        );
    } else {
        out!(
            "images are matched by the nearest {} on the same piece of the path (no wave number \
             for this generator); a gap is measured between the images on a mesh, never \
             inferred from its group",
            c.control
        );
    }
    if c.rungs.is_empty() {
        out!(
            "the reference mesh '{}' has no critical point in range",
            c.reference
        );
    } else {
        let refine = c.refine;
        let iw = c
            .rungs
            .iter()
            .flat_map(|r| {
                r.images
                    .iter()
                    .flat_map(|i| i.levels.iter().map(|l| l.irreps.join(" + ").len()))
            })
            .max()
            .unwrap_or(6)
            .max(6);
        let vw = c
            .rungs
            .iter()
            .flat_map(|r| {
                r.images
                    .iter()
                    .flat_map(|i| i.levels.iter().map(|l| values(&l.values).len()))
            })
            .max()
            .unwrap_or(5)
            .max(c.control.len());
        // With a meridian, each value's distance from the continuum's.
        let continuum = c.rungs.iter().any(|r| r.continuum.is_some());
        let dw = c
            .rungs
            .iter()
            .flat_map(|r| r.images.iter().flat_map(|i| &i.levels))
            .map(|l| distances(&l.distances).len())
            .max()
            .unwrap_or(0)
            .max(9);
        let head = format!(
            "{:>4} {:>3}  {:<lw$}  {:<iw$}  {:<vw$}  {:>10}{}",
            "rung",
            "m",
            "mesh",
            "irreps",
            c.control,
            "gap",
            if continuum {
                format!("  {:<dw$}", "distance")
            } else {
                String::new()
            }
        );
        if refine {
            out!("{head} {:>10} {:>6}  verdict", "gap fine", "order");
        } else {
            out!("{head}  verdict");
        }
        for (n, r) in c.rungs.iter().enumerate() {
            for (k, im) in r.images.iter().enumerate() {
                let (num, m) = if k == 0 {
                    (
                        (n + 1).to_string(),
                        r.m.map_or_else(|| "-".to_string(), |m| m.to_string()),
                    )
                } else {
                    (String::new(), String::new())
                };
                // The first run's images, or the refined run's where the first has none.
                let coarse = &im.levels[0];
                let only_refined = coarse.points.is_empty()
                    && im.levels.get(1).is_some_and(|f| !f.points.is_empty());
                let shown = if only_refined { &im.levels[1] } else { coarse };
                let irreps = if shown.irreps.is_empty() {
                    "-".to_string()
                } else {
                    shown.irreps.join(" + ")
                };
                let distance = match (continuum, c.meshes[k].generator.as_str()) {
                    (false, _) => String::new(),
                    (true, "axisymmetric") if !shown.values.is_empty() => {
                        // Its own error: the meridian at N against 2N elements.
                        let own = r
                            .continuum_error
                            .map_or_else(String::new, |e| format!(" ±{}", sci(e)));
                        format!("  {:<dw$}", format!("continuum{own}"))
                    }
                    (true, _) if shown.distances.is_empty() => format!("  {:<dw$}", "-"),
                    (true, _) => format!("  {:<dw$}", distances(&shown.distances)),
                };
                let line = format!(
                    "{num:>4} {m:>3}  {:<lw$}  {irreps:<iw$}  {:<vw$}  {:>10}{distance}",
                    im.mesh,
                    values(&shown.values),
                    gap_text(coarse)
                );
                if refine {
                    let fine = im.levels.get(1);
                    let order = im
                        .order
                        .map_or_else(|| "-".to_string(), |o| format!("{o:.2}"));
                    let mut verdict = coarse.verdict.to_string();
                    if let Some(f) = fine {
                        if only_refined {
                            verdict = format!("refined run only: {}", f.verdict);
                        } else if f.verdict != coarse.verdict {
                            verdict = format!("{verdict} (refined: {})", f.verdict);
                        }
                    }
                    out!(
                        "{line} {:>10} {order:>6}  {verdict}",
                        fine.map_or_else(|| "-".to_string(), gap_text)
                    );
                } else {
                    out!("{line}  {}", coarse.verdict);
                }
            }
            for o in &r.orders {
                out!(
                    "{:>10}observed order of the distance on {}: {} -> {}: {:.2}",
                    "",
                    o.group,
                    o.coarse,
                    o.fine,
                    o.order
                );
            }
        }
    }
    let coarse: Vec<String> = (c.rungs.iter().enumerate())
        .filter(|(_, r)| r.continuum_coarse)
        .map(|(n, _)| (n + 1).to_string())
        .collect();
    if !coarse.is_empty() {
        out!(
            "warning: the meridian's own error (its run at twice the elements; ±) is not small against the 3-D distances at rung{} {}: give it more elements (axisymmetric:elements=N)",
            if coarse.len() > 1 { "s" } else { "" },
            coarse.join(", ")
        );
    }
    if !c.unmatched.is_empty() {
        out!("points without a counterpart on the reference mesh:");
        for u in &c.unmatched {
            out!(
                "  {} ({} {}): {} at {} = {}{}{}",
                u.mesh,
                c.meshes
                    .iter()
                    .find(|m| m.label == u.mesh)
                    .and_then(|m| Generator::from_name(&m.generator))
                    .and_then(Generator::resolution_key)
                    .unwrap_or("divisions"),
                u.resolution,
                u.irrep,
                c.control,
                sig_digits(u.value, 7),
                u.m.map_or_else(String::new, |m| format!(" (m = {m})")),
                if u.rising {
                    String::new()
                } else {
                    format!(", met as {} falls", c.control)
                }
            );
        }
    }
}
