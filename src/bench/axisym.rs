//! The axisymmetric model, timed: the balloon of `scenes/axisymmetric/balloon.toml` on a
//! meridian of 200 quadratic elements (quick: 64) followed from stretch 1.05 to 4 through its
//! pressure maximum and minimum with the index of every wave number m = 0..20 at every point,
//! as `memstab run` runs it: points, wall time, time per point, of it the blocks, and the
//! turning pressures against the closed form; and the Paper 4 cap of
//! `scenes/axisymmetric/paper4_spinning_cap.toml` (filled fluid, spin, floor, sliding edge,
//! fluid volume held) with its critical points by wave number.

use crate::analysis::run;
use crate::scene::Scene;
use crate::study::meridian::MeridianStudy;
use crate::text::sig_digits;
use std::time::Instant;

/// The bundled axisymmetric balloon scene text (64 elements, modes 0..20).
pub const AXISYM_BALLOON_TOML: &str = include_str!("../../scenes/axisymmetric/balloon.toml");

/// The balloon's pressure maximum and minimum, closed form (k = 0.1).
const TURNS: [f64; 2] = [1.355_106_9, 1.148_747_7];

/// One timed axisymmetric path: the markdown section.
pub fn axisym_section(elements: usize) -> Result<String, String> {
    let text = AXISYM_BALLOON_TOML.replacen("elements = 64", &format!("elements = {elements}"), 1);
    let scene = Scene::from_toml_str(&text, &format!("axisymmetric balloon, {elements} elements"))
        .map_err(|e| e.to_string())?;
    let t = Instant::now();
    let mut study = MeridianStudy::build(scene).map_err(|e| e.to_string())?;
    let result = run(&mut study, |_, _| {}).map_err(|e| e.to_string())?;
    let wall = t.elapsed().as_secs_f64();
    let report = &result.report;
    let points = report.rows.len();
    let mut md = format!(
        "\n## Axisymmetric balloon: modes 0..{} at every point\n\n\
         | elements | unknowns | points | wall (s) | per point (ms) | of it blocks (s) | p_max error | p_min error | critical points |\n\
         |---|---|---|---|---|---|---|---|---|\n",
        study.modes
    );
    let err = |k: usize| {
        report.turning_points.get(k).map_or("—".to_string(), |t| {
            format!("{:.1e}", (t.parameters[0] - TURNS[k]) / TURNS[k])
        })
    };
    let critical: Vec<String> = report
        .critical
        .iter()
        .zip(&report.wave_numbers)
        .map(|(c, m)| format!("m = {m} at {}", sig_digits(c.parameters[0], 8)))
        .collect();
    md += &format!(
        "| {elements} | {} | {points} | {wall:.3} | {:.2} | {:.3} | {} | {} | {} |\n",
        report.unknowns,
        1e3 * wall / points.max(1) as f64,
        result.times.index.as_secs_f64(),
        err(0),
        err(1),
        critical.join(", ")
    );
    Ok(md)
}

/// The bundled axisymmetric Paper 4 scene text (128 elements, modes 0..8).
pub const AXISYM_PAPER4_TOML: &str =
    include_str!("../../scenes/axisymmetric/paper4_spinning_cap.toml");

/// The Paper 4 cap on meridians of `levels` elements, timed: the markdown section.
pub fn paper4_section(levels: &[usize]) -> Result<String, String> {
    let mut md = "\n## Axisymmetric Paper 4 cap: modes 0..8 at every point\n\n\
         | elements | unknowns | points | wall (s) | per point (ms) | of it blocks (s) | critical points (m at w2) |\n\
         |---|---|---|---|---|---|---|\n"
        .to_string();
    for &elements in levels {
        let text =
            AXISYM_PAPER4_TOML.replacen("elements = 128", &format!("elements = {elements}"), 1);
        let scene = Scene::from_toml_str(&text, &format!("axisymmetric Paper 4 cap, {elements}"))
            .map_err(|e| e.to_string())?;
        let t = Instant::now();
        let mut study = MeridianStudy::build(scene).map_err(|e| e.to_string())?;
        let result = run(&mut study, |_, _| {}).map_err(|e| e.to_string())?;
        let wall = t.elapsed().as_secs_f64();
        let report = &result.report;
        let points = report.rows.len();
        let w2 = report
            .parameters
            .iter()
            .position(|p| p == "w2")
            .unwrap_or(0);
        let critical: Vec<String> = report
            .critical
            .iter()
            .zip(&report.wave_numbers)
            .map(|(c, m)| format!("m = {m} at {}", sig_digits(c.parameters[w2], 7)))
            .collect();
        md += &format!(
            "| {elements} | {} | {points} | {wall:.3} | {:.2} | {:.3} | {} |\n",
            report.unknowns,
            1e3 * wall / points.max(1) as f64,
            result.times.index.as_secs_f64(),
            critical.join(", ")
        );
    }
    Ok(md)
}
