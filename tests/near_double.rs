//! A near-double point: a tiny imperfection (one node of the C7v disc moved by 1e-7 along its
//! mirror line, leaving only C1v) turns the E1 double of the ponding ladder into two simple
//! points, in A1 and A2 of C1v, a measured gap apart — never one double point inferred from a
//! declared group, and never two points on the perfect mesh.

use memstab::adapted::SparseBasis;
use memstab::analysis::run;
use memstab::effects::hydrostatic::{Fluid, FluidSide};
use memstab::effects::membrane::{Membrane, MooneyRivlin};
use memstab::effects::Quantity;
use memstab::model::{Effect, FeModel, Model};
use memstab::scene::Scene;
use memstab::study::mesh::MeshStudy;
use meshes::SymmetricMesh;
use symmetry::Invariant;

fn ponding(max: f64) -> MeshStudy {
    let text = std::fs::read_to_string(format!(
        "{}/scenes/ponding.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let text = text
        .replace("divisions = 16 ", "divisions = 8 ")
        .replace("max = 46.0 ", &format!("max = {max} "))
        .replace("samples = 92", "samples = 24");
    MeshStudy::build(Scene::from_toml_str(&text, "near-double").unwrap()).unwrap()
}

/// (irrep, multiplicity, ρ) of the critical points near the E1 rung (ρ ≈ 5.3).
fn e1_rung(study: &mut MeshStudy) -> Vec<(String, usize, f64)> {
    let r = run(study, |_, _| {}).unwrap().report;
    r.critical
        .iter()
        .filter(|c| (c.parameters[0] - 5.3).abs() < 0.5)
        .map(|c| (c.irrep.clone(), c.multiplicity, c.parameters[0]))
        .collect()
}

#[test]
fn a_tiny_imperfection_splits_the_double_into_two_simple_points() {
    let mut perfect = ponding(6.0);
    let double = e1_rung(&mut perfect);
    assert_eq!(double.len(), 1, "{double:?}");
    assert_eq!((double[0].0.as_str(), double[0].1), ("E1", 2));

    // Move an interior node on the x-axis (the first mirror) along x by 1e-7.
    let mut study = ponding(6.0);
    let mut mesh = study.mesh.mesh.clone();
    let rim = &mesh.boundaries["rim"];
    let node = (0..mesh.nodes.len())
        .find(|&i| !rim.contains(&i) && mesh.nodes[i].y == 0.0 && mesh.nodes[i].x > 0.3)
        .expect("an interior node on the x-axis");
    mesh.nodes[node].x += 1e-7;
    // The perturbed mesh keeps only the mirror y → −y: C1v, verified.
    let c1v = study
        .mesh
        .action
        .restrict(&[Invariant::Axis(nalgebra::Vector3::y())])
        .unwrap();
    assert_eq!(c1v.group().name(), "C1v");
    let sym = SymmetricMesh::new(mesh.clone(), c1v.group().clone())
        .expect("C1v acts on the perturbed mesh");
    sym.verify().unwrap();
    assert!(
        SymmetricMesh::new(mesh.clone(), study.mesh.group().clone()).is_err(),
        "C7v must no longer act"
    );
    let m = &sym.mesh;
    let effects: Vec<Box<dyn Effect>> = vec![
        Box::new(
            Membrane::new(
                &m.nodes,
                &m.triangles,
                MooneyRivlin::new(100.0, 0.0, 0.01),
                1.1,
            )
            .unwrap(),
        ),
        Box::new(Fluid {
            filled: false,
            closing: None,
            density: Quantity::Parameter(0),
            gravity: Quantity::Value(1.0),
            level: Quantity::Value(1e-6),
            side: FluidSide::Front,
        }),
    ];
    study.model = FeModel::new(
        m.nodes.clone(),
        m.triangles.clone(),
        &m.boundaries["rim"],
        effects,
        study.parameters.clone(),
    );
    study.basis = SparseBasis::fixed_point(&sym.action, study.model.layout());
    study.action = sym.action.clone();
    study.mesh = sym;
    let split = e1_rung(&mut study);
    assert_eq!(split.len(), 2, "expected two simple points, got {split:?}");
    let mut irreps: Vec<&str> = split.iter().map(|s| s.0.as_str()).collect();
    irreps.sort();
    assert_eq!(irreps, ["A1", "A2"]);
    assert!(split.iter().all(|s| s.1 == 1), "{split:?}");
    let gap = (split[0].2 - split[1].2).abs();
    assert!(
        gap > 0.0 && gap < 1e-4 * double[0].2,
        "gap {gap:e} for a 1e-7 imperfection"
    );
    // Both lie within the gap's order of the perfect double.
    for s in &split {
        assert!(
            (s.2 - double[0].2).abs() < 1e-4 * double[0].2,
            "{s:?} vs {double:?}"
        );
    }
}
