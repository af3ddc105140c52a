//! The figures memstab writes, checked as a reader would: every SVG of fresh runs of small
//! bundled scenes is well-formed XML with the `<svg>` root; its layout (written by the
//! figure builder into the SVG) has no two labels overlapping, no label on the legend or
//! the inset, none left out, every label drawn as a `<text>`, a legend entry for every marker
//! kind drawn and none for a kind not drawn; the caption names the scene and the mesh. The
//! Paper 4 cap's path puts its cluster of critical points at the fold into an inset.

use memstab::output::{read_layout, Layout};
use std::path::{Path, PathBuf};
use std::process::Command;

/// Runs `memstab run scenes/<scene>` into a fresh directory under `root`; returns it.
fn run(root: &Path, scene: &str) -> PathBuf {
    let name = Path::new(scene).file_stem().unwrap().to_string_lossy();
    let out = root.join(name.as_ref());
    let o = Command::new(env!("CARGO_BIN_EXE_memstab"))
        .args(["run", &format!("scenes/{scene}"), "--out"])
        .arg(&out)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("the memstab binary runs");
    assert!(
        o.status.success(),
        "memstab run {scene}: {}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    out
}

/// Every `.svg` under `dir`, sorted.
fn svgs(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            out.extend(svgs(&p));
        } else if p.extension().is_some_and(|x| x == "svg") {
            out.push(p);
        }
    }
    out.sort();
    out
}

/// Checks that `svg` is well-formed XML (one root element, `svg`; matching tags; valid
/// attributes and references) and returns the text of its `<text>` elements.
fn well_formed(svg: &str, what: &str) -> Vec<String> {
    use quick_xml::events::Event;
    let mut reader = quick_xml::Reader::from_str(svg);
    reader.config_mut().check_end_names = true;
    let (mut depth, mut roots, mut in_text) = (0usize, 0usize, false);
    let mut texts: Vec<String> = Vec::new();
    let check_attributes = |e: &quick_xml::events::BytesStart| {
        for a in e.attributes().with_checks(true) {
            let a = a.unwrap_or_else(|err| panic!("{what}: bad attribute: {err}"));
            a.normalized_value(quick_xml::XmlVersion::Implicit1_0)
                .unwrap_or_else(|err| panic!("{what}: bad attribute value: {err}"));
        }
    };
    loop {
        match reader.read_event() {
            Err(e) => panic!(
                "{what}: not well-formed at byte {}: {e}",
                reader.buffer_position()
            ),
            Ok(Event::Eof) => break,
            Ok(Event::Start(e)) => {
                if depth == 0 {
                    roots += 1;
                    assert_eq!(e.name().as_ref(), b"svg", "{what}: the root is not <svg>");
                }
                check_attributes(&e);
                depth += 1;
                if e.name().as_ref() == b"text" {
                    in_text = true;
                    texts.push(String::new());
                }
            }
            Ok(Event::Empty(e)) => {
                assert!(depth > 0, "{what}: an element outside the root");
                check_attributes(&e);
            }
            Ok(Event::End(e)) => {
                assert!(depth > 0, "{what}: an end tag without a start");
                depth -= 1;
                if e.name().as_ref() == b"text" {
                    in_text = false;
                }
            }
            Ok(Event::Text(t)) => {
                let raw = t.decode().expect("UTF-8");
                assert!(
                    depth > 0 || raw.trim().is_empty(),
                    "{what}: text outside the root"
                );
                if in_text {
                    if let Some(last) = texts.last_mut() {
                        last.push_str(&raw);
                    }
                }
            }
            Ok(Event::GeneralRef(r)) => {
                let name = r.decode().expect("UTF-8");
                let c = match name.as_ref() {
                    "lt" => Some('<'),
                    "gt" => Some('>'),
                    "amp" => Some('&'),
                    "quot" => Some('"'),
                    "apos" => Some('\''),
                    _ => r
                        .resolve_char_ref()
                        .unwrap_or_else(|e| panic!("{what}: bad reference &{name};: {e}")),
                };
                let c = c.unwrap_or_else(|| panic!("{what}: unknown entity &{name};"));
                if in_text {
                    if let Some(last) = texts.last_mut() {
                        last.push(c);
                    }
                }
            }
            Ok(_) => {}
        }
    }
    assert_eq!(depth, 0, "{what}: {depth} elements left open");
    assert_eq!(roots, 1, "{what}: {roots} root elements");
    texts.iter().map(|t| t.trim().to_string()).collect()
}

/// The layout's promises: labels apart, off the legend and inset, on the canvas, drawn;
/// the legend's marker entries exactly the kinds drawn; a caption naming the mesh.
fn check_layout(layout: &Layout, texts: &[String], what: &str) {
    let canvas =
        memstab::output::Rect::at(0.0, 0.0, f64::from(layout.width), f64::from(layout.height));
    assert!(
        layout.dropped.is_empty(),
        "{what}: labels left out: {:?}",
        layout.dropped
    );
    for (i, a) in layout.labels.iter().enumerate() {
        assert!(canvas.holds(&a.rect), "{what}: {:?} off the canvas", a.text);
        for b in &layout.labels[..i] {
            assert!(
                !a.rect.overlaps(&b.rect),
                "{what}: labels {:?} {:?} and {:?} {:?} overlap",
                a.text,
                a.rect,
                b.text,
                b.rect
            );
        }
        if let Some(l) = layout.legend_box {
            assert!(!a.rect.overlaps(&l), "{what}: {:?} on the legend", a.text);
        }
        if let (Some(inset), false) = (layout.inset, a.in_inset) {
            assert!(
                !a.rect.overlaps(&inset),
                "{what}: {:?} on the inset",
                a.text
            );
        }
        assert!(
            texts.contains(&a.text),
            "{what}: the label {:?} is not drawn",
            a.text
        );
    }
    let mut drawn = layout.marker_kinds.clone();
    let mut shown = layout.legend_markers.clone();
    drawn.sort();
    shown.sort();
    assert_eq!(drawn, shown, "{what}: marker kinds drawn and in the legend");
    for k in &shown {
        assert!(
            layout.legend.contains(k) && texts.iter().any(|t| t == k),
            "{what}: no legend entry {k:?} in {:?}",
            layout.legend
        );
    }
    for entry in &layout.legend {
        assert!(
            texts.iter().any(|t| t == entry),
            "{what}: legend entry {entry:?} not drawn"
        );
    }
    assert!(
        layout.caption.contains("triangles") && texts.contains(&layout.caption),
        "{what}: caption {:?}",
        layout.caption
    );
}

/// Checks every SVG under `dir`; returns their layouts by file name.
fn check_all(dir: &Path) -> Vec<(String, Layout)> {
    let files = svgs(dir);
    assert!(!files.is_empty(), "no SVG in {}", dir.display());
    files
        .iter()
        .map(|f| {
            let what = f.display().to_string();
            let svg = std::fs::read_to_string(f).unwrap();
            let texts = well_formed(&svg, &what);
            let layout = read_layout(&svg).unwrap_or_else(|| panic!("{what}: no layout"));
            check_layout(&layout, &texts, &what);
            let name = f.strip_prefix(dir).unwrap().to_string_lossy().into_owned();
            (name, layout)
        })
        .collect()
}

#[test]
fn every_figure_of_the_bundled_scenes_is_well_formed_and_legible() {
    let root = tempfile::tempdir().unwrap();
    let mut checked = Vec::new();
    for scene in [
        "balloon.toml",
        "ponding.toml",
        "balloon_deflation.toml",
        "disc_fluid_above.toml",
        "disc_upward.toml",
        "thesis/paper1_disc_limit_curve_radius.toml",
        "thesis/paper1_disc_irregular_diagram.toml",
    ] {
        let dir = run(root.path(), scene);
        for (name, _) in check_all(&dir) {
            checked.push(format!("{scene}: {name}"));
        }
    }
    // The kinds of figure: a path, a spectrum, deflation's solutions, a critical curve, a
    // bifurcation diagram with its branches.
    for f in [
        "balloon.toml: path.svg",
        "ponding.toml: path.svg",
        "balloon_deflation.toml: deflation.svg",
        "thesis/paper1_disc_limit_curve_radius.toml: curve.svg",
        "thesis/paper1_disc_irregular_diagram.toml: diagram.svg",
    ] {
        assert!(checked.iter().any(|c| c == f), "{f} not in {checked:?}");
    }
}

#[test]
fn the_spinning_cap_zooms_on_its_critical_points_at_the_fold() {
    let root = tempfile::tempdir().unwrap();
    let dir = run(root.path(), "thesis/paper4_spinning_cap.toml");
    let layouts = check_all(&dir);
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
}

#[test]
fn the_critical_curve_and_the_surface_show_which_side_is_stable() {
    let root = tempfile::tempdir().unwrap();
    // The disc's path in h reaches the limit curve stable and turns back unstable: both of
    // its states next to the curve's first point are ringed and labelled with their index.
    let dir = run(root.path(), "thesis/paper1_disc_limit_curve_radius.toml");
    let layouts = check_all(&dir);
    let (_, curve) = layouts.iter().find(|(n, _)| n == "curve.svg").unwrap();
    for kind in [
        "state of the path in h: stable",
        "state of the path in h: unstable",
    ] {
        assert!(
            curve.legend_markers.iter().any(|k| k == kind),
            "{kind} not in {:?}",
            curve.legend_markers
        );
    }
    let labels: Vec<&str> = curve.labels.iter().map(|l| l.text.as_str()).collect();
    for text in ["stable (index 0)", "unstable (index 1)"] {
        assert!(labels.contains(&text), "{text} not in {labels:?}");
    }
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
    let dir = run(root.path(), "thesis/paper2_solution_surface_f8.toml");
    let layouts = check_all(&dir);
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
}
