//! Faults injected into whole commands: runs interrupted from inside after the k-th accepted
//! step (the test hook `MEMSTAB_INTERRUPT_AFTER_STEPS`, no timed signals), edited and older
//! run directories, and two runs into one directory at once. The contracts: exit 130 with the
//! outputs written, stop reason `interrupted` and a manifest that verifies; every run lists
//! every file it wrote by its path in the directory; the readers of a finished run refuse an
//! edited file (exit 2, one line naming it) and read a run without a manifest with a warning.

use crate::common::balloon_with_k;
use std::collections::BTreeSet;
use std::path::Path;
use std::process::{Command, Output};

fn memstab(args: &[&str], interrupt_after: Option<usize>) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_memstab"));
    cmd.args(args);
    match interrupt_after {
        Some(k) => cmd.env("MEMSTAB_INTERRUPT_AFTER_STEPS", k.to_string()),
        None => cmd.env_remove("MEMSTAB_INTERRUPT_AFTER_STEPS"),
    };
    cmd.output().expect("the binary runs")
}

fn scene(name: &str) -> String {
    format!("{}/scenes/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// `memstab run SCENE --out OUT --quiet`, with the hook at `k`.
fn run(scene: &str, out: &Path, k: Option<usize>) -> Output {
    memstab(
        &["run", scene, "--out", out.to_str().unwrap(), "--quiet"],
        k,
    )
}

/// Every file under `dir` but its manifest, by its `/`-separated path in `dir`.
fn files_under(dir: &Path) -> BTreeSet<String> {
    fn walk(root: &Path, at: &Path, found: &mut BTreeSet<String>) {
        for e in std::fs::read_dir(at).unwrap() {
            let e = e.unwrap();
            let path = e.path();
            if path.is_dir() {
                walk(root, &path, found);
            } else {
                let rel = path.strip_prefix(root).unwrap();
                let rel: Vec<String> = rel
                    .components()
                    .map(|c| c.as_os_str().to_string_lossy().into_owned())
                    .collect();
                found.insert(rel.join("/"));
            }
        }
    }
    let mut found = BTreeSet::new();
    walk(dir, dir, &mut found);
    found.remove("manifest.json");
    found
}

/// The manifest of `dir` lists every file under it (but itself) once, by its path in `dir`,
/// with its size and checksum; returns its stop reason.
fn assert_manifest_verifies(dir: &Path) -> String {
    let manifest = json(&dir.join("manifest.json"));
    let listed: Vec<String> = manifest["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["file"].as_str().unwrap().to_string())
        .collect();
    let unique: BTreeSet<String> = listed.iter().cloned().collect();
    assert_eq!(unique.len(), listed.len(), "listed twice: {listed:?}");
    assert_eq!(
        unique,
        files_under(dir),
        "the manifest of {}",
        dir.display()
    );
    for f in manifest["files"].as_array().unwrap() {
        let path = dir.join(f["file"].as_str().unwrap());
        assert_eq!(
            memstab::output::sha256(&path).unwrap(),
            f["sha256"].as_str().unwrap(),
            "{}",
            path.display()
        );
        assert_eq!(
            std::fs::metadata(&path).unwrap().len(),
            f["bytes"].as_u64().unwrap()
        );
    }
    if dir.join("path.json").is_file() {
        assert_eq!(
            memstab::output::verify(dir, &["path.json"]),
            Ok(memstab::output::Verified::Listed)
        );
    }
    manifest["stop"].as_str().unwrap().to_string()
}

/// Exit 2 and one line on stderr naming `file`.
fn assert_refused(o: &Output, file: &str) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    assert!(err.contains(file), "{err:?} does not name {file}");
    assert!(err.contains("checksum"), "{err}");
}

/// The bundled balloon at frequency 4 with the analysis `analysis` (k a parameter), in `dir`.
fn balloon_scene(dir: &Path, name: &str, analysis: &str) -> String {
    let path = dir.join(name);
    std::fs::write(&path, balloon_with_k(4, analysis)).unwrap();
    path.to_string_lossy().into_owned()
}

const SURFACE: &str = "[parameters.k]\nstart = 0.1\n\n[analysis]\ntype = \"surface\"\n\
    parameters = [\"p\", \"k\"]\nranges = [[0.0, 2.0], [0.05, 0.2]]\npaths = 3\nsteps = 60\n\
    max-step = 0.1\n\n";

const CURVE: &str = "[parameters.k]\nstart = 0.1\nmin = 0.05\nmax = 0.3\n\n[analysis]\n\
    type = \"critical-curve\"\ncontrol = \"p\"\nsecond = \"k\"\nfrom = \"limit\"\nsteps = 120\n\
    path-steps = 400\nmax-step = 0.05\n\n";

/// A run with branches (the disc pushed upward) lists the files of its branch directories by
/// their paths (`branch_01/path.csv`, not `path.csv` three times), and verifies against its
/// own manifest; so does each branch directory against its own. A second run into the same
/// directory replaces the manifest.
#[test]
fn a_run_with_branches_verifies_against_its_own_manifest() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let o = run(&scene("disc_upward.toml"), &out, None);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.join("branch_01").is_dir());
    assert_manifest_verifies(&out);
    assert_manifest_verifies(&out.join("branch_01"));
    let listed = json(&out.join("manifest.json"))["files"].to_string();
    assert!(listed.contains("\"branch_01/path.csv\""), "{listed}");
    assert!(listed.contains("\"branch_01/manifest.json\""), "{listed}");
    // The meridian goes through the same writer.
    let meridian = dir.path().join("meridian");
    let o = run(&scene("axisymmetric/balloon.toml"), &meridian, None);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_manifest_verifies(&meridian);
    // Another run into the meridian's directory: the old manifest is replaced, not extended
    // (the meridian's files are left, unlisted).
    let o = run(&scene("disc_upward.toml"), &meridian, None);
    assert!(o.status.success(), "{}", stderr(&o));
    let listed = json(&meridian.join("manifest.json"))["files"].to_string();
    assert!(listed.contains("branch_01/path.csv"));
    assert_eq!(
        memstab::output::verify(&meridian, &["path.json", "path.states"]),
        Ok(memstab::output::Verified::Listed)
    );
}

/// The readers of a finished run check what they read against its manifest: `memstab branch`,
/// `spectrum --point`, `export-matrix --point`, `[start] from` and a critical curve's
/// `from-run` refuse an edited file (exit 2, one line naming it, nothing written); a run
/// without a manifest (an older version's) is read with a warning.
#[test]
fn readers_refuse_an_edited_run_and_warn_on_an_unlisted_one() {
    let dir = tempfile::tempdir().unwrap();
    let pristine = dir.path().join("pristine");
    let o = run(&scene("disc_upward.toml"), &pristine, None);
    assert!(o.status.success(), "{}", stderr(&o));
    let copy = |name: &str| {
        let to = dir.path().join(name);
        let o = Command::new("cp")
            .args(["-r", pristine.to_str().unwrap(), to.to_str().unwrap()])
            .status()
            .unwrap();
        assert!(o.success());
        to
    };
    // path.json with its control scaled.
    let edited = copy("edited_json");
    let text = std::fs::read_to_string(edited.join("path.json")).unwrap();
    std::fs::write(
        edited.join("path.json"),
        text.replacen("\"h\"", "\"h\" ", 1),
    )
    .unwrap();
    let e = edited.to_str().unwrap();
    let before = files_under(&edited);
    let o = memstab(&["branch", e, "--critical", "1"], None);
    assert_refused(&o, "path.json");
    let o = memstab(&["spectrum", e, "--point", "3"], None);
    assert_refused(&o, "path.json");
    let mtx = dir.path().join("K.mtx");
    let o = memstab(
        &[
            "export-matrix",
            e,
            "--point",
            "3",
            "--out",
            mtx.to_str().unwrap(),
        ],
        None,
    );
    assert_refused(&o, "path.json");
    assert!(!mtx.exists());
    assert_eq!(files_under(&edited), before, "nothing was written");
    // path.states and critical.states with one byte changed.
    let flip = |file: &Path| {
        let mut bytes = std::fs::read(file).unwrap();
        let n = bytes.len() - 3;
        bytes[n] ^= 1;
        std::fs::write(file, bytes).unwrap();
    };
    let states = copy("edited_states");
    flip(&states.join("path.states"));
    let s = states.to_str().unwrap();
    assert_refused(
        &memstab(&["spectrum", s, "--point", "3"], None),
        "path.states",
    );
    let text = std::fs::read_to_string(scene("disc_upward.toml")).unwrap();
    assert!(!text.contains("[start]"));
    let from = format!(
        "{text}\n[start]\nfrom = \"{}\"\npoint = 3\n",
        states.join("path.json").display()
    );
    let from_scene = dir.path().join("from.toml");
    std::fs::write(&from_scene, &from).unwrap();
    let out = dir.path().join("from_out");
    let o = run(from_scene.to_str().unwrap(), &out, None);
    assert_refused(&o, "path.states");
    assert!(!out.exists(), "nothing written");
    let critical = copy("edited_critical");
    flip(&critical.join("critical.states"));
    let o = memstab(
        &["branch", critical.to_str().unwrap(), "--critical", "1"],
        None,
    );
    assert_refused(&o, "critical.states");

    // A critical curve from a balloon run whose critical.states was edited.
    let path_scene = balloon_scene(
        dir.path(),
        "balloon_path.toml",
        "[parameters.k]\nstart = 0.1\nmin = 0.05\nmax = 0.3\n\n\
         [[constraint]]\ntype = \"fixed\"\nparameter = \"k\"\n\n[analysis]\ntype = \"path\"\n\
         control = \"p\"\nsteps = 40\nmax-step = 0.05\n\n",
    );
    let balloon_run = dir.path().join("balloon_run");
    let o = run(&path_scene, &balloon_run, None);
    assert!(o.status.success(), "{}", stderr(&o));
    let curve = CURVE.replacen(
        "from = \"limit\"\n",
        &format!("from = 0\nfrom-run = \"{}\"\n", balloon_run.display()),
        1,
    );
    let curve_scene = balloon_scene(dir.path(), "curve.toml", &curve);
    let curve_out = dir.path().join("curve_out");
    let o = run(&curve_scene, &curve_out, None);
    assert!(
        o.status.success(),
        "the pristine run restarts: {}",
        stderr(&o)
    );
    flip(&balloon_run.join("critical.states"));
    let o = run(&curve_scene, &dir.path().join("curve_out2"), None);
    assert_refused(&o, "critical.states");
    assert!(!dir.path().join("curve_out2").exists());

    // No manifest: read, with a warning naming the directory.
    let older = copy("older");
    std::fs::remove_file(older.join("manifest.json")).unwrap();
    let o = memstab(&["spectrum", older.to_str().unwrap(), "--point", "3"], None);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("warning") && stderr(&o).contains("no manifest.json"),
        "{}",
        stderr(&o)
    );
    let o = memstab(
        &[
            "branch",
            older.to_str().unwrap(),
            "--critical",
            "1",
            "--json",
        ],
        None,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("no manifest.json"), "{}", stderr(&o));
    // No partial manifest is made for it: its run's files stay readable.
    assert!(!older.join("manifest.json").exists());
}

/// `memstab branch` adds what it wrote to the run's manifest, which still verifies; a later
/// reader accepts the directory.
#[test]
fn branch_adds_its_files_to_the_runs_manifest() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let text = std::fs::read_to_string(scene("disc_upward.toml")).unwrap();
    let at = text
        .find("\n[analysis.branches]")
        .expect("the scene has branches");
    let end = text[at + 1..]
        .find("\n[")
        .map_or(text.len(), |e| at + 1 + e);
    let plain = format!("{}{}", &text[..at], &text[end..]);
    let plain_scene = dir.path().join("plain.toml");
    std::fs::write(&plain_scene, plain).unwrap();
    let o = run(plain_scene.to_str().unwrap(), &out, None);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!out.join("branch_01").exists());
    let o = memstab(
        &[
            "branch",
            out.to_str().unwrap(),
            "--critical",
            "1",
            "--steps",
            "5",
            "--scene",
            plain_scene.to_str().unwrap(),
        ],
        None,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.join("branch_01").is_dir());
    assert_manifest_verifies(&out);
    let o = memstab(&["spectrum", out.to_str().unwrap(), "--point", "2"], None);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
}

/// Exit 130, stop reason `interrupted` in the manifest, and a manifest that verifies.
fn assert_interrupted(o: &Output, out: &Path) {
    assert_eq!(o.status.code(), Some(130), "{}", stderr(o));
    assert!(stderr(o).contains("interrupted"), "{}", stderr(o));
    assert_eq!(assert_manifest_verifies(out), "interrupted");
}

/// A signal while the branches of a finished path are followed (after the path's 32 steps)
/// ends `run` with exit 130; the path is whole, the branches stop where they were.
#[test]
fn an_interrupt_while_branches_are_followed_exits_130() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let o = run(&scene("disc_upward.toml"), &out, Some(40));
    assert_interrupted(&o, &out);
    assert!(out.join("branch_01").is_dir());
    assert_eq!(json(&out.join("path.json"))["stop"], "interrupted");
    let graph = std::fs::read_to_string(out.join("branches.json")).unwrap();
    assert!(graph.contains("interrupted"), "{graph}");
    // And `memstab branch` on a finished run.
    let full = dir.path().join("full");
    let o = run(&scene("disc_upward.toml"), &full, None);
    assert!(o.status.success(), "{}", stderr(&o));
    let branch_out = dir.path().join("branches");
    std::fs::create_dir(&branch_out).unwrap();
    let o = memstab(
        &[
            "branch",
            full.to_str().unwrap(),
            "--critical",
            "1",
            "--out",
            branch_out.to_str().unwrap(),
        ],
        Some(3),
    );
    assert_interrupted(&o, &branch_out);
    assert!(branch_out.join("branches.json").is_file());
}

/// A signal during a cusp curve's slices ends the run with exit 130: in its first slice's
/// path with that path written, later with the slices so far in `cusp_curve.json`.
#[test]
fn an_interrupt_in_a_cusp_curve_exits_130_with_what_it_found() {
    let dir = tempfile::tempdir().unwrap();
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/thesis/paper1_disc_swallowtail.toml"
    );
    // The first slice's path takes about 140 points, its curve 120.
    let out = dir.path().join("early");
    let o = run(scene, &out, Some(20));
    assert_interrupted(&o, &out);
    assert!(out.join("path.csv").is_file());
    let out = dir.path().join("later");
    let o = run(scene, &out, Some(600));
    assert_interrupted(&o, &out);
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("cusp_curve.json")).unwrap())
            .unwrap();
    let slices = report["slices"].as_array().unwrap().len();
    assert!((1..10).contains(&slices), "{slices} slices: cut short");
}

/// A signal in a surface's later paths, and in a critical curve's curve phase, ends the run
/// with exit 130 and the analysis' own files written; in the curve's path phase, with the
/// path so far.
#[test]
fn an_interrupt_in_a_surface_or_a_curve_exits_130() {
    let dir = tempfile::tempdir().unwrap();
    // The surface's first path takes 61 steps; the curve's path 24.
    let surface = balloon_scene(dir.path(), "surface.toml", SURFACE);
    let out = dir.path().join("surface");
    let o = run(&surface, &out, Some(75));
    assert_interrupted(&o, &out);
    assert!(out.join("surface.json").is_file());
    let curve = balloon_scene(dir.path(), "curve.toml", CURVE);
    let out = dir.path().join("curve");
    let o = run(&curve, &out, Some(34));
    assert_interrupted(&o, &out);
    assert!(out.join("curve.csv").is_file());
    let rows = std::fs::read_to_string(out.join("curve.csv"))
        .unwrap()
        .lines()
        .count();
    assert!(
        (2..60).contains(&rows),
        "{rows} rows: the curve was cut short"
    );
    // In the path phase: the path so far, no curve.
    let out = dir.path().join("curve_path");
    let o = run(&curve, &out, Some(10));
    assert_interrupted(&o, &out);
    assert!(out.join("path.csv").is_file());
    assert!(!out.join("curve.csv").exists());
}

/// Two runs started at once into one directory: one takes the directory's lock, the other is
/// refused up front (exit 2, one line naming the directory, nothing written) or runs after it;
/// never a failure, and the directory's manifest verifies. A lock held by a running process
/// is refused the same way; one whose process is gone is taken over.
#[test]
fn concurrent_runs_into_one_directory() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let disc = scene("disc_upward.toml");
    for _ in 0..3 {
        let start = || {
            Command::new(env!("CARGO_BIN_EXE_memstab"))
                .args(["run", &disc, "--out", out.to_str().unwrap(), "--quiet"])
                .env_remove("MEMSTAB_INTERRUPT_AFTER_STEPS")
                .stdout(std::process::Stdio::null())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap()
        };
        let (a, b) = (start(), start());
        let outputs = [a.wait_with_output().unwrap(), b.wait_with_output().unwrap()];
        let codes: Vec<Option<i32>> = outputs.iter().map(|o| o.status.code()).collect();
        assert!(codes.contains(&Some(0)), "{codes:?}");
        for o in &outputs {
            match o.status.code() {
                Some(0) => {}
                Some(2) => {
                    let err = stderr(o);
                    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
                    assert!(err.contains("in use by another memstab run"), "{err}");
                }
                c => panic!("exit {c:?}: {}", stderr(o)),
            }
        }
        assert_manifest_verifies(&out);
        assert!(!out.join(memstab::output::LOCK).exists());
    }
    // A lock held by a running process (this one).
    let held = dir.path().join("held");
    std::fs::create_dir(&held).unwrap();
    let lock = held.join(memstab::output::LOCK);
    std::fs::write(&lock, format!("{}\n", std::process::id())).unwrap();
    let o = run(&disc, &held, None);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains(&std::process::id().to_string()));
    assert_eq!(
        std::fs::read_dir(&held).unwrap().count(),
        1,
        "nothing written"
    );
    // The same lock of a process that is gone: taken over.
    if Path::new("/proc/self").exists() {
        std::fs::write(&lock, format!("{}\n", u32::MAX - 1)).unwrap();
        let o = run(&disc, &held, None);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(!lock.exists());
        assert_manifest_verifies(&held);
    }
}

/// `memstab CMD ARGS` with the Newton-iteration hook at `k`.
fn memstab_iterations(args: &[&str], k: usize) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_memstab"));
    cmd.args(args)
        .env_remove("MEMSTAB_INTERRUPT_AFTER_STEPS")
        .env("MEMSTAB_INTERRUPT_AFTER_ITERATIONS", k.to_string());
    cmd.output().expect("the binary runs")
}

/// A meridian's linear-buckling sweep stops at the sample after the signal: exit 130, the
/// samples so far written with stop reason `interrupted`, a manifest that verifies, and the
/// crossing it had no time to localise named in a warning.
#[test]
fn an_interrupt_in_a_meridian_buckling_sweep_exits_130() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("ponding");
    let o = run(&scene("axisymmetric/ponding.toml"), &out, Some(5));
    assert_interrupted(&o, &out);
    let rows = std::fs::read_to_string(out.join("path.csv"))
        .unwrap()
        .lines()
        .count();
    assert_eq!(rows, 1 + 6, "the header and samples 0..=5");
    assert_eq!(json(&out.join("path.json"))["stop"], "interrupted");
}

/// A start solve stops between its Newton iterations — the 3-D balloon's, and a meridian's
/// held-translation start (a sphere lowered onto its plane) —: exit 130, one line saying so,
/// nothing written (the directory this run made is removed again). `spectrum` and
/// `export-matrix`, which solve a start state too, exit 130 the same way.
#[test]
fn an_interrupt_in_a_start_solve_exits_130_with_nothing_written() {
    let dir = tempfile::tempdir().unwrap();
    for (name, k) in [
        ("balloon.toml", 1),
        ("axisymmetric/paper2_sphere_on_plane.toml", 2),
    ] {
        let out = dir.path().join(name.replace('/', "_"));
        let o = memstab_iterations(
            &[
                "run",
                &scene(name),
                "--out",
                out.to_str().unwrap(),
                "--quiet",
            ],
            k,
        );
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(130), "{name}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains("start solve"), "{err}");
        assert!(!out.exists(), "{name}: nothing written");
    }
    let o = memstab_iterations(&["spectrum", &scene("balloon.toml")], 1);
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    assert!(o.stdout.is_empty());
    let mtx = dir.path().join("K.mtx");
    let o = memstab_iterations(
        &[
            "export-matrix",
            &scene("balloon.toml"),
            "--out",
            mtx.to_str().unwrap(),
        ],
        1,
    );
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    assert!(!mtx.exists());
}

/// `compare` stops its runs under way at their next point and starts no other: exit 130, and
/// what it has — the runs so far, their stop `interrupted` — printed; or, stopped before every
/// mesh had a run, one line saying so.
#[test]
fn an_interrupt_in_compare_exits_130_with_the_runs_so_far() {
    for k in [3, 30] {
        let o = memstab(
            &[
                "compare",
                &scene("ponding.toml"),
                "--meshes",
                "C8v,C2v",
                "--divisions",
                "6",
                "--max",
                "10.5",
                "--json",
                "--quiet",
            ],
            Some(k),
        );
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(130), "{err}");
        assert!(err.contains("interrupted"), "{err}");
        if err.contains("nothing to compare") {
            assert!(o.stdout.is_empty());
            continue;
        }
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("one JSON object");
        let stops: Vec<&str> = v["meshes"]
            .as_array()
            .unwrap()
            .iter()
            .flat_map(|m| m["levels"].as_array().unwrap())
            .map(|l| l["stop"].as_str().unwrap())
            .collect();
        assert!(stops.contains(&"interrupted"), "k = {k}: {stops:?}");
    }
}

/// Exit 2, one line naming every one of `needles`, and nothing written into `out`.
fn assert_refused_up_front(o: &Output, out: &Path, needles: &[&str]) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    for n in needles {
        assert!(err.contains(n), "{err:?} does not name {n}");
    }
    assert!(!out.exists(), "nothing written: {}", out.display());
}

/// Refused before any work (exit 2, one line naming the key or option and its value, nothing
/// written): a mesh whose every node is fixed, a bound whose range overflows the arithmetic of
/// a sweep, a radius at which the mesh's elements are degenerate in floating point (3-D and
/// meridian), and an `--out` that cannot be written.
#[test]
fn hopeless_requests_are_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let with = |name: &str, text: String| {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        path.to_string_lossy().into_owned()
    };
    // Every node fixed: the bundled mesh-file scene on its disc with all nodes in `rim`.
    let disc = std::fs::read_to_string(scene("disc_file.toml")).unwrap();
    let spec = memstab::scene::Scene::load(Path::new(&scene("disc_file.toml"))).unwrap();
    let mut mesh = spec.build_mesh().unwrap().mesh;
    let all: Vec<usize> = (0..mesh.nodes.len()).collect();
    mesh.boundaries.insert("rim".into(), all);
    let msh = dir.path().join("all_fixed.msh");
    meshes::write::write_mesh(
        &msh,
        &mesh,
        &meshes::write::Fields::new(),
        meshes::write::Format::from_path(&msh, false).unwrap(),
    )
    .unwrap();
    assert!(disc.contains("path = \"meshes/disc_c7v.msh\""));
    let text = disc.replacen(
        "path = \"meshes/disc_c7v.msh\"",
        &format!("path = '{}'", msh.display()),
        1,
    );
    let s = with("all_fixed.toml", text);
    let o = run(&s, &out, None);
    assert_refused_up_front(&o, &out, &["boundary.fixed", "\"rim\"", "every one of the"]);

    // A bound whose range overflows: the sweep's samples were infinite.
    let ponding = std::fs::read_to_string(scene("ponding.toml")).unwrap();
    assert!(ponding.contains("max = 46.0"));
    let s = with(
        "max.toml",
        ponding.replacen("max = 46.0", "max = 1.7e308", 1),
    );
    let o = run(&s, &out, None);
    assert_refused_up_front(&o, &out, &["parameters.rho.max", "1.7e308"]);

    // A radius at which the elements are degenerate, on a 3-D mesh and on a meridian.
    for (name, radius) in [
        ("disc_upward.toml", "radius = 1.1"),
        ("axisymmetric/balloon.toml", "radius = 1.0"),
    ] {
        let text = std::fs::read_to_string(scene(name)).unwrap();
        assert!(text.contains(radius), "{name}");
        let s = with("radius.toml", text.replacen(radius, "radius = 1e100", 1));
        let o = run(&s, &out, None);
        assert_refused_up_front(&o, &out, &["mesh.radius", "1e100", "degenerate"]);
    }

    // An --out that cannot be written: refused before the analysis, not after it.
    let o = run(&scene("balloon.toml"), Path::new("/proc"), None);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--out '/proc'") && err.contains("cannot write"),
        "{err}"
    );
    #[cfg(unix)]
    if !is_root() {
        use std::os::unix::fs::PermissionsExt;
        let locked = dir.path().join("locked");
        std::fs::create_dir(&locked).unwrap();
        std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o555)).unwrap();
        let o = run(&scene("balloon.toml"), &locked, None);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(stderr(&o).contains("cannot write"), "{}", stderr(&o));
        assert_eq!(std::fs::read_dir(&locked).unwrap().count(), 0);
        std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
}

/// Whether this process runs as root (whom permission bits do not stop).
#[cfg(unix)]
fn is_root() -> bool {
    std::fs::read_to_string("/proc/self/status")
        .map(|s| {
            s.lines()
                .find(|l| l.starts_with("Uid:"))
                .and_then(|l| l.split_whitespace().nth(1).map(|u| u == "0"))
                .unwrap_or(false)
        })
        .unwrap_or(false)
}

/// A start solve that does not converge says which known cause fits and what to try: a fluid
/// level past the fold (no equilibrium near the start), a sphere whose plane it does not touch
/// yet (`[start] hold-translation`) — on the 3-D mesh and on the meridian —; a flat disc
/// without pre-stretch is refused on both models alike (exit 2, naming the key).
#[test]
fn non_convergence_names_its_cause() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let write = |name: &str, text: String| {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        path.to_string_lossy().into_owned()
    };
    let failed = |s: &str, needles: &[&str]| {
        let o = run(s, &out, None);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        for n in needles {
            assert!(err.contains(n), "{err:?} does not name {n}");
        }
        assert!(!err.contains(" … ("), "cut: {err}");
        assert!(!out.exists());
    };
    // The level far above the fold of the fluid-pushed disc.
    let below = std::fs::read_to_string(scene("disc_fluid_below.toml")).unwrap();
    assert!(below.contains("start = 0.0 ") && below.contains("max = 4.0"));
    let past =
        below
            .replacen("start = 0.0 ", "start = 6.0 ", 1)
            .replacen("max = 4.0", "max = 7.0", 1);
    failed(
        &write("past_fold.toml", past),
        &["no equilibrium near the start", "smaller load"],
    );
    // A sphere above its plane without the held translation: a plane it does not touch.
    for name in [
        "thesis/paper2_sphere_on_plane_f8.toml",
        "axisymmetric/paper2_sphere_on_plane.toml",
    ] {
        let text = std::fs::read_to_string(scene(name)).unwrap();
        let free: String = text
            .lines()
            .filter(|l| !l.starts_with("hold-translation"))
            .map(|l| format!("{l}\n"))
            .collect();
        assert_ne!(free, text, "{name}");
        failed(
            &write("untouched.toml", free),
            &["does not touch", "[start] hold-translation"],
        );
    }
    // Pre-stretch exactly 1 on a flat disc: refused up front on both models.
    for name in ["ponding.toml", "axisymmetric/ponding.toml"] {
        let text = std::fs::read_to_string(scene(name)).unwrap();
        assert!(text.contains("prestretch = 1.1"), "{name}");
        let s = write(
            "unstretched.toml",
            text.replacen("prestretch = 1.1", "prestretch = 1.0", 1),
        );
        let o = run(&s, &out, None);
        assert_refused_up_front(
            &o,
            &out,
            &["material.prestretch", "= 1 ", "pre-stretch > 1"],
        );
    }
}

/// A full file system, as a sink that fails part-way (every file above a size limit fails with
/// "File too large": the process's file-size limit, its signal ignored): the meridian
/// balloon's run writes its path and first states, then fails on a critical state; the
/// message (exit 1, one line) names the file that failed and every file it left — the
/// collections rewritten after each state included —, and no temporary file is left.
#[cfg(unix)]
#[test]
fn a_failing_sink_names_every_file_left() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("full");
    // 16000 blocks of 512 bytes: above a state of the 64-element meridian revolved (7.5 MB),
    // below a critical state with its mode (8.8 MB).
    let o = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "trap '' XFSZ; ulimit -f 16000 && exec '{}' run '{}' --out '{}' --quiet",
            env!("CARGO_BIN_EXE_memstab"),
            scene("axisymmetric/balloon.toml"),
            out.display()
        ))
        .env_remove("MEMSTAB_INTERRUPT_AFTER_STEPS")
        .output()
        .expect("sh runs");
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(
        err.contains("critical_01.vtu") && err.contains("already written: "),
        "{err}"
    );
    let named = err.split("already written: ").nth(1).unwrap().trim_end();
    let named: BTreeSet<String> = named.split(", ").map(str::to_string).collect();
    let left = files_under(&out);
    assert!(left.len() >= 4, "{left:?}");
    assert!(left.contains("path.pvd"), "{left:?}");
    assert_eq!(named, left, "the message names every file left");
    assert!(!out.join("manifest.json").exists());
}

/// `bench` stops at a signal — in the path of its first study, or before its next study —
/// with exit 130 and one line saying so.
#[test]
fn an_interrupt_in_bench_exits_130() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bench");
    let o = memstab(
        &["bench", "--quick", "--out", out.to_str().unwrap()],
        Some(5),
    );
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(130), "{err}");
    let last = err.trim_end().lines().last().unwrap_or_default();
    assert!(last.contains("a signal stopped the bench"), "{err}");
}

/// A balloon above a plane it does not touch has a singular tangent along the free
/// translation: whether its start is accepted at round-off (and then every step fails) or
/// Newton wanders off along that direction is decided by round-off in the assembly. Either
/// way the cause is named with what to try: a path that cannot leave its start is a result
/// whose summary says it; a start that did not converge is an error that writes nothing.
#[test]
fn a_path_stuck_at_its_start_names_the_cause() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(scene("balloon.toml")).unwrap();
    let at = text.find("\n[parameters").unwrap();
    let plane = "\n[[effect]]\ntype = \"plane\"\nnormal = [0.0, 0.0, 1.0]\noffset = -2.0\n\
                 penalty = 1000.0\nexponent = 3\n";
    let path = dir.path().join("plane.toml");
    std::fs::write(&path, format!("{}{plane}{}", &text[..at], &text[at..])).unwrap();
    let out = dir.path().join("out");
    let o = run(path.to_str().unwrap(), &out, None);
    let line = if o.status.success() {
        let summary = String::from_utf8_lossy(&o.stdout).into_owned();
        summary
            .lines()
            .find(|l| l.contains("could not leave its start"))
            .unwrap_or_else(|| panic!("{summary}"))
            .to_string()
    } else {
        let err = stderr(&o);
        assert!(
            err.contains("the start state did not converge") && err.contains("nothing was written"),
            "{err}"
        );
        assert!(
            !out.exists() || files_under(&out).is_empty(),
            "a failed start wrote {:?}",
            files_under(&out)
        );
        err
    };
    assert!(
        line.contains("does not touch yet") && line.contains("[start] hold-translation"),
        "{line}"
    );
}

/// A path stuck at a start that converged in the strict sense (no motion left free) is not
/// blamed on a free body: with one Newton iteration per step the balloon cannot leave its
/// start, and the hint names the corrector's budget.
#[test]
fn a_path_stuck_at_a_regular_start_names_the_budget_not_a_free_body() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(scene("demo.toml"))
        .unwrap()
        .replace(
            "[analysis]",
            "[analysis]\nmax-iterations = 1\nmin-step = 0.01",
        );
    let path = dir.path().join("budget.toml");
    std::fs::write(&path, text).unwrap();
    let out = dir.path().join("out");
    let o = run(path.to_str().unwrap(), &out, None);
    assert!(o.status.success(), "{}", stderr(&o));
    let summary = String::from_utf8_lossy(&o.stdout);
    let line = summary
        .lines()
        .find(|l| l.contains("could not leave its start"))
        .unwrap_or_else(|| panic!("{summary}"));
    assert!(line.contains("`max-iterations` = 1"), "{line}");
    assert!(!line.contains("free body"), "{line}");
}

/// `memstab CMD ARGS` with the test hook `var` at `k`, the others removed, and the blocks of a
/// spectrum analysed one at a time (so that the blocks after the k-th have not started).
fn memstab_hook(args: &[&str], var: &str, k: usize) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_memstab"));
    cmd.args(args);
    for v in [
        "MEMSTAB_INTERRUPT_AFTER_STEPS",
        "MEMSTAB_INTERRUPT_AFTER_ITERATIONS",
        "MEMSTAB_INTERRUPT_AFTER_BLOCKS",
    ] {
        cmd.env_remove(v);
    }
    cmd.env(var, k.to_string()).env("RAYON_NUM_THREADS", "1");
    cmd.output().expect("the binary runs")
}

/// A signal while `spectrum` analyses its blocks (the balloon's 10 irreps of Ih) stops it
/// before the next block: exit 130, one line saying so, no part of the spectrum printed (with
/// or without `--json`). A signal after `export-matrix`'s solve, before its write: exit 130,
/// no file.
#[test]
fn an_interrupt_between_spectrum_blocks_exits_130_with_nothing_printed() {
    let balloon = scene("balloon.toml");
    for json in [false, true] {
        let mut args = vec!["spectrum", balloon.as_str()];
        if json {
            args.push("--json");
        }
        for k in [1, 4] {
            let o = memstab_hook(&args, "MEMSTAB_INTERRUPT_AFTER_BLOCKS", k);
            let err = stderr(&o);
            assert_eq!(o.status.code(), Some(130), "{err}");
            assert_eq!(err.trim_end().lines().count(), 1, "{err}");
            assert!(err.contains("between the tangent's 10 blocks"), "{err}");
            assert!(
                o.stdout.is_empty(),
                "{}",
                String::from_utf8_lossy(&o.stdout)
            );
        }
    }
    // Past the last block the hook never fires: the whole spectrum.
    let o = memstab_hook(
        &["spectrum", &balloon, "--json"],
        "MEMSTAB_INTERRUPT_AFTER_BLOCKS",
        11,
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let spectrum: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(spectrum["irreps"].as_array().unwrap().len(), 10);
    // export-matrix: the signal right after the start solve's last iteration.
    let n = spectrum["iterations"].as_u64().unwrap() as usize;
    let dir = tempfile::tempdir().unwrap();
    let mtx = dir.path().join("K.mtx");
    let args = ["export-matrix", &balloon, "--out", mtx.to_str().unwrap()];
    let o = memstab_hook(&args, "MEMSTAB_INTERRUPT_AFTER_ITERATIONS", n);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("nothing was written"), "{err}");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

/// A path that stalls after some points says which known cause fits its last failure and what
/// to try, in one line of the summary and in path.json: the corrector's budget of two
/// iterations (the demo with `max-iterations = 2`, which stalls after point 2).
#[test]
fn a_path_that_stalls_names_the_cause() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(scene("demo.toml")).unwrap();
    assert_eq!(text.matches("\nstop-stretch = 4.0").count(), 1);
    let path = dir.path().join("short.toml");
    std::fs::write(
        &path,
        text.replacen(
            "\nstop-stretch = 4.0",
            "\nstop-stretch = 4.0\nmax-iterations = 2\nmin-step = 0.015",
            1,
        ),
    )
    .unwrap();
    let out = dir.path().join("out");
    let o = run(path.to_str().unwrap(), &out, None);
    assert!(o.status.success(), "{}", stderr(&o));
    let summary = String::from_utf8_lossy(&o.stdout);
    assert!(summary.contains("stopped: step cut below"), "{summary}");
    let hints: Vec<&str> = summary
        .lines()
        .filter(|l| l.contains("likely cause"))
        .collect();
    assert_eq!(hints.len(), 1, "{summary}");
    let line = hints[0];
    assert!(
        line.starts_with("warning: the path stopped after point "),
        "{line}"
    );
    assert!(
        line.contains("`max-iterations` = 2") && line.contains("smaller `max-step`"),
        "{line}"
    );
    let report = json(&out.join("path.json"));
    let warnings = report["warnings"].to_string();
    assert!(warnings.contains("`max-iterations` = 2"), "{warnings}");
}

/// Each kind of failed step has its own cause and remedy: the branch-jump guard a smaller
/// `max-step`, a corrector that does not converge beside a plane the cubic penalty, a singular
/// system or an inadmissible state a bound on the control.
#[test]
fn each_kind_of_stall_has_its_hint() {
    use memstab::results::{Stalled, StepFailure};
    let text = std::fs::read_to_string(scene("demo.toml")).unwrap();
    let plain = memstab::scene::Scene::from_toml_str(&text, "demo").unwrap();
    let at = text.find("\n[parameters").unwrap();
    let plane = "\n[[effect]]\ntype = \"plane\"\nnormal = [0.0, 0.0, 1.0]\noffset = -2.0\n\
                 penalty = 1000.0\nexponent = 1\n";
    let with_plane = format!("{}{plane}{}", &text[..at], &text[at..]);
    let contact = memstab::scene::Scene::from_toml_str(&with_plane, "plane").unwrap();
    let opts = memstab::continuation::PathOptions {
        max_step: 0.25,
        max_iterations: 12,
        ..Default::default()
    };
    let hint = |scene: &memstab::scene::Scene, kind: StepFailure| {
        let stalled = Stalled {
            min_step: 1e-6,
            after: 7,
            control: 0.5,
            why: "the last failure".into(),
            kind,
        };
        let line = memstab::study::stall_hint(scene, &stalled, "p", &opts);
        assert!(!line.contains('\n'), "{line}");
        assert!(
            line.starts_with("the path stopped after point 7 (p = 0.5): likely cause: "),
            "{line}"
        );
        line
    };
    let jump = hint(&plain, StepFailure::BranchJump);
    assert!(jump.contains("sharp turn") && jump.contains("`max-step` in [analysis] (now 0.25)"));
    let stuck = hint(&plain, StepFailure::NotConverged);
    assert!(stuck.contains("`max-iterations` = 12"), "{stuck}");
    let touching = hint(&contact, StepFailure::NotConverged);
    assert!(
        touching.contains("contact change") && touching.contains("`exponent = 3`"),
        "{touching}"
    );
    for kind in [
        StepFailure::Singular,
        StepFailure::Degenerate,
        StepFailure::Model,
    ] {
        let line = hint(&plain, kind);
        assert!(line.contains("`[parameters.p] min`/`max`"), "{line}");
    }
}

/// Twenty runs of the demo started at once into one directory: each either completes or is
/// refused up front with the lock's message (exit 2, one line); nothing else. The directory's
/// manifest verifies, and no lock is left.
#[test]
fn twenty_concurrent_runs_into_one_directory_complete_or_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let demo = scene("demo.toml");
    let children: Vec<std::process::Child> = (0..20)
        .map(|_| {
            Command::new(env!("CARGO_BIN_EXE_memstab"))
                .args(["run", &demo, "--out", out.to_str().unwrap(), "--quiet"])
                .env_remove("MEMSTAB_INTERRUPT_AFTER_STEPS")
                .env_remove("MEMSTAB_INTERRUPT_AFTER_ITERATIONS")
                .env_remove("MEMSTAB_INTERRUPT_AFTER_BLOCKS")
                .stdout(std::process::Stdio::null())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    let mut completed = 0;
    for child in children {
        let o = child.wait_with_output().unwrap();
        let err = stderr(&o);
        match o.status.code() {
            Some(0) => completed += 1,
            Some(2) => {
                assert_eq!(err.trim_end().lines().count(), 1, "{err}");
                assert!(err.contains("in use by another memstab run"), "{err}");
            }
            c => panic!("exit {c:?}: {err}"),
        }
    }
    assert!(completed >= 1, "no run completed");
    assert_eq!(assert_manifest_verifies(&out), "the stretch reached 4");
    assert!(!out.join(memstab::output::LOCK).exists());
}

/// A branch that cannot leave its point gets one line naming the cause and what to try, in the
/// branches' own keys; one that stalls later gets the path's line for the kind of its
/// failure, about the branch. (The upward disc's A2 point at h = 4.14106 on a C1v branch,
/// whose C1 branch used to stall at its first step, is no bifurcation and is not switched at:
/// `diagram::a_zero_eigenvalue_that_does_not_cross_is_no_bifurcation`.)
#[test]
fn a_stalled_branch_names_the_cause() {
    use memstab::results::{Stalled, StepFailure};
    let text = std::fs::read_to_string(scene("disc_upward.toml")).unwrap();
    let scene = memstab::scene::Scene::from_toml_str(&text, "disc").unwrap();
    let opts = memstab::continuation::PathOptions::default();
    let stalled = |after: usize, kind: StepFailure| Stalled {
        min_step: 1e-6,
        after,
        control: 4.141061160117826,
        why: "the corrector did not converge in 25 iterations".into(),
        kind,
    };
    let first = memstab::study::branch_stall_hint(
        &scene,
        &stalled(0, StepFailure::NotConverged),
        "h",
        &opts,
    );
    assert!(
        first.contains("the branch could not leave its critical point (h = 4.141061160117826")
            && first.contains("likely cause")
            && first.contains("[analysis.branches]")
            && first.contains("the corrector did not converge"),
        "{first}"
    );
    let later = memstab::study::branch_stall_hint(
        &scene,
        &stalled(13, StepFailure::BranchJump),
        "h",
        &opts,
    );
    assert!(
        later.contains("the branch stopped")
            && !later.contains("the path stopped")
            && later.contains("likely cause"),
        "{later}"
    );
}
