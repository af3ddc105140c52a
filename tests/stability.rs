//! Stability by irrep: rigid-body zero modes of a free sphere in T1u and T1g, the balloon's
//! first instability as a limit point in the trivial irrep, and the constrained index
//! against a dense computation on the full matrix.

use crate::common::follow;
use memstab::adapted::{AdaptedBasis, SparseBasis};
use memstab::continuation::PathOptions;
use memstab::effects::gas::GasAmountConstraint;
use memstab::effects::gas::{GasAmount, GasPressure};
use memstab::effects::membrane::{Membrane, MooneyRivlin};
use memstab::effects::Quantity;
use memstab::model::constraint::Constraint;
use memstab::model::{Effect, FeModel, Model, Request};
use memstab::stability::{Detail, Stability};
use memstab::study::SymmetricProblem;
use meshes::generators::{icosphere, IcosphereOptions};
use meshes::SymmetricMesh;
use nalgebra::{DMatrix, DVector};

fn balloon(frequency: usize, k: f64) -> (SymmetricMesh, FeModel) {
    let sym = icosphere(&IcosphereOptions {
        radius: 1.0,
        frequency,
    })
    .unwrap();
    let m = &sym.mesh;
    let effects: Vec<Box<dyn Effect>> = vec![
        Box::new(
            Membrane::new(&m.nodes, &m.triangles, MooneyRivlin::new(1.0, k, 1.0), 1.0).unwrap(),
        ),
        Box::new(GasPressure {
            closing: None,
            pressure: Quantity::Parameter(0),
        }),
    ];
    let model = FeModel::new(
        m.nodes.clone(),
        m.triangles.clone(),
        &[],
        effects,
        vec!["p".into()],
    );
    (sym, model)
}

/// The k = 0.1 balloon holding the amount of gas C = (p + P) V (a global volume, a rank-one
/// stiffness), no parameters.
fn closed_balloon(sym: &SymmetricMesh, c: f64, ambient: f64) -> FeModel {
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
        Box::new(GasAmount {
            amount: Quantity::Value(c),
            ambient,
            closing: None,
            fluid: None,
        }),
    ];
    FeModel::new(m.nodes.clone(), m.triangles.clone(), &[], effects, vec![])
}

/// Converged symmetric states (u, p, stretch) along the pressure-controlled path.
fn states(sym: &SymmetricMesh, model: &FeModel, to_stretch: f64) -> Vec<(Vec<f64>, f64, f64)> {
    let basis = SparseBasis::fixed_point(&sym.action, model.layout());
    let v0 = sym.mesh.volume();
    let mut problem = SymmetricProblem::new(model, &basis, &[], vec![0.0], Some(0));
    let probe = SymmetricProblem::new(model, &basis, &[], vec![0.0], Some(0));
    let stretch = |q: &DVector<f64>| {
        let x = model.positions(&probe.displacement(q), &[]);
        let v: f64 = sym
            .mesh
            .triangles
            .iter()
            .map(|&[a, b, c]| x[a].dot(&x[b].cross(&x[c])))
            .sum::<f64>()
            / 6.0;
        (v / v0).cbrt()
    };
    let opts = PathOptions {
        initial_step: 0.02,
        max_step: 0.1,
        state_scale: (sym.mesh.nodes.len() as f64).sqrt(),
        ..PathOptions::default()
    };
    let path = follow(
        &mut problem,
        &DVector::zeros(basis.dim()),
        &DVector::from_element(1, 0.0),
        &opts,
        |p| stretch(&p.q) > to_stretch,
    )
    .unwrap();
    path.points
        .iter()
        .map(|p| (probe.displacement(&p.q), p.lambda[0], stretch(&p.q)))
        .collect()
}

#[test]
fn free_sphere_has_three_zero_modes_in_t1u_and_three_in_t1g_at_every_state() {
    let (sym, model) = balloon(4, 0.1);
    let basis = AdaptedBasis::new(&sym.action, model.layout()).unwrap();
    let stab = Stability::new(&model, &basis);
    assert_eq!(model.rigid_motions().len(), 6);
    let mut eval = model.new_evaluation();
    let all = states(&sym, &model, 3.0);
    assert!(all.len() > 10);
    for (u, p, s) in all.iter().step_by(3) {
        let sp = stab.spectrum(u, &[*p], &[], &mut eval).unwrap();
        for b in &sp.blocks {
            let expected = if b.irrep == "T1u" || b.irrep == "T1g" {
                1
            } else {
                0
            };
            assert_eq!(b.rigid_modes, expected, "{} at stretch {s}", b.irrep);
            // At an equilibrium the rigid fields are exact null vectors of K.
            assert!(
                b.rigid_residual < 1e-9,
                "{}: K r = {:e} at stretch {s}",
                b.irrep,
                b.rigid_residual
            );
            // Nothing else is near zero in those blocks (no spurious modes) — except at the
            // limit point, which is in the trivial block.
            if expected == 1 {
                let low = b
                    .eigenvalues
                    .iter()
                    .fold(f64::INFINITY, |a, v| a.min(v.abs()));
                assert!(
                    low > 1e-6 * sp.scale,
                    "{}: a second small eigenvalue {low:e}",
                    b.irrep
                );
            }
        }
        // In K itself: d = 3 copies of each, six zero eigenvalues in all.
        let zeros: usize = sp.blocks.iter().map(|b| b.dim * b.rigid_modes).sum();
        assert_eq!(zeros, 6);
    }
}

#[test]
fn balloon_first_instability_is_a_limit_point_in_the_trivial_irrep() {
    let (sym, model) = balloon(4, 0.1);
    let basis = AdaptedBasis::new(&sym.action, model.layout()).unwrap();
    let stab = Stability::new(&model, &basis);
    let mut eval = model.new_evaluation();
    let all = states(&sym, &model, 2.0);
    let mut previous: Option<(Vec<usize>, f64, f64)> = None;
    let mut first = None;
    for (u, p, s) in &all {
        let sp = stab.spectrum(u, &[*p], &[], &mut eval).unwrap();
        let neg = sp.negatives();
        if let Some((prev, pp, ps)) = &previous {
            if *prev != neg && first.is_none() {
                let changed: Vec<&str> = (0..neg.len())
                    .filter(|&i| neg[i] != prev[i])
                    .map(|i| sp.blocks[i].irrep.as_str())
                    .collect();
                first = Some((changed.join(","), *pp, *p, *ps, *s));
            }
        } else {
            assert_eq!(sp.index, 0, "the start is stable");
        }
        previous = Some((neg, *p, *s));
    }
    let (irreps, p0, p1, s0, s1) = first.expect("the balloon loses stability");
    assert_eq!(irreps, "Ag", "first change of index in {irreps}");
    // Between the two states the pressure passes its maximum (stretch ≈ 1.476).
    assert!(
        s0 < 1.48 && s1 > 1.47,
        "stretches {s0}..{s1}, pressures {p0}..{p1}"
    );
}

#[test]
fn constrained_index_matches_a_dense_computation_and_the_gas_amount_effect() {
    // At a state past the pressure maximum the balloon is unstable under pressure control but
    // stable for a fixed amount of gas. The same physics two ways: the gas-amount effect
    // (rank-one stiffness) and the pressure effect bordered by the constraint (p+P)V = C.
    let (sym, model) = balloon(2, 0.1);
    let all = states(&sym, &model, 2.2);
    let (u, p, s) = all
        .iter()
        .find(|st| st.2 > 2.0)
        .cloned()
        .expect("a state past the maximum");
    let basis = AdaptedBasis::new(&sym.action, model.layout()).unwrap();
    let stab = Stability::new(&model, &basis);
    let mut eval = model.new_evaluation();
    let pressure_control = stab.spectrum(&u, &[p], &[], &mut eval).unwrap();
    assert!(
        pressure_control.index >= 1,
        "past the maximum at stretch {s} under pressure control"
    );

    let ambient = 1.0;
    let x = model.positions(&u, &[p]);
    let mut amount = GasAmountConstraint {
        pressure: 0,
        ambient,
        target: 0.0,
        target_parameter: None,
        closing: None,
        fluid: None,
    };
    let c = amount.measure(model.layout(), &x, &[p]);
    amount.set_target(c);
    let constraints: Vec<Box<dyn Constraint>> = vec![Box::new(amount)];
    let bordered = stab.spectrum(&u, &[p], &constraints, &mut eval).unwrap();

    let closed = closed_balloon(&sym, c, ambient);
    let basis2 = AdaptedBasis::new(&sym.action, closed.layout()).unwrap();
    let stab2 = Stability::new(&closed, &basis2);
    let mut eval2 = closed.new_evaluation();
    let by_effect = stab2.spectrum(&u, &[], &[], &mut eval2).unwrap();
    assert_eq!(bordered.index, by_effect.index);
    assert_eq!(
        by_effect.index, 0,
        "a fixed amount of gas stabilises the balloon at stretch {s}"
    );
    let (a, b) = (
        &bordered.blocks[0].eigenvalues,
        &by_effect.blocks[0].eigenvalues,
    );
    assert_eq!(a.len(), b.len());
    for (x1, x2) in a.iter().zip(b) {
        assert!(
            (x1 - x2).abs() < 1e-9 * by_effect.scale,
            "trivial blocks differ: {x1} vs {x2}"
        );
    }

    // Dense on the full matrix: K + c aaᵀ on the complement of the six rigid fields.
    closed.evaluate(&u, &[], Request::ALL, &mut eval2).unwrap();
    let n = closed.unknowns();
    let kd = closed.pattern().to_dense(&eval2.tangent);
    let mut k = DMatrix::from_fn(n, n, |i, j| kd[(i, j)]);
    for (cc, a) in &eval2.rank_one {
        let a = DVector::from_column_slice(a);
        k += &a * a.transpose() * *cc;
    }
    let rigid = closed.rigid_modes(&closed.rigid_motions(), &closed.positions(&u, &[]));
    let r = DMatrix::from_columns(
        &rigid
            .iter()
            .map(|v| DVector::from_column_slice(v))
            .collect::<Vec<_>>(),
    );
    let eig = (&r * r.transpose()).symmetric_eigen();
    let top = eig.eigenvalues.amax();
    let keep: Vec<usize> = (0..n)
        .filter(|&i| eig.eigenvalues[i] < 1e-10 * top)
        .collect();
    let z = DMatrix::from_fn(n, keep.len(), |i, j| eig.eigenvectors[(i, keep[j])]);
    let neg = (z.transpose() * &k * &z)
        .symmetric_eigenvalues()
        .iter()
        .filter(|&&v| v < 0.0)
        .count();
    assert_eq!(neg, by_effect.index);
    // And the pressure-controlled index against the dense K on the same complement.
    model.evaluate(&u, &[p], Request::ALL, &mut eval).unwrap();
    let kd = model.pattern().to_dense(&eval.tangent);
    let k = DMatrix::from_fn(n, n, |i, j| kd[(i, j)]);
    let neg = (z.transpose() * &k * &z)
        .symmetric_eigenvalues()
        .iter()
        .filter(|&&v| v < 0.0)
        .count();
    assert_eq!(neg, pressure_control.index);
}

/// The sparse path (inertia of the bordered block, Haynsworth) gives the same negative count
/// per block as the dense eigenvalues, along the balloon path through its pressure maximum
/// and minimum: under pressure control (rigid modes in T1u and T1g bordered), with the gas
/// amount as a constraint (the trivial block bordered by L and an invertible C) and with the
/// gas-amount effect (a rank-one term bordered with −1/c).
#[test]
fn sparse_block_inertia_agrees_with_dense_eigenvalues_along_the_path() {
    let (sym, model) = balloon(3, 0.1);
    let basis = AdaptedBasis::new(&sym.action, model.layout()).unwrap();
    let dense = Stability::new(&model, &basis).with_dense_limit(usize::MAX);
    let sparse = Stability::new(&model, &basis).with_dense_limit(0);
    let mut eval = model.new_evaluation();
    let mut local = dense.new_evaluation();
    let mut seen = std::collections::BTreeSet::new();
    let ambient = 1.0;
    for (u, p, s) in states(&sym, &model, 3.6) {
        let x = model.positions(&u, &[p]);
        let mut amount = GasAmountConstraint {
            pressure: 0,
            ambient,
            target: 0.0,
            target_parameter: None,
            closing: None,
            fluid: None,
        };
        let c = amount.measure(model.layout(), &x, &[p]);
        amount.set_target(c);
        let constraints: Vec<Box<dyn Constraint>> = vec![Box::new(amount)];
        for cons in [&[][..], &constraints[..]] {
            let a = dense.spectrum(&u, &[p], cons, &mut eval).unwrap();
            let b = sparse.spectrum(&u, &[p], cons, &mut eval).unwrap();
            assert_eq!(
                a.negatives(),
                b.negatives(),
                "stretch {s}, constraints {}",
                cons.len()
            );
            // The same from an evaluation of the triangles around the representatives only.
            let c = dense
                .analyse(&u, &[p], cons, &mut local, None, Detail::Inertia)
                .unwrap();
            assert_eq!(a.negatives(), c.negatives(), "local, stretch {s}");
            for (x, y) in a.blocks.iter().zip(&b.blocks) {
                assert_eq!(x.rigid_modes, y.rigid_modes, "{} at stretch {s}", x.irrep);
                assert!(y.eigenvalues.is_empty());
            }
            seen.insert(a.negatives());
        }
        let closed = closed_balloon(&sym, c, ambient);
        let basis2 = AdaptedBasis::new(&sym.action, closed.layout()).unwrap();
        let mut eval2 = closed.new_evaluation();
        let a = Stability::new(&closed, &basis2)
            .with_dense_limit(usize::MAX)
            .spectrum(&u, &[], &[], &mut eval2)
            .unwrap();
        let local = Stability::new(&closed, &basis2);
        let c = local
            .analyse(
                &u,
                &[],
                &[],
                &mut local.new_evaluation(),
                None,
                Detail::Inertia,
            )
            .unwrap();
        assert_eq!(a.negatives(), c.negatives(), "gas-amount effect, local");
        let b = Stability::new(&closed, &basis2)
            .with_dense_limit(0)
            .spectrum(&u, &[], &[], &mut eval2)
            .unwrap();
        assert_eq!(
            a.negatives(),
            b.negatives(),
            "gas-amount effect, stretch {s}"
        );
    }
    // The comparison covered stable and unstable states (the index changes along the path).
    assert!(seen.len() >= 2, "only {seen:?}");
}

/// The lowest eigenvalues of every block by shift-invert Lanczos on the bordered sparse
/// factorisation are the dense ones, along the balloon path through both pressure extrema:
/// with the rigid modes deflated (T1u, T1g), with the gas amount as a constraint (the trivial
/// block bordered by L and an invertible C) and with the gas-amount effect (a rank-one term).
/// The index from the inertia and from the eigenvalues agree at every point, and the Lanczos
/// eigenvectors are the dense ones (up to sign) where the eigenvalue is simple.
#[test]
fn lanczos_block_eigenvalues_agree_with_dense_along_the_path() {
    use memstab::stability::BlockEigen;
    let (sym, model) = balloon(3, 0.1);
    let basis = AdaptedBasis::new(&sym.action, model.layout()).unwrap();
    let dense = Stability::new(&model, &basis).with_block_eigen(BlockEigen::Dense);
    let lanczos = Stability::new(&model, &basis).with_block_eigen(BlockEigen::Lanczos);
    let mut eval = model.new_evaluation();
    let lowest = 6;
    let compare = |a: &memstab::continuation::crossings::Spectrum,
                   b: &memstab::continuation::crossings::Spectrum,
                   what: &str| {
        assert_eq!(a.negatives(), b.negatives(), "{what}");
        for (x, y) in a.blocks.iter().zip(&b.blocks) {
            assert!(x.complete && y.eigen_error.is_none(), "{what} {}", x.irrep);
            let n = lowest.max(y.negative + 1).min(x.eigenvalues.len());
            assert!(
                y.eigenvalues.len() >= n,
                "{what} {}: {:?}",
                x.irrep,
                y.eigenvalues
            );
            for (i, (u, v)) in x.eigenvalues.iter().zip(&y.eigenvalues).take(n).enumerate() {
                assert!(
                    (u - v).abs() <= 1e-9 * a.scale,
                    "{what} {} λ_{i}: dense {u}, Lanczos {v}",
                    x.irrep
                );
            }
            // The index from the computed eigenvalues is the inertia's.
            let below = y.eigenvalues.iter().filter(|&&v| v < 0.0).count();
            assert_eq!(below, y.negative, "{what} {}", x.irrep);
            // Eigenvectors of simple eigenvalues agree up to sign.
            for i in 0..n.min(x.vectors.ncols()).min(y.vectors.ncols()) {
                let gap = |k: usize| {
                    [k.wrapping_sub(1), k + 1]
                        .iter()
                        .filter_map(|&j| x.eigenvalues.get(j))
                        .map(|w| (w - x.eigenvalues[k]).abs())
                        .fold(f64::INFINITY, f64::min)
                };
                if gap(i) > 1e-6 * a.scale {
                    let c = x.vectors.column(i).dot(&y.vectors.column(i)).abs();
                    assert!(
                        (c - 1.0).abs() < 1e-6,
                        "{what} {} vector {i}: |cos| = {c}",
                        x.irrep
                    );
                }
            }
        }
    };
    let ambient = 1.0;
    let mut seen = std::collections::BTreeSet::new();
    for (u, p, s) in states(&sym, &model, 3.6) {
        let x = model.positions(&u, &[p]);
        let mut amount = GasAmountConstraint {
            pressure: 0,
            ambient,
            target: 0.0,
            target_parameter: None,
            closing: None,
            fluid: None,
        };
        let c = amount.measure(model.layout(), &x, &[p]);
        amount.set_target(c);
        let constraints: Vec<Box<dyn Constraint>> = vec![Box::new(amount)];
        for cons in [&[][..], &constraints[..]] {
            let detail = Detail::Vectors { lowest };
            let a = dense
                .analyse(&u, &[p], cons, &mut eval, None, detail)
                .unwrap();
            let b = lanczos
                .analyse(&u, &[p], cons, &mut eval, None, detail)
                .unwrap();
            compare(&a, &b, &format!("stretch {s}, {} constraints", cons.len()));
            // The index at the point (inertia only) is the same.
            let c = lanczos
                .analyse(&u, &[p], cons, &mut eval, None, Detail::Inertia)
                .unwrap();
            assert_eq!(c.negatives(), b.negatives(), "stretch {s}");
            seen.insert(a.negatives());
        }
        let closed = closed_balloon(&sym, c, ambient);
        let basis2 = AdaptedBasis::new(&sym.action, closed.layout()).unwrap();
        let mut eval2 = closed.new_evaluation();
        let detail = Detail::Vectors { lowest };
        let a = Stability::new(&closed, &basis2)
            .with_block_eigen(BlockEigen::Dense)
            .analyse(&u, &[], &[], &mut eval2, None, detail)
            .unwrap();
        let b = Stability::new(&closed, &basis2)
            .with_block_eigen(BlockEigen::Lanczos)
            .analyse(&u, &[], &[], &mut eval2, None, detail)
            .unwrap();
        compare(&a, &b, &format!("gas-amount effect, stretch {s}"));
    }
    assert!(seen.len() >= 2, "only {seen:?}");
}

/// The test function of a block (docs/theory.md §11.2) is τ = 1/(bᵀ S⁻¹ b) of the same
/// matrix S whose eigenvalues the dense analysis gives: with b an eigenvector φ₀ it is λ₀,
/// with b = (φ₀ + φ₁)/√2 it is 1/(1/(2λ₀) + 1/(2λ₁)); inverse iteration from the start
/// vector turns the border towards the eigenvector of the eigenvalue nearest zero. Checked
/// in every block of the balloon (rigid modes deflated in T1u and T1g), with and without the
/// gas amount bordering the trivial block.
#[test]
fn a_blocks_test_function_is_the_inverse_quadratic_form_of_its_matrix() {
    let (sym, model) = balloon(3, 0.1);
    let basis = AdaptedBasis::new(&sym.action, model.layout()).unwrap();
    let dense = Stability::new(&model, &basis).with_dense_limit(usize::MAX);
    let sparse = Stability::new(&model, &basis);
    let mut eval = model.new_evaluation();
    let mut local = sparse.new_evaluation();
    let all = states(&sym, &model, 2.5);
    let mut checked = 0;
    for (u, p, s) in all.iter().step_by(4) {
        let x = model.positions(u, &[*p]);
        let mut amount = GasAmountConstraint {
            pressure: 0,
            ambient: 1.0,
            target: 0.0,
            target_parameter: None,
            closing: None,
            fluid: None,
        };
        let c = amount.measure(model.layout(), &x, &[*p]);
        amount.set_target(c);
        let constraints: Vec<Box<dyn Constraint>> = vec![Box::new(amount)];
        for cons in [&[][..], &constraints[..]] {
            let sp = dense
                .analyse(
                    u,
                    &[*p],
                    cons,
                    &mut eval,
                    None,
                    Detail::Vectors { lowest: 8 },
                )
                .unwrap();
            for (mu, block) in sp.blocks.iter().enumerate() {
                if block.vectors.ncols() < 2 {
                    continue;
                }
                let (l0, l1) = (block.eigenvalues[0], block.eigenvalues[1]);
                let phi0: Vec<f64> = block.vectors.column(0).iter().copied().collect();
                let mix: Vec<f64> = (block.vectors.column(0) + block.vectors.column(1))
                    .iter()
                    .map(|v| v / 2f64.sqrt())
                    .collect();
                let tau = |b: &[f64], local: &mut _| {
                    sparse
                        .test_function(u, &[*p], cons, local, mu, Some(b), 0)
                        .unwrap()
                        .expect("a test function")
                        .0
                };
                let tol = 1e-9 * sp.scale;
                let t0 = tau(&phi0, &mut local);
                assert!(
                    (t0 - l0).abs() <= tol,
                    "{} at {s}: {t0:e} vs {l0:e}",
                    block.irrep
                );
                let expected = 1.0 / (0.5 / l0 + 0.5 / l1);
                let t1 = tau(&mix, &mut local);
                assert!(
                    (t1 - expected).abs() <= tol,
                    "{} at {s}: {t1:e} vs {expected:e}",
                    block.irrep
                );
                // Inverse iteration from the start vector: the eigenvalue nearest zero, where
                // it is well separated from the next (30 steps converge by 2⁻³⁰ at least).
                let mut by_size: Vec<f64> = block.eigenvalues.clone();
                by_size.sort_by(|a, b| a.abs().total_cmp(&b.abs()));
                let nearest = by_size[0];
                let (t, border) = sparse
                    .test_function(u, &[*p], cons, &mut local, mu, None, 30)
                    .unwrap()
                    .unwrap();
                assert_eq!(border.len(), block.vectors.nrows());
                checked += 1;
                if by_size.len() < 2 || nearest.abs() > 0.5 * by_size[1].abs() {
                    continue;
                }
                assert!(
                    (t - nearest).abs() <= 1e-6 * nearest.abs().max(1e-6 * sp.scale),
                    "{} at {s}: {t:e} vs {nearest:e}",
                    block.irrep
                );
            }
        }
    }
    assert!(checked > 20, "{checked} blocks checked");
}
