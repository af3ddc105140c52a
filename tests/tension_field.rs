//! The relaxed (tension-field) membrane energy on a problem with a closed form: a flat annulus
//! whose rims are held at radii that wrinkle it everywhere (docs/theory.md §13.5). The
//! computed radii and rim force converge to the reference at the second order of linear
//! triangles, every triangle is wrinkled and its tension direction is radial.

use memstab::effects::membrane::{
    Membrane, MooneyRivlin, ReferenceTriangle, TensionState, Wrinkling,
};
use memstab::model::newton::{newton, NewtonOptions};
use memstab::model::{CellQuantity, Effect, FeModel, Model, Vec3};
use memstab::reference::AnnulusTensionField;
use meshes::generators::{disc, DiscOptions};

/// The annulus a ≤ R ≤ b = 1 cut from the C8v disc pattern of `divisions` rings: its
/// stress-free nodes and triangles, and the nodes of the inner and outer rims.
fn annulus(divisions: usize, a: f64) -> (Vec<Vec3>, Vec<[usize; 3]>, Vec<usize>, Vec<usize>) {
    let sym = disc(&DiscOptions {
        radius: 1.0,
        sectors: 8,
        divisions,
        group: None,
    })
    .unwrap();
    let m = &sym.mesh;
    let tol = 1e-9;
    let rho = |i: usize| m.nodes[i].norm();
    let kept: Vec<[usize; 3]> = m
        .triangles
        .iter()
        .copied()
        .filter(|t| t.iter().all(|&i| rho(i) > a - tol))
        .collect();
    let mut number = vec![usize::MAX; m.nodes.len()];
    let mut nodes = Vec::new();
    for &i in kept.iter().flatten() {
        if number[i] == usize::MAX {
            number[i] = nodes.len();
            nodes.push(m.nodes[i]);
        }
    }
    let triangles = kept.iter().map(|t| t.map(|i| number[i])).collect();
    let on = |r: f64| -> Vec<usize> {
        (0..nodes.len())
            .filter(|&i| (nodes[i].norm() - r).abs() < tol)
            .collect()
    };
    let (inner, outer) = (on(a), on(1.0));
    (nodes, triangles, inner, outer)
}

/// What one mesh gives against the reference.
struct Measured {
    /// Triangles.
    triangles: usize,
    /// max over nodes |r − r(R)|.
    radius_error: f64,
    /// |computed rim force − 2πHK| / 2πHK.
    force_error: f64,
    /// max over triangles |tension direction · hoop direction at the centroid|.
    direction_error: f64,
    /// Triangles not wrinkled.
    not_wrinkled: usize,
}

/// Solves the annulus on `divisions` rings with the relaxed energy (residual stiffness
/// `stiffness`) and measures it against `field`.
fn solve(
    divisions: usize,
    field: &AnnulusTensionField,
    rims: (f64, f64),
    stiffness: f64,
) -> Measured {
    let (a, b) = (0.25, field.outer_radius());
    let (mu, k, h) = (1.0, 0.1, 1.0);
    let (nodes, triangles, inner, outer) = annulus(divisions, a);
    // The start: every node moved radially by the linear map of [a, b] onto the rims' radii.
    let start: Vec<Vec3> = nodes
        .iter()
        .map(|x| {
            let r = x.norm();
            x * ((rims.0 + (r - a) * (rims.1 - rims.0) / (b - a)) / r)
        })
        .collect();
    let membrane = Membrane::new(&nodes, &triangles, MooneyRivlin::new(mu, k, h), 1.0)
        .unwrap()
        .with_wrinkling(Wrinkling::Relaxed {
            stiffness,
            width: 0.0,
        });
    let fixed: Vec<usize> = inner.iter().chain(&outer).copied().collect();
    let effects: Vec<Box<dyn Effect>> = vec![Box::new(membrane)];
    let model = FeModel::new(start, triangles.clone(), &fixed, effects, vec![]);
    let options = NewtonOptions {
        max_iterations: 60,
        ..NewtonOptions::default()
    };
    let sol = newton(&model, &vec![0.0; model.unknowns()], &[], &options).unwrap();
    let x = model.positions(&sol.u, &[]);
    let radius_error = nodes
        .iter()
        .zip(&x)
        .map(|(p, q)| (q.norm() - field.radius(p.norm())).abs())
        .fold(0.0, f64::max);
    // The rim force: the energy's gradient at the inner rim's nodes, radially.
    let mat = MooneyRivlin::new(mu, k, h);
    let mut force = 0.0;
    for t in &triangles {
        let touches: Vec<usize> = (0..3).filter(|&n| inner.contains(&t[n])).collect();
        if touches.is_empty() {
            continue;
        }
        let elem = ReferenceTriangle::new(&t.map(|i| nodes[i]), 1.0, h).unwrap();
        let (local, _) = elem
            .relaxed_energy_gradient_hessian(&mat, [stiffness, 0.0], &t.map(|i| x[i]))
            .unwrap();
        for n in touches {
            let radial = x[t[n]] / x[t[n]].norm();
            force += (0..3)
                .map(|c| local.grad[3 * n + c] * radial[c])
                .sum::<f64>();
        }
    }
    // The membrane pulls the inner rim outwards: the energy falls as it moves out.
    let exact = field.rim_force(h);
    let force_error = (-force - exact).abs() / exact;
    let cells = model.cell_fields(&sol.u, &[]);
    let states = &cells
        .iter()
        .find(|f| f.quantity == CellQuantity::MembraneState)
        .unwrap()
        .values;
    let not_wrinkled = states
        .iter()
        .filter(|&&s| s != TensionState::Wrinkled.code())
        .count();
    let directions = &model.cell_vectors(&sol.u, &[])[0];
    assert_eq!(directions.name, "wrinkle_direction");
    let direction_error = triangles
        .iter()
        .zip(&directions.values)
        .map(|(t, d)| {
            let c = (x[t[0]] + x[t[1]] + x[t[2]]) / 3.0;
            let hoop = Vec3::new(-c.y, c.x, 0.0) / c.xy().norm();
            d.dot(&hoop).abs()
        })
        .fold(0.0, f64::max);
    Measured {
        triangles: triangles.len(),
        radius_error,
        force_error,
        direction_error,
        not_wrinkled,
    }
}

#[test]
fn the_wrinkled_annulus_converges_to_its_tension_field_at_second_order() {
    let (mu, k) = (1.0, 0.1);
    let mat = MooneyRivlin::new(mu, k, 1.0);
    let rims = (0.1, 0.92);
    let field = AnnulusTensionField::new(mat.c1, mat.c2, 0.25, 1.0, rims.0, rims.1).unwrap();
    let runs: Vec<Measured> = [8, 16, 32]
        .iter()
        .map(|&d| solve(d, &field, rims, 1e-9))
        .collect();
    for (m, d) in runs.iter().zip([8, 16, 32]) {
        println!(
            "divisions {d}: {} triangles, radius error {:.3e}, rim force error {:.3e}, \
             direction error {:.3e}",
            m.triangles, m.radius_error, m.force_error, m.direction_error
        );
        assert_eq!(m.not_wrinkled, 0, "divisions {d}");
    }
    let order = |e: fn(&Measured) -> f64, i: usize| (e(&runs[i]) / e(&runs[i + 1])).log2();
    for i in 0..2 {
        let (r, f, t) = (
            order(|m| m.radius_error, i),
            order(|m| m.force_error, i),
            order(|m| m.direction_error, i),
        );
        println!("orders {i}: radius {r:.2}, rim force {f:.2}, direction {t:.2}");
        // Linear triangles: the nodal radii and the rim force at the second order; the
        // direction of a triangle's constant strain converges too, more slowly at the
        // inner rim, where the stretch varies fastest.
        assert!(
            r > 1.8 && f > 1.9 && t > 0.5,
            "orders {r:.2}, {f:.2}, {t:.2}"
        );
    }
    assert!(runs[2].radius_error < 5e-5 && runs[2].force_error < 1.1e-3);
    assert!(runs[2].direction_error < 0.02);
}

/// The residual stiffness ε adds a tension ε μH/2 · 2λ: the rim force moves away from the
/// ε → 0 value in proportion to ε (a tenth for a tenth), far below the discretisation error
/// at the default ε = 1e-4.
#[test]
fn the_annulus_moves_in_proportion_to_the_residual_stiffness() {
    let mat = MooneyRivlin::new(1.0, 0.1, 1.0);
    let rims = (0.1, 0.92);
    let field = AnnulusTensionField::new(mat.c1, mat.c2, 0.25, 1.0, rims.0, rims.1).unwrap();
    let base = solve(8, &field, rims, 1e-9).force_error;
    let shift: Vec<f64> = [1e-3, 1e-4, 1e-5]
        .iter()
        .map(|&eps| (solve(8, &field, rims, eps).force_error - base).abs())
        .collect();
    println!("rim force shifts for eps = 1e-3, 1e-4, 1e-5: {shift:?}");
    for w in shift.windows(2) {
        let ratio = w[0] / w[1];
        assert!((8.0..12.0).contains(&ratio), "{shift:?}");
    }
    assert!(shift[1] < 0.05 * base, "{shift:?} vs {base:e}");
}

/// The eigenvalues of the tangent at the annulus's relaxed equilibrium (flat and wrinkled
/// everywhere): with the residual stiffness ε none is negative, and the smallest converges as
/// ε → 0 to a positive limit, its change a tenth for each tenth of ε — the tension rays, held
/// at both rims, leave W* no null direction here, so n₋(K_ε) = n₋(K*) = 0 and the spectrum is
/// that of the tension field up to O(ε) (docs/theory.md §2.9). The plain energy's tangent at
/// the same state counts its lateral compression as dozens of negative eigenvalues.
#[test]
fn the_index_of_the_wrinkled_annulus_stays_zero_and_converges_as_the_stiffness_vanishes() {
    let mat = MooneyRivlin::new(1.0, 0.1, 1.0);
    let rims = (0.1, 0.92);
    let (nodes, triangles, inner, outer) = annulus(8, 0.25);
    let start: Vec<Vec3> = nodes
        .iter()
        .map(|x| {
            let r = x.norm();
            x * ((rims.0 + (r - 0.25) * (rims.1 - rims.0) / 0.75) / r)
        })
        .collect();
    let fixed: Vec<usize> = inner.iter().chain(&outer).copied().collect();
    let model_with = |wrinkling: Wrinkling| {
        let membrane = Membrane::new(&nodes, &triangles, mat, 1.0)
            .unwrap()
            .with_wrinkling(wrinkling);
        let effects: Vec<Box<dyn Effect>> = vec![Box::new(membrane)];
        FeModel::new(start.clone(), triangles.clone(), &fixed, effects, vec![])
    };
    let eigenvalues = |model: &FeModel, u: &[f64]| {
        let mut e = model.new_evaluation();
        model
            .evaluate(u, &[], memstab::model::Request::ALL, &mut e)
            .unwrap();
        let n = model.unknowns();
        let mut k = nalgebra::DMatrix::<f64>::zeros(n, n);
        let mut unit = vec![0.0; n];
        let mut column = vec![0.0; n];
        for j in 0..n {
            unit[j] = 1.0;
            model.pattern().matvec(&e.tangent, &unit, &mut column);
            unit[j] = 0.0;
            k.column_mut(j).copy_from_slice(&column);
        }
        let scale = k.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let mut values: Vec<f64> = k
            .symmetric_eigenvalues()
            .iter()
            .map(|v| v / scale)
            .collect();
        values.sort_by(f64::total_cmp);
        values
    };
    let options = NewtonOptions {
        max_iterations: 60,
        ..NewtonOptions::default()
    };
    let mut smallest = Vec::new();
    let mut last = None;
    for eps in [1e-3, 1e-4, 1e-5, 1e-6] {
        let model = model_with(Wrinkling::Relaxed {
            stiffness: eps,
            width: 0.0,
        });
        let sol = newton(&model, &vec![0.0; model.unknowns()], &[], &options).unwrap();
        let values = eigenvalues(&model, &sol.u);
        println!(
            "ε = {eps:e}: smallest eigenvalue {:.6e} of max|K_ij| ({} unknowns)",
            values[0],
            values.len()
        );
        assert!(values[0] > 0.0, "ε = {eps}: smallest {:e}", values[0]);
        smallest.push(values[0]);
        last = Some(sol.u);
    }
    let changes: Vec<f64> = smallest.windows(2).map(|w| w[0] - w[1]).collect();
    for w in changes.windows(2) {
        let ratio = w[0] / w[1];
        assert!((7.0..12.0).contains(&ratio), "{smallest:?}");
    }
    // The plain energy at the same (wrinkled) state.
    let plain = model_with(Wrinkling::None);
    let negative = eigenvalues(&plain, &last.unwrap())
        .iter()
        .filter(|&&v| v < 0.0)
        .count();
    println!("plain energy: {negative} negative eigenvalues");
    assert!(negative > 20, "{negative}");
}

/// Paper 3's loading (a), the cap between two planes deflated by its gas pressure: the plain
/// energy loses stability once the cap wrinkles (limit points and bifurcations near
/// p = 0.012 on this mesh, all in wrinkled states); with the relaxed energy the index stays 0
/// by every block down to p = 0.005 for every residual stiffness from 1e-3 to 1e-5, while
/// the wrinkled area grows.
#[test]
fn the_deflated_cap_between_planes_stays_stable_under_the_relaxed_energy() {
    let text = std::fs::read_to_string(format!(
        "{}/scenes/thesis/paper3_gas_fluid_pressure.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let run_with = |material: &str| {
        let text = text.replace(
            "prestretch = 1.05          # tension T(1.05) = 0.2562 mu H",
            &format!("prestretch = 1.05\n{material}"),
        );
        let scene = memstab::scene::Scene::from_toml_str(&text, "cap").unwrap();
        let mut study = memstab::study::mesh::MeshStudy::build(scene).unwrap();
        memstab::analysis::run(&mut study, |_, _| {}).unwrap()
    };
    let plain = run_with("");
    assert!(
        plain.report.rows.iter().any(|r| r.index.unwrap() > 0) && !plain.report.critical.is_empty(),
        "the plain energy loses stability"
    );
    for eps in ["1e-3", "1e-4", "1e-5"] {
        let relaxed = run_with(&format!(
            "wrinkling = \"relaxed\"\nwrinkling-stiffness = {eps}"
        ));
        let r = &relaxed.report;
        let p = r.parameters.iter().position(|n| n == "p").unwrap();
        let area = r
            .measures
            .iter()
            .position(|n| n == "wrinkled_area")
            .unwrap();
        assert!(r.critical.is_empty(), "ε = {eps}: {:?}", r.critical);
        assert!(r.rows.iter().all(|row| row.index == Some(0)), "ε = {eps}");
        let end = r.rows.last().unwrap();
        assert!(
            end.parameters[p] < 0.005,
            "ε = {eps}: ends at p = {}",
            end.parameters[p]
        );
        assert!(
            end.measures[area] > 1.0,
            "ε = {eps}: wrinkled area {}",
            end.measures[area]
        );
        println!(
            "ε = {eps}: {} points to p = {:.5}, wrinkled area {:.4} there",
            r.rows.len(),
            end.parameters[p],
            end.measures[area]
        );
    }
}

/// Paper 2's sphere on the plane, gas above a fixed fluid volume V = 2, deflated in p: the
/// scene with V held and a path down from p = 0.5. `material` is added to `[material]`.
fn deflated_sphere(material: &str, steps: usize) -> memstab::results::RunResult {
    let scene = deflated_scene(material, steps, None);
    let mut study = memstab::study::mesh::MeshStudy::build(scene).unwrap();
    memstab::analysis::run(&mut study, |_, _| {}).unwrap()
}

/// The scene of [`deflated_sphere`], its `[mesh]` body replaced by `mesh` if given.
fn deflated_scene(material: &str, steps: usize, mesh: Option<&str>) -> memstab::scene::Scene {
    let mut text = std::fs::read_to_string(format!(
        "{}/scenes/thesis/paper2_gas_pressure_fold_f8.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    if let Some(mesh) = mesh {
        let icosphere = "generator = \"icosphere\"\nradius = 1.0\nfrequency = 8              \
                         # 1280 triangles, 642 nodes\ndown = \"vertex\"            \
                         # gravity and the plane keep C5v";
        assert!(text.contains(icosphere));
        text = text.replacen(icosphere, mesh, 1);
    }
    let (body, start) = text.split_once("[analysis]").unwrap();
    let start = &start[start.find("[start]").unwrap()..];
    let body = body
        .replace(
            "thickness = 0.01           # mu * H = 1",
            &format!("thickness = 0.01\n{material}"),
        )
        .replace(
            "start = 0.5                # the fluid volume",
            "start = 2.0                # the fluid volume",
        );
    let text = format!(
        "{body}[[constraint]]\ntype = \"fixed\"\nparameter = \"V\"\n\n[analysis]\ntype = \"path\"\n\
         control = \"p\"\ndirection = \"decrease\"\nsteps = {steps}\n\n{start}"
    );
    assert!(text.contains("start = 2.0") && text.contains(material));
    memstab::scene::Scene::from_toml_str(&text, "deflated").unwrap()
}

/// The deflated sphere on its meridian (64 elements, wave numbers to 8) under the relaxed
/// energy: the 3-D mesh's first critical point, just after the onset of wrinkling, is there a
/// cluster of double bifurcations of high wave number that starts between the last taut
/// and the first wrinkled path point, the highest wave number first (docs/theory.md §2.9,
/// "On the meridian"): the wrinkled region, stiff across its wrinkles by ε alone, is made
/// unstable by the pressure at every short wave; m = 1 (the 3-D mesh's E1) never.
#[test]
fn the_deflated_sphere_on_its_meridian_loses_stability_at_short_waves_as_it_wrinkles() {
    let scene = deflated_scene(
        "wrinkling = \"relaxed\"",
        8,
        Some("generator = \"axisymmetric\"\nshape = \"sphere\"\nradius = 1.0\nelements = 64\nmodes = 8"),
    );
    let mut study = memstab::study::build(scene).unwrap();
    let run = memstab::analysis::run(study.as_mut(), |_, _| {}).unwrap();
    let r = &run.report;
    let column = |name: &str| r.measures.iter().position(|n| n == name).unwrap();
    let (p, area) = (
        r.parameters.iter().position(|n| n == "p").unwrap(),
        column("wrinkled_area"),
    );
    let onset = r
        .rows
        .iter()
        .position(|row| row.measures[area] > 0.0)
        .expect("the sphere wrinkles");
    assert!(onset > 0, "wrinkled from the start");
    let (taut, wrinkled) = (r.rows[onset - 1].parameters[p], r.rows[onset].parameters[p]);
    assert!(!r.critical.is_empty());
    let first = r
        .critical
        .iter()
        .map(|c| c.parameters[p])
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(
        first < taut && first > wrinkled,
        "{first} not in ({wrinkled}, {taut})"
    );
    // Every point a double bifurcation; those within 0.01 in p of the first are of the
    // highest wave numbers, the largest of them (8) among them.
    let m: Vec<usize> = r.wave_numbers.clone();
    assert_eq!(m.len(), r.critical.len());
    let cluster: Vec<usize> = r
        .critical
        .iter()
        .zip(&m)
        .filter(|(c, _)| c.parameters[p] > first - 0.01)
        .map(|(c, &m)| {
            assert_eq!(c.multiplicity, 2, "{c:?}");
            m
        })
        .collect();
    assert!(
        cluster.contains(&8) && cluster.iter().all(|&m| m >= 5),
        "{cluster:?}"
    );
    assert!(!m.contains(&1), "{m:?}");
}

/// A critical point in a partly wrinkled state and its value as ε → 0: the deflated sphere
/// on the plane (1 280 triangles) meets an E1 double bifurcation just after it starts to
/// wrinkle, at p = 0.366005, 0.365840, 0.365824 for ε = 1e-4, 1e-5, 1e-6 — changes a tenth
/// per tenth of ε, so the point belongs to the relaxed membrane, not to ε. The plain energy
/// has no critical point there (its index stays 0 down to p = 0.26).
#[test]
fn a_critical_point_in_a_wrinkled_state_converges_as_the_stiffness_vanishes() {
    let plain = deflated_sphere("", 8);
    assert!(plain.report.critical.is_empty());
    assert!(plain.report.rows.iter().all(|r| r.index == Some(0)));
    let mut values = Vec::new();
    for eps in ["1e-4", "1e-5", "1e-6"] {
        let run = deflated_sphere(
            &format!("wrinkling = \"relaxed\"\nwrinkling-stiffness = {eps}"),
            6,
        );
        let r = &run.report;
        let p = r.parameters.iter().position(|n| n == "p").unwrap();
        let first = r.critical.first().expect("a critical point");
        assert_eq!(first.irrep, "E1", "ε = {eps}");
        assert_eq!(first.multiplicity, 2);
        // In a wrinkled state.
        let w = r.wrinkling.as_ref().unwrap();
        assert!(
            w.relaxed
                && w.critical
                    .first()
                    .is_some_and(|c| c.critical == 1 && c.wrinkled > 0)
        );
        println!("ε = {eps}: E1 double at p = {:.7}", first.parameters[p]);
        values.push(first.parameters[p]);
    }
    let ratio = (values[0] - values[1]) / (values[1] - values[2]);
    assert!((7.0..13.0).contains(&ratio), "{values:?}");
    assert!((values[2] - 0.36582).abs() < 1e-4, "{values:?}");
}
