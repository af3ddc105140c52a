//! A finished run's saved points and collections: `spectrum RUN_DIR --point N` and
//! `export-matrix RUN_DIR --point N` analyse any path point from `path.states` — on the
//! balloon's unstable stretch between its pressure maximum and minimum the index reported is
//! the run's own index there; `spectrum --at` where no equilibrium is found suggests
//! `--point`; `events.pvd` lists the turning and critical states in path order, named with
//! their irrep; `path.csv` has the index of every point.

use crate::common::{memstab, text};
use serde_json::Value;
use std::path::Path;

/// The balloon at icosphere frequency 4 run through both turning points into `dir/out`.
fn balloon_run(dir: &Path) -> std::path::PathBuf {
    let scene = std::fs::read_to_string(format!(
        "{}/scenes/balloon.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
    .replace("frequency = 8", "frequency = 4");
    let file = dir.join("balloon4.toml");
    std::fs::write(&file, scene).unwrap();
    let out = dir.join("out");
    let o = memstab(&[
        "run",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}{}", text(&o.stdout), text(&o.stderr));
    out
}

#[test]
fn a_saved_unstable_point_reports_the_runs_index_and_exports_its_tangent() {
    let tmp = tempfile::tempdir().unwrap();
    let out = balloon_run(tmp.path());
    let json: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("path.json")).unwrap()).unwrap();
    let rows = json["rows"].as_array().unwrap();
    // The taut balloon wrinkles nowhere.
    assert_eq!(
        json["wrinkling"]["first"],
        Value::Null,
        "{}",
        json["wrinkling"]
    );
    assert_eq!(json["wrinkling"]["triangles"], 320);
    // path.csv's index column is the index of path.json's rows.
    let csv = std::fs::read_to_string(out.join("path.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let ic = header
        .iter()
        .position(|h| *h == "index")
        .expect("an index column");
    // Then a column per irrep block, `index_<irrep>` in the order of path.json's `irreps`,
    // each row's `negative` counts.
    let irreps: Vec<&str> = json["irreps"]
        .as_array()
        .expect("the blocks of the index")
        .iter()
        .map(|i| i.as_str().unwrap())
        .collect();
    assert!(irreps.len() > 1, "{irreps:?}");
    let columns: Vec<String> = irreps.iter().map(|i| format!("index_{i}")).collect();
    // And last the flags of each row's state.
    assert_eq!(header.last(), Some(&"flags"));
    assert_eq!(
        header[ic + 1..header.len() - 1],
        columns.iter().map(String::as_str).collect::<Vec<_>>()[..]
    );
    for (line, row) in lines.zip(rows) {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(
            cells[ic].parse::<u64>().ok(),
            row["index"].as_u64(),
            "{line}"
        );
        let negative: Vec<u64> = cells[ic + 1..cells.len() - 1]
            .iter()
            .map(|c| c.parse().unwrap())
            .collect();
        let recorded: Vec<u64> = row["negative"]
            .as_array()
            .unwrap()
            .iter()
            .map(|n| n.as_u64().unwrap())
            .collect();
        assert_eq!(negative, recorded, "{line}");
        assert_eq!(
            negative.iter().sum::<u64>() > 0,
            row["index"].as_u64() > Some(0)
        );
    }
    let unstable: Vec<usize> = (0..rows.len())
        .filter(|&k| rows[k]["index"].as_u64().is_some_and(|i| i > 0))
        .collect();
    assert!(!unstable.is_empty(), "the balloon has an unstable stretch");
    let n = unstable[unstable.len() / 2];
    let dir = out.to_str().unwrap();
    let o = memstab(&["spectrum", dir, "--point", &n.to_string(), "--json"]);
    assert!(o.status.success(), "{}{}", text(&o.stdout), text(&o.stderr));
    let s: Value = serde_json::from_str(text(&o.stdout).trim()).unwrap();
    assert_eq!(s["index"], rows[n]["index"], "{s}");
    assert!(s["index"].as_u64().unwrap() > 0);
    assert_eq!(s["point"], n);
    assert_eq!(s["run_index"], rows[n]["index"]);
    assert_eq!(s["parameters"]["p"], rows[n]["parameters"][0]);
    // A stable point too.
    let o = memstab(&["spectrum", dir, "--point", "0", "--json"]);
    let s: Value = serde_json::from_str(text(&o.stdout).trim()).unwrap();
    assert_eq!(s["index"], 0);
    // The text output says where the state comes from.
    let o = memstab(&["spectrum", dir, "--point", &n.to_string()]);
    let stdout = text(&o.stdout);
    assert!(
        stdout.contains(&format!("state: path point {n} of")),
        "{stdout}"
    );

    // export-matrix at the same point: the comment names the point's pressure.
    let k = tmp.path().join("K.mtx");
    let o = memstab(&[
        "export-matrix",
        dir,
        "--point",
        &n.to_string(),
        "--out",
        k.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let mtx = std::fs::read_to_string(&k).unwrap();
    let p = rows[n]["parameters"][0].as_f64().unwrap();
    assert!(
        mtx.lines().nth(1).unwrap().contains(&format!("p={p}")),
        "{}",
        &mtx[..200]
    );

    // Bad input: a point out of range, --at with --point, a directory that is no run.
    for (args, needle) in [
        (vec!["spectrum", dir, "--point", "100000"], "--point 100000"),
        (
            vec!["spectrum", dir, "--point", "1", "--at", "p=1"],
            "--at 'p=1'",
        ),
        (
            vec!["spectrum", tmp.path().to_str().unwrap(), "--point", "1"],
            "path.json",
        ),
    ] {
        let o = memstab(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", text(&o.stderr));
        let e = text(&o.stderr);
        assert!(e.contains(needle) && e.trim().lines().count() == 1, "{e}");
    }
}

#[test]
fn spectrum_at_a_pressure_without_a_nearby_equilibrium_suggests_a_saved_point() {
    let scene = format!("{}/scenes/balloon.toml", env!("CARGO_MANIFEST_DIR"));
    let o = memstab(&["spectrum", &scene, "--at", "p=1.5"]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o.stdout));
    let e = text(&o.stderr);
    assert!(
        e.contains("no equilibrium may exist") && e.contains("--point N"),
        "{e}"
    );
}

#[test]
fn events_pvd_lists_the_turning_and_critical_states_in_path_order() {
    let tmp = tempfile::tempdir().unwrap();
    let out = balloon_run(tmp.path());
    let pvd = std::fs::read_to_string(out.join("events.pvd")).unwrap();
    let entries: Vec<(String, String)> = pvd
        .lines()
        .filter(|l| l.starts_with("<DataSet"))
        .map(|l| {
            let attr = |key: &str| {
                let start = l.find(&format!("{key}=\"")).unwrap() + key.len() + 2;
                l[start..start + l[start..].find('"').unwrap()].to_string()
            };
            (attr("file"), attr("name"))
        })
        .collect();
    let json: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("path.json")).unwrap()).unwrap();
    let saved = json["saved"].as_array().unwrap();
    let beside: Vec<&Value> = saved
        .iter()
        .filter(|s| s["in_collection"] == false)
        .collect();
    assert_eq!(entries.len(), beside.len());
    assert_eq!(
        entries.len(),
        4,
        "two turning and two critical points: {pvd}"
    );
    // Path order: the steps never decrease.
    let step = |file: &str| {
        saved.iter().find(|s| s["file"] == file).unwrap()["step"]
            .as_u64()
            .unwrap()
    };
    assert!(
        entries.windows(2).all(|w| step(&w[0].0) <= step(&w[1].0)),
        "{pvd}"
    );
    for (file, name) in &entries {
        assert!(out.join(file).is_file(), "{file}");
        if file.starts_with("critical_") {
            assert!(name.ends_with("limit point in Ag"), "{name}");
        }
    }
}
