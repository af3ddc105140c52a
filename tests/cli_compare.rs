//! `memstab compare`: the ponding scene on C8v, C2v and C1v discs — the m = 1 double of the
//! C8v disc (E1) appears on C2v as B1 + B2 and on C1v as A1 + A2, two simple points whose gap
//! is measured, and shrinks under `--refine`; the JSON form; bad mesh names (exit code 2).

use memstab::reference::PONDING_SCALE;
use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output};

fn memstab(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_memstab"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("the memstab binary runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn scene(name: &str) -> String {
    format!("{}/scenes/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// The ponding scene on 8 sectors of 6 divisions, the density swept over [0, 10.5] in 40
/// samples (past the m = 0, 1, 2 rungs), written into `dir`.
fn small_ponding(dir: &Path) -> String {
    let mut t = std::fs::read_to_string(scene("ponding.toml")).unwrap();
    for (a, b) in [
        ("sectors = 7 ", "sectors = 8 "),
        ("divisions = 16 ", "divisions = 6 "),
        ("max = 46.0 ", "max = 10.5 "),
        ("samples = 92", "samples = 40"),
    ] {
        assert!(t.contains(a), "ponding.toml contains {a:?}");
        t = t.replacen(a, b, 1);
    }
    let path = dir.join("ponding_small.toml");
    std::fs::write(&path, t).unwrap();
    path.display().to_string()
}

fn compare_json(args: &[&str]) -> Value {
    let mut all = vec!["compare"];
    all.extend_from_slice(args);
    all.push("--json");
    let out = memstab(&all);
    assert!(
        out.status.success(),
        "compare {args:?} failed ({:?}): {}{}",
        out.status.code(),
        text(&out.stdout),
        text(&out.stderr)
    );
    serde_json::from_str(text(&out.stdout).trim()).expect("one JSON object")
}

/// The rung of wave number m found on the reference's first run.
fn rung(json: &Value, m: u64) -> &Value {
    json["rungs"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["m"] == m)
        .unwrap_or_else(|| panic!("no rung m = {m} in {}", json["rungs"]))
}

/// The images of a rung on the mesh labelled `mesh`.
fn on<'a>(rung: &'a Value, mesh: &str) -> &'a Value {
    rung["images"]
        .as_array()
        .unwrap()
        .iter()
        .find(|i| i["mesh"] == mesh)
        .unwrap_or_else(|| panic!("no images on {mesh} in {rung}"))
}

fn strings(v: &Value) -> Vec<String> {
    let mut s: Vec<String> = v
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_str().unwrap().to_string())
        .collect();
    s.sort();
    s
}

#[test]
fn the_m1_double_splits_into_two_simple_points_on_c2v_and_c1v() {
    let dir = tempfile::tempdir().unwrap();
    let path = small_ponding(dir.path());
    let json = compare_json(&[&path, "--meshes", "C8v,C2v,C1v"]);
    assert_eq!(json["reference"], "C8v");
    assert_eq!(json["label"], "m");
    let groups: Vec<&str> = json["meshes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["levels"][0]["group"].as_str().unwrap())
        .collect();
    assert_eq!(groups, ["C8v", "C2v", "C1v"]);

    // m = 0: one simple point in A1 everywhere.
    let m0 = rung(&json, 0);
    assert_eq!(strings(&m0["irreps"]), ["A1"]);
    for mesh in ["C2v", "C1v"] {
        assert_eq!(strings(&on(m0, mesh)["levels"][0]["irreps"]), ["A1"]);
    }

    // m = 1: the E1 double on C8v (one point, multiplicity 2) ...
    let m1 = rung(&json, 1);
    assert_eq!(strings(&m1["irreps"]), ["E1"]);
    assert_eq!(m1["multiplicity"], 2);
    assert_eq!(m1["kind"], "double bifurcation");
    let reference = m1["values"][0].as_f64().unwrap();
    // ... close to the closed form gamma_{1,1} = 0.3599389 j_{1,1}^2 on this coarse mesh ...
    assert!((reference / (PONDING_SCALE * 14.681971) - 1.0).abs() < 0.05);
    // ... and two simple points with a measured, positive gap on C2v and C1v.
    for (mesh, pair) in [("C2v", ["B1", "B2"]), ("C1v", ["A1", "A2"])] {
        let image = &on(m1, mesh)["levels"][0];
        assert_eq!(strings(&image["irreps"]), pair, "{mesh}: {image}");
        assert_eq!(image["multiplicity"], 2);
        assert_eq!(image["split"], true, "{mesh}: {image}");
        let values: Vec<f64> = image["values"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let gap = image["gap"].as_f64().unwrap();
        assert!(gap > 0.0 && (gap - (values[1] - values[0]).abs()).abs() < 1e-12 * gap.max(1.0));
        assert!(gap < 0.05 * reference, "{mesh}: gap {gap}");
        for v in &values {
            assert!(
                (v / reference - 1.0).abs() < 0.02,
                "{mesh}: {v} vs {reference}"
            );
        }
    }
    assert_eq!(on(m1, "C8v")["levels"][0]["gap"], 0.0);

    // The table: a row per mesh, the C8v double not split, the others split.
    let out = memstab(&["compare", &path, "--meshes", "C8v,C2v,C1v"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let table = text(&out.stdout);
    assert!(
        table.contains("not split: double bifurcation in E1"),
        "{table}"
    );
    let split_rows = table
        .lines()
        .filter(|l| l.trim_end().ends_with("split") && !l.contains("not split"))
        .count();
    assert!(split_rows >= 2, "{table}");
    assert!(
        table.contains("B2 + B1") || table.contains("B1 + B2"),
        "{table}"
    );
}

/// The chiral C7 disc beside the C7v disc: every E_k rung is a double on both (one point of
/// multiplicity 2, not split), and m = 0 a simple point in A1 and A.
#[test]
fn a_chiral_mesh_compares_with_its_doubles_intact() {
    let dir = tempfile::tempdir().unwrap();
    let mut t = std::fs::read_to_string(scene("ponding.toml")).unwrap();
    for (a, b) in [
        ("divisions = 16 ", "divisions = 6 "),
        ("max = 46.0 ", "max = 10.5 "),
        ("samples = 92", "samples = 40"),
    ] {
        t = t.replacen(a, b, 1);
    }
    let path = dir.path().join("ponding_c7.toml");
    std::fs::write(&path, t).unwrap();
    let path = path.display().to_string();
    let json = compare_json(&[&path, "--meshes", "C7v,C7"]);
    assert_eq!(json["reference"], "C7v");
    let m0 = rung(&json, 0);
    assert_eq!(strings(&on(m0, "C7")["levels"][0]["irreps"]), ["A"]);
    for (m, irrep) in [(1, "E1"), (2, "E2")] {
        let r = rung(&json, m);
        assert_eq!(strings(&r["irreps"]), [irrep]);
        let image = &on(r, "C7")["levels"][0];
        assert_eq!(strings(&image["irreps"]), [irrep], "{image}");
        assert_eq!(image["multiplicity"], 2, "{image}");
        assert_eq!(image["gap"], 0.0, "{image}");
        assert_eq!(
            image["verdict"],
            format!("not split: double bifurcation in {irrep}"),
            "{image}"
        );
    }
}

#[test]
fn refine_shrinks_the_split_gaps() {
    // The bundled scene (7 sectors) with the options: the group names share 8 sectors.
    let json = compare_json(&[
        &scene("ponding.toml"),
        "--meshes",
        "C8v,C2v,C1v",
        "--divisions",
        "4",
        "--max",
        "10.5",
        "--samples",
        "21",
        "--refine",
    ]);
    assert_eq!(json["refine"], true);
    assert_eq!(json["samples"], 21);
    for m in json["meshes"].as_array().unwrap() {
        let levels = m["levels"].as_array().unwrap();
        assert_eq!(levels.len(), 2);
        assert_eq!(levels[0]["resolution"], 4);
        assert_eq!(levels[1]["resolution"], 8);
        assert!(levels[0]["mesh"]
            .as_str()
            .unwrap()
            .starts_with("disc sectors=8 divisions=4"));
    }
    let m1 = rung(&json, 1);
    assert_eq!(strings(&m1["irreps"]), ["E1"]);
    for (mesh, pair) in [("C2v", ["B1", "B2"]), ("C1v", ["A1", "A2"])] {
        let images = on(m1, mesh);
        let (coarse, fine) = (&images["levels"][0], &images["levels"][1]);
        assert_eq!(strings(&coarse["irreps"]), pair);
        assert_eq!(strings(&fine["irreps"]), pair);
        let (g1, g2) = (
            coarse["gap"].as_f64().unwrap(),
            fine["gap"].as_f64().unwrap(),
        );
        let order = images["order"].as_f64().expect("an observed order");
        assert!(
            g2 > 0.0 && g2 < g1 && order > 1.5,
            "{mesh}: gaps {g1:e} -> {g2:e}, order {order}"
        );
        assert!((order - (g1 / g2).log2()).abs() < 1e-9);
    }
    // The E1 double stays one point in E1 on the refined C8v disc.
    let fine = &on(m1, "C8v")["levels"][1];
    assert_eq!(strings(&fine["irreps"]), ["E1"]);
    assert_eq!(fine["multiplicity"], 2);
}

/// The meridian beside the C8v disc: every rung's continuum value is the axisymmetric
/// model's (the closed form γ = j²_{m,1} T0/(μHλ0²) to 1e-5 at 64 elements), the C8v
/// image's distance from it is the C8v mesh's own error against the closed form, and that
/// error falls as h² under `--refine` (6 → 12 divisions).
#[test]
fn the_meridian_gives_every_rung_its_continuum_value_and_distance() {
    let dir = tempfile::tempdir().unwrap();
    let path = small_ponding(dir.path());
    let json = compare_json(&[&path, "--meshes", "axisymmetric,C8v", "--refine"]);
    assert_eq!(json["reference"], "axisymmetric");
    assert_eq!(json["label"], "m");
    let meridian = &json["meshes"][0];
    assert_eq!(meridian["generator"], "axisymmetric");
    assert_eq!(meridian["levels"][0]["group"], "O(2)");
    // The scene's geometry carried over: the disc of radius 1.1.
    let options = meridian["levels"][0]["mesh"].as_str().unwrap();
    assert!(
        options.starts_with("axisymmetric shape=disc elements=64"),
        "{options}"
    );
    for (m, j2) in [(0u64, 5.783186), (1, 14.681971), (2, 26.374616)] {
        let exact = PONDING_SCALE * j2;
        let r = rung(&json, m);
        let continuum = r["continuum"].as_f64().unwrap();
        assert!(
            (continuum / exact - 1.0).abs() < 1e-5,
            "m = {m}: continuum {continuum} vs closed form {exact}"
        );
        let image = &on(r, "C8v")["levels"];
        let mut errors = Vec::new();
        for level in image.as_array().unwrap() {
            let v = level["values"][0].as_f64().unwrap();
            let d = level["distances"][0].as_f64().unwrap();
            assert!((d - (v - continuum)).abs() <= 1e-12 * v, "m = {m}: {level}");
            // The distance is the 3-D mesh's error, to the continuum's own error.
            let error = v - exact;
            assert!(
                (d - error).abs() <= 1e-5 * exact && d.abs() > 100.0 * (d - error).abs(),
                "m = {m}: distance {d} vs the mesh's error {error}"
            );
            errors.push(d.abs());
        }
        let order = r["orders"][0]["order"].as_f64().unwrap();
        assert_eq!(r["orders"][0]["group"], "C8v");
        assert!(
            (order - 2.0).abs() < 0.25,
            "m = {m}: distances {errors:?}, order {order}"
        );
    }
    // The table: the continuum row and each C8v row's distance.
    let out = memstab(&["compare", &path, "--meshes", "axisymmetric,C8v"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let table = text(&out.stdout);
    assert!(table.contains("distance"), "{table}");
    let continuum_rows = table.lines().filter(|l| l.contains("continuum")).count();
    assert_eq!(continuum_rows, 3, "{table}");
    // The same comparison as JSON: the table's distance is its value, printed. (The run
    // above refines, so its continuum is the finer meridian's.)
    let same = compare_json(&[&path, "--meshes", "axisymmetric,C8v"]);
    let m1 = rung(&same, 1);
    let d = m1["images"][1]["levels"][0]["distances"][0]
        .as_f64()
        .unwrap();
    let row = table
        .lines()
        .find(|l| l.contains("E1"))
        .unwrap_or_else(|| panic!("no E1 row in {table}"));
    assert!(row.contains(&memstab::text::sci(d)), "{row} lacks {d}");
}

/// The meridian's own error beside its continuum value: without `--refine`, its run at
/// twice the elements gives |value(2N) − value(N)|, the same as the two levels of `--refine`
/// give, which bounds its distance from the closed form and is far below the C8v distances at 64 elements (no warning); on a meridian of one
/// element it is not, and the table says so in one warning line.
#[test]
fn the_meridian_reports_its_own_error_and_warns_when_it_is_coarse() {
    let dir = tempfile::tempdir().unwrap();
    let path = small_ponding(dir.path());
    let json = compare_json(&[&path, "--meshes", "axisymmetric,C8v"]);
    assert!(json["meshes"][0]["check"].is_object(), "the check run");
    let refined = compare_json(&[&path, "--meshes", "axisymmetric,C8v", "--refine"]);
    assert!(
        refined["meshes"][0]["check"].is_null(),
        "no check run with --refine"
    );
    for (m, j2) in [(0u64, 5.783186), (1, 14.681971), (2, 26.374616)] {
        let exact = PONDING_SCALE * j2;
        let r = rung(&json, m);
        let continuum = r["continuum"].as_f64().unwrap();
        let own = r["continuum_error"].as_f64().unwrap();
        assert!(own > 0.0, "m = {m}");
        // The closed form is the model's to about 1e-6 (the level a hair above the rim,
        // j² to 7 digits).
        assert!(
            (continuum - exact).abs() <= 2.0 * own + 2e-6 * exact,
            "m = {m}: continuum {continuum}, closed form {exact}, own error {own:e}"
        );
        // With --refine the estimate is the one of the meridian's two levels: the same runs.
        let r2 = rung(&refined, m);
        let own2 = r2["continuum_error"].as_f64().unwrap();
        assert!(
            (own2 - own).abs() <= 1e-6 * own,
            "m = {m}: {own2:e} vs {own:e}"
        );
        let d = on(r, "C8v")["levels"][0]["distances"][0].as_f64().unwrap();
        assert!(own < 1e-3 * d.abs(), "m = {m}: {own:e} vs {d:e}");
        assert_eq!(r["continuum_coarse"], false, "m = {m}");
    }
    let out = memstab(&["compare", &path, "--meshes", "axisymmetric,C8v"]);
    let table = text(&out.stdout);
    assert!(table.contains("continuum ±"), "{table}");
    assert!(!table.contains("warning"), "{table}");
    let out = memstab(&["compare", &path, "--meshes", "axisymmetric:elements=1,C8v"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let table = text(&out.stdout);
    let warnings: Vec<&str> = table.lines().filter(|l| l.starts_with("warning")).collect();
    assert_eq!(warnings.len(), 1, "{table}");
    assert!(warnings[0].contains("meridian's own error"), "{table}");
}

/// The same `type = "spin"` on the meridian and on the C8v disc: the flat pre-stretched
/// clamped disc over spinning fluid, held while ω² sweeps. The C8v values approach the
/// meridian's at second order (6 → 12 divisions), so both discretise one continuum spin load.
#[test]
fn the_spin_on_the_meridian_is_the_continuum_of_the_3d_spin() {
    let dir = tempfile::tempdir().unwrap();
    let scene = r#"
[scene]
name = "spun-floor"

[mesh]
generator = "disc"
radius = 1.1
sectors = 8
divisions = 6

[material]
model = "mooney-rivlin"
mu = 100.0
k = 0.0
thickness = 0.01
prestretch = 1.1

[[effect]]
type = "spin"
density = 1.0
omega2 = "w2"

[boundary]
fixed = ["rim"]

[parameters.w2]
start = 0.0
min = 0.0
max = 22.0

[analysis]
type = "linear-buckling"
control = "w2"
samples = 22
"#;
    let path = dir.path().join("spun.toml");
    std::fs::write(&path, scene).unwrap();
    let path = path.display().to_string();
    let json = compare_json(&[&path, "--meshes", "axisymmetric,C8v", "--refine"]);
    for m in [0u64, 1] {
        let r = rung(&json, m);
        assert!(r["continuum"].as_f64().unwrap() > 0.0, "{r}");
        let d: Vec<f64> = on(r, "C8v")["levels"]
            .as_array()
            .unwrap()
            .iter()
            .map(|l| l["distances"][0].as_f64().unwrap())
            .collect();
        let order = r["orders"][0]["order"].as_f64().unwrap();
        assert!(
            d[0] > d[1] && d[1] > 0.0 && (order - 2.0).abs() < 0.25,
            "m = {m}: distances {d:?}, order {order}"
        );
    }
}

/// A scene whose effects the meridian lacks is refused before anything runs: a plane or a
/// sliding edge whose normal is not the axis.
#[test]
fn a_scene_the_meridian_cannot_run_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let cap = std::fs::read_to_string(scene("thesis/paper4_spinning_cap.toml")).unwrap();
    let tilted = cap.replacen(
        "normal = [0.0, 0.0, 1.0]\noffset = 0.0",
        "normal = [0.0, 0.6, 0.8]\noffset = 0.0",
        1,
    );
    assert_ne!(tilted, cap);
    let path = dir.path().join("tilted.toml");
    std::fs::write(&path, tilted).unwrap();
    let path = path.display().to_string();
    assert_rejected(
        &["compare", &path, "--meshes", "axisymmetric,C8v"],
        &["mesh 'axisymmetric'", "effect[2].normal"],
    );
    let mut t = std::fs::read_to_string(scene("disc_upward.toml")).unwrap();
    t.push_str(
        "\n[[effect]]\ntype = \"plane\"\nnormal = [1.0, 0.0, 0.0]\noffset = -1.0\npenalty = 1.0\n",
    );
    let path = dir.path().join("floored.toml");
    std::fs::write(&path, t).unwrap();
    let path = path.display().to_string();
    assert_rejected(
        &["compare", &path, "--meshes", "axisymmetric,C8v"],
        &["effect[1].normal"],
    );
    assert!(std::fs::read_dir(dir.path()).unwrap().count() == 2);
}

fn assert_rejected(args: &[&str], needles: &[&str]) {
    let out = memstab(args);
    assert_eq!(
        out.status.code(),
        Some(2),
        "{args:?}: {}{}",
        text(&out.stdout),
        text(&out.stderr)
    );
    let err = text(&out.stderr);
    assert_eq!(err.trim().lines().count(), 1, "one line: {err}");
    for n in needles {
        assert!(err.contains(n), "{args:?}: {err:?} lacks {n:?}");
    }
}

#[test]
fn bad_meshes_are_one_line_and_exit_code_2() {
    let ponding = scene("ponding.toml");
    // Not a subgroup of the disc's C8v.
    assert_rejected(
        &[
            "compare",
            &ponding,
            "--meshes",
            "C8v,disc:sectors=8,group=C5v",
        ],
        &["C5v", "mesh.group"],
    );
    assert_rejected(
        &["compare", &ponding, "--meshes", "C8v,disc:bogus=1"],
        &["bogus"],
    );
    assert_rejected(
        &["compare", &ponding, "--meshes", "C8v,divisions=3"],
        &["divisions=3"],
    );
    assert_rejected(
        &["compare", &ponding, "--meshes", "C8v,sphere:radius=1"],
        &["sphere"],
    );
    assert_rejected(
        &["compare", &ponding, "--meshes", "C8v", "--max", "-1"],
        &["--max"],
    );
    // An icosphere has no group option.
    assert_rejected(
        &["compare", &scene("demo.toml"), "--meshes", "C2v"],
        &["icosphere"],
    );
}

/// The spinning cap of Paper 4 (6 divisions) on C8v, C2v and C1v, from w2 = 0: on C1v the
/// free drift in x lies in the fixed-point space and is held at the start, so the run starts
/// there and finds its points. cos 2θ lies in the trivial irrep of C2v and C1v, so there the
/// m = 2 double of C8v is imperfect: each path folds near it, and that fold is the rung's
/// image; the points met after the turn are the image of nothing on the C8v path.
#[test]
fn the_spinning_cap_compares_on_c1v_from_rest() {
    let dir = tempfile::tempdir().unwrap();
    let t = std::fs::read_to_string(scene("thesis/paper4_spinning_cap.toml")).unwrap();
    assert!(t.contains("divisions = 12 "));
    let path = dir.path().join("paper4_small.toml");
    std::fs::write(&path, t.replacen("divisions = 12 ", "divisions = 6 ", 1)).unwrap();
    let path = path.display().to_string();
    let out = memstab(&["compare", &path, "--meshes", "C8v,C2v,C1v"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let table = text(&out.stdout);
    assert!(
        table.lines().any(|l| l.contains("C1v") && l.contains("A2")),
        "{table}"
    );
    let json = compare_json(&[&path, "--meshes", "C8v,C2v,C1v", "--quiet"]);
    let m2 = rung(&json, 2);
    let double = on(m2, "C8v")["levels"][0]["values"][0].as_f64().unwrap();
    for mesh in ["C2v", "C1v"] {
        let image = &on(m2, mesh)["levels"][0];
        let verdict = image["verdict"].as_str().unwrap();
        assert!(
            verdict.starts_with("imperfect: a limit point in A1"),
            "{mesh}: {image}"
        );
        let fold = image["values"][0].as_f64().unwrap();
        assert!(
            (fold - double).abs() < 0.05 * double,
            "{mesh}: {fold} vs {double}"
        );
        // Every point left over on the broken meshes is met after the turn, below the fold.
        let left: Vec<&Value> = json["unmatched"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|u| u["mesh"] == mesh)
            .collect();
        assert!(
            !left.is_empty(),
            "{mesh}: the path meets points on its way back"
        );
        for u in left {
            assert_eq!(u["rising"], false, "{mesh}: {u}");
            assert!(u["value"].as_f64().unwrap() < fold, "{mesh}: {u}");
        }
    }
}

/// The critical points (m, value) of a compare run's mesh `label`, in path order.
fn points_of(json: &Value, label: &str) -> Vec<(u64, f64)> {
    let mesh = json["meshes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| {
            let l = m["label"].as_str().unwrap_or("");
            l == label || l.starts_with(&format!("{label}:"))
        })
        .unwrap_or_else(|| panic!("mesh {label}"));
    mesh["levels"][0]["critical"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| (c["m"].as_u64().unwrap(), c["value"].as_f64().unwrap()))
        .collect()
}

/// The Paper 4 cap (filled fluid, spin, floor, sliding edge, fluid volume held) on the
/// meridian and on C8v at 8 and 12 divisions: the meridian finds the m = 2, 1, 3, 4 doubles
/// and the m = 0 fold in the order of the bundled C8v mesh, and the distances of the C8v
/// doubles before and at the pole's contact (m = 2, 1, 3) fall with an observed order near 2,
/// each C8v value at 12 divisions as far from the meridian as its own O(h²) error estimated
/// from the two levels.
#[test]
fn the_paper4_cap_on_the_meridian_is_the_continuum_of_the_c8v_cap() {
    let cap = scene("thesis/paper4_spinning_cap.toml");
    let meshes = "axisymmetric:elements=128,modes=5,C8v";
    let at = |d: &str| compare_json(&[&cap, "--meshes", meshes, "--divisions", d, "--quiet"]);
    let (j8, j12) = (at("8"), at("12"));
    let meridian = points_of(&j12, "axisymmetric");
    assert_eq!(points_of(&j8, "axisymmetric"), meridian);
    let order = |p: &[(u64, f64)]| {
        let mut o: Vec<u64> = p.iter().map(|x| x.0).collect();
        o.dedup();
        o
    };
    assert_eq!(order(&meridian), vec![2, 1, 3, 4, 0], "{meridian:?}");
    let c12 = points_of(&j12, "C8v");
    assert_eq!(order(&c12), vec![2, 1, 3, 4, 0], "{c12:?}");
    let c8 = points_of(&j8, "C8v");
    let first = |p: &[(u64, f64)], m: u64| p.iter().find(|x| x.0 == m).unwrap().1;
    for m in [2, 1, 3] {
        let c = first(&meridian, m);
        let (v8, v12) = (first(&c8, m), first(&c12, m));
        let (d8, d12) = (v8 - c, v12 - c);
        let p = (d8 / d12).ln() / 1.5f64.ln();
        // v_n = c + A/n²: the error at 12 divisions is (v8 − v12)/((12/8)² − 1).
        let own = (v8 - v12) / 1.25;
        eprintln!(
            "m = {m}: meridian {c:.5}, C8v {v8:.5} → {v12:.5}, order {p:.2}, own error {own:.4}"
        );
        assert!(d12 > 0.0 && d8 > d12, "m = {m}: {d8} → {d12}");
        assert!((1.7..2.3).contains(&p), "m = {m}: observed order {p}");
        assert!(
            (d12 - own).abs() < 0.15 * d12,
            "m = {m}: distance {d12} vs own error {own}"
        );
    }
}
