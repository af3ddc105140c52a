//! The path follower gives the same path whether the restricted tangent is passed on dense
//! (LU of the dense extended Jacobian) or sparse (sparse LU, rank-one terms as extra
//! unknowns), and whether the whole mesh is assembled or only the triangles around the orbit
//! representatives: the balloon under pressure control through its pressure maximum, and
//! under control of the amount of gas (a rank-one stiffness and a global volume).

use crate::common::follow;
use memstab::adapted::SparseBasis;
use memstab::continuation::PathOptions;
use memstab::effects::gas::{GasAmount, GasPressure};
use memstab::effects::membrane::{Membrane, MooneyRivlin};
use memstab::effects::Quantity;
use memstab::model::{Effect, FeModel, Model};
use memstab::study::SymmetricProblem;
use meshes::generators::{icosphere, IcosphereOptions};
use nalgebra::DVector;

fn path(
    model: &FeModel,
    basis: &SparseBasis,
    start: f64,
    sparse_from: usize,
    full_assembly: bool,
) -> Vec<(f64, f64)> {
    let mut problem = SymmetricProblem::new(model, basis, &[], vec![start], Some(0))
        .with_sparse_tangent_from(sparse_from);
    if full_assembly {
        problem = problem.with_full_assembly();
    }
    let opts = PathOptions {
        initial_step: 0.05,
        max_step: 0.2,
        max_steps: 14,
        state_scale: 10.0,
        ..PathOptions::default()
    };
    let path = follow(
        &mut problem,
        &DVector::zeros(basis.dim()),
        &DVector::from_element(1, start),
        &opts,
        |_| false,
    )
    .unwrap();
    path.points
        .iter()
        .map(|p| (p.lambda[0], p.q.amax()))
        .collect()
}

/// The same path four ways: dense or sparse extended Jacobian, assembling the whole mesh or
/// only the triangles around the orbit representatives.
fn compare(model: &FeModel, basis: &SparseBasis, start: f64) {
    let reference = path(model, basis, start, usize::MAX, true);
    assert!(reference.len() > 10);
    for (sparse_from, full) in [(0, true), (usize::MAX, false), (0, false)] {
        let other = path(model, basis, start, sparse_from, full);
        assert_eq!(reference.len(), other.len());
        for ((l1, q1), (l2, q2)) in reference.iter().zip(&other) {
            let what = format!("sparse from {sparse_from}, full assembly {full}");
            assert!(
                (l1 - l2).abs() <= 1e-9 * l1.abs().max(1.0),
                "{what}: {l1} vs {l2}"
            );
            assert!(
                (q1 - q2).abs() <= 1e-9 * q1.abs().max(1.0),
                "{what}: {q1} vs {q2}"
            );
        }
    }
}

fn membrane(m: &meshes::Mesh) -> Box<dyn Effect> {
    Box::new(
        Membrane::new(
            &m.nodes,
            &m.triangles,
            MooneyRivlin::new(1.0, 0.1, 1.0),
            1.0,
        )
        .unwrap(),
    )
}

#[test]
fn sparse_and_dense_tangents_give_the_same_path() {
    let sym = icosphere(&IcosphereOptions {
        radius: 1.0,
        frequency: 4,
    })
    .unwrap();
    let m = &sym.mesh;
    let pressure = FeModel::new(
        m.nodes.clone(),
        m.triangles.clone(),
        &[],
        vec![
            membrane(m),
            Box::new(GasPressure {
                closing: None,
                pressure: Quantity::Parameter(0),
            }),
        ],
        vec!["p".into()],
    );
    let basis = SparseBasis::fixed_point(&sym.action, pressure.layout());
    compare(&pressure, &basis, 0.0);

    // Amount of gas C = (p + P) V as the control, from the unstressed sphere at p = 0.
    let ambient = 1.0;
    let amount = FeModel::new(
        m.nodes.clone(),
        m.triangles.clone(),
        &[],
        vec![
            membrane(m),
            Box::new(GasAmount {
                amount: Quantity::Parameter(0),
                ambient,
                closing: None,
                fluid: None,
            }),
        ],
        vec!["C".into()],
    );
    compare(&amount, &basis, ambient * m.volume());
}
