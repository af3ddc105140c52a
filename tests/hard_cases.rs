//! Hard cases stay numerically stable: each case converges or stops with a
//! clear report — never a panic, never NaN or infinity in any output row — and each is a test.
//!
//! 1. The neo-Hookean (k = 0) balloon driven to stretch 5: one pressure maximum, then the
//!    pressure falls far; the path must neither stall nor jump branches.
//! 2. A rigid plane with penalty 10⁸ μH/R (linear and cubic) squeezing a gas-filled icosphere
//!    until contact spreads over many nodes.
//! 3. A waterline passing exactly through nodes and along edges (degenerate clipping): model
//!    level (finite, symmetric, derivatives) and scenes (an equilibrium, a path in density).
//! 4. A fluid level swept from below the lowest node to above the highest.
//! 5. Nearly flat and nearly degenerate triangles, collapsed elements, and a step so large
//!    that the corrector fails and the step must be cut.
//!
//! Scenes live in `tests/data/hard/`; the k = 0 balloon is the bundled `scenes/balloon_k0.toml`.

use memstab::adapted::SparseBasis;
use memstab::analysis::run;
use memstab::continuation::events::trace;
use memstab::continuation::events::Branch;
use memstab::continuation::{step_from, Continuation, PathOptions};
use memstab::effects::gas::GasPressure;
use memstab::effects::hydrostatic::{Fluid, FluidSide};
use memstab::effects::membrane::{Membrane, MooneyRivlin};
use memstab::effects::Quantity;
use memstab::model::check::check_derivatives;
use memstab::model::{Effect, Evaluation, FeModel, Model, ModelError, Request, Vec3};
use memstab::results::{PathReport, RunResult, StopReason};
use memstab::scene::Scene;
use memstab::study::mesh::MeshStudy;
use memstab::study::SymmetricProblem;
use meshes::generators::{
    disc, icosphere, truncated_sphere, DiscOptions, IcosphereOptions, TruncatedSphereOptions,
};
use meshes::GroupAction;
use nalgebra::{DMatrix, DVector};
use std::path::PathBuf;
use std::process::Command;

// ---------------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------------

fn manifest() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn data(name: &str) -> PathBuf {
    manifest().join("tests/data/hard").join(name)
}

fn read(path: &std::path::Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// `text` with `from` replaced by `to`; `from` must occur.
fn edit(text: &str, from: &str, to: &str) -> String {
    assert!(text.contains(from), "the scene has no {from:?}");
    text.replace(from, to)
}

fn study_of(text: &str, origin: &str) -> MeshStudy {
    let scene = Scene::from_toml_str(text, origin).unwrap_or_else(|e| panic!("{origin}: {e}"));
    MeshStudy::build(scene).unwrap_or_else(|e| panic!("{origin}: {e}"))
}

/// Runs the study; every row finite and the stop reason clear.
fn run_checked(study: &mut MeshStudy) -> RunResult {
    let result = run(study, |_, _| {}).unwrap_or_else(|e| panic!("the start failed: {e}"));
    let r = &result.report;
    assert!(
        r.rows.len() >= 2,
        "a path of {} points: {}",
        r.rows.len(),
        r.stop
    );
    for row in &r.rows {
        assert!(
            row.parameters
                .iter()
                .chain(&row.measures)
                .all(|v| v.is_finite())
                && row.arclength.is_finite(),
            "non-finite row {row:?}"
        );
    }
    for t in &r.turning_points {
        assert!(
            t.parameters
                .iter()
                .chain(&t.measures)
                .all(|v| v.is_finite()),
            "non-finite turning point {t:?}"
        );
    }
    for s in &result.states {
        assert!(
            s.u.iter().all(|v| v.is_finite()),
            "non-finite state {}",
            s.label()
        );
    }
    assert_clear_stop(&r.stop.to_string());
    result
}

/// A stop reason says why, and an early stop says where.
fn assert_clear_stop(stop: &str) {
    assert!(!stop.trim().is_empty(), "no stop reason");
    assert!(!stop.contains('\n'), "a stop reason is one line: {stop}");
    if stop.contains("step cut") {
        assert!(
            stop.contains("after point") && stop.contains("control ="),
            "an early stop must say where: {stop}"
        );
    }
}

fn column(report: &PathReport, name: &str) -> usize {
    report
        .measures
        .iter()
        .position(|m| m == name)
        .unwrap_or_else(|| panic!("no measure {name} in {:?}", report.measures))
}

fn parameter(report: &PathReport, name: &str) -> usize {
    report
        .parameters
        .iter()
        .position(|m| m == name)
        .unwrap_or_else(|| panic!("no parameter {name} in {:?}", report.parameters))
}

/// The positions of the last path point.
fn last_positions(study: &MeshStudy, result: &RunResult) -> Vec<Vec3> {
    let last = result.report.rows.len() - 1;
    let label = format!("step {last}");
    let state = result
        .states
        .iter()
        .find(|s| s.label() == label)
        .expect("the last point is saved");
    study.model.positions(&state.u, &state.params)
}

/// Runs `memstab run SCENE --out DIR --quiet --json`; checks the exit code (0, or 1 with a
/// one-line message) and that path.csv has only finite numbers. Returns the JSON summary
/// and path.csv's header and rows.
fn cli_run(scene: &std::path::Path) -> (serde_json::Value, Vec<String>, Vec<Vec<f64>>) {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let out_dir = dir.path().join("out");
    let out = Command::new(env!("CARGO_BIN_EXE_memstab"))
        .arg("run")
        .arg(scene)
        .arg("--out")
        .arg(&out_dir)
        .args(["--quiet", "--json"])
        .output()
        .expect("the memstab binary runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    match out.status.code() {
        Some(0) => {}
        Some(1) => {
            assert_eq!(
                stderr.trim().lines().count(),
                1,
                "exit code 1 needs a one-line message: {stderr}"
            );
            panic!("{}: the run failed cleanly: {stderr}", scene.display());
        }
        code => panic!("{}: exit code {code:?}: {stdout}{stderr}", scene.display()),
    }
    let csv = read(&out_dir.join("path.csv"));
    let lower = csv.to_lowercase();
    assert!(!lower.contains("nan") && !lower.contains("inf"), "{csv}");
    let mut lines = csv.lines();
    let mut header: Vec<String> = lines
        .next()
        .expect("a header")
        .split(',')
        .map(String::from)
        .collect();
    // The numbers, without the last column (the flags' names).
    assert_eq!(header.pop().as_deref(), Some("flags"));
    let rows: Vec<Vec<f64>> = lines
        .map(|line| {
            let (numbers, _flags) = line.rsplit_once(',').expect("a flags column");
            let row: Vec<f64> = numbers
                .split(',')
                .map(|c| c.parse().unwrap_or_else(|_| panic!("cell {c:?} in {line}")))
                .collect();
            assert_eq!(row.len(), header.len(), "{line}");
            assert!(row.iter().all(|v| v.is_finite()), "{line}");
            row
        })
        .collect();
    assert!(rows.len() >= 2, "path.csv has {} rows", rows.len());
    let json: serde_json::Value = serde_json::from_str(&stdout).expect("--json prints JSON");
    assert_clear_stop(json["stop"].as_str().expect("a stop reason"));
    (json, header, rows)
}

fn csv_column(header: &[String], name: &str) -> usize {
    header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name} in {header:?}"))
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

/// Evaluates everything at (u, Λ) and checks that it is finite.
fn evaluate_finite(model: &FeModel, u: &[f64], params: &[f64]) -> Evaluation {
    let mut e = model.new_evaluation();
    model
        .evaluate(u, params, Request::ALL, &mut e)
        .unwrap_or_else(|err| panic!("evaluation at {params:?} failed: {err}"));
    assert!(e.energy.is_finite());
    assert!(e.residual.iter().all(|v| v.is_finite()));
    assert!(e.tangent.iter().all(|v| v.is_finite()));
    assert!(e.loads.iter().flatten().all(|v| v.is_finite()));
    e
}

/// max |K_ij − K_ji| over the pattern.
fn asymmetry(model: &FeModel, e: &Evaluation) -> f64 {
    let p = model.pattern();
    let mut worst: f64 = 0.0;
    for j in 0..p.n() {
        for k in p.col_ptr()[j]..p.col_ptr()[j + 1] {
            let i = p.row_idx()[k];
            let t = p.position(j, i).expect("symmetric pattern");
            worst = worst.max((e.tangent[k] - e.tangent[t]).abs());
        }
    }
    worst
}

/// The dense full tangent (sparse part; no rank-one terms in these models).
fn dense_tangent(model: &FeModel, e: &Evaluation) -> DMatrix<f64> {
    let p = model.pattern();
    let n = p.n();
    let mut k = DMatrix::zeros(n, n);
    for j in 0..n {
        for s in p.col_ptr()[j]..p.col_ptr()[j + 1] {
            k[(p.row_idx()[s], j)] = e.tangent[s];
        }
    }
    assert!(e.rank_one.is_empty());
    k
}

/// A deterministic pseudo-random number in [−1, 1).
fn noise(i: usize) -> f64 {
    let x = (i as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    let x = (x ^ (x >> 29)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    ((x >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

/// A displacement that moves every free node horizontally only (so node heights stay exact):
/// a radial expansion by `grow` plus a small pseudo-random horizontal jiggle.
fn horizontal_displacement(model: &FeModel, grow: f64, jiggle: f64) -> Vec<f64> {
    let mut u = vec![0.0; model.unknowns()];
    for (i, x) in model.reference().iter().enumerate() {
        for c in 0..2 {
            if let Some(d) = model.layout().dof(i, c) {
                u[d] = grow * x[c] + jiggle * noise(3 * i + c);
            }
        }
    }
    u
}

// ---------------------------------------------------------------------------------------------
// 1. The k = 0 balloon to stretch 5
// ---------------------------------------------------------------------------------------------

/// The closed form of the neo-Hookean sphere, p R/(μH) = 2 (λ⁻¹ − λ⁻⁷).
fn closed_form_k0(l: f64) -> f64 {
    2.0 * (1.0 / l - l.powi(-7))
}

use memstab::reference::P_MAX_K0;
const L_MAX_K0: f64 = 1.3830876;

#[test]
fn k0_balloon_reaches_stretch_5_on_one_branch_without_stalling() {
    let path = manifest().join("scenes/balloon_k0.toml");
    let mut study = study_of(&read(&path), "scenes/balloon_k0.toml");
    let result = run_checked(&mut study);
    let r = &result.report;
    let (p, s) = (parameter(r, "p"), column(r, "stretch"));
    // It reaches the stretch 5, and says so.
    let last = r.rows.last().unwrap();
    assert!(r.stop.to_string().contains("stretch reached"), "{}", r.stop);
    assert!(
        last.measures[s] >= 5.0,
        "final stretch {}",
        last.measures[s]
    );
    // Exactly one turning point, the maximum, near the closed form (f = 8: the
    // discretisation error is about 0.4 % in p).
    let kinds: Vec<String> = r
        .turning_points
        .iter()
        .map(|t| t.kind.to_string())
        .collect();
    assert_eq!(kinds, ["maximum"], "turning points");
    let max = &r.turning_points[0];
    let (p_max, l_max) = (max.parameters[p], max.measures[s]);
    assert!(
        (p_max - P_MAX_K0).abs() < 0.01 * P_MAX_K0,
        "maximum p = {p_max}, closed form {P_MAX_K0}"
    );
    assert!(
        (l_max - L_MAX_K0).abs() < 0.01,
        "maximum at stretch {l_max}, closed form {L_MAX_K0}"
    );
    // No branch jump: the stretch grows monotonically, every row lies on the closed form
    // within 2 %, p rises to the maximum and then falls monotonically.
    let mut worst: f64 = 0.0;
    for w in r.rows.windows(2) {
        assert!(
            w[1].measures[s] > w[0].measures[s],
            "the stretch went back at step {}",
            w[1].step
        );
    }
    for row in &r.rows {
        let (l, pv) = (row.measures[s], row.parameters[p]);
        let rel = (pv - closed_form_k0(l)).abs() / closed_form_k0(l);
        worst = worst.max(rel);
        assert!(
            rel < 0.02,
            "step {}: p = {pv} at stretch {l}, closed form {}",
            row.step,
            closed_form_k0(l)
        );
        if l > l_max + 1e-9 {
            assert!(pv < p_max, "step {}: p = {pv} above the maximum", row.step);
        }
    }
    let direction_changes = r
        .rows
        .windows(3)
        .filter(|w| {
            let (a, b) = (
                w[1].parameters[p] - w[0].parameters[p],
                w[2].parameters[p] - w[1].parameters[p],
            );
            a.signum() != b.signum()
        })
        .count();
    assert_eq!(direction_changes, 1, "p must rise, peak once and fall");
    let falling = r
        .rows
        .iter()
        .filter(|row| row.measures[s] > l_max)
        .map(|row| row.parameters[p])
        .collect::<Vec<_>>();
    assert!(
        falling.windows(2).all(|w| w[1] < w[0]),
        "p falls monotonically after the maximum"
    );
    assert!(
        last.parameters[p] < 0.35 * p_max,
        "the pressure falls far: {} at the end",
        last.parameters[p]
    );
    // The step control did not stall: a reasonable number of points, no tiny steps, few
    // Newton iterations.
    let n = r.rows.len();
    assert!((10..=200).contains(&n), "{n} points");
    for w in r.rows.windows(2) {
        assert!(
            w[1].arclength - w[0].arclength >= 0.01,
            "step {}: arclength step {} (stalling)",
            w[1].step,
            w[1].arclength - w[0].arclength
        );
    }
    assert!(r.rows.iter().all(|row| row.iterations <= 10));
    eprintln!(
        "k = 0 balloon: {n} points, final stretch {:.4}, p from {:.4} over the maximum {p_max:.6} \
         at stretch {l_max:.6} to {:.4}; largest deviation from the closed form {:.2} %",
        last.measures[s],
        r.rows[0].parameters[p],
        last.parameters[p],
        100.0 * worst
    );
}

#[test]
fn k0_balloon_through_the_cli() {
    let (json, header, rows) = cli_run(&manifest().join("scenes/balloon_k0.toml"));
    let s = csv_column(&header, "stretch");
    let last = rows.last().unwrap();
    assert!(last[s] >= 5.0, "final stretch {}", last[s]);
    assert!(json["stop"].as_str().unwrap().contains("stretch"), "{json}");
    assert_eq!(
        json["turning_points"].as_array().map(Vec::len),
        Some(1),
        "{json}"
    );
}

// ---------------------------------------------------------------------------------------------
// 2. A stiff plane (penalty 1e8 μH/R) until contact spreads
// ---------------------------------------------------------------------------------------------

/// Runs a squeeze scene (upper plane z ≤ `top`) and checks the contact: returns (points,
/// bottom contact nodes, top contact nodes, nodes, final d).
fn squeeze(
    name: &str,
    group: &str,
    top: f64,
    penetration: f64,
) -> (usize, usize, usize, usize, f64) {
    let mut study = study_of(&read(&data(name)), name);
    // A sphere between horizontal planes keeps the group of the vertical axis: the icosphere
    // with a vertex down keeps C5v, with a face down C3v.
    assert_eq!(study.action.group().name(), group);
    let result = run_checked(&mut study);
    let r = &result.report;
    let (d, min_z, max_z) = (parameter(r, "d"), column(r, "min_z"), column(r, "max_z"));
    let vol = column(r, "volume");
    let last = r.rows.last().unwrap();
    assert!(
        r.stop.to_string().contains("left its [min, max]") && last.parameters[d] >= -0.3,
        "the plane must reach d = -0.3: {} at d = {}",
        r.stop,
        last.parameters[d]
    );
    for row in &r.rows {
        // Both planes are in contact all along, and the stiff penalty keeps the penetration
        // tiny (linear: F/κ; cubic: (F/κ)^(1/3)).
        let below = row.parameters[d] - row.measures[min_z];
        let above = row.measures[max_z] - top;
        assert!(
            (0.0..penetration).contains(&below) && (0.0..penetration).contains(&above),
            "step {}: penetrations {below:e} (lower) and {above:e} (upper)",
            row.step
        );
    }
    // Squeezing at fixed pressure reduces the volume monotonically.
    assert!(r
        .rows
        .windows(2)
        .all(|w| w[1].measures[vol] < w[0].measures[vol]));
    let x = last_positions(&study, &result);
    let d_end = last.parameters[d];
    let bottom = x.iter().filter(|p| p.z < d_end + 1e-9).count();
    let top = x.iter().filter(|p| p.z > top - 1e-9).count();
    assert!(
        10 * bottom >= x.len() && 10 * top >= x.len(),
        "contact must spread over >= 10 % of the {} nodes: {bottom} on the lower plane, {top} on the upper",
        x.len()
    );
    (r.rows.len(), bottom, top, x.len(), d_end)
}

#[test]
fn stiff_linear_plane_squeezes_a_balloon_until_contact_spreads() {
    let (n, bottom, top, nodes, d) = squeeze("squeeze_linear.toml", "C5v", 1.09, 1e-5);
    eprintln!(
        "linear penalty: {n} points to d = {d:.4}; contact {bottom} + {top} of {nodes} nodes"
    );
}

#[test]
fn stiff_cubic_plane_squeezes_a_balloon_until_contact_spreads() {
    let (n, bottom, top, nodes, d) = squeeze("squeeze_cubic.toml", "C3v", 1.07, 5e-3);
    eprintln!("cubic penalty: {n} points to d = {d:.4}; contact {bottom} + {top} of {nodes} nodes");
}

#[test]
fn stiff_cubic_plane_through_the_cli() {
    let (json, header, rows) = cli_run(&data("squeeze_cubic.toml"));
    let (d, min_z) = (csv_column(&header, "d"), csv_column(&header, "min_z"));
    let last = rows.last().unwrap();
    assert!(last[d] >= -0.3, "{json}");
    assert!((0.0..5e-3).contains(&(last[d] - last[min_z])), "{last:?}");
}

// ---------------------------------------------------------------------------------------------
// 3. The waterline exactly through nodes and along edges
// ---------------------------------------------------------------------------------------------

/// Membrane, gas and fluid inside (level = parameter 0) on a mesh.
fn fluid_model(
    nodes: Vec<Vec3>,
    triangles: Vec<[usize; 3]>,
    fixed: &[usize],
    prestretch: f64,
) -> FeModel {
    let membrane = Membrane::new(
        &nodes,
        &triangles,
        MooneyRivlin::new(1.0, 0.1, 1.0),
        prestretch,
    )
    .expect("a valid mesh");
    let effects: Vec<Box<dyn Effect>> = vec![
        Box::new(membrane),
        Box::new(GasPressure {
            closing: None,
            pressure: Quantity::Value(0.5),
        }),
        Box::new(Fluid {
            filled: false,
            closing: None,
            density: Quantity::Value(1.0),
            gravity: Quantity::Value(1.0),
            level: Quantity::Parameter(0),
            side: FluidSide::Behind,
        }),
    ];
    FeModel::new(nodes, triangles, fixed, effects, vec!["h".into()])
}

/// At the level exactly through nodes: finite, symmetric, the gradient matches differences of
/// Π, the tangent and load match differences of F to first order (the Hessian has a kink
/// there), and K and ∂F/∂h are continuous across the level (∂F/∂h relative to
/// `load_scale`, its size with the level inside the membrane). Returns the worst errors.
fn check_at_level(model: &FeModel, u: &[f64], h: f64, load_scale: f64) -> [f64; 4] {
    let e = evaluate_finite(model, u, &[h]);
    let k_norm = max_abs(&e.tangent);
    let asym = asymmetry(model, &e) / k_norm;
    assert!(asym <= 1e-14, "asymmetry {asym:e} at h = {h}");
    let dir: Vec<f64> = (0..u.len()).map(|i| noise(7 * i + 1)).collect();
    let err = check_derivatives(model, u, &[h], &dir, 1e-7)
        .unwrap_or_else(|e| panic!("derivative check at h = {h}: {e}"));
    assert!(
        err.residual < 1e-6,
        "gradient vs FD of Π at h = {h}: {err:?}"
    );
    assert!(err.tangent < 1e-4, "tangent vs FD of F at h = {h}: {err:?}");
    assert!(err.loads < 1e-4, "∂F/∂h vs FD at h = {h}: {err:?}");
    // Continuity across the level: the Hessian is continuous where the level crosses a node
    // of non-horizontal triangles.
    let mut jump: f64 = 0.0;
    for dh in [-1e-10, 1e-10] {
        let f = evaluate_finite(model, u, &[h + dh]);
        let dk = e
            .tangent
            .iter()
            .zip(&f.tangent)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        let dl = max_abs(
            &e.loads[0]
                .iter()
                .zip(&f.loads[0])
                .map(|(a, b)| a - b)
                .collect::<Vec<_>>(),
        );
        jump = jump.max(dk / k_norm).max(dl / load_scale);
    }
    assert!(jump < 1e-6, "K or ∂F/∂h jumps by {jump:e} across h = {h}");
    [asym, err.residual, err.tangent.max(err.loads), jump]
}

#[test]
fn waterline_through_node_rings_of_a_clamped_cap_is_finite_and_symmetric() {
    let sym = truncated_sphere(&TruncatedSphereOptions {
        radius: 1.0,
        cut_height: -0.5,
        pattern: "C8v".into(),
        divisions: 6,
    })
    .unwrap();
    let m = sym.mesh;
    let model = fluid_model(
        m.nodes.clone(),
        m.triangles.clone(),
        &m.boundaries["cut"],
        1.05,
    );
    let mut heights: Vec<f64> = m.nodes.iter().map(|x| x.z).collect();
    heights.sort_by(f64::total_cmp);
    heights.dedup();
    // Rings sit at exactly equal heights (7 for 6 divisions: the cut, five rings, the pole).
    assert_eq!(heights.len(), 7, "{heights:?}");
    let mut worst = [0.0f64; 4];
    for u in [
        vec![0.0; model.unknowns()],
        horizontal_displacement(&model, 0.04, 0.01),
    ] {
        for &h in &heights {
            let on_level = model.positions(&u, &[]).iter().filter(|x| x.z == h).count();
            assert!(on_level >= 1);
            let scale = max_abs(&evaluate_finite(&model, &u, &[0.25]).loads[0]);
            let e = check_at_level(&model, &u, h, scale);
            for k in 0..4 {
                worst[k] = worst[k].max(e[k]);
            }
        }
    }
    eprintln!(
        "cap, level through each of {} node rings: asymmetry {:.1e}, gradient {:.1e}, \
         tangent/loads (first order) {:.1e}, jump across the level {:.1e}",
        heights.len(),
        worst[0],
        worst[1],
        worst[2],
        worst[3]
    );
}

#[test]
fn waterline_along_the_equator_edges_of_an_icosphere_is_finite_and_symmetric() {
    // The plane z = 0 is a mirror of the icosphere: it contains two icosahedron edges (their
    // f + 1 nodes and f segments each) and crosses the faces between them through nodes.
    // Replication leaves those nodes at |z| ~ 1e-17; snap them to exactly 0.
    let mut m = icosphere(&IcosphereOptions {
        radius: 1.0,
        frequency: 4,
    })
    .unwrap()
    .mesh;
    for x in &mut m.nodes {
        if x.z.abs() < 1e-12 {
            x.z = 0.0;
        }
    }
    let on = |i: usize| m.nodes[i].z == 0.0;
    let nodes_on = (0..m.nodes.len()).filter(|&i| on(i)).count();
    let edge_on = m
        .triangles
        .iter()
        .filter(|t| t.iter().filter(|&&i| on(i)).count() == 2)
        .count();
    let node_on_straddling = m
        .triangles
        .iter()
        .filter(|t| {
            let z: Vec<f64> = t.iter().map(|&i| m.nodes[i].z).collect();
            t.iter().filter(|&&i| on(i)).count() == 1
                && z.iter().any(|&v| v > 0.0)
                && z.iter().any(|&v| v < 0.0)
        })
        .count();
    assert_eq!(nodes_on, 16);
    assert!(
        edge_on >= 16,
        "{edge_on} triangles with an edge on the level"
    );
    let model = fluid_model(m.nodes.clone(), m.triangles.clone(), &[], 1.0);
    let mut worst = [0.0f64; 4];
    for u in [
        horizontal_displacement(&model, 0.05, 0.0),
        horizontal_displacement(&model, 0.05, 0.01),
    ] {
        let scale = max_abs(&evaluate_finite(&model, &u, &[0.0]).loads[0]);
        let e = check_at_level(&model, &u, 0.0, scale);
        for k in 0..4 {
            worst[k] = worst[k].max(e[k]);
        }
    }
    eprintln!(
        "icosphere f = 4, level z = 0 through {nodes_on} nodes, {edge_on} triangles with an \
         edge on it, {node_on_straddling} cut through a node: asymmetry {:.1e}, gradient \
         {:.1e}, tangent/loads {:.1e}, jump {:.1e}",
        worst[0], worst[1], worst[2], worst[3]
    );
}

#[test]
fn waterline_through_a_node_ring_equilibrium_converges() {
    // The level exactly at the height of ring 3 of the cap: Newton's first iterate (the
    // reference geometry) has the waterline through 24 nodes and along 24 edges.
    let text = read(&data("waterline_cap.toml"));
    let probe = study_of(&text, "waterline_cap.toml");
    let mut heights: Vec<f64> = probe.mesh.mesh.nodes.iter().map(|x| x.z).collect();
    heights.sort_by(f64::total_cmp);
    heights.dedup();
    let ring = heights[3];
    let on_ring = probe.mesh.mesh.nodes.iter().filter(|x| x.z == ring).count();
    // `{:?}` prints the shortest string that parses back to the same f64.
    let text = edit(&text, "level = -0.5", &format!("level = {ring:?}"));
    assert_eq!(format!("{ring:?}").parse::<f64>().unwrap(), ring);
    let text = edit(&text, "start = 0.0", "start = 1.0");
    let text = edit(
        &text,
        "type = \"path\"\ncontrol = \"rho\"\nsteps = 40\ninitial-step = 0.05\nmax-step = 0.2",
        "type = \"equilibrium\"",
    );
    let mut study = study_of(&text, "waterline_cap.toml (equilibrium)");
    let result = run(&mut study, |_, _| {}).unwrap_or_else(|e| panic!("{e}"));
    let r = &result.report;
    assert_eq!(r.rows.len(), 1);
    let row = &r.rows[0];
    assert!(
        row.measures
            .iter()
            .chain(&row.parameters)
            .all(|v| v.is_finite()),
        "{row:?}"
    );
    let vf = row.measures[column(r, "fluid_volume")];
    assert!(vf > 0.1, "fluid volume {vf}");
    eprintln!(
        "cap equilibrium with the level exactly through {on_ring} nodes at z = {ring}: \
         fluid volume {vf:.6}"
    );
}

#[test]
fn waterline_through_fixed_nodes_along_a_whole_density_path() {
    // The clamped cut ring sits exactly at the level (nothing wet: the trivial case) ...
    let mut cap = study_of(&read(&data("waterline_cap.toml")), "waterline_cap.toml");
    let r = run_checked(&mut cap);
    let rho = parameter(&r.report, "rho");
    assert!(
        r.report.rows.last().unwrap().parameters[rho] >= 1.0,
        "{}",
        r.report.stop
    );
    // ... and the rim of a sagging disc is exactly at the level with fluid in the bowl: the
    // rim triangles are clipped along their rim edge at every point of the path.
    let mut rim = study_of(&read(&data("waterline_rim.toml")), "waterline_rim.toml");
    let result = run_checked(&mut rim);
    let r = &result.report;
    let (rho, vf, min_z) = (
        parameter(r, "rho"),
        column(r, "fluid_volume"),
        column(r, "min_z"),
    );
    let last = r.rows.last().unwrap();
    assert!(
        r.stop.to_string().contains("left its [min, max]") && last.parameters[rho] >= 1.5,
        "{}",
        r.stop
    );
    // The bowl is below the level and holds fluid; it deepens with the density.
    assert!(r
        .rows
        .iter()
        .all(|row| row.measures[min_z] < 0.0 && row.measures[vf] > 0.0));
    assert!(r
        .rows
        .windows(2)
        .all(|w| w[1].measures[min_z] < w[0].measures[min_z]));
    let x = last_positions(&rim, &result);
    assert_eq!(
        x.iter().filter(|p| p.z == 0.0).count(),
        rim.mesh.mesh.boundaries["rim"].len(),
        "exactly the rim nodes are on the level"
    );
    eprintln!(
        "sagging disc, level exactly at the rim: {} points to rho = {:.3}, fluid volume {:.4}, \
         lowest point {:.4}",
        r.rows.len(),
        last.parameters[rho],
        last.measures[vf],
        last.measures[min_z]
    );
}

// ---------------------------------------------------------------------------------------------
// 4. The level swept from below the lowest node to above the highest
// ---------------------------------------------------------------------------------------------

/// Enclosed volume of a membrane clamped on a horizontal cut at height `c`, closed by the
/// plate: (1/6) Σ x1·(x2×x3) over the membrane plus the plate's −c A/3, with A the projected
/// area Σ N_z / 2.
fn enclosed_volume(x: &[Vec3], triangles: &[[usize; 3]], c: f64) -> f64 {
    let (mut v, mut a) = (0.0, 0.0);
    for &[i, j, k] in triangles {
        v += x[i].dot(&x[j].cross(&x[k])) / 6.0;
        a += (x[j] - x[i]).cross(&(x[k] - x[i])).z / 2.0;
    }
    v - c * a / 3.0
}

#[test]
fn level_swept_from_below_the_lowest_node_to_above_the_highest() {
    let mut study = study_of(&read(&data("level_sweep.toml")), "level_sweep.toml");
    let result = run_checked(&mut study);
    let r = &result.report;
    let (h, vf, min_z, max_z) = (
        parameter(r, "h"),
        column(r, "fluid_volume"),
        column(r, "min_z"),
        column(r, "max_z"),
    );
    let (first, last) = (&r.rows[0], r.rows.last().unwrap());
    assert!(
        r.stop.to_string().contains("left its [min, max]"),
        "{}",
        r.stop
    );
    assert!(first.parameters[h] <= -1.5 && first.parameters[h] < first.measures[min_z]);
    assert!(last.parameters[h] >= 1.5 && last.parameters[h] > last.measures[max_z]);
    // The level really passes through the membrane, in many steps.
    let inside = r
        .rows
        .iter()
        .filter(|row| (row.measures[min_z]..row.measures[max_z]).contains(&row.parameters[h]))
        .count();
    assert!(
        inside >= 5,
        "{inside} points with the level inside the membrane"
    );
    // Empty at the start, full at the end, monotonic between.
    assert!(first.measures[vf].abs() < 1e-12, "{}", first.measures[vf]);
    assert!(r
        .rows
        .windows(2)
        .all(|w| w[1].parameters[h] > w[0].parameters[h]
            && w[1].measures[vf] >= w[0].measures[vf] - 1e-12));
    let x = last_positions(&study, &result);
    let full = enclosed_volume(&x, &study.mesh.mesh.triangles, -0.8);
    assert!(
        (last.measures[vf] - full).abs() < 1e-9 * full,
        "final fluid volume {} vs enclosed volume {full}",
        last.measures[vf]
    );
    eprintln!(
        "level sweep: {} points, h from {} to {:.4}, {inside} with the level inside; fluid volume \
         0 -> {:.6} = enclosed volume",
        r.rows.len(),
        first.parameters[h],
        last.parameters[h],
        last.measures[vf]
    );
}

#[test]
fn level_sweep_through_the_cli() {
    let (_, header, rows) = cli_run(&data("level_sweep.toml"));
    let (h, vf) = (
        csv_column(&header, "h"),
        csv_column(&header, "fluid_volume"),
    );
    assert!(rows[0][vf].abs() < 1e-12 && rows.last().unwrap()[h] >= 1.5);
    assert!(rows.windows(2).all(|w| w[1][vf] >= w[0][vf] - 1e-12));
}

// ---------------------------------------------------------------------------------------------
// 5. Nearly flat and nearly degenerate triangles; collapsed elements; too large steps
// ---------------------------------------------------------------------------------------------

/// A clamped, pre-stretched (1.1) disc (6 sectors, 6 rings) without symmetry (`C1`), whose
/// nodes `edit` may move, with fluid below up to the level (parameter 0). Returns the model
/// and the trivial group's action (valid for any node positions).
fn disc_model(
    edit: impl FnOnce(&mut Vec<Vec3>, &[[usize; 3]], &[usize]),
) -> (FeModel, GroupAction) {
    let sym = disc(&DiscOptions {
        radius: 1.1,
        sectors: 6,
        divisions: 6,
        group: Some("C1".into()),
    })
    .unwrap();
    assert_eq!(sym.group().order(), 1);
    let mut nodes = sym.mesh.nodes.clone();
    let rim = sym.mesh.boundaries["rim"].clone();
    edit(&mut nodes, &sym.mesh.triangles, &rim);
    let membrane = Membrane::new(
        &nodes,
        &sym.mesh.triangles,
        MooneyRivlin::new(100.0, 0.0, 0.01),
        1.1,
    )
    .expect("no triangle is exactly degenerate");
    let effects: Vec<Box<dyn Effect>> = vec![
        Box::new(membrane),
        Box::new(Fluid {
            filled: false,
            closing: None,
            density: Quantity::Value(1.0),
            gravity: Quantity::Value(1.0),
            level: Quantity::Parameter(0),
            side: FluidSide::Behind,
        }),
    ];
    let model = FeModel::new(
        nodes,
        sym.mesh.triangles.clone(),
        &rim,
        effects,
        vec!["h".into()],
    );
    (model, sym.action)
}

/// Makes slivers: two interior nodes are moved onto the opposite edge of one of their
/// triangles up to `cap` times their distance (a flat "cap" triangle), two others onto a
/// neighbour up to `needle` times the edge (two "needle" triangles).
fn make_slivers(
    nodes: &mut [Vec3],
    triangles: &[[usize; 3]],
    rim: &[usize],
    cap: f64,
    needle: f64,
) {
    let mut used = vec![false; nodes.len()];
    for &i in rim {
        used[i] = true;
    }
    let mut made = 0;
    for i in 0..nodes.len() {
        if used[i] || made == 4 {
            continue;
        }
        let t = triangles.iter().find(|t| t.contains(&i)).unwrap();
        let k = t.iter().position(|&a| a == i).unwrap();
        let (j, l) = (t[(k + 1) % 3], t[(k + 2) % 3]);
        if used[j] || used[l] {
            continue;
        }
        if made % 2 == 0 {
            let mid = (nodes[j] + nodes[l]) * 0.5;
            nodes[i] = mid + (nodes[i] - mid) * cap;
        } else {
            nodes[i] = nodes[j] + (nodes[i] - nodes[j]) * needle;
        }
        for t in triangles.iter().filter(|t| t.contains(&i)) {
            for &a in t {
                used[a] = true;
            }
        }
        made += 1;
    }
    assert_eq!(made, 4);
}

fn area_ratio(model: &FeModel) -> f64 {
    let x = model.reference();
    let areas: Vec<f64> = model
        .layout()
        .triangles()
        .iter()
        .map(|&[a, b, c]| (x[b] - x[a]).cross(&(x[c] - x[a])).z)
        .collect();
    assert!(areas.iter().all(|&a| a > 0.0), "no triangle is inverted");
    areas.iter().copied().fold(f64::INFINITY, f64::min) / areas.iter().copied().fold(0.0, f64::max)
}

fn disc_options(model: &FeModel) -> PathOptions {
    PathOptions {
        initial_step: 0.02,
        min_step: 1e-6,
        max_step: 0.2,
        max_steps: 60,
        max_iterations: 25,
        tolerance: 1e-9,
        state_scale: 1.1 * (model.reference().len() as f64).sqrt(),
        ..PathOptions::default()
    }
}

/// Follows the level from 0 (the flat disc: every triangle horizontal exactly at the level)
/// to 1; every point finite.
fn follow_level(model: &FeModel, action: &GroupAction, opts: &PathOptions) -> Branch {
    let basis = SparseBasis::fixed_point(action, model.layout());
    assert_eq!(basis.dim(), model.unknowns());
    let problem = SymmetricProblem::new(model, &basis, &[], vec![0.0], Some(0));
    let mut driver = Continuation::start(
        problem,
        &DVector::zeros(basis.dim()),
        &DVector::from_element(1, 0.0),
        opts.clone(),
    )
    .unwrap_or_else(|e| panic!("the start failed: {e}"));
    let path = trace(
        &mut driver,
        opts.max_steps,
        |_, p| (p.lambda[0] >= 1.0).then_some(StopReason::Condition),
        &mut [],
        |_, _| {},
    );
    for p in &path.points {
        assert!(p.q.iter().chain(p.lambda.iter()).all(|v| v.is_finite()));
    }
    if let StopReason::Stalled(why) = &path.stop {
        assert_clear_stop(&why.to_string());
    }
    path
}

#[test]
fn exactly_degenerate_reference_triangle_is_refused_with_its_number() {
    let sym = disc(&DiscOptions {
        radius: 1.0,
        sectors: 6,
        divisions: 2,
        group: None,
    })
    .unwrap();
    let mut nodes = sym.mesh.nodes.clone();
    let t = sym.mesh.triangles[5];
    nodes[t[0]] = nodes[t[1]];
    let err = Membrane::new(
        &nodes,
        &sym.mesh.triangles,
        MooneyRivlin::new(1.0, 0.0, 1.0),
        1.0,
    )
    .expect_err("a collapsed triangle cannot be a reference");
    assert!(
        err.contains("triangle") && err.contains("degenerate"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1);
    // It names a triangle that has collapsed.
    let named: usize = err
        .split_whitespace()
        .find_map(|w| w.parse().ok())
        .unwrap_or_else(|| panic!("no triangle number in {err:?}"));
    let tri = sym.mesh.triangles[named];
    assert!(tri.contains(&t[0]) && tri.contains(&t[1]), "{err}");
}

#[test]
fn collapsed_element_is_a_clean_model_error() {
    let (model, _) = disc_model(|_, _, _| {});
    // Move the centre node (at the origin, so X + u is exact) onto a neighbour: every
    // triangle between them collapses to a segment, where W is undefined.
    let x = model.reference();
    let centre = x
        .iter()
        .position(|p| p.norm() == 0.0)
        .expect("a centre node");
    let t = model
        .layout()
        .triangles()
        .iter()
        .position(|t| t.contains(&centre))
        .unwrap();
    let other = *model.layout().triangles()[t]
        .iter()
        .find(|&&i| i != centre)
        .unwrap();
    let mut u = vec![0.0; model.unknowns()];
    for c in 0..3 {
        u[model.layout().dof(centre, c).unwrap()] = x[other][c];
    }
    assert_eq!(model.positions(&u, &[])[centre], x[other]);
    let mut e = model.new_evaluation();
    let err = model
        .evaluate(&u, &[0.3], Request::ALL, &mut e)
        .expect_err("a collapsed element is an error");
    match &err {
        ModelError::Element { effect, what, .. } => {
            assert_eq!(effect, "membrane");
            assert!(what.contains("collapsed"), "{what}");
        }
        other => panic!("expected an element error, got {other:?}"),
    }
    assert!(err.to_string().contains("triangle"), "{err}");
}

#[test]
fn nearly_degenerate_triangles_converge() {
    // Height/base 1e-4 caps and 1e-3 needles: the smallest triangle is 5e-5 of the largest.
    let (model, action) = disc_model(|n, t, r| make_slivers(n, t, r, 1e-4, 1e-3));
    let ratio = area_ratio(&model);
    assert!(ratio < 1e-4, "{ratio:e}");
    let e = evaluate_finite(&model, &vec![0.0; model.unknowns()], &[0.3]);
    assert!(asymmetry(&model, &e) <= 1e-14 * max_abs(&e.tangent));
    let path = follow_level(&model, &action, &disc_options(&model));
    assert_eq!(path.stop, StopReason::Condition, "{:?}", path.stop);
    eprintln!(
        "slivers (area ratio {ratio:.1e}): {} points to h = {:.3}",
        path.points.len(),
        path.points.last().unwrap().lambda[0]
    );
}

#[test]
fn extreme_slivers_are_followed_to_the_end() {
    // Height/base 1e-7 (area ratio ~4e-8): a metric-based element lost most of its digits
    // here and the path stopped after 5 points; the deformation-gradient element follows it.
    // Whatever happens: no panic, no NaN, and a clear stop.
    let (model, action) = disc_model(|n, t, r| make_slivers(n, t, r, 1e-7, 1e-3));
    let ratio = area_ratio(&model);
    let e = evaluate_finite(&model, &vec![0.0; model.unknowns()], &[0.3]);
    assert!(asymmetry(&model, &e) <= 1e-14 * max_abs(&e.tangent));
    let path = follow_level(&model, &action, &disc_options(&model));
    eprintln!(
        "extreme slivers (area ratio {ratio:.1e}): {} points to h = {:.3e}, stop {:?}",
        path.points.len(),
        path.points.last().unwrap().lambda[0],
        path.stop
    );
    assert_eq!(path.stop, StopReason::Condition, "{:?}", path.stop);
}

#[test]
fn sliver_tangent_is_accurate_at_an_exact_equilibrium() {
    // The flat pre-stretched clamped disc without load is an exact equilibrium whatever its
    // triangulation, and its tangent is positive definite. With a cap of height/base 1e-6, an
    // element computing t = tr(G0⁻¹ g) and J = det g / det G0 from metrics (entries O(1/sin²θ))
    // lost ~1e-16/sin²θ ~ 1e-4 relative; the deformation-gradient form loses only ~cond.
    let (model, action) = disc_model(|n, t, r| make_slivers(n, t, r, 1e-6, 1e-3));
    let u = vec![0.0; model.unknowns()];
    let e = evaluate_finite(&model, &u, &[-1.0]); // level below the disc: membrane only
    let k = dense_tangent(&model, &e);
    let eig = k.symmetric_eigenvalues();
    let (lo, hi) = (eig.min(), eig.amax());
    let force = max_abs(&e.residual);
    eprintln!("cap 1e-6: |F| = {force:e}, eigenvalues in [{lo:e}, {hi:e}]");
    // Nodal forces are ~0.04 here; an element whose round-off grew like cond rather than
    // cond² (cond ~ 1e6) would leave ~1e-11.
    assert!(force < 1e-8, "residual {force:e} at an exact equilibrium");
    assert!(
        lo > 0.0,
        "spurious negative eigenvalue {lo:e} (largest {hi:e})"
    );
    // And then Newton converges under a load.
    let path = follow_level(&model, &action, &disc_options(&model));
    assert_eq!(path.stop, StopReason::Condition, "{:?}", path.stop);
}

#[test]
fn nearly_flat_triangles_at_the_level_are_finite() {
    // The flat disc exactly at the level (every triangle horizontal and on the level: the
    // one place where the fluid Hessian jumps), and with heights jiggled by 1e-13 (nearly
    // flat triangles cut by the level in every way), at levels 0, ±1e-13, ±1e-300.
    for jiggle in [0.0, 1e-13] {
        let (model, _) = disc_model(|nodes, _, rim| {
            for (i, x) in nodes.iter_mut().enumerate() {
                if !rim.contains(&i) {
                    x.z = jiggle * noise(i);
                }
            }
        });
        let u = vec![0.0; model.unknowns()];
        for h in [0.0, 1e-13, -1e-13, 1e-300, -1e-300, 5e-324] {
            let e = evaluate_finite(&model, &u, &[h]);
            assert!(
                asymmetry(&model, &e) <= 1e-14 * max_abs(&e.tangent),
                "h = {h}"
            );
            let err = check_derivatives(&model, &u, &[h], &vec![0.0; model.unknowns()], 1e-7);
            assert!(err.is_ok(), "{err:?}");
        }
    }
}

#[test]
fn too_large_steps_are_cut_not_a_panic() {
    let (model, action) = disc_model(|n, t, r| make_slivers(n, t, r, 1e-4, 1e-3));
    let basis = SparseBasis::fixed_point(&action, model.layout());
    let opts = disc_options(&model);
    let mut problem = SymmetricProblem::new(&model, &basis, &[], vec![0.0], Some(0));
    let start = Continuation::start(
        &mut problem,
        &DVector::zeros(basis.dim()),
        &DVector::from_element(1, 0.0),
        opts.clone(),
    )
    .unwrap()
    .point()
    .clone();
    // A predictor 1000 mesh sizes long: the corrector fails — an Err, not a panic.
    let mut messages = Vec::new();
    for s in [50.0, 1e3, 1e6, 1e150, 1e300] {
        let err = step_from(&mut problem, &start, s, &opts)
            .expect_err("a huge step cannot converge")
            .to_string();
        assert!(!err.is_empty() && !err.contains('\n'), "{err}");
        messages.push(err);
    }
    // Predictors so long that the metric overflows: the elements are refused, as an Err.
    assert!(
        messages
            .iter()
            .any(|m| m.contains("collapsed element") || m.contains("non-finite")),
        "{messages:?}"
    );
    // A path whose first steps are that large cuts them and goes on.
    let path = follow_level(
        &model,
        &action,
        &PathOptions {
            initial_step: 1e3,
            max_step: 1e3,
            ..opts.clone()
        },
    );
    assert_eq!(path.stop, StopReason::Condition, "{:?}", path.stop);
    assert!(path.points[1].arclength < 1e3);
    eprintln!(
        "huge steps: {messages:?}; the path cut its step to {:.3} and reached h = {:.3} in {} points",
        path.points[1].arclength,
        path.points.last().unwrap().lambda[0],
        path.points.len()
    );
}

#[test]
fn too_large_steps_in_a_scene_are_cut() {
    // The bundled disc pushed up by fluid from below (8 rings), once with the default steps
    // and once with steps 100 times the default largest step: the huge steps are cut until
    // the corrector converges, and the path is the same — over the limit point of the level
    // (h = 2.67) and back down to the lower bound — not a jump to another branch.
    let text = read(&manifest().join("scenes/disc_fluid_below.toml"));
    let text = edit(&text, "divisions = 16", "divisions = 8");
    let huge = edit(
        &text,
        "steps = 400",
        "steps = 400\ninitial-step = 20.0\nmax-step = 20.0",
    );
    let mut turning = Vec::new();
    for (text, what) in [(text, "default steps"), (huge, "huge steps")] {
        let mut study = study_of(&text, &format!("disc_fluid_below.toml ({what})"));
        let result = run_checked(&mut study);
        let r = &result.report;
        let h = parameter(r, "h");
        let vf = column(r, "fluid_volume");
        assert!(
            r.stop.to_string().contains("left its [min, max]")
                && r.rows.last().unwrap().parameters[h] < -0.5,
            "{what}: {}",
            r.stop
        );
        let kinds: Vec<String> = r
            .turning_points
            .iter()
            .map(|t| t.kind.to_string())
            .collect();
        assert_eq!(kinds, ["maximum"], "{what}");
        let t = &r.turning_points[0];
        eprintln!(
            "disc, {what}: {} points, first step {:.3}, maximum h = {:.6} at fluid volume {:.4}; {}",
            r.rows.len(),
            r.rows[1].arclength,
            t.parameters[h],
            t.measures[vf],
            r.stop
        );
        turning.push((t.parameters[h], t.measures[vf], r.rows[1].arclength));
    }
    assert!(turning[1].2 < 20.0, "the first huge step was cut");
    assert!(
        (turning[0].0 - turning[1].0).abs() < 1e-6 * turning[0].0
            && (turning[0].1 - turning[1].1).abs() < 1e-4 * turning[0].1,
        "the same limit point: {turning:?}"
    );
}
