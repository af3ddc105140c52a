//! `memstab spectrum` and `memstab export-matrix` analyse the same state: the start state
//! solved as `run` solves it with `--at` in place of start values — on a linear-buckling
//! scene held with its control at the start value, the control's `--at` entering the tangent
//! only, every other `--at` the held state too.

use crate::export_rank_one::read_sparse;
use nalgebra::DMatrix;
use serde_json::Value;
use std::process::Command;

/// A clamped pre-stretched C7v disc under a gas over-pressure p (from below) and fluid of
/// density rho above: the ponding sweep in rho of the state that p inflates.
const SCENE: &str = r#"
[scene]
name = "inflated-ponding"
description = "ponding of a disc held inflated by a gas over-pressure"

[mesh]
generator = "disc"
radius = 1.1
sectors = 7
divisions = 3

[material]
model = "mooney-rivlin"
mu = 100.0
k = 0.0
thickness = 0.01
prestretch = 1.1

[[effect]]
type = "gas"
pressure = "p"

[[effect]]
type = "fluid"
side = "above"
density = "rho"
gravity = 1.0
level = 1e-6

[boundary]
fixed = ["rim"]

[parameters.p]
start = 0.0

[parameters.rho]
start = 0.0
min = 0.0
max = 20.0

[analysis]
type = "linear-buckling"
control = "rho"
samples = 10
"#;

fn memstab(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_memstab"))
        .args(args)
        .output()
        .expect("the binary runs")
}

#[test]
fn spectrum_and_export_matrix_analyse_the_same_held_state() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene.toml");
    std::fs::write(&scene, SCENE).unwrap();
    let scene = scene.to_str().unwrap();
    let at = ["--at", "p=0.3", "--at", "rho=9"];
    let mut args = vec!["spectrum", scene, "--json", "--count", "1000"];
    args.extend(at);
    let out = memstab(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["held"], true);
    assert_eq!(json["parameters"]["p"], 0.3);
    assert_eq!(json["parameters"]["rho"], 9.0);
    let k_file = dir.path().join("K.mtx");
    let mut args = vec!["export-matrix", scene, "--out", k_file.to_str().unwrap()];
    args.extend(at);
    let out = memstab(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

    let (n, entries, _) = read_sparse(&k_file);
    let mut k = DMatrix::zeros(n, n);
    for &(i, j, v) in &entries {
        k[(i, j)] = v;
        k[(j, i)] = v;
    }
    // The same tangent: the same scale, the same index, the same spectrum (each block's
    // eigenvalues counted d times).
    let scale = k.amax();
    assert!((json["scale"].as_f64().unwrap() / scale - 1.0).abs() < 1e-12);
    let mut full: Vec<f64> = k
        .symmetric_eigenvalues()
        .iter()
        .map(|v| v / scale)
        .collect();
    full.sort_by(f64::total_cmp);
    let negative = full.iter().filter(|&&v| v < 0.0).count();
    assert_eq!(json["index"].as_u64().unwrap() as usize, negative);
    let mut blocks: Vec<f64> = Vec::new();
    for irrep in json["irreps"].as_array().unwrap() {
        let d = irrep["dim"].as_u64().unwrap() as usize;
        for v in irrep["lowest"].as_array().unwrap() {
            blocks.extend(std::iter::repeat_n(v.as_f64().unwrap(), d));
        }
    }
    blocks.sort_by(f64::total_cmp);
    assert_eq!(blocks.len(), n, "every eigenvalue of every block");
    let worst = full
        .iter()
        .zip(&blocks)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-10, "spectra differ by {worst:e}");
    // And p moved the held state: at p = 0 the tangent differs.
    let out = memstab(&[
        "export-matrix",
        scene,
        "--at",
        "rho=9",
        "--out",
        k_file.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    let (_, flat, _) = read_sparse(&k_file);
    let differs = flat
        .iter()
        .zip(&entries)
        .any(|(a, b)| (a.2 - b.2).abs() > 1e-6 * scale);
    assert!(differs, "the override of p must change the held state");
}
