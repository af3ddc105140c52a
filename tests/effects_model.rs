//! Every effect assembled into a model and checked against finite differences at random
//! states (residual vs Π, tangent vs residual, symmetry, loads vs Λ), plus Archimedes.

use memstab::effects::hydrostatic::{Fluid, FluidSide};
use memstab::effects::membrane::{Membrane, MooneyRivlin};
use memstab::effects::plane::{PenaltyLaw, Plane};
use memstab::effects::spin::Spin;
use memstab::effects::Quantity;
use memstab::model::check::{check_derivatives, DerivativeErrors};
use memstab::model::{Effect, FeModel, Model, Request};
use meshes::generators::{disc, icosphere, DiscOptions, IcosphereOptions};
use meshes::Mesh;
use nalgebra::Vector3;
use proptest::prelude::*;

fn sphere(frequency: usize) -> Mesh {
    icosphere(&IcosphereOptions {
        radius: 1.0,
        frequency,
    })
    .unwrap()
    .mesh
}

fn random_vector(seed: u64, n: usize, amplitude: f64) -> Vec<f64> {
    let mut s = seed;
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            amplitude * (((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0)
        })
        .collect()
}

/// Random state around a uniform stretch; derivative errors along a random direction.
fn errors(model: &FeModel, seed: u64, stretch: f64, params: &[f64]) -> DerivativeErrors {
    let n = model.unknowns();
    let mut u = random_vector(seed, n, 0.02);
    for (i, x) in model.reference().iter().enumerate() {
        if let Some(d) = model.layout().dof(i, 0) {
            for c in 0..3 {
                u[d + c] += (stretch - 1.0) * x[c];
            }
        }
    }
    let d = random_vector(seed ^ 0x5555, n, 1.0);
    check_derivatives(model, &u, params, &d, 1e-6).unwrap()
}

fn assert_small(e: DerivativeErrors) -> Result<(), TestCaseError> {
    prop_assert!(e.residual < 1e-7, "{e:?}");
    prop_assert!(e.tangent < 1e-5, "{e:?}");
    prop_assert!(e.asymmetry < 1e-13, "{e:?}");
    prop_assert!(e.loads < 1e-6, "{e:?}");
    Ok(())
}

fn membrane(m: &Mesh, prestretch: f64) -> Box<dyn Effect> {
    Box::new(
        Membrane::new(
            &m.nodes,
            &m.triangles,
            MooneyRivlin::new(1.0, 0.1, 1.0),
            prestretch,
        )
        .unwrap(),
    )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, failure_persistence: None, .. ProptestConfig::default() })]

    #[test]
    fn fluid_inside_a_closed_membrane(seed in any::<u64>(), h in -1.2f64..1.2, rho in 0.1f64..3.0) {
        let m = sphere(2);
        let fluid = Fluid { filled: false, closing: None, density: Quantity::Parameter(0), gravity: Quantity::Value(1.0), level: Quantity::Parameter(1), side: FluidSide::Behind };
        let model = FeModel::new(m.nodes.clone(), m.triangles.clone(), &[], vec![membrane(&m, 1.0), Box::new(fluid)], vec!["rho".into(), "h".into()]);
        assert_small(errors(&model, seed, 1.2, &[rho, h]))?;
    }

    #[test]
    fn fluid_above_a_clamped_disc(seed in any::<u64>(), h in -0.2f64..0.3, rho in 0.1f64..3.0) {
        let sym = disc(&DiscOptions { radius: 1.0, sectors: 5, divisions: 4, group: None }).unwrap();
        let m = &sym.mesh;
        let fluid = Fluid { filled: false, closing: None, density: Quantity::Parameter(0), gravity: Quantity::Value(1.0), level: Quantity::Parameter(1), side: FluidSide::Front };
        let model = FeModel::new(m.nodes.clone(), m.triangles.clone(), &m.boundaries["rim"], vec![membrane(m, 1.1), Box::new(fluid)], vec!["rho".into(), "h".into()]);
        assert_small(errors(&model, seed, 1.0, &[rho, h]))?;
    }

    #[test]
    fn spinning_fluid(seed in any::<u64>(), w2 in 0.0f64..4.0, rho in 0.5f64..2.0) {
        let m = sphere(2);
        let spin = Spin { density: Quantity::Parameter(1), omega2: Quantity::Parameter(0), side: FluidSide::Behind };
        let model = FeModel::new(m.nodes.clone(), m.triangles.clone(), &[], vec![membrane(&m, 1.0), Box::new(spin)], vec!["w2".into(), "rho".into()]);
        assert_small(errors(&model, seed, 1.1, &[w2, rho]))?;
    }

    /// Gravity as a parameter: ∂F/∂g = ±ρ ∇φ, with the density and the level also free.
    #[test]
    fn fluid_with_gravity_as_a_parameter(seed in any::<u64>(), h in -0.2f64..0.3, rho in 0.1f64..3.0, g in 0.5f64..2.0) {
        let sym = disc(&DiscOptions { radius: 1.0, sectors: 5, divisions: 4, group: None }).unwrap();
        let m = &sym.mesh;
        let fluid = Fluid { filled: false, closing: None, density: Quantity::Parameter(0), gravity: Quantity::Parameter(2), level: Quantity::Parameter(1), side: FluidSide::Behind };
        let model = FeModel::new(m.nodes.clone(), m.triangles.clone(), &m.boundaries["rim"], vec![membrane(m, 1.1), Box::new(fluid)], vec!["rho".into(), "h".into(), "g".into()]);
        assert_small(errors(&model, seed, 1.0, &[rho, h, g]))?;
    }

    /// The penalty κ of a plane as a parameter, with the offset also free.
    #[test]
    fn plane_with_the_penalty_as_a_parameter(seed in any::<u64>(), d in -1.1f64..-0.8, kappa in 10.0f64..100.0, cubic in any::<bool>()) {
        let m = sphere(2);
        let law = if cubic { PenaltyLaw::Cubic } else { PenaltyLaw::Linear };
        let plane = Plane { normal: Vector3::z(), offset: Quantity::Parameter(0), penalty: Quantity::Parameter(1), law };
        let model = FeModel::new(m.nodes.clone(), m.triangles.clone(), &[], vec![membrane(&m, 1.0), Box::new(plane)], vec!["d".into(), "kappa".into()]);
        assert_small(errors(&model, seed, 1.05, &[d, kappa]))?;
    }

    #[test]
    fn rigid_planes(seed in any::<u64>(), d in -1.1f64..-0.8, cubic in any::<bool>()) {
        let m = sphere(2);
        let law = if cubic { PenaltyLaw::Cubic } else { PenaltyLaw::Linear };
        let plane = Plane { normal: Vector3::z(), offset: Quantity::Parameter(0), penalty: Quantity::Value(50.0), law };
        let model = FeModel::new(m.nodes.clone(), m.triangles.clone(), &[], vec![membrane(&m, 1.0), Box::new(plane)], vec!["d".into()]);
        assert_small(errors(&model, seed, 1.05, &[d]))?;
    }
}

/// Net force of the fluid on a closed membrane immersed in a pool, Σ_i (−F_i).
fn buoyancy(m: &Mesh, level: f64) -> Vector3<f64> {
    let fluid = Fluid {
        filled: false,
        closing: None,
        density: Quantity::Value(2.0),
        gravity: Quantity::Value(9.81),
        level: Quantity::Value(level),
        side: FluidSide::Front,
    };
    let model = FeModel::new(
        m.nodes.clone(),
        m.triangles.clone(),
        &[],
        vec![Box::new(fluid)],
        vec![],
    );
    let mut e = model.new_evaluation();
    model
        .evaluate(&vec![0.0; model.unknowns()], &[], Request::RESIDUAL, &mut e)
        .unwrap();
    let mut f = Vector3::zeros();
    for (i, r) in e.residual.iter().enumerate() {
        f[i % 3] -= r;
    }
    f
}

#[test]
fn archimedes_on_a_sphere_converges_at_second_order() {
    // A unit sphere immersed to the level h = 0.3 displaces the cap below it:
    // V = π (R + h)² (2R − h) / 3 for the part below z = h.
    let h: f64 = 0.3;
    let exact = std::f64::consts::PI * (1.0 + h).powi(2) * (2.0 - h) / 3.0 * 2.0 * 9.81;
    let errs: Vec<f64> = [8, 16]
        .iter()
        .map(|&f| {
            let force = buoyancy(&sphere(f), h);
            assert!(
                force.x.abs() < 1e-10 * exact && force.y.abs() < 1e-10 * exact,
                "{force}"
            );
            (force.z - exact).abs() / exact
        })
        .collect();
    let rate = (errs[0] / errs[1]).log2();
    assert!(errs[1] < 5e-3, "{errs:?}");
    assert!((1.7..2.3).contains(&rate), "rate {rate}, errors {errs:?}");
}

/// An evaluation restricted to the triangles around a few nodes gives the residual and the
/// tangent's columns at those nodes as the whole mesh's evaluation does, from one state to
/// the next (it clears only the slots it writes), and no value in the columns of the nodes
/// outside its triangles.
#[test]
fn a_restricted_evaluation_is_exact_at_its_nodes_from_state_to_state() {
    use memstab::model::Subset;
    let m = sphere(3);
    let model = FeModel::new(
        m.nodes.clone(),
        m.triangles.clone(),
        &[],
        vec![membrane(&m, 1.0)],
        vec![],
    );
    let layout = model.layout();
    let nodes = [0usize, 5, 17, 40];
    let subset = std::sync::Arc::new(Subset::around(layout, &nodes));
    let touched: std::collections::HashSet<usize> = subset
        .triangles()
        .iter()
        .flat_map(|&t| layout.triangles()[t])
        .collect();
    let mut part = model.new_evaluation().restricted_to(subset);
    let mut whole = model.new_evaluation();
    let (col_ptr, n) = (layout.pattern().col_ptr(), model.unknowns());
    for (seed, stretch) in [(1u64, 1.2), (2, 1.5), (3, 1.1)] {
        let mut u = random_vector(seed, n, 0.03);
        for (i, x) in model.reference().iter().enumerate() {
            for c in 0..3 {
                u[layout.dof(i, c).unwrap()] += (stretch - 1.0) * x[c];
            }
        }
        model.evaluate(&u, &[], Request::ALL, &mut whole).unwrap();
        model.evaluate(&u, &[], Request::ALL, &mut part).unwrap();
        let scale = whole.tangent.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for i in 0..m.nodes.len() {
            for c in 0..3 {
                let d = layout.dof(i, c).unwrap();
                let column = col_ptr[d]..col_ptr[d + 1];
                if nodes.contains(&i) {
                    assert!((part.residual[d] - whole.residual[d]).abs() <= 1e-13 * scale);
                    for p in column {
                        let (a, b) = (part.tangent[p], whole.tangent[p]);
                        assert!((a - b).abs() <= 1e-13 * scale, "seed {seed}: {a} vs {b}");
                    }
                } else if !touched.contains(&i) {
                    assert!(column.clone().all(|p| part.tangent[p] == 0.0), "node {i}");
                }
            }
        }
    }
}
