//! Dimensionless axes for the diagrams: what each parameter or measure of a scene is divided
//! by, and the closed form a diagram can draw under the path.
//!
//! A membrane's natural scales are μH (a tension), a length a of the mesh (the stress-free
//! radius: the mesh radius over the prestretch) and, from them, μH/a for a pressure and
//! μH/a² for a weight per volume. A parameter's role in the scene (the pressure of a gas,
//! the density or level of a fluid, the ω² of a spin, the offset of a plane) decides its
//! dimensionless group: `p R/(μH)`, `ρ g a²/(μH)`, `h/a`, `ρ ω² a³/(μH)`, `d/a`. The scale is
//! used only where the scene fixes it (μ, H, the prestretch and whatever else the group
//! needs are numbers, not parameters, and the mesh has a radius); otherwise the axis keeps
//! the parameter's name and its values.

use super::svg::{short, AxisScale, ReferenceCurve};
use crate::effects::spec::Natural;
use crate::results::PathReport;
use crate::scene::{GasEffect, MeshSpec, Quantity, Scene};

/// The scales of a scene's quantities, by name.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Scales {
    entries: Vec<(String, AxisScale)>,
}

impl Scales {
    /// The scale of `name`, if the scene knows one.
    pub fn get(&self, name: &str) -> Option<&AxisScale> {
        self.entries.iter().find(|(n, _)| n == name).map(|(_, s)| s)
    }

    /// The scale of `name`, or the name itself with factor 1.
    pub fn or_name(&self, name: &str) -> AxisScale {
        self.get(name).cloned().unwrap_or_else(|| AxisScale {
            label: name.to_string(),
            factor: 1.0,
        })
    }

    fn add(&mut self, name: &str, label: String, factor: f64) {
        if factor.is_finite() && factor > 0.0 && self.get(name).is_none() {
            self.entries
                .push((name.to_string(), AxisScale { label, factor }));
        }
    }

    /// The scales of the quantities of `scene` and of `report`'s measures (`V/V0` with V0
    /// the first row's volume).
    pub fn of(scene: &Scene, report: &PathReport) -> Self {
        let mut s = Self::of_scene(scene, report.mesh.radius);
        s.measures(scene, report);
        s
    }

    /// The scales of the parameters of `scene` solved on a mesh of radius `mesh_radius`
    /// ([`MeshInfo::radius`](crate::results::MeshInfo::radius); used where the scene gives
    /// none).
    pub fn of_scene(scene: &Scene, mesh_radius: Option<f64>) -> Self {
        let mut s = Self::default();
        let m = &scene.material;
        let (a, mu_h, l) = natural(scene, mesh_radius);
        let with = with_values;
        if let Some(k) = m.k.parameter() {
            s.add(k, "k = c2/c1".into(), 1.0);
        }
        if let Some(p) = m.prestretch.parameter() {
            s.add(p, "λ0 (prestretch)".into(), 1.0);
        }
        let n = Natural {
            length: a,
            tension: mu_h,
            symbol: l,
        };
        for e in &scene.effects {
            for scale in e.spec().scales(&n) {
                let parts: Vec<(&str, f64)> =
                    scale.values.iter().map(|(k, v)| (k.as_str(), *v)).collect();
                s.add(&scale.parameter, with(&scale.group, &parts), scale.factor);
            }
        }
        s
    }

    /// Adds the scales of `report`'s measures.
    fn measures(&mut self, scene: &Scene, report: &PathReport) {
        let s = self;
        let (a, mu_h, l) = natural(scene, report.mesh.radius);
        let with = with_values;
        if report.measures.iter().any(|m| m == "stretch") {
            s.add("stretch", "λ = (V/V_sf)^(1/3)".into(), 1.0);
        }
        if let Some(v) = report.measures.iter().position(|m| m == "volume") {
            if let Some(v0) = report.rows.first().and_then(|r| r.measures.get(v).copied()) {
                s.add("volume", format!("V/V0 (V0 = {})", short(v0)), 1.0 / v0);
            }
        }
        if let Some(a) = a {
            for name in ["max_displacement", "min_z", "max_z", "apex_z"] {
                let what = match name {
                    "max_displacement" => "max|u|",
                    "min_z" => "min z",
                    "max_z" => "max z",
                    _ => "apex z",
                };
                let label = with(&format!("{what}/{l}"), &[(l, a)]);
                s.add(name, label, 1.0 / a);
            }
            if let Some(mu_h) = mu_h {
                for name in report
                    .measures
                    .iter()
                    .filter(|m| m.starts_with("gas_pressure"))
                {
                    let label = with(&format!("{name} {l}/(μH)"), &[("μH", mu_h), (l, a)]);
                    s.add(name, label, a / mu_h);
                }
            }
        }
    }
}

/// The scene's natural length a (the mesh radius over the prestretch), μH, and the length's
/// symbol (`R` for a sphere, `a` for a disc), where the scene fixes them. A generated mesh's
/// radius is the scene's; a mesh read from a file has none in the scene, and its own is taken
/// (`mesh_radius`: the largest distance of a node from the surface's centroid, the generated
/// disc's and sphere's radius alike).
fn natural(scene: &Scene, mesh_radius: Option<f64>) -> (Option<f64>, Option<f64>, &'static str) {
    let m = &scene.material;
    let mu_h = number(&m.mu).zip(number(&m.thickness)).map(|(a, b)| a * b);
    let (radius, length) = match &scene.mesh {
        MeshSpec::Disc(d) => (Some(d.radius), "a"),
        MeshSpec::Icosphere(i) => (Some(i.radius), "R"),
        MeshSpec::TruncatedSphere(t) => (Some(t.radius), "R"),
        MeshSpec::Axisymmetric(a) => (Some(a.radius), "a"),
        MeshSpec::File(_) => (mesh_radius, "a"),
    };
    let a = radius.zip(number(&m.prestretch)).map(|(r, l)| r / l);
    (a, mu_h, length)
}

/// A fixed number of the scene (not a parameter).
fn number(q: &Quantity) -> Option<f64> {
    match q {
        Quantity::Value(v) => Some(*v),
        Quantity::Parameter(_) => None,
    }
}

/// `label (name = value, …)`.
fn with_values(label: &str, parts: &[(&str, f64)]) -> String {
    let values: Vec<String> = parts
        .iter()
        .map(|(n, v)| format!("{n} = {}", trimmed(*v)))
        .collect();
    format!("{label} ({})", values.join(", "))
}

/// `v` with up to six significant digits and no trailing zeros.
fn trimmed(v: f64) -> String {
    let t = format!("{v:.6}");
    let t = if t.contains('.') {
        t.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        t
    };
    if t == "0" || t == "-0" {
        short(v)
    } else {
        t
    }
}

/// The closed form of a balloon under pressure control, as a curve of (stretch, p) over the
/// report's range of stretch: a free closed icosphere loaded by one gas whose pressure is
/// the control, with μ, H, k and the prestretch numbers; `None` for any other scene or a
/// report without a `stretch`.
pub fn balloon_closed_form(scene: &Scene, report: &PathReport) -> Option<ReferenceCurve> {
    let MeshSpec::Icosphere(ico) = &scene.mesh else {
        return None;
    };
    let [effect] = scene.effects.as_slice() else {
        return None;
    };
    let gas = effect.get::<GasEffect>()?;
    if gas.pressure.parameter() != Some(report.control.as_str())
        || !scene.boundary.fixed.is_empty()
        || !scene.boundary.slide.is_empty()
        || !scene.constraints.is_empty()
    {
        return None;
    }
    let m = &scene.material;
    let (mu, k, h, l0) = (
        number(&m.mu)?,
        number(&m.k)?,
        number(&m.thickness)?,
        number(&m.prestretch)?,
    );
    let radius = ico.radius / l0;
    let s = report.measures.iter().position(|m| m == "stretch")?;
    let (lo, hi) = report
        .rows
        .iter()
        .filter_map(|r| r.measures.get(s).copied())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), l| {
            (lo.min(l), hi.max(l))
        });
    if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi > lo) {
        return None;
    }
    let n = 200;
    let points = (0..=n)
        .map(|i| {
            let l = lo + (hi - lo) * f64::from(i) / f64::from(n);
            (l, crate::reference::sphere_pressure(k, l) * mu * h / radius)
        })
        .collect();
    Some(ReferenceCurve {
        label: format!(
            "closed form, k = {}: 2/(1+k)(λ⁻¹ − λ⁻⁷)(1 + kλ²)",
            trimmed(k)
        ),
        points,
    })
}
