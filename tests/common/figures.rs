//! The checks every figure memstab writes must pass, shared by the tests that write them:
//! the SVG is well-formed XML with the `<svg>` root; its layout (written by the figure
//! builder into the SVG as `<metadata>`) has no two labels overlapping, none on the legend or
//! (outside it) on the inset, none off the canvas or left out, every label drawn as a
//! `<text>`, a label without a leader line nearer its own point than any other, a legend
//! entry for every marker kind and every keyed line kind drawn and none for a kind not drawn,
//! and a caption naming the mesh.
#![allow(dead_code)]

use memstab::output::{read_layout, Layout};
use std::path::{Path, PathBuf};

/// Every `.svg` under `dir`, sorted.
pub fn svgs(dir: &Path) -> Vec<PathBuf> {
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
pub fn well_formed(svg: &str, what: &str) -> Vec<String> {
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
pub fn check_layout(layout: &Layout, texts: &[String], what: &str) {
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
    // A label without a leader line is read as labelling the point nearest to it: that must
    // be its own (points closer than 4 pixels are drawn as one).
    let distance = |r: &memstab::output::Rect, p: (f64, f64)| {
        let n = (p.0.clamp(r.x0, r.x1), p.1.clamp(r.y0, r.y1));
        (n.0 - p.0).hypot(n.1 - p.1)
    };
    for a in layout.labels.iter().filter(|l| !l.leader) {
        let own = distance(&a.rect, a.at);
        for b in layout.labels.iter().filter(|b| b.in_inset == a.in_inset) {
            let apart = (b.at.0 - a.at.0).hypot(b.at.1 - a.at.1);
            assert!(
                apart < 4.0 || distance(&a.rect, b.at) > own + 2.0,
                "{what}: the label {:?} is as near the point of {:?} as its own, without a \
                 leader line",
                a.text,
                b.text
            );
        }
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
    // Keyed lines (what a line is, as its legend says): an entry for each kind drawn inside
    // the plot, none for a kind not drawn there.
    let mut drawn = layout.line_kinds.clone();
    let mut shown = layout.legend_lines.clone();
    drawn.sort();
    shown.sort();
    assert_eq!(drawn, shown, "{what}: keyed lines drawn and in the legend");
    for entry in &layout.legend {
        assert!(
            texts.iter().any(|t| t == entry),
            "{what}: legend entry {entry:?} not drawn"
        );
    }
    // (A sweep's figure gathers runs whose meshes may differ: its caption names each size.)
    assert!(
        (layout.caption.contains(" triangles") || layout.caption.contains(" elements"))
            && texts.contains(&layout.caption),
        "{what}: caption {:?}",
        layout.caption
    );
}

/// Checks every SVG under `dir`; returns their layouts by file name.
pub fn check_all(dir: &Path) -> Vec<(String, Layout)> {
    let files = svgs(dir);
    assert!(!files.is_empty(), "no SVG in {}", dir.display());
    files
        .iter()
        .map(|f| {
            let layout = check_svg(f);
            let name = f.strip_prefix(dir).unwrap().to_string_lossy().into_owned();
            (name, layout)
        })
        .collect()
}

/// Checks the SVG file `file` (well-formed, its layout legible); returns its layout.
pub fn check_svg(file: &Path) -> Layout {
    let what = file.display().to_string();
    let svg = std::fs::read_to_string(file).unwrap_or_else(|e| panic!("{what}: {e}"));
    let texts = well_formed(&svg, &what);
    let layout = read_layout(&svg).unwrap_or_else(|| panic!("{what}: no layout"));
    check_layout(&layout, &texts, &what);
    layout
}
