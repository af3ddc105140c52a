//! A scene may name a mesh *file* instead of a generator (`[mesh] generator = "file"`): the
//! disc of `scenes/disc_fluid_below.toml`, written to `.msh` and `.vtu` and read back, gives
//! the same path to the last bit as the generator's disc; the declared group is verified;
//! bad files, groups and keys are one-line errors naming the key, and `memstab run` exits
//! with code 2 without writing anything.

use crate::common::memstab;
use memstab::analysis::run;
use memstab::results::PathReport;
use memstab::scene::{MeshSpec, Scene};
use memstab::study::mesh::MeshStudy;
use meshes::write::{write_mesh, Fields, Format};
use serde_json::Value;
use std::path::{Path, PathBuf};

const SCENE: &str = include_str!("../scenes/disc_fluid_below.toml");

/// The `[mesh]` table of `scenes/disc_fluid_below.toml`.
const GENERATOR_MESH: &str = "[mesh]
generator = \"disc\"
radius = 1.1
sectors = 7
divisions = 16
";

/// The bundled disc scene with a small step budget, so that a run takes about a second.
fn generator_scene() -> String {
    assert!(SCENE.contains(GENERATOR_MESH), "the bundled scene changed");
    SCENE.replacen("steps = 400", "steps = 8", 1)
}

/// The same scene with its `[mesh]` table replaced by `mesh` (TOML lines after `[mesh]`).
fn scene_with_mesh(mesh: &str) -> String {
    generator_scene().replacen(GENERATOR_MESH, &format!("[mesh]\n{mesh}\n"), 1)
}

/// `generator = "file"` with `path` (a TOML literal string) and `group`, if any.
fn file_mesh(path: &Path, group: Option<&str>) -> String {
    let mut m = format!("generator = \"file\"\npath = '{}'\n", path.display());
    if let Some(g) = group {
        m.push_str(&format!("group = \"{g}\"\n"));
    }
    m
}

/// The disc of the bundled scene written as `name` (format from the extension) into `dir`.
fn write_disc(dir: &Path, name: &str, binary: bool) -> PathBuf {
    let scene = Scene::from_toml_str(&generator_scene(), "disc").unwrap();
    let mesh = scene.mesh.build().unwrap();
    let path = dir.join(name);
    let format = Format::from_path(&path, binary).unwrap();
    write_mesh(&path, &mesh.mesh, &Fields::new(), format).unwrap();
    path
}

fn run_text(text: &str, origin: &str) -> (MeshStudy, PathReport) {
    let scene = Scene::from_toml_str(text, origin).unwrap_or_else(|e| panic!("{e}"));
    let mut study = MeshStudy::build(scene).unwrap_or_else(|e| panic!("{e}"));
    let result = run(&mut study, |_, _| {}).unwrap_or_else(|e| panic!("{origin}: {e}"));
    (study, result.report)
}

/// The report as JSON without the fields that name where the scene and mesh came from.
fn comparable(report: &PathReport) -> Value {
    let mut v = serde_json::to_value(report).unwrap();
    let o = v.as_object_mut().unwrap();
    o.remove("origin");
    o["mesh"].as_object_mut().unwrap().remove("generator");
    v
}

#[test]
fn a_mesh_file_gives_the_generators_path_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let (_, reference) = run_text(&generator_scene(), "generator");
    assert_eq!(reference.mesh.generator, "disc");
    assert!(reference.rows.len() > 3, "{}", reference.stop);
    for (name, binary) in [
        ("disc.msh", false),
        ("disc.vtu", false),
        ("base64.vtu", true),
    ] {
        let path = write_disc(dir.path(), name, binary);
        let text = scene_with_mesh(&file_mesh(&path, Some("C7v")));
        let (study, report) = run_text(&text, name);
        assert_eq!(report.mesh.generator, "file");
        assert_eq!(report.mesh.group, "C7v");
        assert_eq!(report.group, reference.group, "{name}: the scene's group");
        assert_eq!(report.mesh.nodes, reference.mesh.nodes);
        assert_eq!(report.symmetric_unknowns, reference.symmetric_unknowns);
        // Every number of the path, the critical and turning points: the same bits (the JSON
        // of an f64 is its shortest round-trip form).
        assert_eq!(comparable(&report), comparable(&reference), "{name}");
        // The disc has no symmetry beyond C7v.
        assert!(study.warnings.is_empty(), "{:?}", study.warnings);
    }
}

#[test]
fn relative_paths_follow_the_scene_file() {
    let dir = tempfile::tempdir().unwrap();
    let sub = dir.path().join("meshes");
    std::fs::create_dir(&sub).unwrap();
    let mesh = write_disc(&sub, "disc.msh", false);
    let text = scene_with_mesh("generator = \"file\"\npath = \"meshes/disc.msh\"\ngroup = \"C7v\"");
    let file = dir.path().join("scene.toml");
    std::fs::write(&file, &text).unwrap();
    let scene = Scene::load(&file).unwrap();
    let MeshSpec::File(f) = &scene.mesh else {
        panic!("a file mesh")
    };
    assert_eq!(f.path, mesh);
    assert_eq!(scene.build_mesh().unwrap().group().name(), "C7v");
    // The scene survives a round trip through TOML, mesh path included.
    let again = Scene::from_toml_str(&scene.to_toml(), &scene.origin).unwrap();
    assert_eq!(again, scene);
    // Parsed from a string, the path is relative to the current directory (the package
    // root here), where there is no such file.
    let from_string = Scene::from_toml_str(&text, "string").unwrap();
    let err = from_string.build_mesh().unwrap_err().to_string();
    assert!(
        err.contains("'mesh.path' = \"meshes/disc.msh\": cannot read the mesh file"),
        "{err}"
    );
}

#[test]
fn the_group_defaults_to_c1_and_hidden_symmetry_is_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_disc(dir.path(), "disc.msh", false);
    let scene = Scene::from_toml_str(&scene_with_mesh(&file_mesh(&path, None)), "c1").unwrap();
    let MeshSpec::File(f) = &scene.mesh else {
        panic!("a file mesh")
    };
    assert_eq!(f.group, "C1");
    let study = MeshStudy::build(scene).unwrap();
    assert_eq!(study.mesh.group().name(), "C1");
    assert_eq!(study.action.group().order(), 1);
    let [warning] = study.warnings.as_slice() else {
        panic!("one warning: {:?}", study.warnings)
    };
    for needle in [
        "symmetry beyond mesh.group = \"C1\"",
        "disc.msh",
        "and 10 more",
    ] {
        assert!(warning.contains(needle), "{needle:?} not in: {warning}");
    }
    // The warning reaches the run's report (path.json and the terminal).
    let warning = warning.clone();
    let mut study = study;
    let result = memstab::analysis::run(&mut study, |_, _| {}).unwrap();
    assert!(
        result.report.warnings.contains(&warning),
        "{:?}",
        result.report.warnings
    );
    // A subgroup that verifies: C7 misses the seven mirrors.
    let c7 = Scene::from_toml_str(&scene_with_mesh(&file_mesh(&path, Some("C7"))), "c7").unwrap();
    let mesh = c7.build_mesh().unwrap();
    let warnings = c7.mesh_warnings(&mesh);
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(warnings[0].contains("mirror"), "{}", warnings[0]);
}

/// The one-line error of loading and building `text`, which must name every needle.
fn rejected(text: &str, needles: &[&str]) -> String {
    let err = match Scene::from_toml_str(text, "test.toml") {
        Ok(scene) => match scene.build_mesh() {
            Ok(_) => panic!("accepted:\n{text}"),
            Err(e) => e,
        },
        Err(e) => e,
    };
    let message = err.to_string();
    assert_eq!(message.lines().count(), 1, "not one line: {message}");
    assert!(message.starts_with("test.toml: "), "{message}");
    for needle in needles {
        assert!(message.contains(needle), "{needle:?} not in: {message}");
    }
    message
}

/// The scene texts that must be refused, with what their messages must say; `dir` holds a
/// good `disc.msh`.
fn bad_scenes(dir: &Path) -> Vec<(String, Vec<String>)> {
    let good = write_disc(dir, "disc.msh", false);
    let missing = dir.join("missing.msh");
    let garbage = dir.join("garbage.msh");
    std::fs::write(
        &garbage,
        "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 2\n",
    )
    .unwrap();
    let xdmf = dir.join("disc.xdmf");
    let s = |x: &str| x.to_string();
    let shown = |p: &Path| format!("\"{}\"", p.display());
    vec![
        (
            scene_with_mesh(&file_mesh(&missing, Some("C7v"))),
            vec![
                s("'mesh.path' = "),
                shown(&missing),
                s("cannot read the mesh file"),
            ],
        ),
        (
            scene_with_mesh(&file_mesh(&garbage, None)),
            vec![s("'mesh.path' = "), s("line 5")],
        ),
        (
            scene_with_mesh(&file_mesh(&xdmf, None)),
            vec![s("'mesh.path'"), s(".msh"), s(".vtu")],
        ),
        (
            scene_with_mesh(&file_mesh(&good, Some("C9v"))),
            vec![
                s("'mesh.group' = \"C9v\": the group does not map the mesh in '"),
                s("disc.msh' to itself ("),
            ],
        ),
        (
            scene_with_mesh(&file_mesh(&good, Some("C14v"))),
            vec![s("'mesh.group' = \"C14v\"")],
        ),
        (
            scene_with_mesh(&file_mesh(&good, Some("D7"))),
            vec![s("'mesh.group' = \"D7\""), s("unknown group")],
        ),
        (
            scene_with_mesh(&format!("{}radius = 1.1\n", file_mesh(&good, None))),
            vec![s(
                "'mesh.radius' is not an option of generator \"file\" (its options: path, group)",
            )],
        ),
        (
            scene_with_mesh(&format!(
                "generator = \"file\"\npaht = '{}'\n",
                good.display()
            )),
            vec![s("unknown key 'mesh.paht'"), s("path")],
        ),
        (
            scene_with_mesh("generator = \"file\"\ngroup = \"C7v\"\n"),
            vec![s("missing field 'mesh.path'")],
        ),
        (
            scene_with_mesh("generator = \"file\"\npath = 7\n"),
            vec![s("'mesh.path': expected a string, got 7")],
        ),
        (
            scene_with_mesh("generator = \"file\"\npath = \"\"\n"),
            vec![s("'mesh.path' must name a mesh file")],
        ),
    ]
}

#[test]
fn bad_files_groups_and_keys_are_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    for (text, needles) in bad_scenes(dir.path()) {
        let needles: Vec<&str> = needles.iter().map(String::as_str).collect();
        rejected(&text, &needles);
    }
    // A file without the node set the scene fixes.
    let sym = Scene::from_toml_str(&generator_scene(), "disc")
        .unwrap()
        .mesh
        .build()
        .unwrap();
    let mut bare = sym.mesh.clone();
    bare.boundaries.clear();
    let path = dir.path().join("bare.vtu");
    write_mesh(&path, &bare, &Fields::new(), Format::VtuAscii).unwrap();
    rejected(
        &scene_with_mesh(&file_mesh(&path, Some("C7v"))),
        &[
            "'boundary.fixed[0]': unknown node set \"rim\" (the mesh in '",
            "bare.vtu' has no node sets)",
        ],
    );
}

#[test]
fn memstab_run_exits_with_2_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("never");
    for (k, (text, needles)) in bad_scenes(dir.path()).into_iter().enumerate() {
        let file = dir.path().join(format!("bad{k}.toml"));
        std::fs::write(&file, text).unwrap();
        let o = memstab(&[
            "run",
            file.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{}: {err}", file.display());
        assert_eq!(err.trim_end().lines().count(), 1, "not one line: {err}");
        assert!(err.contains(&format!("bad{k}.toml")), "{err}");
        for needle in &needles {
            assert!(err.contains(needle.as_str()), "{needle:?} not in: {err}");
        }
        assert!(
            !out.exists(),
            "{} created the output directory",
            file.display()
        );
    }
}

#[test]
fn memstab_run_reads_a_mesh_file_next_to_the_scene() {
    let dir = tempfile::tempdir().unwrap();
    write_disc(dir.path(), "disc.msh", false);
    let file = dir.path().join("scene.toml");
    std::fs::write(
        &file,
        scene_with_mesh("generator = \"file\"\npath = \"disc.msh\"\ngroup = \"C7v\""),
    )
    .unwrap();
    let out = dir.path().join("out");
    let o = memstab(&[
        "run",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--json",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let summary: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(summary["group"], "C7v");
    let path: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("path.json")).unwrap()).unwrap();
    assert_eq!(path["mesh"]["generator"], "file");
    assert_eq!(path["mesh"]["group"], "C7v");
}

#[test]
fn the_bundled_file_scene_matches_its_generator() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut scene = Scene::load(root.join("scenes/disc_file.toml")).unwrap();
    let MeshSpec::File(f) = &scene.mesh else {
        panic!("scenes/disc_file.toml reads its mesh from a file")
    };
    assert!(f.path.is_file(), "{}", f.path.display());
    let size = std::fs::metadata(&f.path).unwrap().len();
    assert!(size < 200_000, "the bundled mesh is {size} bytes");
    let group = f.group.clone();
    // The generator that wrote the file (see the scene's comment), same everything else.
    let mut twin = scene.clone();
    twin.mesh = Scene::from_toml_str(
        &scene_with_mesh("generator = \"disc\"\nradius = 1.1\nsectors = 7\ndivisions = 8"),
        "twin",
    )
    .unwrap()
    .mesh;
    for s in [&mut scene, &mut twin] {
        s.analysis.set_budget(6);
    }
    let run_scene = |s: Scene| {
        let mut study = MeshStudy::build(s).unwrap();
        assert!(study.warnings.is_empty(), "{:?}", study.warnings);
        run(&mut study, |_, _| {}).unwrap().report
    };
    let (a, b) = (run_scene(scene), run_scene(twin));
    assert_eq!(a.mesh.group, group);
    assert_eq!(comparable(&a), comparable(&b));
}
