//! The inflated Mooney-Rivlin balloon against the closed form (docs/theory.md §13.1):
//!
//! ```text
//!   p R/(μH) = 2/(1+k) (λ⁻¹ − λ⁻⁷)(1 + k λ²),   λ = (V/V0)^(1/3)
//! ```
//!
//! For k = 0.1 the pressure has a maximum 1.3551069 at λ = 1.4760698 and a minimum 1.1487477
//! at λ = 3.1426213. The path is followed under pressure control in the Ih fixed-point space
//! of icospheres; the turning points must approach the closed form at second order in h.

use crate::common::follow;
use memstab::adapted::SparseBasis;
use memstab::continuation::PathOptions;
use memstab::effects::gas::GasPressure;
use memstab::effects::membrane::{Membrane, MooneyRivlin};
use memstab::effects::Quantity;
use memstab::model::{Effect, FeModel, Model};
use memstab::study::SymmetricProblem;
use meshes::generators::{icosphere, IcosphereOptions};
use nalgebra::DVector;

use memstab::reference::{sphere_pressure as closed_form, L_MAX, L_MIN, P_MAX, P_MIN};
use memstab::results::{Extremum, StopReason};

struct Extrema {
    max: (f64, f64),
    min: Option<(f64, f64)>,
    points: usize,
    on_curve: f64,
}

/// Follows the balloon of frequency f to stretch `to_stretch`; returns its turning points as
/// (stretch, p) and the largest deviation of the path from the closed form.
fn balloon(frequency: usize, k: f64, to_stretch: f64) -> Extrema {
    let sym = icosphere(&IcosphereOptions {
        radius: 1.0,
        frequency,
    })
    .unwrap();
    let m = &sym.mesh;
    let membrane =
        Membrane::new(&m.nodes, &m.triangles, MooneyRivlin::new(1.0, k, 1.0), 1.0).unwrap();
    let effects: Vec<Box<dyn Effect>> = vec![
        Box::new(membrane),
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
    let basis = SparseBasis::fixed_point(&sym.action, model.layout());
    assert!(basis.dim() > 0 && basis.dim() < model.layout().unknowns() / 20);
    let v0 = m.volume();
    let stretch_of = |problem: &SymmetricProblem, q: &DVector<f64>| -> f64 {
        let x = model.positions(&problem.displacement(q), &[0.0]);
        let v: f64 = m
            .triangles
            .iter()
            .map(|&[a, b, c]| x[a].dot(&x[b].cross(&x[c])))
            .sum::<f64>()
            / 6.0;
        (v / v0).cbrt()
    };
    let mut problem = SymmetricProblem::new(&model, &basis, &[], vec![0.0], Some(0));
    let opts = PathOptions {
        initial_step: 0.02,
        max_step: 0.3,
        max_steps: 400,
        state_scale: (m.nodes.len() as f64).sqrt(),
        ..PathOptions::default()
    };
    let q0 = DVector::zeros(basis.dim());
    let mut stretches = Vec::new();
    let path = {
        let probe = SymmetricProblem::new(&model, &basis, &[], vec![0.0], Some(0));
        follow(
            &mut problem,
            &q0,
            &DVector::from_element(1, 0.0),
            &opts,
            |p| stretch_of(&probe, &p.q) >= to_stretch,
        )
        .unwrap()
    };
    assert_eq!(
        path.stop,
        StopReason::Condition,
        "the path must reach stretch {to_stretch}"
    );
    let probe = SymmetricProblem::new(&model, &basis, &[], vec![0.0], Some(0));
    let mut on_curve: f64 = 0.0;
    for p in &path.points {
        let l = stretch_of(&probe, &p.q);
        stretches.push(l);
        assert!(p.lambda[0].is_finite() && p.q.iter().all(|v| v.is_finite()));
        on_curve = on_curve.max((p.lambda[0] - closed_form(k, l)).abs());
    }
    let tp: Vec<(Extremum, f64, f64)> = path
        .turning_points()
        .map(|t| (t.kind, stretch_of(&probe, &t.point.q), t.point.lambda[0]))
        .collect();
    let max = tp
        .iter()
        .find(|t| t.0 == Extremum::Maximum)
        .map(|t| (t.1, t.2))
        .expect("a pressure maximum");
    let min = tp
        .iter()
        .find(|t| t.0 == Extremum::Minimum)
        .map(|t| (t.1, t.2));
    Extrema {
        max,
        min,
        points: path.points.len(),
        on_curve,
    }
}

#[test]
fn balloon_turning_points_converge_to_the_closed_form_at_second_order() {
    let k = 0.1;
    let coarse = balloon(8, k, 3.6);
    let fine = balloon(16, k, 3.6);
    let (min_c, min_f) = (
        coarse.min.expect("minimum at f = 8"),
        fine.min.expect("minimum at f = 16"),
    );
    let err = |a: (f64, f64), p: f64| (a.1 - p).abs() / p;
    let (emax_c, emax_f) = (err(coarse.max, P_MAX), err(fine.max, P_MAX));
    let (emin_c, emin_f) = (err(min_c, P_MIN), err(min_f, P_MIN));
    let rate_max = (emax_c / emax_f).log2();
    let rate_min = (emin_c / emin_f).log2();
    eprintln!(
        "f=8: max {:?} min {:?} ({} points); f=16: max {:?} min {:?} ({} points); rates {rate_max:.2}, {rate_min:.2}",
        coarse.max, min_c, coarse.points, fine.max, min_f, fine.points
    );
    // The stretch of each extremum too.
    assert!(
        (fine.max.0 - L_MAX).abs() < 0.02,
        "stretch at the maximum {}",
        fine.max.0
    );
    assert!(
        (min_f.0 - L_MIN).abs() < 0.05,
        "stretch at the minimum {}",
        min_f.0
    );
    assert!(
        emax_f < 2e-3 && emin_f < 2e-3,
        "errors {emax_f:e}, {emin_f:e}"
    );
    assert!(
        (1.7..2.3).contains(&rate_max),
        "rate at the maximum {rate_max}"
    );
    assert!(
        (1.7..2.3).contains(&rate_min),
        "rate at the minimum {rate_min}"
    );
    // The whole path stays near the closed-form curve.
    assert!(
        fine.on_curve < 5e-3,
        "largest deviation from the closed form {}",
        fine.on_curve
    );
}
