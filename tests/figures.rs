//! The figures memstab writes, checked as a reader would (the checks are in
//! `common::figures`): every SVG of a fresh run of every bundled scene is well-formed XML
//! with the `<svg>` root; its layout (written by the figure builder into the SVG) has no two
//! labels overlapping, no label on the legend or the inset, none left out, every label drawn
//! as a `<text>` and nearer its own point than any other unless a leader line joins them, a
//! legend entry for every marker kind drawn and none for a kind not drawn; the caption names
//! the scene and the mesh. The Paper 4 cap's path and the Paper 3 squeezed cap's path put
//! their clusters of critical points into an inset.

use crate::common::figures::{check_all, well_formed};
use memstab::output::Layout;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::OnceLock;

/// Every bundled scene: the `.toml` files under `scenes/` but the sweep files of
/// `scenes/sweeps/` (not scenes), as paths relative to `scenes/`, sorted.
fn bundled_scenes() -> Vec<String> {
    fn walk(dir: &Path, root: &Path, out: &mut Vec<String>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                if p.file_name().is_some_and(|n| n != "sweeps") {
                    walk(&p, root, out);
                }
            } else if p.extension().is_some_and(|x| x == "toml") {
                let rel = p.strip_prefix(root).unwrap();
                out.push(rel.to_string_lossy().replace('\\', "/"));
            }
        }
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut out = Vec::new();
    walk(&root, &root, &mut out);
    out.sort();
    out
}

/// Runs `memstab run scenes/<scene>` into `out` (emptied first).
fn run(scene: &str, out: &Path) {
    if out.exists() {
        std::fs::remove_dir_all(out).unwrap();
    }
    let o = Command::new(env!("CARGO_BIN_EXE_memstab"))
        .args(["run", &format!("scenes/{scene}"), "--quiet", "--out"])
        .arg(out)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("the memstab binary runs");
    assert!(
        o.status.success(),
        "memstab run {scene}: {}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}

/// A fresh run of every bundled scene, made once for the tests of this file (two at a time)
/// under the test target's scratch directory: (scene, its output directory).
fn bundled_runs() -> &'static [(String, PathBuf)] {
    static RUNS: OnceLock<Vec<(String, PathBuf)>> = OnceLock::new();
    RUNS.get_or_init(|| {
        let root = Path::new(env!("CARGO_TARGET_TMPDIR")).join("bundled-figures");
        std::fs::create_dir_all(&root).unwrap();
        let runs: Vec<(String, PathBuf)> = bundled_scenes()
            .into_iter()
            .map(|s| {
                let dir = root.join(s.trim_end_matches(".toml").replace('/', "_"));
                (s, dir)
            })
            .collect();
        let next = AtomicUsize::new(0);
        std::thread::scope(|scope| {
            for _ in 0..2 {
                scope.spawn(|| {
                    while let Some((scene, dir)) = runs.get(next.fetch_add(1, Ordering::Relaxed)) {
                        run(scene, dir);
                    }
                });
            }
        });
        runs
    })
}

/// The output directory of the bundled scene `scene` (its path under `scenes/`).
fn bundled(scene: &str) -> &'static Path {
    bundled_runs()
        .iter()
        .find(|(s, _)| s == scene)
        .map(|(_, d)| d.as_path())
        .unwrap_or_else(|| panic!("no bundled scene {scene}"))
}

#[test]
fn every_figure_of_the_bundled_scenes_is_well_formed_and_legible() {
    let mut checked = Vec::new();
    for (scene, dir) in bundled_runs() {
        for (name, _) in check_all(dir) {
            checked.push(format!("{scene}: {name}"));
        }
    }
    // The kinds of figure: a path, a spectrum, deflation's solutions, a critical curve, a
    // solution surface, a bifurcation diagram with its branches and partners, a mode, and
    // the meridian's path.
    for f in [
        "balloon.toml: path.svg",
        "ponding.toml: path.svg",
        "balloon_deflation.toml: deflation.svg",
        "thesis/paper1_disc_limit_curve_radius.toml: curve.svg",
        "thesis/paper2_solution_surface_f8.toml: surface.svg",
        "thesis/paper1_disc_irregular_diagram.toml: diagram.svg",
        "thesis/paper1_disc_irregular_diagram.toml: partners.svg",
        "thesis/paper4_spinning_cap.toml: critical_01_mode.svg",
        "axisymmetric/paper4_spinning_cap.toml: path.svg",
    ] {
        assert!(checked.iter().any(|c| c == f), "{f} not in {checked:?}");
    }
}

/// The layouts of the figures of the bundled scene `scene`, checked, by file name.
fn figures_of(scene: &str) -> (&'static Path, Vec<(String, Layout)>) {
    let dir = bundled(scene);
    (dir, check_all(dir))
}

#[test]
fn the_spinning_cap_zooms_on_its_critical_points_at_the_fold() {
    let (dir, layouts) = figures_of("thesis/paper4_spinning_cap.toml");
    let (_, path) = layouts.iter().find(|(n, _)| n == "path.svg").unwrap();
    let inset = path.inset.expect("an inset");
    let zoomed: Vec<&str> = path
        .labels
        .iter()
        .filter(|l| l.in_inset)
        .map(|l| l.text.as_str())
        .collect();
    // The m = 4 pair (B2, B1) and E3 sit within a label's height of the fold on the page.
    for text in ["simple B2 m = 4", "simple B1 m = 4"] {
        assert!(
            zoomed.contains(&text),
            "{text} not in the inset: {zoomed:?}"
        );
    }
    for l in path.labels.iter().filter(|l| l.in_inset) {
        assert!(inset.holds(&l.rect), "{} outside the inset", l.text);
    }
    // A mode figure for each of the path's six critical points.
    let modes = layouts
        .iter()
        .filter(|(n, _)| n.starts_with("critical_") && n.ends_with("_mode.svg"))
        .count();
    assert_eq!(modes, 6);
    // Every critical point and the turning point has its label.
    // (the limit point is the turning point, one label for both).
    assert_eq!(path.labels.len(), 6, "{:?}", path.labels);
    // The turning point's value reads off the vertical axis: ω² in its group ρ ω² R³/(μH).
    let w2 = path.scales.iter().find(|s| s.quantity == "w2").unwrap();
    assert!(w2.label.starts_with("ρ ω² R³/(μH)"), "{w2:?}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("path.json")).unwrap()).unwrap();
    let max = report["turning_points"][0]["parameters"]["w2"]
        .as_f64()
        .expect("the maximum's w2");
    let label = path
        .labels
        .iter()
        .find(|l| l.text.starts_with("max "))
        .expect("the maximum's label");
    let shown: f64 = label.text["max ρ ω² R³/(μH) = ".len()..]
        .split(' ')
        .next()
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{:?}", label.text));
    assert!((shown - max * w2.factor).abs() < 1e-4, "{shown} vs {max}");
}

#[test]
fn the_squeezed_cap_under_the_linear_penalty_zooms_on_its_bifurcations() {
    // Its bifurcation points all lie near the end of the path, a few pixels apart on the
    // page: every one is labelled in the inset, apart, with leaders where a label could be
    // read as another's.
    let (_, layouts) = figures_of("thesis/paper3_gas_fluid_squeeze_linear.toml");
    let (_, path) = layouts.iter().find(|(n, _)| n == "path.svg").unwrap();
    let inset = path.inset.expect("an inset");
    let critical: Vec<_> = path
        .labels
        .iter()
        .filter(|l| l.text.starts_with("simple"))
        .collect();
    assert!(critical.len() >= 4, "{:?}", path.labels);
    for l in critical {
        assert!(
            l.in_inset && inset.holds(&l.rect),
            "{} not in the inset",
            l.text
        );
    }
}

#[test]
fn the_critical_curve_and_the_surface_show_which_side_is_stable() {
    // The disc's path in h reaches the limit curve stable and turns back unstable: both of
    // its states next to the curve's first point are ringed and labelled with their index.
    let (dir, layouts) = figures_of("thesis/paper1_disc_limit_curve_radius.toml");
    let (_, curve) = layouts.iter().find(|(n, _)| n == "curve.svg").unwrap();
    for kind in [
        "state of the path in h: stable (index 0)",
        "state of the path in h: unstable (index 1)",
    ] {
        assert!(
            curve.legend_markers.iter().any(|k| k == kind),
            "{kind} not in {:?}",
            curve.legend_markers
        );
    }
    // The path is drawn across the curve by its index, stable solid and unstable dashed, each
    // with its legend entry (the checker holds the legend's keyed lines to those drawn).
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("path.json")).unwrap()).unwrap();
    let radius = report["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .position(|p| p == "R")
        .map(|k| report["rows"][0]["parameters"][k].as_f64().unwrap())
        .expect("R on the path");
    for word in ["stable (index 0)", "unstable (index 1)"] {
        let kind = curve
            .line_kinds
            .iter()
            .find(|k| k.starts_with("path in h at R = ") && k.ends_with(&format!(": {word}")))
            .unwrap_or_else(|| panic!("no path {word} in {:?}", curve.line_kinds));
        let held: f64 = kind["path in h at R = ".len()..kind.len() - word.len() - 2]
            .parse()
            .unwrap();
        assert!(
            (held - radius).abs() < 1e-4 * radius,
            "{kind} at R = {radius}"
        );
        assert!(
            curve.legend_lines.contains(kind),
            "{:?}",
            curve.legend_lines
        );
    }
    let labels: Vec<&str> = curve.labels.iter().map(|l| l.text.as_str()).collect();
    for text in ["stable (index 0)", "unstable (index 1)"] {
        assert!(labels.contains(&text), "{text} not in {labels:?}");
    }
    // The figure records its quantities' dimensionless groups for a script to reuse.
    let h = curve.scales.iter().find(|s| s.quantity == "h").expect("h");
    assert!(h.label.starts_with("h/a") && h.factor > 0.0, "{h:?}");
    assert!(curve.scales.iter().any(|s| s.quantity == "R"));
    assert!(
        curve.legend.iter().any(|e| e.contains("limit curve")),
        "{:?}",
        curve.legend
    );
    // The critical point's mode, seen from above with its colour bar, titled with its kind,
    // irrep, wave number and isotropy (the layout checks above covered it).
    assert!(layouts.iter().any(|(n, _)| n == "critical_01_mode.svg"));
    let mode = std::fs::read_to_string(dir.join("critical_01_mode.svg")).unwrap();
    let texts = well_formed(&mode, "critical_01_mode.svg");
    for text in [
        "mode of the limit point in A1, m = 0, isotropy C7v",
        "normal component / max",
        "+1",
        "−1",
    ] {
        assert!(texts.iter().any(|t| t == text), "{text} not in {texts:?}");
    }
    assert!(dir.join("critical_01_mode.png").exists());

    // The surface's regions: one legend entry per index its triangles are shaded by (the
    // largest index of their corners), and none other.
    let (dir, layouts) = figures_of("thesis/paper2_solution_surface_f8.toml");
    let (_, surface) = layouts.iter().find(|(n, _)| n == "surface.svg").unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("surface.json")).unwrap()).unwrap();
    let index: Vec<Option<u64>> = json["paths"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|p| p["vertices"].as_array().unwrap())
        .map(|v| v["index"].as_u64())
        .collect();
    let mut regions: Vec<Option<u64>> = json["triangles"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| {
            t.as_array()
                .unwrap()
                .iter()
                .map(|v| index[v.as_u64().unwrap() as usize])
                .max()
                .flatten()
        })
        .collect();
    regions.sort();
    regions.dedup();
    let expected: Vec<String> = regions
        .iter()
        .map(|r| match r {
            None => "region: index not computed".to_string(),
            Some(0) => "stable region (index 0)".to_string(),
            Some(i) => format!("unstable region (index {i})"),
        })
        .collect();
    let shown: Vec<String> = surface
        .legend
        .iter()
        .filter(|e| e.contains("region"))
        .cloned()
        .collect();
    assert_eq!(shown, expected);
    // This surface has both: the stable sheets and the unstable one between the folds.
    assert!(expected.len() >= 2, "{expected:?}");
    // Its paths by index, one legend entry each.
    for kind in ["index 0 (stable)", "index 1"] {
        assert!(
            surface.line_kinds.iter().any(|k| k == kind),
            "{:?}",
            surface.line_kinds
        );
    }
    // Its paths stop on their step budget at different values of p: the figure cuts them all
    // where the first one stopped, and says so in the caption.
    let column = json["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .position(|q| q == "p")
        .unwrap();
    let ends: Vec<f64> = json["paths"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|p| p["stop"].as_str().unwrap().contains("step budget"))
        .map(|p| {
            let v = p["vertices"].as_array().unwrap().last().unwrap();
            v["parameters"][column].as_f64().unwrap()
        })
        .collect();
    assert!(ends.len() >= 2, "{ends:?}");
    let first = ends.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(ends.iter().any(|&e| e > first), "{ends:?}");
    let at: f64 = surface
        .caption
        .split(" paths cut at p = ")
        .nth(1)
        .and_then(|t| t.strip_suffix(" (step budget)"))
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no cut in the caption {:?}", surface.caption));
    assert!(
        (at - first).abs() < 1e-4 * first.abs(),
        "cut at {at}, first end {first}"
    );
}

#[test]
fn a_mesh_read_from_a_file_is_scaled_by_its_own_radius() {
    // The disc of disc_fluid_below.toml read from a Gmsh file: the scene gives no radius, the
    // mesh's own (its nodes' largest distance from the surface's centroid) scales the axes as
    // the generated disc's radius does.
    let (dir, layouts) = figures_of("disc_file.toml");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("path.json")).unwrap()).unwrap();
    let radius = report["mesh"]["radius"]
        .as_f64()
        .expect("the mesh's radius");
    assert!((radius - 1.1).abs() < 1e-9, "{radius}");
    let (_, generated) = figures_of("disc_fluid_below.toml");
    let scale = |layouts: &[(String, Layout)], q: &str| {
        let (_, path) = layouts.iter().find(|(n, _)| n == "path.svg").unwrap();
        path.scales
            .iter()
            .find(|s| s.quantity == q)
            .cloned()
            .unwrap()
    };
    for q in ["h", "max_displacement"] {
        let (file, disc) = (scale(&layouts, q), scale(&generated, q));
        assert!(file.label.contains("/a (a = 1)"), "{file:?}");
        assert_eq!(file.label, disc.label);
        // a = the radius over the prestretch 1.1.
        assert!((file.factor - 1.1 / radius).abs() < 1e-12, "{file:?}");
    }
}

/// The closed circuit of the squeezed cap: the branch's own point where it reaches the path's
/// jump is drawn as a connection, with its legend entry, apart from the critical points.
#[test]
fn a_connection_has_its_own_mark_in_the_diagram() {
    let (_, layouts) = figures_of("thesis/paper3_gas_fluid_squeeze_linear_diagram.toml");
    let (_, diagram) = layouts
        .iter()
        .find(|(name, _)| name == "diagram.svg")
        .expect("diagram.svg");
    for entry in [
        "connection: a branch reaching a known point",
        "critical point",
    ] {
        assert!(
            diagram.legend.iter().any(|l| l == entry),
            "{entry:?} not in {:?}",
            diagram.legend
        );
    }
}
