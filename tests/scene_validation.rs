//! Scene files: the bundled scenes load and build, and every class of bad input gets one
//! line naming the key path and the value; garbage never panics.

use memstab::scene::{
    Constraint, ConstraintKind, FluidEffect, FluidSide, MeshSpec, PathAnalysis, PlaneEffect,
    Quantity, Scene, SceneError, Target,
};
use proptest::prelude::*;
use std::path::Path;

/// A valid scene that exercises most sections: a small clamped disc with fluid above, a gas
/// pressure and a plane (effect[0], effect[1], effect[2]).
const BASE: &str = r#"
[scene]
name = "test"

[mesh]
generator = "disc"
radius = 1.1
sectors = 6
divisions = 3

[material]
mu = 100.0
k = 0.1
thickness = 0.01
prestretch = 1.1

[[effect]]
type = "fluid"
side = "above"
density = "rho"
gravity = 1.0
level = 0.001

[[effect]]
type = "gas"
pressure = 0.5

[[effect]]
type = "plane"
normal = [0.0, 0.0, 2.0]
offset = -0.5
penalty = 1000.0

[boundary]
fixed = ["rim"]

[parameters.rho]
start = 0.0
min = 0.0
max = 5.0

[analysis]
type = "path"
control = "rho"
"#;

/// BASE with the first occurrence of `from` replaced by `to` (which must exist).
fn edit(from: &str, to: &str) -> String {
    assert!(BASE.contains(from), "BASE has no {from:?}");
    BASE.replacen(from, to, 1)
}

/// The error of loading `text` (and, if that succeeds, of building its mesh), checked to be
/// one line.
fn error_of(text: &str) -> String {
    let err = match Scene::from_toml_str(text, "test.toml") {
        Ok(scene) => match scene.build_mesh() {
            Ok(_) => panic!("the scene was accepted:\n{text}"),
            Err(e) => e,
        },
        Err(e) => e,
    };
    let message = err.to_string();
    assert_eq!(message.lines().count(), 1, "not one line: {message}");
    assert!(message.starts_with("test.toml"), "no origin: {message}");
    message
}

/// Asserts that `text` is rejected with a message containing every needle.
fn rejects(text: &str, needles: &[&str]) -> String {
    let message = error_of(text);
    for needle in needles {
        assert!(
            message.contains(needle),
            "{needle:?} not in the message: {message}"
        );
    }
    message
}

#[test]
fn base_scene_is_valid() {
    let scene = Scene::from_toml_str(BASE, "base").expect("BASE loads");
    let mesh = scene.build_mesh().expect("BASE builds");
    assert_eq!(mesh.mesh.triangles.len(), 6 * 9);
    assert_eq!(scene.effects.len(), 3);
    // Defaults.
    assert_eq!(scene.start.stretch, 1.0);
    let Some(path) = scene.analysis.get::<PathAnalysis>() else {
        panic!("a path analysis")
    };
    assert_eq!(path.settings.steps, 200);
    let s = &path.settings;
    assert!(s.min_step <= s.initial_step && s.initial_step <= s.max_step);
    let Some(plane) = scene.effects[2].get::<PlaneEffect>() else {
        panic!("effect[2] is a plane")
    };
    assert_eq!(plane.normal, [0.0, 0.0, 1.0]);
    assert_eq!(plane.exponent, 1);
    let Some(fluid) = scene.effects[0].get::<FluidEffect>() else {
        panic!("effect[0] is a fluid")
    };
    assert_eq!(fluid.side, FluidSide::Above);
    assert_eq!(fluid.density, Quantity::Parameter("rho".into()));
    assert_eq!(scene.fixed_nodes(&mesh).len(), 6 * 3);
}

#[test]
fn unknown_keys_are_named_with_their_path() {
    rejects(
        &edit("pressure = 0.5", "pressur = 0.5"),
        &["unknown key 'effect[1].pressur'", "pressure"],
    );
    rejects(
        &edit("thickness = 0.01", "thickness = 0.01\nthicknes = 0.01"),
        &["unknown key 'material.thicknes'"],
    );
    rejects(
        &format!("{BASE}\n[solver]\nx = 1\n"),
        &["unknown key 'solver'"],
    );
    rejects(
        &edit("control = \"rho\"", "control = \"rho\"\nstep = 3"),
        &["unknown key 'analysis.step'", "steps"],
    );
    rejects(
        &edit(
            "type = \"path\"\ncontrol = \"rho\"",
            "type = \"equilibrium\"\ncontrol = \"rho\"",
        ),
        &[
            "unknown key 'analysis.control'",
            "type, tolerance, max-iterations",
        ],
    );
    rejects(
        &edit("max = 5.0", "max = 5.0\nscale = 2.0"),
        &["unknown key 'parameters.rho.scale'"],
    );
    // An option of another generator says so.
    rejects(
        &edit("divisions = 3", "divisions = 3\nfrequency = 4"),
        &["'mesh.frequency'", "generator \"disc\"", "sectors"],
    );
    rejects(
        &edit("divisions = 3", "divisions = 3\nrings = 4"),
        &["unknown key 'mesh.rings'", "generator, radius, sectors"],
    );
}

/// The continuation keys an analysis shares with the others (steps, step sizes, direction,
/// save-every, Newton's) are one table: read into its settings where the analysis takes them,
/// refused with the valid keys where it does not.
#[test]
fn shared_continuation_keys_are_taken_where_they_apply() {
    let path = Scene::from_toml_str(
        &edit(
            "control = \"rho\"",
            "control = \"rho\"\nsteps = 7\ndirection = \"decrease\"\nsave-every = 3\ntolerance = 1e-8",
        ),
        "t",
    )
    .unwrap();
    let settings = path.analysis.settings();
    assert_eq!(
        (
            settings.steps,
            settings.direction,
            settings.save_every,
            settings.tolerance
        ),
        (7, -1.0, 3, 1e-8)
    );
    // Written back as TOML and read again: the same analysis.
    let again = Scene::from_toml_str(&path.to_toml(), "again").unwrap();
    assert_eq!(again.analysis, path.analysis);
    rejects(
        &edit(
            "type = \"path\"\ncontrol = \"rho\"",
            "type = \"equilibrium\"\nsteps = 5",
        ),
        &["unknown key 'analysis.steps'", "tolerance, max-iterations"],
    );
    rejects(
        &edit("control = \"rho\"", "control = \"rho\"\ndirection = \"up\""),
        &["'analysis.direction'", "increase", "decrease"],
    );
    rejects(
        &edit("control = \"rho\"", "control = \"rho\"\nmin-step = 0.5"),
        &["'analysis.min-step' must be <= max-step"],
    );
}

#[test]
fn missing_fields_are_named_with_their_path() {
    rejects(&edit("mu = 100.0\n", ""), &["missing field 'material.mu'"]);
    rejects(
        &edit("generator = \"disc\"\n", ""),
        &["missing field 'mesh.generator'"],
    );
    rejects(
        &edit("type = \"gas\"\n", ""),
        &["missing field 'effect[1].type'"],
    );
    rejects(
        &edit("gravity = 1.0\n", ""),
        &["missing field 'effect[0].gravity'"],
    );
    rejects(
        &edit("start = 0.0\n", ""),
        &["missing field 'parameters.rho.start'"],
    );
    rejects(
        &edit("[material]", "[materials]"),
        &["unknown key 'materials'"],
    );
    let no_material = BASE.replace("[material]", "").replace(
        "mu = 100.0\nk = 0.1\nthickness = 0.01\nprestretch = 1.1\n",
        "",
    );
    rejects(&no_material, &["missing section 'material'"]);
}

#[test]
fn wrong_types_name_the_expected_type_and_the_value() {
    rejects(
        &edit("mu = 100.0", "mu = \"one\""),
        &["'material.mu': unknown parameter \"one\""],
    );
    rejects(
        &edit("sectors = 6", "sectors = 6.5"),
        &["'mesh.sectors': expected a non-negative integer, got 6.5"],
    );
    rejects(
        &edit("sectors = 6", "sectors = -6"),
        &["'mesh.sectors'", "-6"],
    );
    rejects(
        &edit("normal = [0.0, 0.0, 2.0]", "normal = [0.0, 2.0]"),
        &["'effect[2].normal'", "an array of 3 numbers", "[0.0, 2.0]"],
    );
    rejects(
        &edit("normal = [0.0, 0.0, 2.0]", "normal = [0.0, \"z\", 2.0]"),
        &["'effect[2].normal[1]': expected a number, got \"z\""],
    );
    rejects(
        &edit("pressure = 0.5", "pressure = true"),
        &["'effect[1].pressure': expected a number or a parameter name, got true"],
    );
    rejects(
        &edit("fixed = [\"rim\"]", "fixed = \"rim\""),
        &["'boundary.fixed': expected an array, got \"rim\""],
    );
    rejects(
        &edit("side = \"above\"", "side = \"sideways\""),
        &[
            "'effect[0].side': unknown value \"sideways\"",
            "inside, below, above",
        ],
    );
    rejects(
        &edit("type = \"gas\"", "type = \"gaz\""),
        &["'effect[1].type': unknown value \"gaz\"", "gas-amount"],
    );
    rejects(
        &edit("type = \"path\"", "type = 3"),
        &["'analysis.type': expected a string, got 3"],
    );
    // Sections of the wrong shape.
    rejects(
        &valid_text().replace("[[effect]]", "[effect]"),
        &["'effect': expected an array of tables ([[effect]]), got a table"],
    );
    rejects(
        &edit("[scene]", "[[scene]]"),
        &["'scene': expected a table, got an array"],
    );
    rejects(
        &edit(
            "[parameters.rho]\nstart = 0.0\nmin = 0.0\nmax = 5.0",
            "[parameters]\nrho = 3",
        ),
        &["'parameters.rho': expected a table, got 3"],
    );
    rejects(
        &edit("mu = 100.0", "mu = 1979-05-27"),
        &["'material.mu': unknown parameter \"1979-05-27\""],
    );
}

#[test]
fn non_physical_values_are_rejected() {
    rejects(
        &edit("thickness = 0.01", "thickness = -0.01"),
        &["'material.thickness' must be > 0, got -0.01"],
    );
    rejects(
        &edit("mu = 100.0", "mu = 0"),
        &["'material.mu' must be > 0, got 0"],
    );
    rejects(
        &edit("k = 0.1", "k = -0.1"),
        &["'material.k' must be >= 0, got -0.1"],
    );
    rejects(
        &edit("penalty = 1000.0", "penalty = 0"),
        &["'effect[2].penalty' must be > 0, got 0"],
    );
    rejects(
        &edit("prestretch = 1.1", "prestretch = -1.1"),
        &["'material.prestretch' must be > 0, got -1.1"],
    );
    rejects(
        &edit("mu = 100.0", "mu = nan"),
        &["'material.mu' must be a finite number, got NaN"],
    );
    rejects(
        &edit("gravity = 1.0", "gravity = 0.0"),
        &["'effect[0].gravity' must be > 0, got 0"],
    );
    rejects(
        &edit("level = 0.001", "level = inf"),
        &["'effect[0].level' must be a finite number, got inf"],
    );
    rejects(
        &edit("penalty = 1000.0", "penalty = 1000.0\nexponent = 2"),
        &["'effect[2].exponent' must be 1 or 3, got 2"],
    );
    rejects(
        &edit("normal = [0.0, 0.0, 2.0]", "normal = [0.0, 0.0, 0.0]"),
        &["'effect[2].normal' must be a finite non-zero vector, got [0, 0, 0]"],
    );
    rejects(
        &edit("radius = 1.1", "radius = -1"),
        &["'mesh.radius' must be > 0, got -1"],
    );
    rejects(
        &edit("sectors = 6", "sectors = 2"),
        &["'mesh.sectors' must be >= 3, got 2"],
    );
    rejects(
        &edit("min = 0.0", "min = 6.0"),
        &["'parameters.rho.min' must be < max = 5, got 6"],
    );
    rejects(
        &edit("start = 0.0", "start = 7.0"),
        &["'parameters.rho.start' must lie within [min, max] = [0, 5], got 7"],
    );
    rejects(
        &edit("control = \"rho\"", "control = \"rho\"\ninitial-step = 0.5"),
        &["'analysis.initial-step'", "0.5"],
    );
    rejects(
        &edit("control = \"rho\"", "control = \"rho\"\nsteps = 0"),
        &["'analysis.steps' must be >= 1, got 0"],
    );
    rejects(
        &edit("name = \"test\"", "name = \" \""),
        &["'scene.name' must not be empty"],
    );
}

#[test]
fn unknown_boundary_names_list_the_available_ones() {
    rejects(
        &edit("fixed = [\"rim\"]", "fixed = [\"rims\"]"),
        &["'boundary.fixed[0]'", "\"rims\"", "rim"],
    );
    rejects(
        &edit("fixed = [\"rim\"]", "fixed = [\"rim\", \"rim\"]"),
        &["'boundary.fixed[1]'", "\"rim\""],
    );
    // Mesh checks through Scene::check_mesh directly.
    let scene = Scene::from_toml_str(&edit("fixed = [\"rim\"]", "fixed = [\"edge\"]"), "t")
        .expect("names are checked against the mesh only");
    let mesh = scene.mesh.build().expect("the mesh builds");
    let err = scene.check_mesh(&mesh).unwrap_err();
    assert_eq!(err.key(), Some("boundary.fixed[0]"));
    assert!(err.to_string().contains("\"edge\""), "{err}");
}

#[test]
fn unknown_parameter_references_are_named() {
    rejects(
        &edit("pressure = 0.5", "pressure = \"q\""),
        &[
            "'effect[1].pressure': unknown parameter \"q\"",
            "declared: rho",
        ],
    );
    rejects(
        &edit("control = \"rho\"", "control = \"p\""),
        &["'analysis.control': unknown parameter \"p\""],
    );
    rejects(
        &format!("{BASE}\n[[constraint]]\ntype = \"fixed\"\nparameter = \"h\"\n"),
        &["'constraint[0].parameter': unknown parameter \"h\""],
    );
    // A declared parameter no effect uses.
    rejects(
        &format!("{BASE}\n[parameters.q]\nstart = 1.0\n"),
        &["'parameters.q' is declared but no quantity uses it"],
    );
}

#[test]
fn constraints_are_checked_against_effects_and_parameters() {
    // Two parameters on a path: the one that is not the control must be governed.
    let two = edit("pressure = 0.5", "pressure = \"p\"") + "\n[parameters.p]\nstart = 0.5\n";
    rejects(&two, &["'parameters.p'", "neither the control"]);
    let fixed = format!("{two}\n[[constraint]]\ntype = \"fixed\"\nparameter = \"p\"\n");
    let scene = Scene::from_toml_str(&fixed, "t").expect("p is held fixed");
    assert_eq!(
        scene.governing("p").map(Constraint::kind),
        Some(ConstraintKind::Fixed)
    );
    // The control cannot be governed.
    rejects(
        &format!("{fixed}\n[[constraint]]\ntype = \"fixed\"\nparameter = \"rho\"\n"),
        &["'analysis.control'", "governed by constraint[1]"],
    );
    // Governed twice.
    rejects(
        &format!("{fixed}\n[[constraint]]\ntype = \"fixed\"\nparameter = \"p\"\n"),
        &["'constraint[1].parameter'", "\"p\"", "constraint[0]"],
    );
    // A fluid-volume constraint needs the level to be a parameter.
    rejects(
        &format!("{BASE}\n[[constraint]]\ntype = \"fluid-volume\"\nvalue = \"initial\"\n"),
        &["'constraint[0]'", "'effect[0].level'", "0.001"],
    );
    rejects(
        &format!("{BASE}\n[[constraint]]\ntype = \"fluid-volume\"\neffect = 1\nvalue = 1.0\n"),
        &["'constraint[0].effect'", "gas"],
    );
    rejects(
        &format!("{BASE}\n[[constraint]]\ntype = \"fluid-volume\"\nvalue = \"init\"\n"),
        &["'constraint[0].value': expected a number or \"initial\", got \"init\""],
    );
    // A valid fluid-volume constraint resolves its effect and the level it governs.
    let volume = edit("level = 0.001", "level = \"h\"")
        + "\n[parameters.h]\nstart = 0.001\n\n[[constraint]]\ntype = \"fluid-volume\"\nvalue = \"initial\"\n";
    let scene = Scene::from_toml_str(&volume, "t").expect("a fluid-volume constraint");
    match &scene.constraints[0] {
        Constraint::FluidVolume(c) => {
            assert_eq!(
                (c.effect, c.level.as_str(), c.value.clone()),
                (0, "h", Target::Initial)
            )
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn syntax_errors_give_the_line() {
    let text = edit("k = 0.1", "k = = 0.1");
    let message = rejects(&text, &["TOML syntax error"]);
    let line = text.lines().position(|l| l == "k = = 0.1").unwrap() + 1;
    assert!(
        message.starts_with(&format!("test.toml:{line}:")),
        "{message}"
    );
    rejects("[scene\nname = 1", &["test.toml:1:", "TOML syntax error"]);
    rejects(
        &format!("{BASE}\n[material]\nmu = 1.0\n"),
        &["TOML syntax error", "duplicate key", "[material]"],
    );
}

#[test]
fn mesh_related_rules_are_checked_after_building() {
    // Generator errors name the option.
    rejects(
        &edit("divisions = 3", "divisions = 3\ngroup = \"C4v\""),
        &["'mesh.group'", "C4v"],
    );
    // Gas on an open membrane whose rim is free.
    rejects(
        &edit("fixed = [\"rim\"]", "fixed = []"),
        &["'effect[0]' (fluid)", "fixed rim"],
    );
    // Fluid below a closed membrane.
    let sphere = BASE
        .replace(
            "generator = \"disc\"\nradius = 1.1\nsectors = 6\ndivisions = 3",
            "generator = \"icosphere\"\nfrequency = 2",
        )
        .replace("fixed = [\"rim\"]", "fixed = []");
    rejects(&sphere, &["'effect[0].side'", "\"above\"", "closed"]);
    // Stop at a stretch needs a closed membrane.
    rejects(
        &edit("control = \"rho\"", "control = \"rho\"\nstop-stretch = 2.0"),
        &["'analysis.stop-stretch'", "open"],
    );
    // A start stretch would move the fixed nodes.
    rejects(
        &format!("{BASE}\n[start]\nstretch = 1.05\n"),
        &["'start.stretch'", "1.05"],
    );
}

#[test]
fn reading_a_missing_file_is_an_input_error() {
    let err = Scene::load("/nonexistent/scene.toml").unwrap_err();
    assert!(matches!(err, SceneError::Read { .. }));
    assert!(err.to_string().contains("/nonexistent/scene.toml"));
}

fn bundled() -> Vec<std::path::PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .expect("scenes/ exists")
        .map(|e| e.expect("a directory entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    files
}

#[test]
fn bundled_scenes_load_and_build() {
    let files = bundled();
    let names: Vec<String> = files
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    for expected in [
        "balloon.toml",
        "balloon_k0.toml",
        "demo.toml",
        "disc_fluid_above.toml",
        "disc_fluid_below.toml",
    ] {
        assert!(names.iter().any(|n| n == expected), "no scenes/{expected}");
    }
    for file in &files {
        let scene = Scene::load(file).unwrap_or_else(|e| panic!("{e}"));
        let mesh = scene.build_mesh().unwrap_or_else(|e| panic!("{e}"));
        for name in &scene.boundary.fixed {
            assert!(
                mesh.mesh.boundaries.contains_key(name),
                "{}",
                file.display()
            );
        }
        // The scene survives a round trip through TOML.
        let again = Scene::from_toml_str(&scene.to_toml(), &scene.origin)
            .unwrap_or_else(|e| panic!("{}: round trip: {e}", file.display()));
        assert_eq!(again, scene, "{}", file.display());
    }
}

#[test]
fn bundled_balloon_reaches_past_the_pressure_minimum() {
    let scene = Scene::load(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/balloon.toml"))
        .expect("balloon loads");
    assert!(matches!(&scene.mesh, MeshSpec::Icosphere(i) if i.frequency == 8));
    assert_eq!(scene.material.k, Quantity::Value(0.1));
    assert!(scene.boundary.fixed.is_empty());
    let Some(path) = scene.analysis.get::<PathAnalysis>() else {
        panic!("a path")
    };
    assert_eq!(path.control, "p");
    assert!(path.stop_stretch.unwrap() > 3.1426213);
    let p = &scene.parameters["p"];
    assert!(p.max.unwrap() > 1.3551069 && p.min.unwrap() < 1.1487477);
    // The start pressure holds the start stretch (closed form).
    let value = |q: &Quantity| scene.start_value(q);
    let (l, k) = (scene.start.stretch, value(&scene.material.k));
    let mu_h = value(&scene.material.mu) * value(&scene.material.thickness);
    let closed = 2.0 / (1.0 + k) * (1.0 / l - l.powi(-7)) * (1.0 + k * l * l) * mu_h;
    assert!((p.start - closed).abs() < 1e-6, "{} vs {closed}", p.start);
}

/// A valid scene used by the property tests: the bundled balloon.
fn valid_text() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/balloon.toml"))
        .expect("balloon.toml")
}

/// Loading never panics; an error is one line; a success builds (when small) or fails with
/// a scene error.
fn load_never_panics(text: &str) {
    match Scene::from_toml_str(text, "prop") {
        Ok(scene) => {
            if scene.mesh.triangle_count() <= 20_000 {
                if let Err(e) = scene.build_mesh() {
                    assert_eq!(e.to_string().lines().count(), 1, "{e}");
                }
            }
        }
        Err(e) => {
            let m = e.to_string();
            assert_eq!(m.lines().count(), 1, "not one line: {m}");
            assert!(!m.trim().is_empty());
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn garbage_never_panics(text in "\\PC{0,300}") {
        load_never_panics(&text);
    }

    #[test]
    fn toml_like_garbage_never_panics(
        text in "(\\[{1,2}[a-z.]{1,12}\\]{1,2}\n|[a-z-]{1,10} = (\"[a-z]{0,6}\"|-?[0-9.e]{1,6}|\\[[0-9., ]{0,10}\\]|true)\n){0,20}"
    ) {
        load_never_panics(&text);
    }

    #[test]
    fn truncated_scenes_never_panic(cut in 0usize..2000) {
        let text = valid_text();
        let cut = cut.min(text.len());
        let cut = (0..=cut).rev().find(|&i| text.is_char_boundary(i)).unwrap_or(0);
        load_never_panics(&text[..cut]);
    }

    #[test]
    fn scenes_with_a_line_dropped_never_panic(drop in 0usize..80) {
        let text: String = valid_text()
            .lines()
            .enumerate()
            .filter(|(i, _)| *i != drop)
            .map(|(_, l)| format!("{l}\n"))
            .collect();
        load_never_panics(&text);
    }

    #[test]
    fn scenes_with_a_value_replaced_never_panic(
        line in 0usize..80,
        value in prop_oneof![
            Just("0".to_string()),
            Just("-1".to_string()),
            Just("nan".to_string()),
            Just("\"\"".to_string()),
            Just("[]".to_string()),
            Just("{}".to_string()),
            Just("1e308".to_string()),
            Just("99999999999".to_string()),
            "-?[0-9]{1,4}(\\.[0-9]{1,3})?",
            "\"[a-z0-9-]{0,8}\"",
        ],
    ) {
        let text: String = valid_text()
            .lines()
            .enumerate()
            .map(|(i, l)| match l.split_once(" = ") {
                Some((key, _)) if i == line => format!("{key} = {value}\n"),
                _ => format!("{l}\n"),
            })
            .collect();
        load_never_panics(&text);
    }
}

#[test]
fn the_documented_example_loads_and_builds() {
    let doc = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/scenes.md"))
        .expect("docs/scenes.md");
    let start = doc.rfind("```toml\n").expect("a toml example") + "```toml\n".len();
    let end = start + doc[start..].find("```").expect("the example ends");
    let scene =
        Scene::from_toml_str(&doc[start..end], "docs/scenes.md").unwrap_or_else(|e| panic!("{e}"));
    scene.build_mesh().unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        scene.governing("h").map(Constraint::kind),
        Some(ConstraintKind::FluidVolume)
    );
}

/// Material quantities, gravity and a plane's penalty may be parameters: a held one loads,
/// counts as used, and its start and bounds keep the quantity's range.
#[test]
fn material_gravity_and_penalty_quantities_may_be_parameters() {
    let held = |name: &str| {
        format!("\n[parameters.{name}]\nstart = 0.2\nmin = 0.1\n\n[[constraint]]\ntype = \"fixed\"\nparameter = \"{name}\"\n")
    };
    for (from, to, name) in [
        ("k = 0.1", "k = \"kk\"", "kk"),
        ("mu = 100.0", "mu = \"m\"", "m"),
        ("thickness = 0.01", "thickness = \"t\"", "t"),
        ("prestretch = 1.1", "prestretch = \"l0\"", "l0"),
        ("gravity = 1.0", "gravity = \"g\"", "g"),
        ("penalty = 1000.0", "penalty = \"kappa\"", "kappa"),
    ] {
        let text = format!("{}{}", edit(from, to), held(name));
        let scene = Scene::from_toml_str(&text, "test").unwrap_or_else(|e| panic!("{to}: {e}"));
        assert!(scene.parameters.contains_key(name));
    }
    // k >= 0, mu > 0: the parameter's start and min keep the range, named by the quantity.
    let text = format!(
        "{}\n[parameters.kk]\nstart = -0.1\n\n[[constraint]]\ntype = \"fixed\"\nparameter = \"kk\"\n",
        edit("k = 0.1", "k = \"kk\"")
    );
    rejects(
        &text,
        &["'parameters.kk.start' must be >= 0 (it is material.k), got -0.1"],
    );
    let text = format!("{}{}", edit("mu = 100.0", "mu = \"m\""), held("m"))
        .replace("min = 0.1", "min = 0.0");
    rejects(
        &text,
        &["'parameters.m.min' must be > 0 (it is material.mu), got 0"],
    );
    rejects(
        &edit("gravity = 1.0", "gravity = \"g\""),
        &["'effect[0].gravity': unknown parameter \"g\""],
    );
}

/// A critical curve names two free parameters and where it starts; bad keys are one line.
#[test]
fn critical_curve_keys_are_checked() {
    let curve = |analysis: &str| {
        let base = edit("k = 0.1", "k = \"kk\"");
        let at = base.find("[analysis]").unwrap();
        format!(
            "{}[parameters.kk]\nstart = 0.1\nmin = 0.0\nmax = 0.3\n\n[analysis]\ntype = \"critical-curve\"\n{analysis}",
            &base[..at]
        )
    };
    Scene::from_toml_str(
        &curve("control = \"rho\"\nsecond = \"kk\"\nfrom = \"E1\"\n"),
        "t",
    )
    .expect("a valid curve");
    Scene::from_toml_str(
        &curve("control = \"rho\"\nsecond = \"kk\"\nfrom = 2\n"),
        "t",
    )
    .expect("a valid curve from an index");
    rejects(
        &curve("control = \"rho\"\nsecond = \"rho\"\n"),
        &["'analysis.second' = \"rho\" is the control"],
    );
    rejects(
        &curve("control = \"rho\"\nsecond = \"q\"\n"),
        &["'analysis.second': unknown parameter \"q\""],
    );
    rejects(
        &curve("control = \"rho\"\nsecond = \"kk\"\nfrom = -1\n"),
        &["'analysis.from'"],
    );
    rejects(
        &curve("control = \"rho\"\nsecond = \"kk\"\nsteps = 0\n"),
        &["'analysis.steps' must be >= 1, got 0"],
    );
    // Without the second parameter free, kk would be neither free nor governed.
    let text = edit("k = 0.1", "k = \"kk\"") + "\n[parameters.kk]\nstart = 0.1\n";
    rejects(&text, &["'parameters.kk' is neither the control"]);
}

/// A cusp curve names three different free parameters and a range of the third inside its
/// bounds; bad keys are one line naming the key and the value.
#[test]
fn cusp_curve_keys_are_checked() {
    let cusps = |analysis: &str| {
        let base = edit("k = 0.1", "k = \"kk\"").replacen("gravity = 1.0", "gravity = \"g\"", 1);
        let at = base.find("[analysis]").unwrap();
        format!(
            "{}[parameters.kk]\nstart = 0.1\nmin = 0.0\nmax = 0.3\n\n[parameters.g]\nstart = 1.0\nmin = 0.5\nmax = 2.0\n\n[analysis]\ntype = \"cusp-curve\"\ncontrol = \"rho\"\nsecond = \"kk\"\n{analysis}",
            &base[..at]
        )
    };
    let scene = Scene::from_toml_str(&cusps("third = \"g\"\nrange = [0.5, 1.5]\n"), "t")
        .expect("a valid cusp curve");
    let spec = scene
        .analysis
        .get::<memstab::scene::CuspCurveAnalysis>()
        .expect("a cusp curve");
    assert_eq!((spec.slices, spec.bisections), (6, 4));
    assert_eq!(spec.values().first(), Some(&0.5));
    assert_eq!(spec.values().last(), Some(&1.5));
    rejects(
        &cusps("third = \"rho\"\nrange = [0.5, 1.5]\n"),
        &["'analysis.third' = \"rho\" is the control"],
    );
    rejects(
        &cusps("third = \"kk\"\nrange = [0.0, 0.2]\n"),
        &["'analysis.third' = \"kk\" is the second parameter"],
    );
    rejects(
        &cusps("third = \"g\"\nrange = [0.1, 1.5]\n"),
        &["'analysis.range' = [0.1, 1.5]: outside [min, max] = [0.5, 2] of parameters.g"],
    );
    rejects(
        &cusps("third = \"g\"\nrange = [1.5, 0.5]\n"),
        &["'analysis.range' = [1.5, 0.5]: needs [min, max]"],
    );
    rejects(
        &cusps("third = \"g\"\nrange = [0.5, 1.5]\nslices = 1\n"),
        &["'analysis.slices' must be >= 2, got 1"],
    );
    rejects(
        &cusps("third = \"q\"\nrange = [0.5, 1.5]\n"),
        &["'analysis.third': unknown parameter \"q\""],
    );
}

/// `material.wrinkling`, `material.wrinkling-stiffness` and `material.wrinkling-width`: the
/// relaxed energy is chosen by name, its stiffness lies in [0, 1], its switching width in
/// [0, 0.1], and both need it; bad values get one line naming the key.
#[test]
fn wrinkling_keys_are_checked() {
    let relaxed = edit(
        "prestretch = 1.1",
        "prestretch = 1.1\nwrinkling = \"relaxed\"",
    );
    let scene = Scene::from_toml_str(&relaxed, "test.toml").unwrap();
    assert_eq!(
        scene.material.relaxed_stiffness(),
        Some(memstab::scene::DEFAULT_WRINKLING_STIFFNESS)
    );
    let plain = Scene::from_toml_str(BASE, "test.toml").unwrap();
    assert_eq!(plain.material.relaxed_stiffness(), None);
    let with = |eps: &str| {
        edit(
            "prestretch = 1.1",
            &format!("prestretch = 1.1\nwrinkling = \"relaxed\"\nwrinkling-stiffness = {eps}"),
        )
    };
    let scene = Scene::from_toml_str(&with("0.0"), "test.toml").unwrap();
    assert_eq!(scene.material.relaxed_stiffness(), Some(0.0));
    rejects(
        &edit("prestretch = 1.1", "prestretch = 1.1\nwrinkling = \"lax\""),
        &["'material.wrinkling'", "\"lax\"", "none", "relaxed"],
    );
    rejects(
        &with("-0.5"),
        &["'material.wrinkling-stiffness'", "between 0 and 1", "-0.5"],
    );
    rejects(
        &with("2.0"),
        &["'material.wrinkling-stiffness'", "between 0 and 1", "2"],
    );
    rejects(
        &with("\"e\""),
        &["'material.wrinkling-stiffness'", "number", "\"e\""],
    );
    rejects(
        &edit(
            "prestretch = 1.1",
            "prestretch = 1.1\nwrinkling-stiffness = 0.01",
        ),
        &[
            "'material.wrinkling-stiffness'",
            "0.01",
            "wrinkling = \"relaxed\"",
        ],
    );
    // The switching width: 0 unless given, in [0, 0.1], only with the relaxed energy.
    assert_eq!(scene.material.relaxed_width(), Some(0.0));
    assert_eq!(plain.material.relaxed_width(), None);
    let width = |w: &str| {
        edit(
            "prestretch = 1.1",
            &format!("prestretch = 1.1\nwrinkling = \"relaxed\"\nwrinkling-width = {w}"),
        )
    };
    let widened = Scene::from_toml_str(&width("1e-3"), "test.toml").unwrap();
    assert_eq!(widened.material.relaxed_width(), Some(1e-3));
    rejects(
        &width("-1e-3"),
        &["'material.wrinkling-width'", "between 0 and 0.1", "-0.001"],
    );
    rejects(
        &width("0.5"),
        &["'material.wrinkling-width'", "between 0 and 0.1", "0.5"],
    );
    rejects(
        &width("\"wide\""),
        &["'material.wrinkling-width'", "number"],
    );
    rejects(
        &edit(
            "prestretch = 1.1",
            "prestretch = 1.1\nwrinkling-width = 0.01",
        ),
        &[
            "'material.wrinkling-width'",
            "0.01",
            "wrinkling = \"relaxed\"",
        ],
    );
    // The relaxed scene builds on a 3-D mesh and on the meridian, with the areas as
    // measures; the meridian refuses a switching width.
    let study = memstab::study::mesh::MeshStudy::build(scene).unwrap();
    let names: Vec<&str> = study.measures.iter().map(|(n, _)| n.as_str()).collect();
    assert!(
        names
            .windows(2)
            .any(|w| w == ["wrinkled_area", "slack_area"]),
        "{names:?}"
    );
    let on_meridian = |text: &str| {
        text.replace(
            "generator = \"disc\"\nradius = 1.1\nsectors = 6\ndivisions = 3",
            "generator = \"axisymmetric\"\nshape = \"disc\"\nradius = 1.1\nelements = 8",
        )
    };
    let meridian = on_meridian(&relaxed);
    assert!(meridian.contains("axisymmetric"));
    let study = memstab::study::build(Scene::from_toml_str(&meridian, "test.toml").unwrap())
        .expect("the meridian takes the relaxed energy");
    assert!(
        study
            .about()
            .measures
            .ends_with(&["wrinkled_area".to_string(), "slack_area".to_string()]),
        "{:?}",
        study.about().measures
    );
    let err = memstab::study::build(
        Scene::from_toml_str(&on_meridian(&width("1e-3")), "test.toml").unwrap(),
    )
    .err()
    .expect("the meridian refuses a switching width")
    .to_string();
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("material.wrinkling-width = 0.001"), "{err}");
}

/// A `[mesh]` table on its own (as the Python package's `memstab.mesh` gives it) is read and
/// checked as a scene's: the generator's options, and one line naming `mesh.<key>`.
#[test]
fn a_mesh_table_alone_parses_with_the_scenes_messages() {
    let spec = MeshSpec::parse(
        "generator = \"disc\"\nsectors = 8\ndivisions = 3\ngroup = \"C4v\"\n",
        "t",
    )
    .expect("a valid [mesh]");
    let MeshSpec::Disc(disc) = &spec else {
        panic!("a disc: {spec:?}")
    };
    assert_eq!(
        (disc.sectors, disc.divisions, disc.group.as_deref()),
        (8, 3, Some("C4v"))
    );
    let built = spec.build().expect("it builds");
    assert_eq!(built.mesh.triangles.len(), 8 * 3 * 3);
    assert_eq!(built.group().name(), "C4v");
    for (text, needles) in [
        (
            "generator = \"disc\"\nsectors = 0\n",
            &["mesh.sectors", "0"][..],
        ),
        (
            "generator = \"disc\"\nfrequency = 3\n",
            &["mesh.frequency", "disc"][..],
        ),
        ("generator = \"cube\"\n", &["mesh.generator", "cube"][..]),
        (
            "generator = \"icosphere\"\nradius = -1.0\n",
            &["mesh.radius", "-1"][..],
        ),
    ] {
        let e = MeshSpec::parse(text, "t").expect_err(text).to_string();
        assert!(!e.contains('\n'), "{e}");
        for n in needles {
            assert!(e.contains(n), "{text:?}: {e} lacks {n}");
        }
    }
}
