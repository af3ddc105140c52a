//! Validity flags end to end (docs/theory.md §8.10): a taut balloon's critical points are all
//! valid; Paper 3's gas-and-fluid cap pressed by its gas wrinkles before it loses stability,
//! and every critical point it finds is listed apart, flagged wrinkled, in the summary,
//! `critical.json` and `run --json`.

use std::process::Command;

fn run(scene: &str, dir: &std::path::Path, json: bool) -> (String, std::path::PathBuf) {
    let out = dir.join("out");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_memstab"));
    cmd.args(["run", scene, "--out"]).arg(&out).arg("--quiet");
    if json {
        cmd.arg("--json");
    }
    let o = cmd.output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    (String::from_utf8_lossy(&o.stdout).into_owned(), out)
}

fn critical(out: &std::path::Path) -> Vec<serde_json::Value> {
    serde_json::from_str(&std::fs::read_to_string(out.join("critical.json")).unwrap()).unwrap()
}

#[test]
fn a_taut_balloons_critical_points_are_valid() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/balloon.toml"))
        .unwrap()
        .replace("frequency = 8", "frequency = 4");
    let scene = dir.path().join("balloon.toml");
    std::fs::write(&scene, text).unwrap();
    let (summary, out) = run(scene.to_str().unwrap(), dir.path(), false);
    let points = critical(&out);
    assert_eq!(points.len(), 2, "{points:?}");
    assert!(points
        .iter()
        .all(|c| c["valid"] == true && c["flags"] == serde_json::json!([])));
    assert!(!summary.contains("flagged"), "{summary}");
}

#[test]
fn critical_points_in_a_wrinkled_state_are_listed_apart() {
    let dir = tempfile::tempdir().unwrap();
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/thesis/paper3_gas_fluid_pressure.toml"
    );
    let (json, out) = run(scene, dir.path(), true);
    let points = critical(&out);
    assert!(!points.is_empty());
    for c in &points {
        assert_eq!(c["valid"], false, "{c}");
        assert_eq!(c["flags"][0]["flag"], "wrinkled", "{c}");
        let (n, of) = (
            c["flags"][0]["triangles"].as_u64().unwrap(),
            c["flags"][0]["of"].as_u64().unwrap(),
        );
        assert!(n > 0 && n < of && of == 1152, "{c}");
        // The critical modes live where the membrane wrinkles: artefacts of the wrinkles.
        assert!(c["flags"][0]["mode"].as_f64().unwrap() > 0.9, "{c}");
    }
    let summary: serde_json::Value = serde_json::from_str(&json).unwrap();
    let listed = summary["critical"].as_array().unwrap();
    assert_eq!(listed.len(), points.len());
    assert!(listed.iter().all(|c| c["valid"] == false));
    // The summary lists them apart, with the reason.
    let again = dir.path().join("again");
    std::fs::create_dir(&again).unwrap();
    let (text, _) = run(scene, &again, false);
    assert!(text.contains("critical points: none valid"), "{text}");
    assert!(text.contains("critical points flagged"), "{text}");
    assert!(text.contains("point 1: wrinkled, "), "{text}");
}

/// `compare` matches only the valid points: the flagged ones are listed apart, unless
/// `--include-flagged`.
#[test]
fn compare_lists_flagged_points_apart_unless_asked() {
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/thesis/paper3_gas_fluid_pressure.toml"
    );
    let compare = |extra: &[&str]| -> serde_json::Value {
        let o = Command::new(env!("CARGO_BIN_EXE_memstab"))
            .args(["compare", scene, "--meshes", "C2v", "--json", "--quiet"])
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        serde_json::from_slice(&o.stdout).unwrap()
    };
    let apart = compare(&[]);
    let level = &apart["meshes"][0]["levels"][0];
    assert_eq!(level["critical"].as_array().unwrap().len(), 0, "{level}");
    let flagged = level["flagged"].as_array().unwrap();
    assert!(!flagged.is_empty());
    assert!(flagged.iter().all(|p| p["flags"][0]["flag"] == "wrinkled"));
    let included = compare(&["--include-flagged"]);
    let level = &included["meshes"][0]["levels"][0];
    assert_eq!(
        level["critical"].as_array().unwrap().len(),
        flagged.len(),
        "{level}"
    );
    assert!(level.get("flagged").is_none());
}
