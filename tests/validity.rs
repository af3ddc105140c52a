//! Validity flags end to end (docs/theory.md §8.10): a taut balloon's critical points are all
//! valid; Paper 3's gas-and-fluid cap pressed by its gas wrinkles before it loses stability,
//! and every critical point it finds is listed apart, flagged wrinkled, in the summary,
//! `critical.json` and `run --json`.

use std::process::Command;

fn run(scene: &str, dir: &std::path::Path, json: bool) -> (String, std::path::PathBuf) {
    let out = dir.join("out");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_memstab"));
    cmd.args(["run", scene, "--out"]).arg(&out).arg("--quiet");
    if json {
        cmd.arg("--json");
    }
    let o = cmd.output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    (String::from_utf8_lossy(&o.stdout).into_owned(), out)
}

fn critical(out: &std::path::Path) -> Vec<serde_json::Value> {
    serde_json::from_str(&std::fs::read_to_string(out.join("critical.json")).unwrap()).unwrap()
}

#[test]
fn a_taut_balloons_critical_points_are_valid() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/balloon.toml"))
        .unwrap()
        .replace("frequency = 8", "frequency = 4");
    let scene = dir.path().join("balloon.toml");
    std::fs::write(&scene, text).unwrap();
    let (summary, out) = run(scene.to_str().unwrap(), dir.path(), false);
    let points = critical(&out);
    assert_eq!(points.len(), 2, "{points:?}");
    assert!(points
        .iter()
        .all(|c| c["valid"] == true && c["flags"] == serde_json::json!([])));
    assert!(!summary.contains("flagged"), "{summary}");
}

#[test]
fn critical_points_in_a_wrinkled_state_are_listed_apart() {
    let dir = tempfile::tempdir().unwrap();
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/thesis/paper3_gas_fluid_pressure.toml"
    );
    let (json, out) = run(scene, dir.path(), true);
    let points = critical(&out);
    assert!(!points.is_empty());
    for c in &points {
        assert_eq!(c["valid"], false, "{c}");
        assert_eq!(c["flags"][0]["flag"], "wrinkled", "{c}");
        let (n, of) = (
            c["flags"][0]["triangles"].as_u64().unwrap(),
            c["flags"][0]["of"].as_u64().unwrap(),
        );
        assert!(n > 0 && n < of && of == 1152, "{c}");
        // The critical modes live where the membrane wrinkles: artefacts of the wrinkles.
        assert!(c["flags"][0]["mode"].as_f64().unwrap() > 0.9, "{c}");
    }
    let summary: serde_json::Value = serde_json::from_str(&json).unwrap();
    let listed = summary["critical"].as_array().unwrap();
    assert_eq!(listed.len(), points.len());
    assert!(listed.iter().all(|c| c["valid"] == false));
    // The summary lists them apart, with the reason.
    let again = dir.path().join("again");
    std::fs::create_dir(&again).unwrap();
    let (text, _) = run(scene, &again, false);
    assert!(text.contains("critical points: none valid"), "{text}");
    assert!(text.contains("critical points flagged"), "{text}");
    assert!(text.contains("point 1: wrinkled, "), "{text}");
}

/// `compare` matches only the valid points: the flagged ones are listed apart, unless
/// `--include-flagged`.
#[test]
fn compare_lists_flagged_points_apart_unless_asked() {
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/thesis/paper3_gas_fluid_pressure.toml"
    );
    let compare = |extra: &[&str]| -> serde_json::Value {
        let o = Command::new(env!("CARGO_BIN_EXE_memstab"))
            .args(["compare", scene, "--meshes", "C2v", "--json", "--quiet"])
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        serde_json::from_slice(&o.stdout).unwrap()
    };
    let apart = compare(&[]);
    let level = &apart["meshes"][0]["levels"][0];
    assert_eq!(level["critical"].as_array().unwrap().len(), 0, "{level}");
    let flagged = level["flagged"].as_array().unwrap();
    assert!(!flagged.is_empty());
    assert!(flagged.iter().all(|p| p["flags"][0]["flag"] == "wrinkled"));
    let included = compare(&["--include-flagged"]);
    let level = &included["meshes"][0]["levels"][0];
    assert_eq!(
        level["critical"].as_array().unwrap().len(),
        flagged.len(),
        "{level}"
    );
    assert!(level.get("flagged").is_none());
}

/// The bundled balloon at frequency 4 with `edits` (old, new) to its text, written into `dir`.
fn small_balloon(dir: &std::path::Path, edits: &[(&str, &str)]) -> std::path::PathBuf {
    let mut text =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/balloon.toml"))
            .unwrap()
            .replace("frequency = 8", "frequency = 4");
    for (old, new) in edits {
        assert!(text.contains(old), "{old}");
        text = text.replace(old, new);
    }
    let scene = dir.join("balloon.toml");
    std::fs::write(&scene, text).unwrap();
    scene
}

/// path.csv's `flags` column with the `stretch` measure of each row.
fn row_flags(out: &std::path::Path) -> Vec<(f64, String)> {
    let csv = std::fs::read_to_string(out.join("path.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(header.last(), Some(&"flags"), "{header:?}");
    let s = header.iter().position(|h| *h == "stretch").unwrap();
    lines
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            assert_eq!(cells.len(), header.len(), "{l}");
            (
                cells[s].parse().unwrap(),
                cells[cells.len() - 1].to_string(),
            )
        })
        .collect()
}

#[test]
fn a_clean_balloon_flags_no_row_and_no_turning_point() {
    let dir = tempfile::tempdir().unwrap();
    let scene = small_balloon(dir.path(), &[]);
    let (json, out) = run(scene.to_str().unwrap(), dir.path(), true);
    let rows = row_flags(&out);
    assert!(
        rows.len() > 10 && rows.iter().all(|(_, f)| f.is_empty()),
        "{rows:?}"
    );
    let json: serde_json::Value = serde_json::from_str(&json).unwrap();
    let turning = json["turning_points"].as_array().unwrap();
    assert_eq!(turning.len(), 2);
    assert!(turning
        .iter()
        .all(|t| t["valid"] == true && t["flags"] == serde_json::json!([])));
    let path: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("path.json")).unwrap()).unwrap();
    assert!(path["turning_points"]
        .as_array()
        .unwrap()
        .iter()
        .all(|t| t["valid"] == true));
    let svg = std::fs::read_to_string(out.join("path.svg")).unwrap();
    assert!(
        !svg.contains("flagged"),
        "a legend entry without flagged stretches"
    );
}

#[test]
fn a_stretch_beyond_the_materials_range_is_flagged_on_rows_and_points() {
    // The balloon passes its pressure maximum at λ = 1.476 and its minimum at 3.143: with
    // max-stretch = 3 the minimum (turning and critical) is flagged, the maximum is not, and
    // so are the rows past λ = 3.
    let dir = tempfile::tempdir().unwrap();
    let scene = small_balloon(
        dir.path(),
        &[("thickness = 0.01 ", "thickness = 0.01\nmax-stretch = 3.0 #")],
    );
    let (json, out) = run(scene.to_str().unwrap(), dir.path(), true);
    let json: serde_json::Value = serde_json::from_str(&json).unwrap();
    let points = critical(&out);
    assert_eq!(points.len(), 2, "{points:?}");
    assert_eq!(points[0]["valid"], true, "{}", points[0]);
    assert_eq!(points[1]["valid"], false, "{}", points[1]);
    let flag = &points[1]["flags"][0];
    assert_eq!(flag["flag"], "stretch", "{flag}");
    assert_eq!(flag["max"], 3.0);
    // The largest principal stretch of the nearly uniform sphere: its volume stretch, nearly.
    let largest = flag["stretch"].as_f64().unwrap();
    let volume_stretch = points[1]["measures"]["stretch"].as_f64().unwrap();
    assert!(
        largest >= volume_stretch && largest < 1.01 * volume_stretch,
        "{flag}"
    );
    let turning = json["turning_points"].as_array().unwrap();
    assert_eq!(turning[0]["valid"], true, "{}", turning[0]);
    assert_eq!(turning[1]["flags"][0]["flag"], "stretch", "{}", turning[1]);
    let rows = row_flags(&out);
    assert!(rows.iter().any(|(_, f)| f == "stretch"));
    for (s, f) in &rows {
        if *s < 2.9 {
            assert_eq!(f, "", "row at stretch {s}");
        } else if *s > 3.1 {
            assert_eq!(f, "stretch", "row at stretch {s}");
        }
    }
    let svg = std::fs::read_to_string(out.join("path.svg")).unwrap();
    assert!(svg.contains("flagged: stretch"), "no legend entry");
}

#[test]
fn a_bad_max_stretch_is_refused_naming_the_key() {
    // On a 3-D mesh and on a meridian alike.
    let dir = tempfile::tempdir().unwrap();
    let bad = "'material.max-stretch' must be a finite number > 1, got";
    for (scene, expect) in [
        (
            small_balloon(
                dir.path(),
                &[("thickness = 0.01 ", "thickness = 0.01\nmax-stretch = 0.5 #")],
            ),
            format!("{bad} 0.5"),
        ),
        (
            meridian_balloon(
                dir.path(),
                &[("thickness = 0.01", "thickness = 0.01\nmax-stretch = 1.0 #")],
            ),
            format!("{bad} 1"),
        ),
    ] {
        let out = dir.path().join("out");
        let o = Command::new(env!("CARGO_BIN_EXE_memstab"))
            .args([
                "run",
                scene.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2));
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(err.contains(&expect), "{err}");
        assert!(!out.exists());
    }
}

#[test]
fn a_contact_change_within_a_points_bracket_is_flagged() {
    use memstab::model::Model;
    use memstab::output::Drawing;
    use memstab::results::validity::Flag;
    use memstab::study::Study;
    // Paper 3's cap squeezed between the planes x = ±a (linear penalty) on a coarse mesh.
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/thesis/paper3_gas_fluid_squeeze_linear.toml"
    ))
    .unwrap()
    .replace("divisions = 12 ", "divisions = 8 #");
    let scene = memstab::scene::Scene::from_toml_str(&text, "squeeze").unwrap();
    let mut study = memstab::study::mesh::MeshStudy::build(scene).unwrap();
    let mut result = memstab::analysis::run(&mut study, |_, _| {}).unwrap();
    let report = &result.report;
    assert!(!report.critical.is_empty());
    // Every point localised in a step carries its bracket. At a smooth zero the contact does
    // not change within it: no flag. Where the eigenvalue jumps across zero instead, nodes
    // enter or leave contact between the jump's two states: both flags.
    for (k, cp) in report.critical.iter().enumerate() {
        let width = cp.bracket.as_ref().expect("a bracket").width;
        assert!(width > 0.0 && width <= 1.0, "{width}");
        let flags = report.flags(k);
        if cp.residual_eigenvalue <= memstab::results::validity::LOCALISED {
            assert!(flags.is_empty(), "{flags:?}");
        } else {
            assert!(
                flags
                    .iter()
                    .any(|f| matches!(f, Flag::ContactJump { nodes, .. } if *nodes > 0)),
                "{flags:?}"
            );
            assert!(
                flags.iter().any(|f| matches!(f, Flag::NotLocalised { .. })),
                "{flags:?}"
            );
        }
    }
    assert!(report
        .critical
        .iter()
        .any(|c| c.residual_eigenvalue <= memstab::results::validity::LOCALISED));
    // The nodes in contact at a state, computed here from the planes n·x ≥ d, n = ∓x̂.
    let d = report.parameters.iter().position(|p| p == "d").unwrap();
    let contact = |u: &[f64], params: &[f64]| -> Vec<bool> {
        let x = study.model.positions(u, params);
        x.iter().map(|x| x[0].abs() > -params[d]).collect()
    };
    let state = |i: usize| {
        let p = &result.points[i];
        (study.expand(&p.q), p.parameters.clone())
    };
    // A bracket from the start (the planes just touching) to a row well into the squeeze.
    let (a, b) = (state(0), state(40));
    let (ca, cb) = (contact(&a.0, &a.1), contact(&b.0, &b.1));
    let changed = ca.iter().zip(&cb).filter(|(x, y)| x != y).count();
    assert!(changed > 0);
    let cp = &mut result.report.critical[0];
    cp.bracket = Some(memstab::results::Bracket {
        width: 0.5,
        ends: [a, b],
    });
    // The deepest penetration at the point over the mean edge length there.
    let x = study.model.positions(&cp.state, &cp.parameters);
    let deepest = x
        .iter()
        .map(|x| (x[0].abs() + cp.parameters[d]).max(0.0))
        .fold(0.0, f64::max);
    let triangles = &Drawing::mesh(&study).triangles;
    let h = triangles
        .iter()
        .map(|&[i, j, k]| (x[j] - x[i]).norm() + (x[k] - x[j]).norm() + (x[i] - x[k]).norm())
        .sum::<f64>()
        / (3 * triangles.len()) as f64;
    assert!(deepest > 0.0);
    study.annotate(&mut result);
    let flags = result.report.flags(0);
    assert_eq!(flags.len(), 1, "{flags:?}");
    let Flag::ContactJump {
        nodes,
        penetration,
        bracket,
    } = flags[0]
    else {
        panic!("{flags:?}")
    };
    assert_eq!(nodes, changed);
    assert!(
        (penetration - deepest / h).abs() <= 1e-9 * penetration,
        "{penetration}"
    );
    assert_eq!(bracket, 0.5);
    assert_eq!(flags[0].name(), "contact-jump");
    // The other smooth zeros keep no flag.
    for (k, cp) in result.report.critical.iter().enumerate().skip(1) {
        if cp.residual_eigenvalue <= memstab::results::validity::LOCALISED {
            assert!(
                result.report.flags(k).is_empty(),
                "{:?}",
                result.report.flags(k)
            );
        }
    }
}

#[test]
fn deflations_solutions_carry_their_states_flags() {
    // The three spheres that hold p = 1.25 (and a wrinkled one): with max-stretch = 2.5 the
    // largest is flagged, the stretch of each the rule's; the wrinkled one is flagged so.
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/balloon_deflation.toml"
    ))
    .unwrap()
    .replace("thickness = 0.01 ", "thickness = 0.01\nmax-stretch = 2.5 #");
    let scene = dir.path().join("deflation.toml");
    std::fs::write(&scene, text).unwrap();
    let (summary, out) = run(scene.to_str().unwrap(), dir.path(), false);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("deflation.json")).unwrap())
            .unwrap();
    let names: Vec<String> = json[0]["measures"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap().to_string())
        .collect();
    let s = names.iter().position(|n| n == "stretch").unwrap();
    let solutions = json[0]["solutions"].as_array().unwrap();
    assert!(solutions.len() >= 3, "{json}");
    let (mut beyond, mut wrinkled) = (0, 0);
    for sol in solutions {
        let stretch = sol["measures"][s].as_f64().unwrap();
        let flags: Vec<&str> = sol["flags"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| f["flag"].as_str().unwrap())
            .collect();
        assert_eq!(flags.contains(&"stretch"), stretch > 2.6, "{sol}");
        assert!(!(2.4..=2.6).contains(&stretch), "{sol}");
        let n = sol["wrinkled"].as_u64().unwrap();
        assert_eq!(flags.contains(&"wrinkled"), n > 0, "{sol}");
        beyond += usize::from(stretch > 2.6);
        wrinkled += usize::from(n > 0);
    }
    assert!(beyond >= 1 && wrinkled >= 1, "{json}");
    assert!(summary.contains("flagged: stretch"), "{summary}");
}

#[test]
fn a_critical_curves_events_carry_their_states_flags() {
    // The balloon's pressure maximum followed in (p, k) from k = 0.1 (λ = 1.48) to its cusp
    // (λ = 1.84) and on down to k = 0.05 (λ = 4.5): with max-stretch = 1.6 the start is
    // valid, the cusp and the end are flagged.
    let dir = tempfile::tempdir().unwrap();
    let text = crate::common::balloon_with_k(
        4,
        "[parameters.k]\nstart = 0.1\nmin = 0.05\nmax = 0.3\n\n[analysis]\ntype = \
         \"critical-curve\"\ncontrol = \"p\"\nsecond = \"k\"\nfrom = \"limit\"\nsteps = 120\n\
         path-steps = 400\nmax-step = 0.05\n\n",
    )
    .replace("thickness = 0.01 ", "thickness = 0.01\nmax-stretch = 1.6 #");
    let scene = dir.path().join("curve.toml");
    std::fs::write(&scene, text).unwrap();
    let (summary, out) = run(scene.to_str().unwrap(), dir.path(), false);
    let curve: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("curve.json")).unwrap()).unwrap();
    let names: Vec<&str> = curve["measures"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap())
        .collect();
    let s = names.iter().position(|n| *n == "stretch").unwrap();
    let events = curve["events"].as_array().unwrap();
    let kinds: Vec<&str> = events.iter().map(|e| e["kind"].as_str().unwrap()).collect();
    assert_eq!(kinds, ["start", "cusp", "end"], "{curve}");
    for e in events {
        let stretch = e["measures"][s].as_f64().unwrap();
        let flagged = e["flags"]
            .as_array()
            .unwrap()
            .iter()
            .any(|f| f["flag"] == "stretch");
        assert_eq!(flagged, stretch > 1.6, "{e}");
    }
    assert!(events[0]["flags"].as_array().unwrap().is_empty());
    assert!(events[1]["flags"][0]["stretch"].as_f64().unwrap() > 1.6);
    // critical.json's events say the same, with `valid`.
    let listed: Vec<serde_json::Value> = critical(&out)
        .into_iter()
        .filter(|c| c["curve"] == true)
        .collect();
    assert_eq!(listed.len(), 3);
    let valid: Vec<bool> = listed.iter().map(|e| e["valid"] == true).collect();
    assert_eq!(valid, [true, false, false]);
    assert!(
        summary.contains("cusp") && summary.contains("— flagged: stretch"),
        "{summary}"
    );
}

/// The bundled balloon's meridian (scenes/axisymmetric/balloon.toml) with `edits` (old, new).
fn meridian_balloon(dir: &std::path::Path, edits: &[(&str, &str)]) -> std::path::PathBuf {
    let mut text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/axisymmetric/balloon.toml"
    ))
    .unwrap();
    for (old, new) in edits {
        assert!(text.contains(old), "{old}");
        text = text.replacen(old, new, 1);
    }
    let path = dir.join("meridian.toml");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn a_meridians_stretch_beyond_the_materials_range_is_flagged_as_on_a_mesh() {
    // The meridian passes the pressure maximum at λ = 1.476 and the minimum at 3.143, as the
    // 3-D balloon does: with max-stretch = 3 the minimum (turning and critical) and the rows
    // past λ = 3 are flagged, the maximum is not; without it nothing is.
    let dir = tempfile::tempdir().unwrap();
    let clean = meridian_balloon(dir.path(), &[]);
    let (summary, out) = run(clean.to_str().unwrap(), dir.path(), false);
    assert!(critical(&out).iter().all(|c| c["valid"] == true));
    assert!(row_flags(&out).iter().all(|(_, f)| f.is_empty()));
    assert!(!summary.contains("flagged"), "{summary}");
    std::fs::remove_dir_all(&out).unwrap();
    let scene = meridian_balloon(
        dir.path(),
        &[("thickness = 0.01", "thickness = 0.01\nmax-stretch = 3.0 #")],
    );
    let (json, out) = run(scene.to_str().unwrap(), dir.path(), true);
    let json: serde_json::Value = serde_json::from_str(&json).unwrap();
    let points = critical(&out);
    assert_eq!(points.len(), 2, "{points:?}");
    assert_eq!(points[0]["valid"], true, "{}", points[0]);
    let flag = &points[1]["flags"][0];
    assert_eq!(flag["flag"], "stretch", "{}", points[1]);
    assert_eq!(flag["max"], 3.0);
    // The sphere's largest principal stretch over the quadrature points: its volume stretch,
    // to the meridian's small discretisation error.
    let largest = flag["stretch"].as_f64().unwrap();
    let volume_stretch = points[1]["measures"]["stretch"].as_f64().unwrap();
    assert!(
        (largest / volume_stretch - 1.0).abs() < 1e-3,
        "{largest} against {volume_stretch}"
    );
    let turning = json["turning_points"].as_array().unwrap();
    assert_eq!(turning[0]["valid"], true, "{}", turning[0]);
    assert_eq!(turning[1]["flags"][0]["flag"], "stretch", "{}", turning[1]);
    let rows = row_flags(&out);
    assert!(rows.iter().any(|(_, f)| f == "stretch"));
    for (s, f) in &rows {
        if *s < 2.99 {
            assert_eq!(f, "", "row at stretch {s}");
        } else if *s > 3.01 {
            assert_eq!(f, "stretch", "row at stretch {s}");
        }
    }
}

#[test]
fn a_contact_change_within_a_meridians_bracket_is_flagged_as_on_a_mesh() {
    use memstab::output::Drawing;
    use memstab::results::validity::Flag;
    use memstab::study::Study;
    // The clamped disc of scenes/axisymmetric/disc_gas.toml inflated by gas past its pressure
    // maximum until its top meets the plane z <= 1.8 (linear penalty).
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/axisymmetric/disc_gas.toml"
    ))
    .unwrap()
    .replacen(
        "[boundary]",
        "[[effect]]\ntype = \"plane\"\nnormal = [0.0, 0.0, -1.0]\noffset = -1.8\n\
         penalty = 1000.0\nexponent = 1\n\n[boundary]",
        1,
    );
    let scene = memstab::scene::Scene::from_toml_str(&text, "disc-under-a-plane").unwrap();
    let mut study = memstab::study::meridian::MeridianStudy::build(scene).unwrap();
    let mut result = memstab::analysis::run(&mut study, |_, _| {}).unwrap();
    // Every point localised in a step carries its bracket, and the model measures its
    // contact there.
    let checks = result.report.checks.clone().expect("the meridian's checks");
    assert_eq!(checks.critical.len(), result.report.critical.len());
    for (cp, check) in result.report.critical.iter().zip(&checks.critical) {
        assert!(cp.bracket.is_some() && check.contact.is_some(), "{check:?}");
    }
    // Where a ring enters or leaves contact, the linear penalty's stiffness jumps and with it
    // eigenvalues across zero: those crossings are points at the jump, flagged not-localised
    // and contact-jump, as on a 3-D mesh; the smooth zeros keep no flag.
    let mut jumps = 0;
    for (k, cp) in result.report.critical.iter().enumerate() {
        let flags: Vec<&str> = result.report.flags(k).iter().map(Flag::name).collect();
        if cp.residual_eigenvalue <= memstab::results::validity::LOCALISED {
            assert!(flags.is_empty(), "{flags:?}");
        } else {
            assert_eq!(flags, ["not-localised", "contact-jump"]);
            jumps += 1;
        }
    }
    assert!(jumps >= 2, "{jumps} jumps");
    // The nodes in contact and their penetration, computed here from z <= 1.8.
    let depth = |u: &[f64]| -> Vec<f64> {
        study
            .model
            .positions(u)
            .iter()
            .map(|x| (x[1] - 1.8).max(0.0))
            .collect()
    };
    let state = |i: usize| {
        let p = &result.points[i];
        (study.expand(&p.q), p.parameters.clone())
    };
    // A bracket across the top's first touch.
    let touching = |i: usize| depth(&state(i).0).iter().any(|&d| d > 0.0);
    let first = (0..result.points.len())
        .find(|&i| touching(i))
        .expect("the top meets the plane");
    let (a, b) = (state(first - 1), state(first));
    let changed = depth(&a.0)
        .iter()
        .zip(depth(&b.0))
        .filter(|(x, y)| (**x > 0.0) != (*y > 0.0))
        .count();
    assert!(changed > 0);
    // A point in contact, its bracket replaced by that one.
    let k = result
        .report
        .critical
        .iter()
        .position(|cp| depth(&cp.state).iter().any(|&d| d > 0.0))
        .expect("a critical point in contact");
    let cp = &mut result.report.critical[k];
    cp.bracket = Some(memstab::results::Bracket {
        width: 0.5,
        ends: [a, b],
    });
    let deepest = depth(&cp.state).into_iter().fold(0.0, f64::max);
    let x = study.model.positions(&cp.state);
    let h = x
        .windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum::<f64>()
        / (x.len() - 1) as f64;
    study.annotate(&mut result);
    let flags = result.report.flags(k);
    let jump = flags
        .iter()
        .find(|f| f.name() == "contact-jump")
        .unwrap_or_else(|| panic!("{flags:?}"));
    let Flag::ContactJump {
        nodes,
        penetration,
        bracket,
    } = jump
    else {
        unreachable!()
    };
    assert_eq!(*nodes, changed);
    assert!(
        (penetration - deepest / h).abs() <= 1e-9 * penetration,
        "{penetration} against {}",
        deepest / h
    );
    assert_eq!(*bracket, 0.5);
    // The balloon's meridian has no plane: no contact measured, no flag.
    let balloon = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/axisymmetric/balloon.toml"
    ))
    .unwrap();
    let scene = memstab::scene::Scene::from_toml_str(&balloon, "balloon").unwrap();
    let mut study = memstab::study::meridian::MeridianStudy::build(scene).unwrap();
    let result = memstab::analysis::run(&mut study, |_, _| {}).unwrap();
    let checks = result.report.checks.clone().unwrap();
    assert!(checks.critical.iter().all(|c| c.contact.is_none()));
    assert!((0..result.report.critical.len()).all(|k| result.report.flags(k).is_empty()));
}

#[test]
fn a_localised_points_bracket_is_the_localisations_own_not_the_steps() {
    // A localisation stops once the eigenvalue is within its tolerance, which its first
    // trial may meet; the bracket it reports (the not-localised flag's measure, the states
    // the contact-jump flag compares) must still be the states on either side of the zero
    // next to it, not the step's far end: on the 3-D balloon (the test function's Newton
    // route) and its meridian (localised to round-off), every point's bracket is a small
    // share of its step.
    let dir = tempfile::tempdir().unwrap();
    let solid =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/balloon.toml"))
            .unwrap()
            .replace("frequency = 8", "frequency = 4");
    let meridian = std::fs::read_to_string(meridian_balloon(dir.path(), &[])).unwrap();
    for text in [solid, meridian] {
        let scene = memstab::scene::Scene::from_toml_str(&text, "balloon").unwrap();
        let mut study = memstab::study::build(scene).unwrap();
        let result = memstab::analysis::run(&mut *study, |_, _| {}).unwrap();
        let critical = &result.report.critical;
        assert_eq!(critical.len(), 2, "{}", study.about().mesh.generator);
        for cp in critical {
            let bracket = cp.bracket.as_ref().expect("a bracket");
            assert!(
                bracket.width > 0.0 && bracket.width <= 1e-4,
                "{}: a bracket of {:e} of the step",
                study.about().mesh.generator,
                bracket.width
            );
        }
    }
}
