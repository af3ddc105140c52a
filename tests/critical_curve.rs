//! Critical curves: the balloon's limit point followed in (p, k) to its cusp against the closed
//! form, the derivatives of the block test function, and the curve's outputs.

use crate::common::{balloon_with_k, fold_k, reservoir_balloon, reservoir_limit, RESERVOIR_PATH};
use memstab::analysis::run;
use memstab::model::Model;
use memstab::results::{CriticalKind, CurveEventKind, CurveReport};
use memstab::scene::Scene;
use memstab::study::block_test::{BlockTest, DIFFERENCE_STEP};
use memstab::study::mesh::MeshStudy;

/// The sphere's pressure in closed form, p R/(μH) = 2/(1+k)(λ⁻¹ − λ⁻⁷)(1 + kλ²); its fold
/// line is [`fold_k`].
fn sphere_p(l: f64, k: f64) -> f64 {
    memstab::reference::sphere_pressure(k, l)
}

/// The cusp: the maximum of k(λ) on the fold line, by golden-section search.
fn cusp() -> (f64, f64, f64) {
    let (mut a, mut b) = (1.4f64, 3.0f64);
    let g = (5f64.sqrt() - 1.0) / 2.0;
    for _ in 0..200 {
        let (c, d) = (b - g * (b - a), a + g * (b - a));
        if fold_k(c) > fold_k(d) {
            b = d;
        } else {
            a = c;
        }
    }
    let l = 0.5 * (a + b);
    (fold_k(l), l, sphere_p(l, fold_k(l)))
}

/// The bundled balloon with k = "k" as a parameter and a critical-curve analysis from its
/// first limit point, at icosphere frequency `f`.
fn balloon_curve_scene(frequency: usize) -> Scene {
    Scene::from_toml_str(&balloon_curve_text(frequency), "balloon-curve").unwrap()
}

/// The text of [`balloon_curve_scene`].
fn balloon_curve_text(frequency: usize) -> String {
    balloon_with_k(
        frequency,
        r#"[parameters.k]
start = 0.1
min = 0.05
max = 0.3

[analysis]
type = "critical-curve"
control = "p"
second = "k"
from = "limit"
steps = 120
path-steps = 400
max-step = 0.05

"#,
    )
}

fn curve_of(frequency: usize) -> (CurveReport, memstab::results::RunResult) {
    let mut study = MeshStudy::build(balloon_curve_scene(frequency)).unwrap();
    let result = run(&mut study, |_, _| {}).expect("the curve runs");
    (
        result
            .outcome::<memstab::results::CurveReport>()
            .cloned()
            .expect("a curve"),
        result,
    )
}

fn col(curve: &CurveReport, name: &str) -> usize {
    curve
        .parameters
        .iter()
        .position(|p| p == name)
        .unwrap_or_else(|| panic!("{name}"))
}

/// The cusp of the balloon's limit-point curve in (p, k), found from the bundled scene with
/// k = "k": every point of the curve lies on the closed-form fold line to the mesh's error,
/// the cusp is where the closed form puts it, and the errors fall as h² from f = 4 to f = 8.
#[test]
fn balloon_limit_curve_reaches_its_cusp_on_the_closed_form_fold_line() {
    let (k_c, l_c, p_c) = cusp();
    // The closed form's own cusp, recomputed here: k = 0.2144584, λ = 1.8407344, p = 1.5050470.
    assert!((k_c - 0.2144584).abs() < 1e-6 && (l_c - 1.8407344).abs() < 1e-6);
    assert!((p_c - 1.5050470).abs() < 1e-6);
    let mut cusp_errors = Vec::new();
    for frequency in [4, 8] {
        let (curve, _) = curve_of(frequency);
        assert_eq!(curve.kind, CriticalKind::LimitPoint);
        assert_eq!(curve.irrep, "Ag");
        let (p, k) = (col(&curve, "p"), col(&curve, "k"));
        let s = curve.measures.iter().position(|m| m == "stretch").unwrap();
        assert!(curve.rows.len() > 20, "{} points", curve.rows.len());
        // Every point: on the fold line at its own stretch, to the mesh's error.
        let mut worst = (0.0f64, 0.0f64);
        for r in &curve.rows {
            let l = r.measures[s];
            worst.0 = worst.0.max((r.parameters[k] - fold_k(l)).abs());
            worst.1 = worst
                .1
                .max((r.parameters[p] / sphere_p(l, fold_k(l)) - 1.0).abs());
            assert!(r.critical_eigenvalue.abs() < 1e-8, "{r:?}");
            assert!(r.second_eigenvalue.abs() > 1e-6, "{r:?}");
        }
        // One cusp, where k turns from increasing to decreasing.
        let cusps: Vec<_> = curve
            .events
            .iter()
            .filter(|e| e.kind == CurveEventKind::Cusp)
            .collect();
        assert_eq!(cusps.len(), 1, "{:?}", curve.events);
        let c = cusps[0];
        let errors = (
            (c.parameters[k] - k_c).abs(),
            (c.measures[s] - l_c).abs(),
            (c.parameters[p] / p_c - 1.0).abs(),
        );
        eprintln!(
            "f = {frequency}: {} points, fold-line errors {worst:?}, cusp (k, λ, p) = ({}, {}, {}), errors {errors:?}",
            curve.rows.len(),
            c.parameters[k],
            c.measures[s],
            c.parameters[p]
        );
        // The discretisation error at f = 8 is below 1 % in the pressure (the path's turning
        // points err by < 2e-3 at f = 16, about four times that at f = 8); f = 4 is four times
        // that again. To leading order it is a uniform factor on the pressure, R·A/(3V) − 1
        // of the polyhedron, which moves neither k nor λ of a fold: those err by far less.
        let tol = if frequency == 8 { 1e-2 } else { 4e-2 };
        assert!(worst.1 < tol, "pressure off the fold line by {}", worst.1);
        assert!(worst.0 < tol / 100.0, "k off the fold line by {}", worst.0);
        assert!(errors.2 < tol, "cusp pressure error {}", errors.2);
        assert!(
            errors.0 < tol / 100.0 && errors.1 < tol / 100.0,
            "cusp errors {errors:?}"
        );
        cusp_errors.push(errors);
        assert!(matches!(
            curve.events.last().map(|e| e.kind),
            Some(CurveEventKind::End)
        ));
    }
    // Second order: halving h divides the cusp's pressure error by about four.
    let rate = (cusp_errors[0].2 / cusp_errors[1].2).log2();
    assert!(
        (1.5..2.5).contains(&rate),
        "rate {rate}, errors {cusp_errors:?}"
    );
}

/// Checks the test function of block `mu` near the critical point `cp` of `study`: ∂σ/∂q
/// (directional differences of the tangent) and ∂σ/∂Λ (differences of the loads) against
/// differences of σ itself, and the step's truncation error, estimated by Richardson
/// extrapolation from ε and 2ε, against 1e-7 of the derivative.
fn check_test_derivatives(study: &MeshStudy, cp: &memstab::results::CriticalPoint) {
    let adapted = memstab::adapted::AdaptedBasis::new(&study.action, study.model.layout()).unwrap();
    let mu = adapted
        .irreps
        .iter()
        .position(|i| i.name == cp.irrep)
        .unwrap();
    let block = adapted.irreps[mu].first();
    let length = 1.0;
    let mut border = block.restrict(&cp.mode);
    // A border off the null vector, so that the test is generic.
    border[0] += 0.3;
    let mut test = BlockTest::new(&study.model, block, &study.basis, mu == 0, &border, length)
        .with_constraints(&study.constraints, &cp.state, &cp.parameters)
        .unwrap();
    // A state near the critical point.
    let u: Vec<f64> = cp.state.iter().map(|v| v * 1.01).collect();
    let params = cp.parameters.clone();
    let t = test.evaluate(&u, &params).unwrap();
    // Along a symmetric direction d (the state itself), dσ = ∂σ/∂q · B₀ᵀ d.
    let d = u.clone();
    let h = 1e-5;
    let shifted = |s: f64| -> Vec<f64> { u.iter().zip(&d).map(|(a, b)| a + s * b).collect() };
    let sp = test.value(&shifted(h), &params).unwrap().0;
    let sm = test.value(&shifted(-h), &params).unwrap().0;
    let fd = (sp - sm) / (2.0 * h);
    let exact = t.grad_q.dot(&study.basis.restrict(&d));
    assert!(
        (fd - exact).abs() < 1e-5 * exact.abs(),
        "{}: dσ/du·d: {exact} vs difference {fd}",
        cp.irrep
    );
    for (j, name) in study.parameters.iter().enumerate() {
        let mut pp = params.clone();
        let hj = 1e-6 * params[j].abs().max(1.0);
        pp[j] += hj;
        let sp = test.value(&u, &pp).unwrap().0;
        pp[j] -= 2.0 * hj;
        let sm = test.value(&u, &pp).unwrap().0;
        let fd = (sp - sm) / (2.0 * hj);
        let scale = fd.abs().max(t.grad_params[j].abs());
        assert!(
            (fd - t.grad_params[j]).abs() <= 1e-5 * scale,
            "{}: dσ/d{name}: {} vs difference {fd}",
            cp.irrep,
            t.grad_params[j]
        );
    }
    let (a, eps) = test.critical_vector(&t.vector);
    let amax = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!((eps * amax - DIFFERENCE_STEP * length).abs() < 1e-12 * eps * amax);
    let (d1, _) = test.third_derivatives(&u, &params, &a, eps).unwrap();
    let (d2, _) = test.third_derivatives(&u, &params, &a, 2.0 * eps).unwrap();
    let norm = d1.amax();
    let err = (&d2 - &d1).amax() / 3.0;
    assert!(
        norm > 0.0 && err < 1e-7 * norm,
        "{}: error {err:e} of {norm:e}",
        cp.irrep
    );
}

/// The test function's derivatives on the balloon's limit point (the trivial block: every
/// evaluation around the orbit representatives) and on the C7v disc's E1 double point (the
/// states u ± εa not symmetric: the whole mesh).
#[test]
fn block_test_function_derivatives_match_differences_of_sigma() {
    let mut study = MeshStudy::build(balloon_curve_scene(4)).unwrap();
    let result = run(&mut study, |_, _| {}).unwrap();
    check_test_derivatives(
        &study,
        result.report.critical.first().expect("a limit point"),
    );
    let mut study = MeshStudy::build(disc_curve_scene()).unwrap();
    let result = run(&mut study, |_, _| {}).unwrap();
    let cp = result.report.critical.last().expect("a critical point");
    assert_eq!(cp.irrep, "E1");
    check_test_derivatives(&study, cp);
}

/// A run writes curve.csv, curve.json and curve.svg; the CSV has a row per point with both
/// parameters and the block's eigenvalues.
#[test]
fn a_critical_curve_run_writes_its_curve() {
    let mut study = MeshStudy::build(balloon_curve_scene(4)).unwrap();
    let mut result = run(&mut study, |_, _| {}).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let written = memstab::analysis::write(&study, &mut result, dir.path()).unwrap();
    let curve = result.outcome::<CurveReport>().unwrap();
    // The path stopped at the point the curve starts from.
    assert_eq!(
        result.report.stop,
        memstab::results::StopReason::CriticalPoint
    );
    for name in ["curve.csv", "curve.json", "curve.svg"] {
        assert!(written.files().contains(&dir.path().join(name)), "{name}");
    }
    let csv = std::fs::read_to_string(dir.path().join("curve.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    for c in [
        "k",
        "p",
        "stretch",
        "critical_eigenvalue",
        "second_eigenvalue",
        "irrep",
    ] {
        assert!(header.contains(&c), "{header:?}");
    }
    assert_eq!(lines.count(), curve.rows.len());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("curve.json")).unwrap())
            .unwrap();
    assert_eq!(json["second"], "k");
    // The warnings of the curve's events, carried to curve.json (none on this curve).
    assert_eq!(
        json["warnings"].as_array().map(Vec::len),
        Some(curve.warnings.len()),
        "{}",
        json["warnings"]
    );
    assert!(curve.warnings.is_empty(), "{:?}", curve.warnings);
    assert!(json["events"]
        .as_array()
        .unwrap()
        .iter()
        .any(|e| e["kind"] == "cusp"));
    crate::common::figures::check_svg(&dir.path().join("curve.svg"));
    let svg = std::fs::read_to_string(dir.path().join("curve.svg")).unwrap();
    assert!(svg.contains("cusp"));
    // critical.json: the path's limit point, then the curve's events with parameters by name.
    let critical: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("critical.json")).unwrap())
            .unwrap();
    let list = critical.as_array().unwrap();
    assert_eq!(list[0]["kind"], "limit point");
    let cusp = list
        .iter()
        .find(|e| e["kind"] == "cusp")
        .expect("the cusp in critical.json");
    assert_eq!(cusp["curve"], true);
    assert_eq!(cusp["extremum"], "maximum");
    assert!(cusp["parameters"]["k"].as_f64().unwrap() > 0.2);
    assert!(cusp["measures"]["stretch"].as_f64().unwrap() > 1.8);
}

/// `memstab run` of a critical curve prints the curve's events and the curve files it wrote.
#[test]
fn memstab_run_prints_the_curve_and_its_files() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("curve.toml");
    std::fs::write(&scene, balloon_curve_text(4)).unwrap();
    let out = dir.path().join("out");
    let output = std::process::Command::new(env!("CARGO_BIN_EXE_memstab"))
        .args([
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "{stdout}");
    assert!(
        stdout.contains("critical curve of the limit point in Ag x1 in (p, k)"),
        "{stdout}"
    );
    assert!(
        stdout.lines().any(|l| l.trim_start().starts_with("cusp")),
        "{stdout}"
    );
    for name in ["curve.csv", "curve.json", "curve.svg"] {
        assert!(out.join(name).is_file(), "{name}");
        assert!(
            stdout.lines().any(|l| l.trim_start().starts_with(name)),
            "{name} not listed: {stdout}"
        );
    }
}

/// The bundled C7v disc pushed up by fluid from below (8 rings) with prestretch = "l0" and a
/// critical curve from its first E1 double point, in (h, l0).
fn disc_curve_scene() -> Scene {
    let text = std::fs::read_to_string(format!(
        "{}/scenes/disc_fluid_below.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let analysis = text.find("[analysis]").unwrap();
    let text = format!(
        "{}{}",
        &text[..analysis],
        r#"[parameters.l0]
start = 1.1
min = 1.05
max = 1.2

[analysis]
type = "critical-curve"
control = "h"
second = "l0"
from = "E1"
steps = 6
path-steps = 400
max-step = 0.05
"#
    )
    .replacen("divisions = 16", "divisions = 8", 1)
    .replacen("prestretch = 1.1", "prestretch = \"l0\"", 1);
    Scene::from_toml_str(&text, "disc-double-curve").unwrap()
}

/// Every accepted state of a run.
#[derive(Default)]
struct States(Vec<(Vec<f64>, Vec<f64>)>);

impl memstab::analysis::Observer for States {
    fn state(&mut self, u: &[f64], params: &[f64]) {
        self.0.push((u.to_vec(), params.to_vec()));
    }
}

/// The eigenvalues of the full tangent K (all unknowns, no symmetry used) at a state, by a
/// dense solve, sorted by modulus and relative to max|K_ij|.
fn full_spectrum(model: &memstab::model::FeModel, u: &[f64], params: &[f64]) -> Vec<f64> {
    let mut eval = model.new_evaluation();
    model
        .evaluate(u, params, memstab::model::Request::ALL, &mut eval)
        .unwrap();
    let n = model.unknowns();
    let mut k = nalgebra::DMatrix::zeros(n, n);
    let mut e = vec![0.0; n];
    for j in 0..n {
        e[j] = 1.0;
        let col = memstab::model::check::tangent_times(model, &eval, &e);
        k.set_column(j, &nalgebra::DVector::from_vec(col));
        e[j] = 0.0;
    }
    let scale = k.amax();
    let mut values: Vec<f64> = nalgebra::SymmetricEigen::new(k)
        .eigenvalues
        .iter()
        .map(|v| v / scale)
        .collect();
    values.sort_by(|a, b| a.abs().total_cmp(&b.abs()));
    values
}

/// The first E1 double bifurcation of the bundled C7v disc pushed up by fluid from below (8
/// rings) is followed in (level h, prestretch): its block's zero is simple, so the curve is
/// an ordinary one in that block, and at its ends the full tangent — all unknowns, no
/// symmetry used — has exactly two zero eigenvalues: the point stays double.
#[test]
fn a_double_point_of_the_c7v_disc_stays_double_along_its_curve() {
    let scene = disc_curve_scene();
    let mut study = MeshStudy::build(scene).unwrap();
    let mut states = States::default();
    let result = memstab::analysis::run_with(&mut study, &mut states).expect("the curve runs");
    let curve = result
        .outcome::<memstab::results::CurveReport>()
        .cloned()
        .expect("a curve");
    assert_eq!(curve.kind, CriticalKind::MultipleBifurcation(2));
    assert_eq!((curve.irrep.as_str(), curve.multiplicity), ("E1", 2));
    let l0 = col(&curve, "l0");
    let first = curve.rows.first().unwrap().parameters[l0];
    let last = curve.rows.last().unwrap().parameters[l0];
    assert!(
        (first - 1.1).abs() < 1e-12 && last > 1.1 + 0.01,
        "l0 {first} → {last}"
    );
    for r in &curve.rows {
        assert!(r.critical_eigenvalue.abs() < 1e-8, "{r:?}");
    }
    // The curve's points are the run's last accepted states.
    let n = curve.rows.len();
    let curve_states = &states.0[states.0.len() - n..];
    for (i, (u, p)) in [(0, &curve_states[0]), (n - 1, &curve_states[n - 1])] {
        assert_eq!(p, &curve.rows[i].parameters);
        let values = full_spectrum(&study.model, u, p);
        eprintln!(
            "curve point {i}: |eigenvalues| of K nearest zero {:?}",
            &values[..4]
        );
        assert!(
            values[0].abs() < 1e-8 && values[1].abs() < 1e-8,
            "{:?}",
            &values[..4]
        );
        assert!(values[2].abs() > 1e-5, "a third zero: {:?}", &values[..4]);
    }
}

/// The bundled C7v disc pushed up by fluid from below (8 rings) with the given analysis, and
/// k = "k" (start 0) as a parameter, or the material's k fixed at `k`.
fn disc_k_scene(analysis: &str, k: Option<f64>) -> Scene {
    let text = std::fs::read_to_string(format!(
        "{}/scenes/disc_fluid_below.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let at = text.find("[analysis]").unwrap();
    let (value, parameter) = match k {
        Some(k) => (format!("k = {k}\n"), String::new()),
        None => (
            "k = \"k\"\n".to_string(),
            "[parameters.k]\nstart = 0.0\nmin = 0.0\nmax = 0.5\n\n".to_string(),
        ),
    };
    let text = format!("{}{parameter}{analysis}", &text[..at])
        .replacen("divisions = 16", "divisions = 8", 1)
        .replacen("k = 0.0\n", &value, 1);
    assert!(text.contains(&value), "{text}");
    Scene::from_toml_str(&text, "disc-k").unwrap()
}

/// The disc's curve from `from` in (h, k), the other blocks watched or not.
fn disc_curve(from: &str, watch: bool) -> CurveReport {
    let scene = disc_k_scene(&format!(
        "[analysis]\ntype = \"critical-curve\"\ncontrol = \"h\"\nsecond = \"k\"\nfrom = \"{from}\"\n\
         steps = 60\npath-steps = 400\nmax-step = 0.05\nwatch = {watch}\n"
    ), None);
    let mut study = MeshStudy::build(scene).unwrap();
    let result = run(&mut study, |_, _| {}).expect("the curve runs");
    result
        .outcome::<memstab::results::CurveReport>()
        .cloned()
        .unwrap()
}

/// `watch = false`: the same limit curve of the disc, point for point, without the hilltop
/// that the watch of the E1 block finds on it.
#[test]
fn an_unwatched_curve_is_the_same_curve_without_its_hilltop() {
    let watched = disc_curve("limit", true);
    let unwatched = disc_curve("limit", false);
    let hilltops = |c: &CurveReport| {
        c.events
            .iter()
            .filter(|e| e.kind == CurveEventKind::Hilltop)
            .count()
    };
    assert_eq!(hilltops(&watched), 1, "{:?}", watched.events);
    assert_eq!(hilltops(&unwatched), 0, "{:?}", unwatched.events);
    assert_eq!(watched.rows.len(), unwatched.rows.len());
    for (a, b) in watched.rows.iter().zip(&unwatched.rows) {
        assert_eq!(a.parameters, b.parameters, "step {}", a.step);
    }
}

/// The one hilltop of the disc's curve from `from` in (h, k): its (h, k) and the other irrep.
fn disc_hilltop(from: &str) -> (f64, f64, String) {
    let curve = disc_curve(from, true);
    let hilltops: Vec<_> = curve
        .events
        .iter()
        .filter(|e| e.kind == CurveEventKind::Hilltop)
        .collect();
    assert_eq!(hilltops.len(), 1, "{:?}", curve.events);
    assert!(
        curve
            .events
            .windows(2)
            .all(|w| w[0].after_step <= w[1].after_step),
        "events out of curve order: {:?}",
        curve.events
    );
    let e = hilltops[0];
    assert!(e.residual_eigenvalue.unwrap() < 1e-10, "{e:?}");
    let (h, k) = (col(&curve, "h"), col(&curve, "k"));
    (e.parameters[h], e.parameters[k], e.irrep.clone().unwrap())
}

/// The disc pushed up from below, at k = 0, meets its limit point (A1) before its first
/// double point (E1) as the level rises; as k grows the limit point moves up faster, and
/// the two curves cross at a hilltop. Followed from either end — the E1 curve watching the
/// trivial block, the limit curve watching E1 — the hilltop is the same point; and paths in h
/// at fixed k on either side of it meet the two points in the opposite orders.
#[test]
fn the_disc_limit_and_double_point_curves_cross_at_one_hilltop() {
    let (h1, k1, other1) = disc_hilltop("E1");
    let (h2, k2, other2) = disc_hilltop("limit");
    assert_eq!((other1.as_str(), other2.as_str()), ("A1", "E1"));
    assert!(
        (h1 - h2).abs() < 1e-6 * h1 && (k1 - k2).abs() < 1e-6 * k1,
        "the E1 curve's hilltop ({h1}, {k1}) and the limit curve's ({h2}, {k2})"
    );
    assert!(k1 > 0.005 && k1 < 0.1, "k = {k1}");
    // The order of the two points on paths at fixed k on either side.
    let first_on_path = |k: f64| {
        let scene = disc_k_scene(
            "[analysis]\ntype = \"path\"\ncontrol = \"h\"\nsteps = 400\nmax-step = 0.05\n",
            Some(k),
        );
        let mut study = MeshStudy::build(scene).unwrap();
        let result = run(&mut study, |_, _| {}).expect("the path runs");
        let h = result
            .report
            .parameters
            .iter()
            .position(|p| p == "h")
            .unwrap();
        let mut points: Vec<(usize, f64, String)> = result
            .report
            .critical
            .iter()
            .filter(|c| c.irrep == "A1" || c.irrep == "E1")
            .map(|c| (c.after_step, c.parameters[h], c.irrep.clone()))
            .collect();
        points.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
        assert!(points.len() >= 2, "k = {k}: {points:?}");
        // Both near the hilltop's level.
        for p in &points[..2] {
            assert!((p.1 - h1).abs() < 0.2, "k = {k}: {points:?}");
        }
        points[0].2.clone()
    };
    assert_eq!(first_on_path(k1 - 0.003), "A1");
    assert_eq!(first_on_path(k1 + 0.003), "E1");
}

/// `from-run`: the curve of a finished path run's first critical point (the pressure maximum)
/// starts at that point — its saved state and mode, without a path — and is the curve that the
/// scene's own path finds; `from` must then be an index of one of the run's critical points.
#[test]
fn a_curve_starts_from_a_finished_runs_critical_point() {
    let curve_text = balloon_curve_text(4);
    let at = curve_text.find("[analysis]").unwrap();
    let end = at + curve_text[at..].find("\n\n").unwrap();
    let path_text = format!(
        "{}[[constraint]]\ntype = \"fixed\"\nparameter = \"k\"\n\n[analysis]\ntype = \"path\"\n\
         control = \"p\"\nsteps = 40\nmax-step = 0.05\n{}",
        &curve_text[..at],
        &curve_text[end..]
    );
    let mut study =
        MeshStudy::build(Scene::from_toml_str(&path_text, "balloon-path").unwrap()).unwrap();
    let mut result = run(&mut study, |_, _| {}).unwrap();
    assert_eq!(result.report.critical[0].kind, CriticalKind::LimitPoint);
    let dir = tempfile::tempdir().unwrap();
    memstab::output::write_run(&study, &study.scene, &mut result, dir.path()).unwrap();
    let from_run = |from: &str| {
        curve_text.replacen(
            "from = \"limit\"\n",
            &format!("from = {from}\nfrom-run = \"{}\"\n", dir.path().display()),
            1,
        )
    };
    let scene = Scene::from_toml_str(&from_run("0"), "balloon-from-run").unwrap();
    let mut study = MeshStudy::build(scene).unwrap();
    let start = memstab::analysis::restart::start_of(&study).unwrap();
    let resumed = memstab::analysis::run_from(
        &mut study,
        &start,
        &mut memstab::analysis::Progress(|_, _| {}),
    )
    .expect("the curve runs from the saved point");
    // No path: the saved point is the run's one row and critical point.
    assert_eq!(resumed.report.rows.len(), 1);
    assert_eq!(resumed.report.critical.len(), 1);
    let resumed = resumed
        .outcome::<memstab::results::CurveReport>()
        .cloned()
        .unwrap();
    let (own, _) = curve_of(4);
    assert_eq!(
        (resumed.kind, resumed.irrep.as_str()),
        (own.kind, own.irrep.as_str())
    );
    let (p, k) = (col(&own, "p"), col(&own, "k"));
    let (a, b) = (&resumed.rows[0], &own.rows[0]);
    assert!(
        (a.parameters[p] / b.parameters[p] - 1.0).abs() < 1e-8,
        "{a:?} vs {b:?}"
    );
    assert_eq!(a.parameters[k], b.parameters[k]);
    let cusp = |c: &CurveReport| {
        c.events
            .iter()
            .find(|e| e.kind == CurveEventKind::Cusp)
            .map(|e| (e.parameters[p], e.parameters[k]))
            .expect("a cusp")
    };
    let (x, y) = (cusp(&resumed), cusp(&own));
    assert!(
        (x.0 / y.0 - 1.0).abs() < 1e-6 && (x.1 / y.1 - 1.0).abs() < 1e-6,
        "cusps {x:?} and {y:?}"
    );
    // `from` must be an index of the run's critical points.
    let err = Scene::from_toml_str(&from_run("\"limit\""), "limit")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("analysis.from") && err.contains("from-run"),
        "{err}"
    );
    let scene = Scene::from_toml_str(&from_run("7"), "seven").unwrap();
    let study = MeshStudy::build(scene).unwrap();
    let err = memstab::analysis::restart::start_of(&study).unwrap_err();
    assert!(
        err.contains("'analysis.from' = 7") && err.contains("critical point"),
        "{err}"
    );
}

/// A Mooney–Rivlin balloon (k = 0.1, f = `frequency`) under two pressures on the same volume:
/// the control p, and the over-pressure q of a fixed amount of gas, (P + q)·V = n with
/// P = 0.1 (a `gas-amount` constraint governing q, its amount the parameter n). Under p the
/// balloon folds where dp/dV = 0 with p = p_s(V) − n/V + P (p_s the sphere's pressure): a
/// limit point of the constrained path, whose bordered trivial block is singular there.
/// `analysis` is the scene's `[analysis]` table and any constraint it needs.
fn reservoir_balloon_text(frequency: usize, analysis: &str) -> String {
    reservoir_balloon(
        "reservoir-balloon",
        &format!("generator = \"icosphere\"\nradius = 1.0\nfrequency = {frequency}"),
        analysis,
    )
}

const RESERVOIR_CURVE: &str = r#"[analysis]
type = "critical-curve"
control = "p"
second = "n"
from = "limit"
steps = 6
path-steps = 400
max-step = 0.1
"#;

/// The reservoir balloon's limit pressure at amount n in closed form.
fn reservoir_limit_p(n: f64) -> f64 {
    reservoir_limit(n).0
}

/// The test function bordered by the gas-amount constraint: its derivatives in q and in every
/// parameter (n, q, p) against differences of σ, near the constrained limit point.
#[test]
fn constrained_block_test_function_derivatives_match_differences_of_sigma() {
    let scene =
        Scene::from_toml_str(&reservoir_balloon_text(3, RESERVOIR_CURVE), "reservoir").unwrap();
    let mut study = MeshStudy::build(scene).unwrap();
    let result = run(&mut study, |_, _| {}).unwrap();
    let cp = result.report.critical.first().expect("a limit point");
    assert_eq!(cp.kind, CriticalKind::LimitPoint);
    check_test_derivatives(&study, cp);
}

/// The constrained limit point followed in (p, n): at three points of the curve its pressure
/// is the limit point that an ordinary constrained path in p at that fixed n localises, and
/// every point lies on the closed-form fold line to the mesh's error.
#[test]
fn constrained_limit_curve_agrees_with_paths_at_fixed_amounts_and_the_closed_form() {
    let scene =
        Scene::from_toml_str(&reservoir_balloon_text(3, RESERVOIR_CURVE), "reservoir").unwrap();
    let mut study = MeshStudy::build(scene).unwrap();
    let result = run(&mut study, |_, _| {}).expect("the constrained curve runs");
    let curve = result
        .outcome::<memstab::results::CurveReport>()
        .cloned()
        .expect("a curve");
    assert_eq!(curve.kind, CriticalKind::LimitPoint);
    let (p, q, n) = (col(&curve, "p"), col(&curve, "q"), col(&curve, "n"));
    assert!(curve.rows.len() >= 4, "{} points", curve.rows.len());
    for r in &curve.rows {
        let closed = reservoir_limit_p(r.parameters[n]);
        eprintln!(
            "n = {}: p = {}, q = {}, closed form p = {closed}",
            r.parameters[n], r.parameters[p], r.parameters[q]
        );
        assert!(r.critical_eigenvalue.abs() < 1e-8, "{r:?}");
        assert!((r.parameters[p] / closed - 1.0).abs() < 8e-2, "{r:?}");
    }
    for r in curve.rows.iter().skip(1).take(3) {
        let path = reservoir_path_limit("", r.parameters[n]);
        let rel = (path / r.parameters[p] - 1.0).abs();
        eprintln!(
            "n = {}: curve p = {}, path limit p = {path}, relative {rel:e}",
            r.parameters[n], r.parameters[p]
        );
        assert!(rel < 1e-6, "n = {}: {rel:e}", r.parameters[n]);
    }
}

/// The limit pressure that a constrained path in p of the reservoir balloon (with the extra
/// scene text `extra` before its path analysis) localises at the amount n = `amount`.
fn reservoir_path_limit(extra: &str, amount: f64) -> f64 {
    let text = reservoir_balloon_text(3, &format!("{extra}{RESERVOIR_PATH}")).replacen(
        "start = 1.94",
        &format!("start = {amount:.17e}"),
        1,
    );
    let mut study =
        MeshStudy::build(Scene::from_toml_str(&text, "reservoir-path").unwrap()).unwrap();
    let result = run(&mut study, |_, _| {}).expect("the path runs");
    let limit = result
        .report
        .critical
        .iter()
        .find(|c| c.kind == CriticalKind::LimitPoint)
        .expect("a limit point on the path");
    let pi = study.parameters.iter().position(|x| x == "p").unwrap();
    limit.parameters[pi]
}

/// The reservoir balloon with a second reservoir (the over-pressure r of a fixed amount 0.97,
/// a second `gas-amount` constraint): the limit point followed in (p, n) with both constraints
/// active along the curve. The fold line is the one-reservoir line at the total amount
/// n + 0.97 raised by the second ambient P = 0.1: p = p_s(V) − (n + 0.97)/V + 2P. Each point
/// keeps the second amount, and is the limit point a constrained path at its n localises.
#[test]
fn a_limit_curve_with_two_constraints_keeps_both_and_agrees_with_paths() {
    let second = "[[effect]]\ntype = \"gas\"\npressure = \"r\"\n\n[parameters.r]\nstart = 0.1\n\n\
                  [[constraint]]\ntype = \"gas-amount\"\neffect = 2\nvalue = 0.97\n\
                  ambient-pressure = 0.1\n\n";
    let text = reservoir_balloon_text(3, &format!("{second}{RESERVOIR_CURVE}"));
    let mut study =
        MeshStudy::build(Scene::from_toml_str(&text, "two-reservoirs").unwrap()).unwrap();
    assert_eq!(study.constraints.len(), 2);
    let result = run(&mut study, |_, _| {}).expect("the curve runs");
    let curve = result
        .outcome::<memstab::results::CurveReport>()
        .cloned()
        .expect("a curve");
    assert_eq!(curve.kind, CriticalKind::LimitPoint);
    let (p, n, r) = (col(&curve, "p"), col(&curve, "n"), col(&curve, "r"));
    let volume = curve.measures.iter().position(|m| m == "volume").unwrap();
    assert!(curve.rows.len() >= 4, "{} points", curve.rows.len());
    let (mut held, mut closed_worst) = (0.0f64, 0.0f64);
    for row in &curve.rows {
        held = held.max(((0.1 + row.parameters[r]) * row.measures[volume] - 0.97).abs());
        let closed = reservoir_limit_p(row.parameters[n] + 0.97) + 0.1;
        closed_worst = closed_worst.max((row.parameters[p] / closed - 1.0).abs());
        assert!(row.critical_eigenvalue.abs() < 1e-8, "{row:?}");
    }
    eprintln!(
        "{} points, n from {} to {}: second amount kept to {held:e}, closed form within \
         {closed_worst:e}",
        curve.rows.len(),
        curve.rows[0].parameters[n],
        curve.rows.last().unwrap().parameters[n]
    );
    assert!(held < 1e-9, "the second amount drifts by {held:e}");
    // f = 3 (180 triangles), the mesh's error: measured 2.0 %.
    assert!(closed_worst < 3e-2, "{closed_worst:e}");
    for row in curve.rows.iter().skip(1).take(2) {
        let path = reservoir_path_limit(second, row.parameters[n]);
        let rel = (path / row.parameters[p] - 1.0).abs();
        eprintln!(
            "n = {}: curve p = {}, path {path}",
            row.parameters[n], row.parameters[p]
        );
        assert!(rel < 1e-6, "n = {}: {rel:e}", row.parameters[n]);
    }
}
