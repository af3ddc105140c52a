//! Deflation (docs/theory.md §16): at a pressure between the balloon's minimum and maximum,
//! deflated Newton from the start state finds the other two inflated spheres — the roots of
//! the closed form p(λ) — on the 3-D mesh (converging at second order under refinement) and
//! on the meridian, says whether the path through the start reaches them, and follows the
//! piece through each.

use memstab::analysis::run;
use memstab::reference::sphere_stretches;
use memstab::results::deflation::{DeflationReport, Solution};
use memstab::results::RunResult;
use memstab::scene::Scene;
use std::process::Command;

const K: f64 = 0.1;
const P: f64 = 1.25;

/// A balloon at p = 1.25 (between the minimum 1.149 and the maximum 1.355) on `mesh`, the
/// path through the start `steps` long.
fn scene(mesh: &str, steps: usize, follow: bool) -> String {
    format!(
        r#"
[scene]
name = "balloon-deflation"

[mesh]
{mesh}

[material]
mu = 100.0
k = {K}
thickness = 0.01

[[effect]]
type = "gas"
pressure = "p"

[parameters.p]
start = {P}
min = 0.0
max = 2.0

[analysis]
type = "deflation"
control = "p"
steps = {steps}
follow = {follow}

[start]
stretch = 1.2
"#
    )
}

fn icosphere(f: usize) -> String {
    format!("generator = \"icosphere\"\nradius = 1.0\nfrequency = {f}")
}

const MERIDIAN: &str =
    "generator = \"axisymmetric\"\nshape = \"sphere\"\nradius = 1.0\nelements = 64\nmodes = 4";

fn deflate(text: &str) -> (DeflationReport, RunResult) {
    let scene = Scene::from_toml_str(text, "deflation").unwrap();
    let mut study = memstab::study::build(scene).unwrap();
    let result = run(&mut *study, |_, _| {}).unwrap();
    let d = result
        .outcome::<Vec<DeflationReport>>()
        .and_then(|s| s.first())
        .cloned()
        .expect("a deflation report");
    (d, result)
}

/// The solutions in tension (no wrinkled triangle): the states the membrane energy
/// describes.
fn taut(d: &DeflationReport) -> Vec<&Solution> {
    d.solutions
        .iter()
        .filter(|s| s.wrinkled.unwrap_or(0) == 0)
        .collect()
}

/// The stretch of every solution in tension, increasing.
fn stretches(d: &DeflationReport) -> Vec<f64> {
    let k = d.measures.iter().position(|m| m == "stretch").unwrap();
    let mut s: Vec<f64> = taut(d).iter().map(|s| s.measures[k]).collect();
    s.sort_by(f64::total_cmp);
    s
}

#[test]
fn deflation_finds_the_three_inflated_spheres_converging_at_second_order() {
    let exact = sphere_stretches(K, P);
    assert_eq!(exact.len(), 3, "{exact:?}");
    let mut errors = Vec::new();
    for f in [4, 8] {
        let (d, _) = deflate(&scene(&icosphere(f), 2, false));
        assert!(d.solutions.iter().all(|s| s.parameters[0] == P));
        // Three spheres in tension; what else solves the discrete equations is wrinkled
        // (a crumpled sphere), labelled so.
        let found = stretches(&d);
        assert_eq!(found.len(), 3, "f = {f}: {d:#?}");
        let error: f64 = found
            .iter()
            .zip(&exact)
            .map(|(a, b)| ((a - b) / b).abs())
            .fold(0.0, f64::max);
        errors.push(error);
        // A 2-step path from the start reaches neither of the others.
        assert!(d.solutions[1..].iter().all(|s| s.on_path.is_none()));
        // The middle sphere (between the maximum and the minimum) is unstable in the
        // symmetric block, the other two stable there.
        let k = d.measures.iter().position(|m| m == "stretch").unwrap();
        let extrema = memstab::reference::sphere_extrema(K);
        let (max, min) = (extrema[0].stretch, extrema[1].stretch);
        for s in taut(&d) {
            let symmetric = s.negative.as_ref().expect("the index")[0];
            let middle = s.measures[k] > max && s.measures[k] < min;
            assert_eq!(symmetric, usize::from(middle), "f = {f}: {s:?}");
        }
    }
    assert!(errors[1] < 0.015, "{errors:?}");
    let order = (errors[0] / errors[1]).log2();
    assert!(
        (1.6..2.6).contains(&order),
        "observed order {order} (errors {errors:?})"
    );
}

#[test]
fn the_solutions_found_on_the_path_and_their_pieces_are_named() {
    // A path long enough to pass the maximum and the minimum reaches both others.
    let (d, result) = deflate(&scene(&icosphere(4), 30, true));
    assert_eq!(d.solutions.len(), 3);
    let rows = &result.report.rows;
    for s in &d.solutions[1..] {
        let row = s.on_path.expect("on the path");
        let (a, b) = (rows[row].parameters[0], rows[row + 1].parameters[0]);
        assert!((a - P) * (b - P) <= 0.0, "row {row} does not cross p = {P}");
        assert!(!s.piece.is_empty() && s.piece_stop.is_some());
        assert_eq!(s.piece[0].parameters[0], P);
    }
}

#[test]
fn the_meridian_deflates_through_the_same_analysis() {
    let (d, _) = deflate(&scene(MERIDIAN, 2, false));
    let exact = sphere_stretches(K, P);
    let found = stretches(&d);
    assert_eq!(found.len(), 3, "{d:#?}");
    for (a, b) in found.iter().zip(&exact) {
        assert!(((a - b) / b).abs() < 1e-4, "{found:?} against {exact:?}");
    }
    assert_eq!(d.blocks[0], "m0");
}

#[test]
fn a_deflation_run_writes_its_files_and_bad_keys_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let scene_path = dir.path().join("balloon.toml");
    std::fs::write(&scene_path, scene(&icosphere(2), 2, true)).unwrap();
    let out = dir.path().join("out");
    let run = Command::new(env!("CARGO_BIN_EXE_memstab"))
        .args(["run", scene_path.to_str().unwrap(), "--out"])
        .arg(&out)
        .arg("--quiet")
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let text = String::from_utf8_lossy(&run.stdout);
    assert!(text.contains("deflation at p = 1.25"), "{text}");
    let manifest = std::fs::read_to_string(out.join("manifest.json")).unwrap();
    for f in ["deflation.json", "deflation.csv", "deflation.svg"] {
        assert!(out.join(f).is_file(), "{f}");
        assert!(manifest.contains(f), "{f} not in the manifest");
    }
    crate::common::figures::check_svg(&out.join("deflation.svg"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("deflation.json")).unwrap())
            .unwrap();
    assert_eq!(json[0]["control"], "p");
    assert!(json[0]["solutions"][0]["distance"].is_null());
    for (from, to, key) in [
        (
            "follow = true",
            "follow = true\noffsets = []",
            "analysis.offsets",
        ),
        (
            "follow = true",
            "follow = true\noffsets = [-1.0]",
            "analysis.offsets[0]",
        ),
        (
            "follow = true",
            "follow = true\nsolutions = 0",
            "analysis.solutions",
        ),
        (
            "follow = true",
            "follow = true\npower = -2.0",
            "analysis.power",
        ),
    ] {
        let bad = scene(&icosphere(2), 2, true).replacen(from, to, 1);
        let bad_path = dir.path().join("bad.toml");
        std::fs::write(&bad_path, bad).unwrap();
        let out = dir.path().join("bad_out");
        let o = Command::new(env!("CARGO_BIN_EXE_memstab"))
            .args(["run", bad_path.to_str().unwrap(), "--out"])
            .arg(&out)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{key}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(&format!("'{key}'")), "{key}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(!out.exists(), "{key}: something was written");
    }
}

/// `at`: a search at every value given, each from a solution known there (the start state
/// carried to the value when the short path does not reach it).
#[test]
fn deflation_searches_at_every_value_given() {
    let text = scene(&icosphere(8), 2, false).replacen(
        "follow = false",
        "follow = false\nat = [1.2, 1.3]",
        1,
    );
    let scene = Scene::from_toml_str(&text, "at").unwrap();
    let mut study = memstab::study::build(scene).unwrap();
    let result = run(&mut *study, |_, _| {}).unwrap();
    let searches = result.outcome::<Vec<DeflationReport>>().unwrap();
    assert_eq!(searches.len(), 2);
    for (d, p) in searches.iter().zip([1.2, 1.3]) {
        assert_eq!(d.value, p);
        let exact = sphere_stretches(K, p);
        let found = stretches(d);
        assert_eq!(found.len(), 3, "p = {p}: {found:?}");
        for (a, b) in found.iter().zip(&exact) {
            assert!(
                ((a - b) / b).abs() < 0.015,
                "p = {p}: {found:?} against {exact:?}"
            );
        }
    }
}

/// Paper 4's spinning cap on the C2v mesh: the m = 2 double of the C8v cap is broken into a
/// fold of the path (the thesis's "two unconnected paths"). Below the fold, deflation along
/// the path's tangent finds a solution the connected path does not reach, unstable, whose
/// piece runs past the connected path's fold.
#[test]
fn deflation_finds_the_unconnected_piece_of_the_broken_double_on_c2v() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/thesis/paper4_spinning_cap.toml"
    ))
    .unwrap()
    .replace("pattern = \"C8v\"", "pattern = \"C2v\"")
    .replace(
        "type = \"path\"",
        "type = \"deflation\"\nat = [16.5]\noffsets = [0.05, -0.05, 0.2, -0.2]",
    )
    .replace("steps = 300", "steps = 120")
    .replace("stop-displacement = 1.2", "");
    let (d, result) = deflate(&text);
    let w2 = |p: &[f64]| p[d.parameters.iter().position(|n| n == "w2").unwrap()];
    // The connected path's fold (the broken double's half that meets it).
    let fold = result
        .report
        .critical
        .iter()
        .find(|c| c.irrep == "A1")
        .map(|c| w2(&c.parameters))
        .expect("the fold of the connected path");
    assert!((16.5..17.0).contains(&fold), "fold at {fold}");
    let apart: Vec<_> = d.solutions.iter().filter(|s| s.on_path.is_none()).collect();
    assert_eq!(apart.len(), 1, "{d:#?}");
    let s = apart[0];
    assert!(s.negative.as_ref().unwrap()[0] >= 1, "{s:?}");
    let reach = s
        .piece
        .iter()
        .map(|p| w2(&p.parameters))
        .fold(f64::MIN, f64::max);
    assert!(
        reach > fold + 0.5,
        "the piece reaches w2 = {reach}, the fold is at {fold}"
    );
}
