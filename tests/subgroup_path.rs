//! The path follower in the fixed-point space of a subgroup: a path of the Ih balloon
//! followed in Fix(H) for a proper subgroup H of Ih (a larger space that contains Fix(Ih))
//! is the same path — the same control values point by point and the same turning point — as
//! in Fix(Ih), because the balloon's path stays Ih-symmetric and both bases are orthonormal.

use crate::common::follow;
use memstab::adapted::SparseBasis;
use memstab::continuation::events::Branch;
use memstab::continuation::PathOptions;
use memstab::effects::gas::GasPressure;
use memstab::effects::membrane::{Membrane, MooneyRivlin};
use memstab::effects::Quantity;
use memstab::model::{Effect, FeModel, Model};
use memstab::results::{Extremum, StopReason};
use memstab::study::SymmetricProblem;
use meshes::generators::{icosphere, IcosphereOptions};
use meshes::GroupAction;
use nalgebra::DVector;

fn path(model: &FeModel, action: &GroupAction) -> (usize, Branch) {
    let basis = SparseBasis::fixed_point(action, model.layout());
    let problem = SymmetricProblem::new(model, &basis, &[], vec![0.0], Some(0));
    let opts = PathOptions {
        initial_step: 0.02,
        max_step: 0.2,
        max_steps: 40,
        state_scale: (model.reference().len() as f64).sqrt(),
        ..PathOptions::default()
    };
    let branch = follow(
        problem,
        &DVector::zeros(basis.dim()),
        &DVector::from_element(1, 0.0),
        &opts,
        |_| false,
    )
    .unwrap();
    (basis.dim(), branch)
}

#[test]
fn a_path_in_the_fixed_space_of_a_subgroup_is_the_same_symmetric_path() {
    let sym = icosphere(&IcosphereOptions {
        radius: 1.0,
        frequency: 3,
    })
    .unwrap();
    let m = &sym.mesh;
    let membrane = Membrane::new(
        &m.nodes,
        &m.triangles,
        MooneyRivlin::new(1.0, 0.1, 1.0),
        1.0,
    )
    .unwrap();
    let effects: Vec<Box<dyn Effect>> = vec![
        Box::new(membrane),
        Box::new(GasPressure::new(Quantity::Parameter(0))),
    ];
    let model = FeModel::new(
        m.nodes.clone(),
        m.triangles.clone(),
        &[],
        effects,
        vec!["p".into()],
    );
    let group = sym.action.group();
    let lattice = group.subgroup_lattice();
    let (full_dim, full) = path(&model, &sym.action);
    for name in ["D5d", "D3d", "Th"] {
        let class = &lattice.classes()[lattice.find(name).expect("an Ih subgroup class")];
        let sub = group.subgroup(&class.representative).unwrap();
        let action = sym.action.restrict_to(&sub).unwrap();
        let (dim, branch) = path(&model, &action);
        assert!(
            dim > full_dim,
            "{name}: Fix(H) ({dim}) must contain Fix(Ih) ({full_dim})"
        );
        assert_eq!(branch.stop, StopReason::StepBudget { steps: 40 }, "{name}");
        assert_eq!(branch.points.len(), full.points.len(), "{name}");
        let worst = branch
            .points
            .iter()
            .zip(&full.points)
            .map(|(a, b)| (a.lambda[0] - b.lambda[0]).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-9, "{name}: control values differ by {worst:e}");
        let max = |b: &Branch| {
            b.turning_points()
                .find(|t| t.kind == Extremum::Maximum)
                .map(|t| t.point.lambda[0])
                .expect("the pressure maximum")
        };
        assert!((max(&branch) - max(&full)).abs() < 1e-9, "{name}");
    }
}
