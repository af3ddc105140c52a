//! A bounded fuzz harness: the bundled scenes and mesh file (the corpus), mutated line by
//! line — values replaced by extreme or ill-typed ones, lines deleted, duplicated or cut,
//! stray characters inserted — are loaded, validated and built into a study as `run` does
//! before it solves. Whatever the mutation, that must return a study or an error whose
//! message, as printed, is one bounded line; never panic, hang or exhaust memory (the
//! limits are set low). The corpus holds every analysis and both models: the bundled scenes
//! (a path with branches among them), the meridian's (`scenes/axisymmetric/`), and the
//! balloon as a surface and as a critical curve. `MEMSTAB_FUZZ_CASES` sets the number of
//! cases of each target (default 160 scenes, 96 meridian scenes and 96 mesh files, a few
//! seconds).

use crate::common::balloon_with_k;
use memstab::limits::Limits;
use memstab::scene::{MeshSpec, Scene};
use memstab::study::meridian::MeridianStudy;
use memstab::study::mesh::MeshStudy;
use proptest::prelude::*;
use std::path::{Path, PathBuf};

/// Values that broke parsers and allocators before: extremes, non-numbers, wrong types.
const VALUES: &[&str] = &[
    "0",
    "-1",
    "1",
    "3",
    "0.5",
    "1e308",
    "-1e308",
    "1e-308",
    "1e-300",
    "nan",
    "inf",
    "-inf",
    "9223372036854775807",
    "-9223372036854775808",
    "18446744073709551616",
    "100000000",
    "\"\"",
    "\"x\"",
    "\"C3000v\"",
    "\"C7\"",
    "\"Ih\"",
    "\"step\"",
    "\"a\\u0000b\"",
    "\"\\uFFFE\"",
    "true",
    "[]",
    "[1, 2]",
    "{}",
    "\"/dev/zero\"",
];

/// Characters inserted at random places.
const STRAY: &[&str] = &[
    "\n", "=", "[", "]", "\"", "#", "\u{0}", "\u{FFFE}", "é", ",", ".",
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

/// The scene files of `dir`, in name order.
fn scenes_in(dir: &Path) -> Vec<String> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    files
        .iter()
        .map(|p| std::fs::read_to_string(p).unwrap())
        .collect()
}

/// The balloon (frequency 4, k a parameter) as a surface in (p, k) and as the critical curve
/// of its pressure maximum in (p, k).
fn surface_and_curve() -> Vec<String> {
    let surface = "[parameters.k]\nstart = 0.1\n\n[analysis]\ntype = \"surface\"\n\
        parameters = [\"p\", \"k\"]\nranges = [[0.0, 2.0], [0.05, 0.2]]\npaths = 3\n\
        steps = 60\nmax-step = 0.1\n\n";
    let curve = "[parameters.k]\nstart = 0.1\nmin = 0.05\nmax = 0.3\n\n[analysis]\n\
        type = \"critical-curve\"\ncontrol = \"p\"\nsecond = \"k\"\nfrom = \"limit\"\n\
        steps = 120\npath-steps = 400\nmax-step = 0.05\n\n";
    vec![balloon_with_k(4, surface), balloon_with_k(4, curve)]
}

/// Every 3-D scene: the bundled ones (a path with branches, linear buckling, deflation …),
/// and the balloon's surface and critical curve.
fn corpus() -> Vec<String> {
    let mut all = scenes_in(&root());
    all.extend(surface_and_curve());
    all
}

/// One mutation of a text, by line.
#[derive(Debug, Clone)]
enum Mutation {
    /// The value after `=` (or the last token) of a line replaced.
    Value { line: usize, value: usize },
    /// A line removed.
    Delete { line: usize },
    /// A line repeated.
    Duplicate { line: usize },
    /// A stray character inserted into a line at a fraction of its length.
    Insert { line: usize, at: f64, stray: usize },
    /// The text cut at a fraction of its length.
    Truncate { at: f64 },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        4 => (any::<usize>(), 0..VALUES.len()).prop_map(|(line, value)| Mutation::Value { line, value }),
        1 => any::<usize>().prop_map(|line| Mutation::Delete { line }),
        1 => any::<usize>().prop_map(|line| Mutation::Duplicate { line }),
        1 => (any::<usize>(), 0.0..1.0f64, 0..STRAY.len())
            .prop_map(|(line, at, stray)| Mutation::Insert { line, at, stray }),
        1 => (0.0..1.0f64).prop_map(|at| Mutation::Truncate { at }),
    ]
}

fn cut(s: &str, at: f64) -> usize {
    let mut i = (s.len() as f64 * at) as usize;
    while !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

fn mutate(text: &str, mutations: &[Mutation]) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    for m in mutations {
        if lines.is_empty() {
            break;
        }
        let n = lines.len();
        match *m {
            Mutation::Value { line, value } => {
                let l = &mut lines[line % n];
                let v = VALUES[value];
                *l = match l.find('=') {
                    Some(eq) => format!("{} {v}", &l[..=eq]),
                    None => match l.rfind(' ') {
                        Some(sp) => format!("{} {v}", &l[..sp]),
                        None => v.to_string(),
                    },
                };
            }
            Mutation::Delete { line } => {
                lines.remove(line % n);
            }
            Mutation::Duplicate { line } => {
                let l = lines[line % n].clone();
                lines.insert(line % n, l);
            }
            Mutation::Insert { line, at, stray } => {
                let l = &mut lines[line % n];
                let i = cut(l, at);
                l.insert_str(i, STRAY[stray]);
            }
            Mutation::Truncate { at } => {
                let joined = lines.join("\n");
                let i = cut(&joined, at);
                lines = joined[..i].lines().map(str::to_string).collect();
            }
        }
    }
    lines.join("\n")
}

/// Low limits: no mutated scene may take the machine (a group of order ≤ 120 — Ih, the
/// balloon's —, 512 MiB).
fn limits() -> Limits {
    Limits {
        memory: 512 << 20,
        group_order: 120,
        scene_bytes: 1 << 20,
    }
}

/// What `run` does before it solves: load (parse, validate, resolve the mesh path) and
/// build the study; an error must print as one line of bounded length.
fn load_and_build(path: &Path) -> Result<(), TestCaseError> {
    let outcome = Scene::load(path)
        .map_err(|e| e.to_string())
        .and_then(|scene| match scene.mesh {
            // A meridian's size is bounded by its own keys (elements, modes).
            MeshSpec::Axisymmetric(_) => MeridianStudy::build(scene)
                .map(|_| ())
                .map_err(|e| e.to_string()),
            _ => MeshStudy::build_within(scene, &limits())
                .map(|_| ())
                .map_err(|e| e.to_string()),
        });
    if let Err(e) = outcome {
        let printed = memstab::text::message(&e);
        prop_assert!(!printed.trim().is_empty(), "an empty message");
        prop_assert!(!printed.contains('\n'), "more than one line: {printed:?}");
        prop_assert!(printed.len() <= 4096, "{} bytes", printed.len());
    }
    Ok(())
}

fn cases(default: u32) -> u32 {
    std::env::var("MEMSTAB_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// A directory with the bundled mesh files, for scenes that name them relatively.
fn workspace() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let meshes = dir.path().join("meshes");
    std::fs::create_dir(&meshes).unwrap();
    for e in std::fs::read_dir(root().join("meshes")).unwrap() {
        let p = e.unwrap().path();
        std::fs::copy(&p, meshes.join(p.file_name().unwrap())).unwrap();
    }
    dir
}

#[test]
fn mutated_scenes_load_or_say_why_in_one_line() {
    let corpus = corpus();
    assert!(corpus.len() >= 5, "the bundled scenes are the corpus");
    mutants_load_or_say_why(&corpus, cases(160));
}

/// `cases` mutants of the scenes of `corpus` (one to three mutations each): each loads and
/// builds, or says why in one bounded line.
fn mutants_load_or_say_why(corpus: &[String], cases: u32) {
    let dir = workspace();
    let path = dir.path().join("scene.toml");
    let config = ProptestConfig {
        cases,
        failure_persistence: None,
        ..ProptestConfig::default()
    };
    proptest!(config, |(
        which in 0..corpus.len(),
        mutations in proptest::collection::vec(mutation(), 1..4),
    )| {
        std::fs::write(&path, mutate(&corpus[which], &mutations)).unwrap();
        load_and_build(&path)?;
    });
}

/// The meridian's scenes (every shape, gas, fluid, spin, planes, a held translation, linear
/// buckling), mutated: a study or one bounded line, as on the 3-D mesh.
#[test]
fn mutated_meridian_scenes_load_or_say_why_in_one_line() {
    let corpus = scenes_in(&root().join("axisymmetric"));
    assert!(
        corpus.len() >= 5,
        "the bundled meridian scenes are the corpus"
    );
    mutants_load_or_say_why(&corpus, cases(96));
}

#[test]
fn mutated_mesh_files_load_or_say_why_in_one_line() {
    let dir = workspace();
    let msh = std::fs::read_to_string(root().join("meshes/disc_c7v.msh")).unwrap();
    let scene = std::fs::read_to_string(root().join("disc_file.toml"))
        .unwrap()
        .replace("meshes/disc_c7v.msh", "meshes/mutated.msh");
    assert!(scene.contains("mutated.msh"));
    let path = dir.path().join("scene.toml");
    std::fs::write(&path, scene).unwrap();
    let config = ProptestConfig {
        cases: cases(96),
        failure_persistence: None,
        ..ProptestConfig::default()
    };
    proptest!(config, |(mutations in proptest::collection::vec(mutation(), 1..4))| {
        std::fs::write(dir.path().join("meshes/mutated.msh"), mutate(&msh, &mutations)).unwrap();
        load_and_build(&path)?;
    });
}

#[test]
fn the_mutations_change_the_text() {
    let text = "a = 1\nb = 2\nc = 3";
    let m = |ms: &[Mutation]| mutate(text, ms);
    assert_eq!(
        m(&[Mutation::Value { line: 1, value: 5 }]),
        "a = 1\nb = 1e308\nc = 3"
    );
    assert_eq!(m(&[Mutation::Delete { line: 3 }]), "b = 2\nc = 3");
    assert_eq!(
        m(&[Mutation::Duplicate { line: 2 }]),
        "a = 1\nb = 2\nc = 3\nc = 3"
    );
    assert_eq!(
        m(&[Mutation::Insert {
            line: 0,
            at: 0.0,
            stray: 1
        }]),
        "=a = 1\nb = 2\nc = 3"
    );
    assert_eq!(m(&[Mutation::Truncate { at: 0.5 }]), "a = 1\nb ");
}

/// A mesh file declared with a huge group (C3000v, order 6000) is refused by the limits, not
/// built while the scene is validated (building it took minutes).
#[test]
fn a_huge_declared_group_is_refused_by_name() {
    let dir = workspace();
    let path = dir.path().join("scene.toml");
    let text = std::fs::read_to_string(root().join("disc_file.toml")).unwrap();
    assert!(text.contains("group = \"C7v\""));
    std::fs::write(&path, text.replace("group = \"C7v\"", "group = \"C3000v\"")).unwrap();
    let scene = Scene::load(&path).expect("a valid group name");
    let err = MeshStudy::build_within(scene, &limits())
        .err()
        .expect("refused by the limits");
    assert!(err.to_string().contains("C3000v"), "{err}");
}

/// The corpus is valid before it is mutated: each scene loads and builds under the harness's
/// limits (so that the mutants explore every analysis and both models).
#[test]
fn the_corpus_loads_and_builds() {
    let dir = workspace();
    let path = dir.path().join("scene.toml");
    let mut all = corpus();
    all.extend(scenes_in(&root().join("axisymmetric")));
    for text in &all {
        std::fs::write(&path, text).unwrap();
        let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
        let built = match scene.mesh {
            MeshSpec::Axisymmetric(_) => MeridianStudy::build(scene)
                .map(|_| ())
                .err()
                .map(|e| e.to_string()),
            _ => MeshStudy::build_within(scene, &limits())
                .map(|_| ())
                .err()
                .map(|e| e.to_string()),
        };
        assert_eq!(built, None);
    }
}
