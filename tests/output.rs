//! The output writers on a synthetic report (the closed-form Mooney-Rivlin balloon, k = 0.1,
//! with its pressure maximum and minimum as turning points) and a small icosphere: CSV, JSON,
//! SVG, VTU + PVD, and their errors.

use memstab::output::{
    default_axes, write_csv, write_diagram, write_diagram_with, write_json, write_spectrum_diagram,
    Diagram, Marker, MarkerKind, OutputError, Progress, PvdTime, Segment, StateWriter, ZERO_LINE,
};
use memstab::results::{
    CriticalKind, CriticalPoint, Extremum, Isotropy, MeshInfo, PathReport, PathRow, Spectra,
    SpectrumIrrep, SpectrumRow, StopReason, TurningRow,
};
use meshes::generators::{icosphere, IcosphereOptions};
use meshes::write::Fields;
use meshes::{Mesh, Vec3};
use std::fs;
use std::path::Path;

use crate::common::figures::check_svg;
use crate::common::{polylines, texts};

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
                negative: Some(vec![usize::from(l > 1.476), 0]),
            }
        })
        .collect();
    rows[0].parameters[0] = -0.0;
    rows[0].measures[2] = 5e-324;
    rows[1].measures[2] = 1.7e300;
    rows[2].arclength = 0.1 + 0.2;
    let turning = |kind: Extremum, after_step, l: f64, p: f64| TurningRow {
        kind,
        after_step,
        parameters: vec![p, 9.81],
        measures: measures(l),
        corner: None,
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
            radius: None,
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
            turning(Extremum::Maximum, 6, 1.4760699, 1.3551069),
            turning(Extremum::Minimum, 28, 3.1426213, 1.1487477),
        ],
        stop: StopReason::Stretch { target: 4.0 },
        saved: Vec::new(),
        spectra: Spectra::default(),
        states: None,
        wrinkling: None,
        wave_numbers: Vec::new(),
        refinement: None,
        checks: None,
        irreps: vec!["Ag".to_string(), "Hg".to_string()],
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
        "step,arclength,p,g,volume,stretch,max_displacement,iterations,index,index_Ag,index_Hg,flags"
    );
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), r.rows.len());
    for (line, row) in rows.iter().zip(&r.rows) {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells.len(), 12, "{line}");
        // Nothing measured of the states: no flags.
        assert_eq!(cells[11], "", "{line}");
        assert_eq!(cells[0].parse::<usize>().unwrap(), row.step);
        assert_eq!(cells[7].parse::<usize>().unwrap(), row.iterations);
        assert_eq!(cells[8].parse::<usize>().ok(), row.index, "{line}");
        let negative: Vec<usize> = cells[9..11].iter().map(|c| c.parse().unwrap()).collect();
        assert_eq!(Some(negative), row.negative, "{line}");
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
    // Turning points by name, with the step before them, as critical.json has them.
    assert_eq!(v["turning_points"][1]["parameters"]["p"], 1.1487477);
    assert_eq!(v["turning_points"][1]["parameters"]["g"], 9.81);
    assert_eq!(v["turning_points"][1]["measures"]["stretch"], 3.1426213);
    assert_eq!(v["turning_points"][1]["step"], 28);
    assert!(v["turning_points"][1].get("after_step").is_none());
    assert_eq!(v["irreps"], serde_json::json!(["Ag", "Hg"]));
    assert_eq!(v["rows"][39]["negative"], serde_json::json!([1, 0]));
    assert_eq!(v["rows"][0]["measures"][2].as_f64().unwrap(), 5e-324);
}

#[test]
fn svg_shows_the_path_and_labels_the_turning_points() {
    let dir = tempfile::tempdir().unwrap();
    let r = report();
    let (x, y) = default_axes(&r);
    assert_eq!((x.as_str(), y.as_str()), ("stretch", "p"));
    let path = write_diagram(dir.path(), &r, &x, &y).unwrap();
    check_svg(&path);
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
    check_svg(&path);
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

/// A crowd of critical points at three points a few pixels apart, and three more apart: every label is
/// placed (none dropped), apart from the others, and the crowd's go into an inset.
#[test]
fn svg_zooms_on_a_crowd_of_critical_points() {
    let dir = tempfile::tempdir().unwrap();
    let r = report();
    let mut markers = Vec::new();
    // Rows 14 (twice, moved along the stretch by 0.03 and 0.06: a few pixels) and three
    // rows apart.
    for (row, moved, label) in [
        (14, 0.0, "simple B1 m = 1"),
        (14, 0.0, "simple A2 m = 2"),
        (14, 0.0, "double E1 m = 1"),
        (14, 0.03, "simple B2 m = 4"),
        (14, 0.03, "simple B1 m = 4"),
        (14, 0.06, "double E3 m = 3"),
        (24, 0.0, "simple A2 m = 6"),
        (33, 0.0, "double E2 m = 2"),
        (38, 0.0, "simple B1 m = 5"),
    ] {
        let mut m = Marker::at_row(&r, row, label, MarkerKind::Bifurcation).unwrap();
        m.measures[1] += moved;
        markers.push(m);
    }
    let diagram = Diagram::new("stretch", "p").markers(markers);
    let path = write_diagram_with(dir.path(), &r, &diagram).unwrap();
    let layout = check_svg(&path);
    let inset = layout.inset.expect("an inset");
    assert_eq!(layout.labels.len(), 9 + 2, "{:?}", layout.labels);
    for l in &layout.labels {
        let crowd = ["m = 1", "A2 m = 2", "m = 4", "m = 3"]
            .iter()
            .any(|t| l.text.ends_with(t));
        assert_eq!(l.in_inset, crowd, "{}", l.text);
        if crowd {
            assert!(inset.holds(&l.rect), "{} outside the inset", l.text);
        }
    }
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
            "events.pvd",
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
    let bar = Progress::new("p", Some((0.0, 2.0)), true);
    assert!(!bar.is_visible());
    bar.set(3, 1.2);
    bar.finish("done");
}

/// `#RRGGBB` of the zero line.
fn zero_colour() -> String {
    format!("#{:02X}{:02X}{:02X}", ZERO_LINE.0, ZERO_LINE.1, ZERO_LINE.2)
}

/// A linear-buckling sweep of ρ over [0, 10] in 20 steps on a held state: A1 crosses zero at
/// ρ = 2.5, E1 at 20/3, A2 stays positive and has no spectrum at rows 7–9, and B1 is a large
/// block without eigenvalues.
fn sweep() -> PathReport {
    let mut r = report();
    let n = 20;
    let rho = |i: usize| 10.0 * i as f64 / n as f64;
    r.scene = "sweep".to_string();
    r.control = "rho".to_string();
    r.parameters = vec!["rho".to_string()];
    r.measures = vec!["max_displacement".to_string()];
    r.turning_points.clear();
    r.rows = (0..=n)
        .map(|i| PathRow {
            step: i,
            arclength: rho(i),
            parameters: vec![rho(i)],
            measures: vec![0.0],
            iterations: 0,
            index: Some(usize::from(rho(i) > 2.5) + 2 * usize::from(rho(i) > 20.0 / 3.0)),
            negative: None,
        })
        .collect();
    let irrep = |name: &str, dim, size, eigenvalues| SpectrumIrrep {
        name: name.to_string(),
        dim,
        size,
        eigenvalues,
    };
    r.spectra = Spectra {
        irreps: vec![
            irrep("A1", 1, 40, true),
            irrep("A2", 1, 30, true),
            irrep("B1", 1, 2500, false),
            irrep("E1", 2, 70, true),
        ],
        rows: (0..=n)
            .map(|i| {
                let x = rho(i);
                let a1 = 0.01 - 0.004 * x;
                let e1 = 0.02 - 0.003 * x;
                let a2 = (!(7..=9).contains(&i)).then_some(0.05 - 0.001 * x);
                SpectrumRow {
                    step: i,
                    control: x,
                    scale: 3.5,
                    lowest: vec![Some(a1), a2, None, Some(e1)],
                    eigenvalues: vec![vec![a1], a2.into_iter().collect(), vec![], vec![e1]],
                    negative: vec![
                        Some(usize::from(a1 < 0.0)),
                        Some(0),
                        Some(0),
                        Some(usize::from(e1 < 0.0)),
                    ],
                }
            })
            .collect(),
    };
    let critical = |kind: CriticalKind, irrep: &str, dim, rho: f64| CriticalPoint {
        kind,
        irrep: irrep.to_string(),
        multiplicity: dim,
        parameters: vec![rho],
        measures: vec![0.0],
        after_step: (rho * 2.0).floor() as usize,
        residual_eigenvalue: 1e-13,
        isotropy: Isotropy {
            name: "C1v".to_string(),
            order: 2,
            elements: vec![0, 1],
        },
        mode: Vec::new(),
        state: Vec::new(),
        bracket: None,
    };
    r.critical = vec![
        critical(CriticalKind::SymmetricBifurcation, "A1", 1, 2.5),
        critical(CriticalKind::MultipleBifurcation(2), "E1", 2, 20.0 / 3.0),
    ];
    r
}

#[test]
fn spectrum_svg_draws_a_line_per_irrep_and_the_zero_line() {
    let dir = tempfile::tempdir().unwrap();
    let r = sweep();
    let path = write_spectrum_diagram(dir.path(), &r).unwrap();
    check_svg(&path);
    assert_eq!(path, dir.path().join("path.svg"));
    let svg = fs::read_to_string(&path).unwrap();
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    assert!(
        !svg.contains("NaN") && !svg.contains("inf"),
        "a non-finite number"
    );
    let texts = texts(&svg);
    for text in [
        "sweep (group Ih): lowest eigenvalue by irrep",
        "rho",
        "lowest eigenvalue / max|K_ij|",
        "A1 (×1)",
        "A2 (×1)",
        "E1 (×2)",
        "B1 (×1): not plotted (2500 columns, negative count only)",
        "symmetric A1",
        "double E1",
        "critical point",
    ] {
        assert!(
            texts.iter().any(|t| t == text),
            "no text {text:?} in {texts:?}"
        );
    }
    let lines = polylines(&svg);
    // The zero line: one horizontal line across the plot in its own colour.
    let zero: Vec<_> = lines.iter().filter(|l| l.0 == zero_colour()).collect();
    assert_eq!(zero.len(), 1, "{zero:?}");
    let zero = &zero[0].1;
    assert_eq!(zero.len(), 2);
    assert_eq!(zero[0].1, zero[1].1, "horizontal");
    let y0 = zero[0].1;
    // A1 and E1 are one line of 21 samples each, crossing zero; A2 is broken into two runs
    // (rows 0–6 and 10–20) above zero; B1 has no line.
    let data: Vec<_> = lines
        .iter()
        .filter(|l| l.1.len() > 2 && l.0 != "#000000")
        .collect();
    let lengths: Vec<usize> = data.iter().map(|l| l.1.len()).collect();
    assert_eq!(lengths, [21, 7, 11, 21], "{data:?}");
    let crosses = |l: &[(i64, i64)]| {
        l.iter().any(|p| p.1 < y0) && l.iter().any(|p| p.1 > y0) // SVG y grows downwards
    };
    assert!(crosses(&data[0].1) && crosses(&data[3].1));
    assert!(data[1].1.iter().chain(&data[2].1).all(|p| p.1 < y0));
    assert_eq!(data[1].0, data[2].0, "A2's runs share a colour");
    let colours: std::collections::BTreeSet<&str> = data.iter().map(|l| l.0.as_str()).collect();
    assert_eq!(colours.len(), 3, "a colour per irrep: {colours:?}");
    assert_eq!(listing(dir.path()), ["path.svg"]);
}

#[test]
fn spectra_go_into_path_json_and_only_there_when_present() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_json(dir.path(), &report()).unwrap();
    let v: serde_json::Value = serde_json::from_str(&fs::read_to_string(&path).unwrap()).unwrap();
    assert!(v.get("spectra").is_none(), "a path report has no spectra");
    let r = sweep();
    write_json(dir.path(), &r).unwrap();
    let v: serde_json::Value = serde_json::from_str(&fs::read_to_string(&path).unwrap()).unwrap();
    let s = &v["spectra"];
    assert_eq!(s["irreps"][3]["name"], "E1");
    assert_eq!(s["irreps"][3]["dim"], 2);
    assert_eq!(s["irreps"][2]["eigenvalues"], false);
    let rows = s["rows"].as_array().unwrap();
    assert_eq!(rows.len(), r.rows.len());
    assert_eq!(rows[4]["control"], 2.0);
    assert_eq!(rows[4]["lowest"][0].as_f64().unwrap(), 0.01 - 0.004 * 2.0);
    assert!(rows[8]["lowest"][1].is_null());
    assert!(rows[8]["lowest"][2].is_null());
    assert_eq!(rows[20]["negative"][3], 1);
}

#[test]
fn spectrum_svg_refuses_a_nan_or_a_report_without_spectra() {
    let dir = tempfile::tempdir().unwrap();
    let err = write_spectrum_diagram(dir.path(), &report()).unwrap_err();
    assert!(err.to_string().contains("no spectra"), "{err}");
    let mut r = sweep();
    r.spectra.rows[3].lowest[3] = Some(f64::NAN);
    for err in [
        write_spectrum_diagram(dir.path(), &r).unwrap_err(),
        write_json(dir.path(), &r).unwrap_err(),
    ] {
        let msg = err.to_string();
        assert!(
            msg.contains("spectra row 3") && msg.contains("E1") && msg.contains("NaN"),
            "{msg}"
        );
    }
    let mut r = sweep();
    r.spectra.rows[5].lowest.pop();
    let err = write_spectrum_diagram(dir.path(), &r).unwrap_err();
    assert!(err.to_string().contains("spectra row 5"), "{err}");
    let mut r = sweep();
    r.critical[1].parameters[0] = f64::INFINITY;
    let err = write_spectrum_diagram(dir.path(), &r).unwrap_err();
    assert!(
        err.to_string().contains("double bifurcation in E1"),
        "{err}"
    );
    assert!(listing(dir.path()).is_empty(), "{:?}", listing(dir.path()));
}

/// The `<circle>`s of an SVG: (cx, cy, fill, stroke).
fn circles(svg: &str) -> Vec<(i64, i64, String, String)> {
    svg.split("<circle")
        .skip(1)
        .map(|c| {
            let attr = |name: &str| {
                let start = c.find(&format!(" {name}=\"")).unwrap() + name.len() + 3;
                c[start..start + c[start..].find('"').unwrap()].to_string()
            };
            (
                attr("cx").parse().unwrap(),
                attr("cy").parse().unwrap(),
                attr("fill"),
                attr("stroke"),
            )
        })
        .collect()
}

fn scene_file(name: &str) -> memstab::scene::Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name);
    memstab::scene::Scene::from_toml_str(&fs::read_to_string(&path).unwrap(), name).unwrap()
}

/// Drawn by index: a legend entry per index, each index in its own colour, and the path's
/// polyline passing through the turning and critical points where the index changes.
#[test]
fn svg_by_index_draws_each_index_and_switches_at_the_critical_point() {
    let dir = tempfile::tempdir().unwrap();
    let mut r = report();
    // Index 0 up to the maximum (after row 6), 1 up to a bifurcation between rows 28 and 29,
    // 2 after it.
    for row in &mut r.rows[29..] {
        row.index = Some(2);
    }
    let l = 1.0 + 3.0 * 28.5 / 40.0;
    let critical = Marker {
        parameters: vec![pressure(0.1, l), 9.81],
        measures: measures(l),
        label: "simple E1".to_string(),
        kind: MarkerKind::Other,
        after_step: Some(28),
        switches: true,
    };
    let mut max = Marker::turning(&r, &r.turning_points[0]);
    max.switches = true;
    let mut diagram = Diagram::new("stretch", "p")
        .markers(vec![max, critical])
        .by_index();
    diagram.turning_points = false;
    let path = write_diagram_with(dir.path(), &r, &diagram).unwrap();
    check_svg(&path);
    let svg = fs::read_to_string(path).unwrap();
    let texts = texts(&svg);
    for entry in ["index 0 (stable)", "index 1", "index 2"] {
        assert_eq!(
            texts.iter().filter(|t| *t == entry).count(),
            1,
            "{entry:?} once in {texts:?}"
        );
    }
    assert!(!texts.iter().any(|t| t == "index 3" || t == "stable"));
    let lines = polylines(&svg);
    let of = |colour: &str| -> Vec<&Vec<(i64, i64)>> {
        lines
            .iter()
            .filter(|l| l.0 == colour && l.1.len() >= 2)
            .map(|l| &l.1)
            .collect()
    };
    // Index 0: one solid blue line from the start to the maximum, ending on its marker (the
    // legend's sample is two short pieces of two points).
    let blue: Vec<_> = of("#1F57B4").into_iter().filter(|l| l.len() > 2).collect();
    assert_eq!(blue.len(), 1, "one stable run: {blue:?}");
    let circles = circles(&svg);
    let max_at = circles
        .iter()
        .find(|c| c.2 == "#C81E1E")
        .expect("the maximum's red disc");
    let near = |a: (i64, i64), b: (i64, i64)| (a.0 - b.0).abs() <= 1 && (a.1 - b.1).abs() <= 1;
    let end = *blue[0].last().unwrap();
    assert!(near(end, (max_at.0, max_at.1)), "{end:?} vs {max_at:?}");
    // Index 1 (red, dashed) starts at the maximum; index 2 (orange, dashed) at the
    // bifurcation's marker.
    let red = of("#C81E1E");
    assert!(red.len() > 3, "dashed");
    assert!(red.iter().any(|l| near(l[0], (max_at.0, max_at.1))));
    let cp = circles
        .iter()
        .find(|c| c.3 == "#000000")
        .expect("the bifurcation's circle");
    let orange = of("#E68200");
    assert!(orange.len() > 3, "dashed");
    let first = orange
        .iter()
        .map(|l| l[0])
        .min_by_key(|p| (p.0 - cp.0).abs() + (p.1 - cp.1).abs())
        .unwrap();
    assert!(
        near(first, (cp.0, cp.1)),
        "index 2 starts at {first:?}, the point is {cp:?}"
    );
    // The index-1 run reaches the critical point too: its pieces come within a dash of it.
    let reach = red
        .iter()
        .flat_map(|l| l.iter())
        .map(|p| (p.0 - cp.0).abs() + (p.1 - cp.1).abs())
        .min()
        .unwrap();
    assert!(
        reach <= 12,
        "index 1 stops {reach} px before the critical point"
    );
}

/// The axes in the scene's dimensionless groups, and the balloon's closed form under it.
#[test]
fn svg_axes_are_dimensionless_and_the_balloon_has_its_closed_form() {
    use memstab::output::{balloon_closed_form, Scales};
    let r = report();
    let balloon = scene_file("balloon.toml");
    let scales = Scales::of(&balloon, &r);
    let p = scales.get("p").expect("the gas pressure's scale");
    assert_eq!(p.label, "p R/(μH) (μH = 1, R = 1)");
    assert!((p.factor - 1.0).abs() < 1e-12);
    assert_eq!(
        scales.or_name("g").label,
        "g",
        "an unknown role keeps its name"
    );
    let v = scales.get("volume").unwrap();
    assert!(
        (v.factor * r.rows[0].measures[0] - 1.0).abs() < 1e-12,
        "V/V0"
    );
    assert!(v.label.starts_with("V/V0"));
    let ponding = scene_file("disc_fluid_above.toml");
    let rho = Scales::of_scene(&ponding, None);
    let rho = rho.get("rho").unwrap();
    assert_eq!(rho.label, "ρ g a²/(μH) (g = 1, μH = 1, a = 1)");
    assert!((rho.factor - 1.0).abs() < 1e-12);
    assert!(balloon_closed_form(&ponding, &r).is_none());

    let curve = balloon_closed_form(&balloon, &r).expect("a balloon");
    assert!(curve.label.contains("k = 0.1"), "{}", curve.label);
    for &(l, p) in &curve.points {
        assert!((p - pressure(0.1, l)).abs() < 1e-12);
    }
    assert!((curve.points[0].0 - 1.0).abs() < 1e-12);
    assert!((curve.points.last().unwrap().0 - 4.0).abs() < 1e-12);
    let dir = tempfile::tempdir().unwrap();
    let diagram = Diagram::new("stretch", "p")
        .scales(scales.or_name("stretch"), scales.or_name("p"))
        .reference(curve.clone())
        .by_index();
    let path = write_diagram_with(dir.path(), &r, &diagram).unwrap();
    check_svg(&path);
    let svg = fs::read_to_string(path).unwrap();
    let texts = texts(&svg);
    for text in [
        "p R/(μH) (μH = 1, R = 1)",
        "λ = (V/V_sf)^(1/3)",
        curve.label.as_str(),
    ] {
        assert!(texts.iter().any(|t| t == text), "no {text:?} in {texts:?}");
    }
    let grey: Vec<_> = polylines(&svg)
        .into_iter()
        .filter(|l| l.0 == "#6E6E6E" && l.1.len() == curve.points.len())
        .collect();
    assert_eq!(grey.len(), 1, "the closed form, thin and grey");
}

/// The later critical points of a block sit on its higher eigenvalues' dashed lines.
#[test]
fn spectrum_svg_draws_the_higher_eigenvalues_that_cross_zero() {
    let dir = tempfile::tempdir().unwrap();
    let mut r = sweep();
    // A1's second eigenvalue crosses zero at rho = 7.5; its third stays positive.
    for row in &mut r.spectra.rows {
        let x = row.control;
        let a1 = row.lowest[0].unwrap();
        row.eigenvalues[0] = vec![a1, 0.03 - 0.004 * x, 0.5 + 0.01 * x];
    }
    let path = write_spectrum_diagram(dir.path(), &r).unwrap();
    check_svg(&path);
    let svg = fs::read_to_string(path).unwrap();
    let texts = texts(&svg);
    assert!(
        texts
            .iter()
            .any(|t| t == "dashed: higher eigenvalues crossing zero"),
        "{texts:?}"
    );
    // A1's colour, thin: the dashes of its second eigenvalue, above zero before the
    // crossing and below it after.
    let a1 = "#1F77B4";
    let dashes: Vec<Vec<i64>> = svg
        .split("<polyline")
        .skip(1)
        .filter(|p| p.contains(&format!("stroke=\"{a1}\"")) && p.contains("stroke-width=\"1\""))
        .map(|p| {
            let start = p.find("points=\"").unwrap() + 8;
            p[start..start + p[start..].find('"').unwrap()]
                .split_whitespace()
                .map(|xy| xy.split_once(',').unwrap().1.parse().unwrap())
                .collect()
        })
        .collect();
    assert!(
        dashes.len() > 5,
        "dashes of the second eigenvalue: {}",
        dashes.len()
    );
    let y0 = polylines(&svg)
        .iter()
        .find(|l| l.0 == zero_colour())
        .unwrap()
        .1[0]
        .1;
    assert!(dashes.iter().flatten().any(|&y| y < y0 - 5));
    assert!(dashes.iter().flatten().any(|&y| y > y0 + 5));
    // Without the crossing one, no dashed lines and no legend entry.
    let r = sweep();
    write_spectrum_diagram(dir.path(), &r).unwrap();
    let svg = fs::read_to_string(dir.path().join("path.svg")).unwrap();
    assert!(!svg.contains("higher eigenvalues"));
}

/// Validity (docs/theory.md §8.10): a critical point in a wrinkled state and one whose
/// eigenvalue was not brought to round-off are flagged, with their measures, in
/// `critical.json`; a localised point in tension is valid. Under the relaxed energy a
/// wrinkled state raises no flag.
#[test]
fn critical_points_carry_their_validity_flags() {
    use memstab::results::validity::{Flag, LOCALISED};
    use memstab::results::{WrinkledCritical, Wrinkling};
    let point = |residual: f64| CriticalPoint {
        kind: CriticalKind::LimitPoint,
        irrep: "Ag".to_string(),
        multiplicity: 1,
        parameters: vec![1.3, 0.0],
        measures: vec![1.0, 1.4, 0.4],
        after_step: 5,
        residual_eigenvalue: residual,
        isotropy: Isotropy {
            name: "Ih".to_string(),
            order: 120,
            elements: Vec::new(),
        },
        mode: Vec::new(),
        state: Vec::new(),
        bracket: None,
    };
    let mut r = report();
    r.critical = vec![point(1e-13), point(1e-13), point(1e-5)];
    r.wrinkling = Some(Wrinkling {
        triangles: 20,
        first: None,
        critical: vec![WrinkledCritical {
            critical: 2,
            wrinkled: 7,
            mode: 0.25,
        }],
        relaxed: false,
        width: 0.0,
    });
    assert!(r.flags(0).is_empty());
    assert_eq!(
        r.flags(1),
        vec![Flag::Wrinkled {
            triangles: 7,
            of: 20,
            mode: Some(0.25)
        }]
    );
    assert_eq!(
        r.flags(2),
        vec![Flag::NotLocalised {
            residual: 1e-5,
            bracket: None
        }]
    );
    // A point localised in a step carries its last bracket's width.
    r.critical[2].bracket = Some(memstab::results::Bracket {
        width: 3e-4,
        ends: [(Vec::new(), Vec::new()), (Vec::new(), Vec::new())],
    });
    assert_eq!(
        r.flags(2),
        vec![Flag::NotLocalised {
            residual: 1e-5,
            bracket: Some(3e-4)
        }]
    );
    assert!(r.flags(2)[0]
        .to_string()
        .contains("in a bracket of 3e-4 of the step"));
    const { assert!(1e-13 < LOCALISED && LOCALISED < 1e-5) };
    let dir = tempfile::tempdir().unwrap();
    let path = memstab::output::write_critical(dir.path(), &r).unwrap();
    let json: serde_json::Value = serde_json::from_str(&fs::read_to_string(path).unwrap()).unwrap();
    assert_eq!(json[0]["valid"], true);
    assert_eq!(json[0]["flags"], serde_json::json!([]));
    assert_eq!(json[1]["valid"], false);
    assert_eq!(
        json[1]["flags"],
        serde_json::json!([{"flag": "wrinkled", "triangles": 7, "of": 20, "mode": 0.25}])
    );
    assert_eq!(json[2]["flags"][0]["flag"], "not-localised");
    assert_eq!(json[2]["flags"][0]["bracket"], 3e-4);
    // The relaxed energy describes wrinkled states: no flag.
    r.wrinkling.as_mut().unwrap().relaxed = true;
    assert!(r.flags(1).is_empty());
}
