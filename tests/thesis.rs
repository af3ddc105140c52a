//! The physics of the thesis problems: gas above fluid in one enclosure, completely filled
//! enclosures, the fluid volume as the control, sliding edges and the moving plate that closes
//! them, bodies resting on planes (the held rolling and drift), the scene's group from the set
//! of effects, restarts and the start homotopy, and classification that agrees with the path.

use memstab::adapted::{AdaptedBasis, SparseBasis};
use memstab::analysis::{run, run_with, Observer};
use memstab::effects::gas::{GasAmount, GasAmountConstraint, GasPressure};
use memstab::effects::hydrostatic::{Fluid, FluidSide, FluidVolumeConstraint};
use memstab::effects::membrane::{Membrane, MooneyRivlin};
use memstab::effects::spin::Spin;
use memstab::effects::volume::ClosingFace;
use memstab::effects::Quantity;
use memstab::model::check::check_derivatives;
use memstab::model::constraint::Constraint;
use memstab::model::{Effect, Evaluation, FeModel, Layout, Model, ModelError, Request, Vec3};
use memstab::results::{CriticalKind, Extremum, PathReport, StopReason};
use memstab::scene::Scene;
use memstab::stability::{Detail, Stability};
use memstab::study::mesh::MeshStudy;
use meshes::generators::{truncated_sphere, TruncatedSphereOptions};
use proptest::prelude::*;
use std::path::Path;
use std::process::Command;
use std::sync::Arc;

fn random_vector(seed: u64, n: usize, amplitude: f64) -> Vec<f64> {
    let mut s = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            amplitude * (((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0)
        })
        .collect()
}

fn column(r: &PathReport, name: &str) -> usize {
    r.measures
        .iter()
        .position(|m| m == name)
        .unwrap_or_else(|| panic!("no measure {name}: {:?}", r.measures))
}

fn parameter(r: &PathReport, name: &str) -> usize {
    r.parameters.iter().position(|m| m == name).unwrap()
}

fn study(text: &str) -> MeshStudy {
    MeshStudy::build(Scene::from_toml_str(text, "test").expect("the scene loads")).expect("builds")
}

fn bundled(name: &str) -> String {
    std::fs::read_to_string(format!("{}/scenes/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

// ---- The moving plate: a truncated sphere whose rim is free, closed by its plate ----

/// A C8v truncated sphere cut at `cut`, its rim nodes free to slide (all nodes free here: the
/// full-space derivatives include the plate's terms at the rim), with the plate.
fn cap_mesh(cut: f64) -> (meshes::SymmetricMesh, Arc<ClosingFace>) {
    let sym = truncated_sphere(&TruncatedSphereOptions {
        divisions: 3,
        cut_height: cut,
        ..TruncatedSphereOptions::for_pattern("C8v")
    })
    .unwrap();
    let face = Arc::new(ClosingFace::new(cut, &sym.mesh.triangles));
    (sym, face)
}

fn membrane(m: &meshes::Mesh) -> Box<dyn Effect> {
    Box::new(
        Membrane::new(
            &m.nodes,
            &m.triangles,
            MooneyRivlin::new(1.0, 0.1, 0.1),
            1.05,
        )
        .unwrap(),
    )
}

/// Parameters: p, ρ, h, C, V*, ω².
fn enclosure_model(filled: bool) -> FeModel {
    let (sym, face) = cap_mesh(-0.3);
    let m = &sym.mesh;
    let effects: Vec<Box<dyn Effect>> = vec![
        membrane(m),
        Box::new(GasPressure {
            pressure: Quantity::Parameter(0),
            closing: Some(face.clone()),
        }),
        Box::new(Fluid {
            density: Quantity::Parameter(1),
            gravity: Quantity::Value(1.3),
            level: Quantity::Parameter(2),
            side: FluidSide::Behind,
            filled,
            closing: Some(face.clone()),
        }),
        Box::new(GasAmount {
            amount: Quantity::Parameter(3),
            ambient: 0.7,
            closing: Some(face.clone()),
            fluid: Some(Quantity::Parameter(4)),
        }),
        Box::new(Spin {
            density: Quantity::Value(0.6),
            omega2: Quantity::Parameter(5),
            side: FluidSide::Behind,
        }),
    ];
    let names = ["p", "rho", "h", "C", "V", "w2"].map(String::from).to_vec();
    FeModel::new(m.nodes.clone(), m.triangles.clone(), &[], effects, names)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 10, failure_persistence: None, .. ProptestConfig::default() })]

    #[test]
    fn enclosures_closed_by_a_moving_plate_match_finite_differences(
        seed in any::<u64>(),
        filled in any::<bool>(),
        h in -0.1f64..1.1,
        w2 in 0.0f64..2.0,
    ) {
        let model = enclosure_model(filled);
        let n = model.unknowns();
        // A random state around the cap stretched by 1.1 in the plane and lifted a little.
        let mut u = random_vector(seed, n, 0.02);
        for (i, x) in model.reference().iter().enumerate() {
            u[3 * i] += 0.1 * x.x;
            u[3 * i + 1] += 0.1 * x.y;
        }
        let d = random_vector(seed ^ 0x77, n, 1.0);
        let params = [0.4, 0.8, h, 3.0, 0.2, w2];
        let e = check_derivatives(&model, &u, &params, &d, 1e-6).unwrap();
        // The clipped fluid's Hessian is only continuous where the level crosses a node.
        let tangent_tol = if filled { 1e-6 } else { 1e-4 };
        prop_assert!(e.residual < 1e-7, "{e:?}");
        prop_assert!(e.tangent < tangent_tol, "{e:?}");
        prop_assert!(e.asymmetry < 1e-13, "{e:?}");
        prop_assert!(e.loads < 1e-5, "{e:?}");
    }

    #[test]
    fn constraints_with_a_moving_plate_match_finite_differences(
        seed in any::<u64>(),
        filled in any::<bool>(),
        h in 0.0f64..1.0,
    ) {
        let (sym, face) = cap_mesh(-0.3);
        let m = &sym.mesh;
        let layout = Layout::new(m.nodes.len(), m.triangles.clone(), &[]);
        let fluid = Fluid {
            density: Quantity::Value(1.0),
            gravity: Quantity::Value(1.0),
            level: Quantity::Parameter(0),
            side: FluidSide::Behind,
            filled,
            closing: Some(face.clone()),
        };
        let volume = FluidVolumeConstraint {
            fluid,
            level: 0,
            target: 0.0,
            target_parameter: Some(1),
            closing: Some(face.clone()),
        };
        let amount = GasAmountConstraint {
            pressure: 2,
            ambient: 1.0,
            target: 0.0,
            target_parameter: Some(3),
            closing: Some(face.clone()),
            fluid: Some(Quantity::Parameter(1)),
        };
        let n = layout.unknowns();
        let mut u = random_vector(seed, n, 0.02);
        for (i, x) in m.nodes.iter().enumerate() {
            u[3 * i] += 0.1 * x.x;
            u[3 * i + 1] += 0.1 * x.y;
        }
        let d = random_vector(seed ^ 0x99, n, 1.0);
        let params = vec![h, 0.3, 0.5, 2.0];
        let at = |u: &[f64], p: &[f64], c: &dyn Constraint| {
            let mut x = m.nodes.clone();
            layout.add_displacements(u, &mut x);
            c.evaluate(&layout, &x, p)
        };
        for c in [&volume as &dyn Constraint, &amount] {
            let g = at(&u, &params, c);
            let step = 1e-6;
            let plus: Vec<f64> = u.iter().zip(&d).map(|(a, b)| a + step * b).collect();
            let minus: Vec<f64> = u.iter().zip(&d).map(|(a, b)| a - step * b).collect();
            let fd = (at(&plus, &params, c).value - at(&minus, &params, c).value) / (2.0 * step);
            let exact: f64 = g.grad_u.iter().zip(&d).map(|(a, b)| a * b).sum();
            let scale = g.grad_u.iter().fold(1e-3f64, |s, v| s.max(v.abs())) * n as f64;
            prop_assert!((fd - exact).abs() < 1e-7 * scale, "{}: {fd} vs {exact}", c.name());
            for j in 0..params.len() {
                let mut pp = params.clone();
                pp[j] += step;
                let mut pm = params.clone();
                pm[j] -= step;
                let fd = (at(&u, &pp, c).value - at(&u, &pm, c).value) / (2.0 * step);
                prop_assert!(
                    (fd - g.grad_params[j]).abs() < 1e-6 * (1.0 + fd.abs()),
                    "{} ∂/∂Λ{j}: {fd} vs {}", c.name(), g.grad_params[j]
                );
            }
        }
    }
}

// ---- Item: gas above fluid ----

/// Paper 2 on a coarse icosphere (f = 4): a gas amount above fluid in a closed sphere
/// resting on a plane, the fluid volume V the control.
fn paper2(frequency: usize, max_v: f64) -> String {
    bundled("thesis/paper2_sphere_on_plane.toml")
        .replace("frequency = 16", &format!("frequency = {frequency}"))
        .replace("max = 6.0", &format!("max = {max_v}"))
}

#[test]
fn gas_above_fluid_fills_what_the_fluid_leaves_and_loads_the_wet_membrane_too() {
    let mut study = study(&paper2(4, 4.0));
    let mut states = States::default();
    let report = run_with(&mut study, &mut states)
        .expect("the path runs")
        .report;
    let (v, vf, p) = (
        column(&report, "volume"),
        column(&report, "fluid_volume"),
        column(&report, "gas_pressure"),
    );
    assert!(report.rows.len() > 10, "{} points", report.rows.len());
    assert_eq!(states.0.len(), report.rows.len());
    let mut last = f64::NEG_INFINITY;
    for (row, (u, params)) in report.rows.iter().zip(&states.0) {
        let m = &row.measures;
        // Boyle's law on the gas volume, with V and V_f measured on their own.
        let boyle = 6.5 / (m[v] - m[vf]) - 1.0;
        assert!(
            (m[p] - boyle).abs() < 1e-12 * boyle.abs().max(1.0),
            "step {}: gas pressure {} vs C/(V - V_f) - P_atm = {boyle}",
            row.step,
            m[p]
        );
        // Filling compresses the gas.
        assert!(m[p] > last, "step {}: the gas pressure fell", row.step);
        last = m[p];
        // The state is the equilibrium of the membrane under that pressure on the whole
        // membrane (dry and wet) plus the fluid to its level: with a fixed-pressure gas in
        // place of the amount, the residual vanishes.
        if row.step % 4 == 0 {
            let equivalent = equivalent_model(&study, params[parameter(&report, "h")], m[p]);
            let mut e = equivalent.new_evaluation();
            equivalent.evaluate(u, &[], Request::ALL, &mut e).unwrap();
            let force = e.tangent.iter().fold(0.0f64, |a, b| a.max(b.abs()));
            let residual = e.residual.iter().fold(0.0f64, |a, b| a.max(b.abs()));
            assert!(
                residual < 1e-8 * force,
                "step {}: residual {residual:e} of the equivalent model (force {force:e})",
                row.step
            );
        }
    }
    // The fluid volume rose to 4 of the ~7.9 enclosed: the gas is markedly compressed.
    assert!(last > 0.9, "gas over-pressure {last} at the end");
}

/// The study's mesh with the membrane, a gas at the fixed over-pressure `p` on the whole
/// A material quantity the thesis scenes give as a number.
fn fixed(q: &memstab::scene::Quantity) -> f64 {
    q.value(&Default::default())
        .expect("a fixed material quantity")
}

/// membrane, the fluid to the fixed level `h` and the plane: no parameters.
fn equivalent_model(study: &MeshStudy, h: f64, p: f64) -> FeModel {
    let m = &study.mesh.mesh;
    let mat = &study.scene.material;
    let effects: Vec<Box<dyn Effect>> = vec![
        Box::new(
            Membrane::new(
                &m.nodes,
                &m.triangles,
                MooneyRivlin::new(fixed(&mat.mu), fixed(&mat.k), fixed(&mat.thickness)),
                fixed(&mat.prestretch),
            )
            .unwrap(),
        ),
        Box::new(GasPressure::new(Quantity::Value(p))),
        Box::new(Fluid::new(
            Quantity::Value(1.0),
            Quantity::Value(1.0),
            Quantity::Value(h),
            FluidSide::Behind,
        )),
        Box::new(memstab::effects::plane::Plane {
            normal: Vec3::z(),
            offset: Quantity::Value(-1.06),
            penalty: Quantity::Value(1000.0),
            law: memstab::effects::plane::PenaltyLaw::Cubic,
        }),
    ];
    FeModel::new(m.nodes.clone(), m.triangles.clone(), &[], effects, vec![])
}

/// Every accepted state of a run.
#[derive(Default)]
struct States(Vec<(Vec<f64>, Vec<f64>)>);

impl Observer for States {
    fn state(&mut self, u: &[f64], params: &[f64]) {
        self.0.push((u.to_vec(), params.to_vec()));
    }
}

// ---- Item: bodies resting on planes ----

/// The model of `inner` without its held mean motions.
struct NoHolds<'a>(&'a dyn Model);

impl Model for NoHolds<'_> {
    fn layout(&self) -> &Layout {
        self.0.layout()
    }
    fn reference(&self) -> &[Vec3] {
        self.0.reference()
    }
    fn rigid_motions(&self) -> Vec<[f64; 6]> {
        self.0.rigid_motions()
    }
    fn parameters(&self) -> &[String] {
        self.0.parameters()
    }
    fn evaluate(
        &self,
        u: &[f64],
        params: &[f64],
        request: Request,
        out: &mut Evaluation,
    ) -> Result<(), ModelError> {
        self.0.evaluate(u, params, request, out)
    }
    fn new_evaluation(&self) -> Evaluation {
        self.0.new_evaluation()
    }
}

#[test]
fn a_sphere_resting_on_a_plane_has_no_spurious_e1_points_where_it_is_stable() {
    for (frequency, max_v) in [(8, 3.0), (16, 1.3)] {
        let mut study = study(&paper2(frequency, max_v));
        let mut states = States::default();
        let report = run_with(&mut study, &mut states)
            .expect("the path runs")
            .report;
        // The axisymmetric path is stable, and no critical point is found on it.
        assert!(
            report.rows.iter().all(|r| r.index == Some(0)),
            "f = {frequency}"
        );
        assert!(
            report.critical.is_empty(),
            "f = {frequency}: {:?}",
            report.critical
        );
        let basis = AdaptedBasis::new(&study.action, study.model.layout()).unwrap();
        let e1 = basis.irreps.iter().position(|b| b.name == "E1").unwrap();
        let held = Stability::new(&study.model, &basis);
        let bare = NoHolds(&study.model);
        let unheld = Stability::new(&bare, &basis);
        let mut eval = study.model.new_evaluation();
        let (mut flips, mut last) = (0, None);
        for (u, p) in &states.0 {
            let a = held
                .analyse(u, p, &study.constraints, &mut eval, None, Detail::Inertia)
                .unwrap();
            // The rolling about the two horizontal axes is held in E1 (one pair), nowhere else.
            let counts: Vec<usize> = a.blocks.iter().map(|b| b.held).collect();
            let expected: Vec<usize> = a
                .blocks
                .iter()
                .map(|b| usize::from(b.irrep == "E1"))
                .collect();
            assert_eq!(counts, expected, "f = {frequency}");
            assert_eq!(a.blocks[e1].negative, 0, "f = {frequency}");
            // Without the hold the nearly neutral rolling wanders across zero.
            let b = unheld
                .analyse(u, p, &study.constraints, &mut eval, None, Detail::Inertia)
                .unwrap();
            let n = b.blocks[e1].negative;
            if last.is_some_and(|l| l != n) {
                flips += 1;
            }
            last = Some(n);
        }
        assert!(
            flips >= 2,
            "f = {frequency}: the unheld E1 count changed {flips} times"
        );
    }
}

#[test]
fn the_spectrum_reports_the_held_rolling() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p2.toml");
    std::fs::write(&path, paper2(4, 1.0)).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_memstab"))
        .args(["spectrum", path.to_str().unwrap(), "--json"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for irrep in json["irreps"].as_array().unwrap() {
        let held = usize::from(irrep["name"] == "E1");
        assert_eq!(irrep["held_motions"], held, "{irrep}");
    }
    assert_eq!(json["index"], 0);
}

// ---- Item: the scene's group from the set of effects ----

#[test]
fn two_planes_one_offset_keep_c2v_and_unequal_ones_do_not() {
    let text =
        bundled("thesis/paper3_squeezed_cap.toml").replace("divisions = 12", "divisions = 4");
    assert_eq!(study(&text).action.group().name(), "C2v");
    // One plane alone, or planes with different offsets, keep only the mirror y = 0.
    let one = text.replacen(
        "normal = [1.0, 0.0, 0.0]\noffset = \"d\"",
        "normal = [1.0, 0.0, 0.0]\noffset = -2.0",
        1,
    );
    assert_ne!(one, text);
    assert_eq!(study(&one).action.group().name(), "C1v");
    let soft = text.replacen(
        "offset = \"d\"               # x >= d = -a\npenalty = 1000.0",
        "offset = \"d\"               # x >= d = -a\npenalty = 999.0",
        1,
    );
    assert_ne!(soft, text);
    assert_eq!(study(&soft).action.group().name(), "C1v");
}

#[test]
fn the_squeezed_cap_is_stable_and_antisymmetric_modes_are_not_folds() {
    let text = bundled("thesis/paper3_squeezed_cap.toml")
        .replace("divisions = 12", "divisions = 6")
        .replace("max = -0.4", "max = -0.7");
    let mut s = study(&text);
    let report = run(&mut s, |_, _| {}).unwrap().report;
    assert!(report.rows.len() > 5);
    assert!(report.critical.is_empty(), "{:?}", report.critical);
    assert!(report.rows.iter().all(|r| r.index == Some(0)));
}

// ---- Item: the fluid volume as the control ----

fn ponding_disc(control_volume: bool) -> String {
    let volume = if control_volume {
        "[[constraint]]\ntype = \"fluid-volume\"\nvalue = \"V\"\n\n[parameters.V]\nstart = 0.004\nmax = 30.0\n\n[parameters.h]\nstart = 0.001\n"
    } else {
        "[parameters.h]\nstart = 0.001\nmax = 3.0\n"
    };
    format!(
        r#"
[scene]
name = "downward-loaded-disc"
[mesh]
generator = "disc"
radius = 1.1
sectors = 7
divisions = 6
[material]
mu = 100.0
k = 0.0
thickness = 0.01
prestretch = 1.1
[[effect]]
type = "fluid"
side = "above"
density = 1.0
gravity = 1.0
level = "h"
[boundary]
fixed = ["rim"]
{volume}
[analysis]
type = "path"
control = "{}"
steps = 150
stop-displacement = 1.5
"#,
        if control_volume { "V" } else { "h" }
    )
}

#[test]
fn the_downward_loaded_disc_folds_in_the_level_but_not_in_the_volume() {
    let level = run(&mut study(&ponding_disc(false)), |_, _| {})
        .unwrap()
        .report;
    let limits: Vec<_> = level
        .critical
        .iter()
        .filter(|c| c.kind == CriticalKind::LimitPoint)
        .collect();
    assert_eq!(limits.len(), 1, "{:?}", level.critical);
    assert_eq!(level.turning_points.len(), 1);
    let h_max = level.turning_points[0].parameters[0];
    let volume = run(&mut study(&ponding_disc(true)), |_, _| {})
        .unwrap()
        .report;
    assert!(
        volume.turning_points.is_empty(),
        "{:?}",
        volume.turning_points
    );
    assert!(volume.critical.is_empty(), "{:?}", volume.critical);
    assert!(volume.rows.iter().all(|r| r.index == Some(0)));
    assert!(
        matches!(volume.stop, StopReason::Displacement { .. }),
        "{}",
        volume.stop
    );
    // The volume path passes the level's maximum: h rises to it and falls again, and the
    // fluid volume follows the control to round-off.
    let (v, h, vf) = (
        parameter(&volume, "V"),
        parameter(&volume, "h"),
        column(&volume, "fluid_volume"),
    );
    let top = volume
        .rows
        .iter()
        .map(|r| r.parameters[h])
        .fold(f64::MIN, f64::max);
    assert!((top - h_max).abs() < 0.02 * h_max, "{top} vs {h_max}");
    assert!(volume.rows.last().unwrap().parameters[h] < 0.9 * top);
    for r in &volume.rows {
        assert!((r.measures[vf] - r.parameters[v]).abs() < 1e-9 * r.parameters[v].max(1e-3));
    }
}

// ---- Item: sliding edges ----

#[test]
fn a_sliding_edge_moves_in_its_plane_only_and_settles_at_a_right_angle() {
    // The pre-stretched cap below the equator (cut at z = -0.5) meets the floor at an angle:
    // with its edge sliding, the gas pushes the edge outward until the membrane meets the floor
    // at a right angle, the rim reaching about the equator's radius.
    let text = bundled("thesis/paper3_squeezed_cap.toml")
        .replace("divisions = 12", "divisions = 6")
        .replace("cut-height = 0.0", "cut-height = -0.5");
    let (body, _) = text
        .split_once("[[effect]]                 # effect[1]")
        .unwrap();
    let text = body.to_string()
        + "[boundary]\n\n[[boundary.slide]]\nset = \"cut\"\nnormal = [0.0, 0.0, 1.0]\n\n[parameters.p]\nstart = 0.5124\n\n[analysis]\ntype = \"equilibrium\"\n";
    let mut s = study(&text);
    assert_eq!(s.action.group().name(), "C8v");
    let result = run(&mut s, |_, _| {}).expect("the equilibrium converges");
    let u = &result.states[0].u;
    let x = s.model.positions(u, &result.states[0].params);
    let rim = &s.mesh.mesh.boundaries["cut"];
    for &i in rim {
        assert_eq!(x[i].z, -0.5, "node {i} left the floor");
        let r = x[i].xy().norm();
        assert!(r > 0.95 && r < 1.2, "rim radius {r}");
    }
    // The bases span only displacements with u_z = 0 at the sliding nodes.
    let basis = AdaptedBasis::new(&s.action, s.model.layout()).unwrap();
    let total: usize = basis.irreps.iter().map(|b| b.dim * b.multiplicity).sum();
    assert_eq!(total, s.model.unknowns() - rim.len());
    let fixed = SparseBasis::fixed_point(&s.action, s.model.layout());
    for col in fixed.columns() {
        for &(d, v) in col {
            if let Some(&i) = rim.iter().find(|&&i| s.model.layout().dof(i, 2) == Some(d)) {
                assert!(v.abs() < 1e-14, "column value {v} at node {i} along z");
            }
        }
    }
}

// ---- Item: completely filled enclosures ----

#[test]
fn a_filled_cap_is_pulled_where_a_clipped_one_forms_a_void() {
    // The spinning cap of Paper 4 spun up to w2 = 9, its fluid volume held: spin pushes the
    // wall out, so the top must be pulled in. The filled fluid does (ρ g (h − z) < 0 there);
    // a clipped one cannot, its level sinks below the top and leaves a void, where the spin
    // still acts.
    let base =
        bundled("thesis/paper4_spinning_cap.toml").replace("divisions = 12", "divisions = 6");
    let scene = |filled: bool| {
        base.replace("filled = true", &format!("filled = {filled}"))
            .replace("max = 30.0", "max = 9.0")
    };
    let solve = |filled: bool| {
        let mut s = study(&scene(filled));
        let r = run(&mut s, |_, _| {}).expect("the path runs").report;
        assert!(matches!(r.stop, StopReason::Bounds), "{}", r.stop);
        let row = r.rows.last().unwrap().clone();
        let m = |name: &str| row.measures[column(&r, name)];
        (
            m("max_z"),
            m("volume"),
            m("fluid_volume"),
            row.parameters[parameter(&r, "h")],
        )
    };
    let (top_clipped, volume_clipped, fluid_clipped, h_clipped) = solve(false);
    let (top_filled, volume_filled, fluid_filled, h_filled) = solve(true);
    // Both hold the fluid volume of the start; the filled one's is the enclosed volume.
    assert!(
        (fluid_clipped - fluid_filled).abs() < 1e-9,
        "{fluid_clipped} vs {fluid_filled}"
    );
    assert!(
        (volume_filled - fluid_filled).abs() < 1e-12,
        "{volume_filled} vs {fluid_filled}"
    );
    // The clipped one: a void above its level.
    assert!(
        h_clipped < top_clipped,
        "level {h_clipped}, top {top_clipped}"
    );
    assert!(
        volume_clipped > fluid_clipped + 1e-3,
        "void {}",
        volume_clipped - fluid_clipped
    );
    // The filled one: suction at the top (head below it), the top pulled lower.
    assert!(h_filled < top_filled, "head {h_filled}, top {top_filled}");
    assert!(
        top_filled < top_clipped - 1e-3,
        "top {top_filled} vs {top_clipped}"
    );
}

// ---- Item: classification that agrees with the path ----

#[test]
fn a_trivial_zero_where_the_control_does_not_turn_is_a_symmetric_bifurcation() {
    // The coarse disc pushed up by fluid (disc_file.toml), analysed in C1v only: the E1
    // double of C7v on the post-fold branch appears as A1 + A2, and its A1 partner is a branch
    // point of the symmetric path where the level goes on falling — a symmetric bifurcation;
    // only the fold of the level is a limit point.
    let text = bundled("disc_file.toml")
        .replace("group = \"C7v\"", "group = \"C1v\"")
        .replace(
            "path = \"meshes/disc_c7v.msh\"",
            &format!(
                "path = \"{}/scenes/meshes/disc_c7v.msh\"",
                env!("CARGO_MANIFEST_DIR")
            ),
        );
    let report = run(&mut study(&text), |_, _| {}).unwrap().report;
    assert_eq!(report.group, "C1v");
    let h = parameter(&report, "h");
    let turning: Vec<f64> = report
        .turning_points
        .iter()
        .map(|t| t.parameters[h])
        .collect();
    assert_eq!(turning.len(), 1);
    let (mut limits, mut symmetric) = (0, 0);
    for cp in report.critical.iter().filter(|c| c.irrep == "A1") {
        let at_turn = (turning[0] - cp.parameters[h]).abs() < 1e-9 * turning[0];
        match cp.kind {
            CriticalKind::LimitPoint => {
                assert!(at_turn, "a limit point at h = {}", cp.parameters[h]);
                limits += 1;
            }
            CriticalKind::SymmetricBifurcation => {
                assert!(!at_turn);
                symmetric += 1;
            }
            other => panic!("{other} in A1"),
        }
    }
    assert_eq!(
        limits,
        1,
        "{:?}",
        report.critical.iter().map(|c| c.kind).collect::<Vec<_>>()
    );
    // The first E1 point of C7v (h = 2.60897): its A1 and A2 halves.
    let near = |irrep: &str| {
        report
            .critical
            .iter()
            .any(|c| c.irrep == irrep && (c.parameters[h] - 2.60897).abs() < 1e-4)
    };
    assert!(
        symmetric >= 1 && near("A1") && near("A2"),
        "{:?}",
        report
            .critical
            .iter()
            .map(|c| (c.kind, c.parameters[h]))
            .collect::<Vec<_>>()
    );
}

// ---- Item: stops and starts ----

fn memstab(dir: &Path, args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_memstab"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap()
}

#[test]
fn a_run_restarts_from_a_saved_point_with_its_state_and_parameters() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("first.toml"), paper2(4, 2.0)).unwrap();
    let out = memstab(
        dir.path(),
        &["run", "first.toml", "--out", "first", "--quiet", "--json"],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let first: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("first/path.json")).unwrap())
            .unwrap();
    assert_eq!(first["states"]["file"], "path.states");
    let points = first["rows"].as_array().unwrap();
    assert_eq!(first["states"]["points"], points.len());
    let k = 6;
    // Continue from point 6 to a larger volume: the first row is the saved one.
    let second = paper2(4, 3.0).replace(
        "hold-translation = [0.0, 0.0, 1.0]",
        &format!("from = \"first/path.json\"\npoint = {k}"),
    );
    let second = second.replace("stretch = 1.05\n", "");
    std::fs::write(dir.path().join("second.toml"), second).unwrap();
    let out = memstab(
        dir.path(),
        &["run", "second.toml", "--out", "second", "--quiet"],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let again: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("second/path.json")).unwrap(),
    )
    .unwrap();
    let (a, b) = (&points[k], &again["rows"][0]);
    for key in ["parameters", "measures"] {
        for (x, y) in a[key]
            .as_array()
            .unwrap()
            .iter()
            .zip(b[key].as_array().unwrap())
        {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            assert!((x - y).abs() < 1e-8 * x.abs().max(1.0), "{key}: {x} vs {y}");
        }
    }
    assert!(
        b["iterations"].as_u64().unwrap() <= 2,
        "{}",
        b["iterations"]
    );
    let last = again["rows"].as_array().unwrap().last().unwrap()["parameters"][0]
        .as_f64()
        .unwrap();
    assert!(last > 3.0, "the restarted path went on to V = {last}");
    // Bad saved states: one line naming the key, exit 2, nothing written.
    for (from, point, key) in [
        ("missing/path.json", 0, "'start.from'"),
        ("first/path.json", 999, "'start.point'"),
    ] {
        let bad = paper2(4, 3.0).replace(
            "hold-translation = [0.0, 0.0, 1.0]",
            &format!("from = \"{from}\"\npoint = {point}"),
        );
        std::fs::write(dir.path().join("bad.toml"), bad).unwrap();
        let out = memstab(dir.path(), &["run", "bad.toml", "--out", "bad", "--quiet"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains(key), "{err}");
        assert!(!dir.path().join("bad").exists());
    }
    // Another mesh does not fit the saved states.
    let other = paper2(8, 3.0).replace(
        "hold-translation = [0.0, 0.0, 1.0]",
        "from = \"first/path.json\"\npoint = 0",
    );
    std::fs::write(dir.path().join("other.toml"), other).unwrap();
    let out = memstab(
        dir.path(),
        &["run", "other.toml", "--out", "other", "--quiet"],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("unknowns"), "{err}");
}

#[test]
fn a_sphere_that_newton_cannot_rest_on_the_plane_starts_by_the_homotopy() {
    let with = paper2(8, 0.6);
    let without = with.replace("hold-translation = [0.0, 0.0, 1.0]", "");
    let mut plain = study(&without);
    let err = run(&mut plain, |_, _| {}).expect_err("a plain Newton does not reach the rest");
    let message = err.to_string();
    // The message names the control by its name, the limit the start solve had (50, not the
    // path's 25) and the residual left.
    assert!(
        message.contains("at V = 0.5")
            && message.contains("in 50 iterations")
            && message.contains("residual")
            && !message.contains('λ'),
        "{message}"
    );
    let mut held = study(&with);
    let report = run(&mut held, |_, _| {})
        .expect("the homotopy starts it")
        .report;
    // At rest on the plane z = -1.06: the lowest node presses into it (penalty), by a little.
    let min_z = report.rows[0].measures[column(&report, "min_z")];
    assert!(min_z < -1.06 && min_z > -1.1, "lowest point {min_z}");
}

#[test]
fn the_ponding_path_ends_where_its_scene_says() {
    let text = bundled("disc_fluid_above.toml").replace("divisions = 16 ", "divisions = 8 ");
    let report = run(&mut study(&text), |_, _| {}).unwrap().report;
    assert!(
        matches!(report.stop, StopReason::Displacement { target } if target == 1.1),
        "{}",
        report.stop
    );
    let last = report.rows.last().unwrap();
    assert!(last.measures[column(&report, "max_displacement")] >= 1.1);
    assert!(report.rows.len() < 60, "{} points", report.rows.len());
    assert_eq!(report.turning_points.len(), 1, "the fold of the density");
}

#[test]
fn the_bundled_thesis_scenes_run_without_the_artefacts() {
    // Paper 2 on the thesis mesh (f = 16): stable, no critical point (no rolling artefact).
    let mut s = study(&bundled("thesis/paper2_sphere_on_plane.toml"));
    let r = run(&mut s, |_, _| {})
        .expect("starts by the homotopy")
        .report;
    assert_eq!((r.group.as_str(), r.mesh.elements), ("C5v", 5120));
    assert!(r.critical.is_empty(), "{:?}", r.critical);
    assert!(r.rows.iter().all(|row| row.index == Some(0)));
    assert!(matches!(r.stop, StopReason::Bounds), "{}", r.stop);
    // Paper 3: C2v between the two planes, stable.
    let mut s = study(&bundled("thesis/paper3_squeezed_cap.toml"));
    let r = run(&mut s, |_, _| {}).unwrap().report;
    assert_eq!(r.group, "C2v");
    assert!(r.critical.is_empty(), "{:?}", r.critical);
    // Paper 4: no drift or relabelling artefact before the first genuine bifurcation, and the
    // only limit point is the fold of w2.
    let mut s = study(&bundled("thesis/paper4_spinning_cap.toml"));
    let r = run(&mut s, |_, _| {}).unwrap().report;
    let w2 = parameter(&r, "w2");
    let first = r
        .critical
        .iter()
        .map(|c| c.parameters[w2])
        .fold(f64::INFINITY, f64::min);
    assert!(first > 15.0, "a critical point at w2 = {first}");
    assert_eq!(r.turning_points.len(), 1);
    let limits: Vec<_> = r
        .critical
        .iter()
        .filter(|c| c.kind == CriticalKind::LimitPoint)
        .collect();
    assert_eq!(limits.len(), 1);
    assert!((limits[0].parameters[w2] - r.turning_points[0].parameters[w2]).abs() < 1e-6);
    assert!(r
        .critical
        .iter()
        .any(|c| c.irrep == "E2" && c.kind == CriticalKind::MultipleBifurcation(2)));
}

#[test]
fn a_gas_amount_agrees_as_effect_and_as_constraint_on_a_plate_off_the_origin() {
    // A cap closed by its plate at z = -0.3 (rim fixed): the plate's z_c A_z / 3 is part of V
    // for both, so at the effect's pressure C/V - P_atm the constraint (P_atm + p) V = C holds.
    let (sym, face) = cap_mesh(-0.3);
    let m = &sym.mesh;
    let rim = &m.boundaries["cut"];
    let layout = Layout::new(m.nodes.len(), m.triangles.clone(), rim);
    let effect = GasAmount {
        amount: Quantity::Value(4.0),
        ambient: 1.0,
        closing: Some(face.clone()),
        fluid: None,
    };
    let constraint = GasAmountConstraint {
        pressure: 0,
        ambient: 1.0,
        target: 4.0,
        target_parameter: None,
        closing: Some(face.clone()),
        fluid: None,
    };
    let x = m.nodes.clone();
    let p = effect.over_pressure(&m.triangles, &x, &[]);
    let g = constraint.evaluate(&layout, &x, &[p]);
    assert!(g.value.abs() < 1e-12, "g = {}", g.value);
    // The plate matters: without it the volume differs by z_c A_z / 3.
    let plate = face.volume(&m.triangles, &x);
    assert!(plate.abs() > 0.1, "plate volume {plate}");
}

#[test]
fn fluid_below_pushes_up_whichever_way_the_mesh_normals_point() {
    // The same disc written with its triangles reversed (normals down): `below` still means
    // below in z, so the equilibrium is the same bulge upwards.
    let dir = tempfile::tempdir().unwrap();
    let sym = meshes::generators::disc(&meshes::generators::DiscOptions {
        radius: 1.1,
        sectors: 7,
        divisions: 4,
        group: None,
    })
    .unwrap();
    let mut flipped = sym.mesh.clone();
    for t in &mut flipped.triangles {
        t.swap(1, 2);
    }
    for (name, mesh) in [("up.msh", &sym.mesh), ("down.msh", &flipped)] {
        meshes::write::write_mesh(
            &dir.path().join(name),
            mesh,
            &meshes::write::Fields::new(),
            meshes::write::Format::Msh41,
        )
        .unwrap();
    }
    let scene = |file: &str| {
        format!(
            "[scene]\nname = \"bulge\"\n[mesh]\ngenerator = \"file\"\npath = \"{}\"\ngroup = \"C7v\"\n\
             [material]\nmu = 100.0\nk = 0.0\nthickness = 0.01\nprestretch = 1.1\n\
             [[effect]]\ntype = \"fluid\"\nside = \"below\"\ndensity = 1.0\ngravity = 1.0\nlevel = 0.3\n\
             [boundary]\nfixed = [\"rim\"]\n[analysis]\ntype = \"equilibrium\"\n",
            dir.path().join(file).display()
        )
    };
    let top = |file: &str| {
        let r = run(&mut study(&scene(file)), |_, _| {}).unwrap().report;
        r.rows[0].measures[column(&r, "max_z")]
    };
    let (up, down) = (top("up.msh"), top("down.msh"));
    assert!(up > 0.01, "the bulge rises to {up}");
    assert!((up - down).abs() < 1e-9 * up, "{up} vs {down}");
}

#[test]
fn bad_values_of_the_new_keys_are_one_line_errors_naming_the_key() {
    // Each a one-line message naming the key (and its value where there is one), exit code 2,
    // nothing written.
    let cap = bundled("thesis/paper4_spinning_cap.toml");
    let sphere = paper2(4, 2.0);
    let cases: Vec<(String, &str, &[&str])> = vec![
        (
            cap.replacen(
                "set = \"cut\"\nnormal = [0.0, 0.0, 1.0]",
                "set = \"cut\"\nnormal = [0.0, 0.0, 0.0]",
                1,
            ),
            "run",
            &["'boundary.slide[0].normal'"],
        ),
        (
            cap.replacen("[boundary]\n", "[boundary]\nfixed = [\"cut\"]\n", 1),
            "run",
            &["'boundary.slide[0].set'", "cut"],
        ),
        (
            cap.replacen("side = \"inside\"", "side = \"above\"", 1),
            "run",
            &["'effect[0].filled'"],
        ),
        (
            cap.replacen("stop-displacement = 1.2", "stop-displacement = -1.0", 1),
            "run",
            &["'analysis.stop-displacement'", "-1"],
        ),
        (cap.clone(), "export-matrix", &["'boundary.slide'"]),
        (
            sphere.replacen("value = \"V\"", "value = \"W\"", 1),
            "run",
            &["'constraint[0].value'", "W"],
        ),
        (
            sphere
                .replacen("value = \"V\"", "value = \"initial\"", 1)
                .replacen("amount = 6.5", "amount = \"V\"", 1),
            "run",
            &["'effect[1]'", "fluid-volume"],
        ),
        (
            sphere.replacen(
                "hold-translation = [0.0, 0.0, 1.0]",
                "hold-translation = [1.0, 0.0, 0.0]",
                1,
            ),
            "run",
            &["'start.hold-translation'"],
        ),
        (
            sphere.replacen(
                "hold-translation = [0.0, 0.0, 1.0]",
                "from = \"first/path.json\"",
                1,
            ),
            "run",
            &["start.from", "start.point"],
        ),
    ];
    for (k, (text, command, needles)) in cases.iter().enumerate() {
        let dir = tempfile::tempdir().unwrap();
        let scene = dir.path().join("bad.toml");
        let unchanged = text == &cap || text == &sphere;
        assert!(
            !unchanged || *command != "run",
            "case {k}: the replacement did not happen"
        );
        std::fs::write(&scene, text).unwrap();
        let out_path = dir.path().join("out");
        let target = if *command == "run" {
            out_path.clone()
        } else {
            dir.path().join("K.mtx")
        };
        let out = memstab(
            dir.path(),
            &[
                command,
                scene.to_str().unwrap(),
                "--out",
                target.to_str().unwrap(),
                "--quiet",
            ]
            .into_iter()
            .filter(|a| *command == "run" || *a != "--quiet")
            .collect::<Vec<_>>(),
        );
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "case {k}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "case {k}: {err}");
        for n in *needles {
            assert!(err.contains(n), "case {k}: no {n} in {err}");
        }
        assert!(!target.exists(), "case {k}: {} written", target.display());
    }
}

// ---- Item: neutral motions held in the fixed-point space ----

/// The spinning cap of Paper 4 on a C1v mesh of 6 divisions, the spin starting at `start`.
fn paper4_c1v(start: &str) -> String {
    let text = bundled("thesis/paper4_spinning_cap.toml");
    for key in ["pattern = \"C8v\"", "divisions = 12 ", "start = 0.0\n"] {
        assert!(
            text.contains(key),
            "paper4_spinning_cap.toml contains {key:?}"
        );
    }
    text.replace("pattern = \"C8v\"", "pattern = \"C1v\"")
        .replace("divisions = 12 ", "divisions = 6 ")
        .replace("start = 0.0\n", &format!("start = {start}\n"))
}

#[test]
fn a_free_cap_on_a_c1v_mesh_starts_at_rest_with_its_drift_held() {
    // At w2 = 0 the drift in x lies in Fix(C1v) and is neutral: held in the start solve and
    // the start's tangent, the path starts there and finds the broken m = 2 pair (two simple
    // bifurcations in A2) before the A1 fold of the path.
    let mut s = study(&paper4_c1v("0.0"));
    assert_eq!(s.action.group().name(), "C1v");
    let r = run(&mut s, |_, _| {}).expect("starts at w2 = 0").report;
    let w2 = parameter(&r, "w2");
    assert_eq!(r.rows[0].parameters[w2], 0.0);
    let values = |r: &PathReport, irrep: &str, kind: CriticalKind| -> Vec<f64> {
        let mut v: Vec<f64> = r
            .critical
            .iter()
            .filter(|c| c.irrep == irrep && c.kind == kind)
            .map(|c| c.parameters[w2])
            .collect();
        v.sort_by(f64::total_cmp);
        v
    };
    let a2 = values(&r, "A2", CriticalKind::SimpleBifurcation);
    let fold = values(&r, "A1", CriticalKind::LimitPoint);
    assert_eq!((a2.len(), fold.len()), (2, 1), "{:?}", r.critical);
    assert!(a2[1] < fold[0], "A2 {a2:?} before the fold {fold:?}");
    // The same points as a start off the neutral value (w2 = 0.01, where the drift has a
    // stiffness of its own); the start's fixed volume differs slightly, by 5e-4 here.
    let mut s = study(&paper4_c1v("0.01"));
    let off = run(&mut s, |_, _| {}).unwrap().report;
    let (a2_off, fold_off) = (
        values(&off, "A2", CriticalKind::SimpleBifurcation),
        values(&off, "A1", CriticalKind::LimitPoint),
    );
    assert_eq!((a2_off.len(), fold_off.len()), (2, 1));
    for (a, b) in a2.iter().chain(&fold).zip(a2_off.iter().chain(&fold_off)) {
        assert!((a - b).abs() < 0.01, "{a} against {b}");
    }
    // C8v moves the drift (E1): nothing is held in its fixed-point space.
    let c8v = study(
        &bundled("thesis/paper4_spinning_cap.toml").replace("divisions = 12 ", "divisions = 6 "),
    );
    assert_eq!(
        memstab::study::held_gauge(&c8v.model, &c8v.basis, true).ncols(),
        0
    );
}

#[test]
fn the_held_tangent_is_the_derivative_of_the_held_residual() {
    // The gauge of §7.9: R → P R with P = I − W Wᵀ; on the complement of W the held tangent
    // is the derivative of the held residual, dense and sparse, and W is its eigenvector.
    use memstab::continuation::{Problem, Tangent};
    use memstab::study::SymmetricProblem;
    let s = study(&paper4_c1v("0.5"));
    let w = memstab::study::held_gauge(&s.model, &s.basis, true);
    assert_eq!(w.ncols(), 1, "the x drift");
    let m = s.basis.dim();
    let u0 = random_vector(7, s.model.unknowns(), 1e-3);
    let q0 = s.basis.restrict(&u0);
    let mut v = nalgebra::DVector::from_vec(random_vector(11, m, 1.0));
    v -= &w * (w.transpose() * &v);
    for sparse_from in [usize::MAX, 0] {
        let mut p = SymmetricProblem::new(&s.model, &s.basis, &[], s.start.clone(), s.control)
            .holding_neutral()
            .with_sparse_tangent_from(sparse_from);
        let lambda = p.free_values(&s.start);
        let lin = p.evaluate(&q0, &lambda).unwrap();
        let apply = |t: &Tangent, x: &nalgebra::DVector<f64>| {
            t.times(&nalgebra::DMatrix::from_column_slice(
                x.len(),
                1,
                x.as_slice(),
            ))
            .column(0)
            .into_owned()
        };
        assert_eq!(
            matches!(lin.tangent, Tangent::Sparse { .. }),
            sparse_from == 0
        );
        assert!(w.column(0).dot(&lin.residual).abs() < 1e-12 * lin.residual.amax().max(1e-300));
        let kv = apply(&lin.tangent, &v);
        let eps = 1e-6;
        let plus = p.evaluate(&(&q0 + &v * eps), &lambda).unwrap().residual;
        let minus = p.evaluate(&(&q0 - &v * eps), &lambda).unwrap().residual;
        let fd = (plus - minus) / (2.0 * eps);
        let err = (&fd - &kv).amax() / kv.amax();
        assert!(
            err < 1e-5,
            "sparse_from {sparse_from}: relative error {err:e}"
        );
        let kw = apply(&lin.tangent, &w.column(0).into_owned());
        let rayleigh = w.column(0).dot(&kw);
        assert!((&kw - w.column(0) * rayleigh).amax() < 1e-9 * rayleigh.abs());
    }
}

// ---- Paper 3: gas above fluid between two planes, linear against cubic penalty ----

/// A bundled Paper 3 gas-and-fluid scene on the 512-triangle mesh with the penalty law
/// `exponent` and stiffness `kappa` on both planes, after the textual `edits`.
fn paper3_gas_fluid(name: &str, exponent: u32, kappa: f64, edits: &[(&str, &str)]) -> PathReport {
    let mut text = bundled(name);
    for (from, to) in edits {
        assert!(text.contains(from), "{from}");
        text = text.replace(from, to);
    }
    let text = text
        .replace("divisions = 12", "divisions = 8")
        .replace("\nexponent = 3", &format!("\nexponent = {exponent}"))
        .replace("\npenalty = 1000.0", &format!("\npenalty = {kappa:?}"));
    assert_eq!(text.matches(&format!("\nexponent = {exponent}")).count(), 2);
    assert_eq!(text.matches(&format!("\npenalty = {kappa:?}")).count(), 2);
    let mut s = study(&text);
    assert_eq!(s.action.group().name(), "C2v");
    let mut result = run(&mut s, |_, _| {}).unwrap();
    // Writing the run finds where the membrane wrinkles (from every point's state).
    let dir = tempfile::tempdir().unwrap();
    memstab::output::write_run(&s, &s.scene, &mut result, dir.path()).unwrap();
    result.report
}

/// The measure `name` of path `r` at the control value `x`, linear between the two path
/// points around it (`None` where the path does not reach `x`).
fn measure_at(r: &PathReport, name: &str, x: f64) -> Option<f64> {
    let (c, m) = (parameter(r, &r.control), column(r, name));
    r.rows.windows(2).find_map(|w| {
        let (a, b) = (w[0].parameters[c], w[1].parameters[c]);
        ((a - x) * (b - x) <= 0.0 && a != b).then(|| {
            let t = (x - a) / (b - a);
            w[0].measures[m] + t * (w[1].measures[m] - w[0].measures[m])
        })
    })
}

/// The largest difference of the measure `name` between two paths over 101 control values
/// evenly spread in [lo, hi].
fn largest_difference(a: &PathReport, b: &PathReport, name: &str, lo: f64, hi: f64) -> f64 {
    (0..=100)
        .map(|i| lo + (hi - lo) * i as f64 / 100.0)
        .map(|x| {
            let (u, v) = (measure_at(a, name, x), measure_at(b, name, x));
            let (u, v) = (u.expect("path a reaches x"), v.expect("path b reaches x"));
            (u - v).abs()
        })
        .fold(0.0, f64::max)
}

#[test]
fn squeezed_gas_and_fluid_the_two_penalty_laws_differ_by_the_cubic_penetration() {
    // Loading (b): fluid volume and gas amount held, the planes closing in from a = 0.99 to
    // a = 0.5. Stable and without critical points for both laws and both stiffnesses.
    let name = "thesis/paper3_gas_fluid_squeeze.toml";
    let edits = [("max = -0.1 ", "max = -0.5 ")];
    let lin3 = paper3_gas_fluid(name, 1, 1e3, &edits);
    let cub3 = paper3_gas_fluid(name, 3, 1e3, &edits);
    let lin4 = paper3_gas_fluid(name, 1, 1e4, &edits);
    let cub4 = paper3_gas_fluid(name, 3, 1e4, &edits);
    for r in [&lin3, &cub3, &lin4, &cub4] {
        assert!(r.critical.is_empty(), "{:?}", r.critical);
        assert!(r.rows.iter().all(|row| row.index == Some(0)));
        assert!(matches!(r.stop, StopReason::Bounds), "{}", r.stop);
    }
    let (lo, hi) = (-0.99, -0.5);
    let d3 = largest_difference(&lin3, &cub3, "volume", lo, hi);
    let d4 = largest_difference(&lin4, &cub4, "volume", lo, hi);
    // Measured 0.0318 and 0.0155 (volume about 2.1): a ratio of 2.05 per decade, the
    // cubic law's κ^(-1/3) (2.15), not the linear law's κ^(-1) (10).
    assert!(d3 > 0.02 && d3 < 0.05, "{d3}");
    let rate = d3 / d4;
    assert!(rate > 1.8 && rate < 2.4, "{d3} / {d4} = {rate}");
    // The linear law is already close to rigid: a decade of κ moves its volume by 2.1e-5,
    // about a tenth per decade (the next decade, 1e4 to 1e5, moves it by 2.1e-6).
    let lin = largest_difference(&lin3, &lin4, "volume", lo, hi);
    assert!(lin > 1e-6 && lin < 1e-4, "{lin}");
    assert!(lin < 1e-2 * d4, "{lin} against {d4}");
}

#[test]
fn gas_and_fluid_between_planes_lose_stability_only_once_wrinkled_and_where_the_law_says() {
    // Loading (a): the planes fixed at x = ±0.9, the fluid volume held, the gas pressure
    // lowered towards zero. Both laws are stable down to p = 0.015, wrinkle from p ≈ 0.1
    // first, and their first critical points lie in wrinkled states, at values and in
    // irreps that depend on the law: linear, a B1 bifurcation at p = 0.0130 for every κ on
    // this mesh; cubic, first points at p < 0.013 that move with κ.
    let name = "thesis/paper3_gas_fluid_pressure.toml";
    let mut firsts = Vec::new();
    for (exponent, kappa) in [(1, 1e3), (1, 1e4), (3, 1e3), (3, 1e4)] {
        // Past the bundled bound p = 0.005 to reach the cubic law's first points, and only
        // as far as them.
        let edits = [
            ("min = 0.005", "min = -0.005"),
            ("steps = 200", "steps = 40"),
        ];
        let r = paper3_gas_fluid(name, exponent, kappa, &edits);
        let p = parameter(&r, "p");
        assert!(r
            .rows
            .iter()
            .filter(|row| row.parameters[p] > 0.015)
            .all(|row| row.index == Some(0)));
        let w = r.wrinkling.as_ref().expect("the run was written");
        let first_wrinkled = w.first.expect("the cap wrinkles").step;
        let pw = r.rows[first_wrinkled].parameters[p];
        assert!(pw > 0.05 && pw < 0.15, "wrinkled from p = {pw}");
        let first = r.critical.first().expect("a critical point").clone();
        assert!(first.after_step >= first_wrinkled);
        assert!(w.critical.iter().any(|c| c.critical == 1));
        firsts.push((first.kind, first.irrep.clone(), first.parameters[p]));
    }
    // The linear law: the same B1 bifurcation at either κ (to 2e-4 in p).
    for f in &firsts[..2] {
        assert_eq!((f.0, f.1.as_str()), (CriticalKind::SimpleBifurcation, "B1"));
        assert!((f.2 - 0.0130).abs() < 5e-4, "{f:?}");
    }
    assert!((firsts[0].2 - firsts[1].2).abs() < 2e-4, "{firsts:?}");
    // The cubic law: its first point comes later (smaller p) than the linear law's and moves
    // with κ (measured -0.00167 in A1 and -0.00147 in B1).
    for f in &firsts[2..] {
        assert!(f.2 < firsts[0].2 - 5e-3, "{firsts:?}");
    }
    assert!((firsts[2].2 - firsts[3].2).abs() > 1e-4, "{firsts:?}");
}

#[test]
fn squeezed_closer_the_linear_penalty_bifurcates_where_the_cubic_one_does_not_yet() {
    // Loading (b) to a = 0.08: the linear law meets a simple bifurcation in B1 (m = 1) at
    // a = 0.1462 (κ = 1e3) and 0.1463 (κ = 1e4) on this mesh, in a state the membrane model
    // still describes; the cubic law is stable to a = 0.08 at κ = 1e3 and has its first B1
    // point at a = 0.0900 only at κ = 1e5.
    let name = "thesis/paper3_gas_fluid_squeeze.toml";
    let edits = [("max = -0.1 ", "max = -0.08 ")];
    assert!(bundled(name).contains("max-step = 0.05"));
    let first_b1 = |r: &PathReport| {
        let d = parameter(r, "d");
        let c = r.critical.first().expect("a critical point");
        assert_eq!(
            (c.kind, c.irrep.as_str()),
            (CriticalKind::SimpleBifurcation, "B1")
        );
        assert!(r.rows[..=c.after_step]
            .iter()
            .all(|row| row.index == Some(0)));
        let w = r.wrinkling.as_ref().expect("the run was written");
        assert!(w.critical.iter().all(|w| w.critical != 1), "{w:?}");
        -c.parameters[d]
    };
    let lin3 = first_b1(&paper3_gas_fluid(name, 1, 1e3, &edits));
    let lin4 = first_b1(&paper3_gas_fluid(name, 1, 1e4, &edits));
    assert!((lin3 - 0.1462).abs() < 5e-4, "{lin3}");
    assert!((lin4 - 0.1463).abs() < 5e-4, "{lin4}");
    let cub3 = paper3_gas_fluid(name, 3, 1e3, &edits);
    assert!(cub3.critical.is_empty(), "{:?}", cub3.critical);
    assert!(cub3.rows.iter().all(|row| row.index == Some(0)));
    assert!(matches!(cub3.stop, StopReason::Bounds), "{}", cub3.stop);
    let cub5 = first_b1(&paper3_gas_fluid(name, 3, 1e5, &edits));
    assert!((cub5 - 0.0900).abs() < 1e-3, "{cub5}");
}

// ---- Paper 3: the fluid level as the control, and the fold line of each penalty law ----

/// The lower fold of the level at planes x = ±a under the penalty of `exponent`
/// (`scenes/thesis/paper3_fluid_level_linear.toml`): the lowest h past the level's maximum
/// among the path's turning minima and A1 critical points; the contact nodes there; and
/// whether the fold is pinned to a change of the contact set (the critical point's two
/// bracket states have different contact sets: an eigenvalue that jumps across zero).
fn level_fold(exponent: u32, a: f64) -> (f64, f64, bool) {
    let text = bundled("thesis/paper3_fluid_level_linear.toml")
        .replace("start = -1.7 ", &format!("start = {:?} ", -a))
        .replace("\nexponent = 1", &format!("\nexponent = {exponent}"));
    assert_eq!(text.matches(&format!("\nexponent = {exponent}")).count(), 2);
    let mut s = study(&text);
    let r = run(&mut s, |_, _| {}).unwrap().report;
    let (h, contact) = (parameter(&r, "h"), column(&r, "contact_nodes"));
    let max = r
        .turning_points
        .iter()
        .find(|t| t.kind == memstab::results::Extremum::Maximum)
        .unwrap_or_else(|| panic!("a = {a}: no maximum of the level"));
    let minima = r
        .turning_points
        .iter()
        .filter(|t| t.kind == memstab::results::Extremum::Minimum)
        .map(|t| (t.parameters[h], t.measures[contact], false));
    let critical: Vec<_> = r
        .critical
        .iter()
        .filter(|c| c.irrep == "A1" && c.after_step >= max.after_step)
        .filter(|c| c.parameters[h] < max.parameters[h] - 1e-6)
        .map(|c| {
            let pinned = c.bracket.as_ref().is_some_and(|b| {
                let [(u0, p0), (u1, p1)] = &b.ends;
                s.measure(u0, p0)[contact] != s.measure(u1, p1)[contact]
            });
            (c.parameters[h], c.measures[contact], pinned)
        })
        .collect();
    let lowest = minima
        .chain(critical.iter().copied())
        .min_by(|x, y| x.0.total_cmp(&y.0))
        .unwrap_or_else(|| panic!("a = {a}: no lower fold of the level"));
    // The turning point and the critical point of one fold agree to round-off; the critical
    // point says whether it is pinned.
    critical
        .into_iter()
        .find(|c| (c.0 - lowest.0).abs() < 1e-8)
        .unwrap_or(lowest)
}

/// The curvature h'' of the fold line h(a) sampled at `a0 + i δ` by second differences
/// (index i - 1 for the sample i), and its largest jump between neighbours with where.
fn curvature(h: &[f64], delta: f64) -> (Vec<f64>, f64, usize) {
    let c: Vec<f64> = h
        .windows(3)
        .map(|w| (w[2] - 2.0 * w[1] + w[0]) / (delta * delta))
        .collect();
    let (at, jump) = c
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .enumerate()
        .max_by(|x, y| x.1.total_cmp(&y.1))
        .unwrap();
    (c, jump, at)
}

#[test]
fn the_linear_penaltys_fold_line_bends_where_its_contact_set_changes_and_the_cubic_ones_does_not() {
    // The level's lower fold past its maximum, for planes a ∈ [2.05, 2.11] at δ = 0.0025,
    // and from every other sample at 2δ. Along it the contact set at the fold changes under
    // both laws. The linear law's fold is pinned to four nodes entering contact (a corner of
    // the path) on part of the range and a smooth limit point on the rest; where that changes
    // the curvature of the fold line jumps by as much as the curvature itself, at δ and 2δ
    // alike, while its slope stays continuous (the curvature does not grow as δ halves). The
    // cubic law's fold is a smooth limit point everywhere and its curvature varies by a few
    // per cent of itself across its contact changes.
    let (a0, delta, n) = (2.05, 0.0025, 24);
    let sample = |exponent| -> Vec<(f64, f64, bool)> {
        (0..=n)
            .map(|i| level_fold(exponent, a0 + i as f64 * delta))
            .collect()
    };
    let smoothness = |folds: &[(f64, f64, bool)], law: &str| {
        let h: Vec<f64> = folds.iter().map(|f| f.0).collect();
        let coarse: Vec<f64> = h.iter().step_by(2).copied().collect();
        let (c, jump, at) = curvature(&h, delta);
        let (c2, jump2, _) = curvature(&coarse, 2.0 * delta);
        let peak = c.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let peak2 = c2.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        eprintln!(
            "{law}: contact nodes at the fold {:?}; pinned {:?}; curvature h'' {:.3?}; \
             largest jump {jump:.4} (δ = {delta}) and {jump2:.4} (2δ), largest |h''| \
             {peak:.4} and {peak2:.4}",
            folds.iter().map(|f| f.1).collect::<Vec<_>>(),
            folds.iter().map(|f| f.2).collect::<Vec<_>>(),
            c
        );
        (jump, jump2, peak, peak2, at)
    };
    let linear = sample(1);
    let cubic = sample(3);
    let (lj, lj2, lpeak, lpeak2, at) = smoothness(&linear, "linear");
    let (cj, cj2, cpeak, _, _) = smoothness(&cubic, "cubic");
    // Linear: pinned and smooth folds both occur, and the largest curvature jump lies where
    // that changes (the jump between c[at] and c[at + 1] uses samples at ..= at + 3).
    assert!(linear.iter().any(|f| f.2) && linear.iter().any(|f| !f.2));
    assert!(
        (at..at + 3).any(|i| linear[i].2 != linear[i + 1].2),
        "{at}: {linear:?}"
    );
    // ... a jump of the order of the curvature that does not shrink as the step halves ...
    assert!(
        lj > 0.5 * lpeak && lj2 > 0.5 * lpeak2,
        "{lj} {lpeak} {lj2} {lpeak2}"
    );
    assert!(lj > 0.5 * lj2, "{lj} {lj2}");
    // ... while the slope is continuous: no kink, whose second difference would double.
    assert!(lpeak < 1.5 * lpeak2, "{lpeak} {lpeak2}");
    // Cubic: the contact set at the fold changes too, but every fold is a smooth limit point
    // and the curvature is continuous across the change.
    assert!(cubic.iter().all(|f| !f.2), "{cubic:?}");
    assert!(cubic.windows(2).any(|w| w[0].1 != w[1].1), "{cubic:?}");
    assert!(cj < 0.1 * cpeak && cj2 < 0.1 * cpeak, "{cj} {cj2} {cpeak}");
    assert!(lj > 10.0 * cj, "{lj} {cj}");
}

/// The filled cap between two planes of `text` (C2v) run and written, as its report (the
/// writing adds the wrinkling summary and the validity flags).
fn between_planes(text: &str) -> memstab::results::PathReport {
    let mut s = study(text);
    assert_eq!(s.action.group().name(), "C2v");
    let mut result = run(&mut s, |_, _| {}).unwrap();
    let dir = tempfile::tempdir().unwrap();
    memstab::output::write_run(&s, &s.scene, &mut result, dir.path()).unwrap();
    result.report
}

#[test]
fn the_filled_cap_between_planes_has_limit_points_of_the_fluid_level_in_taut_states() {
    // The bundled scene (linear law, a = 1.7) and the cubic law: the level's maximum is the
    // free cap's (no node in contact, the same under both laws); its minimum lies where the
    // cap presses on the planes: a smooth limit point under the cubic law, a corner where
    // nodes enter contact under the linear one. Every triangle is in tension along both paths.
    // Planes at a = 1.4 leave no limit point: the two folds have merged.
    let run_law = |exponent: u32, a: f64| {
        between_planes(
            &bundled("thesis/paper3_fluid_level_linear.toml")
                .replace("start = -1.7 ", &format!("start = {:?} ", -a))
                .replace("\nexponent = 1", &format!("\nexponent = {exponent}")),
        )
    };
    let mut maxima = Vec::new();
    for exponent in [1, 3] {
        let r = run_law(exponent, 1.7);
        let (h, contact) = (parameter(&r, "h"), column(&r, "contact_nodes"));
        let w = r.wrinkling.as_ref().expect("the run was written");
        assert!(w.first.is_none(), "{exponent}: {:?}", w.first);
        let limits: Vec<_> = r
            .critical
            .iter()
            .filter(|c| c.kind == CriticalKind::LimitPoint && c.irrep == "A1")
            .collect();
        assert_eq!(limits.len(), 2, "{exponent}: {limits:?}");
        assert!(r.critical.iter().all(|c| c.irrep == "A1"));
        assert!(limits[0].parameters[h] > limits[1].parameters[h]);
        assert_eq!(limits[0].measures[contact], 0.0);
        assert!(limits[1].measures[contact] > 0.0);
        let jump = limits[1].residual_eigenvalue > 1e-8;
        assert_eq!(
            jump,
            exponent == 1,
            "{exponent}: {}",
            limits[1].residual_eigenvalue
        );
        maxima.push(limits[0].parameters[h]);
        let r = run_law(exponent, 1.4);
        assert!(
            r.critical.is_empty() && r.turning_points.is_empty(),
            "{exponent}"
        );
        assert!(r.rows.iter().all(|row| row.index == Some(0)));
    }
    assert!((maxima[0] - maxima[1]).abs() < 1e-9, "{maxima:?}");
}

#[test]
fn the_linear_penalty_turns_the_fluid_level_at_the_contact_jump() {
    // Under the linear law the level's minimum is a corner of the path: four nodes enter
    // contact and the control's tangent jumps across zero there without passing through it.
    // The turning point is at the jump (the critical point flagged contact-jump, to its
    // bracket), at the lowest level the path reaches, and flagged contact-jump itself; under
    // the cubic law the minimum is a smooth turning point, unflagged.
    let run_law = |exponent: u32| {
        let text = bundled("thesis/paper3_fluid_level_linear.toml")
            .replace("\nexponent = 1", &format!("\nexponent = {exponent}"));
        let mut s = study(&text);
        let mut result = run(&mut s, |_, _| {}).unwrap();
        let dir = tempfile::tempdir().unwrap();
        memstab::output::write_run(&s, &s.scene, &mut result, dir.path()).unwrap();
        result.report
    };
    for exponent in [1, 3] {
        let r = run_law(exponent);
        let h = parameter(&r, "h");
        let minima: Vec<usize> = (0..r.turning_points.len())
            .filter(|&t| r.turning_points[t].kind == Extremum::Minimum)
            .collect();
        assert_eq!(minima.len(), 1, "{exponent}: {:?}", r.turning_points);
        let t = minima[0];
        let h_min = r.turning_points[t].parameters[h];
        let flags: Vec<&str> = r.turning_flags(t).iter().map(|f| f.name()).collect();
        let maximum = r
            .turning_points
            .iter()
            .find(|p| p.kind == Extremum::Maximum)
            .expect("a maximum");
        // The lowest level over the rows past the maximum (the path starts lower, at h = 3).
        let lowest_row = r.rows[maximum.after_step + 1..]
            .iter()
            .map(|row| row.parameters[h])
            .fold(f64::INFINITY, f64::min);
        assert!(r.turning_flags(0).is_empty() && maximum.corner.is_none());
        if exponent == 1 {
            let k = r
                .critical
                .iter()
                .position(|c| c.parameters[h] < 7.8)
                .expect("the jump");
            assert!(r.flags(k).iter().any(|f| f.name() == "contact-jump"));
            let jump = r.critical[k].parameters[h];
            // Both are bisected to 1e-10 of a step of 0.01 in arclength, where |dh/ds| < 1.
            assert!((h_min - jump).abs() < 1e-11, "{h_min} {jump}");
            assert!((h_min - 7.72412).abs() < 5e-6, "{h_min}");
            // The lowest level reached: below every row (the corner lies inside a step).
            assert!(h_min <= lowest_row, "{h_min} {lowest_row}");
            assert!(lowest_row - h_min < 1e-3, "{h_min} {lowest_row}");
            assert_eq!(flags, ["contact-jump"], "{:?}", r.turning_flags(t));
            assert!(r.turning_points[t].corner.is_some());
        } else {
            assert!((h_min - 7.70640).abs() < 5e-6, "{h_min}");
            assert!(h_min <= lowest_row, "{h_min} {lowest_row}");
            assert!(flags.is_empty(), "{flags:?}");
            assert!(r.turning_points[t].corner.is_none());
        }
    }
}

#[test]
fn close_planes_give_the_fluid_level_a_b1_bifurcation_that_moves_with_the_mesh_and_the_law() {
    // The filled cap between planes at a = 0.55 (the bundled scene), the level raised: the
    // linear law meets a simple bifurcation in B1 (m = 1, isotropy C1v) in a taut state, its
    // eigenvalue crossing zero smoothly (the point is valid: not wrinkled, localised, no
    // contact change), and the path is unstable in B1 only up to the next change of the
    // contact set, a B1 point flagged contact-jump. It is penalty- and mesh-induced: it moves
    // from h = 17.2602 (512 triangles) to 18.4818 (1 152), and the cubic law at the same κ
    // has no critical point, index 0 in every block along its path.
    let run_scene = |divisions: usize, exponent: u32| {
        between_planes(
            &bundled("thesis/paper3_fluid_level_bifurcation.toml")
                .replace("divisions = 8 ", &format!("divisions = {divisions} "))
                .replace("\nexponent = 1", &format!("\nexponent = {exponent}")),
        )
    };
    let mut onsets = Vec::new();
    for divisions in [8, 12] {
        let r = run_scene(divisions, 1);
        let (h, contact) = (parameter(&r, "h"), column(&r, "contact_nodes"));
        let b1 = r.irreps.iter().position(|i| i == "B1").unwrap();
        assert!(r.critical.iter().all(|c| c.irrep == "B1"), "{divisions}");
        assert!(r.critical.len() >= 2, "{divisions}: {}", r.critical.len());
        let (onset, end) = (&r.critical[0], &r.critical[1]);
        assert_eq!(
            (onset.kind, onset.multiplicity, onset.isotropy.name.as_str()),
            (CriticalKind::SimpleBifurcation, 1, "C1v"),
            "{divisions}"
        );
        assert!(r.flags(0).is_empty(), "{divisions}: {:?}", r.flags(0));
        let end_flags: Vec<&str> = r.flags(1).iter().map(|f| f.name()).collect();
        assert!(
            end_flags.contains(&"contact-jump"),
            "{divisions}: {end_flags:?}"
        );
        assert!(
            !end_flags.contains(&"wrinkled"),
            "{divisions}: {end_flags:?}"
        );
        // The path point past the jump has more nodes in contact than the onset's state.
        let past = &r.rows[end.after_step + 1];
        assert_eq!(past.step, end.after_step + 1);
        assert!(
            past.measures[contact] > onset.measures[contact],
            "{divisions}: {} {}",
            past.measures[contact],
            onset.measures[contact]
        );
        // Unstable in B1 exactly between the two points, stable in every other block.
        let (h0, h1) = (onset.parameters[h], end.parameters[h]);
        let unstable: Vec<f64> = r
            .rows
            .iter()
            .filter(|row| row.negative.as_ref().unwrap()[b1] > 0)
            .map(|row| row.parameters[h])
            .collect();
        assert!(!unstable.is_empty(), "{divisions}");
        assert!(
            unstable.iter().all(|&v| v > h0 && v < h1),
            "{divisions}: {unstable:?}"
        );
        assert!(r
            .rows
            .iter()
            .all(|row| row.index == row.negative.as_ref().map(|n| n[b1])));
        onsets.push(h0);
    }
    assert!((onsets[0] - 17.2602).abs() < 1e-3, "{onsets:?}");
    assert!((onsets[1] - 18.4818).abs() < 1e-3, "{onsets:?}");
    assert!(onsets[1] - onsets[0] > 1.0, "{onsets:?}");
    let cubic = run_scene(8, 3);
    assert!(cubic.critical.is_empty(), "{:?}", cubic.critical.len());
    assert!(cubic.rows.iter().all(|row| row.index == Some(0)));
    assert!(cubic.rows.len() > 50);
}
