//! The per-triangle fields of a state: on the uniformly inflated balloon the principal
//! tensions and thickness follow the closed forms T = μH (1 − λ⁻⁶)(1 + kλ²)/(1 + k) and
//! h = H/λ², nowhere wrinkled; a slack disc (pre-stretch below 1) is wrinkled everywhere;
//! and every state file carries the fields.

use memstab::model::{CellQuantity, Model};
use memstab::scene::Scene;
use memstab::study::mesh::{Measure, MeshStudy};
use std::path::Path;

fn scene_text(name: &str) -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes")
            .join(name),
    )
    .unwrap()
}

#[test]
fn the_balloon_tension_follows_the_closed_form_and_a_slack_disc_wrinkles() {
    let text = scene_text("balloon.toml").replace("frequency = 8", "frequency = 4");
    let mut study = MeshStudy::build(Scene::from_toml_str(&text, "balloon").unwrap()).unwrap();
    let start = study.start.clone();
    let (u, params) = (
        memstab::bench::solve_start(&mut study, &start).unwrap(),
        start.clone(),
    );
    let k = study
        .measures
        .iter()
        .position(|(_, m)| *m == Measure::Stretch)
        .unwrap();
    let lambda = study.measure(&u, &params)[k];
    let (mu, kk, h) = (100.0, 0.1, 0.01);
    let t = mu * h * (1.0 - lambda.powi(-6)) * (1.0 + kk * lambda * lambda) / (1.0 + kk);
    let fields = study.model.cell_fields(&u, &params);
    let get = |q: CellQuantity| &fields.iter().find(|f| f.quantity == q).unwrap().values;
    // A faceted sphere: each triangle's stretch is the sphere's to the mesh's O(h²) error.
    for v in get(CellQuantity::Tension1)
        .iter()
        .chain(get(CellQuantity::Tension2))
    {
        assert!((v / t - 1.0).abs() < 0.05, "{v} vs {t}");
    }
    let mean = get(CellQuantity::Thickness).iter().sum::<f64>()
        / get(CellQuantity::Thickness).len() as f64;
    assert!(
        (mean / (h / (lambda * lambda)) - 1.0).abs() < 0.02,
        "{mean}"
    );
    assert!(get(CellQuantity::Wrinkled).iter().all(|&w| w == 0.0));

    let slack = scene_text("disc_fluid_below.toml").replace("prestretch = 1.1", "prestretch = 0.9");
    assert!(slack.contains("prestretch = 0.9"));
    let study = MeshStudy::build(Scene::from_toml_str(&slack, "slack").unwrap()).unwrap();
    let u = vec![0.0; study.model.layout().unknowns()];
    let fields = study.model.cell_fields(&u, &study.start);
    let wrinkled = &fields
        .iter()
        .find(|f| f.quantity == CellQuantity::Wrinkled)
        .unwrap()
        .values;
    assert!(wrinkled.iter().all(|&w| w == 1.0));
}

#[test]
fn every_state_file_carries_the_fields() {
    let dir = tempfile::tempdir().unwrap();
    let text = scene_text("balloon.toml")
        .replace("frequency = 8", "frequency = 4")
        .replace("steps = 400", "steps = 3");
    let path = dir.path().join("b.toml");
    std::fs::write(&path, text).unwrap();
    let out = dir.path().join("out");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_memstab"))
        .args([
            "run",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let vtu = std::fs::read_to_string(out.join("state_0000.vtu")).unwrap();
    for q in [
        CellQuantity::Stretch1,
        CellQuantity::Stretch2,
        CellQuantity::Thickness,
        CellQuantity::Tension1,
        CellQuantity::Tension2,
        CellQuantity::Wrinkled,
    ] {
        assert!(
            vtu.contains(&format!("Name=\"{}\"", q.name())),
            "{}",
            q.name()
        );
    }
}

#[test]
fn the_node_fields_are_the_normal_and_the_pressure_of_the_loads() {
    use memstab::model::NodeQuantity;
    use memstab::output::Drawing;
    use memstab::results::{State, StateKind};
    // The balloon: the gas pressure p at every node, normals of unit length out of the sphere.
    let text = scene_text("balloon.toml").replace("frequency = 8", "frequency = 4");
    let mut study = MeshStudy::build(Scene::from_toml_str(&text, "balloon").unwrap()).unwrap();
    let start = study.start.clone();
    let (u, params) = (
        memstab::bench::solve_start(&mut study, &start).unwrap(),
        start.clone(),
    );
    let nodes = study.model.node_fields(&u, &params);
    assert_eq!(nodes.len(), 1);
    assert_eq!(nodes[0].quantity, NodeQuantity::Pressure);
    assert!(
        nodes[0].values.iter().all(|&v| v == params[0]),
        "{params:?}"
    );
    let x = study.model.positions(&u, &params);
    let normals = memstab::output::node_normals(&x, &study.mesh.mesh.triangles);
    for (n, xi) in normals.iter().zip(&x) {
        let n = nalgebra::Vector3::from(*n);
        assert!((n.norm() - 1.0).abs() < 1e-12);
        // On a sphere the vertex normal is the radial direction to the mesh's O(h²).
        assert!(n.dot(&xi.normalize()) > 0.99, "{n} at {xi}");
    }
    let (_, fields) = study.draw(&State {
        step: 0,
        kind: StateKind::Step,
        control: params[0],
        u: u.clone(),
        params: params.clone(),
        mode: None,
    });
    let names: Vec<&str> = fields.point.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["normal", "pressure"]);

    // Fluid below a flat disc with the level 0.5 above it: ρ g h = 0.5 per triangle, and at
    // the nodes +0.5 (the fluid pushes along the upward normal).
    let text = scene_text("disc_fluid_below.toml").replace("start = 0.0 ", "start = 0.5 ");
    assert!(text.contains("start = 0.5 "));
    let study = MeshStudy::build(Scene::from_toml_str(&text, "disc").unwrap()).unwrap();
    let u = vec![0.0; study.model.layout().unknowns()];
    let cells = study.model.cell_fields(&u, &study.start);
    let fluid = cells
        .iter()
        .find(|f| f.quantity == CellQuantity::FluidPressure)
        .unwrap();
    assert!(fluid.values.iter().all(|&v| (v - 0.5).abs() < 1e-15));
    let nodes = study.model.node_fields(&u, &study.start);
    assert!(nodes[0].values.iter().all(|&v| (v - 0.5).abs() < 1e-15));
    let x = study.model.positions(&u, &study.start);
    let normals = memstab::output::node_normals(&x, &study.mesh.mesh.triangles);
    assert!(normals.iter().all(|n| (n[2] - 1.0).abs() < 1e-12));
}

#[test]
fn a_slack_disc_run_reports_wrinkling_from_its_first_point() {
    let dir = tempfile::tempdir().unwrap();
    let text = scene_text("disc_fluid_below.toml")
        .replace("prestretch = 1.1", "prestretch = 0.9")
        .replace("divisions = 16", "divisions = 4")
        .replace("steps = 400", "steps = 3");
    assert!(text.contains("prestretch = 0.9") && text.contains("steps = 3"));
    let path = dir.path().join("slack.toml");
    std::fs::write(&path, text).unwrap();
    let out = dir.path().join("out");
    let run = |json: bool| {
        let mut args = vec![
            "run".to_string(),
            path.to_str().unwrap().to_string(),
            "--out".to_string(),
            out.to_str().unwrap().to_string(),
            "--quiet".to_string(),
        ];
        if json {
            args.push("--json".into());
        }
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_memstab"))
            .args(&args)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let summary = run(false);
    assert!(
        summary.contains("wrinkling: first at step 0 (112 of 112 triangles"),
        "{summary}"
    );
    let json: serde_json::Value = serde_json::from_str(run(true).trim()).unwrap();
    let w = &json["wrinkling"];
    assert_eq!(w["triangles"], 112, "{json}");
    assert_eq!(w["first"]["step"], 0);
    assert_eq!(w["first"]["wrinkled"], 112);
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("path.json")).unwrap()).unwrap();
    assert_eq!(&report["wrinkling"], w);
}

/// A critical point in a wrinkled state is flagged, with a warning that names it: a slack
/// disc (pre-stretch 0.9, every triangle wrinkled at rest) against the same disc taut.
#[test]
fn a_critical_point_in_a_wrinkled_state_is_warned_about() {
    use memstab::results::{CriticalKind, CriticalPoint, Isotropy, Wrinkling};
    let point = |study: &MeshStudy, kind| CriticalPoint {
        kind,
        irrep: "E1".to_string(),
        multiplicity: 2,
        parameters: study.start.clone(),
        measures: Vec::new(),
        after_step: 3,
        residual_eigenvalue: 1e-12,
        isotropy: Isotropy {
            name: "C1v".to_string(),
            order: 2,
            elements: vec![0, 1],
        },
        mode: Vec::new(),
        state: vec![0.0; study.model.layout().unknowns()],
        bracket: None,
    };
    let taut = scene_text("disc_fluid_below.toml");
    let slack = taut.replace("prestretch = 1.1", "prestretch = 0.9");
    assert_ne!(taut, slack);
    let taut = MeshStudy::build(Scene::from_toml_str(&taut, "taut").unwrap()).unwrap();
    let slack = MeshStudy::build(Scene::from_toml_str(&slack, "slack").unwrap()).unwrap();
    let triangles = slack.mesh.mesh.triangles.len();

    let taut_points = [point(&taut, CriticalKind::SimpleBifurcation)];
    assert!(taut.wrinkled_critical(&taut_points).is_empty());
    let slack_points = [
        point(&slack, CriticalKind::SimpleBifurcation),
        point(&slack, CriticalKind::MultipleBifurcation(2)),
    ];
    let flagged = slack.wrinkled_critical(&slack_points);
    assert_eq!(
        flagged
            .iter()
            .map(|c| (c.critical, c.wrinkled))
            .collect::<Vec<_>>(),
        [(1, triangles), (2, triangles)]
    );
    let w = Wrinkling {
        triangles,
        first: None,
        critical: flagged[1..].to_vec(),
        relaxed: false,
        width: 0.0,
    };
    let warnings = w.warnings(&slack_points);
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert_eq!(
        warnings[0],
        format!(
            "critical point 2 ({} in E1) lies in a wrinkled state ({triangles} of {triangles} \
             triangles): the membrane model does not describe it there",
            CriticalKind::MultipleBifurcation(2)
        )
    );
    // A number beyond the report's critical points gives no warning (and no panic).
    let stray = Wrinkling {
        triangles,
        first: None,
        critical: vec![memstab::results::WrinkledCritical {
            critical: 7,
            wrinkled: 1,
            mode: 0.5,
        }],
        relaxed: false,
        width: 0.0,
    };
    assert!(stray.warnings(&slack_points).is_empty());
}

/// A relaxed run writes the state of every triangle and the wrinkle direction into its state
/// files and the wrinkled and slack areas into `path.csv`; its summary reads the wrinkled
/// triangles as described by the energy. A plain run has none of these.
#[test]
fn a_relaxed_run_writes_states_directions_and_areas() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(format!(
        "{}/scenes/thesis/paper3_gas_fluid_pressure.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
    .replace(
        "prestretch = 1.05          # tension T(1.05) = 0.2562 mu H",
        "prestretch = 1.05\nwrinkling = \"relaxed\"",
    );
    assert!(text.contains("wrinkling = \"relaxed\""));
    let path = dir.path().join("cap.toml");
    std::fs::write(&path, text).unwrap();
    let out = dir.path().join("out");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_memstab"))
        .args([
            "run",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary = String::from_utf8_lossy(&o.stdout);
    assert!(
        summary.contains("wrinkled or slack, under the relaxed energy"),
        "{summary}"
    );
    assert!(!summary.contains("not valid"), "{summary}");
    let csv = std::fs::read_to_string(out.join("path.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let last: Vec<f64> = csv
        .lines()
        .last()
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap_or(f64::NAN))
        .collect();
    assert!(last[col("wrinkled_area")] > 1.0, "{csv}");
    assert!(last[col("slack_area")] >= 0.0);
    // The relaxed energy describes the wrinkled rows: none is flagged.
    assert_eq!(col("flags"), header.len() - 1);
    assert!(csv.lines().skip(1).all(|l| l.ends_with(',')), "{csv}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("path.json")).unwrap()).unwrap();
    assert_eq!(report["wrinkling"]["relaxed"], true);
    let last_state = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.starts_with("state_") && n.ends_with(".vtu"))
        .max()
        .unwrap();
    let vtu = std::fs::read_to_string(out.join(last_state)).unwrap();
    assert!(vtu.contains("Name=\"membrane_state\""));
    let at = vtu
        .find("Name=\"wrinkle_direction\"")
        .expect("the direction field");
    let tag = &vtu[vtu[..at].rfind('<').unwrap()..at + vtu[at..].find('>').unwrap()];
    assert!(tag.contains("NumberOfComponents=\"3\""), "{tag}");
    // The plain energy's state files are as before.
    let plain = dir.path().join("plain");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_memstab"))
        .args([
            "run",
            &format!("{}/scenes/balloon.toml", env!("CARGO_MANIFEST_DIR")),
            "--out",
            plain.to_str().unwrap(),
            "--quiet",
        ])
        .output()
        .unwrap();
    assert!(o.status.success());
    let vtu = std::fs::read_to_string(plain.join("state_0000.vtu")).unwrap();
    assert!(!vtu.contains("membrane_state") && !vtu.contains("wrinkle_direction"));
    let csv = std::fs::read_to_string(plain.join("path.csv")).unwrap();
    assert!(!csv.contains("wrinkled_area"));
}
