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
        .with_wrinkling(Wrinkling::Relaxed { stiffness });
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
            .relaxed_energy_gradient_hessian(&mat, stiffness, &t.map(|i| x[i]))
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
