//! Smoke tests of `memstab bench --quick` and `memstab export-matrix` (no timing assertions:
//! the figures are for BENCHMARKS.md, never for tests).

use std::process::Command;

fn memstab() -> Command {
    Command::new(env!("CARGO_BIN_EXE_memstab"))
}

#[test]
fn quick_bench_writes_finite_tables_and_a_plot() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bench");
    let o = memstab()
        .args(["bench", "--quick", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "bench failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let md = std::fs::read_to_string(out.join("accuracy.md")).unwrap();
    for heading in [
        "## Balloon",
        "## Symmetry payoff on one tangent matrix",
        "## Symmetry payoff on a C8v tangent matrix",
        "## Stability along the path, with and without symmetry",
        "## Ponding ladder",
    ] {
        assert!(md.contains(heading), "accuracy.md lacks {heading}");
    }
    assert!(!md.contains("NaN") && !md.contains("inf"), "{md}");
    // The block eigenvalues agree with the dense ones, for Ih and for C8v.
    assert_eq!(md.matches("The multisets agree").count(), 2, "{md}");

    let csv = std::fs::read_to_string(out.join("accuracy.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 2, "quick mode: frequencies 4 and 8\n{csv}");
    for row in &rows {
        assert_eq!(row.len(), header.len());
        for (name, cell) in header.iter().zip(row) {
            if cell.is_empty() {
                continue; // order and Richardson columns of the first level
            }
            let v: f64 = cell.parse().unwrap_or_else(|_| panic!("{name} = {cell:?}"));
            assert!(v.is_finite(), "{name} = {v}");
        }
    }
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    // Errors shrink under refinement (second order is measured, not asserted here).
    let e4: f64 = rows[0][col("err_max")].parse().unwrap();
    let e8: f64 = rows[1][col("err_max")].parse().unwrap();
    assert!(e8 < e4 && e8 > 0.0, "{e4} -> {e8}");
    assert!(!rows[1][col("richardson_max")].is_empty());

    // Stability along the path without symmetry at both quick levels, dense at f = 4: the
    // index agrees with the one by blocks at every point (a check of correctness, not time).
    for (i, row) in rows.iter().enumerate() {
        let points: usize = row[col("stab_points")].parse().unwrap();
        assert_eq!(points, row[col("points")].parse::<usize>().unwrap());
        assert_eq!(row[col("index_mismatches")], "0", "row {i}\n{csv}");
        // The blocks' own pass over the same states finds the path's index again.
        assert_eq!(
            row[col("index_mismatches_blocks_pass")],
            "0",
            "row {i}\n{csv}"
        );
        assert_eq!(
            row[col("index_max")],
            "1",
            "past the pressure maximum\n{csv}"
        );
    }
    assert_eq!(rows[0][col("index_mismatches_dense")], "0", "{csv}");
    assert!(rows[1][col("index_mismatches_dense")].is_empty(), "{csv}");

    // One row per payoff case, the multisets agreeing to round-off.
    let payoff = std::fs::read_to_string(out.join("payoff.csv")).unwrap();
    let mut lines = payoff.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let cases: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(cases.len(), 2, "{payoff}");
    let pcol = |name: &str| header.iter().position(|h| *h == name).unwrap();
    assert_eq!(cases[0][pcol("group")], "Ih");
    assert_eq!(cases[1][pcol("group")], "C8v");
    for row in &cases {
        assert_eq!(row.len(), header.len(), "{payoff}");
        for (name, cell) in header.iter().zip(row).skip(2) {
            if cell.is_empty() {
                continue; // the peer's columns without scipy or for the disc
            }
            let v: f64 = cell.parse().unwrap_or_else(|_| panic!("{name} = {cell:?}"));
            assert!(v.is_finite() && v >= 0.0, "{name} = {v}");
        }
        let diff: f64 = row[pcol("dense_difference")].parse().unwrap();
        assert!(
            diff < 1e-10,
            "block vs dense eigenvalues differ by {diff:e}"
        );
    }

    crate::common::figures::check_svg(&out.join("accuracy.svg"));
    let svg = std::fs::read_to_string(out.join("accuracy.svg")).unwrap();
    assert!(
        svg.starts_with("<svg") && svg.contains("f=8"),
        "{}",
        &svg[..200.min(svg.len())]
    );
}

#[test]
fn export_matrix_writes_the_lower_triangle_of_the_pattern() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("K.mtx");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/demo.toml");
    let o = memstab()
        .args(["export-matrix", scene, "--at", "p=0.6", "--out"])
        .arg(&path)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "export-matrix failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "%%MatrixMarket matrix coordinate real symmetric"
    );
    let mut lines = lines.skip_while(|l| l.starts_with('%'));
    let size: Vec<usize> = lines
        .next()
        .unwrap()
        .split_whitespace()
        .map(|s| s.parse().unwrap())
        .collect();
    let (n, count) = (size[0], size[2]);
    assert_eq!(size[1], n);
    let mut entries = 0;
    for l in lines {
        let f: Vec<&str> = l.split_whitespace().collect();
        assert_eq!(f.len(), 3, "{l}");
        let (i, j): (usize, usize) = (f[0].parse().unwrap(), f[1].parse().unwrap());
        let v: f64 = f[2].parse().unwrap();
        assert!(i >= j && j >= 1 && i <= n && v.is_finite(), "{l}");
        entries += 1;
    }
    assert_eq!(entries, count);

    // The pattern's lower triangle, from the same scene built by the library.
    // A pressure-controlled balloon has no rank-one terms: no companion file, no mention.
    assert!(!dir.path().join("K.rank1.mtx").exists());
    assert!(!text.contains("rank-one file:"));

    let scene = memstab::scene::Scene::load(scene).unwrap();
    let study = memstab::study::mesh::MeshStudy::build(scene).unwrap();
    use memstab::model::Model;
    let pattern = study.model.pattern();
    assert_eq!(n, pattern.n());
    assert_eq!(count, (pattern.nnz() + pattern.n()) / 2);
}

#[test]
fn export_matrix_rejects_an_unknown_parameter() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("K.mtx");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/demo.toml");
    let o = memstab()
        .args(["export-matrix", scene, "--at", "nope=1", "--out"])
        .arg(&path)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("nope"));
    assert!(!path.exists());
}

#[test]
fn scaling_study_writes_times_memory_and_exponents() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("scaling");
    let o = memstab()
        .args([
            "bench",
            "--scaling",
            "2,4",
            "--scaling-points",
            "6",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "bench --scaling failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let md = std::fs::read_to_string(out.join("scaling.md")).unwrap();
    assert!(md.contains("## Scaling"), "{md}");
    assert!(md.contains("Growth exponents"), "{md}");
    assert!(
        !out.join("accuracy.md").exists(),
        "--scaling runs the scaling study only"
    );
    let csv = std::fs::read_to_string(out.join("scaling.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 2, "{csv}");
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    for row in &rows {
        assert_eq!(row.len(), header.len());
        assert_eq!(row[col("points")], "6", "{csv}");
        for name in [
            "total_s",
            "index_s",
            "stability_s",
            "points_per_s",
            "exponent_total",
        ] {
            let v: f64 = row[col(name)].parse().unwrap();
            assert!(v.is_finite(), "{name} = {v}");
        }
        // Peak memory where /proc/self/clear_refs exists (Linux), else empty ("n/a").
        let peak = row[col("peak_rss_mib")];
        if std::path::Path::new("/proc/self/clear_refs").exists() {
            assert!(peak.parse::<f64>().unwrap() > 0.0, "{csv}");
        }
    }
    assert_eq!(rows[0][col("frequency")], "2");
    assert_eq!(rows[1][col("frequency")], "4");
}

#[test]
fn bench_rejects_bad_flags_with_exit_code_2() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bad");
    for args in [
        vec!["--scaling", "0"],
        vec!["--scaling", "x"],
        vec!["--scaling", "4,,8"],
        vec!["--scaling", "4", "--quick"],
        vec!["--scaling", "4", "--frequencies", "8"],
        vec!["--scaling", "4", "--scaling-points", "1"],
        vec!["--scaling-points", "5"],
        vec!["--frequencies", "0"],
    ] {
        let o = memstab()
            .arg("bench")
            .args(&args)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
        assert!(!out.exists(), "{args:?} wrote {}", out.display());
    }
}

/// `memstab bench --thesis --quick` (the library call): the five meshes run (C1v twice, the
/// second time through its fold), every crossing is localised on every mesh (no warning), and
/// thesis.md is written.
#[test]
fn thesis_quick_runs_every_group() {
    let dir = tempfile::tempdir().unwrap();
    let options = memstab::bench::ThesisOptions {
        out: dir.path().to_path_buf(),
        quick: true,
    };
    let files = memstab::bench::run_thesis(&options, &mut |_| {}).unwrap();
    let md = std::fs::read_to_string(dir.path().join("thesis.md")).unwrap();
    assert_eq!(md, files.markdown);
    for group in ["C8v", "C4v", "C2v", "C1v", "C1"] {
        let row = md
            .lines()
            .find(|l| l.starts_with(&format!("| {group} |")))
            .unwrap_or_else(|| panic!("no row for {group}"));
        assert!(!row.contains("NaN"), "{row}");
    }
    let rows: Vec<&str> = md.lines().filter(|l| l.starts_with("| C")).collect();
    assert_eq!(rows.len(), 6, "{md}");
    // The bundled scenes are timed by the full study only.
    assert!(!md.contains("bundled thesis scenes"), "{md}");
    for row in rows {
        assert!(row.ends_with("| 0 |"), "{row}");
    }
}

/// A bundled thesis scene timed for `memstab bench --thesis`: its row counts what the run
/// found (the squeezed gas cap: C2v, no critical point) and its wall time.
#[test]
fn a_bundled_thesis_scene_is_timed_with_its_points_and_critical_points() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes/thesis/paper3_squeezed_cap.toml");
    let r = memstab::bench::thesis::scene_run(&path).unwrap();
    assert_eq!(
        (r.file.as_str(), r.group.as_str()),
        ("paper3_squeezed_cap.toml", "C2v")
    );
    assert_eq!((r.elements, r.critical, r.curve_points), (1152, 0, None));
    assert!(r.points > 10, "{r:?}");
    let md = memstab::bench::thesis::scenes_table(std::slice::from_ref(&r));
    let row = md.lines().find(|l| l.starts_with("| `paper3")).unwrap();
    let cells: Vec<&str> = row.split('|').map(str::trim).collect();
    assert_eq!(
        cells[2..7],
        ["C2v", "1152", &r.points.to_string(), "0", "–"]
    );
    let wall: f64 = cells[7].parse().unwrap();
    assert!((wall - r.wall.as_secs_f64()).abs() < 0.01, "{row}");
}
