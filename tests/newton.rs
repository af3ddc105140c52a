//! The full-space Newton solver (sparse LDLᵀ) as the check of the symmetric solver: from a
//! non-symmetric start it converges, quadratically, to the state the fixed-point solver found;
//! rank-one terms are handled by Woodbury; free bodies are refused clearly.

use memstab::adapted::SparseBasis;
use memstab::analysis::run;
use memstab::effects::gas::GasAmount;
use memstab::effects::hydrostatic::{Fluid, FluidSide};
use memstab::effects::membrane::{Membrane, MooneyRivlin};
use memstab::effects::volume::ClosingFace;
use memstab::effects::Quantity;
use memstab::model::newton::{newton, NewtonOptions};
use memstab::model::{Effect, FeModel, Model, Request};
use memstab::scene::Scene;
use memstab::study::mesh::MeshStudy;
use meshes::generators::{truncated_sphere, TruncatedSphereOptions};

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

#[test]
fn full_newton_recovers_the_symmetric_equilibrium_of_the_sagging_disc() {
    let text = std::fs::read_to_string(format!(
        "{}/scenes/disc_fluid_above.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let (body, _) = text.split_once("[analysis]").unwrap();
    let text = body
        .replace("divisions = 16 ", "divisions = 8 ")
        .replace("start = 0.0 ", "start = 1.5 ")
        + "[analysis]\ntype = \"equilibrium\"\n";
    let mut study = MeshStudy::build(Scene::from_toml_str(&text, "sag").unwrap()).unwrap();
    let result = run(&mut study, |_, _| {}).unwrap();
    let u_sym = &result.states.last().expect("the equilibrium is saved").u;
    let params = vec![1.5];
    // The symmetric solution is an equilibrium of the full model.
    let mut eval = study.model.new_evaluation();
    study
        .model
        .evaluate(u_sym, &params, Request::ALL, &mut eval)
        .unwrap();
    let force = max_abs(&eval.tangent);
    assert!(
        max_abs(&eval.residual) < 1e-9 * force,
        "full residual {:e}",
        max_abs(&eval.residual)
    );
    // From a non-symmetric start, full Newton finds the same state.
    let u0: Vec<f64> = u_sym
        .iter()
        .enumerate()
        .map(|(i, v)| v + 1e-3 * ((i as f64 * 0.37).sin()))
        .collect();
    let sol = newton(&study.model, &u0, &params, &NewtonOptions::default()).unwrap();
    assert!(sol.iterations <= 8, "{} iterations", sol.iterations);
    let diff = sol
        .u
        .iter()
        .zip(u_sym)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        diff < 1e-9 * max_abs(u_sym).max(1e-12),
        "full and symmetric solutions differ by {diff:e}"
    );
}

#[test]
fn rank_one_terms_are_solved_by_woodbury() {
    // A truncated sphere clamped at its cut, holding a fixed amount of gas (K + c ∇V ∇Vᵀ).
    let sym = truncated_sphere(&TruncatedSphereOptions {
        divisions: 6,
        ..TruncatedSphereOptions::for_pattern("C8v")
    })
    .unwrap();
    let m = &sym.mesh;
    let fixed = m.boundaries["cut"].clone();
    let membrane = Membrane::new(
        &m.nodes,
        &m.triangles,
        MooneyRivlin::new(1.0, 0.1, 1.0),
        1.05,
    )
    .unwrap();
    // The membrane with the plate below: the plate's part of V is a constant (the rim is
    // fixed), so the amount fixes a pressure near C/V − P.
    let plate = ClosingFace::new(m.nodes[fixed[0]].z, &m.triangles);
    let effects: Vec<Box<dyn Effect>> = vec![
        Box::new(membrane),
        Box::new(GasAmount {
            amount: Quantity::Value(6.0),
            ambient: 1.0,
            closing: Some(std::sync::Arc::new(plate)),
            fluid: None,
        }),
    ];
    let model = FeModel::new(
        m.nodes.clone(),
        m.triangles.clone(),
        &fixed,
        effects,
        vec![],
    );
    let sol = newton(
        &model,
        &vec![0.0; model.unknowns()],
        &[],
        &NewtonOptions::default(),
    )
    .unwrap();
    let mut e = model.new_evaluation();
    model.evaluate(&sol.u, &[], Request::ALL, &mut e).unwrap();
    assert!(!e.rank_one.is_empty());
    assert!(sol.iterations <= 12, "{} iterations", sol.iterations);
    // The symmetric solver agrees.
    let basis = SparseBasis::fixed_point(&sym.action, model.layout());
    let q = basis.restrict(&sol.u);
    let mut back = vec![0.0; model.unknowns()];
    basis.expand(&q, &mut back);
    let off = back
        .iter()
        .zip(&sol.u)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        off < 1e-9 * max_abs(&sol.u),
        "the full solution leaves the fixed-point space by {off:e}"
    );
}

#[test]
fn a_free_body_is_refused_clearly() {
    let sym = meshes::generators::icosphere(&meshes::generators::IcosphereOptions {
        radius: 1.0,
        frequency: 2,
    })
    .unwrap();
    let m = &sym.mesh;
    let effects: Vec<Box<dyn Effect>> = vec![
        Box::new(
            Membrane::new(
                &m.nodes,
                &m.triangles,
                MooneyRivlin::new(1.0, 0.1, 1.0),
                1.0,
            )
            .unwrap(),
        ),
        Box::new(Fluid {
            filled: false,
            closing: None,
            density: Quantity::Value(1.0),
            gravity: Quantity::Value(1.0),
            level: Quantity::Value(0.0),
            side: FluidSide::Behind,
        }),
    ];
    let model = FeModel::new(m.nodes.clone(), m.triangles.clone(), &[], effects, vec![]);
    let err = newton(
        &model,
        &vec![0.0; model.unknowns()],
        &[],
        &NewtonOptions::default(),
    )
    .unwrap_err();
    assert!(err.contains("rigid-body"), "{err}");
}
