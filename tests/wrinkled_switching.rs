//! Branches and critical curves through wrinkled states: the relaxed energy with a switching
//! width δ (`material.wrinkling-width`, docs/theory.md §2.9). Paper 2's sphere on a plane,
//! deflated at a fixed fluid volume, on the f = 4 icosphere (320 triangles): it wrinkles
//! from p ≈ 0.37 and meets bifurcations and limit points in partly wrinkled and slack states.
//! With the exact relaxed energy (δ = 0) the path and branches have corners where triangles
//! switch state, and some branches, a limit point and a critical curve stop at them; with
//! δ = 1e-3 they pass, and the critical values move by O(δ).

use serde_json::Value;
use std::path::Path;

use crate::common::{memstab, text};

/// The deflated sphere: `paper2_gas_pressure_fold_f8.toml` on f = 4 with V = 2, the relaxed
/// energy of switching width `width`, and `analysis` (a TOML `[analysis]` section and what
/// follows it) in place of the scene's; with `held` the volume is held by a `fixed`
/// constraint (a path in p), else V is free (a critical curve in (p, V)).
fn deflated_sphere(width: f64, held: bool, analysis: &str) -> String {
    let text = std::fs::read_to_string(format!(
        "{}/scenes/thesis/paper2_gas_pressure_fold_f8.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let (body, start) = text.split_once("[analysis]").unwrap();
    let start = &start[start.find("[start]").unwrap()..];
    let material = format!("thickness = 0.01\nwrinkling = \"relaxed\"\nwrinkling-width = {width}");
    let body = body
        .replace("thickness = 0.01           # mu * H = 1", &material)
        .replace(
            "start = 0.5                # the fluid volume",
            "start = 2.0                # the fluid volume",
        )
        .replace("frequency = 8 ", "frequency = 4 ");
    assert!(body.contains("frequency = 4") && body.contains("wrinkling-width"));
    let fixed = if held {
        "[[constraint]]\ntype = \"fixed\"\nparameter = \"V\"\n\n"
    } else {
        ""
    };
    format!("{body}{fixed}{analysis}\n\n{start}")
}

/// The path in p, decreasing, for `steps` steps (and the branches of its bifurcations with
/// `branches`) as a library run: the report.
fn path_report(width: f64, steps: usize) -> memstab::results::PathReport {
    let text = deflated_sphere(
        width,
        true,
        &format!("[analysis]\ntype = \"path\"\ncontrol = \"p\"\ndirection = \"decrease\"\nsteps = {steps}"),
    );
    let scene = memstab::scene::Scene::from_toml_str(&text, "deflated").unwrap();
    let mut study = memstab::study::mesh::MeshStudy::build(scene).unwrap();
    memstab::analysis::run(&mut study, |_, _| {})
        .unwrap()
        .report
}

/// The E1 double bifurcation just after the sphere starts to wrinkle (p ≈ 0.319 on this
/// mesh): its value with δ = 1e-3, 5e-4, 2.5e-4, 1.25e-4 approaches the exact relaxed
/// energy's, the distance shrinking by a factor approaching 2 per halving of δ (measured
/// 6.65, 3.89, 2.24, 1.24 × 1e-4): the blend moves a critical value by O(δ).
#[test]
fn a_switching_width_moves_a_wrinkled_critical_point_in_proportion_to_it() {
    let first_e1 = |width: f64| {
        let r = path_report(width, 8);
        let p = r.parameters.iter().position(|n| n == "p").unwrap();
        let c = r
            .critical
            .iter()
            .find(|c| c.irrep == "E1")
            .unwrap_or_else(|| panic!("δ = {width}: no E1 point in {:?}", r.critical));
        // In a partly wrinkled state.
        let number = 1 + r.critical.iter().position(|d| std::ptr::eq(c, d)).unwrap();
        let w = r.wrinkling.as_ref().unwrap();
        assert!(w.relaxed);
        assert!(w
            .critical
            .iter()
            .any(|d| d.critical == number && d.wrinkled > 0));
        c.parameters[p]
    };
    let exact = first_e1(0.0);
    let distances: Vec<f64> = [1e-3, 5e-4, 2.5e-4, 1.25e-4]
        .iter()
        .map(|&w| {
            let d = (first_e1(w) - exact).abs();
            println!("δ = {w:e}: E1 moved by {d:.3e} from {exact:.6}");
            assert!(d < 3.0 * w, "δ = {w}: moved by {d}");
            d
        })
        .collect();
    for pair in distances.windows(2) {
        let ratio = pair[0] / pair[1];
        assert!((1.5..2.5).contains(&ratio), "{distances:?}");
    }
}

/// Runs `scene` (TOML text) with the binary into `dir/name`; the output directory.
fn run(dir: &Path, name: &str, scene: &str) -> std::path::PathBuf {
    let file = dir.join(format!("{name}.toml"));
    std::fs::write(&file, scene).unwrap();
    let out = dir.join(name);
    let o = memstab(&[
        "run",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success(), "{name}: {}", text(&o.stderr));
    out
}

fn json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// The path of the deflated sphere for 40 steps with the branches of every bifurcation on
/// it (10 points each), then the critical curve in (p, V) of its E2 double near p = 0.0656
/// (`from-run`, 30 steps), in wrinkled and slack states all along. With the exact relaxed
/// energy a branch stops where the branch-jump guard refuses a corner, the A1 limit point
/// at the minimum of p is an eigenvalue jump that is not localised, and the E2 curve stops
/// at a corner after 19 points; with δ = 1e-3 every branch runs its budget, the limit point
/// is localised at the turning point, and the curve runs its 30 steps through two folds.
#[test]
fn with_a_switching_width_branches_and_critical_curves_pass_state_changes() {
    let tmp = tempfile::tempdir().unwrap();
    let path =
        "[analysis]\ntype = \"path\"\ncontrol = \"p\"\ndirection = \"decrease\"\nsteps = 40\n\n\
                [analysis.branches]\ndepth = 1\nsteps = 10";
    let stops = |out: &Path| -> Vec<String> {
        json(&out.join("branches.json"))["branches"]
            .as_array()
            .unwrap()
            .iter()
            .map(|b| b["stop"].as_str().unwrap().to_string())
            .collect()
    };
    // The A1 limit point at the path's minimum of p, 0.06553.
    let has_minimum = |out: &Path| {
        json(&out.join("critical.json"))
            .as_array()
            .unwrap()
            .iter()
            .any(|c| {
                c["irrep"] == "A1"
                    && c["kind"] == "limit point"
                    && (c["parameters"]["p"].as_f64().unwrap() - 0.06553).abs() < 1e-4
            })
    };
    let exact = run(tmp.path(), "exact", &deflated_sphere(0.0, true, path));
    let stopped = stops(&exact);
    assert!(
        stopped.iter().any(|s| s.contains("branch jump")),
        "{stopped:?}"
    );
    assert!(!has_minimum(&exact));
    let smooth = run(tmp.path(), "smooth", &deflated_sphere(1e-3, true, path));
    let stopped = stops(&smooth);
    assert!(stopped.len() >= 6, "{stopped:?}");
    assert!(
        stopped.iter().all(|s| s == "the step budget (10) was used"),
        "{stopped:?}"
    );
    assert!(has_minimum(&smooth));
    // Every branch state is of its isotropy, and the branches' states are wrinkled.
    for b in json(&smooth.join("branches.json"))["branches"]
        .as_array()
        .unwrap()
    {
        assert_eq!(b["isotropy_exact"], true, "{b}");
    }

    // The E2 double's critical curve in (p, V), from each run's saved point.
    let curve_of = |name: &str, from: &Path, width: f64| {
        let e2 = json(&from.join("critical.json"))
            .as_array()
            .unwrap()
            .iter()
            .position(|c| {
                c["irrep"] == "E2" && (c["parameters"]["p"].as_f64().unwrap() - 0.0656).abs() < 1e-4
            })
            .expect("the E2 double near p = 0.0656");
        let analysis = format!(
            "[analysis]\ntype = \"critical-curve\"\ncontrol = \"p\"\nsecond = \"V\"\n\
             from-run = \"{}\"\nfrom = {e2}\nsteps = 30\nmax-step = 0.05",
            from.display()
        );
        let out = run(tmp.path(), name, &deflated_sphere(width, false, &analysis));
        let csv = std::fs::read_to_string(out.join("curve.csv")).unwrap();
        let mut lines = csv.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
        let (area, irrep, v) = (col("wrinkled_area"), col("irrep"), col("V"));
        lines
            .map(|l| {
                let f: Vec<&str> = l.split(',').collect();
                assert_eq!(f[irrep], "E2");
                (
                    f[v].parse::<f64>().unwrap(),
                    f[area].parse::<f64>().unwrap(),
                )
            })
            .collect::<Vec<_>>()
    };
    let exact_curve = curve_of("exact_curve", &exact, 0.0);
    let smooth_curve = curve_of("smooth_curve", &smooth, 1e-3);
    println!(
        "E2 curve: {} points with δ = 0, {} with δ = 1e-3",
        exact_curve.len(),
        smooth_curve.len()
    );
    assert!(exact_curve.len() < 31, "{}", exact_curve.len());
    assert_eq!(smooth_curve.len(), 31);
    assert!(smooth_curve.iter().all(|&(_, area)| area > 1.0));
    // It turns in V at a fold (V = 2.5576) and back at another (2.5553), and goes on.
    let falls = smooth_curve.windows(2).filter(|w| w[1].0 < w[0].0).count();
    let rises_after = smooth_curve
        .windows(2)
        .skip_while(|w| w[1].0 >= w[0].0)
        .any(|w| w[1].0 > w[0].0);
    assert!(falls > 0 && rises_after, "{smooth_curve:?}");
}
