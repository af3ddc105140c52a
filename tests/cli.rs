//! The command line end to end: `memstab group` and `memstab mesh`, their JSON, and the
//! handling of bad input (one line naming the value, exit code 2, no file written).

use crate::common::memstab;
use serde_json::Value;
use std::path::Path;

fn json(args: &[&str]) -> Value {
    let out = memstab(args);
    assert!(
        out.status.success(),
        "memstab {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("stdout is one JSON object")
}

/// Bad input: exit code 2, exactly one line on stderr that mentions `needle`.
fn assert_rejected(args: &[&str], needle: &str) {
    let out = memstab(args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "memstab {args:?}: {err}");
    assert_eq!(
        err.trim_end().lines().count(),
        1,
        "memstab {args:?}: not one line: {err}"
    );
    assert!(
        err.contains(needle),
        "memstab {args:?}: '{needle}' not in: {err}"
    );
}

#[test]
fn group_json_has_elements_and_characters() {
    for (name, order, irreps) in [
        ("C7v", 14, 5),
        ("C8v", 16, 7),
        ("Ih", 120, 10),
        ("C7", 7, 4),
    ] {
        let v = json(&["group", name, "--json"]);
        assert_eq!(v["name"], name);
        assert_eq!(v["order"], order);
        let elements = v["elements"].as_array().unwrap();
        assert_eq!(elements.len(), order);
        let m = &elements[0]["matrix"];
        assert_eq!(
            m,
            &serde_json::json!([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
        );
        let irr = v["irreps"].as_array().unwrap();
        assert_eq!(irr.len(), irreps);
        // Σ d²/c = |G| read back from the JSON (c = 2 for complex type).
        let sum: f64 = irr
            .iter()
            .map(|r| {
                let d = r["dim"].as_f64().unwrap();
                let c = if r["kind"] == "complex" { 2.0 } else { 1.0 };
                assert_eq!(r["characters"].as_array().unwrap().len(), order);
                assert_eq!(r["characters"][0].as_f64().unwrap(), d);
                d * d / c
            })
            .sum();
        assert!((sum - order as f64).abs() < 1e-9);
    }
}

#[test]
fn group_table_prints() {
    let out = memstab(&["group", "C2v"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for irrep in ["A1", "A2", "B1", "B2"] {
        assert!(text.contains(irrep), "{text}");
    }
}

#[test]
fn bad_group_names_are_rejected() {
    assert_rejected(&["group", "D7"], "'D7'");
    assert_rejected(&["group", "C0v", "--json"], "'C0v'");
}

#[test]
fn reference_disc_has_1792_triangles() {
    let v = json(&[
        "mesh",
        "disc",
        "--sectors",
        "7",
        "--divisions",
        "16",
        "--json",
    ]);
    assert_eq!(v["elements"], 1792);
    assert_eq!(v["nodes"], 7 * 16 * 17 / 2 + 1);
    assert_eq!(v["group"], "C7v");
    assert_eq!(v["order"], 14);
    assert_eq!(v["verified"], true);
    assert_eq!(v["boundaries"]["rim"], 7 * 16);
    assert_eq!(v["hidden_symmetries"], serde_json::json!([]));
}

#[test]
fn icosphere_frequency_16() {
    let v = json(&["mesh", "icosphere", "--frequency", "16", "--json"]);
    assert_eq!(v["elements"], 5120);
    assert_eq!(v["nodes"], 2562);
    assert_eq!(v["group"], "Ih");
    assert_eq!(v["order"], 120);
    assert_eq!(v["verified"], true);
}

#[test]
fn truncated_sphere_patterns() {
    for (pattern, order) in [("C8v", 16), ("C2v", 4), ("C1v", 2)] {
        let v = json(&["mesh", "truncated-sphere", "--pattern", pattern, "--json"]);
        assert_eq!(v["group"], pattern);
        assert_eq!(v["order"], order);
        assert_eq!(v["verified"], true);
        assert!(v["boundaries"]["cut"].as_u64().unwrap() > 0);
        let n = v["elements"].as_u64().unwrap();
        assert!((4000..8000).contains(&n), "{pattern}: {n} elements");
    }
}

#[test]
fn mesh_writes_every_format() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["d.vtu", "d.msh", "d.xdmf"] {
        let path = dir.path().join(name);
        let p = path.to_str().unwrap();
        let v = json(&[
            "mesh",
            "disc",
            "--sectors",
            "5",
            "--divisions",
            "3",
            "--out",
            p,
            "--json",
        ]);
        assert_eq!(v["elements"], 45);
        assert!(path.is_file(), "{name} not written");
        assert!(std::fs::metadata(&path).unwrap().len() > 100);
    }
}

#[test]
fn bad_mesh_arguments_are_rejected_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m.vtu");
    let o = out.to_str().unwrap();
    assert_rejected(&["mesh", "disc", "--sectors", "0", "--out", o], "0");
    assert_rejected(&["mesh", "disc", "--divisions", "0", "--out", o], "0");
    assert_rejected(&["mesh", "disc", "--sectors", "seven", "--out", o], "seven");
    assert_rejected(&["mesh", "disc", "--group", "C3v", "--out", o], "C3v");
    assert_rejected(&["mesh", "icosphere", "--frequency", "0", "--out", o], "0");
    assert_rejected(
        &[
            "mesh",
            "truncated-sphere",
            "--cut-height",
            "1.5",
            "--out",
            o,
        ],
        "1.5",
    );
    assert_rejected(
        &["mesh", "truncated-sphere", "--cut-height", "-1", "--out", o],
        "-1",
    );
    assert_rejected(
        &["mesh", "truncated-sphere", "--pattern", "C5v", "--out", o],
        "C5v",
    );
    assert_rejected(&["mesh", "sphere", "--out", o], "sphere");
    assert_rejected(&["mesh", "disc", "--radius", "-1", "--out", o], "-1");
    assert_rejected(&["mesh", "disc", "--radius", "nan", "--out", o], "NaN");
    let missing = dir.path().join("missing").join("m.vtu");
    assert_rejected(
        &["mesh", "disc", "--out", missing.to_str().unwrap()],
        "missing",
    );
    let bad_ext = dir.path().join("m.stl");
    assert_rejected(&["mesh", "disc", "--out", bad_ext.to_str().unwrap()], "stl");
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "a file was written"
    );
    assert!(!Path::new(o).exists());
}
