//! Fluid volume of an open membrane closed by a flat plate (a truncated sphere clamped on a
//! plate): against the closed form of a sphere segment, converging at second order; and the
//! fixed-fluid-volume constraint holds it along a path (the docs/scenes.md example).

use memstab::analysis::run;
use memstab::effects::hydrostatic::FluidVolumeConstraint as FluidVolume;
use memstab::effects::hydrostatic::{Fluid, FluidSide};
use memstab::effects::Quantity;
use memstab::model::constraint::Constraint;
use memstab::model::Model;
use memstab::scene::Scene;
use memstab::study::mesh::MeshStudy;
use std::f64::consts::PI;

/// Volume of the unit sphere between z = c and z = t (c ≤ t ≤ 1): π ∫ (1 − z²) dz.
fn segment(c: f64, t: f64) -> f64 {
    let f = |z: f64| z - z * z * z / 3.0;
    PI * (f(t) - f(c))
}

fn study(divisions: usize) -> MeshStudy {
    let text = format!(
        r#"
[scene]
name = "cap"
[mesh]
generator = "truncated-sphere"
cut-height = -0.5
divisions = {divisions}
[material]
mu = 1.0
k = 0.1
thickness = 1.0
prestretch = 1.05
[[effect]]
type = "fluid"
side = "inside"
density = 1.0
gravity = 1.0
level = "h"
[boundary]
fixed = ["cut"]
[parameters.h]
start = 0.2
[[constraint]]
type = "fluid-volume"
value = "initial"
[analysis]
type = "equilibrium"
"#
    );
    MeshStudy::build(Scene::from_toml_str(&text, "cap").unwrap()).unwrap()
}

#[test]
fn plate_closed_fluid_volume_converges_to_the_sphere_segment() {
    let levels = [-0.7, -0.2, 0.3, 0.9, 1.2];
    let mut errors = Vec::new();
    for d in [8, 16] {
        let s = study(d);
        let x = s.model.reference().to_vec();
        let fluid = Fluid {
            filled: false,
            closing: None,
            density: Quantity::Value(1.0),
            gravity: Quantity::Value(1.0),
            level: Quantity::Parameter(0),
            side: FluidSide::Behind,
        };
        let c = FluidVolume {
            fluid,
            level: 0,
            target: 0.0,
            target_parameter: None,
            closing: None,
        };
        let mut worst: f64 = 0.0;
        for h in levels {
            // The study's constraint carries the plate; compare with the closed form.
            let measured = s.constraints[0].measure(s.model.layout(), &x, &[h]);
            let exact = if h <= -0.5 {
                0.0
            } else {
                segment(-0.5, h.min(1.0))
            };
            worst = worst.max((measured - exact).abs() / segment(-0.5, 1.0));
            // Without the plate the level below the rim would count the plate's column wrongly.
            let bare = c.measure(s.model.layout(), &x, &[h]);
            if h > -0.5 {
                assert!(
                    (bare - measured).abs() > 1e-3,
                    "the plate contributes at h = {h}"
                );
            }
        }
        errors.push(worst);
    }
    let rate = (errors[0] / errors[1]).log2();
    assert!(errors[1] < 5e-3, "{errors:?}");
    assert!((1.7..2.4).contains(&rate), "rate {rate}, errors {errors:?}");
}

#[test]
fn the_docs_example_holds_its_fluid_volume_along_the_path() {
    let docs =
        std::fs::read_to_string(format!("{}/docs/scenes.md", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let start = docs.find("## A complete example").unwrap();
    let block = &docs[start..];
    let toml = block
        .split("```toml")
        .nth(1)
        .unwrap()
        .split("```")
        .next()
        .unwrap();
    let toml = toml
        .replace("steps = 300", "steps = 40")
        .replace("divisions = 12 ", "divisions = 6 ");
    let mut study = MeshStudy::build(Scene::from_toml_str(&toml, "docs example").unwrap()).unwrap();
    assert_eq!(study.action.group().name(), "C8v");
    let r = run(&mut study, |_, _| {}).unwrap().report;
    assert!(r.rows.len() > 5, "{}", r.stop);
    let k = r.measures.iter().position(|m| m == "fluid_volume").unwrap();
    let v0 = r.rows[0].measures[k];
    assert!(v0 > 0.5);
    for row in &r.rows {
        assert!(
            (row.measures[k] - v0).abs() < 1e-8 * v0,
            "fluid volume drifts: {} vs {v0}",
            row.measures[k]
        );
    }
    // The level moved: the constraint frees it.
    let h = r.parameters.iter().position(|p| p == "h").unwrap();
    let (h0, h1) = (
        r.rows[0].parameters[h],
        r.rows.last().unwrap().parameters[h],
    );
    assert!((h1 - h0).abs() > 1e-6, "level {h0} → {h1}: {}", r.stop);
}
