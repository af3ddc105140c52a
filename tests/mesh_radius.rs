//! The reference radius of a generated mesh as a parameter (`[mesh] radius = "R"`): the
//! balloon's limit curve in (p, R) against the closed form p R/(μH) = const, a path in R
//! against the mesh generated at that radius, and the values refused.

use memstab::analysis::critical::CriticalKind;
use memstab::analysis::run;
use memstab::model::Model;
use memstab::scene::Scene;
use memstab::study::Study;

/// The closed-form limit pressure of the k = 0.1 balloon, p R/(μH) at its maximum, and the
/// stretch there (scenes/balloon.toml).
const LIMIT_PR: f64 = 1.3551069;
const LIMIT_STRETCH: f64 = 1.4760699;

/// The bundled balloon at icosphere frequency 4 with its `[parameters]`, `[analysis]` and
/// `[start]` replaced by `tail`, and its mesh radius set to `radius` (TOML: a number or a
/// parameter's name in quotes).
fn balloon(radius: &str, tail: &str) -> String {
    let text = std::fs::read_to_string(format!(
        "{}/scenes/balloon.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let params = text.find("[parameters.p]").unwrap();
    let text = format!("{}{tail}", &text[..params])
        .replacen("radius = 1.0", &format!("radius = {radius}"), 1)
        .replacen("frequency = 8", "frequency = 4", 1);
    assert!(text.contains(&format!("radius = {radius}")), "{text}");
    text
}

fn scene(text: &str) -> Scene {
    Scene::from_toml_str(text, "mesh-radius").unwrap()
}

/// The limit point followed in (p, R): by scaling, p R is the same at every point of the
/// curve (to the solver's tolerance: the mesh is the same one, scaled), and that constant is
/// the closed form's to the mesh's error; the stretch at the limit does not change either.
#[test]
fn the_balloons_limit_pressure_scales_as_one_over_the_radius() {
    let text = balloon(
        "\"R\"",
        r#"[parameters.p]
start = 0.4879036
min = 0.0
max = 4.0

[parameters.R]
start = 1.0
min = 0.5
max = 2.0

[analysis]
type = "critical-curve"
control = "p"
second = "R"
from = "limit"
steps = 200
path-steps = 400
max-step = 0.05

[start]
stretch = 1.05
"#,
    );
    let loaded = scene(&text);
    // The scene written back names the parameter again.
    let again = Scene::from_toml_str(&loaded.to_toml(), "again").unwrap();
    assert_eq!(again.mesh_radius, loaded.mesh_radius);
    assert_eq!(again.mesh, loaded.mesh);
    let mut study = Study::build(loaded).unwrap();
    let result = run(&mut study, |_, _| {}).expect("the curve runs");
    let curve = result.curve.expect("a curve");
    assert_eq!(curve.kind, CriticalKind::LimitPoint);
    let col = |name: &str| curve.parameters.iter().position(|p| p == name).unwrap();
    let (p, r) = (col("p"), col("R"));
    let s = curve.measures.iter().position(|m| m == "stretch").unwrap();
    let first = &curve.rows[0];
    let pr0 = first.parameters[p] * first.parameters[r];
    let (mut lo, mut hi, mut spread, mut stretch_spread) = (f64::MAX, 0.0f64, 0.0f64, 0.0f64);
    for row in &curve.rows {
        let radius = row.parameters[r];
        lo = lo.min(radius);
        hi = hi.max(radius);
        spread = spread.max((row.parameters[p] * radius / pr0 - 1.0).abs());
        stretch_spread = stretch_spread.max((row.measures[s] / first.measures[s] - 1.0).abs());
    }
    let closed = (pr0 / LIMIT_PR - 1.0).abs();
    let closed_stretch = (first.measures[s] / LIMIT_STRETCH - 1.0).abs();
    eprintln!(
        "{} points, R in [{lo}, {hi}], p R = {pr0}: spread {spread:e}, stretch spread \
         {stretch_spread:e}; closed form: {closed:e} (p R), {closed_stretch:e} (stretch)",
        curve.rows.len()
    );
    assert!(curve.rows.len() > 10, "{} points", curve.rows.len());
    // The curve runs from R = 1 to the bound R = 2.
    assert!(hi / lo > 1.9, "R covers [{lo}, {hi}]");
    // Measured: both about 2e-15.
    assert!(spread < 1e-12, "p R varies by {spread:e}");
    assert!(
        stretch_spread < 1e-12,
        "the stretch varies by {stretch_spread:e}"
    );
    // Frequency 4 (320 triangles): the mesh's error in the limit pressure is 1.5 %, in the
    // stretch at the limit 1.5e-5.
    assert!(closed < 0.02, "p R = {pr0} vs {LIMIT_PR}");
    assert!(
        closed_stretch < 1e-4,
        "{} vs {LIMIT_STRETCH}",
        first.measures[s]
    );
}

/// A path in R at the fixed pressure p = 0.9 from R = 1, and at its last point an
/// equilibrium of the mesh generated at that radius (a number): the same positions, volume
/// and stretch to the solver's tolerance.
#[test]
fn a_path_in_the_radius_is_the_mesh_generated_at_each_radius() {
    let text = balloon(
        "\"R\"",
        r#"[parameters.p]
start = 0.9

[parameters.R]
start = 1.0
min = 0.5
max = 1.3

[[constraint]]
type = "fixed"
parameter = "p"

[analysis]
type = "path"
control = "R"
direction = "increase"
steps = 60
max-step = 0.05

[start]
stretch = 1.1
"#,
    );
    let mut study = Study::build(scene(&text)).unwrap();
    let result = run(&mut study, |_, _| {}).expect("the path runs");
    let last = result.states.last().expect("the last state");
    let r_col = study.parameters.iter().position(|p| p == "R").unwrap();
    let radius = last.params[r_col];
    assert!(
        radius > 1.25 && radius <= 1.3 + 0.05,
        "the path ends at R = {radius}"
    );
    let row = result.report.rows.last().unwrap();
    let names = &result.report.measures;
    let at = |name: &str| names.iter().position(|m| m == name).unwrap();
    let stretch = row.measures[at("stretch")];
    let x = study.model.positions(&last.u);
    // The same balloon generated at that radius, found by its own start solve.
    let fixed = balloon(
        &format!("{radius:?}"),
        &format!(
            "[parameters.p]\nstart = 0.9\n\n[analysis]\ntype = \"equilibrium\"\n\n[start]\nstretch = {stretch:?}\n"
        ),
    );
    let mut other = Study::build(scene(&fixed)).unwrap();
    let alone = run(&mut other, |_, _| {}).expect("the equilibrium solves");
    let y = other.model.positions(&alone.states.last().unwrap().u);
    let gap = x
        .iter()
        .zip(&y)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    let own = alone.report.rows.last().unwrap();
    let volume = (row.measures[at("volume")] / own.measures[at("volume")] - 1.0).abs();
    let stretches = (stretch / own.measures[at("stretch")] - 1.0).abs();
    let moved = (row.measures[at("max_displacement")] - own.measures[at("max_displacement")]).abs();
    eprintln!(
        "R = {radius}: positions within {gap:e}, volume {volume:e}, stretch {stretches:e}, \
         max_displacement {moved:e}"
    );
    // Measured: all within 1e-15.
    assert!(gap < 1e-11 * radius, "positions differ by {gap:e}");
    assert!(volume < 1e-11 && stretches < 1e-11 && moved < 1e-11);
}

fn memstab(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_memstab"))
        .args(args)
        .output()
        .expect("the memstab binary runs")
}

/// A radius parameter that starts or may go at or below 0, on a membrane with fixed nodes, or
/// of the axisymmetric generator: exit code 2, one line naming the key, nothing written.
#[test]
fn bad_radius_parameters_are_refused_without_writing() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("never");
    let path_tail = |r: &str| {
        format!(
            "[parameters.p]\nstart = 0.4879036\n\n[parameters.R]\n{r}\n\n[[constraint]]\ntype = \"fixed\"\nparameter = \"R\"\n\n[analysis]\ntype = \"path\"\ncontrol = \"p\"\nsteps = 3\n"
        )
    };
    let disc = std::fs::read_to_string(format!(
        "{}/scenes/disc_upward.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
    .replacen("radius = 1.1", "radius = \"R\"", 1)
        + "\n[parameters.R]\nstart = 1.1\n\n[[constraint]]\ntype = \"fixed\"\nparameter = \"R\"\n";
    let axisym = std::fs::read_to_string(format!(
        "{}/scenes/axisymmetric/balloon.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let axisym_radius = axisym
        .lines()
        .find(|l| l.trim_start().starts_with("radius"))
        .expect("the axisymmetric balloon gives its radius")
        .to_string();
    let cases = [
        (
            "start.toml",
            balloon("\"R\"", &path_tail("start = -1.0")),
            vec!["mesh.radius", "-1"],
        ),
        (
            "min.toml",
            balloon("\"R\"", &path_tail("start = 1.0\nmin = 0.0")),
            vec!["parameters.R.min", "mesh.radius"],
        ),
        ("fixed.toml", disc, vec!["mesh.radius", "rim"]),
        (
            "axisym.toml",
            axisym.replacen(&axisym_radius, "radius = \"R\"", 1),
            vec!["mesh.radius", "axisymmetric"],
        ),
    ];
    for (name, text, needles) in cases {
        let file = tmp.path().join(name);
        std::fs::write(&file, text).unwrap();
        let out = memstab(&[
            "run",
            file.to_str().unwrap(),
            "--out",
            dir.to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {err}");
        assert_eq!(
            err.trim_end().lines().count(),
            1,
            "{name}: not one line: {err}"
        );
        for needle in needles {
            assert!(err.contains(needle), "{name}: '{needle}' not in: {err}");
        }
        assert!(!dir.exists(), "{name}: {} was created", dir.display());
    }
}
