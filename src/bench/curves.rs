//! Critical curves, timed: the balloon's limit point followed in (p, k) through its cusp
//! (the closed form's fold line, [`crate::reference`] §13.1 of docs/theory.md), and the first
//! E1 double point of the C7v disc under fluid from below followed in its prestretch.

use crate::analysis::run;
use crate::results::{CurveEventKind, CurveReport};
use crate::scene::Scene;
use crate::study::mesh::MeshStudy;
use std::time::{Duration, Instant};

/// The bundled fluid-below disc scene text (C7v, 16 divisions).
const DISC_FLUID_BELOW_TOML: &str = include_str!("../../scenes/disc_fluid_below.toml");

/// `text` with its `[analysis]` section (the last one) replaced by `analysis`.
fn with_analysis(text: &str, analysis: &str) -> String {
    let at = text.find("[analysis]").unwrap_or(text.len());
    let rest = text[at..].find("\n[start]").map_or("", |i| &text[at + i..]);
    format!("{}{analysis}{rest}", &text[..at])
}

/// The bundled balloon with k = "k" (start 0.1, bounds [0.05, 0.3]) and a critical-curve
/// analysis from its pressure maximum, at frequency `frequency`, `steps` curve steps of at
/// most `max_step`, the other blocks watched or not (`watch`).
pub fn fold_line_scene(
    frequency: usize,
    steps: usize,
    max_step: f64,
    watch: bool,
) -> Result<Scene, String> {
    let analysis = format!(
        "[parameters.k]\nstart = 0.1\nmin = 0.05\nmax = 0.3\n\n[analysis]\ntype = \
         \"critical-curve\"\ncontrol = \"p\"\nsecond = \"k\"\nfrom = \"limit\"\nsteps = \
         {steps}\npath-steps = 400\nmax-step = {max_step}\ninitial-step = {max_step}\n\
         watch = {watch}\n"
    );
    let text = with_analysis(super::BALLOON_TOML, &analysis)
        .replacen("k = 0.1\n", "k = \"k\"\n", 1)
        .replacen("frequency = 8 ", &format!("frequency = {frequency} "), 1);
    Scene::from_toml_str(&text, &format!("balloon fold line, frequency {frequency}"))
        .map_err(|e| e.to_string())
}

/// The fluid-below C7v disc at `divisions` with prestretch = "l0" (start 1.1, bounds
/// [1.05, 1.4]) and a critical-curve analysis from its first E1 double point.
pub fn double_curve_scene(divisions: usize, steps: usize) -> Result<Scene, String> {
    let analysis = format!(
        "[parameters.l0]\nstart = 1.1\nmin = 1.05\nmax = 1.4\n\n[analysis]\ntype = \
         \"critical-curve\"\ncontrol = \"h\"\nsecond = \"l0\"\nfrom = \"E1\"\nsteps = \
         {steps}\npath-steps = 400\nmax-step = 0.02\ninitial-step = 0.02\n"
    );
    let text = with_analysis(DISC_FLUID_BELOW_TOML, &analysis)
        .replacen("divisions = 16", &format!("divisions = {divisions}"), 1)
        .replacen("prestretch = 1.1", "prestretch = \"l0\"", 1);
    Scene::from_toml_str(
        &text,
        &format!("C7v disc double curve, {divisions} divisions"),
    )
    .map_err(|e| e.to_string())
}

/// One timed critical curve.
#[derive(Debug, Clone)]
pub struct CurveRun {
    /// What was followed.
    pub label: String,
    /// Unknowns of the model and of the fixed-point space.
    pub unknowns: (usize, usize),
    /// The run's result.
    pub curve: CurveReport,
    /// Wall time of the path that found the point (start solve included).
    pub path: Duration,
    /// Wall time of the whole run; the curve is the difference.
    pub total: Duration,
}

/// Runs `scene` and times it.
pub fn curve_run(label: &str, scene: Scene) -> Result<CurveRun, String> {
    let mut study = MeshStudy::build(scene).map_err(|e| e.to_string())?;
    let unknowns = (study.basis.unknowns(), study.basis.dim());
    let t = Instant::now();
    let result = run(&mut study, |_, _| {}).map_err(|e| e.to_string())?;
    let total = t.elapsed();
    let path = result.times.start + result.times.adapted_basis + result.times.path;
    let curve = result
        .outcome::<CurveReport>()
        .cloned()
        .ok_or("the run made no curve")?;
    Ok(CurveRun {
        label: label.to_string(),
        unknowns,
        curve,
        path,
        total,
    })
}

/// The markdown table of the runs, with the cusp of each limit curve.
pub fn curves_table(runs: &[CurveRun]) -> String {
    let mut md = String::from(
        "| curve | unknowns (fixed-point) | points | path to the point (s) | curve (s) | per point (ms) | events |\n|---|---|---|---|---|---|---|\n",
    );
    for r in runs {
        let curve = r.total.saturating_sub(r.path);
        let n = r.curve.rows.len();
        let events: Vec<String> = r
            .curve
            .events
            .iter()
            .filter(|e| matches!(e.kind, CurveEventKind::Cusp | CurveEventKind::Fold))
            .map(|e| {
                let at: Vec<String> = r
                    .curve
                    .parameters
                    .iter()
                    .zip(&e.parameters)
                    .map(|(name, v)| format!("{name} = {v:.7}"))
                    .collect();
                format!("{} at {}", e.kind, at.join(", "))
            })
            .collect();
        md += &format!(
            "| {} | {} ({}) | {n} | {:.2} | {:.2} | {:.1} | {} |\n",
            r.label,
            r.unknowns.0,
            r.unknowns.1,
            r.path.as_secs_f64(),
            curve.as_secs_f64(),
            1e3 * curve.as_secs_f64() / n.max(1) as f64,
            if events.is_empty() {
                "none".to_string()
            } else {
                events.join("; ")
            }
        );
    }
    md
}
