//! `memstab run` and `memstab demo` end to end: every output file written and consistent,
//! the JSON summary, and bad input (one line naming the key or value, exit code 2, the output
//! directory not created).

use memstab::reference::{L_MAX, P_MAX};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn memstab_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_memstab"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("the memstab binary runs")
}

fn memstab(args: &[&str]) -> Output {
    memstab_in(Path::new(env!("CARGO_MANIFEST_DIR")), args)
}

fn scene(name: &str) -> String {
    format!("{}/scenes/{name}", env!("CARGO_MANIFEST_DIR"))
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

/// Checks every output file in `dir` and returns the number of path points.
fn check_outputs(dir: &Path) -> usize {
    let csv = std::fs::read_to_string(dir.join("path.csv")).expect("path.csv");
    let json: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("path.json")).expect("path.json"))
            .expect("path.json parses");
    let rows = json["rows"].as_array().expect("rows").len();
    assert!(rows >= 2, "a path of {rows} points");
    // One line per point plus the header; no NaN or infinity anywhere.
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), rows + 1, "path.csv lines");
    assert!(lines[0].starts_with("step,arclength,"), "{}", lines[0]);
    let columns = lines[0].split(',').count();
    // The last column names each row's flags; every other is a number.
    assert!(lines[0].ends_with(",flags"), "{}", lines[0]);
    for line in &lines[1..] {
        assert_eq!(line.split(',').count(), columns, "row {line}");
        let cells: Vec<&str> = line.split(',').collect();
        for cell in &cells[..columns - 1] {
            let v: f64 = cell.parse().unwrap_or_else(|_| panic!("cell {cell:?}"));
            assert!(v.is_finite(), "non-finite cell {cell:?} in {line}");
        }
        let flags = cells[columns - 1];
        assert!(
            flags.is_empty()
                || flags
                    .split(';')
                    .all(|f| ["wrinkled", "stretch"].contains(&f)),
            "flags {flags:?} in {line}"
        );
    }
    assert!(!csv.to_lowercase().contains("nan"), "NaN in path.csv");
    assert!(!csv.to_lowercase().contains("inf"), "inf in path.csv");
    let svg = std::fs::read_to_string(dir.join("path.svg")).expect("path.svg");
    assert!(svg.contains("<svg"), "path.svg is no SVG");
    // The PVD lists the VTUs, which exist, and path.json's `saved` lists the same files.
    let pvd = std::fs::read_to_string(dir.join("path.pvd")).expect("path.pvd");
    let listed: Vec<&str> = pvd
        .split("file=\"")
        .skip(1)
        .map(|s| s.split('"').next().unwrap())
        .collect();
    assert!(!listed.is_empty(), "path.pvd lists no state");
    for f in &listed {
        assert!(f.ends_with(".vtu"), "{f}");
        let vtu = std::fs::read_to_string(dir.join(f)).unwrap_or_else(|_| panic!("{f} exists"));
        assert!(vtu.contains("<VTKFile"), "{f}");
    }
    // `saved` lists the collection's states and, beside them, the turning and critical
    // points (each with its label); every one exists.
    let saved = json["saved"].as_array().expect("saved");
    let in_collection: Vec<&str> = saved
        .iter()
        .filter(|s| s["in_collection"].as_bool().unwrap())
        .map(|s| s["file"].as_str().unwrap())
        .collect();
    assert_eq!(in_collection, listed);
    for s in saved {
        let f = s["file"].as_str().unwrap();
        assert!(dir.join(f).is_file(), "{f} listed but missing");
        assert!(!s["label"].as_str().unwrap().is_empty());
    }
    // critical.json lists the critical points: for the balloon, limit points in Ag.
    let critical: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("critical.json")).expect("critical.json"),
    )
    .unwrap();
    for c in critical.as_array().expect("a list") {
        assert_eq!(c["kind"], "limit point");
        assert_eq!(c["irrep"], "Ag");
        assert_eq!(c["multiplicity"], 1);
        assert!(c["parameters"]["p"].as_f64().unwrap() > 1.0);
        assert!(c["step"].as_u64().is_some());
    }
    // No temporary files are left behind.
    for entry in std::fs::read_dir(dir).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        assert!(!name.ends_with(".tmp"), "left over: {name}");
    }
    rows
}

#[test]
fn run_writes_every_output() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("out");
    let out = memstab(&[
        "run",
        &scene("demo.toml"),
        "--out",
        dir.to_str().unwrap(),
        "--quiet",
    ]);
    assert_success(&out, "memstab run");
    assert!(out.stderr.is_empty(), "stderr: {}", text(&out.stderr));
    let rows = check_outputs(&dir);
    let stdout = text(&out.stdout);
    for needle in [
        "path.csv",
        "path.json",
        "path.svg",
        "path.pvd",
        "state_0000.vtu",
        "group Ih",
        "symmetric unknowns of",
        "maximum p = ",
        "minimum p = ",
        "stopped: the stretch reached 4",
        &format!("path: {rows} points"),
    ] {
        assert!(stdout.contains(needle), "'{needle}' not in:\n{stdout}");
    }
    // Running again into the existing directory replaces the files.
    let again = memstab(&[
        "run",
        &scene("demo.toml"),
        "--out",
        dir.to_str().unwrap(),
        "--quiet",
    ]);
    assert_success(&again, "memstab run again");
    assert_eq!(check_outputs(&dir), rows);
}

#[test]
fn run_json_lists_the_files() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("json");
    let out = memstab(&[
        "run",
        &scene("demo.toml"),
        "--out",
        dir.to_str().unwrap(),
        "--quiet",
        "--json",
    ]);
    assert_success(&out, "memstab run --json");
    let v: Value = serde_json::from_slice(&out.stdout).expect("stdout is one JSON object");
    assert_eq!(v["out"], dir.to_str().unwrap());
    assert_eq!(v["group"], "Ih");
    assert_eq!(v["control"], "p");
    let points = v["points"].as_u64().unwrap() as usize;
    assert_eq!(points, check_outputs(&dir));
    let files: Vec<PathBuf> = v["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| PathBuf::from(f.as_str().unwrap()))
        .collect();
    for name in [
        "path.csv",
        "path.json",
        "path.svg",
        "path.pvd",
        "state_0000.vtu",
    ] {
        assert!(files.contains(&dir.join(name)), "{name} not in {files:?}");
    }
    for f in &files {
        assert!(f.is_file(), "{} listed but missing", f.display());
    }
    let written = std::fs::read_dir(&dir).unwrap().count();
    assert_eq!(files.len(), written, "every file in DIR is listed");
    let turning = v["turning_points"].as_array().unwrap();
    let kinds: Vec<&str> = turning
        .iter()
        .map(|t| t["kind"].as_str().unwrap())
        .collect();
    assert_eq!(kinds, ["maximum", "minimum"]);
    let max = &turning[0];
    assert!(
        max["step"].as_u64().is_some() && max.get("after_step").is_none(),
        "{max}"
    );
    assert!(
        (max["value"].as_f64().unwrap() / P_MAX - 1.0).abs() < 0.03,
        "{max}"
    );
    assert!(
        (max["stretch"].as_f64().unwrap() - L_MAX).abs() < 0.01,
        "{max}"
    );
    assert!(v["stop"].as_str().unwrap().contains("stretch"), "{v}");
    assert!(v["symmetric_unknowns"].as_u64().unwrap() < v["unknowns"].as_u64().unwrap());
}

#[test]
fn demo_runs_the_bundled_scene_and_compares_with_the_closed_form() {
    let tmp = tempfile::tempdir().unwrap();
    let out = memstab(&[
        "demo",
        "--out",
        tmp.path().join("demo").to_str().unwrap(),
        "--quiet",
    ]);
    assert_success(&out, "memstab demo");
    check_outputs(&tmp.path().join("demo"));
    let stdout = text(&out.stdout);
    for needle in [
        "scenes/demo.toml (bundled)",
        "closed form",
        "its maximum 1.3551069 at l = 1.47606",
        "its minimum 1.1487477 at l = 3.1426213",
        "difference",
        "path.svg",
    ] {
        assert!(stdout.contains(needle), "'{needle}' not in:\n{stdout}");
    }
}

#[test]
fn demo_writes_into_memstab_demo_by_default() {
    // Run from a directory without the sources: the scene is in the binary.
    let tmp = tempfile::tempdir().unwrap();
    let out = memstab_in(tmp.path(), &["demo", "--quiet"]);
    assert_success(&out, "memstab demo");
    check_outputs(&tmp.path().join("memstab-demo"));
}

/// Bad input: exit code 2, one line on stderr naming `needles`, `dir` not created.
fn assert_rejected(args: &[&str], needles: &[&str], dir: &Path) {
    let out = memstab(args);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "memstab {args:?}: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "not one line: {err}");
    for needle in needles {
        assert!(err.contains(needle), "'{needle}' not in: {err}");
    }
    assert!(out.stdout.is_empty(), "stdout: {}", text(&out.stdout));
    assert!(!dir.exists(), "{} was created", dir.display());
}

/// The demo scene with the line starting with `from` changed to start with `to` (`from` must
/// begin exactly one line).
fn variant(dir: &Path, name: &str, from: &str, to: &str) -> String {
    let text = std::fs::read_to_string(scene("demo.toml")).unwrap();
    let from = format!("\n{from}");
    assert_eq!(text.matches(&from).count(), 1, "{from:?} in the demo scene");
    let path = dir.join(name);
    std::fs::write(&path, text.replacen(&from, &format!("\n{to}"), 1)).unwrap();
    path.to_str().unwrap().to_string()
}

#[test]
fn bad_scenes_are_rejected_without_writing() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("never");
    let out = dir.to_str().unwrap();
    let unknown = variant(
        tmp.path(),
        "unknown.toml",
        "k = 0.1",
        "k = 0.1\nstiffness = 3",
    );
    assert_rejected(
        &["run", &unknown, "--out", out, "--quiet"],
        &["unknown.toml", "material.stiffness"],
        &dir,
    );
    let thickness = variant(
        tmp.path(),
        "thin.toml",
        "thickness = 0.01",
        "thickness = -0.01",
    );
    assert_rejected(
        &["run", &thickness, "--out", out],
        &["material.thickness", "-0.01"],
        &dir,
    );
    let mu = variant(tmp.path(), "mu.toml", "mu = 100.0", "mu = 0.0");
    assert_rejected(
        &["run", &mu, "--out", out, "--json"],
        &["material.mu", "0"],
        &dir,
    );
    let syntax = variant(tmp.path(), "syntax.toml", "mu = 100.0", "mu = = 100.0");
    assert_rejected(
        &["run", &syntax, "--out", out, "--quiet"],
        &["syntax.toml:", "syntax error", "mu = = 100.0"],
        &dir,
    );
    let typo = variant(tmp.path(), "type.toml", "mu = 100.0", "mu = \"hard\"");
    assert_rejected(
        &["run", &typo, "--out", out],
        &["material.mu", "hard"],
        &dir,
    );
    let missing = tmp.path().join("missing.toml");
    assert_rejected(
        &["run", missing.to_str().unwrap(), "--out", out, "--quiet"],
        &["missing.toml", "cannot read"],
        &dir,
    );
}

#[test]
fn out_under_a_missing_parent_is_rejected() {
    let tmp = tempfile::tempdir().unwrap();
    let parent = tmp.path().join("no-such-dir");
    let dir = parent.join("out");
    assert_rejected(
        &[
            "run",
            &scene("demo.toml"),
            "--out",
            dir.to_str().unwrap(),
            "--quiet",
        ],
        &["no-such-dir", "does not exist"],
        &dir,
    );
    assert!(!parent.exists());
    assert_rejected(
        &["demo", "--out", dir.to_str().unwrap(), "--quiet"],
        &["no-such-dir", "does not exist"],
        &dir,
    );
    // An existing file is not a directory.
    let file = tmp.path().join("a-file");
    std::fs::write(&file, "x").unwrap();
    let out = memstab(&["run", &scene("demo.toml"), "--out", file.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    assert!(text(&out.stderr).contains("not a directory"));
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "x");
}

#[test]
fn a_start_that_does_not_converge_fails_and_leaves_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("failed");
    // A fluid level far above the fold: no equilibrium near the flat start for Newton to
    // reach.
    let slack_scene = std::fs::read_to_string(scene("disc_fluid_below.toml"))
        .unwrap()
        .replacen(
            "[parameters.h]\nstart = 0.0 ",
            "[parameters.h]\nstart = 6.0 ",
            1,
        )
        .replacen("max = 4.0", "max = 7.0", 1);
    let slack = tmp.path().join("slack.toml");
    std::fs::write(&slack, slack_scene).unwrap();
    let out = memstab(&[
        "run",
        slack.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
        "--quiet",
    ]);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "not one line: {err}");
    assert!(err.contains("did not converge"), "{err}");
    assert!(err.contains("nothing was written"), "{err}");
    assert!(!dir.exists(), "{} left behind", dir.display());
}

#[test]
fn a_path_that_stops_early_still_writes_its_outputs() {
    // One Newton iteration per step and a large minimum step: the step is cut below the
    // minimum after a few points, which is a result, not a failure.
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("early");
    let short = variant(
        tmp.path(),
        "short.toml",
        "stop-stretch = 4.0",
        "stop-stretch = 4.0\nmax-iterations = 1\nmin-step = 0.015",
    );
    let out = memstab(&["run", &short, "--out", dir.to_str().unwrap(), "--quiet"]);
    assert_success(&out, "memstab run (stops early)");
    let stdout = text(&out.stdout);
    assert!(stdout.contains("stopped: step cut below"), "{stdout}");
    for name in ["path.csv", "path.json", "path.svg", "path.pvd"] {
        assert!(dir.join(name).is_file(), "{name}");
    }
}
