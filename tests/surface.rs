//! The equilibrium surface of the balloon in (p, k): its limit points on the closed-form fold
//! line, the index across it, its triangles and critical lines, its files, and bad keys.

use crate::common::{balloon_with_k, fold_k};
use memstab::analysis::run;
use memstab::results::{CriticalKind, SurfaceReport};
use memstab::scene::Scene;
use memstab::study::mesh::MeshStudy;
use std::path::Path;
use std::process::Command;

/// The bundled balloon with k = "k" and a surface analysis in (p, k) at icosphere frequency
/// `f`, with `extra` lines appended to `[analysis]`.
fn surface_text(frequency: usize, extra: &str) -> String {
    balloon_with_k(
        frequency,
        &format!(
            "[parameters.k]\nstart = 0.1\n\n[analysis]\ntype = \"surface\"\n\
             parameters = [\"p\", \"k\"]\nranges = [[0.0, 2.0], [0.05, 0.2]]\npaths = 3\n\
             steps = 60\nmax-step = 0.1\n{extra}\n"
        ),
    )
}

fn surface_of(frequency: usize) -> SurfaceReport {
    let scene = Scene::from_toml_str(
        &surface_text(frequency, "measure = \"stretch\""),
        "balloon-surface",
    )
    .unwrap();
    let mut study = MeshStudy::build(scene).unwrap();
    let result = run(&mut study, |_, _| {}).expect("the surface runs");
    result
        .outcome::<memstab::results::SurfaceReport>()
        .cloned()
        .expect("a surface")
}

/// Every limit point the surface's paths localise lies on the closed-form fold line at its
/// own stretch (k to 1e-4 at f = 8, the pressure to the mesh's error, which falls as h²), and
/// the index of the path's vertices is 0 up to the first (the pressure maximum), 1 between
/// it and the second (the minimum), 0 again after it.
#[test]
fn balloon_surface_contains_the_closed_form_fold_line() {
    let mut worst = Vec::new();
    for frequency in [4, 8] {
        let s = surface_of(frequency);
        let (p, k) = (s.parameter("p").unwrap(), s.parameter("k").unwrap());
        let stretch = s.measures.iter().position(|m| m == "stretch").unwrap();
        assert_eq!(s.measure, "stretch");
        assert_eq!(s.paths.len(), 3);
        let mut errors = (0.0f64, 0.0f64);
        for path in &s.paths {
            let limits: Vec<_> = path
                .critical
                .iter()
                .filter(|c| c.kind == CriticalKind::LimitPoint)
                .collect();
            assert_eq!(limits.len(), 2, "k = {}: {:?}", path.b, path.critical);
            for c in &limits {
                let l = c.measures[stretch];
                assert_eq!(c.parameters[k], path.b);
                errors.0 = errors.0.max((c.parameters[k] - fold_k(l)).abs());
                let closed = memstab::reference::sphere_pressure(path.b, l);
                errors.1 = errors.1.max((c.parameters[p] / closed - 1.0).abs());
            }
            // The index: 0 before the maximum, 1 up to the minimum, 0 after.
            let (first, second) = (limits[0].after_step, limits[1].after_step);
            for v in &path.vertices {
                let expected = usize::from(v.step > first && v.step <= second);
                assert_eq!(v.index, Some(expected), "k = {}, step {}", path.b, v.step);
            }
        }
        eprintln!("f = {frequency}: fold-line errors (k, p) = {errors:?}");
        let tol = if frequency == 8 { 1e-2 } else { 4e-2 };
        assert!(errors.1 < tol, "pressure off the fold line by {}", errors.1);
        assert!(
            errors.0 < tol / 100.0,
            "k off the fold line by {}",
            errors.0
        );
        worst.push(errors.1);
        // Two limit lines across all three paths; a strip of n + m − 2 triangles between
        // every two neighbouring paths.
        let limit_lines: Vec<_> = s
            .lines
            .iter()
            .filter(|l| l.kind == CriticalKind::LimitPoint)
            .collect();
        assert_eq!(limit_lines.len(), 2);
        assert!(limit_lines.iter().all(|l| l.points.len() == 3));
        let strips: usize = s
            .paths
            .windows(2)
            .map(|w| w[0].vertices.len() + w[1].vertices.len() - 2)
            .sum();
        assert_eq!(s.triangles.len(), strips);
        assert!(s.triangles.iter().flatten().all(|&v| v < s.vertex_count()));
    }
    // Second order: halving h divides the pressure error by about four.
    let rate = (worst[0] / worst[1]).log2();
    assert!((1.5..2.5).contains(&rate), "rate {rate}, errors {worst:?}");
}

/// `memstab run` writes surface.vtu, surface.json and surface.svg; the VTU lists every vertex
/// and critical-line point and the index of every vertex.
#[test]
fn surface_run_writes_its_files() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = tmp.path().join("surface.toml");
    std::fs::write(&scene, surface_text(4, "")).unwrap();
    let out = tmp.path().join("out");
    let run = Command::new(env!("CARGO_BIN_EXE_memstab"))
        .args([
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(stdout.contains("surface in (p, k): 3 paths"), "{stdout}");
    assert!(
        stdout.contains("critical line: limit point in Ag over 3 paths"),
        "{stdout}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("surface.json")).unwrap()).unwrap();
    // The default measure: the scene's first.
    assert_eq!(json["measure"], "max_displacement");
    let vertices: usize = json["paths"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["vertices"].as_array().unwrap().len())
        .sum();
    let line_points: usize = json["lines"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l["points"].as_array().unwrap().len())
        .sum();
    let vtu = std::fs::read_to_string(out.join("surface.vtu")).unwrap();
    assert!(
        vtu.contains(&format!("NumberOfPoints=\"{}\"", vertices + line_points)),
        "{}",
        &vtu[..300]
    );
    crate::common::figures::check_svg(&out.join("surface.svg"));
    let svg = std::fs::read_to_string(out.join("surface.svg")).unwrap();
    assert!(svg.contains("limit line (fold)") && svg.contains("index 0 (stable)"));
    let manifest = std::fs::read_to_string(out.join("manifest.json")).unwrap();
    assert!(manifest.contains("surface.vtu"));
}

/// Bad keys of a surface: one line naming the key and the value, exit code 2, nothing
/// written.
#[test]
fn bad_surface_keys_are_rejected_without_writing() {
    let tmp = tempfile::tempdir().unwrap();
    let never = tmp.path().join("never");
    let cases: [(&str, &str, &[&str]); 5] = [
        (
            "measure = \"height\"",
            "m.toml",
            &["analysis.measure", "height"],
        ),
        ("", "p.toml", &["analysis.paths", "1"]),
        ("", "r.toml", &["analysis.ranges[1]", "[0.2, 0.05]"]),
        ("", "n.toml", &["analysis.parameters", "[\"p\"]"]),
        (
            "",
            "b.toml",
            &["analysis.ranges[1]", "[0.05, 0.2]", "parameters.k"],
        ),
    ];
    for (i, (extra, name, needles)) in cases.into_iter().enumerate() {
        let mut text = surface_text(4, extra);
        match i {
            1 => text = text.replacen("paths = 3", "paths = 1", 1),
            2 => text = text.replacen("[0.05, 0.2]]", "[0.2, 0.05]]", 1),
            3 => text = text.replacen("parameters = [\"p\", \"k\"]", "parameters = [\"p\"]", 1),
            4 => text = text.replacen("start = 0.1\n", "start = 0.1\nmax = 0.15\n", 1),
            _ => {}
        }
        let path = tmp.path().join(name);
        std::fs::write(&path, text).unwrap();
        let out = Command::new(env!("CARGO_BIN_EXE_memstab"))
            .args([
                "run",
                path.to_str().unwrap(),
                "--out",
                never.to_str().unwrap(),
            ])
            .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "not one line: {err}");
        for needle in needles {
            assert!(err.contains(needle), "'{needle}' not in: {err}");
        }
        assert!(!never.exists(), "{name}: the output directory was created");
    }
}
