//! `memstab sweep` and `memstab collect`: a 3 × 3 grid over a material constant and the mesh
//! of a tiny disc run here (in parallel and one at a time, with the same table), re-run
//! without redoing anything, handed to the schedulers' scripts and run task by task; a sweep
//! interrupted from inside (the test hook `MEMSTAB_INTERRUPT_AFTER_STEPS`) resumed without
//! redoing its finished runs; failed, cut-short and edited runs listed by `collect`, not merged;
//! the ends of pairs of cusps of `cusp-curve` runs collected; bad sweep files refused with one
//! line naming the key and value, nothing written.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn memstab(args: &[&str], interrupt_after: Option<usize>) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_memstab"));
    cmd.args(args)
        .env_remove("MEMSTAB_INTERRUPT_AFTER_ITERATIONS")
        .env_remove("MEMSTAB_INTERRUPT_AFTER_BLOCKS");
    match interrupt_after {
        Some(k) => cmd.env("MEMSTAB_INTERRUPT_AFTER_STEPS", k.to_string()),
        None => cmd.env_remove("MEMSTAB_INTERRUPT_AFTER_STEPS"),
    };
    cmd.output().expect("the binary runs")
}

fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn scene(name: &str) -> String {
    format!("{}/scenes/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// The upward-loaded disc of the first paper without its branches: the base scene, written
/// into `dir`.
fn tiny_disc(dir: &Path) -> PathBuf {
    let full = std::fs::read_to_string(scene("disc_upward.toml")).unwrap();
    let cut = full.find("\n[analysis.branches]").unwrap();
    let path = dir.join("disc.toml");
    std::fs::write(&path, &full[..cut]).unwrap();
    path
}

/// A 3 × 3 sweep file over `material.k` and `mesh.divisions` of [`tiny_disc`].
fn grid_sweep(dir: &Path) -> PathBuf {
    tiny_disc(dir);
    let path = dir.join("grid.toml");
    std::fs::write(
        &path,
        "[sweep]\nscene = \"disc.toml\"\nname = \"disc-k\"\n\n[grid]\n\
         \"material.k\" = [0.0, 0.05, 0.1]\n\"mesh.divisions\" = [3, 4, 5]\n",
    )
    .unwrap();
    path
}

fn sweep(file: &Path, out: &Path, extra: &[&str], k: Option<usize>) -> Output {
    let mut args = vec![
        "sweep",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ];
    args.extend(extra);
    memstab(&args, k)
}

fn collect(dir: &Path) -> Output {
    memstab(&["collect", dir.to_str().unwrap()], None)
}

/// The CSV `file` as rows of cells (no quoted commas in the columns compared here).
fn csv(file: &Path) -> Vec<Vec<String>> {
    std::fs::read_to_string(file)
        .unwrap()
        .lines()
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

/// Every run directory's manifest lists every file in it, the scene and summary included, and
/// matches it.
fn assert_runs_verify(out: &Path, runs: usize) {
    for n in 1..=runs {
        let dir = out.join(format!("run_{n:04}"));
        let manifest = json(&dir.join("manifest.json"));
        let listed: Vec<&str> = manifest["files"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| f["file"].as_str().unwrap())
            .collect();
        for name in ["scene.toml", "summary.json", "path.json", "critical.json"] {
            assert!(listed.contains(&name), "{}: {listed:?}", dir.display());
        }
        let on_disk: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|f| f != "manifest.json")
            .collect();
        for f in &on_disk {
            assert!(
                listed.contains(&f.as_str()),
                "{f} not in the manifest of {}",
                dir.display()
            );
        }
        assert_eq!(
            memstab::output::verify(&dir, &listed),
            Ok(memstab::output::Verified::Listed)
        );
    }
}

/// Every row of `collected.csv` holds the value its run's own `critical.json` (or
/// `path.json`'s turning points) gives, and the run's swept values; the runs on the finer
/// discs have their E1 double point; returns the rows.
fn assert_table_matches_runs(out: &Path) -> Vec<Vec<String>> {
    let rows = csv(&out.join("collected.csv"));
    let header = &rows[0];
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    assert_eq!(
        &header[..4],
        ["task", "dir", "material.k", "mesh.divisions"]
    );
    let expected_k = ["0.0", "0.05", "0.1"];
    let expected_d = ["3", "4", "5"];
    let mut with_e1 = std::collections::BTreeSet::new();
    for row in &rows[1..] {
        let task: usize = row[col("task")].parse().unwrap();
        assert_eq!(row[col("dir")], format!("run_{task:04}"));
        assert_eq!(row[col("material.k")], expected_k[(task - 1) / 3]);
        assert_eq!(row[col("mesh.divisions")], expected_d[(task - 1) % 3]);
        let run = out.join(&row[col("dir")]);
        let scene = std::fs::read_to_string(run.join("scene.toml")).unwrap();
        assert!(scene.contains(&format!("k = {}", expected_k[(task - 1) / 3])));
        assert!(scene.contains(&format!("divisions = {}", expected_d[(task - 1) % 3])));
        let value: f64 = row[col("value")].parse().unwrap();
        let step: u64 = row[col("step")].parse().unwrap();
        let found = if row[col("point")] == "critical" {
            let critical = json(&run.join("critical.json"));
            critical.as_array().unwrap().iter().any(|c| {
                c["step"].as_u64() == Some(step)
                    && c["irrep"] == row[col("irrep")].as_str()
                    && c["parameters"]["h"].as_f64() == Some(value)
            })
        } else {
            let path = json(&run.join("path.json"));
            path["turning_points"].as_array().unwrap().iter().any(|t| {
                t["step"].as_u64() == Some(step)
                    && t["kind"] == row[col("kind")].as_str()
                    && t["parameters"]["h"].as_f64() == Some(value)
            })
        };
        assert!(found, "row {row:?} is not in its run's files");
        if row[col("irrep")] == "E1" && row[col("m")] == "1" {
            with_e1.insert(task);
        }
    }
    // On the coarsest disc the stiffest material's E1 point lies beyond the level's range.
    for task in [2, 3, 5, 6, 8, 9] {
        assert!(
            with_e1.contains(&task),
            "task {task} meets the E1 double point: {with_e1:?}"
        );
    }
    rows
}

#[test]
fn a_three_by_three_sweep_runs_here_resumes_and_collects() {
    let dir = tempfile::tempdir().unwrap();
    let file = grid_sweep(dir.path());
    let out = dir.path().join("two");
    let o = sweep(&file, &out, &["--jobs", "2"], None);
    let (stdout, stderr) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{stdout}{stderr}");
    assert!(stdout.contains("ran 9, skipped 0"), "{stdout}");
    assert_runs_verify(&out, 9);
    let tsv = std::fs::read_to_string(out.join("tasks.tsv")).unwrap();
    assert_eq!(tsv.lines().count(), 10, "{tsv}");
    assert!(tsv.starts_with("task\tdir\tmaterial.k\tmesh.divisions\n1\trun_0001\t0.0\t3\n"));

    // Again: nothing is redone, nothing rewritten.
    let before = std::fs::read(out.join("run_0005/manifest.json")).unwrap();
    let mtime = |p: &Path| std::fs::metadata(p).unwrap().modified().unwrap();
    let at = mtime(&out.join("run_0005/path.json"));
    let o = memstab(&["sweep", out.to_str().unwrap(), "--quiet"], None);
    let (stdout, _) = text(&o);
    assert_eq!(o.status.code(), Some(0));
    assert!(stdout.contains("ran 0, skipped 9"), "{stdout}");
    assert_eq!(
        std::fs::read(out.join("run_0005/manifest.json")).unwrap(),
        before
    );
    assert_eq!(mtime(&out.join("run_0005/path.json")), at);

    let o = collect(&out);
    let (stdout, stderr) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{stderr}");
    assert!(
        stdout.contains("9 runs: 9 finished, 0 failed, 0 cut short, 0 not run"),
        "{stdout}"
    );
    assert!(!stdout.contains("not merged"), "{stdout}");
    assert_table_matches_runs(&out);
    let layout = crate::common::figures::check_svg(&out.join("collected.svg"));
    let svg = std::fs::read_to_string(out.join("collected.svg")).unwrap();
    assert!(svg.contains("material.k") && svg.contains("E1, m = 1"));
    // The caption names the meshes the runs solved on: one disc at three sizes, the sizes
    // read from the runs' own path.json.
    let triangles: Vec<u64> = [1, 2, 3]
        .map(|t| {
            json(&out.join(format!("run_000{t}/path.json")))["mesh"]["elements"]
                .as_u64()
                .unwrap()
        })
        .to_vec();
    assert!(
        triangles[0] < triangles[1] && triangles[1] < triangles[2],
        "{triangles:?}"
    );
    let group = json(&out.join("run_0001/path.json"))["mesh"]["group"].clone();
    let meshes = format!(
        "meshes: disc, {} to {} triangles, group {}",
        triangles[0],
        triangles[2],
        group.as_str().unwrap()
    );
    assert!(layout.caption.ends_with(&meshes), "{:?}", layout.caption);

    // One at a time, in another directory: the same table.
    let one = dir.path().join("one");
    let o = sweep(&file, &one, &["--jobs", "1"], None);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o).1);
    assert_eq!(collect(&one).status.code(), Some(0));
    assert_eq!(
        std::fs::read(out.join("collected.csv")).unwrap(),
        std::fs::read(one.join("collected.csv")).unwrap()
    );

    // The schedulers' scripts, and a task run alone as they run it.
    let emitted = dir.path().join("emitted");
    let o = sweep(&file, &emitted, &["--emit", "snakemake"], None);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o).1);
    let snakefile = std::fs::read_to_string(emitted.join("Snakefile")).unwrap();
    assert_eq!(snakefile.matches("\"run_00").count(), 9, "{snakefile}");
    assert!(snakefile.contains("--task {params.task}"), "{snakefile}");
    assert!(
        !emitted.join("run_0001/path.json").exists(),
        "--emit runs nothing"
    );
    let o = memstab(
        &["sweep", emitted.to_str().unwrap(), "--emit", "slurm"],
        None,
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o).1);
    let slurm = std::fs::read_to_string(emitted.join("sweep.slurm")).unwrap();
    assert!(slurm.contains("#SBATCH --array=1-9"), "{slurm}");
    assert!(slurm.contains("--task \"$SLURM_ARRAY_TASK_ID\""), "{slurm}");
    let o = memstab(&["sweep", emitted.to_str().unwrap(), "--task", "5"], None);
    let (stdout, stderr) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{stderr}");
    assert!(
        stdout.starts_with("task 5 (run_0005: material.k = 0.05, mesh.divisions = 4): finished"),
        "{stdout}"
    );
    assert_eq!(
        std::fs::read(emitted.join("run_0005/critical.json")).unwrap(),
        std::fs::read(out.join("run_0005/critical.json")).unwrap()
    );
    let o = memstab(&["sweep", emitted.to_str().unwrap(), "--task", "5"], None);
    assert!(text(&o).0.contains("finished before, skipped"));
    let o = memstab(&["sweep", emitted.to_str().unwrap(), "--task", "10"], None);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).1.contains("--task 10: the sweep has tasks 1 to 9"));
}

#[test]
fn an_interrupted_sweep_resumes_without_redoing_its_finished_runs() {
    let dir = tempfile::tempdir().unwrap();
    let file = grid_sweep(dir.path());
    let out = dir.path().join("cut");
    // The first run (divisions 3, k = 0) takes fewer steps than this: the stop comes within
    // the second.
    let first_steps = {
        let probe = dir.path().join("probe");
        let o = sweep(&file, &probe, &["--task", "1"], None);
        assert_eq!(o.status.code(), Some(0), "{}", text(&o).1);
        json(&probe.join("run_0001/path.json"))["rows"]
            .as_array()
            .unwrap()
            .len()
    };
    let o = sweep(&file, &out, &["--jobs", "1"], Some(first_steps + 5));
    let (stdout, stderr) = text(&o);
    assert_eq!(o.status.code(), Some(130), "{stdout}{stderr}");
    assert!(
        stdout.contains("ran 1, skipped 0 (finished before), failed 0, stopped 8"),
        "{stdout}"
    );
    assert!(
        stderr.contains("interrupted: 8 of 9 tasks were stopped"),
        "{stderr}"
    );
    assert_eq!(
        json(&out.join("run_0002/manifest.json"))["stop"],
        "interrupted"
    );
    assert!(!out.join("run_0003/path.json").exists());

    let o = collect(&out);
    let (stdout, _) = text(&o);
    assert!(
        stdout.contains("9 runs: 1 finished, 0 failed, 1 cut short, 7 not run"),
        "{stdout}"
    );
    assert!(
        stdout.contains(
            "task 2 (run_0002: material.k = 0.0, mesh.divisions = 4) cut-short: interrupted"
        ),
        "{stdout}"
    );
    assert!(
        stdout.contains("task 9 (run_0009: material.k = 0.1, mesh.divisions = 5) not-run"),
        "{stdout}"
    );
    let rows = csv(&out.join("collected.csv"));
    assert!(
        rows[1..].iter().all(|r| r[0] == "1"),
        "only the finished run is merged"
    );

    let finished = std::fs::read(out.join("run_0001/manifest.json")).unwrap();
    let mtime = |p: &Path| std::fs::metadata(p).unwrap().modified().unwrap();
    let at = mtime(&out.join("run_0001/path.json"));
    let o = sweep(&file, &out, &["--jobs", "1"], None);
    let (stdout, stderr) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{stdout}{stderr}");
    assert!(stdout.contains("ran 8, skipped 1"), "{stdout}");
    assert_eq!(
        std::fs::read(out.join("run_0001/manifest.json")).unwrap(),
        finished
    );
    assert_eq!(mtime(&out.join("run_0001/path.json")), at);
    assert_ne!(
        json(&out.join("run_0002/manifest.json"))["stop"],
        "interrupted"
    );
    assert_runs_verify(&out, 9);
    assert_eq!(collect(&out).status.code(), Some(0));
    assert_table_matches_runs(&out);
}

#[test]
fn collect_lists_failed_and_edited_runs_without_merging_them() {
    let dir = tempfile::tempdir().unwrap();
    // The level far above the fold of the fluid-pushed disc: no equilibrium near that start.
    let file = dir.path().join("levels.toml");
    std::fs::write(
        &file,
        format!(
            "[sweep]\nscene = \"{}\"\n[grid]\n\"parameters.h.start\" = [0.0, 6.0]\n\
             [set]\n\"parameters.h.max\" = 7.0\n\"mesh.divisions\" = 6\n",
            scene("disc_fluid_below.toml")
        ),
    )
    .unwrap();
    let out = dir.path().join("levels");
    let o = sweep(&file, &out, &["--jobs", "2"], None);
    let (stdout, stderr) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{stdout}{stderr}");
    assert!(
        stdout.contains(
            "failed: task 2 (run_0002: parameters.h.start = 6.0): the start state did not converge"
        ),
        "{stdout}"
    );
    assert!(stderr.contains("1 of 2 tasks failed"), "{stderr}");
    assert!(json(&out.join("run_0002/failed.json"))["message"]
        .as_str()
        .unwrap()
        .contains("no equilibrium near the start"));

    let o = collect(&out);
    let (stdout, stderr) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{stderr}");
    assert!(stdout.contains("2 runs: 1 finished, 1 failed"), "{stdout}");
    assert!(
        stdout.contains(
            "task 2 (run_0002: parameters.h.start = 6.0) failed: the start state did not converge"
        ),
        "{stdout}"
    );
    let rows = csv(&out.join("collected.csv"));
    assert!(
        rows.len() > 1 && rows[1..].iter().all(|r| r[0] == "1"),
        "{rows:?}"
    );
    let runs = std::fs::read_to_string(out.join("collected_runs.csv")).unwrap();
    assert!(
        runs.lines()
            .nth(2)
            .unwrap()
            .starts_with("2,run_0002,6.0,failed,,"),
        "{runs}"
    );

    // A finished run's file edited afterwards: listed as cut short, naming the file; a
    // re-run of the sweep runs it again (and the failed one, which fails again).
    let summary = out.join("run_0001/summary.json");
    let edited = std::fs::read_to_string(&summary)
        .unwrap()
        .replace("\"points\"", "\"points\" ");
    std::fs::write(&summary, edited).unwrap();
    let (stdout, _) = text(&collect(&out));
    assert!(
        stdout.contains("2 runs: 0 finished, 1 failed, 1 cut short"),
        "{stdout}"
    );
    assert!(
        stdout.contains("summary.json: does not match its checksum"),
        "{stdout}"
    );
    assert_eq!(csv(&out.join("collected.csv")).len(), 1, "nothing merged");
    let o = memstab(&["sweep", out.to_str().unwrap(), "--quiet"], None);
    assert!(
        text(&o)
            .0
            .contains("ran 1, skipped 0 (finished before), failed 1"),
        "{}",
        text(&o).0
    );
    let (stdout, _) = text(&collect(&out));
    assert!(stdout.contains("2 runs: 1 finished, 1 failed"), "{stdout}");
}

#[test]
fn bad_sweep_files_are_refused_with_one_line_and_nothing_written() {
    let dir = tempfile::tempdir().unwrap();
    tiny_disc(dir.path());
    let out = dir.path().join("out");
    let cases: &[(&str, &[&str])] = &[
        (
            "[grid]\n\"material.kk\" = [0.1, 0.2]",
            &["grid 'material.kk' = 0.1", "unknown key 'material.kk'"],
        ),
        (
            "[grid]\n\"material.k\" = [0.1, -2.0]",
            &["grid 'material.k' = -2.0", "must be >= 0"],
        ),
        (
            "[grid]\n\"mesh.group\" = [\"C7v\", \"C5v\"]",
            &["grid 'mesh.group' = C5v", "not a subgroup of C7v"],
        ),
        (
            "[grid]\n\"material.k\" = 0.1",
            &["grid.material.k = 0.1", "a list of values"],
        ),
        ("[grid]\n\"material.k\" = []", &["grid.material.k = []"]),
        (
            "[grid]\n\"material.k\" = [0.1, 0.1]",
            &["grid.material.k", "0.1 is listed twice"],
        ),
        (
            "[grid]\n\"effect[3].density\" = [1.0]",
            &["'effect[3].density'", "has 1 entries"],
        ),
        (
            "[grid]\n\"material.k\" = [0.1]\n[set]\n\"analysis.steps\" = -3",
            &["set 'analysis.steps' = -3"],
        ),
        (
            "[grid]\n\"material.k\" = [0.1]\n[sweeep]\nx = 1",
            &["unknown section 'sweeep'"],
        ),
    ];
    for (body, needles) in cases {
        let file = dir.path().join("bad.toml");
        std::fs::write(&file, format!("[sweep]\nscene = \"disc.toml\"\n{body}\n")).unwrap();
        let o = sweep(&file, &out, &[], None);
        let (stdout, stderr) = text(&o);
        assert_eq!(o.status.code(), Some(2), "{body}: {stderr}");
        assert!(stdout.is_empty(), "{stdout}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
        assert!(stderr.contains("bad.toml"), "{stderr}");
        for n in *needles {
            assert!(stderr.contains(n), "{body}: {stderr:?} does not say {n}");
        }
        assert!(!out.exists(), "{body}: nothing is written");
    }
    // A directory that holds another sweep is refused too, and left as it was.
    let file = grid_sweep(dir.path());
    let o = sweep(&file, &out, &["--emit", "slurm"], None);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o).1);
    let other = dir.path().join("other.toml");
    std::fs::write(
        &other,
        "[sweep]\nscene = \"disc.toml\"\n[grid]\n\"material.k\" = [0.2]\n",
    )
    .unwrap();
    let before = std::fs::read(out.join("sweep.json")).unwrap();
    let o = sweep(&other, &out, &[], None);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).1.contains("holds another sweep"), "{}", text(&o).1);
    assert_eq!(std::fs::read(out.join("sweep.json")).unwrap(), before);
    // collect of a directory that is no sweep.
    let o = collect(dir.path());
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o).1.contains("not the directory of a memstab sweep"),
        "{}",
        text(&o).1
    );
}

#[test]
fn the_bundled_sweep_expands_into_its_tasks() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("k");
    let file = Path::new(&scene("sweeps/paper1_disc_k.toml")).to_path_buf();
    let o = sweep(&file, &out, &["--emit", "slurm"], None);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o).1);
    let tsv = std::fs::read_to_string(out.join("tasks.tsv")).unwrap();
    let ks: Vec<&str> = tsv
        .lines()
        .skip(1)
        .map(|l| l.split('\t').nth(2).unwrap())
        .collect();
    assert_eq!(ks, ["0.0", "0.025", "0.05", "0.075", "0.1"]);
    let scene = std::fs::read_to_string(out.join("run_0003/scene.toml")).unwrap();
    assert!(
        scene.contains("k = 0.05") && scene.contains("max = 4.9"),
        "{scene}"
    );
    assert!(std::fs::read_to_string(out.join("sweep.slurm"))
        .unwrap()
        .contains("--array=1-5"));
}

#[test]
fn collect_gathers_where_the_pairs_of_cusps_of_a_cusp_curve_run_end() {
    // The swallowtail of the disc pushed up by fluid from below, on two small meshes: each
    // run's pair of cusps ends between its slices in the fluid's density. The collected
    // table has a `cusp-end` row per end with its kind, the curve's irrep and the run's
    // estimate of where it ends (the value is the third parameter, named in the table's
    // `third`); the figure, drawn against the control, leaves them out. An edited
    // `cusp_curve.json` makes its run cut short, nothing of it merged.
    let dir = tempfile::tempdir().unwrap();
    let base = std::fs::read_to_string(scene("thesis/paper1_disc_swallowtail.toml")).unwrap();
    let cheap = [
        ("divisions = 8 ", "divisions = 3 "),
        ("range = [0.3, 0.55] ", "range = [0.4, 0.8] "),
        ("slices = 6\n", "slices = 5\n"),
        ("bisections = 4 ", "bisections = 1 "),
    ]
    .iter()
    .fold(base, |t, (a, b)| {
        assert!(t.contains(a), "{a}");
        t.replace(a, b)
    });
    std::fs::write(dir.path().join("disc.toml"), cheap).unwrap();
    let file = dir.path().join("cusps.toml");
    std::fs::write(
        &file,
        "[sweep]\nscene = \"disc.toml\"\nname = \"swallowtail\"\n\n[grid]\n\
         \"mesh.divisions\" = [3, 4]\n",
    )
    .unwrap();
    let out = dir.path().join("cusps");
    let o = sweep(&file, &out, &["--jobs", "2"], None);
    assert_eq!(o.status.code(), Some(0), "{:?}", text(&o));
    let o = collect(&out);
    let (stdout, stderr) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{stderr}");
    assert!(
        stdout.contains("and 2 ends of pairs of cusps (their value: rho)"),
        "{stdout}"
    );
    let rows = csv(&out.join("collected.csv"));
    let header = &rows[0];
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let ends: Vec<&Vec<String>> = rows[1..]
        .iter()
        .filter(|r| r[col("point")] == "cusp-end")
        .collect();
    assert_eq!(ends.len(), 2, "{rows:?}");
    for (n, row) in ends.iter().enumerate() {
        let task = n + 1;
        assert_eq!(row[col("task")], task.to_string());
        let report = json(&out.join(format!("run_{task:04}/cusp_curve.json")));
        let end = &report["ends"][0];
        assert_eq!(report["ends"].as_array().unwrap().len(), 1);
        assert_eq!(row[col("kind")], end["kind"].as_str().unwrap());
        assert_eq!(row[col("kind")], "swallowtail");
        assert_eq!(row[col("irrep")], report["irrep"].as_str().unwrap());
        assert_eq!(row[col("step")], "");
        let value: f64 = row[col("value")].parse().unwrap();
        assert_eq!(value, end["estimate"].as_f64().unwrap());
        let bracket = end["bracket"].as_array().unwrap();
        assert!(value >= bracket[0].as_f64().unwrap() && value <= bracket[1].as_f64().unwrap());
        assert_eq!(row[col("valid")], "true");
    }
    let o = memstab(&["collect", out.to_str().unwrap(), "--json"], None);
    let table = &serde_json::from_slice::<serde_json::Value>(&o.stdout).unwrap()["table"];
    assert_eq!(table["third"], "rho");
    assert_eq!(table["control"], "h");
    let svg = std::fs::read_to_string(out.join("collected.svg")).unwrap();
    assert!(svg.contains("A1, m = 0"), "the limit points are drawn");
    assert!(!svg.contains("cusp end"), "the ends are not");

    // Run 2's report edited: cut short, naming the file, and none of its rows merged.
    let report = out.join("run_0002/cusp_curve.json");
    let edited = std::fs::read_to_string(&report)
        .unwrap()
        .replacen("\"ends\"", "\"ends\" ", 1);
    std::fs::write(&report, edited).unwrap();
    let (stdout, _) = text(&collect(&out));
    assert!(
        stdout.contains("2 runs: 1 finished, 0 failed, 1 cut short"),
        "{stdout}"
    );
    assert!(
        stdout.contains("cusp_curve.json: does not match its checksum"),
        "{stdout}"
    );
    let rows = csv(&out.join("collected.csv"));
    assert!(rows[1..].iter().all(|r| r[0] == "1"), "{rows:?}");
    assert_eq!(
        rows[1..]
            .iter()
            .filter(|r| r[col("point")] == "cusp-end")
            .count(),
        1
    );
    // The sweep run again runs that task again (the others stay), and all is collected.
    let o = sweep(&file, &out, &["--jobs", "2"], None);
    assert!(o.status.success(), "{}", text(&o).1);
    let (stdout, _) = text(&collect(&out));
    assert!(
        stdout.contains("2 runs: 2 finished, 0 failed, 0 cut short"),
        "{stdout}"
    );
}
