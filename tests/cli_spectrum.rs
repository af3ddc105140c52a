//! `memstab spectrum`: the tangent's spectrum by irrep at a scene's start state — rigid-body
//! zero modes of the free balloon in T1u and T1g, `--at` overriding a start value, the held
//! state of a linear-buckling scene, and bad input (exit code 2, one line naming the value).

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

fn scene(name: &str) -> String {
    format!("{}/scenes/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// Runs `spectrum --json` and parses its one object.
fn spectrum_json(args: &[&str]) -> Value {
    let mut all = vec!["spectrum"];
    all.extend_from_slice(args);
    all.push("--json");
    let out = memstab(&all);
    assert!(
        out.status.success(),
        "spectrum {args:?} failed ({:?}): {}{}",
        out.status.code(),
        text(&out.stdout),
        text(&out.stderr)
    );
    serde_json::from_str(text(&out.stdout).trim()).expect("one JSON object")
}

fn irrep<'a>(json: &'a Value, name: &str) -> &'a Value {
    json["irreps"]
        .as_array()
        .expect("irreps")
        .iter()
        .find(|i| i["name"] == name)
        .unwrap_or_else(|| panic!("irrep {name} in {json}"))
}

/// A variant of a bundled scene, text replaced, written into `dir`.
fn variant(dir: &Path, from: &str, replacements: &[(&str, &str)]) -> String {
    let mut t = std::fs::read_to_string(scene(from)).unwrap();
    for (a, b) in replacements {
        assert!(t.contains(a), "{from} contains {a:?}");
        t = t.replacen(a, b, 1);
    }
    let path = dir.join(from);
    std::fs::write(&path, t).unwrap();
    path.display().to_string()
}

#[test]
fn the_free_balloon_has_its_rigid_modes_in_t1u_and_t1g_and_is_stable_at_the_start() {
    let json = spectrum_json(&[&scene("demo.toml")]);
    assert_eq!(json["group"], "Ih");
    assert_eq!(json["order"], 120);
    assert_eq!(json["scene"], "demo");
    assert_eq!(json["index"], 0, "{json}");
    let irreps = json["irreps"].as_array().unwrap();
    assert_eq!(irreps.len(), 10, "Ih has ten irreps");
    // Σ d·m = the unknowns.
    let total: u64 = irreps
        .iter()
        .map(|i| i["dim"].as_u64().unwrap() * i["size"].as_u64().unwrap())
        .sum();
    assert_eq!(total, json["unknowns"].as_u64().unwrap());
    for i in irreps {
        let zero = i["zero_modes"].as_u64().unwrap();
        let expected = if i["name"] == "T1u" || i["name"] == "T1g" {
            1
        } else {
            0
        };
        assert_eq!(zero, expected, "zero modes in {}", i["name"]);
        // Deflated rigid modes leave positive eigenvalues, ascending, in units of max|K_ij|.
        let lowest: Vec<f64> = i["lowest"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert_eq!(lowest.len(), 6.min(i["size"].as_u64().unwrap() as usize));
        assert!(lowest.windows(2).all(|w| w[0] <= w[1]), "{lowest:?}");
        assert!(lowest.iter().all(|v| *v > 0.0 && *v < 10.0), "{lowest:?}");
        assert_eq!(i["negative"], 0);
    }
    assert_eq!(irrep(&json, "T1u")["dim"], 3);
    assert_eq!(irrep(&json, "T1g")["dim"], 3);
    assert!(irrep(&json, "T1u")["zero_mode_residual"].as_f64().unwrap() < 1e-8);
    assert_eq!(json["parameters"]["p"], 0.4879036);

    // The table says the same.
    let out = memstab(&["spectrum", &scene("demo.toml")]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let table = text(&out.stdout);
    assert!(table.contains("units of max|K_ij|"), "{table}");
    assert!(
        table.contains("rigid-body zero modes: 6 (T1g 1x3, T1u 1x3)"),
        "{table}"
    );
    assert!(table.contains("instability index 0"), "{table}");
}

#[test]
fn at_overrides_a_start_value() {
    let start = spectrum_json(&[&scene("demo.toml"), "--count", "3"]);
    let more = spectrum_json(&[&scene("demo.toml"), "--at", "p=1.3", "--count", "3"]);
    assert_eq!(more["parameters"]["p"], 1.3);
    // Below the pressure maximum the inflated balloon is still stable, its rigid modes
    // unchanged, but the spectrum has moved.
    assert_eq!(more["index"], 0);
    assert_eq!(irrep(&more, "T1u")["zero_modes"], 1);
    assert_eq!(irrep(&more, "T1g")["zero_modes"], 1);
    let lowest = |j: &Value| irrep(j, "Ag")["lowest"][0].as_f64().unwrap();
    assert_eq!(irrep(&more, "Ag")["lowest"].as_array().unwrap().len(), 3);
    assert!(
        (lowest(&start) - lowest(&more)).abs() > 1e-3 * lowest(&start).abs(),
        "{} vs {}",
        lowest(&start),
        lowest(&more)
    );
    assert!(
        more["scale"].as_f64().unwrap() != start["scale"].as_f64().unwrap(),
        "the tangent changed"
    );
}

#[test]
fn a_held_ponding_state_past_the_first_rungs_has_index_three() {
    // The flat disc (C8v, d = 6) under fluid: rho = 6 is past gamma_{0,1} (A1) and gamma_{1,1}
    // (E1, double), before gamma_{2,1}: one negative eigenvalue in A1 and one in E1 (twice in
    // K).
    let dir = tempfile::tempdir().unwrap();
    let path = variant(
        dir.path(),
        "ponding.toml",
        &[
            ("sectors = 7 ", "sectors = 8 "),
            ("divisions = 16 ", "divisions = 6 "),
        ],
    );
    let json = spectrum_json(&[&path, "--at", "rho=6"]);
    assert_eq!(json["group"], "C8v");
    assert_eq!(json["held"], true);
    assert_eq!(irrep(&json, "A1")["negative"], 1, "{json}");
    assert_eq!(irrep(&json, "E1")["negative"], 1, "{json}");
    assert_eq!(irrep(&json, "E2")["negative"], 0, "{json}");
    assert_eq!(json["index"], 3);
    let start = spectrum_json(&[&path]);
    assert_eq!(start["index"], 0);
    assert_eq!(start["parameters"]["rho"], 0.0);
}

fn assert_rejected(args: &[&str], needles: &[&str]) {
    let out = memstab(args);
    assert_eq!(
        out.status.code(),
        Some(2),
        "{args:?}: {}{}",
        text(&out.stdout),
        text(&out.stderr)
    );
    let err = text(&out.stderr);
    assert_eq!(err.trim().lines().count(), 1, "one line: {err}");
    for n in needles {
        assert!(err.contains(n), "{args:?}: {err:?} lacks {n:?}");
    }
    assert!(out.stdout.is_empty(), "nothing on stdout");
}

#[test]
fn bad_input_is_one_line_and_exit_code_2() {
    let demo = scene("demo.toml");
    assert_rejected(&["spectrum", &demo, "--at", "q=1"], &["'q'", "p"]);
    assert_rejected(&["spectrum", &demo, "--at", "p=abc"], &["'abc'", "p"]);
    assert_rejected(&["spectrum", &demo, "--at", "p"], &["NAME=VALUE"]);
    assert_rejected(&["spectrum", &demo, "--at", "p=nan"], &["'nan'"]);
    assert_rejected(&["spectrum", "/nonexistent/scene.toml"], &["scene.toml"]);
}

#[test]
fn a_chiral_disc_has_hermitian_e_k_blocks() {
    // The C7 disc: its 2-D irreps are of complex type, each block m complex columns whose
    // every eigenvalue is double in K. Past gamma_{0,1} and gamma_{1,1}: one negative
    // eigenvalue in A and one in E1 (twice in K), as on the C7v disc.
    let dir = tempfile::tempdir().unwrap();
    let chiral = variant(
        dir.path(),
        "ponding.toml",
        &[("divisions = 16 ", "group = \"C7\"\ndivisions = 6 ")],
    );
    let json = spectrum_json(&[&chiral, "--at", "rho=6"]);
    assert_eq!(json["group"], "C7");
    let names: Vec<&str> = json["irreps"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| i["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["A", "E1", "E2", "E3"]);
    let total: u64 = json["irreps"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| i["dim"].as_u64().unwrap() * i["size"].as_u64().unwrap())
        .sum();
    assert_eq!(total, json["unknowns"].as_u64().unwrap());
    assert_eq!(irrep(&json, "E1")["dim"], 2);
    assert_eq!(irrep(&json, "A")["negative"], 1, "{json}");
    assert_eq!(irrep(&json, "E1")["negative"], 1, "{json}");
    assert_eq!(irrep(&json, "E2")["negative"], 0, "{json}");
    assert_eq!(json["index"], 3);
}
