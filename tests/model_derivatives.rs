//! Assembled models against finite differences: residual vs Π, tangent (with its rank-one
//! terms) vs residual, symmetry, load vectors vs differences in Λ — at random states.

use memstab::effects::gas::{GasAmount, GasPressure};
use memstab::effects::membrane::{MaterialQuantities, Membrane, MooneyRivlin, Wrinkling};
use memstab::effects::Quantity;
use memstab::model::check::check_derivatives;
use memstab::model::CellQuantity;
use memstab::model::{Effect, FeModel, Model};
use meshes::generators::{disc, icosphere, DiscOptions, IcosphereOptions};
use proptest::prelude::*;

fn sphere_model(k: f64, with_amount: bool) -> FeModel {
    let sym = icosphere(&IcosphereOptions {
        radius: 1.0,
        frequency: 2,
    })
    .unwrap();
    let m = &sym.mesh;
    let membrane =
        Membrane::new(&m.nodes, &m.triangles, MooneyRivlin::new(1.0, k, 0.1), 1.0).unwrap();
    let mut effects: Vec<Box<dyn Effect>> = vec![Box::new(membrane)];
    if with_amount {
        effects.push(Box::new(GasAmount {
            amount: Quantity::Parameter(0),
            ambient: 1.0,
            closing: None,
            fluid: None,
        }));
    } else {
        effects.push(Box::new(GasPressure {
            closing: None,
            pressure: Quantity::Parameter(0),
        }));
    }
    FeModel::new(
        m.nodes.clone(),
        m.triangles.clone(),
        &[],
        effects,
        vec!["p".into()],
    )
}

fn random_vector(seed: u64, n: usize, amplitude: f64) -> Vec<f64> {
    // A small deterministic generator: the proptest seed drives it.
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

proptest! {
    #![proptest_config(ProptestConfig { cases: 16, failure_persistence: None, .. ProptestConfig::default() })]

    #[test]
    fn membrane_with_gas_pressure(seed in any::<u64>(), k in 0.0f64..0.3, p in -1.0f64..2.0, stretch in 1.0f64..1.6) {
        let model = sphere_model(k, false);
        let n = model.unknowns();
        // A random state around a uniformly stretched sphere.
        let mut u = random_vector(seed, n, 0.03);
        for (i, x) in model.reference().iter().enumerate() {
            for c in 0..3 {
                u[3 * i + c] += (stretch - 1.0) * x[c];
            }
        }
        let d = random_vector(seed ^ 0xabcdef, n, 1.0);
        let e = check_derivatives(&model, &u, &[p], &d, 1e-6).unwrap();
        prop_assert!(e.residual < 1e-7, "{e:?}");
        prop_assert!(e.tangent < 1e-6, "{e:?}");
        prop_assert!(e.asymmetry < 1e-13, "{e:?}");
        prop_assert!(e.loads < 1e-7, "{e:?}");
    }

    #[test]
    fn membrane_with_a_fixed_amount_of_gas(seed in any::<u64>(), c in 1.0f64..10.0, stretch in 1.0f64..1.6) {
        let model = sphere_model(0.1, true);
        let n = model.unknowns();
        let mut u = random_vector(seed, n, 0.03);
        for (i, x) in model.reference().iter().enumerate() {
            for k in 0..3 {
                u[3 * i + k] += (stretch - 1.0) * x[k];
            }
        }
        let d = random_vector(seed ^ 0x1234, n, 1.0);
        let e = check_derivatives(&model, &u, &[c], &d, 1e-6).unwrap();
        prop_assert!(e.residual < 1e-7, "{e:?}");
        prop_assert!(e.tangent < 1e-6, "{e:?}");
        prop_assert!(e.asymmetry < 1e-13, "{e:?}");
        prop_assert!(e.loads < 1e-7, "{e:?}");
    }
}

/// A sphere whose membrane has μ, k, H and λ0 as parameters 0…3, under a gas pressure
/// (parameter 4); with `built_at`, generated at that radius and with its reference radius as
/// parameter 5.
fn parametric_sphere_model(built_at: Option<f64>) -> FeModel {
    parametric_sphere_model_with(built_at, Wrinkling::None)
}

/// [`parametric_sphere_model`] with the plain or the relaxed energy.
fn parametric_sphere_model_with(built_at: Option<f64>, wrinkling: Wrinkling) -> FeModel {
    let sym = icosphere(&IcosphereOptions {
        radius: built_at.unwrap_or(1.0),
        frequency: 2,
    })
    .unwrap();
    let m = &sym.mesh;
    let material = MaterialQuantities {
        mu: Quantity::Parameter(0),
        k: Quantity::Parameter(1),
        thickness: Quantity::Parameter(2),
        prestretch: Quantity::Parameter(3),
    };
    let mut membrane = Membrane::parametric(&m.nodes, &m.triangles, material)
        .unwrap()
        .with_wrinkling(wrinkling);
    let mut names = vec!["mu", "k", "thickness", "prestretch", "p"];
    if let Some(r0) = built_at {
        membrane = membrane.with_reference_radius(Quantity::Parameter(5), r0);
        names.push("R");
    }
    let effects: Vec<Box<dyn Effect>> = vec![
        Box::new(membrane),
        Box::new(GasPressure {
            pressure: Quantity::Parameter(4),
            closing: None,
        }),
    ];
    FeModel::new(
        m.nodes.clone(),
        m.triangles.clone(),
        &[],
        effects,
        names.iter().map(|s| s.to_string()).collect(),
    )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 16, failure_persistence: None, .. ProptestConfig::default() })]

    /// The loads of the material quantities: ∂F/∂μ, ∂F/∂k, ∂F/∂H and ∂F/∂λ0 against central
    /// differences of F in each (check_derivatives), with the residual and tangent checks.
    #[test]
    fn material_quantities_as_parameters(
        seed in any::<u64>(),
        mu in 0.5f64..2.0,
        k in 0.0f64..0.3,
        thickness in 0.05f64..0.2,
        prestretch in 1.0f64..1.3,
        p in -1.0f64..2.0,
        stretch in 1.0f64..1.6,
    ) {
        let model = parametric_sphere_model(None);
        let n = model.unknowns();
        let mut u = random_vector(seed, n, 0.03);
        for (i, x) in model.reference().iter().enumerate() {
            for c in 0..3 {
                u[3 * i + c] += (stretch - 1.0) * x[c];
            }
        }
        let d = random_vector(seed ^ 0x77, n, 1.0);
        let params = [mu, k, thickness, prestretch, p];
        let e = check_derivatives(&model, &u, &params, &d, 1e-6).unwrap();
        prop_assert!(e.residual < 1e-7, "{e:?}");
        prop_assert!(e.tangent < 1e-6, "{e:?}");
        prop_assert!(e.asymmetry < 1e-13, "{e:?}");
        prop_assert!(e.loads < 1e-7, "{e:?}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 16, failure_persistence: None, .. ProptestConfig::default() })]

    /// The relaxed energy assembled, at states that mix taut, wrinkled and slack triangles,
    /// exact or with a switching width: the residual against Π, the tangent against the
    /// residual, its symmetry and the loads of μ, k, H, λ0 and R against differences in each.
    #[test]
    fn relaxed_membrane_with_material_parameters(
        seed in any::<u64>(),
        built_at in 0.7f64..1.5,
        k in 0.0f64..0.3,
        prestretch in 1.0f64..1.2,
        stretch in 0.95f64..1.15,
        eps in 0.0f64..0.01,
        p in -1.0f64..2.0,
        width in prop_oneof![Just(0.0), 1e-3f64..2e-2],
    ) {
        let model = parametric_sphere_model_with(Some(built_at), Wrinkling::Relaxed {
            stiffness: eps,
            width,
        });
        let n = model.unknowns();
        let mut u = random_vector(seed, n, 0.08 * built_at);
        for (i, x) in model.reference().iter().enumerate() {
            for c in 0..3 {
                u[3 * i + c] += (stretch / prestretch - 1.0) * x[c];
            }
        }
        let params = [1.0, k, 0.1, prestretch, p, built_at];
        let states_at = |u: &[f64], params: &[f64]| {
            model
                .cell_fields(u, params)
                .into_iter()
                .find(|f| f.quantity == CellQuantity::MembraneState)
                .unwrap()
                .values
        };
        let states = states_at(&u, &params);
        let count = |code: f64| states.iter().filter(|&&s| s == code).count();
        prop_assume!(count(0.0) > 0 && count(1.0) > 0);
        let d = random_vector(seed ^ 0x33, n, 1.0);
        // A width puts curvature on the scale δ into the energy near the natural state: there
        // the differences' truncation error, which falls as h² (measured: loads 4e-3, 4e-5,
        // 4e-7, 2e-8 for h = 1e-4 … 1e-7), needs the smaller step. At δ ≈ 1e-3 it is still
        // up to 1e-7 at h = 1e-7, where round-off (up to 1e-7 there, growing as 1/h) forbids a
        // smaller one: an error above the tolerance must then stay within ten times it and be
        // that truncation, growing as h² from 4h to 8h (where round-off is smaller), which a
        // wrong derivative (an error that does not move with h) cannot do.
        let h = if width > 0.0 { 1e-7 } else { 1e-6 };
        if width == 0.0 {
            // The exact energy's residual has a kink where a triangle changes state: central
            // differences are only checked on states whose every triangle keeps its state
            // over the steps taken, in u and in each parameter.
            let shifted = |s: f64| -> Vec<f64> {
                u.iter().zip(&d).map(|(a, b)| a + s * b).collect()
            };
            prop_assume!(states_at(&shifted(h), &params) == states);
            prop_assume!(states_at(&shifted(-h), &params) == states);
            for j in 0..params.len() {
                for sign in [-1.0, 1.0] {
                    let mut pj = params;
                    pj[j] += sign * h * params[j].abs().max(1.0);
                    prop_assume!(states_at(&u, &pj) == states);
                }
            }
        }
        let e = check_derivatives(&model, &u, &params, &d, h).unwrap();
        prop_assert!(e.residual < 1e-7, "{e:?}");
        prop_assert!(e.asymmetry < 1e-13, "{e:?}");
        if e.tangent >= 1e-6 || e.loads >= 1e-7 {
            prop_assert!(width > 0.0, "{e:?}");
            let e4 = check_derivatives(&model, &u, &params, &d, 4.0 * h).unwrap();
            let e8 = check_derivatives(&model, &u, &params, &d, 8.0 * h).unwrap();
            for (name, at_h, at_4h, at_8h, tol) in [
                ("tangent", e.tangent, e4.tangent, e8.tangent, 1e-6),
                ("loads", e.loads, e4.loads, e8.loads, 1e-7),
            ] {
                if at_h >= tol {
                    prop_assert!(
                        at_h < 10.0 * tol && at_8h >= 3.0 * at_4h,
                        "{name}: {at_h:.2e} at h, {at_4h:.2e} at 4h, {at_8h:.2e} at 8h"
                    );
                }
            }
        }
    }
}

/// On a state in tension the relaxed energy without residual stiffness is the plain one:
/// the same energy, residual and tangent to round-off (the same sums, bit for bit), with
/// every parameter's load.
#[test]
fn relaxed_is_plain_on_an_inflated_sphere() {
    let plain = parametric_sphere_model_with(Some(1.0), Wrinkling::None);
    let relaxed = parametric_sphere_model_with(
        Some(1.0),
        Wrinkling::Relaxed {
            stiffness: 0.0,
            width: 0.0,
        },
    );
    let n = plain.unknowns();
    let mut u = random_vector(7, n, 0.01);
    for (i, x) in plain.reference().iter().enumerate() {
        for c in 0..3 {
            u[3 * i + c] += 0.3 * x[c];
        }
    }
    let params = [1.0, 0.1, 0.1, 1.05, 1.0, 1.0];
    let states = relaxed
        .cell_fields(&u, &params)
        .into_iter()
        .find(|f| f.quantity == CellQuantity::MembraneState)
        .unwrap()
        .values;
    assert!(states.iter().all(|&s| s == 0.0), "every triangle taut");
    let (mut a, mut b) = (plain.new_evaluation(), relaxed.new_evaluation());
    plain
        .evaluate(&u, &params, memstab::model::Request::ALL, &mut a)
        .unwrap();
    relaxed
        .evaluate(&u, &params, memstab::model::Request::ALL, &mut b)
        .unwrap();
    let close = |x: &[f64], y: &[f64]| {
        let scale = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        x.iter().zip(y).all(|(p, q)| (p - q).abs() <= 1e-13 * scale)
    };
    assert!((a.energy - b.energy).abs() <= 1e-14 * a.energy.abs());
    assert!(close(&a.residual, &b.residual));
    assert!(close(&a.tangent, &b.tangent));
    for (la, lb) in a.loads.iter().zip(&b.loads) {
        assert!(close(la, lb));
    }
}

/// The parametric membrane at given parameter values is the membrane with those values fixed.
#[test]
fn parametric_material_matches_fixed_values() {
    let model = parametric_sphere_model(None);
    let sym = icosphere(&IcosphereOptions {
        radius: 1.0,
        frequency: 2,
    })
    .unwrap();
    let m = &sym.mesh;
    let (mu, k, h, l0, p) = (1.3, 0.2, 0.1, 1.15, 0.7);
    let fixed = FeModel::new(
        m.nodes.clone(),
        m.triangles.clone(),
        &[],
        vec![
            Box::new(
                Membrane::new(&m.nodes, &m.triangles, MooneyRivlin::new(mu, k, h), l0).unwrap(),
            ),
            Box::new(GasPressure {
                pressure: Quantity::Value(p),
                closing: None,
            }),
        ],
        vec![],
    );
    let u: Vec<f64> = random_vector(3, model.unknowns(), 0.03)
        .iter()
        .zip(m.nodes.iter().flat_map(|x| [x.x, x.y, x.z]))
        .map(|(r, x)| r + 0.2 * x)
        .collect();
    let (mut a, mut b) = (model.new_evaluation(), fixed.new_evaluation());
    model
        .evaluate(&u, &[mu, k, h, l0, p], memstab::model::Request::ALL, &mut a)
        .unwrap();
    fixed
        .evaluate(&u, &[], memstab::model::Request::ALL, &mut b)
        .unwrap();
    let scale = b.residual.iter().fold(0.0f64, |s, v| s.max(v.abs()));
    let diff = a
        .residual
        .iter()
        .zip(&b.residual)
        .fold(0.0f64, |s, (x, y)| s.max((x - y).abs()));
    assert!(diff <= 1e-13 * scale, "{diff:e} of {scale:e}");
    let kd = a
        .tangent
        .iter()
        .zip(&b.tangent)
        .fold(0.0f64, |s, (x, y)| s.max((x - y).abs()));
    assert!(kd <= 1e-12 * b.tangent.iter().fold(0.0f64, |s, v| s.max(v.abs())));
}

#[test]
fn a_wrong_tangent_is_detected() {
    // The check can fail: drop the rank-one term of the fixed gas amount and the tangent
    // error must be large.
    let model = sphere_model(0.1, true);
    let n = model.unknowns();
    let u: Vec<f64> = model
        .reference()
        .iter()
        .flat_map(|x| [0.2 * x.x, 0.2 * x.y, 0.2 * x.z])
        .collect();
    let d = random_vector(7, n, 1.0);
    let good = check_derivatives(&model, &u, &[5.0], &d, 1e-6).unwrap();
    assert!(good.tangent < 1e-6);
    struct NoRankOne(FeModel);
    impl Model for NoRankOne {
        fn layout(&self) -> &memstab::model::Layout {
            self.0.layout()
        }
        fn reference(&self) -> &[memstab::model::Vec3] {
            self.0.reference()
        }
        fn rigid_motions(&self) -> Vec<[f64; 6]> {
            self.0.rigid_motions()
        }
        fn parameters(&self) -> &[String] {
            self.0.parameters()
        }
        fn new_evaluation(&self) -> memstab::model::Evaluation {
            self.0.new_evaluation()
        }
        fn evaluate(
            &self,
            u: &[f64],
            p: &[f64],
            r: memstab::model::Request,
            out: &mut memstab::model::Evaluation,
        ) -> Result<(), memstab::model::ModelError> {
            self.0.evaluate(u, p, r, out)?;
            out.rank_one.clear();
            Ok(())
        }
    }
    let bad = check_derivatives(&NoRankOne(model), &u, &[5.0], &d, 1e-6).unwrap();
    assert!(bad.tangent > 1e-3, "{bad:?}");
}

#[test]
fn a_uniformly_prestretched_flat_disc_is_in_equilibrium_without_load() {
    let sym = disc(&DiscOptions {
        radius: 1.0,
        sectors: 7,
        divisions: 6,
        group: None,
    })
    .unwrap();
    let m = &sym.mesh;
    let membrane = Membrane::new(
        &m.nodes,
        &m.triangles,
        MooneyRivlin::new(1.0, 0.1, 0.01),
        1.1,
    )
    .unwrap();
    let model = FeModel::new(
        m.nodes.clone(),
        m.triangles.clone(),
        &m.boundaries["rim"],
        vec![Box::new(membrane)],
        vec![],
    );
    let mut e = model.new_evaluation();
    model
        .evaluate(
            &vec![0.0; model.unknowns()],
            &[],
            memstab::model::Request::ALL,
            &mut e,
        )
        .unwrap();
    let fmax = e.residual.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    let kmax = e.tangent.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    assert!(
        fmax < 1e-14 * kmax.max(1.0),
        "residual {fmax:e} at the pre-stretched flat state"
    );
    assert!(kmax > 0.0);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 16, failure_persistence: None, .. ProptestConfig::default() })]

    /// The load of the reference radius, ∂F/∂R, with those of the material quantities,
    /// against central differences of F in each, on a mesh generated at another radius.
    #[test]
    fn reference_radius_as_a_parameter(
        seed in any::<u64>(),
        built_at in 0.5f64..2.0,
        ratio in 0.7f64..1.4,
        k in 0.0f64..0.3,
        prestretch in 1.0f64..1.3,
        p in -1.0f64..2.0,
        stretch in 1.0f64..1.6,
    ) {
        let model = parametric_sphere_model(Some(built_at));
        let n = model.unknowns();
        let mut u = random_vector(seed, n, 0.03 * built_at);
        // Around the reference at R = ratio · R0, uniformly stretched.
        for (i, x) in model.reference().iter().enumerate() {
            for c in 0..3 {
                u[3 * i + c] += (ratio * stretch - 1.0) * x[c];
            }
        }
        let d = random_vector(seed ^ 0x55, n, 1.0);
        let params = [1.0, k, 0.1, prestretch, p, ratio * built_at];
        let e = check_derivatives(&model, &u, &params, &d, 1e-6).unwrap();
        prop_assert!(e.residual < 1e-7, "{e:?}");
        prop_assert!(e.tangent < 1e-6, "{e:?}");
        prop_assert!(e.asymmetry < 1e-13, "{e:?}");
        prop_assert!(e.loads < 1e-7, "{e:?}");
    }
}

/// A membrane generated at R0 = 1 with its reference radius at R = 1.3 is the membrane
/// generated at 1.3: the same energy, residual and tangent at the same positions.
#[test]
fn a_scaled_reference_is_the_mesh_generated_at_that_radius() {
    let scaled = parametric_sphere_model(Some(1.0));
    let generated = parametric_sphere_model(Some(1.3));
    let (r, mu, k, h, l0, p) = (1.3, 1.2, 0.15, 0.1, 1.1, 0.4);
    // Positions 1.5 X(1.3) plus a perturbation, as displacements of each model's nodes.
    let wobble = random_vector(11, scaled.unknowns(), 0.02);
    let x: Vec<f64> = generated
        .reference()
        .iter()
        .flat_map(|x| [1.5 * x.x, 1.5 * x.y, 1.5 * x.z])
        .zip(&wobble)
        .map(|(a, b)| a + b)
        .collect();
    let displacement = |m: &FeModel| -> Vec<f64> {
        let reference = m.reference().iter().flat_map(|x| [x.x, x.y, x.z]);
        x.iter().zip(reference).map(|(a, b)| a - b).collect()
    };
    let (mut a, mut b) = (scaled.new_evaluation(), generated.new_evaluation());
    let params = [mu, k, h, l0, p, r];
    scaled
        .evaluate(
            &displacement(&scaled),
            &params,
            memstab::model::Request::ALL,
            &mut a,
        )
        .unwrap();
    generated
        .evaluate(
            &displacement(&generated),
            &params,
            memstab::model::Request::ALL,
            &mut b,
        )
        .unwrap();
    let max = |v: &[f64]| v.iter().fold(0.0f64, |s, x| s.max(x.abs()));
    let gap = |u: &[f64], v: &[f64]| {
        u.iter()
            .zip(v)
            .fold(0.0f64, |s, (x, y)| s.max((x - y).abs()))
    };
    assert!(
        (a.energy - b.energy).abs() <= 1e-13 * b.energy.abs(),
        "{} vs {}",
        a.energy,
        b.energy
    );
    assert!(gap(&a.residual, &b.residual) <= 1e-12 * max(&b.residual));
    assert!(gap(&a.tangent, &b.tangent) <= 1e-12 * max(&b.tangent));
    // Every load agrees, that of R too: ∂F/∂R does not depend on where the mesh was built.
    for j in 0..6 {
        assert!(
            gap(&a.loads[j], &b.loads[j]) <= 1e-11 * max(&b.loads[j]).max(1e-300),
            "load {j}"
        );
    }
}

/// A reference radius at or below 0 is an evaluation error naming it, never a NaN.
#[test]
fn a_radius_at_or_below_zero_is_refused() {
    let model = parametric_sphere_model(Some(1.0));
    let u = vec![0.0; model.unknowns()];
    let mut eval = model.new_evaluation();
    for r in [0.0, -0.5, f64::NAN] {
        let err = model
            .evaluate(
                &u,
                &[1.0, 0.1, 0.1, 1.0, 0.5, r],
                memstab::model::Request::ALL,
                &mut eval,
            )
            .expect_err("no energy at R <= 0");
        assert!(err.to_string().contains("R/R0"), "{err}");
    }
}
