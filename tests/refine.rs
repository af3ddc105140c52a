//! `memstab run --refine` end to end (docs/theory.md §8.11): on the balloon (an icosphere of
//! frequency 4, refined to 8 and 16) every limit point's error estimate brackets its true
//! error against the closed form, and the meridian's value (`--continuum`) is the closed form;
//! a minimum of the pressure that the finer mesh does not reach (its path leaves the
//! pressure's range first) is flagged not mesh-converged; bad requests write nothing.

use crate::common::{memstab, text};
use memstab::reference::{P_MAX, P_MIN};
use serde_json::Value;
use std::path::Path;
use std::process::Command;

fn json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// The bundled balloon at frequency 4, with `edits` (old, new) to its lines.
fn balloon(dir: &Path, edits: &[(&str, &str)]) -> String {
    let mut text =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/balloon.toml"))
            .unwrap()
            .replace("frequency = 8 ", "frequency = 4 ");
    for (old, new) in edits {
        assert!(text.contains(old), "{old}");
        text = text.replace(old, new);
    }
    let path = dir.join("balloon.toml");
    std::fs::write(&path, text).unwrap();
    path.to_str().unwrap().to_string()
}

fn run(args: &[&str]) -> String {
    let out = memstab(args);
    assert!(
        out.status.success(),
        "{:?}: {}{}",
        out.status.code(),
        text(&out.stdout),
        text(&out.stderr)
    );
    text(&out.stdout)
}

#[test]
fn the_balloons_error_estimates_bracket_the_true_errors() {
    let dir = tempfile::tempdir().unwrap();
    let scene = balloon(dir.path(), &[]);
    let out = dir.path().join("out");
    let stdout = run(&[
        "run",
        &scene,
        "--out",
        out.to_str().unwrap(),
        "--refine",
        "2",
        "--continuum",
        "--quiet",
        "--json",
    ]);
    let summary: Value = serde_json::from_str(&stdout).unwrap();
    let refinement = &summary["refinement"];
    // refine.json holds what --json prints, and the manifest lists it.
    assert_eq!(&json(&out.join("refine.json")), refinement);
    let manifest = json(&out.join("manifest.json"));
    assert!(
        manifest["files"]
            .as_array()
            .unwrap()
            .iter()
            .any(|f| f["file"] == "refine.json"),
        "{manifest}"
    );
    let levels = refinement["levels"].as_array().unwrap();
    let resolutions: Vec<u64> = levels
        .iter()
        .map(|l| l["resolution"].as_u64().unwrap())
        .collect();
    assert_eq!(resolutions, [4, 8, 16]);
    assert!(levels.iter().all(|l| l["seconds"].as_f64().unwrap() > 0.0));
    let points = refinement["critical"].as_array().unwrap();
    assert_eq!(points.len(), 2, "{refinement}");
    let turning = refinement["turning"].as_array().unwrap();
    assert_eq!(turning.len(), 2, "{refinement}");
    for (p, exact) in points
        .iter()
        .zip([P_MAX, P_MIN])
        .chain(turning.iter().zip([P_MAX, P_MIN]))
    {
        assert_eq!(p["estimate"]["basis"], "richardson", "{p}");
        assert_eq!(p["estimate"]["observed"], true, "{p}");
        let order = p["observed_order"].as_f64().unwrap();
        assert!((order - 2.0).abs() < 0.1, "{p}");
        for (v, e) in p["values"]
            .as_array()
            .unwrap()
            .iter()
            .zip(p["errors"].as_array().unwrap())
        {
            let (v, e) = (v.as_f64().unwrap(), e.as_f64().unwrap());
            let truth = (v - exact).abs();
            // The estimate brackets the true error: within a factor 1.5 either way.
            assert!(
                truth <= 1.5 * e && truth >= e / 1.5,
                "value {v}: true error {truth}, estimated {e}: {p}"
            );
        }
        // Richardson is better than the finest level by far.
        let r = p["richardson"].as_f64().unwrap();
        let finest = p["values"][2].as_f64().unwrap();
        assert!(
            (r - exact).abs() < 0.01 * (finest - exact).abs(),
            "{r} against {exact}: {p}"
        );
    }
    // The meridian's value is the closed form, and each level's distance from it its error,
    // for the critical and the turning points alike.
    for (p, exact) in points
        .iter()
        .zip([P_MAX, P_MIN])
        .chain(turning.iter().zip([P_MAX, P_MIN]))
    {
        let c = p["continuum"].as_f64().unwrap();
        assert!((c - exact).abs() < 1e-6, "{p}");
        let d = p["distances"][0].as_f64().unwrap();
        let v = p["values"][0].as_f64().unwrap();
        assert!((d - (v - c)).abs() < 1e-12, "{p}");
    }
    assert!(summary["critical"]
        .as_array()
        .unwrap()
        .iter()
        .all(|c| c["valid"] == true));
    // Without --refine: no refine.json, no refinement in the summary.
    let plain = dir.path().join("plain");
    let stdout = run(&["run", &scene, "--out", plain.to_str().unwrap(), "--quiet"]);
    assert!(!plain.join("refine.json").exists());
    assert!(!stdout.contains("mesh refinement"), "{stdout}");
    assert!(!json(&plain.join("manifest.json"))
        .to_string()
        .contains("refine"));
    // The run's own files are the same with and without --refine.
    for file in ["path.csv", "path.json", "critical.json"] {
        let a = std::fs::read_to_string(out.join(file)).unwrap();
        let b = std::fs::read_to_string(plain.join(file)).unwrap();
        assert_eq!(
            a.replace(out.to_str().unwrap(), ""),
            b.replace(plain.to_str().unwrap(), ""),
            "{file}"
        );
    }
}

#[test]
fn a_minimum_the_finer_mesh_does_not_reach_is_not_mesh_converged() {
    // Started above the pressure minimum of the closed form (1.1487) with the lower bound
    // 1.16 between the minima of frequency 4 (1.1665) and 8 (1.1532): the coarse path turns
    // at its minimum, the finer one leaves the range before it.
    let dir = tempfile::tempdir().unwrap();
    let scene = balloon(
        dir.path(),
        &[
            ("start = 0.4879036", "start = 1.2409396 #"),
            ("min = 0.0", "min = 1.16"),
            ("stretch = 1.05 ", "stretch = 1.25 #"),
        ],
    );
    let out = dir.path().join("out");
    let summary = run(&[
        "run",
        &scene,
        "--out",
        out.to_str().unwrap(),
        "--refine",
        "--quiet",
    ]);
    let critical = json(&out.join("critical.json"));
    let critical = critical.as_array().unwrap();
    assert_eq!(critical.len(), 2, "{critical:?}");
    assert_eq!(critical[0]["valid"], true, "{:?}", critical[0]);
    assert_eq!(critical[1]["valid"], false, "{:?}", critical[1]);
    assert_eq!(critical[1]["flags"][0]["flag"], "not-mesh-converged");
    assert_eq!(critical[1]["flags"][0]["finer"], "icosphere frequency=8");
    let refinement = json(&out.join("refine.json"));
    assert_eq!(
        refinement["critical"][1]["estimate"]["basis"],
        "not-mesh-converged"
    );
    assert_eq!(refinement["critical"][1]["values"][1], Value::Null);
    assert_eq!(
        refinement["turning"][1]["estimate"]["basis"],
        "not-mesh-converged"
    );
    assert_eq!(refinement["critical"][0]["estimate"]["basis"], "richardson");
    // The summary lists it apart, with the reason.
    let flagged = summary
        .split("critical points flagged")
        .nth(1)
        .expect("a flagged list");
    assert!(
        flagged
            .lines()
            .any(|l| l
                .contains("point 2: not mesh-converged, no counterpart on icosphere frequency=8")),
        "{summary}"
    );
}

#[test]
fn bad_refinements_are_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let scene = balloon(dir.path(), &[]);
    let file_scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/disc_file.toml");
    for (args, expect) in [
        (vec![scene.as_str(), "--refine", "3"], "--refine 3"),
        (
            vec![file_scene, "--refine"],
            "--refine 1: the scene's mesh is the file",
        ),
        (
            vec![file_scene, "--refine", "2"],
            "--refine 2: the scene's mesh is the file",
        ),
    ] {
        let out = dir.path().join("out");
        let mut all = vec!["run"];
        all.extend(args);
        all.extend(["--out", out.to_str().unwrap()]);
        let o = memstab(&all);
        assert_eq!(o.status.code(), Some(2), "{all:?}");
        let err = text(&o.stderr);
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(err.contains(expect), "{err}");
        assert!(!out.exists(), "{all:?} wrote {}", out.display());
    }
}

#[test]
fn a_signal_during_the_refinement_writes_the_run_without_it() {
    // The balloon's own path takes 24 steps; the hook stops the first refined run after 6 of
    // its own.
    let dir = tempfile::tempdir().unwrap();
    let scene = balloon(dir.path(), &[]);
    let out = dir.path().join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_memstab"))
        .args([
            "run",
            &scene,
            "--out",
            out.to_str().unwrap(),
            "--refine",
            "--quiet",
        ])
        .env("MEMSTAB_INTERRUPT_AFTER_STEPS", "30")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(130), "{}", text(&o.stderr));
    assert!(
        text(&o.stderr).contains("refinement was interrupted"),
        "{}",
        text(&o.stderr)
    );
    assert!(!out.join("refine.json").exists());
    let path = json(&out.join("path.json"));
    assert_eq!(path["stop"], "the stretch reached 4", "{}", path["stop"]);
    assert!(json(&out.join("critical.json"))
        .as_array()
        .unwrap()
        .iter()
        .all(|c| c["valid"] == true));
    assert!(out.join("manifest.json").exists());
}

#[test]
fn a_meridian_assumes_the_order_of_its_quadratic_elements() {
    // The balloon's meridian at 64 and 128 elements: order 4 assumed, and the Richardson
    // value of its maximum is the closed form.
    let dir = tempfile::tempdir().unwrap();
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/axisymmetric/balloon.toml"
    );
    let out = dir.path().join("out");
    let stdout = run(&[
        "run",
        scene,
        "--out",
        out.to_str().unwrap(),
        "--refine",
        "--quiet",
        "--json",
    ]);
    let summary: Value = serde_json::from_str(&stdout).unwrap();
    let refinement = &summary["refinement"];
    assert_eq!(refinement["assumed_order"], 4.0, "{refinement}");
    let max = &refinement["critical"][0];
    assert_eq!(max["estimate"]["basis"], "richardson", "{max}");
    let r = max["richardson"].as_f64().unwrap();
    assert!((r - P_MAX).abs() < 1e-6, "{max}");
}

/// refine.json without the wall times, which differ from run to run.
fn without_seconds(mut v: Value) -> Value {
    for level in v["levels"].as_array_mut().unwrap() {
        level.as_object_mut().unwrap().remove("seconds");
    }
    v
}

#[test]
fn the_scenes_refine_section_is_the_flag_and_the_flag_overrides_it() {
    // The balloon at frequency 4 to its pressure maximum (stretch 2), refined once.
    let dir = tempfile::tempdir().unwrap();
    let short = ("stop-stretch = 4.0 ", "stop-stretch = 2.0 #");
    let by_key = balloon(
        dir.path(),
        &[short, ("[start]", "[refine]\nlevels = 1\n\n[start]")],
    );
    let a = dir.path().join("a");
    run(&["run", &by_key, "--out", a.to_str().unwrap(), "--quiet"]);
    let b = dir.path().join("b");
    let by_flag = dir.path().join("flag.toml");
    std::fs::write(
        &by_flag,
        std::fs::read_to_string(&by_key)
            .unwrap()
            .replace("[refine]\nlevels = 1\n", ""),
    )
    .unwrap();
    let by_flag = by_flag.to_str().unwrap();
    run(&[
        "run",
        by_flag,
        "--out",
        b.to_str().unwrap(),
        "--quiet",
        "--refine",
    ]);
    let (ra, rb) = (json(&a.join("refine.json")), json(&b.join("refine.json")));
    assert_eq!(ra["levels"].as_array().unwrap().len(), 2, "{ra}");
    assert_eq!(without_seconds(ra), without_seconds(rb.clone()));
    // The flag overrides the section: two levels asked in the scene, one on the command line.
    let two = dir.path().join("two.toml");
    std::fs::write(
        &two,
        std::fs::read_to_string(&by_key)
            .unwrap()
            .replace("levels = 1", "levels = 2"),
    )
    .unwrap();
    let c = dir.path().join("c");
    run(&[
        "run",
        two.to_str().unwrap(),
        "--out",
        c.to_str().unwrap(),
        "--quiet",
        "--refine",
        "1",
    ]);
    assert_eq!(
        without_seconds(json(&c.join("refine.json"))),
        without_seconds(rb)
    );
}

#[test]
fn a_bad_refine_section_is_refused_naming_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let file_scene = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/disc_file.toml"
    ))
    .unwrap()
    .replace(
        "path = \"",
        &format!("path = \"{}/scenes/", env!("CARGO_MANIFEST_DIR")),
    );
    for (scene, expect) in [
        (
            {
                let d = dir.path().join("0");
                std::fs::create_dir(&d).unwrap();
                balloon(&d, &[("[start]", "[refine]\nlevels = 3\n\n[start]")])
            },
            "'refine.levels' must be 1 (the mesh at twice the divisions) or 2 (at twice and four times), got 3",
        ),
        (
            {
                let d = dir.path().join("1");
                std::fs::create_dir(&d).unwrap();
                balloon(&d, &[("[start]", "[refine]\nlevel = 1\n\n[start]")])
            },
            "unknown key 'refine.level'",
        ),
        (
            {
                let d = dir.path().join("2");
                std::fs::create_dir(&d).unwrap();
                balloon(&d, &[("[start]", "[refine]\ncontinuum = \"yes\"\n\n[start]")])
            },
            "'refine.continuum'",
        ),
        (
            {
                let path = dir.path().join("file.toml");
                std::fs::write(&path, format!("{file_scene}\n[refine]\nlevels = 2\n")).unwrap();
                path.to_str().unwrap().to_string()
            },
            "'refine.levels' = 2: the scene's mesh is the file",
        ),
    ] {
        let out = dir.path().join("out");
        let o = memstab(&["run", &scene, "--out", out.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(2), "{scene}");
        let err = text(&o.stderr);
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(err.contains(expect), "{err}");
        assert!(!out.exists(), "{scene} wrote {}", out.display());
    }
    // --continuum needs a refinement to add the meridian to.
    let out = dir.path().join("out");
    let o = memstab(&[
        "run",
        &balloon(dir.path(), &[]),
        "--out",
        out.to_str().unwrap(),
        "--continuum",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o.stderr).contains("--continuum: needs --refine"),
        "{}",
        text(&o.stderr)
    );
    assert!(!out.exists());
}

#[test]
fn a_refined_level_that_fails_is_recorded_and_the_run_reports_the_others() {
    // Started at p = 1.368, between the pressure maxima of frequency 4 (1.3760) and 8
    // (1.3603): the coarse balloon has an equilibrium there, the finer one has none, and its
    // start solve fails.
    let dir = tempfile::tempdir().unwrap();
    let scene = balloon(
        dir.path(),
        &[
            ("start = 0.4879036", "start = 1.368 #"),
            ("stretch = 1.05 ", "stretch = 1.35 #"),
            ("stop-stretch = 4.0 ", "stop-stretch = 2.0 #"),
        ],
    );
    let out = dir.path().join("out");
    let summary = run(&[
        "run",
        &scene,
        "--out",
        out.to_str().unwrap(),
        "--refine",
        "2",
        "--quiet",
    ]);
    let refinement = json(&out.join("refine.json"));
    let failed = refinement["failed"].as_array().unwrap();
    assert_eq!(failed.len(), 2, "{refinement}");
    assert_eq!(failed[0]["run"], "level 1");
    assert_eq!(failed[0]["mesh"], "icosphere frequency=8");
    let reason = failed[0]["reason"].as_str().unwrap();
    assert!(
        reason.starts_with("the start state did not converge"),
        "{reason}"
    );
    assert_eq!(failed[1]["run"], "level 2");
    assert_eq!(failed[1]["reason"], "not run: level 1 failed");
    // The run's own level is reported, its point without an estimate and not flagged.
    assert_eq!(refinement["levels"].as_array().unwrap().len(), 1);
    let point = &refinement["critical"][0];
    assert_eq!(point["estimate"]["basis"], "not-refined", "{point}");
    assert_eq!(point["values"].as_array().unwrap().len(), 1);
    assert_eq!(json(&out.join("critical.json"))[0]["valid"], true);
    assert!(
        summary
            .contains("level 1 (icosphere frequency=8) failed: the start state did not converge"),
        "{summary}"
    );
    assert!(summary.contains("no refined level ran"), "{summary}");
}

/// Paper 1's disc from below on the thesis mesh (C7v, 1 792 triangles): `run --refine
/// --continuum` gives the fold and the first two doubles the values `compare --meshes
/// axisymmetric,C7v --refine` finds on the same two meshes, and error estimates (value less
/// the Richardson value) within 1 % of their distance from the meridian's value there; the
/// points farther along the path, which the finer mesh does not have, are labelled not
/// mesh-converged.
#[test]
fn the_disc_from_below_refined_agrees_with_compare_and_labels_its_post_fold_points() {
    let dir = tempfile::tempdir().unwrap();
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/disc_fluid_below.toml");
    let out = dir.path().join("below");
    run(&[
        "run",
        scene,
        "--refine",
        "--continuum",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    let refine = json(&out.join("refine.json"));
    let critical = refine["critical"].as_array().unwrap();
    let compare = memstab(&[
        "compare",
        scene,
        "--meshes",
        "axisymmetric,C7v",
        "--refine",
        "--json",
    ]);
    assert!(compare.status.success(), "{}", text(&compare.stderr));
    let compare: Value = serde_json::from_slice(&compare.stdout).unwrap();
    // The C7v mesh's levels in compare: each critical value per level, by irrep.
    let c7v = compare["meshes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["label"] == "C7v")
        .unwrap();
    let level = |k: usize| -> Vec<(String, f64)> {
        c7v["levels"][k]["critical"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| {
                (
                    c["irrep"].as_str().unwrap().to_string(),
                    c["value"].as_f64().unwrap(),
                )
            })
            .collect()
    };
    let reference: Vec<f64> = compare["meshes"][0]["levels"][0]["critical"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["value"].as_f64().unwrap())
        .collect();
    let mut converged = 0;
    for p in critical {
        let irrep = p["irreps"][0].as_str().unwrap();
        // The coarse run's critical point number (1-based, in path order).
        let number = p["points"][0].as_u64().unwrap();
        if number <= 3 {
            // The fold and the first two doubles (E1, E2) on its far side: the same value on
            // both levels as compare's.
            for l in 0..2 {
                let v = p["values"][l].as_f64().unwrap();
                assert!(
                    level(l)
                        .iter()
                        .any(|(i, w)| i == irrep && (v - w).abs() <= 1e-9 * w.abs()),
                    "{irrep} {v} not among {:?}",
                    level(l)
                );
            }
            assert_eq!(p["estimate"]["basis"], "richardson", "{p}");
            // The error estimate against the distance from the meridian (compare's
            // continuum): within 1 %.
            let continuum = p["continuum"].as_f64().unwrap();
            assert!(reference
                .iter()
                .any(|r| (r - continuum).abs() <= 1e-12 * r.abs()));
            for l in 0..2 {
                let error = p["errors"][l].as_f64().unwrap();
                let distance = (p["values"][l].as_f64().unwrap() - continuum).abs();
                assert!(
                    (error - distance).abs() <= 0.01 * distance,
                    "{irrep}: {error} vs {distance}"
                );
            }
            converged += 1;
        } else {
            // Farther down the path, where the meridian and the finer mesh part ways with it.
            assert_eq!(p["estimate"]["basis"], "not-mesh-converged", "{p}");
        }
    }
    assert_eq!(converged, 3);
    assert!(critical.len() > 3, "no point farther along: {critical:?}");
}

/// The cusp of the balloon's limit-point curve in (p, k) in closed form: the maximum of k on
/// the fold line k(λ) (golden-section search), with the sphere's pressure there.
fn closed_form_cusp() -> (f64, f64) {
    let (mut a, mut b) = (1.4f64, 3.0f64);
    let g = (5f64.sqrt() - 1.0) / 2.0;
    for _ in 0..200 {
        let (c, d) = (b - g * (b - a), a + g * (b - a));
        if crate::common::fold_k(c) > crate::common::fold_k(d) {
            b = d;
        } else {
            a = c;
        }
    }
    let l = 0.5 * (a + b);
    let k = crate::common::fold_k(l);
    (memstab::reference::sphere_pressure(k, l), k)
}

/// A critical curve's cusp under `--refine 2` (the balloon's limit point followed in (p, k)
/// at icosphere frequency 4, 8, 16): both coordinates on every level, the pressure's observed
/// order 2, its error estimates bracketing the true errors against the closed form and its
/// Richardson value far closer than the finest level; k, which the fold line's maximum fixes
/// to within 3e-7 on every level, is said to converge outside the assumed order rather than
/// extrapolated. The cusp has counterparts on every level: no flag in critical.json. With
/// `--continuum` the meridian's curve gives the cusp as well, at the closed form, with each
/// level's distance from it.
#[test]
fn a_critical_curves_cusp_is_refined_against_its_closed_form() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("curve.toml");
    std::fs::write(
        &scene,
        crate::common::balloon_with_k(
            4,
            "[parameters.k]\nstart = 0.1\nmin = 0.05\nmax = 0.3\n\n[analysis]\n\
             type = \"critical-curve\"\ncontrol = \"p\"\nsecond = \"k\"\nfrom = \"limit\"\n\
             steps = 120\npath-steps = 400\nmax-step = 0.05\n\n",
        ),
    )
    .unwrap();
    let out = dir.path().join("out");
    let stdout = run(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--refine",
        "2",
        "--continuum",
        "--quiet",
    ]);
    let (p_c, k_c) = closed_form_cusp();
    let refinement = json(&out.join("refine.json"));
    assert_eq!(refinement["second"], "k", "{refinement}");
    let events = refinement["events"].as_array().unwrap();
    assert_eq!(events.len(), 1, "{refinement}");
    let cusp = &events[0];
    assert_eq!(cusp["kind"], "cusp");
    assert_eq!(cusp["extremum"], "maximum");
    // The curve's events: start, cusp, end.
    assert_eq!(cusp["event"], 2);
    let p = &cusp["control"];
    assert_eq!(p["estimate"]["basis"], "richardson", "{cusp}");
    assert!(
        (p["observed_order"].as_f64().unwrap() - 2.0).abs() < 0.1,
        "{cusp}"
    );
    let values: Vec<f64> = p["values"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(values.len(), 3);
    for (v, e) in values.iter().zip(p["errors"].as_array().unwrap()) {
        let (truth, e) = ((v - p_c).abs(), e.as_f64().unwrap());
        assert!(
            truth <= 1.5 * e && truth >= e / 1.5,
            "p {v}: true error {truth}, estimated {e}: {cusp}"
        );
    }
    let r = p["richardson"].as_f64().unwrap();
    assert!(
        (r - p_c).abs() < 0.01 * (values[2] - p_c).abs(),
        "Richardson {r} against {p_c}: {cusp}"
    );
    let k = &cusp["second"];
    for v in k["values"].as_array().unwrap() {
        assert!((v.as_f64().unwrap() - k_c).abs() < 1e-6, "{cusp}");
    }
    assert_eq!(k["estimate"]["basis"], "not-asymptotic", "{cusp}");
    // The meridian's cusp: the closed form's to its quadratic elements' accuracy (a relative
    // 6e-9 at 64 elements), with its own error from twice the elements, and every level's
    // distance from it.
    let on_meridian = &cusp["continuum"];
    for (coordinate, truth, tolerance) in [("control", p_c, 3e-8), ("second", k_c, 1e-9)] {
        let c = &on_meridian[coordinate];
        let value = c["value"].as_f64().unwrap();
        assert!((value - truth).abs() < tolerance, "{coordinate}: {cusp}");
        assert!(
            c["error"].as_f64().unwrap() < tolerance,
            "{coordinate}: {cusp}"
        );
        for (l, d) in c["distances"].as_array().unwrap().iter().enumerate() {
            let v = cusp[coordinate]["values"][l].as_f64().unwrap();
            // (to the last bit the JSON parser rounds)
            let d = d.as_f64().unwrap();
            assert!(
                (d - (v - value)).abs() <= 1e-15 * v.abs(),
                "{coordinate}: {cusp}"
            );
        }
    }
    // The summary prints the cusp's levels; critical.json carries no flag on it.
    assert!(
        stdout.contains("curve event 2: cusp (maximum of k)"),
        "{stdout}"
    );
    assert!(stdout.contains("level 2: k = "), "{stdout}");
    assert!(stdout.contains("continuum: p = 1.505047"), "{stdout}");
    let critical = json(&out.join("critical.json"));
    let listed = critical
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["kind"] == "cusp")
        .unwrap();
    assert_eq!(listed["flags"], serde_json::json!([]), "{listed}");
}
