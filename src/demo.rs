//! The bundled demo: a Mooney–Rivlin balloon (k = 0.1) inflated by gas under pressure control
//! through its pressure maximum and minimum, and the comparison of its turning points with
//! the closed form of a sphere (docs/theory.md §13.1–§13.2).

use crate::reference::{sphere_extrema, sphere_pressure, SphereExtremum};
use crate::results::{Extremum, PathReport};
use crate::scene::{GasEffect, MeshSpec, Scene, SceneError};

/// The demo scene's text, bundled so that `memstab demo` works from anywhere.
pub const SCENE: &str = include_str!("../scenes/demo.toml");
/// How the bundled demo scene is named in messages and in `path.json`.
pub const ORIGIN: &str = "scenes/demo.toml (bundled)";

/// The demo scene.
pub fn scene() -> Result<Scene, SceneError> {
    Scene::from_toml_str(SCENE, ORIGIN)
}

/// A balloon's turning points against the closed form.
#[derive(Debug, Clone)]
pub struct ClosedFormCheck {
    /// k of the material.
    pub k: f64,
    /// The closed form's extrema.
    pub extrema: Vec<SphereExtremum>,
    /// One per turning point of the run.
    pub turning: Vec<TurningCheck>,
    /// R A/(3V) − 1 of the mesh: the polyhedron's pressure scale over the sphere's.
    pub polyhedron: f64,
    /// The icosphere's frequency.
    pub frequency: usize,
}

/// One turning point against the closed form.
#[derive(Debug, Clone)]
pub struct TurningCheck {
    /// Maximum or minimum.
    pub kind: Extremum,
    /// p R/(μH) found.
    pub pressure: f64,
    /// The stretch found.
    pub stretch: f64,
    /// The closed form's pressure at that stretch.
    pub exact: f64,
    /// The relative difference of the stretch from the closed form's extremum of its kind.
    pub stretch_difference: Option<f64>,
}

impl TurningCheck {
    /// found / exact − 1.
    pub fn difference(&self) -> f64 {
        self.pressure / self.exact - 1.0
    }
}

impl ClosedFormCheck {
    /// Whether the polyhedron's pressure scale is most of every difference.
    pub fn explained_by_mesh(&self) -> bool {
        self.turning
            .iter()
            .all(|t| (t.difference() - self.polyhedron).abs() < 0.5 * t.difference().abs())
    }
}

/// The closed-form check of a run of a balloon under pressure control (an icosphere whose
/// only effect is a gas at the control's pressure); `None` for any other run.
pub fn closed_form_check(
    scene: &crate::scene::Scene,
    mesh: &meshes::Mesh,
    report: &PathReport,
) -> Option<ClosedFormCheck> {
    let MeshSpec::Icosphere(ico) = &scene.mesh else {
        return None;
    };
    let c = report
        .parameters
        .iter()
        .position(|p| *p == report.control)?;
    let s = report.measures.iter().position(|m| m == "stretch")?;
    let pressure_control = scene.effects.iter().any(|e| {
        e.get::<GasEffect>()
            .is_some_and(|g| g.pressure.parameter() == Some(report.control.as_str()))
    });
    if !pressure_control || scene.effects.len() != 1 {
        return None;
    }
    let mat = &scene.material;
    let [mu, k, thickness, prestretch] =
        [&mat.mu, &mat.k, &mat.thickness, &mat.prestretch].map(|q| scene.start_value(q));
    // The stress-free sphere: radius R/λ0, thickness H.
    let scale = ico.radius / prestretch / (mu * thickness);
    let extrema = sphere_extrema(k);
    // A polyhedron's pressure scale: p = dW/dV, with dW ∝ area and dV ∝ 3·volume, so the
    // discrete balloon's pressure exceeds the sphere's by R·A/(3V) − 1.
    let polyhedron = ico.radius * mesh.area() / (3.0 * mesh.volume()) - 1.0;
    let turning = report
        .turning_points
        .iter()
        .map(|t| {
            let stretch = t.measures[s];
            let nearest = extrema
                .iter()
                .filter(|e| e.maximum == (t.kind == Extremum::Maximum))
                .map(|e| e.stretch)
                .min_by(|a, b| (a - stretch).abs().total_cmp(&(b - stretch).abs()));
            TurningCheck {
                kind: t.kind,
                pressure: t.parameters[c] * scale,
                stretch,
                exact: sphere_pressure(k, stretch),
                stretch_difference: nearest.map(|le| stretch / le - 1.0),
            }
        })
        .collect();
    Some(ClosedFormCheck {
        k,
        extrema,
        turning,
        polyhedron,
        frequency: ico.frequency,
    })
}
