//! The ponding ladder of a clamped pre-stretched C7v disc under a fluid of rising density:
//! the first rungs (m, 1), m = 0 … 3, found by `run` against the closed form
//! [`PONDING_SCALE`] × j²_{m,1} ([`BESSEL_J2`]).

use crate::model::Model;
use crate::reference::{BESSEL_J2, PONDING_SCALE};
use crate::scene::Scene;
use crate::study::mesh::MeshStudy;
use std::time::{Duration, Instant};

/// The bundled ponding scene text (C7v disc, `divisions = 16`).
pub const PONDING_TOML: &str = include_str!("../../scenes/ponding.toml");

/// The rungs (m, k) of the ladder the study looks for, each the first of its wave number m.
pub const RUNGS: [(usize, usize); 4] = [(0, 1), (1, 1), (2, 1), (3, 1)];

/// The ponding scene on a C7v disc with `divisions`, density swept over [0, `max`] in
/// `samples` steps.
pub fn ponding_scene(divisions: usize, max: f64, samples: usize) -> Result<Scene, String> {
    let text = PONDING_TOML
        .replace("divisions = 16 ", &format!("divisions = {divisions} "))
        .replace("max = 46.0 ", &format!("max = {max} "))
        .replace("samples = 92", &format!("samples = {samples}"));
    Scene::from_toml_str(&text, &format!("ponding, divisions {divisions}"))
        .map_err(|e| e.to_string())
}

/// One rung of the ponding ladder found on a mesh.
#[derive(Debug, Clone)]
pub struct Rung {
    /// (m, k) of the closed form.
    pub mk: (usize, usize),
    /// Irrep of the singular block.
    pub irrep: String,
    /// Multiplicity d_μ.
    pub multiplicity: usize,
    /// Critical density found.
    pub rho: f64,
    /// Closed form PONDING_SCALE × j²_{m,k}.
    pub exact: f64,
}

/// A ponding run on one disc.
#[derive(Debug, Clone)]
pub struct PondingLevel {
    /// Radial divisions of the disc.
    pub divisions: usize,
    /// The disc's group: C7v, or the chiral C7 of [`ponding_level_in`].
    pub group: String,
    /// Triangles.
    pub elements: usize,
    /// Unknowns.
    pub unknowns: usize,
    /// Rungs found (the first of each tabulated (m, 1)).
    pub rungs: Vec<Rung>,
    /// Wall time of `run` (start state, sweep, localisation).
    pub time: Duration,
}

/// The ponding ladder on a C7v disc with `divisions`, density swept over [0, 20] in 60 steps
/// (past the (3, 1) rung at 14.65 even on coarse discs), by [`crate::analysis::run`].
pub fn ponding_level(divisions: usize) -> Result<PondingLevel, String> {
    ponding_level_in(divisions, None)
}

/// [`ponding_level`] on the same disc with its group replaced by `group` (a subgroup of C7v:
/// the chiral C7, whose E_k blocks are of complex type).
pub fn ponding_level_in(divisions: usize, group: Option<&str>) -> Result<PondingLevel, String> {
    let t = Instant::now();
    let scene = match group {
        None => ponding_scene(divisions, 20.0, 60)?,
        Some(g) => {
            let text = PONDING_TOML
                .replace(
                    "divisions = 16 ",
                    &format!("group = \"{g}\"\ndivisions = {divisions} "),
                )
                .replace("max = 46.0 ", "max = 20.0 ")
                .replace("samples = 92", "samples = 60");
            Scene::from_toml_str(&text, &format!("ponding on {g}, divisions {divisions}"))
                .map_err(|e| e.to_string())?
        }
    };
    let mut study = MeshStudy::build(scene).map_err(|e| e.to_string())?;
    let r = crate::analysis::run(&mut study, |_, _| {})
        .map_err(|e| e.to_string())?
        .report;
    let time = t.elapsed();
    let mut rungs = Vec::new();
    for (m, k) in RUNGS {
        let j2 = BESSEL_J2
            .iter()
            .find(|(mk, _)| *mk == (m, k))
            .map(|(_, j2)| *j2)
            .ok_or_else(|| format!("no tabulated Bessel zero j_({m},{k})"))?;
        let found = r
            .critical
            .iter()
            .filter(|c| wave_number(&study, &c.mode) == m)
            .min_by(|a, b| a.parameters[0].total_cmp(&b.parameters[0]));
        if let Some(c) = found {
            rungs.push(Rung {
                mk: (m, k),
                irrep: c.irrep.clone(),
                multiplicity: c.multiplicity,
                rho: c.parameters[0],
                exact: PONDING_SCALE * j2,
            });
        }
    }
    Ok(PondingLevel {
        divisions,
        group: study.action.group().name().to_string(),
        elements: study.model.layout().triangles().len(),
        unknowns: study.model.unknowns(),
        rungs,
        time,
    })
}

/// The wave number of a critical mode about z (see [`crate::adapted::labels::wave_number`]).
pub fn wave_number(study: &MeshStudy, mode: &[f64]) -> usize {
    crate::adapted::labels::wave_number(study.model.reference(), study.model.layout(), mode, 12)
}
