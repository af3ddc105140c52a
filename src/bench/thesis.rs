//! The thesis-size study behind `memstab bench --thesis`: a Paper 4-like cap — the clamped
//! truncated sphere (c = −R/2) filled with fluid under a head above its top and spinning about
//! z, ω² the control — on the patterns C8v, C4v, C2v, C1v and C1 at ≈ 5 400 triangles (and C2v
//! at 4× that), each run as `memstab run` runs it (the index by irrep at every point, every
//! crossing localised), timed by phase, against the same path's states analysed without
//! symmetry: the index of the full K (one sparse LBLᵀ per point) and, with it, its 20
//! eigenvalues nearest a shift by sparse shift-invert ([`super::full_path_stability`]); scipy
//! `eigsh` on the exported K at the last point when a python with scipy is found.
//!
//! The fluid here is the gravity fluid of a cap on a plate (`side = "inside"`) with its level
//! above the top, so the cap is full; the spin acts on the same enclosed region.

use super::full_path::{full_path_stability, FullPathStability};
use super::peer::{run_peer, PeerResult};
use crate::analysis::{run_with, Observer};
use crate::model::Model;
use crate::results::{PathReport, RunTimes};
use crate::scene::Scene;
use crate::study::mesh::MeshStudy;
use std::path::Path;
use std::time::{Duration, Instant};

/// The scene: `{pattern}`, `{divisions}` and `{steps}` are replaced.
pub const SPINNING_CAP_TOML: &str = r#"
[scene]
name = "spinning-cap"
description = "Clamped cap full of fluid under a head above its top, spinning about z"
[mesh]
generator = "truncated-sphere"
cut-height = -0.5
pattern = "{pattern}"
divisions = {divisions}
[material]
mu = 100.0
k = 0.1
thickness = 0.01
prestretch = 1.05
[[effect]]
type = "fluid"
side = "inside"
density = 1.0
gravity = 1.0
level = 1.5
[[effect]]
type = "spin"
density = 1.0
omega2 = "w"
[boundary]
fixed = ["cut"]
[parameters.w]
start = 0.0
max = 40.0
[analysis]
type = "path"
control = "w"
steps = {steps}
initial-step = 0.05
max-step = 0.5
save-every = 1000
"#;

/// The spinning cap on `pattern` with `divisions` (8 d² triangles), `steps` path steps.
pub fn spinning_cap_scene(pattern: &str, divisions: usize, steps: usize) -> Result<Scene, String> {
    let text = SPINNING_CAP_TOML
        .replace("{pattern}", pattern)
        .replace("{divisions}", &divisions.to_string())
        .replace("{steps}", &steps.to_string());
    Scene::from_toml_str(&text, "spinning-cap").map_err(|e| e.to_string())
}

/// One run of the study.
#[derive(Debug, Clone)]
pub struct ThesisRun {
    /// The mesh pattern (the scene's group).
    pub pattern: String,
    /// Triangles.
    pub elements: usize,
    /// Unknowns of the model.
    pub unknowns: usize,
    /// Unknowns of the fixed-point space.
    pub symmetric_unknowns: usize,
    /// Columns of the largest irrep block.
    pub largest_block: usize,
    /// Path points.
    pub points: usize,
    /// Wall time of the run (study built, start solve, basis, path with stability).
    pub total: Duration,
    /// Building the study (mesh, group action, model).
    pub study: Duration,
    /// The run's phases.
    pub times: RunTimes,
    /// The critical points found: (irrep, control value, |eigenvalue|/‖K‖).
    pub critical: Vec<(String, f64, f64)>,
    /// The run's warnings (crossings that could not be localised).
    pub warnings: Vec<String>,
    /// The same states without symmetry (`None` at the finest level, not run).
    pub full: Option<FullPathStability>,
    /// scipy `eigsh` on the last point's K.
    pub peer: Option<Result<PeerResult, String>>,
}

impl ThesisRun {
    /// The localisation: the events' time without the index at every point.
    pub fn localisation(&self) -> Duration {
        self.times.steps.events.saturating_sub(self.times.index)
    }
}

/// Keeps every accepted state.
struct States(Vec<(Vec<f64>, Vec<f64>)>);

impl Observer for States {
    fn state(&mut self, u: &[f64], params: &[f64]) {
        self.0.push((u.to_vec(), params.to_vec()));
    }
}

/// Runs the cap on `pattern` with `divisions` for `steps` steps as `memstab run` does, then
/// (with `compare`) the same states without symmetry and (with `peer_out`) scipy on the last.
pub fn thesis_run(
    pattern: &str,
    divisions: usize,
    steps: usize,
    compare: bool,
    peer_out: Option<&Path>,
) -> Result<ThesisRun, String> {
    let wall = Instant::now();
    let mut study = MeshStudy::build(spinning_cap_scene(pattern, divisions, steps)?)
        .map_err(|e| e.to_string())?;
    let study_time = wall.elapsed();
    let mut states = States(Vec::new());
    let result = run_with(&mut study, &mut states).map_err(|e| e.to_string())?;
    let total = wall.elapsed();
    let report: &PathReport = &result.report;
    let control = study.control.unwrap_or(0);
    let largest_block = crate::adapted::AdaptedBasis::new(&study.action, study.model.layout())
        .map(|b| b.irreps.iter().map(|i| i.first().dim()).max().unwrap_or(0))
        .unwrap_or(0);
    let full = if compare {
        Some(full_path_stability(&study, &states.0, 20, false)?)
    } else {
        None
    };
    let peer = peer_out.and_then(|out| {
        let (u, p) = states.0.last()?;
        Some(run_peer(out, &study, u, p, -1e-3))
    });
    Ok(ThesisRun {
        pattern: pattern.to_string(),
        elements: report.mesh.elements,
        unknowns: report.unknowns,
        symmetric_unknowns: report.symmetric_unknowns,
        largest_block,
        points: report.rows.len(),
        total,
        study: study_time,
        times: result.times,
        critical: report
            .critical
            .iter()
            .map(|c| {
                (
                    c.irrep.clone(),
                    c.parameters[control],
                    c.residual_eigenvalue,
                )
            })
            .collect(),
        warnings: report.warnings.clone(),
        full,
        peer,
    })
}

/// The markdown of the study.
pub fn thesis_table(runs: &[ThesisRun]) -> String {
    let ms = |d: Duration| format!("{:.0}", d.as_secs_f64() * 1e3);
    let mut md = String::from(
        "## The thesis caps: a spinning fluid-filled cap by mesh symmetry\n\n\
         Times in ms, wall. total = the whole run as `memstab run` does it (study, start, \
         adapted basis, path with the index by irrep at every point, every crossing \
         localised), outputs not written; path = the steps of the follower (of which asm = \
         assembly, proj = restriction to the fixed-point space; the rest is the linear \
         algebra); index = the negative count of every block at every point; loc = the \
         localisation of the crossings; full index = the same states without symmetry: one \
         sparse LBLᵀ of the whole K per point, its assembly and symbolic analysis included; \
         full + 20 = that and the 20 eigenvalues nearest σ = −1e-3 max|K_ij| by shift-invert.\n\n\
         | mesh | triangles | unknowns | fixed-point | largest block | points | total | start | basis | path | asm | proj | index | index/pt | loc | full index | full index/pt | full + 20 | critical points | not localised |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in runs {
        let t = &r.times;
        let per = |d: Duration| format!("{:.1}", d.as_secs_f64() * 1e3 / r.points.max(1) as f64);
        let critical = r
            .critical
            .iter()
            .map(|(irrep, v, res)| format!("{irrep} {v:.6} ({res:.0e})"))
            .collect::<Vec<_>>()
            .join(", ");
        let (full, full_per, full20) = r.full.as_ref().map_or(
            ("–".to_string(), "–".to_string(), "–".to_string()),
            |f| (ms(f.index_only()), per(f.index_only()), ms(f.total())),
        );
        md += &format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            r.pattern,
            r.elements,
            r.unknowns,
            r.symmetric_unknowns,
            r.largest_block,
            r.points,
            ms(r.total),
            ms(t.start),
            ms(t.adapted_basis),
            ms(t.steps.steps),
            ms(t.steps.steps_problem.assembly),
            ms(t.steps.steps_problem.projection),
            ms(t.index),
            per(t.index),
            ms(r.localisation()),
            full,
            full_per,
            full20,
            if critical.is_empty() { "none".into() } else { critical },
            r.warnings.len(),
        );
    }
    for r in runs {
        for w in &r.warnings {
            md += &format!("\n- {} ({} triangles): {w}", r.pattern, r.elements);
        }
        if let Some(peer) = &r.peer {
            md += &match peer {
                Ok(p) => format!(
                    "\n- {}: scipy `eigsh` (k = 20, σ = {:e}) on the last point's K: {:.0} ms ({})",
                    r.pattern,
                    p.sigma,
                    p.seconds * 1e3,
                    p.python
                ),
                Err(e) => format!("\n- {}: scipy `eigsh` not run: {e}", r.pattern),
            };
        }
    }
    md.push('\n');
    md
}

/// The bundled thesis scenes (`scenes/thesis/*.toml`), embedded in the binary: (file name,
/// text). `memstab bench --thesis` runs these, so an installed binary needs no source tree.
pub const THESIS_SCENES: &[(&str, &str)] = &[
    (
        "paper1_disc_above_cusp_level.toml",
        include_str!("../../scenes/thesis/paper1_disc_above_cusp_level.toml"),
    ),
    (
        "paper1_disc_cusps_prestretch.toml",
        include_str!("../../scenes/thesis/paper1_disc_cusps_prestretch.toml"),
    ),
    (
        "paper1_disc_irregular.toml",
        include_str!("../../scenes/thesis/paper1_disc_irregular.toml"),
    ),
    (
        "paper1_disc_irregular_diagram.toml",
        include_str!("../../scenes/thesis/paper1_disc_irregular_diagram.toml"),
    ),
    (
        "paper1_disc_limit_curve_k.toml",
        include_str!("../../scenes/thesis/paper1_disc_limit_curve_k.toml"),
    ),
    (
        "paper1_disc_limit_curve_radius.toml",
        include_str!("../../scenes/thesis/paper1_disc_limit_curve_radius.toml"),
    ),
    (
        "paper1_disc_swallowtail.toml",
        include_str!("../../scenes/thesis/paper1_disc_swallowtail.toml"),
    ),
    (
        "paper1_disc_swallowtail_radius.toml",
        include_str!("../../scenes/thesis/paper1_disc_swallowtail_radius.toml"),
    ),
    (
        "paper2_gas_pressure_fold.toml",
        include_str!("../../scenes/thesis/paper2_gas_pressure_fold.toml"),
    ),
    (
        "paper2_gas_pressure_fold_f8.toml",
        include_str!("../../scenes/thesis/paper2_gas_pressure_fold_f8.toml"),
    ),
    (
        "paper2_solution_surface.toml",
        include_str!("../../scenes/thesis/paper2_solution_surface.toml"),
    ),
    (
        "paper2_solution_surface_f8.toml",
        include_str!("../../scenes/thesis/paper2_solution_surface_f8.toml"),
    ),
    (
        "paper2_sphere_on_plane.toml",
        include_str!("../../scenes/thesis/paper2_sphere_on_plane.toml"),
    ),
    (
        "paper2_sphere_on_plane_f8.toml",
        include_str!("../../scenes/thesis/paper2_sphere_on_plane_f8.toml"),
    ),
    (
        "paper3_fluid_level_bifurcation.toml",
        include_str!("../../scenes/thesis/paper3_fluid_level_bifurcation.toml"),
    ),
    (
        "paper3_fluid_level_fold_line.toml",
        include_str!("../../scenes/thesis/paper3_fluid_level_fold_line.toml"),
    ),
    (
        "paper3_fluid_level_linear.toml",
        include_str!("../../scenes/thesis/paper3_fluid_level_linear.toml"),
    ),
    (
        "paper3_gas_fluid_pressure.toml",
        include_str!("../../scenes/thesis/paper3_gas_fluid_pressure.toml"),
    ),
    (
        "paper3_gas_fluid_squeeze.toml",
        include_str!("../../scenes/thesis/paper3_gas_fluid_squeeze.toml"),
    ),
    (
        "paper3_gas_fluid_squeeze_linear.toml",
        include_str!("../../scenes/thesis/paper3_gas_fluid_squeeze_linear.toml"),
    ),
    (
        "paper3_gas_fluid_squeeze_linear_diagram.toml",
        include_str!("../../scenes/thesis/paper3_gas_fluid_squeeze_linear_diagram.toml"),
    ),
    (
        "paper3_gas_fluid_squeeze_linear_thesis_mesh.toml",
        include_str!("../../scenes/thesis/paper3_gas_fluid_squeeze_linear_thesis_mesh.toml"),
    ),
    (
        "paper3_squeezed_cap.toml",
        include_str!("../../scenes/thesis/paper3_squeezed_cap.toml"),
    ),
    (
        "paper4_hilltop_k.toml",
        include_str!("../../scenes/thesis/paper4_hilltop_k.toml"),
    ),
    (
        "paper4_spinning_cap.toml",
        include_str!("../../scenes/thesis/paper4_spinning_cap.toml"),
    ),
    (
        "paper4_spinning_cap_clamped.toml",
        include_str!("../../scenes/thesis/paper4_spinning_cap_clamped.toml"),
    ),
];

/// The mesh files the bundled thesis scenes read, by their path relative to `scenes/` (a
/// scene's `mesh.path` is relative to its own directory, `scenes/thesis`).
pub const THESIS_MESHES: &[(&str, &[u8])] = &[(
    "meshes/disc_irregular.vtu",
    include_bytes!("../../scenes/meshes/disc_irregular.vtu"),
)];

/// Writes the bundled thesis scenes into `dir` as `dir/thesis/*.toml`, with the mesh files
/// they read beside them as in the source tree (`dir/meshes/…`); returns the scenes' paths in
/// the order of [`THESIS_SCENES`].
pub fn write_thesis_scenes(dir: &Path) -> Result<Vec<std::path::PathBuf>, String> {
    let write = |rel: &str, bytes: &[u8]| -> Result<std::path::PathBuf, String> {
        let path = dir.join(rel);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).map_err(|e| format!("{}: {e}", parent.display()))?;
        }
        std::fs::write(&path, bytes).map_err(|e| format!("{}: {e}", path.display()))?;
        Ok(path)
    };
    for (rel, bytes) in THESIS_MESHES {
        write(rel, bytes)?;
    }
    THESIS_SCENES
        .iter()
        .map(|(name, text)| write(&format!("thesis/{name}"), text.as_bytes()))
        .collect()
}

/// One bundled thesis scene run as `memstab run` runs it, outputs not written.
#[derive(Debug, Clone)]
pub struct SceneRun {
    /// The scene file's name.
    pub file: String,
    /// The scene's group.
    pub group: String,
    /// Triangles of its mesh.
    pub elements: usize,
    /// Path points.
    pub points: usize,
    /// Critical points of the path.
    pub critical: usize,
    /// Points of the critical curve, for a critical-curve scene.
    pub curve_points: Option<usize>,
    /// Wall time of the whole run: load, build, start, path (and curve).
    pub wall: Duration,
}

/// Runs the scene file `path` and times it.
pub fn scene_run(path: &Path) -> Result<SceneRun, String> {
    let wall = Instant::now();
    let scene = Scene::load(path).map_err(|e| e.to_string())?;
    let mut study = MeshStudy::build(scene).map_err(|e| e.to_string())?;
    let result = crate::analysis::run(&mut study, |_, _| {}).map_err(|e| e.to_string())?;
    let wall = wall.elapsed();
    let report = &result.report;
    Ok(SceneRun {
        file: path
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
        group: report.group.clone(),
        elements: report.mesh.elements,
        points: report.rows.len(),
        critical: report.critical.len(),
        curve_points: result
            .outcome::<crate::results::CurveReport>()
            .map(|c| c.rows.len()),
        wall,
    })
}

/// The markdown table of the bundled scenes' runs.
pub fn scenes_table(runs: &[SceneRun]) -> String {
    let mut md = String::from(
        "## The bundled thesis scenes\n\n\
         Each of `scenes/thesis/*.toml` as bundled, run as `memstab run` runs it (the index \
         by irrep at every point, every crossing localised), outputs not written; wall time \
         in s.\n\n\
         | scene | group | triangles | path points | critical points | curve points | wall |\n\
         |---|---|---|---|---|---|---|\n",
    );
    for r in runs {
        md += &format!(
            "| `{}` | {} | {} | {} | {} | {} | {:.2} |\n",
            r.file,
            r.group,
            r.elements,
            r.points,
            r.critical,
            r.curve_points.map_or("–".to_string(), |n| n.to_string()),
            r.wall.as_secs_f64()
        );
    }
    md
}

#[cfg(test)]
mod tests {
    use super::{write_thesis_scenes, THESIS_MESHES, THESIS_SCENES};

    /// The embedded scenes are exactly the bundled `scenes/thesis/*.toml`, byte for byte, and
    /// every mesh file one of them reads is embedded; written out, each scene loads with its
    /// mesh found beside it.
    #[test]
    fn the_embedded_thesis_scenes_are_the_bundled_ones_and_load_where_written() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
        let mut bundled: Vec<String> = std::fs::read_dir(root.join("thesis"))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".toml"))
            .collect();
        bundled.sort();
        let embedded: Vec<String> = THESIS_SCENES.iter().map(|(n, _)| n.to_string()).collect();
        assert_eq!(embedded, bundled);
        for (name, text) in THESIS_SCENES {
            let on_disk = std::fs::read_to_string(root.join("thesis").join(name)).unwrap();
            assert_eq!(*text, on_disk, "{name}");
        }
        for (rel, bytes) in THESIS_MESHES {
            assert_eq!(
                *bytes,
                std::fs::read(root.join(rel)).unwrap().as_slice(),
                "{rel}"
            );
        }
        let dir = tempfile::tempdir().unwrap();
        let paths = write_thesis_scenes(dir.path()).unwrap();
        assert_eq!(paths.len(), THESIS_SCENES.len());
        for path in &paths {
            let scene = crate::scene::Scene::load(path)
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            if let crate::scene::MeshSpec::File(f) = &scene.mesh {
                assert!(f.path.is_file(), "{}: {}", path.display(), f.path.display());
            }
        }
    }
}
