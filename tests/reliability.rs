//! What fuzzing and interrupts found, each a test: outputs never replace what is not a
//! regular file, user input never panics or exhausts memory, and the messages name what is
//! wrong.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn memstab(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_memstab"))
        .args(args)
        .output()
        .expect("the binary runs")
}

fn scene(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
        .to_string_lossy()
        .into_owned()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Exit code 2 and one line on stderr containing every needle.
fn assert_rejected(out: &Output, needles: &[&str]) {
    let err = stderr(out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    for n in needles {
        assert!(err.contains(n), "{err:?} lacks {n:?}");
    }
}

fn fifo(path: &Path) {
    let ok = Command::new("mkfifo")
        .arg(path)
        .status()
        .expect("mkfifo runs");
    assert!(ok.success());
}

#[cfg(unix)]
fn is_fifo(path: &Path) -> bool {
    use std::os::unix::fs::FileTypeExt;
    std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_fifo())
}

#[cfg(unix)]
#[test]
fn outputs_never_replace_a_fifo_a_symlink_or_a_directory() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("precious.txt");
    std::fs::write(&target, "keep me").unwrap();
    let link = dir.path().join("link.mtx");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    let dangling = dir.path().join("dangling.mtx");
    std::os::unix::fs::symlink(dir.path().join("nowhere"), &dangling).unwrap();
    let pipe = dir.path().join("pipe.mtx");
    fifo(&pipe);
    let demo = scene("demo.toml");
    for (out, what) in [
        (&link, "a symbolic link"),
        (&dangling, "a symbolic link"),
        (&pipe, "a FIFO"),
    ] {
        let o = memstab(&["export-matrix", &demo, "--out", out.to_str().unwrap()]);
        assert_rejected(&o, &["--out", what]);
        let o = memstab(&["mesh", "disc", "--out", &format!("{}.vtu", out.display())]);
        assert_eq!(o.status.code(), Some(0), "a new file beside it is fine");
    }
    // Mesh files: a FIFO with the right extension.
    let pipe_vtu = dir.path().join("pipe.vtu");
    fifo(&pipe_vtu);
    let o = memstab(&["mesh", "disc", "--out", pipe_vtu.to_str().unwrap()]);
    assert_rejected(&o, &["--out", "a FIFO"]);
    // Nothing was replaced.
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "keep me");
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    assert!(std::fs::symlink_metadata(&dangling)
        .unwrap()
        .file_type()
        .is_symlink());
    assert!(is_fifo(&pipe) && is_fifo(&pipe_vtu));
    // A run directory whose path.csv is a link: refused before anything runs.
    let run_dir = dir.path().join("run");
    std::fs::create_dir(&run_dir).unwrap();
    std::os::unix::fs::symlink(&target, run_dir.join("path.csv")).unwrap();
    let o = memstab(&["run", &demo, "--out", run_dir.to_str().unwrap(), "--quiet"]);
    assert_rejected(&o, &["path.csv", "a symbolic link"]);
    let left: Vec<PathBuf> = std::fs::read_dir(&run_dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(left, [run_dir.join("path.csv")], "nothing written");
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "keep me");
}

/// Every command that prints ends quietly with exit code 0 when its reader has gone.
#[test]
fn a_closed_stdout_is_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo");
    let demo = scene("demo.toml");
    for args in [
        vec!["group", "Ih"],
        vec!["spectrum", demo.as_str()],
        vec!["demo", "--quiet", "--out", out.to_str().unwrap()],
        vec!["mesh", "icosphere", "--json"],
    ] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_memstab"))
            .args(&args)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take());
        let o = child.wait_with_output().unwrap();
        assert_eq!(o.status.code(), Some(0), "{args:?}: {}", stderr(&o));
        assert!(!stderr(&o).contains("panicked"), "{args:?}: {}", stderr(&o));
    }
}

/// A scene, a group or a mesh over the limits is refused with its estimate before anything
/// is allocated or written; the limits are configurable.
#[test]
fn requests_over_the_limits_are_refused_before_they_start() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let out = out.to_str().unwrap();
    let ponding = std::fs::read_to_string(scene("ponding.toml")).unwrap();
    for samples in ["9223372036854775807", "100000000"] {
        let path = dir.path().join(format!("s{samples}.toml"));
        std::fs::write(
            &path,
            ponding.replace("samples = 92", &format!("samples = {samples}")),
        )
        .unwrap();
        let o = memstab(&["run", path.to_str().unwrap(), "--out", out]);
        assert_rejected(&o, &["would need about", "MEMSTAB_MAX_MEMORY"]);
        assert!(!Path::new(out).exists(), "nothing written");
    }
    assert_rejected(
        &memstab(&["run", "/dev/zero", "--out", out]),
        &["/dev/zero", "a device, not a regular file"],
    );
    assert_rejected(
        &memstab(&["group", "C800v"]),
        &["1600", "MEMSTAB_MAX_GROUP_ORDER"],
    );
    assert_rejected(
        &memstab(&["mesh", "disc", "--sectors", "1000000"]),
        &["the disc mesh", "MEMSTAB_MAX_MEMORY"],
    );
    assert_rejected(
        &memstab(&["mesh", "icosphere", "--frequency", "1000"]),
        &["the icosphere mesh", "MEMSTAB_MAX_MEMORY"],
    );
    // Configurable: the demo in 1 MB, and a bad value named.
    let demo = scene("demo.toml");
    let run = |var: &str, value: &str| {
        Command::new(env!("CARGO_BIN_EXE_memstab"))
            .args(["run", &demo, "--out", out, "--quiet"])
            .env(var, value)
            .output()
            .unwrap()
    };
    assert_rejected(
        &run("MEMSTAB_MAX_MEMORY", "1M"),
        &["scene 'demo'", "1.0 MB"],
    );
    assert_rejected(
        &run("MEMSTAB_MAX_MEMORY", "lots"),
        &["MEMSTAB_MAX_MEMORY", "'lots'"],
    );
    assert_rejected(
        &run("MEMSTAB_MAX_SCENE_BYTES", "100"),
        &["larger than 100 B"],
    );
    assert!(!Path::new(out).exists(), "nothing written");
}

/// Names from a scene reach the SVG as valid XML text; parameter names are identifiers that
/// do not collide with a column; messages are one bounded line whatever the value.
#[test]
fn names_and_messages_stay_valid() {
    let dir = tempfile::tempdir().unwrap();
    let demo = std::fs::read_to_string(scene("demo.toml")).unwrap();
    let named = demo.replacen("name = \"demo\"", r#"name = "a<b&c\u0001d\uFFFE""#, 1);
    assert_ne!(named, demo);
    let path = dir.path().join("named.toml");
    std::fs::write(&path, named).unwrap();
    let out = dir.path().join("named");
    let o = memstab(&[
        "run",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    crate::common::figures::check_svg(&out.join("path.svg"));
    let svg = std::fs::read_to_string(out.join("path.svg")).unwrap();
    let xml_char = |c: char| {
        matches!(c, '\t' | '\n' | '\r' | '\u{20}'..='\u{D7FF}' | '\u{E000}'..='\u{FFFD}')
            || c >= '\u{10000}'
    };
    assert!(svg.chars().all(xml_char), "a character XML does not allow");
    assert!(svg.contains("a&lt;b&amp;c"), "markup escaped");

    // Parameter names.
    for (name, needle) in [
        ("volume", "column of path.csv"),
        ("step", "column of path.csv"),
        ("\"a b\"", "not an identifier"),
        ("\"\"", "not an identifier"),
        ("\"1p\"", "not an identifier"),
    ] {
        let text = demo
            .replace("[parameters.p]", &format!("[parameters.{name}]"))
            .replace("pressure = \"p\"", &format!("pressure = {}", quoted(name)))
            .replace("control = \"p\"", &format!("control = {}", quoted(name)));
        let path = dir.path().join("p.toml");
        std::fs::write(&path, text).unwrap();
        let o = memstab(&["run", path.to_str().unwrap(), "--out", "unused"]);
        assert_rejected(&o, &["parameters", needle]);
    }
    // A negative spin or density parameter.
    let ponding = std::fs::read_to_string(scene("ponding.toml")).unwrap();
    let text = ponding
        .replace("start = 0.0 ", "start = -1.0 ")
        .replace("min = 0.0", "min = -2.0");
    let path = dir.path().join("neg.toml");
    std::fs::write(&path, text).unwrap();
    let o = memstab(&["run", path.to_str().unwrap(), "--out", "unused"]);
    assert_rejected(&o, &["parameters.rho.start", ">= 0", "effect[0].density"]);

    // A value with line breaks, and a huge one: one bounded line.
    for value in [
        "\"C7\\nv\"".to_string(),
        format!("\"{}\"", "C".repeat(100_000)),
    ] {
        let text = demo.replacen("frequency = 4", &format!("frequency = {value}"), 1);
        let path = dir.path().join("v.toml");
        std::fs::write(&path, text).unwrap();
        let o = memstab(&["run", path.to_str().unwrap(), "--out", "unused"]);
        assert_rejected(&o, &["mesh.frequency"]);
        assert!(stderr(&o).len() < 600, "{} bytes", stderr(&o).len());
    }
}

/// `name` as a TOML string (already quoted names stay as they are).
fn quoted(name: &str) -> String {
    if name.starts_with('"') {
        name.to_string()
    } else {
        format!("\"{name}\"")
    }
}

/// A VTU file (ascii) of the given points and triangles.
fn vtu(points: &[[f64; 3]], triangles: &[[usize; 3]]) -> String {
    let p: Vec<String> = points
        .iter()
        .map(|x| format!("{} {} {}", x[0], x[1], x[2]))
        .collect();
    let c: Vec<String> = triangles
        .iter()
        .map(|t| format!("{} {} {}", t[0], t[1], t[2]))
        .collect();
    let offsets: Vec<String> = (1..=triangles.len()).map(|i| (3 * i).to_string()).collect();
    let types = vec!["5"; triangles.len()].join(" ");
    format!(
        r#"<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64">
<UnstructuredGrid>
<Piece NumberOfPoints="{}" NumberOfCells="{}">
<Points>
<DataArray type="Float64" Name="Points" NumberOfComponents="3" format="ascii">
{}
</DataArray>
</Points>
<Cells>
<DataArray type="Int64" Name="connectivity" format="ascii">
{}
</DataArray>
<DataArray type="Int64" Name="offsets" format="ascii">
{}
</DataArray>
<DataArray type="UInt8" Name="types" format="ascii">
{types}
</DataArray>
</Cells>
</Piece>
</UnstructuredGrid>
</VTKFile>
"#,
        points.len(),
        triangles.len(),
        p.join("\n"),
        c.join("\n"),
        offsets.join(" ")
    )
}

/// The messages and exit codes of what fuzzing found: each names the key or flag at fault.
#[test]
fn messages_name_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };
    // A mesh file with a repeated node, and one with a degenerate triangle.
    let s = 0.5 * 3f64.sqrt();
    let file_scene = |mesh: &str| {
        format!(
            "[scene]\nname = \"file\"\n[mesh]\ngenerator = \"file\"\npath = \"{mesh}\"\n\
             [material]\nmodel = \"mooney-rivlin\"\nmu = 1.0\nk = 0.0\nthickness = 1.0\n\
             [analysis]\ntype = \"equilibrium\"\n"
        )
    };
    write(
        "twice.vtu",
        &vtu(
            &[
                [0., 0., 0.],
                [1., 0., 0.],
                [-0.5, s, 0.],
                [-0.5, -s, 0.],
                [1., 0., 0.],
            ],
            &[[0, 1, 2], [0, 2, 3], [0, 3, 4]],
        ),
    );
    let o = memstab(&["spectrum", &write("twice.toml", &file_scene("twice.vtu"))]);
    assert_rejected(&o, &["mesh.path", "twice.vtu", "nodes 1 and 4 coincide"]);
    write(
        "flat.vtu",
        &vtu(&[[0., 0., 0.], [1., 0., 0.], [2., 0., 0.]], &[[0, 1, 2]]),
    );
    let o = memstab(&["spectrum", &write("flat.toml", &file_scene("flat.vtu"))]);
    assert_rejected(&o, &["mesh.path", "flat.vtu", "triangle 0 is degenerate"]);

    // Newton settings no double precision can meet, and a range of infinite width.
    let demo = std::fs::read_to_string(scene("demo.toml")).unwrap();
    let with = |extra: &str| demo.replace("[analysis]\n", &format!("[analysis]\n{extra}\n"));
    let o = memstab(&["spectrum", &write("t.toml", &with("tolerance = 1e-300"))]);
    assert_rejected(&o, &["analysis.tolerance", "1e-300"]);
    let o = memstab(&[
        "spectrum",
        &write("m.toml", &with("max-iterations = 9223372036854775807")),
    ]);
    assert_rejected(&o, &["analysis.max-iterations", "at most 1000"]);
    let ponding = std::fs::read_to_string(scene("ponding.toml")).unwrap();
    let wide = ponding
        .replace("min = 0.0\n", "min = -1.7e308\n")
        .replace("max = 46.0 ", "max = 1.7e308 ");
    assert_ne!(wide, ponding);
    let o = memstab(&["spectrum", &write("w.toml", &wide)]);
    assert_rejected(&o, &["parameters.rho.max", "finite width"]);

    // Flags.
    let o = memstab(&[
        "compare",
        &scene("ponding.toml"),
        "--meshes",
        "C8v",
        "--max",
        "1e300",
    ]);
    assert_rejected(&o, &["--max 1e300", "--samples"]);
    let o = memstab(&[
        "bench",
        "--frequencies",
        "4,100000",
        "--out",
        "unused-bench",
    ]);
    assert_rejected(&o, &["--frequencies 100000", "MEMSTAB_MAX_MEMORY"]);
    assert!(!Path::new("unused-bench").exists());
    #[cfg(unix)]
    {
        let link = dir.path().join("dangling");
        std::os::unix::fs::symlink(dir.path().join("nowhere"), &link).unwrap();
        let o = memstab(&["run", &scene("demo.toml"), "--out", link.to_str().unwrap()]);
        assert_rejected(&o, &["--out", "symbolic link"]);
    }
}

/// A spinning body on an icosphere keeps the elements that map the spin axis to itself as a
/// line: D5d with a vertex down, D2h in the reference orientation (a 2-fold axis along z).
/// The spin is moderate (ω² = 0.1, a stable state that Newton reaches in a few iterations):
/// at ω² = 0.5 the balloon's state has an index of 35, and whether Newton finds it from a
/// uniform stretch is decided by round-off.
#[test]
fn spin_on_an_icosphere_keeps_the_axis_stabiliser() {
    let dir = tempfile::tempdir().unwrap();
    for (down, group) in [("down = \"vertex\"\n", "D5d"), ("", "D2h")] {
        let text = format!(
            "[scene]\nname = \"spinning balloon\"\n[mesh]\ngenerator = \"icosphere\"\n\
             frequency = 2\n{down}[material]\nmodel = \"mooney-rivlin\"\nmu = 100.0\nk = 0.1\n\
             thickness = 0.01\n[[effect]]\ntype = \"gas\"\npressure = 1.2\n[[effect]]\n\
             type = \"spin\"\ndensity = 1.0\nomega2 = 0.1\n[analysis]\ntype = \"equilibrium\"\n\
             [start]\nstretch = 1.2\n"
        );
        let path = dir.path().join("spin.toml");
        std::fs::write(&path, text).unwrap();
        let o = memstab(&["spectrum", path.to_str().unwrap(), "--json"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(json["group"], group);
        assert_eq!(json["index"], 0, "the moderate spin's state is stable");
    }
}

/// SIGINT stops a run at its next point: what the path has is written with the stop reason
/// "interrupted", exit code 130, a manifest with every file's checksum last, and no temporary
/// file left (a stale one of an earlier, killed run is swept).
#[cfg(unix)]
#[test]
fn an_interrupted_run_writes_what_it_has_and_a_manifest() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    std::fs::create_dir(&out).unwrap();
    let stale = out.join(".memstab-stale.tmp");
    std::fs::write(&stale, "debris").unwrap();
    // The disc under fluid without its displacement stop, on 32 divisions (7 168
    // triangles): about 3 s of path, four times the wait before the interrupt, and its first
    // point within a tenth of a second.
    let text = std::fs::read_to_string(scene("disc_fluid_above.toml")).unwrap();
    let long = text
        .lines()
        .filter(|l| !l.starts_with("stop-displacement"))
        .map(|l| {
            if l.starts_with("divisions = 16") {
                "divisions = 32"
            } else {
                l
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    assert!(long.contains("\ndivisions = 32\n"), "the mesh was refined");
    assert_ne!(long.len(), text.trim_end().len(), "the stop was removed");
    let long_scene = dir.path().join("long.toml");
    std::fs::write(&long_scene, long).unwrap();
    let child = Command::new(env!("CARGO_BIN_EXE_memstab"))
        .args([
            "run",
            long_scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(700));
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    assert!(stderr(&o).contains("interrupted"), "{}", stderr(&o));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("path.json")).unwrap()).unwrap();
    assert_eq!(report["stop"], "interrupted");
    let rows = report["rows"].as_array().unwrap().len();
    assert!((1..400).contains(&rows), "{rows} rows");
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("manifest.json")).unwrap()).unwrap();
    assert_eq!(manifest["stop"], "interrupted");
    let files = manifest["files"].as_array().unwrap();
    assert!(files.len() >= 6);
    for f in files {
        let path = out.join(f["file"].as_str().unwrap());
        assert_eq!(
            memstab::output::sha256(&path).unwrap(),
            f["sha256"].as_str().unwrap()
        );
    }
    let left: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

/// The bundled balloon with its lines changed by `edit` (a line starting with the key is
/// replaced), at frequency 4, written into `dir`.
fn balloon_with(dir: &Path, edit: &[(&str, &str)]) -> PathBuf {
    let text = std::fs::read_to_string(scene("balloon.toml")).unwrap();
    let mut lines: Vec<String> = Vec::new();
    for line in text.lines() {
        let replaced = edit
            .iter()
            .chain([("frequency", "frequency = 4")].iter())
            .find(|(key, _)| line.starts_with(&format!("{key} =")));
        lines.push(replaced.map_or(line.to_string(), |(_, new)| new.to_string()));
    }
    let path = dir.join("balloon.toml");
    std::fs::write(&path, lines.join("\n")).unwrap();
    path
}

/// A state that Newton or the corrector converges to must be a membrane state: a balloon
/// whose shear modulus is 1e-100, whose first guess is scaled by 1e-300, or whose radius is
/// 1e75 collapses to a point; that is an error naming the stretch found, with nothing
/// written, never a path of collapsed states reported as a result.
#[test]
fn collapsed_states_are_errors_not_results() {
    let dir = tempfile::tempdir().unwrap();
    for edit in [
        ("mu", "mu = 1e-100"),
        ("stretch", "stretch = 1e-300"),
        ("radius", "radius = 1e75"),
    ] {
        let path = balloon_with(dir.path(), &[edit]);
        let out = dir.path().join("out");
        let o = memstab(&[
            "run",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{edit:?}: {err}");
        assert!(
            err.contains("inadmissible state") && err.contains("principal stretch"),
            "{edit:?}: {err}"
        );
        assert!(!out.exists(), "{edit:?}: nothing is written");
    }
}

/// A step so long that its corrector lands beyond both pressure extrema — once on a balloon
/// turned inside out — is cut, not accepted: with steps of 20 the balloon's maximum and
/// minimum are still found.
#[test]
fn huge_steps_do_not_jump_over_the_limit_points() {
    let dir = tempfile::tempdir().unwrap();
    let path = balloon_with(
        dir.path(),
        &[("steps", "steps = 60\nmax-step = 20\ninitial-step = 20")],
    );
    let out = dir.path().join("out");
    let o = memstab(&[
        "run",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("path.json")).unwrap()).unwrap();
    let kinds: Vec<&str> = report["turning_points"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t["kind"].as_str().unwrap())
        .collect();
    assert_eq!(kinds, ["maximum", "minimum"], "{report}");
    let k = report["measures"]
        .as_array()
        .unwrap()
        .iter()
        .position(|m| m == "stretch")
        .unwrap();
    let stretches: Vec<f64> = report["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["measures"][k].as_f64().unwrap())
        .collect();
    assert!(stretches.iter().all(|&s| s > 1.0), "{stretches:?}");
}

/// `stop-stretch` is reached where the stretch passes it from the start's side: a target
/// below the start is not "reached" at the first step, and a path that never passes it says
/// so.
#[test]
fn a_stop_stretch_behind_the_start_is_not_reached() {
    let dir = tempfile::tempdir().unwrap();
    let path = balloon_with(
        dir.path(),
        &[
            ("stop-stretch", "stop-stretch = 1.01"),
            ("steps", "steps = 8"),
        ],
    );
    let out = dir.path().join("out");
    let o = memstab(&[
        "run",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("stopped: the step budget (8) was used"),
        "{text}"
    );
    assert!(
        text.contains("analysis.stop-stretch = 1.01 was not reached"),
        "{text}"
    );
}

/// A mesh file with every triangle reversed (normals down) is turned to point up, with a
/// warning: fluid `side = "below"` still pushes the disc up, and the path is the one of the
/// file as given.
#[test]
fn an_inverted_mesh_file_is_oriented_by_the_fluid_side() {
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let msh = std::fs::read_to_string(root.join("meshes/disc_c7v.msh")).unwrap();
    // Swap the last two nodes of every element line between $Elements' headers and its end.
    let mut inverted = Vec::new();
    let mut in_elements = 0;
    for line in msh.lines() {
        match line {
            "$Elements" => in_elements = 1,
            "$EndElements" => in_elements = 0,
            _ if in_elements > 0 => in_elements += 1,
            _ => {}
        }
        let fields: Vec<&str> = line.split_whitespace().collect();
        if in_elements > 3 && fields.len() == 4 {
            inverted.push(format!(
                "{} {} {} {}",
                fields[0], fields[1], fields[3], fields[2]
            ));
        } else {
            inverted.push(line.to_string());
        }
    }
    assert_ne!(inverted.join("\n"), msh.trim_end());
    std::fs::write(dir.path().join("inverted.msh"), inverted.join("\n")).unwrap();
    let text = std::fs::read_to_string(root.join("disc_file.toml")).unwrap();
    let mut runs = Vec::new();
    for (name, mesh) in [
        ("given", root.join("meshes/disc_c7v.msh")),
        ("inverted", dir.path().join("inverted.msh")),
    ] {
        let scene = text
            .replace("path = \"meshes/disc_c7v.msh\"", &quoted_path(&mesh))
            .replace("steps = 400", "steps = 12");
        let path = dir.path().join(format!("{name}.toml"));
        std::fs::write(&path, scene).unwrap();
        let out = dir.path().join(name);
        let o = memstab(&[
            "run",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ]);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("path.json")).unwrap()).unwrap();
        runs.push(report);
    }
    let flipped = |r: &serde_json::Value| {
        r["warnings"].as_array().is_some_and(|w| {
            w.iter()
                .any(|w| w.as_str().unwrap().contains("normals pointed down"))
        })
    };
    assert!(!flipped(&runs[0]) && flipped(&runs[1]));
    let max_z = |r: &serde_json::Value| -> Vec<f64> {
        let k = r["measures"]
            .as_array()
            .unwrap()
            .iter()
            .position(|m| m == "max_z")
            .unwrap();
        r["rows"]
            .as_array()
            .unwrap()
            .iter()
            .map(|row| row["measures"][k].as_f64().unwrap())
            .collect()
    };
    let (a, b) = (max_z(&runs[0]), max_z(&runs[1]));
    assert_eq!(a.len(), b.len());
    assert!(a.last().unwrap() > &0.05, "the fluid lifts the disc: {a:?}");
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() <= 1e-9 * x.abs().max(1e-3), "{a:?} vs {b:?}");
    }
}

fn quoted_path(p: &Path) -> String {
    format!("path = {}", quoted(p.to_str().unwrap()))
}

/// A start state whose residual is at round-off of the force scale while Newton's correction
/// does not vanish — a balloon with a plane it does not touch, free to translate along z in
/// the fixed-point space of C5v — is accepted, with a warning that names the near-singular
/// direction and what holds it, instead of "did not converge".
#[test]
fn a_start_at_round_off_along_a_free_translation_is_accepted_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(scene("balloon.toml")).unwrap();
    let free = text
        .replacen("frequency = 8 ", "frequency = 4 \ndown = \"vertex\"", 1)
        .replacen(
            "[parameters.p]",
            "[[effect]]\ntype = \"plane\"\nnormal = [0.0, 0.0, 1.0]\noffset = -2.0\n\
             penalty = 1000.0\nexponent = 3\n\n[parameters.p]",
            1,
        )
        .replacen("steps = 400", "steps = 3", 1);
    assert!(free.contains("offset = -2.0") && free.contains("down = \"vertex\""));
    let path = dir.path().join("free.toml");
    std::fs::write(&path, free).unwrap();
    let out = dir.path().join("out");
    let o = memstab(&[
        "run",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let all = format!("{}{}", String::from_utf8_lossy(&o.stdout), stderr(&o));
    assert!(o.status.success(), "{all}");
    assert!(!all.contains("did not converge at"), "{all}");
    assert!(all.contains("accepted at round-off"), "{all}");
    assert!(all.contains("rigid translation along [0, 0, 1]"), "{all}");
    assert!(all.contains("hold-translation = [0, 0, 1]"), "{all}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("path.json")).unwrap()).unwrap();
    assert!(
        report["warnings"].to_string().contains("round-off"),
        "{report}"
    );
}

/// `memstab ARGS`, ended (and the test failed) if it has not exited within a minute: a read
/// that blocks forever must fail the test, not hang it.
#[cfg(unix)]
fn memstab_bounded(args: &[&str]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_memstab"))
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > std::time::Duration::from_secs(60) {
            child.kill().unwrap();
            let _ = child.wait();
            panic!("memstab {args:?} still runs after a minute: blocked");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// A scene that is a FIFO, and a mesh file or a `[start] from` a scene names that is one, is
/// refused before it is opened (opening a FIFO waits for a writer, and no signal ends that
/// wait): exit 2, one line naming the path (and the key), nothing written. A directory is
/// refused the same way. Skipped where `mkfifo` is missing.
#[cfg(unix)]
#[test]
fn a_scene_or_a_file_it_names_that_is_a_fifo_is_refused_before_it_is_opened() {
    let dir = tempfile::tempdir().unwrap();
    let pipe = dir.path().join("pipe.toml");
    match Command::new("mkfifo").arg(&pipe).status() {
        Ok(s) if s.success() => {}
        _ => {
            eprintln!("skipped: mkfifo is missing or failed");
            return;
        }
    }
    let out = dir.path().join("out");
    let out_s = out.to_str().unwrap();
    let p = pipe.to_str().unwrap();
    for args in [
        vec!["run", p, "--out", out_s, "--quiet"],
        vec!["spectrum", p],
        vec!["export-matrix", p, "--out", &format!("{out_s}.mtx")],
    ] {
        let o = memstab_bounded(&args);
        assert_rejected(&o, &[p, "a FIFO, not a regular file"]);
    }
    let d = dir.path().to_str().unwrap();
    assert_rejected(
        &memstab_bounded(&["run", d, "--out", out_s]),
        &[d, "a directory, not a regular file"],
    );
    // A mesh file that is a FIFO.
    let disc = std::fs::read_to_string(scene("disc_file.toml")).unwrap();
    assert!(disc.contains("path = \"meshes/disc_c7v.msh\""));
    let mesh_pipe = dir.path().join("pipe.msh");
    assert!(Command::new("mkfifo")
        .arg(&mesh_pipe)
        .status()
        .unwrap()
        .success());
    let s = dir.path().join("mesh.toml");
    std::fs::write(
        &s,
        disc.replacen(
            "path = \"meshes/disc_c7v.msh\"",
            &format!("path = '{}'", mesh_pipe.display()),
            1,
        ),
    )
    .unwrap();
    let o = memstab_bounded(&["run", s.to_str().unwrap(), "--out", out_s]);
    assert_rejected(&o, &["mesh.path", "pipe.msh", "a FIFO"]);
    // A `[start] from` that is a FIFO.
    let demo = std::fs::read_to_string(scene("demo.toml")).unwrap();
    assert!(demo.contains("[start]\nstretch = 1.05\n"));
    let from_pipe = dir.path().join("path.json");
    assert!(Command::new("mkfifo")
        .arg(&from_pipe)
        .status()
        .unwrap()
        .success());
    let s = dir.path().join("from.toml");
    std::fs::write(
        &s,
        demo.replacen(
            "[start]\nstretch = 1.05\n",
            &format!("[start]\nfrom = '{}'\npoint = 3\n", from_pipe.display()),
            1,
        ),
    )
    .unwrap();
    let o = memstab_bounded(&["run", s.to_str().unwrap(), "--out", out_s]);
    assert_rejected(&o, &["start.from", "path.json", "a FIFO"]);
    assert!(!out.exists(), "nothing written");
}

/// A finished run whose `path.json`, `path.states` or `manifest.json` has been replaced by a
/// FIFO: `spectrum RUN_DIR --point N` refuses it in one line saying so (exit 2) instead of
/// waiting for a writer. Skipped where `mkfifo` is missing.
#[cfg(unix)]
#[test]
fn a_run_directory_file_that_is_a_fifo_is_refused_before_it_is_opened() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    let o = memstab(&[
        "run",
        &scene("demo.toml"),
        "--out",
        run.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for name in ["path.json", "path.states", "manifest.json"] {
        let file = run.join(name);
        let kept = std::fs::read(&file).unwrap();
        std::fs::remove_file(&file).unwrap();
        match Command::new("mkfifo").arg(&file).status() {
            Ok(s) if s.success() => {}
            _ => {
                eprintln!("skipped: mkfifo is missing or failed");
                return;
            }
        }
        let o = memstab_bounded(&["spectrum", run.to_str().unwrap(), "--point", "2"]);
        assert_rejected(&o, &[name, "a FIFO, not a regular file"]);
        std::fs::remove_file(&file).unwrap();
        std::fs::write(&file, kept).unwrap();
    }
    let o = memstab_bounded(&["spectrum", run.to_str().unwrap(), "--point", "2"]);
    assert!(o.status.success(), "{}", stderr(&o));
}
