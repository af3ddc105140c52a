//! The output writers on a synthetic report (the closed-form Mooney-Rivlin balloon, k = 0.1,
//! with its pressure maximum and minimum as turning points) and a small icosphere: CSV, JSON,
//! SVG, VTU + PVD, and their errors.

use memstab::output::{
    default_axes, write_csv, write_diagram, write_diagram_with, write_json, Diagram, Marker,
    MarkerKind, OutputError, Progress, PvdTime, Segment, StateWriter,
};
use memstab::report::{MeshInfo, PathReport, PathRow, TurningRow};
use meshes::generators::{icosphere, IcosphereOptions};
use meshes::write::Fields;
use meshes::{Mesh, Vec3};
use std::fs;
use std::path::Path;

/// p R/(μH) of the Mooney-Rivlin sphere at stretch l.
fn pressure(k: f64, l: f64) -> f64 {
    2.0 / (1.0 + k) * (1.0 / l - l.powi(-7)) * (1.0 + k * l * l)
}

fn measures(l: f64) -> Vec<f64> {
    let v0 = 4.0 / 3.0 * std::f64::consts::PI;
    vec![v0 * l.powi(3), l, l - 1.0]
}

/// The balloon path for stretch 1 … 4 in 40 steps, with its two turning points; the first
/// rows carry awkward numbers (−0, subnormal, huge, 0.1 + 0.2) to test exactness.
fn report() -> PathReport {
    let k = 0.1;
    let mut rows: Vec<PathRow> = (0..=40)
        .map(|i| {
            let l = 1.0 + 3.0 * i as f64 / 40.0;
            PathRow {
                step: i,
                arclength: 0.1 * i as f64,
                parameters: vec![pressure(k, l), 9.81],
                measures: measures(l),
                iterations: 3 + i % 4,
                index: Some(usize::from(l > 1.476)),
            }
        })
        .collect();
    rows[0].parameters[0] = -0.0;
    rows[0].measures[2] = 5e-324;
    rows[1].measures[2] = 1.7e300;
    rows[2].arclength = 0.1 + 0.2;
    let turning = |kind: &str, after_step, l: f64, p: f64| TurningRow {
        kind: kind.to_string(),
        after_step,
        parameters: vec![p, 9.81],
        measures: measures(l),
    };
    PathReport {
        scene: "balloon".to_string(),
        origin: "scenes/balloon.toml".to_string(),
        version: "0.1.0".to_string(),
        mesh: MeshInfo {
            generator: "icosphere".to_string(),
            nodes: 12,
            elements: 20,
            group: "Ih".to_string(),
            order: 120,
        },
        group: "Ih".to_string(),
        group_order: 120,
        unknowns: 36,
        symmetric_unknowns: 1,
        control: "p".to_string(),
        parameters: vec!["p".to_string(), "g".to_string()],
        measures: vec![
            "volume".to_string(),
            "stretch".to_string(),
            "max_displacement".to_string(),
        ],
        rows,
        critical: Vec::new(),
        warnings: Vec::new(),
        stability_note: None,
        turning_points: vec![
            turning("maximum", 6, 1.4760699, 1.3551069),
            turning("minimum", 28, 3.1426213, 1.1487477),
        ],
        stop: "reached the bound stretch = 4".to_string(),
        saved: Vec::new(),
    }
}

fn tiny_mesh() -> Mesh {
    icosphere(&IcosphereOptions {
        radius: 1.0,
        frequency: 1,
    })
    .unwrap()
    .mesh
}

/// Names of the files in `dir`, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// The contents of the SVG's `<text>` elements, trimmed.
fn texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| {
            let body = &t[t.find('>')? + 1..];
            Some(body[..body.find("</text>")?].trim().to_string())
        })
        .collect()
}

#[test]
fn csv_has_the_header_and_exact_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let r = report();
    let path = write_csv(dir.path(), &r).unwrap();
    assert_eq!(path, dir.path().join("path.csv"));
    let text = fs::read_to_string(&path).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "step,arclength,p,g,volume,stretch,max_displacement,iterations"
    );
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), r.rows.len());
    for (line, row) in rows.iter().zip(&r.rows) {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells.len(), 8, "{line}");
        assert_eq!(cells[0].parse::<usize>().unwrap(), row.step);
        assert_eq!(cells[7].parse::<usize>().unwrap(), row.iterations);
        let numbers: Vec<f64> = cells[1..7].iter().map(|c| c.parse().unwrap()).collect();
        let expected: Vec<f64> = std::iter::once(row.arclength)
            .chain(row.parameters.iter().copied())
            .chain(row.measures.iter().copied())
            .collect();
        for (a, b) in numbers.iter().zip(&expected) {
            assert_eq!(a.to_bits(), b.to_bits(), "{line}: {a} vs {b}");
        }
    }
    assert!(rows[0].starts_with("0,0,-0,9.81,"), "{}", rows[0]);
    assert!(rows[2].starts_with("2,0.30000000000000004,"), "{}", rows[2]);
    assert!(rows[1].contains(",1.7e300,"), "{}", rows[1]);
}

#[test]
fn json_holds_the_whole_report() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_json(dir.path(), &report()).unwrap();
    let v: serde_json::Value = serde_json::from_str(&fs::read_to_string(path).unwrap()).unwrap();
    for key in [
        "scene",
        "origin",
        "version",
        "mesh",
        "group",
        "group_order",
        "unknowns",
        "symmetric_unknowns",
        "control",
        "parameters",
        "measures",
        "rows",
        "turning_points",
        "stop",
        "saved",
    ] {
        assert!(v.get(key).is_some(), "missing key {key}");
    }
    assert_eq!(v["mesh"]["group"], "Ih");
    assert_eq!(v["rows"].as_array().unwrap().len(), 41);
    assert_eq!(v["turning_points"][0]["kind"], "maximum");
    assert_eq!(v["turning_points"][1]["parameters"][0], 1.1487477);
    assert_eq!(v["rows"][0]["measures"][2].as_f64().unwrap(), 5e-324);
}

#[test]
fn svg_shows_the_path_and_labels_the_turning_points() {
    let dir = tempfile::tempdir().unwrap();
    let r = report();
    let (x, y) = default_axes(&r);
    assert_eq!((x.as_str(), y.as_str()), ("stretch", "p"));
    let path = write_diagram(dir.path(), &r, &x, &y).unwrap();
    assert_eq!(path, dir.path().join("path.svg"));
    let svg = fs::read_to_string(&path).unwrap();
    assert!(svg.starts_with("<svg"), "{}", &svg[..80]);
    assert!(svg.trim_end().ends_with("</svg>"));
    assert!(svg.contains("<polyline"));
    assert_eq!(svg.matches("<text").count(), svg.matches("</text>").count());
    let texts = texts(&svg);
    for text in [
        "max p = 1.3551",
        "min p = 1.1487",
        "balloon (group Ih)",
        "stretch",
        "p",
    ] {
        assert!(
            texts.iter().any(|t| t == text),
            "no text {text:?} in {texts:?}"
        );
    }
    assert_eq!(listing(dir.path()), ["path.svg"]);
}

#[test]
fn svg_takes_segments_and_markers() {
    let dir = tempfile::tempdir().unwrap();
    let r = report();
    let diagram = Diagram::new("volume", "p")
        .segments(vec![
            Segment {
                first: 0,
                last: 6,
                stable: true,
            },
            Segment {
                first: 6,
                last: 28,
                stable: false,
            },
            Segment {
                first: 28,
                last: 40,
                stable: true,
            },
        ])
        .markers(vec![Marker::at_row(
            &r,
            20,
            "bifurcation <D5d>",
            MarkerKind::Bifurcation,
        )
        .unwrap()])
        .file("stability.svg");
    let path = write_diagram_with(dir.path(), &r, &diagram).unwrap();
    let svg = fs::read_to_string(path).unwrap();
    for text in [
        "stable",
        "unstable",
        "bifurcation &lt;D5d&gt;",
        "max p = 1.3551",
    ] {
        assert!(svg.contains(text), "no {text:?} in the SVG");
    }

    let bad = Diagram::new("volume", "p").segments(vec![Segment {
        first: 30,
        last: 41,
        stable: true,
    }]);
    let err = write_diagram_with(dir.path(), &r, &bad).unwrap_err();
    assert!(err.to_string().contains("30..=41"), "{err}");
}

#[test]
fn svg_rejects_an_unknown_axis_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let err = write_diagram(dir.path(), &report(), "lambda", "p").unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("\"lambda\"") && msg.contains("path.svg"),
        "{msg}"
    );
    assert!(msg.contains("stretch"), "lists the names: {msg}");
    assert!(listing(dir.path()).is_empty());
}

#[test]
fn states_are_written_and_collected() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = tiny_mesh();
    let mut states = StateWriter::new(dir.path(), &mesh).unwrap();
    for (step, scale) in [(0usize, 1.0), (10, 1.5), (20, 2.0)] {
        let x: Vec<Vec3> = mesh.nodes.iter().map(|p| p * scale).collect();
        let w: Vec<f64> = x.iter().map(|p| p.norm()).collect();
        let saved = states
            .save(
                step,
                pressure(0.1, scale),
                &x,
                Fields::new().point_scalar("radius", w),
            )
            .unwrap();
        assert_eq!(saved.file, format!("state_{step:04}.vtu"));
    }
    let saved = states.finish().unwrap();
    assert_eq!(saved.len(), 3);
    assert_eq!(
        listing(dir.path()),
        [
            "path.pvd",
            "state_0000.vtu",
            "state_0010.vtu",
            "state_0020.vtu"
        ]
    );
    let pvd = fs::read_to_string(dir.path().join("path.pvd")).unwrap();
    for s in &saved {
        assert!(pvd.contains(&format!("file=\"{}\"", s.file)), "{pvd}");
    }
    assert!(pvd.contains("timestep=\"0\""), "{pvd}");
    let vtu = fs::read_to_string(dir.path().join("state_0010.vtu")).unwrap();
    assert!(vtu.contains("Name=\"displacement\"") && vtu.contains("Name=\"radius\""));
    assert!(vtu.contains("format=\"binary\""));
}

#[test]
fn states_can_be_timed_by_step() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = tiny_mesh();
    let mut states = StateWriter::new(dir.path(), &mesh)
        .unwrap()
        .with_time(PvdTime::Step);
    states.save(7, 1.25, &mesh.nodes, Fields::new()).unwrap();
    states.save(7, 1.5, &mesh.nodes, Fields::new()).unwrap();
    assert_eq!(states.saved().len(), 1, "saving a step again replaces it");
    states.finish().unwrap();
    let pvd = fs::read_to_string(dir.path().join("path.pvd")).unwrap();
    assert!(pvd.contains("timestep=\"7\" group=\"\" part=\"0\" file=\"state_0007.vtu\""));
}

#[test]
fn a_nan_state_is_refused_and_leaves_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = tiny_mesh();
    let mut states = StateWriter::new(dir.path(), &mesh).unwrap();
    let mut x = mesh.nodes.clone();
    x[5].y = f64::NAN;
    let err = states.save(3, 1.0, &x, Fields::new()).unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("state_0003.vtu") && msg.contains("node 5"),
        "{msg}"
    );
    assert!(matches!(err, OutputError::Invalid { .. }));

    let mut w = vec![0.0; mesh.nodes.len()];
    w[2] = f64::INFINITY;
    let err = states
        .save(4, 1.0, &mesh.nodes, Fields::new().point_scalar("w", w))
        .unwrap_err();
    assert!(err.to_string().contains("state_0004.vtu"), "{err}");
    assert!(err.to_string().contains("\"w\""), "{err}");
    let err = states
        .save(5, f64::NAN, &mesh.nodes, Fields::new())
        .unwrap_err();
    assert!(err.to_string().contains("control"), "{err}");
    assert!(listing(dir.path()).is_empty(), "{:?}", listing(dir.path()));
    assert!(states.saved().is_empty());
}

#[test]
fn a_nan_in_the_report_is_refused_and_keeps_the_old_file() {
    let dir = tempfile::tempdir().unwrap();
    let mut r = report();
    write_csv(dir.path(), &r).unwrap();
    let before = fs::read(dir.path().join("path.csv")).unwrap();
    r.rows[7].measures[0] = f64::NAN;
    for err in [
        write_csv(dir.path(), &r).unwrap_err(),
        write_json(dir.path(), &r).unwrap_err(),
        write_diagram(dir.path(), &r, "stretch", "p").unwrap_err(),
    ] {
        let msg = err.to_string();
        assert!(
            msg.contains("path row 7") && msg.contains("volume"),
            "{msg}"
        );
    }
    assert_eq!(fs::read(dir.path().join("path.csv")).unwrap(), before);
    assert_eq!(listing(dir.path()), ["path.csv"]);
}

#[test]
fn a_missing_directory_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("no-such-dir");
    let r = report();
    let errors = [
        write_csv(&missing, &r).unwrap_err(),
        write_json(&missing, &r).unwrap_err(),
        write_diagram(&missing, &r, "stretch", "p").unwrap_err(),
        StateWriter::new(&missing, &tiny_mesh()).unwrap_err(),
    ];
    for err in errors {
        assert!(matches!(err, OutputError::NoDirectory { .. }), "{err:?}");
        let msg = err.to_string();
        assert!(msg.contains("no-such-dir"), "{msg}");
        assert!(msg.contains("does not exist"), "{msg}");
    }
    assert!(!missing.exists());
}

#[test]
fn a_quiet_progress_bar_is_silent() {
    let bar = Progress::new(10, true);
    assert!(!bar.is_visible());
    bar.set(3, "p = 1.2");
    bar.finish("done");
}
