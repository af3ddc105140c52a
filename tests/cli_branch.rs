//! Branches on the command line: `memstab run` of a scene with `[analysis.branches]` writes
//! `branches.json`, one directory per branch and `diagram.svg`; `memstab branch RUN_DIR
//! --critical N` switches at a finished run's point; bad input is one line and exit code 2.

use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output};

fn memstab(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_memstab"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("the memstab binary runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn assert_success(out: &Output, what: &str) {
    assert!(
        out.status.success(),
        "{what} failed ({:?}): {}{}",
        out.status.code(),
        text(&out.stdout),
        text(&out.stderr)
    );
}

/// The bundled upward-loaded disc on a coarse mesh (6 divisions), short branches, with
/// `[analysis.branches]` replaced by `branches` (nothing for none).
fn coarse_scene(dir: &Path, branches: &str) -> String {
    let text = std::fs::read_to_string(format!(
        "{}/scenes/disc_upward.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let cut = text.find("\n[analysis.branches]").expect("branches");
    let text = format!("{}\n{branches}", &text[..cut]).replace("divisions = 16 ", "divisions = 6 ");
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    path.to_string_lossy().into_owned()
}

fn json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap_or_else(|_| panic!("{path:?}")))
        .unwrap_or_else(|e| panic!("{path:?}: {e}"))
}

/// `memstab run` with `[analysis.branches] depth = 1`: the path's one critical point, the E1
/// double point, gets the number of branches the lemma gives — one axial class (C1v) times
/// two non-conjugate halves — each in its own directory with the usual path files, listed in
/// branches.json with its irrep, isotropy, half and points; diagram.svg draws them.
#[test]
fn run_with_branches_writes_the_graph_the_directories_and_the_diagram() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = coarse_scene(tmp.path(), "[analysis.branches]\ndepth = 1\nsteps = 8\n");
    let dir = tmp.path().join("out");
    let json_out = memstab(&[
        "run",
        &scene,
        "--out",
        dir.to_str().unwrap(),
        "--quiet",
        "--json",
    ]);
    assert_success(&json_out, "memstab run --json");
    let summary: Value = serde_json::from_str(text(&json_out.stdout).trim()).expect("JSON");
    assert_eq!(summary["branches"], 2);
    let out = memstab(&["run", &scene, "--out", dir.to_str().unwrap(), "--quiet"]);
    assert_success(&out, "memstab run");
    let stdout = text(&out.stdout);
    for needle in [
        "branches (depth 1): 2",
        "path #1 double bifurcation in E1: 2 branches",
        "branch_01 C1v+",
        "branch_02 C1v-",
        "branches.json",
        "diagram.svg",
    ] {
        assert!(stdout.contains(needle), "'{needle}' not in:\n{stdout}");
    }
    let graph = json(&dir.join("branches.json"));
    assert_eq!(graph["group"], "C7v");
    assert_eq!(graph["control"], "h");
    let branches = graph["branches"].as_array().expect("branches");
    assert_eq!(
        branches.len(),
        2,
        "one class times two halves, no symmetric copy"
    );
    let nodes = graph["nodes"].as_array().expect("nodes");
    let from = &nodes[branches[0]["from"].as_u64().unwrap() as usize];
    assert_eq!(from["type"], "critical");
    assert_eq!(from["on"], "path");
    assert_eq!(from["irrep"], "E1");
    let mut halves = Vec::new();
    for b in branches {
        assert_eq!(b["irrep"], "E1");
        assert_eq!(b["isotropy"], "C1v");
        assert_eq!(b["isotropy_order"], 2);
        assert_eq!(b["halves"], "distinct");
        assert_eq!(b["bifurcation"], "pitchfork");
        assert_eq!(b["isotropy_of_states"], "C1v");
        assert_eq!(b["isotropy_exact"], true);
        assert_eq!(b["points"], 9);
        assert_eq!(b["on"], "path");
        halves.push(b["half"].as_str().unwrap().to_string());
        let end = &nodes[b["to"].as_u64().unwrap() as usize];
        assert_eq!(end["type"], "end");
        assert_eq!(end["branch"], b["id"]);
        // The branch's directory holds the usual files; its rows are its points.
        let sub = dir.join(b["directory"].as_str().unwrap());
        let report = json(&sub.join("path.json"));
        assert_eq!(report["group"], "C1v");
        assert_eq!(report["rows"].as_array().unwrap().len(), 9);
        assert!(report["measures"]
            .as_array()
            .unwrap()
            .iter()
            .any(|m| m == "asymmetry"));
        let csv = std::fs::read_to_string(sub.join("path.csv")).unwrap();
        assert_eq!(csv.lines().count(), 10);
        assert!(csv.lines().next().unwrap().contains(",asymmetry,"));
        for f in ["critical.json", "path.svg", "path.pvd", "state_0000.vtu"] {
            assert!(sub.join(f).is_file(), "{f} in {}", sub.display());
        }
        assert!(b["stability"].as_array().is_some_and(|s| !s.is_empty()));
    }
    halves.sort();
    assert_eq!(halves, ["+", "-"]);
    crate::common::figures::check_svg(&dir.join("diagram.svg"));
    let svg = std::fs::read_to_string(dir.join("diagram.svg")).unwrap();
    for needle in [
        "path (C7v)",
        "C1v",
        "double E1",
        "stable: solid",
        "unstable: dashed",
    ] {
        assert!(svg.contains(needle), "'{needle}' not in diagram.svg");
    }
    // Then from the finished run: the same point, into another directory.
    let again = tmp.path().join("again");
    std::fs::create_dir(&again).unwrap();
    let out = memstab(&[
        "branch",
        dir.to_str().unwrap(),
        "--critical",
        "1",
        "--steps",
        "8",
        "--out",
        again.to_str().unwrap(),
        "--json",
    ]);
    assert_success(&out, "memstab branch");
    let summary: Value = serde_json::from_str(text(&out.stdout).trim()).expect("one JSON object");
    assert_eq!(summary["count"], 2);
    let reopened = json(&again.join("branches.json"));
    let rb = reopened["branches"].as_array().unwrap();
    assert_eq!(rb.len(), 2);
    // The same branches: the control at their last points agrees with the run's.
    for (a, b) in branches.iter().zip(rb) {
        assert_eq!(a["half"], b["half"]);
        let (x, y) = (
            a["end"]["h"].as_f64().unwrap(),
            b["end"]["h"].as_f64().unwrap(),
        );
        assert!((x - y).abs() < 1e-6 * x.abs(), "{x} vs {y}");
    }
}

/// A scene without `[analysis.branches]` writes no branch output.
#[test]
fn run_without_branches_writes_none() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = coarse_scene(tmp.path(), "");
    let dir = tmp.path().join("out");
    let out = memstab(&["run", &scene, "--out", dir.to_str().unwrap(), "--quiet"]);
    assert_success(&out, "memstab run");
    assert!(!dir.join("branches.json").exists());
    assert!(!dir.join("diagram.svg").exists());
    assert!(!dir.join("branch_01").exists());
    assert!(!text(&out.stdout).contains("branches ("));
    let out = memstab(&[
        "run",
        &scene,
        "--out",
        dir.to_str().unwrap(),
        "--quiet",
        "--json",
    ]);
    let summary: Value = serde_json::from_str(text(&out.stdout).trim()).expect("JSON");
    assert!(summary.get("branches").is_none(), "{summary}");
}

/// Bad `[analysis.branches]` values and bad `memstab branch` arguments: one line naming the
/// key or value, exit code 2, nothing written.
#[test]
fn bad_branch_input_is_exit_code_2() {
    let tmp = tempfile::tempdir().unwrap();
    for (branches, needle) in [
        (
            "[analysis.branches]\ndepth = 0\n",
            "'analysis.branches.depth' must lie within [1, 3], got 0",
        ),
        (
            "[analysis.branches]\ndepth = 4\n",
            "analysis.branches.depth",
        ),
        (
            "[analysis.branches]\nsteps = 0\n",
            "'analysis.branches.steps' must be >= 1, got 0",
        ),
        (
            "[analysis.branches]\nmax-step = -1.0\n",
            "'analysis.branches.max-step' must be > 0, got -1",
        ),
        (
            "[analysis.branches]\npoints = [1, 1]\n",
            "'analysis.branches.points[1]' = 1 is listed twice",
        ),
        (
            "[analysis.branches]\npoints = [0]\n",
            "analysis.branches.points[0]",
        ),
        ("[analysis.branches]\ndepht = 1\n", "depht"),
    ] {
        let scene = coarse_scene(tmp.path(), branches);
        let dir = tmp.path().join("never");
        let out = memstab(&["run", &scene, "--out", dir.to_str().unwrap(), "--quiet"]);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{branches}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(err.contains(needle), "'{needle}' not in {err}");
        assert!(!dir.exists());
    }
    // memstab branch: no run, a point out of range, a bad depth.
    let scene = coarse_scene(tmp.path(), "");
    let run = tmp.path().join("run");
    assert_success(
        &memstab(&["run", &scene, "--out", run.to_str().unwrap(), "--quiet"]),
        "memstab run",
    );
    let empty = tmp.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let run_dir = run.to_str().unwrap();
    for (args, needle) in [
        (
            vec!["branch", empty.to_str().unwrap(), "--critical", "1"],
            "path.json",
        ),
        (
            vec!["branch", run_dir, "--critical", "2"],
            "--critical 2: the run in",
        ),
        (vec!["branch", run_dir, "--critical", "0"], "--critical 0"),
        (
            vec!["branch", run_dir, "--critical", "1", "--depth", "9"],
            "--depth 9",
        ),
        (
            vec!["branch", run_dir, "--critical", "1", "--steps", "0"],
            "--steps 0",
        ),
        (
            vec!["branch", run_dir, "--critical", "1", "--max-step", "0"],
            "--max-step 0",
        ),
    ] {
        let out = memstab(&args);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(err.contains(needle), "'{needle}' not in {err}");
    }
    assert!(!run.join("branches.json").exists(), "nothing written");
    // A held state's critical points are not points of a path.
    let ponding = std::fs::read_to_string(format!(
        "{}/scenes/ponding.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
    .replace("divisions = 16 ", "divisions = 4 ")
    .replace("max = 46.0 ", "max = 8.0 ")
    .replace("samples = 92", "samples = 16");
    let held = tmp.path().join("ponding.toml");
    std::fs::write(&held, ponding).unwrap();
    let held_run = tmp.path().join("held");
    assert_success(
        &memstab(&[
            "run",
            held.to_str().unwrap(),
            "--out",
            held_run.to_str().unwrap(),
            "--quiet",
        ]),
        "memstab run (linear buckling)",
    );
    let out = memstab(&["branch", held_run.to_str().unwrap(), "--critical", "1"]);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("linear-buckling analysis"), "{err}");
    assert!(!held_run.join("branches.json").exists());
    // A scene that is not the run's.
    let other = tmp.path().join("other.toml");
    std::fs::write(
        &other,
        std::fs::read_to_string(&scene)
            .unwrap()
            .replace("divisions = 6 ", "divisions = 4 "),
    )
    .unwrap();
    let out = memstab(&[
        "branch",
        run_dir,
        "--critical",
        "1",
        "--scene",
        other.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    assert!(
        text(&out.stderr).contains("the number of unknowns"),
        "{}",
        text(&out.stderr)
    );
}
